//! The paper's Section 6 reproduced: its Figures 2 and 3 regenerated from a scenario, and the
//! study that settles the open points of docs/model.md §4 ([`study`]).
//!
//! ```text
//! thermocontact figures   → record_run(scenario) and two runs at α_exp = 1·10⁻⁴, 1·10⁻³
//!                         → Fig. 2 (four times), Fig. 3 (t = T), slip history, Γ_C profiles
//! thermocontact reproduce → the figures + study::run_study → tables (Markdown, JSON)
//! ```
//!
//! What the paper reports for its example (Section 6, "to compare against, not to tune towards")
//! is kept in [`PAPER_COUNTS`]; figures and tables print it next to what this solver computes.

pub mod study;

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::driver::{self, record, OutputRecord, RunOptions, Summary};
use crate::error::Error;
use crate::mesh::chains;
use crate::model::contact_rows;
use crate::model::Problem;
use crate::model::State;
use crate::output::figures::{
    self, format_number, ContactProfileFigure, DeformedFigure, FigureError, HistorySeries, Panel, SlipHistoryFigure,
};
use crate::output::{write_atomic, OutputError};
use crate::scenario::Scenario;

/// A slip count the paper reports: at time `t` with α_exp = `expansion`, `slip_nodes` slip.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct PaperCount {
    pub expansion: f64,
    pub t: f64,
    pub slip_nodes: usize,
}

/// Section 6: "4 of them are in the slip status on the right side … at t = 0.25 s", "at t = 1 s
/// we have 30 nodes in the slip status" (Fig. 2, α_exp = 3·10⁻⁴); "only 5 nodes in slip status
/// in the first case, … 33 in the second" (Fig. 3, t = 1 s, α_exp = 1·10⁻⁴ and 1·10⁻³).
pub const PAPER_COUNTS: [PaperCount; 4] = [
    PaperCount {
        expansion: 3e-4,
        t: 0.25,
        slip_nodes: 4,
    },
    PaperCount {
        expansion: 3e-4,
        t: 1.0,
        slip_nodes: 30,
    },
    PaperCount {
        expansion: 1e-4,
        t: 1.0,
        slip_nodes: 5,
    },
    PaperCount {
        expansion: 1e-3,
        t: 1.0,
        slip_nodes: 33,
    },
];

/// The α_exp values of the paper's Fig. 3.
pub const FIGURE3_EXPANSIONS: [f64; 2] = [1e-4, 1e-3];

/// The paper's count at (α_exp, t), if it reports one.
pub fn paper_count(expansion: f64, t: f64) -> Option<usize> {
    PAPER_COUNTS
        .iter()
        .find(|c| same(c.expansion, expansion) && same(c.t, t))
        .map(|c| c.slip_nodes)
}

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

/// Whether a scenario is the paper's example up to what the paper leaves open or varies: mesh,
/// time step, θ_D, α_exp, solver settings and outputs. Only then are the paper's counts shown.
pub fn is_paper_example(scenario: &Scenario) -> bool {
    let paper = Scenario::default();
    let mut material = scenario.material.clone();
    material.thermal_expansion = paper.material.thermal_expansion;
    let mut boundary = scenario.boundary.clone();
    boundary.temperature = paper.boundary.temperature;
    scenario.geometry == paper.geometry
        && same(scenario.time.final_time, paper.time.final_time)
        && boundary == paper.boundary
        && material == paper.material
        && scenario.initial == paper.initial
        && scenario.loads == paper.loads
        && scenario.friction == paper.friction
        && scenario.heat_exchange == paper.heat_exchange
        && scenario.frictional_heating == paper.frictional_heating
}

/// A state kept at an output time, with its contact rows and figures.
pub struct Snapshot {
    pub record: OutputRecord,
    pub state: State,
}

/// How far apart stick and slip nodes are in |w_τ| over a whole run: every stick node has
/// |w_τ| ≤ `max_stick_rate`, every slip node |w_τ| ≥ `min_slip_rate`. Any slip tolerance in
/// between gives the same statuses.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Separation {
    pub max_stick_rate: f64,
    pub min_slip_rate: f64,
}

