//! How cheap can the per-step sparse solves of the 2D reference run get? (A measured study;
//! the numbers and the recommendation are in docs/linear-algebra-study.md.)
//!
//! ```text
//! CARGO_TARGET_DIR=/work/target-la cargo run --release --example solve_study
//! CARGO_TARGET_DIR=/work/target-la cargo run --release --example solve_study -- --set mesh.nx=128
//! ```
//!
//! On the step matrix of the reference run (`--set mesh.nx=256 --set mesh.ny=64
//! --set time.steps=64`, further `--set`s are laid over it), S = J A = [K_w, G; Gᵀ, −K_θ], it
//! measures:
//!
//! 1. the production factorization ([`QuasiDefiniteLdlt`], faer supernodal LDLᵀ under AMD):
//!    nnz(L), factor time, single-RHS solve time (median);
//! 2. S under nested-dissection orderings (METIS `NodeND` through `metis-sys`, and the pure-Rust
//!    `feral-metis` and `feral-scotch`), and with a simplicial factor;
//! 3. K_w and K_θ factored separately (LLᵀ), and a block Gauss–Seidel solve of the coupled
//!    system with them to relative residual 1e-12;
//! 4. `Par::rayon(2)` inside one solve, and blocks of several right-hand sides;
//! 5. the 256-column condensation block as `Condensation::new` solves it (two halves on the two
//!    cores), per ordering;
//! 6. the peak resident memory added by each factorization (VmHWM, reset through
//!    /proc/self/clear_refs; Linux only).

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;
use thermocontact::fem::sparse::CscMatrix;
use thermocontact::solver::factor::QuasiDefiniteLdlt;
use thermocontact::solver::system::{State, StepSystem};
use thermocontact::{Problem, Scenario};

/// Repetitions of a single-RHS solve (the median is reported).
const REPEATS: usize = 25;

