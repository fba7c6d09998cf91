//! The fast solver's globalization: descent on the energy of the condensed step
//! (`solver::descent`). It must return solutions of the step (the condensed equations and the
//! nodal law) from any start, agree with Newton where the solution is unique, and finish the
//! steps the convexification loop cannot.

mod common;

use common::coarse;
use thermocontact::driver::{self, OutputPlan, RunOptions, RunStatus};
use thermocontact::model::norms;
use thermocontact::model::{ContactLaws, Problem, State};
use thermocontact::step::StepSystem;
use thermocontact::step::{descend, ContactStiffness, DescentParams, Start};
use thermocontact::step::{CondensedStep, NewtonParams};
use thermocontact::step::{PaperParams, PaperSolver};
use thermocontact::Scenario;

const NEWTON: NewtonParams = NewtonParams {
    tolerance: 1e-12,
    max_iterations: 30,
};

/// The condensed problem of step 6 of the coarse example (after five steps of the fast solver),
/// handed to `check` with w_τ^free and the previous step's tangential velocities.
fn with_step_six(scenario: &Scenario, check: impl FnOnce(&CondensedStep, &ContactStiffness, &[f64], &[f64])) {
    let problem = scenario.build().unwrap();
    let params = scenario.solver_params();
    let mut states = Vec::new();
    thermocontact::time::run::<thermocontact::time::TimeError>(&problem, &params, |state, _| {
        states.push(state.clone());
        Ok(())
    })
    .unwrap();
    let previous: &State = &states[4];
    assert_eq!(previous.n, 5);
    let t = 6.0 * problem.time_step();
    let system = StepSystem::new(&problem).unwrap();
    let paper = PaperSolver::new(&problem, StepSystem::new(&problem).unwrap(), paper_params()).unwrap();
    let free = system.free_step(&problem, previous, t, None).unwrap();
    let laws = ContactLaws::new(&problem, t, &previous.slip_distance).unwrap();
    let step = condensed(&laws, &paper, problem.dim());
    let stiffness = stiffness(&problem, &paper);
    let w_previous = thermocontact::model::contact_tangential(&problem, &previous.w);
    check(&step, &stiffness, &free.w_free, &w_previous);
}

fn paper_params() -> PaperParams {
    PaperParams {
        tolerance: 1e-6,
        max_convexification: 200,
        inner_tolerance: 1e-10,
        max_inner: 20_000,
    }
}

fn condensed<'a>(laws: &'a ContactLaws<'a>, paper: &'a PaperSolver, dim: usize) -> CondensedStep<'a> {
    CondensedStep {
        condensation: paper.condensation(),
        laws,
        tangential: dim - 1,
        augmentation: paper.augmentation,
        lu_cache: Default::default(),
    }
}

fn stiffness(problem: &Problem, paper: &PaperSolver) -> ContactStiffness {
    let c = paper.condensation();
    let weights: Vec<f64> = problem.contact.iter().map(|node| node.weight).collect();
    ContactStiffness::new(c, problem.dim() - 1, &weights).unwrap()
}

