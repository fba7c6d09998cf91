//! `mpirun -n P thermocontact run` (cargo feature `mpi`; docs/distributed.md) against one
//! process: the same stick/slip state at every step and at every contact node of every output,
//! the same cutbacks, and fields within the bound the solvers' tolerances give, in the contact
//! CSVs and in the frames (each rank's piece, listed by a `.pvtu`, reassembled by the points'
//! coordinates). Also: a distributed run with the direct path is refused naming
//! `solver.linear`, and a step that does not converge, or a rank that cannot write its piece of
//! a frame, ends every rank with a non-zero status, the message once and a folder that says
//! `failed`.
//!
//! **The bound.** The ranks' GCR stops at ‖b − Ax‖ ≤ 10⁻¹⁰ ‖b‖ as the serial GMRES does, but
//! with another preconditioner (ILU(0) on the ranks' overlapping parts), so the Newton
//! iterates differ by the solves' errors, and the convexification loop, which stops once its
//! relative changes fall below ε_conv = 10⁻⁶, may stop one iterate apart: each step's solution
//! is known to a few ε_conv (the loop contracts slowly), and that error is carried from step to
//! step. Fields are therefore compared to 10 ε_conv = 10⁻⁵ of their largest magnitude.
//! Measured: 8·10⁻⁸ (ξ) and 10⁻⁹ (w_τ, θ) on the 3D example after 16 steps on 2 ranks;
//! 4.7·10⁻⁶ (w_τ) and 2·10⁻⁵ (ξ) after 400 steps of the 12 × 3 × 3 example at k = 1/400. The stick/slip state must be identical.

#[cfg(not(feature = "mpi"))]
#[test]
fn skipped_without_the_mpi_feature() {
    eprintln!("tests/distributed_run.rs needs `--features mpi` (and Open MPI's mpirun)");
}

#[cfg(feature = "mpi")]
mod distributed {
    use std::collections::BTreeMap;
    use std::path::{Path, PathBuf};
    use std::process::{Command, Output};

    use vtkio::model::{Attribute, DataSet};
    use vtkio::Vtk;

    const CLI: &str = env!("CARGO_BIN_EXE_thermocontact");

    /// Relative bound on the fields (the module header).
    const FIELD_BOUND: f64 = 1e-5;

