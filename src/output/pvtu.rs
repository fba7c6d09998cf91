//! A frame in pieces: the piece of a grid that some of its cells make ([`GridPiece`], written
//! as an ordinary `.vtu`), and the `.pvtu` file (VTK's parallel unstructured grid) that lists
//! the pieces of one frame, which ParaView reads as one data set.
//!
//! A distributed run writes its frames this way (docs/distributed.md, "Output"): each rank the
//! piece of its own cells, rank 0 the `.pvtu` once every piece is on disk. A piece holds its
//! cells and every node they use, so the nodes on the boundary between two parts appear in both
//! pieces with the same values; no cell appears twice, so there are no ghost cells
//! (`GhostLevel="0"`). The `.pvtu` names the arrays and their component counts as the pieces
//! write them ([`super::vtk::written_components`]: 2D vectors padded to 3), which ParaView
//! checks against each piece.
//!
//! *Rejected*: XDMF + HDF5 (one file per frame, written in parallel through MPI-IO). It scales
//! to more ranks than a file per rank does, but it is a new system library (libhdf5 with MPI)
//! and a second writer beside vtkio's; at the sizes a run reaches today (10⁶ unknowns on a few
//! ranks) P pieces per frame are few files. docs/distributed.md gives the measurement.

use std::fmt::Write as _;
use std::path::Path;

use super::atomic::write_atomic;
use super::vtk::{written_components, xml_escape, Field, Grid};
use super::OutputError;

/// The piece of a grid made of some of its cells: the points those cells use, in ascending
/// order of the grid's numbering, and the cells' connectivity renumbered into them.
#[derive(Debug, Clone, PartialEq)]
pub struct GridPiece {
    dim: usize,
    /// The grid's index of each point of the piece, ascending.
    pub points_of_grid: Vec<usize>,
    /// The grid's index of each cell of the piece, as given.
    pub cells_of_grid: Vec<usize>,
    points: Vec<[f64; 3]>,
    connectivity: Vec<usize>,
}

impl GridPiece {
    /// The piece of `grid` made of `cells` (its indices, each once).
    pub fn new(grid: &Grid, cells: Vec<usize>) -> Self {
        let npc = grid.dim + 1;
        let mut local = vec![usize::MAX; grid.points.len()];
        for &c in &cells {
            grid.cells[c * npc..(c + 1) * npc].iter().for_each(|&p| local[p] = 0);
        }
        let mut points_of_grid = Vec::new();
        for (p, l) in local.iter_mut().enumerate().filter(|(_, l)| **l == 0) {
            *l = points_of_grid.len();
            points_of_grid.push(p);
        }
        // Sized once: collected from a flat map it grew by doubling and kept up to twice its
        // length (a rank's piece of a 10⁶-unknown mesh: 32 MiB for 22 MiB of entries).
        let mut connectivity = Vec::with_capacity(cells.len() * npc);
        for &c in &cells {
            connectivity.extend(grid.cells[c * npc..(c + 1) * npc].iter().map(|&p| local[p]));
        }
        GridPiece {
            dim: grid.dim,
            points: points_of_grid.iter().map(|&p| grid.points[p]).collect(),
            points_of_grid,
            cells_of_grid: cells,
            connectivity,
        }
    }

    /// The piece as a grid of its own.
    pub fn grid(&self) -> Grid<'_> {
        Grid {
            dim: self.dim,
            points: &self.points,
            cells: &self.connectivity,
        }
    }

    /// The values of a point field of the whole grid at the piece's points.
    pub fn point_values(&self, field: &Field) -> Vec<f64> {
        restrict(field, &self.points_of_grid)
    }

    /// The values of a cell field of the whole grid at the piece's cells.
    pub fn cell_values(&self, field: &Field) -> Vec<f64> {
        restrict(field, &self.cells_of_grid)
    }
}

/// `field`'s values at `entities` (each with its `n_components` values).
fn restrict(field: &Field, entities: &[usize]) -> Vec<f64> {
    let m = field.n_components;
    entities
        .iter()
        .flat_map(|&e| &field.values[e * m..(e + 1) * m])
        .copied()
        .collect()
}

