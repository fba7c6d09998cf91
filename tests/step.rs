//! One time step and whole runs of the paper's example: reduction to the linear viscoelastic
//! step, exactness of the condensation onto Γ_C, and the nodal friction law at the solution.

use faer::linalg::solvers::Solve;
use thermocontact::contact::friction::law_residual;
use thermocontact::la::LaError;
use thermocontact::model::contact_rows;
use thermocontact::model::{samples, State};
use thermocontact::step::Condensation;
use thermocontact::step::{add_contact_terms, tangential_velocities, StepSystem};
use thermocontact::step::{Criterion, SolveError, StepError};
use thermocontact::step::{LinearSystem, StepSolver};
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
    let solver = StepSolver::new(&problem, LinearSystem::Direct(system), &scenario.solver_params()).unwrap();
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
    let problem = samples::paper(16, 4, 64).unwrap();
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
    let solver = StepSolver::new(&problem, LinearSystem::Direct(system), &scenario.solver_params()).unwrap();
    let mut state = State::initial(&problem);
    let tol = scenario.solver.slip_tolerance;
    let mut slipped = 0;
    for _ in 0..scenario.time.steps {
        state = solver.step(&state, state.t + problem.time_step()).unwrap().0;
        for row in contact_rows(&problem, &state, tol) {
            let bound = |r: f64| problem.friction_bound(row.x, state.t, r);
            let residual = law_residual(bound, &row.w_tau[..1], &row.xi[..1], tol);
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
                assert!(row.xi[0].abs() <= bound(0.0) * (1.0 + 1e-9));
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
        let solver = StepSolver::new(&problem, LinearSystem::Direct(system), &scenario.solver_params()).unwrap();
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
    let problem = samples::paper(16, 4, 64).unwrap();
    let system = StepSystem::new(&problem).unwrap();
    let mut x = system
        .rhs(&problem, &State::initial(&problem), problem.time_step())
        .unwrap();
    system.solve_in_place(&mut x.clone()).unwrap();
    x[0] = f64::NAN;
    match system.solve_in_place(&mut x) {
        Err(StepError::La(LaError::NonFiniteSolution { non_finite, unknowns })) => {
            assert!(non_finite > 0 && non_finite <= unknowns);
            assert_eq!(unknowns, system.n_unknowns());
        }
        other => panic!("{other:?}"),
    }
}

/// Small problems of every kind the factor meets: 2D (one and two contact faces), 2D and 3D from
/// Gmsh with curved contact faces, a 3D box, a 3D slab between symmetry planes (tangential
/// coordinates held at zero).
fn problems() -> Vec<(&'static str, thermocontact::Problem)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = |path: &str, overrides: &[&str]| {
        Scenario::load_file(
            &root.join(path),
            &overrides.iter().map(|s| s.to_string()).collect::<Vec<_>>(),
        )
        .unwrap()
        .build()
        .unwrap()
    };
    let pad = format!(
        "mesh.file={:?}",
        root.join("tests/meshes/pad3d_coarse.msh").to_str().unwrap()
    );
    vec![
        ("2D", samples::paper(16, 4, 64).unwrap()),
        (
            "2D, two contact faces",
            coarse(&[
                r#"boundary.contact=["bottom", "right"]"#,
                r#"boundary.neumann=["top"]"#,
                r#"loads.traction=[{part="top", constant=[0.0, 0.0], rate=[0.0, -800.0]}]"#,
            ])
            .build()
            .unwrap(),
        ),
        ("2D Gmsh brake shoe", file("scenarios/brake_shoe.toml", &[])),
        (
            "3D box",
            file("scenarios/paper3d.toml", &["mesh.nx=8", "mesh.ny=3", "mesh.nz=3"]),
        ),
        (
            "3D slab, symmetry planes",
            file(
                "scenarios/paper3d.toml",
                &[
                    "mesh.nx=8",
                    "mesh.ny=2",
                    "mesh.nz=3",
                    r#"boundary.neumann=["x+", "z+"]"#,
                    r#"boundary.symmetry=["y-", "y+"]"#,
                ],
            ),
        ),
        ("3D Gmsh pad", file("scenarios/pad3d.toml", &[&pad])),
    ]
}

