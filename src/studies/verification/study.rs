//! The convergence studies: the paper's self-convergence study of Fig. 4 and the manufactured
//! solution, each on the sequence h = k = 1/2, 1/4, …, 1/2^N.
//!
//! Level l (h = 2^{−l}) follows the paper's rule: Γ_C (the bottom, of length L₁) is cut into
//! 4/h parts, so n_x = 4/h, and n_y = n_x L₂/L₁ (= 1/h for the paper's 40 × 10 m body: square
//! cells); the time step is k = T h (= h for T = 1 s), N_l = 2^l steps. The meshes are nested
//! and every time level of a level is a time level of all finer ones.
//!
//! * Self-convergence ([`self_convergence`]): the finest level is the reference ("exact")
//!   solution, as in the paper. The coarse levels are run first and their states kept; the
//!   reference is then run once, and at every time level it shares with a coarse level the
//!   coarse fields are prolonged exactly onto the reference mesh and the errors of (73) measured
//!   there ([`super::errors::discrete_errors`]).
//! * Manufactured solution ([`manufactured`]): every level is measured against the exact
//!   solution of [`super::manufactured`] at each of its time levels.
//!
//! The observed order between successive levels is p = log₂(e_{h} / e_{h/2}). Against a
//! self-computed reference the last coarse level sits only a factor 2 from the reference, and its
//! error e ≈ c(h − h_ref) is underestimated; the observed orders at the finest levels are then
//! biased upwards (for p = 1 the last rate tends to log₂ 3 ≈ 1.58). The manufactured study has
//! no such bias.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::errors::{discrete_errors, exact_errors, ErrorHistory, ErrorNorms};
use super::manufactured::Manufactured;
use super::nested::Prolongation;
use crate::error::Error;
use crate::model::Problem;
use crate::model::State;
use crate::output::convergence_plot::{write_convergence_plot, Curve};
use crate::output::{self, OutputError};
use crate::scenario::Scenario;
use crate::time;

/// The largest number of levels: level 8 (h = 1/256) already has 1024 × 256 cells per level for
/// the paper's body and a dense 1024² contact compliance.
pub const MAX_LEVELS: usize = 8;

/// The discretization of one level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LevelSpec {
    /// l: h = 2^{−l}.
    pub level: u32,
    /// h.
    pub h: f64,
    pub nx: usize,
    pub ny: usize,
    /// N = T/k.
    pub steps: usize,
}

/// The levels 1…N of the paper's sequence for a rectangle scenario.
pub fn levels(scenario: &Scenario, n_levels: usize) -> Result<Vec<LevelSpec>, Error> {
    if !(2..=MAX_LEVELS).contains(&n_levels) {
        return Err(Error::InvalidValue {
            key: "--levels".into(),
            value: n_levels.to_string(),
            expected: format!(
                "a number of levels N with 2 ≤ N ≤ {MAX_LEVELS} (h = 1/2 … 1/2^N; at least two levels give a rate)"
            ),
        });
    }
    let Some(grid) = scenario.structured().filter(|g| g.lengths.len() == 2) else {
        return Err(Error::InvalidValue {
            key: "mesh".into(),
            value: format!("{:?}", scenario.mesh),
            expected: "a structured rectangle (2 lengths): the study uses nested rectangle meshes".into(),
        });
    };
    let [l1, l2] = [grid.lengths[0], grid.lengths[1]];
    // n_y = n_x L₂/L₁ = 2^l · (4 L₂/L₁), rounded once so that the levels stay nested.
    let ny_unit = ((l2 / l1) * 4.0).round().max(1.0) as usize;
    Ok((1..=n_levels as u32)
        .map(|level| {
            let parts = 1usize << level;
            LevelSpec {
                level,
                h: 1.0 / parts as f64,
                nx: 4 * parts,
                ny: ny_unit * parts,
                steps: parts,
            }
        })
        .collect())
}

/// The scenario of one level: the base with the level's mesh and time step.
pub fn level_scenario(base: &Scenario, spec: &LevelSpec) -> Result<Scenario, Error> {
    let mut scenario = base.clone();
    scenario.set_cells(spec.nx, spec.ny);
    scenario.time.steps = spec.steps;
    scenario.validate()?;
    Ok(scenario)
}

/// What one level's run cost.
#[derive(Debug, Clone, Serialize)]
pub struct LevelRun {
    pub level: u32,
    pub h: f64,
    /// k = T/N.
    pub k: f64,
    pub nx: usize,
    pub ny: usize,
    pub steps: usize,
    pub nodes: usize,
    pub cells: usize,
    /// Velocity + temperature unknowns per time level.
    pub unknowns: usize,
    pub contact_nodes: usize,
    pub convexification_iterations: usize,
    pub inner_iterations: usize,
    /// Contact nodes slipping at t = T.
    pub slip_nodes_final: usize,
    /// Wall time of the run (assembly, factorization, stepping and measuring), seconds.
    pub wall_time: f64,
}