fn main() -> anyhow::Result<()> {
    let mut overrides: Vec<String> = vec!["mesh.nx=256".into(), "mesh.ny=64".into(), "time.steps=64".into()];
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--set" => overrides.push(args.next().ok_or_else(|| anyhow::anyhow!("--set needs KEY=VALUE"))?),
            other => anyhow::bail!("unknown argument {other}"),
        }
    }
    let scenario = Scenario::load(None, &overrides)?;
    let problem = scenario.build()?;
    let system = StepSystem::new(&problem)?;
    let s = system.matrix();
    let (n, n_w) = (s.n_rows, system.n_w());
    println!(
        "S: {n} unknowns ({n_w} velocity + {} temperature), nnz(S) {}, rayon threads {}",
        n - n_w,
        s.nnz(),
        rayon::current_num_threads()
    );

    // Right-hand sides: a realistic one (step 5 after four contact-free steps), a random one and
    // one condensation column (unit tangential load at the middle contact node).
    let rhs_real = realistic_rhs(&problem, &system)?;
    let rhs_rand = random_vector(n, 7);
    let mut rhs_unit = vec![0.0; n];
    let middle = &problem.contact[problem.contact.len() / 2];
    rhs_unit[middle.tangent_dofs[0].expect("a free tangential dof")] = 1.0;
    // The three as right-hand sides of S x = J b.
    let flip = |b: &[f64]| -> Vec<f64> {
        b.iter()
            .enumerate()
            .map(|(i, v)| if i < n_w { *v } else { -v })
            .collect()
    };
    let (sb_real, sb_rand) = (flip(&rhs_real), flip(&rhs_rand));

    // ---- 1. Production factorization. -------------------------------------------------------
    println!("\n## 1. Production QuasiDefiniteLdlt (faer supernodal LDLᵀ, AMD), single RHS");
    let base_mem = reset_peak();
    let clock = Instant::now();
    let production = QuasiDefiniteLdlt::new(s)?;
    let factor_s = clock.elapsed().as_secs_f64();
    let peak = peak_kb().saturating_sub(base_mem);
    let solve = median_time(|| {
        let mut x = sb_real.clone();
        production.solve_in_place(&mut x, 1);
    });
    println!(
        "production: nnz(L) {} ({:.1} MB of values), factor {:.3} s, solve {:.2} ms, peak +{} MB",
        production.factor_nnz(),
        production.factor_nnz() as f64 * 8e-6,
        factor_s,
        solve * 1e3,
        peak / 1024
    );
    let mut x_exact = sb_real.clone();
    production.solve_in_place(&mut x_exact, 1);
    println!(
        "relative residual of the production solve: {:.1e}",
        residual(s, &x_exact, &sb_real)
    );
    drop(production);

    // ---- 2. Orderings of S. -----------------------------------------------------------------
    println!("\n## 2. Orderings of S (LDLᵀ, supernodal unless noted), single RHS, Par::Seq");
    let orderings = orderings(s);
    let mut s_factors = Vec::new();
    for (name, perm, order_s) in &orderings {
        let f = Factor::new(s, perm.as_ref(), true, SupernodalThreshold::AUTO)?;
        f.report(&format!("S {name}"), *order_s, &sb_real, s);
        s_factors.push((name.clone(), f));
    }
    // Simplicial factor of S under the AMD and best ND orderings.
    for (name, perm, order_s) in orderings.iter().filter(|(name, _, _)| name == "AMD" || name == "METIS") {
        let f = Factor::new(s, perm.as_ref(), true, SupernodalThreshold::FORCE_SIMPLICIAL)?;
        f.report(&format!("S {name} simplicial"), *order_s, &sb_real, s);
    }

    // ---- 3. The blocks separately, block Gauss–Seidel. --------------------------------------
    println!("\n## 3. K_w and K_θ factored separately (LLᵀ), single RHS, Par::Seq");
    let (k_w, k_theta, g) = blocks(s, n_w);
    println!(
        "K_w {}×{} nnz {}, K_θ {}×{} nnz {}, G nnz {}",
        k_w.n_rows,
        k_w.n_cols,
        k_w.nnz(),
        k_theta.n_rows,
        k_theta.n_cols,
        k_theta.nnz(),
        g.nnz()
    );
    let mut block_factors = Vec::new();
    for (name, perm_w, order_w) in orderings_subset(&k_w) {
        let f_w = Factor::new(&k_w, perm_w.as_ref(), false, SupernodalThreshold::AUTO)?;
        let probe: Vec<f64> = rhs_real[..n_w].to_vec();
        f_w.report(&format!("K_w {name}"), order_w, &probe, &k_w);
        block_factors.push((name, f_w));
    }
    let mut theta_factors = Vec::new();
    for (name, perm_t, order_t) in orderings_subset(&k_theta) {
        let f_t = Factor::new(&k_theta, perm_t.as_ref(), false, SupernodalThreshold::AUTO)?;
        let probe: Vec<f64> = rhs_real[n_w..].to_vec();
        f_t.report(&format!("K_θ {name}"), order_t, &probe, &k_theta);
        theta_factors.push((name, f_t));
    }

    println!("\n### Block Gauss–Seidel on A x = b (w ← K_w⁻¹(b_w − Gθ), θ ← K_θ⁻¹(b_θ + Gᵀw)), to 1e-12");
    for ((name_w, f_w), (_, f_t)) in block_factors.iter().zip(&theta_factors) {
        for (label, b) in [
            ("realistic", &rhs_real),
            ("random", &rhs_rand),
            ("unit contact", &rhs_unit),
        ] {
            let sb = flip(b);
            let (sweeps, history) = gauss_seidel(f_w, f_t, &g, b, n_w, s, &sb, 1e-12, 60, true);
            let time = median_time(|| {
                gauss_seidel(f_w, f_t, &g, b, n_w, s, &sb, 0.0, sweeps, false);
            });
            let rate = if history.len() >= 3 {
                history[history.len() - 1] / history[history.len() - 2]
            } else {
                f64::NAN
            };
            println!(
                "GS {name_w} {label:>12}: {sweeps} sweeps to {:.1e} (last contraction {rate:.1e}), {:.2} ms; history {}",
                history.last().copied().unwrap_or(f64::NAN),
                time * 1e3,
                history.iter().map(|r| format!("{r:.0e}")).collect::<Vec<_>>().join(" ")
            );
        }
    }

    // ---- 4. Parallel solve and several RHS. -------------------------------------------------
    println!("\n## 4. Par::rayon(2) in one solve; blocks of m RHS (ms per block, ms per column)");
    for (name, f) in s_factors.iter().filter(|(name, _)| name == "AMD" || name == "METIS") {
        let seq = median_time(|| f.solve_copy(&sb_real, 1, Par::Seq));
        let par = median_time(|| f.solve_copy(&sb_real, 1, Par::rayon(2)));
        println!(
            "S {name}: 1 RHS Seq {:.2} ms, Par::rayon(2) {:.2} ms",
            seq * 1e3,
            par * 1e3
        );
        let two_separate = median_time(|| {
            f.solve_copy(&sb_real, 1, Par::Seq);
            f.solve_copy(&sb_rand, 1, Par::Seq);
        });
        let two_threads = median_time(|| {
            rayon::join(
                || f.solve_copy(&sb_real, 1, Par::Seq),
                || f.solve_copy(&sb_rand, 1, Par::Seq),
            );
        });
        println!(
            "S {name}: 2 RHS as 2 sequential solves {:.2} ms, on 2 threads (rayon::join) {:.2} ms",
            two_separate * 1e3,
            two_threads * 1e3
        );
        for m in [2usize, 4, 8, 16, 32, 128] {
            let block: Vec<f64> = (0..m)
                .flat_map(|j| if j % 2 == 0 { sb_real.clone() } else { sb_rand.clone() })
                .collect();
            for par in [Par::Seq, Par::rayon(2)] {
                let t = median_time(|| f.solve_copy(&block, m, par));
                println!(
                    "S {name}: {m:>3} RHS in one block, {:>9}: {:.2} ms, {:.3} ms per column",
                    par_name(par),
                    t * 1e3,
                    t * 1e3 / m as f64
                );
            }
        }
    }

    // ---- 5. The condensation block. ---------------------------------------------------------
    println!("\n## 5. The 256-column condensation block (unit tangential loads) as Condensation::new solves it");
    let n_t = problem.contact.len() * (problem.dim() - 1);
    let mut block = vec![0.0; n * n_t];
    for (j, column) in block.chunks_exact_mut(n).enumerate() {
        if let Some(dof) = problem.contact[j / (problem.dim() - 1)].tangent_dofs[j % (problem.dim() - 1)] {
            column[dof] = 1.0;
        }
    }
    for (name, f) in &s_factors {
        let halves = median_time_n(5, || {
            let mut work = block.clone();
            let half = n_t.div_ceil(2);
            work.par_chunks_mut(n * half)
                .for_each(|part| f.solve(part, part.len() / n, Par::Seq));
        });
        let whole = median_time_n(5, || f.solve_copy(&block, n_t, Par::rayon(2)));
        println!(
            "S {name}: {n_t} columns, 2 halves × Par::Seq on 2 threads {:.3} s; one block Par::rayon(2) {:.3} s",
            halves, whole
        );
    }

    // ---- 6. What a solve cannot beat: streaming the factor through memory. -----------------
    println!("\n## 6. Memory-bandwidth floor and 32-bit indices");
    let probe = vec![1.0f64; 5_129_118];
    // Eight independent accumulators, so that the loop is limited by memory, not by the latency
    // of the additions.
    let stream = median_time(|| {
        let mut acc = [0.0f64; 8];
        for chunk in probe.chunks_exact(8) {
            for (a, v) in acc.iter_mut().zip(chunk) {
                *a += v;
            }
        }
        acc.iter().sum::<f64>()
    });
    println!(
        "streaming 41.0 MB of f64 (the production factor's values) once: {:.2} ms ({:.1} GB/s); a solve reads them twice",
        stream * 1e3,
        41.0e-3 / stream
    );
    drop(probe);
    for (name, perm, _) in orderings.iter().filter(|(name, _, _)| name == "AMD" || name == "METIS") {
        for threshold in [SupernodalThreshold::AUTO, SupernodalThreshold::FORCE_SIMPLICIAL] {
            let (nnz, kind, solve, res) = u32_factor_solve(s, perm.as_ref(), threshold, &sb_real)?;
            println!(
                "S {name} u32 indices [{kind}] nnz(L) {nnz}, solve {:.2} ms, residual {res:.0e}",
                solve * 1e3
            );
        }
    }

    // ---- 7. Contact unknowns ordered last: the condensation from the trailing block of L. ---
    println!("\n## 7. Contact unknowns (tangential velocities, temperatures) ordered last");
    contact_last(&problem, s, n_w, &block, n_t, &sb_real)?;
    Ok(())
}

