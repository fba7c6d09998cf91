//! The `thermocontact` command line.
//!
//! ```text
//! thermocontact run                         # the paper's Section 6 example, results in out/
//! thermocontact run my.toml --out results   # a scenario file laid over the default
//! thermocontact run --set mesh.nx=256 --set mesh.ny=64 --set time.steps=64
//! thermocontact scenario > my.toml          # the default scenario, commented
//! thermocontact converge                    # Fig. 4 and the manufactured solution, h = 1/2 … 1/64
//! thermocontact figures --out out/figures   # the paper's Figs. 2 and 3 (PNG + SVG)
//! thermocontact reproduce --report docs/reproduction.md   # figures + study, tables into the report
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand};
use thermocontact::driver::{self, RunOptions, StopFlag, Summary};
use thermocontact::scenario::{Scenario, DEFAULT_TOML};
use thermocontact::studies::reproduction::study::{self, StudyPlan};
use thermocontact::studies::reproduction::{self as repro, FigureOptions, FiguresMade};
use thermocontact::studies::verification::{self, study::LevelRun};
use thermocontact::Interruption;

/// Dynamic frictional contact of thermo-viscoelastic bodies with nonmonotone (velocity-weakening)
/// friction: the P1 / backward-Euler scheme of Bartosz, Danan & Szafraniec, Comput. Math. Appl.
/// 73 (2017) 727–746.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Options shared by every command that reads a scenario.
#[derive(clap::Args)]
struct ScenarioArgs {
    /// Scenario file (TOML), laid over the built-in default (the paper's example); without it
    /// the default runs as is.
    scenario: Option<PathBuf>,
    /// Override one scenario key, e.g. `--set mesh.nx=256` or `--set solver.kind=paper`
    /// (dotted path into the TOML; the value is read as TOML, or as a string). Repeatable; a key
    /// given twice takes the later value (with a warning), and a key inside another --set's
    /// value (`friction=1`, `friction.bound=2`) is refused.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
}

impl ScenarioArgs {
    fn load(&self) -> anyhow::Result<Scenario> {
        let scenario = match &self.scenario {
            Some(path) => Scenario::load_file(path, &self.overrides)?,
            None => Scenario::load(None, &self.overrides)?,
        };
        Ok(scenario)
    }
}

