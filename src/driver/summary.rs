//! What a run reports: `summary.json` ([`Summary`]), the figures of each output time and of
//! each step, and the tally a run accumulates step by step (kept in checkpoints, so that a
//! continued run reports the whole run).

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::model::ContactRow;
use crate::model::State;
use crate::model::StepEnergy;

pub use super::watch::RunWarning;
use crate::output::PvdEntry;
use crate::step::{StepFailure, StepInfo};
use crate::time::TimeError;

/// Wall time per phase, in seconds.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Timings {
    /// Mesh, spaces, matrices and loads.
    pub assembly: f64,
    /// Reduced step matrix and its sparse LU.
    pub factorization: f64,
    /// Solver set-up (condensation onto Γ_C).
    pub solver_setup: f64,
    /// The time loop without output.
    pub time_stepping: f64,
    /// Of which: sparse solves with the factored step matrix (in the loop).
    pub linear_solves: f64,
    /// Of which: building right-hand sides.
    pub right_hand_sides: f64,
    /// Of which: setting up the cutback levels k/2, k/4, … (factorization and condensation)
    /// when a cutback first needs them.
    pub cutback_setup: f64,
    /// Of which: the energies of each step (`crate::model::energy`).
    pub energies: f64,
    /// Of which: the nonsmooth solver on Γ_C and bookkeeping (the rest).
    pub contact_solver: f64,
    /// Writing files, as far as the run waited for it: the frames are written on a thread
    /// beside the time loop (`frames`), the loop waiting only where it gets two frames ahead,
    /// before a checkpoint, and at the end.
    pub output: f64,
    /// The frames' own time (fields, encoding, files), on the writer thread in parallel with the
    /// time loop (in `output` where the run writes them inline, `RunOptions::inline_frames`);
    /// in a distributed run, the slowest rank's, each writing its pieces.
    pub frames: f64,
    /// Everything.
    pub total: f64,
}

/// The contact state at one output time.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct OutputRecord {
    /// Time level n.
    pub n: usize,
    /// t_n.
    pub t: f64,
    /// Contact nodes with |w_τ| > slip tolerance.
    pub slip_nodes: usize,
    /// The other contact nodes.
    pub stick_nodes: usize,
    /// Largest |w_τ| on Γ_C.
    pub max_slip_rate: f64,
    /// Temperature range over Ω.
    pub min_temperature: f64,
    pub max_temperature: f64,
    /// Largest |u| over Ω.
    pub max_displacement: f64,
    /// ‖u_n‖_E.
    pub energy_norm_u: f64,
    /// Contact rows (not serialized; in the CSV files).
    #[serde(skip)]
    pub contact: Vec<ContactRow>,
}

