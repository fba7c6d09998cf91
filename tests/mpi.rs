//! The distributed foundation under `mpirun` (cargo feature `mpi`; docs/distributed.md): the
//! communicator, the partition of the 3D example's mesh, and the distributed assembly and solve
//! of the step matrix, on 1, 2 and 3 ranks against the serial direct solve.
//!
//! Each `on_*_ranks` test starts this test binary under `mpirun -n P` (`--oversubscribe`: CI has
//! 2 cores) with `THERMOCONTACT_MPI_RANK_PROGRAM` set, which makes `rank_program` run on every
//! rank (it does nothing otherwise); a failure on a rank ends all of them through
//! `Communicator::abort_all`, with the message once, and the test fails on mpirun's status
//! (which a test of its own checks, with a failure forced on one rank).
//! Built without the feature, the file is one test that says it skipped.

#[cfg(not(feature = "mpi"))]
#[test]
fn skipped_without_the_mpi_feature() {
    eprintln!("tests/mpi.rs skipped: built without the `mpi` feature (run `cargo test --features mpi --test mpi`)");
}

#[cfg(feature = "mpi")]
mod distributed {
    use std::process::Command;

    use thermocontact::la::mpi::{
        Communicator, DistributedKrylov, DistributedMatrix, DistributedPreconditioner, GhostedVector, Reduction,
    };
    use thermocontact::la::{CsrMatrix, Ilu0, LaError, Preconditioner, QuasiDefiniteLdlt};
    use thermocontact::mesh::cuboid;
    use thermocontact::model::{samples, DistributedStepMatrix, Problem, State, StepMatrix};
    use thermocontact::partition::{DofLayout, MeshPartition};

    const PROGRAM: &str = "THERMOCONTACT_MPI_RANK_PROGRAM";

