//! The files of one frame: the figures of an output time ([`record`]), the contact CSV and the
//! `.vtu` of a state, named by its time level: whole, or (a distributed run) this rank's piece,
//! which a `.pvtu` lists once every rank has written its own ([`Layout`]).

use std::path::Path;

use super::summary::OutputRecord;
use super::OutputPlan;
use crate::error::Error;
use crate::model::Problem;
use crate::model::State;
use crate::model::{contact_rows, ContactRow};
use crate::output::{self, fields, Compression, Field, Grid, GridPiece, PvdEntry};

/// `_0042.` in the file names of time level 42's frame ([`crate::output::folder::frame_step`]
/// reads it back).
fn frame_tag(n: usize) -> String {
    format!("_{n:04}.")
}

/// The name of rank `rank`'s piece of time level `n`'s frame: `solution_0042_p1.vtu`.
fn piece_name(n: usize, rank: usize) -> String {
    format!("solution_{n:04}_p{rank}.vtu")
}

/// How this process writes the `.vtu` of a frame.
///
/// **Pieces, in the folder beside the frames.** A distributed run's frame at time level 42 is
/// `solution_0042.pvtu` and its pieces `solution_0042_p0.vtu` … `solution_0042_p{P−1}.vtu`,
/// one per rank, in the run's folder: the folder's rules (the frames after a checkpoint removed
/// by `--restart`, another run's by `--overwrite`) find them by name as they find whole frames
/// ([`crate::output::folder::frame_step`]), and a subfolder per frame would be a directory to
/// remove. A `.pvd` of a run continued on another number of ranks lists whole `.vtu` frames and
/// `.pvtu` frames of any piece count: ParaView reads it as one series.
#[derive(Debug)]
pub(super) enum Layout {
    /// One `solution_NNNN.vtu` of the whole mesh: one process.
    Whole,
    /// Rank `rank`'s piece of `n_ranks`: the cells of its part of the run's partition and the
    /// nodes they use, with the arrays of a whole frame there; rank 0 also writes the contact
    /// CSV, and the `.pvtu` once every piece is on disk (`frames`).
    Piece {
        rank: usize,
        n_ranks: usize,
        piece: GridPiece,
    },
}

/// A frame's `.vtu` as written.
#[derive(Debug, Clone)]
pub(super) enum Written {
    /// The whole frame, for the collection at once.
    Whole(PvdEntry),
    /// This rank's piece: the collection lists `entry` (the `.pvtu`) once every rank has
    /// written its piece; rank 0 then writes the `.pvtu`'s bytes `pvtu`.
    Piece { entry: PvdEntry, pvtu: Option<Vec<u8>> },
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
        energy_norm_u: crate::model::norms::energy(&problem.mesh, &state.u),
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

/// Writes the frame of `state` into `dir` in `layout`: the contact CSV (one process, or rank 0)
/// and the `.vtu` (whole, or this rank's piece), which comes back (none without `.vtu` files).
pub(super) fn write_snapshot(
    problem: &Problem,
    plan: &OutputPlan,
    state: &State,
    record: &OutputRecord,
    dir: &Path,
    layout: &Layout,
) -> Result<Option<Written>, Error> {
    let d = problem.dim();
    let writes_csv = match layout {
        Layout::Whole => true,
        Layout::Piece { rank, .. } => *rank == 0,
    };
    if plan.csv && writes_csv {
        let path = dir.join(format!("contact{}csv", frame_tag(state.n)));
        let header = contact_csv_header(d, problem.uses_slip_distance(), problem.pressure.is_some());
        output::write_csv(&path, &header, &contact_csv_rows(d, &record.contact))?;
    }
    if !plan.vtk {
        return Ok(None);
    }
    frame_vtu(problem, plan, state, record, dir, layout).map(Some)
}

/// The `.vtu` of a frame: the state's point fields (u, w, θ, the contact status and the
/// friction stress; the slip distance and the pressure where a law uses them) and σ with its
/// von Mises norm per cell, whole or as this rank's piece.
fn frame_vtu(
    problem: &Problem,
    plan: &OutputPlan,
    state: &State,
    record: &OutputRecord,
    dir: &Path,
    layout: &Layout,
) -> Result<Written, Error> {
    let d = problem.dim();
    let stress = match layout {
        Layout::Whole => fields::cell_stress(problem, state),
        Layout::Piece { piece, .. } => fields::cell_stress_of(problem, state, piece.cells_of_grid.iter().copied()),
    };
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
    match layout {
        Layout::Whole => {
            let file = format!("solution{}vtu", frame_tag(state.n));
            output::write_vtu(&dir.join(&file), &grid, &point_fields, &cell_fields, compression)?;
            Ok(Written::Whole(PvdEntry { time: record.t, file }))
        }
        &Layout::Piece {
            rank,
            n_ranks,
            ref piece,
        } => {
            let fields = (&point_fields[..], &cell_fields[..]);
            write_piece(dir, (state.n, record.t), (rank, n_ranks, piece), fields, compression)
        }
    }
}

/// Writes rank `rank`'s `piece` (of `n_ranks`) of the frame of time level `n` at time `t`: the
/// whole mesh's point fields at the piece's nodes, the cell fields (the piece's cells' already);
/// rank 0 also makes the frame's `.pvtu`.
fn write_piece(
    dir: &Path,
    (n, t): (usize, f64),
    (rank, n_ranks, piece): (usize, usize, &GridPiece),
    (point_fields, cell_fields): (&[Field], &[Field]),
    compression: Compression,
) -> Result<Written, Error> {
    let values: Vec<Vec<f64>> = point_fields.iter().map(|f| piece.point_values(f)).collect();
    let point_fields: Vec<Field> = (point_fields.iter().zip(&values))
        .map(|(f, values)| Field { values, ..*f })
        .collect();
    let path = dir.join(piece_name(n, rank));
    output::write_vtu(&path, &piece.grid(), &point_fields, cell_fields, compression)?;
    let pieces: Vec<String> = (0..n_ranks).map(|r| piece_name(n, r)).collect();
    let dim = piece.grid().dim;
    Ok(Written::Piece {
        entry: PvdEntry {
            time: t,
            file: format!("solution{}pvtu", frame_tag(n)),
        },
        pvtu: (rank == 0).then(|| output::pvtu_bytes(dim, &point_fields, cell_fields, &pieces)),
    })
}
