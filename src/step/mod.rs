//! One time step: the nonsmooth solvers of Problem 17 over two linear back-ends.
//!
//! Depends on: [`crate::model`] (the problem, the state, the step matrix, the norms),
//! [`crate::la`], [`crate::contact`] (the laws' projections).
//!
//! - **Back-ends.** [`StepSystem`]: the step matrix factored once per step size (LDLᵀ) and each
//!   step condensed onto Γ_C ([`Condensation`]); [`KrylovSystem`]: the step matrix ordered with its
//!   Γ_C rows last, ILU(0) (and an AMG correction, [`VelocityAmg`]), GMRES on all unknowns.
//! - **The loop.** `convexification::convexify`: the convexification loop of Problem 17, one function
//!   generic over its convex-problem solver and its stop test; every solver below runs it.
//! - **Solvers.** [`PaperSolver`] (Uzawa inner iterations on Γ_C) and [`PaperKrylov`] (the same on
//!   the iterative back-end): `kind = "paper"`. [`FastSolver`] (Newton on the condensed law, then the
//!   loop with descent inner solves, then the descent of [`descend`]) and [`NewtonKrylov`] (the
//!   loop with semismooth-Newton inner solves on all unknowns): `kind = "fast"` on the two paths
//!   ([`StepSolver`] says which is which).
//! - **Figures and failures.** [`StepInfo`] per step, [`StepFailure`] (criterion, value,
//!   tolerance) where a solver gives up, [`StepError`] for what stops a run.

pub mod abort;
mod amg;
mod anderson;
mod condensed;
mod contact_condensation;
mod convexification;
mod descent;
mod direct;
mod fast;
pub mod heartbeat;
mod iterative;
mod newton;
mod newton_krylov;
mod paper;
mod paper_krylov;
#[cfg(feature = "mpi")]
mod ranks;
mod select;

use serde::{Deserialize, Serialize};

use crate::la::{GmresParams, LaError};
use crate::model::ModelError;

pub use amg::VelocityAmg;
pub use condensed::Condensation;
pub use descent::{descend, ContactStiffness, DescentParams, Start};
pub use direct::{add_contact_terms, tangential_velocities, FreeStep, StepSystem, SystemStats};
pub use fast::FastSolver;
pub use iterative::KrylovSystem;
pub use newton::{CondensedStep, NewtonParams, NewtonResult};
pub use newton_krylov::NewtonKrylov;
pub use paper::{PaperParams, PaperSolver};
pub use paper_krylov::PaperKrylov;
pub use select::{LinearSystem, StepSolver, COMPLIANCE_ESTIMATE_UP_TO, EXCHANGE_ITERATIONS};

/// What stops a step for good (no cutback helps): the linear algebra or the model's data.
#[derive(Debug, thiserror::Error)]
pub enum StepError {
    /// A factorization or solve of the step matrix (or its Newton linearization) failed.
    #[error("the step matrix: {0}")]
    La(#[from] LaError),
    /// A load or datum could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The step was cut short from outside ([`abort`]): not a failure, no cutback retries it.
    #[error("the step was cut short (a second stop request)")]
    Aborted,
}

/// Tolerance and caps of a Krylov solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KrylovParams {
    /// Stop when ‖b − A x‖ ≤ rtol ‖b‖ (the unpreconditioned residual; in one process carried
    /// through each GMRES cycle by the Arnoldi relation, equal to b − A x to rounding).
    pub rtol: f64,
    /// The Newton–Krylov solver's forcing term η: each Newton iteration's solve also stops
    /// once ‖b̃ − Ã x‖ ≤ η ‖b̃ − Ã x₀‖ from the last iterate x₀ (the looser of that and rtol;
    /// [`crate::la::Gmres::solve_inexact`]; `step::newton_krylov`); 0: every solve to rtol.
    /// Default [`KrylovParams::NEWTON_FORCING`].
    pub forcing: f64,
    /// Iteration cap (products with A).
    pub max_iterations: usize,
    /// GMRES restart length.
    pub restart: usize,
    /// ILU(0) alone, or with the AMG coarse correction of the velocities ([`VelocityAmg`]).
    pub preconditioner: PreconditionerKind,
    /// Run the solves on PETSc over the MPI ranks of the process's world (cargo feature `mpi`,
    /// `mpirun -n P`): every rank holds the problem and the iterates, each owns the rows of Ã
    /// of its part of the mesh; the preconditioner is then ILU(0) on each rank's block (`ilu`,
    /// with the ranks' blocks overlapping by [`KrylovParams::overlap`]) or those sweeps around
    /// PETSc's GAMG on the velocity block (`amg`), `auto` by the same probe
    /// (docs/distributed.md). Default: false.
    pub distributed: bool,
    /// In a distributed run with ILU(0): 0, block Jacobi (each rank's block its own rows and
    /// columns); 1, restricted additive Schwarz (each rank's block also holds the rows of other
    /// ranks that its rows read, and the rank keeps its own entries of the result). Default 1:
    /// at 972k unknowns on 2 ranks, 304 Krylov iterations against block Jacobi's 344 (one
    /// process: 303). Not read in one process.
    pub overlap: usize,
    /// The layers of bulk unknowns next to Γ_C through which the predicted bounds' sweeps see
    /// the body follow (`solver.condensed_layers`: the step matrix condensed onto Γ_C through
    /// them, `contact_condensation`; at the first sweep in one process, at set-up on the ranks,
    /// which then also assemble those layers' rows). 0: Γ_C's own rows, the body held.
    /// Default 2.
    pub condensed_layers: usize,
}

