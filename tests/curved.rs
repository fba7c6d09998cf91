//! Geometry beyond the flat contact face: the paper's example rotated (2D and 3D), and a ring
//! on a shaft, a curved contact boundary with a known answer.

mod common;

use thermocontact::contact::{LinearHeating, QuadraticExchange, VelocityWeakening};
use thermocontact::loads::Datum;
use thermocontact::mesh::{self, Mesh};
use thermocontact::model::contact_rows;
use thermocontact::model::State;
use thermocontact::model::{LoadTarget, Problem, ProblemBuilder, TimeGrid};
use thermocontact::step::{SolverKind, SolverParams};

type Rotation = [[f64; 3]; 3];

fn rotate(r: &Rotation, v: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for i in 0..3 {
        out[i] = (0..v.len()).map(|j| r[i][j] * v[j]).sum();
    }
    out
}

/// The rotation by `angle` about the unit `axis` (Rodrigues).
fn rotation(axis: [f64; 3], angle: f64) -> Rotation {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|a| a / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [c + x * x * t, x * y * t - z * s, x * z * t + y * s],
        [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
        [z * x * t - y * s, z * y * t + x * s, c + z * z * t],
    ]
}

/// The paper's example (Section 6) on `mesh` with its loads turned by `r`: clamped on
/// `parts[0]`, loaded on `parts[1]` (the top: (0, −800 t) turned), free on `parts[2..]`, in
/// contact on `contact`.
fn paper_problem(mesh: Mesh, r: &Rotation, parts: &[&str], contact: &str, steps: usize) -> Problem {
    let d = mesh.dim;
    let down = |size: f64| {
        let mut v = vec![0.0; d];
        v[d - 1] = size;
        rotate(r, &v)[..d].to_vec()
    };
    ProblemBuilder::new(mesh, common::paper_material(), TimeGrid::new(1.0, steps))
        .dirichlet(&parts[..1])
        .neumann(&parts[1..])
        .contact(&[contact])
        .boundary_temperature(25.0)
        .initial_temperature(Datum::scalar(25.0), "θ₀")
        .friction(
            150.0,
            VelocityWeakening {
                a: 1.0,
                b: 0.2,
                alpha: 100.0,
            },
        )
        .heat_exchange(QuadraticExchange {
            coefficient: 2.0,
            foundation_temperature: 0.0,
        })
        .frictional_heating(LinearHeating::affine(0.0, 10.0))
        .load(LoadTarget::BodyForce, Datum::constant(down(-10.0)))
        .load(
            LoadTarget::Traction(parts[1].into()),
            Datum::affine(vec![0.0; d], down(-800.0)),
        )
        .build()
        .unwrap()
}

/// Runs every step and returns the states, with the slip count of each.
fn run(problem: &Problem, kind: SolverKind) -> Vec<(State, usize)> {
    let params = SolverParams {
        kind,
        ..SolverParams::default()
    };
    let mut states = Vec::new();
    thermocontact::time::run::<thermocontact::time::TimeError>(problem, &params, |state, _| {
        let slip = contact_rows(problem, state, 1e-6).iter().filter(|r| r.slip).count();
        states.push((state.clone(), slip));
        Ok(())
    })
    .unwrap();
    states
}

/// The same body, loads and laws turned by `r` give the same slip and stick counts at every
/// step, the turned displacement field to 1e-8 relative, and the same temperatures.
fn assert_rotation_invariant(mesh: Mesh, r: Rotation, parts: &[&str], contact: &str, steps: usize, kind: SolverKind) {
    let d = mesh.dim;
    let mut turned = mesh.clone();
    turned.coords.iter_mut().for_each(|x| *x = rotate(&r, x));
    let identity = rotation([0.0, 0.0, 1.0], 0.0);
    let plain = run(&paper_problem(mesh, &identity, parts, contact, steps), kind);
    let rotated = run(&paper_problem(turned, &r, parts, contact, steps), kind);
    assert!(plain.iter().any(|(_, slip)| *slip > 0), "the example slips");
    for ((a, slip_a), (_, slip_b)) in plain.iter().zip(&rotated) {
        assert_eq!(slip_a, slip_b, "slip counts differ at step {}", a.n);
    }
    let (a, b) = (&plain.last().unwrap().0, &rotated.last().unwrap().0);
    let scale = a.u.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let mut err: f64 = 0.0;
    for (ua, ub) in a.u.chunks_exact(d).zip(b.u.chunks_exact(d)) {
        let turned = rotate(&r, ua);
        err = err.max((0..d).map(|c| (turned[c] - ub[c]).abs()).fold(0.0, f64::max));
    }
    eprintln!("turned displacements differ by {err:e} (scale {scale:e})");
    assert!(
        err <= 1e-8 * scale,
        "turned displacements differ by {err:e} (scale {scale:e})"
    );
    let theta_err = a
        .theta
        .iter()
        .zip(&b.theta)
        .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()));
    assert!(theta_err <= 1e-8 * 25.0, "temperatures differ by {theta_err:e}");
}