/// Orders the contact unknowns last (the rest by AMD or METIS), factors S (simplicial, to read
/// L), and computes the condensation block E S⁻¹ E_tᵀ from the trailing m × m block of L D Lᵀ
/// alone; checks it against full solves of the unit columns.
fn contact_last(
    problem: &Problem,
    s: &CscMatrix,
    n_w: usize,
    block: &[f64],
    n_t: usize,
    sb: &[f64],
) -> anyhow::Result<()> {
    let n = s.n_rows;
    // The contact unknowns: tangential velocity dofs first (in column order of the block), then
    // the temperature dofs of the contact nodes.
    let mut contact: Vec<usize> = problem
        .contact
        .iter()
        .flat_map(|c| c.tangent_dofs.iter().flatten().copied())
        .collect();
    let n_tan = contact.len();
    contact.extend(problem.contact.iter().filter_map(|c| c.theta_dof.map(|r| n_w + r)));
    let m = contact.len();
    let mut is_contact = vec![usize::MAX; n];
    for (k, &c) in contact.iter().enumerate() {
        is_contact[c] = k;
    }
    let rest: Vec<usize> = (0..n).filter(|&i| is_contact[i] == usize::MAX).collect();
    let mut local = vec![usize::MAX; n];
    for (k, &i) in rest.iter().enumerate() {
        local[i] = k;
    }
    let sub = CscMatrix::from_triplets(
        rest.len(),
        rest.len(),
        s.triplets()
            .filter(|&(r, c, _)| local[r] != usize::MAX && local[c] != usize::MAX)
            .map(|(r, c, v)| (local[r], local[c], v))
            .collect(),
    );
    println!(
        "{m} contact unknowns ({n_tan} tangential velocities + {} temperatures)",
        m - n_tan
    );
    for name in ["AMD", "METIS"] {
        let clock = Instant::now();
        let sub_perm: Vec<usize> = if name == "METIS" {
            metis_nd(&sub)
        } else {
            let sym = factorize_symbolic_cholesky(
                sub.to_faer().symbolic(),
                Side::Lower,
                SymmetricOrdering::Amd,
                Default::default(),
            )
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
            sym.perm().expect("AMD permutes").arrays().0.to_vec()
        };
        let fwd: Vec<usize> = sub_perm
            .iter()
            .map(|&k| rest[k])
            .chain(contact.iter().copied())
            .collect();
        let perm = with_inverse(fwd);
        let order_s = clock.elapsed().as_secs_f64();
        let sup = Factor::new(s, Some(&perm), true, SupernodalThreshold::AUTO)?;
        sup.report(&format!("S {name}, contact last"), order_s, sb, s);
        let f = Factor::new(s, Some(&perm), true, SupernodalThreshold::FORCE_SIMPLICIAL)?;
        f.report(&format!("S {name}, contact last"), order_s, sb, s);
        let full_block = median_time_n(3, || {
            let mut work = block.to_vec();
            let half = n_t.div_ceil(2);
            work.par_chunks_mut(n * half)
                .for_each(|part| sup.solve(part, part.len() / n, Par::Seq));
        });

        // Trailing block: L22 (unit lower, m × m) and D2 from the simplicial L D Lᵀ.
        let clock = Instant::now();
        let faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Simplicial(simp) = f.symbolic.raw() else {
            anyhow::bail!("expected a simplicial factor");
        };
        let l = simp.factor();
        let (col_ptr, row_idx) = (l.col_ptr(), l.row_idx());
        let first = n - m;
        let mut l22 = faer::Mat::<f64>::zeros(m, m);
        let mut d2 = vec![0.0; m];
        for j in first..n {
            for k in col_ptr[j]..col_ptr[j + 1] {
                let i = row_idx[k];
                if i == j {
                    d2[j - first] = f.values[k];
                } else {
                    l22[(i - first, j - first)] = f.values[k];
                }
            }
        }
        for j in 0..m {
            l22[(j, j)] = 1.0;
        }
        // X = (L22 D2 L22ᵀ)⁻¹ E for the n_tan tangential unit columns (positions 0..n_tan of the
        // trailing block, in the order of `contact`).
        let mut x = faer::Mat::<f64>::zeros(m, n_tan);
        for j in 0..n_tan {
            x[(j, j)] = 1.0;
        }
        faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(l22.as_ref(), x.as_mut(), Par::Seq);
        for j in 0..n_tan {
            for i in 0..m {
                x[(i, j)] /= d2[i];
            }
        }
        faer::linalg::triangular_solve::solve_unit_upper_triangular_in_place(l22.transpose(), x.as_mut(), Par::Seq);
        let trailing_s = clock.elapsed().as_secs_f64();

        // Check against the full solves: column j of `block` is the unit load at the j-th
        // tangential contact dof (column order = contact order, held coordinates skipped).
        let mut full = block.to_vec();
        sup.solve(&mut full, n_t, Par::Seq);
        let mut max_diff: f64 = 0.0;
        let mut max_val: f64 = 0.0;
        let mut col = 0;
        for (j, column) in full.chunks_exact(n).enumerate() {
            let Some(dof) = problem.contact[j / (problem.dim() - 1)].tangent_dofs[j % (problem.dim() - 1)] else {
                continue;
            };
            assert_eq!(dof, contact[col]);
            for (i, &c) in contact.iter().enumerate() {
                max_diff = max_diff.max((column[c] - x[(i, col)]).abs());
                max_val = max_val.max(column[c].abs());
            }
            col += 1;
        }
        // A right-hand side supported on the contact unknowns only (the correction solve after
        // the contact iteration, A⁻¹ Eᵀ(ℓξ, ℓh)): the forward sweep runs on the trailing block
        // only. Hand-written simplicial sweeps over faer's L (diagonal = D first in each column).
        let (fwd, inv) = &perm;
        let lv = &f.values;
        let sweep = |b: &[f64], from: usize| -> Vec<f64> {
            let mut y: Vec<f64> = fwd.iter().map(|&old| b[old]).collect();
            for j in from..n {
                let yj = y[j];
                if yj != 0.0 {
                    for k in col_ptr[j] + 1..col_ptr[j + 1] {
                        y[row_idx[k]] -= lv[k] * yj;
                    }
                }
            }
            for j in 0..n {
                y[j] /= lv[col_ptr[j]];
            }
            for j in (0..n).rev() {
                let mut acc = y[j];
                for k in col_ptr[j] + 1..col_ptr[j + 1] {
                    acc -= lv[k] * y[row_idx[k]];
                }
                y[j] = acc;
            }
            (0..n).map(|i| y[inv[i]]).collect()
        };
        let mut contact_rhs = vec![0.0; n];
        for (k, &c) in contact.iter().enumerate() {
            contact_rhs[c] = ((k % 7) as f64 - 3.0) * 0.1;
        }
        let full_custom = median_time(|| sweep(sb, 0));
        let full_on_contact = median_time(|| sweep(&contact_rhs, 0));
        let partial = median_time(|| sweep(&contact_rhs, first));
        let x_partial = sweep(&contact_rhs, first);
        println!(
            "S {name}, contact last, hand-written simplicial solve: full {:.2} ms (residual {:.0e}); \
             contact-supported RHS: full sweeps {:.2} ms, forward on the trailing block only {:.2} ms (residual {:.0e})",
            full_custom * 1e3,
            residual(s, &sweep(sb, 0), sb),
            full_on_contact * 1e3,
            partial * 1e3,
            residual(s, &x_partial, &contact_rhs)
        );
        println!(
            "S {name}, contact last: condensation {n_tan}×{m} entries of S⁻¹ from the trailing {m}×{m} block of L: {:.1} ms \
             (vs {:.3} s for the {n_t} full solves on 2 threads); max |difference| / max |entry| = {:.1e}",
            trailing_s * 1e3,
            full_block,
            max_diff / max_val
        );
    }
    Ok(())
}

