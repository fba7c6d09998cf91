//! The iterative path (`solver.linear = "iterative"`: Newton–Krylov on all unknowns, nothing
//! condensed) reaches the direct path's solution: the same fields to a small multiple of the
//! solvers' tolerance ε_conv = 1e-6 and the same stick/slip state at every node, in 2D and 3D,
//! with the velocity-weakening law (non-unique regime: both follow the convexification loop from the
//! previous step) and with Tresca's law (unique solution).

use thermocontact::driver::Summary;
use thermocontact::model::norms;
use thermocontact::model::State;
use thermocontact::Scenario;

const PAPER3D: &str = include_str!("../scenarios/paper3d.toml");

fn load(file: Option<&str>, overrides: &[&str], linear: &str) -> Scenario {
    let mut all: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    all.push(format!("solver.linear={linear}"));
    Scenario::load(file, &all).unwrap()
}

/// Each contact node's stick/slip state in an output's rows.
fn status(rows: &[thermocontact::model::ContactRow]) -> Vec<bool> {
    rows.iter().map(|r| r.slip).collect()
}

fn run(file: Option<&str>, overrides: &[&str], linear: &str) -> (Summary, State) {
    load(file, overrides, linear).run_quiet().unwrap()
}

/// The error that validating the default scenario with `set` gives.
fn refused(set: &str) -> String {
    (Scenario::load(None, &[set.to_string()]).and_then(|s| s.validate()))
        .unwrap_err()
        .to_string()
}

/// Runs both paths and compares them; returns the iterative run's summary.
fn compare(file: Option<&str>, overrides: &[&str]) -> Summary {
    let (direct_summary, direct) = run(file, overrides, "direct");
    let (iterative_summary, iterative) = run(file, overrides, "iterative");
    assert_eq!(direct_summary.linear, "direct");
    assert_eq!(iterative_summary.linear, "iterative");
    assert!(iterative_summary.krylov_iterations > 0);
    let problem = load(file, overrides, "direct").build().unwrap();
    let m = &problem.mesh;
    let diff = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
    let du = norms::energy(m, &diff(&direct.u, &iterative.u)) / norms::energy(m, &direct.u);
    let dtheta = norms::gradient(m, &diff(&direct.theta, &iterative.theta)) / norms::gradient(m, &direct.theta);
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let dw = max_abs(&diff(&direct.w, &iterative.w)) / max_abs(&direct.w);
    let dxi = max_abs(&diff(&direct.xi, &iterative.xi)) / max_abs(&direct.xi);
    assert!(du < 1e-6, "displacements differ: {du:e}");
    assert!(dtheta < 1e-6, "temperatures differ: {dtheta:e}");
    assert!(dw < 1e-5, "velocities differ: {dw:e}");
    assert!(dxi < 1e-5, "friction stresses differ: {dxi:e}");
    assert!(
        iterative_summary.max_law_residual <= 1e-6,
        "law residual {:e}",
        iterative_summary.max_law_residual
    );
    for (d, i) in direct_summary.outputs.iter().zip(&iterative_summary.outputs) {
        assert_eq!(status(&d.contact), status(&i.contact), "node statuses at t = {}", d.t);
        assert!(d.slip_nodes > 0, "the comparison should see slip (t = {})", d.t);
    }
    iterative_summary
}

#[test]
fn iterative_path_matches_the_direct_path_in_2d() {
    compare(None, &["mesh.nx=32", "mesh.ny=8", "time.steps=16"]);
}

/// The 3D example, coarsened.
/// The paper's loop on the iterative path: one solve per iterate, no prediction.
const PAPERS_LOOP: &str = "solver.contact_sweeps=0";

/// The law's sweeps over Γ_C's own rows (`solver.prediction = "law"`, the body held), the
/// prediction before the loop on Γ_C's rows became the default; with `solver.contact_sweeps`.
const LAW_SWEEPS: [&str; 2] = ["solver.prediction=\"law\"", "solver.condensed_layers=0"];

const SLAB_3D: [&str; 4] = ["mesh.nx=12", "mesh.ny=3", "mesh.nz=3", "time.steps=16"];

/// Half of it with a symmetry plane: some contact nodes have a tangential coordinate held at
/// zero.
const SYMMETRIC_3D: [&str; 7] = [
    "mesh.nx=12",
    "mesh.ny=2",
    "mesh.nz=3",
    "time.steps=8",
    "geometry.lengths=[40.0, 5.0, 10.0]",
    "boundary.symmetry=[\"y-\"]",
    "boundary.neumann=[\"x+\", \"y+\", \"z+\"]",
];

#[test]
fn iterative_path_matches_the_direct_path_in_3d() {
    let summary = compare(Some(PAPER3D), &SLAB_3D);
    // `auto` (the default) stays with ILU(0) where it needs few iterations, in any build.
    assert_eq!(summary.preconditioner.as_deref(), Some("ilu"));
    assert!(summary.amg.is_none());
    compare(Some(PAPER3D), &SYMMETRIC_3D);
}

/// The coarse 3D example with Tresca's law (a unique solution).
const TRESCA_3D: [&str; 6] = [
    "mesh.nx=12",
    "mesh.ny=3",
    "mesh.nz=3",
    "time.steps=8",
    "friction.law=tresca",
    "friction.bound=60",
];

#[test]
fn iterative_path_matches_the_direct_path_with_tresca_friction() {
    compare(Some(PAPER3D), &TRESCA_3D);
}

