//! Convergence tests: the observed orders of the scheme on short level sequences.
//!
//! Reference: Bartosz, Danan, Szafraniec (2017), Corollary 16 — the estimate (73),
//! error ≤ c(h + k) — and Section 6, Fig. 4 (errors against the finest solution, h = k = 1/2^l,
//! Γ_C cut into 4/h parts).
//!
//! Goal: assertions that fail when the scheme is wrong (a sign, a mass term, the coupling), while
//! each study runs in seconds: levels h = k = 1/2 … 1/16 (8 × 2 … 64 × 16 cells, 2 … 16 steps).
//! The full studies (h down to 1/64) are `thermocontact converge`; docs/verification.md has them.

use std::process::Command;

use thermocontact::model::contact_rows;
use thermocontact::studies::verification::manufactured::Manufactured;
use thermocontact::studies::verification::study::{self, LevelRun, StudyReport};
use thermocontact::time;
use thermocontact::Scenario;

fn quiet(_: &LevelRun) {}

fn print(report: &StudyReport) {
    // Shown on failure (cargo test captures stdout of passing tests).
    println!("{}", report.table());
}

/// Manufactured solution with exact stick and slip on Γ_C (docs/verification.md): against the
/// exact solution the observed order between h = 1/8 and 1/16 is at least 0.8 (theory: 1) in the
/// E-norm of u, at t = T and over all time levels, and in the L² norm of θ; the L² error of the
/// velocity decreases from level to level.
#[test]
fn manufactured_solution_converges_at_order_one() {
    let report = study::manufactured(4, &mut quiet).unwrap();
    print(&report);
    let finest = report.levels.last().unwrap();
    let rates = finest.rates.unwrap();
    assert!(
        rates.u_energy_final >= 0.8,
        "‖u − u_h‖_E(T): order {}",
        rates.u_energy_final
    );
    assert!(
        rates.u_energy_max >= 0.8,
        "max ‖u − u_h‖_E: order {}",
        rates.u_energy_max
    );
    assert!(
        rates.theta_l2_max >= 0.8,
        "max ‖θ − θ_h‖_L²: order {}",
        rates.theta_l2_max
    );
    for pair in report.levels.windows(2) {
        assert!(
            pair[1].errors.w_l2_max < pair[0].errors.w_l2_max,
            "the velocity error grows from h = {} to h = {}",
            pair[0].run.h,
            pair[1].run.h
        );
    }
    // The errors are small against the solution (the test is not passed by two large numbers).
    assert!(finest.errors.u_energy_final < 0.1 * report.solution_norms.u_energy_final);
}

/// The paper's example (default scenario) on h = k = 1/2 … 1/16, the finest as the reference, as
/// in Fig. 4: every observed order is positive and ‖u − u_h‖_E at t = T decreases monotonically.
#[test]
fn paper_example_self_converges_on_levels_half_to_one_sixteenth() {
    let report = study::self_convergence(&Scenario::default(), 4, &mut quiet).unwrap();
    print(&report);
    assert_eq!(report.levels.len(), 3);
    assert_eq!(report.reference.as_ref().unwrap().nx, 64);
    for level in &report.levels[1..] {
        for (name, rate) in level.rates.unwrap().entries() {
            assert!(rate > 0.0, "{name}: order {rate} at h = {}", level.run.h);
        }
    }
    for pair in report.levels.windows(2) {
        assert!(pair[1].errors.u_energy_final < pair[0].errors.u_energy_final);
    }
}

