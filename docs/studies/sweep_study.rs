//! The split triangular sweeps of `QuasiDefiniteLdlt` against faer's own supernodal solve, and
//! what ordering the contact unknowns last costs and saves (numbers in
//! docs/linear-algebra-study.md, "What was implemented").
//!
//! ```text
//! cp docs/studies/sweep_study.rs examples/ && cargo run --release --example sweep_study
//! cargo run --release --example sweep_study -- scenarios/paper3d.toml --set mesh.nx=56 --set mesh.ny=14 --set mesh.nz=14
//! ```
//!
//! Without a scenario file it builds the 2D reference run (`--set mesh.nx=256 --set mesh.ny=64
//! --set time.steps=64`); further `--set`s are laid over it.

use std::time::Instant;

use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::Side;
use thermocontact::solver::condensed::Condensation;
use thermocontact::solver::factor::QuasiDefiniteLdlt;
use thermocontact::solver::system::{State, StepSystem};
use thermocontact::Scenario;

const REPEATS: usize = 25;

fn main() -> anyhow::Result<()> {
    let mut file = None;
    let mut overrides: Vec<String> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--set" => overrides.push(args.next().ok_or_else(|| anyhow::anyhow!("--set needs KEY=VALUE"))?),
            other => file = Some(std::path::PathBuf::from(other)),
        }
    }
    let scenario = match &file {
        Some(path) => Scenario::load_file(path, &overrides)?,
        None => {
            let mut all: Vec<String> = vec!["mesh.nx=256".into(), "mesh.ny=64".into(), "time.steps=64".into()];
            all.extend(overrides);
            Scenario::load(None, &all)?
        }
    };
    let problem = scenario.build()?;
    let clock = Instant::now();
    let system = StepSystem::new(&problem)?;
    let with_trailing = clock.elapsed().as_secs_f64();
    let factor = system.factor();
    let n = system.n_unknowns();
    let t0 = factor.trailing_start();
    println!(
        "{}D: {n} unknowns, {} contact unknowns last (from position {t0}), nnz(S) {}",
        problem.dim(),
        n - t0,
        system.matrix().nnz()
    );
    let SymbolicCholeskyRaw::Supernodal(sn) = factor.symbolic().raw() else {
        anyhow::bail!("expected a supernodal factor");
    };
    let straddling = (0..sn.n_supernodes())
        .filter(|&k| sn.supernode_begin()[k] < t0 && sn.supernode_end()[k] > t0)
        .count();
    let trailing_nodes = (0..sn.n_supernodes()).filter(|&k| sn.supernode_end()[k] > t0).count();
    let trailing_nnz: usize = (0..sn.n_supernodes())
        .filter(|&k| sn.supernode_end()[k] > t0)
        .map(|k| sn.col_ptr_for_val()[k + 1] - sn.col_ptr_for_val()[k])
        .sum();
    println!(
        "contact last: nnz(L) {} ({:.1} MB), {} supernodes, {trailing_nodes} on the trailing block ({straddling} straddling its start, {:.2} MB of values), assembly + factorization {:.3} s",
        factor.factor_nnz(),
        factor.factor_nnz() as f64 * 8e-6,
        sn.n_supernodes(),
        trailing_nnz as f64 * 8e-6,
        with_trailing
    );
    // Factorization times (ordering, symbolic, numeric), the best of three: contact last
    // against AMD on all unknowns.
    let contact: Vec<usize> = (t0..n).map(|p| factor.unknown_at(p)).collect();
    let best_of_three = |f: &dyn Fn() -> QuasiDefiniteLdlt| {
        (0..3)
            .map(|_| {
                let clock = Instant::now();
                std::hint::black_box(f());
                clock.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let last_s = best_of_three(&|| QuasiDefiniteLdlt::with_trailing(system.matrix(), &contact).unwrap());
    let amd_s = best_of_three(&|| QuasiDefiniteLdlt::new(system.matrix()).unwrap());
    let amd = QuasiDefiniteLdlt::new(system.matrix())?;
    println!(
        "AMD on all unknowns: nnz(L) {} (contact last: {:+.1} %); factorization {:.3} s (contact last: {:.3} s)",
        amd.factor_nnz(),
        100.0 * (factor.factor_nnz() as f64 / amd.factor_nnz() as f64 - 1.0),
        amd_s,
        last_s
    );

    // Another way to put the contact unknowns last: AMD on all unknowns, the contact unknowns
    // then moved to the end (the others keep their relative order). Symbolic factorization only.
    let amd_order = amd.symbolic().perm().expect("AMD permutes").arrays().0.to_vec();
    let is_contact = {
        let mut mark = vec![false; n];
        contact.iter().for_each(|&c| mark[c] = true);
        mark
    };
    let moved: Vec<usize> = amd_order
        .iter()
        .copied()
        .filter(|&i| !is_contact[i])
        .chain(contact.iter().copied())
        .collect();
    let mut moved_inv = vec![0; n];
    for (p, &i) in moved.iter().enumerate() {
        moved_inv[i] = p;
    }
    let symbolic = factorize_symbolic_cholesky(
        system.matrix().to_faer().symbolic(),
        Side::Lower,
        SymmetricOrdering::Custom(PermRef::new_checked(&moved, &moved_inv, n)),
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        },
    )
    .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    println!(
        "AMD on all unknowns, then the contact unknowns moved last: nnz(L) {} ({:+.1} % against AMD)",
        symbolic.len_val(),
        100.0 * (symbolic.len_val() as f64 / amd.factor_nnz() as f64 - 1.0)
    );

    // A realistic right-hand side: step 5 after four contact-free steps.
    let k = system.step_size();
    let mut state = State::initial(&problem);
    for step in 1..=4 {
        let t = step as f64 * k;
        let mut x = system.rhs(&problem, &state, t)?;
        system.solve_in_place(&mut x)?;
        state = system.state_from(&problem, &state, t, &x, state.xi.clone());
    }
    let mut b = system.rhs(&problem, &state, 5.0 * k)?;
    b[system.n_w()..].iter_mut().for_each(|v| *v = -*v);

    let (mut permuted, mut scratch) = (vec![0.0; n], vec![0.0; factor.scratch_len()]);
    let mut expected = b.clone();
    factor.solve_in_place(&mut expected, 1);
    let mut x = b.clone();
    factor.solve_split_in_place(&mut x, &mut permuted, &mut scratch);
    let diff = x.iter().zip(&expected).fold(0.0f64, |m, (a, e)| m.max((a - e).abs()));
    let scale = expected.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    factor.permute(&b, &mut permuted);
    let y = permuted.clone();
    factor.forward(&mut permuted, &mut scratch, 0);
    factor.diagonal(&mut permuted, 0);
    let z = permuted.clone();

    // The variants run round-robin, so that the load of the machine spreads over all of them.
    let labels = [
        "faer's solve, AMD factor",
        "faer's solve, contact-last factor",
        "split sweeps (P, forward, D, backward, Pᵀ)",
        "forward sweep, all of L",
        "backward sweep, all of L",
        "forward sweep, trailing block",
        "backward sweep, trailing block",
    ];
    let mut times = vec![Vec::new(); labels.len()];
    for round in 0..=REPEATS {
        for (v, samples) in times.iter_mut().enumerate() {
            let clock = Instant::now();
            match v {
                0 => {
                    x.copy_from_slice(&b);
                    amd.solve_in_place(&mut x, 1);
                }
                1 => {
                    x.copy_from_slice(&b);
                    factor.solve_in_place(&mut x, 1);
                }
                2 => {
                    x.copy_from_slice(&b);
                    factor.solve_split_in_place(&mut x, &mut permuted, &mut scratch);
                }
                3 => {
                    permuted.copy_from_slice(&y);
                    factor.forward(&mut permuted, &mut scratch, 0);
                }
                4 => {
                    permuted.copy_from_slice(&z);
                    factor.backward(&mut permuted, &mut scratch, 0);
                }
                5 => {
                    permuted[t0..].copy_from_slice(&y[t0..]);
                    factor.forward(&mut permuted, &mut scratch, t0);
                }
                _ => {
                    permuted[t0..].copy_from_slice(&z[t0..]);
                    factor.backward(&mut permuted, &mut scratch, t0);
                }
            }
            // Round 0 warms up.
            if round > 0 {
                samples.push(clock.elapsed().as_secs_f64());
            }
        }
    }
    println!("one right-hand side, {REPEATS} rounds (ms): median, min");
    for (label, samples) in labels.iter().zip(&mut times) {
        samples.sort_by(f64::total_cmp);
        println!(
            "  {label:<44} {:8.3} {:8.3}",
            samples[REPEATS / 2] * 1e3,
            samples[0] * 1e3
        );
    }
    println!("split sweeps against faer's solve: max |difference| / max |x| = {:.1e}", diff / scale);

    let clock = Instant::now();
    let cond = Condensation::new(&problem, &system)?;
    println!(
        "condensation ({} × {} and {} × {}) from the trailing block: {:.1} ms",
        cond.n_t,
        cond.n_t,
        cond.n_t,
        cond.n_h,
        clock.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}
