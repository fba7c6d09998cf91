//! The convexification loop of Problem 17, once, for every solver of both paths.
//!
//! Outer iteration m: freeze the friction bound at the current iterate, g_i = μ(|w_i^(m)|) S,
//! so that −ξ_i ∈ g_i ∂|w_i| is the subdifferential of a convex function; solve that convex
//! (Tresca-type) problem from the current iterate; stop when the solver's criteria between two
//! iterates all hold. What varies between the solvers is the convex problem's solver and the
//! stop test, and they come in through [`ConvexSubproblem`]:
//!
//! | solver | iterate | convex problem solved by | stop test |
//! |---|---|---|---|
//! | [`super::paper`], [`super::paper_krylov`] | the full state, ξ, w, h on Γ_C | Uzawa iterations on ξ | (77)–(80): the relative increments of u, θ, ξ, ζ |
//! | [`super::fast`] (direct path) | w, ξ on Γ_C | the descent's sweeps (or Newton) on the condensed problem | increments of w and ξ on Γ_C and the nodal law, then the law on a fresh stress |
//! | [`super::newton_krylov`] (iterative path) | all unknowns, w, ξ | semismooth Newton iterations with GMRES (where the loop fails: Newton on the nonmonotone law) | increments of w and ξ and the nodal law, once the convex problem's law holds |
//!
//! **The inner tolerance.** The paper's Uzawa loop solves each convex problem to a fixed
//! tolerance ([`InnerTolerance::Fixed`]). The Newton-type inner solvers need each convex problem
//! solved only as far as the loop is converged: to 1 % of the loop's smallest change so far,
//! never looser than a ceiling nor tighter than a floor ([`InnerTolerance::Adaptive`]). The
//! direct path's ceiling is 10⁻⁴; the iterative path's is 10⁻³, where every inner Newton
//! iteration is a Krylov solve ([`super::newton_krylov`] has the measurements).
//!
//! Depends on: the step's figures and failures ([`super::StepInfo`], [`super::StepFailure`]).

use super::{all_hold, worst_criterion, Criterion, SolveError, StepFailure, StepInfo};

/// A convex problem of the loop, solved in place, and the stop test of the loop.
pub(super) trait ConvexSubproblem {
    /// What the loop carries from one outer iteration to the next.
    type Iterate;

    /// Problem 17_n^m: the convex problem with the bounds frozen at `iterate`, solved from it
    /// to `inner_tolerance`; `iterate` becomes its solution. Returns the stop criteria between
    /// the old iterate and the new, as (criterion, value, tolerance). A convex problem that
    /// cannot be solved is a step failure.
    fn solve(
        &mut self,
        m: usize,
        iterate: &mut Self::Iterate,
        inner_tolerance: f64,
        info: &mut StepInfo,
    ) -> Result<Vec<(Criterion, f64, f64)>, SolveError>;

    /// Whether an iterate whose criteria all hold is the step's solution; a solver with a
    /// further test may change the iterate and go on (`false`).
    fn accept(&mut self, _iterate: &mut Self::Iterate) -> bool {
        true
    }
}

/// How tightly each convex problem is solved.
#[derive(Debug, Clone, Copy)]
pub(super) enum InnerTolerance {
    /// The same tolerance for every convex problem.
    Fixed(f64),
    /// 1 % of the loop's smallest change so far, between `floor` and `ceiling` (or `floor`,
    /// if larger).
    Adaptive { floor: f64, ceiling: f64 },
}

impl InnerTolerance {
    fn first(self) -> f64 {
        match self {
            InnerTolerance::Fixed(tolerance) => tolerance,
            InnerTolerance::Adaptive { floor, ceiling } => ceiling.max(floor),
        }
    }

    fn next(self, current: f64, checks: &[(Criterion, f64, f64)]) -> f64 {
        match self {
            InnerTolerance::Fixed(tolerance) => tolerance,
            InnerTolerance::Adaptive { floor, .. } => {
                let change = checks.iter().fold(0.0f64, |m, c| m.max(c.1));
                (0.01 * change).clamp(floor, current)
            }
        }
    }
}

/// The loop's settings.
#[derive(Debug, Clone, Copy)]
pub(super) struct LoopParams {
    /// The solver's name in a failure (`paper`, `fast`, `iterative`).
    pub solver: &'static str,
    /// Cap on outer iterations.
    pub max_iterations: usize,
    /// How tightly each convex problem is solved.
    pub inner: InnerTolerance,
}

/// The convexification loop from `iterate`: outer iterations until the criteria of
/// `subproblem` all hold and it accepts the iterate, or [`LoopParams::max_iterations`] of them
/// (then a failure of the `convexification` loop with the worst criterion of the last iterate).
/// `info.convexification_iterations` counts the outer iterations.
pub(super) fn convexify<C: ConvexSubproblem>(
    subproblem: &mut C,
    mut iterate: C::Iterate,
    params: &LoopParams,
    info: &mut StepInfo,
) -> Result<C::Iterate, SolveError> {
    let mut inner_tolerance = params.inner.first();
    let mut checks = Vec::new();
    for m in 1..=params.max_iterations {
        super::abort::check()?;
        checks = subproblem.solve(m, &mut iterate, inner_tolerance, info)?;
        info.convexification_iterations = m;
        super::heartbeat::outer("convexification", m, &checks);
        inner_tolerance = params.inner.next(inner_tolerance, &checks);
        if all_hold(&checks) && subproblem.accept(&mut iterate) {
            return Ok(iterate);
        }
    }
    let (criterion, value, tolerance) = worst_criterion(&checks);
    Err(SolveError::NotConverged(StepFailure {
        solver: params.solver,
        loop_name: "convexification",
        iterations: params.max_iterations,
        criterion,
        value,
        tolerance,
        residual_history: Vec::new(),
    }))
}
