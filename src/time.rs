//! Time stepping: t_n = n k, n = 1..N, each step solved by the chosen nonsmooth solver, with
//! u_n = u_{n−1} + k w_n (eq. (57)) carried in [`State`].
//!
//! **Cutback.** A step whose solver does not converge is retried as two substeps of k/2, each
//! of which may again be halved, down to k/2^depth ([`SolverParams::max_cutback_depth`]). This
//! is the paper's scheme on a finer grid over that interval, not a different method, and it is
//! the remedy the theory points to: the step problem's solution is unique (and the solvers
//! converge) when the law's steepness is small against ρ/k and the viscosity (conditions
//! (16)–(18)), and halving k halves the contact compliance that the steepness is measured
//! against. The step matrices of k/2, k/4, … are factored and condensed when a cutback first
//! needs them and kept for the rest of the run ([`Levels`]). `cutback = false` keeps the
//! paper's uniform k.

use std::cell::{Cell, OnceCell};
use std::time::Instant;

use serde::Serialize;

use crate::error::Error;
use crate::problem::Problem;
use crate::solver::amg::VelocityAmg;
use crate::solver::fast::FastSolver;
use crate::solver::krylov::PreconditionerKind;
use crate::solver::matrix::StepMatrix;
use crate::solver::newton::NewtonParams;
use crate::solver::newton_krylov::{KrylovSystem, NewtonKrylov};
use crate::solver::paper::{PaperParams, PaperSolver};
use crate::solver::paper_krylov::PaperKrylov;
use crate::solver::system::{norm2, State, StepSystem, SystemStats};
use crate::solver::{LinearKind, SolveError, SolverKind, SolverParams, StepInfo};

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

/// The linear part of a step, set up once per step size: factored (direct path) or ordered
/// and preconditioned (iterative path), as [`SolverParams::linear`] resolves for the problem.
pub enum LinearSystem {
    /// The LDLᵀ factor of the step matrix.
    Direct(StepSystem),
    /// The step matrix with its ILU(0), for GMRES.
    Iterative(KrylovSystem),
}

impl LinearSystem {
    /// Assembles the step matrix of step size k and factors or preconditions it.
    pub fn new(problem: &Problem, k: f64, params: &SolverParams) -> Result<Self, Error> {
        let memory = crate::resources::machine_memory().unwrap_or(f64::INFINITY);
        let linear = (params.linear).resolve(problem.dim(), problem.n_unknowns(), params.kind, memory);
        Ok(match linear {
            LinearKind::Iterative => LinearSystem::Iterative(KrylovSystem::new(problem, k, params.krylov)?),
            _ => LinearSystem::Direct(StepSystem::factored(problem, StepMatrix::assemble(problem, k))?),
        })
    }
}

