//! The frames of a run (`.vtu`, contact CSV, `solution.pvd` rewritten) written on a thread of
//! their own, so that the time loop does not wait for them.
//!
//! At an output time the loop sends the writer an owned copy of the state and of the output
//! record (a few vectors of the mesh's size) through a channel that holds [`QUEUE`] frames:
//! memory holds at most `QUEUE + 1` frames' data, and a loop that gets that far ahead waits.
//! The writer computes the frame's fields (stress, von Mises, contact fields), encodes and
//! writes the files, and rewrites `solution.pvd` after each frame, exactly as the loop did
//! before: the collection always lists exactly the frames written whole, and every file is whole
//! or absent ([`crate::output::atomic`]). Frames are written in the order they were sent, one at
//! a time.
//!
//! The loop looks for the writer's reports every step ([`FrameWriter::poll`]) and waits for all
//! of them ([`FrameWriter::flush`]) before it writes a checkpoint or `summary.json`, and at the
//! end of the run ([`FrameWriter::finish`]), so that these list the frames on disk. An error of
//! the writer (an I/O error) stops the writer at that frame: the frames queued behind it are
//! dropped, the run keeps no output record of any of them (as where the loop itself stopped at
//! the frame), and the error comes back to the loop as it is, which stops the run the way it
//! stopped at a failed frame before — a step or two later at most.
//!
//! `inline` writes each frame on the loop's thread at once instead (no thread), through the
//! same code: the files are the same bytes either way (`tests/run_folder.rs` checks it).
//!
//! **In pieces** (a rank of a distributed run, [`Layout::Piece`]) the writer writes this rank's
//! piece of each frame and does not touch `solution.pvd`: the frames it has written wait in
//! [`FrameWriter::take_written`] until every rank has written its own (module `listing`, the
//! ranks' agreement), and rank 0 then lists them.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, SyncSender};
use std::thread::{Scope, ScopedJoinHandle};
use std::time::Instant;

use super::snapshot::{write_snapshot, Layout, Written};
use super::summary::{OutputRecord, Tally};
use super::OutputPlan;
use crate::error::Error;
use crate::model::Problem;
use crate::model::State;
use crate::output::{self, PvdEntry};

/// Frames sent to the writer and not yet taken up, beyond the one it writes.
pub const QUEUE: usize = 1;

/// What writes the frames of a run into its folder, and what it has written.
struct FrameFiles<'a> {
    problem: &'a Problem,
    plan: &'a OutputPlan,
    dir: PathBuf,
    layout: &'a Layout,
    /// The frames written whole, as `solution.pvd` lists them.
    frames: Vec<PvdEntry>,
}

impl FrameFiles<'_> {
    /// Writes the frame of `state`; its `.vtu` (none without `.vtu` files), the collection
    /// rewritten where the frame is whole.
    fn write(&mut self, state: &State, record: &OutputRecord) -> Result<Option<Written>, Error> {
        let written = write_snapshot(self.problem, self.plan, state, record, &self.dir, self.layout)?;
        if let Some(Written::Whole(entry)) = &written {
            self.frames.push(entry.clone());
            output::write_pvd(&self.dir.join("solution.pvd"), &self.frames)?;
        }
        Ok(written)
    }
}

/// A frame for the writer thread: owned copies.
struct Job {
    state: State,
    record: OutputRecord,
}

/// The writer's report on one frame.
struct Done {
    outcome: Result<Option<Written>, Error>,
    seconds: f64,
}