/// How the iterative path's sweeps over Γ_C predict the bounds of each convexification iterate
/// after the first (`solver.prediction`; [`SolverParams::contact_sweeps`] sweeps, through
/// [`KrylovParams::condensed_layers`] layers of the body; the `newton_krylov` module header).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Prediction {
    /// The convexification loop itself, run on Γ_C's rows between two solves: each node's
    /// bound frozen at its slip after the last bound update, the sweeps solving that convex
    /// problem on the rows, the bounds of its slip the next update's, until they settle. The
    /// loop's front is carried where the solves would carry it one ring at a time, so the step
    /// lands on the paper's loop's solution where the rows model the body well (every case
    /// measured with one solution per step, and the 3D example at 17k unknowns over 64 steps).
    #[default]
    Loop,
    /// Each node's slip the local minimizer of its nodal problem with the law itself, reached
    /// downhill from its current slip: a front crosses in fewer sweeps, but where a step has
    /// several solutions it may settle on another than the loop's.
    Law,
}

/// The largest [`KrylovParams::overlap`] there is.
pub const MAX_OVERLAP: usize = 1;

/// The preconditioner of the iterative path's GMRES.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PreconditionerKind {
    /// ILU(0) of the Newton matrix: bounded iterations while the mass term dominates (the
    /// paper's k), growing like h⁻¹ once the stiffness weighs.
    #[default]
    Ilu,
    /// ILU(0) sweeps around a smoothed-aggregation AMG correction of the velocities (PETSc's
    /// GAMG; builds with the `petsc` feature): bounded iterations where the stiffness weighs.
    Amg,
    /// [`PreconditionerKind::Amg`] where the build has it and ILU(0) needs more than
    /// [`PreconditionerKind::AUTO_AMG_ABOVE`] Krylov iterations for the first step's system,
    /// [`PreconditionerKind::Ilu`] otherwise ([`iterative::KrylovSystem::new`]).
    Auto,
}

impl PreconditionerKind {
    /// The ILU(0) Krylov count (first step's system from zero, relative residual 10⁻⁸) above
    /// which `auto` sets up the AMG. An AMG-preconditioned iteration costs 4–6 ILU(0) ones (two
    /// sweeps, two products with Ã and PETSc's single-threaded V-cycle), and the warm-started
    /// Newton solves of a run need fewer iterations than this cold probe, so the AMG pays only
    /// where ILU(0)'s count is far beyond its own 7–14. Measured on the 3D example at 70k
    /// unknowns, 4 steps (docs/performance.md): at k = 1/8 (probe 19) ILU(0) runs the solves
    /// in 4.9 s, the AMG in 9.5 s; at k = 1/2 (probe 71) 30.3 s against 30.5 s; at k = 1 (probe
    /// 146) 39.0 s against 22.6 s.
    pub const AUTO_AMG_ABOVE: usize = 80;

    /// The name in scenarios and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            PreconditionerKind::Ilu => "ilu",
            PreconditionerKind::Amg => "amg",
            PreconditionerKind::Auto => "auto",
        }
    }
}

impl Default for KrylovParams {
    fn default() -> Self {
        KrylovParams {
            rtol: 1e-10,
            forcing: KrylovParams::NEWTON_FORCING,
            max_iterations: 500,
            restart: 30,
            preconditioner: PreconditionerKind::Ilu,
            distributed: false,
            overlap: 1,
            condensed_layers: 2,
        }
    }
}