/// With the AMG coarse correction (`solver.preconditioner = "amg"`, feature `petsc`) the
/// iterative path reaches the same solution, 3D with velocity weakening and with symmetry planes
/// (contact nodes with a held tangential coordinate: padded slots in the AMG's blocks), at
/// k = 1/16 and 1/8.
#[cfg(feature = "petsc")]
#[test]
fn amg_preconditioned_path_matches_the_direct_path() {
    for case in [&SLAB_3D[..], &SYMMETRIC_3D[..]] {
        let sets: Vec<&str> = case.iter().copied().chain(["solver.preconditioner=amg"]).collect();
        let summary = compare(Some(PAPER3D), &sets);
        assert_eq!(summary.preconditioner.as_deref(), Some("amg"));
        assert!(summary
            .amg
            .is_some_and(|amg| amg.levels >= 1 && amg.operator_complexity >= 1.0));
    }
}

/// The paper's solver on the iterative path runs the direct path's iterates, w(ξ, h) from a
/// Krylov solve instead of the condensed compliances: the same iteration counts and the same
/// fields to the Krylov tolerance, in 2D and 3D.
#[test]
fn the_papers_solver_on_the_iterative_path_runs_the_direct_paths_iterates() {
    let cases: [(Option<&str>, Vec<&str>); 2] = [
        (None, vec!["mesh.nx=16", "mesh.ny=4", "time.steps=16"]),
        (
            Some(PAPER3D),
            vec!["mesh.nx=8", "mesh.ny=2", "mesh.nz=2", "time.steps=4"],
        ),
    ];
    for (file, mut sets) in cases {
        sets.push("solver.kind=paper");
        let (direct_summary, direct) = run(file, &sets, "direct");
        let (iterative_summary, iterative) = run(file, &sets, "iterative");
        assert_eq!(iterative_summary.linear, "iterative");
        assert_eq!(iterative_summary.solver, "paper");
        assert!(iterative_summary.krylov_iterations > 0);
        assert_eq!(
            direct_summary.convexification_iterations,
            iterative_summary.convexification_iterations
        );
        assert_eq!(direct_summary.inner_iterations, iterative_summary.inner_iterations);
        assert_fields_agree(&direct, &iterative, 1e-7, "paper");
    }
}

/// An accelerated run reaches the plain loop's solution: the fields within 10 ε_conv (both stop
/// where the loop's increments fall below ε_conv), the same stick/slip state at every node and
/// output, and the nonmonotone law at every step it returns.
fn assert_same_solution(case: &str, (plain_summary, plain): (&Summary, &State), (summary, fast): (&Summary, &State)) {
    assert_fields_agree(plain, fast, 1e-5, case);
    for (a, b) in plain_summary.outputs.iter().zip(&summary.outputs) {
        assert_eq!(
            status(&a.contact),
            status(&b.contact),
            "{case}: node statuses at t = {}",
            a.t
        );
    }
    assert!(
        summary.max_law_residual <= 1e-6,
        "{case}: {:e}",
        summary.max_law_residual
    );
}

/// The run `summary` (with `what`) took fewer Newton iterations than the run `plain` (without).
fn assert_fewer_newton_iterations(case: &str, what: &str, plain: &Summary, summary: &Summary) {
    assert!(
        summary.newton_iterations < plain.newton_iterations,
        "{case}: {} Newton iterations with {what}, {} without",
        summary.newton_iterations,
        plain.newton_iterations
    );
}

/// u, w, θ and ξ of `b` within `tolerance` of `a`'s, relative to a's largest entry.
fn assert_fields_agree(a: &State, b: &State, tolerance: f64, case: &str) {
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let rel = |a: &[f64], b: &[f64]| {
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        max_abs(&d) / max_abs(a)
    };
    for (name, x, y) in [
        ("u", &a.u, &b.u),
        ("w", &a.w, &b.w),
        ("θ", &a.theta, &b.theta),
        ("ξ", &a.xi, &b.xi),
    ] {
        assert!(rel(x, y) < tolerance, "{case}: {name} differs by {:e}", rel(x, y));
    }
}

/// GMRES + ILU(0) at the paper's k = 1/64: the Krylov iterations per solve stay bounded when the
/// mesh is refined (docs/krylov-study.md measured 5 → 8–9 for h/2.15 at 10⁵–10⁶ unknowns; here
/// h/2 from 1.7k to 10.7k unknowns must stay within 2×).
#[test]
fn krylov_iterations_stay_bounded_under_refinement() {
    let per_solve = |cells: [usize; 3]| {
        let sets = [
            format!("mesh.nx={}", cells[0]),
            format!("mesh.ny={}", cells[1]),
            format!("mesh.nz={}", cells[2]),
            "time.steps=4".into(),
            "time.final_time=0.0625".into(),
            "output.times=[0.0625]".into(),
        ];
        let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
        let (summary, _) = run(Some(PAPER3D), &sets, "iterative");
        summary.krylov_iterations as f64 / summary.linear_solves as f64
    };
    let coarse = per_solve([16, 4, 4]);
    let fine = per_solve([32, 8, 8]);
    assert!(coarse >= 1.0 && fine >= 1.0, "{coarse} {fine}");
    assert!(
        fine <= 2.0 * coarse,
        "iterations per solve grew from {coarse:.1} to {fine:.1}"
    );
}

