//! The files of a run in its folder: claimed at the start, `scenario.toml`, `solution.pvd` and a
//! `running` summary before the march, `steps.csv`, `summary.json`, the checkpoint and a frame
//! on request, and what a run leaves when it ends ([`Files::close`]).

use std::path::Path;

use super::recorder::Recorder;
use super::snapshot::{record, write_snapshot, Layout, Written};
use super::summary::{FailureRecord, OutputRecord, RunStatus, StepRecord, Summary, Tally};
use super::{OutputPlan, RunOptions, CHECKPOINT_FILE};
use crate::error::Error;
use crate::model::Problem;
use crate::model::State;
use crate::output;
use crate::output::checkpoint::{self, Checkpoint, Identity};
use crate::output::folder::{Existing, RunFolder};

/// What a checkpoint must match to be continued: the scenario and the mesh.
pub(super) fn identity(problem: &Problem, plan: &OutputPlan) -> Identity {
    Identity {
        scenario: plan.fingerprint.clone(),
        mesh: checkpoint::mesh_fingerprint(&problem.mesh),
    }
}

/// The files of a run in its folder.
pub(super) struct Files<'a> {
    folder: RunFolder,
    plan: &'a OutputPlan,
    problem: &'a Problem,
}

impl<'a> Files<'a> {
    /// Claims `options.out_dir` (none: no files): refused where it holds another run's results,
    /// unless they are replaced (`overwrite`, or `replace_completed` for a completed run's) or continued (`restart`, with the frames of its
    /// `tally`).
    pub fn claim(
        problem: &'a Problem,
        plan: &'a OutputPlan,
        options: &RunOptions,
        tally: &Tally,
    ) -> Result<Option<Self>, Error> {
        let Some(dir) = &options.out_dir else { return Ok(None) };
        let existing = match (&options.restart, options.overwrite) {
            (Some(_), _) => Existing::Continue {
                frames: tally.outputs.iter().map(|o| o.n).collect(),
            },
            (None, true) => Existing::Overwrite,
            (None, false) if options.replace_completed => Existing::ReplaceCompleted,
            (None, false) => Existing::Refuse,
        };
        Ok(Some(Files {
            folder: RunFolder::claim(dir, &existing)?,
            plan,
            problem,
        }))
    }

    pub fn dir(&self) -> &Path {
        self.folder.dir()
    }

    fn io(&self, name: &str) -> impl FnOnce(std::io::Error) -> Error + '_ {
        let path = self.dir().join(name);
        move |source| output::OutputError::Io { path, source }.into()
    }

    /// Before the march: the input (`scenario.toml`), the collection of the frames so far (a
    /// continued run's, up to its checkpoint), and `summary.json` saying `running`.
    pub fn open(&self, recorder: &Recorder) -> Result<(), Error> {
        if let Some(record) = &self.plan.record {
            output::write_atomic(&self.dir().join("scenario.toml"), record.as_bytes())
                .map_err(self.io("scenario.toml"))?;
        }
        if self.plan.vtk {
            output::write_pvd(&self.dir().join("solution.pvd"), &recorder.tally.frames)?;
        }
        self.summary(&recorder.summary(RunStatus::Running, None))
    }

    pub fn summary(&self, summary: &Summary) -> Result<(), Error> {
        let json = serde_json::to_vec_pretty(summary).expect("a summary serializes");
        output::write_atomic(&self.dir().join("summary.json"), &json).map_err(self.io("summary.json"))
    }

    pub fn steps(&self, tally: &Tally) -> Result<(), Error> {
        let rows: Vec<Vec<f64>> = tally.steps.iter().map(StepRecord::row).collect();
        output::write_csv(&self.dir().join("steps.csv"), &StepRecord::HEADER, &rows)?;
        Ok(())
    }

    /// The frame of `state`, whole (and its `.pvd` entry, the collection rewritten). Rank 0 of
    /// a distributed run writes it so too: every rank holds the whole state, and this frame
    /// (a stopped run's last state) is written where the ranks no longer agree on anything.
    fn frame(&self, state: &State, record: &OutputRecord, tally: &mut Tally) -> Result<(), Error> {
        let written = write_snapshot(self.problem, self.plan, state, record, self.dir(), &Layout::Whole)?;
        if let Some(Written::Whole(entry)) = written {
            tally.frames.push(entry);
            output::write_pvd(&self.dir().join("solution.pvd"), &tally.frames)?;
        }
        Ok(())
    }

    pub fn checkpoint(&self, state: &State, tally: &Tally) -> Result<(), Error> {
        let checkpoint = Checkpoint {
            identity: identity(self.problem, self.plan),
            state: state.clone(),
            record: serde_json::to_value(tally).expect("a tally serializes"),
        };
        checkpoint::write(&self.dir().join(CHECKPOINT_FILE), &checkpoint).map_err(self.io(CHECKPOINT_FILE))
    }

    /// What a run leaves when it ends at `state` with `status` (`failure`: it stopped early): a stopped run's
    /// checkpoint and last frame, or a completed run's checkpoint removed; then `steps.csv` and
    /// `summary.json`, its output time `waited` plus these files'. Each file is tried even where
    /// one before it failed, so that a stopped run still leaves its summary: the first error
    /// comes back, the others are logged.
    pub fn close(
        &self,
        state: &State,
        status: RunStatus,
        failure: Option<&FailureRecord>,
        recorder: &mut Recorder,
        waited: f64,
        log: impl Fn(String),
    ) -> Result<(), Error> {
        let clock = std::time::Instant::now();
        let mut first = None;
        let mut keep = |written: Result<(), Error>| match (written, &first) {
            (Err(error), None) => first = Some(error),
            (Err(error), Some(_)) => log(format!("error: {error}")),
            (Ok(()), _) => {}
        };
        if failure.is_some() {
            // A stopped run keeps its last completed state: as a checkpoint to continue from
            // (with the planned frames only: a continued run drops the next one), and as a frame
            // beside those written so far, unless it has one (an output time whose frame was
            // written).
            if state.n > 0 {
                keep(self.checkpoint(state, &recorder.tally));
            }
            if !recorder.tally.outputs.iter().any(|o| o.n == state.n) {
                let record = record(self.problem, state, self.plan.slip_tolerance);
                keep(self.frame(state, &record, &mut recorder.tally));
            }
        } else {
            // A completed run's checkpoint is of no use any more, whether this run wrote it
            // (`checkpoint_every`) or the stopped run it continued did; left in place,
            // `--restart` would silently compute the end again from it.
            match std::fs::remove_file(self.dir().join(CHECKPOINT_FILE)) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => keep(Err(self.io(CHECKPOINT_FILE)(e))),
                _ => {}
            }
        }
        keep(self.steps(&recorder.tally));
        recorder.ended(waited + clock.elapsed().as_secs_f64());
        keep(self.summary(&recorder.summary(status, failure.cloned())));
        first.map_or(Ok(()), Err)
    }
}