/// A nonsmooth solver of one time step, chosen by [`SolverParams::kind`] and
/// [`SolverParams::linear`], with the linear system of its step size.
pub enum StepSolver<'a> {
    /// The paper's convexification + augmented Lagrangian.
    Paper(PaperSolver<'a>),
    /// Semismooth Newton on the condensed problem.
    Fast(FastSolver<'a>),
    /// Newton on all unknowns with Krylov solves (the iterative path).
    NewtonKrylov(NewtonKrylov<'a>),
    /// The paper's loop with a Krylov solve per Uzawa iterate (the iterative path).
    PaperKrylov(PaperKrylov<'a>),
}

impl<'a> StepSolver<'a> {
    /// Sets the chosen solver up on a linear system (on the direct path: the condensation onto
    /// Γ_C).
    pub fn new(problem: &'a Problem, linear: LinearSystem, params: &SolverParams) -> Result<Self, Error> {
        let paper_params = PaperParams {
            tolerance: params.tolerance,
            max_convexification: params.max_convexification,
            inner_tolerance: params.inner_tolerance,
            max_inner: params.max_inner,
        };
        let system = match linear {
            LinearSystem::Direct(system) => system,
            LinearSystem::Iterative(system) => {
                return Ok(match params.kind {
                    SolverKind::Paper => StepSolver::PaperKrylov(PaperKrylov::new(problem, system, paper_params)?),
                    SolverKind::Fast => StepSolver::NewtonKrylov(NewtonKrylov::new(
                        problem,
                        system,
                        params.tolerance,
                        params.max_convexification,
                    )),
                })
            }
        };
        let paper = PaperSolver::new(problem, system, paper_params)?;
        Ok(match params.kind {
            SolverKind::Paper => StepSolver::Paper(paper),
            SolverKind::Fast => StepSolver::Fast(FastSolver::new(
                problem,
                paper,
                paper_params,
                NewtonParams {
                    tolerance: params.inner_tolerance,
                    max_iterations: 8,
                },
                params.max_sweeps,
            )),
        })
    }

    /// One step of the solver's step size, from `previous` to time `t`.
    pub fn step(&self, previous: &State, t: f64) -> Result<(State, StepInfo), SolveError> {
        match self {
            StepSolver::Paper(solver) => solver.step(previous, t),
            StepSolver::Fast(solver) => solver.step(previous, t),
            StepSolver::NewtonKrylov(solver) => solver.step(previous, t),
            StepSolver::PaperKrylov(solver) => solver.step(previous, t),
        }
    }

    /// The solver's linear system, on whichever path.
    fn system(&self) -> SystemRef<'_> {
        match self {
            StepSolver::Paper(solver) => SystemRef::Direct(solver.system()),
            StepSolver::Fast(solver) => SystemRef::Direct(solver.system()),
            StepSolver::NewtonKrylov(solver) => SystemRef::Iterative(solver.system()),
            StepSolver::PaperKrylov(solver) => SystemRef::Iterative(solver.system()),
        }
    }

    /// The factored step matrix of the direct path (`None` on the iterative path).
    pub fn direct(&self) -> Option<&StepSystem> {
        match self.system() {
            SystemRef::Direct(system) => Some(system),
            SystemRef::Iterative(_) => None,
        }
    }

    /// Which path the solver is on.
    pub fn linear(&self) -> LinearKind {
        match self.system() {
            SystemRef::Direct(_) => LinearKind::Direct,
            SystemRef::Iterative(_) => LinearKind::Iterative,
        }
    }

    /// The step size k of its linear system.
    pub fn step_size(&self) -> f64 {
        match self.system() {
            SystemRef::Direct(system) => system.step_size(),
            SystemRef::Iterative(system) => system.step_size(),
        }
    }

    /// Stored entries of the factor: the LDLᵀ's, or the ILU(0)'s on the iterative path.
    pub fn factor_nnz(&self) -> usize {
        match self.system() {
            SystemRef::Direct(system) => system.factor_nnz(),
            SystemRef::Iterative(system) => system.factor_nnz(),
        }
    }

    /// The iterative path's preconditioner as set up (`auto` resolved; `None` on the direct
    /// path).
    pub fn preconditioner(&self) -> Option<PreconditionerKind> {
        match self.system() {
            SystemRef::Direct(_) => None,
            SystemRef::Iterative(system) => Some(system.preconditioner()),
        }
    }

    /// The AMG coarse correction of the iterative path, where its preconditioner has one.
    pub fn amg(&self) -> Option<&VelocityAmg> {
        match self.system() {
            SystemRef::Direct(_) => None,
            SystemRef::Iterative(system) => system.amg(),
        }
    }

    /// The linear system's work counters.
    pub fn stats(&self) -> SystemStats {
        match self.system() {
            SystemRef::Direct(system) => system.stats(),
            SystemRef::Iterative(system) => system.stats(),
        }
    }
}

/// A [`StepSolver`]'s linear system, borrowed.
enum SystemRef<'s> {
    Direct(&'s StepSystem),
    Iterative(&'s KrylovSystem),
}

/// The step solvers of step sizes k, k/2, k/4, … (cutback levels 0, 1, 2, …): level 0 is
/// given, the others are factored when a cutback first needs them and kept.
pub struct Levels<'a> {
    problem: &'a Problem,
    params: SolverParams,
    levels: Vec<OnceCell<StepSolver<'a>>>,
    /// Seconds spent setting up levels 1, 2, … (factorization and condensation).
    setup_seconds: Cell<f64>,
    /// The work of all levels' set-up (condensation solves), level 0's included.
    setup_stats: Cell<SystemStats>,
}

impl<'a> Levels<'a> {
    /// The levels over a solver of the problem's step size k.
    pub fn new(problem: &'a Problem, params: &SolverParams, first: StepSolver<'a>) -> Self {
        let depth = if params.cutback { params.max_cutback_depth } else { 0 };
        let levels: Vec<OnceCell<StepSolver<'a>>> = (0..=depth).map(|_| OnceCell::new()).collect();
        let setup_stats = Cell::new(first.stats());
        let _ = levels[0].set(first);
        Levels {
            problem,
            params: *params,
            levels,
            setup_seconds: Cell::new(0.0),
            setup_stats,
        }
    }

    /// Sets up level 0 (factorization and condensation) and the empty deeper levels.
    pub fn build(problem: &'a Problem, params: &SolverParams) -> Result<Self, Error> {
        let linear = LinearSystem::new(problem, problem.time_step(), params)?;
        Ok(Levels::new(problem, params, StepSolver::new(problem, linear, params)?))
    }

    /// The deepest level a cutback may use.
    pub fn max_depth(&self) -> usize {
        self.levels.len() - 1
    }

    /// The solver of step size k/2^depth, made on first use.
    pub fn level(&self, depth: usize) -> Result<&StepSolver<'a>, Error> {
        let cell = &self.levels[depth];
        if let Some(solver) = cell.get() {
            return Ok(solver);
        }
        let clock = Instant::now();
        let k = self.problem.time_step() / (1u64 << depth) as f64;
        let linear = LinearSystem::new(self.problem, k, &self.params)?;
        let solver = StepSolver::new(self.problem, linear, &self.params)?;
        let solver = cell.get_or_init(|| solver);
        self.setup_seconds
            .set(self.setup_seconds.get() + clock.elapsed().as_secs_f64());
        self.setup_stats.set(self.setup_stats.get().plus(solver.stats()));
        Ok(solver)
    }

    /// Seconds spent so far setting up the cutback levels (factorization and condensation).
    pub fn cutback_setup_seconds(&self) -> f64 {
        self.setup_seconds.get()
    }

    /// The solver of the problem's own step size.
    pub fn first(&self) -> &StepSolver<'a> {
        self.levels[0].get().expect("level 0 is set at construction")
    }

    /// Work of the time steps so far, summed over the levels made so far, without their
    /// set-up (the condensation's block solves).
    pub fn step_stats(&self) -> SystemStats {
        self.levels
            .iter()
            .filter_map(|cell| cell.get())
            .map(|solver| solver.stats())
            .fold(SystemStats::default(), SystemStats::plus)
            .since(self.setup_stats.get())
    }

    /// One step from `previous` to time `t` at level `depth`, cut into two halves of the next
    /// level where it does not converge; `n` is the time level being computed (for errors).
    fn advance(&self, previous: &State, t: f64, depth: usize, n: usize) -> Result<(State, StepInfo), Error> {
        match self.level(depth)?.step(previous, t) {
            Ok((state, mut info)) => {
                info.substeps = 1;
                info.cutback_depth = depth;
                Ok((state, info))
            }
            Err(SolveError::Other(error)) => Err(error),
            Err(SolveError::NotConverged(failure)) => {
                if depth >= self.max_depth() {
                    return Err(Error::NotConverged {
                        step: n,
                        time: t,
                        cutback_depth: depth,
                        failure,
                    });
                }
                let middle = previous.t + 0.5 * (t - previous.t);
                let (half, mut info) = self.advance(previous, middle, depth + 1, n)?;
                let (end, rest) = self.advance(&half, t, depth + 1, n)?;
                info.absorb(&rest);
                Ok((end, info))
            }
        }
    }
}

