//! What the sparse factorization of the step matrix costs, and what limits it in 3D.
//!
//! ```text
//! cargo run --release --example factor_fill -- scenarios/paper3d.toml --set mesh.nx=72 --set mesh.ny=18 --set mesh.nz=18
//! cargo run --release --example factor_fill -- scenarios/paper3d.toml --symbolic-only --set mesh.nx=104 ...
//! ```
//!
//! For a scenario (laid over the default like `thermocontact run`), it reports:
//!
//! 1. the discrete problem: unknowns and nnz of the reduced step matrix of Problem 14;
//! 2. the fill of a symmetric factorization L D Lᵀ of the same matrix under an AMD ordering
//!    (symbolic only, cheap): the step matrix with its temperature rows negated,
//!    [ℳ/k + 𝒦_A + k𝒦_B, G; Gᵀ, −(ℳ_θ/k + 𝒦_θ)], is symmetric quasi-definite, so it has an
//!    L D Lᵀ for every symmetric ordering;
//! 3. unless `--symbolic-only`: the time of the factorization the solver uses
//!    (`StepSystem::new`: assembly of the reduced matrix and its L D Lᵀ), and the process's peak
//!    resident memory (VmHWM from /proc/self/status, Linux) after it.
//!
//! Measured at 98 334 unknowns of the 3D scenario (72 × 18 × 18 cells): nnz(L) = 127 M,
//! `StepSystem::new` 15 s, peak 1.5 GB (the sparse LU it replaced took minutes and ~8 GB).

use std::time::Instant;

use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymmetricOrdering};
use faer::sparse::SymbolicSparseColMat;
use faer::Side;
use thermocontact::la::NodeGraph;
use thermocontact::step::StepSystem;
use thermocontact::{Problem, Scenario};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let (mut file, mut overrides, mut symbolic_only) = (None, Vec::new(), false);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--set" => overrides.push(args.next().ok_or_else(|| anyhow::anyhow!("--set needs KEY=VALUE"))?),
            "--symbolic-only" => symbolic_only = true,
            path => file = Some(std::fs::read_to_string(path)?),
        }
    }
    let scenario = Scenario::load(file.as_deref(), &overrides)?;

    let clock = Instant::now();
    let problem = scenario.build()?;
    let assembly = clock.elapsed().as_secs_f64();
    let (col_ptr, row_idx) = lower_pattern(&problem);
    let n = problem.n_unknowns();
    let nnz_lower = row_idx.len();
    println!(
        "unknowns {n} ({} velocity + {} temperature), contact nodes {}, nnz(A) {}, assembly {assembly:.2} s",
        problem.n_w(),
        problem.temperature.n_free,
        problem.contact.len(),
        2 * nnz_lower - n
    );

    let clock = Instant::now();
    let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    let symbolic = factorize_symbolic_cholesky(
        pattern.as_ref(),
        Side::Lower,
        SymmetricOrdering::Amd,
        Default::default(),
    )
    .map_err(|e| anyhow::anyhow!("symbolic factorization: {e:?}"))?;
    println!(
        "AMD L D Lᵀ (symbolic): nnz(L) {} = {:.2} GB of values, {:.2} s",
        symbolic.len_val(),
        symbolic.len_val() as f64 * 8e-9,
        clock.elapsed().as_secs_f64()
    );
    if symbolic_only {
        return Ok(());
    }
    let clock = Instant::now();
    let system = StepSystem::new(&problem)?;
    println!(
        "L D Lᵀ factorization (StepSystem::new): {:.2} s, peak resident memory {}",
        clock.elapsed().as_secs_f64(),
        peak_memory()
    );
    anyhow::ensure!(
        system.matrix().nnz() == 2 * nnz_lower - n,
        "the pattern above ({}) is not the step matrix's ({})",
        2 * nnz_lower - n,
        system.matrix().nnz()
    );
    Ok(())
}

/// The lower triangle (with diagonal) of the reduced step matrix's pattern, which is
/// structurally symmetric: unknowns of nodes p and q couple when p and q share a cell.
fn lower_pattern(problem: &Problem) -> (Vec<usize>, Vec<usize>) {
    let mesh = &problem.mesh;
    let d = mesh.dim;
    let n_w = problem.n_w();
    let unknowns: Vec<Vec<usize>> = (0..mesh.n_nodes())
        .map(|p| {
            let mut u: Vec<usize> = (0..d)
                .flat_map(|c| problem.velocity.row(p * d + c).iter().map(|&(j, _)| j))
                .collect();
            u.extend(problem.temperature.free[p].map(|r| n_w + r));
            u.sort_unstable();
            u.dedup();
            u
        })
        .collect();
    let graph = NodeGraph::new(mesh.n_nodes(), &mesh.cells, mesh.nodes_per_cell());
    let n = problem.n_unknowns();
    let mut columns: Vec<Vec<usize>> = vec![Vec::new(); n];
    for q in 0..mesh.n_nodes() {
        for &p in graph.neighbours(q) {
            for &c in &unknowns[q] {
                columns[c].extend(unknowns[p].iter().filter(|&&r| r >= c));
            }
        }
    }
    let mut col_ptr = vec![0];
    let mut row_idx = Vec::new();
    for mut col in columns {
        col.sort_unstable();
        col.dedup();
        row_idx.extend(col);
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}

/// VmHWM of this process, as /proc/self/status writes it.
fn peak_memory() -> String {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM"))
                .map(|l| l[6..].trim().to_string())
        })
        .unwrap_or_else(|| "(unknown: no /proc/self/status)".into())
}
