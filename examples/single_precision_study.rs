//! Study (issue 28 item 3): L of the step matrix's LDLᵀ in f32, the solves refined from the
//! previous step's solution.
//!
//! ```text
//! cargo run --release --example single_precision_study [-- scenario.toml --set …]
//! ```
//!
//! Runs the 2D reference run (256 × 64, 64 steps, fast solver, direct path) and keeps the
//! solutions x_n; then, on the run's step matrix S:
//! 1. times, round-robin, a full solve with L in f64 (the production sweeps), with L in f32 (D,
//!    vectors and sums f64), and a mat-vec with S;
//! 2. the error of one f32 solve of S x = S x_n (cold: x from zero) and of the correction
//!    S δ = S (x_n − x_{n−1}) (warm: x_{n−1} + δ), against x_n, per block (velocities,
//!    temperatures), relative to the block's ∞-norm of x_n; the f64 solve's as reference.

use std::time::Instant;

use thermocontact::step::StepSystem;
use thermocontact::{Problem, Scenario, State};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let mut file = None;
    let mut overrides: Vec<String> = ["mesh.nx=256", "mesh.ny=64", "time.steps=64", "solver.kind=fast"]
        .map(String::from)
        .to_vec();
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--set" => overrides.push(args.next().ok_or_else(|| anyhow::anyhow!("--set needs KEY=VALUE"))?),
            path => file = Some(std::fs::read_to_string(path)?),
        }
    }
    let scenario = Scenario::load(file.as_deref(), &overrides)?;
    let problem = scenario.build()?;
    let params = scenario.solver_params();
    let mut states = vec![State::initial(&problem)];
    thermocontact::time::run::<thermocontact::time::TimeError>(&problem, &params, |state, _| {
        states.push(state.clone());
        Ok(())
    })?;
    let system = StepSystem::new(&problem)?;
    let factor = system.factor();
    let s = system.matrix();
    let n = factor.n();
    let n_w = system.n_w();
    let xs: Vec<Vec<f64>> = states.iter().map(|st| unknowns(&problem, st)).collect();
    println!(
        "unknowns {n}, nnz(L) {} ({:.1} MB f64, {:.1} MB f32), nnz(S) {}",
        factor.factor_nnz(),
        factor.factor_nnz() as f64 * 8e-6,
        factor.factor_nnz() as f64 * 4e-6,
        s.nnz()
    );

    let single = factor.study_single_values();
    let (mut permuted, mut scratch) = (vec![0.0; n], vec![0.0; factor.scratch_len()]);
    // 1. Timing, round-robin.
    let b = s.mul(&xs[xs.len() / 2]);
    let rounds = 25;
    let mut times = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
    for _ in 0..rounds {
        let mut x = b.clone();
        let clock = Instant::now();
        factor.solve_split_in_place(&mut x, &mut permuted, &mut scratch);
        times[0].push(clock.elapsed().as_secs_f64());
        let mut x = b.clone();
        let clock = Instant::now();
        factor.study_solve_with(&single, &mut x, &mut permuted, &mut scratch);
        times[1].push(clock.elapsed().as_secs_f64());
        let mut y = vec![0.0; n];
        let clock = Instant::now();
        s.mul_add(1.0, &xs[1], &mut y);
        times[2].push(clock.elapsed().as_secs_f64());
        let mut x = b.clone();
        let clock = Instant::now();
        // What a warm f32 step costs: r = S x_{n−1} (b − r is free), then the f32 solve.
        s.mul_add(-1.0, &xs[1], &mut x);
        factor.study_solve_with(&single, &mut x, &mut permuted, &mut scratch);
        times[3].push(clock.elapsed().as_secs_f64());
    }
    for (name, t) in ["solve, L f64", "solve, L f32", "mat-vec S", "mat-vec + solve f32"]
        .iter()
        .zip(&mut times)
    {
        t.sort_by(f64::total_cmp);
        println!("{name:>22}: median {:.2} ms, min {:.2} ms", 1e3 * t[rounds / 2], 1e3 * t[0]);
    }

    // 2. Errors along the run.
    let err = |x: &[f64], exact: &[f64]| -> [f64; 2] {
        let block = |r: std::ops::Range<usize>| {
            let scale = exact[r.clone()].iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let diff = (r.clone()).fold(0.0f64, |m, i| m.max((x[i] - exact[i]).abs()));
            diff / scale.max(f64::MIN_POSITIVE)
        };
        [block(0..n_w), block(n_w..n)]
    };
    let solve = |b: &[f64], single_precision: bool| -> Vec<f64> {
        let mut x = b.to_vec();
        let (mut permuted, mut scratch) = (vec![0.0; n], vec![0.0; factor.scratch_len()]);
        if single_precision {
            factor.study_solve_with(&single, &mut x, &mut permuted, &mut scratch);
        } else {
            factor.solve_split_in_place(&mut x, &mut permuted, &mut scratch);
        }
        x
    };
    println!("step | change |Δx|/|x| (w, θ) | f64 cold (w, θ) | f32 cold (w, θ) | f32 warm (w, θ) | f32 warm + 1 refinement");
    let mut worst = [[0.0f64; 2]; 4];
    let mut extrapolated = [0.0f64; 2];
    for k in 1..xs.len() {
        let (x, before) = (&xs[k], &xs[k - 1]);
        let sx = s.mul(x);
        let cold64 = err(&solve(&sx, false), x);
        let cold32 = err(&solve(&sx, true), x);
        let delta: Vec<f64> = x.iter().zip(before).map(|(a, b)| a - b).collect();
        let _ = delta;
        let change = err(before, x);
        // The linear extrapolation 2 x_{n−1} − x_{n−2} as the predictor.
        let predictor: Vec<f64> = if k >= 2 {
            before.iter().zip(&xs[k - 2]).map(|(a, b)| 2.0 * a - b).collect()
        } else {
            before.clone()
        };
        let change2 = err(&predictor, x);
        let warm2: Vec<f64> = {
            let mut r = sx.clone();
            s.mul_add(-1.0, &predictor, &mut r);
            let d = solve(&r, true);
            predictor.iter().zip(&d).map(|(a, b)| a + b).collect()
        };
        let warm2 = err(&warm2, x);
        extrapolated[0] = extrapolated[0].max(warm2[0]);
        extrapolated[1] = extrapolated[1].max(warm2[1]);
        let warm: Vec<f64> = {
            let mut r = sx.clone();
            s.mul_add(-1.0, before, &mut r);
            let d = solve(&r, true);
            before.iter().zip(&d).map(|(a, b)| a + b).collect()
        };
        let warm32 = err(&warm, x);
        let refined: Vec<f64> = {
            let mut r = sx.clone();
            s.mul_add(-1.0, &warm, &mut r);
            let d = solve(&r, true);
            warm.iter().zip(&d).map(|(a, b)| a + b).collect()
        };
        let refined32 = err(&refined, x);
        for (w, e) in worst.iter_mut().zip([cold64, cold32, warm32, refined32]) {
            w[0] = w[0].max(e[0]);
            w[1] = w[1].max(e[1]);
        }
        if k <= 4 || k % 8 == 0 {
            println!(
                "{k:>4} | {:.1e} {:.1e} | {:.1e} {:.1e} | {:.1e} {:.1e} | {:.1e} {:.1e} | {:.1e} {:.1e} | extrapolated: change {:.1e} {:.1e}, f32 {:.1e} {:.1e}",
                change[0],
                change[1],
                cold64[0],
                cold64[1],
                cold32[0],
                cold32[1],
                warm32[0],
                warm32[1],
                refined32[0],
                refined32[1],
                change2[0],
                change2[1],
                warm2[0],
                warm2[1]
            );
        }
    }
    println!(
        "worst over the run: f64 cold {:.1e} {:.1e}; f32 cold {:.1e} {:.1e}; f32 warm {:.1e} {:.1e}; f32 warm + 1 refinement {:.1e} {:.1e}",
        worst[0][0], worst[0][1], worst[1][0], worst[1][1], worst[2][0], worst[2][1], worst[3][0], worst[3][1]
    );
    println!("worst f32 from the extrapolated predictor: {:.1e} {:.1e}", extrapolated[0], extrapolated[1]);
    Ok(())
}

/// The unknowns x of a state: velocities at the free dofs, temperatures at the free nodes.
fn unknowns(problem: &Problem, state: &State) -> Vec<f64> {
    let mut x = problem.velocity.restrict_values(&state.w);
    let mut theta = vec![0.0; problem.temperature.n_free];
    for (p, free) in problem.temperature.free.iter().enumerate() {
        if let Some(r) = free {
            theta[*r] = state.theta[p];
        }
    }
    x.extend(theta);
    x
}
