//! The paper's numerical example (Section 6) as builder calls: the problem that tests, studies
//! and examples start from when the scenario file is not what they test. `scenarios/paper.toml`
//! describes the same problem; a test below keeps the two the same to the bit.
//!
//! Depends on: the problem and its builder, [`crate::mesh`], [`crate::material`], [`crate::contact`],
//! [`crate::loads`].

use super::error::ModelError;
use super::problem::{LoadTarget, Problem, ProblemBuilder, TimeGrid};
use crate::contact::{LinearHeating, QuadraticExchange, VelocityWeakening};
use crate::loads::Datum;
use crate::material::{Isotropic, Material};
use crate::mesh;

/// The example's material: ρ = 100, c_p = 0.1, μ₁ = 50, μ₂ = 200, E = 10⁴, κ = 0.3,
/// α_exp = 3·10⁻⁴, k = 0.5, θ_ref = 0.
pub fn paper_material() -> Material {
    Material {
        density: 100.0,
        heat_capacity: 0.1,
        viscosity: Isotropic::viscosity(50.0, 200.0),
        elasticity: Isotropic::elasticity(10_000.0, 0.3),
        expansion: Material::expansion_from(3e-4, 10_000.0, 0.3),
        conductivity: 0.5,
        reference_temperature: 0.0,
    }
}

/// The example's problem on Ω = (0, 40) × (0, 10) with `nx` × `ny` cells, T = 1 in `steps`
/// steps: clamped on the left, a traction (0, −800 t) on the top, contact on the bottom with
/// the exponential velocity-weakening law (S = 150, a = 1, b = 0.2, α = 100), heat exchange
/// k_e = 2 against θ_R = 0, frictional heating 10 t r, θ₀ = θ_D = 25, gravity (0, −10).
/// The paper's reference run is `paper(128, 32, 64)` (the default scenario).
pub fn paper(nx: usize, ny: usize, steps: usize) -> Result<Problem, ModelError> {
    paper_builder(nx, ny, steps).build()
}

/// [`paper`] before its last step, for a test or a study that changes one part of it.
pub fn paper_builder(nx: usize, ny: usize, steps: usize) -> ProblemBuilder {
    let mesh = mesh::rectangle(40.0, 10.0, nx, ny);
    with_paper_data(
        ProblemBuilder::new(mesh, paper_material(), TimeGrid::new(1.0, steps)),
        2,
    )
    .dirichlet(&["left"])
    .neumann(&["top", "right"])
    .contact(&["bottom"])
    .load(
        LoadTarget::Traction("top".into()),
        Datum::affine(vec![0.0, 0.0], vec![0.0, -800.0]),
    )
    .load(
        LoadTarget::Traction("right".into()),
        Datum::affine(vec![0.0, 0.0], vec![0.0, 0.0]),
    )
}

/// The 3D example (`scenarios/paper3d.toml`): the paper's slab as the box (0, 40) × (0, 10) ×
/// (0, 10) with `cells` cells, clamped at x = 0, a traction (0, 0, −800 t) on z = 10, contact on
/// z = 0, the 2D example's material, laws and gravity (0, 0, −10).
pub fn paper_3d(cells: [usize; 3], steps: usize) -> Result<Problem, ModelError> {
    paper_3d_builder(cells, steps).build()
}

/// [`paper_3d`]'s builder.
pub fn paper_3d_builder(cells: [usize; 3], steps: usize) -> ProblemBuilder {
    let mesh = mesh::cuboid([40.0, 10.0, 10.0], cells);
    with_paper_data(
        ProblemBuilder::new(mesh, paper_material(), TimeGrid::new(1.0, steps)),
        3,
    )
    .dirichlet(&["x-"])
    .neumann(&["x+", "y-", "y+", "z+"])
    .contact(&["z-"])
    .load(
        LoadTarget::Traction("z+".into()),
        Datum::affine(vec![0.0; 3], vec![0.0, 0.0, -800.0]),
    )
}

/// The example's laws and data in `d` dimensions: θ_D = θ₀ = 25, heat exchange k_e = 2 against
/// θ_R = 0, frictional heating 10 t r, the velocity-weakening law (S = 150, a = 1, b = 0.2,
/// α = 100), u₀ = u₁ = 0, gravity −10 along the last axis, no heat source.
fn with_paper_data(builder: ProblemBuilder, d: usize) -> ProblemBuilder {
    let mut gravity = vec![0.0; d];
    gravity[d - 1] = -10.0;
    builder
        .boundary_temperature(25.0)
        .heat_exchange(QuadraticExchange {
            coefficient: 2.0,
            foundation_temperature: 0.0,
        })
        .frictional_heating(LinearHeating::affine(0.0, 10.0))
        .initial_displacement(Datum::constant(vec![0.0; d]), "initial.displacement")
        .initial_velocity(Datum::constant(vec![0.0; d]), "initial.velocity")
        .initial_temperature(Datum::scalar(25.0), "initial.temperature")
        .friction(
            150.0,
            VelocityWeakening {
                a: 1.0,
                b: 0.2,
                alpha: 100.0,
            },
        )
        .load(LoadTarget::BodyForce, Datum::affine(gravity, vec![0.0; d]))
        .load(LoadTarget::HeatSource, Datum::affine(vec![0.0], vec![0.0]))
}
