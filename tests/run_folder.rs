//! Runs a user can trust: a folder owned by one run, a run stopped from outside that keeps what
//! it computed, and a continued run that gives the bits of the uninterrupted one.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::{assert_no_temporary_files, bin, coarse, same_bytes, steps_without_seconds, summary, wait_for};
use thermocontact::driver::{self, OutputPlan, Restart, RunOptions, RunStatus, StopFlag, CHECKPOINT_FILE};
use thermocontact::step::SolverParams;
use thermocontact::{Error, Interruption, Scenario};

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-folder-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn options(dir: &Path) -> RunOptions {
    RunOptions {
        out_dir: Some(dir.to_path_buf()),
        ..RunOptions::default()
    }
}

/// The frames a `.pvd` lists.
fn pvd_files(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("solution.pvd")).unwrap();
    text.split("file=\"")
        .skip(1)
        .map(|rest| rest.split('"').next().unwrap().to_string())
        .collect()
}

fn vtu_files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".vtu"))
        .collect();
    names.sort();
    names
}

/// Output every second step of the coarse example, so that frames fall before and after a stop.
fn scenario() -> Scenario {
    coarse(&["output.times=[0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0]"])
}

/// A scenario's problem, solver settings and output plan: what `driver::run` takes.
fn parts(scenario: &Scenario) -> (thermocontact::Problem, SolverParams, OutputPlan) {
    (
        scenario.build().unwrap(),
        scenario.solver_params(),
        scenario.output_plan(),
    )
}