/// One measured level.
#[derive(Debug, Clone, Serialize)]
pub struct LevelResult {
    pub run: LevelRun,
    pub errors: ErrorNorms,
    /// Observed orders against the next coarser level (none for the coarsest).
    pub rates: Option<ErrorNorms>,
}

/// Which study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StudyKind {
    /// Errors against the finest level (the paper's Fig. 4).
    SelfConvergence,
    /// Errors against the manufactured exact solution.
    Manufactured,
}

/// A finished study: what `converge` prints and writes.
#[derive(Debug, Clone, Serialize)]
pub struct StudyReport {
    pub study: StudyKind,
    pub title: String,
    /// The reference level of a self-convergence study.
    pub reference: Option<LevelRun>,
    /// The same norms of the reference (self-convergence) or exact (manufactured) solution
    /// itself, for scale: max_n ‖u_n‖_E, …, ‖u(T)‖_E.
    pub solution_norms: ErrorNorms,
    pub levels: Vec<LevelResult>,
    /// The whole study, seconds.
    pub wall_time: f64,
}

/// Runs one level, calling `observe` with every new state, and accounts for it.
fn run_level(
    spec: &LevelSpec,
    scenario: &Scenario,
    problem: &Problem,
    mut observe: impl FnMut(&State) -> Result<(), Error>,
) -> Result<LevelRun, Error> {
    let clock = Instant::now();
    let (mut outer, mut inner) = (0, 0);
    let last = time::run(problem, &scenario.solver_params(), |state, info| {
        outer += info.convexification_iterations;
        inner += info.inner_iterations;
        observe(state)
    })?;
    let slip_tolerance = scenario.solver.slip_tolerance;
    let slip_nodes_final = crate::model::contact_rows(problem, &last, slip_tolerance)
        .iter()
        .filter(|r| r.slip)
        .count();
    Ok(LevelRun {
        level: spec.level,
        h: spec.h,
        k: problem.time_step(),
        nx: spec.nx,
        ny: spec.ny,
        steps: spec.steps,
        nodes: problem.mesh.n_nodes(),
        cells: problem.mesh.n_cells(),
        unknowns: problem.n_unknowns(),
        contact_nodes: problem.contact.len(),
        convexification_iterations: outer,
        inner_iterations: inner,
        slip_nodes_final,
        wall_time: clock.elapsed().as_secs_f64(),
    })
}

/// Attaches the observed orders between successive levels.
fn with_rates(measured: Vec<(LevelRun, ErrorNorms)>) -> Vec<LevelResult> {
    let mut results: Vec<LevelResult> = Vec::with_capacity(measured.len());
    for (run, errors) in measured {
        let rates = results
            .last()
            .map(|prev| ErrorNorms::rates(&prev.errors, &errors, prev.run.h / run.h));
        results.push(LevelResult { run, errors, rates });
    }
    results
}

/// The paper's study of Fig. 4 for a scenario: levels 1…N−1 against level N.
/// `progress` sees every finished run (the reference last).
pub fn self_convergence(
    base: &Scenario,
    n_levels: usize,
    progress: &mut dyn FnMut(&LevelRun),
) -> Result<StudyReport, Error> {
    let clock = Instant::now();
    let specs = levels(base, n_levels)?;
    let (coarse_specs, reference_spec) = specs.split_at(specs.len() - 1);
    let reference_spec = reference_spec[0];

    // 1. The coarse levels, keeping their states at every time level.
    let mut coarse = Vec::with_capacity(coarse_specs.len());
    for spec in coarse_specs {
        let problem = level_scenario(base, spec)?.build()?;
        let mut states = Vec::with_capacity(spec.steps);
        let run = run_level(spec, base, &problem, |state| {
            states.push(state.clone());
            Ok(())
        })?;
        progress(&run);
        coarse.push((problem, states, run));
    }

    // 2. The reference, measuring each coarse level at the time levels they share.
    let reference = level_scenario(base, &reference_spec)?.build()?;
    let prolongations = coarse
        .iter()
        .map(|(problem, _, _)| Prolongation::new(problem, &reference))
        .collect::<Result<Vec<_>, _>>()?;
    let mut histories: Vec<ErrorHistory> = coarse
        .iter()
        .map(|(problem, _, _)| ErrorHistory::new(problem.time_step()))
        .collect();
    let mut own = ErrorHistory::new(reference.time_step());
    let zero = |n: usize| vec![0.0; n];
    let reference_run = run_level(&reference_spec, base, &reference, |state| {
        let (nu, nt) = (state.u.len(), state.theta.len());
        own.push(&discrete_errors(&reference, &zero(nu), &zero(nu), &zero(nt), state));
        for (((_, states, run), p), history) in coarse.iter().zip(&prolongations).zip(&mut histories) {
            let ratio = reference_spec.steps / run.steps;
            if state.n % ratio == 0 {
                let c = &states[state.n / ratio - 1];
                debug_assert_eq!(c.n, state.n / ratio);
                let errors = discrete_errors(
                    &reference,
                    &p.apply(&c.u, 2),
                    &p.apply(&c.w, 2),
                    &p.apply(&c.theta, 1),
                    state,
                );
                history.push(&errors);
            }
        }
        Ok(())
    })?;
    progress(&reference_run);

    let measured = coarse
        .into_iter()
        .zip(&histories)
        .map(|((_, _, run), history)| {
            debug_assert_eq!(history.len(), run.steps, "every coarse time level is measured");
            (run, history.norms())
        })
        .collect();
    Ok(StudyReport {
        study: StudyKind::SelfConvergence,
        title: format!(
            "Self-convergence (Fig. 4): errors against the reference h = k = 1/{} ({} × {} cells, {} steps)",
            1usize << reference_spec.level,
            reference_spec.nx,
            reference_spec.ny,
            reference_spec.steps
        ),
        reference: Some(reference_run),
        solution_norms: own.norms(),
        levels: with_rates(measured),
        wall_time: clock.elapsed().as_secs_f64(),
    })
}

