//! The watch observer: the warnings of a run that leaves the plausible, each given once per run
//! with the step, the node and the value, logged and kept in the tally (`summary.json`). A
//! warning does not stop the run; a run that completes with some says "completed with N
//! warnings".
//!
//! - `energy_balance` / `heat_balance`: a step's balance residual ([`crate::model::energy`])
//!   above [`BALANCE_TOLERANCE`] of the balance's largest term;
//! - `unrestrained`: a rigid displacement along motions nothing holds but friction beyond
//!   [`RIGID_DISPLACEMENT_LIMIT`] of the body's size ([`RigidModes`]);
//! - `temperature`: a temperature outside the data's plausible range ([`TemperatureRange`]).

use serde::{Deserialize, Serialize};

use super::summary::StepRecord;
use crate::model::plausibility::{RigidModes, TemperatureRange, RIGID_DISPLACEMENT_LIMIT};
use crate::model::{Problem, State};

/// A step's mechanical balance residual above this fraction of the balance's largest term is a
/// warning: the direct path closes to about 1e-15, the iterative one to the order of its
/// Krylov tolerance (1e-10 relative: 3e-10 on the paper's example).
pub const BALANCE_TOLERANCE: f64 = 1e-6;

/// The same for the heat balance, looser: a nonlinear heat exchange's fixed point stops where ζ
/// changes by ε_conv = 1e-6 relative, so its heat is that exact (6e-7 of the largest heat on
/// `scenarios/own_laws.toml`); affine exchanges close to 1e-13 (direct) and 5e-9 (iterative).
pub const HEAT_BALANCE_TOLERANCE: f64 = 1e-4;

/// A warning of the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunWarning {
    /// `energy_balance`, `heat_balance`, `unrestrained` or `temperature`.
    pub kind: String,
    /// The time level and time where it was first met.
    pub step: usize,
    pub t: f64,
    /// What was met, with the value and the limit.
    pub message: String,
}

/// The watch: what it checks against, set up once.
pub(super) struct Watch {
    rigid: RigidModes,
    temperatures: TemperatureRange,
}

impl Watch {
    pub fn new(problem: &Problem) -> Self {
        Watch {
            rigid: RigidModes::of(problem),
            temperatures: TemperatureRange::of(problem),
        }
    }

    /// The run header's line on the rigid motions the constraints leave free (none: no line).
    pub fn header_line(&self) -> Option<String> {
        (!self.rigid.is_empty()).then(|| {
            format!(
                "note: Γ_D, the symmetry planes and the normal constraint on Γ_C leave {} rigid motion(s) free ({}): friction alone holds the body against them (a warning comes if it moves rigidly by more than {:.3e} m)",
                self.rigid.names.len(),
                self.rigid.names.join("; "),
                self.rigid.limit()
            )
        })
    }

    /// The warnings that the step to `state` (its record `step`) raises and `given` does not
    /// hold yet.
    pub fn check(&self, problem: &Problem, state: &State, step: &StepRecord, given: &[RunWarning]) -> Vec<RunWarning> {
        let mut new: Vec<RunWarning> = Vec::new();
        let mut raise = |kind: &str, message: String| {
            if !given.iter().chain(new.iter()).any(|w| w.kind == kind) {
                new.push(RunWarning {
                    kind: kind.to_string(),
                    step: state.n,
                    t: state.t,
                    message: format!("step {} (t = {}): {message}", state.n, state.t),
                });
            }
        };
        let balances = [
            (
                "energy_balance",
                "mechanical energy",
                step.energy_residual,
                BALANCE_TOLERANCE,
            ),
            ("heat_balance", "heat", step.heat_residual, HEAT_BALANCE_TOLERANCE),
        ];
        for (kind, name, value, tolerance) in balances {
            if value > tolerance {
                raise(
                    kind,
                    format!(
                        "the {name} balance's residual is {value:.3e} of its largest term (tolerance {tolerance:e}): the step's equations were not solved that well"
                    ),
                );
            }
        }
        if !self.rigid.is_empty() {
            let moved = self.rigid.rigid_displacement(&state.u);
            if moved > self.rigid.limit() {
                raise(
                    "unrestrained",
                    format!(
                        "the body moved rigidly by {moved:.3e} m along motions only friction holds ({}), beyond {} of its size {:.3e} m: an unrestrained mechanism, and beyond the small displacements the model assumes",
                        self.rigid.names.join("; "),
                        RIGID_DISPLACEMENT_LIMIT,
                        self.rigid.size
                    ),
                );
            }
        }
        let range = &self.temperatures;
        if let Some((node, value)) = range.worst_outside(&state.theta) {
            raise(
                "temperature",
                format!(
                    "θ = {value:.4e} at node {node} (x = {:?}) is outside the plausible range [{:.4e}, {:.4e}] (the data span [{}, {}])",
                    &problem.mesh.coords[node][..problem.dim()],
                    range.low,
                    range.high,
                    range.data_min,
                    range.data_max
                ),
            );
        }
        new
    }
}
