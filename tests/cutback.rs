//! Runs that do not die, and runs that die without losing anything: a step that does not
//! converge is cut back into substeps; a run that still stops leaves its frames, its last
//! completed state and a summary that says what failed, by how much.

mod common;

use std::path::PathBuf;
use std::process::Command;

use common::coarse;
use thermocontact::contact::friction::law_residual;
use thermocontact::driver::{self, OutputPlan, RunOptions, RunStatus};
use thermocontact::model::contact_rows;
use thermocontact::time::{Levels, TimeError};
use thermocontact::Scenario;

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-cutback-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `thermocontact run` of the coarse example (16 × 4 cells, 16 steps) into `out`, without
/// cutback, with `sets` laid over it.
fn run_coarse_without_cutback(out: &std::path::Path, sets: &[&str]) -> std::process::Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_thermocontact"));
    command.args(["run", "--quiet"]);
    for set in ["mesh.nx=16", "mesh.ny=4", "time.steps=16", "solver.cutback=false"]
        .iter()
        .chain(sets)
    {
        command.args(["--set", set]);
    }
    command.arg("--out").arg(out).output().unwrap()
}

/// Five convexification iterations are not enough at step 6 of the coarse example (it needs
/// seven at k = 1/16), and the fast solver's descent is off: without cutback the run stops
/// there. (With the descent the step is solved at k: tests/descent.rs.)
const STARVED: [&str; 2] = ["solver.max_convexification=5", "solver.max_sweeps=0"];

#[test]
fn a_starved_solver_is_rescued_by_cutback_and_every_step_satisfies_the_law() {
    let scenario = coarse(&STARVED);
    let problem = scenario.build().unwrap();
    let params = scenario.solver_params();
    assert!(params.cutback, "cutback is on by default");
    let bound = |r: f64| problem.friction_bound([0.0; 3], 0.0, r);
    let law = &bound;
    let tolerance = scenario.solver.slip_tolerance;
    let mut worst: f64 = 0.0;
    let run = driver::run_observed(
        &problem,
        &params,
        &OutputPlan::default(),
        &RunOptions::default(),
        |problem, state, _| {
            for row in contact_rows(problem, state, tolerance) {
                worst = worst.max(law_residual(law, &row.w_tau, &row.xi, tolerance) / bound(0.0));
            }
        },
    )
    .unwrap();
    let summary = run.summary;
    assert_eq!(summary.status, RunStatus::Completed);
    assert_eq!(run.state.n, 16);
    assert!(
        summary.cutbacks.iter().any(|c| c.step == 6),
        "step 6 needs a cutback: {:?}",
        summary.cutbacks
    );
    for c in &summary.cutbacks {
        assert!(c.depth >= 1 && c.substeps >= 2 && c.substeps <= 1 << c.depth, "{c:?}");
        assert!((c.t - c.step as f64 / 16.0).abs() < 1e-12);
    }
    assert!(worst <= 1e-6, "nodal law residual {worst:e} (relative to μ(0)S)");

    // Without cutback the same run stops at step 6, naming the criterion that failed.
    let mut no_cutback = params;
    no_cutback.cutback = false;
    let error = driver::run(&problem, &no_cutback, &OutputPlan::default(), &RunOptions::default()).unwrap_err();
    match error {
        thermocontact::Error::Time(TimeError::NotConverged {
            step,
            cutback_depth,
            failure,
            ..
        }) => {
            assert_eq!(step, 6);
            assert_eq!(cutback_depth, 0);
            assert_eq!(failure.iterations, 5);
            assert!(failure.value > failure.tolerance, "{failure}");
        }
        other => panic!("{other}"),
    }
}

