//! The energies of a step (`model::energy`) and the warnings of a run that leaves the
//! plausible (`driver`): the mechanical balance of the paper's example closes on both linear
//! paths, a free body's energy is accounted for to the bit's order, the heat of an insulated
//! body grows by its source, and an unrestrained pad warns where the paper's example does not.

use thermocontact::contact::{LinearHeating, VelocityWeakening};
use thermocontact::driver::{self, OutputPlan};
use thermocontact::loads::Datum;
use thermocontact::material::Material;
use thermocontact::model::energy::energy_levels;
use thermocontact::model::{samples, LoadTarget, Problem, ProblemBuilder, StepEnergy, TimeGrid};
use thermocontact::step::{LinearKind, SolverKind, SolverParams};
use thermocontact::time::{self, TimeError};

/// Each step's energies, after checking that its levels and changes are those of the states.
fn energies(problem: &Problem, params: &SolverParams) -> Vec<StepEnergy> {
    let mut out = Vec::new();
    let mut before = energy_levels(problem, &thermocontact::model::State::initial(problem)).unwrap();
    time::run::<TimeError>(problem, params, |state, info| {
        let e = info.energy;
        let now = energy_levels(problem, state).unwrap();
        for (level, change, was, is) in [
            (e.kinetic, e.kinetic_change, before.0, now.0),
            (e.elastic, e.elastic_change, before.1, now.1),
            (e.thermal, e.thermal_change, before.2, now.2),
        ] {
            let scale = was.abs().max(is.abs()).max(1e-300);
            assert!(
                (level - is).abs() <= 1e-12 * scale,
                "step {}: level {level} against {is}",
                state.n
            );
            assert!(
                (change - (is - was)).abs() <= 1e-10 * scale,
                "step {}: change {change} against {}",
                state.n,
                is - was
            );
        }
        before = now;
        out.push(e);
        Ok(())
    })
    .unwrap();
    out
}

fn params(linear: LinearKind, kind: SolverKind) -> SolverParams {
    SolverParams {
        linear,
        kind,
        ..SolverParams::default()
    }
}

/// The paper's example (16 × 4 cells, 16 steps): every step's balance closes to 1e-12 of its
/// largest term on the direct path (measured: 3e-16), to 1e-7 on the iterative one (Krylov
/// tolerance 1e-10; measured 3e-9); the dissipations are positive and every term is at work.
#[test]
fn paper_balance_closes_at_every_step_on_both_linear_paths() {
    let problem = samples::paper(16, 4, 16).unwrap();
    for (linear, kind, tolerance) in [
        (LinearKind::Direct, SolverKind::Fast, 1e-12),
        (LinearKind::Direct, SolverKind::Paper, 1e-12),
        (LinearKind::Iterative, SolverKind::Fast, 1e-7),
        (LinearKind::Iterative, SolverKind::Paper, 1e-7),
    ] {
        let e = energies(&problem, &params(linear, kind));
        for (n, e) in e.iter().enumerate() {
            let (mech, heat) = (e.relative_residual(), e.relative_heat_residual());
            assert!(
                mech <= tolerance && heat <= tolerance,
                "{linear:?} {kind:?}, step {}: residuals {mech:e}, {heat:e} ({e:?})",
                n + 1
            );
            assert!(e.viscous > 0.0 && e.numerical > 0.0 && e.frictional >= 0.0, "{e:?}");
            assert!(
                e.loads != 0.0 && e.thermal_stress != 0.0 && e.heat_exchange < 0.0,
                "{e:?}"
            );
            assert_eq!(e.foundation, 0.0);
        }
        // The friction dissipates once the contact slips, and heats the body.
        let last = e.last().unwrap();
        assert!(last.frictional > 0.0 && last.heat_friction > 0.0, "{last:?}");
    }
}

/// A material without thermal expansion (the free body's motion and the insulated body's heat
/// do not couple).
fn uncoupled() -> Material {
    Material {
        expansion: 0.0,
        ..samples::paper_material()
    }
}

/// A free body (no Γ_D, no contact, no load) with a shearing initial velocity: the kinetic
/// energy it starts with is all in K + E + D_num + D_visc at every step.
#[test]
fn free_body_accounts_for_its_initial_kinetic_energy() {
    let mesh = thermocontact::mesh::rectangle(4.0, 1.0, 8, 2);
    let problem = ProblemBuilder::new(mesh, uncoupled(), TimeGrid::new(0.5, 20))
        .initial_velocity(Datum::expressions(&["y - 0.5", "0.2*x"]).unwrap(), "u₁")
        .build()
        .unwrap();
    let initial = energy_levels(&problem, &thermocontact::model::State::initial(&problem)).unwrap();
    assert!(initial.0 > 1.0, "{initial:?}");
    let e = energies(&problem, &params(LinearKind::Direct, SolverKind::Fast));
    let mut dissipated = 0.0;
    for e in &e {
        dissipated += e.numerical + e.viscous;
        let accounted = e.kinetic + e.elastic + dissipated;
        assert!(
            (accounted - initial.0).abs() <= 1e-12 * initial.0,
            "{accounted} against K₀ = {}",
            initial.0
        );
        assert!(e.loads == 0.0 && e.frictional == 0.0 && e.thermal_stress == 0.0);
    }
    // Both dissipations took a real share (the test sees each of them).
    let last = e.last().unwrap();
    assert!(
        dissipated > 0.1 * initial.0 && last.kinetic + last.elastic > 0.01 * initial.0,
        "{last:?}"
    );
}