#[derive(Subcommand)]
enum Command {
    /// Run a scenario: VTK series, contact CSVs and summary.json in the output folder, a
    /// summary table on stdout.
    Run {
        #[command(flatten)]
        scenario: ScenarioArgs,
        /// Output folder (created if missing; default `out`). A run locks it while it runs, and
        /// refuses a folder that holds another run's results (see --overwrite and --restart);
        /// without --out, a *completed* run's results in `out` are replaced (said in one line).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Remove the results of the previous run in the output folder first (only the files a
        /// run writes: summary.json, solution.pvd, the frames, steps.csv, scenario.toml,
        /// checkpoint.bin; other files stay).
        #[arg(long)]
        overwrite: bool,
        /// Continue the run stopped in DIR (interrupted, failed, or killed after a checkpoint)
        /// from DIR/checkpoint.bin, writing into DIR. The scenario is DIR/scenario.toml unless
        /// one is given; it must describe the same problem (output and solver settings may
        /// change). Frames after the checkpoint are replaced.
        #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "overwrite"])]
        restart: Option<PathBuf>,
        /// No progress bar and no progress lines.
        #[arg(long)]
        quiet: bool,
    },
    /// Print the built-in default scenario (the paper's Section 6 example) as a commented,
    /// complete TOML file.
    Scenario,
    /// Benchmark: the paper's reference discretization (nx = 256, ny = 64, k = 1/64) with each
    /// solver, then the fast solver over mesh sizes; prints time per phase, iterations and peak
    /// memory, the growth exponent, and writes bench.json / bench_*.csv. Each run is a child
    /// process.
    Bench {
        /// Output folder for the runs and the tables.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Mesh sizes nx of the scaling table (ny = nx/4); add 1024 for the 790k-unknown case
        /// (minutes: the dense contact problem grows as (nx)³ per Newton iteration).
        #[arg(long, value_delimiter = ',', default_value = "64,128,256,512")]
        sizes: Vec<usize>,
        /// Time steps (k = 1/steps).
        #[arg(long, default_value_t = 64)]
        steps: usize,
        /// Also run the paper's solver in the scaling table up to this nx.
        #[arg(long, default_value_t = 128)]
        paper_up_to: usize,
        /// Run the hard suite instead: long runs, a coarse k, steep velocity weakening (α = 1000,
        /// b = 0.05), the 3D example at 47k unknowns and k = 1/8 on both linear paths (about 20 s,
        /// most of it the 3D cases). Prints for each case whether it completed, its cutbacks, the steps the
        /// descent (direct path) or Newton on the law (iterative path) finished and the worst nodal-law residual, and writes bench_hard.json. Run from the repository root (the 3D
        /// case reads scenarios/paper3d.toml).
        #[arg(long)]
        hard: bool,
        /// Run the 3D scaling suite instead: the 3D example (scenarios/paper3d.toml) with
        /// nx × nx/4 × nx/4 cells for each nx of --cells-3d (about 47k, 98k, 291k and 972k
        /// unknowns), --steps-3d steps of k = 1/--inverse-k each, on the iterative path and, up
        /// to --direct-up-to, on the direct one; then nx = --coarse-k-cells again at k = 1/8 on
        /// both paths. Prints set-up, time per step, Newton and Krylov iterations per step and
        /// peak memory with their growth exponents, and writes bench_3d.json (about 30 s).
        #[arg(long = "3d")]
        three_d: bool,
        /// Cells along x of the 3D suite.
        #[arg(long, value_delimiter = ',', default_value = "56,72,104,156")]
        cells_3d: Vec<usize>,
        /// Time steps of each 3D run.
        #[arg(long, default_value_t = 4)]
        steps_3d: usize,
        /// 1/k of the 3D runs (64: the paper's k = 1/64).
        #[arg(long, default_value_t = 64)]
        inverse_k: usize,
        /// The largest nx of the 3D suite (and of its k = 1/8 runs) also run on the direct path
        /// (its factor grows like N^{4/3}: 12 s of set-up at 98k unknowns, no fit at 291k).
        #[arg(long, default_value_t = 72)]
        direct_up_to: usize,
        /// nx of the 3D runs at k = 1/8 (0: none). The iterative path takes about twice the
        /// Newton iterations per step at k = 1/8 as at 1/64 (47k unknowns: 9.5 against 5.0), each
        /// with more Krylov iterations, so 156 (972k unknowns) takes about 40 s; 56 about 1 s.
        #[arg(long, default_value_t = 56)]
        coarse_k_cells: usize,
        /// The preconditioners of the 3D suite's iterative runs, each run once per entry:
        /// `ilu` (ILU(0)) and `amg` (ILU(0) sweeps around PETSc's GAMG on the velocity block;
        /// needs a build with `--features petsc`).
        #[arg(long, value_delimiter = ',', default_value = "ilu")]
        preconditioners: Vec<String>,
        /// The friction bound S of the 3D suite's runs (`friction.bound`; default: the
        /// scenario's 150). The 3D example's slip zone is the contact face's boundary ring of
        /// nodes at every size (its edges' stress concentration): a finer mesh resolves it no
        /// better. With S = 8 a zone of about 40 % of the face grows inward, the same on every
        /// mesh from nx = 80 on: the case on which the outer iterations' growth with refinement
        /// is a property of the method rather than of the zone (docs/performance.md).
        #[arg(long)]
        friction_bound_3d: Option<f64>,
        /// The 3D suite's iterative runs with their convexification iterates' bounds predicted
        /// by this many symmetric Gauss–Seidel sweeps over Γ_C (`solver.contact_sweeps`;
        /// default: the scenario's 1; 0: the paper's loop; docs/solvers.md).
        #[arg(long)]
        contact_sweeps_3d: Option<usize>,
        /// What those sweeps relax the contact nodes with (`solver.prediction`): `loop` (the
        /// convexification loop on Γ_C's rows, the scenario's default) or `law` (the friction
        /// law itself; docs/solvers.md).
        #[arg(long, value_parser = ["loop", "law"])]
        prediction_3d: Option<String>,
        /// Those sweeps with the step matrix condensed onto Γ_C through this many layers of the
        /// body next to it (`solver.condensed_layers`; default: the scenario's 2; 0: Γ_C's own
        /// rows; docs/solvers.md).
        #[arg(long)]
        condensed_layers_3d: Option<usize>,
    },
    /// Convergence study on h = k = 1/2, 1/4, …, 1/2^N (Γ_C cut into 4/h parts): the paper's
    /// self-convergence study of Fig. 4 (errors against the finest level) and a manufactured
    /// solution with exact stick and slip (errors against the exact solution), in the norms of
    /// (73). Prints a table with observed orders; writes CSV, JSON and log-log plots (PNG, SVG).
    /// A scenario file or --set changes the self-convergence study's problem; each level
    /// replaces its mesh (n_x = 4/h, n_y = n_x L₂/L₁) and time step (k = T h).
    Converge {
        #[command(flatten)]
        scenario: ScenarioArgs,
        /// N, the number of levels: h = k = 1/2 … 1/2^N (the default 6 is the paper's study up
        /// to h = 1/64, about a minute in release builds).
        #[arg(long, default_value_t = 6)]
        levels: usize,
        /// Which study: `paper` (self-convergence of the scenario, Fig. 4), `manufactured`
        /// (the exact-solution family; takes no scenario file or --set), or `both`.
        #[arg(long, value_enum, default_value_t = Study::Both)]
        study: Study,
        /// Output folder (created if missing).
        #[arg(long, default_value = "out/converge")]
        out: PathBuf,
    },
    /// Draw the paper's Section 6 figures for a scenario, as PNG and SVG: Fig. 2 (deformed
    /// configuration, temperature, friction stresses, stick/slip nodes at the output times),
    /// Fig. 3 (the same at t = T for other α_exp), the slip count against time and θ, w_τ, ξ
    /// along Γ_C. Also writes summary.json of the Fig. 2 run.
    Figures {
        #[command(flatten)]
        scenario: ScenarioArgs,
        /// Output folder (created if missing).
        #[arg(long, default_value = "out/figures")]
        out: PathBuf,
        #[command(flatten)]
        figures: FigureArgs,
    },
    /// Reproduce the paper's Section 6: the figures, then the study of its open points (θ_D = 0
    /// or θ₀, meshes, time steps, α_exp, slip tolerance) as Markdown tables (tables.md) and JSON
    /// (study.json); `--report FILE` also refreshes the tables in FILE (docs/reproduction.md).
    Reproduce {
        #[command(flatten)]
        scenario: ScenarioArgs,
        /// Output folder for figures and tables (created if missing).
        #[arg(long, default_value = "docs/figures")]
        out: PathBuf,
        /// Markdown report whose generated section (between the reproduce:begin/end markers) is
        /// replaced by the new tables.
        #[arg(long, value_name = "FILE")]
        report: Option<PathBuf>,
        /// Meshes of the study: nx values (ny = nx·L₂/L₁), each run with every --steps.
        #[arg(long, value_delimiter = ',', default_values_t = [16, 32, 40, 64, 128])]
        meshes: Vec<usize>,
        /// Numbers of time steps N (k = T/N) of the study.
        #[arg(long, value_delimiter = ',', default_values_t = [16, 32, 64])]
        steps: Vec<usize>,
        /// Finer meshes run at the scenario's N and α_exp only (the paper's h = 1/64 is nx = 256).
        #[arg(long, value_delimiter = ',', default_values_t = [256])]
        fine_meshes: Vec<usize>,
        /// Skip the fine meshes (a quicker study).
        #[arg(long)]
        no_fine: bool,
        #[command(flatten)]
        figures: FigureArgs,
    },
}

/// The studies of `converge`.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Study {
    Paper,
    Manufactured,
    Both,
}

/// Options of the figures.
#[derive(clap::Args)]
struct FigureArgs {
    /// Displacement scale of the deformed configurations (1, as in the paper, draws x + u).
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// α_exp values [1/°C] of Fig. 3 (the paper's: 1e-4 and 1e-3); also the α_exp of the study.
    #[arg(long, value_delimiter = ',', default_values_t = [1e-4, 1e-3])]
    expansions: Vec<f64>,
}

impl FigureArgs {
    fn options(&self) -> FigureOptions {
        FigureOptions {
            scale: self.scale,
            expansions: self.expansions.clone(),
        }
    }
}

