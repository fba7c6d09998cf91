//! Function spaces and assembly: P1 simplices, element kernels, sparse patterns, the
//! constrained spaces E^h and V^h, and global assembly of the matrices of Problem 14.
//!
//! Depends on: [`crate::mesh`] (cells, simplices), [`crate::la`] (the sparse patterns),
//! [`crate::material`] (the tensors of the integrands).

pub mod assembly;
pub(crate) mod dofs;
pub(crate) mod kernels;