/// Everything `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub dim: usize,
    pub nodes: usize,
    pub elements: usize,
    pub velocity_unknowns: usize,
    pub temperature_unknowns: usize,
    pub unknowns: usize,
    pub contact_nodes: usize,
    pub steps: usize,
    pub time_step: f64,
    pub solver: String,
    /// The algorithm that ran (`solver.kind` names one per linear path): `convexification-uzawa`
    /// or `condensed-newton` on the direct path, `convexification-uzawa-krylov` or
    /// `newton-krylov` on the iterative one.
    #[serde(default)]
    pub algorithm: String,
    /// The constants of the laws' hypotheses (c_τ, m_τ, m_θ, L_τ; MODEL.md §6).
    pub laws: crate::model::LawConstants,
    /// The sufficient condition for every step to have a unique solution, where the solver
    /// has the contact compliance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uniqueness: Option<Uniqueness>,
    pub slip_tolerance: f64,
    pub convexification_iterations: usize,
    pub inner_iterations: usize,
    pub max_convexification_per_step: usize,
    /// Semismooth Newton iterations (fast solver) of the steps kept: the sum of `steps.csv`'s
    /// column. Those of attempts given up and cut back are not in it; on the iterative path each
    /// Newton iteration is one solve, so `linear_solves` counts them all.
    pub newton_iterations: usize,
    /// Steps the fast solver took through the convexification loop (law too steep for Newton).
    pub fallback_steps: usize,
    /// Steps (or substeps) the fast solver finished by descent on the step's energy (the
    /// convexification loop failed there).
    pub descent_steps: usize,
    /// Descent sweeps over all steps.
    pub descent_sweeps: usize,
    /// Steps (or substeps) the iterative path finished by Newton on the nonmonotone law (the
    /// convexification loop failed there), and that Newton's iterations over all steps.
    #[serde(default)]
    pub nonmonotone_newton_steps: usize,
    #[serde(default)]
    pub nonmonotone_newton_iterations: usize,
    /// Convexification iterates of the iterative path that started from an Anderson
    /// combination of the bounds (`solver.anderson_depth`), over all steps.
    #[serde(default)]
    pub anderson_combinations: usize,
    /// Convexification iterates of the iterative path whose bounds the Gauss–Seidel sweeps over
    /// Γ_C predicted (`solver.contact_sweeps`), over all steps.
    #[serde(default)]
    pub predicted_iterates: usize,
    /// Newton iterations of the iterative path's convex problems cut back along their step
    /// (the full step raised the law's residual), over all steps.
    #[serde(default)]
    pub backtracked_newton_iterations: usize,
    /// Sparse solves in the time loop: full solves and their equivalents, two sweeps over all of
    /// the factor counting one (rounded up; sweeps over the contact block alone are not counted).
    /// Over the whole run: a continued run adds its own to those of the parts before (their
    /// checkpoint carries them), failed attempts at a step included.
    pub linear_solves: usize,
    /// Triangular sweeps over all of the factor in the time loop (forward or backward; a full
    /// solve counts two), over the whole run as `linear_solves`.
    pub full_sweeps: usize,
    /// Stored entries of the LDLᵀ factor of the step matrix (direct path), or of its ILU(0)
    /// factor (iterative path).
    pub factor_nnz: usize,
    /// The linear path the run took: `direct` or `iterative` (`solver.linear`, `auto` resolved).
    pub linear: String,
    /// The iterative path's preconditioner, `ilu` or `amg` (`solver.preconditioner`; absent on
    /// the direct path).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preconditioner: Option<String>,
    /// The AMG hierarchy, where the preconditioner has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amg: Option<AmgRecord>,
    /// Krylov iterations over all linear solves in the time loop (iterative path; 0 on the
    /// direct path), as `linear_solves`: those of a step's attempts that were given up and cut
    /// back included, so more than the sum of `steps.csv`'s column where a step was cut back.
    pub krylov_iterations: usize,
    /// Iterates of the fixed point on a nonlinear heat exchange over all steps (0 where ∂j is
    /// affine: in the step matrix).
    #[serde(skip_serializing_if = "is_zero")]
    pub exchange_iterations: usize,
    /// Iterates of the fixed point on the contact pressure over all steps (Coulomb friction;
    /// 0 otherwise).
    #[serde(skip_serializing_if = "is_zero")]
    pub pressure_iterations: usize,
    /// Peak resident memory of the process at the end of the run (Linux), MiB; in a
    /// distributed run, the largest rank's.
    pub peak_memory_mib: Option<f64>,
    /// In a distributed run, each rank's peak resident memory (MiB, in rank order; 0 where it
    /// could not be read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_memory_per_rank_mib: Option<Vec<f64>>,
    /// The largest residual of the nodal friction law (−ξ_i ∈ ∂j_τ(w_i): |ξ_i| ≤ μ(0)S at
    /// stick, ξ_i = −μ(|w_i|)S w_i/|w_i| at slip) over every completed step and Γ_C node,
    /// relative to μ(0)S: how well the returned states solve the discrete problem.
    pub max_law_residual: f64,
    /// Steps cut back into substeps (a step that converged at k is not listed).
    pub cutbacks: Vec<CutbackRecord>,
    /// `running`, `completed`, or `failed` / `interrupted` with [`Summary::failure`].
    pub status: RunStatus,
    /// This run's identifier: `summary.json`, `solution.pvd`, the frames and the checkpoint of
    /// a folder belong to it (a continued run keeps it).
    pub run_id: String,
    /// The scenario's fingerprint (SHA-256 of everything in it that changes the solution).
    pub scenario_fingerprint: Option<String>,
    /// Time levels from which the run was continued (`run --restart`), in order.
    pub restarts: Vec<usize>,
    /// Why the run stopped, when it did.
    pub failure: Option<FailureRecord>,
    pub timings: Timings,
    pub outputs: Vec<OutputRecord>,
    /// The energies over the run (none before the first step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy: Option<EnergySummary>,
    /// The warnings of a run that leaves the plausible (`watch`), once per kind.
    pub warnings: Vec<RunWarning>,
    /// `status`, and for a completed run with warnings "completed with N warnings".
    pub outcome: String,
}

