//! Studies on the public API: the benchmark, the verification (convergence on manufactured
//! solutions and nested meshes), the reproduction of the paper's Section 6.
//!
//! Depends on: [`crate::scenario`], [`crate::driver`], and everything below them.

pub mod bench;
pub mod reproduction;
pub mod verification;
