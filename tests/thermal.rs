//! Thermal boundary conditions per boundary part (`model::ThermalCondition`, `[[thermal]]`)
//! against closed forms: a prescribed flux and a convection condition through a slab at steady
//! state, the conservation of heat in an insulated body, a θ_D that moves in t, the release of
//! θ = θ_D on a loaded part, and the scenario's errors.
//!
//! The slabs are thermal only (expansion 0: the velocity stays zero and the coupling term does
//! not enter) and take a few steps of a time step far beyond the conduction time L²ρc_p/K, so
//! that the implicit scheme sits at its steady state (the transient decays by 1/(1 + kλ₁) per
//! step, λ₁ = Kπ²/(4L²ρc_p): below 1e-4 per step here). Every steady profile below is affine
//! in x, which P1 elements represent exactly: the tolerances are round-off.

mod common;

use thermocontact::loads::Datum;
use thermocontact::material::{Isotropic, Material};
use thermocontact::mesh;
use thermocontact::model::{LoadTarget, Problem, ProblemBuilder, State, ThermalCondition, TimeGrid};
use thermocontact::step::{LinearKind, SolverParams};
use thermocontact::{Error, Scenario};

/// Slab length L (along x) and conductivity K; ρ c_p = 1.
const LENGTH: f64 = 1.0;
const CONDUCTIVITY: f64 = 2.0;

fn thermal_material() -> Material {
    Material {
        density: 1.0,
        heat_capacity: 1.0,
        viscosity: Isotropic::viscosity(1.0, 1.0),
        elasticity: Isotropic::elasticity(100.0, 0.3),
        expansion: 0.0,
        conductivity: CONDUCTIVITY,
        reference_temperature: 0.0,
    }
}

/// The slab [0, L] × [0, L/4] clamped on the left (the rest of the boundary in no mechanical
/// role), over `steps` steps up to `final_time`.
fn slab(final_time: f64, steps: usize) -> ProblemBuilder {
    let mesh = mesh::rectangle(LENGTH, LENGTH / 4.0, 8, 2);
    ProblemBuilder::new(mesh, thermal_material(), TimeGrid::new(final_time, steps)).dirichlet(&["left"])
}

