//! The fast step solver: condensation onto Γ_C + semismooth Newton on the nonmonotone law
//! ([`super::newton`]), with the convexification loop of Problem 17 (its convex problems solved
//! by the sweeps of [`super::descent`]) where the law is too steep, and the descent on the
//! nonconvex energy where both fail.
//!
//! Per step: the forward sweep and the contact block of the backward one for w_τ^free, the
//! iterations on Γ_C (dense, small), the contact block of the forward sweep and a full backward
//! one for the fields ([`super::direct`]): one sparse solve — against half a solve per
//! convexification iterate for the paper's solver.
//!
//! The order of the three methods decides which solution a step with several gets: Newton from
//! the previous step's state where the nodal problems are monotone (steepness below 1, then the
//! solution is unique); otherwise the fixed point of the convexification loop started from the
//! previous step, as the paper's solver (so the two solvers agree wherever the paper's
//! converges); where that loop cycles or stalls, a stationary point of the step's energy
//! reached downhill from the previous step's velocities. Only when the descent too misses the
//! tolerance within its sweeps does the step fail (and the time loop cut it back).
//!
//! **The loop on Γ_C's rows** (`solver.prediction = "loop"` with `solver.contact_sweeps` = s >
//! 0, the default s = 1; the iterative path's counterpart is in [`super::newton_krylov`]). From
//! the loop's second iterate on, each convex problem's descent re-freezes the bounds at its
//! slip after every s sweeps, and its sweeps run Γ_C's order and back: the convexification loop
//! itself, one bound update per s sweeps of the exact condensed rows instead of one per
//! converged convex problem, so the iterate it returns is a fixed point of the loop and the
//! next iterate confirms it. The loop's front moves one ring per update as it moves one ring per
//! iterate, so the step lands on the paper's loop's fixed point where the step has one, in
//! far fewer sweeps (release, the direct path, `solver.contact_sweeps = 0` for the paper's
//! loop): the 3D example at 47k unknowns and k = 1/8 (8 steps) 633 → 40 iterates, 9 724 → 1 699
//! sweeps, 5.9 → 1.0 s on Γ_C, no step left to the descent (one before, which ended on another
//! solution at step 3: 529 slipping nodes; now 525, the iterative path's paper's loop's, fields
//! within 7.5·10⁻⁷ of it); a slab of 104 × 6 × 6 cells at k = 1/8, 16 steps, 1 251 → 80
//! iterates, 42.2 → 5.8 s, the same slip counts; `paper3d.toml` (64 steps) 1 387 → 285 iterates,
//! fields within 6.6·10⁻⁷; the 2D reference run (256 × 64, 64 steps) 510 → 319 iterates, the
//! same slip counts, fields within 7.2·10⁻⁸; `own_laws3d.toml`, `own_laws.toml`, the brake shoe
//! the same solutions; the pad (`pad3d.toml`, several solutions per step) one node apart at
//! one step of 32. Forward sweeps only (the descent's own order) parted from the paper's loop
//! at step 48 of `paper3d.toml` (268 slipping nodes against 269).

use std::cell::OnceCell;

use super::condensed::Condensation;
use super::convexification::{convexify, ConvexSubproblem, InnerTolerance, LoopParams};
use super::descent::{descend, ContactStiffness, DescentParams, Start};
use super::direct::StepSystem;
use super::newton::{CondensedStep, NewtonParams, NewtonResult};
use super::paper::{PaperParams, PaperSolver};
use super::StepError as Error;
use super::{Criterion, SolveError, StepFailure, StepInfo};
use crate::la::vector::max_abs_diff as max_diff;
use crate::model::{contact_tangential, ContactLaws, Problem, State};

/// Semismooth Newton on the condensed problem, falling back to [`PaperSolver`]'s loop and to
/// the descent.
pub struct FastSolver<'a> {
    problem: &'a Problem,
    paper: PaperSolver<'a>,
    paper_params: PaperParams,
    params: NewtonParams,
    /// Cap on the descent's sweeps (0: no descent).
    max_sweeps: usize,
    /// The loop on Γ_C's rows: from the loop's second iterate on, each convex problem solved by
    /// lagged descent sweeps, the bounds frozen again after this many (0: the paper's loop;
    /// `solver.contact_sweeps` where `solver.prediction = "loop"`).
    lag_sweeps: usize,
    /// K = D⁻¹ on Γ_C, inverted at the first convexification iterate (or descent).
    stiffness: OnceCell<ContactStiffness>,
    /// max_i C_ii, the largest nodal contact compliance.
    max_compliance: f64,
}

