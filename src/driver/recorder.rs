//! The step recorder: each step's figures (a line of `steps.csv`) and the run's tally, the
//! cutbacks, the linear work, the timings, and the summary they make with the set-up's report.

use std::time::Instant;

use super::summary::{
    AmgRecord, CutbackRecord, EnergySummary, FailureRecord, RunStatus, StepRecord, Summary, Tally, Timings, Uniqueness,
};
use super::watch::{RunWarning, Watch};
use super::OutputPlan;
use crate::model::{LawConstants, Problem, State, StepEnergy};
use crate::step::{LinearKind, PreconditionerKind, Prediction, SolverKind, SolverParams, StepInfo, StepSolver};
use crate::time::Levels;

/// The fixed part of a run's report: the linear path as set up.
struct Report {
    /// The step solver's algorithm ([`StepSolver::algorithm`]).
    algorithm: &'static str,
    factor_nnz: usize,
    /// The linear path taken.
    linear: LinearKind,
    /// The iterative path's preconditioner as set up.
    preconditioner: Option<PreconditionerKind>,
    amg: Option<AmgRecord>,
    laws: LawConstants,
    uniqueness: Option<Uniqueness>,
}

impl Report {
    fn new(problem: &Problem, solver: &StepSolver) -> Self {
        let laws = problem.law_constants();
        let uniqueness = (solver.compliance()).map(|c| Uniqueness::new(c, laws.m_tau, problem.time_step()));
        Report {
            laws,
            uniqueness,
            algorithm: solver.algorithm(),
            factor_nnz: solver.factor_nnz(),
            linear: solver.linear(),
            preconditioner: solver.preconditioner(),
            amg: solver.amg().map(|amg| AmgRecord {
                levels: amg.levels(),
                operator_complexity: amg.operator_complexity(),
            }),
        }
    }
}

/// The recorder observer: what the run reports, step by step.
pub(super) struct Recorder<'a, 'p> {
    problem: &'a Problem,
    params: &'a SolverParams,
    plan: &'a OutputPlan,
    levels: &'a Levels<'p>,
    report: Report,
    watch: Watch,
    /// The run's tally (a continued run's goes on from its checkpoint's).
    pub tally: Tally,
    /// The loop's linear work before this process (a continued run's checkpoint has it): the
    /// tally adds this process's to it wherever it is saved.
    solves_before: usize,
    sweeps_before: usize,
    krylov_before: usize,
    timings: Timings,
    /// Each rank's peak memory, MiB, once the ranks of a distributed run have shared them at
    /// its end ([`Recorder::ranks_peak_memory`]).
    ranks_peak_memory: Option<Vec<f64>>,
    /// When the run started, when the march did, and when the step under way did.
    started: Instant,
    marching: Instant,
    step_clock: Instant,
}

impl<'a, 'p> Recorder<'a, 'p> {
    /// The recorder of a run started at `started`, with `tally` so far and the set-up's
    /// `timings`.
    pub fn new(
        problem: &'a Problem,
        params: &'a SolverParams,
        plan: &'a OutputPlan,
        levels: &'a Levels<'p>,
        tally: Tally,
        timings: Timings,
        started: Instant,
    ) -> Self {
        Recorder {
            problem,
            params,
            plan,
            levels,
            report: Report::new(problem, levels.first()),
            watch: Watch::new(problem),
            solves_before: tally.solves,
            sweeps_before: tally.sweeps,
            krylov_before: tally.krylov_iterations,
            tally,
            timings,
            ranks_peak_memory: None,
            started,
            marching: started,
            step_clock: started,
        }
    }

    /// The march starts: its clock, and the first step's.
    pub fn marching(&mut self) {
        self.marching = Instant::now();
        self.step_clock = self.marching;
    }