/// `auto` takes the path whose estimated run is cheaper: direct on compact bodies (the 2D and 3D
/// examples, the brake pads), iterative on thin pads and strips whose contact nodes make the
/// direct path's dense condensation on Γ_C the larger cost; in 3D never direct beyond 70 000
/// unknowns nor where the direct factor does not fit in half the machine's memory; the paper's
/// solver takes the direct path wherever its factor fits.
#[test]
fn auto_picks_the_path_by_its_estimated_cost() {
    use thermocontact::step::{LinearKind, ProblemSize, SolverKind};
    use LinearKind::{Auto, Direct, Iterative};
    use SolverKind::{Fast, Paper};
    let gib = (1u64 << 30) as f64;
    let size = |dim, unknowns, contact_nodes, steps| ProblemSize {
        dim,
        unknowns,
        contact_nodes,
        steps,
    };
    // (requested, size, solver, machine memory in GiB) → path. The sizes are those of the
    // measurements in `LinearKind::choose`.
    let cases = [
        // Compact bodies: the 2D reference run, the 3D example at two sizes, the brake pad.
        (Auto, size(2, 12_384, 128, 64), Fast, 24.0, Direct),
        (Auto, size(2, 12_384, 128, 16), Fast, 24.0, Direct),
        (Auto, size(2, 7_611, 316, 60), Fast, 24.0, Direct),
        (Auto, size(2, 49_344, 256, 64), Fast, 24.0, Direct),
        (Auto, size(3, 17_590, 440, 64), Fast, 24.0, Direct),
        (Auto, size(3, 6_978, 384, 60), Fast, 24.0, Direct),
        (Auto, size(3, 6_978, 384, 3), Fast, 24.0, Direct),
        // The 3D example at 47k unknowns over 64 steps: 7.9 s direct, about 2.5 s iterative.
        (Auto, size(3, 46_970, 840, 64), Fast, 24.0, Iterative),
        // Thin pads and strips: 15–17 % of the nodes on Γ_C in 3D (the report of issue 28: 31k
        // unknowns, 30 steps), a strip of 4 cells in 2D.
        (Auto, size(3, 27_025, 1_260, 64), Fast, 24.0, Iterative),
        (Auto, size(3, 31_000, 1_160, 30), Fast, 24.0, Iterative),
        (Auto, size(2, 26_620, 2_048, 16), Fast, 24.0, Iterative),
        // Size and memory, as before the cost model.
        (Auto, size(2, 10_000_000, 0, 64), Fast, 24.0, Direct),
        (Auto, size(3, 46_970, 840, 64), Fast, 0.5, Iterative),
        (Auto, size(3, 98_334, 1_387, 64), Fast, 24.0, Iterative),
        (Auto, size(3, 972_270, 0, 64), Fast, 24.0, Iterative),
        (Auto, size(3, 98_334, 1_387, 64), Paper, 24.0, Direct),
        (Auto, size(3, 27_025, 1_260, 64), Paper, 24.0, Direct),
        (Auto, size(3, 972_270, 0, 64), Paper, 24.0, Iterative),
        (Direct, size(3, 972_270, 0, 64), Fast, 24.0, Direct),
        (Iterative, size(2, 12_384, 128, 64), Fast, 24.0, Iterative),
    ];
    for (requested, size, kind, memory, expected) in cases {
        assert_eq!(
            requested.resolve(&size, kind, memory * gib),
            expected,
            "{requested:?}, {size:?}, {kind:?}, {memory} GiB: {:?}",
            LinearKind::costs(&size)
        );
    }
    let error = Scenario::load(None, &["solver.linear=cg".into()])
        .unwrap_err()
        .to_string();
    assert!(error.contains("solver.linear"), "{error}");
}

/// On whole scenarios `auto` resolves by the cost model from the built problem's sizes: the 3D
/// example as it ships (17.6k unknowns, 440 contact nodes, 64 steps) takes the direct path; a
/// pad one cell thick with half its nodes on Γ_C (13k unknowns, 1 701 contact nodes) the
/// iterative one, and a run of it (32 steps of k = 1/64) takes that path; one step of it, whose
/// estimated direct run is short, the direct one.
#[test]
fn auto_takes_the_direct_path_on_a_compact_block_and_the_iterative_one_on_a_thin_pad() {
    use thermocontact::step::{LinearKind, ProblemSize};
    let chosen = |sets: &[&str]| {
        let scenario = load(Some(PAPER3D), sets, "\"auto\"");
        let (problem, params) = (scenario.build().unwrap(), scenario.solver_params());
        params
            .linear
            .resolve(&ProblemSize::of(&problem), params.kind, f64::INFINITY)
    };
    assert_eq!(chosen(&[]), LinearKind::Direct);
    let thin = [
        "geometry.lengths=[40.0, 10.0, 1.0]",
        "mesh.nx=80",
        "mesh.ny=20",
        "mesh.nz=1",
    ];
    assert_eq!(chosen(&thin), LinearKind::Iterative);
    // A run of it takes that path (32 steps: one step's estimated direct run is short enough
    // to take the reference path anyway, `LinearKind::AUTO_DIRECT_ANYWAY_SECONDS`).
    let mut short = thin.to_vec();
    short.extend(["time.final_time=0.5", "time.steps=32", "output.times=[]"]);
    assert_eq!(run(Some(PAPER3D), &short, "\"auto\"").0.linear, "iterative");
    short.extend(["time.final_time=0.015625", "time.steps=1"]);
    assert_eq!(run(Some(PAPER3D), &short, "\"auto\"").0.linear, "direct");
}

/// A Krylov solve at its cap fails the step by the linear residual, named as such; without
/// cutback the run stops there.
#[test]
fn a_krylov_solve_at_its_cap_fails_the_step_naming_the_linear_residual() {
    let scenario = load(
        Some(PAPER3D),
        &[
            "mesh.nx=8",
            "mesh.ny=2",
            "mesh.nz=2",
            "time.steps=4",
            "solver.max_krylov=1",
            "solver.krylov_tolerance=1e-14",
            "solver.cutback=false",
        ],
        "iterative",
    );
    let error = scenario.run_quiet().unwrap_err().to_string();
    assert!(
        error.contains("GMRES") && error.contains("relative residual of the linear solve"),
        "{error}"
    );
}

