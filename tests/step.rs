//! One time step and whole runs of the paper's example: reduction to the linear viscoelastic
//! step, exactness of the condensation onto Γ_C, and the nodal friction law at the solution.

use faer::linalg::solvers::Solve;
use thermocontact::contact::friction::law_residual;
use thermocontact::solver::condensed::Condensation;
use thermocontact::solver::system::{add_contact_terms, tangential_velocities, State, StepSystem};
use thermocontact::solver::{Criterion, SolveError};
use thermocontact::time::{contact_rows, StepSolver};
use thermocontact::Scenario;

fn coarse(overrides: &[&str]) -> Scenario {
    let mut all = vec!["mesh.nx=16".to_string(), "mesh.ny=4".to_string()];
    all.extend(overrides.iter().map(|s| s.to_string()));
    Scenario::load(None, &all).unwrap()
}

/// With S = 0 and α_exp = 0 the mechanics decouple from friction and heat: the first step must
/// be the plain linear viscoelastic step (ℳ/k + 𝒦_A + k𝒦_B) W₁ = ℳW₀/k − 𝒦_B U₀ + F₁ on E^h,
/// here solved densely from the assembled blocks.
#[test]
fn frictionless_uncoupled_step_is_the_linear_viscoelastic_step() {
    let scenario = coarse(&["friction.bound=0.0", "material.thermal_expansion=0.0"]);
    let problem = scenario.build().unwrap();
    let system = StepSystem::new(&problem).unwrap();
    let solver = StepSolver::new(&problem, system, &scenario.solver_params()).unwrap();
    let (state, _) = solver.step(&State::initial(&problem), problem.time_step()).unwrap();

    let k = problem.time_step();
    let n = problem.velocity.n_free;
    let m = &problem.matrices;
    let columns: Vec<Vec<f64>> = (0..n)
        .map(|j| {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            problem.velocity.prolong(&e)
        })
        .collect();
    let mut a = faer::Mat::<f64>::zeros(n, n);
    for (j, pj) in columns.iter().enumerate() {
        let mut s = m.mass.mul(pj).iter().map(|v| v / k).collect::<Vec<_>>();
        m.viscosity.mul_add(1.0, pj, &mut s);
        m.elasticity.mul_add(k, pj, &mut s);
        for (i, pi) in columns.iter().enumerate() {
            a[(i, j)] = pi.iter().zip(&s).map(|(x, y)| x * y).sum();
        }
    }
    let force = problem.force(k).unwrap();
    let mut b = faer::Mat::<f64>::zeros(n, 1);
    for (i, pi) in columns.iter().enumerate() {
        b[(i, 0)] = pi.iter().zip(&force).map(|(x, y)| x * y).sum();
    }
    let w = a.partial_piv_lu().solve(&b);
    let w_full = problem.velocity.prolong(&(0..n).map(|i| w[(i, 0)]).collect::<Vec<_>>());
    let scale = w_full.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let err = w_full
        .iter()
        .zip(&state.w)
        .fold(0.0f64, |s, (a, b)| s.max((a - b).abs()));
    assert!(scale > 1e-3, "the load moves the body");
    assert!(
        err < 1e-10 * scale,
        "step differs from the linear viscoelastic step by {err:e}"
    );
    assert!(state.xi.iter().all(|&x| x == 0.0), "S = 0 gives no friction stress");
}

/// The condensed compliances C and H reproduce full solves with arbitrary contact loads.
#[test]
fn condensation_matches_full_solves() {
    let problem = coarse(&[]).build().unwrap();
    let system = StepSystem::new(&problem).unwrap();
    let cond = Condensation::new(&problem, &system).unwrap();
    let n_c = problem.contact.len();
    let xi: Vec<f64> = (0..n_c).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
    let heat: Vec<f64> = (0..n_c).map(|i| 0.1 * (i % 3) as f64).collect();
    let mut x = vec![0.0; system.n_unknowns()];
    add_contact_terms(&problem, problem.n_w(), &xi, &heat, &mut x);
    system.solve_in_place(&mut x).unwrap();
    let direct = tangential_velocities(&problem, &x);
    let mut w = vec![0.0; cond.n_t];
    cond.velocities(&vec![0.0; cond.n_t], &xi, &heat, &mut w);
    let scale = direct.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    for (a, b) in direct.iter().zip(&w) {
        assert!((a - b).abs() < 1e-12 * scale);
    }
    // The heat columns matter: thermal expansion couples heat on Γ_C back into w_τ.
    assert!(cond.heat.iter().any(|h| h.abs() > 0.0));
}