/// The same factorization with 32-bit indices: (nnz(L), kind, median solve seconds, residual).
fn u32_factor_solve(
    a: &CscMatrix,
    perm: Option<&(Vec<usize>, Vec<usize>)>,
    threshold: SupernodalThreshold,
    rhs: &[f64],
) -> anyhow::Result<(usize, &'static str, f64, f64)> {
    use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
    use faer::sparse::{SparseColMat, SymbolicSparseColMat};
    let n = a.n_rows;
    let pattern = SymbolicSparseColMat::new_checked(
        n,
        n,
        a.col_ptr.iter().map(|&p| p as u32).collect(),
        None,
        a.row_idx.iter().map(|&r| r as u32).collect(),
    );
    let mat = SparseColMat::new(pattern, a.values.clone());
    let perm32 = perm.map(|(f, i)| {
        (
            f.iter().map(|&p| p as u32).collect::<Vec<u32>>(),
            i.iter().map(|&p| p as u32).collect::<Vec<u32>>(),
        )
    });
    let ordering = match &perm32 {
        Some((f, i)) => SymmetricOrdering::Custom(PermRef::new_checked(f, i, n)),
        None => SymmetricOrdering::Amd,
    };
    let symbolic = factorize_symbolic_cholesky(
        mat.symbolic(),
        Side::Lower,
        ordering,
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: threshold,
            ..Default::default()
        },
    )
    .map_err(|e| anyhow::anyhow!("symbolic: {e:?}"))?;
    let mut values = vec![0.0; symbolic.len_val()];
    let mut mem = MemBuffer::new(symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()));
    symbolic
        .factorize_numeric_ldlt(
            &mut values,
            mat.as_ref(),
            Side::Lower,
            LdltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| anyhow::anyhow!("numeric: {e:?}"))?;
    let solve_copy = || {
        let mut x = rhs.to_vec();
        let mut mem = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        LdltRef::new(&symbolic, &values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut x, n, 1),
            Par::Seq,
            MemStack::new(&mut mem),
        );
        x
    };
    let solve = median_time(solve_copy);
    let res = residual(a, &solve_copy(), rhs);
    let kind = match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(_) => "simplicial",
        SymbolicCholeskyRaw::Supernodal(_) => "supernodal",
    };
    Ok((values.len(), kind, solve, res))
}