impl KrylovParams {
    /// The default forcing term of the Newton–Krylov solver's solves. Measured on the
    /// iterative path against 0 (every solve to rtol, the builds before): the 3D example at
    /// 972k unknowns, 4 steps, 303 → 149 Krylov iterations (the same 64 Newton iterations), at
    /// 47k with k = 1/8, 8 steps, 7 306 → 2 302, the same slip counts at every step and the
    /// contact fields within 2·10⁻⁷. 0.03 saves more there (121, 1 814) but costs the brake pad
    /// a Newton iteration per pressure iterate and ends its last step at another solution;
    /// docs/performance.md has the tables.
    pub const NEWTON_FORCING: f64 = 0.01;

    /// The GMRES settings of these.
    pub fn gmres(&self) -> GmresParams {
        GmresParams {
            rtol: self.rtol,
            max_iterations: self.max_iterations,
            restart: self.restart,
        }
    }
}

/// Which nonsmooth solver runs each time step.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SolverKind {
    /// Convexification loop + Uzawa augmented Lagrangian (Problem 17).
    Paper,
    /// Semismooth Newton on the condensed nonmonotone law, the convexification loop where the
    /// law is too steep, and a descent on the step's energy where both fail.
    Fast,
}

impl SolverKind {
    /// The name in scenarios and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            SolverKind::Paper => "paper",
            SolverKind::Fast => "fast",
        }
    }
}

/// How the linear systems of a step are solved.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum LinearKind {
    /// The LDLᵀ factor of the step matrix, the step condensed onto Γ_C ([`StepSystem`]).
    Direct,
    /// GMRES + ILU(0) inside a Newton method on all unknowns, nothing condensed
    /// ([`NewtonKrylov`]).
    Iterative,
    /// The path whose estimated run is cheaper, for the unknowns, the contact nodes and the
    /// steps at hand ([`LinearKind::choose`]).
    Auto,
}