/// The manufactured-solution study: every level 1…N against the exact solution.
pub fn manufactured(n_levels: usize, progress: &mut dyn FnMut(&LevelRun)) -> Result<StudyReport, Error> {
    manufactured_with(n_levels, &[], progress)
}

/// [`manufactured`] with `key=value` overrides of the family's scenario (another law of the
/// same family: the exact solution's loads take the laws from the problem).
pub fn manufactured_with(
    n_levels: usize,
    overrides: &[String],
    progress: &mut dyn FnMut(&LevelRun),
) -> Result<StudyReport, Error> {
    let clock = Instant::now();
    let base = Manufactured::scenario(overrides)?;
    let specs = levels(&base, n_levels)?;
    let mut measured = Vec::with_capacity(specs.len());
    let mut solution_norms = ErrorNorms::default();
    for (i, spec) in specs.iter().enumerate() {
        let scenario = level_scenario(&base, spec)?;
        let exact = Manufactured::new(&scenario)?;
        let problem = scenario.builder()?.extra_loads(Box::new(exact)).build()?;
        let k = problem.time_step();
        let mut history = ErrorHistory::new(k);
        // The exact solution's own norms, on the finest mesh (its quadrature is the most exact).
        let finest = i + 1 == specs.len();
        let mut norms = ErrorHistory::new(k);
        let run = run_level(spec, &scenario, &problem, |state| {
            let t = state.n as f64 * k;
            history.push(&exact_errors(&problem, state, &exact, t));
            if finest {
                let zero = State {
                    n: state.n,
                    t: state.t,
                    w: vec![0.0; state.w.len()],
                    u: vec![0.0; state.u.len()],
                    theta: vec![0.0; state.theta.len()],
                    xi: Vec::new(),
                    slip_distance: Vec::new(),
                    slip_distance_before: Vec::new(),
                    pressure: Vec::new(),
                    elastic_force: Vec::new(),
                };
                norms.push(&exact_errors(&problem, &zero, &exact, t));
            }
            Ok(())
        })?;
        progress(&run);
        if finest {
            solution_norms = norms.norms();
        }
        measured.push((run, history.norms()));
    }
    Ok(StudyReport {
        study: StudyKind::Manufactured,
        title: "Manufactured solution with exact stick and slip: errors against the exact solution".into(),
        reference: None,
        solution_norms,
        levels: with_rates(measured),
        wall_time: clock.elapsed().as_secs_f64(),
    })
}

/// Column labels of the table and CSV, in [`ErrorNorms::entries`] order.
pub const NORM_LABELS: [&str; 6] = [
    "‖u−u_h‖_E(T)",
    "max‖u−u_h‖_E",
    "max‖w−w_h‖_L²",
    "max‖θ−θ_h‖_L²",
    "‖θ−θ_h‖_L²(V)",
    "(73)",
];

