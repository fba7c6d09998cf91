//! Loads and data given as constants, affine functions of t, or expressions of x, y, z, t, and
//! their integration into P1 load vectors.
//!
//! A [`Datum`] is the data (n components); a [`Load`] binds one to a region of the mesh — the
//! cells for a body force f₀ or a heat source g, boundary parts for a traction f₂ or a pressure —
//! and adds ∫ f · φ_p to a full nodal vector at any time t ([`Load::add_to`]). What does not
//! change with t is integrated once at construction; see [`Load`] for the strategies.
//! [`nodal_values`] samples a datum at the nodes (initial fields u₀, u₁, θ₀).
//!
//! Full nodal numbering as in [`crate::fem::assembly`]: vector dof (p, c) ↦ p·d + c, scalar
//! dof p ↦ p.
//!
//! Depends on: [`crate::mesh`], [`crate::fem`] (quadrature on simplices, the nodal numbering).

mod datum;
mod expression;
mod load;
mod quadrature;

pub use datum::Datum;
pub use expression::{Expression, ExpressionError, MAX_EXPRESSION_BYTES, MAX_EXPRESSION_DEPTH};
pub use load::{nodal_values, Load, LoadKind};

/// Errors of building or evaluating a load; each names the load's label.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LoadError {
    /// The datum has the wrong number of components for the kind of load.
    #[error("the {kind} `{label}` needs {expected} component(s), its datum has {found}")]
    ComponentCount {
        label: String,
        kind: &'static str,
        expected: usize,
        found: usize,
    },
    /// An affine datum whose constant and rate have different lengths.
    #[error("the affine datum of `{label}` has {constant} constant component(s) but {rate} rate component(s)")]
    AffineLengths {
        label: String,
        constant: usize,
        rate: usize,
    },
    /// A boundary part index the mesh does not have.
    #[error("`{label}` is applied on boundary part {part}, but the mesh has {n_parts} parts")]
    UnknownPart { label: String, part: usize, n_parts: usize },
    /// The datum is NaN or infinite somewhere it is evaluated.
    #[error("`{label}` is not finite at x = {x:?}, t = {t}: {value}")]
    NotFinite {
        label: String,
        x: [f64; 3],
        t: f64,
        value: f64,
    },
    /// The output vector does not have one entry per nodal dof of the mesh.
    #[error("`{label}` adds into a vector of {expected} entries, got {found}")]
    OutputLength {
        label: String,
        expected: usize,
        found: usize,
    },
}
