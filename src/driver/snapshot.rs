//! The files of one frame: the figures of an output time ([`record`]), the contact CSV and the
//! `.vtu` of a state, named by its time level.

use std::path::Path;

use super::summary::OutputRecord;
use super::OutputPlan;
use crate::error::Error;
use crate::model::Problem;
use crate::model::State;
use crate::model::{contact_rows, ContactRow};
use crate::output::{self, fields, Compression, Field, Grid, PvdEntry};

/// `_0042.` in the file names of time level 42's frame ([`crate::output::folder::frame_step`]
/// reads it back).
fn frame_tag(n: usize) -> String {
    format!("_{n:04}.")
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
        energy_norm_u: crate::model::norms::energy(&problem.matrices, &state.u),
        contact,
    }
}

/// Header of the contact CSV files: position, outward normal ν, (3D: the first tangent t₁; in
/// 2D t = ν turned by +90°), w_τ and ξ in the node's tangent coordinates (w_τ is the slip
/// relative to the foundation, w_τ − v_F,τ: the velocity itself where the foundation is at
/// rest), the friction bound, slip (1) or stick (0), θ; the slip distance s where a law weakens
/// with it (`slip_distance`), and the contact pressure p where a law scales with it
/// (`pressure`).
pub fn contact_csv_header(dim: usize, slip_distance: bool, pressure: bool) -> Vec<&'static str> {
    let mut header = if dim == 2 {
        vec!["x", "y", "nu_x", "nu_y", "w_tau", "xi", "bound", "slip", "theta"]
    } else {
        vec![
            "x", "y", "z", "nu_x", "nu_y", "nu_z", "t1_x", "t1_y", "t1_z", "w_tau1", "w_tau2", "xi1", "xi2", "bound",
            "slip", "theta",
        ]
    };
    if slip_distance {
        header.push("slip_distance");
    }
    if pressure {
        header.push("pressure");
    }
    header
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
            v.extend(r.slip_distance);
            v.extend(r.pressure);
            v
        })
        .collect()
}

pub(super) fn write_snapshot(
    problem: &Problem,
    plan: &OutputPlan,
    state: &State,
    record: &OutputRecord,
    dir: &Path,
    pvd: &mut Vec<PvdEntry>,
) -> Result<(), Error> {
    let d = problem.dim();
    if plan.csv {
        let path = dir.join(format!("contact{}csv", frame_tag(state.n)));
        let header = contact_csv_header(d, problem.uses_slip_distance(), problem.pressure.is_some());
        output::write_csv(&path, &header, &contact_csv_rows(d, &record.contact))?;
    }
    if plan.vtk {
        let file = format!("solution{}vtu", frame_tag(state.n));
        let stress = fields::cell_stress(problem, state);
        let von_mises = fields::von_mises(&stress);
        let (status, friction) = fields::nodal_contact_fields(problem, &record.contact);
        let mut slip_distance = vec![0.0; problem.mesh.n_nodes()];
        let mut pressure = vec![0.0; problem.mesh.n_nodes()];
        for row in &record.contact {
            slip_distance[row.node] = row.slip_distance.unwrap_or(0.0);
            pressure[row.node] = row.pressure.unwrap_or(0.0);
        }
        let grid = Grid {
            dim: d,
            points: &problem.mesh.coords,
            cells: &problem.mesh.cells,
        };
        let mut point_fields = vec![
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
        // The slip distance only where a law weakens with it, the contact pressure only where
        // a law scales with it (the other runs' files stay as they were).
        if problem.uses_slip_distance() {
            point_fields.push(Field {
                name: "slip_distance",
                n_components: 1,
                values: &slip_distance,
            });
        }
        if problem.pressure.is_some() {
            point_fields.push(Field {
                name: "contact_pressure",
                n_components: 1,
                values: &pressure,
            });
        }
        let cell_fields = [
            Field {
                name: "stress",
                n_components: fields::STRESS_COMPONENTS.len(),
                values: &stress,
            },
            Field {
                name: "von_mises",
                n_components: 1,
                values: &von_mises,
            },
        ];
        let compression = if plan.compress {
            Compression::Zlib
        } else {
            Compression::None
        };
        output::write_vtu(&dir.join(&file), &grid, &point_fields, &cell_fields, compression)?;
        pvd.push(PvdEntry { time: record.t, file });
    }
    Ok(())
}
