//! The selection of a step solver, in one place: the linear path from `solver.linear` (and
//! the problem's size), then the nonsmooth solver of `solver.kind` on it.
//!
//! | kind \ path | direct (LDLᵀ + condensation on Γ_C) | iterative (Newton matrix + GMRES) |
//! |---|---|---|
//! | `paper` | `convexification-uzawa` ([`PaperSolver`]): the convexification loop, Uzawa inner iterations on Γ_C | `convexification-uzawa-krylov` ([`PaperKrylov`]): the same loop and iterations, each Uzawa iterate a Krylov solve |
//! | `fast` | `condensed-newton` ([`FastSolver`]): Newton on the condensed law, the convexification loop with descent inner solves, the descent where both fail | `newton-krylov` ([`NewtonKrylov`]): the convexification loop with semismooth-Newton inner solves on all unknowns, no descent |
//!
//! `paper` is one algorithm on both paths; `fast` means "the fastest solver of the path": two
//! algorithms, with two names ([`StepSolver::algorithm`], `summary.json`'s `algorithm`).
//!
//! Depends on: the solvers of this folder, [`crate::model`].

use super::amg::VelocityAmg;
use super::direct::{StepSystem, SystemStats};
use super::fast::FastSolver;
use super::iterative::KrylovSystem;
use super::newton::NewtonParams;
use super::newton_krylov::NewtonKrylov;
use super::paper::{PaperParams, PaperSolver};
use super::paper_krylov::PaperKrylov;
use super::{LinearKind, PreconditionerKind, SolveError, SolverKind, SolverParams, StepError, StepInfo};
use crate::model::{Problem, State, StepMatrix};

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
    pub fn new(problem: &Problem, k: f64, params: &SolverParams) -> Result<Self, StepError> {
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
    pub fn new(problem: &'a Problem, linear: LinearSystem, params: &SolverParams) -> Result<Self, StepError> {
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

    /// The algorithm that runs, by its own name: `solver.kind` names one per linear path
    /// (the table of this module's header), and a summary records which one ran.
    pub fn algorithm(&self) -> &'static str {
        match self {
            StepSolver::Paper(_) => "convexification-uzawa",
            StepSolver::PaperKrylov(_) => "convexification-uzawa-krylov",
            StepSolver::Fast(_) => "condensed-newton",
            StepSolver::NewtonKrylov(_) => "newton-krylov",
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
    pub fn time_step(&self) -> f64 {
        match self.system() {
            SystemRef::Direct(system) => system.time_step(),
            SystemRef::Iterative(system) => system.time_step(),
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
