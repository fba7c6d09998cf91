//! The fast step solver: condensation onto Γ_C + semismooth Newton on the nonmonotone law
//! ([`super::newton`]), with the convexification loop of Problem 17 (Newton inner solves) as
//! the safeguard where the law is too steep.
//!
//! Per step: one solve for the free fields, a few dense Newton iterations on Γ_C, one solve
//! for the full fields — against one solve per convexification iterate for the paper's solver.

use super::condensed::Condensation;
use super::newton::{CondensedStep, NewtonParams, NewtonResult};
use super::paper::{contact_tangential, PaperParams, PaperSolver};
use super::system::{add_contact_terms, tangential_velocities, State, StepSystem};
use super::StepInfo;
use crate::error::Error;
use crate::problem::Problem;

/// Semismooth Newton on the condensed problem, falling back to [`PaperSolver`].
pub struct FastSolver<'a> {
    problem: &'a Problem,
    system: &'a StepSystem,
    paper: PaperSolver<'a>,
    paper_params: PaperParams,
    params: NewtonParams,
    steepness: f64,
}

impl<'a> FastSolver<'a> {
    /// Sets the solver up (the condensation is shared with the fallback solver).
    pub fn new(
        problem: &'a Problem,
        system: &'a StepSystem,
        paper: PaperSolver<'a>,
        paper_params: PaperParams,
        params: NewtonParams,
    ) -> Self {
        let condensation = paper.condensation();
        let n_t = condensation.n_t;
        let max_compliance = (0..n_t).map(|i| condensation.friction[i * n_t + i]).fold(0.0, f64::max);
        let steepness = max_compliance * (-problem.friction.bound_derivative(0.0)).max(0.0);
        FastSolver {
            problem,
            system,
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

    /// One time step: from the state at t_{n−1} to the state at t_n.
    pub fn step(&self, previous: &State) -> Result<(State, StepInfo), Error> {
        let problem = self.problem;
        let tangential = problem.dim() - 1;
        let n = previous.n + 1;
        let t = n as f64 * problem.time_step();
        let base = self.system.rhs(problem, previous, t)?;
        let mut x = base.clone();
        self.system.solve_in_place(&mut x);
        let w_free = tangential_velocities(problem, &x);

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
                    .map_err(|residuals| Error::NotConverged {
                        solver: "fast",
                        loop_name: "convexification",
                        step: n,
                        time: t,
                        iterations: info.convexification_iterations,
                        residuals,
                        tolerance: self.paper_params.tolerance,
                    })?
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
        x.copy_from_slice(&base);
        add_contact_terms(problem, problem.n_w(), &xi, &heat, &mut x);
        self.system.solve_in_place(&mut x);
        let state = self.system.state_from(problem, previous, &x, xi);
        Ok((state, info))
    }

    /// The convexification loop of Problem 17 on the condensed problem, each convex problem
    /// solved by semismooth Newton; stops when w and ξ on Γ_C change by less than ε_conv
    /// (relative to their largest values).
    fn convexified(
        &self,
        step: &CondensedStep,
        w_free: &[f64],
        mut w: Vec<f64>,
        mut xi: Vec<f64>,
        info: &mut StepInfo,
    ) -> Result<NewtonResult, String> {
        let t = step.tangential;
        let n_nodes = self.problem.contact.len();
        let mut last = String::new();
        for m in 1..=self.paper_params.max_convexification {
            let bounds: Vec<f64> = (0..n_nodes)
                .map(|i| self.problem.friction.bound(norm(&w[i * t..(i + 1) * t])))
                .collect();
            let inner = step
                .solve(w_free, w.clone(), xi.clone(), Some(&bounds), self.params)
                .ok_or_else(|| {
                    format!(
                        "semismooth Newton on convex subproblem {m} stalled after {} iterations",
                        self.params.max_iterations
                    )
                })?;
            info.newton_iterations += inner.iterations;
            info.convexification_iterations = m;
            let dw = max_diff(&inner.w, &w);
            let dxi = max_diff(&inner.xi, &xi);
            let w_scale = inner.w.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            let g_scale = bounds.iter().fold(0.0f64, |s, v| s.max(*v));
            w = inner.w;
            xi = inner.xi;
            last = format!(
                "max |Δw_τ| / max |w_τ| = {:.3e}, max |Δξ| / max bound = {:.3e}",
                dw / w_scale.max(f64::MIN_POSITIVE),
                dxi / g_scale.max(f64::MIN_POSITIVE)
            );
            // The frozen bounds lag one iterate behind; also require the nonmonotone law itself
            // to hold to the tolerance at every node (relative to the smallest bound).
            let g_min = bounds.iter().fold(f64::INFINITY, |s, v| s.min(*v));
            let settled = dw <= self.paper_params.tolerance * w_scale && dxi <= self.paper_params.tolerance * g_scale;
            if settled && step.residuals(w_free, &w, &xi, None).1 <= self.paper_params.tolerance * g_min {
                return Ok(NewtonResult {
                    w,
                    xi,
                    iterations: info.newton_iterations,
                });
            }
        }
        Err(last)
    }
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}