fn main() -> ExitCode {
    if let Err(message) = thermocontact::resources::check_instruction_set() {
        eprintln!("error: {message}");
        return ExitCode::FAILURE;
    }
    let cli = Cli::parse();
    // Measured on 2 cores: faer's sequential kernels beat its rayon ones for these sizes.
    faer::set_global_parallelism(faer::Par::Seq);
    match execute(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let error = e.downcast_ref::<thermocontact::Error>();
            let message = match error.and_then(thermocontact::scenario::keys_behind) {
                Some(keys) => format!("error: {}. {keys}", chain(&e)),
                None => format!("error: {}", chain(&e)),
            };
            let code = match error {
                // 130 / 143, as the shell reports a process ended by SIGINT / SIGTERM.
                Some(thermocontact::Error::Interrupted { cause, .. }) => cause.exit_code(),
                _ => 1,
            };
            ranks::end_with(&message, code)
        }
    }
}

/// The ranks of a distributed run (`mpirun -n P thermocontact run`, cargo feature `mpi`). MPI
/// starts only where a launcher started more than one rank (Open MPI's `OMPI_COMM_WORLD_SIZE`,
/// or `PMI_SIZE`): one process behaves as without the feature.
mod ranks {
    use std::sync::atomic::{AtomicUsize, Ordering};

    static SIZE: AtomicUsize = AtomicUsize::new(1);
    static RANK: AtomicUsize = AtomicUsize::new(0);

    /// The ranks the launcher started (1 without a launcher).
    fn launched() -> usize {
        (["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"].iter())
            .filter_map(|v| std::env::var(v).ok()?.parse::<usize>().ok())
            .max()
            .unwrap_or(1)
    }

    /// (rank, size) of this process, MPI started where there is more than one rank.
    pub fn start() -> anyhow::Result<(usize, usize)> {
        if launched() <= 1 {
            return Ok((0, 1));
        }
        #[cfg(feature = "mpi")]
        {
            let comm = thermocontact::la::mpi::Communicator::world()?;
            SIZE.store(comm.size(), Ordering::SeqCst);
            RANK.store(comm.rank(), Ordering::SeqCst);
            Ok((comm.rank(), comm.size()))
        }
        #[cfg(not(feature = "mpi"))]
        anyhow::bail!(
            "started as {} ranks, but this build has no MPI: build thermocontact with `--features mpi` \
             (docs/distributed.md), or run one process",
            launched()
        )
    }

    /// This rank's problem in a distributed run: its share of the matrices (`continued`: from
    /// its checkpoint, as `Scenario::build_continued`); collective.
    pub fn build_share(
        scenario: &thermocontact::scenario::Scenario,
        continued: bool,
    ) -> anyhow::Result<thermocontact::model::Problem> {
        #[cfg(feature = "mpi")]
        {
            let comm = thermocontact::la::mpi::Communicator::world()?;
            Ok(scenario.build_on_ranks(continued, comm)?)
        }
        // `start` refuses more than one rank without MPI: no share to build.
        #[cfg(not(feature = "mpi"))]
        {
            let _ = (scenario, continued);
            anyhow::bail!(
                "started over several ranks, but this build has no MPI: build thermocontact with `--features mpi`"
            )
        }
    }

    /// Ends the process after an error: one process prints it and exits with `code`. In a
    /// distributed run the ranks meet the same error from the same numbers, so rank 0 prints it
    /// and ends every rank (`MPI_Abort`); another rank waits for that, and ends every rank with
    /// its own message where rank 0 did not (an error of its own).
    pub fn end_with(message: &str, code: u8) -> std::process::ExitCode {
        let (rank, size) = (RANK.load(Ordering::SeqCst), SIZE.load(Ordering::SeqCst));
        if size <= 1 {
            eprintln!("{message}");
            return std::process::ExitCode::from(code);
        }
        #[cfg(feature = "mpi")]
        if let Ok(comm) = thermocontact::la::mpi::Communicator::world() {
            if rank == 0 {
                eprintln!("{message}");
                // mpirun forwards the ranks' output as it comes: time for the message to leave
                // before MPI_Abort ends the ranks.
                std::thread::sleep(std::time::Duration::from_millis(500));
                comm.abort_all(
                    "the run failed on rank 0 (the error above); every rank ends",
                    i32::from(code),
                );
            }
            std::thread::sleep(std::time::Duration::from_secs(5));
            comm.abort_all(message, i32::from(code));
        }
        let _ = rank;
        eprintln!("{message}");
        std::process::ExitCode::from(code)
    }
}

/// The error and its causes, joined by ": ", each cause once: a message that already quotes its
/// cause (`cannot read x: No such file or directory (os error 2)`, as the library's errors do so
/// that their `to_string()` is complete) is not followed by that cause again.
fn chain(error: &anyhow::Error) -> String {
    let mut text = String::new();
    let mut previous = String::new();
    for cause in error.chain() {
        let message = cause.to_string();
        if !previous.is_empty() && previous.contains(&message) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&message);
        previous = message;
    }
    text
}

/// What to try after a run whose linear solves ran out of Krylov iterations with ILU(0) alone
/// (`preconditioner` the run's setting): ILU(0) keeps them short while the mass term dominates,
/// not where the stiffness weighs, which is what the two-level preconditioner is for. None after
/// any other error, or where that preconditioner could have been taken (`auto` or `amg` in a
/// build with PETSc).
fn krylov_hint(
    error: &thermocontact::Error,
    preconditioner: thermocontact::step::PreconditionerKind,
) -> Option<String> {
    use thermocontact::step::{Criterion, PreconditionerKind};
    use thermocontact::time::TimeError;
    let thermocontact::Error::Time(TimeError::NotConverged { failure, .. }) = error else {
        return None;
    };
    if failure.criterion != Criterion::LinearResidual {
        return None;
    }
    let why = "hint: the linear solves ran out of Krylov iterations (`solver.max_krylov`) with ILU(0) alone, \
               which keeps them short while the mass term dominates (the paper's k) but not where the stiffness \
               weighs (a large k, a stiff or thin body)";
    let direct = "or `solver.linear = \"direct\"` solves each step exactly where the body fits in memory";
    match (cfg!(feature = "petsc"), preconditioner) {
        (false, _) => Some(format!(
            "{why}: a build with `--features petsc` (PETSc from Debian: README, Install) takes the two-level \
             preconditioner there (`solver.preconditioner = \"auto\"`, the default, or `\"amg\"`), {direct}"
        )),
        (true, PreconditionerKind::Ilu) => Some(format!(
            "{why}: `solver.preconditioner = \"auto\"` (the default) or `\"amg\"` takes the two-level \
             preconditioner, {direct}"
        )),
        (true, _) => None,
    }
}

