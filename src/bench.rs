//! The `bench` command: the paper's reference discretization for each solver, and a scaling
//! table of the fast solver over mesh sizes.
//!
//! Every configuration runs in a child process (`thermocontact run` with outputs off), so that
//! each run's peak memory (VmHWM, read by the child at its end) is its own.

use std::path::Path;
use std::process::Command;

use serde::{Deserialize, Serialize};

use crate::output;

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
    pub peak_memory_mib: Option<f64>,
}

/// Runs `thermocontact run` on one configuration in a child process and reads its summary.
pub fn measure(exe: &Path, work: &Path, solver: &str, nx: usize, steps: usize) -> anyhow::Result<BenchRow> {
    let ny = (nx / 4).max(1);
    let dir = work.join(format!("{solver}-{nx}x{ny}-{steps}"));
    let status = Command::new(exe)
        .args(["run", "--quiet", "--out"])
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
        ])
        .stdout(std::process::Stdio::null())
        .status()?;
    anyhow::ensure!(status.success(), "the {solver} run at nx = {nx} failed ({status})");
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("summary.json"))?)?;
    let t = &summary["timings"];
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    let int = |v: &serde_json::Value| v.as_u64().unwrap_or(0) as usize;
    Ok(BenchRow {
        solver: solver.to_string(),
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
        peak_memory_mib: summary["peak_memory_mib"].as_f64(),
    })
}

/// The table header and one line per row.
pub fn format_table(rows: &[BenchRow]) -> String {
    let mut out = format!(
        "{:<6} {:>5} {:>8} {:>9} {:>10} {:>8} {:>8} {:>8} {:>9} {:>8} {:>8} {:>8} {:>7} {:>7} {:>9}\n",
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
        "peak MiB"
    );
    for r in rows {
        out.push_str(&format!(
            "{:<6} {:>5} {:>8} {:>9} {:>10} {:>8.3} {:>8.3} {:>8.3} {:>9.3} {:>8.3} {:>8.3} {:>8.3} {:>7} {:>7} {:>9}\n",
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

/// Peak resident memory of this process so far (Linux: VmHWM), in MiB.
pub fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
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
}