/// An insulated body (no Γ_D, no Γ_N, no Γ_C) with a heat source g: H grows by g |Ω| t, all of
/// it from the source, with no heat through a boundary.
#[test]
fn insulated_body_heats_by_its_source() {
    let (g, area, final_time) = (3.0, 4.0, 0.5);
    let mesh = thermocontact::mesh::rectangle(4.0, 1.0, 8, 2);
    let problem = ProblemBuilder::new(mesh, uncoupled(), TimeGrid::new(final_time, 10))
        .initial_temperature(Datum::expression("25 + x").unwrap(), "θ₀")
        .load(LoadTarget::HeatSource, Datum::scalar(g))
        .build()
        .unwrap();
    let initial = energy_levels(&problem, &thermocontact::model::State::initial(&problem))
        .unwrap()
        .2;
    let e = energies(&problem, &params(LinearKind::Direct, SolverKind::Fast));
    let (mut sources, mut t) = (0.0, 0.0);
    for e in &e {
        sources += e.heat_sources;
        t += final_time / 10.0;
        let expected = initial + g * area * t;
        assert!(
            (e.thermal - expected).abs() <= 1e-12 * expected,
            "H = {} against {expected}",
            e.thermal
        );
        assert!((sources - g * area * t).abs() <= 1e-12 * g * area * t);
        // No exchange: 1ᵀ𝒦_θθ is conduction's, zero but for rounding.
        assert!(e.heat_dirichlet == 0.0 && e.heat_friction == 0.0, "{e:?}");
        assert!(e.heat_exchange.abs() <= 1e-12 * e.heat_sources, "{e:?}");
    }
}

/// The nonsense run, small: a pad with no clamp on the paper's friction law, pressed
/// on top and pushed sideways far beyond what friction holds. It completes with warnings (the
/// rigid motion nothing holds, the temperatures beyond the data's range), where the paper's
/// example completes without one.
#[test]
fn unrestrained_pad_warns_and_the_paper_does_not() {
    let mesh = thermocontact::mesh::rectangle(4.0, 1.0, 8, 2);
    let problem = ProblemBuilder::new(mesh, samples::paper_material(), TimeGrid::new(2.0, 16))
        .neumann(&["top", "left", "right"])
        .contact(&["bottom"])
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
        .frictional_heating(LinearHeating::affine(0.0, 1000.0))
        .load(
            LoadTarget::Pressure("top".into()),
            Datum::affine(vec![0.0], vec![400.0]),
        )
        .load(
            LoadTarget::Traction("left".into()),
            Datum::affine(vec![0.0, 0.0], vec![2000.0, 0.0]),
        )
        .build()
        .unwrap();
    let plan = OutputPlan::default();
    let (summary, _) = driver::run_quiet(&problem, &SolverParams::default(), &plan).unwrap();
    let kinds: Vec<&str> = summary.warnings.iter().map(|w| w.kind.as_str()).collect();
    assert!(
        kinds.contains(&"unrestrained") && kinds.contains(&"temperature"),
        "{:#?}",
        summary.warnings
    );
    assert_eq!(summary.outcome, format!("completed with {} warnings", kinds.len()));
    let energy = summary.energy.unwrap();
    assert!(energy.max_energy_residual < 1e-12, "{energy:?}");

    let (paper, _) = driver::run_quiet(&samples::paper(16, 4, 16).unwrap(), &SolverParams::default(), &plan).unwrap();
    assert!(paper.warnings.is_empty(), "{:#?}", paper.warnings);
    assert_eq!(paper.outcome, "completed");
}

/// A cut-back step's figures are its substeps' summed, each substep's balance exact: the
/// balance still closes (the starved solver of tests/cutback.rs cuts steps back).
#[test]
fn cut_back_steps_balance_over_their_substeps() {
    let problem = samples::paper(16, 4, 16).unwrap();
    let params = SolverParams {
        max_convexification: 5,
        max_sweeps: 0,
        ..params(LinearKind::Direct, SolverKind::Fast)
    };
    let mut cut = 0;
    time::run::<TimeError>(&problem, &params, |state, info| {
        cut += usize::from(info.substeps > 1);
        let e = info.energy;
        assert!(e.relative_residual() <= 1e-12, "step {}: {e:?}", state.n);
        // The heat residual's floor is rounding in ℳ_θ(θ_n − θ_{n−1})/k at k/2^depth.
        assert!(e.relative_heat_residual() <= 1e-10, "step {}: {e:?}", state.n);
        Ok(())
    })
    .unwrap();
    assert!(cut > 0, "no step was cut back");
}

/// The rigid motions the constraints leave free: none for the clamped example, the tangential
/// translation for a slab on a flat Γ_C without Γ_D, all three for a free slab.
#[test]
fn free_rigid_motions_are_those_the_constraints_leave() {
    use thermocontact::model::plausibility::RigidModes;
    assert!(RigidModes::of(&samples::paper(16, 4, 2).unwrap()).is_empty());
    let slab = |contact: &[&str]| {
        let mesh = thermocontact::mesh::rectangle(4.0, 1.0, 8, 2);
        ProblemBuilder::new(mesh, uncoupled(), TimeGrid::new(1.0, 2))
            .contact(contact)
            .build()
            .unwrap()
    };
    let on_contact = RigidModes::of(&slab(&["bottom"]));
    assert_eq!(on_contact.names, ["translation along x"]);
    // Its measure: a rigid shift by 0.3 along x, and nothing for a shift across Γ_C's normal.
    let shift = |c: usize| {
        (0..2 * 9 * 3)
            .map(|i| if i % 2 == c { 0.3 } else { 0.0 })
            .collect::<Vec<f64>>()
    };
    assert!((on_contact.rigid_displacement(&shift(0)) - 0.3).abs() < 1e-12);
    assert!(on_contact.rigid_displacement(&shift(1)).abs() < 1e-12);
    assert_eq!(RigidModes::of(&slab(&[])).names.len(), 3);
}