/// What a stopped run left in its folder, for the message after its error: only the files that
/// are there (a run that fails before its first step has written no checkpoint, or nothing).
fn stopped_run_hint(out: &std::path::Path) -> String {
    let has = |name: &str| out.join(name).is_file();
    let mut left = Vec::new();
    if has("solution.pvd") {
        left.push("solution.pvd with the frames so far and the last completed step".to_string());
    }
    if has(driver::CHECKPOINT_FILE) {
        left.push(format!(
            "{} to continue with `thermocontact run --restart {}`",
            driver::CHECKPOINT_FILE,
            out.display()
        ));
    }
    if has("summary.json") {
        left.push("summary.json with the status and the reason".to_string());
    }
    if left.is_empty() {
        format!(
            "the run stopped before it wrote any result into {}/ (nothing to continue from)",
            out.display()
        )
    } else {
        format!(
            "the run stopped; what it computed is in {}/ ({})",
            out.display(),
            left.join(", ")
        )
    }
}

/// SIGINT and SIGTERM ask the run to stop after the current step: it then writes the last
/// completed state as a checkpoint, finishes its files and says `interrupted`, so that the folder
/// continues with `--restart`. A second signal cuts the current step short
/// ([`StopFlag::request_now`]): the run ends at the last completed step, its files written the
/// same way. A third ends the process at once (ending it at the second, as before, left `running`,
/// no checkpoint and sometimes a half-written frame), and the message says what is then lost.
///
/// The signals are read on a thread of their own (`signal_hook::iterator`), not in a handler,
/// so it may count them and print (`say`: rank 0 of a distributed run, whose ranks agree on the
/// stop, or the one process).
///
/// **Over ranks** (`over_ranks`) the first signal already cuts the step short: a rank hears one
/// SIGTERM (Open MPI's `mpirun` sends it for a Ctrl-C and kills the ranks a second later; Slurm
/// for its time limit, 30 s before), and the ranks leave the step at the same check, then write
/// the folder ([`thermocontact::step::abort`]).
fn stop_on_signals(say: bool, over_ranks: bool) -> anyhow::Result<StopFlag> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let flag = StopFlag::new();
    let stop = flag.clone();
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::spawn(move || {
        for (heard, signal) in signals.forever().enumerate() {
            let cause = match signal {
                SIGTERM => Interruption::Terminate,
                _ => Interruption::Interrupt,
            };
            if over_ranks {
                stop.request_now(cause);
                if say && heard == 0 {
                    eprintln!(
                        "\nstopping: the ranks cut the current step short and write the folder, with a checkpoint \
                         of the last completed step to continue from"
                    );
                }
                continue;
            }
            match heard {
                0 if !say => stop.request(cause),
                1 if !say => stop.request_now(cause),
                0 => {
                    stop.request(cause);
                    eprintln!(
                        "\nstopping after the current step, then writing a checkpoint to continue from \
                         (a second Ctrl-C cuts the step short and stops at the step before)"
                    );
                }
                1 => {
                    stop.request_now(cause);
                    eprintln!(
                        "\ncutting the current step short: the run ends at the last completed step and writes its \
                         checkpoint (a third Ctrl-C ends the process at once, without it: summary.json then still \
                         says running)"
                    );
                }
                _ => {
                    eprintln!("\nended at once: the folder keeps only the files written so far");
                    std::process::exit(128 + signal);
                }
            }
        }
    });
    Ok(flag)
}

/// The output times of `scenario` at or before the checkpoint of `restart` that the stopped run
/// did not write: a continued run starts after the checkpoint, so it cannot write them.
fn skipped_output_times(scenario: &Scenario, restart: &driver::Restart) -> Vec<f64> {
    let at = restart.checkpoint.state.n;
    let written: Vec<u64> = (restart.checkpoint.record.get("outputs").and_then(|o| o.as_array()))
        .map(|outputs| outputs.iter().filter_map(|o| o.get("n")?.as_u64()).collect())
        .unwrap_or_default();
    let k = scenario.time_step();
    (scenario.output_plan().steps.into_iter())
        .filter(|&n| n <= at && !written.contains(&(n as u64)))
        .map(|n| n as f64 * k)
        .collect()
}

/// A restart with a scenario other than the one of the checkpoint's run: refused naming the keys
/// whose values differ, read from the folder's `scenario.toml` (the stopped run's). Without that
/// file, or where no key of the problem differs, the driver's check (by fingerprint) decides.
fn refuse_another_scenario(
    scenario: &Scenario,
    restart: &driver::Restart,
    dir: &std::path::Path,
) -> anyhow::Result<()> {
    let expected = scenario.fingerprint();
    if restart
        .checkpoint
        .identity
        .scenario
        .as_deref()
        .is_none_or(|found| found == expected)
    {
        return Ok(());
    }
    let echo = dir.join("scenario.toml");
    let Ok(before) = std::fs::read_to_string(&echo) else {
        return Ok(());
    };
    let keys = thermocontact::scenario::differing_keys(&before, &scenario.to_toml());
    if keys.is_empty() {
        return Ok(());
    }
    anyhow::bail!(
        "the checkpoint {} belongs to another scenario; these keys differ from the stopped run's ({}):\n  {}\n\
         a run continues only from its own checkpoints (only [output] and [solver] may change)",
        restart.path.display(),
        echo.display(),
        keys.join("\n  ")
    )
}

/// The solver settings of a run over `size` ranks: the iterative path's Newton–Krylov solver
/// with its Krylov solves on PETSc over the ranks. The paper's solver and the direct path
/// (the LDLᵀ factor and the dense condensation on Γ_C) run on one process: a distributed run
/// with them is refused, naming the key.
fn distributed_params(
    mut params: thermocontact::step::SolverParams,
    size: usize,
) -> anyhow::Result<thermocontact::step::SolverParams> {
    use thermocontact::step::{LinearKind, SolverKind};
    if size <= 1 {
        return Ok(params);
    }
    if params.kind == SolverKind::Paper {
        anyhow::bail!(
            "solver.kind = \"paper\" runs on one process (its Uzawa iterations on Γ_C): a run over {size} ranks \
             needs solver.kind = \"fast\" (Newton–Krylov on the iterative path), or run it without mpirun"
        );
    }
    if params.linear == LinearKind::Direct {
        anyhow::bail!(
            "solver.linear = \"direct\" runs on one process (an LDLᵀ factor and the dense condensation on Γ_C): \
             a run over {size} ranks needs solver.linear = \"iterative\" (or \"auto\"), or run it without mpirun"
        );
    }
    params.linear = LinearKind::Iterative;
    params.krylov.distributed = true;
    Ok(params)
}