    /// Runs [`rank_program`] (`program`: "checks" or "fail") on `ranks` ranks, at most 300 s:
    /// mpirun's exit status and output.
    fn mpirun(ranks: usize, program: &str) -> (std::process::ExitStatus, String) {
        let exe = std::env::current_exe().unwrap();
        let output = Command::new("timeout")
            .args([
                "300",
                "mpirun",
                "--allow-run-as-root",
                "--oversubscribe",
                "-n",
                &ranks.to_string(),
            ])
            .arg(exe)
            .args([
                "--exact",
                "distributed::rank_program",
                "--nocapture",
                "--test-threads=1",
            ])
            .env(PROGRAM, program)
            .env("RAYON_NUM_THREADS", "1")
            .output()
            .expect("mpirun (Debian: apt-get install openmpi-bin) runs");
        let text = format!(
            "{}\n{}",
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
        (output.status, text)
    }

    /// The checks of [`rank_program`] pass on every rank.
    fn checks_pass(ranks: usize) {
        let (status, text) = mpirun(ranks, "checks");
        assert!(status.success(), "mpirun -n {ranks} failed ({status}):\n{text}");
        assert_eq!(text.matches("rank program done").count(), ranks, "{text}");
    }

    #[test]
    fn on_one_rank() {
        checks_pass(1);
    }

    #[test]
    fn on_two_ranks() {
        checks_pass(2);
    }

    #[test]
    fn on_three_ranks() {
        checks_pass(3);
    }

    /// The last of 3 ranks fails while the others wait in a barrier: every rank ends (no hang:
    /// `timeout` would exit 124), mpirun's status is non-zero, the message printed once.
    #[test]
    fn a_failure_on_one_rank_ends_every_rank_with_its_message_once() {
        let (status, text) = mpirun(3, "fail");
        assert!(!status.success() && status.code() != Some(124), "{status}:\n{text}");
        assert_eq!(text.matches("a failure forced on the last rank").count(), 1, "{text}");
        assert!(text.contains("(rank 2 of 3)"), "{text}");
        assert!(!text.contains("rank program done"), "{text}");
    }

    /// What every rank runs under `mpirun`; a panic on one rank aborts them all with its message.
    #[test]
    fn rank_program() {
        if std::env::var_os(PROGRAM).is_none() {
            return;
        }
        let comm = Communicator::world().unwrap();
        if std::env::var(PROGRAM).unwrap() == "fail" {
            if comm.rank() + 1 == comm.size() {
                comm.abort_all("a failure forced on the last rank", 3);
            }
            comm.barrier().unwrap();
        }
        let outcome = std::panic::catch_unwind(|| {
            the_communicator_reduces_and_broadcasts(&comm);
            a_laplacian_assembled_by_elements_on_all_ranks_is_exact(&comm);
            the_partition_is_the_same_on_every_rank(&comm);
            let k_2d = samples::paper(16, 4, 8).unwrap();
            the_distributed_step_solve_equals_the_serial_one(&comm, &k_2d, "2D 16 × 4");
            let k_3d = samples::paper_3d([12, 3, 3], 8).unwrap();
            the_distributed_step_solve_equals_the_serial_one(&comm, &k_3d, "3D 12 × 3 × 3");
        });
        if let Err(panic) = outcome {
            let message = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            comm.abort_all(&format!("rank program failed: {message}"), 1);
        }
        comm.barrier().unwrap();
        println!("rank {} of {}: rank program done", comm.rank(), comm.size());
    }

    /// Sum, max and min over the ranks of f64 and usize values; rank 0's bytes everywhere.
    fn the_communicator_reduces_and_broadcasts(comm: &Communicator) {
        let (rank, size) = (comm.rank(), comm.size());
        let mut values = [rank as f64 + 1.0, -(rank as f64), rank as f64];
        comm.all_reduce_f64(&mut values[..1], Reduction::Sum).unwrap();
        comm.all_reduce_f64(&mut values[1..2], Reduction::Min).unwrap();
        comm.all_reduce_f64(&mut values[2..], Reduction::Max).unwrap();
        assert_eq!(
            values,
            [(size * (size + 1) / 2) as f64, -(size as f64 - 1.0), size as f64 - 1.0]
        );
        let mut counts = [rank, 7];
        comm.all_reduce_usize(&mut counts, Reduction::Sum).unwrap();
        assert_eq!(counts, [size * (size - 1) / 2, 7 * size]);
        let mut bytes = if comm.is_root() {
            b"from rank 0".to_vec()
        } else {
            vec![9; rank]
        };
        comm.broadcast_bytes(&mut bytes).unwrap();
        assert_eq!(bytes, b"from rank 0");
    }

    /// −u'' = 1 on (0, 1), u(0) = u(1) = 0, by P1 on 60 elements: the nodal values are exact,
    /// u(x) = x(1 − x)/2. The element matrices (1/h)[1 −1; −1 1] and loads h/2 go to PETSc
    /// from the rank e mod P, whichever rank owns their rows (PETSc sends them and sums); the
    /// rows are split in consecutive runs. GMRES + block Jacobi/ILU(0) to 1e-12.
    fn a_laplacian_assembled_by_elements_on_all_ranks_is_exact(comm: &Communicator) {
        let (n_elements, size, rank) = (60, comm.size(), comm.rank());
        let n = n_elements - 1; // interior nodes 1..n_elements-1, unknown i - 1
        let h = 1.0 / n_elements as f64;
        let n_owned = n / size + usize::from(rank < n % size);
        let (mut rows, mut cols, mut values, mut index, mut load) = (vec![], vec![], vec![], vec![], vec![]);
        for e in (rank..n_elements).step_by(size) {
            let unknowns = [e.checked_sub(1), Some(e).filter(|&i| i < n)];
            for (a, row) in unknowns.iter().enumerate() {
                let Some(row) = row else { continue };
                index.push(*row);
                load.push(h / 2.0);
                for (b, col) in unknowns.iter().enumerate() {
                    if let Some(col) = col {
                        rows.push(*row);
                        cols.push(*col);
                        values.push(if a == b { 1.0 / h } else { -1.0 / h });
                    }
                }
            }
        }
        let mut matrix = DistributedMatrix::new(comm, n_owned, 1, &rows, &cols).unwrap();
        assert_eq!(matrix.n_global(), n);
        matrix.set_values(&values).unwrap();
        let params = DistributedKrylov {
            rtol: 1e-12,
            ..DistributedKrylov::default()
        };
        let (owned, _) = matrix.solve(&params, &index, &load).unwrap();
        for (i, u) in matrix.owned().zip(owned) {
            let x = (i + 1) as f64 * h;
            assert!((u - x * (1.0 - x) / 2.0).abs() < 1e-11, "u({x}) = {u}");
        }
        let whole = matrix.gather_on_root(comm).unwrap();
        assert_eq!(whole.map(|w| w.len()), comm.is_root().then_some(n));
        // Entries of any rank, a different selection on each, in no order: their exact values.
        let selected = [n - 1 - rank, 0, (7 * rank + 3) % n, n / 2];
        matrix.select(&selected).unwrap();
        let mut values = [0.0; 4];
        matrix.gather_selected(&mut values).unwrap();
        for (i, u) in selected.iter().zip(values) {
            let x = (i + 1) as f64 * h;
            assert!((u - x * (1.0 - x) / 2.0).abs() < 1e-11, "selected u({x}) = {u}");
        }
        assert!(matrix.select(&[n]).is_err());
        let (mut ptr, mut cols, mut values) = (vec![0], vec![], vec![]);
        for i in matrix.owned() {
            for j in [i.checked_sub(1), Some(i), Some(i + 1).filter(|&j| j < n)]
                .into_iter()
                .flatten()
            {
                cols.push(j as u32);
                values.push(if i == j { 2.0 / h } else { -1.0 / h });
            }
            ptr.push(cols.len());
        }
        let by_rows = DistributedMatrix::from_rows(comm, &ptr, &cols, &values).unwrap();
        assert_eq!((by_rows.owned(), by_rows.n_global()), (matrix.owned(), n));
        a_changed_row_solved_with_the_callers_blocks_is_exact(by_rows, h);
        let by_rows = DistributedMatrix::from_rows(comm, &ptr, &cols, &values).unwrap();
        overlapping_blocks_solve_it_exactly(by_rows, (&ptr, &cols, &values), h);
    }

    /// The same system given as each rank's CSR rows, each rank's last row (and its load) then
    /// doubled through `set_rows`,
    /// solved from zero by GCR with block Jacobi whose blocks apply the ILU(0) of each rank's
    /// tridiagonal block (exact there) through PETSc's PCSHELL: the same exact nodal values. The
    /// shell without a block preconditioner is an error, not a crash.
    fn a_changed_row_solved_with_the_callers_blocks_is_exact(mut matrix: DistributedMatrix, h: f64) {
        let (owned, n) = (matrix.owned(), matrix.n_global());
        let last = owned.end - 1;
        let neighbours: Vec<usize> = [last.checked_sub(1), Some(last), Some(last + 1).filter(|&j| j < n)]
            .into_iter()
            .flatten()
            .collect();
        let doubled: Vec<f64> = neighbours
            .iter()
            .map(|&j| if j == last { 4.0 / h } else { -2.0 / h })
            .collect();
        let pattern = matrix
            .row_pattern(&[last], &[0, neighbours.len()], &neighbours)
            .unwrap();
        matrix.set_rows(&pattern, &doubled).unwrap();
        let (mut ptr, mut col, mut val) = (vec![0], vec![], vec![]);
        for i in owned.clone() {
            for j in [i.checked_sub(1), Some(i), Some(i + 1)].into_iter().flatten() {
                if owned.contains(&j) {
                    col.push((j - owned.start) as u32);
                    let scale = if i == last { 2.0 } else { 1.0 };
                    val.push(scale * if i == j { 2.0 / h } else { -1.0 / h });
                }
            }
            ptr.push(col.len());
        }
        let block = Ilu0::new(&CsrMatrix::from_rows(owned.len(), ptr, col, val)).unwrap();
        let rhs: Vec<f64> = owned.clone().map(|i| if i == last { 2.0 * h } else { h }).collect();
        let params = DistributedKrylov {
            preconditioner: DistributedPreconditioner::BlockJacobiShell,
            rtol: 1e-12,
            ..DistributedKrylov::default()
        };
        let mut u = vec![0.0; owned.len()];
        assert!(matrix.solve_from(&params, (&rhs, &mut u), None, None).is_err());
        let info = matrix.solve_from(&params, (&rhs, &mut u), None, Some(&block)).unwrap();
        assert_exact(
            owned.clone(),
            &u,
            h,
            &format!("block Jacobi, {} iterations", info.iterations),
        );
        // Without a preconditioner (the identity as each rank's block) the solve needs more
        // iterations than GCR's first restart (10): it goes on with the asked restart from
        // where it stopped, and so does the next solve, to the same exact values and the
        // residual handed over.
        struct Identity;
        impl Preconditioner for Identity {
            fn apply(&self, r: &[f64], z: &mut [f64]) -> Result<(), LaError> {
                z.copy_from_slice(r);
                Ok(())
            }
            fn method(&self) -> &'static str {
                "GCR"
            }
        }
        for _ in 0..2 {
            let (mut u, mut residual) = (vec![0.0; owned.len()], Vec::new());
            let info = (matrix.solve_from(&params, (&rhs, &mut u), Some(&mut residual), Some(&Identity))).unwrap();
            assert!(info.iterations > 10, "{info:?}");
            assert_exact(
                owned.clone(),
                &u,
                h,
                &format!("unpreconditioned, {} iterations", info.iterations),
            );
            assert!(
                residual.iter().all(|r| r.abs() <= 1e-12 * 2.0 * h * n as f64),
                "{residual:?}"
            );
        }
    }