impl<'a> FastSolver<'a> {
    /// λ_max(C) of the contact compliance ([`PaperSolver::compliance`]).
    pub fn system_compliance(&self) -> f64 {
        self.paper.compliance()
    }

    /// The problem and ε_conv.
    pub(super) fn problem_and_tolerance(&self) -> (&'a Problem, f64) {
        (self.problem, self.paper_params.tolerance)
    }

    /// Sets the solver up (the condensation is shared with the fallback solver); `max_sweeps`
    /// caps the descent's sweeps (0 switches it off), `lag_sweeps` runs the loop on Γ_C's rows
    /// with that many sweeps per bound update (0: the paper's loop).
    pub fn new(
        problem: &'a Problem,
        paper: PaperSolver<'a>,
        paper_params: PaperParams,
        params: NewtonParams,
        (max_sweeps, lag_sweeps): (usize, usize),
    ) -> Self {
        let condensation = paper.condensation();
        let n_t = condensation.n_t;
        let max_compliance = (0..n_t).map(|i| condensation.friction[i * n_t + i]).fold(0.0, f64::max);
        FastSolver {
            problem,
            paper,
            paper_params,
            params,
            max_sweeps,
            lag_sweeps,
            stiffness: OnceCell::new(),
            max_compliance,
        }
    }

    /// max_i C_ii · max_i m_τ,i (m_τ = sup max(−b′, 0), the law's steepest fall): how much
    /// faster the friction bound weakens than the body's contact compliance can follow. Below 1
    /// the nodal step problems are monotone and Newton on the nonmonotone law is safe; at or
    /// above 1 they may have several solutions and each step goes through the convexification
    /// loop (with Newton inner solves) directly.
    pub fn steepness(&self, laws: &ContactLaws) -> f64 {
        self.max_compliance * laws.steepest_fall()
    }

    fn condensation(&self) -> &Condensation {
        self.paper.condensation()
    }

    /// The factored step matrix (shared with the fallback solver).
    pub fn system(&self) -> &StepSystem {
        self.paper.system()
    }

    /// One step of the system's size k, from `previous` to the state at time `laws.t`.
    pub fn step(&self, previous: &State, laws: &ContactLaws) -> Result<(State, StepInfo), SolveError> {
        let problem = self.problem;
        let system = self.system();
        let tangential = problem.dim() - 1;
        let t = laws.t;
        let steepness = self.steepness(laws);
        let mut free = system.free_step(problem, previous, t, laws.exchange_temperature.as_deref())?;
        // The condensed problem in the relative slip z = w_τ − v_F: z = (w_free − v_F) + C ξ + H h.
        let mut w_free = std::mem::take(&mut free.w_free);
        laws.make_relative(&mut w_free);

        let step = CondensedStep {
            condensation: self.condensation(),
            laws,
            tangential,
            augmentation: self.paper.augmentation,
            lu_cache: Default::default(),
        };
        let mut guess_w = contact_tangential(problem, &previous.w);
        laws.make_relative(&mut guess_w);
        let guess_xi = previous.xi.clone();
        let mut info = StepInfo::default();
        let direct = if steepness < 1.0 {
            step.solve(&w_free, guess_w.clone(), guess_xi.clone(), None, self.params)
        } else {
            None
        };
        let result = match direct {
            Some(result) => {
                info.newton_iterations = result.iterations;
                result
            }
            None => {
                // Newton on the nonmonotone law cycles where the law is steep: convexify as the
                // paper does, solving each convex problem by Newton.
                info.fallback = true;
                if steepness < 1.0 {
                    info.newton_iterations = self.params.max_iterations;
                }
                match self.convexified(&step, &w_free, guess_w.clone(), guess_xi, &mut info) {
                    Ok(result) => result,
                    Err(SolveError::NotConverged(_)) if self.max_sweeps > 0 => {
                        self.descent(&step, &w_free, guess_w, &mut info)?
                    }
                    Err(error) => return Err(error),
                }
            }
        };
        let heat = laws.heats(&result.w);
        let xi = result.xi;
        let state = system.loaded_state(problem, previous, t, &mut free, xi, &heat)?;
        Ok((state, info))
    }

