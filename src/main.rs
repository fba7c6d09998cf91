//! The `thermocontact` command line.
//!
//! ```text
//! thermocontact run                         # the paper's Section 6 example, results in out/
//! thermocontact run my.toml --out results   # a scenario file laid over the default
//! thermocontact run --set mesh.nx=256 --set mesh.ny=64 --set time.steps=64
//! thermocontact scenario > my.toml          # the default scenario, commented
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand};
use thermocontact::driver::{self, RunOptions, Summary};
use thermocontact::scenario::{Scenario, DEFAULT_TOML};

/// Dynamic frictional contact of thermo-viscoelastic bodies with nonmonotone (slip-weakening)
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
    /// (dotted path into the TOML; the value is read as TOML, or as a string). Repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
}

impl ScenarioArgs {
    fn load(&self) -> anyhow::Result<Scenario> {
        let text = match &self.scenario {
            Some(path) => Some(
                std::fs::read_to_string(path).with_context(|| format!("cannot read scenario {}", path.display()))?,
            ),
            None => None,
        };
        let scenario = Scenario::load(text.as_deref(), &self.overrides)?;
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
        /// Output folder (created if missing).
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// No progress bar.
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
        /// Mesh sizes nx of the scaling table (ny = nx/4).
        #[arg(long, value_delimiter = ',', default_value = "64,128,256,512,1024")]
        sizes: Vec<usize>,
        /// Time steps (k = 1/steps).
        #[arg(long, default_value_t = 64)]
        steps: usize,
        /// Also run the paper's solver in the scaling table up to this nx.
        #[arg(long, default_value_t = 128)]
        paper_up_to: usize,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Measured on 2 cores: faer's sequential kernels beat its rayon ones for these sizes.
    faer::set_global_parallelism(faer::Par::Seq);
    match execute(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
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
        } => bench(&out, &sizes, steps, paper_up_to),
        Command::Run { scenario, out, quiet } => {
            let scenario = scenario.load()?;
            print_setup(&scenario);
            let options = RunOptions {
                out_dir: Some(out.clone()),
                progress: !quiet,
            };
            let summary = driver::run(&scenario, &options)?;
            print_summary(&summary);
            println!(
                "results written to {}/ (solution.pvd, solution_*.vtu, contact_*.csv, summary.json)",
                out.display()
            );
            Ok(())
        }
    }
}

fn bench(out: &std::path::Path, sizes: &[usize], steps: usize, paper_up_to: usize) -> anyhow::Result<()> {
    use thermocontact::bench::{format_table, loglog_slope, measure, write_results};
    let exe = std::env::current_exe()?;
    std::fs::create_dir_all(out)?;
    println!("reference discretization of the paper: nx = 256, ny = 64, k = 1/{steps}");
    let mut rows = Vec::new();
    for solver in ["fast", "paper"] {
        let row = measure(&exe, out, solver, 256, steps)?;
        println!("{solver:>6}: {:.3} s wall", row.total);
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
    let work = |r: &&thermocontact::bench::BenchRow| (r.unknowns * r.steps) as f64;
    let fit = |f: &dyn Fn(&thermocontact::bench::BenchRow) -> f64| {
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

fn print_setup(s: &Scenario) {
    let mesh = match s.mesh.nz {
        Some(nz) => format!("{} × {} × {}", s.mesh.nx, s.mesh.ny, nz),
        None => format!("{} × {}", s.mesh.nx, s.mesh.ny),
    };
    println!(
        "thermocontact: Ω = {:?} m, mesh {mesh} cells, T = {} s in {} steps (k = {:.6}), solver {:?}, θ_D = {} °C, α_exp = {:e}",
        s.geometry.lengths,
        s.time.final_time,
        s.time.steps,
        s.time_step(),
        s.solver.kind,
        s.boundary.temperature,
        s.material.thermal_expansion,
    );
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
    println!("{:<34} {:>12}", "inner (augmented-Lagrangian) its", s.inner_iterations);
    println!("{:<34} {:>12}", "semismooth Newton iterations", s.newton_iterations);
    println!("{:<34} {:>12}", "steps through convexification", s.fallback_steps);
    println!();
    println!("{:<34} {:>10.3} s", "assembly", t.assembly);
    println!("{:<34} {:>10.3} s", "factorization", t.factorization);
    println!("{:<34} {:>10.3} s", "solver set-up (condensation)", t.solver_setup);
    println!("{:<34} {:>10.3} s", "time stepping", t.time_stepping);
    println!(
        "{:<34} {:>10.3} s",
        format!("  sparse solves ({})", s.linear_solves),
        t.linear_solves
    );
    println!("{:<34} {:>10.3} s", "  right-hand sides", t.right_hand_sides);
    println!("{:<34} {:>10.3} s", "  nonsmooth solver on Γ_C", t.contact_solver);
    println!("{:<34} {:>10.3} s", "output", t.output);
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
}
