//! The checkpoints observer: every `checkpoint_every` steps (not at the last), the frames sent
//! awaited, then `checkpoint.bin`, `steps.csv` and `summary.json` ("running"), so that all three
//! list the frames on disk. It keeps the seconds this took.
//!
//! In a distributed run every rank awaits its frames (the ranks agree on them: module
//! `listing`), rank 0 writes the files, and the ranks agree on its outcome, so that an error
//! there ends every rank at this step.

use std::time::Instant;

use super::files::Files;
use super::frames::Frames;
use super::recorder::Recorder;
use super::summary::RunStatus;
use crate::error::Error;
use crate::model::State;

/// The checkpoints of a run with a folder and a cadence.
pub(super) struct Checkpoints<'a> {
    files: Option<&'a Files<'a>>,
    every: Option<usize>,
    /// The run's last time level, which needs no checkpoint.
    steps: usize,
    seconds: f64,
}

impl<'a> Checkpoints<'a> {
    /// A checkpoint into `files` every `every` steps of a run of `steps` steps (none without
    /// both).
    pub fn new(files: Option<&'a Files<'a>>, every: Option<usize>, steps: usize) -> Self {
        Checkpoints {
            files,
            every,
            steps,
            seconds: 0.0,
        }
    }

    /// After the step that reached `state`: a checkpoint where one is due.
    pub fn step(&mut self, state: &State, frames: &mut Frames, recorder: &mut Recorder) -> Result<(), Error> {
        let Some(every) = self.every else { return Ok(()) };
        if !state.n.is_multiple_of(every) || state.n >= self.steps || (self.files.is_none() && !frames.in_pieces()) {
            return Ok(());
        }
        let clock = Instant::now();
        // The checkpoint and the summary list the frames on disk.
        frames.flush(&mut recorder.tally)?;
        let written = match self.files {
            Some(files) => {
                recorder.count_work();
                (files.checkpoint(state, &recorder.tally))
                    .and_then(|()| files.steps(&recorder.tally))
                    .and_then(|()| files.summary(&recorder.summary(RunStatus::Running, None)))
            }
            None => Ok(()),
        };
        frames.agree(written)?;
        self.seconds += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// The seconds the checkpoints took.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }
}
