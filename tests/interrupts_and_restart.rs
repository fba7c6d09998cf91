//! Issue 26, the driver's part: input and interruptions that must leave a folder a user can go
//! on with. Two Ctrl-C still leave a folder that continues to the bits of the uninterrupted run;
//! a run started from another run's checkpoint (`initial.from`) continues after that checkpoint
//! is gone; the README's first command runs twice (a completed run in the default folder is
//! replaced, nothing else is) and no finished folder keeps the lock file; a refused restart names
//! the keys that differ, a restart says which output times it cannot write, and contradicting
//! `--set`s are refused naming both.
//!
//! The CLI is run as a child process (the built binary), as a user runs it.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

use common::{assert_no_temporary_files, bin, same_bytes, steps_without_seconds, summary, wait_for};
use thermocontact::driver::{self, Restart, RunOptions, StopFlag, CHECKPOINT_FILE};
use thermocontact::{Error, Interruption};

const LOCK: &str = ".thermocontact.lock";

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-i26-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `thermocontact run --quiet ARGS`, its output captured.
fn run(args: &[&str]) -> Output {
    bin().arg("run").arg("--quiet").args(args).output().unwrap()
}

fn text(output: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

fn ok(output: Output) -> Output {
    assert!(output.status.success(), "{}", text(&output));
    output
}

fn names(dir: &Path, keep: impl Fn(&str) -> bool) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| keep(n))
        .collect();
    names.sort();
    names
}

/// The frames a `.pvd` lists.
fn pvd_files(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("solution.pvd")).unwrap();
    let mut files: Vec<String> = text
        .split("file=\"")
        .skip(1)
        .map(|rest| rest.split('"').next().unwrap().to_string())
        .collect();
    files.sort();
    files
}

fn signal(child: &std::process::Child, name: &str) {
    let sent = Command::new("kill")
        .arg(name)
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(sent.success());
}

/// The whole output of a run (frames, contact CSVs, steps.csv) equals the uninterrupted run's.
fn assert_same_run(whole: &Path, dir: &Path) {
    let frames = names(whole, |n| n.ends_with(".vtu") || n.starts_with("contact_"));
    assert!(!frames.is_empty());
    assert_eq!(names(dir, |n| n.ends_with(".vtu") || n.starts_with("contact_")), frames);
    same_bytes(whole, dir, &frames);
    assert_eq!(steps_without_seconds(dir), steps_without_seconds(whole));
}

/// Finding 11: a second Ctrl-C, sent while the run still finishes the step of the first, used
/// to end the process at once (status `running`, no checkpoint without `checkpoint_every`,
/// sometimes a temporary file and a frame missing from the `.pvd`). It now leaves a folder that
/// says `interrupted`, lists its frames, and continues to the bits of the uninterrupted run.
#[test]
fn a_second_ctrl_c_still_leaves_a_folder_that_continues() {
    // Steps of some tens of milliseconds, and a frame of a 256 × 64 mesh to write at the stop.
    let args = [
        "--set",
        "mesh.nx=256",
        "--set",
        "mesh.ny=64",
        "--set",
        "time.steps=200",
        "--set",
        "output.times=[0.25, 0.5, 0.75, 1.0]",
    ];
    let whole = scratch("twice-whole");
    ok(bin()
        .args(["run", "--quiet", "--out"])
        .arg(&whole)
        .args(args)
        .output()
        .unwrap());

    let dir = scratch("twice");
    let child = bin()
        .args(["run", "--quiet", "--out"])
        .arg(&dir)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The march has begun (summary.json is written just before it), and is far from the end.
    wait_for(&dir.join("summary.json"));
    std::thread::sleep(Duration::from_millis(300));
    signal(&child, "-INT");
    std::thread::sleep(Duration::from_millis(15));
    signal(&child, "-INT");
    let stopped = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&stopped.stderr).into_owned();
    assert_eq!(stopped.status.code(), Some(130), "{stderr}");
    assert!(!stderr.contains("loses that step"), "{stderr}");
    assert_eq!(summary(&dir)["status"], "interrupted", "{stderr}");
    assert!(dir.join(CHECKPOINT_FILE).exists(), "{stderr}");
    assert_no_temporary_files(&dir);
    assert_eq!(pvd_files(&dir), names(&dir, |n| n.ends_with(".vtu")));
    assert!(!dir.join(LOCK).exists(), "the lock file stays after an interruption");

    let restarted = ok(run(&["--restart", dir.to_str().unwrap()]));
    assert!(text(&restarted).contains("continuing from step"));
    assert_eq!(summary(&dir)["status"], "completed");
    assert_same_run(&whole, &dir);
    assert_no_temporary_files(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&whole).unwrap();
}

