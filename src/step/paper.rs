//! The paper's nonsmooth solver (Section 6, Problem 17): a convexification loop around an
//! augmented-Lagrangian solver of a convex Tresca-type problem.
//!
//! Outer loop (m): freeze the friction bound at the previous iterate, g_i = μ(|w_i^(m)|) S, so
//! that −ξ_i ∈ g_i ∂|w_i| is the subdifferential of a convex function. Stop when the relative
//! increments (77)–(80) of u (E-norm), θ (V-norm), ξ and ζ (L²(Γ_C)) are all ≤ ε_conv.
//!
//! Inner loop: the Uzawa form of the augmented Lagrangian on nodal multipliers,
//! ξ_i ← P_{g_i}(ξ_i − r w_i(ξ)), where w(ξ) is the tangential velocity of the linear step
//! problem loaded by ξ and P_g projects onto the ball of radius g. The frictional heat
//! h_τ(|w^(m+1)|) is updated with the same iterates. The step r is 1/λ_max of the contact
//! compliance C, which makes the iteration a contraction for stick nodes (r λ ≤ 1 < 2).
//!
//! The paper runs this in GetFEM on the full system. Here the inner iterations run on the
//! condensed contact problem ([`super::condensed`]): w(ξ) = w_free + C ξ + H h is exact (up to
//! round-off) and costs a dense product on Γ_C instead of a solve; each outer iterate then costs
//! the full fields that (77)–(80) measure: a forward sweep over the contact block of the factor
//! and one backward sweep over all of it, half a solve ([`StepSystem::loaded_state`]).

use super::condensed::Condensation;
use super::convexification::{convexify, ConvexSubproblem, InnerTolerance, LoopParams};
use super::direct::StepSystem;
use super::StepError as Error;
use super::{Criterion, SolveError, StepFailure, StepInfo};
use crate::contact::project_to_ball;
use crate::fem::assembly::NormGrams;
use crate::la::vector::norm2;
use crate::model::norms::relative_increments;
use crate::model::Problem;
use crate::model::{contact_tangential, ContactLaws, State};

/// Settings of the paper's solver.
#[derive(Debug, Clone, Copy)]
pub struct PaperParams {
    /// ε_conv of (77)–(80).
    pub tolerance: f64,
    /// Cap on convexification iterations per step.
    pub max_convexification: usize,
    /// Relative tolerance of the inner augmented-Lagrangian loop (on ξ, relative to max g).
    pub inner_tolerance: f64,
    /// Cap on inner iterations per convex problem.
    pub max_inner: usize,
}

/// The convexification + augmented-Lagrangian solver.
pub struct PaperSolver<'a> {
    problem: &'a Problem,
    /// The norms of the stop criteria (77)–(78), evaluated at every iterate.
    grams: NormGrams,
    system: StepSystem,
    condensation: Condensation,
    params: PaperParams,
    /// Augmentation (Uzawa step) parameter r.
    pub augmentation: f64,
    /// λ_max of the contact compliance C.
    compliance: f64,
}

impl<'a> PaperSolver<'a> {
    /// The problem and ε_conv.
    pub(super) fn problem_and_tolerance(&self) -> (&'a Problem, f64) {
        (self.problem, self.params.tolerance)
    }

    /// Sets the solver up: condenses onto Γ_C and picks the augmentation parameter.
    pub fn new(problem: &'a Problem, system: StepSystem, params: PaperParams) -> Result<Self, Error> {
        let condensation = Condensation::new(problem, &system)?;
        let lambda_max = condensation.friction_spectral_bound();
        let augmentation = if lambda_max > 0.0 { 1.0 / lambda_max } else { 1.0 };
        Ok(PaperSolver {
            problem,
            grams: NormGrams::assemble(&problem.mesh),
            system,
            condensation,
            params,
            augmentation,
            compliance: lambda_max,
        })
    }

    /// λ_max(C), the largest eigenvalue of the contact compliance (the step condensed onto the
    /// tangential unknowns of Γ_C, weighted by ℓ): the step has a unique solution where
    /// m_τ λ_max(C) < 1 (MODEL.md §6).
    pub fn compliance(&self) -> f64 {
        self.compliance
    }

