//! A whole run, as the `run` command does it: claim the output folder, factor, step through
//! time, write the results, and account for the time spent. The problem comes built
//! ([`crate::model::ProblemBuilder`]); the time loop is [`time::march_from`], observed here
//! for output, checkpoints, progress, logs and timings.
//!
//! ```text
//! claim the folder → factor or precondition (time::LinearSystem::new) → set the solver up → steps (time::march_from)
//!   each step: steps.csv record, log line; output steps: the frame to the writer thread, which
//!   writes it and rewrites solution.pvd (and steps.csv, at most every 10 s);
//!   every `checkpoint_every` steps: the frames sent awaited, checkpoint.bin, steps.csv,
//!   summary.json ("running")
//! → the frames sent awaited → summary.json ("completed", or "failed" / "interrupted" with the
//!   last state written)
//! ```
//!
//! The frames are written on a thread beside the time loop (module `writer`: owned copies
//! through a channel of one frame, so memory stays bounded), so that the loop, which mostly uses
//! one core, does not wait for them; `RunOptions::inline_frames` writes them on the loop's
//! thread instead, into the same bytes.
//!
//! **The folder never lies.** A run owns its folder ([`output::folder`]): a lock, and another
//! run's results are refused, replaced (`overwrite`) or continued (`restart`). `summary.json`
//! says `running` from the start, `solution.pvd` lists exactly the frames present, and a run
//! that stops early (a step that does not converge even after the cutbacks, an output error, a
//! signal) still leaves the frames written so far, the last completed state as a frame and a
//! checkpoint, and `summary.json` with the status and the reason (step, time, the criterion
//! that failed with its value and tolerance, or the signal).

mod stop;
mod summary;
mod writer;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

use crate::error::Error;
use crate::output::checkpoint::{self, Checkpoint, CheckpointError, Identity};
use crate::output::folder::{Existing, RunFolder};
use crate::output::{self, fields, Compression, Field, Grid, PvdEntry};
use crate::model::Problem;
use crate::step::PreconditionerKind;
use crate::model::State;
use crate::step::{LinearKind, SolverKind, SolverParams, StepInfo};
use crate::model::{contact_rows, ContactRow};
use crate::step::{LinearSystem, StepSolver};
use crate::time::{self, Levels, Stopped};

pub use stop::StopFlag;
use writer::FrameWriter;

pub use summary::{
    AmgRecord, CutbackRecord, FailureRecord, OutputRecord, RunStatus, StepRecord, Summary, Tally, Timings,
};

/// How to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Where to write results; `None` writes nothing.
    pub out_dir: Option<PathBuf>,
    /// Draw a progress bar on stderr (a log line now and then where stderr is not a terminal).
    pub progress: bool,
    /// Print a line on stderr for every cutback (batch logs); the error that stops a run is
    /// returned to the caller, which reports it.
    pub log: bool,
    /// Replace another run's results found in `out_dir` (otherwise the folder is refused).
    pub overwrite: bool,
    /// Set from outside (a signal handler, another thread) to stop after the current step.
    pub stop: Option<StopFlag>,
    /// Continue this checkpoint's run (its folder is `out_dir`) instead of starting at t = 0.
    pub restart: Option<Restart>,
    /// Write the frames on the time loop's thread, the loop waiting for each, instead of on a
    /// writer thread beside it (the default; `writer`): the same files either way.
    pub inline_frames: bool,
}

/// A checkpoint to continue from, and where it was read (for messages).
#[derive(Debug, Clone)]
pub struct Restart {
    pub path: PathBuf,
    pub checkpoint: Checkpoint,
}

impl Restart {
    /// Reads `path` ([`checkpoint::read`]).
    pub fn read(path: &Path) -> Result<Self, Error> {
        Ok(Restart {
            path: path.to_path_buf(),
            checkpoint: checkpoint::read(path)?,
        })
    }
}

/// The checkpoint's file name in an output folder.
pub const CHECKPOINT_FILE: &str = crate::output::folder::CHECKPOINT_FILE;