#[test]
fn a_folder_with_another_runs_results_is_refused_unless_overwritten() {
    let dir = scratch("refuse");
    let (problem, params, plan) = parts(&coarse(&["time.steps=4", "output.times=[0.5, 1.0]"]));
    let first = driver::run(&problem, &params, &plan, &options(&dir)).unwrap();
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();

    let error = driver::run(&problem, &params, &plan, &options(&dir)).unwrap_err();
    assert!(matches!(error, Error::Folder(_)), "{error}");
    assert!(error.to_string().contains("--overwrite"), "{error}");
    assert_eq!(
        summary(&dir)["run_id"],
        first.run_id.as_str(),
        "the refused run touched nothing"
    );

    // A shorter run with --overwrite leaves none of the first run's frames.
    let short = coarse(&["time.steps=2", "output.times=[1.0]"]);
    let short_problem = short.build().unwrap();
    let overwrite = RunOptions {
        overwrite: true,
        ..options(&dir)
    };
    let second = driver::run(&short_problem, &short.solver_params(), &short.output_plan(), &overwrite).unwrap();
    assert_ne!(second.run_id, first.run_id);
    assert_eq!(summary(&dir)["run_id"], second.run_id.as_str());
    assert_eq!(vtu_files(&dir), vec!["solution_0002.vtu".to_string()]);
    assert_eq!(pvd_files(&dir), vtu_files(&dir));
    assert_eq!(std::fs::read_to_string(dir.join("notes.txt")).unwrap(), "mine");
    let steps = std::fs::read_to_string(dir.join("steps.csv")).unwrap();
    assert_eq!(steps.lines().count(), 3, "a header and a line per step:\n{steps}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_stopped_run_keeps_its_frames_and_continues_to_the_bits_of_the_uninterrupted_run() {
    let (problem, params, plan) = parts(&scenario());

    let whole = scratch("whole");
    let reference = driver::run(&problem, &params, &plan, &options(&whole)).unwrap();
    assert_eq!(reference.status, RunStatus::Completed);
    assert!(!whole.join(CHECKPOINT_FILE).exists());

    // Stopped after step 5, as SIGTERM does (the flag set while step 5 runs).
    let dir = scratch("stopped");
    let stop = StopFlag::new();
    let stopping = RunOptions {
        stop: Some(stop.clone()),
        ..options(&dir)
    };
    let error = driver::run_observed(&problem, &params, &plan, &stopping, |_, state, _| {
        if state.n == 5 {
            stop.request(Interruption::Terminate);
        }
    })
    .err()
    .unwrap();
    assert!(
        matches!(
            error,
            Error::Interrupted {
                step: 5,
                cause: Interruption::Terminate,
                ..
            }
        ),
        "{error}"
    );
    let stopped = summary(&dir);
    assert_eq!(stopped["status"], "interrupted");
    assert_eq!(stopped["failure"]["interrupted"], "terminate");
    assert_eq!(stopped["failure"]["last_step"], 5);
    // The frames of steps 2 and 4, and the last state (5): all listed, all present.
    assert_eq!(
        vtu_files(&dir),
        ["solution_0002.vtu", "solution_0004.vtu", "solution_0005.vtu"].map(String::from)
    );
    assert_eq!(pvd_files(&dir), vtu_files(&dir));
    same_bytes(&whole, &dir, &["solution_0002.vtu".into(), "solution_0004.vtu".into()]);
    assert_no_temporary_files(&dir);

    // Continued from the checkpoint of step 5: every frame and the final fields bit for bit.
    let restart = Restart::read(&dir.join(CHECKPOINT_FILE)).unwrap();
    assert_eq!(restart.checkpoint.state.n, 5);
    let continuing = RunOptions {
        restart: Some(restart),
        ..options(&dir)
    };
    let continued = driver::run(&problem, &params, &plan, &continuing).unwrap();
    assert_eq!(continued.status, RunStatus::Completed);
    assert_eq!(continued.restarts, vec![5]);
    assert_eq!(continued.run_id, summary(&dir)["run_id"].as_str().unwrap());
    let frames: Vec<String> = (1..=8).map(|i| format!("solution_{:04}.vtu", 2 * i)).collect();
    assert_eq!(vtu_files(&dir), frames, "the stop's own frame of step 5 is gone");
    assert_eq!(pvd_files(&dir), frames);
    same_bytes(&whole, &dir, &frames);
    let csvs: Vec<String> = (1..=8).map(|i| format!("contact_{:04}.csv", 2 * i)).collect();
    same_bytes(&whole, &dir, &csvs);
    // The whole run's figures, not the continued part's: the iterations, and the loop's work
    // (linear solves and sweeps, Krylov iterations), which the checkpoint carries.
    assert_eq!(
        continued.convexification_iterations,
        reference.convexification_iterations
    );
    assert!(reference.linear_solves > 0 && reference.full_sweeps > 0);
    assert_eq!(continued.linear_solves, reference.linear_solves);
    assert_eq!(continued.full_sweeps, reference.full_sweeps);
    assert_eq!(continued.krylov_iterations, reference.krylov_iterations);
    for key in ["linear_solves", "full_sweeps", "krylov_iterations", "newton_iterations"] {
        assert_eq!(summary(&dir)[key], summary(&whole)[key], "{key}");
    }
    assert_eq!(continued.outputs.len(), reference.outputs.len());
    // steps.csv: every row as the uninterrupted run's, bit for bit, but the wall times (the
    // rows before the stop travel through the checkpoint's JSON header).
    assert_eq!(steps_without_seconds(&dir), steps_without_seconds(&whole));
    assert_eq!(steps_without_seconds(&dir).len(), 17);

    // A checkpoint of another problem is refused, naming what differs.
    let other = coarse(&["material.density=50"]);
    let other_problem = other.build().unwrap();
    let stopped_again = scratch("other");
    std::fs::create_dir_all(&stopped_again).unwrap();
    let error = driver::run(
        &other_problem,
        &other.solver_params(),
        &other.output_plan(),
        &RunOptions {
            restart: Some(Restart::read(&whole_checkpoint(&problem, &plan, &stopped_again)).unwrap()),
            ..options(&stopped_again)
        },
    )
    .unwrap_err();
    assert!(error.to_string().contains("another scenario"), "{error}");
    for d in [whole, dir, stopped_again] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// A checkpoint of `problem` at step 3, written into `dir` by a run stopped there.
fn whole_checkpoint(problem: &thermocontact::Problem, plan: &OutputPlan, dir: &Path) -> PathBuf {
    let stop = StopFlag::new();
    let scratch_dir = dir.join("first");
    let params = scenario().solver_params();
    let options = RunOptions {
        stop: Some(stop.clone()),
        ..options(&scratch_dir)
    };
    let _ = driver::run_observed(problem, &params, plan, &options, |_, state, _| {
        if state.n == 3 {
            stop.request(Interruption::Caller);
        }
    });
    scratch_dir.join(CHECKPOINT_FILE)
}

/// The CLI under signals: SIGTERM stops after the step with exit code 143 and a complete
/// folder; SIGKILL after a periodic checkpoint loses only the steps since, and `--restart`
/// continues either to the bits of the uninterrupted run.
#[test]
fn the_cli_stops_on_sigterm_survives_sigkill_and_restarts() {
    let args = [
        "--set",
        "mesh.nx=8",
        "--set",
        "mesh.ny=2",
        "--set",
        "time.steps=3000",
        "--set",
        "output.times=[0.5, 1.0]",
        "--set",
        "output.checkpoint_every=200",
    ];
    let whole = scratch("cli-whole");
    let status = bin()
        .args(["run", "--quiet", "--out"])
        .arg(&whole)
        .args(args)
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());

    for (signal, code) in [("-TERM", Some(143)), ("-KILL", None)] {
        let dir = scratch(&format!("cli{signal}"));
        let mut child = bin()
            .args(["run", "--quiet", "--out"])
            .arg(&dir)
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // After the first periodic checkpoint, and long before the end.
        wait_for(&dir.join(CHECKPOINT_FILE));
        let killed = Command::new("kill")
            .arg(signal)
            .arg(child.id().to_string())
            .status()
            .unwrap();
        assert!(killed.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), code, "{signal}: {status:?}");
        let stopped = summary(&dir);
        match code {
            Some(_) => {
                assert_eq!(stopped["status"], "interrupted");
                assert_eq!(pvd_files(&dir), vtu_files(&dir));
            }
            // Killed outright: the summary still says running, the checkpoint is whole.
            None => assert_eq!(stopped["status"], "running"),
        }
        let restarted = bin().args(["run", "--quiet", "--restart"]).arg(&dir).output().unwrap();
        assert!(
            restarted.status.success(),
            "{}",
            String::from_utf8_lossy(&restarted.stderr)
        );
        assert_eq!(summary(&dir)["status"], "completed");
        let frames = vec!["solution_1500.vtu".to_string(), "solution_3000.vtu".to_string()];
        assert_eq!(vtu_files(&dir), frames);
        same_bytes(&whole, &dir, &frames);
        std::fs::remove_dir_all(&dir).unwrap();
    }
    std::fs::remove_dir_all(&whole).unwrap();
}

