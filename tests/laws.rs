//! The laws of Γ_C in the paper's generality: the paper's law written as an expression and as a
//! table reproduces the built-in one; a nonmonotone heat exchange reaches its algebraic steady
//! state; slip-distance weakening accumulates the slip and restarts bit for bit; per-part laws
//! slip at their own bounds; the reported m_τ and the uniqueness condition.

mod common;

use std::path::{Path, PathBuf};

use common::coarse;
use thermocontact::driver::{self, OutputPlan, Restart, RunOptions, StopFlag, CHECKPOINT_FILE};
use thermocontact::model::{contact_rows, contact_tangential, State};
use thermocontact::step::{LinearSystem, StepSolver};
use thermocontact::{Interruption, Scenario};

const PAPER3D: &str = include_str!("../scenarios/paper3d.toml");

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-laws-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn run(scenario: &Scenario) -> State {
    let problem = scenario.build().unwrap();
    driver::run_quiet(&problem, &scenario.solver_params(), &OutputPlan::default())
        .unwrap()
        .1
}

/// The largest difference of two fields relative to the larger field's largest value.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().chain(b).fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale.max(f64::MIN_POSITIVE)
}

fn slip_set(scenario: &Scenario, state: &State) -> Vec<bool> {
    let problem = scenario.build().unwrap();
    contact_rows(&problem, state, scenario.solver.slip_tolerance)
        .iter()
        .map(|r| r.slip)
        .collect()
}

/// μ of the paper's law in a CSV file: 8001 slip rates on [0, 0.4] (h = 5·10⁻⁵).
fn paper_table(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("mu.csv");
    let mut text = String::from("slip_rate,coefficient\n");
    for k in 0..=8000 {
        let r = 0.4 * k as f64 / 8000.0;
        text += &format!("{r:e},{:e}\n", 0.8 * (-100.0 * r).exp() + 0.2);
    }
    std::fs::write(&path, text).unwrap();
    path
}

/// The paper's law three ways on one path: built in, as an expression (to 10⁻¹²; measured:
/// bit for bit with exmex's symbolic derivative as the Newton slope; to 10⁻¹² with the automatic
/// derivative that replaced it) and as a
/// piecewise-linear table 5·10⁻⁵ apart (interpolation error h²/8 · max|μ''| = 2.5·10⁻⁶ of
/// μ(0); measured: 10⁻⁹ in 2D, 3·10⁻⁸ in 3D, relative).
fn the_paper_law_three_ways(base: Option<&str>, overrides: &[&str], tag: &str) {
    let load = |extra: &[String]| {
        let mut all: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        all.extend(extra.iter().cloned());
        Scenario::load(base, &all).unwrap()
    };
    let builtin = load(&[]);
    let expression =
        load(&["friction={law=\"expression\", bound=150.0, coefficient=\"0.8*exp(-100*r) + 0.2\"}".into()]);
    let file = paper_table(&scratch(tag));
    let table = load(&[format!(
        "friction={{law=\"table\", bound=150.0, file=\"{}\"}}",
        file.display()
    )]);
    let reference = run(&builtin);
    for (name, scenario, tolerance) in [("expression", &expression, 1e-12), ("table", &table, 1e-6)] {
        let state = run(scenario);
        for (field, a, b) in [
            ("u", &state.u, &reference.u),
            ("w", &state.w, &reference.w),
            ("θ", &state.theta, &reference.theta),
            ("ξ", &state.xi, &reference.xi),
        ] {
            let d = relative_difference(a, b);
            eprintln!("{tag}, {name}: {field} differs by {d:.2e}");
            assert!(d <= tolerance, "{tag}, {name}: {field} differs by {d:e} (relative)");
        }
        assert_eq!(
            slip_set(scenario, &state),
            slip_set(&builtin, &reference),
            "{tag}, {name}: the same nodes slip"
        );
    }
}

#[test]
fn the_paper_law_as_expression_and_table_2d_direct() {
    the_paper_law_three_ways(None, &["mesh.nx=16", "mesh.ny=4", "time.steps=16"], "2d-direct");
}