impl LinearKind {
    /// The name in scenarios and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            LinearKind::Direct => "direct",
            LinearKind::Iterative => "iterative",
            LinearKind::Auto => "auto",
        }
    }

    /// The share of the machine's memory that `auto` lets the direct path's estimated peak
    /// take before it takes the iterative path.
    pub const AUTO_DIRECT_MEMORY_SHARE: f64 = 0.5;

    /// The most unknowns for which `auto` takes the direct path in 3D: where the two paths'
    /// whole runs cross.
    pub const AUTO_DIRECT_UNKNOWNS_3D: usize = 70_000;

    /// Outer (convexification) iterations per step that `auto` assumes on both paths (measured:
    /// 5–11 at k = 1/64 on every body of the table in [`LinearKind::choose`], the same on both
    /// paths within 10 %).
    pub const AUTO_OUTER_PER_STEP: f64 = 10.0;

    /// Seconds per entry of the direct factor to factor it (and assemble, condense): the
    /// set-up of the direct path (measured 2.1–5.1·10⁻⁸ on the bodies of [`LinearKind::choose`]).
    pub const AUTO_DIRECT_SECONDS_PER_FACTOR_ENTRY: f64 = 3.5e-8;

    /// Seconds per step per entry of the direct factor: each step's sparse solves with it
    /// (measured 8.3·10⁻¹⁰–1.0·10⁻⁹).
    pub const AUTO_DIRECT_SECONDS_PER_FACTOR_ENTRY_STEP: f64 = 9e-10;

    /// Seconds per outer iteration per entry of the dense compliance on Γ_C (n_t², n_t = (d − 1)
    /// × contact nodes): the direct path's nonsmooth iterations are dense products with C
    /// (measured 4.8·10⁻¹⁰–9.8·10⁻¹⁰, 1.7·10⁻⁹ on the strip 512 × 4).
    pub const AUTO_DIRECT_SECONDS_PER_COMPLIANCE_ENTRY: f64 = 7e-10;

    /// Seconds per step per n_t³ in 2D, where the direct path's fast solver starts each step
    /// with Newton on the condensed law: a dense n_t × n_t LU per iteration, up to 8 (measured
    /// on the strip 2048 × 4: 8 per step, 1.4 s per step; in 3D the descent's sweeps take
    /// their place, and α n_t² covers them).
    pub const AUTO_DIRECT_SECONDS_PER_NEWTON_CUBE_2D: f64 = 1.6e-10;

    /// Seconds per outer iteration per unknown of the iterative path (its Newton iterations'
    /// GMRES + ILU(0) solves; its set-up is a twentieth of the direct path's and left out;
    /// measured 0.96–1.9·10⁻⁷ in 3D, 0.35–5.3·10⁻⁷ in 2D).
    pub const AUTO_ITERATIVE_SECONDS_PER_UNKNOWN: f64 = 1.2e-7;

    /// An estimated direct run shorter than this takes the direct path whatever the iterative
    /// one's estimate: the saving would be about a second at most (the 3D example, 64 steps:
    /// 1.76 s direct against 1.16 s, estimated 1.9 s and 1.4 s), the model leaves out the
    /// per-step overheads that dominate small runs, and the direct path is the robust one and
    /// the reference (it reports the uniqueness condition, and it is the path verified against
    /// GetFEM to 10⁻¹⁰). The iterative path's ILU(0) may stall on a stiff body of several
    /// materials: the 3D brake (steel backplate and lining, 6 978 unknowns, 384 contact nodes)
    /// reaches GMRES's cap at a relative residual of 2e-9.
    pub const AUTO_DIRECT_ANYWAY_SECONDS: f64 = 2.0;

    /// The estimated cost of a whole run of `size` on each path, in seconds of this machine
    /// (the constants `AUTO_*` of [`LinearKind`]; the measurements in [`LinearKind::choose`]).
    ///
    /// With N unknowns, n_c contact nodes, n_t = (d − 1) n_c, S steps and I =
    /// [`Self::AUTO_OUTER_PER_STEP`] outer iterations per step:
    ///
    /// ```text
    /// F         = F_sparse(d, N) + (d n_c)² / 2          the factor's entries: the sparse fill
    ///                                                   (crate::resources) and the dense block of
    ///                                                   the contact unknowns, ordered last
    /// direct    = φ F + S σ F + S I α n_t² + [d = 2] S ν n_t³
    /// iterative = S I β N
    /// ```
    pub fn costs(size: &ProblemSize) -> PathCosts {
        let d = size.dim as f64;
        let n = size.unknowns as f64;
        let contact = size.contact_nodes as f64;
        let n_t = (d - 1.0) * contact;
        let factor = crate::resources::estimated_factor_entries(size.dim, n) + (d * contact).powi(2) / 2.0;
        let outer = size.steps as f64 * Self::AUTO_OUTER_PER_STEP;
        let newton = if size.dim < 3 {
            Self::AUTO_DIRECT_SECONDS_PER_NEWTON_CUBE_2D * n_t.powi(3)
        } else {
            0.0
        };
        PathCosts {
            factor_entries: factor,
            direct: Self::AUTO_DIRECT_SECONDS_PER_FACTOR_ENTRY * factor
                + size.steps as f64 * Self::AUTO_DIRECT_SECONDS_PER_FACTOR_ENTRY_STEP * factor
                + outer * Self::AUTO_DIRECT_SECONDS_PER_COMPLIANCE_ENTRY * n_t * n_t
                + size.steps as f64 * newton,
            iterative: outer * Self::AUTO_ITERATIVE_SECONDS_PER_UNKNOWN * n,
        }
    }

    /// Direct or iterative for a problem of `size` solved by `kind` on a machine with `memory`
    /// bytes ([`LinearKind::choose`] without its reason).
    pub fn resolve(self, size: &ProblemSize, kind: SolverKind, memory: f64) -> LinearKind {
        self.choose(size, kind, memory).linear
    }

    /// The path `self` resolves to, and why. `auto` takes the direct path where
    ///
    /// 1. in 3D, its estimated peak memory ([`crate::resources::estimated_memory`]) is at most
    ///    [`Self::AUTO_DIRECT_MEMORY_SHARE`] of the machine's;
    /// 2. in 3D, the problem has at most [`Self::AUTO_DIRECT_UNKNOWNS_3D`] unknowns: the factor's
    ///    fill grows like N^{4/3}, the iterative path's cost like N (98k unknowns, 64 steps,
    ///    2026-11-27: 33.8 s direct against 30.4 s, 2.3 GiB against 0.45 GiB);
    /// 3. and its estimated run ([`LinearKind::costs`]) is no dearer than the iterative one's
    ///    (or shorter than [`Self::AUTO_DIRECT_ANYWAY_SECONDS`]):
    ///    the direct path's cost is also its dense condensation on Γ_C, which grows with the
    ///    contact nodes, not the unknowns, and each step's sparse solves with its factor.
    ///    Measured (release, 16 steps at k = 1/64, both paths one after the other on an idle
    ///    machine, 2026-11-29, fifth session, both paths' loops on Γ_C's rows; whole-run
    ///    seconds direct against iterative, the estimate of each, and the peak memory):
    ///
    /// | body | d | N | n_c | direct | iterative | estimated | peak MiB |
    /// |---|---|---|---|---|---|---|---|
    /// | 3D example 40 × 10 × 10 | 3 | 17 590 | 440 | 0.70 | 0.34 | 0.93 / 0.34 | 199 / 53 |
    /// | 3D example 56 × 14 × 14 | 3 | 46 970 | 840 | 3.41 | 0.72 | 3.5 / 0.90 | 737 / 125 |
    /// | pad 40 × 10 × 5 (60 × 15 × 7 cells) | 3 | 27 862 | 960 | 2.22 | 0.53 | 2.1 / 0.53 | 505 / 81 |
    /// | thin pad 40 × 13.2 × 3.3 (60 × 20 × 5) | 3 | 27 025 | 1 260 | 3.34 | 0.59 | 2.5 / 0.52 | 678 / 81 |
    /// | thin pad 40 × 10 × 2 (40 × 10 × 2) | 3 | 4 222 | 440 | 0.20 | 0.13 | 0.25 / 0.08 | 82 / 21 |
    /// | 2D example 128 × 32 | 2 | 12 384 | 128 | 0.06 | 0.07 | 0.08 / 0.24 | 39 / 22 |
    /// | 2D example 256 × 64 | 2 | 49 344 | 256 | 0.29 | 0.42 | 0.37 / 0.95 | 126 / 68 |
    /// | strip 40 × 2.5 (512 × 4) | 2 | 6 652 | 512 | 0.22 | 0.18 | 0.43 / 0.13 | 71 / 19 |
    /// | strip 40 × 1 (2048 × 4) | 2 | 26 620 | 2 048 | 27.0 | 2.26 | 26 / 0.51 | |
    ///
    /// φ, σ, α, ν, β are fitted to these runs (the direct runs' set-up, solves and contact
    /// solver from `summary.json`'s timings). The constants before these (fitted on 2026-11-27
    /// under a load of about 7 on 2 cores, where the memory-bound iterative path slowed most,
    /// and before either path's loop ran on Γ_C's rows) estimated 4–30× today's seconds and
    /// sent the 3D example at 47k unknowns over 64 steps to the direct path: 7.9 s against
    /// about 2.5 s on the iterative one. Where the estimated direct run is under
    /// [`Self::AUTO_DIRECT_ANYWAY_SECONDS`] it is taken anyway (the 3D example at 17.6k
    /// unknowns, the brake pads, the 2D examples). The paper's solver takes the direct path
    /// wherever its factor fits: on the iterative path it pays a Krylov solve per Uzawa
    /// iterate ([`PaperKrylov`]).
    /// `size.contact_nodes = 0` (not known yet: the scenario's memory check before the mesh)
    /// leaves the unknowns to decide, as before the cost model.
    pub fn choose(self, size: &ProblemSize, kind: SolverKind, memory: f64) -> LinearChoice {
        let chosen = |linear, reason: String| LinearChoice { linear, reason };
        if self != LinearKind::Auto {
            return chosen(self, "solver.linear".to_string());
        }
        let direct_memory = crate::resources::estimated_memory(size.dim, size.unknowns as f64);
        if size.dim == 3 && direct_memory > Self::AUTO_DIRECT_MEMORY_SHARE * memory {
            let reason = format!(
                "auto: the direct path's estimated {} exceeds half the machine's {}",
                crate::resources::human(direct_memory),
                crate::resources::human(memory)
            );
            return chosen(LinearKind::Iterative, reason);
        }
        if kind == SolverKind::Paper {
            return chosen(
                LinearKind::Direct,
                "auto: the paper's solver, whose factor fits".to_string(),
            );
        }
        if size.dim == 3 && size.unknowns > Self::AUTO_DIRECT_UNKNOWNS_3D {
            let reason = format!("auto: more than {} unknowns in 3D", Self::AUTO_DIRECT_UNKNOWNS_3D);
            return chosen(LinearKind::Iterative, reason);
        }
        let costs = Self::costs(size);
        let linear = if costs.direct <= costs.iterative.max(Self::AUTO_DIRECT_ANYWAY_SECONDS) {
            LinearKind::Direct
        } else {
            LinearKind::Iterative
        };
        let reason = format!(
            "auto: estimated {:.2} s direct (factor {:.1e} entries, {} contact unknowns) against {:.2} s iterative",
            costs.direct,
            costs.factor_entries,
            size.dim.saturating_sub(1) * size.contact_nodes,
            costs.iterative
        );
        chosen(linear, reason)
    }
}