/// Where the convexification loop fails (here: capped at a few iterates, too few for its first
/// way out, the loop with predicted bounds, as well), the iterative path finishes the step by
/// Newton on the nonmonotone law from the step's start instead of cutting it back, and reaches the loop's solution where the step has one solution: the paper's 2D
/// example (velocity weakening, 32 × 8 cells) and the 3D example with Tresca's law, against the
/// same runs with the loop uncapped, fields to 10⁻⁷ and the same stick/slip state.
#[test]
fn newton_on_the_law_finishes_the_steps_the_loop_cannot() {
    let cases: [(Option<&str>, Vec<&str>, &str); 2] = [
        (
            None,
            vec!["mesh.nx=32", "mesh.ny=8", "time.steps=16"],
            "solver.max_convexification=3",
        ),
        (Some(PAPER3D), TRESCA_3D.to_vec(), "solver.max_convexification=1"),
    ];
    for (file, sets, cap) in cases {
        let (loop_summary, by_loop) = run(file, &sets, "iterative");
        let capped: Vec<&str> = sets.iter().copied().chain([cap]).collect();
        let (summary, by_newton) = run(file, &capped, "iterative");
        assert_eq!(loop_summary.nonmonotone_newton_steps, 0);
        assert!(
            summary.nonmonotone_newton_steps >= 4,
            "{cap}: {} steps by Newton on the law",
            summary.nonmonotone_newton_steps
        );
        assert!(summary.cutbacks.is_empty() && loop_summary.cutbacks.is_empty());
        assert!(
            summary.max_law_residual <= 1e-6,
            "law residual {:e}",
            summary.max_law_residual
        );
        assert_fields_agree(&by_loop, &by_newton, 1e-7, cap);
        for (a, b) in loop_summary.outputs.iter().zip(&summary.outputs) {
            assert_eq!(status(&a.contact), status(&b.contact), "node statuses at t = {}", a.t);
        }
    }
}

/// The 3D example with the friction bound S = 8: a slip zone that grows inward from the long
/// edges and the free end over about 40 % of the face, the same on every fine enough mesh
/// (docs/performance.md, "The slip zone under refinement"), unlike the example's own boundary
/// ring. 4 steps of `inverse_k`.
/// The 3D example on nx × ny × ny cells, on the iterative path, with the keys `sets`.
fn example_3d(nx: usize, ny: usize, sets: &[&str]) -> (Summary, State) {
    let mesh = [
        format!("mesh.nx={nx}"),
        format!("mesh.ny={ny}"),
        format!("mesh.nz={ny}"),
    ];
    let all: Vec<&str> = mesh.iter().map(String::as_str).chain(sets.iter().copied()).collect();
    run(Some(PAPER3D), &all, "iterative")
}

fn resolved_zone(nx: usize, inverse_k: usize, anderson_depth: usize) -> (Summary, State) {
    resolved_zone_with(nx, inverse_k, anderson_depth, 0)
}

/// [`resolved_zone`] with `contact_sweeps` Gauss–Seidel sweeps of the law over Γ_C's rows
/// predicting the bounds ([`LAW_SWEEPS`]; 0: the paper's loop).
fn resolved_zone_with(nx: usize, inverse_k: usize, anderson_depth: usize, contact_sweeps: usize) -> (Summary, State) {
    let k = 1.0 / inverse_k as f64;
    let times: Vec<String> = (1..=4).map(|n| format!("{}", n as f64 * k)).collect();
    let sets = [
        "friction.bound=8".into(),
        "time.steps=4".into(),
        format!("time.final_time={}", 4.0 * k),
        format!("output.times=[{}]", times.join(", ")),
        format!("solver.anderson_depth={anderson_depth}"),
        format!("solver.contact_sweeps={contact_sweeps}"),
        LAW_SWEEPS[0].into(),
        LAW_SWEEPS[1].into(),
    ];
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    example_3d(nx, nx / 4, &sets)
}

/// Where the slip zone converges, the convexification loop's iterations per step stay bounded
/// under refinement and at a coarse k (≤ 10, and at most 1.3× from the coarse mesh to the fine
/// one); the Anderson acceleration of its tail (`solver.anderson_depth`) takes fewer iterations
/// to the same solution: the same stick/slip state at every node and step, the fields within
/// 10 ε_conv (both stop where the loop's increments fall below ε_conv).
#[test]
fn outer_iterations_stay_bounded_where_the_slip_zone_converges() {
    let outer_per_step = |s: &Summary| s.convexification_iterations as f64 / 4.0;
    let mut per_mesh = Vec::new();
    for (nx, inverse_k) in [(32, 64), (48, 64), (32, 8)] {
        let (plain_summary, plain) = resolved_zone(nx, inverse_k, 0);
        let (summary, accelerated) = resolved_zone(nx, inverse_k, 2);
        let case = format!("nx = {nx}, k = 1/{inverse_k}");
        assert_eq!(plain_summary.anderson_combinations, 0, "{case}");
        assert!(summary.anderson_combinations > 0, "{case}");
        assert_fewer_newton_iterations(&case, "Anderson", &plain_summary, &summary);
        assert_same_solution(&case, (&plain_summary, &plain), (&summary, &accelerated));
        for a in &plain_summary.outputs {
            assert!(a.slip_nodes > 0, "{case}: the zone should slip at t = {}", a.t);
        }
        let outer = outer_per_step(&summary);
        assert!(outer <= 10.0, "{case}: {outer} convexification iterations per step");
        if inverse_k == 64 {
            per_mesh.push(outer);
        }
    }
    assert!(
        per_mesh[1] <= 1.3 * per_mesh[0],
        "outer iterations per step grew from {} to {} (h/1.5)",
        per_mesh[0],
        per_mesh[1]
    );
}

#[test]
fn the_anderson_depth_is_bounded_with_a_clear_error() {
    let error = refused("solver.anderson_depth=40");
    assert!(
        error.contains("solver.anderson_depth") && error.contains("40") && error.contains("at most 8"),
        "{error}"
    );
    let negative = Scenario::load(None, &["solver.anderson_depth=-1".into()])
        .unwrap_err()
        .to_string();
    assert!(negative.contains("anderson_depth"), "{negative}");
}

