//! The selection of a step solver, in one place: the linear path from `solver.linear` (and
//! the problem's size), then the nonsmooth solver of `solver.kind` on it.
//!
//! | kind \ path | direct (LDLᵀ + condensation on Γ_C) | iterative (Newton matrix + GMRES) |
//! |---|---|---|
//! | `paper` | `convexification-uzawa` ([`PaperSolver`]): the convexification loop, Uzawa inner iterations on Γ_C | `convexification-uzawa-krylov` ([`PaperKrylov`]): the same loop and iterations, each Uzawa iterate a Krylov solve |
//! | `fast` | `condensed-newton` ([`FastSolver`]): Newton on the condensed law, the convexification loop with descent inner solves, the descent where both fail | `newton-krylov` ([`NewtonKrylov`]): the convexification loop with semismooth-Newton inner solves on all unknowns, Newton on the nonmonotone law where it fails |
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
use super::{
    Criterion, LinearKind, PreconditionerKind, SolveError, SolverKind, SolverParams, StepError, StepFailure, StepInfo,
};
use crate::model::norms::{contact_l2, heat_exchange_multiplier};
use crate::model::{ContactLaws, Problem, State, StepMatrix};

/// The largest problem (unknowns) for which the iterative path's fast solver estimates the
/// contact compliance of the uniqueness report ([`StepSolver::compliance`]).
pub const COMPLIANCE_ESTIMATE_UP_TO: usize = 200_000;

/// Cap on the iterates of the fixed point on a nonlinear heat exchange per step
/// (in [`StepSolver::step`]).
pub const EXCHANGE_ITERATIONS: usize = 50;