/// A reproducible vector with entries in [−1, 1).
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

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// The split sweeps (forward, diagonal, backward over faer's supernodal layout) solve as faer's
/// own solve does, and the sweeps restricted to the trailing block give the same numbers where
/// they apply: a right-hand side on the contact unknowns, x read on the contact unknowns.
#[test]
fn split_sweeps_agree_with_faers_solve() {
    for (name, problem) in problems() {
        let system = StepSystem::new(&problem).unwrap();
        let factor = system.factor();
        let n = system.n_unknowns();
        let t0 = factor.trailing_start();
        let n_contact_unknowns = problem
            .contact
            .iter()
            .map(|c| c.tangent_dofs.iter().flatten().count() + usize::from(c.theta_dof.is_some()))
            .sum::<usize>();
        assert_eq!(n - t0, n_contact_unknowns, "{name}");
        let (mut permuted, mut scratch) = (vec![0.0; n], vec![0.0; factor.scratch_len()]);
        for seed in 1..4 {
            let b = random_vector(n, seed);
            let mut expected = b.clone();
            factor.solve_in_place(&mut expected, 1);
            let mut x = b.clone();
            factor.solve_split_in_place(&mut x, &mut permuted, &mut scratch);
            let err = max_diff(&x, &expected) / max_abs(&expected);
            assert!(err < 1e-12, "{name}: split sweeps differ from faer's solve by {err:e}");
        }
        // A right-hand side on the contact unknowns: forward over the trailing block only.
        let mut b = vec![0.0; n];
        for (k, p) in (t0..n).enumerate() {
            b[factor.unknown_at(p)] = ((k % 7) as f64 - 3.0) * 0.1;
        }
        let mut expected = b.clone();
        factor.solve_in_place(&mut expected, 1);
        factor.permute(&b, &mut permuted);
        factor.forward(&mut permuted, &mut scratch, t0);
        factor.diagonal(&mut permuted, t0);
        let z = permuted.clone();
        factor.backward(&mut permuted, &mut scratch, 0);
        let mut x = vec![0.0; n];
        factor.unpermute(&permuted, &mut x);
        let err = max_diff(&x, &expected) / max_abs(&expected);
        assert!(err < 1e-12, "{name}: trailing forward sweep off by {err:e}");
        // x on the contact unknowns from z on them alone.
        let mut trailing = vec![f64::NAN; n];
        trailing[t0..].copy_from_slice(&z[t0..]);
        factor.backward(&mut trailing, &mut scratch, t0);
        let err = max_diff(&trailing[t0..], &permuted[t0..]) / max_abs(&permuted[t0..]);
        assert!(err < 1e-12, "{name}: trailing backward sweep off by {err:e}");
    }
}

