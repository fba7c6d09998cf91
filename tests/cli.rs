//! The command line as a user meets it: files written, errors named, exit codes.

use std::path::PathBuf;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_thermocontact"))
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn run_writes_summary_vtk_series_and_contact_csvs() {
    let out = scratch("run");
    let status = bin()
        .args(["run", "--quiet", "--set", "mesh.nx=16", "--set", "mesh.ny=4", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
    let stdout = String::from_utf8_lossy(&status.stdout);
    assert!(stdout.contains("wall time"), "{stdout}");
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let outputs = summary["outputs"].as_array().unwrap();
    let times: Vec<f64> = outputs.iter().map(|o| o["t"].as_f64().unwrap()).collect();
    assert_eq!(times, vec![0.25, 0.5, 0.75, 1.0]);
    for o in outputs {
        let n = o["n"].as_u64().unwrap();
        assert!(out.join(format!("solution_{n:04}.vtu")).is_file());
        let csv = std::fs::read_to_string(out.join(format!("contact_{n:04}.csv"))).unwrap();
        assert!(csv.starts_with("x,y,nu_x,nu_y,w_tau,xi,bound,slip,theta\n"), "{csv}");
        let slip_in_csv = csv.lines().skip(1).filter(|l| l.split(',').nth(7) == Some("1")).count();
        // The paper's Γ_C is the bottom: every node's normal is (0, −1).
        assert!(
            csv.lines()
                .skip(1)
                .all(|l| l.split(',').nth(2) == Some("0") && l.split(',').nth(3) == Some("-1")),
            "{csv}"
        );
        assert_eq!(slip_in_csv as u64, o["slip_nodes"].as_u64().unwrap());
        assert_eq!(
            csv.lines().count() - 1,
            summary["contact_nodes"].as_u64().unwrap() as usize
        );
    }
    let pvd = std::fs::read_to_string(out.join("solution.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 4);
    // The resolved scenario is saved and loads back to the same run.
    let saved = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    let again = thermocontact::Scenario::load(Some(&saved), &[]).unwrap();
    assert_eq!(again.mesh.nx, Some(16));
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn bad_scenario_keys_and_values_exit_non_zero_naming_the_key() {
    let out = scratch("bad");
    let result = bin()
        .args(["run", "--quiet", "--set", "solver.tolerence=1e-6", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(stderr.contains("solver.tolerence"), "{stderr}");
    assert!(!out.exists(), "nothing is written for an invalid scenario");

    let file = std::env::temp_dir().join(format!("thermocontact-bad-{}.toml", std::process::id()));
    std::fs::write(&file, "[time]\nsteps = -4\n").unwrap();
    let result = bin()
        .args(["run", "--quiet"])
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(stderr.contains("time.steps") && stderr.contains("-4"), "{stderr}");
    std::fs::remove_file(&file).ok();
}

#[test]
fn scenario_prints_the_default_as_a_loadable_file() {
    let result = bin().arg("scenario").output().unwrap();
    assert!(result.status.success());
    let text = String::from_utf8(result.stdout).unwrap();
    assert!(text.contains("# thermocontact scenario"));
    assert_eq!(
        thermocontact::Scenario::load(Some(&text), &[]).unwrap(),
        thermocontact::Scenario::default()
    );
}

/// The front page stays a front page, and the scenario reference documents every key of the
/// default scenario (docs/scenario.md, one row per `table.key`), so that neither is a copy to
/// keep in step by hand.
#[test]
fn readme_is_a_front_page_and_the_scenario_reference_covers_every_default_key() {
    let readme = include_str!("../README.md");
    assert!(
        readme.lines().count() <= 250,
        "README.md is {} lines",
        readme.lines().count()
    );
    assert!(
        include_str!("../.ci/run").contains("cargo test"),
        ".ci/run runs the README's test command"
    );
    fn keys(prefix: &str, value: &toml::Value, out: &mut Vec<String>) {
        match value {
            toml::Value::Table(table) => {
                for (key, value) in table {
                    let path = if prefix.is_empty() {
                        key.clone()
                    } else {
                        format!("{prefix}.{key}")
                    };
                    keys(&path, value, out);
                }
            }
            toml::Value::Array(items) if items.iter().all(toml::Value::is_table) && !items.is_empty() => {
                items.iter().for_each(|item| keys(prefix, item, out));
            }
            _ => out.push(prefix.to_string()),
        }
    }
    let default: toml::Value = toml::from_str(thermocontact::scenario::DEFAULT_TOML).unwrap();
    let mut all = Vec::new();
    keys("", &default, &mut all);
    let reference = include_str!("../docs/scenario.md");
    let missing: Vec<&String> = all.iter().filter(|k| !reference.contains(&format!("`{k}`"))).collect();
    assert!(all.len() > 40, "{all:?}");
    assert!(missing.is_empty(), "docs/scenario.md lacks {missing:?}");
}

/// Boxes within the length range whose cells are too elongated for a mesh: a clean error
/// naming the keys and the bound, exit 1 (they panicked with exit 101 before).
#[test]
fn elongated_boxes_are_refused_naming_the_lengths_and_the_cell_counts() {
    let paper3d = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/paper3d.toml");
    let cases: [(&[&str], &str); 2] = [
        (&["--set", "geometry.lengths=[1e-6,1e6]"], "mesh.nx, mesh.ny"),
        (
            &[
                paper3d,
                "--set",
                "geometry.lengths=[1e-4,1.0,1e4]",
                "--set",
                "mesh.nx=4",
                "--set",
                "mesh.ny=2",
                "--set",
                "mesh.nz=2",
                "--set",
                "time.steps=4",
            ],
            "mesh.nx, mesh.ny, mesh.nz",
        ),
    ];
    for (args, counts) in cases {
        let out = scratch("elongated");
        let result = bin()
            .args(["run", "--quiet"])
            .args(args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(
            stderr.contains("`geometry.lengths`") && stderr.contains(counts) && stderr.contains("at most 1e4 times"),
            "{stderr}"
        );
        assert!(!out.exists(), "nothing is written for an invalid scenario");
    }
}

/// An OS error is printed once, not once by the message that quotes it and again as its cause.
#[test]
fn os_errors_are_printed_once() {
    let file = scratch("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    let result = bin().args(["run", "--quiet", "--out"]).arg(&file).output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success());
    assert!(
        stderr.contains("cannot use") && stderr.contains("as the output folder"),
        "{stderr}"
    );
    assert_eq!(stderr.matches("(os error").count(), 1, "{stderr}");
    std::fs::remove_file(&file).unwrap();

    let missing = scratch("no-such-run");
    let result = bin()
        .args(["run", "--quiet", "--restart"])
        .arg(&missing)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(stderr.contains("scenario.toml"), "{stderr}");
    assert_eq!(stderr.matches("(os error").count(), 1, "{stderr}");
}

/// A run that fails before its first step has written no checkpoint (nor anything else):
/// the message after the error says so instead of pointing at `checkpoint.bin`.
#[test]
fn a_run_that_fails_before_its_first_step_points_at_no_checkpoint() {
    let out = scratch("singular");
    let result = bin()
        .args(["run", "--quiet", "--set", "material.thermal_expansion=1e18", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("the step matrix: factoring failed"), "{stderr}");
    // The scenario layer names the keys the matrix is built from.
    assert!(stderr.contains("material.thermal_expansion"), "{stderr}");
    assert!(!out.join("checkpoint.bin").exists());
    assert!(
        !stderr.contains("checkpoint.bin") && !stderr.contains("--restart"),
        "{stderr}"
    );
    assert!(stderr.contains("before it wrote any result"), "{stderr}");
    std::fs::remove_dir_all(&out).ok();
}

/// Batch runs (stderr not a terminal): progress lines with the step, t, iterations, cutbacks,
/// slip and stick counts, elapsed and remaining time; steps.csv with a row per step that has
/// the slip and stick counts, the increments and the law residual.
#[test]
fn batch_runs_log_progress_lines_and_steps_csv_has_slip_and_stick_counts() {
    let out = scratch("batch");
    let result = bin()
        .args([
            "run",
            "--set",
            "mesh.nx=16",
            "--set",
            "mesh.ny=4",
            "--set",
            "time.steps=16",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("step ") && l.contains("/16 t = "))
        .collect();
    // One line per output time (4), the last one at the end.
    assert_eq!(lines.len(), 4, "{stderr}");
    assert!(lines[3].starts_with("step 16/16 t = 1.000000: "), "{stderr}");
    for line in &lines {
        assert_has_parts(
            line,
            &[
                " convexification, ",
                " inner, ",
                " Newton, ",
                " steps cut back so far; ",
                " slip, ",
                " stick; ",
                "law residual ",
                "elapsed ",
                "remaining ",
            ],
        );
    }

    let steps = std::fs::read_to_string(out.join("steps.csv")).unwrap();
    let mut rows = steps.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    for column in [
        "n",
        "t",
        "convexification",
        "krylov",
        "increment_u",
        "increment_theta",
        "increment_xi",
        "increment_zeta",
        "law_residual",
        "slip",
        "stick",
        "seconds",
    ] {
        assert!(header.contains(&column), "{column} missing: {header:?}");
    }
    let column = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let contact_nodes = summary["contact_nodes"].as_u64().unwrap();
    let rows: Vec<Vec<&str>> = rows.map(|r| r.split(',').collect()).collect();
    assert_eq!(rows.len(), 16);
    for row in &rows {
        let count = |name: &str| row[column(name)].parse::<u64>().unwrap();
        assert_eq!(count("slip") + count("stick"), contact_nodes, "{row:?}");
    }
    // At the output times, the counts of the summary (and of the contact CSVs).
    for o in summary["outputs"].as_array().unwrap() {
        let row = &rows[o["n"].as_u64().unwrap() as usize - 1];
        assert_eq!(row[column("slip")], o["slip_nodes"].to_string(), "{row:?}");
        assert_eq!(row[column("stick")], o["stick_nodes"].to_string(), "{row:?}");
    }
    // The paper's solver measures the increments (77)–(80): each within its tolerance.
    let paper = scratch("batch-paper");
    let result = bin()
        .args([
            "run",
            "--quiet",
            "--set",
            "solver.kind=paper",
            "--set",
            "mesh.nx=8",
            "--set",
            "mesh.ny=2",
        ])
        .args(["--set", "time.steps=4", "--out"])
        .arg(&paper)
        .output()
        .unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let steps = std::fs::read_to_string(paper.join("steps.csv")).unwrap();
    for row in steps.lines().skip(1) {
        let row: Vec<f64> = row.split(',').map(|v| v.parse().unwrap()).collect();
        for name in ["increment_u", "increment_theta", "increment_xi", "increment_zeta"] {
            let value = row[column(name)];
            assert!((0.0..=1e-6).contains(&value), "{name} = {value}");
        }
    }
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&paper).ok();
}

/// The files of a folder, each as the bytes that must not depend on the thread count:
/// steps.csv without its `seconds` column, summary.json without the run id, timings and peak
/// memory, every other file (frames, contact CSVs, the .pvd, scenario.toml) as it is.
fn thread_independent_contents(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| !name.starts_with('.'))
        .map(|name| {
            let bytes = std::fs::read(dir.join(&name)).unwrap();
            let bytes = match name.as_str() {
                "steps.csv" => {
                    let text = String::from_utf8(bytes).unwrap();
                    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
                    let seconds = header.iter().position(|c| *c == "seconds").unwrap();
                    let kept: Vec<String> = text
                        .lines()
                        .map(|line| {
                            let mut cells: Vec<&str> = line.split(',').collect();
                            cells.remove(seconds);
                            cells.join(",")
                        })
                        .collect();
                    kept.join("\n").into_bytes()
                }
                "summary.json" => {
                    let mut summary: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                    let map = summary.as_object_mut().unwrap();
                    for machine in ["run_id", "timings", "peak_memory_mib"] {
                        assert!(map.remove(machine).is_some(), "{machine}");
                    }
                    serde_json::to_vec_pretty(&summary).unwrap()
                }
                _ => bytes,
            };
            (name, bytes)
        })
        .collect();
    files.sort();
    files
}

/// Bitwise reproducible on any thread count: the CLI run on 1 and on 2 threads writes the same
/// files, byte for byte (less the wall times and the run id), in 2D and 3D, and on the iterative
/// path (its ILU(0) sweeps run two domains on two threads).
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let paper3d = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/paper3d.toml");
    let cases: [(&str, Vec<&str>); 3] = [
        (
            "2d",
            vec!["--set", "mesh.nx=16", "--set", "mesh.ny=4", "--set", "time.steps=16"],
        ),
        (
            "3d",
            vec![
                paper3d,
                "--set",
                "mesh.nx=8",
                "--set",
                "mesh.ny=2",
                "--set",
                "mesh.nz=2",
                "--set",
                "time.steps=4",
            ],
        ),
        (
            "3d-iterative",
            vec![
                paper3d,
                "--set",
                "mesh.nx=12",
                "--set",
                "mesh.ny=3",
                "--set",
                "mesh.nz=3",
                "--set",
                "time.steps=4",
                "--set",
                "solver.linear=iterative",
            ],
        ),
    ];
    for (tag, args) in cases {
        let contents: Vec<Vec<(String, Vec<u8>)>> = ["1", "2"]
            .iter()
            .map(|threads| {
                let out = scratch(&format!("threads-{tag}-{threads}"));
                let result = bin()
                    .env("RAYON_NUM_THREADS", threads)
                    .args(["run", "--quiet"])
                    .args(&args)
                    .arg("--out")
                    .arg(&out)
                    .output()
                    .unwrap();
                assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
                let contents = thread_independent_contents(&out);
                std::fs::remove_dir_all(&out).unwrap();
                contents
            })
            .collect();
        let names = |c: &[(String, Vec<u8>)]| c.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
        assert_eq!(names(&contents[0]), names(&contents[1]), "{tag}");
        assert!(
            names(&contents[0]).iter().filter(|n| n.ends_with(".vtu")).count() >= 4,
            "{tag}: {:?}",
            names(&contents[0])
        );
        for ((name, one), (_, two)) in contents[0].iter().zip(&contents[1]) {
            assert!(one == two, "{tag}: {name} differs between 1 and 2 threads");
        }
    }
}

/// A step that runs longer than the heartbeat's threshold reports its outer iterations on a
/// non-terminal stderr (the batch lines' stream); `THERMOCONTACT_HEARTBEAT_SECONDS=0` forces the
/// threshold to zero, so every iteration of this tiny run reports. Without it (threshold 3 s),
/// or with `--quiet`, the short run prints no such line. The header names the linear path and
/// why `auto` took it.
#[test]
fn long_steps_report_their_outer_iterations_and_the_header_names_the_linear_path() {
    let run = |tag: &str, forced: bool, quiet: bool| {
        let out = scratch(tag);
        let mut command = bin();
        command.args([
            "run",
            "--set",
            "mesh.nx=16",
            "--set",
            "mesh.ny=4",
            "--set",
            "time.steps=2",
            "--out",
        ]);
        command.arg(&out);
        if quiet {
            command.arg("--quiet");
        }
        if forced {
            command.env("THERMOCONTACT_HEARTBEAT_SECONDS", "0");
        } else {
            command.env_remove("THERMOCONTACT_HEARTBEAT_SECONDS");
        }
        let result = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr).to_string();
        assert!(result.status.success(), "{stderr}");
        (String::from_utf8_lossy(&result.stdout).to_string(), stderr)
    };
    let beats = |stderr: &str| stderr.lines().filter(|l| l.starts_with("  step ")).count();
    let (stdout, stderr) = run("heartbeat", true, false);
    assert!(
        stderr.contains("  step 1 (t = 0.5): convexification iteration 1, ")
            && stderr.contains("  step 2 (t = 1): convexification iteration 1, "),
        "{stderr}"
    );
    assert!(stderr.contains(" (tolerance 1.0e-6), "), "{stderr}");
    assert!(stdout.contains("linear path: direct (auto: estimated "), "{stdout}");
    assert_eq!(beats(&run("heartbeat-default", false, false).1), 0);
    assert_eq!(beats(&run("heartbeat-quiet", true, true).1), 0);
}

/// A step whose convexification loop does not converge within `solver.max_convexification`
/// iterates, and which a way out finishes, says so in the log with what finished it: the 3D
/// example on a slab of 64 × 4 × 4 cells on the iterative path, whose second step takes the
/// paper's loop (`solver.contact_sweeps = 0`) 140 iterates (a slip front along a row of contact
/// nodes), capped at 100.
#[test]
fn a_step_a_way_out_finished_is_logged() {
    let out = scratch("way-out");
    let sets = [
        "solver.contact_sweeps=0",
        "mesh.nx=64",
        "mesh.ny=4",
        "mesh.nz=4",
        "time.steps=4",
        "time.final_time=0.0625",
        "solver.linear=iterative",
        "solver.max_convexification=100",
        "output.times=[0.0625]",
        "output.vtk=false",
    ];
    let mut command = bin();
    command
        .args(["run", "scenarios/paper3d.toml", "--quiet", "--out"])
        .arg(&out);
    for set in sets {
        command.args(["--set", set]);
    }
    let output = command.output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains(
            "step 2 (t = 0.03125): the convexification loop did not converge in 100 iterates; the loop with the law's predicted bounds finished the step ("
        ),
        "{stderr}"
    );
    assert_eq!(stderr.matches("did not converge").count(), 1, "{stderr}");
    std::fs::remove_dir_all(&out).ok();
}

/// A step that does not converge says why before it is cut back: the loop, its iterations, the
/// criterion and by how much, and the substeps it is cut into; one line per failed (sub)step,
/// then the step's own line. The 2D example on 16 × 4 cells with the convexification loop
/// capped at 5 iterates and the descent off cuts four steps back.
#[test]
fn a_step_cut_back_says_why() {
    let out = scratch("cut-back-why");
    let output = bin()
        .args(["run", "--out"])
        .arg(&out)
        .args(["--set", "mesh.nx=16", "--set", "mesh.ny=4", "--set", "time.steps=16"])
        .args(["--set", "solver.max_sweeps=0", "--set", "solver.max_convexification=5"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let why: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("; cut back to substeps of k/"))
        .collect();
    for line in &why {
        assert_has_parts(
            line,
            &[
                "  step ",
                ": from t = ",
                "the fast solver's convexification loop stopped after 5 iterations: ",
                " > tolerance 1e-6",
            ],
        );
    }
    assert!(
        why.iter().any(|l| l.ends_with("cut back to substeps of k/2")),
        "{why:?}"
    );
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let cutbacks = summary["cutbacks"].as_array().unwrap();
    let cut_steps = cutbacks.len();
    assert!(cut_steps > 0);
    // summary.json keeps each cut-back step's reason: its failure at the full k, the first of
    // the log's lines for that step.
    for cutback in cutbacks {
        let reason = cutback["reason"].as_str().unwrap_or_else(|| panic!("{cutback}"));
        assert!(
            reason.starts_with("the fast solver's convexification loop stopped after 5 iterations: "),
            "{reason}"
        );
        let (step, t) = (cutback["step"].as_u64().unwrap(), cutback["t"].as_f64().unwrap());
        let first = why
            .iter()
            .find(|l| l.starts_with(&format!("  step {step} (t = {t}): ")))
            .unwrap();
        assert!(first.contains(reason), "{first} / {reason}");
    }
    assert_eq!(stderr.matches(": cut back, ").count(), cut_steps, "{stderr}");
    // Each cut-back step failed once at k, and each failed substep adds a line.
    assert!(why.len() >= cut_steps, "{why:?}");
    std::fs::remove_dir_all(&out).ok();
}

/// A run stopped by linear solves that ran out of Krylov iterations with ILU(0) alone says what
/// takes such a body: the two-level preconditioner (a `petsc` build) or the direct path; after
/// another failure (the convexification loop's) it says nothing of the kind.
#[test]
fn a_run_stopped_by_its_krylov_solves_says_what_to_try() {
    let out = scratch("krylov-hint");
    let run = |sets: &[&str]| {
        let mut command = bin();
        command.args(["run", "--quiet", "--out"]).arg(&out).arg("--overwrite");
        let base = ["mesh.nx=16", "mesh.ny=4", "time.steps=4", "solver.cutback=false"];
        for set in base.iter().chain(sets) {
            command.args(["--set", set]);
        }
        let output = command.output().unwrap();
        assert!(!output.status.success());
        String::from_utf8_lossy(&output.stderr).into_owned()
    };
    let krylov = run(&[
        "solver.linear=iterative",
        "solver.max_krylov=1",
        "solver.preconditioner=ilu",
    ]);
    assert!(krylov.contains("relative residual of the linear solve"), "{krylov}");
    let hint = krylov
        .lines()
        .find(|l| l.starts_with("hint: "))
        .unwrap_or_else(|| panic!("{krylov}"));
    assert_has_parts(
        hint,
        &[
            "ILU(0) alone",
            "`solver.max_krylov`",
            "`\"amg\"`",
            "`solver.linear = \"direct\"`",
        ],
    );
    let loop_failure = run(&["solver.max_sweeps=0", "solver.max_convexification=2"]);
    assert!(loop_failure.contains("convexification loop stopped"), "{loop_failure}");
    assert!(!loop_failure.contains("hint: "), "{loop_failure}");
    std::fs::remove_dir_all(&out).ok();
}

/// Every one of `parts` in `line`.
fn assert_has_parts(line: &str, parts: &[&str]) {
    for part in parts {
        assert!(line.contains(part), "`{part}` missing in: {line}");
    }
}
