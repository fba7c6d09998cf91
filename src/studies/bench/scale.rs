//! `bench --3d`: the 3D example at growing sizes, a few steps each, on the direct and the
//! iterative path: set-up, time per step, Newton and Krylov iterations per step and peak memory,
//! with their growth exponents in the unknowns (issue 11's targets: ≤ 0.5 s per step at 100k
//! unknowns, ≤ 5 s per step and ≤ 4 GiB at 1M, linear growth on the iterative path).

use std::path::Path;
use std::process::Command;

use serde::{Deserialize, Serialize};

use super::loglog_slope;

/// One measured 3D run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ScaleRow {
    /// `direct` or `iterative`.
    pub linear: String,
    /// The iterative path's preconditioner, `ilu` or `amg` (absent on the direct path).
    #[serde(default)]
    pub preconditioner: Option<String>,
    /// Cells along x, y, z.
    pub cells: [usize; 3],
    pub unknowns: usize,
    pub contact_nodes: usize,
    /// The time step k and the steps run.
    pub k: f64,
    pub steps: usize,
    /// `completed` or `failed` (with the message).
    pub status: String,
    pub failure: Option<String>,
    /// Assembly of the problem's matrices, s.
    pub assembly: f64,
    /// Set-up of the linear path: the LDLᵀ factor and the condensation (direct), or the
    /// ordered matrix and its ILU(0) (iterative), s.
    pub setup: f64,
    /// Time stepping per step (without output), s.
    pub per_step: f64,
    pub newton_per_step: f64,
    /// Convexification (outer) iterations per step, each one or more Newton iterations.
    #[serde(default)]
    pub outer_per_step: f64,
    pub krylov_per_step: f64,
    /// Slip nodes at the last step (the size of the slip zone the steps' iterations resolve).
    #[serde(default)]
    pub slip_nodes: Option<usize>,
    /// Steps cut back into substeps (where the step's loop and its ways out failed).
    #[serde(default)]
    pub cutback_steps: usize,
    /// Stored entries of the factor (LDLᵀ or ILU(0)).
    pub factor_nnz: usize,
    pub peak_memory_mib: Option<f64>,
    /// Wall time of the child process, s.
    pub wall: f64,
}

/// The sizes of `bench --3d`: cells along x (y and z are a quarter), about 47k, 98k, 291k and
/// 972k unknowns.
pub const DEFAULT_SIZES: [usize; 4] = [56, 72, 104, 156];

impl ScaleRow {
    /// The row's path in tables: `direct`, `iterative` (ILU(0)) or `iterative/amg`.
    pub fn path(&self) -> String {
        match self.preconditioner.as_deref() {
            Some("amg") => format!("{}/amg", self.linear),
            _ => self.linear.clone(),
        }
    }
}