/// `solver.contact_sweeps = 1` with the law's sweeps ([`LAW_SWEEPS`]): from the loop's second
/// iterate on, the bounds are frozen at the slip that one nonlinear Gauss–Seidel sweep over
/// Γ_C's rows predicts. Where the step has one
/// solution it is the paper's loop's, reached in fewer outer iterations: the paper's 2D example
/// (32 × 8), the 3D example with Tresca's law, and the 3D example's resolved slip zone (S = 8)
/// on two meshes and at a coarse k, against the same runs with the plain loop: fields within
/// 10 ε_conv, the same stick/slip state at every node and output, the law at every returned
/// step; and the outer iterations per step stay bounded under refinement.
#[test]
fn predicted_bounds_reach_the_loops_solution_in_fewer_iterations() {
    let mut cases: Vec<(String, Summary, State, Summary, State)> = Vec::new();
    for (file, sets) in [
        (None, vec!["mesh.nx=32", "mesh.ny=8", "time.steps=16"]),
        (Some(PAPER3D), TRESCA_3D.to_vec()),
    ] {
        let loop_sets: Vec<&str> = sets.iter().copied().chain([PAPERS_LOOP]).collect();
        let (plain_summary, plain) = run(file, &loop_sets, "iterative");
        let with: Vec<&str> = (sets.iter().copied())
            .chain(LAW_SWEEPS)
            .chain(["solver.contact_sweeps=1"])
            .collect();
        let (summary, predicted) = run(file, &with, "iterative");
        cases.push((sets.join(" "), plain_summary, plain, summary, predicted));
    }
    let mut per_mesh = Vec::new();
    for (nx, inverse_k) in [(32, 64), (48, 64), (32, 8)] {
        let (plain_summary, plain) = resolved_zone_with(nx, inverse_k, 2, 0);
        let (summary, predicted) = resolved_zone_with(nx, inverse_k, 2, 1);
        if inverse_k == 64 {
            per_mesh.push(summary.newton_iterations as f64 / 4.0);
        }
        cases.push((
            format!("S = 8, nx = {nx}, k = 1/{inverse_k}"),
            plain_summary,
            plain,
            summary,
            predicted,
        ));
    }
    for (case, plain_summary, plain, summary, predicted) in &cases {
        assert_eq!(plain_summary.predicted_iterates, 0, "{case}");
        assert!(summary.predicted_iterates > 0, "{case}");
        // Tresca's bounds do not depend on the slip: the same iterates.
        let fewer = if case.contains("tresca") {
            summary.newton_iterations == plain_summary.newton_iterations
        } else {
            summary.newton_iterations < plain_summary.newton_iterations
        };
        assert!(
            fewer,
            "{case}: {} Newton iterations with predicted bounds, {} without",
            summary.newton_iterations, plain_summary.newton_iterations
        );
        assert_same_solution(case, (plain_summary, plain), (summary, predicted));
        assert!(summary.cutbacks.is_empty(), "{case}");
        eprintln!(
            "{case}: Newton iterations {} → {}",
            plain_summary.newton_iterations, summary.newton_iterations
        );
    }
    assert!(
        per_mesh[1] <= 1.3 * per_mesh[0],
        "Newton iterations per step grew from {} to {} (h/1.5)",
        per_mesh[0],
        per_mesh[1]
    );
}

/// Where a step has several solutions the predicted bounds may settle on another than the
/// paper's loop (on the coarse 3D example, one step of 16 where the loop passes near one
/// solution and leaves it for another: docs/solvers.md); every step they return still
/// satisfies the nonmonotone law, with no cutback.
#[test]
fn predicted_bounds_return_solutions_of_the_law_where_a_step_has_several() {
    let sets: Vec<&str> = (SLAB_3D.iter().copied())
        .chain(LAW_SWEEPS)
        .chain(["solver.contact_sweeps=1"])
        .collect();
    let (summary, _) = run(Some(PAPER3D), &sets, "iterative");
    assert_eq!(summary.status, thermocontact::driver::RunStatus::Completed);
    assert!(summary.cutbacks.is_empty());
    assert!(summary.predicted_iterates > 0);
    assert!(summary.max_law_residual <= 1e-6, "{:e}", summary.max_law_residual);
}

