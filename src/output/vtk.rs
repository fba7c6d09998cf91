//! VTK XML unstructured grid (`.vtu`) files through `vtkio`, and ParaView collection (`.pvd`)
//! files, which `vtkio` does not write (a few lines of XML).
//!
//! Arrays are written inline in binary form, zlib-compressed (`vtkZLibDataCompressor`, VTK's
//! block header) and base64-encoded by `vtkio`, so `f64` values are exact.

use std::fmt::Write as _;
use std::path::Path;

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

use vtkio::xml::Compressor;

use super::atomic::write_atomic;
use super::OutputError;

/// How the arrays of a `.vtu` are stored.
///
/// vtkio feeds the deflate encoder one value (8 bytes) at a time, so the write costs more than
/// the compression itself and the backend's cost per call matters: flate2's `zlib-rs` backend
/// (Cargo.toml; pure Rust, like its default `miniz_oxide`) at level 2 gives the bytes of
/// `miniz_oxide` at level 1 in a third of the time. Measured on one frame (encoding into memory,
/// best of 3, 2026-11-25; the file is written in a few ms more):
///
/// | frame | none | miniz level 1 (before) | zlib-rs level 1 | **zlib-rs level 2** | zlib-rs level 6 | LZ4 (vtkio) |
/// |---|---|---|---|---|---|---|
/// | 2D reference run (nx = 256, t = 1) | 6.39 MB, 0.018 s | 2.75 MB, 0.155 s | 3.24 MB, 0.036 s | **2.75 MB, 0.048 s** | 2.77 MB, 0.077 s | 3.49 MB, 0.011 s |
/// | 3D example (40 × 10 × 10, t = 1) | 3.85 MB, 0.012 s | 2.16 MB, 0.099 s | 2.50 MB, 0.030 s | **2.15 MB, 0.037 s** | 2.16 MB, 0.050 s | 2.64 MB, 0.009 s |
///
/// A run writes its frames on a thread beside the time loop (`driver::writer`), so this time is
/// hidden where a core is free. LZ4 (`vtkLZ4DataCompressor`) would be 4× faster again
/// but 27 % larger, and readers need an LZ4 library (meshio the `lz4` package), so zlib stays
/// the only compressor. `Compression::None` (`output.compress = false`) remains for runs where
/// the write time matters more than the disk.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compression {
    /// Raw little-endian arrays, base64-encoded.
    None,
    /// `vtkZLibDataCompressor` at level `ZLIB_LEVEL`, base64-encoded.
    Zlib,
}

/// The deflate level of [`Compression::Zlib`] (the table above).
pub const ZLIB_LEVEL: u32 = 2;

/// A named array with `n_components` values per point (or per cell),
/// stored point-major: `values[i * n_components + c]`.
#[derive(Debug, Clone, Copy)]
pub struct Field<'a> {
    pub name: &'a str,
    pub n_components: usize,
    pub values: &'a [f64],
}

/// A simplicial mesh: triangles (`dim == 2`) or tetrahedra (`dim == 3`).
#[derive(Debug, Clone, Copy)]
pub struct Grid<'a> {
    /// 2 or 3.
    pub dim: usize,
    /// Coordinates; z = 0 in 2D.
    pub points: &'a [[f64; 3]],
    /// Flat connectivity, `dim + 1` point indices per cell.
    pub cells: &'a [usize],
}

/// One time step of a `.pvd` collection.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PvdEntry {
    pub time: f64,
    /// Path of the data file, relative to the `.pvd` file.
    pub file: String,
}