/// C and H from the trailing block of the factor equal C and H from n_t full solves with unit
/// right-hand sides (the column-solve condensation this replaced, kept here as the oracle).
#[test]
fn trailing_block_condensation_equals_column_solves() {
    for (name, problem) in problems() {
        let system = StepSystem::new(&problem).unwrap();
        let cond = Condensation::new(&problem, &system).unwrap();
        let tangential = problem.dim() - 1;
        let n_contact = problem.contact.len();
        let n_t = n_contact * tangential;
        let n = system.n_unknowns();
        let n_w = system.n_w();
        let tangent_dof = |col: usize| problem.contact[col / tangential].tangent_dofs[col % tangential];
        let mut friction = vec![0.0; n_t * n_t];
        let mut heat = vec![0.0; n_t * n_contact];
        let mut block = vec![0.0; n * n_t];
        for (j, column) in block.chunks_exact_mut(n).enumerate() {
            if let Some(dof) = tangent_dof(j) {
                column[dof] = 1.0;
            }
        }
        system.solve_symmetric_block_in_place(&mut block, n_t).unwrap();
        for (col, column) in block.chunks_exact(n).enumerate() {
            let weight = problem.contact[col / tangential].weight;
            for row in 0..n_t {
                friction[row * n_t + col] = tangent_dof(row).map_or(0.0, |dof| column[dof] * weight);
            }
            for (i, node) in problem.contact.iter().enumerate() {
                if let Some(r) = node.theta_dof {
                    heat[col * n_contact + i] = -column[n_w + r] * node.weight;
                }
            }
        }
        let held: Vec<usize> = (0..n_t).filter(|&c| tangent_dof(c).is_none()).collect();
        if !held.is_empty() {
            let free: Vec<usize> = (0..n_t).filter(|&c| tangent_dof(c).is_some()).collect();
            let mean = free.iter().map(|&c| friction[c * n_t + c]).sum::<f64>() / free.len().max(1) as f64;
            for &c in &held {
                friction[c * n_t + c] = if mean > 0.0 { mean } else { 1.0 };
            }
        }
        assert_eq!((cond.n_t, cond.n_h), (n_t, n_contact), "{name}");
        let err = max_diff(&cond.friction, &friction) / max_abs(&friction);
        assert!(err < 1e-12, "{name}: C differs by {err:e} (relative)");
        let err = max_diff(&cond.heat, &heat) / max_abs(&heat);
        assert!(err < 1e-12, "{name}: H differs by {err:e} (relative)");
        assert!(max_abs(&heat) > 0.0, "{name}: thermal expansion couples heat into w_τ");
        if name.contains("symmetry") {
            assert!(!held.is_empty(), "{name}: the case has held tangential coordinates");
        }
    }
}

/// free_step and loaded_state (one full forward sweep, one full backward sweep, the rest on the
/// contact block) give the fields of one full solve of the right-hand side with the contact
/// terms, and w_τ^free of a full solve without them; loaded_state may be called again (the
/// paper's solver does per convexification iterate).
#[test]
fn free_and_loaded_steps_equal_one_full_solve() {
    for (name, problem) in problems() {
        let system = StepSystem::new(&problem).unwrap();
        let k = problem.time_step();
        let mut previous = State::initial(&problem);
        let kick = random_vector(previous.w.len(), 5);
        previous.w.iter_mut().zip(kick).for_each(|(w, r)| *w += 0.1 * r);
        let t = k;
        let tangential = problem.dim() - 1;
        let n_c = problem.contact.len();
        let before = system.stats();
        let mut free = system.free_step(&problem, &previous, t, None).unwrap();
        let base = system.rhs(&problem, &previous, t).unwrap();
        let mut x = base.clone();
        system.solve_in_place(&mut x).unwrap();
        let w_free = tangential_velocities(&problem, &x);
        let err = max_diff(&free.w_free, &w_free) / max_abs(&w_free);
        assert!(err < 1e-12, "{name}: w_free off by {err:e}");
        for seed in [11, 12] {
            let xi: Vec<f64> = random_vector(n_c * tangential, seed).iter().map(|v| 3.0 * v).collect();
            let heat: Vec<f64> = random_vector(n_c, seed + 100).iter().map(|v| 0.5 * v.abs()).collect();
            let state = system
                .loaded_state(&problem, &previous, t, &mut free, xi.clone(), &heat)
                .unwrap();
            let mut x = base.clone();
            add_contact_terms(&problem, system.n_w(), &xi, &heat, &mut x);
            system.solve_in_place(&mut x).unwrap();
            let expected = system.state_from(&problem, &previous, t, &x, xi);
            let err = max_diff(&state.w, &expected.w) / max_abs(&expected.w);
            assert!(err < 1e-12, "{name}: w off by {err:e}");
            let err = max_diff(&state.theta, &expected.theta) / max_abs(&expected.theta);
            assert!(err < 1e-12, "{name}: θ off by {err:e}");
        }
        // One forward sweep, two backward sweeps over all of L, three full solves by faer.
        let work = system.stats().since(before);
        assert_eq!((work.sweeps, work.trailing_sweeps, work.solves), (3, 3, 3), "{name}");
    }
}