/// What `auto` weighs ([`LinearKind::choose`]), known before anything is assembled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProblemSize {
    /// d, 2 or 3.
    pub dim: usize,
    /// Unknowns of the step matrix (velocities and temperatures).
    pub unknowns: usize,
    /// Nodes of Γ_C (0 where not known yet).
    pub contact_nodes: usize,
    /// Time steps of the run.
    pub steps: usize,
}

impl ProblemSize {
    /// The size of `problem`.
    pub fn of(problem: &crate::model::Problem) -> Self {
        ProblemSize {
            dim: problem.dim(),
            unknowns: problem.n_unknowns(),
            contact_nodes: problem.contact.len(),
            steps: problem.time.steps,
        }
    }
}

/// The estimated cost of a run on each path ([`LinearKind::costs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathCosts {
    /// Entries of the direct factor, estimated (sparse fill and the dense contact block).
    pub factor_entries: f64,
    /// Seconds of the run on the direct path.
    pub direct: f64,
    /// Seconds of the run on the iterative path.
    pub iterative: f64,
}

/// The path a run takes and why ([`LinearKind::choose`]), for the run's header.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearChoice {
    /// Direct or iterative.
    pub linear: LinearKind,
    /// `solver.linear` where it was given, or `auto:` and the figures that decided.
    pub reason: String,
}