    /// The factored step matrix (of step size k).
    pub fn system(&self) -> &StepSystem {
        &self.system
    }

    /// The condensed compliances on Γ_C.
    pub fn condensation(&self) -> &Condensation {
        &self.condensation
    }

    /// One step of the system's size k, from `previous` to the state at time `laws.t`.
    pub fn step(&self, previous: &State, laws: &ContactLaws) -> Result<(State, StepInfo), SolveError> {
        let t = laws.t;
        let mut free = (self.system).free_step(self.problem, previous, t, laws.exchange_temperature.as_deref())?;
        let w_free = std::mem::take(&mut free.w_free);
        let mut loaded = CondensedStep {
            solver: self,
            previous,
            t,
            free,
            w_free,
        };
        let k = self.system.time_step();
        paper_step(
            (self.problem, &self.grams),
            &self.params,
            self.augmentation,
            "paper",
            (previous, k, laws),
            &mut loaded,
        )
    }
}

/// The linear step problem as the paper's loop sees it: loaded by the nodal friction stresses
/// ξ and the frictional heat h on Γ_C, it gives the tangential velocities w(ξ, h) there (node-
/// major, d − 1 per node, 0 where held), and the full state once the loop accepts (ξ, h). The
/// direct path answers from the condensed compliances ([`CondensedStep`]), the iterative path
/// by a Krylov solve of the whole step ([`super::paper_krylov`]).
pub(super) trait LoadedStep {
    /// w(ξ, h) on Γ_C (the paper's loop makes them relative to the foundation).
    fn velocities(&mut self, xi: &[f64], heat: &[f64], w: &mut [f64]) -> Result<(), SolveError>;
    /// The full state at (ξ, h).
    fn state(&mut self, xi: Vec<f64>, heat: &[f64]) -> Result<State, SolveError>;
}

/// The direct path's answers: w = w_free + C ξ + H h, and the state in half a solve.
struct CondensedStep<'s, 'a> {
    solver: &'s PaperSolver<'a>,
    previous: &'s State,
    t: f64,
    free: super::direct::FreeStep,
    w_free: Vec<f64>,
}

impl LoadedStep for CondensedStep<'_, '_> {
    fn velocities(&mut self, xi: &[f64], heat: &[f64], w: &mut [f64]) -> Result<(), SolveError> {
        self.solver.condensation.velocities(&self.w_free, xi, heat, w);
        Ok(())
    }

    fn state(&mut self, xi: Vec<f64>, heat: &[f64]) -> Result<State, SolveError> {
        let problem = self.solver.problem;
        Ok(self
            .solver
            .system
            .loaded_state(problem, self.previous, self.t, &mut self.free, xi, heat)?)
    }
}

/// The paper's loop (Problem 17) for one step of size k from `previous` to time `laws.t`:
/// convexification ([`convexify`]) around Uzawa iterations with the augmentation r, on
/// whatever answers the loaded step.
pub(super) fn paper_step(
    (problem, grams): (&Problem, &NormGrams),
    params: &PaperParams,
    augmentation: f64,
    solver: &'static str,
    (previous, k, laws): (&State, f64, &ContactLaws),
    step: &mut impl LoadedStep,
) -> Result<(State, StepInfo), SolveError> {
    let t = laws.t;
    // Iterate m = 0 is the previous step's solution (u advanced by k w_{n−1}).
    let mut state = previous.clone();
    state.n = previous.n + 1;
    state.t = t;
    state.u = previous.u.iter().zip(&previous.w).map(|(u, w)| u + k * w).collect();
    let mut w = contact_tangential(problem, &previous.w);
    laws.make_relative(&mut w);
    let heat = laws.heats(&w);
    let iterate = PaperIterate {
        state,
        xi: previous.xi.clone(),
        w,
        heat,
    };
    let mut uzawa = Uzawa {
        problem,
        grams,
        params,
        augmentation,
        solver,
        laws,
        step,
    };
    let loop_params = LoopParams {
        solver,
        max_iterations: params.max_convexification,
        inner: InnerTolerance::Fixed(params.inner_tolerance),
    };
    let mut info = StepInfo::default();
    let iterate = convexify(&mut uzawa, iterate, &loop_params, &mut info)?;
    Ok((iterate.state, info))
}