/// What a run records, and when.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputPlan {
    /// Time levels n at which to record the contact state and write files.
    pub steps: Vec<usize>,
    /// Write a `.vtu` per output time and a `.pvd` collection.
    pub vtk: bool,
    /// zlib-compress the `.vtu` arrays ([`output::Compression`]).
    pub compress: bool,
    /// Write a contact CSV per output time.
    pub csv: bool,
    /// A contact node slips when |w_τ| exceeds this [m/s].
    pub slip_tolerance: f64,
    /// The run's input as text, saved beside the results as `scenario.toml`.
    pub record: Option<String>,
    /// The input's fingerprint: a checkpoint continues only a run of the same one.
    pub fingerprint: Option<String>,
    /// Write a checkpoint every this many steps (`None`: only where the run stops early).
    pub checkpoint_every: Option<usize>,
}

impl Default for OutputPlan {
    fn default() -> Self {
        OutputPlan {
            steps: Vec::new(),
            vtk: true,
            compress: true,
            csv: true,
            slip_tolerance: 1e-6,
            record: None,
            fingerprint: None,
            checkpoint_every: None,
        }
    }
}

/// Runs a problem end to end.
pub fn run(
    problem: &Problem,
    params: &SolverParams,
    plan: &OutputPlan,
    options: &RunOptions,
) -> Result<Summary, Error> {
    run_observed(problem, params, plan, options, |_, _, _| ()).map(|run| run.summary)
}

/// Runs without writing files or drawing progress (tests and studies); also returns the state
/// at T.
pub fn run_quiet(problem: &Problem, params: &SolverParams, plan: &OutputPlan) -> Result<(Summary, State), Error> {
    run_observed(problem, params, plan, &RunOptions::default(), |_, _, _| ()).map(|run| (run.summary, run.state))
}

/// A finished run: its summary and the state at T.
pub struct Run {
    pub summary: Summary,
    pub state: State,
}

/// The fixed part of a run's report: sizes and set-up.
struct Setup<'a> {
    problem: &'a Problem,
    params: &'a SolverParams,
    plan: &'a OutputPlan,
    factor_nnz: usize,
    /// The linear path taken.
    linear: LinearKind,
    /// The iterative path's preconditioner as set up.
    preconditioner: Option<PreconditionerKind>,
    amg: Option<AmgRecord>,
}

impl Setup<'_> {
    fn summary(&self, tally: &Tally, status: RunStatus, failure: Option<FailureRecord>, timings: Timings) -> Summary {
        let problem = self.problem;
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
            slip_tolerance: self.plan.slip_tolerance,
            convexification_iterations: tally.convexification_iterations,
            inner_iterations: tally.inner_iterations,
            max_convexification_per_step: tally.max_convexification_per_step,
            newton_iterations: tally.newton_iterations,
            fallback_steps: tally.fallback_steps,
            descent_steps: tally.descent_steps,
            descent_sweeps: tally.descent_sweeps,
            krylov_iterations: tally.krylov_iterations,
            linear: self.linear.name().to_string(),
            preconditioner: self.preconditioner.map(|p| p.name().to_string()),
            amg: self.amg,
            linear_solves: tally.solve_equivalents(),
            full_sweeps: tally.full_sweeps(),
            factor_nnz: self.factor_nnz,
            peak_memory_mib: crate::resources::peak_memory_mib(),
            max_law_residual: tally.max_law_residual,
            cutbacks: tally.cutbacks.clone(),
            status,
            run_id: tally.run_id.clone(),
            scenario_fingerprint: self.plan.fingerprint.clone(),
            restarts: tally.restarts.clone(),
            failure,
            timings,
            outputs: tally.outputs.clone(),
        }
    }
}

/// The files of a run in its folder.
struct Files<'a> {
    folder: RunFolder,
    plan: &'a OutputPlan,
    problem: &'a Problem,
}