/// A failed run continued to the end leaves no checkpoint, even without `checkpoint_every`
/// (a stale one made `--restart` silently compute the end again), and the folder it leaves is
/// refused without the offer to `--restart` it (there is nothing to continue).
#[test]
fn a_failed_run_continued_to_the_end_leaves_no_checkpoint() {
    let dir = scratch("cli-failed");
    let small = ["--set", "mesh.nx=16", "--set", "mesh.ny=4", "--set", "time.steps=16"];
    let failing = [
        "--set",
        "solver.cutback=false",
        "--set",
        "solver.max_sweeps=0",
        "--set",
        "solver.max_convexification=5",
    ];
    let failed = bin()
        .args(["run", "--quiet"])
        .args(small)
        .args(failing)
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&failed.stderr);
    assert_eq!(failed.status.code(), Some(1), "{stderr}");
    assert_eq!(summary(&dir)["status"], "failed");
    assert!(dir.join(CHECKPOINT_FILE).exists());
    assert!(
        stderr.contains(&format!(
            "checkpoint.bin to continue with `thermocontact run --restart {}`",
            dir.display()
        )),
        "{stderr}"
    );

    let continued = bin()
        .args(["run", "--quiet", "--restart"])
        .arg(&dir)
        .args(["--set", "solver.max_convexification=200"])
        .output()
        .unwrap();
    assert!(
        continued.status.success(),
        "{}",
        String::from_utf8_lossy(&continued.stderr)
    );
    assert_eq!(summary(&dir)["status"], "completed");
    assert!(
        !dir.join(CHECKPOINT_FILE).exists(),
        "a completed run keeps no checkpoint"
    );

    let again = bin()
        .args(["run", "--quiet"])
        .args(small)
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&again.stderr);
    assert_eq!(again.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("holds the results of another run") && stderr.contains("--overwrite"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("--restart"),
        "no checkpoint to continue from: {stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `initial.from`: a checkpoint's fields become the initial data of another run on the same
/// mesh; a checkpoint of another mesh is refused, naming the key.
#[test]
fn initial_fields_come_from_a_checkpoint_of_the_same_mesh() {
    let dir = scratch("initial-from");
    let (problem, _, plan) = parts(&scenario());
    let checkpoint = whole_checkpoint(&problem, &plan, &dir);
    let state = Restart::read(&checkpoint).unwrap().checkpoint.state;
    assert_eq!(state.n, 3);
    assert!(state.u.iter().any(|&u| u != 0.0));

    let from = format!("initial.from={:?}", checkpoint.display().to_string());
    let next = coarse(&[from.as_str(), "material.density=50"]).build().unwrap();
    let close = |a: &[f64], b: &[f64]| {
        let scale = b.iter().fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()));
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * scale)
    };
    assert!(close(&next.initial.displacement, &state.u));
    assert!(close(&next.initial.velocity, &state.w));
    assert_eq!(next.initial.temperature, state.theta);

    let other_mesh = coarse(&[from.as_str(), "mesh.nx=12"]).build().unwrap_err().to_string();
    assert!(
        other_mesh.contains("initial.from") && other_mesh.contains("mesh"),
        "{other_mesh}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The arrays of a `.vtu` as vtkio reads them back, by name (point arrays, then cell arrays).
fn vtu_arrays(path: &Path) -> Vec<(String, Vec<f64>)> {
    use vtkio::model::{Attribute, DataSet, Vtk};
    let vtk = Vtk::import(path).unwrap();
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("{} is not an unstructured grid", path.display())
    };
    let piece = pieces[0].load_piece_data(None).unwrap();
    let attributes = piece.data.point.iter().chain(&piece.data.cell);
    attributes
        .filter_map(|a| match a {
            Attribute::DataArray(d) => Some((d.name.clone(), d.data.clone().into_vec::<f64>().unwrap())),
            _ => None,
        })
        .collect()
}