enum Mode<'scope, 'env> {
    Inline(FrameFiles<'env>),
    Thread {
        /// `None` once [`FrameWriter::finish`] has closed it.
        jobs: Option<SyncSender<Job>>,
        done: Receiver<Done>,
        handle: Option<ScopedJoinHandle<'scope, ()>>,
    },
}

/// The run's frame writer: a thread in `scope`, or the loop's own thread (`inline`).
pub struct FrameWriter<'scope, 'env> {
    mode: Mode<'scope, 'env>,
    /// Time levels sent and not yet reported, in order.
    pending: VecDeque<usize>,
    /// Seconds spent on the frames reported (on the writer's thread, or inline).
    seconds: f64,
    /// In pieces: the frames written and not yet taken, in order (none without `.vtu` files).
    written: Option<VecDeque<Option<Written>>>,
}

impl<'scope, 'env> FrameWriter<'scope, 'env> {
    /// A writer of frames into `dir`, after the `frames` already there (a continued run's).
    pub fn start(
        scope: &'scope Scope<'scope, 'env>,
        problem: &'env Problem,
        plan: &'env OutputPlan,
        (dir, layout): (&Path, &'env Layout),
        frames: Vec<PvdEntry>,
        inline: bool,
    ) -> Self {
        let files = |frames| FrameFiles {
            problem,
            plan,
            dir: dir.to_path_buf(),
            layout,
            frames,
        };
        let mode = if inline {
            Mode::Inline(files(frames))
        } else {
            let (jobs, queue) = mpsc::sync_channel::<Job>(QUEUE);
            let (report, done) = mpsc::channel();
            let mut thread_files = files(frames.clone());
            let spawned = std::thread::Builder::new()
                .name("frame writer".into())
                .spawn_scoped(scope, move || {
                    for job in queue {
                        let clock = Instant::now();
                        let outcome = thread_files.write(&job.state, &job.record);
                        let failed = outcome.is_err();
                        let seconds = clock.elapsed().as_secs_f64();
                        // The loop gone, or this frame failed: no more frames (those queued are
                        // dropped with the channel).
                        if report.send(Done { outcome, seconds }).is_err() || failed {
                            break;
                        }
                    }
                });
            match spawned {
                Ok(handle) => Mode::Thread {
                    jobs: Some(jobs),
                    done,
                    handle: Some(handle),
                },
                // No thread to be had (the OS refused one): the frames are written inline.
                Err(_) => Mode::Inline(files(frames)),
            }
        };
        FrameWriter {
            mode,
            pending: VecDeque::new(),
            seconds: 0.0,
            written: matches!(layout, Layout::Piece { .. }).then(VecDeque::new),
        }
    }

    /// Writes the frame of `state` (with `record`, which the caller adds to `tally.outputs`
    /// once this returns): sends it to the writer, waiting while [`QUEUE`] frames are queued,
    /// or writes it at once (`inline`). Reports an error of an earlier frame first.
    pub fn submit(&mut self, state: &State, record: &OutputRecord, tally: &mut Tally) -> Result<(), Error> {
        self.poll(tally)?;
        self.pending.push_back(state.n);
        match &mut self.mode {
            Mode::Inline(files) => {
                let clock = Instant::now();
                let outcome = files.write(state, record);
                let seconds = clock.elapsed().as_secs_f64();
                self.report(Done { outcome, seconds }, tally)
            }
            Mode::Thread { jobs, .. } => {
                let job = Job {
                    state: state.clone(),
                    record: record.clone(),
                };
                let sent = jobs.as_ref().is_some_and(|jobs| jobs.send(job).is_ok());
                if sent {
                    Ok(())
                } else {
                    // The writer stopped at a failed frame, whose report is on its way.
                    self.flush(tally)
                }
            }
        }
    }

    /// Takes the writer's reports so far without waiting: the frames written go to
    /// `tally.frames` (in pieces: to [`FrameWriter::take_written`]); the first error comes back.
    pub fn poll(&mut self, tally: &mut Tally) -> Result<(), Error> {
        while !self.pending.is_empty() {
            let Mode::Thread { done, .. } = &self.mode else { break };
            match done.try_recv() {
                Ok(report) => self.report(report, tally)?,
                Err(_) => break,
            }
        }
        Ok(())
    }

    /// Waits until every frame sent is written (or the writer has stopped at an error, which
    /// comes back).
    pub fn flush(&mut self, tally: &mut Tally) -> Result<(), Error> {
        while !self.pending.is_empty() {
            let Mode::Thread { done, handle, .. } = &mut self.mode else {
                break;
            };
            match done.recv() {
                Ok(report) => self.report(report, tally)?,
                // The writer ended without a report on every frame: only a panic does that.
                Err(_) => {
                    if let Some(Err(panic)) = handle.take().map(ScopedJoinHandle::join) {
                        std::panic::resume_unwind(panic);
                    }
                    unreachable!("the frame writer ended with frames pending");
                }
            }
        }
        Ok(())
    }

    /// Waits for every frame sent ([`FrameWriter::flush`]) and ends the thread; the seconds
    /// spent on all the frames.
    pub fn finish(mut self, tally: &mut Tally) -> (f64, Result<(), Error>) {
        let flushed = self.flush(tally);
        if let Mode::Thread { jobs, handle, .. } = &mut self.mode {
            drop(jobs.take());
            if let Some(Err(panic)) = handle.take().map(ScopedJoinHandle::join) {
                std::panic::resume_unwind(panic);
            }
        }
        (self.seconds, flushed)
    }

    /// In pieces: the frames written since the last call, oldest first, up to `count` (those
    /// written so far: [`FrameWriter::n_written`]).
    pub fn take_written(&mut self, count: usize) -> Vec<Option<Written>> {
        let pieces = self.written.as_mut().expect("a writer in pieces");
        pieces.drain(..count).collect()
    }

    /// In pieces: the frames written and not yet taken.
    pub fn n_written(&self) -> usize {
        self.written.as_ref().map_or(0, VecDeque::len)
    }

    /// The report on the oldest pending frame.
    fn report(&mut self, report: Done, tally: &mut Tally) -> Result<(), Error> {
        self.seconds += report.seconds;
        let n = self.pending.pop_front().expect("a report answers a frame sent");
        match (report.outcome, &mut self.written) {
            (Ok(written), Some(pieces)) => {
                pieces.push_back(written);
                Ok(())
            }
            (Ok(written), None) => {
                if let Some(Written::Whole(entry)) = written {
                    tally.frames.push(entry);
                }
                Ok(())
            }
            (Err(error), _) => {
                // This frame is not on disk (its CSV may be), nor are those queued behind it,
                // which the writer drops: the run keeps no record of them, as where the loop
                // stopped at the frame itself.
                let lost: Vec<usize> = std::iter::once(n).chain(self.pending.drain(..)).collect();
                tally.outputs.retain(|o| !lost.contains(&o.n));
                Err(error)
            }
        }
    }
}