/// Finding 11, the library's side: a stop requested "now" (what the CLI's second Ctrl-C asks)
/// cuts the step it is on short; the run ends at the last completed step, `interrupted`, with its
/// checkpoint, and continues to the bits of the uninterrupted run. (Here the request comes
/// between two steps, so that the step it cuts is known: step 6, stopped before its first solve.)
#[test]
fn a_stop_requested_now_ends_at_the_last_completed_step_and_continues() {
    let scenario = common::coarse(&["output.times=[0.25, 0.5, 0.75, 1.0]"]);
    let problem = scenario.build().unwrap();
    let (params, plan) = (scenario.solver_params(), scenario.output_plan());
    let root = scratch("now");
    let whole = root.join("whole");
    let into = |dir: &Path| RunOptions {
        out_dir: Some(dir.to_path_buf()),
        ..RunOptions::default()
    };
    driver::run(&problem, &params, &plan, &into(&whole)).unwrap();

    let dir = root.join("cut");
    let stop = StopFlag::new();
    let options = RunOptions {
        stop: Some(stop.clone()),
        ..into(&dir)
    };
    let mut seen = Vec::new();
    let stopped = driver::run_observed(&problem, &params, &plan, &options, |_, state, _| {
        seen.push(state.n);
        if state.n == 5 {
            stop.now().store(true, std::sync::atomic::Ordering::SeqCst);
        }
    });
    let error = stopped.err().unwrap();
    assert!(matches!(error, Error::Interrupted { step: 5, .. }), "{error}");
    assert_eq!(seen, [1, 2, 3, 4, 5]);
    assert_eq!(summary(&dir)["status"], "interrupted");
    assert_no_temporary_files(&dir);
    assert_eq!(pvd_files(&dir), names(&dir, |n| n.ends_with(".vtu")));

    let restart = Restart::read(&dir.join(CHECKPOINT_FILE)).unwrap();
    assert_eq!(restart.checkpoint.state.n, 5);
    let continuing = RunOptions {
        restart: Some(restart),
        ..into(&dir)
    };
    driver::run(&problem, &params, &plan, &continuing).unwrap();
    assert_eq!(summary(&dir)["status"], "completed");
    assert_same_run(&whole, &dir);
    std::fs::remove_dir_all(&root).unwrap();
}

/// A checkpoint of the coarse example at step 3, in `dir` (a run stopped there).
fn checkpoint_at_step_3(dir: &Path) -> PathBuf {
    let scenario = common::coarse(&[]);
    let problem = scenario.build().unwrap();
    let stop = StopFlag::new();
    let options = RunOptions {
        out_dir: Some(dir.to_path_buf()),
        stop: Some(stop.clone()),
        ..RunOptions::default()
    };
    let stopped = driver::run_observed(
        &problem,
        &scenario.solver_params(),
        &scenario.output_plan(),
        &options,
        |_, state, _| {
            if state.n == 3 {
                stop.request(Interruption::Caller);
            }
        },
    );
    assert!(stopped.is_err());
    dir.join(CHECKPOINT_FILE)
}

