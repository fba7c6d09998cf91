//! Facet–cell incidence: which cells a facet bounds, the checks that a mesh is a conforming,
//! untangled simplicial complex, and the outward orientation of the boundary facets that every
//! normal in the code relies on.
//!
//! The incidence is one sorted list of every cell face (its sorted nodes, the cell, the vertex
//! opposite the face): O(N log N) time and a few words per face, rather than a hash map of
//! vectors, so that meshes of 10⁶ cells check in about a second.

use rayon::prelude::*;

use super::{Mesh, MeshError};

/// A cell face: its sorted nodes (unused slots of 2D edges are `usize::MAX` so that keys of one
/// mesh compare), the cell, and the cell's vertex opposite the face.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Face {
    pub key: [usize; 3],
    pub cell: usize,
    pub opposite: usize,
}

/// The sorted nodes of a facet: the key under which cells and facets meet.
pub(crate) fn facet_key(nodes: &[usize]) -> [usize; 3] {
    let mut key = [usize::MAX; 3];
    key[..nodes.len()].copy_from_slice(nodes);
    key[..nodes.len()].sort_unstable();
    key
}

/// Every face of every cell, sorted by key (faces shared by two cells are adjacent).
pub(crate) fn cell_faces(mesh: &Mesh) -> Vec<Face> {
    let npc = mesh.nodes_per_cell();
    let mut faces: Vec<Face> = (0..mesh.n_cells())
        .into_par_iter()
        .flat_map_iter(|e| {
            let cell = mesh.cell(e);
            (0..npc).map(move |skip| {
                let mut nodes = [usize::MAX; 3];
                let mut k = 0;
                for (a, &p) in cell.iter().enumerate() {
                    if a != skip {
                        nodes[k] = p;
                        k += 1;
                    }
                }
                Face {
                    key: facet_key(&nodes[..npc - 1]),
                    cell: e,
                    opposite: cell[skip],
                }
            })
        })
        .collect();
    faces.par_sort_unstable();
    faces
}

/// The faces with this key (one for a boundary facet, two for an interior one).
pub(crate) fn faces_with<'a>(faces: &'a [Face], key: &[usize; 3]) -> &'a [Face] {
    let start = faces.partition_point(|f| f.key < *key);
    let end = start + faces[start..].partition_point(|f| f.key == *key);
    &faces[start..end]
}

/// Checks that every face bounds at most two cells and that the two cells of an interior face
/// lie on opposite sides of it (a cell turned inside out, or two overlapping cells, put both
/// opposite vertices on one side).
pub(crate) fn check_cells(mesh: &Mesh, faces: &[Face]) -> Result<(), MeshError> {
    let mut i = 0;
    while i < faces.len() {
        let run = faces[i..].partition_point(|f| f.key == faces[i].key);
        let group = &faces[i..i + run];
        if group.len() > 2 {
            return Err(MeshError::NonManifold {
                facet: face_coords(mesh, &group[0].key),
                cells: group.iter().map(|f| f.cell).collect(),
            });
        }
        if let [a, b] = group {
            // Signs, not the product: two sides of 10⁻²⁰⁰ each multiply to 0 (underflow).
            let (sa, sb) = (side_of(mesh, &a.key, a.opposite), side_of(mesh, &a.key, b.opposite));
            if sa == 0.0 || sb == 0.0 || sa.is_sign_positive() == sb.is_sign_positive() || sa.is_nan() || sb.is_nan() {
                return Err(MeshError::Tangled {
                    cells: [a.cell, b.cell],
                    facet: face_coords(mesh, &a.key),
                });
            }
        }
        i += run;
    }
    Ok(())
}

/// Checks that every boundary facet is the face of exactly one cell, and orders its nodes so that
/// its right-hand normal ([`Mesh::facet_normal`]) points out of that cell.
pub(crate) fn orient_boundary(mesh: &mut Mesh, faces: &[Face]) -> Result<(), MeshError> {
    for f in 0..mesh.n_facets() {
        let key = facet_key(mesh.facet(f));
        let part = || mesh.part_names[mesh.facet_parts[f]].clone();
        let opposite = match faces_with(faces, &key) {
            [face] => face.opposite,
            [] => {
                return Err(MeshError::FacetOnNoCell {
                    part: part(),
                    facet: face_coords(mesh, &key),
                })
            }
            _ => {
                return Err(MeshError::FacetInside {
                    part: part(),
                    facet: face_coords(mesh, &key),
                })
            }
        };
        let normal = mesh.facet_area_vector(f);
        let x0 = mesh.coords[mesh.facet(f)[0]];
        let xo = mesh.coords[opposite];
        let inward: f64 = (0..3).map(|c| normal[c] * (xo[c] - x0[c])).sum();
        if inward > 0.0 {
            let d = mesh.dim;
            mesh.facets.swap(f * d, f * d + 1);
        }
    }
    Ok(())
}

/// Which side of the face `key` the point `p` lies on (the sign of its distance, for a fixed
/// orientation of the face).
fn side_of(mesh: &Mesh, key: &[usize; 3], p: usize) -> f64 {
    let x = |i: usize| mesh.coords[i];
    let (a, b, q) = (x(key[0]), x(key[1]), x(p));
    let e = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let r = [q[0] - a[0], q[1] - a[1], q[2] - a[2]];
    if mesh.dim == 2 {
        e[0] * r[1] - e[1] * r[0]
    } else {
        let c = x(key[2]);
        let g = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            e[1] * g[2] - e[2] * g[1],
            e[2] * g[0] - e[0] * g[2],
            e[0] * g[1] - e[1] * g[0],
        ];
        n[0] * r[0] + n[1] * r[1] + n[2] * r[2]
    }
}

fn face_coords(mesh: &Mesh, key: &[usize; 3]) -> Vec<[f64; 3]> {
    key.iter()
        .filter(|&&p| p != usize::MAX)
        .map(|&p| mesh.coords[p])
        .collect()
}
