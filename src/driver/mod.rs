//! The driver layer: a whole run, as the `run` command does it — claim the output folder, set
//! up (the starting state, fresh or a checkpoint's; the step matrix factored or preconditioned,
//! the step solver), march through time ([`time::march_from`]) with the run's observers, and
//! finish (the files a run leaves, its summary and status). The problem comes built
//! ([`crate::model::ProblemBuilder`]).
//!
//! Depends on: output, time, step, model, error (and below).
//!
//! ```text
//! claim the folder → set up (setup: start state, time::Levels) → open the folder (scenario.toml,
//! solution.pvd, summary.json "running") → march (time::march_from), each step seen in order by:
//!   recorder     the steps.csv record with the step's energies, the tally, the cutbacks
//!                (recorder.rs); the warnings of a run that leaves the plausible (watch.rs)
//!   progress     the cutback log line, the bar or a batch line (progress.rs)
//!   frames       at output times: the figures, the frame to the writer thread, which writes it
//!                and rewrites solution.pvd (and steps.csv, at most every 10 s) (frames.rs,
//!                writer.rs)
//!   checkpoints  every `checkpoint_every` steps: the frames sent awaited, checkpoint.bin,
//!                steps.csv, summary.json ("running") (checkpoints.rs)
//!   stop         a stop requested from outside ends the march (stop.rs); one requested
//!                "now" cuts the step short too (step::abort), the run ending at the last one
//! → finish: the frames sent awaited → summary.json ("completed", or "failed" / "interrupted"
//!   with the last state written) (files.rs)
//! ```
//!
//! The frames are written on a thread beside the time loop (module `writer`: owned copies
//! through a channel of one frame, so memory stays bounded), so that the loop, which mostly uses
//! one core, does not wait for them; `RunOptions::inline_frames` writes them on the loop's
//! thread instead, into the same bytes. Each observer keeps the time it reports (the recorder
//! the steps' and the march's, the frames and the checkpoints the output time waited for).
//!
//! **The folder never lies.** A run owns its folder ([`crate::output::folder`]): a lock, and
//! another run's results are refused, replaced (`overwrite`) or continued (`restart`).
//! `summary.json` says `running` from the start, `solution.pvd` lists exactly the frames
//! present, and a run that stops early (a step that does not converge even after the cutbacks,
//! an output error, a signal) still leaves the frames written so far, the last completed state
//! as a frame and a checkpoint, and `summary.json` with the status and the reason (step, time,
//! the criterion that failed with its value and tolerance, or the signal).

mod checkpoints;
mod files;
mod frames;
mod listing;
mod progress;
mod ranks;
mod recorder;
mod setup;
mod snapshot;
mod stop;
mod summary;
mod watch;
mod writer;

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::Error;
use crate::model::Problem;
use crate::model::State;
use crate::output::checkpoint::{self, Checkpoint};
use crate::step::{SolverParams, StepInfo};
use crate::time::{self, Levels, Stopped};

use checkpoints::Checkpoints;
use files::Files;
use frames::Frames;
use progress::Progress;
use ranks::Ranks;
use recorder::Recorder;
use stop::Stop;

pub use snapshot::{contact_csv_header, contact_csv_rows, record};
pub use stop::StopFlag;
pub use summary::{
    AmgRecord, CutbackRecord, EnergySummary, FailureRecord, OutputRecord, RunStatus, StepRecord, Summary, Tally,
    Timings, Uniqueness,
};
pub use watch::{RunWarning, BALANCE_TOLERANCE, HEAT_BALANCE_TOLERANCE};

/// How to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Where to write results; `None` writes nothing. In a distributed run
    /// ([`crate::step::KrylovParams::distributed`]) every rank is given the folder: rank 0
    /// claims it and writes its files, and every rank writes its piece of each frame there.
    pub out_dir: Option<PathBuf>,
    /// Draw a progress bar on stderr (a log line now and then where stderr is not a terminal).
    pub progress: bool,
    /// Print a line on stderr for every cutback (batch logs); the error that stops a run is
    /// returned to the caller, which reports it.
    pub log: bool,
    /// Replace another run's results found in `out_dir` (otherwise the folder is refused).
    pub overwrite: bool,
    /// Replace the results found in `out_dir` if their run completed, refuse them otherwise
    /// (the CLI's default folder, [`crate::output::folder::Existing::ReplaceCompleted`]).
    pub replace_completed: bool,
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
    /// zlib-compress the `.vtu` arrays ([`crate::output::Compression`]).
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