    /// u at the unknowns `owned` (node i + 1 of the 1D mesh of step h) is x(1 − x)/2 to 1e-11.
    fn assert_exact(owned: std::ops::Range<usize>, u: &[f64], h: f64, what: &str) {
        for (i, u) in owned.zip(u) {
            let x = (i + 1) as f64 * h;
            assert!((u - x * (1.0 - x) / 2.0).abs() < 1e-11, "{what}: u({x}) = {u}");
        }
    }

    /// The same system by rows (`rows`: this rank's, global columns), solved by restricted
    /// additive Schwarz: each rank's block is its rows and the rows of other ranks that they
    /// read (its overlap), numbered [owned, overlap], the rank's own read where PETSc keeps them
    /// (`split_rows`), the overlap's fetched from their ranks (`fetch_rows`); its ILU(0) through
    /// PETSc's PCSHELL gives the exact nodal values. An overlap naming an owned row is an error.
    /// The solve's residual, handed to the next solve (every right-hand side doubled), starts it
    /// without a product: 2u; a zero residual handed over leaves u as it is.
    fn overlapping_blocks_solve_it_exactly(mut matrix: DistributedMatrix, rows: (&[usize], &[u32], &[f64]), h: f64) {
        let (owned, n) = (matrix.owned(), matrix.n_global());
        let (ptr, cols, values) = rows;
        let mut overlap: Vec<usize> = (cols.iter().map(|&c| c as usize))
            .filter(|c| !owned.contains(c))
            .collect();
        overlap.sort_unstable();
        overlap.dedup();
        assert!(matrix.set_overlap(&[owned.start]).is_err());
        matrix.set_overlap(&overlap).unwrap();
        let n_owned = owned.len();
        let block_col = |g: usize| match owned.contains(&g) {
            true => (g - owned.start) as u32,
            false => (n_owned + overlap.binary_search(&g).unwrap()) as u32,
        };
        let split = matrix.split_rows().expect("rows kept where they are given");
        let (mut block_ptr, mut block_col_of, mut block_values) = (vec![0], vec![], vec![]);
        for r in 0..n_owned {
            let ((diagonal_cols, diagonal_values), off_values) = split.row(r);
            let entries = ptr[r]..ptr[r + 1];
            let (inside, outside): (Vec<usize>, Vec<usize>) =
                entries.partition(|&e| owned.contains(&(cols[e] as usize)));
            let local: Vec<u32> = inside.iter().map(|&e| block_col(cols[e] as usize)).collect();
            let given: Vec<f64> = inside.iter().map(|&e| values[e]).collect();
            assert_eq!(diagonal_cols, &local[..], "row {r}'s diagonal block as given");
            assert_eq!(diagonal_values, &given[..], "row {r}'s diagonal block as given");
            assert_eq!(off_values.len(), outside.len(), "row {r}'s off-diagonal part as given");
            let mut row: Vec<(u32, f64)> = (local.iter().copied().zip(diagonal_values.iter().copied()))
                .chain(
                    outside
                        .iter()
                        .map(|&e| block_col(cols[e] as usize))
                        .zip(off_values.iter().copied()),
                )
                .collect();
            row.sort_by_key(|e| e.0);
            block_col_of.extend(row.iter().map(|e| e.0));
            block_values.extend(row.iter().map(|e| e.1));
            block_ptr.push(block_col_of.len());
        }
        let mut columns: Vec<usize> = overlap.iter().copied().chain(owned.clone()).collect();
        columns.sort_unstable();
        let (fetched_ptr, fetched_cols, fetched_values) = matrix.fetch_rows(&overlap, &columns).unwrap();
        for (v, &g) in overlap.iter().enumerate() {
            let mut row: Vec<(u32, f64)> = (fetched_ptr[v]..fetched_ptr[v + 1])
                .map(|e| (block_col(columns[fetched_cols[e] as usize]), fetched_values[e]))
                .collect();
            assert!(
                row.iter().any(|&(c, value)| c == block_col(g) && value == 2.0 / h),
                "row {g}'s diagonal"
            );
            row.sort_by_key(|e| e.0);
            block_col_of.extend(row.iter().map(|e| e.0));
            block_values.extend(row.iter().map(|e| e.1));
            block_ptr.push(block_col_of.len());
        }
        let size = n_owned + overlap.len();
        let block = Ilu0::new(&CsrMatrix::from_rows(size, block_ptr, block_col_of, block_values)).unwrap();
        let params = DistributedKrylov {
            preconditioner: DistributedPreconditioner::SchwarzShell,
            rtol: 1e-12,
            ..DistributedKrylov::default()
        };
        let rhs = vec![h; n_owned];
        let mut u = vec![0.0; n_owned];
        assert!(matrix.solve_from(&params, (&rhs, &mut u), None, None).is_err());
        let mut residual = Vec::new();
        let info = (matrix.solve_from(&params, (&rhs, &mut u), Some(&mut residual), Some(&block))).unwrap();
        let what = format!("restricted Schwarz, {} iterations of {n} unknowns", info.iterations);
        assert_exact(owned.clone(), &u, h, &what);
        // The solver's residual b − A u at this rank's rows, handed over without a product.
        assert_eq!(residual.len(), n_owned);
        assert!(residual.iter().all(|r| r.abs() <= 1e-12 * h * n as f64), "{residual:?}");
        // A Newton iteration's next solve: every right-hand side doubled, started from u with
        // its residual there (r + h 1, no product with A), gives 2u.
        let doubled: Vec<f64> = rhs.iter().map(|b| 2.0 * b).collect();
        let mut carried = residual.clone();
        carried.iter_mut().zip(&rhs).for_each(|(r, b)| *r += b);
        let mut v = u.clone();
        matrix
            .solve_from(&params, (&doubled, &mut v), Some(&mut carried), Some(&block))
            .unwrap();
        let half: Vec<f64> = v.iter().map(|v| v / 2.0).collect();
        assert_exact(owned.clone(), &half, h, "the carried residual's solve, halved");
        // An inexact Newton iteration's solve (forcing η = 0.1) of the doubled system from
        // x₀ = 2(1 − ε)u, whose residual r₀ = 2εh 1 + 2(1 − ε) r is ε = 10⁻³ of b: it must
        // iterate (‖r₀‖ > η ‖r₀‖, however small r₀ is against b) and stop at ‖b − A x‖ ≤ η ‖r₀‖,
        // with r₀ given and without (PETSc's own relative test from a guess is on ‖b‖: it
        // would stop at once here).
        let eps = 1e-3;
        let start: Vec<f64> = u.iter().map(|u| 2.0 * (1.0 - eps) * u).collect();
        let r0: Vec<f64> = residual.iter().map(|r| 2.0 * eps * h + 2.0 * (1.0 - eps) * r).collect();
        for given in [true, false] {
            let mut x = start.clone();
            let mut carried = if given { r0.clone() } else { Vec::new() };
            let info = (matrix.solve_from_inexact(&params, (&doubled, &mut x), Some(&mut carried), Some(&block), 0.1))
                .unwrap();
            assert!(
                info.iterations >= 1 && info.residual <= 0.1 * eps * (1.0 + 1e-6),
                "r₀ given: {given}, {info:?}"
            );
        }
        // The solve trusts the residual it is given: zero says u solves the doubled system, and
        // u stays (so the one above started from the residual, not from a product).
        let mut trusted = vec![0.0; n_owned];
        let mut w = u.clone();
        let info = (matrix.solve_from(&params, (&doubled, &mut w), Some(&mut trusted), Some(&block))).unwrap();
        assert_eq!((info.iterations, &w), (0, &u));
    }

