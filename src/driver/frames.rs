//! The frames observer: at the planned output times, the figures of the state (the run's
//! outputs) and its frame, handed to the frame writer (module `writer`); `steps.csv` rewritten
//! beside them, at most every 10 s. It keeps the output time the march waited for.

use std::collections::BTreeSet;
use std::thread::Scope;
use std::time::Instant;

use super::files::Files;
use super::progress::Progress;
use super::snapshot::record;
use super::summary::Tally;
use super::writer::FrameWriter;
use super::OutputPlan;
use crate::error::Error;
use crate::model::Problem;
use crate::model::State;
use crate::output::PvdEntry;

/// The frames of a run: their output times, and their writer where the run has a folder.
pub(super) struct Frames<'scope, 'env> {
    problem: &'env Problem,
    plan: &'env OutputPlan,
    files: Option<&'env Files<'env>>,
    writer: Option<FrameWriter<'scope, 'env>>,
    /// Looked up every step: a set, since `output.every = 1` makes it as long as the run.
    levels: BTreeSet<usize>,
    last_steps_write: Instant,
    /// Seconds the march waited for output.
    waited: f64,
}

/// The frames' end: the seconds spent on them, those the run waited for, and the writer's error.
pub(super) struct Finished {
    pub written: f64,
    pub waited: f64,
    pub result: Result<(), Error>,
}

impl<'scope, 'env> Frames<'scope, 'env> {
    /// The frames of a run into `files` (none: the outputs are recorded, nothing is written),
    /// after the `frames` there already (a continued run's), written on a thread of `scope` or
    /// `inline`.
    pub fn start(
        scope: &'scope Scope<'scope, 'env>,
        problem: &'env Problem,
        plan: &'env OutputPlan,
        files: Option<&'env Files<'env>>,
        frames: &[PvdEntry],
        inline: bool,
    ) -> Self {
        let writer = files.map(|files| FrameWriter::start(scope, problem, plan, files.dir(), frames.to_vec(), inline));
        Frames {
            problem,
            plan,
            files,
            writer,
            levels: plan.steps.iter().copied().collect(),
            last_steps_write: Instant::now(),
            waited: 0.0,
        }
    }

    /// The initial state is a frame when an output time rounds to level 0 (a continued run has
    /// it already).
    pub fn initial(&mut self, first: &State, tally: &mut Tally) -> Result<(), Error> {
        if first.n == 0 && self.levels.contains(&0) {
            let clock = Instant::now();
            let record = record(self.problem, first, self.plan.slip_tolerance);
            if let Some(writer) = &mut self.writer {
                writer.submit(first, &record, tally)?;
            }
            tally.outputs.push(record);
            self.waited += clock.elapsed().as_secs_f64();
        }
        Ok(())
    }

    /// After a step: the writer's reports (an error of an earlier frame stops the run here);
    /// at an output time (whether this is one comes back), the state's figures, shown by
    /// `progress`, and its frame.
    pub fn step(&mut self, state: &State, tally: &mut Tally, progress: &Progress) -> Result<bool, Error> {
        let clock = Instant::now();
        if let Some(writer) = &mut self.writer {
            writer.poll(tally)?;
        }
        let is_output = self.levels.contains(&state.n);
        if is_output {
            let record = record(self.problem, state, self.plan.slip_tolerance);
            progress.output(&record);
            if let (Some(files), Some(writer)) = (self.files, &mut self.writer) {
                writer.submit(state, &record, tally)?;
                // steps.csv grows with the run: rewritten at output times at most every 10 s
                // (so that a long run with many frames does not rewrite it quadratically).
                if self.last_steps_write.elapsed().as_secs_f64() >= 10.0 {
                    files.steps(tally)?;
                    self.last_steps_write = Instant::now();
                }
            }
            tally.outputs.push(record);
        }
        self.waited += clock.elapsed().as_secs_f64();
        Ok(is_output)
    }

    /// Waits until every frame sent is on disk (before a checkpoint lists them).
    pub fn flush(&mut self, tally: &mut Tally) -> Result<(), Error> {
        match &mut self.writer {
            Some(writer) => writer.flush(tally),
            None => Ok(()),
        }
    }

    /// The seconds the march waited for output so far.
    pub fn waited(&self) -> f64 {
        self.waited
    }

    /// Waits for the frames still queued and ends the writer.
    pub fn finish(self, tally: &mut Tally) -> Finished {
        let mut waited = self.waited;
        let (written, result) = match self.writer {
            Some(writer) => {
                let clock = Instant::now();
                let (seconds, finished) = writer.finish(tally);
                waited += clock.elapsed().as_secs_f64();
                (seconds, finished)
            }
            None => (0.0, Ok(())),
        };
        Finished {
            written,
            waited,
            result,
        }
    }
}