/// Output levels: the times (0 is the initial state) and every `output.every`-th level; the
/// initial frame holds u₀, θ₀; compressed frames hold the values of uncompressed ones, exactly,
/// in half the bytes or less.
#[test]
fn frames_at_the_initial_state_every_nth_step_and_compressed() {
    let every = coarse(&["time.steps=8", "output.times=[0.0, 0.3]", "output.every=3"]);
    assert_eq!(every.output_steps(), vec![0, 2, 3, 6]);
    let (dir, raw_dir) = (scratch("every"), scratch("every-raw"));
    let problem = every.build().unwrap();
    let run = driver::run(&problem, &every.solver_params(), &every.output_plan(), &options(&dir)).unwrap();
    let levels: Vec<usize> = run.outputs.iter().map(|o| o.n).collect();
    assert_eq!(levels, vec![0, 2, 3, 6]);
    let names = vtu_files(&dir);
    assert_eq!(
        names,
        [
            "solution_0000.vtu",
            "solution_0002.vtu",
            "solution_0003.vtu",
            "solution_0006.vtu"
        ]
    );
    assert_eq!(pvd_files(&dir), names);

    let initial = vtu_arrays(&dir.join("solution_0000.vtu"));
    let field = |name: &str| &initial.iter().find(|(n, _)| n == name).unwrap().1;
    assert!(field("temperature").iter().all(|&t| t == 25.0), "θ₀ = 25");
    assert!(field("displacement").iter().all(|&u| u == 0.0), "u₀ = 0");

    let raw = coarse(&[
        "time.steps=8",
        "output.times=[0.0, 0.3]",
        "output.every=3",
        "output.compress=false",
    ]);
    driver::run(&problem, &raw.solver_params(), &raw.output_plan(), &options(&raw_dir)).unwrap();
    for name in &names {
        let (zipped, plain) = (dir.join(name), raw_dir.join(name));
        assert_eq!(vtu_arrays(&zipped), vtu_arrays(&plain), "{name}");
        let size = |p: &Path| std::fs::metadata(p).unwrap().len();
        assert!(
            2 * size(&zipped) < size(&plain) + 2048,
            "{name}: {} against {}",
            size(&zipped),
            size(&plain)
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&raw_dir).unwrap();
}

/// The regular files of `dir` whose names end with `suffix`, sorted.
fn files_ending(dir: &Path, suffix: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_type().unwrap().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(suffix))
        .collect();
    names.sort();
    names
}