/// The energies of a run: the levels at the start and the end, the flows summed over its steps
/// ([`StepEnergy`] from t = 0 to the last step), and the worst step's balance residuals.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct EnergySummary {
    /// K₀, E₀, H₀.
    pub initial_kinetic: f64,
    pub initial_elastic: f64,
    pub initial_thermal: f64,
    /// The levels at the last step and the sums from t = 0.
    pub total: StepEnergy,
    /// The largest relative residual of a step's mechanical and heat balance.
    pub max_energy_residual: f64,
    pub max_heat_residual: f64,
    /// Above these, a step's residual is a warning.
    pub tolerance: f64,
    pub heat_tolerance: f64,
}

impl EnergySummary {
    /// Over the recorded steps (none: `None`).
    pub fn of(steps: &[StepRecord]) -> Option<Self> {
        let (first, total) = (steps.first()?.energy, steps.last()?.energy);
        let worst = |f: fn(&StepRecord) -> f64| steps.iter().map(f).fold(0.0, f64::max);
        // The levels before the first step, from its own change (smaller than the run's).
        Some(EnergySummary {
            initial_kinetic: first.kinetic - first.kinetic_change,
            initial_elastic: first.elastic - first.elastic_change,
            initial_thermal: first.thermal - first.thermal_change,
            total,
            max_energy_residual: worst(|s| s.energy_residual),
            max_heat_residual: worst(|s| s.heat_residual),
            tolerance: super::watch::BALANCE_TOLERANCE,
            heat_tolerance: super::watch::HEAT_BALANCE_TOLERANCE,
        })
    }
}

impl RunStatus {
    /// "completed", "completed with N warnings", "failed", …
    pub fn outcome(self, warnings: usize) -> String {
        let status = serde_json::to_value(self).expect("a status serializes");
        let name = status.as_str().unwrap_or("unknown").to_string();
        match warnings {
            0 => name,
            1 => format!("{name} with 1 warning"),
            n => format!("{name} with {n} warnings"),
        }
    }
}

/// The step's sufficient condition for a unique solution (MODEL.md §6): for frozen θ the
/// step minimizes ½ wᵀ S w − bᵀ w + Σ ℓ_i j_τ(w_i) on Γ_C (S the step condensed onto the
/// tangential unknowns), strictly convex where S − m_τ diag(ℓ) is positive definite, that is
/// where m_τ λ_max(C) < 1 for the weighted compliance C = S⁻¹ diag(ℓ).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Uniqueness {
    /// λ_max(C) at the run's k.
    pub compliance: f64,
    /// max m_τ of the laws.
    pub m_tau: f64,
    /// m_τ λ_max(C): below 1, every step has one solution.
    pub product: f64,
    pub unique: bool,
    /// k at which the product reaches 1, where C scales like k (the mass term dominates the
    /// step matrix, as for the paper's k): an estimate of the largest k with unique steps.
    /// `None` where m_τ = 0 (convex laws: unique for every k).
    pub time_step_limit: Option<f64>,
}

impl Uniqueness {
    /// The condition for the compliance λ_max(C) at step k and the laws' m_τ.
    pub fn new(compliance: f64, m_tau: f64, time_step: f64) -> Self {
        let product = m_tau * compliance;
        Uniqueness {
            compliance,
            m_tau,
            product,
            unique: product < 1.0,
            time_step_limit: (product > 0.0).then(|| time_step / product),
        }
    }