/// A faer sparse Cholesky (LLᵀ) or LDLᵀ with its timings.
struct Factor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    ldlt: bool,
    symbolic_s: f64,
    numeric_s: f64,
    peak_kb: u64,
}

impl Factor {
    fn new(
        a: &CscMatrix,
        perm: Option<&(Vec<usize>, Vec<usize>)>,
        ldlt: bool,
        threshold: SupernodalThreshold,
    ) -> anyhow::Result<Self> {
        let faer_a = a.to_faer();
        let base = reset_peak();
        let clock = Instant::now();
        let ordering = match perm {
            Some((fwd, inv)) => SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, a.n_rows)),
            None => SymmetricOrdering::Amd,
        };
        let symbolic = factorize_symbolic_cholesky(
            faer_a.symbolic(),
            Side::Lower,
            ordering,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: threshold,
                ..Default::default()
            },
        )
        .map_err(|e| anyhow::anyhow!("symbolic: {e:?}"))?;
        let symbolic_s = clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let mut values = vec![0.0; symbolic.len_val()];
        let par = Par::Seq;
        if ldlt {
            let mut mem = MemBuffer::new(symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()));
            symbolic
                .factorize_numeric_ldlt(
                    &mut values,
                    faer_a.as_ref(),
                    Side::Lower,
                    LdltRegularization::default(),
                    par,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .map_err(|e| anyhow::anyhow!("numeric LDLᵀ: {e:?}"))?;
        } else {
            let mut mem = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
            symbolic
                .factorize_numeric_llt(
                    &mut values,
                    faer_a.as_ref(),
                    Side::Lower,
                    LltRegularization::default(),
                    par,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .map_err(|e| anyhow::anyhow!("numeric LLᵀ: {e:?}"))?;
        }
        let numeric_s = clock.elapsed().as_secs_f64();
        let peak_kb = peak_kb().saturating_sub(base);
        Ok(Factor {
            symbolic,
            values,
            ldlt,
            symbolic_s,
            numeric_s,
            peak_kb,
        })
    }

    /// Solves in place for a column-major block of `n_cols` right-hand sides (scratch allocated
    /// per call, as in production).
    fn solve(&self, block: &mut [f64], n_cols: usize, par: Par) {
        let n = self.symbolic.nrows();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(n_cols, par));
        let rhs = MatMut::from_column_major_slice_mut(block, n, n_cols);
        if self.ldlt {
            LdltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                par,
                MemStack::new(&mut mem),
            );
        } else {
            LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                par,
                MemStack::new(&mut mem),
            );
        }
    }

    fn solve_copy(&self, block: &[f64], n_cols: usize, par: Par) -> Vec<f64> {
        let mut x = block.to_vec();
        self.solve(&mut x, n_cols, par);
        x
    }

    fn kind(&self) -> &'static str {
        use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => "simplicial",
            SymbolicCholeskyRaw::Supernodal(_) => "supernodal",
        }
    }

    fn report(&self, label: &str, order_s: f64, rhs: &[f64], a: &CscMatrix) {
        let solve = median_time(|| {
            self.solve_copy(rhs, 1, Par::Seq);
        });
        let x = self.solve_copy(rhs, 1, Par::Seq);
        println!(
            "{label:<28} [{}] nnz(L) {:>9}, ordering {:.3} s, symbolic {:.3} s, numeric {:.3} s, solve {:6.2} ms, residual {:.0e}, peak +{} MB",
            self.kind(),
            self.values.len(),
            order_s,
            self.symbolic_s,
            self.numeric_s,
            solve * 1e3,
            residual(a, &x, rhs),
            self.peak_kb / 1024
        );
    }
}

