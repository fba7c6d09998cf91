//! Time stepping and the nonsmooth solvers of one step.
//!
//! [`system::StepSystem`] holds the linear part of Problem 14, factored once per run;
//! [`paper::PaperSolver`] is the convexification + augmented-Lagrangian solver of Problem 17;
//! [`fast::FastSolver`] a semismooth Newton method on the same condensed problem.

pub mod condensed;
pub mod factor;
pub mod fast;
pub mod newton;
pub mod paper;
pub mod system;

use serde::{Deserialize, Serialize};

use crate::norms;
use crate::problem::Problem;
use system::State;

/// Which nonsmooth solver runs each time step.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SolverKind {
    /// Convexification loop + Uzawa augmented Lagrangian (Problem 17).
    Paper,
    /// Semismooth Newton on the condensed nonmonotone law, the convexification loop where the
    /// law is too steep.
    Fast,
}

impl SolverKind {
    /// The name in scenarios and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            SolverKind::Paper => "paper",
            SolverKind::Fast => "fast",
        }
    }
}

/// The step solver's settings; defaults are the paper's (ε_conv = 1e-6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverParams {
    /// Which solver.
    pub kind: SolverKind,
    /// ε_conv of the stop criteria (77)–(80).
    pub tolerance: f64,
    /// Cap on convexification iterations per step.
    pub max_convexification: usize,
    /// Relative tolerance of the inner solvers (Uzawa, Newton).
    pub inner_tolerance: f64,
    /// Cap on inner Uzawa iterations per convex problem.
    pub max_inner: usize,
}

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            kind: SolverKind::Fast,
            tolerance: 1e-6,
            max_convexification: 200,
            inner_tolerance: 1e-10,
            max_inner: 20_000,
        }
    }
}

/// What one time step cost and how it ended.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StepInfo {
    /// Outer (convexification) iterations.
    pub convexification_iterations: usize,
    /// Inner iterations summed over the outer ones (one linear solve each).
    pub inner_iterations: usize,
    /// Last relative increments of u, θ, ξ, ζ: the left sides of (77)–(80) over the right
    /// sides' norms.
    pub increments: [f64; 4],
    /// Semismooth Newton iterations (fast solver).
    pub newton_iterations: usize,
    /// The fast solver went through the convexification loop in this step.
    pub fallback: bool,
}

/// Relative increments (77)–(80) between two iterates of one time step.
pub fn relative_increments(problem: &Problem, old: &State, new: &State) -> [f64; 4] {
    let diff = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
    let ratio = |num: f64, den: f64| {
        if num == 0.0 {
            0.0
        } else if den == 0.0 {
            f64::INFINITY
        } else {
            num / den
        }
    };
    let m = &problem.matrices;
    let du = norms::energy(m, &diff(&new.u, &old.u));
    let dtheta = norms::gradient(m, &diff(&new.theta, &old.theta));
    let dxi = norms::contact_l2(problem, &diff(&new.xi, &old.xi));
    let zeta_new = norms::heat_exchange_multiplier(problem, &new.theta);
    let zeta_old = norms::heat_exchange_multiplier(problem, &old.theta);
    let zeta_diff = diff(&zeta_new, &zeta_old);
    let zeta_ref = zeta_old;
    [
        ratio(du, norms::energy(m, &old.u)),
        ratio(dtheta, norms::gradient(m, &old.theta)),
        ratio(dxi, norms::contact_l2(problem, &old.xi)),
        ratio(
            norms::contact_l2(problem, &zeta_diff),
            norms::contact_l2(problem, &zeta_ref),
        ),
    ]
}

/// All of (77)–(80) hold.
pub fn increments_converged(increments: &[f64; 4], tolerance: f64) -> bool {
    increments.iter().all(|&r| r <= tolerance)
}
