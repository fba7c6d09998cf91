//! The frames of a distributed run, listed once every rank has written its piece.
//!
//! Each rank's frame writer (module `writer`) writes the rank's piece of a frame on its own
//! thread, at its own pace. A frame is complete when every piece is on disk, and only then may
//! rank 0 write its `.pvtu` and list it in `solution.pvd`, so that the collection, as in one
//! process, lists exactly the frames written whole. The ranks learn it by agreeing
//! ([`super::ranks::Ranks::agree`], one reduction of two integers) on the number of frames every
//! rank has written and on whether any rank failed, at points that are the same on every rank:
//! after each step while frames are in flight, and, waiting for the writers first, before a
//! checkpoint and at the run's end ([`Listing::agree`]).
//!
//! Rank 0 writes the `.pvtu` files and the collection right after the agreement; an error there
//! is its alone, and the next agreement (after the next step, or at once where the run waits
//! for its frames) makes it every rank's. A rank's error (its piece, rank 0's CSV or
//! `steps.csv`) is kept until that agreement, the rank going on as the others do meanwhile: the
//! error then ends every rank at the same step, with the failing rank's message, and the frames
//! in flight are dropped from the run's outputs on every rank, as one process drops the frames
//! queued behind a failed one. Their pieces already written stay in the folder, unlisted (a
//! `--restart` removes them with the other frames after its checkpoint).

use std::collections::VecDeque;
use std::path::PathBuf;

use super::ranks::Ranks;
use super::snapshot::Written;
use super::summary::Tally;
use super::writer::FrameWriter;
use crate::error::Error;
use crate::output;

/// The frames sent to the ranks' writers and not yet listed.
pub(super) struct Listing {
    ranks: Ranks,
    dir: PathBuf,
    /// The time levels of the frames sent and not yet listed, in order: the same on every rank.
    awaiting: VecDeque<usize>,
    /// This rank's error, not yet agreed on.
    failed: Option<Error>,
    /// Frames were listed at the last agreement: rank 0's `.pvtu` files and collection await
    /// the next one (the same on every rank).
    unconfirmed: bool,
    /// An error was agreed on: nothing more is listed or agreed.
    ended: bool,
}

impl Listing {
    /// The listing of this rank's frames in `dir`.
    pub fn new(ranks: Ranks, dir: PathBuf) -> Self {
        Listing {
            ranks,
            dir,
            awaiting: VecDeque::new(),
            failed: None,
            unconfirmed: false,
            ended: false,
        }
    }

    /// The frame of time level `n` was sent to the writer (or would have been: every rank
    /// counts it, whatever its own writer did).
    pub fn sent(&mut self, n: usize) {
        self.awaiting.push_back(n);
    }

    /// This rank's error, kept for the next agreement (the first one).
    pub fn fail(&mut self, error: Error) {
        self.failed.get_or_insert(error);
    }

    /// An error of this rank: [`Listing::fail`], `Ok` meanwhile.
    pub fn keep<T>(&mut self, outcome: Result<T, Error>) -> Option<T> {
        outcome.map_err(|error| self.fail(error)).ok()
    }

    /// Whether this rank has an error awaiting the agreement (its writer sends nothing more).
    pub fn failed_here(&self) -> bool {
        self.failed.is_some()
    }

    /// Whether the ranks have something to agree on: frames in flight, or the listing of the
    /// last agreement to confirm. The same on every rank.
    pub fn due(&self) -> bool {
        !self.ended && (!self.awaiting.is_empty() || self.unconfirmed)
    }

    /// The ranks agree (collective, where [`Listing::due`]): the frames written on every rank
    /// are listed (rank 0 writes their `.pvtu` and the collection), and an error of any rank
    /// comes back on every rank.
    pub fn agree(&mut self, writer: &mut FrameWriter, tally: &mut Tally) -> Result<(), Error> {
        if !self.due() {
            return Ok(());
        }
        let mut counts = [writer.n_written()];
        let local = self.failed.take().map_or(Ok(()), Err);
        self.unconfirmed = false;
        if let Err(error) = self.ranks.agree(local, &mut counts) {
            self.ended = true;
            let lost = std::mem::take(&mut self.awaiting);
            tally.outputs.retain(|o| !lost.contains(&o.n));
            return Err(error);
        }
        let complete = counts[0];
        if complete > 0 {
            self.awaiting.drain(..complete);
            self.unconfirmed = true;
            let listed = self.list(writer.take_written(complete), tally);
            self.keep(listed);
        }
        Ok(())
    }

    /// The ranks' agreement on `outcome`, this rank's alone (collective): where any rank
    /// failed, every rank fails ([`Ranks::agree`]).
    pub fn agree_on(&self, outcome: Result<(), Error>) -> Result<(), Error> {
        self.ranks.agree(outcome, &mut [])
    }

    /// The slowest rank's `seconds` (collective).
    pub fn slowest(&self, seconds: f64) -> f64 {
        self.ranks.max(seconds)
    }

    /// Lists `frames`, written on every rank: their entries in the collection; on rank 0 their
    /// `.pvtu` files, then the collection.
    fn list(&self, frames: Vec<Option<Written>>, tally: &mut Tally) -> Result<(), Error> {
        let before = tally.frames.len();
        for written in frames.into_iter().flatten() {
            let Written::Piece { entry, pvtu } = written else {
                unreachable!("a writer in pieces writes pieces")
            };
            if let Some(bytes) = pvtu.filter(|_| self.ranks.is_root()) {
                output::write_pvtu(&self.dir.join(&entry.file), &bytes)?;
            }
            tally.frames.push(entry);
        }
        if self.ranks.is_root() && tally.frames.len() > before {
            output::write_pvd(&self.dir.join("solution.pvd"), &tally.frames)?;
        }
        Ok(())
    }
}