/// The loop on Γ_C's rows (`solver.prediction = "loop"`, the default: one sweep per bound
/// update, through two layers of the body) runs the convexification loop itself on Γ_C's
/// condensed rows between two solves, so the global iterates follow the paper's loop's path in
/// fewer solves. Where a step has one solution it is the paper's loop's: the coarse 3D example
/// (12 × 3 × 3 cells, 16 steps), where the law's sweeps part from it at one step, and 40 × 10 ×
/// 10 cells over 16 steps, where they part at step 12: fields within 10 ε_conv, the same
/// stick/slip state at every node and output, the law at every step, in fewer Newton
/// iterations, at most 10 iterates in every step and Newton iterations per step growing by at
/// most 1.3× from the coarse mesh to the fine one (measured: 7 iterates; 5.25 and 5.5 Newton
/// iterations per step). At k = 1/8 (8 steps on 24 × 6 × 6 and 40 × 10 × 10 cells) the iterates per step
/// stay bounded under refinement (at most 12 in every step: measured 7 and 9, where the paper's
/// loop takes 21 and 76), no step is cut back, and where a step has several solutions its slip
/// count stays within one node of the paper's loop's at every step (measured: one node apart at
/// three and two steps of 8; the law's sweeps: up to two and three nodes, at five steps each).
#[test]
fn the_loop_on_the_contact_rows_reaches_the_papers_loops_solution_in_fewer_iterations() {
    let mesh_40 = ["mesh.nx=40", "mesh.ny=10", "mesh.nz=10"];
    let sixteen = [
        "time.steps=16",
        "time.final_time=0.25",
        "output.times=[0.0625, 0.125, 0.1875, 0.25]",
    ];
    let mut newton_per_step = Vec::new();
    for (case, sets) in [
        ("12 × 3 × 3", SLAB_3D.to_vec()),
        ("40 × 10 × 10", [&mesh_40[..], &sixteen[..]].concat()),
    ] {
        let (plain_summary, plain) = run(Some(PAPER3D), &[&sets[..], &[PAPERS_LOOP]].concat(), "iterative");
        let (summary, rows) = run(Some(PAPER3D), &sets, "iterative");
        assert_eq!(plain_summary.predicted_iterates, 0, "{case}");
        assert!(summary.predicted_iterates > 0, "{case}");
        // Each predicted iterate's sweeps over the rows count as inner iterations.
        assert_eq!(plain_summary.inner_iterations, 0, "{case}");
        assert!(summary.inner_iterations >= summary.predicted_iterates, "{case}");
        assert_fewer_newton_iterations(case, "the loop on the rows", &plain_summary, &summary);
        assert!(
            plain_summary.cutbacks.is_empty() && summary.cutbacks.is_empty(),
            "{case}"
        );
        assert!(
            summary.max_convexification_per_step <= 10,
            "{case}: {} iterates in a step",
            summary.max_convexification_per_step
        );
        newton_per_step.push(summary.newton_iterations as f64 / 16.0);
        assert_same_solution(case, (&plain_summary, &plain), (&summary, &rows));
    }
    assert!(
        newton_per_step[1] <= 1.3 * newton_per_step[0],
        "Newton iterations per step {newton_per_step:?} under refinement"
    );
    let times: Vec<String> = (1..=8).map(|n| format!("{}", n as f64 / 8.0)).collect();
    let times = format!("output.times=[{}]", times.join(", "));
    let coarse_k = ["time.steps=8", "time.final_time=1", &times, "output.vtk=false"];
    for nx in [24, 40] {
        let (plain, _) = example_3d(nx, nx / 4, &[&coarse_k[..], &[PAPERS_LOOP]].concat());
        let (summary, _) = example_3d(nx, nx / 4, &coarse_k);
        assert!(
            summary.max_convexification_per_step <= 12,
            "nx = {nx}: {} iterates in a step (the paper's loop: {})",
            summary.max_convexification_per_step,
            plain.max_convexification_per_step
        );
        assert!(plain.cutbacks.is_empty() && summary.cutbacks.is_empty(), "nx = {nx}");
        assert!(
            summary.max_law_residual <= 1e-6,
            "nx = {nx}: {:e}",
            summary.max_law_residual
        );
        assert_eq!(summary.outputs.len(), 8);
        for (a, b) in plain.outputs.iter().zip(&summary.outputs) {
            assert!(
                a.slip_nodes.abs_diff(b.slip_nodes) <= 1,
                "nx = {nx}, t = {}: {} slipping nodes, the paper's loop {}",
                a.t,
                b.slip_nodes,
                a.slip_nodes
            );
        }
    }
}

/// `solver.contact_sweeps` and `solver.condensed_layers` out of range are refused by key, value
/// and what is expected.
#[test]
fn the_sweep_settings_are_bounded_with_a_clear_error() {
    for key in ["solver.contact_sweeps", "solver.condensed_layers"] {
        let error = refused(&format!("{key}=9"));
        assert!(
            error.contains(key) && error.contains('9') && error.contains("at most 8"),
            "{error}"
        );
    }
}

/// The Newton iterations' solves stopped at the forcing term (`solver.krylov_forcing`, default
/// 0.01 of the residual each starts from) reach the solution of the solves to rtol: the same
/// stick/slip state at every node and output, the fields within 10 ε_conv, the law at every
/// step, and no cutback, in at most 3/4 of the Krylov iterations (measured: 161 → 111 on the 2D
/// example 32 × 8, whose solves take 3 iterations anyway, with 56 → 63 Newton iterations; 404 →
/// 189 on the 3D example 16 × 4 × 4; 634 → 237 on 24 × 6 × 6 at k = 1/8).
#[test]
fn inexact_newton_solves_reach_the_exact_solves_solution_in_fewer_krylov_iterations() {
    let two_d = ["mesh.nx=32", "mesh.ny=8"];
    let three_d = ["mesh.nx=16", "mesh.ny=4", "mesh.nz=4"];
    let sixteen = ["time.steps=16", "time.final_time=0.25", "output.times=[0.125, 0.25]"];
    let coarse_k = ["mesh.nx=24", "mesh.ny=6", "mesh.nz=6", "time.steps=8"];
    let cases: [(&str, Option<&str>, Vec<&str>); 3] = [
        (
            "2D example, 32 × 8",
            None,
            two_d.iter().chain(&sixteen).copied().collect(),
        ),
        (
            "3D example, 16 × 4 × 4",
            Some(PAPER3D),
            three_d.iter().chain(&sixteen).copied().collect(),
        ),
        ("3D example, 24 × 6 × 6, k = 1/8", Some(PAPER3D), coarse_k.to_vec()),
    ];
    for (case, file, sets) in cases {
        let exact_sets: Vec<&str> = sets.iter().copied().chain(["solver.krylov_forcing=0"]).collect();
        let (exact_summary, exact) = run(file, &exact_sets, "iterative");
        let (summary, state) = run(file, &sets, "iterative");
        assert_same_solution(case, (&exact_summary, &exact), (&summary, &state));
        assert!(
            summary.cutbacks.is_empty() && exact_summary.cutbacks.is_empty(),
            "{case}"
        );
        assert!(
            4 * summary.krylov_iterations <= 3 * exact_summary.krylov_iterations,
            "{case}: {} Krylov iterations against {} to rtol",
            summary.krylov_iterations,
            exact_summary.krylov_iterations
        );
    }
}

#[test]
fn the_krylov_forcing_is_a_fraction_with_a_clear_error() {
    for value in ["1.0", "-0.1", "nan"] {
        let error = refused(&format!("solver.krylov_forcing={value}"));
        assert!(
            error.contains("solver.krylov_forcing") && error.contains("[0, 1)"),
            "{value}: {error}"
        );
    }
}

