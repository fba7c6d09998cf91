//! The frames observer: at the planned output times, the figures of the state (the run's
//! outputs) and its frame, handed to the frame writer (module `writer`); `steps.csv` rewritten
//! beside them, at most every 10 s. It keeps the output time the march waited for.
//!
//! In a distributed run every rank has a writer, for its piece of each frame, and the frames
//! are listed once every rank has written its own (module `listing`); the errors of a rank's
//! files wait for the ranks' agreement after the step, which ends every rank with them.

use std::collections::BTreeSet;
use std::path::Path;
use std::thread::Scope;
use std::time::Instant;

use super::files::Files;
use super::listing::Listing;
use super::progress::Progress;
use super::ranks::Ranks;
use super::snapshot::{record, Layout};
use super::summary::{OutputRecord, Tally};
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
    /// A distributed run's frames in pieces, listed once every rank has written its own.
    listing: Option<Listing>,
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
    /// The frames of a run into the folder `out` in its `layout` (none: the outputs are
    /// recorded, nothing is written), with the folder's other `files` (one process, or rank 0
    /// of a distributed run), after the `frames` there already (a continued run's), written on
    /// a thread of `scope` or `inline`.
    pub fn start(
        scope: &'scope Scope<'scope, 'env>,
        problem: &'env Problem,
        plan: &'env OutputPlan,
        files: Option<&'env Files<'env>>,
        out: Option<(&Path, &'env Layout)>,
        frames: &[PvdEntry],
        inline: bool,
    ) -> Self {
        let writer = out.map(|out| FrameWriter::start(scope, problem, plan, out, frames.to_vec(), inline));
        let listing = match out {
            Some((dir, &Layout::Piece { rank, n_ranks, .. })) => {
                Some(Listing::new(Ranks { rank, size: n_ranks }, dir.to_path_buf()))
            }
            _ => None,
        };
        Frames {
            problem,
            plan,
            files,
            writer,
            listing,
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
            let submitted = self.submit(first, &record, tally);
            self.waited += clock.elapsed().as_secs_f64();
            submitted?;
            tally.outputs.push(record);
        }
        Ok(())
    }

    /// After a step: the writer's reports (an error of an earlier frame stops the run here);
    /// at an output time (whether this is one comes back), the state's figures, shown by
    /// `progress`, and its frame. In a distributed run the ranks then agree on the frames
    /// written and on any error (module `listing`).
    pub fn step(&mut self, state: &State, tally: &mut Tally, progress: &Progress) -> Result<bool, Error> {
        let clock = Instant::now();
        let is_output = self.levels.contains(&state.n);
        let mut outcome = self.poll(tally);
        if is_output && outcome.is_ok() {
            let record = record(self.problem, state, self.plan.slip_tolerance);
            progress.output(&record);
            outcome = self.submit(state, &record, tally);
            // steps.csv grows with the run: rewritten at output times at most every 10 s (so
            // that a long run with many frames does not rewrite it quadratically).
            if let Some(files) = self.files.filter(|_| outcome.is_ok()) {
                if self.last_steps_write.elapsed().as_secs_f64() >= 10.0 {
                    let written = files.steps(tally);
                    self.last_steps_write = Instant::now();
                    outcome = self.settle(written);
                }
            }
            if outcome.is_ok() {
                tally.outputs.push(record);
            }
        }
        if let (Some(listing), Some(writer)) = (&mut self.listing, &mut self.writer) {
            outcome = listing.agree(writer, tally);
        }
        self.waited += clock.elapsed().as_secs_f64();
        outcome.map(|()| is_output)
    }

    /// An error of this rank: it comes back (one process), or is kept for the ranks' agreement
    /// (in pieces: [`Listing::agree`]).
    fn settle(&mut self, outcome: Result<(), Error>) -> Result<(), Error> {
        match &mut self.listing {
            Some(listing) => {
                listing.keep(outcome);
                Ok(())
            }
            None => outcome,
        }
    }

    /// The writer's reports so far, its error [settled](Frames::settle).
    fn poll(&mut self, tally: &mut Tally) -> Result<(), Error> {
        let Some(writer) = &mut self.writer else { return Ok(()) };
        let polled = writer.poll(tally);
        self.settle(polled)
    }

    /// The frame of `state` to the writer, if there is one, its error
    /// [settled](Frames::settle). In pieces every rank counts the frame sent, and a rank with
    /// an error writes no more.
    fn submit(&mut self, state: &State, record: &OutputRecord, tally: &mut Tally) -> Result<(), Error> {
        let Some(writer) = &mut self.writer else { return Ok(()) };
        let Some(listing) = &mut self.listing else {
            return writer.submit(state, record, tally);
        };
        listing.sent(state.n);
        if !listing.failed_here() {
            let submitted = writer.submit(state, record, tally);
            listing.keep(submitted);
        }
        Ok(())
    }

    /// Waits until every frame sent is on disk (before a checkpoint lists them); in a
    /// distributed run, on every rank, and listed (collective).
    pub fn flush(&mut self, tally: &mut Tally) -> Result<(), Error> {
        let Some(writer) = &mut self.writer else { return Ok(()) };
        let Some(listing) = &mut self.listing else {
            return writer.flush(tally);
        };
        while listing.due() {
            let flushed = writer.flush(tally);
            listing.keep(flushed);
            listing.agree(writer, tally)?;
        }
        Ok(())
    }

    /// Whether the frames are written in pieces, listed by the ranks' agreement: then
    /// [`Frames::flush`] is collective.
    pub fn in_pieces(&self) -> bool {
        self.listing.is_some()
    }

    /// The ranks' agreement on `outcome`, this rank's alone (collective in pieces; as it is
    /// otherwise): where any rank failed, every rank fails.
    pub fn agree(&self, outcome: Result<(), Error>) -> Result<(), Error> {
        match &self.listing {
            Some(listing) => listing.agree_on(outcome),
            None => outcome,
        }
    }

    /// The seconds the march waited for output so far.
    pub fn waited(&self) -> f64 {
        self.waited
    }

    /// Waits for the frames still queued (in a distributed run: on every rank, and lists them)
    /// and ends the writer.
    pub fn finish(mut self, tally: &mut Tally) -> Finished {
        let mut waited = self.waited;
        let clock = Instant::now();
        let listed = if self.in_pieces() { self.flush(tally) } else { Ok(()) };
        let (written, result) = match self.writer {
            Some(writer) => {
                let (seconds, finished) = writer.finish(tally);
                waited += clock.elapsed().as_secs_f64();
                match &self.listing {
                    // In pieces the agreement has the errors (an error of this rank's writer
                    // after it is one the run already has), and the frames took the slowest
                    // rank's time.
                    Some(listing) => (listing.slowest(seconds), listed),
                    None => (seconds, finished),
                }
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