impl Files<'_> {
    fn dir(&self) -> &Path {
        self.folder.dir()
    }

    fn io(&self, name: &str) -> impl FnOnce(std::io::Error) -> Error + '_ {
        let path = self.dir().join(name);
        move |source| output::OutputError::Io { path, source }.into()
    }

    fn summary(&self, summary: &Summary) -> Result<(), Error> {
        let json = serde_json::to_vec_pretty(summary).expect("a summary serializes");
        output::write_atomic(&self.dir().join("summary.json"), &json).map_err(self.io("summary.json"))
    }

    fn steps(&self, tally: &Tally) -> Result<(), Error> {
        let rows: Vec<Vec<f64>> = tally.steps.iter().map(StepRecord::row).collect();
        output::write_csv(&self.dir().join("steps.csv"), &StepRecord::HEADER, &rows)?;
        Ok(())
    }

    /// The frame of `state` (and its `.pvd` entry, the collection rewritten).
    fn frame(&self, state: &State, record: &OutputRecord, tally: &mut Tally) -> Result<(), Error> {
        write_snapshot(self.problem, self.plan, state, record, self.dir(), &mut tally.frames)?;
        if self.plan.vtk {
            output::write_pvd(&self.dir().join("solution.pvd"), &tally.frames)?;
        }
        Ok(())
    }

    fn checkpoint(&self, state: &State, tally: &Tally) -> Result<(), Error> {
        let checkpoint = Checkpoint {
            identity: identity(self.problem, self.plan),
            state: state.clone(),
            record: serde_json::to_value(tally).expect("a tally serializes"),
        };
        checkpoint::write(&self.dir().join(CHECKPOINT_FILE), &checkpoint).map_err(self.io(CHECKPOINT_FILE))
    }
}

fn identity(problem: &Problem, plan: &OutputPlan) -> Identity {
    Identity {
        scenario: plan.fingerprint.clone(),
        mesh: checkpoint::mesh_fingerprint(&problem.mesh),
    }
}

