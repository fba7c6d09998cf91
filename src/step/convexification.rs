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
//! **Cycles.** Where a step problem has several solutions and none near the previous step's
//! state attracts the loop, the loop can go round a cycle instead of converging: at k = 1/8 on a
//! thin slab (104 × 6 × 6 cells of the 3D example) the iterates alternate between two states
//! (644 and 643 slipping nodes, the law's residual 7.5 and 0.98 of the smallest bound) for all
//! 200 iterates, then the way out and the cutback follow. Each iterate is a function of the last
//! (the bounds, the convex problem solved from the iterate; the inner tolerance and the
//! solver's own rules change only as the loop converges or stalls), so a cycle seen three times
//! is one the loop would go round until its cap. A solver that counts its slipping nodes
//! ([`ConvexSubproblem::slipping`]: the iterative path's) has its loop given up once the same
//! slipping count and criteria (to 10⁻³) repeat with a period 2 ≤ p ≤ 8 for three periods; the
//! failure names the period, and the step goes on to its way out or its cutback as at the cap.
//! A front moving one node per iterate changes the slipping count every iterate, a stall
//! (period 1, the stall rule's case) and a converging loop change their criteria: neither is a
//! cycle. Measured on that slab (16 steps of 1/8, 8 sweeps through two layers, before
//! [`super::newton_krylov`]'s backtracking): the same iterates and solution in every step, 109
//! → 52 s, the failed attempts of periods 2 and 4 given up after 6–26 iterates instead of 200
//! (one of period 24, longer than the rule looks for, still ran to the cap). Longer periods
//! would need longer histories and a looser notion of "the same"; the cycles traced there came
//! from unsolved convex problems, which the backtracking now solves.
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

    /// The number of slipping nodes at the iterate just solved, where the solver can tell:
    /// with the criteria, what [`CycleWatch`] compares between iterates. `None`: no cycle rule.
    fn slipping(&self) -> Option<usize> {
        None
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
    let mut watch = CycleWatch::default();
    for m in 1..=params.max_iterations {
        super::abort::check()?;
        checks = subproblem.solve(m, &mut iterate, inner_tolerance, info)?;
        info.convexification_iterations = m;
        super::heartbeat::outer("convexification", m, &checks);
        inner_tolerance = params.inner.next(inner_tolerance, &checks);
        if all_hold(&checks) && subproblem.accept(&mut iterate) {
            return Ok(iterate);
        }
        let cycle = subproblem
            .slipping()
            .and_then(|slipping| watch.record(slipping, &checks));
        if cycle.is_some() {
            return Err(failure(params, m, &checks, cycle));
        }
    }
    Err(failure(params, params.max_iterations, &checks, None))
}

/// The loop's failure after `iterations`, at the worst of its last `checks`.
fn failure(params: &LoopParams, iterations: usize, checks: &[(Criterion, f64, f64)], cycle: Option<u8>) -> SolveError {
    let (criterion, value, tolerance) = worst_criterion(checks);
    SolveError::NotConverged(StepFailure {
        solver: params.solver,
        loop_name: "convexification",
        iterations,
        criterion,
        value,
        tolerance,
        residual_history: Vec::new(),
        cycle,
    })
}

/// Periods up to which [`CycleWatch`] looks for a cycle.
const MAX_CYCLE_PERIOD: u8 = 8;

/// How many times a period repeats before [`CycleWatch`] calls it a cycle.
const CYCLE_REPEATS: usize = 3;

/// Two iterates' criteria count as the same where they agree to this, relatively.
const CYCLE_AGREEMENT: f64 = 1e-3;

/// The cycle rule: a loop whose iterates repeat, the same number of slipping nodes and the
/// same criteria (to [`CYCLE_AGREEMENT`]) every p iterates for [`CYCLE_REPEATS`] periods with
/// 2 ≤ p ≤ [`MAX_CYCLE_PERIOD`], is a map going round a cycle it does not leave (each iterate
/// a function of the last: a cycle seen three times is one the cap would only go round more
/// often), and is given up there instead of at its cap, its failure naming the period. A
/// front that moves one node per iterate changes its slipping nodes every iterate, and a loop
/// that converges changes its increments: neither repeats.
#[derive(Debug, Default)]
struct CycleWatch {
    /// Each iterate's (slipping nodes, criteria), oldest first.
    history: Vec<(usize, Vec<f64>)>,
}

