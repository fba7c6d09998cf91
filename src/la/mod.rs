//! Generic sparse linear algebra: what the step's linear back-ends are built from.
//!
//! Depends on: nothing of this crate (faer, rayon; PETSc through `csrc/` behind the `petsc`
//! feature). It knows no mesh, no problem and no Γ_C: a matrix is a matrix, an unknown an index.
//!
//! - [`CscMatrix`] (assembly's format, faer's view) and [`CsrMatrix`] (the Krylov path's rows);
//! - [`vector`]: the vector kernels, sequential and blocked-parallel;
//! - [`QuasiDefiniteLdlt`]: the LDLᵀ of a symmetric quasi-definite matrix with a trailing block
//!   read on its own;
//! - [`Ilu0`] and [`gmres`]: the incomplete factor and the restarted Krylov method;
//! - [`NodeCells`], [`NodeGraph`] and [`level_bisection`]: the cells of each node, the cell
//!   graph of the nodes and its two-way split for the parallel sweeps;
//! - `petsc` (feature `petsc`): the thin binding to PETSc's GAMG;
//! - `mpi` (feature `mpi`): the communicator, PETSc's graph partitioner and its distributed
//!   matrix with GMRES (docs/distributed.md).
//!
//! Errors: [`LaError`], with the stage of a factorization that failed ([`FactorStage`]).

mod error;
mod gmres;
mod graph;
mod ilu;
mod ldlt;
#[cfg(feature = "mpi")]
pub mod mpi;
#[cfg(feature = "petsc")]
pub mod petsc;
mod sparse;
pub mod vector;

pub use error::{FactorStage, LaError};
pub use gmres::{gmres, Gmres, GmresParams, Preconditioner, SolveInfo};
pub use graph::{level_bisection, NodeCells, NodeGraph, Part};
pub use ilu::{Ilu0, RowParts};
pub use ldlt::QuasiDefiniteLdlt;
pub use sparse::{row_index, ColumnsMut, CscMatrix, CsrMatrix};