/// [`run`], with `observer` called on every new state (with the step's solver figures), and
/// returning the state at T too.
pub fn run_observed(
    problem: &Problem,
    params: &SolverParams,
    plan: &OutputPlan,
    options: &RunOptions,
    mut observer: impl FnMut(&Problem, &State, &StepInfo),
) -> Result<Run, Error> {
    let start = Instant::now();
    let mut timings = Timings {
        assembly: problem.build_seconds,
        ..Timings::default()
    };

    // The starting state and the run's tally: fresh, or a checkpoint's.
    let (first, mut tally) = match &options.restart {
        None => (State::initial(problem), Tally::new()),
        Some(Restart { path, checkpoint }) => {
            checkpoint.check(
                path,
                &identity(problem, plan),
                problem.time.steps,
                &State::initial(problem),
            )?;
            let mut tally: Tally =
                serde_json::from_value(checkpoint.record.clone()).map_err(|_| CheckpointError::Damaged {
                    path: path.clone(),
                    reason: "its record of the run is not valid",
                })?;
            tally.restarts.push(checkpoint.state.n);
            (checkpoint.state.clone(), tally)
        }
    };
    // The loop's linear work before this process (a continued run's checkpoint has it): the
    // tally adds this process's to it wherever it is saved.
    let (solves_before, sweeps_before) = (tally.solves, tally.sweeps);

    // Claim the folder before the expensive set-up: a refused folder fails at once.
    let files = match &options.out_dir {
        None => None,
        Some(dir) => {
            let existing = match (&options.restart, options.overwrite) {
                (Some(_), _) => Existing::Continue {
                    frames: tally.outputs.iter().map(|o| o.n).collect(),
                },
                (None, true) => Existing::Overwrite,
                (None, false) => Existing::Refuse,
            };
            Some(Files {
                folder: RunFolder::claim(dir, &existing)?,
                plan,
                problem,
            })
        }
    };

    let clock = Instant::now();
    let linear = LinearSystem::new(problem, problem.time_step(), params)?;
    timings.factorization = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let levels = Levels::new(problem, params, StepSolver::new(problem, linear, params)?);
    timings.solver_setup = clock.elapsed().as_secs_f64();
    let setup = Setup {
        problem,
        params,
        plan,
        factor_nnz: levels.first().factor_nnz(),
        linear: levels.first().linear(),
        preconditioner: levels.first().preconditioner(),
        amg: levels.first().amg().map(|amg| AmgRecord {
            levels: amg.levels(),
            operator_complexity: amg.operator_complexity(),
        }),
    };
    let count_work = |tally: &mut Tally| {
        let stats = levels.step_stats();
        tally.solves = solves_before + stats.solves;
        tally.sweeps = sweeps_before + stats.sweeps;
    };

    if let Some(files) = &files {
        if let Some(record) = &plan.record {
            output::write_atomic(&files.dir().join("scenario.toml"), record.as_bytes())
                .map_err(files.io("scenario.toml"))?;
        }
        if plan.vtk {
            // A continued run's collection: the frames up to its checkpoint.
            output::write_pvd(&files.dir().join("solution.pvd"), &tally.frames)?;
        }
        files.summary(&setup.summary(&tally, RunStatus::Running, None, timings.clone()))?;
    }

    let n_steps = problem.time.steps;
    // Looked up every step: a set, since `output.every = 1` makes it as long as the run.
    let output_levels: std::collections::BTreeSet<usize> = plan.steps.iter().copied().collect();
    let terminal = options.progress && std::io::stderr().is_terminal();
    let bar = if terminal {
        ProgressBar::new(n_steps as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} step {pos}/{len} [{bar:30}] {elapsed_precise} (eta {eta}) {msg}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_position(first.n as u64);
    let log = |line: String| {
        if options.log {
            if bar.is_hidden() {
                eprintln!("{line}");
            } else {
                bar.println(line);
            }
        }
    };
    // Batch runs (stderr not a terminal) get a progress line at most every 10 s, at the output
    // times and at the end instead of the bar.
    let batch = options.progress && !terminal;
    let mut last_line = Instant::now();
    let mut last_steps_write = Instant::now();

    // The frames are written on a thread of the scope (module `writer`), which ends with it.
    std::thread::scope(|scope| {
        let mut writer = files.as_ref().map(|files| {
            FrameWriter::start(
                scope,
                problem,
                plan,
                files.dir(),
                tally.frames.clone(),
                options.inline_frames,
            )
        });
        let mut output_time = 0.0;
        // The initial state is a frame when an output time rounds to level 0 (a continued run has
        // it already).
        if first.n == 0 && output_levels.contains(&0) {
            let clock = Instant::now();
            let record = record(problem, &first, plan.slip_tolerance);
            if let Some(writer) = &mut writer {
                writer.submit(&first, &record, &mut tally)?;
            }
            tally.outputs.push(record);
            output_time += clock.elapsed().as_secs_f64();
        }
        let loop_clock = Instant::now();
        let mut step_clock = Instant::now();
        let first_step = first.n;
        let marched = time::march_from(problem, &levels, first, |state, info| {
            observer(problem, state, info);
            let (residual, slip_nodes) = law_residual(problem, state, plan.slip_tolerance);
            let step_record = StepRecord {
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
                increments: match params.kind {
                    SolverKind::Paper => info.increments,
                    SolverKind::Fast => [f64::NAN; 4],
                },
                law_residual: residual,
                slip_nodes,
                stick_nodes: problem.contact.len() - slip_nodes,
                seconds: step_clock.elapsed().as_secs_f64(),
            };
            tally.add_step(info, step_record);
            if info.cutback_depth > 0 {
                let cutback = CutbackRecord {
                    step: state.n,
                    t: state.t,
                    depth: info.cutback_depth,
                    substeps: info.substeps,
                };
                log(format!(
                    "step {} (t = {}): cut back, {} substeps, the shortest k/{}",
                    cutback.step,
                    cutback.t,
                    cutback.substeps,
                    1usize << cutback.depth
                ));
                tally.cutbacks.push(cutback);
            }
            bar.inc(1);
            let clock = Instant::now();
            // An error of an earlier frame stops the run here.
            if let Some(writer) = &mut writer {
                writer.poll(&mut tally)?;
            }
            let is_output = output_levels.contains(&state.n);
            if is_output {
                let record = record(problem, state, plan.slip_tolerance);
                bar.set_message(format!(
                    "t = {:.3}: {} slip, {} stick",
                    record.t, record.slip_nodes, record.stick_nodes
                ));
                if let (Some(files), Some(writer)) = (&files, &mut writer) {
                    writer.submit(state, &record, &mut tally)?;
                    // steps.csv grows with the run: rewritten at output times at most every 10 s
                    // (so that a long run with many frames does not rewrite it quadratically).
                    if last_steps_write.elapsed().as_secs_f64() >= 10.0 {
                        files.steps(&tally)?;
                        last_steps_write = Instant::now();
                    }
                }
                tally.outputs.push(record);
            }
            if let (Some(files), Some(every)) = (&files, plan.checkpoint_every) {
                if state.n % every == 0 && state.n < n_steps {
                    // The checkpoint and the summary list the frames on disk.
                    if let Some(writer) = &mut writer {
                        writer.flush(&mut tally)?;
                    }
                    count_work(&mut tally);
                    files.checkpoint(state, &tally)?;
                    files.steps(&tally)?;
                    files.summary(&setup.summary(&tally, RunStatus::Running, None, timings.clone()))?;
                }
            }
            output_time += clock.elapsed().as_secs_f64();
            if batch && (is_output || state.n == n_steps || last_line.elapsed().as_secs_f64() >= 10.0) {
                last_line = Instant::now();
                // The remaining steps at this process's pace so far.
                let done = state.n - first_step;
                let remaining = loop_clock.elapsed().as_secs_f64() / done.max(1) as f64 * (n_steps - state.n) as f64;
                eprintln!(
                    "{}",
                    progress_line(&ProgressLine {
                        record: &step_record,
                        steps: n_steps,
                        cutbacks: tally.cutbacks.len(),
                        elapsed: start.elapsed().as_secs_f64(),
                        remaining,
                    })
                );
            }
            if let Some(cause) = options.stop.as_ref().and_then(StopFlag::requested) {
                return Err(Error::Interrupted {
                    step: state.n,
                    time: state.t,
                    cause,
                });
            }
            step_clock = Instant::now();
            Ok(())
        });
        let (state, mut failure) = match marched {
            Ok(state) => {
                bar.finish_and_clear();
                (state, None)
            }
            Err(stopped) => {
                let Stopped { error, last } = *stopped;
                // The caller reports the error itself.
                bar.abandon();
                (last, Some(error))
            }
        };
        timings.time_stepping = loop_clock.elapsed().as_secs_f64() - output_time;
        let loop_stats = levels.step_stats();
        timings.linear_solves = loop_stats.solve_seconds;
        timings.right_hand_sides = loop_stats.rhs_seconds;
        timings.cutback_setup = levels.cutback_setup_seconds();
        timings.contact_solver =
            timings.time_stepping - timings.linear_solves - timings.right_hand_sides - timings.cutback_setup;

        // The frames still queued are written before anything else is recorded. The writer's error
        // stops a run that completed; one that stopped already reports its own error first.
        if let Some(writer) = writer.take() {
            let clock = Instant::now();
            let (seconds, finished) = writer.finish(&mut tally);
            output_time += clock.elapsed().as_secs_f64();
            timings.frames = seconds;
            if let Err(error) = finished {
                match failure {
                    None => failure = Some(error),
                    Some(_) => log(format!("error: {error}")),
                }
            }
        }

        count_work(&mut tally);
        let status = RunStatus::of(failure.as_ref());
        let failure_record = failure.as_ref().map(|e| FailureRecord::new(e, &state));
        let written = match &files {
            Some(files) => {
                let clock = Instant::now();
                {
                    // Each file is tried even where one before it failed, so that a stopped run
                    // still leaves its summary: the first error comes back, the others are logged.
                    let mut first = None;
                    let mut keep = |written: Result<(), Error>| match (written, &first) {
                        (Err(error), None) => first = Some(error),
                        (Err(error), Some(_)) => log(format!("error: {error}")),
                        (Ok(()), _) => {}
                    };
                    if failure.is_some() {
                        // A stopped run keeps its last completed state: as a checkpoint to continue
                        // from (with the planned frames only: a continued run drops the next one),
                        // and as a frame beside those written so far, unless it has one (an output
                        // time whose frame was written).
                        if state.n > 0 {
                            keep(files.checkpoint(&state, &tally));
                        }
                        if !tally.outputs.iter().any(|o| o.n == state.n) {
                            let record = record(problem, &state, plan.slip_tolerance);
                            keep(files.frame(&state, &record, &mut tally));
                        }
                    } else {
                        // A completed run's checkpoint is of no use any more, whether this run wrote
                        // it (`checkpoint_every`) or the stopped run it continued did; left in place,
                        // `--restart` would silently compute the end again from it.
                        match std::fs::remove_file(files.dir().join(CHECKPOINT_FILE)) {
                            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                                keep(Err(files.io(CHECKPOINT_FILE)(e)))
                            }
                            _ => {}
                        }
                    }
                    keep(files.steps(&tally));
                    timings.output = output_time + clock.elapsed().as_secs_f64();
                    timings.total = problem.build_seconds + start.elapsed().as_secs_f64();
                    keep(files.summary(&setup.summary(&tally, status, failure_record.clone(), timings.clone())));
                    first.map_or(Ok(()), Err)
                }
            }
            None => Ok(()),
        };
        timings.output = timings.output.max(output_time);
        timings.total = problem.build_seconds + start.elapsed().as_secs_f64();
        let summary = setup.summary(&tally, status, failure_record, timings);
        match (failure, written) {
            // The error that stopped the run comes first; one met while recording it is logged.
            (Some(error), written) => {
                if let Err(also) = written {
                    log(format!("error: {also}"));
                }
                Err(error)
            }
            (None, written) => written.map(|()| Run { summary, state }),
        }
    })
}

