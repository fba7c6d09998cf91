//! The library's error: each layer's own, wrapped (a mesh's, a problem's, a step's, the time
//! loop's, an output file's), and the scenario's keys and values that are refused.
//!
//! Depends on: [`crate::mesh`], [`crate::loads`], [`crate::la`], [`crate::model`],
//! [`crate::step`], [`crate::time`], [`crate::output`]. Only [`crate::scenario`] maps a failure
//! to the keys behind it ([`crate::scenario::keys_behind`]).

use std::path::PathBuf;

/// Errors of the thermocontact library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scenario key that does not exist.
    #[error("unknown scenario key `{key}` (expected one of {expected})")]
    UnknownKey { key: String, expected: String },
    /// A scenario key that its table needs and the scenario lacks (e.g. a law's parameter).
    #[error("the scenario lacks `{key}`, which its table needs here (see docs/scenario.md)")]
    MissingKey { key: String },
    /// A scenario key that no longer exists.
    #[error("`{key}` is no longer a scenario key: {instead}")]
    RemovedKey { key: String, instead: String },
    /// A scenario value outside its admissible range or of the wrong type.
    #[error("invalid value for `{key}`: {} (expected {expected})", shortened(value))]
    InvalidValue {
        key: String,
        value: String,
        expected: String,
    },
    /// A problem too large for the machine, found before anything is allocated.
    #[error(
        "{keys} give {unknowns:.3e} unknowns, which need about {needed} of memory (estimated for the {path}), \
         but this machine has {available}: use fewer cells{hint}"
    )]
    TooLarge {
        /// The keys that set the size.
        keys: String,
        /// What the estimate is for: `direct factorization` or `iterative solver`.
        path: &'static str,
        /// What else may help (the iterative path, for a direct run).
        hint: &'static str,
        unknowns: f64,
        needed: String,
        available: String,
    },
    /// A mesh that cannot be read or is not valid.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// A load that cannot be built or evaluated.
    #[error(transparent)]
    Load(#[from] crate::loads::LoadError),
    /// A scenario that does not parse.
    #[error("scenario: {0}")]
    Scenario(String),
    /// A problem that cannot be built (parts, loads, initial data).
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    /// A step's linear algebra or data failed: no cutback helps.
    #[error(transparent)]
    Step(#[from] crate::step::StepError),
    /// The time loop could not solve a step, even at its deepest cutback.
    #[error(transparent)]
    Time(crate::time::TimeError),
    /// Writing an output file failed.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// The run was stopped from outside between two steps (a signal, or a caller's observer).
    #[error("the run was interrupted ({cause}) after step {step} (t = {time})")]
    Interrupted {
        /// The last completed time level and its time.
        step: usize,
        time: f64,
        cause: Interruption,
    },
    /// The output folder cannot be used (locked by another run, or holding another run's
    /// results).
    #[error(transparent)]
    Folder(#[from] crate::output::folder::FolderError),
    /// A checkpoint that cannot be read or does not belong to this run.
    #[error(transparent)]
    Checkpoint(#[from] crate::output::checkpoint::CheckpointError),
    /// Reading an input file failed.
    #[error("cannot read {}: {source}", path.display())]
    Read { path: PathBuf, source: std::io::Error },
}

/// Who stopped a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Interruption {
    /// SIGINT (Ctrl-C).
    Interrupt,
    /// SIGTERM (a batch system's stop).
    Terminate,
    /// The program driving the run (an observer of the time loop) asked it to stop.
    Caller,
}

impl Interruption {
    /// The shell's exit code for a process stopped by this: 128 + the signal's number.
    pub fn exit_code(self) -> u8 {
        match self {
            Interruption::Interrupt => 130,
            Interruption::Terminate => 143,
            Interruption::Caller => 1,
        }
    }
}

impl std::fmt::Display for Interruption {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Interruption::Interrupt => "SIGINT",
            Interruption::Terminate => "SIGTERM",
            Interruption::Caller => "stopped by the caller",
        })
    }
}

impl From<crate::la::LaError> for Error {
    fn from(e: crate::la::LaError) -> Self {
        Error::Step(e.into())
    }
}

impl From<crate::time::TimeError> for Error {
    fn from(e: crate::time::TimeError) -> Self {
        match e {
            crate::time::TimeError::Step(step) => Error::Step(step),
            other => Error::Time(other),
        }
    }
}

/// A value as an error shows it: whole up to 160 characters, else its start and end around the
/// number of characters left out (a 100 kB expression is not echoed to the terminal).
fn shortened(value: &str) -> String {
    let n = value.chars().count();
    if n <= 160 {
        return value.to_string();
    }
    let head: String = value.chars().take(100).collect();
    let tail: String = value.chars().skip(n - 40).collect();
    format!("{head}…[{} characters]…{tail}", n - 140)
}