/// Descent alone (no hand-over to Newton) to `tolerance`.
fn descent_only(tolerance: f64) -> DescentParams {
    DescentParams {
        tolerance,
        max_sweeps: 200_000,
        handover: 0.0,
        newton: NEWTON,
        lagged: 0,
    }
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// With Tresca friction the energy is convex and the step has one solution: the descent, from
/// rest, must reach the one semismooth Newton finds. This checks K = D⁻¹, the weights and the
/// heat coupling of the energy against an independent method.
#[test]
fn with_a_convex_law_the_descent_finds_newtons_solution() {
    let scenario = coarse(&["friction={law=\"tresca\", bound=40.0}"]);
    with_step_six(&scenario, |step, stiffness, w_free, w_previous| {
        let newton = step
            .solve(w_free, w_previous.to_vec(), vec![0.0; w_free.len()], None, NEWTON)
            .expect("Newton converges on a convex problem");
        let mut newton_iterations = 0;
        let descent = descend(
            step,
            stiffness,
            w_free,
            Start::at(vec![0.0; w_free.len()]),
            None,
            &descent_only(1e-10),
            &mut newton_iterations,
        )
        .unwrap();
        assert_eq!(newton_iterations, 0);
        let w_scale = max_abs(&newton.w);
        assert!(w_scale > 1e-3, "some nodes slip: max |w_τ| = {w_scale:e}");
        let sticking = newton.w.iter().filter(|w| **w == 0.0).count();
        assert!(sticking > 0, "some nodes stick");
        assert!(max_diff(&descent.w, &newton.w) <= 1e-8 * w_scale);
        assert!(max_diff(&descent.xi, &newton.xi) <= 1e-8 * 40.0);
        // The same stick set, exactly: the descent puts stick nodes at w = 0.
        for (d, n) in descent.w.iter().zip(&newton.w) {
            assert_eq!(*d == 0.0, *n == 0.0);
        }
    });
}

/// A steep law (α = 1000 s/m, b = 0.05): from rest, from the previous step, from w_τ^free and
/// from twice that, the descent returns states that satisfy the condensed step and the nodal
/// law; they may be different solutions.
#[test]
fn with_a_steep_law_the_descent_reaches_a_solution_from_any_start() {
    let scenario = coarse(&["friction.alpha=1000", "friction.b=0.05"]);
    with_step_six(&scenario, |step, stiffness, w_free, w_previous| {
        let starts = [
            vec![0.0; w_free.len()],
            w_previous.to_vec(),
            w_free.to_vec(),
            w_free.iter().map(|w| 2.0 * w).collect(),
        ];
        for start in starts {
            let mut newton_iterations = 0;
            let result = descend(
                step,
                stiffness,
                w_free,
                Start::at(start),
                None,
                &descent_only(1e-9),
                &mut newton_iterations,
            )
            .unwrap();
            let (e1, e2) = step.residuals(w_free, &result.w, &result.xi, None);
            let g_min = (0..result.w.len())
                .map(|i| step.laws.bound(i, result.w[i].abs()))
                .fold(f64::INFINITY, f64::min);
            let w_scale = max_abs(&result.w).max(max_abs(w_free));
            assert!(e1 <= 1e-9 * w_scale, "condensed equations: {e1:e} against {w_scale:e}");
            assert!(e2 <= 1e-9 * g_min, "nodal law: {e2:e}");
            assert!(result.iterations >= 1);
        }
    });
}

/// Five iterations of the paper's loop (`solver.contact_sweeps = 0`; the loop on Γ_C's rows
/// needs fewer) are not enough at step 6 of the coarse example: with the descent the run
/// completes without cutback, every step satisfies the law, and the fields are those of the
/// run whose convexification loop has room to converge (the same solution).
#[test]
fn the_descent_finishes_the_steps_the_convexification_loop_cannot() {
    let starved = coarse(&[
        "solver.contact_sweeps=0",
        "solver.max_convexification=5",
        "solver.cutback=false",
    ]);
    let problem = starved.build().unwrap();
    let params = starved.solver_params();
    let run = driver::run_observed(
        &problem,
        &params,
        &OutputPlan::default(),
        &RunOptions::default(),
        |_, _, _| (),
    )
    .unwrap();
    assert_eq!(run.summary.status, RunStatus::Completed);
    assert!(run.summary.descent_steps >= 1, "{}", run.summary.descent_steps);
    // Over every step and contact node, relative to μ(0)S.
    let worst = run.summary.max_law_residual;
    assert!(worst <= 1e-6, "nodal law residual {worst:e}");

    let (_, reference) = coarse(&["solver.contact_sweeps=0"]).run_quiet().unwrap();
    let diff = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
    let m = &problem.mesh;
    let du = norms::energy(m, &diff(&run.state.u, &reference.u)) / norms::energy(m, &reference.u);
    assert!(du < 1e-5, "displacements differ from the unstarved run: {du:e}");
}