type Ordering = (String, Option<(Vec<usize>, Vec<usize>)>, f64);

/// AMD (faer's, inside the symbolic factorization) and the nested-dissection orderings of a
/// symmetric pattern, each with the seconds it took.
fn orderings(a: &CscMatrix) -> Vec<Ordering> {
    let mut out: Vec<Ordering> = vec![("AMD".into(), None, 0.0)];
    let clock = Instant::now();
    let perm = metis_nd(a);
    out.push(("METIS".into(), Some(with_inverse(perm)), clock.elapsed().as_secs_f64()));

    let (col_ptr, row_idx) = pattern_i32(a);
    let pattern = feral_ordering_core_pattern(a.n_rows, &col_ptr, &row_idx);
    let clock = Instant::now();
    match feral_metis::metis_order(&pattern) {
        Ok(perm) => out.push((
            "feral-metis".into(),
            Some(with_inverse(perm.into_iter().map(|p| p as usize).collect())),
            clock.elapsed().as_secs_f64(),
        )),
        Err(e) => println!("feral-metis failed: {e:?}"),
    }
    let clock = Instant::now();
    match feral_scotch::scotch_order(&pattern) {
        Ok(perm) => out.push((
            "feral-scotch".into(),
            Some(with_inverse(perm.into_iter().map(|p| p as usize).collect())),
            clock.elapsed().as_secs_f64(),
        )),
        Err(e) => println!("feral-scotch failed: {e:?}"),
    }
    out
}

