//! The fast step solver: condensation onto Γ_C + semismooth Newton on the nonmonotone law
//! ([`super::newton`]), with the convexification loop of Problem 17 (Newton inner solves) as
//! the safeguard where the law is too steep.
//!
//! Per step: one solve for the free fields, a few dense Newton iterations on Γ_C, one solve
//! for the full fields — against one solve per convexification iterate for the paper's solver.

use super::condensed::Condensation;
use super::newton::{CondensedStep, NewtonParams, NewtonResult};
use super::paper::{contact_tangential, PaperParams, PaperSolver};
use super::system::{State, StepSystem};
use super::{worst_criterion, Criterion, SolveError, StepFailure, StepInfo};
use crate::problem::Problem;

/// Semismooth Newton on the condensed problem, falling back to [`PaperSolver`].
pub struct FastSolver<'a> {
    problem: &'a Problem,
    paper: PaperSolver<'a>,
    paper_params: PaperParams,
    params: NewtonParams,
    steepness: f64,
}

impl<'a> FastSolver<'a> {
    /// Sets the solver up (the condensation is shared with the fallback solver).
    pub fn new(problem: &'a Problem, paper: PaperSolver<'a>, paper_params: PaperParams, params: NewtonParams) -> Self {
        let condensation = paper.condensation();
        let n_t = condensation.n_t;
        let max_compliance = (0..n_t).map(|i| condensation.friction[i * n_t + i]).fold(0.0, f64::max);
        let steepness = max_compliance * (-problem.friction.bound_derivative(0.0)).max(0.0);
        FastSolver {
            problem,
            paper,
            paper_params,
            params,
            steepness,
        }
    }

    /// max_i C_ii · max(−b'(0), 0): how much faster the friction bound weakens than the
    /// body's contact compliance can follow. Below 1 the nodal step problems are monotone and
    /// Newton on the nonmonotone law is safe; at or above 1 they may have several solutions and
    /// each step goes through the convexification loop (with Newton inner solves) directly.
    pub fn steepness(&self) -> f64 {
        self.steepness
    }

    fn condensation(&self) -> &Condensation {
        self.paper.condensation()
    }

    /// The factored step matrix (shared with the fallback solver).
    pub fn system(&self) -> &StepSystem {
        self.paper.system()
    }

    /// One step of the system's size k, from `previous` to the state at time `t`.
    pub fn step(&self, previous: &State, t: f64) -> Result<(State, StepInfo), SolveError> {
        let problem = self.problem;
        let system = self.system();
        let tangential = problem.dim() - 1;
        let mut free = system.free_step(problem, previous, t)?;
        let w_free = std::mem::take(&mut free.w_free);

        let step = CondensedStep {
            condensation: self.condensation(),
            friction: problem.friction.as_ref(),
            heat_rate: problem.heating.heat(t, 1.0),
            tangential,
            augmentation: self.paper.augmentation,
            lu_cache: Default::default(),
        };
        let guess_w = contact_tangential(problem, &previous.w);
        let guess_xi = previous.xi.clone();
        let mut info = StepInfo::default();
        let direct = if self.steepness < 1.0 {
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
                if self.steepness < 1.0 {
                    info.newton_iterations = self.params.max_iterations;
                }
                self.convexified(&step, &w_free, guess_w, guess_xi, &mut info)
                    .map_err(SolveError::NotConverged)?
            }
        };
        let heat: Vec<f64> = (0..problem.contact.len())
            .map(|i| {
                problem
                    .heating
                    .heat(t, norm(&result.w[i * tangential..(i + 1) * tangential]))
            })
            .collect();
        let xi = result.xi;
        let state = system.loaded_state(problem, previous, t, &mut free, xi, &heat)?;
        Ok((state, info))
    }

    /// The convexification loop of Problem 17 on the condensed problem, each convex problem
    /// solved by semismooth Newton; stops when w and ξ on Γ_C change by less than ε_conv
    /// (relative to their largest values) and the nonmonotone law holds at every node.
    fn convexified(
        &self,
        step: &CondensedStep,
        w_free: &[f64],
        mut w: Vec<f64>,
        mut xi: Vec<f64>,
        info: &mut StepInfo,
    ) -> Result<NewtonResult, StepFailure> {
        let t = step.tangential;
        let n_nodes = self.problem.contact.len();
        let tolerance = self.paper_params.tolerance;
        let mut checks = Vec::new();
        for m in 1..=self.paper_params.max_convexification {
            let bounds: Vec<f64> = (0..n_nodes)
                .map(|i| self.problem.friction.bound(norm(&w[i * t..(i + 1) * t])))
                .collect();
            let g_min = bounds.iter().fold(f64::INFINITY, |s, v| s.min(*v));
            let Some(inner) = step.solve(w_free, w.clone(), xi.clone(), Some(&bounds), self.params) else {
                // The convex subproblem's Newton stalled: report how far the current iterate is
                // from solving the step (the nonmonotone law at the nodes).
                return Err(StepFailure {
                    solver: "fast",
                    loop_name: "semismooth Newton (convex subproblem)",
                    iterations: self.params.max_iterations,
                    criterion: Criterion::NodalLaw,
                    value: step.residuals(w_free, &w, &xi, None).1 / g_min.max(f64::MIN_POSITIVE),
                    tolerance,
                });
            };
            info.newton_iterations += inner.iterations;
            info.convexification_iterations = m;
            let dw = max_diff(&inner.w, &w);
            let dxi = max_diff(&inner.xi, &xi);
            let w_scale = inner.w.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            let g_scale = bounds.iter().fold(0.0f64, |s, v| s.max(*v));
            w = inner.w;
            xi = inner.xi;
            // The frozen bounds lag one iterate behind; also require the nonmonotone law itself
            // to hold to the tolerance at every node (relative to the smallest bound).
            let law = step.residuals(w_free, &w, &xi, None).1;
            checks = vec![
                (Criterion::IncrementW, dw / w_scale.max(f64::MIN_POSITIVE), tolerance),
                (
                    Criterion::IncrementXiNodal,
                    dxi / g_scale.max(f64::MIN_POSITIVE),
                    tolerance,
                ),
                (Criterion::NodalLaw, law / g_min.max(f64::MIN_POSITIVE), tolerance),
            ];
            if checks.iter().all(|&(_, value, tol)| value <= tol) {
                return Ok(NewtonResult {
                    w,
                    xi,
                    iterations: info.newton_iterations,
                });
            }
        }
        let (criterion, value, tolerance) = worst_criterion(&checks);
        Err(StepFailure {
            solver: "fast",
            loop_name: "convexification",
            iterations: self.paper_params.max_convexification,
            criterion,
            value,
            tolerance,
        })
    }
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}