    /// Records the step that reached `state`: its `steps.csv` line (returned), its figures in
    /// the tally, its cutback.
    pub fn step(&mut self, state: &State, info: &StepInfo) -> StepRecord {
        let problem = self.problem;
        let (residual, slip_nodes) = law_residual(problem, state, self.plan.slip_tolerance);
        let step = StepRecord {
            n: state.n,
            t: state.t,
            convexification_iterations: info.convexification_iterations,
            inner_iterations: info.inner_iterations,
            newton_iterations: info.newton_iterations,
            descent_sweeps: info.descent_sweeps,
            krylov_iterations: info.krylov_iterations,
            substeps: info.substeps,
            cutback_depth: info.cutback_depth,
            // Only the paper's solver measures (77)–(80); the fast solver stops on the nodal
            // law and leaves them unset, which a 0 would misreport as converged.
            increments: match self.params.kind {
                SolverKind::Paper => info.increments,
                SolverKind::Fast => [f64::NAN; 4],
            },
            law_residual: residual,
            slip_nodes,
            stick_nodes: problem.contact.len() - slip_nodes,
            seconds: self.step_clock.elapsed().as_secs_f64(),
            energy: self.cumulative_energy(&info.energy),
            energy_residual: info.energy.relative_residual(),
            nonmonotone_newton_iterations: info.nonmonotone_newton_iterations,
            anderson_combinations: info.anderson_combinations,
            predicted_iterates: info.predicted_iterates,
            way_out_iterates: info.way_out_iterates,
            backtracked_newton_iterations: info.backtracked_newton_iterations,
            heat_residual: info.energy.relative_heat_residual(),
        };
        self.tally.add_step(info, step);
        if info.cutback_depth > 0 {
            self.tally.cutbacks.push(CutbackRecord {
                step: state.n,
                t: state.t,
                depth: info.cutback_depth,
                substeps: info.substeps,
                reason: self.levels.take_cutback_reason().map(|failure| failure.to_string()),
            });
        }
        step
    }

    /// The energies from t = 0 to the end of a step of energies `step`: the last record's
    /// (none: the step is the first) with the step's added.
    fn cumulative_energy(&self, step: &StepEnergy) -> StepEnergy {
        let mut total = self.tally.steps.last().map(|s| s.energy).unwrap_or_default();
        total.absorb(step);
        total
    }

    /// The log line of a step whose convexification loop failed and a way out of the iterative
    /// path finished it ([`crate::step`]'s Newton–Krylov solver: the loop with the law's
    /// predicted bounds, then Newton on the nonmonotone law); none where the loop converged.
    pub fn way_out(&self, step: &StepRecord) -> Option<String> {
        let finished = if step.nonmonotone_newton_iterations > 0 {
            format!(
                "Newton on the nonmonotone law finished the step ({} iterations)",
                step.nonmonotone_newton_iterations
            )
        } else if step.way_out_iterates > 0 {
            let hint = match self.params.contact_sweeps {
                0 => "; `solver.contact_sweeps = 1`, the default, predicts them from the start",
                _ => "",
            };
            format!(
                "the loop with the law's predicted bounds finished the step ({} iterates{hint})",
                step.way_out_iterates
            )
        } else {
            return None;
        };
        Some(format!(
            "step {} (t = {}): the convexification loop did not converge in {} iterates; {finished}",
            step.n, step.t, self.params.max_convexification
        ))
    }

    /// The warnings the step to `state` (its record `step`) raises, kept in the tally.
    pub fn watch(&mut self, state: &State, step: &StepRecord) -> Vec<RunWarning> {
        let new = self.watch.check(self.problem, state, step, &self.tally.warnings);
        self.tally.warnings.extend(new.iter().cloned());
        new
    }

    /// The step's observers are done: the next step's clock starts.
    pub fn next_step(&mut self) {
        self.step_clock = Instant::now();
    }

    /// The march ended, having waited `waited` seconds for output: the time-stepping timings.
    pub fn marched(&mut self, waited: f64) {
        let timings = &mut self.timings;
        timings.time_stepping = self.marching.elapsed().as_secs_f64() - waited;
        let stats = self.levels.step_stats();
        timings.linear_solves = stats.solve_seconds;
        timings.right_hand_sides = stats.rhs_seconds;
        timings.cutback_setup = self.levels.cutback_setup_seconds();
        timings.energies = self.levels.energy_seconds();
        timings.contact_solver = timings.time_stepping
            - timings.linear_solves
            - timings.right_hand_sides
            - timings.cutback_setup
            - timings.energies;
    }