/// The step solver's settings; defaults are the paper's (ε_conv = 1e-6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverParams {
    /// Which solver.
    pub kind: SolverKind,
    /// ε_conv of the stop criteria (77)–(80).
    pub tolerance: f64,
    /// Cap on convexification iterations per step.
    pub max_convexification: usize,
    /// Relative tolerance of the inner solvers (Uzawa, Newton).
    pub inner_tolerance: f64,
    /// Cap on inner Uzawa iterations per convex problem.
    pub max_inner: usize,
    /// Cap on sweeps of the fast solver's descent ([`descend`]); 0 switches it off.
    pub max_sweeps: usize,
    /// Retry a step that fails as 2, 4, … substeps of k/2, k/4, … ([`crate::time::march`]).
    pub cutback: bool,
    /// The deepest cutback: at most 2^depth substeps of k/2^depth.
    pub max_cutback_depth: usize,
    /// Direct, iterative, or chosen by size.
    pub linear: LinearKind,
    /// Tolerance and caps of the iterative path's Krylov solves.
    pub krylov: KrylovParams,
    /// Depth of the Anderson acceleration of the iterative path's convexification loop in its
    /// linear tail (`anderson::TailAnderson`; 0: off).
    pub anderson_depth: usize,
    /// Symmetric Gauss–Seidel sweeps over Γ_C that predict the bounds of each iterate of the
    /// iterative path's convexification loop after its first, per bound update of the loop on
    /// Γ_C's rows ([`Prediction::Loop`]) or in all ([`Prediction::Law`]). 0: the paper's loop,
    /// one solve per iterate. Default 1.
    pub contact_sweeps: usize,
    /// What those sweeps relax each contact node with (`solver.prediction`). Default
    /// [`Prediction::Loop`].
    pub prediction: Prediction,
    /// Cut back a Newton step of the iterative path's convex problems that raises the law's
    /// residual (`newton_krylov`; false: every full step, as before 2026-11-29's fourth session).
    pub backtracking: bool,
}

impl SolverParams {
    /// Sweeps per bound update of the loop on Γ_C's rows ([`Prediction::Loop`]), 0 where the
    /// paper's loop runs (`contact_sweeps` = 0, or the law's sweeps, which the direct path
    /// does not have).
    pub fn loop_on_rows_sweeps(&self) -> usize {
        match self.prediction {
            Prediction::Loop => self.contact_sweeps,
            Prediction::Law => 0,
        }
    }

    /// The linear path `problem` takes with these settings on this machine, and why
    /// ([`LinearKind::choose`] with the machine's memory): what the set-up follows and the run's
    /// header reports.
    pub fn linear_choice(&self, problem: &crate::model::Problem) -> LinearChoice {
        let memory = crate::resources::machine_memory().unwrap_or(f64::INFINITY);
        (self.linear).choose(&ProblemSize::of(problem), self.kind, memory)
    }
}

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            kind: SolverKind::Fast,
            tolerance: 1e-6,
            max_convexification: 200,
            inner_tolerance: 1e-10,
            max_inner: 20_000,
            max_sweeps: 20_000,
            cutback: true,
            max_cutback_depth: 5,
            linear: LinearKind::Auto,
            krylov: KrylovParams::default(),
            anderson_depth: 2,
            contact_sweeps: 1,
            prediction: Prediction::Loop,
            backtracking: true,
        }
    }
}

