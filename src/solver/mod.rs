//! Time stepping and the nonsmooth solvers of one step.
//!
//! [`system::StepSystem`] holds the linear part of Problem 14, factored once per run;
//! [`paper::PaperSolver`] is the convexification + augmented-Lagrangian solver of Problem 17;
//! [`fast::FastSolver`] a semismooth Newton method on the same condensed problem, globalized by
//! the descent of [`descent`] where Newton and the convexification loop both fail. On the
//! iterative path nothing is condensed: [`newton_krylov::NewtonKrylov`] (the fast solver's
//! counterpart) and [`paper_krylov::PaperKrylov`] (the paper's loop) solve the whole step by
//! GMRES + ILU(0) ([`krylov`]), in the order of [`bisection`].

pub mod amg;
pub mod bisection;
pub mod condensed;
pub mod descent;
pub mod factor;
pub mod fast;
pub mod krylov;
pub mod matrix;
pub mod newton;
pub mod newton_krylov;
pub mod paper;
pub mod paper_krylov;
#[cfg(feature = "petsc")]
pub mod petsc;
pub mod system;

use serde::{Deserialize, Serialize};

use crate::error::Error;
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
    /// law is too steep, and a descent on the step's energy where both fail.
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

/// How the linear systems of a step are solved.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum LinearKind {
    /// The LDLᵀ factor of the step matrix, the step condensed onto Γ_C ([`system`]).
    Direct,
    /// GMRES + ILU(0) inside a Newton method on all unknowns, nothing condensed
    /// ([`newton_krylov`]).
    Iterative,
    /// [`LinearKind::Direct`] in 2D and for small 3D problems, iterative beyond
    /// ([`LinearKind::resolve`]).
    Auto,
}

impl LinearKind {
    /// The name in scenarios and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            LinearKind::Direct => "direct",
            LinearKind::Iterative => "iterative",
            LinearKind::Auto => "auto",
        }
    }

    /// The share of the machine's memory that `auto` lets the direct path's estimated peak
    /// take before it takes the iterative path.
    pub const AUTO_DIRECT_MEMORY_SHARE: f64 = 0.5;

    /// The most unknowns for which `auto` takes the direct path in 3D: where the two paths'
    /// whole runs cross.
    pub const AUTO_DIRECT_UNKNOWNS_3D: usize = 70_000;

    /// Direct or iterative for a problem of `dim` dimensions and `unknowns` unknowns solved by
    /// `kind` on a machine with `memory` bytes. `auto` is direct always in 2D (the factor has
    /// about 5× A's entries there, and the iterative path pays a Krylov solve per
    /// convexification iterate: 4.5 s against 1.2 s on the reference run), in 3D up to
    /// [`Self::AUTO_DIRECT_UNKNOWNS_3D`] unknowns while the estimated peak of the direct path
    /// ([`crate::resources::estimated_memory`]) is at most half the machine's memory, and
    /// iterative beyond. Measured on the 3D example, 64 steps, whole runs (direct against
    /// iterative): 17.6k unknowns 2.1 s against 3.5 s, 47k 10.6 s against 12.4 s, 98k 33.8 s
    /// against 30.4 s (and 2.3 GiB against 0.45 GiB); the 3D factor's fill grows like N^{4/3},
    /// the iterative path's cost per iteration like N. The paper's solver takes the direct path
    /// wherever its factor fits: on the iterative path it pays a Krylov solve per Uzawa iterate
    /// ([`paper_krylov`]).
    pub fn resolve(self, dim: usize, unknowns: usize, kind: SolverKind, memory: f64) -> LinearKind {
        match self {
            LinearKind::Auto if dim < 3 => LinearKind::Direct,
            LinearKind::Auto => {
                let direct = crate::resources::estimated_memory(dim, unknowns as f64);
                let fits = direct <= Self::AUTO_DIRECT_MEMORY_SHARE * memory;
                if fits && (unknowns <= Self::AUTO_DIRECT_UNKNOWNS_3D || kind == SolverKind::Paper) {
                    LinearKind::Direct
                } else {
                    LinearKind::Iterative
                }
            }
            chosen => chosen,
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
    /// Cap on sweeps of the fast solver's descent ([`descent`]); 0 switches it off.
    pub max_sweeps: usize,
    /// Retry a step that fails as 2, 4, … substeps of k/2, k/4, … ([`crate::time::march`]).
    pub cutback: bool,
    /// The deepest cutback: at most 2^depth substeps of k/2^depth.
    pub max_cutback_depth: usize,
    /// Direct, iterative, or chosen by size.
    pub linear: LinearKind,
    /// Tolerance and caps of the iterative path's Krylov solves.
    pub krylov: krylov::KrylovParams,
}

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            kind: SolverKind::Fast,
            tolerance: 1e-6,
            max_convexification: 200,
            inner_tolerance: 1e-10,
            max_inner: 20_000,
            max_sweeps: 20_000,
            cutback: true,
            max_cutback_depth: 5,
            linear: LinearKind::Auto,
            krylov: krylov::KrylovParams::default(),
        }
    }
}