/// Runs the 3D example (`scenario`, a path) with nx × nx/4 × nx/4 cells for `steps` steps of
/// size `k` on the `linear` path (the iterative one with `preconditioner`, `ilu` or `amg`) in a
/// child process (outputs off), with the scenario's keys `overrides` (`key=value`) on top, and
/// reads its summary.
#[allow(clippy::too_many_arguments)]
pub fn measure_3d(
    exe: &Path,
    work: &Path,
    scenario: &Path,
    overrides: &[String],
    linear: &str,
    preconditioner: &str,
    nx: usize,
    steps: usize,
    k: f64,
) -> anyhow::Result<ScaleRow> {
    let ny = (nx / 4).max(1);
    let label = if linear == "iterative" && preconditioner != "ilu" {
        format!("{linear}-{preconditioner}")
    } else {
        linear.to_string()
    };
    let dir = work.join(format!("3d-{label}-{nx}x{ny}x{ny}-k{}", (1.0 / k).round()));
    let final_time = k * steps as f64;
    let sets = [
        format!("mesh.nx={nx}"),
        format!("mesh.ny={ny}"),
        format!("mesh.nz={ny}"),
        format!("time.steps={steps}"),
        format!("time.final_time={final_time}"),
        format!("output.times=[{final_time}]"),
        format!("solver.linear={linear}"),
        format!("solver.preconditioner={preconditioner}"),
        "output.vtk=false".into(),
        "output.csv=false".into(),
    ];
    let mut command = Command::new(exe);
    command
        .args(["run", "--quiet", "--overwrite", "--out"])
        .arg(&dir)
        .arg(scenario);
    for set in sets.iter().chain(overrides) {
        command.args(["--set", set]);
    }
    let clock = std::time::Instant::now();
    let result = command.stdout(std::process::Stdio::null()).output()?;
    let wall = clock.elapsed().as_secs_f64();
    let summary: serde_json::Value = match std::fs::read(dir.join("summary.json")) {
        Ok(bytes) => serde_json::from_slice(&bytes)?,
        Err(_) => anyhow::bail!(
            "the {linear} run at nx = {nx} stopped before its time loop: {}",
            String::from_utf8_lossy(&result.stderr).trim()
        ),
    };
    let t = &summary["timings"];
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    let int = |v: &serde_json::Value| v.as_u64().unwrap_or(0) as usize;
    // A failed run's figures are over the steps it completed.
    let done = summary["failure"]["last_step"]
        .as_u64()
        .map_or(steps, |n| n as usize)
        .max(1) as f64;
    Ok(ScaleRow {
        linear: summary["linear"].as_str().unwrap_or(linear).to_string(),
        preconditioner: summary["preconditioner"].as_str().map(str::to_string),
        cells: [nx, ny, ny],
        unknowns: int(&summary["unknowns"]),
        contact_nodes: int(&summary["contact_nodes"]),
        k,
        steps,
        status: summary["status"].as_str().unwrap_or("unknown").to_string(),
        failure: summary["failure"]["message"].as_str().map(str::to_string),
        assembly: num(&t["assembly"]),
        setup: num(&t["factorization"]) + num(&t["solver_setup"]),
        per_step: num(&t["time_stepping"]) / done,
        newton_per_step: int(&summary["newton_iterations"]) as f64 / done,
        outer_per_step: int(&summary["convexification_iterations"]) as f64 / done,
        slip_nodes: (summary["outputs"].as_array())
            .and_then(|outputs| outputs.last())
            .and_then(|last| last["slip_nodes"].as_u64())
            .map(|n| n as usize),
        cutback_steps: summary["cutbacks"].as_array().map_or(0, Vec::len),
        krylov_per_step: int(&summary["krylov_iterations"]) as f64 / done,
        factor_nnz: int(&summary["factor_nnz"]),
        peak_memory_mib: summary["peak_memory_mib"].as_f64(),
        wall,
    })
}

