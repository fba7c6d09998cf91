//! The `bench` command: the paper's reference discretization for each solver, and a scaling
//! table of the fast solver over mesh sizes; with `--hard`, a suite of difficult cases
//! ([`hard_cases`]) that reports whether each completed, its cutbacks and the worst nodal-law
//! residual of the states it returned.
//!
//! Every configuration runs in a child process (`thermocontact run` with outputs off), so that
//! each run's peak memory (VmHWM, read by the child at its end) is its own.

use std::path::Path;
use std::process::Command;

use serde::{Deserialize, Serialize};

use crate::output;

pub mod scale;

/// One measured run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BenchRow {
    pub solver: String,
    pub nx: usize,
    pub ny: usize,
    pub steps: usize,
    pub nodes: usize,
    pub unknowns: usize,
    pub contact_nodes: usize,
    pub factor_nnz: usize,
    pub assembly: f64,
    pub factorization: f64,
    pub solver_setup: f64,
    pub time_stepping: f64,
    pub linear_solves: f64,
    pub contact_solver: f64,
    pub total: f64,
    pub sparse_solves: usize,
    pub convexification_iterations: usize,
    pub inner_iterations: usize,
    pub newton_iterations: usize,
    /// Steps cut back into substeps.
    #[serde(default)]
    pub cutback_steps: usize,
    /// Iterates of the fixed point on a nonlinear heat exchange, over all steps.
    #[serde(default)]
    pub exchange_iterations: usize,
    pub peak_memory_mib: Option<f64>,
}

/// The reference run with the user's laws ([`measure_with`]): the paper's friction law as an
/// expression and as a table (8001 points, in `work`), and a nonmonotone heat exchange.
pub fn user_law_variants(work: &Path) -> anyhow::Result<Vec<(&'static str, Vec<String>)>> {
    std::fs::create_dir_all(work)?;
    let table = work.join("paper_mu.csv");
    let mut text = String::from("slip_rate,coefficient\n");
    for k in 0..=8000 {
        let r = 0.4 * k as f64 / 8000.0;
        text += &format!("{r:e},{:e}\n", 0.8 * (-100.0 * r).exp() + 0.2);
    }
    std::fs::write(&table, text)?;
    Ok(vec![
        (
            "fast+expression",
            vec!["friction={law=\"expression\", bound=150.0, coefficient=\"0.8*exp(-100*r) + 0.2\"}".to_string()],
        ),
        (
            "fast+table",
            vec![format!(
                "friction={{law=\"table\", bound=150.0, file=\"{}\"}}",
                table.display()
            )],
        ),
        (
            "fast+nonmonotone-heat",
            vec!["heat_exchange={law=\"expression\", flux=\"2*theta - 60*sin(theta/20)\"}".to_string()],
        ),
    ])
}

/// Runs `thermocontact run` on one configuration in a child process and reads its summary. The
/// run's folder belongs to the bench: a configuration measured again (the reference run is
/// also a row of the scaling table, and a bench may be repeated) replaces its earlier run.
pub fn measure(exe: &Path, work: &Path, solver: &str, nx: usize, steps: usize) -> anyhow::Result<BenchRow> {
    measure_with(exe, work, solver, solver, nx, steps, &[])
}

/// [`measure`] with `--set` overrides, the row labelled `label`.
pub fn measure_with(
    exe: &Path,
    work: &Path,
    label: &str,
    solver: &str,
    nx: usize,
    steps: usize,
    overrides: &[String],
) -> anyhow::Result<BenchRow> {
    let ny = (nx / 4).max(1);
    let dir = work.join(format!("{label}-{nx}x{ny}-{steps}"));
    let mut command = Command::new(exe);
    command
        .args(["run", "--quiet", "--overwrite", "--out"])
        .arg(&dir)
        .args(["--set", &format!("mesh.nx={nx}"), "--set", &format!("mesh.ny={ny}")])
        .args([
            "--set",
            &format!("time.steps={steps}"),
            "--set",
            &format!("solver.kind={solver}"),
        ])
        .args([
            "--set",
            "output.vtk=false",
            "--set",
            "output.csv=false",
            "--set",
            "output.times=[1.0]",
        ]);
    for set in overrides {
        command.args(["--set", set]);
    }
    let status = command.stdout(std::process::Stdio::null()).status()?;
    anyhow::ensure!(status.success(), "the {solver} run at nx = {nx} failed ({status})");
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("summary.json"))?)?;
    let t = &summary["timings"];
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    let int = |v: &serde_json::Value| v.as_u64().unwrap_or(0) as usize;
    Ok(BenchRow {
        solver: label.to_string(),
        nx,
        ny,
        steps,
        nodes: int(&summary["nodes"]),
        unknowns: int(&summary["unknowns"]),
        contact_nodes: int(&summary["contact_nodes"]),
        factor_nnz: int(&summary["factor_nnz"]),
        assembly: num(&t["assembly"]),
        factorization: num(&t["factorization"]),
        solver_setup: num(&t["solver_setup"]),
        time_stepping: num(&t["time_stepping"]),
        linear_solves: num(&t["linear_solves"]),
        contact_solver: num(&t["contact_solver"]),
        total: num(&t["total"]),
        sparse_solves: int(&summary["linear_solves"]),
        convexification_iterations: int(&summary["convexification_iterations"]),
        inner_iterations: int(&summary["inner_iterations"]),
        newton_iterations: int(&summary["newton_iterations"]),
        cutback_steps: summary["cutbacks"].as_array().map_or(0, Vec::len),
        exchange_iterations: int(&summary["exchange_iterations"]),
        peak_memory_mib: summary["peak_memory_mib"].as_f64(),
    })
}