/// The bytes of a `.pvtu` file listing the `pieces` (paths relative to it), whose point and
/// cell arrays are named and shaped as `point_fields` and `cell_fields` (their values are not
/// read), on a grid of dimension `dim`.
pub fn pvtu_bytes(dim: usize, point_fields: &[Field], cell_fields: &[Field], pieces: &[String]) -> Vec<u8> {
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str(
        "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    s.push_str("  <PUnstructuredGrid GhostLevel=\"0\">\n");
    let arrays = |s: &mut String, tag: &str, fields: &[Field]| {
        let _ = writeln!(s, "    <{tag}>");
        for f in fields {
            let _ = writeln!(
                s,
                "      <PDataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\"/>",
                xml_escape(f.name),
                written_components(dim, f)
            );
        }
        let _ = writeln!(s, "    </{tag}>");
    };
    arrays(&mut s, "PPointData", point_fields);
    arrays(&mut s, "PCellData", cell_fields);
    s.push_str("    <PPoints>\n");
    s.push_str("      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n");
    s.push_str("    </PPoints>\n");
    for piece in pieces {
        let _ = writeln!(s, "    <Piece Source=\"{}\"/>", xml_escape(piece));
    }
    s.push_str("  </PUnstructuredGrid>\n</VTKFile>\n");
    s.into_bytes()
}

/// Writes `bytes` of [`pvtu_bytes`] to `path` atomically.
pub fn write_pvtu(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomic(path, bytes).map_err(OutputError::io(path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{write_vtu, Compression};
    use vtkio::model::{Attribute, DataSet, IOBuffer, Vtk};

    /// Two triangles of a square, then each as a piece: the pieces hold their cells' points in
    /// the grid's order, and a `.pvtu` over them reads back through vtkio as two pieces with
    /// the grid's values.
    #[test]
    fn pieces_of_a_grid_and_their_pvtu_read_back() {
        let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let grid = Grid {
            dim: 2,
            points: &points,
            cells: &[0, 1, 2, 0, 2, 3],
        };
        let temperature = [1.0, 2.0, 3.0, 4.0];
        let velocity = [0.5, -0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let stress = [10.0, 20.0];
        let point_fields = [
            Field {
                name: "temperature",
                n_components: 1,
                values: &temperature,
            },
            Field {
                name: "velocity",
                n_components: 2,
                values: &velocity,
            },
        ];
        let cell_fields = [Field {
            name: "von_mises",
            n_components: 1,
            values: &stress,
        }];
        let second = GridPiece::new(&grid, vec![1]);
        assert_eq!(second.points_of_grid, vec![0, 2, 3]);
        assert_eq!(second.grid().cells, &[0, 1, 2]);
        assert_eq!(
            second.point_values(&point_fields[1]),
            vec![0.5, -0.5, 3.0, 4.0, 5.0, 6.0]
        );
        assert_eq!(second.cell_values(&cell_fields[0]), vec![20.0]);

        let dir = std::env::temp_dir().join(format!("thermocontact-pvtu-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let names: Vec<String> = (0..2).map(|r| format!("frame_p{r}.vtu")).collect();
        for (cell, name) in names.iter().enumerate() {
            let piece = GridPiece::new(&grid, vec![cell]);
            let values: Vec<Vec<f64>> = point_fields.iter().map(|f| piece.point_values(f)).collect();
            let fields: Vec<Field> = (point_fields.iter().zip(&values))
                .map(|(f, v)| Field { values: v, ..*f })
                .collect();
            let cell_values = piece.cell_values(&cell_fields[0]);
            let cells = [Field {
                values: &cell_values,
                ..cell_fields[0]
            }];
            write_vtu(&dir.join(name), &piece.grid(), &fields, &cells, Compression::Zlib).unwrap();
        }
        let path = dir.join("frame.pvtu");
        write_pvtu(&path, &pvtu_bytes(2, &point_fields, &cell_fields, &names)).unwrap();
        let xml = std::fs::read_to_string(&path).unwrap();
        assert!(xml.contains("Name=\"velocity\" NumberOfComponents=\"3\""), "{xml}");

        let mut vtk = Vtk::import(&path).unwrap();
        vtk.load_all_pieces().unwrap();
        let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
            panic!("an unstructured grid")
        };
        let mut seen = vec![None; 4];
        for piece in &pieces {
            let data = piece.load_piece_data(None).unwrap();
            let xs: Vec<f64> = data.points.cast_into().unwrap();
            let t = data.data.point.iter().find_map(|a| match a {
                Attribute::DataArray(d) if d.name == "temperature" => Some(d.data.clone()),
                _ => None,
            });
            let Some(IOBuffer::F64(t)) = t else {
                panic!("temperature")
            };
            for (x, t) in xs.chunks_exact(3).zip(t) {
                let p = points.iter().position(|q| q[..] == x[..]).unwrap();
                seen[p] = Some(t);
            }
        }
        assert_eq!(seen, temperature.map(Some).to_vec());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