/// The table of `bench --3d`, with the growth exponents of each path in the unknowns.
pub fn format_scale_table(rows: &[ScaleRow]) -> String {
    let mut out = format!(
        "{:<13} {:>14} {:>8} {:>7} {:>9} {:>8} {:>8} {:>10} {:>8} {:>7} {:>9} {:>6} {:>4} {:>11} {:>8} {:>9}\n",
        "path",
        "cells",
        "unknowns",
        "k",
        "status",
        "assem s",
        "setup s",
        "s / step",
        "Newton",
        "outer",
        "Krylov",
        "slip",
        "cut",
        "factor nnz",
        "peak MiB",
        "wall s"
    );
    for r in rows {
        out.push_str(&format!(
            "{:<13} {:>14} {:>8} {:>7} {:>9} {:>8.2} {:>8.2} {:>10.3} {:>8.1} {:>7.1} {:>9.1} {:>6} {:>4} {:>11} {:>8} {:>9.1}\n",
            r.path(),
            format!("{}×{}×{}", r.cells[0], r.cells[1], r.cells[2]),
            r.unknowns,
            format!("1/{}", (1.0 / r.k).round()),
            r.status,
            r.assembly,
            r.setup,
            r.per_step,
            r.newton_per_step,
            r.outer_per_step,
            r.krylov_per_step,
            r.slip_nodes.map_or("-".to_string(), |n| n.to_string()),
            r.cutback_steps,
            r.factor_nnz,
            r.peak_memory_mib.map_or("-".to_string(), |m| format!("{m:.0}")),
            r.wall,
        ));
    }
    let paths: std::collections::BTreeSet<String> = rows.iter().map(ScaleRow::path).collect();
    for linear in paths {
        let same: Vec<&ScaleRow> = rows
            .iter()
            .filter(|r| r.path() == linear && r.status == "completed")
            .collect();
        // One k only: the exponents are in the unknowns at a fixed step size.
        let Some(k) = same.first().map(|r| r.k) else { continue };
        let same: Vec<&ScaleRow> = same.into_iter().filter(|r| r.k == k).collect();
        let fit = |f: &dyn Fn(&ScaleRow) -> f64| {
            loglog_slope(&same.iter().map(|r| (r.unknowns as f64, f(r))).collect::<Vec<_>>())
        };
        if let (Some(step), Some(setup), Some(memory)) = (
            fit(&|r| r.per_step),
            fit(&|r| r.setup),
            fit(&|r| r.peak_memory_mib.unwrap_or(0.0)),
        ) {
            let (smallest, largest) = (
                same.iter().min_by_key(|r| r.unknowns),
                same.iter().max_by_key(|r| r.unknowns),
            );
            let ratio = |f: fn(&ScaleRow) -> f64| match (smallest, largest) {
                (Some(a), Some(b)) => f(b) / f(a),
                _ => f64::NAN,
            };
            out.push_str(&format!(
                "{linear}: growth exponents in the unknowns (least squares, k = 1/{}): time per step {step:.2}, set-up {setup:.2}, peak memory {memory:.2}; Newton iterations per step ×{:.2} and outer ×{:.2} from the first size to the largest\n",
                (1.0 / k).round(),
                ratio(|r| r.newton_per_step),
                ratio(|r| r.outer_per_step),
            ));
        }
    }
    for r in rows.iter().filter(|r| r.failure.is_some()) {
        out.push_str(&format!(
            "{} {}×{}×{}: {}\n",
            r.path(),
            r.cells[0],
            r.cells[1],
            r.cells[2],
            r.failure.as_deref().unwrap_or_default()
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(nx: usize, unknowns: usize, newton: f64, outer: f64, per_step: f64) -> ScaleRow {
        ScaleRow {
            linear: "iterative".into(),
            preconditioner: Some("ilu".into()),
            cells: [nx, nx / 4, nx / 4],
            unknowns,
            contact_nodes: (nx + 1) * (nx / 4 + 1),
            k: 1.0 / 64.0,
            steps: 4,
            status: "completed".into(),
            failure: None,
            assembly: 0.1,
            setup: unknowns as f64 * 1e-6,
            per_step,
            newton_per_step: newton,
            outer_per_step: outer,
            krylov_per_step: 3.0 * newton,
            slip_nodes: Some(nx * 2),
            cutback_steps: usize::from(nx == 160),
            factor_nnz: 60 * unknowns,
            peak_memory_mib: Some(unknowns as f64 * 1e-3),
            wall: 1.0,
        }
    }

    /// The table's growth line: the time exponent fitted in the unknowns, and the iteration
    /// ratios from the smallest size to the largest whatever the rows' order.
    #[test]
    fn the_growth_line_has_the_exponent_and_the_iteration_ratios() {
        // Time per step ∝ N^1.5, Newton 6 → 18, outer 5 → 10; the largest size listed first.
        let rows = [
            row(160, 1_000_000, 18.0, 10.0, 1000f64.powf(1.5) * 1e-4),
            row(40, 10_000, 6.0, 5.0, 10f64.powf(1.5) * 1e-4),
            row(80, 100_000, 12.0, 8.0, 100f64.powf(1.5) * 1e-4),
        ];
        let table = format_scale_table(&rows);
        assert!(table.contains("time per step 1.50"), "{table}");
        assert!(
            table.contains("Newton iterations per step ×3.00 and outer ×2.00"),
            "{table}"
        );
        // The slip and cutback columns show each row's counts.
        assert!(
            table.lines().nth(1).is_some_and(|line| line.contains(" 320    1 ")),
            "{table}"
        );
        assert!(
            table.lines().nth(2).is_some_and(|line| line.contains(" 80    0 ")),
            "{table}"
        );
    }
}