/// The slab in 2D (parts left, right, …) or 3D ([0, L] × [0, L/4]², parts x-, x+, …), clamped on
/// its x = 0 face; with the names of its x = 0 and x = L faces and of a side.
fn slab_in(dim: usize, final_time: f64, steps: usize) -> (ProblemBuilder, [&'static str; 3]) {
    let (mesh, faces) = match dim {
        2 => (mesh::rectangle(LENGTH, LENGTH / 4.0, 8, 2), ["left", "right", "top"]),
        _ => (
            mesh::cuboid([LENGTH, LENGTH / 4.0, LENGTH / 4.0], [6, 2, 2]),
            ["x-", "x+", "z+"],
        ),
    };
    let time = TimeGrid::new(final_time, steps);
    (
        ProblemBuilder::new(mesh, thermal_material(), time).dirichlet(&faces[..1]),
        faces,
    )
}

fn run(problem: &Problem) -> State {
    run_with(problem, LinearKind::Auto)
}

fn run_with(problem: &Problem, linear: LinearKind) -> State {
    let params = SolverParams {
        linear,
        ..SolverParams::default()
    };
    thermocontact::driver::run_quiet(problem, &params, &Default::default())
        .unwrap()
        .1
}

/// The largest |θ_p − exact(x_p)| over the nodes.
fn max_error(problem: &Problem, theta: &[f64], exact: impl Fn([f64; 3]) -> f64) -> f64 {
    (problem.mesh.coords.iter().zip(theta))
        .map(|(x, t)| (t - exact(*x)).abs())
        .fold(0.0, f64::max)
}

/// A flux q into the x = L face, θ = θ_D on x = 0, the other faces insulated (one of them
/// explicitly, the others as parts in no role): at steady state θ(x) = θ_D + q x / K, so the
/// flux face sits at θ_D + qL/K. In 2D and 3D.
#[test]
fn prescribed_flux_through_a_slab_gives_the_linear_profile() {
    for dim in [2, 3] {
        prescribed_flux_in(dim);
    }
}

fn prescribed_flux_in(dim: usize) {
    let (theta_d, q) = (10.0, 3.0);
    let (builder, [near, far, side]) = slab_in(dim, 1e4, 4);
    let problem = builder
        .boundary_temperature(-50.0) // replaced on x = 0 by its temperature condition
        .thermal(near, ThermalCondition::Temperature(Datum::scalar(theta_d)))
        .thermal(far, ThermalCondition::Flux(Datum::scalar(q)))
        .thermal(side, ThermalCondition::Insulated)
        .build()
        .unwrap();
    let state = run(&problem);
    let exact = |x: [f64; 3]| theta_d + q * x[0] / CONDUCTIVITY;
    let error = max_error(&problem, &state.theta, exact);
    let face = theta_d + q * LENGTH / CONDUCTIVITY;
    let right = (problem.mesh.coords.iter().zip(&state.theta))
        .filter(|(x, _)| x[0] == LENGTH)
        .map(|(_, t)| *t)
        .fold(f64::NAN, f64::max);
    assert!(
        error < 1e-9 * face,
        "{dim}D: max error {error:e} (flux face {right}, closed form {face})"
    );
    assert!((right - face).abs() < 1e-9 * face, "{right} vs {face}");
}

/// θ = θ_D on the left, convection h(θ − θ_∞) on the right: at steady state θ is affine with
/// θ(L) = (Kθ_D/L + hθ_∞)/(K/L + h).
#[test]
fn convection_through_a_slab_gives_the_robin_closed_form() {
    let (theta_d, h, ambient) = (10.0, 4.0, 20.0);
    let problem = slab(1e4, 4)
        .boundary_temperature(theta_d)
        .thermal(
            "right",
            ThermalCondition::Convection {
                coefficient: h,
                ambient,
            },
        )
        .build()
        .unwrap();
    let state = run(&problem);
    let k_over_l = CONDUCTIVITY / LENGTH;
    let face = (k_over_l * theta_d + h * ambient) / (k_over_l + h);
    let exact = |x: [f64; 3]| theta_d + (face - theta_d) * x[0] / LENGTH;
    let error = max_error(&problem, &state.theta, exact);
    assert!(error < 1e-9 * face, "max error {error:e}, θ(L) = {face}");
    // The closed form is not the insulated answer (θ_D everywhere) nor θ_∞.
    assert!(face - theta_d > 5.0 && ambient - face > 3.0);
}

/// Insulated everywhere — the clamped left part and the loaded top part released from
/// θ = θ_D — with a heat source g: the thermal energy ∫ρc_pθ grows by exactly g|Ω|t (nothing
/// leaves), from a non-uniform θ₀.
#[test]
fn an_insulated_body_keeps_the_heat_of_its_source() {
    let g = 5.0;
    let (final_time, steps) = (0.05, 5);
    let problem = slab(final_time, steps)
        .neumann(&["top"])
        .boundary_temperature(100.0)
        .thermal("left", ThermalCondition::Insulated)
        .thermal("top", ThermalCondition::Insulated)
        .load(LoadTarget::HeatSource, Datum::scalar(g))
        .initial_temperature(Datum::expression("3*x*x - y").unwrap(), "θ₀")
        .build()
        .unwrap();
    assert_eq!(problem.temperature.n_free, problem.mesh.n_nodes(), "no Dirichlet node");
    let energy = |theta: &[f64]| {
        let mut m_theta = vec![0.0; theta.len()];
        problem.matrices.heat_mass.mul_add(1.0, theta, &mut m_theta);
        m_theta.iter().sum::<f64>()
    };
    let initial = energy(&problem.initial.temperature);
    let state = run(&problem);
    let area = LENGTH * LENGTH / 4.0;
    let gained = energy(&state.theta) - initial;
    let expected = g * area * final_time;
    assert!(
        (gained - expected).abs() < 1e-10 * expected,
        "gained {gained}, the source gave {expected}"
    );
    // The field is not trivially uniform: conduction has moved heat around.
    let spread = state.theta.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - state.theta.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    assert!(spread > 0.1, "{spread}");
}

/// A heat flux that varies in x and t, q = 2t(1 + y) into the right face of an otherwise
/// insulated body: the implicit scheme gains Σ_n k ∫ q(t_n) = Σ_n k 2t_n (H + H²/2) (the
/// face's quadrature is exact for data affine in x).
#[test]
fn a_flux_that_moves_in_time_enters_at_every_step() {
    let (final_time, steps) = (0.4, 4);
    let problem = slab(final_time, steps)
        .thermal("left", ThermalCondition::Insulated)
        .thermal(
            "right",
            ThermalCondition::Flux(Datum::expression("2*t*(1 + y)").unwrap()),
        )
        .build()
        .unwrap();
    let energy = |theta: &[f64]| {
        let mut m_theta = vec![0.0; theta.len()];
        problem.matrices.heat_mass.mul_add(1.0, theta, &mut m_theta);
        m_theta.iter().sum::<f64>()
    };
    let state = run(&problem);
    let gained = energy(&state.theta) - energy(&problem.initial.temperature);
    let (k, height) = (final_time / steps as f64, LENGTH / 4.0);
    let expected: f64 = (1..=steps)
        .map(|n| k * 2.0 * (n as f64 * k) * (height + height * height / 2.0))
        .sum();
    assert!(
        (gained - expected).abs() < 1e-10 * expected,
        "gained {gained}, the flux gave {expected}"
    );
}

/// A θ_D that moves in t: θ_D = 20 + 3t + 2x on the left and right with g = ρc_p · 3 makes
/// θ = 20 + 3t + 2x the exact solution, and of the implicit scheme too (it is affine in x and
/// t): every node follows it, interior ones included, only if the lift takes θ_D(t_n) at each
/// step — on both linear paths.
#[test]
fn a_temperature_that_moves_in_time_is_lifted_at_every_step() {
    let rate = 3.0;
    let data = [
        Datum::expression("20 + 3*t + 2*x").unwrap(),
        Datum::Affine {
            constant: vec![20.0],
            rate: vec![rate],
        },
    ];
    for (datum, linear) in data.into_iter().zip([LinearKind::Direct, LinearKind::Iterative]) {
        let slope = if datum.uses_space() { 2.0 } else { 0.0 };
        let problem = slab(2.0, 4)
            .thermal("left", ThermalCondition::Temperature(datum.clone()))
            .thermal("right", ThermalCondition::Temperature(datum))
            .load(LoadTarget::HeatSource, Datum::scalar(rate))
            .initial_temperature(Datum::expression(&format!("20 + {slope}*x")).unwrap(), "θ₀")
            .build()
            .unwrap();
        assert!(problem.thermal.has_moving_temperature());
        let state = run_with(&problem, linear);
        let exact = |x: [f64; 3]| 20.0 + rate * state.t + slope * x[0];
        let error = max_error(&problem, &state.theta, exact);
        // The iterative path solves to its Krylov and Newton tolerances.
        let tolerance = if linear == LinearKind::Direct { 1e-10 } else { 1e-6 };
        assert!(
            error < tolerance * 30.0,
            "{linear:?}: max error {error:e} at t = {}",
            state.t
        );
    }
}

/// A Γ_N part declared insulated is no longer a Dirichlet part: its nodes off the corners with
/// Γ_D are unknowns, and a run moves their temperature off θ_D.
#[test]
fn an_insulated_loaded_part_is_not_dirichlet() {
    let build = |insulated: bool| {
        let mut builder = slab(1.0, 2)
            .neumann(&["top"])
            .boundary_temperature(0.0)
            .load(LoadTarget::HeatSource, Datum::scalar(10.0));
        if insulated {
            builder = builder.thermal("top", ThermalCondition::Insulated);
        }
        builder.build().unwrap()
    };
    let (paper, released) = (build(false), build(true));
    let top = paper.mesh.part_index("top").unwrap();
    let on_top = paper.mesh.nodes_on(&[top]);
    let left = paper.mesh.nodes_on(&[paper.mesh.part_index("left").unwrap()]);
    for p in (0..paper.mesh.n_nodes()).filter(|&p| on_top[p]) {
        assert!(paper.temperature.free[p].is_none(), "node {p} is Dirichlet on Γ_N");
        assert_eq!(
            released.temperature.free[p].is_none(),
            left[p],
            "node {p}: only the corner stays"
        );
    }
    let state = run(&released);
    for p in (0..released.mesh.n_nodes()).filter(|&p| on_top[p] && !left[p]) {
        assert!(state.theta[p] > 0.1, "node {p}: θ = {}", state.theta[p]);
    }
}

/// A scenario with `[[thermal]]` tables: the paper's loaded top insulated, the loaded right
/// face under convection; it runs, keeps the keys in its record (and fingerprint), and the
/// top's temperatures leave θ_D.
#[test]
fn scenario_keys_build_the_conditions() {
    let text = r#"
[[thermal]]
part = "top"
condition = "insulated"

[[thermal]]
part = "right"
condition = "convection"
coefficient = 25
ambient = 20.0
"#;
    let scenario = Scenario::load(
        Some(text),
        &["mesh.nx=8".into(), "mesh.ny=2".into(), "time.steps=4".into()],
    )
    .unwrap();
    assert_eq!(scenario.thermal.len(), 2);
    let record = scenario.to_toml();
    assert!(
        record.contains("[[thermal]]") && record.contains("convection"),
        "{record}"
    );
    let reloaded = Scenario::load(Some(&record), &[]).unwrap();
    assert_eq!(reloaded.thermal, scenario.thermal);
    // Part of the problem: a restart with other conditions is refused, naming them.
    let paper = common::coarse(&[]);
    assert_ne!(scenario.fingerprint(), paper.fingerprint());
    let differing = thermocontact::scenario::differing_keys(&paper.to_toml(), &record);
    assert!(differing.iter().any(|k| k.starts_with("thermal")), "{differing:?}");
    let problem = scenario.build().unwrap();
    assert_eq!(problem.thermal.conditions.len(), 2);
    let (_, state) = scenario.run_quiet().unwrap();
    let theta_d = scenario.boundary.temperature;
    let top = problem.mesh.nodes_on(&[problem.mesh.part_index("top").unwrap()]);
    let left = problem.mesh.nodes_on(&[problem.mesh.part_index("left").unwrap()]);
    let moved = (0..top.len())
        .filter(|&p| top[p] && !left[p] && state.theta[p] != theta_d)
        .count();
    assert!(moved > 0, "the insulated top kept θ_D");
}

fn load_error(text: &str) -> String {
    match Scenario::load(Some(text), &[]) {
        Ok(_) => panic!("accepted: {text}"),
        Err(e) => {
            assert!(
                matches!(e, Error::InvalidValue { .. } | Error::MissingKey { .. }),
                "{e:?}"
            );
            e.to_string()
        }
    }
}

#[test]
fn scenario_errors_name_the_key_the_value_and_what_was_expected() {
    let e = load_error("[[thermal]]\npart = \"back\"\ncondition = \"insulated\"");
    assert!(
        e.contains("thermal[0].part") && e.contains("back") && e.contains("\"left\""),
        "{e}"
    );

    let e = load_error(
        "[[thermal]]\npart = \"top\"\ncondition = \"insulated\"\n[[thermal]]\npart = \"top\"\ncondition = \"flux\"\nvalue = 1.0",
    );
    assert!(e.contains("thermal[1].part") && e.contains("thermal[0]"), "{e}");

    let e = load_error("[[thermal]]\npart = \"right\"\ncondition = \"convection\"\nambient = 20.0");
    assert!(e.contains("thermal[0].coefficient") && e.contains("missing"), "{e}");

    let e = load_error("[[thermal]]\npart = \"right\"\ncondition = \"convective\"");
    assert!(e.contains("thermal[0].condition") && e.contains("convective"), "{e}");
    for name in ["insulated", "temperature", "flux", "convection"] {
        assert!(e.contains(name), "{e}");
    }

    let e = load_error("[[thermal]]\npart = \"bottom\"\ncondition = \"insulated\"");
    assert!(e.contains("thermal[0].part") && e.contains("boundary.contact"), "{e}");

    let e = load_error("[[thermal]]\npart = \"right\"\ncondition = \"insulated\"\nvalue = 3.0");
    assert!(e.contains("thermal[0].value") && e.contains("insulated"), "{e}");

    let e = load_error("[[thermal]]\npart = \"right\"\ncondition = \"convection\"\ncoefficient = -1\nambient = 0");
    assert!(e.contains("thermal[0].coefficient") && e.contains("-1"), "{e}");

    let e = load_error("[[thermal]]\npart = \"right\"\ncondition = \"flux\"\nvalue = \"2*x +\"");
    assert!(e.contains("thermal[0].value"), "{e}");
}

/// Data that are not finite where they are used stop the build naming their key.
#[test]
fn data_that_are_not_finite_name_their_key() {
    for condition in ["temperature", "flux"] {
        let text = format!("[[thermal]]\npart = \"right\"\ncondition = \"{condition}\"\nvalue = \"1/(x - 40)\"");
        let scenario = Scenario::load(Some(&text), &["mesh.nx=4".into(), "mesh.ny=2".into()]).unwrap();
        let e = scenario.build().unwrap_err().to_string();
        assert!(e.contains("thermal[0].value") && e.contains("inf"), "{condition}: {e}");
    }
}

/// The builder refuses what the scenario layer checks first: a contact part, a part twice.
#[test]
fn builder_refuses_a_contact_part_and_a_part_twice() {
    let on_contact = slab(1.0, 1)
        .contact(&["bottom"])
        .thermal("bottom", ThermalCondition::Insulated)
        .build()
        .unwrap_err()
        .to_string();
    assert!(
        on_contact.contains("`bottom`") && on_contact.contains("heat exchange"),
        "{on_contact}"
    );
    let twice = slab(1.0, 1)
        .thermal("top", ThermalCondition::Insulated)
        .thermal("top", ThermalCondition::Flux(Datum::scalar(1.0)))
        .build()
        .unwrap_err()
        .to_string();
    assert!(
        twice.contains("`top`") && twice.contains("two thermal conditions"),
        "{twice}"
    );
    let unknown = slab(1.0, 1)
        .thermal("back", ThermalCondition::Insulated)
        .build()
        .unwrap_err()
        .to_string();
    assert!(unknown.contains("back") && unknown.contains("left"), "{unknown}");
}