/// Serializes `grid` and its fields to the bytes of a `.vtu` file.
///
/// In 2D a field with exactly 2 components is a vector and is written as a 3-vector with
/// z = 0, because ParaView treats only 3-component arrays as vectors (Warp By Vector, glyphs).
/// Other component counts are written as given (a stress keeps its 6 components).
///
/// Errors: [`OutputError::Shape`] if a field does not hold `n_components` values per point
/// (cell); [`OutputError::Vtk`] for an invalid grid or a field with zero components.
pub fn vtu_bytes(
    grid: &Grid,
    point_fields: &[Field],
    cell_fields: &[Field],
    compression: Compression,
) -> Result<Vec<u8>, OutputError> {
    let n_cells = check_grid(grid)?;
    for f in point_fields {
        check_field(f, grid.points.len())?;
    }
    for f in cell_fields {
        check_field(f, n_cells)?;
    }
    let npc = grid.dim + 1;
    let cell_type = if grid.dim == 2 {
        CellType::Triangle
    } else {
        CellType::Tetra
    };
    let attributes = |fields: &[Field]| -> Vec<Attribute> { fields.iter().map(|f| attribute(grid.dim, f)).collect() };
    let vtk = Vtk {
        version: Version::new_xml(1, 0),
        title: String::from("thermocontact"),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: IOBuffer::F64(grid.points.iter().flatten().copied().collect()),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity: grid.cells.iter().map(|&i| i as u64).collect(),
                    offsets: (1..=n_cells).map(|c| (c * npc) as u64).collect(),
                },
                types: vec![cell_type; n_cells],
            },
            data: Attributes {
                point: attributes(point_fields),
                cell: attributes(cell_fields),
            },
        }),
    };
    let file = vtk
        .try_into_xml_format(
            match compression {
                Compression::None => Compressor::None,
                Compression::Zlib => Compressor::ZLib,
            },
            ZLIB_LEVEL,
        )
        .map_err(|e| OutputError::Vtk(e.to_string()))?;
    let mut bytes = Vec::new();
    file.write(&mut bytes).map_err(|e| OutputError::Vtk(e.to_string()))?;
    Ok(bytes)
}

/// The components a field is written with: those it has, but 3 for a 2D vector (padded with
/// z = 0, [`vtu_bytes`]).
pub(super) fn written_components(dim: usize, f: &Field) -> usize {
    if dim == 2 && f.n_components == 2 {
        3
    } else {
        f.n_components
    }
}

/// A field as a vtkio data array, 2D vectors padded to three components.
fn attribute(dim: usize, f: &Field) -> Attribute {
    let (elem, data) = if dim == 2 && f.n_components == 2 {
        let padded = f.values.chunks_exact(2).flat_map(|v| [v[0], v[1], 0.0]).collect();
        (ElementType::Vectors, padded)
    } else if f.n_components == 3 {
        (ElementType::Vectors, f.values.to_vec())
    } else if f.n_components == 1 {
        (
            ElementType::Scalars {
                num_comp: 1,
                lookup_table: None,
            },
            f.values.to_vec(),
        )
    } else {
        (ElementType::Generic(f.n_components as u32), f.values.to_vec())
    };
    Attribute::DataArray(DataArray {
        name: f.name.to_string(),
        elem,
        data: IOBuffer::F64(data),
    })
}

/// Writes a `.vtu` file atomically; see [`vtu_bytes`] for the rules.
pub fn write_vtu(
    path: &Path,
    grid: &Grid,
    point_fields: &[Field],
    cell_fields: &[Field],
    compression: Compression,
) -> Result<(), OutputError> {
    let bytes = vtu_bytes(grid, point_fields, cell_fields, compression)?;
    write_atomic(path, &bytes).map_err(OutputError::io(path))
}