/// The same family with a nonmonotone heat exchange, ∂j(θ) = θ + ½ sin(3θ) (slope from −½ to
/// 5/2; Remark 3): the fixed point on ζ keeps order one in u and θ. (With θ + 2 sin(3θ), slope
/// down to −5, the errors stall near 10 % on these meshes: docs/laws.md.)
#[test]
fn manufactured_solution_with_a_nonmonotone_heat_exchange_converges_at_order_one() {
    let overrides = ["heat_exchange={law=\"expression\", flux=\"theta + 0.5*sin(3*theta)\"}".to_string()];
    let report = study::manufactured_with(4, &overrides, &mut quiet).unwrap();
    print(&report);
    let rates = report.levels.last().unwrap().rates.unwrap();
    for (name, rate) in [
        ("‖u − u_h‖_E(T)", rates.u_energy_final),
        ("max ‖u − u_h‖_E", rates.u_energy_max),
        ("max ‖θ − θ_h‖_L²", rates.theta_l2_max),
    ] {
        assert!(rate >= 0.8, "{name}: order {rate}");
    }
}

/// The discrete solution of the manufactured problem reproduces the exact contact state: at
/// t = 0.5 the points of Γ_C whose slip began well before (τ_s(x) < t − 0.15) slip, those whose
/// slip begins well after (τ_s(x) > t + 0.15) stick, with w_τ zero to the slip tolerance.
#[test]
fn manufactured_contact_has_the_exact_stick_and_slip_zones() {
    let scenario = Manufactured::scenario(&["mesh.nx=32".into(), "mesh.ny=8".into(), "time.steps=8".into()]).unwrap();
    let exact = Manufactured::new(&scenario).unwrap();
    let problem = scenario
        .builder()
        .unwrap()
        .extra_loads(Box::new(exact))
        .build()
        .unwrap();
    let tolerance = scenario.solver.slip_tolerance;
    let (mut stick, mut slip) = (0, 0);
    time::run::<time::TimeError>(&problem, &scenario.solver_params(), |state, _| {
        if state.n == 4 {
            let t = 0.5;
            for row in contact_rows(&problem, state, tolerance) {
                let onset = exact.slip_onset(row.x[0]);
                if onset < t - 0.15 {
                    assert!(row.slip && row.w_tau[0] > 0.0, "x = {} should slip", row.x[0]);
                    slip += 1;
                } else if onset > t + 0.15 {
                    assert!(!row.slip, "x = {} should stick: w_τ = {}", row.x[0], row.w_tau[0]);
                    stick += 1;
                }
            }
        }
        Ok(())
    })
    .unwrap();
    assert!(stick >= 8 && slip >= 8, "{stick} stick and {slip} slip nodes checked");
}

/// `thermocontact converge` prints the tables with observed orders and writes CSV, JSON and
/// the plots of both studies; bad level counts are refused before anything runs.
#[test]
fn converge_command_writes_tables_and_plots() {
    let out = std::env::temp_dir().join(format!("thermocontact-converge-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let result = Command::new(env!("CARGO_BIN_EXE_thermocontact"))
        .args(["converge", "--levels", "2", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        stdout.contains("Self-convergence") && stdout.contains("Manufactured"),
        "{stdout}"
    );
    assert_eq!(
        stdout.matches("observed order at the finest levels").count(),
        1,
        "{stdout}"
    );
    for file in [
        "self_convergence.csv",
        "self_convergence.png",
        "self_convergence.svg",
        "manufactured.csv",
        "manufactured.png",
        "manufactured.svg",
    ] {
        assert!(out.join(file).is_file(), "{file} missing");
    }
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("convergence.json")).unwrap()).unwrap();
    let levels = json["manufactured"]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 2);
    assert!(levels[1]["rates"]["u_energy_final"].as_f64().unwrap() > 0.5);
    let csv = std::fs::read_to_string(out.join("manufactured.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3);

    let bad = Command::new(env!("CARGO_BIN_EXE_thermocontact"))
        .args(["converge", "--levels", "12", "--out"])
        .arg(out.join("bad"))
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(stderr.contains("--levels") && stderr.contains("12"), "{stderr}");
    assert!(!out.join("bad").exists(), "nothing is written for bad input");
    std::fs::remove_dir_all(&out).ok();
}
