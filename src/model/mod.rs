//! The discrete problem and its state: everything fixed during a run, and what changes.
//!
//! Depends on: [`crate::mesh`], [`crate::la`], [`crate::fem`], [`crate::material`],
//! [`crate::loads`], [`crate::contact`]; with the `mpi` feature, `crate::partition`.
//!
//! - [`Problem`], built by [`ProblemBuilder`] from typed parts (no TOML);
//! - [`State`]: the fields carried from time level to time level;
//! - [`StepMatrix`] and [`StepRhs`]: the linear part of one step of Problem 14;
//! - [`norms`]: the norms of the stop criteria (77)–(80);
//! - [`ContactLaws`]: the laws on Γ_C node by node at one step ([`Friction`], [`Heating`]);
//! - [`ContactRow`]: the state at a node of Γ_C, as output reads it;
//! - [`thermal`]: thermal boundary conditions per part ([`ThermalCondition`]);
//! - [`energy`]: the energies of a step and their balances ([`StepEnergy`]);
//! - [`plausibility`]: the rigid motions nothing holds, the plausible temperatures;
//! - [`samples`]: the paper's example (and its 3D counterpart) as builder calls;
//! - [`ColumnShare`]: a rank's share of the matrices in a distributed run (the columns its rows
//!   read) and the sum of its part of the energies over the ranks;
//! - `DistributedStepMatrix` (feature `mpi`): the step matrix as a PETSc matrix distributed
//!   by rows over the ranks, and its solve.

mod contact_rows;
#[cfg(feature = "mpi")]
mod distributed;
pub mod energy;
mod error;
mod laws;
pub mod norms;
pub mod plausibility;
mod pressure;
mod problem;
pub mod samples;
mod share;
mod state;
mod step_matrix;
pub mod thermal;

pub use contact_rows::{contact_rows, contact_tangential, ContactRow};
#[cfg(feature = "mpi")]
pub use distributed::{node_unknowns, DistributedStepMatrix};
pub use energy::{step_energy, step_energy_and_elastic_force, StepEnergy};
pub use error::ModelError;
pub use laws::{
    foundation_tangential, law_scale, relative_slip, ContactLaws, Friction, FrictionConstants, Heating, LawConstants,
};
pub use pressure::ContactPressure;
pub use problem::*;
pub use share::{nodes_within, ColumnShare, RowProducts};
pub use state::State;
pub use step_matrix::{
    assemble_by_columns, ordered_rows, ordered_rows_at, ordered_rows_range, rows_of_symmetric_form,
    rows_of_symmetric_form_ordered, StepMatrix, StepRhs,
};
pub use thermal::{ThermalBoundary, ThermalCondition};