/// A difficult configuration: the default scenario (or a scenario file) with overrides.
#[derive(Debug, Clone)]
pub struct HardCase {
    pub name: &'static str,
    /// Why it is hard.
    pub what: &'static str,
    /// A scenario file (relative to the working directory), or `None` for the default.
    pub scenario: Option<&'static str>,
    pub overrides: Vec<&'static str>,
}

/// The hard suite: long runs, a coarse k, steep velocity weakening (α up to 1000 s/m, b down to
/// 0.05), and the 3D example on a finer mesh at a coarse k.
pub fn hard_cases() -> Vec<HardCase> {
    let case = |name, what, scenario, overrides: &[&'static str]| HardCase {
        name,
        what,
        scenario,
        overrides: overrides.to_vec(),
    };
    let long = ["time.final_time=3.0", "time.steps=192"];
    let steep = ["friction.alpha=1000.0", "friction.b=0.05"];
    let cells = ["mesh.nx=56", "mesh.ny=14", "mesh.nz=14", "time.steps=8"];
    let iterative = [&cells[..], &["solver.linear=iterative"]].concat();
    vec![
        case(
            "long-fast",
            "default example to T = 3 s (192 steps), fast solver",
            None,
            &long,
        ),
        case(
            "long-no-cut",
            "the same without cutback: the descent must solve every step at k",
            None,
            &[long[0], long[1], "solver.cutback=false"],
        ),
        case(
            "long-paper",
            "the same, the paper's solver",
            None,
            &[long[0], long[1], "solver.kind=\"paper\""],
        ),
        case("coarse-k", "default example with k = 1/8", None, &["time.steps=8"]),
        case(
            "alpha-1000",
            "velocity weakening α = 1000 s/m",
            None,
            &["friction.alpha=1000.0"],
        ),
        case("steep-fast", "α = 1000 s/m and b = 0.05, fast solver", None, &steep),
        case(
            "steep-paper",
            "α = 1000 s/m and b = 0.05, the paper's solver",
            None,
            &[steep[0], steep[1], "solver.kind=\"paper\""],
        ),
        case(
            "3d-56x14x14",
            "3D example on 56 × 14 × 14 cells (47k unknowns), k = 1/8, direct path",
            Some("scenarios/paper3d.toml"),
            &[&cells[..], &["solver.linear=direct"]].concat(),
        ),
        case(
            "3d-iterative",
            "the same on the iterative path (Newton–Krylov, the loop's bounds predicted by the loop on Γ_C's rows through two layers of the body; where it fails, the loop with the law's sweeps, then Newton on the law)",
            Some("scenarios/paper3d.toml"),
            &iterative,
        ),
        case(
            "3d-paper-loop",
            "the same with the paper's loop, one solve per iterate (solver.contact_sweeps = 0)",
            Some("scenarios/paper3d.toml"),
            &[&iterative[..], &["solver.contact_sweeps=0"]].concat(),
        ),
        case(
            "3d-predicted",
            "the same with the bounds of one sweep of the law over Γ_C's own rows (solver.prediction = \"law\", solver.condensed_layers = 0)",
            Some("scenarios/paper3d.toml"),
            &[&iterative[..], &["solver.prediction=\"law\"", "solver.condensed_layers=0"]].concat(),
        ),
        case(
            "3d-condensed",
            "the same with 8 sweeps of the law through two layers of the body (solver.contact_sweeps = 8, solver.prediction = \"law\")",
            Some("scenarios/paper3d.toml"),
            &[&iterative[..], &["solver.contact_sweeps=8", "solver.prediction=\"law\""]].concat(),
        ),
    ]
}

