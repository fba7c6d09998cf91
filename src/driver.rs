//! A whole run, as the `run` command does it: factor, step through time, write the results,
//! and account for the time spent. The problem comes built ([`crate::problem::ProblemBuilder`]);
//! the time loop is [`time::march`], observed here for output, progress and timings.
//!
//! ```text
//! factor (StepSystem::new) → set the solver up → N steps (time::march) → outputs
//! ```
//!
//! A run that stops early (a step that does not converge even after the cutbacks, an output
//! error) still leaves a consistent folder: the frames written so far and the last completed
//! state in `solution.pvd`, and `summary.json` with `"status": "failed"` and the failure (step,
//! time, the criterion that failed with its value and tolerance).

use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::error::Error;
use crate::output::{self, fields, Field, Grid, PvdEntry};
use crate::problem::Problem;
use crate::solver::system::{State, StepSystem};
use crate::solver::{SolverParams, StepFailure, StepInfo};
use crate::time::{self, contact_rows, ContactRow, Levels, StepSolver, Stopped};

/// How to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Where to write results; `None` writes nothing.
    pub out_dir: Option<PathBuf>,
    /// Draw a progress bar on stderr.
    pub progress: bool,
    /// Print a line on stderr for every cutback (batch logs); the error that stops a run is
    /// returned to the caller, which reports it.
    pub log: bool,
}

/// What a run records, and when.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputPlan {
    /// Time levels n at which to record the contact state and write files.
    pub steps: Vec<usize>,
    /// Write a `.vtu` per output time and a `.pvd` collection.
    pub vtk: bool,
    /// Write a contact CSV per output time.
    pub csv: bool,
    /// A contact node slips when |w_τ| exceeds this [m/s].
    pub slip_tolerance: f64,
    /// The run's input as text, saved beside the results as `scenario.toml`.
    pub record: Option<String>,
}

impl Default for OutputPlan {
    fn default() -> Self {
        OutputPlan {
            steps: Vec::new(),
            vtk: true,
            csv: true,
            slip_tolerance: 1e-6,
            record: None,
        }
    }
}

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
    /// Of which: the nonsmooth solver on Γ_C and bookkeeping (the rest).
    pub contact_solver: f64,
    /// Writing files.
    pub output: f64,
    /// Everything.
    pub total: f64,
}

/// The contact state at one output time.
#[derive(Debug, Clone, Serialize)]
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
    pub slip_tolerance: f64,
    pub convexification_iterations: usize,
    pub inner_iterations: usize,
    pub max_convexification_per_step: usize,
    /// Semismooth Newton iterations (fast solver).
    pub newton_iterations: usize,
    /// Steps the fast solver took through the convexification loop (law too steep for Newton).
    pub fallback_steps: usize,
    /// Steps (or substeps) the fast solver finished by descent on the step's energy (the
    /// convexification loop failed there).
    pub descent_steps: usize,
    /// Descent sweeps over all steps.
    pub descent_sweeps: usize,
    /// Sparse solves in the time loop: full solves and their equivalents, two sweeps over all of
    /// the factor counting one (rounded up; sweeps over the contact block alone are not counted).
    pub linear_solves: usize,
    /// Triangular sweeps over all of the factor in the time loop (forward or backward; a full
    /// solve counts two).
    pub full_sweeps: usize,
    /// Stored entries of the LDLᵀ factor of the step matrix.
    pub factor_nnz: usize,
    /// Peak resident memory of the process at the end of the run (Linux), MiB.
    pub peak_memory_mib: Option<f64>,
    /// The largest residual of the nodal friction law (−ξ_i ∈ ∂j_τ(w_i): |ξ_i| ≤ μ(0)S at
    /// stick, ξ_i = −μ(|w_i|)S w_i/|w_i| at slip) over every completed step and Γ_C node,
    /// relative to μ(0)S: how well the returned states solve the discrete problem.
    pub max_law_residual: f64,
    /// Steps cut back into substeps (a step that converged at k is not listed).
    pub cutbacks: Vec<CutbackRecord>,
    /// `completed`, or `failed` with [`Summary::failure`].
    pub status: RunStatus,
    /// Why the run stopped, when it did.
    pub failure: Option<FailureRecord>,
    pub timings: Timings,
    pub outputs: Vec<OutputRecord>,
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
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

