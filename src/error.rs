//! The library's error type: everything user input or a non-converging solver can cause.

use std::path::PathBuf;

/// Errors of the thermocontact library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scenario key that does not exist.
    #[error("unknown scenario key `{key}` (expected one of {expected})")]
    UnknownKey { key: String, expected: String },
    /// A scenario key that its table needs and the scenario lacks (e.g. a law's parameter).
    #[error("the scenario lacks `{key}`, which its table needs here (see the README's scenario format)")]
    MissingKey { key: String },
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
    /// Nodal initial fields whose sizes are not the mesh's.
    #[error("`{label}` has fields of {found:?} values, but the mesh needs {expected:?} (u₀, u₁, θ₀)")]
    InitialFieldSizes {
        label: String,
        found: Vec<usize>,
        expected: Vec<usize>,
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
    #[error(
        "factoring the step matrix failed ({stage}: {detail}); the matrix is singular in floating point. It is \
         built from {DATA_KEYS}: check their magnitudes"
    )]
    Factorization { stage: FactorStage, detail: String },
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
        "a linear solve with the step matrix gave {non_finite} non-finite values among {unknowns} unknowns: the \
         step matrix is singular in floating point, or the data overflow. They come from {DATA_KEYS} and the \
         loads: check their magnitudes"
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

/// The scenario keys the step matrix is built from (named where it turns out singular).
const DATA_KEYS: &str = "material.density, material.young, material.poisson, material.viscosity_mu1, \
                         material.viscosity_mu2, material.conductivity, material.heat_capacity, \
                         material.thermal_expansion, heat_exchange.coefficient, the mesh's cell sizes and time.steps (k)";

/// The stage of factoring the step matrix that failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FactorStage {
    /// The fill-reducing ordering.
    Ordering,
    /// The symbolic LDLᵀ.
    Symbolic,
    /// The numeric LDLᵀ.
    Numeric,
    /// The factor's layout is not the supernodal one the sweeps read.
    Layout,
    /// The Cholesky factor of the contact compliance D on Γ_C (the descent's metric).
    ContactCompliance,
    /// The incomplete LU factor ILU(0) that preconditions the Krylov solver.
    IncompleteLu,
    /// The AMG hierarchy of the velocity block (PETSc's GAMG, `solver.preconditioner = "amg"`).
    Multigrid,
}

impl std::fmt::Display for FactorStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FactorStage::Ordering => "the ordering",
            FactorStage::Symbolic => "the symbolic LDLᵀ",
            FactorStage::Numeric => "the numeric LDLᵀ",
            FactorStage::Layout => "the factor's layout",
            FactorStage::ContactCompliance => "the contact compliance's Cholesky factor",
            FactorStage::IncompleteLu => "the incomplete LU factor ILU(0)",
            FactorStage::Multigrid => "the AMG hierarchy of the velocity block (PETSc GAMG)",
        })
    }
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
