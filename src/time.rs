//! Time stepping: t_n = n k, n = 1..N, each step solved by the chosen nonsmooth solver, with
//! u_n = u_{n−1} + k w_n (eq. (57)) carried in [`State`].

use serde::Serialize;

use crate::error::Error;
use crate::problem::Problem;
use crate::solver::fast::FastSolver;
use crate::solver::newton::NewtonParams;
use crate::solver::paper::{PaperParams, PaperSolver};
use crate::solver::system::{norm2, State, StepSystem};
use crate::solver::{SolverKind, SolverParams, StepInfo};

/// The contact state at one node of Γ_C.
#[derive(Debug, Clone, Serialize)]
pub struct ContactRow {
    /// Mesh node.
    pub node: usize,
    /// Position in the reference configuration.
    pub x: [f64; 3],
    /// ν_i, the node's unit outward normal.
    pub normal: [f64; 3],
    /// The node's tangent basis t_1 … t_{d−1} (2D: ν turned by +90°, the x direction for the
    /// paper's Γ_C).
    pub tangents: Vec<[f64; 3]>,
    /// w_τ in the node's tangent coordinates (d − 1).
    pub w_tau: Vec<f64>,
    /// ξ, the friction stress, in the node's tangent coordinates (d − 1).
    pub xi: Vec<f64>,
    /// The friction bound μ(|w_τ|) S at this node.
    pub bound: f64,
    /// |w_τ| > slip tolerance.
    pub slip: bool,
    /// θ at the node.
    pub theta: f64,
}

impl ContactRow {
    /// ξ as a vector in global coordinates, Σ_k ξ_k t_k.
    pub fn friction_vector(&self) -> [f64; 3] {
        combine(&self.tangents, &self.xi)
    }

    /// w_τ as a vector in global coordinates, Σ_k w_{τ,k} t_k.
    pub fn slip_vector(&self) -> [f64; 3] {
        combine(&self.tangents, &self.w_tau)
    }

    /// |w_τ|.
    pub fn slip_rate(&self) -> f64 {
        norm2(&self.w_tau)
    }
}

fn combine(tangents: &[[f64; 3]], coordinates: &[f64]) -> [f64; 3] {
    let mut v = [0.0; 3];
    for (t, a) in tangents.iter().zip(coordinates) {
        (0..3).for_each(|c| v[c] += a * t[c]);
    }
    v
}

/// The contact rows of a state; a node slips when |w_τ| exceeds `slip_tolerance`.
pub fn contact_rows(problem: &Problem, state: &State, slip_tolerance: f64) -> Vec<ContactRow> {
    let tangential = problem.dim() - 1;
    let w_tau = crate::solver::paper::contact_tangential(problem, &state.w);
    problem
        .contact
        .iter()
        .zip(w_tau.chunks_exact(tangential))
        .zip(state.xi.chunks_exact(tangential))
        .map(|((node, w), xi)| {
            let speed = norm2(w);
            ContactRow {
                node: node.node,
                x: problem.mesh.coords[node.node],
                normal: node.normal,
                tangents: node.tangents.clone(),
                w_tau: w.to_vec(),
                xi: xi.to_vec(),
                bound: problem.friction.bound(speed),
                slip: speed > slip_tolerance,
                theta: state.theta[node.node],
            }
        })
        .collect()
}

/// A nonsmooth solver of one time step, chosen by [`SolverParams::kind`].
pub enum StepSolver<'a> {
    /// The paper's convexification + augmented Lagrangian.
    Paper(PaperSolver<'a>),
    /// Semismooth Newton on the condensed problem.
    Fast(FastSolver<'a>),
}

impl<'a> StepSolver<'a> {
    /// Sets the chosen solver up (the condensation onto Γ_C).
    pub fn new(problem: &'a Problem, system: &'a StepSystem, params: &SolverParams) -> Self {
        let paper_params = PaperParams {
            tolerance: params.tolerance,
            max_convexification: params.max_convexification,
            inner_tolerance: params.inner_tolerance,
            max_inner: params.max_inner,
        };
        let paper = PaperSolver::new(problem, system, paper_params);
        match params.kind {
            SolverKind::Paper => StepSolver::Paper(paper),
            SolverKind::Fast => StepSolver::Fast(FastSolver::new(
                problem,
                system,
                paper,
                paper_params,
                NewtonParams {
                    tolerance: params.inner_tolerance,
                    max_iterations: 8,
                },
            )),
        }
    }

    /// One step from t_{n−1} to t_n.
    pub fn step(&self, previous: &State) -> Result<(State, StepInfo), Error> {
        match self {
            StepSolver::Paper(solver) => solver.step(previous),
            StepSolver::Fast(solver) => solver.step(previous),
        }
    }
}

/// The time loop: steps n = 1 … N from the initial state (10); `observer` sees every new state
/// with the step's solver figures and may stop the run with an error. Every run goes through
/// here ([`crate::driver`] observes it for output, progress and timings).
pub fn march(
    problem: &Problem,
    solver: &StepSolver,
    mut observer: impl FnMut(&State, &StepInfo) -> Result<(), Error>,
) -> Result<State, Error> {
    let mut state = State::initial(problem);
    for _ in 0..problem.time.steps {
        let (next, info) = solver.step(&state)?;
        observer(&next, &info)?;
        state = next;
    }
    Ok(state)
}

/// Sets the solver up and runs all N steps ([`march`]).
pub fn run(
    problem: &Problem,
    system: &StepSystem,
    params: &SolverParams,
    observer: impl FnMut(&State, &StepInfo) -> Result<(), Error>,
) -> Result<State, Error> {
    march(problem, &StepSolver::new(problem, system, params), observer)
}