    /// K = D⁻¹ on Γ_C for the descent, inverted on first use.
    fn stiffness(&self, tangential: usize) -> Result<&ContactStiffness, Error> {
        if let Some(stiffness) = self.stiffness.get() {
            return Ok(stiffness);
        }
        let condensation = self.condensation();
        let weights: Vec<f64> = self.problem.contact.iter().map(|node| node.weight).collect();
        let stiffness = ContactStiffness::new(condensation, tangential, &weights)?;
        Ok(self.stiffness.get_or_init(|| stiffness))
    }

    /// The convex subproblem of a convexification iterate (bounds frozen at `bounds`), solved
    /// by the descent to `tolerance` from the iterate `(w, ξ)` (`descended`: the previous
    /// subproblem's result, whose gradient ℓ ξ carries over): no factorization, a few sweeps
    /// of O(n_t²) each. Semismooth Newton (one dense n_t × n_t LU per iteration, ≈ 0.1 s each at
    /// 880 tangential unknowns in 3D, where its matrix changes with every slip direction) does
    /// it only where the descent is switched off (`max_sweeps` = 0). Measured on Γ_C: the 2D
    /// reference run 0.54 s with Newton, 0.10 s with the descent; the 3D example 162 s and
    /// 0.8 s.
    fn convex_subproblem(
        &self,
        step: &CondensedStep,
        w_free: &[f64],
        (w, xi, descended): (&[f64], &[f64], bool),
        bounds: &[f64],
        tolerance: f64,
        info: &mut StepInfo,
    ) -> Result<Option<NewtonResult>, Error> {
        if self.max_sweeps == 0 {
            let result = step.solve(w_free, w.to_vec(), xi.to_vec(), Some(bounds), self.params);
            info.newton_iterations += result.as_ref().map_or(self.params.max_iterations, |r| r.iterations);
            return Ok(result);
        }
        let params = DescentParams {
            tolerance,
            max_sweeps: self.max_sweeps,
            handover: 0.0,
            newton: self.params,
            lagged: if descended { self.lag_sweeps } else { 0 },
        };
        let stiffness = self.stiffness(step.tangential)?;
        let start = Start {
            w: w.to_vec(),
            xi: descended.then_some(xi),
        };
        let result = descend(step, stiffness, w_free, start, Some(bounds), &params, &mut 0);
        info.inner_iterations += result.as_ref().map_or(self.max_sweeps, |r| r.iterations);
        Ok(result.ok())
    }

    /// The descent on the step's energy from the previous step's velocities `w`
    /// ([`super::descent`]).
    fn descent(
        &self,
        step: &CondensedStep,
        w_free: &[f64],
        w: Vec<f64>,
        info: &mut StepInfo,
    ) -> Result<NewtonResult, SolveError> {
        let stiffness = self.stiffness(step.tangential)?;
        let params = DescentParams {
            tolerance: self.paper_params.tolerance,
            max_sweeps: self.max_sweeps,
            handover: 1e-2,
            newton: self.params,
            lagged: 0,
        };
        let mut newton_iterations = 0;
        let outcome = descend(
            step,
            stiffness,
            w_free,
            Start::at(w),
            None,
            &params,
            &mut newton_iterations,
        );
        info.newton_iterations += newton_iterations;
        match outcome {
            Ok(result) => {
                info.descent_sweeps = result.iterations;
                Ok(result)
            }
            Err(stall) => {
                info.descent_sweeps = stall.sweeps;
                Err(SolveError::NotConverged(StepFailure {
                    solver: "fast",
                    loop_name: "descent",
                    iterations: stall.sweeps,
                    criterion: Criterion::NodalLaw,
                    value: stall.law_residual,
                    tolerance: self.paper_params.tolerance,
                    residual_history: Vec::new(),
                    cycle: None,
                }))
            }
        }
    }