    /// The cells' parts computed on rank 0 reach every rank: the same checksum everywhere. A
    /// nodal field (one unknown per node, as θ) in the partition's layout, with the ghosts of
    /// each rank as a `VecGhost`: after the update, every ghost holds its owner's value.
    fn the_partition_is_the_same_on_every_rank(comm: &Communicator) {
        let mesh = cuboid([40.0, 10.0, 10.0], [12, 3, 3]);
        let partition = MeshPartition::on_root(comm, &mesh).unwrap();
        let layout = DofLayout::new(&partition, mesh.n_nodes(), |p, out| out.push(p));
        let field = |p: usize| 0.5 * p as f64 + mesh.coords[p][2];
        let ghosts = partition.ghost_nodes(&mesh, comm.rank());
        let ghost_index: Vec<usize> = ghosts.iter().map(|&p| layout.index_of[p]).collect();
        let mut vector = GhostedVector::new(layout.owned(comm.rank()).len(), &ghost_index).unwrap();
        let owned: Vec<f64> = layout.owned(comm.rank()).map(|g| field(layout.order[g])).collect();
        vector.update(&owned).unwrap();
        let local = vector.local().unwrap();
        assert_eq!(local[..owned.len()], owned[..]);
        for (&p, &value) in ghosts.iter().zip(&local[owned.len()..]) {
            assert_eq!(value, field(p), "ghost node {p} on rank {}", comm.rank());
        }
        assert!(
            comm.rank() > 0 || ghosts.is_empty(),
            "rank 0 owns every node of its cells"
        );
        let mut n_ghosts = [ghosts.len()];
        comm.all_reduce_usize(&mut n_ghosts, Reduction::Sum).unwrap();
        assert_eq!(
            n_ghosts[0] > 0,
            comm.size() > 1,
            "{} ghosts over the ranks",
            n_ghosts[0]
        );
        let checksum = partition
            .cell_part
            .iter()
            .enumerate()
            .map(|(e, &p)| (e % 97 + 1) * (p + 1))
            .sum::<usize>();
        let mut range = [checksum as f64, -(checksum as f64)];
        comm.all_reduce_f64(&mut range[..1], Reduction::Max).unwrap();
        comm.all_reduce_f64(&mut range[1..], Reduction::Max).unwrap();
        assert_eq!((range[0], -range[1]), (checksum as f64, checksum as f64));
        assert_eq!(partition.n_parts, comm.size());
    }