impl CycleWatch {
    /// Records an iterate; the period of the cycle it closes, if any.
    fn record(&mut self, slipping: usize, checks: &[(Criterion, f64, f64)]) -> Option<u8> {
        self.history.push((slipping, checks.iter().map(|c| c.1).collect()));
        let same = |a: &(usize, Vec<f64>), b: &(usize, Vec<f64>)| {
            a.0 == b.0 && (a.1.iter().zip(&b.1)).all(|(x, y)| (x - y).abs() <= CYCLE_AGREEMENT * x.abs().max(y.abs()))
        };
        let h = &self.history;
        let repeats = |p: usize| {
            let window = &h[h.len() - CYCLE_REPEATS * p..];
            (p..window.len()).all(|j| same(&window[j], &window[j - p]))
        };
        // A steady iterate (period 1) is a stall or a front, not a cycle.
        (2..=MAX_CYCLE_PERIOD)
            .filter(|&p| h.len() >= CYCLE_REPEATS * usize::from(p))
            .find(|&p| repeats(usize::from(p)) && !repeats(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A loop whose iterate m has the slipping nodes and criteria `of(m)`.
    struct Scripted<F: FnMut(usize) -> (usize, [f64; 3])> {
        of: F,
        slipping: usize,
    }

    impl<F: FnMut(usize) -> (usize, [f64; 3])> ConvexSubproblem for Scripted<F> {
        type Iterate = ();

        fn solve(
            &mut self,
            m: usize,
            _iterate: &mut (),
            _inner_tolerance: f64,
            _info: &mut StepInfo,
        ) -> Result<Vec<(Criterion, f64, f64)>, SolveError> {
            let (slipping, values) = (self.of)(m);
            self.slipping = slipping;
            let criteria = [Criterion::IncrementW, Criterion::IncrementXiNodal, Criterion::NodalLaw];
            Ok(criteria.into_iter().zip(values).map(|(c, v)| (c, v, 1e-6)).collect())
        }

        fn slipping(&self) -> Option<usize> {
            Some(self.slipping)
        }
    }

    /// How the loop of `of` ends within 200 iterates: Ok(iterates) or Err((iterates, cycle)).
    fn run(of: impl FnMut(usize) -> (usize, [f64; 3])) -> Result<usize, (usize, Option<u8>)> {
        let params = LoopParams {
            solver: "test",
            max_iterations: 200,
            inner: InnerTolerance::Fixed(1e-8),
        };
        let mut info = StepInfo::default();
        match convexify(&mut Scripted { of, slipping: 0 }, (), &params, &mut info) {
            Ok(()) => Ok(info.convexification_iterations),
            Err(SolveError::NotConverged(failure)) => Err((failure.iterations, failure.cycle)),
            Err(other) => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_loop_going_round_a_cycle_is_given_up_once_it_has_gone_round_three_times() {
        // The thin slab's step 6 at k = 1/8 (8 sweeps through 2 layers): two iterates in turn.
        let two = |m: usize| match m % 2 {
            0 => (644, [0.8625, 1.601, 7.534]),
            _ => (643, [1.258, 1.583, 0.9825]),
        };
        assert_eq!(run(two), Err((6, Some(2))));
        // After a start of its own, and with period 4 (the slipping nodes' period).
        let four = |m: usize| match (m < 10, m % 4) {
            (true, _) => (600 + m, [1.0 / m as f64, 1.0, 5.0]),
            (false, 0) => (644, [0.8626, 1.583, 7.490]),
            (false, 1) => (643, [1.258, 1.583, 0.9825]),
            (false, 2) => (644, [0.8625, 1.601, 7.534]),
            _ => (644, [1.257, 1.601, 0.9833]),
        };
        assert_eq!(run(four), Err((21, Some(4))));
    }

    #[test]
    fn fronts_stalls_and_converging_loops_are_no_cycle() {
        // A front: one more node every iterate, the same criteria (the slab's crawl).
        assert_eq!(run(|m| (100 + m, [0.217, 0.5, 0.099])), Err((200, None)));
        // A stall: nothing changes (the stall rule's case, not a cycle's).
        assert_eq!(run(|_| (100, [0.217, 0.5, 0.099])), Err((200, None)));
        // Two iterates in turn, but 1 % apart from one turn to the next: not a cycle by this rule.
        let drifting = |m: usize| (100 + m % 2, [0.5 * (1.0 + 0.01 * m as f64), 0.5, 0.1]);
        assert_eq!(run(drifting), Err((200, None)));
        // A loop that converges while its split alternates.
        let converging = |m: usize| (100 + m % 2, [0.5f64.powi(m as i32); 3]);
        assert_eq!(run(converging), Ok(20));
    }
}