/// What one time step cost and how it ended.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct StepInfo {
    /// Outer (convexification) iterations.
    pub convexification_iterations: usize,
    /// Inner iterations summed over the outer ones: the paper's Uzawa iterations, the descent
    /// sweeps of the fast solver's convex subproblems on the direct path, or the iterative
    /// path's symmetric sweeps over Γ_C's rows that predict its iterates' bounds.
    pub inner_iterations: usize,
    /// Last relative increments of u, θ, ξ, ζ: the left sides of (77)–(80) over the right
    /// sides' norms.
    pub increments: [f64; 4],
    /// Semismooth Newton iterations (fast solver).
    pub newton_iterations: usize,
    /// The fast solver went through the convexification loop in this step.
    pub fallback: bool,
    /// Sweeps of the fast solver's descent (0 where Newton or the convexification loop solved
    /// the step).
    pub descent_sweeps: usize,
    /// Iterations of the iterative path's Newton on the nonmonotone law, its way out where the
    /// convexification loop failed (0 where the loop solved the step).
    pub nonmonotone_newton_iterations: usize,
    /// Convexification iterates of the iterative path that started from an Anderson
    /// combination of the bounds (`solver.anderson_depth`).
    pub anderson_combinations: usize,
    /// Convexification iterates of the iterative path whose bounds the Gauss–Seidel sweeps over
    /// Γ_C predicted (`solver.contact_sweeps`, or the way out of a failed paper's loop, whose
    /// step's `convexification_iterations` then count both loops').
    pub predicted_iterates: usize,
    /// Iterates of the iterative path's first way out, the loop with the law's sweeps from the
    /// step's start where the step's own loop failed (0 where it converged; the step's
    /// `convexification_iterations` count both loops').
    pub way_out_iterates: usize,
    /// Newton iterations of the iterative path's convex problems whose step was cut back
    /// because the full step raised the law's residual (`newton_krylov`'s backtracking).
    pub backtracked_newton_iterations: usize,
    /// Substeps the step took: 1 without cutback, 2^depth at the deepest cutback.
    pub substeps: usize,
    /// The deepest cutback of the step (0: none): its shortest substep was k/2^depth.
    pub cutback_depth: usize,
    /// Krylov iterations of the iterative path's linear solves (0 on the direct path).
    pub krylov_iterations: usize,
    /// Iterates of the fixed point on a nonlinear heat exchange (0 where ∂j is affine).
    pub exchange_iterations: usize,
    /// Iterates of the fixed point on the contact pressure (Coulomb friction; 0 otherwise).
    pub pressure_iterations: usize,
    /// The step's energies ([`crate::model::energy`]), substeps summed; set by the time loop.
    pub energy: crate::model::StepEnergy,
}

impl StepInfo {
    /// Adds the figures of a substep.
    pub fn absorb(&mut self, other: &StepInfo) {
        self.convexification_iterations += other.convexification_iterations;
        self.inner_iterations += other.inner_iterations;
        self.newton_iterations += other.newton_iterations;
        self.increments = other.increments;
        self.fallback |= other.fallback;
        self.descent_sweeps += other.descent_sweeps;
        self.nonmonotone_newton_iterations += other.nonmonotone_newton_iterations;
        self.anderson_combinations += other.anderson_combinations;
        self.predicted_iterates += other.predicted_iterates;
        self.way_out_iterates += other.way_out_iterates;
        self.backtracked_newton_iterations += other.backtracked_newton_iterations;
        self.substeps += other.substeps;
        self.cutback_depth = self.cutback_depth.max(other.cutback_depth);
        self.krylov_iterations += other.krylov_iterations;
        self.exchange_iterations += other.exchange_iterations;
        self.pressure_iterations += other.pressure_iterations;
        self.energy.absorb(&other.energy);
    }
}

/// A stop criterion of a step solver, as it is reported when it fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Criterion {
    /// (77): ‖Δu‖_E / ‖u‖_E between convexification iterates.
    IncrementU,
    /// (78): ‖Δθ‖_V / ‖θ‖_V.
    IncrementTheta,
    /// (79): ‖Δξ‖_{L²(Γ_C)} / ‖ξ‖_{L²(Γ_C)}.
    IncrementXi,
    /// (80): ‖Δζ‖_{L²(Γ_C)} / ‖ζ‖_{L²(Γ_C)}.
    IncrementZeta,
    /// max |Δp| / max p between iterates of the fixed point on the contact pressure.
    IncrementPressure,
    /// max |Δw_τ| / max |w_τ| between iterates on Γ_C.
    IncrementW,
    /// max |Δξ| / max friction bound between iterates on Γ_C (also the inner Uzawa loop's).
    IncrementXiNodal,
    /// max_i |ξ_i − P_{b(|w_i|)}(ξ_i − r w_i)| / min_i b(|w_i|): the nonmonotone friction law
    /// itself at the nodes.
    NodalLaw,
    /// A linear solve of the Newton method gave a non-finite update.
    NonFiniteUpdate,
    /// ‖b̃ − Ã x‖ / ‖b̃‖ of a Krylov solve at its iteration cap.
    LinearResidual,
}