/// A run recorded for figures and tables.
pub struct Recorded {
    pub problem: Problem,
    /// The same figures as `thermocontact run` writes to summary.json.
    pub summary: Summary,
    /// States at the output times (only when asked for).
    pub snapshots: Vec<Snapshot>,
    /// (t_n, number of slip nodes) for n = 1..N.
    pub slip_history: Vec<(f64, usize)>,
    pub separation: Separation,
}

/// Runs a scenario, keeping the slip count of every step, the stick/slip separation and, if
/// `keep_states`, the states at the output times.
pub fn record_run(scenario: &Scenario, keep_states: bool) -> Result<Recorded, Error> {
    let output_steps = scenario.output_steps();
    let tolerance = scenario.solver.slip_tolerance;
    let k = scenario.time_step();
    let mut snapshots = Vec::new();
    let mut slip_history = Vec::with_capacity(scenario.time.steps);
    let mut separation = Separation {
        max_stick_rate: 0.0,
        min_slip_rate: f64::INFINITY,
    };
    let problem = scenario.build()?;
    let run = driver::run_observed(
        &problem,
        &scenario.solver_params(),
        &scenario.output_plan(),
        &RunOptions::default(),
        |problem, state, _| {
            let rows = contact_rows(problem, state, tolerance);
            for row in &rows {
                let rate = row.slip_rate();
                if row.slip {
                    separation.min_slip_rate = separation.min_slip_rate.min(rate);
                } else {
                    separation.max_stick_rate = separation.max_stick_rate.max(rate);
                }
            }
            slip_history.push((state.n as f64 * k, rows.iter().filter(|r| r.slip).count()));
            if keep_states && output_steps.contains(&state.n) {
                snapshots.push(Snapshot {
                    record: record(problem, state, tolerance),
                    state: state.clone(),
                });
            }
        },
    )?;
    Ok(Recorded {
        problem,
        summary: run.summary,
        snapshots,
        slip_history,
        separation,
    })
}