/// Two substeps of k/2 are two steps of the problem with 2N steps: the cutback levels step to
/// the right times with the right matrices.
#[test]
fn two_substeps_of_half_size_are_the_run_with_twice_the_steps() {
    let coarse_steps = coarse(&[]);
    let fine = coarse(&["time.steps=32"]);
    let problem = coarse_steps.build().unwrap();
    let fine_problem = fine.build().unwrap();
    let params = coarse_steps.solver_params();
    let levels = Levels::build(&problem, &params).unwrap();
    let half = levels.level(1).unwrap();
    assert_eq!(half.time_step(), problem.time_step() / 2.0);

    let mut fine_states = Vec::new();
    thermocontact::time::run::<thermocontact::time::TimeError>(&fine_problem, &params, |state, _| {
        fine_states.push(state.clone());
        Ok(())
    })
    .unwrap();

    let mut state = thermocontact::model::State::initial(&problem);
    let k = problem.time_step();
    for n in 1..=4 {
        let middle = state.t + k / 2.0;
        state = half.step(&state, middle).unwrap().0;
        state = half.step(&state, n as f64 * k).unwrap().0;
        let reference = &fine_states[2 * n - 1];
        assert!((state.t - reference.t).abs() < 1e-15);
        let scale = reference.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = state
            .u
            .iter()
            .zip(&reference.u)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-10 * scale, "step {n}: {diff:e} against {scale:e}");
        let diff_theta = state
            .theta
            .iter()
            .zip(&reference.theta)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff_theta <= 1e-10, "step {n}: θ differs by {diff_theta:e}");
    }
}

/// The forced failure, on the coarse mesh: exit non-zero, and the folder holds the frames
/// written so far, the last completed state in the `.pvd`, and a summary that says what failed.
#[test]
fn a_run_that_stops_leaves_its_frames_its_last_state_and_a_failed_summary() {
    let out = scratch("stop");
    let result = run_coarse_without_cutback(&out, &["solver.max_convexification=5", "solver.max_sweeps=0"]);
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(stderr.contains("time step 6"), "{stderr}");
    assert!(stderr.contains("> tolerance 1e-6"), "{stderr}");

    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    let failure = &summary["failure"];
    assert_eq!(failure["step"], 6);
    assert_eq!(failure["last_step"], 5);
    assert!((failure["last_time"].as_f64().unwrap() - 5.0 / 16.0).abs() < 1e-12);
    let solver = &failure["solver"];
    assert_eq!(solver["loop_name"], "convexification");
    assert!(solver["value"].as_f64().unwrap() > solver["tolerance"].as_f64().unwrap());
    // The output at t = 0.25 (n = 4) was written before the stop, and n = 5 is the last state.
    assert_eq!(summary["outputs"].as_array().unwrap().len(), 1);
    let pvd = std::fs::read_to_string(out.join("solution.pvd")).unwrap();
    for file in ["solution_0004.vtu", "solution_0005.vtu"] {
        assert!(pvd.contains(file), "{pvd}");
        let vtu = std::fs::read_to_string(out.join(file)).unwrap();
        assert!(vtu.trim_end().ends_with("</VTKFile>"), "{file} is whole");
    }
    assert!(out.join("contact_0005.csv").exists());
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn the_cutback_depth_is_bounded_with_a_clear_error() {
    let error = Scenario::load(None, &["solver.max_cutback_depth=40".into()])
        .and_then(|s| s.validate())
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("solver.max_cutback_depth") && error.contains("40"),
        "{error}"
    );
}

/// A Krylov solve at its cap on the iterative path stops the run (no cutback here) with a
/// failure record that names the linear solve and carries its residual history: the relative
/// residual before its one iteration and after it, as GMRES estimates it, the last one the
/// reported (true) residual to rounding. The summary's Krylov iterations count the solves that
/// failed too.
#[test]
fn a_capped_krylov_solve_is_reported_with_its_residual_history() {
    let out = scratch("krylov");
    let result = run_coarse_without_cutback(&out, &["solver.linear=iterative", "solver.max_krylov=1"]);
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(stderr.contains("relative residual of the linear solve"), "{stderr}");
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    // The solves that reached their cap did their iterations: one each, counted in the run's
    // work (no step completed to count them).
    assert!(summary["linear_solves"].as_u64().unwrap() >= 1, "{summary}");
    assert_eq!(summary["krylov_iterations"], summary["linear_solves"], "{summary}");
    let solver = &summary["failure"]["solver"];
    assert_eq!(solver["loop_name"], "GMRES");
    assert_eq!(solver["iterations"], 1);
    let history: Vec<f64> = (solver["residual_history"].as_array().unwrap().iter())
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(history.len(), 2, "{history:?}");
    assert!(history[0] > 0.0, "{history:?}");
    let (value, tolerance) = (solver["value"].as_f64().unwrap(), solver["tolerance"].as_f64().unwrap());
    assert!(
        (history[1] - value).abs() <= 1e-8 * value,
        "{history:?} against {value}"
    );
    assert!(history[1] < history[0], "{history:?}");
    assert!(value > tolerance, "{value} against {tolerance}");
    std::fs::remove_dir_all(&out).ok();
}
