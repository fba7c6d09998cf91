//! Output layer: VTK XML unstructured grids (`.vtu`), in pieces listed by a `.pvtu` where
//! several processes write a frame ([`GridPiece`]), plus PVD collections for ParaView time
//! series, CSV tables, and raw bytes (e.g. serialized JSON); the run folder and
//! its lock ([`folder`]), checkpoints ([`checkpoint`]), the fields of a state ([`fields`]) and
//! the figures ([`figures`]).
//!
//! Every file goes through [`write_atomic`], so a crash or an error
//! mid-write never leaves a truncated result behind: each output file is
//! either the previous version or the complete new one.
//!
//! Depends on: [`crate::model`] (the state, the contact rows), [`crate::mesh`], [`crate::la`].
//! It knows no time loop, step solver or driver: files only.

use std::path::{Path, PathBuf};

mod atomic;
pub mod checkpoint;
pub(crate) mod convergence_plot;
mod csv;
pub mod fields;
pub mod figures;
pub mod folder;
mod plot;
mod pvtu;
mod vtk;

pub use atomic::{write_atomic, write_atomic_with};
pub use csv::{csv_bytes, write_csv};
pub use pvtu::{pvtu_bytes, write_pvtu, GridPiece};
pub use vtk::{vtu_bytes, write_pvd, write_vtu, Compression, Field, Grid, PvdEntry};

/// Errors of the output layer.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("invalid VTK data: {0}")]
    Vtk(String),
    #[error("`{field}` has {found} values, expected {expected}")]
    Shape {
        field: String,
        expected: usize,
        found: usize,
    },
    /// An output error of another rank of a distributed run, as that rank reported it: every
    /// rank ends with it (`driver`'s agreement over the ranks).
    #[error("rank {rank}: {message}")]
    OnRank { rank: usize, message: String },
}

impl OutputError {
    /// Adapter for `map_err` that attaches the path being written.
    pub(crate) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Self + '_ {
        move |source| OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