/// Finding 12: a run started from another run's checkpoint (`initial.from`) continues with
/// `--restart` after that checkpoint is gone (a completed run removes its checkpoint): the state
/// comes from the run's own checkpoint, and `initial.from` is not read again.
#[test]
fn a_run_from_another_runs_checkpoint_restarts_after_that_checkpoint_is_gone() {
    let root = scratch("initial-from");
    let source = checkpoint_at_step_3(&root.join("a"));
    let from = format!("initial.from={:?}", source.display().to_string());
    let args = [
        "--set",
        "mesh.nx=16",
        "--set",
        "mesh.ny=4",
        "--set",
        "time.steps=3000",
        "--set",
        "output.times=[0.5, 1.0]",
        "--set",
        "output.checkpoint_every=200",
        "--set",
        from.as_str(),
    ];
    let whole = root.join("b-whole");
    ok(bin()
        .args(["run", "--quiet", "--out"])
        .arg(&whole)
        .args(args)
        .output()
        .unwrap());

    let dir = root.join("b");
    let mut child = bin()
        .args(["run", "--quiet", "--out"])
        .arg(&dir)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&dir.join(CHECKPOINT_FILE));
    signal(&child, "-KILL");
    child.wait().unwrap();

    std::fs::remove_file(&source).unwrap();
    let restarted = ok(run(&["--restart", dir.to_str().unwrap()]));
    assert!(text(&restarted).contains("continuing from step"));
    assert_eq!(summary(&dir)["status"], "completed");
    let frames = vec!["solution_1500.vtu".to_string(), "solution_3000.vtu".to_string()];
    assert_eq!(names(&dir, |n| n.ends_with(".vtu")), frames);
    same_bytes(&whole, &dir, &frames);
    same_bytes(&whole, &dir, &["contact_1500.csv".into(), "contact_3000.csv".into()]);
    std::fs::remove_dir_all(&root).unwrap();
}

const SMALL: [&str; 6] = ["--set", "mesh.nx=8", "--set", "mesh.ny=2", "--set", "time.steps=8"];