/// `_0042.` in the file names of time level 42's frame ([`crate::output::folder::frame_step`]
/// reads it back).
fn frame_tag(n: usize) -> String {
    format!("_{n:04}.")
}

/// The largest nodal friction-law residual of a state on Γ_C, relative to μ(0)S, and the
/// number of Γ_C nodes that slip (|w_τ| > the slip tolerance, as in the contact CSV).
fn law_residual(problem: &Problem, state: &State, slip_tolerance: f64) -> (f64, usize) {
    let law = problem.friction.as_ref();
    let tangential = problem.dim() - 1;
    let w_tau = crate::model::contact_tangential(problem, &state.w);
    let mut worst: f64 = 0.0;
    let mut slip = 0;
    for (w, xi) in w_tau.chunks_exact(tangential).zip(state.xi.chunks_exact(tangential)) {
        worst = worst.max(crate::contact::friction::law_residual(law, w, xi, slip_tolerance));
        slip += usize::from(crate::la::vector::norm2(w) > slip_tolerance);
    }
    (worst / law.bound(0.0).max(f64::MIN_POSITIVE), slip)
}

/// What a batch run's progress line tells.
struct ProgressLine<'a> {
    record: &'a StepRecord,
    steps: usize,
    /// Steps cut back so far.
    cutbacks: usize,
    /// Seconds since the run started, and the estimate of those still to come.
    elapsed: f64,
    remaining: f64,
}