#[test]
fn the_paper_law_as_expression_and_table_2d_iterative() {
    the_paper_law_three_ways(
        None,
        &["mesh.nx=16", "mesh.ny=4", "time.steps=16", "solver.linear=iterative"],
        "2d-iterative",
    );
}

#[test]
fn the_paper_law_as_expression_and_table_3d_both_paths() {
    let small = ["mesh.nx=6", "mesh.ny=2", "mesh.nz=2", "time.steps=8"];
    the_paper_law_three_ways(Some(PAPER3D), &small, "3d-direct");
    let iterative = [&small[..], &["solver.linear=iterative"]].concat();
    the_paper_law_three_ways(Some(PAPER3D), &iterative, "3d-iterative");
}

/// ∂j(θ) = θ/2 − 5 sin(θ/5), nonmonotone (slope from −½ to 3/2), on the bottom of a unit
/// square held at θ_D = 50 on the top, insulated sides, no mechanics: the steady state is
/// θ linear in y, which P1 represents exactly, with θ_C at the bottom solving
/// K (θ_D − θ_C)/H = ∂j(θ_C). After T = 20 τ (τ = ρ c_p H²/K) the run is there to 10⁻⁸.
#[test]
fn a_nonmonotone_heat_exchange_reaches_its_algebraic_steady_state() {
    let scenario = Scenario::load(
        None,
        &[
            "geometry.lengths=[1.0, 1.0]".into(),
            "mesh.nx=4".into(),
            "mesh.ny=4".into(),
            "boundary.dirichlet=[\"top\"]".into(),
            "boundary.neumann=[]".into(),
            "boundary.contact=[\"bottom\"]".into(),
            "boundary.temperature=50.0".into(),
            "initial.temperature=0.0".into(),
            "material.conductivity=100.0".into(),
            "material.thermal_expansion=0.0".into(),
            "loads.body_force=[0.0, 0.0]".into(),
            "loads.traction=[]".into(),
            "time.final_time=2.0".into(),
            "time.steps=40".into(),
            "heat_exchange={law=\"expression\", flux=\"0.5*theta - 5*sin(theta/5)\"}".into(),
        ],
    )
    .unwrap();
    let problem = scenario.build().unwrap();
    let (summary, state) = driver::run_quiet(&problem, &scenario.solver_params(), &OutputPlan::default()).unwrap();
    // The root of 100 (50 − θ) = θ/2 − 5 sin(θ/5), unique (the left side falls at 100).
    let f = |theta: f64| 100.0 * (50.0 - theta) - (0.5 * theta - 5.0 * (theta / 5.0).sin());
    let (mut lo, mut hi) = (0.0, 60.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    let theta_c = 0.5 * (lo + hi);
    for node in &problem.contact {
        let theta = state.theta[node.node];
        assert!((theta - theta_c).abs() < 1e-8, "θ_C = {theta}, expected {theta_c}");
    }
    // Linear in y everywhere.
    for (p, x) in problem.mesh.coords.iter().enumerate() {
        let expected = theta_c + (50.0 - theta_c) * x[1];
        assert!((state.theta[p] - expected).abs() < 1e-8, "node {p}: {}", state.theta[p]);
    }
    assert!(
        summary.laws.m_theta > 1.49 && summary.laws.m_theta < 1.51,
        "{}",
        summary.laws.m_theta
    );
    assert_eq!(summary.laws.heat_exchange, "expression");
}

/// Slip-distance weakening: s_i = Σ k |w_τ,i| over the steps, the bound S μ(s) of the state
/// before each step, and a restart that continues bit for bit, s included.
#[test]
fn slip_distance_weakening_accumulates_and_restarts_bitwise() {
    let law = "friction={law=\"slip-distance-weakening\", bound=150.0, static=1.0, dynamic=0.2, distance=0.002}";
    let scenario = coarse(&[law, "output.times=[0.5, 1.0]"]);
    let problem = scenario.build().unwrap();
    let params = scenario.solver_params();
    let plan = scenario.output_plan();
    let k = problem.time_step();
    let mut sum = vec![0.0; problem.contact.len()];
    let mut previous_sum = sum.clone();
    let mut weakened = false;
    let whole = scratch("slip-whole");
    let reference = driver::run_observed(
        &problem,
        &params,
        &plan,
        &RunOptions {
            out_dir: Some(whole.clone()),
            ..RunOptions::default()
        },
        |problem, state, _| {
            let td = problem.dim() - 1;
            let w = contact_tangential(problem, &state.w);
            previous_sum.clone_from(&sum);
            for (i, s) in sum.iter_mut().enumerate() {
                *s += k * w[i * td..(i + 1) * td].iter().map(|x| x * x).sum::<f64>().sqrt();
            }
            for (i, row) in contact_rows(problem, state, 1e-6).iter().enumerate() {
                let s = row.slip_distance.expect("reported");
                assert!(
                    (s - sum[i]).abs() <= 1e-12 * sum[i].max(1e-30),
                    "node {i}: {s} vs {}",
                    sum[i]
                );
                // The step read s_{n−1}: its bound is S μ(s_{n−1}).
                let mu = 1.0 - 0.8 * (previous_sum[i] / 0.002).min(1.0);
                assert!((row.bound - 150.0 * mu).abs() < 1e-9, "node {i}: bound {}", row.bound);
                weakened |= previous_sum[i] > 0.002;
            }
        },
    )
    .unwrap();
    assert!(weakened, "some node slides past D_c");
    assert!(std::fs::read_to_string(whole.join("contact_0016.csv"))
        .unwrap()
        .starts_with("x,y,nu_x,nu_y,w_tau,xi,bound,slip,theta,slip_distance"));

    // Stopped after step 5, continued from its checkpoint: the same final state, bit for bit.
    let dir = scratch("slip-restart");
    let stop = StopFlag::new();
    let stopped = driver::run_observed(
        &problem,
        &params,
        &plan,
        &RunOptions {
            out_dir: Some(dir.clone()),
            stop: Some(stop.clone()),
            ..RunOptions::default()
        },
        |_, state, _| {
            if state.n == 5 {
                stop.request(Interruption::Terminate);
            }
        },
    )
    .err();
    assert!(matches!(stopped, Some(thermocontact::Error::Interrupted { .. })));
    let restart = Restart::read(&dir.join(CHECKPOINT_FILE)).unwrap();
    assert!(restart.checkpoint.state.slip_distance.iter().any(|&s| s > 0.0));
    let continued = driver::run_observed(
        &problem,
        &params,
        &plan,
        &RunOptions {
            out_dir: Some(dir.clone()),
            restart: Some(restart),
            ..RunOptions::default()
        },
        |_, _, _| {},
    )
    .unwrap();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (a, b) in [
        (&continued.state.u, &reference.state.u),
        (&continued.state.theta, &reference.state.theta),
        (&continued.state.slip_distance, &reference.state.slip_distance),
    ] {
        assert_eq!(bits(a), bits(b));
    }
}

/// Two contact parts (bottom and top) with their own Tresca bounds, a body held by friction
/// alone and pulled along x: the part with the small bound slips at its bound, the other
/// sticks; swapping the bounds swaps the roles.
#[test]
fn per_part_laws_slip_at_their_own_bounds() {
    for (bottom, top) in [(5.0, 5000.0), (5000.0, 5.0)] {
        let scenario = coarse(&[
            "boundary.dirichlet=[]",
            "boundary.neumann=[\"left\", \"right\"]",
            "boundary.contact=[\"bottom\", \"top\"]",
            "material.thermal_expansion=0.0",
            "loads.body_force={constant=[0.0, 0.0], rate=[40.0, 0.0]}",
            "loads.traction=[]",
            &format!(
                "friction=[{{law=\"tresca\", part=\"bottom\", bound={bottom}}}, {{law=\"tresca\", part=\"top\", bound={top}}}]"
            ),
        ]);
        let problem = scenario.build().unwrap();
        let state = run(&scenario);
        let rows = contact_rows(&problem, &state, scenario.solver.slip_tolerance);
        let (mut slipped, mut stuck) = (0, 0);
        for row in &rows {
            let on_bottom = row.x[1] == 0.0;
            let bound = if on_bottom { bottom } else { top };
            assert_eq!(row.bound, bound, "node {}", row.node);
            if row.slip {
                assert!((row.xi[0].abs() - bound).abs() <= 1e-6 * bound, "slips at its bound");
                assert_eq!(bound, 5.0, "only the weak part slips (node {})", row.node);
                slipped += 1;
            } else {
                assert!(row.xi[0].abs() <= bound * (1.0 + 1e-9));
                stuck += 1;
            }
        }
        assert!(slipped > 0 && stuck > 0, "{slipped} slip, {stuck} stick");
    }
}

/// m_τ of the paper's law is S α (a − b) = 12 000; Tresca's is 0 and its steps are unique
/// for every k. For the paper's law on the coarse grid the condition m_τ λ_max(C) < 1 holds
/// at small k and fails as k grows, where the reported limit says.
#[test]
fn the_reported_constants_and_the_uniqueness_condition() {
    let paper = coarse(&[]);
    let problem = paper.build().unwrap();
    let constants = problem.law_constants();
    assert_eq!(constants.friction[0].law, "velocity-weakening");
    assert!((constants.m_tau - 12_000.0).abs() < 1e-6, "{}", constants.m_tau);
    assert!((constants.c_tau - 150.0).abs() < 1e-9);
    assert!((constants.m_theta - 2.0).abs() < 1e-12 && (constants.l_tau - 10.0).abs() < 1e-12);
    let tresca = coarse(&["friction={law=\"tresca\", bound=150.0}"])
        .build()
        .unwrap()
        .law_constants();
    assert_eq!(tresca.m_tau, 0.0);
    let unique = driver::Uniqueness::new(1.0, tresca.m_tau, 0.1);
    assert!(unique.unique && unique.time_step_limit.is_none());
    assert!(constants.warnings.is_empty() && tresca.warnings.is_empty());
    // Outside the theory but computable: a bound that grows without limit runs, with a warning.
    let growing = coarse(&["friction={law=\"expression\", bound=1.0, coefficient=\"0.5 + r\"}"]);
    let warnings = growing.build().unwrap().law_constants().warnings;
    assert!(warnings.len() == 1 && warnings[0].contains("H(j_τ)(c)"), "{warnings:?}");

    let verdict = |steps: usize| {
        let scenario = coarse(&[&format!("time.steps={steps}")]);
        let problem = scenario.build().unwrap();
        let params = scenario.solver_params();
        let linear = LinearSystem::new(&problem, problem.time_step(), &params).unwrap();
        let solver = StepSolver::new(&problem, linear, &params).unwrap();
        driver::Uniqueness::new(
            solver.compliance().unwrap(),
            problem.law_constants().m_tau,
            problem.time_step(),
        )
    };
    let (fine, coarse_k) = (verdict(4096), verdict(16));
    // The iterative path's fast solver estimates the same compliance (power iteration, 10⁻³).
    let iterative = coarse(&["solver.linear=iterative"]);
    let problem = iterative.build().unwrap();
    let params = iterative.solver_params();
    let linear = LinearSystem::new(&problem, problem.time_step(), &params).unwrap();
    let estimate = StepSolver::new(&problem, linear, &params)
        .unwrap()
        .compliance()
        .unwrap();
    let exact = verdict(16).compliance;
    assert!((estimate - exact).abs() <= 1e-2 * exact, "{estimate} against {exact}");
    assert!(fine.unique, "k = 1/4096: {}", fine.line());
    assert!(!coarse_k.unique, "k = 1/16: {}", coarse_k.line());
    // The compliance grows with k, and the estimated limit lies between the two.
    assert!(coarse_k.compliance > fine.compliance);
    let limit = fine.time_step_limit.unwrap();
    assert!(limit > 1.0 / 4096.0 && limit < 1.0 / 16.0, "limit {limit}");
}

/// Refused input names the key, the value and what was expected.
#[test]
fn bad_laws_are_refused_by_key() {
    let refused = |set: &str, fragments: &[&str]| {
        let e = Scenario::load(None, &[set.to_string()]).unwrap_err().to_string();
        for f in fragments {
            assert!(e.contains(f), "{set}: {e}");
        }
    };
    refused(
        "friction={law=\"table\", bound=1.0, slip_rate=[0.0, 0.0], coefficient=[1.0, 0.5]}",
        &["friction.slip_rate", "increasing"],
    );
    refused(
        "friction={law=\"table\", bound=1.0, slip_rate=[0.0, 1.0], coefficient=[1.0, -0.5]}",
        &["friction.coefficient", "non-negative"],
    );
    refused(
        "friction={law=\"expression\", bound=1.0, coefficient=\"0.5*q\"}",
        &["friction.coefficient", "`q`", "r"],
    );
    refused(
        "heat_exchange={law=\"expression\", flux=\"r*theta\"}",
        &["heat_exchange.flux", "`r`"],
    );
    refused(
        "heat_exchange={law=\"table\", temperature=[0.0, 1.0], flux=[0.0, inf]}",
        &["heat_exchange.flux", "finite"],
    );
    refused("frictional_heating.share=1.5", &["frictional_heating.share", "1.5"]);
    refused(
        "friction=[{law=\"tresca\", part=\"bottom\", bound=1.0}, {law=\"tresca\", part=\"top\", bound=-2.0}]",
        &["friction[1].bound"],
    );
    refused(
        "friction={law=\"table\", bound=1.0, file=\"/nonexistent/mu.csv\"}",
        &["friction.file", "mu.csv"],
    );
    let e = Scenario::load(None, &["friction.law=\"amontons\"".into()])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("amontons")
            && e.contains("coulomb")
            && e.contains("velocity-weakening")
            && e.contains("slip-distance-weakening"),
        "{e}"
    );
}