fn orderings_subset(a: &CscMatrix) -> Vec<Ordering> {
    orderings(a)
        .into_iter()
        .filter(|(name, _, _)| name == "AMD" || name == "METIS")
        .collect()
}

fn feral_ordering_core_pattern<'a>(n: usize, col_ptr: &'a [i32], row_idx: &'a [i32]) -> feral_metis::CscPattern<'a> {
    feral_metis::CscPattern::new(n, col_ptr, row_idx).expect("a valid pattern")
}

fn pattern_i32(a: &CscMatrix) -> (Vec<i32>, Vec<i32>) {
    (
        a.col_ptr.iter().map(|&p| p as i32).collect(),
        a.row_idx.iter().map(|&r| r as i32).collect(),
    )
}

fn with_inverse(fwd: Vec<usize>) -> (Vec<usize>, Vec<usize>) {
    let mut inv = vec![0; fwd.len()];
    for (new, &old) in fwd.iter().enumerate() {
        inv[old] = new;
    }
    (fwd, inv)
}

/// METIS_NodeND on the adjacency graph of a (diagonal left out), default options.
fn metis_nd(a: &CscMatrix) -> Vec<usize> {
    let n = a.n_rows;
    let mut xadj = vec![0i32; n + 1];
    let mut adjncy = Vec::with_capacity(a.nnz());
    for j in 0..n {
        for k in a.col_ptr[j]..a.col_ptr[j + 1] {
            if a.row_idx[k] != j {
                adjncy.push(a.row_idx[k] as i32);
            }
        }
        xadj[j + 1] = adjncy.len() as i32;
    }
    let mut nvtxs = n as i32;
    let mut options = [0i32; metis_sys::METIS_NOPTIONS as usize];
    let mut perm = vec![0i32; n];
    let mut iperm = vec![0i32; n];
    // SAFETY: the arrays have the sizes METIS_NodeND documents (n + 1, nnz, n, n, NOPTIONS).
    let status = unsafe {
        metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        metis_sys::METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    assert_eq!(
        status as i64,
        metis_sys::rstatus_et_METIS_OK as i64,
        "METIS_NodeND failed"
    );
    // METIS: row i of the permuted matrix is row perm[i] of the original (new → old).
    perm.into_iter().map(|p| p as usize).collect()
}

/// K_w, K_θ (sign restored, SPD) and G out of S = [K_w, G; Gᵀ, −K_θ].
fn blocks(s: &CscMatrix, n_w: usize) -> (CscMatrix, CscMatrix, CscMatrix) {
    let n = s.n_rows;
    let (mut kw, mut kt, mut g) = (Vec::new(), Vec::new(), Vec::new());
    for (r, c, v) in s.triplets() {
        match (r < n_w, c < n_w) {
            (true, true) => kw.push((r, c, v)),
            (false, false) => kt.push((r - n_w, c - n_w, -v)),
            (true, false) => g.push((r, c - n_w, v)),
            (false, true) => {}
        }
    }
    (
        CscMatrix::from_triplets(n_w, n_w, kw),
        CscMatrix::from_triplets(n - n_w, n - n_w, kt),
        CscMatrix::from_triplets(n_w, n - n_w, g),
    )
}

/// Block Gauss–Seidel for A x = b, A = [K_w, G; −Gᵀ, K_θ], from θ = 0. With `check`, stops at
/// relative residual ‖S x − J b‖/‖J b‖ ≤ tol and returns the residual after every sweep; without,
/// runs `max_sweeps` sweeps.
#[allow(clippy::too_many_arguments)]
fn gauss_seidel(
    f_w: &Factor,
    f_t: &Factor,
    g: &CscMatrix,
    b: &[f64],
    n_w: usize,
    s: &CscMatrix,
    sb: &[f64],
    tol: f64,
    max_sweeps: usize,
    check: bool,
) -> (usize, Vec<f64>) {
    let n = b.len();
    let mut theta = vec![0.0; n - n_w];
    let mut w = vec![0.0; n_w];
    let mut history = Vec::new();
    for sweep in 1..=max_sweeps {
        w.copy_from_slice(&b[..n_w]);
        g.mul_add(-1.0, &theta, &mut w);
        f_w.solve(&mut w, 1, Par::Seq);
        theta.copy_from_slice(&b[n_w..]);
        g.mul_transpose_add(1.0, &w, &mut theta);
        f_t.solve(&mut theta, 1, Par::Seq);
        if check {
            let x: Vec<f64> = w.iter().chain(&theta).copied().collect();
            let r = residual(s, &x, sb);
            history.push(r);
            if r <= tol {
                return (sweep, history);
            }
        }
    }
    (max_sweeps, history)
}

/// ‖A x − b‖ / ‖b‖.
fn residual(a: &CscMatrix, x: &[f64], b: &[f64]) -> f64 {
    let ax = a.mul(x);
    let num: f64 = ax.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum();
    let den: f64 = b.iter().map(|q| q * q).sum();
    (num / den).sqrt()
}

/// The right-hand side of step 5 after four contact-free steps from the initial state.
fn realistic_rhs(problem: &Problem, system: &StepSystem) -> anyhow::Result<Vec<f64>> {
    let k = system.step_size();
    let mut state = State::initial(problem);
    for step in 1..=4 {
        let t = step as f64 * k;
        let mut x = system.rhs(problem, &state, t)?;
        system.solve_in_place(&mut x);
        state = system.state_from(problem, &state, t, &x, state.xi.clone());
    }
    Ok(system.rhs(problem, &state, 5.0 * k)?)
}

/// A reproducible vector with entries in [−1, 1) (xorshift).
fn random_vector(n: usize, seed: u64) -> Vec<f64> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect()
}

fn median_time<R>(f: impl FnMut() -> R) -> f64 {
    median_time_n(REPEATS, f)
}

fn median_time_n<R>(repeats: usize, mut f: impl FnMut() -> R) -> f64 {
    std::hint::black_box(f()); // warm-up
    let mut times: Vec<f64> = (0..repeats)
        .map(|_| {
            let clock = Instant::now();
            std::hint::black_box(f());
            clock.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[repeats / 2]
}

fn par_name(par: Par) -> &'static str {
    match par {
        Par::Seq => "Par::Seq",
        _ => "rayon(2)",
    }
}

/// Resets the peak resident set size (VmHWM) of the process and returns the current one, kB.
fn reset_peak() -> u64 {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    status_kb("VmRSS")
}

/// The peak resident set size since the last reset, kB.
fn peak_kb() -> u64 {
    status_kb("VmHWM")
}

fn status_kb(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l[key.len() + 1..].trim().trim_end_matches("kB").trim().parse().ok())
        })
        .unwrap_or(0)
}
