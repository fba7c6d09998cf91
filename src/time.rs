//! The time loop: t_n = n k, n = 1..N, each step solved by the chosen nonsmooth solver, with
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
//!
//! **The energies stay on the loop's thread, after their step.** Tried: step n's energies
//! computed on a second thread while step n+1 solves, with the observers of step n one step
//! late. The output was byte-identical and the energies were hidden (0.21–0.47 s of the 2D
//! reference run). But on this project's 2-core machine, shared with other work, the solves and
//! the rest of the step slowed by as much: the time loop changed by a median of +0.05 s
//! (−0.35 to +0.36 s) over 20 interleaved pairs. It also delays every observer by a step (a
//! graceful stop discards the step already solved), so it is not done
//! (docs/linear-algebra-study.md, issue 28 item 3).
//!
//! Depends on: [`crate::step`] (the step solvers and their selection), [`crate::model`].

use std::cell::{Cell, OnceCell};
use std::time::Instant;

use crate::model::{Problem, State};
use crate::step::SystemStats;
use crate::step::{LinearSystem, SolveError, SolverParams, StepError, StepFailure, StepInfo, StepSolver};

/// Why the time loop stops on its own.
#[derive(Debug, thiserror::Error)]
pub enum TimeError {
    /// The nonsmooth solver hit its iteration cap, at the step size k and at every cutback.
    #[error(
        "time step {step} (t = {time}) did not converge{}: {failure}",
        cutback_phrase(*cutback_depth)
    )]
    NotConverged {
        step: usize,
        time: f64,
        /// The deepest cutback tried (0: none): substeps of k/2^depth.
        cutback_depth: usize,
        failure: StepFailure,
    },
    /// A step's linear algebra or data failed (no cutback helps).
    #[error(transparent)]
    Step(#[from] StepError),
}

fn cutback_phrase(depth: usize) -> String {
    match depth {
        0 => String::new(),
        d => format!(" even in {} substeps of k/{}", 1usize << d, 1usize << d),
    }
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
    /// Seconds spent on the steps' energies ([`crate::model::energy`]).
    energy_seconds: Cell<f64>,
    /// Why the last step cut back was: its failure at its full length.
    cut_back_because: std::cell::RefCell<Option<StepFailure>>,
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
            energy_seconds: Cell::new(0.0),
            cut_back_because: std::cell::RefCell::new(None),
        }
    }

    /// Sets up level 0 (factorization and condensation) and the empty deeper levels.
    pub fn build(problem: &'a Problem, params: &SolverParams) -> Result<Self, StepError> {
        let linear = LinearSystem::new(problem, problem.time_step(), params)?;
        Ok(Levels::new(problem, params, StepSolver::new(problem, linear, params)?))
    }

    /// The deepest level a cutback may use.
    pub fn max_depth(&self) -> usize {
        self.levels.len() - 1
    }

    /// The solver of step size k/2^depth, made on first use.
    pub fn level(&self, depth: usize) -> Result<&StepSolver<'a>, StepError> {
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

    /// Seconds spent so far on the steps' energies.
    pub fn energy_seconds(&self) -> f64 {
        self.energy_seconds.get()
    }

    /// Why the last step that was cut back was: how its solve at its full length failed (taken:
    /// the next call returns `None` until another step is cut back).
    pub fn take_cutback_reason(&self) -> Option<StepFailure> {
        self.cut_back_because.borrow_mut().take()
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

    /// The energies of the (sub)step from `previous` to `state` ([`crate::model::energy`]); a
    /// rank of a distributed run keeps the elastic force its pass forms in the state, for the
    /// next step's right-hand side ([`State::elastic_force`]).
    fn energy(&self, previous: &State, state: &mut State) -> Result<crate::model::StepEnergy, StepError> {
        let clock = Instant::now();
        let energy = crate::model::step_energy_and_elastic_force(self.problem, previous, state);
        self.energy_seconds
            .set(self.energy_seconds.get() + clock.elapsed().as_secs_f64());
        let (energy, elastic_force) = energy?;
        state.elastic_force = elastic_force;
        Ok(energy)
    }

    /// One step from `previous` to time `t` at level `depth`, cut into two halves of the next
    /// level where it does not converge; `n` is the time level being computed (for errors).
    fn advance(&self, previous: &State, t: f64, depth: usize, n: usize) -> Result<(State, StepInfo), TimeError> {
        // A step cut short from outside (`step::abort`) stops before each (sub)step.
        crate::step::abort::check()?;
        match self.level(depth)?.step(previous, t) {
            Ok((mut state, mut info)) => {
                info.substeps = 1;
                info.cutback_depth = depth;
                info.energy = self.energy(previous, &mut state)?;
                Ok((state, info))
            }
            Err(SolveError::Other(error)) => Err(error.into()),
            Err(SolveError::NotConverged(failure)) => {
                if depth >= self.max_depth() {
                    return Err(TimeError::NotConverged {
                        step: n,
                        time: t,
                        cutback_depth: depth,
                        failure,
                    });
                }
                crate::step::heartbeat::cut_back(previous.t, t, depth + 1, &failure);
                if depth == 0 {
                    *self.cut_back_because.borrow_mut() = Some(failure);
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
pub struct Stopped<E> {
    pub error: E,
    pub last: State,
}

/// The time loop: steps n = 1 … N from the initial state (10), each cut back where it does not
/// converge; `observer` sees every new state with the step's solver figures and may stop the
/// run with an error of its own type `E`, which the loop's own [`TimeError`]s convert into
/// (the state it saw is then the last one reached). Every run goes through here
/// (`crate::driver` observes it for output, progress and timings).
pub fn march<E: From<TimeError>>(
    problem: &Problem,
    levels: &Levels,
    observer: impl FnMut(&State, &StepInfo) -> Result<(), E>,
) -> Result<State, Box<Stopped<E>>> {
    march_from(problem, levels, State::initial(problem), observer)
}

/// [`march`] from a state `start` at time level `start.n` (a restart): steps n = start.n + 1 … N.
pub fn march_from<E: From<TimeError>>(
    problem: &Problem,
    levels: &Levels,
    start: State,
    mut observer: impl FnMut(&State, &StepInfo) -> Result<(), E>,
) -> Result<State, Box<Stopped<E>>> {
    let mut state = start;
    let k = problem.time_step();
    for n in state.n + 1..=problem.time.steps {
        let t = n as f64 * k;
        let (mut next, info) = match levels.advance(&state, t, 0, n) {
            Ok(step) => step,
            Err(error) => {
                return Err(Box::new(Stopped {
                    error: error.into(),
                    last: state,
                }))
            }
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
pub fn run<E: From<TimeError>>(
    problem: &Problem,
    params: &SolverParams,
    observer: impl FnMut(&State, &StepInfo) -> Result<(), E>,
) -> Result<State, E> {
    let levels = Levels::build(problem, params).map_err(|e| E::from(e.into()))?;
    march(problem, &levels, observer).map_err(|stopped| stopped.error)
}