/// The same step solved again (as the fixed points on the contact pressure and on a nonlinear
/// heat exchange do, each iterate a whole step) starts its Newton iterations from its last
/// solution: the same solution to the tolerance, in fewer Krylov iterations (here 41 → 35, every
/// solve to rtol: the loop's iterates are the same, its first solve starts nearer; on the brake
/// pad, whose pressure iterates each solve the step again in two iterates, 21 250 → 12 633),
/// and a step solved after another starts from the previous step's state as before (the same
/// iterations as the first time).
#[test]
fn a_step_solved_again_starts_from_its_last_solution() {
    use thermocontact::step::{LinearSystem, StepSolver};
    let scenario = load(
        Some(PAPER3D),
        &[
            "mesh.nx=16",
            "mesh.ny=4",
            "mesh.nz=4",
            "time.steps=16",
            "time.final_time=0.25",
            "output.times=[0.25]",
            "solver.krylov_forcing=0",
        ],
        "iterative",
    );
    let problem = scenario.build().unwrap();
    let params = scenario.solver_params();
    let linear = LinearSystem::new(&problem, problem.time_step(), &params).unwrap();
    let solver = StepSolver::new(&problem, linear, &params).unwrap();
    let k = problem.time_step();
    let mut state = State::initial(&problem);
    for _ in 0..4 {
        state = solver.step(&state, state.t + k).unwrap().0;
    }
    let (first, first_info) = solver.step(&state, state.t + k).unwrap();
    let (again, again_info) = solver.step(&state, state.t + k).unwrap();
    assert_fields_agree(&first, &again, 1e-5, "the step solved again");
    assert!(first_info.krylov_iterations > 0);
    assert!(
        again_info.krylov_iterations < first_info.krylov_iterations,
        "{} Krylov iterations solving the step again, {} the first time",
        again_info.krylov_iterations,
        first_info.krylov_iterations
    );
    // Another step in between: the next solve starts from the previous step's state again.
    let (next, _) = solver.step(&first, first.t + k).unwrap();
    let (_, cold) = solver.step(&state, state.t + k).unwrap();
    assert!(next.t > first.t && cold.krylov_iterations == first_info.krylov_iterations);
}

/// The 3D example on a slab long in x, `nx × ny × ny` cells, 16 steps of the paper's k = 1/64,
/// with an output every 4 steps; `sets` added.
fn long_slab(nx: usize, ny: usize, sets: &[&str]) -> (Summary, State) {
    let steps = [
        "time.steps=16",
        "time.final_time=0.25",
        "output.times=[0.0625, 0.125, 0.1875, 0.25]",
    ];
    example_3d(nx, ny, &[&steps[..], sets].concat())
}

/// On a slab long in x (80 × 8 × 8 cells) a slip front runs along a row of contact nodes in
/// some steps, and the paper's loop moves it about one node per iterate (154 iterates in its
/// longest step; one forward sweep, the predicted bounds before 2026-11-29, 76): a node that
/// starts slipping weakens only in the next iterate, and only then sheds load onto the next.
/// The symmetric sweep of `solver.contact_sweeps = 1` (Γ_C's order and back) weakens the nodes
/// along the front within one sweep whichever way it runs: at most 10 iterates in every step
/// (measured 7), to the paper's loop's solution (fields within 10 ε_conv, the same stick/slip
/// state at every output, the law at every step).
#[test]
fn a_symmetric_sweep_carries_a_slip_front_along_the_contact_nodes() {
    let (plain_summary, plain) = long_slab(80, 8, &[PAPERS_LOOP]);
    let (summary, predicted) = long_slab(80, 8, &[&LAW_SWEEPS[..], &["solver.contact_sweeps=1"]].concat());
    assert_front_carried(
        "80 × 8 × 8 slab",
        (&plain_summary, &plain),
        (&summary, &predicted),
        (50, 10),
    );
}

/// The front crawls in the run `slow` (its longest step more than `crawl` iterates) and the
/// run `fast` carries it (at most `carried` iterates in every step), neither cut back, to the
/// same solution ([`assert_same_solution`]).
fn assert_front_carried(
    case: &str,
    slow: (&Summary, &State),
    fast: (&Summary, &State),
    (crawl, carried): (usize, usize),
) {
    let (slowest, fastest) = (slow.0.max_convexification_per_step, fast.0.max_convexification_per_step);
    assert!(
        slowest > crawl,
        "{case}: the slower loop should crawl here: {slowest} iterates at most"
    );
    assert!(
        fastest <= carried,
        "{case}: {fastest} iterates in a step where the front is carried"
    );
    assert!(slow.0.cutbacks.is_empty() && fast.0.cutbacks.is_empty(), "{case}");
    assert_same_solution(case, slow, fast);
}

/// On a thinner slab (104 × 6 × 6 cells, the loop capped at 120 iterates) the paper's loop fails
/// in two steps, where fronts run along rows of 100 nodes; the loop with predicted bounds, run
/// again from each step's start, is its first way out and finishes both (36 and 98 iterates:
/// one of these fronts the sweep does not carry), with no Newton on the law and no cutback.
/// With `contact_sweeps = 1` from the start the predicted bounds stall in two steps (the
/// iterates stop moving with the law not yet holding at them: a node the sweep relaxes to
/// another local minimizer than the convex problem holds it at) and the paper's bounds at the
/// nodes where the law fails finish each from there (without that, one step ran to the cap and
/// was cut back). Both runs reach the same solution.
#[test]
fn predicted_bounds_finish_the_steps_the_papers_loop_cannot_and_their_stalls_end_in_it() {
    let cap = "solver.max_convexification=120";
    let (plain_summary, plain) = long_slab(104, 6, &[cap, PAPERS_LOOP]);
    let (summary, predicted) = long_slab(104, 6, &[&LAW_SWEEPS[..], &[cap, "solver.contact_sweeps=1"]].concat());
    for (case, s) in [("paper's loop", &plain_summary), ("predicted bounds", &summary)] {
        assert!(s.cutbacks.is_empty(), "{case}: {:?}", s.cutbacks);
        assert_eq!(s.nonmonotone_newton_steps, 0, "{case}");
        assert!(s.predicted_iterates > 0, "{case}");
    }
    assert_same_solution("104 × 6 × 6 slab", (&plain_summary, &plain), (&summary, &predicted));
}