/// A batch run's progress line: the step and t, the step's iterations, the cutbacks so far,
/// the slip and stick counts, the law residual, and the elapsed and remaining time.
fn progress_line(p: &ProgressLine) -> String {
    let r = p.record;
    let mut iterations = format!(
        "{} convexification, {} inner, {} Newton, {} sweeps",
        r.convexification_iterations, r.inner_iterations, r.newton_iterations, r.descent_sweeps
    );
    if r.krylov_iterations > 0 {
        iterations.push_str(&format!(", {} Krylov", r.krylov_iterations));
    }
    let cut = match r.cutback_depth {
        0 => String::new(),
        depth => format!(", this one into {} substeps (k/{})", r.substeps, 1usize << depth),
    };
    format!(
        "step {}/{} t = {:.6}: {iterations}; {} steps cut back so far{cut}; {} slip, {} stick; \
         law residual {:.1e}; step {:.2} s, elapsed {}, remaining {}",
        r.n,
        p.steps,
        r.t,
        p.cutbacks,
        r.slip_nodes,
        r.stick_nodes,
        r.law_residual,
        r.seconds,
        duration(p.elapsed),
        duration(p.remaining)
    )
}

/// A duration for a log line: `4.2 s`, `12 min 05 s`, `3 h 07 min`.
fn duration(seconds: f64) -> String {
    let s = seconds.max(0.0);
    if s < 60.0 {
        format!("{s:.1} s")
    } else if s < 3600.0 {
        let whole = s.round() as u64;
        format!("{} min {:02} s", whole / 60, whole % 60)
    } else {
        let minutes = (s / 60.0).round() as u64;
        format!("{} h {:02} min", minutes / 60, minutes % 60)
    }
}