/// A run that stopped: why, and the last state it reached (t_n of the last completed step).
#[derive(Debug)]
pub struct Stopped {
    pub error: Error,
    pub last: State,
}

/// The time loop: steps n = 1 … N from the initial state (10), each cut back where it does not
/// converge; `observer` sees every new state with the step's solver figures and may stop the
/// run with an error (the state it saw is then the last one reached). Every run goes through here ([`crate::driver`] observes it for output,
/// progress and timings).
pub fn march(
    problem: &Problem,
    levels: &Levels,
    observer: impl FnMut(&State, &StepInfo) -> Result<(), Error>,
) -> Result<State, Box<Stopped>> {
    march_from(problem, levels, State::initial(problem), observer)
}

/// [`march`] from a state `start` at time level `start.n` (a restart): steps n = start.n + 1 … N.
pub fn march_from(
    problem: &Problem,
    levels: &Levels,
    start: State,
    mut observer: impl FnMut(&State, &StepInfo) -> Result<(), Error>,
) -> Result<State, Box<Stopped>> {
    let mut state = start;
    let k = problem.time_step();
    for n in state.n + 1..=problem.time.steps {
        let t = n as f64 * k;
        let (mut next, info) = match levels.advance(&state, t, 0, n) {
            Ok(step) => step,
            Err(error) => return Err(Box::new(Stopped { error, last: state })),
        };
        // Substeps advanced the level once each; t_n is n k exactly.
        next.n = n;
        next.t = t;
        // The step is complete even where its observer fails (an output error, a stop
        // request): it is the last state reached.
        if let Err(error) = observer(&next, &info) {
            return Err(Box::new(Stopped { error, last: next }));
        }
        state = next;
    }
    Ok(state)
}

/// Sets the solver up and runs all N steps ([`march`]).
pub fn run(
    problem: &Problem,
    params: &SolverParams,
    observer: impl FnMut(&State, &StepInfo) -> Result<(), Error>,
) -> Result<State, Error> {
    march(problem, &Levels::build(problem, params)?, observer).map_err(|stopped| stopped.error)
}