/// Source: the paper's Section 6 example, turned by 30° in its plane (mesh 32 × 8, k = 1/16).
#[test]
fn rotated_paper_example_2d_gives_the_rotated_solution() {
    let mesh = mesh::rectangle(40.0, 10.0, 32, 8);
    let r = rotation([0.0, 0.0, 1.0], 30f64.to_radians());
    assert_rotation_invariant(mesh, r, &["left", "top", "right"], "bottom", 16, SolverKind::Fast);
}

/// The 3D example (a 40 × 10 × 10 m box, 8 × 2 × 2 cells, k = 1/8) turned about a general
/// axis: the contact face is then oblique to every coordinate axis.
#[test]
fn rotated_paper_example_3d_gives_the_rotated_solution() {
    let mesh = mesh::cuboid([40.0, 10.0, 10.0], [8, 2, 2]);
    let r = rotation([1.0, 2.0, 3.0], 40f64.to_radians());
    let parts = ["x-", "z+", "x+", "y-", "y+"];
    assert_rotation_invariant(mesh, r, &parts, "z-", 8, SolverKind::Fast);
}

/// What one ring-on-shaft run shows.
struct RingRun {
    /// |ξ|/τ(t) on the inner circle while all of it sticks (at t = 0.5).
    stress_ratio: f64,
    /// Spread of |ξ| over the contact nodes at t = 0.5, relative to its mean.
    spread: f64,
    /// The first step at which the inner circle slips.
    onset_step: usize,
}

/// A ring a ≤ r ≤ b on a rigid shaft, with no clamped part (Γ_D = ∅: friction alone holds
/// it), loaded on its outer circle by the shear traction τ(t) e_θ, τ = τ̇ t.
///
/// Source: the equilibrium of a ring in antiplane-free plane shear: with no body force and
/// inertia negligible, d/dr (r² σ_rθ) = 0, so the inner circle carries σ_rθ(a) = τ b²/a²,
/// whatever the material. The bound there is μ(0) S = g, so the ring slips when
/// τ b²/a² = g: at t* = g a²/(τ̇ b²). Conditions: a = 1, b = 2 m, the paper's material without
/// thermal expansion and with ρ = 1 (quasi-static), velocity weakening μ(0) S = 106 N/m,
/// τ̇ = 40 N/(m s), so t* = 0.6625 s
/// (k = 1/40: the first step past t* is n = 27).
fn ring_on_shaft(n_radial: usize, n_around: usize) -> RingRun {
    let (a, b, rate, bound) = (1.0, 2.0, 40.0, 106.0);
    let mesh = mesh::annulus(a, b, n_radial, n_around);
    // The paper's material without thermal expansion, and light (ρ = 1 kg/m²), so that the
    // ring's shear waves (period ≈ 0.03 s) are fast against the load ramp: quasi-static.
    let mut material = common::paper_material();
    material.expansion = 0.0;
    material.density = 1.0;
    let shear = format!("{rate}*t/sqrt(x^2+y^2)");
    let traction = Datum::expressions(&[format!("-y*{shear}"), format!("x*{shear}")]).unwrap();
    let problem = ProblemBuilder::new(mesh, material, TimeGrid::new(0.75, 30))
        .neumann(&["outer"])
        .contact(&["inner"])
        .friction(
            bound,
            VelocityWeakening {
                a: 1.0,
                b: 0.5,
                alpha: 10.0,
            },
        )
        .load(LoadTarget::Traction("outer".into()), traction)
        .build()
        .unwrap();
    assert!(problem.parts.dirichlet.is_empty());
    assert_eq!(problem.contact.len(), n_around, "every inner node carries friction");
    let states = run(&problem, SolverKind::Fast);
    let k = problem.time_step();
    let mut onset_step = usize::MAX;
    let (mut stress_ratio, mut spread) = (0.0, f64::INFINITY);
    for (state, slip) in &states {
        // By symmetry all inner nodes share one state.
        assert!(
            *slip == 0 || *slip == n_around,
            "step {}: {slip} of {n_around} slip",
            state.n
        );
        if *slip > 0 && onset_step == usize::MAX {
            onset_step = state.n;
        }
        if state.n == 20 {
            let rows = contact_rows(&problem, state, 1e-6);
            let size: Vec<f64> = rows.iter().map(|r| r.xi[0].abs()).collect();
            let mean = size.iter().sum::<f64>() / size.len() as f64;
            spread = size.iter().fold(0.0f64, |s, v| s.max((v - mean).abs())) / mean;
            stress_ratio = mean / (rate * state.n as f64 * k);
            // ξ is the foundation's traction on the body: it opposes the applied shear.
            for r in &rows {
                let xi = r.friction_vector();
                let e_theta = [-r.x[1], r.x[0]];
                assert!(xi[0] * e_theta[0] + xi[1] * e_theta[1] < 0.0);
            }
        }
    }
    RingRun {
        stress_ratio,
        spread,
        onset_step,
    }
}