pub fn write_pvd(path: &Path, entries: &[PvdEntry]) -> Result<(), OutputError> {
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    s.push_str("  <Collection>\n");
    for e in entries {
        if !e.time.is_finite() {
            return Err(OutputError::Vtk(format!(
                "time step of `{}` is not finite: {}",
                e.file, e.time
            )));
        }
        let _ = writeln!(
            s,
            "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
            e.time,
            xml_escape(&e.file)
        );
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    write_atomic(path, s.as_bytes()).map_err(OutputError::io(path))
}

/// Validates the grid and returns the number of cells.
fn check_grid(grid: &Grid) -> Result<usize, OutputError> {
    if grid.dim != 2 && grid.dim != 3 {
        return Err(OutputError::Vtk(format!("dimension must be 2 or 3, got {}", grid.dim)));
    }
    let npc = grid.dim + 1;
    if !grid.cells.len().is_multiple_of(npc) {
        return Err(OutputError::Vtk(format!(
            "connectivity length {} is not a multiple of {npc}",
            grid.cells.len()
        )));
    }
    if let Some(pos) = grid.cells.iter().position(|&i| i >= grid.points.len()) {
        return Err(OutputError::Vtk(format!(
            "cell {} references point {}, but there are {} points",
            pos / npc,
            grid.cells[pos],
            grid.points.len()
        )));
    }
    Ok(grid.cells.len() / npc)
}

fn check_field(f: &Field, n_entities: usize) -> Result<(), OutputError> {
    if f.n_components == 0 {
        return Err(OutputError::Vtk(format!("field `{}` has zero components", f.name)));
    }
    let expected = n_entities * f.n_components;
    if f.values.len() != expected {
        return Err(OutputError::Shape {
            field: f.name.to_string(),
            expected,
            found: f.values.len(),
        });
    }
    Ok(())
}

pub(super) fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    const SQUARE: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    const SQUARE_CELLS: [usize; 6] = [0, 1, 2, 0, 2, 3];

    fn scratch_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("thermocontact-vtk-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn attr<'a>(tag: &'a str, key: &str) -> Option<&'a str> {
        let start = tag.find(&format!("{key}=\""))? + key.len() + 2;
        let len = tag[start..].find('"')?;
        Some(&tag[start..start + len])
    }

    fn piece(path: &Path) -> UnstructuredGridPiece {
        let vtk = Vtk::import(path).unwrap();
        match vtk.data {
            DataSet::UnstructuredGrid { pieces, .. } => pieces[0].load_piece_data(None).unwrap(),
            other => panic!("not an unstructured grid: {other:?}"),
        }
    }

    fn array<'p>(attrs: &'p [Attribute], name: &str) -> &'p DataArray {
        attrs
            .iter()
            .find_map(|a| match a {
                Attribute::DataArray(d) if d.name == name => Some(d),
                _ => None,
            })
            .unwrap_or_else(|| panic!("no array {name}"))
    }

    #[test]
    fn triangle_grid_round_trips() {
        let dir = scratch_dir("tri");
        let path = dir.join("two.vtu");
        let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let grid = Grid {
            dim: 2,
            points: &points,
            cells: &[0, 1, 2, 0, 2, 3],
        };
        let temperature = [1.0, 2.0, 3.0, 4.0];
        let velocity = [0.5, -0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let stress = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        write_vtu(
            &path,
            &grid,
            &[
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
            ],
            &[Field {
                name: "stress",
                n_components: 3,
                values: &stress,
            }],
            Compression::Zlib,
        )
        .unwrap();
        let p = piece(&path);
        assert_eq!(p.num_points(), 4);
        assert_eq!(p.cells.types, vec![CellType::Triangle; 2]);
        let v = array(&p.data.point, "velocity");
        assert_eq!(
            v.data.clone().into_vec::<f64>().unwrap()[..6],
            [0.5, -0.5, 0.0, 1.0, 2.0, 0.0]
        );
        let t = array(&p.data.point, "temperature");
        assert_eq!(t.data.clone().into_vec::<f64>().unwrap(), temperature.to_vec());
        assert_eq!(array(&p.data.cell, "stress").data.len(), 6);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn tetra_grid_round_trips() {
        let dir = scratch_dir("tet");
        let path = dir.join("tet.vtu");
        let points = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let grid = Grid {
            dim: 3,
            points: &points,
            cells: &[0, 1, 2, 3],
        };
        let u = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        write_vtu(
            &path,
            &grid,
            &[Field {
                name: "displacement",
                n_components: 3,
                values: &u,
            }],
            &[],
            Compression::Zlib,
        )
        .unwrap();
        let p = piece(&path);
        assert_eq!(p.cells.types, vec![CellType::Tetra]);
        assert_eq!(
            array(&p.data.point, "displacement")
                .data
                .clone()
                .into_vec::<f64>()
                .unwrap(),
            u.to_vec()
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn wrong_field_length_is_a_shape_error() {
        let grid = Grid {
            dim: 2,
            points: &SQUARE,
            cells: &SQUARE_CELLS,
        };
        let short = [0.0; 7];
        let err = vtu_bytes(
            &grid,
            &[Field {
                name: "u",
                n_components: 2,
                values: &short,
            }],
            &[],
            Compression::Zlib,
        )
        .unwrap_err();
        assert!(
            matches!(&err, OutputError::Shape { field, expected: 8, found: 7 } if field == "u"),
            "{err:?}"
        );
        let err = vtu_bytes(
            &grid,
            &[],
            &[Field {
                name: "c",
                n_components: 1,
                values: &[1.0],
            }],
            Compression::Zlib,
        )
        .unwrap_err();
        assert!(matches!(
            err,
            OutputError::Shape {
                expected: 2,
                found: 1,
                ..
            }
        ));

        // A failed write must not create the target.
        let dir = scratch_dir("shape");
        let path = dir.join("bad.vtu");
        assert!(write_vtu(
            &path,
            &grid,
            &[Field {
                name: "u",
                n_components: 2,
                values: &short
            }],
            &[],
            Compression::Zlib
        )
        .is_err());
        assert!(!path.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn invalid_grids_are_rejected() {
        let bad_dim = Grid {
            dim: 1,
            points: &SQUARE,
            cells: &[],
        };
        let ragged = Grid {
            dim: 2,
            points: &SQUARE,
            cells: &[0, 1, 2, 3],
        };
        let out_of_range = Grid {
            dim: 2,
            points: &SQUARE,
            cells: &[0, 1, 4],
        };
        for g in [bad_dim, ragged, out_of_range] {
            assert!(matches!(
                vtu_bytes(&g, &[], &[], Compression::Zlib),
                Err(OutputError::Vtk(_))
            ));
        }
        let grid = Grid {
            dim: 2,
            points: &SQUARE,
            cells: &SQUARE_CELLS,
        };
        let zero = Field {
            name: "z",
            n_components: 0,
            values: &[],
        };
        assert!(matches!(
            vtu_bytes(&grid, &[zero], &[], Compression::Zlib),
            Err(OutputError::Vtk(_))
        ));
    }

    #[test]
    fn pvd_lists_every_step() {
        let dir = scratch_dir("pvd");
        let path = dir.join("run.pvd");
        let entries: Vec<PvdEntry> = [0.0, 0.25, 1e-3]
            .iter()
            .enumerate()
            .map(|(i, &time)| PvdEntry {
                time,
                file: format!("run/step_{i:04}.vtu"),
            })
            .collect();
        write_pvd(&path, &entries).unwrap();
        let xml = std::fs::read_to_string(&path).unwrap();
        assert!(xml.contains("<VTKFile type=\"Collection\" version=\"0.1\""));
        let sets: Vec<&str> = xml
            .lines()
            .map(str::trim)
            .filter(|l| l.starts_with("<DataSet "))
            .collect();
        assert_eq!(sets.len(), entries.len());
        for (line, e) in sets.iter().zip(&entries) {
            let t: f64 = attr(line, "timestep").unwrap().parse().unwrap();
            assert_eq!(t, e.time);
            assert_eq!(attr(line, "file"), Some(e.file.as_str()));
            assert_eq!(attr(line, "part"), Some("0"));
        }
        let nan = [PvdEntry {
            time: f64::NAN,
            file: "x.vtu".into(),
        }];
        assert!(matches!(write_pvd(&path, &nan), Err(OutputError::Vtk(_))));
        assert_eq!(std::fs::read_to_string(&path).unwrap(), xml);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