    /// One line for the run header.
    pub fn line(&self) -> String {
        let verdict = if self.unique {
            "< 1: every step has a unique solution"
        } else {
            "≥ 1: a step may have several solutions (the solvers return one that satisfies the law)"
        };
        let limit = match self.time_step_limit {
            Some(k) => format!("; the condition holds for k below about {k:.3e} (mass-dominated estimate)"),
            None => String::new(),
        };
        format!(
            "uniqueness: m_τ λ_max(C) = {:.4e} × {:.4e} = {:.3} {verdict}{limit}",
            self.m_tau, self.compliance, self.product
        )
    }
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// Still running (what `summary.json` says until the run ends; a run killed outright
    /// leaves it so).
    Running,
    Completed,
    Failed,
    /// Stopped from outside between two steps (SIGINT, SIGTERM, or the caller).
    Interrupted,
}

impl RunStatus {
    /// How a run that ended with `failure` (none: it completed) ended.
    pub fn of(failure: Option<&Error>) -> Self {
        match failure {
            None => RunStatus::Completed,
            Some(Error::Interrupted { .. }) => RunStatus::Interrupted,
            Some(_) => RunStatus::Failed,
        }
    }
}

/// The AMG hierarchy of the velocity block (`solver.preconditioner`), as PETSc's GAMG built it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AmgRecord {
    pub levels: usize,
    /// Stored entries of all levels' matrices over the finest level's.
    pub operator_complexity: f64,
}

/// A step that went through substeps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CutbackRecord {
    /// Time level n of the step and t_n.
    pub step: usize,
    pub t: f64,
    /// The deepest cutback: the shortest substep was k/2^depth.
    pub depth: usize,
    /// Substeps taken.
    pub substeps: usize,
    /// Why the step was cut back: how its solve at the full k failed (the loop, its iterations,
    /// the criterion and by how much); none in checkpoints from before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// Why a run stopped.
#[derive(Debug, Clone, Serialize)]
pub struct FailureRecord {
    /// The error as the command prints it.
    pub message: String,
    /// Who stopped the run, when it was interrupted.
    pub interrupted: Option<crate::error::Interruption>,
    /// The step being computed, its target time and the deepest cutback tried (solver
    /// failures only).
    pub step: Option<usize>,
    pub time: Option<f64>,
    pub cutback_depth: Option<usize>,
    /// The loop and the criterion that failed, with its value and tolerance.
    pub solver: Option<StepFailure>,
    /// The last completed time level and its time (0: the initial state).
    pub last_step: usize,
    pub last_time: f64,
}

impl FailureRecord {
    pub fn new(error: &Error, last: &State) -> Self {
        let (step, time, cutback_depth, solver) = match error {
            Error::Time(TimeError::NotConverged {
                step,
                time,
                cutback_depth,
                failure,
            }) => (Some(*step), Some(*time), Some(*cutback_depth), Some(failure.clone())),
            _ => (None, None, None, None),
        };
        FailureRecord {
            message: error.to_string(),
            interrupted: match error {
                Error::Interrupted { cause, .. } => Some(*cause),
                _ => None,
            },
            step,
            time,
            cutback_depth,
            solver,
            last_step: last.n,
            last_time: last.t,
        }
    }
}

/// The solver's figures of one time step (a line of `steps.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StepRecord {
    pub n: usize,
    pub t: f64,
    pub convexification_iterations: usize,
    pub inner_iterations: usize,
    pub newton_iterations: usize,
    pub descent_sweeps: usize,
    /// Krylov iterations of the step (iterative path).
    #[serde(default)]
    pub krylov_iterations: usize,
    /// Substeps taken (1: no cutback) and the deepest cutback.
    pub substeps: usize,
    pub cutback_depth: usize,
    /// The last relative increments of u, θ, ξ, ζ of the step's solver (the left sides of the
    /// stop criteria (77)–(80); [`StepInfo::increments`]); NaN for the fast solver, which
    /// stops on the nodal law instead and does not measure them.
    #[serde(default = "unmeasured", deserialize_with = "nan_from_null")]
    pub increments: [f64; 4],
    /// The step's nodal friction-law residual, relative to μ(0)S.
    pub law_residual: f64,
    /// Contact nodes that slip (|w_τ| > the slip tolerance) and that stick at the step's end.
    #[serde(default)]
    pub slip_nodes: usize,
    #[serde(default)]
    pub stick_nodes: usize,
    /// Wall time of the step, s.
    pub seconds: f64,
    /// The energies from t = 0 to t_n ([`crate::model::energy`]): the levels at t_n, the
    /// changes, flows and residuals summed over the steps (0 in checkpoints from before them).
    #[serde(default)]
    pub energy: StepEnergy,
    /// This step's mechanical and heat balance residuals relative to their largest terms.
    #[serde(default)]
    pub energy_residual: f64,
    #[serde(default)]
    pub heat_residual: f64,
    /// Iterations of the iterative path's Newton on the nonmonotone law, where the loop failed
    /// ([`StepInfo::nonmonotone_newton_iterations`]).
    #[serde(default)]
    pub nonmonotone_newton_iterations: usize,
    /// Convexification iterates that started from an Anderson combination of the bounds
    /// ([`StepInfo::anderson_combinations`]).
    #[serde(default)]
    pub anderson_combinations: usize,
    /// Convexification iterates whose bounds the sweeps over Γ_C predicted
    /// ([`StepInfo::predicted_iterates`]).
    #[serde(default)]
    pub predicted_iterates: usize,
    /// Iterates of the iterative path's first way out, where the step's loop failed
    /// ([`StepInfo::way_out_iterates`]).
    #[serde(default)]
    pub way_out_iterates: usize,
    /// Newton iterations cut back along their step
    /// ([`StepInfo::backtracked_newton_iterations`]).
    #[serde(default)]
    pub backtracked_newton_iterations: usize,
}

