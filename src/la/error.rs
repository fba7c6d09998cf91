//! The errors of the linear algebra: a factorization that breaks down, a solve that gives
//! non-finite values, a Krylov solve at its cap. They carry numbers, never the scenario keys
//! behind the matrix (the scenario layer names those: `crate::scenario`).

/// A failure of the linear algebra.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LaError {
    /// A factorization failed.
    #[error("factoring failed ({stage}: {detail}); the matrix is singular in floating point")]
    Factorization { stage: FactorStage, detail: String },
    /// A solve gave NaN or ±∞.
    #[error(
        "a linear solve gave {non_finite} non-finite values among {unknowns} unknowns: the matrix is singular \
         in floating point, or the data overflow"
    )]
    NonFiniteSolution { non_finite: usize, unknowns: usize },
    /// A Krylov solve hit its iteration cap.
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
    /// A call into PETSc or MPI failed (the distributed back-end, cargo feature `mpi`).
    #[error("PETSc failed in {operation}: {detail}")]
    Petsc { operation: &'static str, detail: String },
}

/// The stage of a factorization that failed.
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
    /// A dense Cholesky factor (the descent's metric: the contact compliance).
    Cholesky,
    /// The incomplete LU factor ILU(0).
    IncompleteLu,
    /// An AMG hierarchy (PETSc's GAMG).
    Multigrid,
    /// The step matrix condensed onto Γ_C through the bulk rows next to it (the predicted
    /// bounds' sweeps through the body: their Gauss–Seidel sweeps on those rows, or their rows
    /// missing on a rank).
    CondensedLayers,
}

impl std::fmt::Display for FactorStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FactorStage::Ordering => "the ordering",
            FactorStage::Symbolic => "the symbolic LDLᵀ",
            FactorStage::Numeric => "the numeric LDLᵀ",
            FactorStage::Layout => "the factor's layout",
            FactorStage::Cholesky => "the dense Cholesky factor",
            FactorStage::IncompleteLu => "the incomplete LU factor ILU(0)",
            FactorStage::Multigrid => "the AMG hierarchy (PETSc GAMG)",
            FactorStage::CondensedLayers => "the condensation of the bulk layers next to Γ_C (solver.condensed_layers)",
        })
    }
}