    /// The seconds spent on the frames themselves (on the writer's thread, or inline).
    pub fn frames_written(&mut self, seconds: f64) {
        self.timings.frames = seconds;
    }

    /// The linear work of the whole run so far into the tally.
    pub fn count_work(&mut self) {
        let stats = self.levels.step_stats();
        self.tally.solves = self.solves_before + stats.solves;
        self.tally.sweeps = self.sweeps_before + stats.sweeps;
        self.tally.krylov_iterations = self.krylov_before + stats.krylov_iterations;
    }

    /// Each rank's peak memory (MiB, in rank order): the summary's is then the largest.
    pub fn ranks_peak_memory(&mut self, peaks: Vec<f64>) {
        self.ranks_peak_memory = Some(peaks);
    }

    /// The output time the run waited for so far, and the total time.
    pub fn ended(&mut self, output: f64) {
        self.timings.output = output;
        self.timings.total = self.problem.build_seconds + self.started.elapsed().as_secs_f64();
    }

    /// The output time recorded so far ([`Recorder::ended`]).
    pub fn output_seconds(&self) -> f64 {
        self.timings.output
    }

    /// The run's summary as it stands.
    /// The laws' constants, what they fail, and the uniqueness condition: the run header's
    /// lines before the first step.
    pub fn header_lines(&self) -> Vec<String> {
        let laws = &self.report.laws;
        let mut lines: Vec<String> = (laws.friction.iter())
            .map(|f| {
                let parts = if f.parts.is_empty() {
                    "every contact part".to_string()
                } else {
                    f.parts.join(", ")
                };
                format!(
                    "friction {} on {parts}: c_τ = {:.4e}, m_τ = {:.4e}",
                    f.law, f.c_tau, f.m_tau
                )
            })
            .collect();
        lines.push(format!(
            "heat exchange {}: m_θ = {:.4e}; frictional heating: L_τ = {:.4e}",
            laws.heat_exchange, laws.m_theta, laws.l_tau
        ));
        lines.extend(laws.warnings.iter().map(|w| format!("warning: {w}")));
        lines.extend(self.watch.header_line());
        lines.push(match &self.report.uniqueness {
            Some(u) => u.line(),
            None => "uniqueness: not computed (the iterative path's fast solver never forms the contact compliance)"
                .to_string(),
        });
        lines.push(self.linear_line());
        lines.extend(self.loop_line());
        lines
    }

    /// How the fast solver's convexification loop runs (the paper's solver has its own):
    /// `convexification loop: …`.
    fn loop_line(&self) -> Option<String> {
        let params = &self.params;
        if params.kind != SolverKind::Fast {
            return None;
        }
        let n = params.contact_sweeps;
        let every = match n {
            1 => "every sweep".to_string(),
            _ => format!("every {n} sweeps"),
        };
        let layers = params.krylov.condensed_layers;
        let through = match (self.report.linear, layers) {
            (LinearKind::Direct, _) => " of the exact condensed rows".to_string(),
            (_, 0) => ", the body held".to_string(),
            (_, 1) => " through 1 layer of the body".to_string(),
            (_, l) => format!(" through {l} layers of the body"),
        };
        let line = match (n, params.prediction) {
            (0, _) => "the paper's, one convex problem per iterate (solver.contact_sweeps = 0)".to_string(),
            (_, Prediction::Law) if self.report.linear == LinearKind::Direct => {
                "the paper's, one convex problem per iterate (solver.prediction = \"law\" is the iterative path's)"
                    .to_string()
            }
            (_, Prediction::Loop) => format!(
                "run on Γ_C's rows from its second iterate, the bounds updated after {every}{through} (solver.prediction = \"loop\")"
            ),
            (_, Prediction::Law) => format!(
                "bounds predicted by {n} sweep{} of the law over Γ_C{through} (solver.prediction = \"law\")",
                if n == 1 { "" } else { "s" }
            ),
        };
        Some(format!("convexification loop: {line}"))
    }