/// On the 104 × 6 × 6 slab a front in step 14 crosses the slab through the body, not along
/// Γ_C's own rows: the sweeps over those rows, which hold the body, move it one node per
/// iterate however many there are (93 iterates with 8 sweeps). The same sweeps with the step
/// matrix condensed onto Γ_C through two layers of the body (`solver.condensed_layers = 2`: a
/// node that weakens sheds its load through the body within the sweep) carry it in a few (19),
/// to the same solution (fields within 10 ε_conv, the stick/slip state at every output, the law
/// at every step).
#[test]
fn sweeps_through_the_condensed_body_carry_a_front_the_contact_rows_alone_crawl_along() {
    let sweeps = ["solver.contact_sweeps=8", LAW_SWEEPS[0]];
    let (rows_summary, rows) = long_slab(104, 6, &[&sweeps[..], &["solver.condensed_layers=0"]].concat());
    let (summary, condensed) = long_slab(104, 6, &[&sweeps[..], &["solver.condensed_layers=2"]].concat());
    let case = "104 × 6 × 6 slab, through the body";
    assert_front_carried(case, (&rows_summary, &rows), (&summary, &condensed), (60, 30));
}

/// At a coarse k (1/8: the body's stiffness weighs more than its mass, and fronts cross it) the
/// sweeps through two layers of the body keep the loop's iterates per step bounded under
/// refinement: at most 8 in every step on 24 × 6 × 6 and on 40 × 10 × 10 cells (measured 5 and
/// 6, 8 steps), where one sweep over Γ_C's own rows takes a step of 31 iterates on the finer
/// mesh (8 sweeps over them: 19); no cutback, and the law at every step.
#[test]
fn sweeps_through_the_body_bound_the_iterates_per_step_at_a_coarse_k_under_refinement() {
    let coarse_k = |nx: usize, sets: &[&str]| {
        let steps = ["time.steps=8", "time.final_time=1", "output.times=[1]"];
        example_3d(nx, nx / 4, &[&steps[..], sets].concat()).0
    };
    let through = ["solver.contact_sweeps=8", LAW_SWEEPS[0], "solver.condensed_layers=2"];
    for nx in [24, 40] {
        let summary = coarse_k(nx, &through);
        assert!(
            summary.max_convexification_per_step <= 8,
            "nx = {nx}: {} iterates in a step",
            summary.max_convexification_per_step
        );
        assert!(summary.cutbacks.is_empty(), "nx = {nx}: {:?}", summary.cutbacks);
        assert!(
            summary.max_law_residual <= 1e-6,
            "nx = {nx}: law {}",
            summary.max_law_residual
        );
    }
    let rows = coarse_k(40, &[&LAW_SWEEPS[..], &["solver.contact_sweeps=1"]].concat());
    assert!(
        rows.max_convexification_per_step > 20,
        "one sweep over Γ_C's rows: {} iterates at most",
        rows.max_convexification_per_step
    );
}

/// At k = 1/8 on thin slabs some convex problems' semismooth Newton iterations flip a few
/// contact nodes' slip direction at every iteration (w_τ +0.08, −0.17, +0.10, … m/s, ξ along w:
/// the law's residual twice the bound), and the problem runs through its 20 iterations
/// unsolved. Cutting such a step back along itself where it raises the law's residual
/// (`solver.backtracking`, the default) solves them: on 52 × 3 × 3 cells (16 steps, 8 sweeps
/// through two layers) no step is cut back, where without it two are (measured: to k/2), and
/// every step satisfies the law. Where the loop converges either way it is the same solution:
/// on 80 × 4 × 4 cells with the paper's loop (1 343 → 1 326 Newton iterations) the fields agree
/// to 10 ε_conv and the stick/slip state at every output.
#[test]
fn backtracking_solves_the_convex_problems_whose_newton_steps_flip_their_nodes() {
    let coarse_k = |nx: usize, ny: usize, sets: &[&str]| {
        let steps = ["time.steps=16", "time.final_time=2", "output.times=[0.5, 1, 1.5, 2]"];
        example_3d(nx, ny, &[&steps[..], sets].concat())
    };
    let through = ["solver.contact_sweeps=8", LAW_SWEEPS[0], "solver.condensed_layers=2"];
    let (full, _) = coarse_k(52, 3, &[&through[..], &["solver.backtracking=false"]].concat());
    let (backtracked, _) = coarse_k(52, 3, &through);
    assert!(!full.cutbacks.is_empty(), "full steps: no cutback");
    assert_eq!(full.backtracked_newton_iterations, 0);
    assert!(backtracked.cutbacks.is_empty(), "{:?}", backtracked.cutbacks);
    assert!(backtracked.backtracked_newton_iterations > 0);
    assert!(
        backtracked.max_law_residual <= 1e-6,
        "{:e}",
        backtracked.max_law_residual
    );

    let plain = coarse_k(80, 4, &[PAPERS_LOOP, "solver.backtracking=false"]);
    let with = coarse_k(80, 4, &[PAPERS_LOOP]);
    assert!(
        with.0.backtracked_newton_iterations > 0,
        "the comparison should backtrack"
    );
    assert!(plain.0.cutbacks.is_empty() && with.0.cutbacks.is_empty());
    assert_same_solution("80 × 4 × 4 slab, k = 1/8", (&plain.0, &plain.1), (&with.0, &with.1));
}