/// The figures of one output time.
pub fn record(problem: &Problem, state: &State, slip_tolerance: f64) -> OutputRecord {
    let contact = contact_rows(problem, state, slip_tolerance);
    let slip_nodes = contact.iter().filter(|r| r.slip).count();
    let d = problem.dim();
    let max_displacement = state
        .u
        .chunks_exact(d)
        .map(|v| v.iter().map(|x| x * x).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    OutputRecord {
        n: state.n,
        t: state.t,
        slip_nodes,
        stick_nodes: contact.len() - slip_nodes,
        max_slip_rate: contact.iter().map(ContactRow::slip_rate).fold(0.0, f64::max),
        min_temperature: state.theta.iter().cloned().fold(f64::INFINITY, f64::min),
        max_temperature: state.theta.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        max_displacement,
        energy_norm_u: crate::model::norms::energy(&problem.matrices, &state.u),
        contact,
    }
}

/// Header of the contact CSV files: position, outward normal ν, (3D: the first tangent t₁; in
/// 2D t = ν turned by +90°), w_τ and ξ in the node's tangent coordinates, the friction bound,
/// slip (1) or stick (0), θ.
pub fn contact_csv_header(dim: usize) -> Vec<&'static str> {
    if dim == 2 {
        vec!["x", "y", "nu_x", "nu_y", "w_tau", "xi", "bound", "slip", "theta"]
    } else {
        vec![
            "x", "y", "z", "nu_x", "nu_y", "nu_z", "t1_x", "t1_y", "t1_z", "w_tau1", "w_tau2", "xi1", "xi2", "bound",
            "slip", "theta",
        ]
    }
}

/// The contact CSV rows, in the columns of [`contact_csv_header`].
pub fn contact_csv_rows(dim: usize, rows: &[ContactRow]) -> Vec<Vec<f64>> {
    rows.iter()
        .map(|r| {
            let mut v: Vec<f64> = r.x[..dim].to_vec();
            v.extend_from_slice(&r.normal[..dim]);
            if dim == 3 {
                v.extend_from_slice(&r.tangents[0]);
            }
            v.extend_from_slice(&r.w_tau);
            v.extend_from_slice(&r.xi);
            v.extend([r.bound, if r.slip { 1.0 } else { 0.0 }, r.theta]);
            v
        })
        .collect()
}

fn write_snapshot(
    problem: &Problem,
    plan: &OutputPlan,
    state: &State,
    record: &OutputRecord,
    dir: &Path,
    pvd: &mut Vec<PvdEntry>,
) -> Result<(), Error> {
    let d = problem.dim();
    if plan.csv {
        let path = dir.join(format!("contact{}csv", frame_tag(state.n)));
        output::write_csv(&path, &contact_csv_header(d), &contact_csv_rows(d, &record.contact))?;
    }
    if plan.vtk {
        let file = format!("solution{}vtu", frame_tag(state.n));
        let stress = fields::cell_stress(problem, state);
        let von_mises = fields::von_mises(&stress);
        let (status, friction) = fields::nodal_contact_fields(problem, &record.contact);
        let grid = Grid {
            dim: d,
            points: &problem.mesh.coords,
            cells: &problem.mesh.cells,
        };
        let point_fields = [
            Field {
                name: "displacement",
                n_components: d,
                values: &state.u,
            },
            Field {
                name: "velocity",
                n_components: d,
                values: &state.w,
            },
            Field {
                name: "temperature",
                n_components: 1,
                values: &state.theta,
            },
            Field {
                name: "contact_status",
                n_components: 1,
                values: &status,
            },
            Field {
                name: "friction_stress",
                n_components: d,
                values: &friction,
            },
        ];
        let cell_fields = [
            Field {
                name: "stress",
                n_components: fields::STRESS_COMPONENTS.len(),
                values: &stress,
            },
            Field {
                name: "von_mises",
                n_components: 1,
                values: &von_mises,
            },
        ];
        let compression = if plan.compress {
            Compression::Zlib
        } else {
            Compression::None
        };
        output::write_vtu(&dir.join(&file), &grid, &point_fields, &cell_fields, compression)?;
        pvd.push(PvdEntry { time: record.t, file });
    }
    Ok(())
}
