//! Progress: the bar on a terminal, or a batch run's progress lines (at most every 10 s, at the
//! output times and at the end), and inside a step that runs longer than a few seconds its outer
//! iteration ([`crate::step::heartbeat`]); and the log lines (`RunOptions::log`) of cutbacks and of the
//! errors met while a stopped run records its stop.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use super::summary::{OutputRecord, StepRecord};
use super::RunOptions;
use crate::step::heartbeat;

/// The environment variable that sets the threshold and interval of a long step's progress
/// lines, in seconds ([`Progress::heartbeat`]; default [`heartbeat::AFTER`], [`heartbeat::EVERY`]).
pub const HEARTBEAT_ENV: &str = "THERMOCONTACT_HEARTBEAT_SECONDS";

/// The progress observer: the bar, the batch lines, the log lines.
pub(super) struct Progress {
    bar: ProgressBar,
    /// Log lines wanted (`RunOptions::log`).
    log: bool,
    /// Progress lines instead of the bar (stderr is not a terminal).
    batch: bool,
    steps: usize,
    /// The time level the march starts from.
    first_step: usize,
    /// When the run started (the lines' elapsed time) and when the march did (their pace).
    started: Instant,
    marching: Instant,
    last_line: Instant,
}

impl Progress {
    /// The progress of a run of `steps` steps started at `started`, marching from `first_step`.
    pub fn new(options: &RunOptions, steps: usize, first_step: usize, started: Instant) -> Self {
        let terminal = options.progress && std::io::stderr().is_terminal();
        let bar = if terminal {
            ProgressBar::new(steps as u64)
        } else {
            ProgressBar::hidden()
        };
        bar.set_style(
            ProgressStyle::with_template("{spinner} step {pos}/{len} [{bar:30}] {elapsed_precise} (eta {eta}) {msg}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_position(first_step as u64);
        let now = Instant::now();
        Progress {
            bar,
            log: options.log,
            // Batch runs (stderr not a terminal) get progress lines instead of the bar.
            batch: options.progress && !terminal,
            steps,
            first_step,
            started,
            marching: now,
            last_line: now,
        }
    }

    /// The march starts: the pace of the lines is measured from here.
    pub fn marching(&mut self) {
        self.marching = Instant::now();
    }

    /// The lines of a long step ([`crate::step::heartbeat`]) for the time of the march, above
    /// the bar or as batch lines on stderr; none where there is no progress (`--quiet`). The
    /// environment variable [`HEARTBEAT_ENV`] (seconds) replaces both the threshold and the
    /// interval (0: a line at every outer iteration; for tests).
    pub fn heartbeat(&self) -> Option<heartbeat::HeartbeatScope> {
        if !self.batch && self.bar.is_hidden() {
            return None;
        }
        let bar = self.bar.clone();
        let sink = move |line: &str| {
            if bar.is_hidden() {
                eprintln!("{line}");
            } else {
                bar.println(line);
            }
        };
        let forced = std::env::var(HEARTBEAT_ENV).ok().and_then(|s| s.parse::<f64>().ok());
        let (after, every) = match forced {
            Some(seconds) if seconds >= 0.0 && seconds.is_finite() => {
                (Duration::from_secs_f64(seconds), Duration::from_secs_f64(seconds))
            }
            _ => (heartbeat::AFTER, heartbeat::EVERY),
        };
        Some(heartbeat::report_to(Box::new(sink), after, every))
    }

    /// A log line, above the bar where there is one.
    pub fn log(&self, line: String) {
        if self.log {
            if self.bar.is_hidden() {
                eprintln!("{line}");
            } else {
                self.bar.println(line);
            }
        }
    }

    /// A step done: its cutback, if it had one, as a log line; the bar one step on.
    pub fn step(&self, step: &StepRecord) {
        if step.cutback_depth > 0 {
            self.log(format!(
                "step {} (t = {}): cut back, {} substeps, the shortest k/{}",
                step.n,
                step.t,
                step.substeps,
                1usize << step.cutback_depth
            ));
        }
        self.bar.inc(1);
    }

    /// An output time: its slip and stick counts beside the bar.
    pub fn output(&self, record: &OutputRecord) {
        self.bar.set_message(format!(
            "t = {:.3}: {} slip, {} stick",
            record.t, record.slip_nodes, record.stick_nodes
        ));
    }

    /// A batch run's progress line after `step` (an output time or not; `cutbacks` steps cut
    /// back so far): at output times, at the end, and otherwise at most every 10 s.
    pub fn line(&mut self, step: &StepRecord, output: bool, cutbacks: usize) {
        if !(self.batch && (output || step.n == self.steps || self.last_line.elapsed().as_secs_f64() >= 10.0)) {
            return;
        }
        self.last_line = Instant::now();
        // The remaining steps at this process's pace so far.
        let done = step.n - self.first_step;
        let remaining = self.marching.elapsed().as_secs_f64() / done.max(1) as f64 * (self.steps - step.n) as f64;
        eprintln!(
            "{}",
            progress_line(&ProgressLine {
                record: step,
                steps: self.steps,
                cutbacks,
                elapsed: self.started.elapsed().as_secs_f64(),
                remaining,
            })
        );
    }

    /// The march ended: the bar cleared where it completed, left standing where it stopped (the
    /// caller reports the error itself).
    pub fn end(&self, completed: bool) {
        if completed {
            self.bar.finish_and_clear();
        } else {
            self.bar.abandon();
        }
    }
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