/// How a hard case ended.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct HardRow {
    pub name: String,
    pub what: String,
    /// `completed`, `failed` or `skipped` (the scenario file is missing).
    pub status: String,
    pub unknowns: usize,
    pub steps: usize,
    /// Steps cut back, and the deepest cutback (substeps of k/2^depth).
    pub cutback_steps: usize,
    pub deepest_cutback: usize,
    /// Steps the fast solver finished by descent (the convexification loop failed there).
    pub descent_steps: usize,
    /// Steps the iterative path finished by Newton on the nonmonotone law (its loop failed).
    #[serde(default)]
    pub nonmonotone_newton_steps: usize,
    /// Largest nodal friction-law residual of the returned states, relative to μ(0)S.
    pub max_law_residual: Option<f64>,
    /// Wall time of the child process.
    pub wall: f64,
    pub peak_memory_mib: Option<f64>,
    /// The error of a failed run.
    pub failure: Option<String>,
}

/// Runs one hard case in a child process (outputs off) and reads its summary, failed or not.
pub fn run_hard(exe: &Path, work: &Path, case: &HardCase) -> anyhow::Result<HardRow> {
    let dir = work.join(format!("hard-{}", case.name));
    let mut row = HardRow {
        name: case.name.to_string(),
        what: case.what.to_string(),
        status: "skipped".into(),
        unknowns: 0,
        steps: 0,
        cutback_steps: 0,
        deepest_cutback: 0,
        descent_steps: 0,
        nonmonotone_newton_steps: 0,
        max_law_residual: None,
        wall: 0.0,
        peak_memory_mib: None,
        failure: None,
    };
    let mut command = Command::new(exe);
    command.args(["run", "--quiet", "--overwrite", "--out"]).arg(&dir);
    if let Some(file) = case.scenario {
        if !Path::new(file).exists() {
            row.failure = Some(format!("{file} not found (run from the repository root)"));
            return Ok(row);
        }
        command.arg(file);
    }
    for o in &case.overrides {
        command.args(["--set", o]);
    }
    command.args(["--set", "output.vtk=false", "--set", "output.csv=false"]);
    let clock = std::time::Instant::now();
    let result = command.stdout(std::process::Stdio::null()).output()?;
    row.wall = clock.elapsed().as_secs_f64();
    let summary: serde_json::Value = match std::fs::read(dir.join("summary.json")) {
        Ok(bytes) => serde_json::from_slice(&bytes)?,
        Err(_) => {
            // Stopped before the time loop (an invalid case): no summary to read.
            row.status = "failed".into();
            row.failure = Some(String::from_utf8_lossy(&result.stderr).trim().to_string());
            return Ok(row);
        }
    };
    let int = |v: &serde_json::Value| v.as_u64().unwrap_or(0) as usize;
    row.status = summary["status"].as_str().unwrap_or("unknown").to_string();
    row.unknowns = int(&summary["unknowns"]);
    row.steps = int(&summary["steps"]);
    let cutbacks = summary["cutbacks"].as_array().cloned().unwrap_or_default();
    row.cutback_steps = cutbacks.len();
    row.deepest_cutback = cutbacks.iter().map(|c| int(&c["depth"])).max().unwrap_or(0);
    row.descent_steps = int(&summary["descent_steps"]);
    row.nonmonotone_newton_steps = int(&summary["nonmonotone_newton_steps"]);
    row.max_law_residual = summary["max_law_residual"].as_f64();
    row.peak_memory_mib = summary["peak_memory_mib"].as_f64();
    row.failure = summary["failure"]["message"].as_str().map(str::to_string);
    Ok(row)
}