/// A step that went through substeps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CutbackRecord {
    /// Time level n of the step and t_n.
    pub step: usize,
    pub t: f64,
    /// The deepest cutback: the shortest substep was k/2^depth.
    pub depth: usize,
    /// Substeps taken.
    pub substeps: usize,
}

/// Why a run stopped.
#[derive(Debug, Clone, Serialize)]
pub struct FailureRecord {
    /// The error as the command prints it.
    pub message: String,
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
    fn new(error: &Error, last: &State) -> Self {
        let (step, time, cutback_depth, solver) = match error {
            Error::NotConverged {
                step,
                time,
                cutback_depth,
                failure,
            } => (Some(*step), Some(*time), Some(*cutback_depth), Some(*failure)),
            _ => (None, None, None, None),
        };
        FailureRecord {
            message: error.to_string(),
            step,
            time,
            cutback_depth,
            solver,
            last_step: last.n,
            last_time: last.t,
        }
    }
}

/// Runs a problem end to end.
pub fn run(
    problem: &Problem,
    params: &SolverParams,
    plan: &OutputPlan,
    options: &RunOptions,
) -> Result<Summary, Error> {
    run_observed(problem, params, plan, options, |_, _, _| ()).map(|run| run.summary)
}

/// Runs without writing files or drawing progress (tests and studies); also returns the state
/// at T.
pub fn run_quiet(problem: &Problem, params: &SolverParams, plan: &OutputPlan) -> Result<(Summary, State), Error> {
    run_observed(problem, params, plan, &RunOptions::default(), |_, _, _| ()).map(|run| (run.summary, run.state))
}

/// A finished run: its summary and the state at T.
pub struct Run {
    pub summary: Summary,
    pub state: State,
}