    fn scenarios() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios")
    }

    /// `thermocontact run` on `ranks` ranks (one: no mpirun) into a fresh `out`.
    fn run(ranks: usize, out: &Path, args: &[String]) -> Output {
        let _ = std::fs::remove_dir_all(out);
        let mut command = if ranks == 1 {
            Command::new(CLI)
        } else {
            let mut c = Command::new("timeout");
            c.args(["600", "mpirun", "--allow-run-as-root", "--oversubscribe", "-n"])
                .arg(ranks.to_string())
                .arg(CLI);
            c
        };
        command.arg("run").args(args).arg("--out").arg(out).arg("--quiet");
        command
            .output()
            .expect("thermocontact (and, for several ranks, mpirun: Debian's openmpi-bin) runs")
    }

    fn text(output: &Output) -> String {
        format!(
            "{}{}",
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        )
    }

    fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
        let body = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut lines = body.lines();
        let header = lines.next().expect("a header").split(',').map(String::from).collect();
        let rows = lines.map(|l| l.split(',').map(String::from).collect()).collect();
        (header, rows)
    }

    /// The frames `solution.pvd` lists in `dir`: (time, file).
    fn collection(dir: &Path) -> Vec<(f64, String)> {
        let xml = std::fs::read_to_string(dir.join("solution.pvd")).unwrap();
        let attr = |line: &str, key: &str| -> String {
            let start = line.find(&format!("{key}=\"")).unwrap() + key.len() + 2;
            line[start..start + line[start..].find('"').unwrap()].to_string()
        };
        (xml.lines().filter(|l| l.trim_start().starts_with("<DataSet ")))
            .map(|l| (attr(l, "timestep").parse().unwrap(), attr(l, "file")))
            .collect()
    }

    /// The point arrays of a frame by name, each a map from the point's coordinates (exact:
    /// every rank copies the mesh's) to its values, and the frame's cells: a whole `.vtu`, or a
    /// `.pvtu` with its pieces (a node on the boundary of two parts is in both, with the same
    /// values).
    type FramePoints = BTreeMap<String, BTreeMap<[u64; 3], Vec<f64>>>;
    fn frame_points(path: &Path) -> (FramePoints, usize) {
        let mut vtk = Vtk::import(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        vtk.load_all_pieces().unwrap();
        let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
            panic!("{} is not an unstructured grid", path.display())
        };
        let (mut arrays, mut cells) = (FramePoints::new(), 0);
        for piece in &pieces {
            let piece = piece.load_piece_data(None).unwrap();
            cells += piece.cells.num_cells();
            let points: Vec<f64> = piece.points.cast_into().unwrap();
            for attribute in &piece.data.point {
                let Attribute::DataArray(array) = attribute else {
                    continue;
                };
                let values: Vec<f64> = array.data.clone().into_vec().unwrap();
                let m = values.len() / (points.len() / 3);
                let by_point = arrays.entry(array.name.clone()).or_default();
                for (x, v) in points.chunks_exact(3).zip(values.chunks_exact(m)) {
                    let key = [x[0].to_bits(), x[1].to_bits(), x[2].to_bits()];
                    let before = by_point.insert(key, v.to_vec());
                    assert!(
                        before.is_none_or(|b| b == v),
                        "{}: a node's values differ between pieces",
                        path.display()
                    );
                }
            }
        }
        (arrays, cells)
    }

    /// The frames of `other` hold those of `one` (the same times, cells and points, every
    /// point array within [`FIELD_BOUND`] of its largest magnitude), whole or in pieces.
    fn assert_frames_agree(one: &Path, other: &Path) {
        let (frames, others) = (collection(one), collection(other));
        assert_eq!(frames.len(), others.len(), "{}: the same frames", other.display());
        for ((time, file), (other_time, other_file)) in frames.iter().zip(&others) {
            assert_eq!(time, other_time);
            let (a, cells) = frame_points(&one.join(file));
            let (b, other_cells) = frame_points(&other.join(other_file));
            assert_eq!(cells, other_cells, "{other_file}: every cell once");
            assert_eq!(
                a.keys().collect::<Vec<_>>(),
                b.keys().collect::<Vec<_>>(),
                "{other_file}"
            );
            for (name, values) in &a {
                let other_values = &b[name];
                assert_eq!(values.len(), other_values.len(), "{other_file} {name}: every point");
                let scale = (values.values().flatten()).fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()));
                for (point, v) in values {
                    let w = &other_values[point];
                    let worst = v.iter().zip(w).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                    assert!(
                        worst <= FIELD_BOUND * scale,
                        "{other_file} {name}: {worst:e} apart at a point, bound {FIELD_BOUND:e} × {scale:e}"
                    );
                }
            }
        }
    }

    /// The runs in `one` and `other` agree: steps.csv's slip, stick, substeps and cutback depth
    /// at every step, its energies within [`FIELD_BOUND`] of each one's largest magnitude, every
    /// contact CSV's slip flag at every node, its fields within
    /// [`FIELD_BOUND`] of their largest magnitude; their frames ([`assert_frames_agree`]).
    fn assert_runs_agree(one: &Path, other: &Path) {
        assert_frames_agree(one, other);
        let (header, a) = read_csv(&one.join("steps.csv"));
        let (_, b) = read_csv(&other.join("steps.csv"));
        assert_eq!(a.len(), b.len(), "the same steps");
        for name in ["n", "slip", "stick", "substeps", "cutback_depth"] {
            let c = header.iter().position(|h| h == name).expect(name);
            for (ra, rb) in a.iter().zip(&b) {
                assert_eq!(ra[c], rb[c], "steps.csv {name} at step {}", ra[0]);
            }
        }
        // The energies, each rank's part of those read from its share of the matrices summed
        // over the ranks (`model::ColumnShare`): within the fields' bound of each column's
        // largest magnitude (the balances' residuals are rounding: left out).
        let energies = header
            .iter()
            .enumerate()
            .filter(|(_, h)| h.ends_with("_J") && !h.contains("residual"));
        for (c, name) in energies {
            let values = |rows: &[Vec<String>]| -> Vec<f64> { rows.iter().map(|r| r[c].parse().unwrap()).collect() };
            let (va, vb) = (values(&a), values(&b));
            let scale = va.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
            let worst = va.iter().zip(&vb).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(
                worst <= FIELD_BOUND * scale,
                "steps.csv {name}: {worst:e} apart, bound {FIELD_BOUND:e} × {scale:e}"
            );
        }
        let mut contact: Vec<PathBuf> = std::fs::read_dir(one)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with("contact_"))
            .collect();
        contact.sort();
        assert!(!contact.is_empty(), "contact CSVs in {}", one.display());
        for path in contact {
            let name = path.file_name().unwrap();
            let (header, a) = read_csv(&path);
            let (_, b) = read_csv(&other.join(name));
            assert_eq!(a.len(), b.len(), "{name:?}: the same nodes");
            for (c, column) in header.iter().enumerate() {
                let values =
                    |rows: &[Vec<String>]| -> Vec<f64> { rows.iter().map(|r| r[c].parse().unwrap()).collect() };
                let (va, vb) = (values(&a), values(&b));
                if column == "slip" {
                    assert_eq!(va, vb, "{name:?}: the stick/slip state at every node");
                    continue;
                }
                let scale = va.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
                let worst = va.iter().zip(&vb).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                assert!(
                    worst <= FIELD_BOUND * scale,
                    "{name:?} {column}: {worst:e} apart, bound {FIELD_BOUND:e} × {scale:e}"
                );
            }
        }
    }

    /// The case on 1, 2 and 3 ranks: the runs agree with the one-process run.
    fn agrees_over_ranks(case: &str, args: &[String]) {
        let dir = std::env::temp_dir().join(format!("thermocontact-distributed-{case}-{}", std::process::id()));
        let one = dir.join("ranks-1");
        let output = run(1, &one, args);
        assert!(output.status.success(), "one process:\n{}", text(&output));
        let summary = std::fs::read_to_string(one.join("summary.json")).unwrap();
        assert!(
            !summary.contains("peak_memory_per_rank_mib"),
            "one process lists no ranks"
        );
        for ranks in [2, 3] {
            let out = dir.join(format!("ranks-{ranks}"));
            let output = run(ranks, &out, args);
            assert!(output.status.success(), "{ranks} ranks:\n{}", text(&output));
            assert!(
                text(&output).contains(&format!("distributed over {ranks} ranks")),
                "{ranks} ranks: the run says so:\n{}",
                text(&output)
            );
            assert!(
                collection(&out).iter().all(|(_, file)| file.ends_with(".pvtu")),
                "{ranks} ranks: the frames in pieces"
            );
            assert_runs_agree(&one, &out);
            assert_peak_memory_per_rank(&out, ranks);
            assert_eq!(
                preconditioner(&out),
                preconditioner(&one),
                "{ranks} ranks: the preconditioner `auto` takes"
            );
        }
        let again = dir.join("ranks-2-again");
        let output = run(2, &again, args);
        assert!(output.status.success(), "2 ranks again:\n{}", text(&output));
        assert_runs_identical(&dir.join("ranks-2"), &again);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The summary of a run on `ranks` ranks lists each rank's peak memory, and its peak
    /// memory is the largest of them.
    fn assert_peak_memory_per_rank(out: &Path, ranks: usize) {
        let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
        let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
        let each: Vec<f64> = (summary["peak_memory_per_rank_mib"].as_array())
            .unwrap_or_else(|| panic!("no peak memory per rank in {text}"))
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(each.len(), ranks, "{each:?}");
        assert!(each.iter().all(|&m| m > 1.0), "every rank's peak read: {each:?}");
        let largest = each.iter().copied().fold(0.0, f64::max);
        assert_eq!(summary["peak_memory_mib"].as_f64(), Some(largest), "{each:?}");
    }

    /// Two runs of one case on the same ranks give the same numbers: `steps.csv` but its
    /// wall-clock column, and every contact file, byte for byte (the partition is the same
    /// every time: `partition::tests`).
    fn assert_runs_identical(one: &Path, other: &Path) {
        let (header, first) = read_csv(&one.join("steps.csv"));
        let (_, second) = read_csv(&other.join("steps.csv"));
        let seconds = header.iter().position(|h| h == "seconds").expect("a seconds column");
        let without_clock = |rows: Vec<Vec<String>>| -> Vec<Vec<String>> {
            rows.into_iter()
                .map(|mut row| {
                    row.remove(seconds);
                    row
                })
                .collect()
        };
        assert_eq!(
            without_clock(first),
            without_clock(second),
            "steps.csv of two identical runs"
        );
        let mut contact_files = 0;
        for entry in std::fs::read_dir(one).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            if name.starts_with("contact_") && name.ends_with(".csv") {
                let bytes = |dir: &Path| std::fs::read(dir.join(&name)).unwrap();
                assert!(bytes(one) == bytes(other), "{name} of two identical runs");
                contact_files += 1;
            }
        }
        assert!(contact_files > 0, "contact files in {}", one.display());
    }

    fn scenario(name: &str) -> String {
        scenarios().join(name).display().to_string()
    }

    /// The arguments of `run`: the scenario `name`, then `--set` for each of `sets`.
    fn scenario_with(name: &str, sets: &[&str]) -> Vec<String> {
        let mut args = vec![scenario(name)];
        for set in sets {
            args.extend(["--set".to_string(), set.to_string()]);
        }
        args
    }

    #[test]
    fn the_3d_example_on_two_and_three_ranks_equals_one_process() {
        agrees_over_ranks(
            "paper3d",
            &scenario_with(
                "paper3d.toml",
                &[
                    "mesh.nx=12",
                    "mesh.ny=3",
                    "mesh.nz=3",
                    "time.steps=16",
                    "time.final_time=0.25",
                    "output.times=[0.125,0.25]",
                    "solver.linear=\"iterative\"",
                ],
            ),
        );
    }

    /// The same with the loop's bounds predicted by a symmetric Gauss–Seidel sweep of the law
    /// over Γ_C's own rows (`solver.prediction = "law"`, `solver.condensed_layers = 0`; the
    /// default, the loop on Γ_C's rows through two layers, runs in every other test here):
    /// every rank sweeps the same nodes from the same numbers.
    #[test]
    fn predicted_bounds_on_two_and_three_ranks_equal_one_process() {
        agrees_over_ranks(
            "paper3d-predicted",
            &scenario_with(
                "paper3d.toml",
                &[
                    "mesh.nx=16",
                    "mesh.ny=4",
                    "mesh.nz=4",
                    "time.steps=8",
                    "time.final_time=0.125",
                    "output.times=[0.0625,0.125]",
                    "solver.linear=\"iterative\"",
                    "solver.contact_sweeps=1",
                    "solver.prediction=\"law\"",
                    "solver.condensed_layers=0",
                ],
            ),
        );
    }

    /// The same at a coarse k with 8 sweeps of the law through two layers of the body
    /// (`solver.condensed_layers`): every rank assembles the layers' rows and condenses the same
    /// numbers (`ProblemBuilder::contact_layers`).
    #[test]
    fn sweeps_through_the_body_on_two_and_three_ranks_equal_one_process() {
        agrees_over_ranks(
            "paper3d-condensed",
            &scenario_with(
                "paper3d.toml",
                &[
                    "mesh.nx=24",
                    "mesh.ny=6",
                    "mesh.nz=6",
                    "time.steps=8",
                    "time.final_time=1",
                    "output.times=[0.5,1]",
                    "solver.linear=\"iterative\"",
                    "solver.contact_sweeps=8",
                    "solver.prediction=\"law\"",
                    "solver.condensed_layers=2",
                ],
            ),
        );
    }

    /// A thin slab at k = 1/8 whose convex problems' Newton steps flip nodes and are cut back
    /// along themselves (`solver.backtracking`): every rank takes the same cuts, from the same
    /// gathered w and ξ, and ends where one process does.
    #[test]
    fn backtracked_newton_steps_on_two_and_three_ranks_equal_one_process() {
        let args = scenario_with(
            "paper3d.toml",
            &[
                "mesh.nx=52",
                "mesh.ny=3",
                "mesh.nz=3",
                "time.steps=16",
                "time.final_time=2",
                "output.times=[1,2]",
                "solver.linear=\"iterative\"",
                "solver.contact_sweeps=8",
                "solver.prediction=\"law\"",
                "solver.condensed_layers=2",
            ],
        );
        agrees_over_ranks("paper3d-backtracked", &args);
        let one = std::env::temp_dir().join(format!("thermocontact-backtracked-{}", std::process::id()));
        let output = run(1, &one, &args);
        assert!(output.status.success(), "{}", text(&output));
        let backtracked = summary_of(&one)["backtracked_newton_iterations"].as_u64().unwrap();
        assert!(backtracked > 0, "the case should backtrack");
        let _ = std::fs::remove_dir_all(&one);
    }

    /// The brake pad (a Gmsh mesh, a moving counter-face, friction from the contact pressure,
    /// thermal conditions): its stiffness weighs, so `auto` takes the two-level method (GAMG on
    /// the velocity block between the ranks' ILU(0) sweeps, as one process does), without which
    /// the ranks' Krylov solves stalled near 10⁻⁸ and the run stopped in its first step.
    #[test]
    fn the_brake_pad_on_two_and_three_ranks_equals_one_process() {
        let args = scenario_with(
            "brake_pad3d.toml",
            &[
                "time.steps=6",
                "time.final_time=0.3",
                "output.times=[0.3]",
                "solver.linear=\"iterative\"",
            ],
        );
        agrees_over_ranks("brake_pad3d", &args);
    }

    /// A run's `summary.json`.
    fn summary_of(out: &Path) -> serde_json::Value {
        let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    }

    /// The preconditioner a run set up (`summary.json`).
    fn preconditioner(out: &Path) -> String {
        let summary = summary_of(out);
        summary["preconditioner"]
            .as_str()
            .unwrap_or_else(|| panic!("{summary}"))
            .to_string()
    }

    /// The Krylov iterations of a run (`summary.json`).
    fn krylov_iterations(out: &Path) -> u64 {
        let summary = summary_of(out);
        summary["krylov_iterations"]
            .as_u64()
            .unwrap_or_else(|| panic!("{summary}"))
    }

    /// On 3 ranks, block Jacobi (`solver.overlap = 0`) and restricted additive Schwarz (1, the
    /// default) both agree with one process, and Schwarz's overlapped blocks take fewer Krylov
    /// iterations (measured: 452 against 607; 304 against 344 at 972k unknowns on 2 ranks).
    #[test]
    fn overlapping_blocks_take_fewer_krylov_iterations_for_the_same_run() {
        let dir = std::env::temp_dir().join(format!("thermocontact-distributed-overlap-{}", std::process::id()));
        let sets = [
            "mesh.nx=12",
            "mesh.ny=3",
            "mesh.nz=3",
            "time.steps=16",
            "time.final_time=0.25",
            "output.times=[0.25]",
            "solver.linear=\"iterative\"",
        ];
        let one = dir.join("one");
        let output = run(1, &one, &scenario_with("paper3d.toml", &sets));
        assert!(output.status.success(), "one process:\n{}", text(&output));
        let mut iterations = Vec::new();
        for overlap in ["solver.overlap=0", "solver.overlap=1"] {
            let out = dir.join(overlap);
            let args = scenario_with("paper3d.toml", &[&sets[..], &[overlap]].concat());
            let output = run(3, &out, &args);
            assert!(output.status.success(), "{overlap}:\n{}", text(&output));
            assert_runs_agree(&one, &out);
            iterations.push(krylov_iterations(&out));
        }
        assert!(
            iterations[1] < iterations[0],
            "Krylov iterations on 3 ranks, block Jacobi then Schwarz: {iterations:?}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The 2D example with the paper's loop (`solver.contact_sweeps = 0`, one solve per
    /// iterate).
    #[test]
    fn the_2d_example_on_two_and_three_ranks_equals_one_process() {
        agrees_over_ranks(
            "paper2d",
            &scenario_with(
                "paper.toml",
                &[
                    "mesh.nx=32",
                    "mesh.ny=8",
                    "time.steps=16",
                    "solver.linear=\"iterative\"",
                    "solver.contact_sweeps=0",
                ],
            ),
        );
    }

    /// A Gmsh mesh with a curved contact boundary (the brake shoe).
    #[test]
    fn a_gmsh_mesh_on_two_and_three_ranks_equals_one_process() {
        agrees_over_ranks(
            "brake_shoe",
            &scenario_with(
                "brake_shoe.toml",
                &[
                    "time.steps=8",
                    "time.final_time=0.5",
                    "output.times=[0.25,0.5]",
                    "solver.linear=\"iterative\"",
                ],
            ),
        );
    }

    /// The direct path over ranks is refused naming `solver.linear`, once, with a non-zero
    /// status; a step forced not to converge (a Krylov cap of 2, no cutback) ends every rank
    /// with a non-zero status, the error once, and rank 0's folder says `failed`.
    #[test]
    fn the_direct_path_is_refused_and_a_failed_step_ends_every_rank() {
        let dir = std::env::temp_dir().join(format!("thermocontact-distributed-fail-{}", std::process::id()));
        let small = |extra: &[&str]| -> Vec<String> {
            let sets = [
                "mesh.nx=12",
                "mesh.ny=3",
                "mesh.nz=3",
                "time.steps=4",
                "time.final_time=0.0625",
                "output.times=[0.0625]",
            ];
            scenario_with("paper3d.toml", &[&sets[..], extra].concat())
        };
        let refused = run(2, &dir.join("direct"), &small(&["solver.linear=\"direct\""]));
        let said = text(&refused);
        assert!(!refused.status.success(), "refused:\n{said}");
        assert_eq!(said.matches("error: solver.linear = \"direct\"").count(), 1, "{said}");
        assert!(!dir.join("direct").join("summary.json").exists(), "nothing written");

        let failed = run(
            2,
            &dir.join("failed"),
            // Every solve to rtol (the Newton iterations' inexact solves reach their forcing
            // term within 2 iterations here).
            &small(&["solver.max_krylov=2", "solver.krylov_forcing=0", "solver.cutback=false"]),
        );
        let said = text(&failed);
        assert!(!failed.status.success(), "a failed step:\n{said}");
        assert!(!said.contains("timeout"), "no hang:\n{said}");
        assert_eq!(said.matches("did not converge").count(), 1, "the error once:\n{said}");
        let summary = std::fs::read_to_string(dir.join("failed").join("summary.json")).unwrap();
        assert!(summary.contains("\"failed\""), "{summary}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A rank that cannot write its piece of a frame (rank 1 given a folder under a file,
    /// through mpirun's one command per rank) ends every rank after that step: a non-zero
    /// status, rank 1's error once, and rank 0's folder says `failed` and lists no frame of
    /// that step in pieces.
    #[test]
    fn a_rank_that_cannot_write_its_piece_ends_every_rank() {
        let dir = std::env::temp_dir().join(format!("thermocontact-distributed-io-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("a-file"), "").unwrap();
        let args = scenario_with(
            "paper3d.toml",
            &[
                "mesh.nx=12",
                "mesh.ny=3",
                "mesh.nz=3",
                "time.steps=4",
                "time.final_time=0.0625",
                "output.times=[0.03125,0.0625]",
                "solver.linear=\"iterative\"",
            ],
        );
        let (folder, unwritable) = (dir.join("out"), dir.join("a-file").join("out"));
        let mut command = Command::new("timeout");
        command.args(["300", "mpirun", "--allow-run-as-root", "--oversubscribe"]);
        for (rank, out) in [&folder, &unwritable].iter().enumerate() {
            if rank > 0 {
                command.arg(":");
            }
            command
                .args(["-n", "1", CLI, "run"])
                .args(&args)
                .arg("--out")
                .arg(out)
                .arg("--quiet");
        }
        let output = command.output().unwrap();
        let said = text(&output);
        assert!(!output.status.success(), "{said}");
        assert!(!said.contains("timeout"), "no hang:\n{said}");
        assert_eq!(
            said.matches("error: rank 1: cannot write").count(),
            1,
            "the error once:\n{said}"
        );
        let summary = std::fs::read_to_string(folder.join("summary.json")).unwrap();
        assert!(summary.contains("\"failed\""), "{summary}");
        assert!(
            collection(&folder).iter().all(|(_, file)| !file.ends_with(".pvtu")),
            "no frame in pieces listed: {:?}",
            collection(&folder)
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// SIGINT to `mpirun` (a Ctrl-C at the terminal): Open MPI's `mpirun` sends every rank
    /// SIGTERM and kills the ranks a second later (`odls_base_sigkill_timeout`); the ranks cut
    /// the step short at the same check and write the folder in that second: a non-zero status,
    /// the message once, `interrupted`, a checkpoint, fewer steps than asked.
    #[test]
    fn sigint_to_mpirun_stops_every_rank_with_a_checkpoint() {
        let dir = std::env::temp_dir().join(format!("thermocontact-distributed-sigint-{}", std::process::id()));
        let folder = dir.join("stopped");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let args = scenario_with(
            "paper3d.toml",
            &[
                "mesh.nx=40",
                "mesh.ny=10",
                "mesh.nz=10",
                "time.steps=1024",
                "time.final_time=1.0",
                "output.times=[1.0]",
                "output.vtk=false",
                "output.checkpoint_every=8",
                "solver.linear=\"iterative\"",
            ],
        );
        let log = dir.join("said.txt");
        let file = std::fs::File::create(&log).unwrap();
        // Without a terminal: stdin closed (`mpirun` forwards its stdin to rank 0; one left
        // open held its Ctrl-C back until the job ended).
        let mut child = Command::new("mpirun")
            .args(["--allow-run-as-root", "--oversubscribe", "-n", "2", CLI, "run"])
            .args(&args)
            .arg("--out")
            .arg(&folder)
            .arg("--quiet")
            .env("RAYON_NUM_THREADS", "1")
            .stdin(std::process::Stdio::null())
            .stdout(file.try_clone().unwrap())
            .stderr(file)
            .spawn()
            .expect("mpirun runs");
        // Once the run is stepping (its first checkpoint, after 8 of the 1 024 steps).
        let started = std::time::Instant::now();
        while !folder.join("checkpoint.bin").exists() {
            assert!(started.elapsed().as_secs() < 120, "the run completed its first steps");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let signalled = (Command::new("kill").args(["-INT", &child.id().to_string()]).status()).unwrap();
        assert!(signalled.success(), "mpirun was running");
        while child.try_wait().unwrap().is_none() {
            if started.elapsed().as_secs() > 300 {
                let _ = child.kill();
                panic!("mpirun still running 300 s after the start");
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let said = std::fs::read_to_string(&log).unwrap();
        assert!(!child.wait().unwrap().success(), "interrupted:\n{said}");
        assert_eq!(
            said.matches("the run was interrupted").count(),
            1,
            "the message once:\n{said}"
        );
        let summary = std::fs::read_to_string(folder.join("summary.json")).unwrap();
        assert!(summary.contains("\"interrupted\""), "{summary}\n{said}");
        assert!(folder.join("checkpoint.bin").is_file(), "a checkpoint:\n{said}");
        let (_, steps) = read_csv(&folder.join("steps.csv"));
        assert!(steps.len() < 1024, "{} steps:\n{said}", steps.len());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// SIGTERM to every rank (as a batch system's time limit sends it) stops the 2-rank run
    /// after the same step on every rank: a non-zero status, `interrupted`, a checkpoint. That
    /// run continued on 3 ranks, and on one process, equals the uninterrupted one-process run
    /// (the stick/slip state and the fields as in [`assert_runs_agree`]).
    #[test]
    fn a_run_stopped_on_two_ranks_continues_on_three_and_on_one() {
        let dir = std::env::temp_dir().join(format!("thermocontact-distributed-restart-{}", std::process::id()));
        let args = scenario_with(
            "paper3d.toml",
            &[
                "mesh.nx=40",
                "mesh.ny=10",
                "mesh.nz=10",
                "time.steps=16",
                "time.final_time=0.25",
                "output.times=[0.125,0.25]",
                "output.vtk=false",
                "output.checkpoint_every=1",
                "solver.linear=\"iterative\"",
            ],
        );
        let whole = dir.join("whole");
        let output = run(1, &whole, &args);
        assert!(output.status.success(), "{}", text(&output));

        let stopped = dir.join("stopped");
        let _ = std::fs::remove_dir_all(&stopped);
        let child = Command::new("mpirun")
            .args(["--allow-run-as-root", "--oversubscribe", "-n", "2", CLI, "run"])
            .args(&args)
            .arg("--out")
            .arg(&stopped)
            .arg("--quiet")
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("mpirun runs");
        // Once the run has completed a step (its first checkpoint), the ranks are signalled:
        // the processes whose command line names this folder after `run` (a signal before the
        // first step ends the run with nothing to continue from).
        let opened = std::time::Instant::now();
        while !stopped.join("checkpoint.bin").exists() {
            assert!(opened.elapsed().as_secs() < 120, "the run completed a step");
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        let pattern = format!("^{CLI} run .*{}", stopped.display());
        let signalled = Command::new("pkill").args(["-TERM", "-f", &pattern]).status().unwrap();
        assert!(signalled.success(), "the ranks were running");
        let output = child.wait_with_output().unwrap();
        let said = text(&output);
        assert!(!output.status.success(), "interrupted:\n{said}");
        let summary = std::fs::read_to_string(stopped.join("summary.json")).unwrap();
        assert!(summary.contains("\"interrupted\""), "{summary}\n{said}");
        assert!(stopped.join("checkpoint.bin").is_file(), "a checkpoint:\n{said}");

        for ranks in [3, 1] {
            let continued = dir.join(format!("continued-{ranks}"));
            let _ = std::fs::remove_dir_all(&continued);
            let copied = Command::new("cp")
                .arg("-r")
                .arg(&stopped)
                .arg(&continued)
                .status()
                .unwrap();
            assert!(copied.success());
            let restart = vec!["--restart".to_string(), continued.display().to_string()];
            let mut command = if ranks == 1 {
                Command::new(CLI)
            } else {
                let mut c = Command::new("mpirun");
                c.args(["--allow-run-as-root", "--oversubscribe", "-n", "3", CLI]);
                c
            };
            let output = command.arg("run").args(&restart).arg("--quiet").output().unwrap();
            assert!(output.status.success(), "continued on {ranks}:\n{}", text(&output));
            // The continued run's contact files of the output times after the checkpoint.
            let (_, a) = read_csv(&whole.join("contact_0016.csv"));
            let (header, b) = read_csv(&continued.join("contact_0016.csv"));
            for (c, column) in header.iter().enumerate() {
                let va: Vec<f64> = a.iter().map(|r| r[c].parse().unwrap()).collect();
                let vb: Vec<f64> = b.iter().map(|r| r[c].parse().unwrap()).collect();
                let scale = va.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
                let worst = va.iter().zip(&vb).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                let bound = if column == "slip" { 0.0 } else { FIELD_BOUND * scale };
                assert!(
                    worst <= bound,
                    "continued on {ranks}: {column} {worst:e} apart (largest {scale:e})"
                );
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