/// What one time step cost and how it ended.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StepInfo {
    /// Outer (convexification) iterations.
    pub convexification_iterations: usize,
    /// Inner iterations summed over the outer ones: the paper's Uzawa iterations, or the
    /// descent sweeps of the fast solver's convex subproblems in 3D.
    pub inner_iterations: usize,
    /// Last relative increments of u, θ, ξ, ζ: the left sides of (77)–(80) over the right
    /// sides' norms.
    pub increments: [f64; 4],
    /// Semismooth Newton iterations (fast solver).
    pub newton_iterations: usize,
    /// The fast solver went through the convexification loop in this step.
    pub fallback: bool,
    /// Sweeps of the fast solver's descent (0 where Newton or the convexification loop solved
    /// the step).
    pub descent_sweeps: usize,
    /// Substeps the step took: 1 without cutback, 2^depth at the deepest cutback.
    pub substeps: usize,
    /// The deepest cutback of the step (0: none): its shortest substep was k/2^depth.
    pub cutback_depth: usize,
    /// Krylov iterations of the iterative path's linear solves (0 on the direct path).
    pub krylov_iterations: usize,
}

impl StepInfo {
    /// Adds the figures of a substep.
    pub fn absorb(&mut self, other: &StepInfo) {
        self.convexification_iterations += other.convexification_iterations;
        self.inner_iterations += other.inner_iterations;
        self.newton_iterations += other.newton_iterations;
        self.increments = other.increments;
        self.fallback |= other.fallback;
        self.descent_sweeps += other.descent_sweeps;
        self.substeps += other.substeps;
        self.cutback_depth = self.cutback_depth.max(other.cutback_depth);
        self.krylov_iterations += other.krylov_iterations;
    }
}

/// A stop criterion of a step solver, as it is reported when it fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Criterion {
    /// (77): ‖Δu‖_E / ‖u‖_E between convexification iterates.
    IncrementU,
    /// (78): ‖Δθ‖_V / ‖θ‖_V.
    IncrementTheta,
    /// (79): ‖Δξ‖_{L²(Γ_C)} / ‖ξ‖_{L²(Γ_C)}.
    IncrementXi,
    /// (80): ‖Δζ‖_{L²(Γ_C)} / ‖ζ‖_{L²(Γ_C)}.
    IncrementZeta,
    /// max |Δw_τ| / max |w_τ| between iterates on Γ_C.
    IncrementW,
    /// max |Δξ| / max friction bound between iterates on Γ_C (also the inner Uzawa loop's).
    IncrementXiNodal,
    /// max_i |ξ_i − P_{b(|w_i|)}(ξ_i − r w_i)| / min_i b(|w_i|): the nonmonotone friction law
    /// itself at the nodes.
    NodalLaw,
    /// A linear solve of the Newton method gave a non-finite update.
    NonFiniteUpdate,
    /// ‖b̃ − Ã x‖ / ‖b̃‖ of a Krylov solve at its iteration cap.
    LinearResidual,
}

impl Criterion {
    /// What the criterion measures, for messages.
    pub fn describe(&self) -> &'static str {
        match self {
            Criterion::IncrementU => "relative increment of u (77)",
            Criterion::IncrementTheta => "relative increment of θ (78)",
            Criterion::IncrementXi => "relative increment of ξ (79)",
            Criterion::IncrementZeta => "relative increment of ζ (80)",
            Criterion::IncrementW => "max |Δw_τ| / max |w_τ|",
            Criterion::IncrementXiNodal => "max |Δξ| / max friction bound",
            Criterion::NodalLaw => "nodal friction-law residual / smallest bound",
            Criterion::NonFiniteUpdate => "non-finite Newton update",
            Criterion::LinearResidual => "relative residual of the linear solve",
        }
    }
}

/// Why a step solver gave up: the loop, how long it ran, and the criterion that failed with its
/// value and tolerance (the worst one against its tolerance, never one that passed).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepFailure {
    /// `paper` or `fast`.
    pub solver: &'static str,
    /// The loop that hit its cap: `convexification`, `inner augmented-Lagrangian`, …
    pub loop_name: &'static str,
    pub iterations: usize,
    pub criterion: Criterion,
    /// May be +∞ (a relative increment against a zero previous iterate): JSON gets "inf".
    #[serde(serialize_with = "number_or_text")]
    pub value: f64,
    pub tolerance: f64,
    /// A failed Krylov solve's relative residuals, before its first iteration and after each
    /// one, as GMRES estimates them (empty for the other loops; not in JSON then).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub residual_history: Vec<f64>,
}

/// A finite number as a JSON number, ±∞ and NaN (which JSON lacks) as the strings "inf",
/// "-inf", "NaN".
fn number_or_text<S: serde::Serializer>(value: &f64, serializer: S) -> Result<S::Ok, S::Error> {
    if value.is_finite() {
        serializer.serialize_f64(*value)
    } else {
        serializer.serialize_str(&value.to_string())
    }
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the {} solver's {} loop stopped after {} iterations: {} = {:.3e} > tolerance {:e}",
            self.solver,
            self.loop_name,
            self.iterations,
            self.criterion.describe(),
            self.value,
            self.tolerance
        )
    }
}

/// How one step solve ends when it does not return a state.
#[derive(Debug)]
pub enum SolveError {
    /// The nonsmooth solver did not converge: the time loop may cut the step back.
    NotConverged(StepFailure),
    /// Anything else (a load that evaluates to NaN, …): the run stops.
    Other(Error),
}

impl From<Error> for SolveError {
    fn from(e: Error) -> Self {
        SolveError::Other(e)
    }
}

/// The worst of several (criterion, value, tolerance): the one furthest past its tolerance.
pub fn worst_criterion(checks: &[(Criterion, f64, f64)]) -> (Criterion, f64, f64) {
    *checks
        .iter()
        .max_by(|a, b| (a.1 / a.2).total_cmp(&(b.1 / b.2)))
        .expect("at least one criterion")
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