/// Errors of figure and study making.
#[derive(Debug, thiserror::Error)]
pub enum ReproductionError {
    /// A run failed (invalid scenario, solver not converged, …).
    #[error(transparent)]
    Run(#[from] Error),
    #[error(transparent)]
    Figure(#[from] FigureError),
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The report file lacks the markers between which the tables go.
    #[error("{}: no `{marker}` line; the generated tables go between `{}` and `{}`", path.display(), study::BEGIN_MARKER, study::END_MARKER)]
    ReportMarkers { path: PathBuf, marker: &'static str },
    /// Bad options of a figure or study command.
    #[error("invalid value for `{option}`: {value} (expected {expected})")]
    InvalidOption {
        option: &'static str,
        value: String,
        expected: String,
    },
}

/// Settings of the figures.
#[derive(Debug, Clone)]
pub struct FigureOptions {
    /// Displacement scale s of the deformed configurations (1 as in the paper).
    pub scale: f64,
    /// α_exp values of Fig. 3 (the paper's: 1·10⁻⁴ and 1·10⁻³).
    pub expansions: Vec<f64>,
}

impl Default for FigureOptions {
    fn default() -> Self {
        FigureOptions {
            scale: 1.0,
            expansions: FIGURE3_EXPANSIONS.to_vec(),
        }
    }
}

/// What [`make_figures`] wrote and computed.
pub struct FiguresMade {
    /// Every PNG and SVG written.
    pub files: Vec<PathBuf>,
    /// The Fig. 2 run (the scenario as given).
    pub main: Summary,
    /// The Fig. 3 runs: (α_exp, summary).
    pub expansions: Vec<(f64, Summary)>,
    /// Wall time of the whole command \[s\].
    pub wall_time: f64,
}

/// The title of a deformed-configuration panel: time, slip and stick counts, and the paper's
/// count where it reports one. Tests read the counts back from the SVG.
pub fn panel_title(prefix: &str, record: &OutputRecord, paper: Option<usize>) -> String {
    let mut title = format!(
        "{prefix}t = {} s: {} slip, {} stick",
        format_number(record.t),
        record.slip_nodes,
        record.stick_nodes
    );
    if let Some(n) = paper {
        title.push_str(&format!(" (paper: {n} slip)"));
    }
    title
}

/// Makes the figures of Section 6 for a scenario into `dir`:
///
/// * `fig2_deformed.{png,svg}`: the scenario at its output times (Fig. 2);
/// * `fig3_expansion.{png,svg}`: the scenario at its last output time for each α_exp of
///   `options.expansions` (Fig. 3);
/// * `slip_history.{png,svg}`: slip nodes against time for all these runs;
/// * `contact_profiles.{png,svg}`: θ, w_τ, ξ along Γ_C at the output times of the Fig. 2 run;
/// * `summary.json` (the Fig. 2 run, as `thermocontact run` writes it) and
///   `fig3_summaries.json` (one per α_exp).
pub fn make_figures(
    scenario: &Scenario,
    dir: &Path,
    options: &FigureOptions,
) -> Result<FiguresMade, ReproductionError> {
    let start = Instant::now();
    if !(options.scale.is_finite() && options.scale >= 0.0) {
        return Err(ReproductionError::InvalidOption {
            option: "--scale",
            value: options.scale.to_string(),
            expected: "a finite displacement scale ≥ 0".into(),
        });
    }
    for &a in &options.expansions {
        if !a.is_finite() {
            return Err(ReproductionError::InvalidOption {
                option: "--expansions",
                value: a.to_string(),
                expected: "finite thermal expansion coefficients α_exp [1/°C]".into(),
            });
        }
    }
    if scenario.dim() != 2 {
        return Err(ReproductionError::InvalidOption {
            option: "mesh",
            value: format!("{}D", scenario.dim()),
            expected: "a 2D mesh: the figures are planar".into(),
        });
    }
    scenario.validate()?;
    if scenario.output.times.is_empty() {
        return Err(ReproductionError::InvalidOption {
            option: "output.times",
            value: "[]".into(),
            expected: "at least one output time: the panels of Fig. 2".into(),
        });
    }
    std::fs::create_dir_all(dir).map_err(OutputError::io(dir))?;
    let paper = is_paper_example(scenario);
    let expansion = scenario.material.thermal_expansion;

    let main = record_run(scenario, true)?;
    let mut variants = Vec::new();
    for &a in &options.expansions {
        let mut s = scenario.clone();
        s.material.thermal_expansion = a;
        variants.push((a, record_run(&s, true)?));
    }

    let mesh = match (scenario.structured(), &scenario.mesh.file) {
        (Some(s), _) => format!("mesh {} × {}", s.nx(), s.ny()),
        (None, Some(file)) => format!(
            "mesh {}",
            file.file_name().map(|n| n.to_string_lossy()).unwrap_or_default()
        ),
        (None, None) => String::new(),
    };
    let setting = format!(
        "{mesh}, k = 1/{}, θ_D = {} °C, slip when |w_τ| > {} m/s",
        scenario.time.steps,
        format_number(scenario.boundary.temperature),
        format_number(scenario.solver.slip_tolerance)
    );
    let gamma_c = chains::part_chains(&main.problem.mesh, &main.problem.parts.contact);
    let paper_at = |a: f64, t: f64| if paper { paper_count(a, t) } else { None };
    let mut files = Vec::new();

    let fig2 = DeformedFigure {
        name: "fig2_deformed".into(),
        heading: format!(
            "Fig. 2: deformed configuration, temperature and friction stresses on Γ_C (α_exp = {})",
            format_number(expansion)
        ),
        subheading: setting.clone(),
        panels: main
            .snapshots
            .iter()
            .map(|s| Panel {
                title: panel_title("", &s.record, paper_at(expansion, s.record.t)),
                mesh: &main.problem.mesh,
                u: &s.state.u,
                theta: &s.state.theta,
                contact: &s.record.contact,
            })
            .collect(),
        columns: 1,
        scale: options.scale,
        gamma_c: gamma_c.clone(),
        force_unit: arrow_unit(&main.problem),
    };
    files.extend(figures::write(&fig2, dir)?);

    if !variants.is_empty() {
        let fig3 = DeformedFigure {
            name: "fig3_expansion".into(),
            heading: "Fig. 3: the influence of the thermal expansion α_exp at the last output time".into(),
            subheading: setting.clone(),
            panels: variants
                .iter()
                .filter_map(|(a, run)| {
                    run.snapshots.last().map(|s| Panel {
                        title: panel_title(
                            &format!("α_exp = {}, ", format_number(*a)),
                            &s.record,
                            paper_at(*a, s.record.t),
                        ),
                        mesh: &run.problem.mesh,
                        u: &s.state.u,
                        theta: &s.state.theta,
                        contact: &s.record.contact,
                    })
                })
                .collect(),
            columns: 1,
            scale: options.scale,
            gamma_c: gamma_c.clone(),
            force_unit: arrow_unit(&main.problem),
        };
        if !fig3.panels.is_empty() {
            files.extend(figures::write(&fig3, dir)?);
        }
    }

    let mut runs: Vec<(f64, &Recorded)> = std::iter::once((expansion, &main))
        .chain(variants.iter().map(|(a, r)| (*a, r)))
        .collect();
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let history = SlipHistoryFigure {
        name: "slip_history".into(),
        heading: "Slip nodes on Γ_C against time".into(),
        subheading: setting.clone(),
        series: runs
            .iter()
            .map(|(a, run)| HistorySeries {
                label: format!("α_exp = {} (this solver)", format_number(*a)),
                counts: run.slip_history.clone(),
                paper: if paper {
                    PAPER_COUNTS
                        .iter()
                        .filter(|c| same(c.expansion, *a))
                        .map(|c| (c.t, c.slip_nodes))
                        .collect()
                } else {
                    Vec::new()
                },
            })
            .collect(),
    };
    files.extend(figures::write(&history, dir)?);

    let profiles = ContactProfileFigure {
        name: "contact_profiles".into(),
        heading: format!(
            "Temperature, tangential velocity and friction stress along Γ_C (α_exp = {})",
            format_number(expansion)
        ),
        subheading: setting.clone(),
        profiles: main
            .snapshots
            .iter()
            .map(|s| (s.record.t, s.record.contact.clone()))
            .collect(),
        gamma_c,
        bound_at_rest: arrow_unit(&main.problem),
    };
    files.extend(figures::write(&profiles, dir)?);

    let expansions: Vec<(f64, Summary)> = variants.into_iter().map(|(a, r)| (a, r.summary)).collect();
    write_json(&dir.join("summary.json"), &main.summary)?;
    let fig3_json: Vec<serde_json::Value> = expansions
        .iter()
        .map(|(a, s)| serde_json::json!({ "thermal_expansion": a, "summary": s }))
        .collect();
    write_json(&dir.join("fig3_summaries.json"), &fig3_json)?;
    Ok(FiguresMade {
        files,
        main: main.summary,
        expansions,
        wall_time: start.elapsed().as_secs_f64(),
    })
}

/// Writes pretty JSON atomically.
pub(crate) fn write_json(path: &Path, value: &impl Serialize) -> Result<(), OutputError> {
    let json = serde_json::to_vec_pretty(value).expect("plain data serializes");
    write_atomic(path, &json).map_err(OutputError::io(path))
}

/// The friction stress drawn as a full-length arrow: the bound at rest μ(0)S where it is
/// prescribed; where it scales with the contact pressure (Coulomb) no datum gives it, and the
/// figure takes its largest |ξ| (0).
fn arrow_unit(problem: &crate::model::Problem) -> f64 {
    if problem.pressure.is_some() {
        0.0
    } else {
        problem.friction_bound([0.0; 3], 0.0, 0.0)
    }
}