/// The paper's example on a coarse mesh runs to T and its contact state obeys the nodal law:
/// |ξ_i| = μ(|w_i|)S at slip nodes (with the right sign), |ξ_i| ≤ μ(0)S at stick nodes.
#[test]
fn default_scenario_on_a_coarse_mesh_satisfies_the_friction_law() {
    let scenario = coarse(&[]);
    let problem = scenario.build().unwrap();
    let system = StepSystem::new(&problem).unwrap();
    let solver = StepSolver::new(&problem, system, &scenario.solver_params()).unwrap();
    let mut state = State::initial(&problem);
    let tol = scenario.solver.slip_tolerance;
    let mut slipped = 0;
    for _ in 0..scenario.time.steps {
        state = solver.step(&state, state.t + problem.time_step()).unwrap().0;
        for row in contact_rows(&problem, &state, tol) {
            let residual = law_residual(problem.friction.as_ref(), &row.w_tau[..1], &row.xi[..1], tol);
            assert!(
                residual <= 1e-6 * row.bound.max(1.0),
                "law violated at node {} (t_n = {}): {residual:e}",
                row.node,
                state.n
            );
            if row.slip {
                slipped += 1;
                assert!((row.xi[0].abs() - row.bound).abs() <= 1e-6 * row.bound);
                assert!(row.xi[0] * row.w_tau[0] < 0.0, "friction opposes slip");
            } else {
                assert!(row.xi[0].abs() <= problem.friction.bound(0.0) * (1.0 + 1e-9));
            }
        }
    }
    assert_eq!(state.n, scenario.time.steps);
    assert!(slipped > 0, "the example has slipping nodes");
    let (summary, last) = scenario.run_quiet().unwrap();
    assert_eq!(summary.outputs.len(), 4);
    let end = summary.outputs.last().unwrap();
    assert_eq!(end.slip_nodes + end.stick_nodes, problem.contact.len());
    assert_eq!(last.u, state.u, "the driver runs the same steps");
}

/// A solver that hits its iteration cap names the loop and the criterion that failed, with its
/// value above the tolerance.
#[test]
fn non_convergence_names_the_failed_criterion_and_its_value() {
    // The fast solver's descent off (it would take over from the convexification loop), then on
    // with one sweep: its failure is the nodal law after that sweep.
    for (kind, sweeps) in [("paper", 0), ("fast", 0), ("fast", 1)] {
        let scenario = coarse(&[
            &format!("solver.kind={kind}"),
            "solver.max_convexification=1",
            "solver.tolerance=1e-14",
            &format!("solver.max_sweeps={sweeps}"),
        ]);
        let problem = scenario.build().unwrap();
        let system = StepSystem::new(&problem).unwrap();
        let solver = StepSolver::new(&problem, system, &scenario.solver_params()).unwrap();
        let mut state = State::initial(&problem);
        let failure = loop {
            match solver.step(&state, state.t + problem.time_step()) {
                Ok((next, _)) => state = next,
                Err(SolveError::NotConverged(failure)) => break failure,
                Err(SolveError::Other(e)) => panic!("{kind}: {e}"),
            }
            assert!(
                state.n < scenario.time.steps,
                "{kind}: a single convexification iterate cannot meet 1e-14 all the way"
            );
        };
        // The failure names the criterion that failed, past its tolerance, not one that passed.
        if sweeps == 0 {
            assert_eq!(failure.loop_name, "convexification", "{failure}");
        } else {
            assert_eq!(failure.loop_name, "descent", "{failure}");
            assert_eq!(failure.criterion, Criterion::NodalLaw, "{failure}");
        }
        assert_eq!(failure.iterations, 1);
        assert_eq!(failure.tolerance, 1e-14);
        assert!(failure.value > failure.tolerance, "{failure}");
        let message = failure.to_string();
        assert!(message.contains(failure.criterion.describe()), "{message}");
        if kind == "paper" {
            assert!(
                matches!(
                    failure.criterion,
                    Criterion::IncrementU
                        | Criterion::IncrementTheta
                        | Criterion::IncrementXi
                        | Criterion::IncrementZeta
                ),
                "{failure}"
            );
        }
    }
}

/// A linear solve never passes NaN on: a non-finite right-hand side comes back as an error that
/// counts the bad values.
#[test]
fn a_non_finite_solve_is_an_error() {
    let problem = coarse(&[]).build().unwrap();
    let system = StepSystem::new(&problem).unwrap();
    let mut x = system
        .rhs(&problem, &State::initial(&problem), problem.time_step())
        .unwrap();
    system.solve_in_place(&mut x.clone()).unwrap();
    x[0] = f64::NAN;
    match system.solve_in_place(&mut x) {
        Err(thermocontact::Error::NonFiniteSolution { non_finite, unknowns }) => {
            assert!(non_finite > 0 && non_finite <= unknowns);
            assert_eq!(unknowns, system.n_unknowns());
        }
        other => panic!("{other:?}"),
    }
}
