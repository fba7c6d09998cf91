//! The laws on the contact boundary Γ_C: friction (8), heat exchange and frictional heating (9).
//!
//! The bilateral condition (7), u_ν = 0, is not a law but a constraint on the velocity space,
//! posed in each node's frame ([`frames`]) and built into E^h by the constrained spaces of `crate::fem`.
//!
//! Depends on: [`crate::mesh`] (the normals and tangents of the contact nodes), [`crate::loads`]
//! (the expressions of the user's laws).

pub mod foundation;
pub mod frames;
pub mod friction;
pub mod heat;
pub mod table;

pub use foundation::{Foundation, NormalForce};
#[allow(deprecated)]
pub use friction::SlipWeakening;
pub use friction::{
    project_to_ball, Coulomb, ExpressionFriction, FrictionLaw, LawPoint, SlipDistanceWeakening, TabulatedFriction,
    Tresca, VelocityWeakening,
};
pub use heat::{
    ExpressionExchange, ExpressionHeating, FrictionalHeating, HeatExchange, LinearHeating, QuadraticExchange,
    TabulatedExchange,
};
pub use table::{Table, TableError};