/// [`run`], with `observer` called on every new state (with the step's solver figures), and
/// returning the state at T too.
pub fn run_observed(
    problem: &Problem,
    params: &SolverParams,
    plan: &OutputPlan,
    options: &RunOptions,
    mut observer: impl FnMut(&Problem, &State, &StepInfo),
) -> Result<Run, Error> {
    let started = Instant::now();
    let (first, tally) = setup::start(problem, plan, options.restart.as_ref())?;
    let ranks = Ranks::of(params)?;
    // Claim the folder before the expensive set-up: a refused folder fails at once. In a
    // distributed run rank 0 claims it.
    let claimed = match ranks {
        Some(ranks) if !ranks.is_root() => Ok(None),
        _ => Files::claim(problem, plan, options, &tally),
    };
    // Collective in a distributed run: every rank learns whether rank 0 claimed the folder,
    // and none writes into it before.
    let files = match ranks {
        None => claimed?,
        Some(ranks) => {
            let (files, local) = match claimed {
                Ok(files) => (files, Ok(())),
                Err(error) => (None, Err(error)),
            };
            ranks.agree(local, &mut [])?;
            files
        }
    };
    let (layout, layout_seconds) = setup::layout(problem, ranks, options.out_dir.is_some())?;
    let (levels, mut timings) = setup::levels(problem, params)?;
    timings.factorization += layout_seconds;
    let mut recorder = Recorder::new(problem, params, plan, &levels, tally, timings, started);
    if options.log {
        recorder.header_lines().iter().for_each(|line| println!("{line}"));
    }
    if let Some(files) = &files {
        files.open(&recorder)?;
    }
    let progress = Progress::new(options, problem.time.steps, first.n, started);

    // The frames are written on a thread of the scope (module `writer`), which ends with it.
    std::thread::scope(|scope| {
        let files = files.as_ref();
        let frames = &recorder.tally.frames;
        let out = options.out_dir.as_deref().map(|dir| (dir, &layout));
        let mut frames = Frames::start(scope, problem, plan, files, out, frames, options.inline_frames);
        frames.initial(&first, &mut recorder.tally)?;
        let mut observers = Observers {
            recorder,
            progress,
            frames,
            checkpoints: Checkpoints::new(files, plan.checkpoint_every, problem.time.steps),
            stop: Stop {
                flag: options.stop.as_ref(),
                over_ranks: params.krylov.distributed,
            },
        };
        let (last, failure) = march(problem, &levels, first, &mut observers, &mut observer);
        finish(last, failure, observers, (files, ranks))
    })
}

/// The run's observers of the march, in the order they see each step.
struct Observers<'scope, 'env, 'p> {
    recorder: Recorder<'env, 'p>,
    progress: Progress,
    frames: Frames<'scope, 'env>,
    checkpoints: Checkpoints<'env>,
    stop: Stop<'env>,
}

/// Marches from `first` ([`time::march_from`]), each new state seen by the caller's `observer`
/// and then by the run's observers in order: the last state reached, and the error that stopped
/// the march there (none: it reached T).
fn march(
    problem: &Problem,
    levels: &Levels,
    first: State,
    o: &mut Observers,
    observer: &mut impl FnMut(&Problem, &State, &StepInfo),
) -> (State, Option<Error>) {
    o.recorder.marching();
    o.progress.marching();
    // A stop requested "now" cuts the step short inside its loops (`step::abort`).
    let _abort = o.stop.cutting_steps_short();
    // A step that runs long reports its outer iterations (`step::heartbeat`).
    let _heartbeat = o.progress.heartbeat();
    crate::step::heartbeat::step_started(first.n + 1, problem.time.time(first.n + 1));
    let marched = time::march_from(problem, levels, first, |state, info| {
        observer(problem, state, info);
        let step = o.recorder.step(state, info);
        for warning in o.recorder.watch(state, &step) {
            o.progress.log(format!("warning: {}", warning.message));
        }
        if let Some(line) = o.recorder.way_out(&step) {
            o.progress.log(line);
        }
        o.progress.step(&step);
        let output = o.frames.step(state, &mut o.recorder.tally, &o.progress)?;
        o.checkpoints.step(state, &mut o.frames, &mut o.recorder)?;
        o.progress.line(&step, output, o.recorder.tally.cutbacks.len());
        o.stop.step(state)?;
        o.recorder.next_step();
        crate::step::heartbeat::step_started(state.n + 1, problem.time.time(state.n + 1));
        Ok(())
    });
    o.progress.end(marched.is_ok());
    o.recorder.marched(o.frames.waited() + o.checkpoints.seconds());
    match marched {
        Ok(last) => (last, None),
        Err(stopped) => {
            let Stopped { error, last } = *stopped;
            let error = o.stop.reported(error, &last);
            (last, Some(error))
        }
    }
}

/// The run's end at `last` (`failure`: the march stopped there): the frames still queued
/// written, the files a run leaves ([`Files::close`]), the summary. The error that stopped the
/// run comes back first; one met while recording it is logged.
fn finish(
    last: State,
    mut failure: Option<Error>,
    o: Observers,
    (files, ranks): (Option<&Files>, Option<Ranks>),
) -> Result<Run, Error> {
    let Observers {
        mut recorder,
        progress,
        frames,
        ..
    } = o;
    // The frames still queued are written before anything else is recorded. The writer's error
    // stops a run that completed; one that stopped already reports its own error first.
    let frames = frames.finish(&mut recorder.tally);
    recorder.frames_written(frames.written);
    if let Err(error) = frames.result {
        match failure {
            None => failure = Some(error),
            Some(_) => progress.log(format!("error: {error}")),
        }
    }

    recorder.count_work();
    // Every rank of a distributed run ends here (a rank with an error of its own ends them all
    // from `main`): they share their peak memory for the summary.
    if let Some(ranks) = ranks {
        recorder.ranks_peak_memory(ranks.each(crate::resources::peak_memory_mib().unwrap_or(0.0)));
    }
    let status = RunStatus::of(failure.as_ref());
    let failure_record = failure.as_ref().map(|e| FailureRecord::new(e, &last));
    let written = match files {
        Some(files) => {
            let log = |line| progress.log(line);
            files.close(
                &last,
                status,
                failure_record.as_ref(),
                &mut recorder,
                frames.waited,
                log,
            )
        }
        None => Ok(()),
    };
    recorder.ended(recorder.output_seconds().max(frames.waited));
    let summary = recorder.summary(status, failure_record);
    match (failure, written) {
        (Some(error), written) => {
            if let Err(also) = written {
                progress.log(format!("error: {also}"));
            }
            Err(error)
        }
        (None, written) => written.map(|()| Run { summary, state: last }),
    }
}