/// An iterate of the paper's loop: the full fields, and ξ, w_τ and h on Γ_C.
struct PaperIterate {
    state: State,
    xi: Vec<f64>,
    w: Vec<f64>,
    heat: Vec<f64>,
}

/// The convex problems of the paper's loop, solved by Uzawa iterations on ξ over a loaded step.
struct Uzawa<'p, S> {
    problem: &'p Problem,
    /// The E- and V-norms of (77)–(78).
    grams: &'p NormGrams,
    params: &'p PaperParams,
    augmentation: f64,
    solver: &'static str,
    laws: &'p ContactLaws<'p>,
    step: &'p mut S,
}

impl<S: LoadedStep> ConvexSubproblem for Uzawa<'_, S> {
    type Iterate = PaperIterate;

    /// The Uzawa form of the augmented Lagrangian, ξ_i ← P_{g_i}(ξ_i − r w_i(ξ)), with the
    /// frictional heat updated from the same iterates, then the full fields; the criteria are
    /// (77)–(80).
    fn solve(
        &mut self,
        _m: usize,
        iterate: &mut PaperIterate,
        inner_tolerance: f64,
        info: &mut StepInfo,
    ) -> Result<Vec<(Criterion, f64, f64)>, SolveError> {
        let (problem, laws) = (self.problem, self.laws);
        let tangential = problem.dim() - 1;
        let n_contact = problem.contact.len();
        let PaperIterate { state, xi, w, heat } = iterate;
        // Problem 17_n^m: the bound frozen at the previous iterate.
        let bounds = laws.bounds(w);
        let g_max = bounds.iter().cloned().fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let mut converged = false;
        let mut change = f64::INFINITY;
        for _ in 0..self.params.max_inner {
            info.inner_iterations += 1;
            self.step.velocities(xi, heat, w)?;
            laws.make_relative(w);
            change = 0.0;
            for i in 0..n_contact {
                let range = i * tangential..(i + 1) * tangential;
                let mut trial = [0.0; 2];
                for (k, j) in range.clone().enumerate() {
                    trial[k] = xi[j] - self.augmentation * w[j];
                }
                project_to_ball(&mut trial[..tangential], bounds[i]);
                for (k, j) in range.enumerate() {
                    change = change.max((trial[k] - xi[j]).abs());
                    xi[j] = trial[k];
                }
            }
            let mut heat_change: f64 = 0.0;
            let mut heat_scale: f64 = 0.0;
            for (i, h) in heat.iter_mut().enumerate() {
                let new = laws.heat(i, norm2(&w[i * tangential..(i + 1) * tangential]));
                heat_change = heat_change.max((new - *h).abs());
                heat_scale = heat_scale.max(new.abs());
                *h = new;
            }
            if change <= inner_tolerance * g_max && heat_change <= inner_tolerance * heat_scale.max(1.0) {
                converged = true;
                break;
            }
        }
        if !converged {
            return Err(SolveError::NotConverged(StepFailure {
                solver: self.solver,
                loop_name: "inner augmented-Lagrangian",
                iterations: self.params.max_inner,
                criterion: Criterion::IncrementXiNodal,
                value: change / g_max,
                tolerance: inner_tolerance,
                residual_history: Vec::new(),
                cycle: None,
            }));
        }
        // The full fields of this iterate with the converged contact terms.
        self.step.velocities(xi, heat, w)?;
        laws.make_relative(w);
        let next = self.step.state(xi.clone(), heat)?;
        let increments = relative_increments(problem, self.grams, state, &next);
        info.increments = increments;
        *state = next;
        let criteria = [
            Criterion::IncrementU,
            Criterion::IncrementTheta,
            Criterion::IncrementXi,
            Criterion::IncrementZeta,
        ];
        Ok(criteria
            .into_iter()
            .zip(increments)
            .map(|(c, v)| (c, v, self.params.tolerance))
            .collect())
    }
}