#[test]
fn ring_on_a_shaft_carries_tau_b2_over_a2_and_slips_at_the_predicted_time() {
    let (a, b) = (1.0, 2.0);
    let exact = b * b / (a * a);
    let levels = [(2, 32), (4, 64), (8, 128)];
    let runs: Vec<RingRun> = levels.iter().map(|&(nr, nt)| ring_on_shaft(nr, nt)).collect();
    let errors: Vec<f64> = runs.iter().map(|r| (r.stress_ratio - exact).abs() / exact).collect();
    for (run, (level, error)) in runs.iter().zip(levels.iter().zip(&errors)) {
        eprintln!(
            "{level:?}: |ξ|/τ = {:.5} (exact {exact}), error {error:.2e}, spread {:.1e}, slip from step {}",
            run.stress_ratio, run.spread, run.onset_step
        );
        assert!(
            run.spread < 1e-8,
            "the nodes of the inner circle differ: {:e}",
            run.spread
        );
    }
    // Mesh convergence: the error falls at least linearly with h (measured: 3.2e-3, 8.0e-4,
    // 2.0e-4, order 2, the polygons' error in the circles), and is below 1 % on the
    // finest mesh, where the slip starts at the first step past t* = 0.6625 s.
    for pair in errors.windows(2) {
        assert!(pair[1] < 0.6 * pair[0], "no convergence: {errors:?}");
    }
    assert!(errors[2] < 0.01, "{errors:?}");
    assert_eq!(runs[2].onset_step, 27);
    for run in &runs {
        assert!((26..=28).contains(&run.onset_step), "onset at step {}", run.onset_step);
    }
}

/// Two contact parts meeting at a corner (the issue's `contact = ["bottom", "right"]`): each
/// node takes its own face's normal, and the corner node, where the normals differ by 90°,
/// keeps u_ν = 0 of both faces: it does not move.
#[test]
fn two_contact_parts_meeting_at_a_corner_get_their_own_normals_and_a_held_corner() {
    let scenario = thermocontact::Scenario::load(
        None,
        &[
            "mesh.nx=16",
            "mesh.ny=4",
            "time.steps=8",
            r#"boundary.contact=["bottom", "right"]"#,
            r#"boundary.neumann=["top"]"#,
            r#"loads.traction=[{part="top", constant=[0.0, 0.0], rate=[0.0, -800.0]}]"#,
        ]
        .map(String::from),
    )
    .unwrap();
    let problem = scenario.build().unwrap();
    let (_, last) = scenario.run_quiet().unwrap();
    let rows = contact_rows(&problem, &last, 1e-6);
    // The bottom's nodes but the clamped (0, 0) and the corner, and the right's above the corner
    // (the top one too: contact wins over Neumann) carry friction; the corner (40, 0) does not.
    assert_eq!(rows.len(), 15 + 4);
    for r in &rows {
        let expected = if r.x[1] == 0.0 { [0.0, -1.0] } else { [1.0, 0.0] };
        assert_eq!([r.normal[0], r.normal[1]], expected, "node at {:?}", r.x);
    }
    let corner = problem
        .mesh
        .coords
        .iter()
        .position(|x| x[0] == 40.0 && x[1] == 0.0)
        .unwrap();
    assert_eq!(&last.u[2 * corner..2 * corner + 2], &[0.0, 0.0]);
    // The bilateral condition holds along each face: no normal velocity anywhere on Γ_C.
    for r in &rows {
        let w = &last.w[2 * r.node..2 * r.node + 2];
        assert!((w[0] * r.normal[0] + w[1] * r.normal[1]).abs() < 1e-14);
    }
}
