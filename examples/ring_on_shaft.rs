//! # A ring on a shaft, from Rust, with no scenario file
//!
//! What it solves: a thermo-viscoelastic ring a ≤ r ≤ b sits on a rigid shaft. Its inner circle
//! Γ_C is in bilateral contact with the shaft (u_ν = 0, normals from the mesh, one per node)
//! with velocity-weakening friction μ(r) S and frictional heating; its outer circle Γ_N carries a
//! shear traction τ(t) e_θ that grows linearly in time. Nothing clamps the ring (Γ_D = ∅):
//! friction alone holds it, until the shear it must carry on the inner circle, τ b²/a² by the
//! ring's equilibrium, reaches the friction bound μ(0) S. Then the whole inner circle slips at
//! once (the problem is rotationally symmetric).
//!
//! The scheme is the paper's (Bartosz, Danan, Szafraniec 2017): P1 elements, backward Euler,
//! the step problem of Problem 14 solved by the fast solver (semismooth Newton on the
//! condensed nonmonotone law).
//!
//! Sample runs:
//! ```text
//! cargo run --release --example ring_on_shaft                 # 8 × 128 cells, 40 steps
//! cargo run --release --example ring_on_shaft -- 16 256 out/ring   # finer, with VTK output
//! ```
//! CI runs it at reduced size (`cargo test --example ring_on_shaft`).
//!
//! What to read first: `ProblemBuilder` in `src/model/problem.rs` (the parts a problem is made of),
//! then `driver::run` (the time loop with output).

use std::path::PathBuf;

use thermocontact::contact::{LinearHeating, QuadraticExchange, VelocityWeakening};
use thermocontact::driver::{self, OutputPlan, RunOptions, Summary};
use thermocontact::loads::Datum;
use thermocontact::material::{Isotropic, Material};
use thermocontact::mesh;
use thermocontact::model::{LoadTarget, ProblemBuilder, TimeGrid};
use thermocontact::step::SolverParams;

/// The ring and its loading.
struct Ring {
    /// a, b [m].
    radii: (f64, f64),
    /// τ̇ [N/(m s)]: τ(t) = τ̇ t.
    shear_rate: f64,
    /// S [N/m]: the friction bound at rest is μ(0) S = a_μ S.
    bound: f64,
}

/// The run's outcome.
struct Outcome {
    summary: Summary,
    /// t* = μ(0) S a²/(τ̇ b²): the predicted onset of slip.
    predicted_onset: f64,
    /// The first output time with slipping nodes.
    observed_onset: Option<f64>,
}

