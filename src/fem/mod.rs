//! Function spaces and assembly: P1 simplices, element kernels, sparse patterns, the
//! constrained spaces E^h and V^h, and global assembly of the matrices of Problem 14.

pub mod assembly;
pub mod dofs;
pub mod kernels;