/// The showcases: a table on one contact part, an expression on another and a nonmonotone
/// heat exchange, in 2D and 3D; the direct and the iterative paths agree.
#[test]
fn the_own_laws_showcases_run_on_both_paths_in_2d_and_3d() {
    for (file, sizes) in [
        (
            "scenarios/own_laws.toml",
            &["mesh.nx=16", "mesh.ny=4", "time.steps=16"][..],
        ),
        (
            "scenarios/own_laws3d.toml",
            &["mesh.nx=8", "mesh.ny=2", "mesh.nz=2", "time.steps=8"][..],
        ),
    ] {
        let states: Vec<State> = ["direct", "iterative"]
            .iter()
            .map(|linear| {
                let mut overrides: Vec<String> = sizes.iter().map(|s| s.to_string()).collect();
                overrides.push(format!("solver.linear={linear}"));
                let scenario = Scenario::load_file(Path::new(file), &overrides).unwrap();
                let problem = scenario.build().unwrap();
                let (summary, state) =
                    driver::run_quiet(&problem, &scenario.solver_params(), &OutputPlan::default()).unwrap();
                assert!(
                    summary.exchange_iterations >= state.n,
                    "{file}: the heat exchange iterates"
                );
                assert_eq!(summary.laws.friction.len(), 2);
                state
            })
            .collect();
        let d = relative_difference(&states[0].u, &states[1].u);
        assert!(d < 1e-6, "{file}: the paths differ by {d:e} in u");
        let d = relative_difference(&states[0].theta, &states[1].theta);
        assert!(d < 1e-6, "{file}: the paths differ by {d:e} in θ");
    }
}

/// A heat exchange given as a table and as an expression of the same ∂j = 2θ take the same
/// path (nodal, iterated) and agree; against the built-in linear law (a Robin term with the
/// consistent boundary mass) they differ by the quadrature only.
#[test]
fn a_tabulated_heat_exchange_agrees_with_its_expression_and_the_linear_law() {
    let table = coarse(&["heat_exchange={law=\"table\", temperature=[-1000.0, 1000.0], flux=[-2000.0, 2000.0]}"]);
    let expression = coarse(&["heat_exchange={law=\"expression\", flux=\"2*theta\"}"]);
    let linear = coarse(&[]);
    let (a, b, c) = (run(&table), run(&expression), run(&linear));
    let d = relative_difference(&a.theta, &b.theta);
    assert!(d < 1e-9, "table against expression: {d:e}");
    let d = relative_difference(&a.u, &b.u);
    assert!(d < 1e-9, "table against expression, u: {d:e}");
    let d = relative_difference(&a.theta, &c.theta);
    assert!(d < 1e-2, "nodal against consistent quadrature: {d:e}");
}