impl StudyReport {
    /// The table `converge` prints: per level the errors and the observed orders.
    pub fn table(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(s, "{}", self.title);
        let _ = write!(s, "{:>6} {:>7} {:>6} ", "h", "cells", "steps");
        for label in NORM_LABELS {
            let _ = write!(s, "│ {label:>14} {:>5} ", "rate");
        }
        s.push('\n');
        for level in &self.levels {
            let r = &level.run;
            let _ = write!(
                s,
                "{:>6} {:>7} {:>6} ",
                format!("1/{}", 1usize << r.level),
                r.cells,
                r.steps
            );
            let rates = level.rates.map(|r| r.entries());
            for (i, (_, value)) in level.errors.entries().iter().enumerate() {
                let rate = rates.map_or("".to_string(), |r| format!("{:.2}", r[i].1));
                let _ = write!(s, "│ {value:>14.4e} {rate:>5} ");
            }
            s.push('\n');
        }
        let _ = write!(s, "{:>21} ", "solution norms");
        for (_, value) in self.solution_norms.entries() {
            let _ = write!(s, "│ {value:>14.4e} {:>5} ", "");
        }
        s.push('\n');
        if let Some(last) = self.levels.last().and_then(|l| l.rates) {
            let _ = writeln!(
                s,
                "observed order at the finest levels: {:.2} (‖u−u_h‖_E at T), {:.2} (max ‖u−u_h‖_E), {:.2} (max ‖w−w_h‖_L²), {:.2} (max ‖θ−θ_h‖_L²), {:.2} (‖θ−θ_h‖_L²(V)), {:.2} ((73)); theory: 1",
                last.u_energy_final,
                last.u_energy_max,
                last.w_l2_max,
                last.theta_l2_max,
                last.theta_l2_v,
                last.estimate_73
            );
        }
        s
    }

    /// The CSV columns: level data, then every norm followed by its rate (NaN on the coarsest).
    pub fn csv_table(&self) -> (Vec<&'static str>, Vec<Vec<f64>>) {
        let mut header = vec!["level", "h", "k", "nx", "ny", "steps", "cells", "unknowns", "wall_time"];
        let names = [
            ("u_energy_final", "rate_u_energy_final"),
            ("u_energy_max", "rate_u_energy_max"),
            ("w_l2_max", "rate_w_l2_max"),
            ("theta_l2_max", "rate_theta_l2_max"),
            ("theta_l2_v", "rate_theta_l2_v"),
            ("estimate_73", "rate_estimate_73"),
        ];
        for (value, rate) in names {
            header.push(value);
            header.push(rate);
        }
        let rows = self
            .levels
            .iter()
            .map(|level| {
                let r = &level.run;
                let mut row = vec![
                    r.level as f64,
                    r.h,
                    r.k,
                    r.nx as f64,
                    r.ny as f64,
                    r.steps as f64,
                    r.cells as f64,
                    r.unknowns as f64,
                    r.wall_time,
                ];
                let rates = level.rates.map(|r| r.entries());
                for (i, (_, value)) in level.errors.entries().iter().enumerate() {
                    row.push(*value);
                    row.push(rates.map_or(f64::NAN, |r| r[i].1));
                }
                row
            })
            .collect();
        (header, rows)
    }

    /// File stem of the study's outputs.
    pub fn file_stem(&self) -> &'static str {
        match self.study {
            StudyKind::SelfConvergence => "self_convergence",
            StudyKind::Manufactured => "manufactured",
        }
    }

    /// Writes `<stem>.csv` and the log-log plot `<stem>.png` / `<stem>.svg` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, OutputError> {
        let stem = dir.join(self.file_stem());
        let csv = stem.with_extension("csv");
        let (header, rows) = self.csv_table();
        output::write_csv(&csv, &header, &rows)?;
        let curves: Vec<Curve> = NORM_LABELS
            .iter()
            .enumerate()
            .map(|(i, label)| Curve {
                label: label.to_string(),
                points: self.levels.iter().map(|l| (l.run.h, l.errors.entries()[i].1)).collect(),
                emphasis: i == 0,
            })
            .collect();
        let title = match self.study {
            StudyKind::SelfConvergence => "Self-convergence of the paper's example (cf. Fig. 4)",
            StudyKind::Manufactured => "Manufactured solution with stick and slip",
        };
        let mut files = vec![csv];
        files.extend(write_convergence_plot(&stem, title, &curves)?);
        Ok(files)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_follow_the_paper_rule() {
        let specs = levels(&Scenario::default(), 6).unwrap();
        let last = specs.last().unwrap();
        assert_eq!((last.nx, last.ny, last.steps), (256, 64, 64));
        assert_eq!((specs[0].nx, specs[0].ny, specs[0].steps), (8, 2, 2));
        let err = levels(&Scenario::default(), 1).unwrap_err().to_string();
        assert!(err.contains("--levels") && err.contains('1'), "{err}");
        assert!(levels(&Scenario::default(), MAX_LEVELS + 1).is_err());
    }
}