    /// The linear path taken and why ([`SolverParams::linear_choice`]): `linear path: direct
    /// (auto: …)`.
    fn linear_line(&self) -> String {
        let choice = self.params.linear_choice(self.problem);
        format!("linear path: {} ({})", self.report.linear.name(), choice.reason)
    }

    pub fn summary(&self, status: RunStatus, failure: Option<FailureRecord>) -> Summary {
        let (problem, tally, report) = (self.problem, &self.tally, &self.report);
        Summary {
            dim: problem.dim(),
            nodes: problem.mesh.n_nodes(),
            elements: problem.mesh.n_cells(),
            velocity_unknowns: problem.velocity.n_free,
            temperature_unknowns: problem.temperature.n_free,
            unknowns: problem.n_unknowns(),
            contact_nodes: problem.contact.len(),
            steps: problem.time.steps,
            time_step: problem.time_step(),
            solver: self.params.kind.name().to_string(),
            algorithm: report.algorithm.to_string(),
            laws: report.laws.clone(),
            uniqueness: report.uniqueness,
            slip_tolerance: self.plan.slip_tolerance,
            convexification_iterations: tally.convexification_iterations,
            inner_iterations: tally.inner_iterations,
            max_convexification_per_step: tally.max_convexification_per_step,
            newton_iterations: tally.newton_iterations,
            exchange_iterations: tally.exchange_iterations,
            pressure_iterations: tally.pressure_iterations,
            fallback_steps: tally.fallback_steps,
            descent_steps: tally.descent_steps,
            descent_sweeps: tally.descent_sweeps,
            nonmonotone_newton_steps: tally.nonmonotone_newton_steps,
            nonmonotone_newton_iterations: tally.nonmonotone_newton_iterations,
            anderson_combinations: tally.anderson_combinations,
            predicted_iterates: tally.predicted_iterates,
            backtracked_newton_iterations: tally.backtracked_newton_iterations,
            krylov_iterations: tally.krylov_iterations,
            linear: report.linear.name().to_string(),
            preconditioner: report.preconditioner.map(|p| p.name().to_string()),
            amg: report.amg,
            linear_solves: tally.solve_equivalents(),
            full_sweeps: tally.full_sweeps(),
            factor_nnz: report.factor_nnz,
            peak_memory_mib: match &self.ranks_peak_memory {
                Some(peaks) => Some(peaks.iter().fold(0.0, |m: f64, &p| m.max(p))),
                None => crate::resources::peak_memory_mib(),
            },
            peak_memory_per_rank_mib: self.ranks_peak_memory.clone(),
            max_law_residual: tally.max_law_residual,
            cutbacks: tally.cutbacks.clone(),
            status,
            run_id: tally.run_id.clone(),
            scenario_fingerprint: self.plan.fingerprint.clone(),
            restarts: tally.restarts.clone(),
            failure,
            timings: self.timings.clone(),
            outputs: tally.outputs.clone(),
            energy: EnergySummary::of(&tally.steps),
            warnings: tally.warnings.clone(),
            outcome: status.outcome(tally.warnings.len()),
        }
    }
}

/// The largest nodal friction-law residual of a state on Γ_C, relative to μ(0)S, and the
/// number of Γ_C nodes that slip (|w_τ| > the slip tolerance, as in the contact CSV).
///
/// The law is the one the step solved (its time, the slip distances before it).
fn law_residual(problem: &Problem, state: &State, slip_tolerance: f64) -> (f64, usize) {
    let tangential = problem.dim() - 1;
    let mut worst: f64 = 0.0;
    let mut slip = 0;
    let Ok(laws) = crate::model::ContactLaws::of_state(problem, state) else {
        return (f64::NAN, 0);
    };
    let w_tau = laws.slip(&state.w);
    let chunks = w_tau.chunks_exact(tangential).zip(state.xi.chunks_exact(tangential));
    for (i, (w, xi)) in chunks.enumerate() {
        worst = worst.max(crate::contact::friction::law_residual(
            |r| laws.bound(i, r),
            w,
            xi,
            slip_tolerance,
        ));
        slip += usize::from(crate::la::vector::norm2(w) > slip_tolerance);
    }
    (worst / laws.largest_bound_at_rest().max(f64::MIN_POSITIVE), slip)
}