/// The frames written on the writer thread are the bytes of those written on the time loop's
/// thread (`inline_frames`), with a frame at every step (the loop gets ahead of the writer and
/// waits) and checkpoints in between (the loop waits for the frames before each).
#[test]
fn frames_from_the_writer_thread_are_the_bytes_of_inline_frames() {
    let (problem, params, plan) = parts(&coarse(&["output.every=1", "output.checkpoint_every=5"]));
    let (threaded, inline) = (scratch("threaded"), scratch("inline"));
    let a = driver::run(&problem, &params, &plan, &options(&threaded)).unwrap();
    let inline_options = RunOptions {
        inline_frames: true,
        ..options(&inline)
    };
    let b = driver::run(&problem, &params, &plan, &inline_options).unwrap();
    assert_eq!(a.status, RunStatus::Completed);
    assert_eq!(b.status, RunStatus::Completed);

    let frames: Vec<String> = (1..=16).map(|n| format!("solution_{n:04}.vtu")).collect();
    assert_eq!(files_ending(&threaded, ".vtu"), frames);
    assert_eq!(files_ending(&inline, ".vtu"), frames);
    assert_eq!(pvd_files(&threaded), frames);
    let mut names = frames;
    names.extend(
        files_ending(&inline, ".csv")
            .into_iter()
            .filter(|n| n.starts_with("contact_")),
    );
    names.push("solution.pvd".into());
    assert_eq!(names.len(), 16 + 16 + 1, "{names:?}");
    same_bytes(&threaded, &inline, &names);
    let levels = |s: &driver::Summary| s.outputs.iter().map(|o| o.n).collect::<Vec<_>>();
    assert_eq!(levels(&a), (1..=16).collect::<Vec<_>>());
    assert_eq!(levels(&a), levels(&b));
    assert!(a.timings.frames > 0.0 && b.timings.frames > 0.0);
    for d in [threaded, inline] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// An I/O error of a frame (a folder where `solution_0006.vtu` goes) stops the run, on the
/// writer thread as on the loop's: the error names the file, and the folder stays consistent —
/// `solution.pvd` lists exactly the `.vtu` files present, each whole; no temporary file is
/// left; `summary.json` says `failed`, with no output record of the failed frame; the last state
/// is kept as a checkpoint and a frame.
#[test]
fn an_io_error_of_a_frame_stops_the_run_and_leaves_a_consistent_folder() {
    let (problem, params, plan) = parts(&scenario());
    let whole = scratch("io-whole");
    driver::run(&problem, &params, &plan, &options(&whole)).unwrap();
    for inline_frames in [false, true] {
        let dir = scratch(&format!("io-error-{inline_frames}"));
        let obstacle = dir.join("solution_0006.vtu");
        let failing = RunOptions {
            inline_frames,
            ..options(&dir)
        };
        let error = driver::run_observed(&problem, &params, &plan, &failing, |_, state, _| {
            if state.n == 3 {
                std::fs::create_dir(&obstacle).unwrap();
            }
        })
        .err()
        .unwrap();
        assert!(
            matches!(&error, Error::Output(thermocontact::output::OutputError::Io { path, .. }) if *path == obstacle),
            "{error}"
        );
        let stopped = summary(&dir);
        assert_eq!(stopped["status"], "failed", "{stopped}");
        assert!(
            stopped["failure"]["message"]
                .as_str()
                .unwrap()
                .contains("solution_0006.vtu"),
            "{stopped}"
        );
        let last = stopped["failure"]["last_step"].as_u64().unwrap() as usize;
        // Inline, the run stops at the frame; on the writer thread, once the loop hears of it.
        if inline_frames {
            assert_eq!(last, 6);
        } else {
            assert!((6..=10).contains(&last), "{last}");
        }
        let recorded: Vec<u64> = stopped["outputs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|o| o["n"].as_u64().unwrap())
            .collect();
        assert_eq!(recorded, [2, 4]);

        let present = files_ending(&dir, ".vtu");
        assert_eq!(pvd_files(&dir), present);
        let mut expected = vec!["solution_0002.vtu".to_string(), "solution_0004.vtu".to_string()];
        if last != 6 {
            // The last state's frame (at 6 it is the obstacle's place again).
            expected.push(format!("solution_{last:04}.vtu"));
        }
        assert_eq!(present, expected);
        for name in &present {
            assert_eq!(vtu_arrays(&dir.join(name)).len(), 7, "{name} is whole");
        }
        same_bytes(&whole, &dir, &expected[..2]);
        assert_no_temporary_files(&dir);
        let restart = Restart::read(&dir.join(CHECKPOINT_FILE)).unwrap();
        assert_eq!(restart.checkpoint.state.n, last);
        assert_eq!(
            steps_without_seconds(&dir).len(),
            last + 1,
            "steps.csv: a header and a row per step"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
    std::fs::remove_dir_all(&whole).unwrap();
}