    /// A x = b with A the step matrix of the example's step size and b its first step's
    /// right-hand side, distributed (GMRES + block Jacobi/ILU(0), rtol 1e-10 on the true
    /// residual) against the serial LDLᵀ of the symmetric form S = J A: the same solution within
    /// ‖x − x_LDLᵀ‖∞ ≤ 1e-7 ‖x_LDLᵀ‖∞ (κ(A) · rtol with room; measured: 1e-11 to 1e-9), on rank 0.
    /// And with GAMG as the preconditioner on the same matrix.
    fn the_distributed_step_solve_equals_the_serial_one(comm: &Communicator, problem: &Problem, case: &str) {
        let k = problem.time_step();
        let partition = MeshPartition::on_root(comm, &problem.mesh).unwrap();
        let mut distributed = DistributedStepMatrix::assemble(comm, problem, &partition, k).unwrap();
        let serial = StepMatrix::assemble(problem, k);
        let b = serial.rhs.rhs(problem, &State::initial(problem), k, None).unwrap();
        let reference = comm.is_root().then(|| {
            let mut x = b.clone();
            x[serial.rhs.n_w()..].iter_mut().for_each(|v| *v = -*v);
            QuasiDefiniteLdlt::new(&serial.matrix)
                .unwrap()
                .solve_in_place(&mut x, 1);
            x
        });
        for preconditioner in [
            DistributedPreconditioner::BlockJacobiIlu0,
            DistributedPreconditioner::Gamg,
        ] {
            let params = DistributedKrylov {
                preconditioner,
                rtol: 1e-10,
                ..DistributedKrylov::default()
            };
            let (_, info) = distributed.solve(&params, &b).unwrap();
            if let (Some(x), Some(reference)) = (distributed.gather_on_root(comm).unwrap(), &reference) {
                let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let error = x.iter().zip(reference).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                println!(
                    "{case}, {} ranks, {preconditioner:?}: {} unknowns, {} GMRES iterations, relative residual {:.1e}, \
                     ‖x − x_LDLᵀ‖∞/‖x_LDLᵀ‖∞ = {:.1e}",
                    comm.size(),
                    b.len(),
                    info.iterations,
                    info.residual,
                    error / scale
                );
                assert!(error <= 1e-7 * scale, "{case}: {error:e} against {scale:e}");
            }
        }
    }

