//! The library's error type: everything user input or a non-converging solver can cause.

use std::path::PathBuf;

/// Errors of the thermocontact library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scenario key that does not exist.
    #[error("unknown scenario key `{key}` (expected one of {expected})")]
    UnknownKey { key: String, expected: String },
    /// A scenario value outside its admissible range or of the wrong type.
    #[error("invalid value for `{key}`: {value} (expected {expected})")]
    InvalidValue {
        key: String,
        value: String,
        expected: String,
    },
    /// A scenario that does not parse.
    #[error("scenario: {0}")]
    Scenario(String),
    /// The sparse factorization of the step matrix failed.
    #[error("factorization of the step matrix failed: {0}")]
    Factorization(String),
    /// The nonsmooth solver hit its iteration cap.
    #[error(
        "the {solver} solver did not converge at time step {step} (t = {time}): after {iterations} \
         {loop_name} iterations the relative increments are {residuals} (tolerance {tolerance:e})"
    )]
    NotConverged {
        solver: &'static str,
        loop_name: &'static str,
        step: usize,
        time: f64,
        iterations: usize,
        residuals: String,
        tolerance: f64,
    },
    /// Writing an output file failed.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// Reading an input file failed.
    #[error("cannot read {}: {source}", path.display())]
    Read { path: PathBuf, source: std::io::Error },
}