fn solve(ring: &Ring, n_radial: usize, n_around: usize, steps: usize, out: Option<PathBuf>) -> Outcome {
    let (a, b) = ring.radii;

    // 1. The mesh: a structured annulus; its parts are `inner` and `outer`. A Gmsh mesh would
    //    come from `thermocontact::mesh::read_msh(path)` with the parts named by its physical
    //    groups.
    let mesh = mesh::annulus(a, b, n_radial, n_around);

    // 2. The material: the paper's, light (ρ = 1) so that the ring's shear waves are fast
    //    against the loading and the response is quasi-static.
    let (young, poisson) = (10_000.0, 0.3);
    let material = Material {
        density: 1.0,
        heat_capacity: 0.1,
        viscosity: Isotropic::viscosity(50.0, 200.0),
        elasticity: Isotropic::elasticity(young, poisson),
        expansion: Material::expansion_from(3e-4, young, poisson),
        conductivity: 0.5,
        reference_temperature: 0.0,
    };

    // 3. The problem: boundary roles by part name, the laws on Γ_C, and the loads. The shear
    //    traction is an expression of x, y, t (τ(t) e_θ, e_θ = (−y, x)/r), compiled once and
    //    integrated at quadrature points.
    let shear = format!("{}*t/sqrt(x^2+y^2)", ring.shear_rate);
    let traction = Datum::expressions(&[format!("-y*{shear}"), format!("x*{shear}")]).expect("valid expressions");
    let friction = VelocityWeakening {
        a: 1.0,
        b: 0.5,
        alpha: 10.0,
    };
    let problem = ProblemBuilder::new(mesh, material, TimeGrid::new(1.0, steps))
        .neumann(&["outer"])
        .contact(&["inner"])
        .boundary_temperature(20.0)
        .initial_temperature(Datum::scalar(20.0), "θ₀")
        .friction(ring.bound, friction)
        .heat_exchange(QuadraticExchange {
            coefficient: 2.0,
            foundation_temperature: 20.0,
        })
        .frictional_heating(LinearHeating::affine(0.0, 10.0))
        .load(LoadTarget::Traction("outer".into()), traction)
        .build()
        .expect("a well-posed problem");

    // 4. The run: every tenth step recorded (slip counts; VTK and contact CSV when an output
    //    folder is given).
    let plan = OutputPlan {
        steps: (1..=steps).filter(|n| n % (steps / 10).max(1) == 0).collect(),
        ..OutputPlan::default()
    };
    let options = RunOptions {
        out_dir: out,
        log: true,
        // Each run of the example replaces the previous one's files.
        overwrite: true,
        ..RunOptions::default()
    };
    let summary = driver::run(&problem, &SolverParams::default(), &plan, &options).expect("the run converges");

    // 5. Compare the onset of slip with the ring's equilibrium.
    let predicted_onset = friction.a * ring.bound * a * a / (ring.shear_rate * b * b);
    let observed_onset = summary.outputs.iter().find(|o| o.slip_nodes > 0).map(|o| o.t);
    Outcome {
        summary,
        predicted_onset,
        observed_onset,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n_radial = args.first().and_then(|s| s.parse().ok()).unwrap_or(8);
    let n_around = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(128);
    let out = args.get(2).map(PathBuf::from);
    let ring = Ring {
        radii: (1.0, 2.0),
        shear_rate: 40.0,
        bound: 120.0,
    };
    let outcome = solve(&ring, n_radial, n_around, 40, out);
    println!("{:>8} {:>6} {:>6} {:>12}", "t [s]", "slip", "stick", "max |w_τ|");
    for o in &outcome.summary.outputs {
        println!(
            "{:>8.3} {:>6} {:>6} {:>12.4e}",
            o.t, o.slip_nodes, o.stick_nodes, o.max_slip_rate
        );
    }
    println!(
        "slip predicted from t* = μ(0) S a²/(τ̇ b²) = {:.4} s; first output with slip: {}",
        outcome.predicted_onset,
        outcome
            .observed_onset
            .map_or("none".to_string(), |t| format!("{t:.4} s"))
    );
}

// Things to try: clamp a piece of the ring (`.dirichlet(&["..."])` needs a part: use a Gmsh mesh
// with a named radial cut); replace the shear by a pressure `LoadTarget::Pressure("outer")`
// (the ring then never slips: pressure makes no torque); make the friction law steeper
// (`alpha: 100.0`) and watch the fast solver take the convexification loop.

#[cfg(test)]
mod tests {
    use super::*;

    /// At reduced size the example still slips at the predicted time (to the output spacing).
    #[test]
    fn the_ring_slips_when_the_shear_reaches_the_bound() {
        let ring = Ring {
            radii: (1.0, 2.0),
            shear_rate: 40.0,
            bound: 120.0,
        };
        let outcome = solve(&ring, 2, 32, 20, None);
        let onset = outcome.observed_onset.expect("the ring slips");
        // Outputs every 0.1 s: the first one with slip is the first one past t* = 0.75 s.
        assert!(onset > outcome.predicted_onset && onset - outcome.predicted_onset <= 0.1 + 1e-9);
        let first = outcome.summary.outputs.iter().find(|o| o.slip_nodes > 0).unwrap();
        assert_eq!(first.stick_nodes, 0, "the whole inner circle slips at once");
    }
}
