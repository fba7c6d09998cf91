//! Verification: the convergence study of the paper's Fig. 4 and a manufactured solution with
//! exact stick and slip, measuring the errors of the estimate (73) of Corollary 16,
//! ‖u − u^{hk}‖ ≤ c(h + k).
//!
//! * [`nested`]: exact P1 prolongation between nested rectangle meshes;
//! * [`errors`]: the norms of (73), between discrete solutions (exact P1 norms) or against an
//!   exact solution (quadrature);
//! * [`manufactured`]: the exact solution family and the loads it needs ([`crate::model::ExtraLoads`]);
//! * [`jet`], [`quadrature`]: exact derivatives of the formulas, and the rules that integrate them;
//! * [`study`]: the level sequence h = k = 1/2 … 1/2^N, the runs, the observed orders and the
//!   files `thermocontact converge` writes.

pub mod errors;
pub mod jet;
pub mod manufactured;
pub mod nested;
pub mod quadrature;
pub mod study;
