//! The library's error type: everything user input or a non-converging solver can cause.

use std::path::PathBuf;

/// Errors of the thermocontact library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scenario key that does not exist.
    #[error("unknown scenario key `{key}` (expected one of {expected})")]
    UnknownKey { key: String, expected: String },
    /// A scenario key that no longer exists.
    #[error("`{key}` is no longer a scenario key: {instead}")]
    RemovedKey { key: String, instead: String },
    /// A scenario value outside its admissible range or of the wrong type.
    #[error("invalid value for `{key}`: {value} (expected {expected})")]
    InvalidValue {
        key: String,
        value: String,
        expected: String,
    },
    /// A boundary part the mesh does not have.
    #[error("the mesh has no boundary part `{name}` (named for {role}); its parts are {known:?}")]
    UnknownPart {
        role: String,
        name: String,
        known: Vec<String>,
    },
    /// A traction or pressure on a part that is not a Neumann part.
    #[error("`{label}` acts on `{part}`, which is not a Neumann part (those are {neumann:?})")]
    LoadOffNeumann {
        label: String,
        part: String,
        neumann: Vec<String>,
    },
    /// Initial data outside E^h: not zero on Γ_D, a normal component on Γ_C, or across a
    /// symmetry plane.
    #[error(
        "`{label}` is not admissible at node {node} (x = {x:?}): {value:?} must vanish on Γ_D and have no \
         normal component on Γ_C or across a symmetry plane"
    )]
    InitialNotAdmissible {
        label: String,
        node: usize,
        x: [f64; 3],
        value: Vec<f64>,
    },
    /// Two boundary parts given roles share facets (one facet in two physical groups).
    #[error(
        "the boundary parts `{first}` and `{second}` share facets: give each facet one role (in Gmsh, put it in one physical group)"
    )]
    PartsShareFacets { first: String, second: String },
    /// A symmetry part that is not flat.
    #[error("the symmetry part `{part}` is not flat (a symmetry plane needs one normal)")]
    CurvedSymmetryPart { part: String },
    /// A mesh that cannot be read or is not valid.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// A load that cannot be built or evaluated.
    #[error(transparent)]
    Load(#[from] crate::loads::LoadError),
    /// A scenario that does not parse.
    #[error("scenario: {0}")]
    Scenario(String),
    /// The sparse factorization of the step matrix failed.
    #[error("factorization of the step matrix failed: {0}")]
    Factorization(String),
    /// The nonsmooth solver hit its iteration cap, at the step size k and at every cutback.
    #[error(
        "time step {step} (t = {time}) did not converge{}: {failure}",
        cutback_phrase(*cutback_depth)
    )]
    NotConverged {
        step: usize,
        time: f64,
        /// The deepest cutback tried (0: none): substeps of k/2^depth.
        cutback_depth: usize,
        failure: crate::solver::StepFailure,
    },
    /// A linear solve with the factored step matrix gave NaN or ±∞.
    #[error(
        "a linear solve with the step matrix gave {non_finite} non-finite values among {unknowns} unknowns \
         (the step matrix is singular, or the data overflow)"
    )]
    NonFiniteSolution { non_finite: usize, unknowns: usize },
    /// A Krylov solve of the step system hit its iteration cap.
    #[error(
        "{method} did not reach ‖b − Ax‖ ≤ {rtol:e} ‖b‖ in {iterations} iterations (relative residual {residual:e})"
    )]
    KrylovNotConverged {
        method: &'static str,
        iterations: usize,
        rtol: f64,
        /// The last relative residual.
        residual: f64,
        /// The relative residual before the first iteration and after each one (as the method
        /// estimates it).
        history: Vec<f64>,
    },
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

fn cutback_phrase(depth: usize) -> String {
    match depth {
        0 => String::new(),
        d => format!(" even in {} substeps of k/{}", 1usize << d, 1usize << d),
    }
}