/// The hard suite's table.
pub fn format_hard_table(rows: &[HardRow]) -> String {
    let mut out = format!(
        "{:<12} {:>9} {:>8} {:>5} {:>9} {:>7} {:>10} {:>11} {:>8} {:>8}\n",
        "case", "status", "unknowns", "steps", "cutbacks", "descent", "law Newton", "law resid.", "wall [s]", "mem MiB"
    );
    for r in rows {
        out.push_str(&format!(
            "{:<12} {:>9} {:>8} {:>5} {:>9} {:>7} {:>10} {:>11} {:>8.2} {:>8}\n",
            r.name,
            r.status,
            r.unknowns,
            r.steps,
            if r.deepest_cutback == 0 {
                "0".to_string()
            } else {
                format!("{} (k/{})", r.cutback_steps, 1usize << r.deepest_cutback)
            },
            r.descent_steps,
            r.nonmonotone_newton_steps,
            r.max_law_residual.map_or("-".to_string(), |v| format!("{v:.1e}")),
            r.wall,
            r.peak_memory_mib.map_or("-".to_string(), |m| format!("{m:.0}")),
        ));
    }
    for r in rows.iter().filter(|r| r.failure.is_some()) {
        out.push_str(&format!("{}: {}\n", r.name, r.failure.as_deref().unwrap_or_default()));
    }
    out
}

/// The table header and one line per row.
pub fn format_table(rows: &[BenchRow]) -> String {
    let mut out = format!(
        "{:<21} {:>5} {:>8} {:>9} {:>10} {:>8} {:>8} {:>8} {:>9} {:>8} {:>8} {:>8} {:>7} {:>7} {:>8} {:>9}\n",
        "solver",
        "nx",
        "nodes",
        "unknowns",
        "factor nnz",
        "assem s",
        "factor s",
        "setup s",
        "solves s",
        "Γ_C s",
        "loop s",
        "total s",
        "outer",
        "newton",
        "cutbacks",
        "peak MiB"
    );
    for r in rows {
        out.push_str(&format!(
            "{:<21} {:>5} {:>8} {:>9} {:>10} {:>8.3} {:>8.3} {:>8.3} {:>9.3} {:>8.3} {:>8.3} {:>8.3} {:>7} {:>7} {:>8} {:>9}\n",
            r.solver,
            r.nx,
            r.nodes,
            r.unknowns,
            r.factor_nnz,
            r.assembly,
            r.factorization,
            r.solver_setup,
            r.linear_solves,
            r.contact_solver,
            r.time_stepping,
            r.total,
            r.convexification_iterations,
            r.newton_iterations,
            r.cutback_steps,
            r.peak_memory_mib.map_or("-".to_string(), |m| format!("{m:.0}")),
        ));
    }
    out
}

/// Least-squares slope of log(y) against log(x).
pub fn loglog_slope(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Writes the rows as JSON and CSV into `dir`.
pub fn write_results(dir: &Path, rows: &[BenchRow]) -> anyhow::Result<()> {
    output::write_atomic(&dir.join("bench.json"), &serde_json::to_vec_pretty(rows)?)?;
    let header = [
        "nx",
        "unknowns",
        "factor_nnz",
        "assembly",
        "factorization",
        "solver_setup",
        "linear_solves",
        "contact_solver",
        "time_stepping",
        "total",
        "peak_memory_mib",
    ];
    for solver in ["fast", "paper"] {
        let data: Vec<Vec<f64>> = rows
            .iter()
            .filter(|r| r.solver == solver)
            .map(|r| {
                vec![
                    r.nx as f64,
                    r.unknowns as f64,
                    r.factor_nnz as f64,
                    r.assembly,
                    r.factorization,
                    r.solver_setup,
                    r.linear_solves,
                    r.contact_solver,
                    r.time_stepping,
                    r.total,
                    r.peak_memory_mib.unwrap_or(f64::NAN),
                ]
            })
            .collect();
        if !data.is_empty() {
            output::write_csv(&dir.join(format!("bench_{solver}.csv")), &header, &data)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<(f64, f64)> = [1.0, 2.0, 4.0, 8.0].iter().map(|&x| (x, 3.0 * x * x)).collect();
        assert!((loglog_slope(&pts).unwrap() - 2.0).abs() < 1e-12);
        assert!(loglog_slope(&pts[..1]).is_none());
    }

    /// Every hard case is a valid scenario (a mistyped key would make the suite measure
    /// nothing), and the 3D case is the size the issue names.
    #[test]
    fn the_hard_cases_are_valid_scenarios() {
        for case in hard_cases() {
            let text = case
                .scenario
                .map(|f| std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(f)).unwrap());
            let overrides: Vec<String> = case.overrides.iter().map(|o| o.to_string()).collect();
            let scenario =
                crate::Scenario::load(text.as_deref(), &overrides).unwrap_or_else(|e| panic!("{}: {e}", case.name));
            scenario.validate().unwrap_or_else(|e| panic!("{}: {e}", case.name));
            if case.name.starts_with("3d") {
                assert_eq!(scenario.dim(), 3);
            }
        }
    }
}