fn execute(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Scenario => {
            print!("{DEFAULT_TOML}");
            Ok(())
        }
        Command::Bench {
            out,
            sizes,
            steps,
            paper_up_to,
            hard,
            three_d,
            cells_3d,
            steps_3d,
            inverse_k,
            direct_up_to,
            coarse_k_cells,
            preconditioners,
            friction_bound_3d,
            contact_sweeps_3d,
            prediction_3d,
            condensed_layers_3d,
        } => {
            if three_d {
                let suite = Suite3d {
                    cells: cells_3d,
                    steps: steps_3d,
                    inverse_k,
                    direct_up_to,
                    coarse_k_cells,
                    preconditioners,
                    overrides: (friction_bound_3d.map(|s| format!("friction.bound={s}")).into_iter())
                        .chain(contact_sweeps_3d.map(|n| format!("solver.contact_sweeps={n}")))
                        .chain(prediction_3d.map(|p| format!("solver.prediction=\"{p}\"")))
                        .chain(condensed_layers_3d.map(|n| format!("solver.condensed_layers={n}")))
                        .collect(),
                };
                bench_3d(&out, &suite)
            } else if hard {
                bench_hard(&out)
            } else {
                bench(&out, &sizes, steps, paper_up_to)
            }
        }
        Command::Converge {
            scenario,
            levels,
            study,
            out,
        } => converge(scenario, levels, study, out),
        Command::Run {
            scenario,
            out,
            overwrite,
            restart,
            quiet,
        } => {
            let (rank, size) = ranks::start()?;
            let root = rank == 0;
            // Without --out, the default folder takes a new run in place of a completed one
            // (running the same command twice is the first thing a newcomer does).
            let replace_completed = out.is_none() && restart.is_none();
            let out = out.unwrap_or_else(|| PathBuf::from("out"));
            let (scenario, out, restart) = match restart {
                None => (scenario.load()?, out, None),
                Some(dir) => {
                    let scenario = match &scenario.scenario {
                        Some(_) => scenario.load()?,
                        None => Scenario::load_file(&dir.join("scenario.toml"), &scenario.overrides)?,
                    };
                    let checkpoint = driver::Restart::read(&dir.join(driver::CHECKPOINT_FILE))?;
                    (scenario, dir, Some(checkpoint))
                }
            };
            let params = distributed_params(scenario.solver_params(), size)?;
            if root {
                print_setup(&scenario);
            }
            if let Some(restart) = &restart {
                refuse_another_scenario(&scenario, restart, &out)?;
            }
            if let Some(restart) = restart.as_ref().filter(|_| root) {
                println!(
                    "continuing from step {} (t = {}) of {}",
                    restart.checkpoint.state.n,
                    restart.checkpoint.state.t,
                    restart.path.display()
                );
                let skipped = skipped_output_times(&scenario, restart);
                if !skipped.is_empty() {
                    let times: Vec<String> = skipped.iter().map(|t| format!("{t}")).collect();
                    eprintln!(
                        "warning: {} output time(s) at or before the checkpoint (t = {}) are not written, as the run continues after it: t = {}",
                        skipped.len(),
                        restart.checkpoint.state.t,
                        times.join(", ")
                    );
                }
            }
            // A continued run starts from its checkpoint: `initial.from` is not read again (that
            // checkpoint may be gone; its name still counts in the scenario's fingerprint).
            // A rank of a distributed run builds its share of the matrices (the columns its
            // rows read: `model::ColumnShare`).
            let problem = if size > 1 {
                ranks::build_share(&scenario, restart.is_some())?
            } else if restart.is_some() {
                scenario.build_continued()?
            } else {
                scenario.build()?
            };
            if root && replace_completed && !overwrite && thermocontact::output::folder::holds_completed_run(&out) {
                println!(
                    "replacing the completed run in {}/ (give --out to keep results apart)",
                    out.display()
                );
            }
            if size > 1 && root {
                println!(
                    "distributed over {size} ranks (PETSc + MPI): each rank owns the rows of its part of the mesh \
                     and writes its piece of each frame into {}/; rank 0 the other files",
                    out.display()
                );
            }
            // In a distributed run rank 0 owns the folder and the terminal; the other ranks
            // compute the same steps and write only their pieces of the frames.
            let options = RunOptions {
                out_dir: Some(out.clone()),
                progress: !quiet && root,
                log: root,
                overwrite,
                replace_completed,
                stop: Some(stop_on_signals(root, size > 1)?),
                restart,
                ..RunOptions::default()
            };
            let summary =
                driver::run(&problem, &params, &scenario.output_plan(), &options).inspect_err(|error| match error {
                    thermocontact::Error::Folder(_) | thermocontact::Error::Checkpoint(_) => {}
                    _ if !root => {}
                    _ => {
                        eprintln!("{}", stopped_run_hint(&out));
                        if let Some(hint) = krylov_hint(error, params.krylov.preconditioner) {
                            eprintln!("{hint}");
                        }
                    }
                })?;
            if !root {
                return Ok(());
            }
            print_summary(&summary);
            println!(
                "{}; results written to {}/ (solution.pvd, solution_*.{}, contact_*.csv, summary.json)",
                summary.outcome,
                out.display(),
                if size > 1 { "pvtu and their pieces" } else { "vtu" }
            );
            Ok(())
        }
        Command::Figures { scenario, out, figures } => {
            let scenario = scenario.load()?;
            print_setup(&scenario);
            let made = repro::make_figures(&scenario, &out, &figures.options())?;
            print_figures(&made);
            Ok(())
        }
        Command::Reproduce {
            scenario,
            out,
            report,
            meshes,
            steps,
            fine_meshes,
            no_fine,
            figures,
        } => {
            let start = std::time::Instant::now();
            let scenario = scenario.load()?;
            print_setup(&scenario);
            let made = repro::make_figures(&scenario, &out, &figures.options())?;
            print_figures(&made);
            let mut plan = StudyPlan::paper(&scenario);
            plan.meshes = meshes;
            plan.steps = steps;
            plan.fine_meshes = if no_fine { Vec::new() } else { fine_meshes };
            let mut expansions = figures.expansions.clone();
            expansions.push(scenario.material.thermal_expansion);
            expansions.sort_by(f64::total_cmp);
            expansions.dedup();
            plan.expansions = expansions;
            println!("\nthe study (θ_D, mesh, k, α_exp: slip nodes at the output times):");
            let result = study::run_study(&scenario, &plan, |i, n, r| {
                let c = &r.case;
                println!(
                    "  [{i:>2}/{n}] θ_D = {:>4}, {:>3} × {:<3}, k = 1/{:<3}, α_exp = {:e}: {:?} ({:.1} s)",
                    c.boundary_temperature, c.nx, c.ny, c.steps, c.expansion, r.slip_nodes, r.wall_time
                );
            })?;
            let tables = result.tables();
            let tables_path = out.join("tables.md");
            thermocontact::output::write_atomic(&tables_path, tables.as_bytes())
                .with_context(|| format!("cannot write {}", tables_path.display()))?;
            let json = serde_json::to_vec_pretty(&result).expect("the study serializes");
            let json_path = out.join("study.json");
            thermocontact::output::write_atomic(&json_path, &json)
                .with_context(|| format!("cannot write {}", json_path.display()))?;
            println!("\n{tables}");
            if let Some(report) = &report {
                study::update_report(report, &tables)?;
                println!("tables written into {}", report.display());
            }
            println!(
                "figures and tables in {}/ (tables.md, study.json); reproduce took {:.0} s",
                out.display(),
                start.elapsed().as_secs_f64()
            );
            Ok(())
        }
    }
}