impl Criterion {
    /// What the criterion measures, for messages.
    pub fn describe(&self) -> &'static str {
        match self {
            Criterion::IncrementU => "relative increment of u (77)",
            Criterion::IncrementTheta => "relative increment of θ (78)",
            Criterion::IncrementXi => "relative increment of ξ (79)",
            Criterion::IncrementZeta => "relative increment of ζ (80)",
            Criterion::IncrementPressure => "max |Δp| / max p (contact pressure)",
            Criterion::IncrementW => "max |Δw_τ| / max |w_τ|",
            Criterion::IncrementXiNodal => "max |Δξ| / max friction bound",
            Criterion::NodalLaw => "nodal friction-law residual / smallest bound",
            Criterion::NonFiniteUpdate => "non-finite Newton update",
            Criterion::LinearResidual => "relative residual of the linear solve",
        }
    }
}

/// Why a step solver gave up: the loop, how long it ran, and the criterion that failed with its
/// value and tolerance (the worst one against its tolerance, never one that passed).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepFailure {
    /// `paper` or `fast`.
    pub solver: &'static str,
    /// The loop that hit its cap: `convexification`, `inner augmented-Lagrangian`, …
    pub loop_name: &'static str,
    pub iterations: usize,
    pub criterion: Criterion,
    /// May be +∞ (a relative increment against a zero previous iterate): JSON gets "inf".
    #[serde(serialize_with = "number_or_text")]
    pub value: f64,
    pub tolerance: f64,
    /// A failed Krylov solve's relative residuals, before its first iteration and after each
    /// one, as GMRES estimates them (empty for the other loops; not in JSON then).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub residual_history: Vec<f64>,
    /// The period of the cycle the loop was found in, where it was given up on one
    /// (the convexification loop's cycle rule, periods up to 8) rather than at its cap (a byte: the
    /// failure travels inside every run's error type, which clippy keeps small).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cycle: Option<u8>,
}

/// A finite number as a JSON number, ±∞ and NaN (which JSON lacks) as the strings "inf",
/// "-inf", "NaN".
fn number_or_text<S: serde::Serializer>(value: &f64, serializer: S) -> Result<S::Ok, S::Error> {
    if value.is_finite() {
        serializer.serialize_f64(*value)
    } else {
        serializer.serialize_str(&value.to_string())
    }
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the {} solver's {} loop stopped after {} iterations: {} = {:.3e} > tolerance {:e}",
            self.solver,
            self.loop_name,
            self.iterations,
            self.criterion.describe(),
            self.value,
            self.tolerance
        )?;
        match self.cycle {
            Some(period) => write!(f, ", cycling with period {period}"),
            None => Ok(()),
        }
    }
}

/// How one step solve ends when it does not return a state.
#[derive(Debug)]
pub enum SolveError {
    /// The nonsmooth solver did not converge: the time loop may cut the step back.
    NotConverged(StepFailure),
    /// Anything else (a load that evaluates to NaN, …): the run stops.
    Other(StepError),
}

impl From<StepError> for SolveError {
    fn from(e: StepError) -> Self {
        SolveError::Other(e)
    }
}

impl From<LaError> for SolveError {
    fn from(e: LaError) -> Self {
        SolveError::Other(e.into())
    }
}

impl From<ModelError> for SolveError {
    fn from(e: ModelError) -> Self {
        SolveError::Other(e.into())
    }
}

/// Whether every (criterion, value, tolerance) holds.
pub(crate) fn all_hold(checks: &[(Criterion, f64, f64)]) -> bool {
    checks.iter().all(|&(_, value, tolerance)| value <= tolerance)
}

/// The worst of several (criterion, value, tolerance): the one furthest past its tolerance.
pub fn worst_criterion(checks: &[(Criterion, f64, f64)]) -> (Criterion, f64, f64) {
    *checks
        .iter()
        .max_by(|a, b| (a.1 / a.2).total_cmp(&(b.1 / b.2)))
        .expect("at least one criterion")
}