/// Increments not measured (and those of checkpoints written before steps.csv had them).
fn unmeasured() -> [f64; 4] {
    [f64::NAN; 4]
}

/// JSON writes NaN as `null`: read it back as NaN.
fn nan_from_null<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<[f64; 4], D::Error> {
    let values = <[Option<f64>; 4]>::deserialize(deserializer)?;
    Ok(values.map(|v| v.unwrap_or(f64::NAN)))
}

impl StepRecord {
    /// The columns of `steps.csv`: the solver's figures, then the energies (J; in 2D J per
    /// metre of thickness): the levels K, E, H at t_n, the dissipations, works and heats summed
    /// from t = 0 (so that K + E + viscous + numerical + frictional + thermal stress work − load
    /// work − foundation work − energy_residual_J = K₀ + E₀ on every row), and this step's
    /// residuals relative to their balance's largest term (docs/energy.md); last, the iterations
    /// of the iterative path's way out where the convexification loop failed and the iterates
    /// its loop started from an Anderson combination.
    pub const HEADER: [&'static str; 39] = [
        "n",
        "t",
        "convexification",
        "inner",
        "newton",
        "descent_sweeps",
        "krylov",
        "substeps",
        "cutback_depth",
        "increment_u",
        "increment_theta",
        "increment_xi",
        "increment_zeta",
        "law_residual",
        "slip",
        "stick",
        "seconds",
        "kinetic_J",
        "elastic_J",
        "thermal_J",
        "viscous_dissipation_J",
        "numerical_dissipation_J",
        "frictional_dissipation_J",
        "thermal_stress_work_J",
        "load_work_J",
        "foundation_work_J",
        "energy_residual_J",
        "energy_residual_rel",
        "heat_source_J",
        "heat_exchange_J",
        "heat_friction_J",
        "heat_coupling_J",
        "heat_dirichlet_J",
        "heat_residual_J",
        "heat_residual_rel",
        "nonmonotone_newton",
        "anderson",
        "predicted",
        "backtracked",
    ];

    /// The record as a `steps.csv` row.
    pub fn row(&self) -> Vec<f64> {
        let mut row = vec![
            self.n as f64,
            self.t,
            self.convexification_iterations as f64,
            self.inner_iterations as f64,
            self.newton_iterations as f64,
            self.descent_sweeps as f64,
            self.krylov_iterations as f64,
            self.substeps as f64,
            self.cutback_depth as f64,
        ];
        row.extend(self.increments);
        row.extend([
            self.law_residual,
            self.slip_nodes as f64,
            self.stick_nodes as f64,
            self.seconds,
        ]);
        let e = &self.energy;
        row.extend([
            e.kinetic,
            e.elastic,
            e.thermal,
            e.viscous,
            e.numerical,
            e.frictional,
            e.thermal_stress,
            e.loads,
            e.foundation,
            e.residual,
            self.energy_residual,
            e.heat_sources,
            e.heat_exchange,
            e.heat_friction,
            e.heat_coupling,
            e.heat_dirichlet,
            e.heat_residual,
            self.heat_residual,
            self.nonmonotone_newton_iterations as f64,
            self.anderson_combinations as f64,
            self.predicted_iterates as f64,
            self.backtracked_newton_iterations as f64,
        ]);
        row
    }
}