fn bench(out: &std::path::Path, sizes: &[usize], steps: usize, paper_up_to: usize) -> anyhow::Result<()> {
    use thermocontact::studies::bench::{
        format_table, loglog_slope, measure, measure_with, user_law_variants, write_results,
    };
    let exe = std::env::current_exe()?;
    std::fs::create_dir_all(out)?;
    println!("reference discretization of the paper: nx = 256, ny = 64, k = 1/{steps}");
    let mut rows = Vec::new();
    for solver in ["fast", "paper"] {
        let row = measure(&exe, out, solver, 256, steps)?;
        println!("{solver:>6}: {:.3} s wall", row.total);
        rows.push(row);
    }
    // The user's laws on the reference run: the friction law as an expression and as a table
    // (target: within 15 % of the built-in law), and a nonmonotone heat exchange.
    for (label, overrides) in user_law_variants(out)? {
        let row = measure_with(&exe, out, label, "fast", 256, steps, &overrides)?;
        let against = rows[0].total;
        println!(
            "{label:>22}: {:.3} s wall ({:+.0} % against the built-in law), {} heat-exchange iterates ({:.2} per step)",
            row.total,
            100.0 * (row.total / against - 1.0),
            row.exchange_iterations,
            row.exchange_iterations as f64 / steps as f64
        );
        rows.push(row);
    }
    println!("\n{}", format_table(&rows));
    let mut scaling = Vec::new();
    for &nx in sizes {
        for solver in ["fast", "paper"] {
            if solver == "paper" && nx > paper_up_to {
                continue;
            }
            let row = measure(&exe, out, solver, nx, steps)?;
            eprintln!("  {solver} nx = {nx}: {:.3} s", row.total);
            scaling.push(row);
        }
    }
    println!("scaling (ny = nx/4, {steps} steps):\n{}", format_table(&scaling));
    let fast: Vec<_> = scaling.iter().filter(|r| r.solver == "fast").collect();
    let work = |r: &&thermocontact::studies::bench::BenchRow| (r.unknowns * r.steps) as f64;
    let fit = |f: &dyn Fn(&thermocontact::studies::bench::BenchRow) -> f64| {
        loglog_slope(&fast.iter().map(|r| (work(r), f(r))).collect::<Vec<_>>())
    };
    if let (Some(total), Some(stepping), Some(memory)) = (
        fit(&|r| r.total),
        fit(&|r| r.time_stepping),
        fit(&|r| r.peak_memory_mib.unwrap_or(0.0)),
    ) {
        println!(
            "growth exponents in unknowns × steps (fast solver, least squares): total {total:.2}, time loop {stepping:.2}, peak memory {memory:.2}"
        );
    }
    rows.extend(scaling);
    write_results(out, &rows)?;
    println!(
        "tables written to {}/ (bench.json, bench_fast.csv, bench_paper.csv)",
        out.display()
    );
    Ok(())
}

/// `bench --hard`: every hard case in a child process, then the table.
fn bench_hard(out: &std::path::Path) -> anyhow::Result<()> {
    use thermocontact::studies::bench::{format_hard_table, hard_cases, run_hard};
    let exe = std::env::current_exe()?;
    std::fs::create_dir_all(out)?;
    let mut rows = Vec::new();
    for case in hard_cases() {
        eprintln!("{}: {} …", case.name, case.what);
        let row = run_hard(&exe, out, &case)?;
        eprintln!("  {} in {:.1} s", row.status, row.wall);
        rows.push(row);
    }
    println!("\n{}", format_hard_table(&rows));
    let path = out.join("bench_hard.json");
    thermocontact::output::write_atomic(&path, &serde_json::to_vec_pretty(&rows)?)?;
    println!("written to {}", path.display());
    Ok(())
}

/// What `bench --3d` runs (its options).
struct Suite3d {
    cells: Vec<usize>,
    steps: usize,
    inverse_k: usize,
    direct_up_to: usize,
    coarse_k_cells: usize,
    preconditioners: Vec<String>,
    /// Scenario keys set on every run (`key=value`).
    overrides: Vec<String>,
}

/// `bench --3d`: the 3D example at growing sizes on both linear paths, then one size at
/// k = 1/8.
fn bench_3d(out: &std::path::Path, suite: &Suite3d) -> anyhow::Result<()> {
    use thermocontact::studies::bench::scale::{format_scale_table, measure_3d};
    let exe = std::env::current_exe()?;
    let scenario = std::path::Path::new("scenarios/paper3d.toml");
    anyhow::ensure!(
        scenario.exists(),
        "{} not found: run bench --3d from the repository root",
        scenario.display()
    );
    anyhow::ensure!(
        suite.inverse_k > 0 && suite.steps > 0,
        "--inverse-k and --steps-3d must be positive"
    );
    if let Some(bad) = (suite.preconditioners.iter()).find(|p| !["ilu", "amg"].contains(&p.as_str())) {
        anyhow::bail!("--preconditioners: `{bad}` is not a preconditioner (expected ilu or amg)");
    }
    std::fs::create_dir_all(out)?;
    let k = 1.0 / suite.inverse_k as f64;
    let mut cases: Vec<(usize, f64)> = suite.cells.iter().map(|&nx| (nx, k)).collect();
    if suite.coarse_k_cells > 0 && suite.inverse_k != 8 {
        cases.push((suite.coarse_k_cells, 1.0 / 8.0));
    }
    let mut runs: Vec<(&str, &str, usize, f64)> = Vec::new();
    for (nx, k) in cases {
        if nx <= suite.direct_up_to {
            runs.push(("direct", "ilu", nx, k));
        }
        runs.extend(suite.preconditioners.iter().map(|p| ("iterative", p.as_str(), nx, k)));
    }
    let mut rows = Vec::new();
    for (linear, preconditioner, nx, k) in runs {
        eprintln!("{linear} ({preconditioner}), nx = {nx}, k = 1/{} …", (1.0 / k).round());
        let row = measure_3d(
            &exe,
            out,
            scenario,
            &suite.overrides,
            linear,
            preconditioner,
            nx,
            suite.steps,
            k,
        )?;
        eprintln!(
            "  {} in {:.1} s: {:.3} s per step, {:.0} MiB",
            row.status,
            row.wall,
            row.per_step,
            row.peak_memory_mib.unwrap_or(f64::NAN)
        );
        rows.push(row);
    }
    println!("\n{}", format_scale_table(&rows));
    let path = out.join("bench_3d.json");
    thermocontact::output::write_atomic(&path, &serde_json::to_vec_pretty(&rows)?)?;
    println!("written to {}", path.display());
    Ok(())
}