    /// The 3D example's 12 × 3 × 3 mesh in 3 parts by PT-Scotch: cells within 5 % of a third
    /// each, every node owned once, the ghosts of a part the non-owned nodes of its cells (and
    /// only those), owned by a lower part. One process (no `mpirun`).
    #[test]
    fn the_3d_example_splits_into_balanced_parts() {
        let mesh = cuboid([40.0, 10.0, 10.0], [12, 3, 3]);
        let parts = 3;
        let partition = MeshPartition::new(&mesh, parts).unwrap();
        let n_cells = mesh.n_cells();
        let mut owned_nodes = vec![0; mesh.n_nodes()];
        for part in 0..parts {
            let cells = partition.cells_of(part).len() as f64;
            let share = n_cells as f64 / parts as f64;
            assert!(
                (cells - share).abs() <= 0.05 * share,
                "part {part}: {cells} cells of {n_cells}"
            );
            partition.owned_nodes(part).iter().for_each(|&p| owned_nodes[p] += 1);
            let mut of_cells: Vec<usize> = partition
                .cells_of(part)
                .iter()
                .flat_map(|&e| mesh.cell(e).to_vec())
                .collect();
            of_cells.sort_unstable();
            of_cells.dedup();
            let ghosts = partition.ghost_nodes(&mesh, part);
            let expected: Vec<usize> = of_cells
                .into_iter()
                .filter(|&p| partition.node_owner[p] != part)
                .collect();
            assert_eq!(ghosts, expected);
            assert!(ghosts.iter().all(|&p| partition.node_owner[p] < part));
        }
        assert!(owned_nodes.iter().all(|&c| c == 1), "every node owned once");
        let total: usize = (0..parts).map(|p| partition.cells_of(p).len()).sum();
        assert_eq!(total, n_cells, "every cell once");
    }
}