/// [`run`], with `observer` called on every new state (with the step's solver figures), and
/// returning the state at T too.
pub fn run_observed(
    problem: &Problem,
    params: &SolverParams,
    plan: &OutputPlan,
    options: &RunOptions,
    mut observer: impl FnMut(&Problem, &State, &StepInfo),
) -> Result<Run, Error> {
    let start = Instant::now();
    let mut timings = Timings {
        assembly: problem.build_seconds,
        ..Timings::default()
    };

    let clock = Instant::now();
    let system = StepSystem::new(problem)?;
    timings.factorization = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let levels = Levels::new(problem, params, StepSolver::new(problem, system, params)?);
    timings.solver_setup = clock.elapsed().as_secs_f64();

    if let Some(dir) = &options.out_dir {
        std::fs::create_dir_all(dir).map_err(|source| output::OutputError::Io {
            path: dir.clone(),
            source,
        })?;
        if let Some(record) = &plan.record {
            output::write_atomic(&dir.join("scenario.toml"), record.as_bytes()).map_err(|source| {
                output::OutputError::Io {
                    path: dir.join("scenario.toml"),
                    source,
                }
            })?;
        }
    }

    let n_steps = problem.time.steps;
    let bar = if options.progress {
        ProgressBar::new(n_steps as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} step {pos}/{len} [{bar:30}] {elapsed_precise} (eta {eta}) {msg}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    let log = |line: String| {
        if options.log {
            if bar.is_hidden() {
                eprintln!("{line}");
            } else {
                bar.println(line);
            }
        }
    };
    let mut outputs = Vec::new();
    let mut pvd = Vec::new();
    let mut cutbacks = Vec::new();
    let mut max_law_residual: f64 = 0.0;
    let (mut outer_total, mut inner_total, mut outer_max) = (0, 0, 0);
    let (mut newton_total, mut fallbacks) = (0, 0);
    let (mut descent_steps, mut descent_sweeps) = (0, 0);
    let mut output_time = 0.0;
    let loop_clock = Instant::now();
    let marched = time::march(problem, &levels, |state, info| {
        observer(problem, state, info);
        outer_total += info.convexification_iterations;
        inner_total += info.inner_iterations;
        outer_max = outer_max.max(info.convexification_iterations);
        newton_total += info.newton_iterations;
        fallbacks += usize::from(info.fallback);
        descent_steps += usize::from(info.descent_sweeps > 0);
        descent_sweeps += info.descent_sweeps;
        max_law_residual = max_law_residual.max(law_residual(problem, state, plan.slip_tolerance));
        if info.cutback_depth > 0 {
            let cutback = CutbackRecord {
                step: state.n,
                t: state.t,
                depth: info.cutback_depth,
                substeps: info.substeps,
            };
            log(format!(
                "step {} (t = {}): cut back, {} substeps, the shortest k/{}",
                cutback.step,
                cutback.t,
                cutback.substeps,
                1usize << cutback.depth
            ));
            cutbacks.push(cutback);
        }
        bar.inc(1);
        if plan.steps.contains(&state.n) {
            let clock = Instant::now();
            let record = record(problem, state, plan.slip_tolerance);
            bar.set_message(format!(
                "t = {:.3}: {} slip, {} stick",
                record.t, record.slip_nodes, record.stick_nodes
            ));
            if let Some(dir) = &options.out_dir {
                write_snapshot(problem, plan, state, &record, dir, &mut pvd)?;
            }
            outputs.push(record);
            output_time += clock.elapsed().as_secs_f64();
        }
        Ok(())
    });
    let (state, failure) = match marched {
        Ok(state) => {
            bar.finish_and_clear();
            (state, None)
        }
        Err(stopped) => {
            let Stopped { error, last } = *stopped;
            // The caller reports the error itself.
            bar.abandon();
            (last, Some(error))
        }
    };
    timings.time_stepping = loop_clock.elapsed().as_secs_f64() - output_time;
    let loop_stats = levels.step_stats();
    timings.linear_solves = loop_stats.solve_seconds;
    timings.right_hand_sides = loop_stats.rhs_seconds;
    timings.cutback_setup = levels.cutback_setup_seconds();
    timings.contact_solver =
        timings.time_stepping - timings.linear_solves - timings.right_hand_sides - timings.cutback_setup;
    let loop_solves = loop_stats.solve_equivalents();

    let mut summary = Summary {
        dim: problem.dim(),
        nodes: problem.mesh.n_nodes(),
        elements: problem.mesh.n_cells(),
        velocity_unknowns: problem.velocity.n_free,
        temperature_unknowns: problem.temperature.n_free,
        unknowns: problem.n_unknowns(),
        contact_nodes: problem.contact.len(),
        steps: n_steps,
        time_step: problem.time_step(),
        solver: params.kind.name().to_string(),
        slip_tolerance: plan.slip_tolerance,
        convexification_iterations: outer_total,
        inner_iterations: inner_total,
        max_convexification_per_step: outer_max,
        newton_iterations: newton_total,
        fallback_steps: fallbacks,
        descent_steps,
        descent_sweeps,
        linear_solves: loop_solves,
        full_sweeps: loop_stats.full_sweeps(),
        factor_nnz: levels.first().system().factor_nnz(),
        peak_memory_mib: crate::bench::peak_memory_mib(),
        max_law_residual,
        cutbacks,
        status: RunStatus::of(failure.as_ref()),
        failure: failure.as_ref().map(|e| FailureRecord::new(e, &state)),
        timings,
        outputs,
    };
    let written = match &options.out_dir {
        Some(dir) => {
            let clock = Instant::now();
            (|| -> Result<(), Error> {
                // A stopped run keeps its last completed state beside the frames written so far.
                if failure.is_some() && !plan.steps.contains(&state.n) {
                    let record = record(problem, &state, plan.slip_tolerance);
                    write_snapshot(problem, plan, &state, &record, dir, &mut pvd)?;
                }
                if plan.vtk {
                    output::write_pvd(&dir.join("solution.pvd"), &pvd)?;
                }
                summary.timings.output = output_time + clock.elapsed().as_secs_f64();
                summary.timings.total = problem.build_seconds + start.elapsed().as_secs_f64();
                let json = serde_json::to_vec_pretty(&summary).expect("a summary serializes");
                output::write_atomic(&dir.join("summary.json"), &json).map_err(|source| output::OutputError::Io {
                    path: dir.join("summary.json"),
                    source,
                })?;
                Ok(())
            })()
        }
        None => {
            summary.timings.output = output_time;
            summary.timings.total = problem.build_seconds + start.elapsed().as_secs_f64();
            Ok(())
        }
    };
    match (failure, written) {
        // The error that stopped the run comes first; one met while recording it is logged.
        (Some(error), written) => {
            if let Err(also) = written {
                log(format!("error: {also}"));
            }
            Err(error)
        }
        (None, written) => written.map(|()| Run { summary, state }),
    }
}

/// The largest nodal friction-law residual of a state on Γ_C, relative to μ(0)S.
fn law_residual(problem: &Problem, state: &State, slip_tolerance: f64) -> f64 {
    let law = problem.friction.as_ref();
    let tangential = problem.dim() - 1;
    let w_tau = crate::solver::paper::contact_tangential(problem, &state.w);
    let worst = w_tau
        .chunks_exact(tangential)
        .zip(state.xi.chunks_exact(tangential))
        .map(|(w, xi)| crate::contact::friction::law_residual(law, w, xi, slip_tolerance))
        .fold(0.0, f64::max);
    worst / law.bound(0.0).max(f64::MIN_POSITIVE)
}

/// The figures of one output time.
pub fn record(problem: &Problem, state: &State, slip_tolerance: f64) -> OutputRecord {
    let contact = contact_rows(problem, state, slip_tolerance);
    let slip_nodes = contact.iter().filter(|r| r.slip).count();
    let d = problem.dim();
    let max_displacement = state
        .u
        .chunks_exact(d)
        .map(|v| v.iter().map(|x| x * x).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    OutputRecord {
        n: state.n,
        t: state.t,
        slip_nodes,
        stick_nodes: contact.len() - slip_nodes,
        max_slip_rate: contact.iter().map(ContactRow::slip_rate).fold(0.0, f64::max),
        min_temperature: state.theta.iter().cloned().fold(f64::INFINITY, f64::min),
        max_temperature: state.theta.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        max_displacement,
        energy_norm_u: crate::norms::energy(&problem.matrices, &state.u),
        contact,
    }
}

/// Header of the contact CSV files: position, outward normal ν, (3D: the first tangent t₁; in
/// 2D t = ν turned by +90°), w_τ and ξ in the node's tangent coordinates, the friction bound,
/// slip (1) or stick (0), θ.
pub fn contact_csv_header(dim: usize) -> Vec<&'static str> {
    if dim == 2 {
        vec!["x", "y", "nu_x", "nu_y", "w_tau", "xi", "bound", "slip", "theta"]
    } else {
        vec![
            "x", "y", "z", "nu_x", "nu_y", "nu_z", "t1_x", "t1_y", "t1_z", "w_tau1", "w_tau2", "xi1", "xi2", "bound",
            "slip", "theta",
        ]
    }
}

/// The contact CSV rows, in the columns of [`contact_csv_header`].
pub fn contact_csv_rows(dim: usize, rows: &[ContactRow]) -> Vec<Vec<f64>> {
    rows.iter()
        .map(|r| {
            let mut v: Vec<f64> = r.x[..dim].to_vec();
            v.extend_from_slice(&r.normal[..dim]);
            if dim == 3 {
                v.extend_from_slice(&r.tangents[0]);
            }
            v.extend_from_slice(&r.w_tau);
            v.extend_from_slice(&r.xi);
            v.extend([r.bound, if r.slip { 1.0 } else { 0.0 }, r.theta]);
            v
        })
        .collect()
}

fn write_snapshot(
    problem: &Problem,
    plan: &OutputPlan,
    state: &State,
    record: &OutputRecord,
    dir: &Path,
    pvd: &mut Vec<PvdEntry>,
) -> Result<(), Error> {
    let d = problem.dim();
    if plan.csv {
        let path = dir.join(format!("contact_{:04}.csv", state.n));
        output::write_csv(&path, &contact_csv_header(d), &contact_csv_rows(d, &record.contact))?;
    }
    if plan.vtk {
        let file = format!("solution_{:04}.vtu", state.n);
        let stress = fields::cell_stress(problem, state);
        let (status, friction) = fields::nodal_contact_fields(problem, &record.contact);
        let grid = Grid {
            dim: d,
            points: &problem.mesh.coords,
            cells: &problem.mesh.cells,
        };
        let point_fields = [
            Field {
                name: "displacement",
                n_components: d,
                values: &state.u,
            },
            Field {
                name: "velocity",
                n_components: d,
                values: &state.w,
            },
            Field {
                name: "temperature",
                n_components: 1,
                values: &state.theta,
            },
            Field {
                name: "contact_status",
                n_components: 1,
                values: &status,
            },
            Field {
                name: "friction_stress",
                n_components: d,
                values: &friction,
            },
        ];
        let cell_fields = [Field {
            name: "stress",
            n_components: fields::stress_components(d).len(),
            values: &stress,
        }];
        output::write_vtu(&dir.join(&file), &grid, &point_fields, &cell_fields)?;
        pvd.push(PvdEntry { time: record.t, file });
    }
    Ok(())
}
