//! The AMG-preconditioned iterative path (`solver.preconditioner = "amg"`, cargo feature
//! `petsc`): its solves agree with the direct LDLᵀ, its Krylov iteration counts stay bounded
//! when the mesh is refined at a large time step (where ILU(0)'s grow), and whole runs reach the
//! direct path's solution (`tests/newton_krylov.rs`).
#![cfg(feature = "petsc")]

use thermocontact::la::SolveInfo;
use thermocontact::model::{samples, State};
use thermocontact::step::KrylovSystem;
use thermocontact::step::StepSystem;
use thermocontact::step::{KrylovParams, PreconditionerKind};

/// The 3D example with nx × nx/4 × nx/4 cells.
fn problem(nx: usize, steps: usize) -> thermocontact::model::Problem {
    samples::paper_3d([nx, nx / 4, nx / 4], steps).unwrap()
}

fn params(preconditioner: PreconditionerKind) -> KrylovParams {
    KrylovParams {
        rtol: 1e-8,
        preconditioner,
        ..KrylovParams::default()
    }
}

/// GMRES from zero on the first step's right-hand side with the step matrix of step size k.
fn first_step_solve(
    problem: &thermocontact::model::Problem,
    preconditioner: PreconditionerKind,
) -> (Vec<f64>, SolveInfo) {
    let k = problem.time_step();
    let system = KrylovSystem::new(problem, k, params(preconditioner)).unwrap();
    let b = system.rhs(problem, &State::initial(problem), k).unwrap();
    let mut x = vec![0.0; b.len()];
    let info = system.solve(&b, &mut x).unwrap();
    (x, info)
}

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

#[test]
fn amg_and_direct_solves_agree() {
    for steps in [64, 8] {
        let problem = problem(16, steps);
        let (x, info) = first_step_solve(&problem, PreconditionerKind::Amg);
        let k = problem.time_step();
        let direct = StepSystem::new(&problem).unwrap();
        let mut reference = direct.rhs(&problem, &State::initial(&problem), k).unwrap();
        direct.solve_in_place(&mut reference).unwrap();
        let diff = max_rel_diff(&reference, &x);
        assert!(diff < 1e-6, "k = {k}: {diff:e} ({info:?})");
    }
}

/// Refining the 3D example 4× (1.3k → 70k unknowns) at the step sizes where the stiffness
/// weighs, k = 1/8 and 1: the AMG's Krylov count at most doubles (the bound this test states;
/// measured 4 → 5 → 7 and 9 → 11 → 14), where ILU(0)'s does not stay within it (7 → 10 → 19,
/// 32 → 68 → 146: it grows like h⁻¹). On the way, `auto` takes the AMG where ILU(0) needs more
/// than 80 iterations (k = 1 at 70k unknowns) and ILU(0) elsewhere.
#[test]
fn amg_iterations_stay_bounded_under_refinement() {
    for steps in [8, 1] {
        let mut counts = Vec::new();
        for nx in [16, 32, 64] {
            let problem = problem(nx, steps);
            let (_, ilu) = first_step_solve(&problem, PreconditionerKind::Ilu);
            let (_, amg) = first_step_solve(&problem, PreconditionerKind::Amg);
            eprintln!(
                "k = 1/{steps}, nx = {nx}: {} unknowns, ILU(0) {} iterations, AMG {}",
                problem.n_unknowns(),
                ilu.iterations,
                amg.iterations
            );
            counts.push((ilu.iterations as f64, amg.iterations as f64));
            // `auto` sets up the AMG exactly where this solve needs more than its threshold.
            let k = problem.time_step();
            let auto = KrylovSystem::new(&problem, k, params(PreconditionerKind::Auto)).unwrap();
            let expected = if ilu.iterations > PreconditionerKind::AUTO_AMG_ABOVE {
                PreconditionerKind::Amg
            } else {
                PreconditionerKind::Ilu
            };
            assert_eq!(auto.preconditioner(), expected, "k = 1/{steps}, nx = {nx}: {ilu:?}");
        }
        let growth = |f: fn(&(f64, f64)) -> f64| f(&counts[counts.len() - 1]) / f(&counts[0]);
        let (ilu_growth, amg_growth) = (growth(|c| c.0), growth(|c| c.1));
        assert!(amg_growth <= 2.0, "k = 1/{steps}: AMG counts {counts:?}");
        assert!(
            ilu_growth > 2.0,
            "k = 1/{steps}: ILU(0) stayed within the bound too: {counts:?}"
        );
    }
}