/// Finding 15: the README's first command, run a second time, replaces the completed run in the
/// default folder (saying so); an explicit `--out` still refuses it; a run that did not complete
/// is not replaced; a user's own file stays; no finished folder keeps `.thermocontact.lock`.
#[test]
fn the_default_folder_takes_a_new_run_in_place_of_a_completed_one() {
    let root = scratch("default-out");
    std::fs::create_dir_all(&root).unwrap();
    let here = |args: &[&str]| {
        bin()
            .current_dir(&root)
            .arg("run")
            .arg("--quiet")
            .args(args)
            .output()
            .unwrap()
    };
    let out = root.join("out");
    let first = ok(here(&SMALL));
    assert!(!text(&first).contains("replacing"), "{}", text(&first));
    assert!(!out.join(LOCK).exists(), "the lock file stays after a completed run");
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let first_id = summary(&out)["run_id"].clone();

    // Again, with another number of steps: the old run's frames go.
    let again = ok(here(&[
        "--set",
        "mesh.nx=8",
        "--set",
        "mesh.ny=2",
        "--set",
        "time.steps=4",
    ]));
    assert!(
        text(&again).contains(&"replacing the completed run in out/".to_string()),
        "{}",
        text(&again)
    );
    assert_ne!(summary(&out)["run_id"], first_id);
    assert_eq!(summary(&out)["steps"], 4);
    assert!(!out.join("solution_0008.vtu").exists(), "a frame of the old run stays");
    assert_eq!(std::fs::read_to_string(out.join("notes.txt")).unwrap(), "mine");
    assert!(!out.join(LOCK).exists());

    // An explicit --out keeps the refusal.
    let refused = here(&[&SMALL[..], &["--out", "out"]].concat());
    assert!(!refused.status.success());
    assert!(text(&refused).contains("--overwrite"), "{}", text(&refused));
    assert!(!out.join(LOCK).exists(), "a refused claim leaves the lock file");

    // A run that did not complete (here: failed at once, a load that is NaN) is not replaced.
    let failed = here(&[
        "--set",
        "mesh.nx=8",
        "--set",
        "mesh.ny=2",
        "--set",
        "time.steps=8",
        "--out",
        "stopped",
        "--set",
        "loads.body_force=[\"0\", \"sqrt(-1)\"]",
    ]);
    let stopped_dir = root.join("stopped");
    if !failed.status.success() && stopped_dir.join("summary.json").exists() {
        assert!(
            !stopped_dir.join(LOCK).exists(),
            "the lock file stays after a failed run"
        );
    }
    std::fs::write(out.join("summary.json"), r#"{"status": "interrupted"}"#).unwrap();
    let kept = here(&SMALL);
    assert!(!kept.status.success(), "{}", text(&kept));
    assert!(text(&kept).contains("--overwrite"), "{}", text(&kept));
    assert_eq!(summary(&out)["status"], "interrupted");
    std::fs::remove_dir_all(&root).unwrap();
}

/// A killed run's lock file stays, unlocked: the next run takes the folder as before.
#[test]
fn a_killed_runs_lock_is_still_stale() {
    let dir = scratch("stale-lock");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(LOCK), "process 1").unwrap();
    ok(run(&[&SMALL[..], &["--out", dir.to_str().unwrap()]].concat()));
    assert_eq!(summary(&dir)["status"], "completed");
    assert!(!dir.join(LOCK).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A folder stopped after step 3 of the coarse example, with its `scenario.toml`, through the CLI
/// (SIGKILL after a periodic checkpoint).
fn stopped_folder(dir: &Path, args: &[&str]) {
    let mut child = bin()
        .args(["run", "--quiet", "--out"])
        .arg(dir)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&dir.join(CHECKPOINT_FILE));
    signal(&child, "-KILL");
    child.wait().unwrap();
}

const LONG: [&str; 10] = [
    "--set",
    "mesh.nx=8",
    "--set",
    "mesh.ny=2",
    "--set",
    "time.steps=3000",
    "--set",
    "output.times=[0.5, 1.0]",
    "--set",
    "output.checkpoint_every=1000",
];

/// Finding 14 (a): a restart with another scenario is refused naming the keys that differ (with
/// both values), not two 64-hex digests.
#[test]
fn a_refused_restart_names_the_keys_that_differ() {
    let dir = scratch("refused-restart");
    stopped_folder(&dir, &LONG);
    let other = dir.join("other.toml");
    let echo = std::fs::read_to_string(dir.join("scenario.toml")).unwrap();
    std::fs::write(&other, echo).unwrap();
    let refused = run(&[
        other.to_str().unwrap(),
        "--restart",
        dir.to_str().unwrap(),
        "--set",
        "material.density=50",
    ]);
    assert!(!refused.status.success());
    let message = text(&refused);
    assert!(message.contains("material.density"), "{message}");
    assert!(message.contains("50"), "{message}");
    let hex64 = message.split(|c: char| !c.is_ascii_hexdigit()).any(|w| w.len() == 64);
    assert!(!hex64, "{message}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Finding 14 (b): output times at or before the checkpoint cannot be written by a continued
/// run; it says so (how many, which) instead of dropping them silently, and continues.
#[test]
fn a_restart_says_which_output_times_it_cannot_write() {
    let dir = scratch("skipped-times");
    stopped_folder(&dir, &LONG);
    let continued = ok(run(&[
        "--restart",
        dir.to_str().unwrap(),
        "--set",
        "output.times=[0.01, 0.02, 0.5, 1.0]",
    ]));
    let message = text(&continued);
    assert!(message.contains("warning: 2 output time(s)"), "{message}");
    assert!(message.contains("0.01, 0.02"), "{message}");
    assert_eq!(summary(&dir)["status"], "completed");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Finding 14 (c): `--set friction=1 --set friction.bound=2` is refused naming both (the first
/// vanished without a word); a key given twice is a warning, the later value used.
#[test]
fn contradicting_overrides_are_refused_and_repeated_ones_warned() {
    let dir = scratch("overrides");
    let refused = run(&[
        "--set",
        "friction=1",
        "--set",
        "friction.bound=2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(!refused.status.success());
    let message = text(&refused);
    assert!(
        message.contains("friction=1") && message.contains("friction.bound=2"),
        "{message}"
    );
    assert!(!message.contains("panicked"), "{message}");
    assert!(!dir.exists(), "a refused scenario writes nothing");

    let twice = ok(run(&[
        &SMALL[..],
        &["--set", "mesh.nx=4", "--out", dir.to_str().unwrap()],
    ]
    .concat()));
    let message = text(&twice);
    assert!(message.contains("warning: --set mesh.nx is given twice"), "{message}");
    assert_eq!(summary(&dir)["nodes"], 5 * 3);
    std::fs::remove_dir_all(&dir).unwrap();
}