    /// The convexification loop of Problem 17 ([`convexify`]) on the condensed problem, each
    /// convex problem solved by the descent (or semismooth Newton); stops when w and ξ on Γ_C
    /// change by less than ε_conv (relative to their largest values) and the nonmonotone law
    /// holds at every node.
    fn convexified(
        &self,
        step: &CondensedStep,
        w_free: &[f64],
        w: Vec<f64>,
        xi: Vec<f64>,
        info: &mut StepInfo,
    ) -> Result<NewtonResult, SolveError> {
        let mut subproblem = CondensedConvex {
            solver: self,
            step,
            w_free,
            g_min: f64::INFINITY,
        };
        let params = LoopParams {
            solver: "fast",
            max_iterations: self.paper_params.max_convexification,
            inner: InnerTolerance::Adaptive {
                floor: self.params.tolerance,
                ceiling: 1e-4,
            },
        };
        let iterate = convexify(&mut subproblem, OnContact { w, xi }, &params, info)?;
        Ok(NewtonResult {
            w: iterate.w,
            xi: iterate.xi,
            iterations: info.newton_iterations,
        })
    }
}

/// An iterate of the fast solver's loop: w_τ and ξ on Γ_C.
struct OnContact {
    w: Vec<f64>,
    xi: Vec<f64>,
}

/// The convex problems of the fast solver's loop, on the condensed problem.
struct CondensedConvex<'s, 'a> {
    solver: &'s FastSolver<'a>,
    step: &'s CondensedStep<'s>,
    w_free: &'s [f64],
    /// The smallest bound frozen at the last iterate.
    g_min: f64,
}

impl ConvexSubproblem for CondensedConvex<'_, '_> {
    type Iterate = OnContact;

    /// The bounds frozen at w, the convex problem by [`FastSolver::convex_subproblem`]; the
    /// criteria: max |Δw| / max |w|, max |Δξ| / max g, and the nonmonotone law (the frozen
    /// bounds lag one iterate behind) relative to the smallest bound.
    fn solve(
        &mut self,
        m: usize,
        iterate: &mut OnContact,
        inner_tolerance: f64,
        info: &mut StepInfo,
    ) -> Result<Vec<(Criterion, f64, f64)>, SolveError> {
        let (solver, step) = (self.solver, self.step);
        let t = step.tangential;
        let tolerance = solver.paper_params.tolerance;
        let bounds = step.laws.bounds(&iterate.w);
        let g_min = crate::model::law_scale(bounds.iter().copied());
        self.g_min = g_min;
        let Some(inner) = solver
            .convex_subproblem(
                step,
                self.w_free,
                (&iterate.w, &iterate.xi, m > 1),
                &bounds,
                inner_tolerance,
                info,
            )
            .map_err(SolveError::Other)?
        else {
            // The convex subproblem's solver stalled: report how far the current iterate is
            // from solving the step (the nonmonotone law at the nodes).
            return Err(SolveError::NotConverged(StepFailure {
                solver: "fast",
                loop_name: if t == 1 {
                    "semismooth Newton (convex subproblem)"
                } else {
                    "descent (convex subproblem)"
                },
                iterations: solver.params.max_iterations,
                criterion: Criterion::NodalLaw,
                value: step.law_residual(&iterate.w, &iterate.xi, None) / g_min.max(f64::MIN_POSITIVE),
                tolerance,
                residual_history: Vec::new(),
                cycle: None,
            }));
        };
        let dw = max_diff(&inner.w, &iterate.w);
        let dxi = max_diff(&inner.xi, &iterate.xi);
        let w_scale = inner.w.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let g_scale = bounds.iter().fold(0.0f64, |s, v| s.max(*v));
        let law = step.law_residual(&inner.w, &inner.xi, None);
        iterate.w = inner.w;
        iterate.xi = inner.xi;
        Ok(vec![
            (Criterion::IncrementW, dw / w_scale.max(f64::MIN_POSITIVE), tolerance),
            (
                Criterion::IncrementXiNodal,
                dxi / g_scale.max(f64::MIN_POSITIVE),
                tolerance,
            ),
            (Criterion::NodalLaw, law / g_min.max(f64::MIN_POSITIVE), tolerance),
        ])
    }

    /// The descent's ξ comes from gradients updated sweep by sweep: accept the state on a
    /// fresh one (E1 exactly), where the law must hold too; where it does not, go on from it.
    fn accept(&mut self, iterate: &mut OnContact) -> bool {
        let solver = self.solver;
        let Some(stiffness) = solver.stiffness.get().filter(|_| solver.max_sweeps > 0) else {
            return true;
        };
        let fresh = stiffness.friction_stress(self.step, self.w_free, &iterate.w);
        let law = self.step.law_residual(&iterate.w, &fresh, None);
        iterate.xi = fresh;
        law / self.g_min.max(f64::MIN_POSITIVE) <= solver.paper_params.tolerance
    }
}