/// `converge`: run the studies, print their tables, write CSV, JSON and plots.
fn converge(scenario: ScenarioArgs, n_levels: usize, study: Study, out: PathBuf) -> anyhow::Result<()> {
    let given = scenario.scenario.is_some() || !scenario.overrides.is_empty();
    if study == Study::Manufactured && given {
        anyhow::bail!("a scenario file or --set applies to the paper's self-convergence study only (--study paper or both); the manufactured family has its own data");
    }
    // Check everything before the first (long) run.
    let base = scenario.load()?;
    verification::study::levels(&base, n_levels)?;
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut progress = |run: &LevelRun| {
        eprintln!(
            "  h = k = 1/{:<4} {:>5} × {:<4} cells, {:>4} steps: {:>8.2} s, {} convexification iterations",
            1usize << run.level,
            run.nx,
            run.ny,
            run.steps,
            run.wall_time,
            run.convexification_iterations
        );
    };
    let mut reports = Vec::new();
    if study != Study::Manufactured {
        println!(
            "thermocontact converge: Ω = {:?} m, T = {} s, solver {:?}, θ_D = {} °C, α_exp = {:e}; each level replaces the scenario's mesh and time step",
            base.structured().map(|s| s.lengths).unwrap_or_default(),
            base.time.final_time,
            base.solver.kind,
            base.boundary.temperature,
            base.material.thermal_expansion,
        );
        eprintln!("self-convergence study, {n_levels} levels:");
        reports.push(verification::study::self_convergence(&base, n_levels, &mut progress)?);
    }
    if study != Study::Paper {
        eprintln!("manufactured solution, {n_levels} levels:");
        reports.push(verification::study::manufactured(n_levels, &mut progress)?);
    }
    let mut files = Vec::new();
    for report in &reports {
        println!();
        print!("{}", report.table());
        files.extend(report.write(&out)?);
    }
    let json: serde_json::Map<String, serde_json::Value> = reports
        .iter()
        .map(|r| {
            (
                r.file_stem().to_string(),
                serde_json::to_value(r).expect("a report serializes"),
            )
        })
        .collect();
    let path = out.join("convergence.json");
    thermocontact::output::write_atomic(&path, &serde_json::to_vec_pretty(&json)?)
        .with_context(|| format!("cannot write {}", path.display()))?;
    files.push(path);
    println!();
    let names: Vec<String> = files
        .iter()
        .map(|f| {
            f.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .collect();
    println!("results written to {}/ ({})", out.display(), names.join(", "));
    Ok(())
}

fn print_figures(made: &FiguresMade) {
    println!();
    println!("{:>12} {:>8} {:>6} {:>6}", "α_exp", "t [s]", "slip", "stick");
    let main = std::iter::once((None, &made.main));
    for (alpha, summary) in main.chain(made.expansions.iter().map(|(a, s)| (Some(*a), s))) {
        let label = alpha.map_or("scenario".to_string(), |a| format!("{a:e}"));
        for o in &summary.outputs {
            println!("{:>12} {:>8.4} {:>6} {:>6}", label, o.t, o.slip_nodes, o.stick_nodes);
        }
    }
    for file in &made.files {
        println!("wrote {}", file.display());
    }
    println!("figures took {:.1} s", made.wall_time);
}

fn print_setup(s: &Scenario) {
    let mesh = match (s.structured(), &s.mesh.file) {
        (Some(g), _) => {
            let cells: Vec<String> = g.cells.iter().map(usize::to_string).collect();
            format!("Ω = {:?} m, mesh {} cells", g.lengths, cells.join(" × "))
        }
        (None, Some(file)) => format!("mesh {} ({}D)", file.display(), s.dim()),
        (None, None) => "no mesh".to_string(),
    };
    println!(
        "thermocontact: {mesh}, T = {} s in {} steps (k = {:.6}), solver {:?}, θ_D = {} °C, α_exp = {:e}",
        s.time.final_time,
        s.time.steps,
        s.time_step(),
        s.solver.kind,
        s.boundary.temperature,
        s.material.thermal_expansion,
    );
    if !s.thermal.is_empty() {
        let listed: Vec<String> = s
            .thermal
            .iter()
            .map(|t| format!("{} {}", t.part, t.condition))
            .collect();
        println!(
            "thermal conditions: {} (other parts as the paper: θ_D on Γ_D ∪ Γ_N)",
            listed.join(", ")
        );
    }
    for warning in &s.warnings {
        eprintln!("warning: {warning}");
    }
}

fn print_summary(s: &Summary) {
    let t = &s.timings;
    println!();
    println!("{:<34} {:>12}", "nodes", s.nodes);
    println!("{:<34} {:>12}", "elements", s.elements);
    println!(
        "{:<34} {:>12}",
        "unknowns (velocity + temperature)",
        format!("{} + {}", s.velocity_unknowns, s.temperature_unknowns)
    );
    println!("{:<34} {:>12}", "contact nodes", s.contact_nodes);
    println!("{:<34} {:>12}", "time steps", s.steps);
    println!(
        "{:<34} {:>12}",
        "convexification iterations", s.convexification_iterations
    );
    println!("{:<34} {:>12}", "inner iterations (Uzawa / sweeps)", s.inner_iterations);
    println!("{:<34} {:>12}", "semismooth Newton iterations", s.newton_iterations);
    if s.linear == "iterative" {
        let per_solve = s.krylov_iterations as f64 / s.linear_solves.max(1) as f64;
        println!(
            "{:<34} {:>12}",
            format!(
                "Krylov iterations ({}, per solve)",
                s.preconditioner.as_deref().unwrap_or("ilu")
            ),
            format!("{} ({per_solve:.1})", s.krylov_iterations)
        );
    } else {
        println!("{:<34} {:>12}", "steps through convexification", s.fallback_steps);
    }
    if s.descent_steps > 0 {
        println!(
            "{:<34} {:>12}",
            "steps finished by descent (sweeps)",
            format!("{} ({})", s.descent_steps, s.descent_sweeps)
        );
    }
    if s.nonmonotone_newton_steps > 0 {
        println!(
            "{:<34} {:>12}",
            "steps by Newton on the law (its)",
            format!("{} ({})", s.nonmonotone_newton_steps, s.nonmonotone_newton_iterations)
        );
    }
    if s.anderson_combinations > 0 {
        println!(
            "{:<34} {:>12}",
            "iterates from Anderson (of all)",
            format!("{} ({})", s.anderson_combinations, s.convexification_iterations)
        );
    }
    if s.predicted_iterates > 0 {
        println!(
            "{:<34} {:>12}",
            "iterates with predicted bounds",
            format!("{} ({})", s.predicted_iterates, s.convexification_iterations)
        );
    }
    if s.backtracked_newton_iterations > 0 {
        println!(
            "{:<34} {:>12}",
            "Newton steps cut back (of all)",
            format!("{} ({})", s.backtracked_newton_iterations, s.newton_iterations)
        );
    }
    if s.exchange_iterations > 0 {
        println!(
            "{:<34} {:>12}",
            "heat-exchange iterates (per step)",
            format!(
                "{} ({:.2})",
                s.exchange_iterations,
                s.exchange_iterations as f64 / s.steps as f64
            )
        );
    }
    if s.pressure_iterations > 0 {
        println!(
            "{:<34} {:>12}",
            "contact-pressure iterates (per step)",
            format!(
                "{} ({:.2})",
                s.pressure_iterations,
                s.pressure_iterations as f64 / s.steps as f64
            )
        );
    }
    let deepest = s.cutbacks.iter().map(|c| c.depth).max().unwrap_or(0);
    println!(
        "{:<34} {:>12}",
        "steps cut back (shortest substep)",
        if deepest == 0 {
            "0".to_string()
        } else {
            format!("{} (k/{})", s.cutbacks.len(), 1usize << deepest)
        }
    );
    println!();
    println!("{:<34} {:>10.3} s", "assembly", t.assembly);
    if s.linear == "iterative" {
        let label = match s.preconditioner.as_deref() {
            Some("amg") => "ILU(0) + AMG preconditioner",
            _ => "ILU(0) preconditioner",
        };
        println!("{:<34} {:>10.3} s", label, t.factorization);
        if let Some(amg) = s.amg {
            println!(
                "{:<34} {:>12}",
                "  AMG levels (operator complexity)",
                format!("{} ({:.2})", amg.levels, amg.operator_complexity)
            );
        }
    } else {
        println!("{:<34} {:>10.3} s", "factorization", t.factorization);
        println!("{:<34} {:>10.3} s", "solver set-up (condensation)", t.solver_setup);
    }
    println!("{:<34} {:>10.3} s", "time stepping", t.time_stepping);
    println!(
        "{:<34} {:>10.3} s",
        format!("  sparse solves ({})", s.linear_solves),
        t.linear_solves
    );
    println!("{:<34} {:>10.3} s", "  right-hand sides", t.right_hand_sides);
    if t.cutback_setup > 0.0 {
        println!("{:<34} {:>10.3} s", "  cutback levels set-up", t.cutback_setup);
    }
    println!("{:<34} {:>10.3} s", "  nonsmooth solver on Γ_C", t.contact_solver);
    println!("{:<34} {:>10.3} s", "  energies", t.energies);
    println!("{:<34} {:>10.3} s", "output (waited for)", t.output);
    println!("{:<34} {:>10.3} s", "  frames (writer thread)", t.frames);
    println!("{:<34} {:>10.3} s", "wall time", t.total);
    println!();
    println!(
        "{:>8} {:>6} {:>6} {:>6} {:>12} {:>10} {:>10}",
        "t [s]", "n", "slip", "stick", "max|w_τ|", "min θ", "max θ"
    );
    for o in &s.outputs {
        println!(
            "{:>8.4} {:>6} {:>6} {:>6} {:>12.4e} {:>10.4} {:>10.4}",
            o.t, o.n, o.slip_nodes, o.stick_nodes, o.max_slip_rate, o.min_temperature, o.max_temperature
        );
    }
    println!("(a contact node slips when |w_τ| > {:e} m/s)", s.slip_tolerance);
    if let Some(e) = &s.energy {
        print_energy(e);
    }
}

/// The energies of a run: the levels at 0 and T, what was dissipated and worked, the heats,
/// and the worst step's balance residuals.
fn print_energy(e: &driver::EnergySummary) {
    let t = &e.total;
    println!();
    println!("{:<34} {:>12} {:>12}", "energy [J] (2D: per metre)", "t = 0", "t = T");
    println!(
        "{:<34} {:>12.4e} {:>12.4e}",
        "  kinetic K", e.initial_kinetic, t.kinetic
    );
    println!(
        "{:<34} {:>12.4e} {:>12.4e}",
        "  elastic E", e.initial_elastic, t.elastic
    );
    println!(
        "{:<34} {:>12.4e} {:>12.4e}",
        "  thermal H = ∫ρc_pθ", e.initial_thermal, t.thermal
    );
    for (label, value) in [
        ("  dissipated: viscous", t.viscous),
        ("  dissipated: numerical (Euler)", t.numerical),
        ("  dissipated: friction", t.frictional),
        ("  work of the thermal stress", t.thermal_stress),
        ("  work of the loads", t.loads),
        ("  work of the foundation", t.foundation),
        ("  heat in: sources", t.heat_sources),
        ("  heat in: exchange on Γ_C", t.heat_exchange),
        ("  heat in: friction", t.heat_friction),
        ("  heat in: coupling", t.heat_coupling),
        ("  heat in: fixed temperatures", t.heat_dirichlet),
    ] {
        println!("{label:<34} {:>25.4e}", value);
    }
    println!(
        "{:<34} {:>25}",
        "balance residual (worst step)",
        format!("{:.1e} / {:.1e}", e.max_energy_residual, e.max_heat_residual)
    );
}