/// Cap on the iterates of the fixed point on the contact pressure per step (Coulomb friction,
/// in [`StepSolver::step`]).
pub const PRESSURE_ITERATIONS: usize = 50;

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
        Ok(match params.linear_choice(problem).linear {
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
                        (
                            params.anderson_depth,
                            (params.contact_sweeps, params.prediction),
                            params.backtracking,
                        ),
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
                (params.max_sweeps, params.loop_on_rows_sweeps()),
            )),
        })
    }

    /// One step of the solver's step size, from `previous` to time `t`: the laws on Γ_C at t
    /// with the slip distances of `previous`, and where the heat exchange is nonlinear, the
    /// fixed point on it (docs/laws.md, "Heat exchange").
    pub fn step(&self, previous: &State, t: f64) -> Result<(State, StepInfo), SolveError> {
        let (problem, _) = self.problem_and_tolerance();
        let mut laws =
            ContactLaws::new(problem, t, &previous.slip_distance).map_err(|e| SolveError::Other(e.into()))?;
        if laws.uses_pressure() {
            self.pressure_iteration(previous, laws)
        } else {
            self.step_with_exchange(previous, &mut laws)
        }
    }

    /// One step with the laws `laws` and, where the heat exchange is nonlinear, the fixed
    /// point on it.
    fn step_with_exchange(&self, previous: &State, laws: &mut ContactLaws) -> Result<(State, StepInfo), SolveError> {
        let (problem, _) = self.problem_and_tolerance();
        if problem.exchange.robin().is_some() {
            self.step_with(previous, laws)
        } else {
            self.exchange_iteration(previous, laws)
        }
    }

    /// The step with Coulomb friction, whose bound μ(r) p_i scales with the contact pressure
    /// p_i that the step's own solution carries ([`crate::model::ContactPressure`]): a fixed
    /// point on p, each iterate a whole step with the bounds scaled by the previous iterate's
    /// pressure (p⁽⁰⁾ = p_{n−1}), until p changes by at most ε_conv relative to its largest
    /// value. This is the classic solution of Coulomb friction as a sequence of Tresca
    /// problems (Panagiotopoulos; Haslinger, Hlaváček and Nečas), here with each iterate's
    /// friction law nonmonotone and solved by the chosen solver, on either path. The pressure
    /// depends on the friction stresses only through the body's shear–normal coupling
    /// (Poisson's effect, the contact's curvature, the thermal stress), so the iterates
    /// contract fast where that coupling is weak; beyond [`PRESSURE_ITERATIONS`] the step
    /// fails on the pressure's increment, and the time loop cuts it back.
    fn pressure_iteration(&self, previous: &State, mut laws: ContactLaws) -> Result<(State, StepInfo), SolveError> {
        let (problem, tolerance) = self.problem_and_tolerance();
        let rows = problem
            .pressure
            .as_ref()
            .expect("a law that scales with the pressure has its rows");
        let force = problem.force(laws.t).map_err(|e| SolveError::Other(e.into()))?;
        let n_contact = problem.contact.len();
        let mut pressure = if previous.pressure.len() == n_contact {
            previous.pressure.clone()
        } else {
            vec![0.0; n_contact]
        };
        let mut total = StepInfo::default();
        let mut change = f64::INFINITY;
        for j in 1..=PRESSURE_ITERATIONS {
            laws.set_pressures(&pressure);
            let (mut state, info) = self.step_with_exchange(previous, &mut laws)?;
            total.absorb(&info);
            total.increments = info.increments;
            total.pressure_iterations = j;
            let next = rows.pressures(problem, previous, &state, &force);
            let scale = next.iter().fold(0.0f64, |m, p| m.max(*p));
            change = crate::la::vector::max_abs_diff(&next, &pressure) / scale.max(f64::MIN_POSITIVE);
            super::heartbeat::outer(
                "contact pressure",
                j,
                &[(Criterion::IncrementPressure, change, tolerance)],
            );
            if change <= tolerance {
                state.pressure = next;
                return Ok((state, total));
            }
            pressure = next;
        }
        Err(SolveError::NotConverged(StepFailure {
            solver: self.algorithm(),
            loop_name: "contact pressure",
            iterations: PRESSURE_ITERATIONS,
            criterion: Criterion::IncrementPressure,
            value: change,
            tolerance,
            residual_history: Vec::new(),
            cycle: None,
        }))
    }

    /// One step with the laws `laws`.
    fn step_with(&self, previous: &State, laws: &ContactLaws) -> Result<(State, StepInfo), SolveError> {
        match self {
            StepSolver::Paper(solver) => solver.step(previous, laws),
            StepSolver::Fast(solver) => solver.step(previous, laws),
            StepSolver::NewtonKrylov(solver) => solver.step(previous, laws),
            StepSolver::PaperKrylov(solver) => solver.step(previous, laws),
        }
    }

    /// The step with a nonlinear heat exchange ∂j (a table or an expression of θ, possibly
    /// nonmonotone): a fixed point on the heat-exchange multiplier ζ = −∂j(θ) on Γ_C. Iterate j
    /// solves the whole step (friction and all) with ∂j evaluated at θ^(j) (θ^(0) = Θ_{n−1}),
    /// a nodal load on Γ_C, until ζ changes by at most ε_conv relative in L²(Γ_C): the
    /// paper's criterion (80) between two iterates. Each iterate contracts by about
    /// m_θ ℓ k/(ρ c_p |ω_i|) (the nodal heat capacity against the exchange's slope), so a few
    /// iterates suffice where the step's thermal mass dominates m_θ; beyond
    /// [`EXCHANGE_ITERATIONS`] the step fails on criterion (80), and the time loop cuts it back.
    fn exchange_iteration(&self, previous: &State, laws: &mut ContactLaws) -> Result<(State, StepInfo), SolveError> {
        let (problem, tolerance) = self.problem_and_tolerance();
        let t = laws.t;
        let mut zeta = heat_exchange_multiplier(problem, t, &previous.theta);
        laws.exchange_temperature = Some(previous.theta.clone());
        let mut total = StepInfo::default();
        let mut change = f64::INFINITY;
        for j in 1..=EXCHANGE_ITERATIONS {
            let (state, info) = self.step_with(previous, laws)?;
            total.absorb(&info);
            total.increments = info.increments;
            let next = heat_exchange_multiplier(problem, t, &state.theta);
            let difference: Vec<f64> = next.iter().zip(&zeta).map(|(a, b)| a - b).collect();
            let scale = contact_l2(problem, &next);
            change = contact_l2(problem, &difference) / scale.max(f64::MIN_POSITIVE);
            total.exchange_iterations = j;
            if change <= tolerance {
                return Ok((state, total));
            }
            zeta = next;
            laws.exchange_temperature = Some(state.theta);
        }
        Err(SolveError::NotConverged(StepFailure {
            solver: self.algorithm(),
            loop_name: "heat exchange",
            iterations: EXCHANGE_ITERATIONS,
            criterion: Criterion::IncrementZeta,
            value: change,
            tolerance,
            residual_history: Vec::new(),
            cycle: None,
        }))
    }

    /// λ_max(C) of the contact compliance: the direct path's condensation has it, the
    /// iterative `paper` solver estimates it for its augmentation; for `newton-krylov`, which
    /// never forms C, a power iteration of Krylov solves (to 10⁻³, at most 40) estimates it up
    /// to [`COMPLIANCE_ESTIMATE_UP_TO`] unknowns, and beyond that it is `None` (minutes at 10⁶).
    pub fn compliance(&self) -> Option<f64> {
        match self {
            StepSolver::Paper(solver) => Some(solver.compliance()),
            StepSolver::Fast(solver) => Some(solver.system_compliance()),
            StepSolver::PaperKrylov(solver) => Some(1.0 / solver.augmentation),
            StepSolver::NewtonKrylov(solver) => {
                let (problem, _) = solver.problem_and_tolerance();
                (problem.n_unknowns() <= COMPLIANCE_ESTIMATE_UP_TO)
                    .then(|| super::paper_krylov::spectral_bound_within(problem, solver.system(), 1e-3, 40).ok())
                    .flatten()
            }
        }
    }

    /// The problem and ε_conv.
    fn problem_and_tolerance(&self) -> (&'a Problem, f64) {
        match self {
            StepSolver::Paper(solver) => solver.problem_and_tolerance(),
            StepSolver::Fast(solver) => solver.problem_and_tolerance(),
            StepSolver::NewtonKrylov(solver) => solver.problem_and_tolerance(),
            StepSolver::PaperKrylov(solver) => solver.problem_and_tolerance(),
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