/// What a run accumulates step by step; a checkpoint keeps it, so that a continued run
/// reports the whole run.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Tally {
    pub run_id: String,
    pub restarts: Vec<usize>,
    pub convexification_iterations: usize,
    pub inner_iterations: usize,
    pub max_convexification_per_step: usize,
    pub newton_iterations: usize,
    pub fallback_steps: usize,
    pub descent_steps: usize,
    pub descent_sweeps: usize,
    #[serde(default)]
    pub nonmonotone_newton_steps: usize,
    #[serde(default)]
    pub nonmonotone_newton_iterations: usize,
    #[serde(default)]
    pub anderson_combinations: usize,
    #[serde(default)]
    pub predicted_iterates: usize,
    #[serde(default)]
    pub backtracked_newton_iterations: usize,
    #[serde(default)]
    pub krylov_iterations: usize,
    /// Iterates of the fixed point on a nonlinear heat exchange, over all steps.
    #[serde(default)]
    pub exchange_iterations: usize,
    /// Iterates of the fixed point on the contact pressure, over all steps.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub pressure_iterations: usize,
    /// Full solves with the step matrix in the time loop, over every part of the run (a
    /// continued run adds its own to those of its checkpoint; 0 in checkpoints from before
    /// they were kept).
    #[serde(default)]
    pub solves: usize,
    /// Triangular sweeps over all of the factor done on their own in the time loop, likewise.
    #[serde(default)]
    pub sweeps: usize,
    pub max_law_residual: f64,
    pub cutbacks: Vec<CutbackRecord>,
    pub outputs: Vec<OutputRecord>,
    /// The frames written, as `solution.pvd` lists them.
    pub frames: Vec<PvdEntry>,
    pub steps: Vec<StepRecord>,
    /// The warnings of a run that leaves the plausible, once per kind (`watch`).
    #[serde(default)]
    pub warnings: Vec<RunWarning>,
}

impl Tally {
    /// A new run's tally.
    pub fn new() -> Self {
        Tally {
            run_id: new_run_id(),
            ..Tally::default()
        }
    }

    /// Counts a completed step.
    pub fn add_step(&mut self, info: &StepInfo, record: StepRecord) {
        self.convexification_iterations += info.convexification_iterations;
        self.inner_iterations += info.inner_iterations;
        self.max_convexification_per_step = self.max_convexification_per_step.max(info.convexification_iterations);
        self.newton_iterations += info.newton_iterations;
        self.fallback_steps += usize::from(info.fallback);
        self.descent_steps += usize::from(info.descent_sweeps > 0);
        self.descent_sweeps += info.descent_sweeps;
        self.nonmonotone_newton_steps += usize::from(info.nonmonotone_newton_iterations > 0);
        self.nonmonotone_newton_iterations += info.nonmonotone_newton_iterations;
        self.anderson_combinations += info.anderson_combinations;
        self.predicted_iterates += info.predicted_iterates;
        self.backtracked_newton_iterations += info.backtracked_newton_iterations;
        self.exchange_iterations += info.exchange_iterations;
        self.pressure_iterations += info.pressure_iterations;
        self.max_law_residual = self.max_law_residual.max(record.law_residual);
        self.steps.push(record);
    }

    /// Sweeps over all of the factor in the time loop, a full solve counting two
    /// (`summary.json`'s `full_sweeps`).
    pub fn full_sweeps(&self) -> usize {
        2 * self.solves + self.sweeps
    }

    /// Full solves and their equivalents, two sweeps counting one, rounded up
    /// (`summary.json`'s `linear_solves`).
    pub fn solve_equivalents(&self) -> usize {
        self.full_sweeps().div_ceil(2)
    }
}

/// A run identifier: the start time (ns since the epoch) and the process id, in hex.
fn new_run_id() -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    format!("{nanos:x}-{:x}", std::process::id())
}
