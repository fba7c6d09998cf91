//! Cells that overlap without sharing a face: one triangle laid across others, or a mesh given
//! twice on separate nodes. The face check of [`super::topology`] sees a fold between two
//! neighbours only; these cells have no common face, so each face looks valid.
//!
//! **The test.** A cell's centre lies inside that cell and in no other cell of a valid mesh
//! (the cells' interiors are disjoint). So every centre is located among the cells near it: a
//! uniform grid of about one bin per cell over the mesh's bounding box lists each cell in the
//! bins its bounding box meets, and the centre of cell e is tested against the cells of its bin
//! (barycentric coordinates all above 10⁻⁹: strictly inside; a neighbour's centre is outside by
//! a fraction of the cell). Building the grid is O(N) for meshes whose cells are not much
//! larger than their share of the box, the test O(N · cells per bin); the tests run in
//! parallel. A box of 1.06·10⁶ tetrahedra takes 1.1 s on the 2-core machine (release; about
//! 22 grid entries per cell; `cargo test --release --lib mesh::overlap -- --ignored`), so the
//! generators, whose cells tile their box or ring by construction, skip it
//! ([`Mesh::checked`]); read and user-built meshes pass through it.
//!
//! **What it does not see.** Two cells whose overlap contains neither centre (a sliver grazing
//! a neighbour it shares no face with). The cases users produce (a stray cell across a part, a
//! duplicated volume, two copies of a mesh) put centres inside other cells.
//!
//! **Rejected: the global measure identity** Σ|cells| = (1/d) Σ_boundary faces (x_f · ν_f)|f|.
//! With each boundary face oriented out of its own cell, the identity holds for *any* set of
//! cells (it is the divergence theorem cell by cell, the shared faces cancelling), overlapping
//! or not: it cannot see an overlap.

use rayon::prelude::*;

use super::{Mesh, MeshError};

/// Barycentric coordinates above this (relative) margin put a point strictly inside a cell.
const INSIDE: f64 = 1e-9;

/// The uniform grid: bins per axis, its origin and bin sizes, and the cells of every bin (CSR).
struct Grid {
    bins: [usize; 3],
    origin: [f64; 3],
    size: [f64; 3],
    start: Vec<usize>,
    cells: Vec<usize>,
}

impl Grid {
    /// The bin range [lo, hi] along each axis of the box [a, b].
    fn range(&self, a: [f64; 3], b: [f64; 3], dim: usize) -> [[usize; 2]; 3] {
        let mut r = [[0, 0]; 3];
        for c in 0..dim {
            let at = |x: f64| (((x - self.origin[c]) / self.size[c]).floor().max(0.0) as usize).min(self.bins[c] - 1);
            r[c] = [at(a[c]), at(b[c])];
        }
        r
    }

    fn index(&self, i: [usize; 3]) -> usize {
        (i[2] * self.bins[1] + i[1]) * self.bins[0] + i[0]
    }
}

/// The cells' bounding boxes.
fn bounding_box(mesh: &Mesh, e: usize) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &p in mesh.cell(e) {
        for c in 0..3 {
            lo[c] = lo[c].min(mesh.coords[p][c]);
            hi[c] = hi[c].max(mesh.coords[p][c]);
        }
    }
    (lo, hi)
}

/// Bins per axis: about one bin per cell, none finer than the box along a thin axis.
fn bins_for(extent: [f64; 3], dim: usize, n_cells: usize) -> [usize; 3] {
    let count = |h: f64| -> f64 { (0..dim).map(|c| (extent[c] / h).ceil().max(1.0)).product() };
    // Bisection on the bin size h (log scale): the largest count not above n_cells.
    let longest = extent[..dim].iter().cloned().fold(0.0, f64::max);
    let (mut small, mut large) = (longest * 1e-12, longest);
    for _ in 0..100 {
        let h = (small * large).sqrt();
        if count(h) > n_cells as f64 {
            small = h;
        } else {
            large = h;
        }
    }
    let mut bins = [1; 3];
    for c in 0..dim {
        bins[c] = (extent[c] / large).ceil().max(1.0) as usize;
    }
    bins
}

fn build(mesh: &Mesh) -> Grid {
    let dim = mesh.dim;
    let mut origin = [f64::INFINITY; 3];
    let mut top = [f64::NEG_INFINITY; 3];
    for x in &mesh.coords {
        for c in 0..3 {
            origin[c] = origin[c].min(x[c]);
            top[c] = top[c].max(x[c]);
        }
    }
    let extent = [0, 1, 2].map(|c| top[c] - origin[c]);
    let bins = bins_for(extent, dim, mesh.n_cells());
    let size = [0, 1, 2].map(|c| if c < dim { extent[c] / bins[c] as f64 } else { 1.0 });
    let mut grid = Grid {
        bins,
        origin,
        size,
        start: vec![0; bins.iter().product::<usize>() + 1],
        cells: Vec::new(),
    };
    let ranges: Vec<[[usize; 2]; 3]> = (0..mesh.n_cells())
        .into_par_iter()
        .map(|e| {
            let (a, b) = bounding_box(mesh, e);
            grid.range(a, b, dim)
        })
        .collect();
    let each = |r: &[[usize; 2]; 3], f: &mut dyn FnMut(usize)| {
        for k in r[2][0]..=r[2][1] {
            for j in r[1][0]..=r[1][1] {
                for i in r[0][0]..=r[0][1] {
                    f((k * bins[1] + j) * bins[0] + i);
                }
            }
        }
    };
    let mut start = std::mem::take(&mut grid.start);
    for r in &ranges {
        each(r, &mut |b| start[b + 1] += 1);
    }
    for b in 1..start.len() {
        start[b] += start[b - 1];
    }
    let mut next = start.clone();
    let mut cells = vec![0; start[start.len() - 1]];
    for (e, r) in ranges.iter().enumerate() {
        each(r, &mut |b| {
            cells[next[b]] = e;
            next[b] += 1;
        });
    }
    grid.start = start;
    grid.cells = cells;
    grid
}

/// The vertices of cell e (the last unused in 2D), without allocating.
fn vertices(mesh: &Mesh, e: usize) -> [[f64; 3]; 4] {
    let mut v = [[0.0; 3]; 4];
    for (a, &p) in mesh.cell(e).iter().enumerate() {
        v[a] = mesh.coords[p];
    }
    v
}

/// Whether `p` lies strictly inside the simplex `v` (barycentric coordinates all > INSIDE). Most
/// candidates are rejected by their bounding box, the rest at the first coordinate out.
fn strictly_inside(dim: usize, v: &[[f64; 3]; 4], p: [f64; 3]) -> bool {
    for c in 0..dim {
        let (lo, hi) = v[..=dim]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(x[c]), hi.max(x[c]))
            });
        if p[c] <= lo || p[c] >= hi {
            return false;
        }
    }
    let d = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let r = d(p, v[0]);
    // λ_k = numerator_k / det, the last one 1 − Σ λ_k.
    let mut sum = 0.0;
    let mut inside = |numerator: f64, det: f64| {
        let l = numerator / det;
        sum += l;
        l > INSIDE
    };
    if dim == 2 {
        let (e1, e2) = (d(v[1], v[0]), d(v[2], v[0]));
        let det = e1[0] * e2[1] - e1[1] * e2[0];
        inside(r[0] * e2[1] - r[1] * e2[0], det) && inside(e1[0] * r[1] - e1[1] * r[0], det) && 1.0 - sum > INSIDE
    } else {
        let (e1, e2, e3) = (d(v[1], v[0]), d(v[2], v[0]), d(v[3], v[0]));
        let n23 = cross(e2, e3);
        let det = dot(e1, n23);
        inside(dot(r, n23), det)
            && inside(dot(e1, cross(r, e3)), det)
            && inside(dot(e1, cross(e2, r)), det)
            && 1.0 - sum > INSIDE
    }
}

/// Checks that no cell's centre lies inside another cell.
pub(crate) fn check_overlap(mesh: &Mesh) -> Result<(), MeshError> {
    let grid = build(mesh);
    let dim = mesh.dim;
    let hit = (0..mesh.n_cells())
        .into_par_iter()
        .filter_map(|e| {
            let v = vertices(mesh, e);
            let n = (dim + 1) as f64;
            let centre = [0, 1, 2].map(|c| v[..=dim].iter().map(|x| x[c]).sum::<f64>() / n);
            let [i, j, k] = grid.range(centre, centre, dim).map(|r| r[0]);
            let b = grid.index([i, j, k]);
            grid.cells[grid.start[b]..grid.start[b + 1]]
                .iter()
                .find(|&&f| f != e && strictly_inside(dim, &vertices(mesh, f), centre))
                .map(|&f| (e, f, centre))
        })
        .min_by_key(|&(e, f, _)| (e, f));
    match hit {
        Some((e, f, at)) => Err(MeshError::Overlapping { cells: [e, f], at }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh;

    fn with_cells(mesh: &Mesh, coords: Vec<[f64; 3]>, cells: Vec<usize>) -> Result<Mesh, MeshError> {
        Mesh::new(
            mesh.dim,
            coords,
            cells,
            mesh.facets.clone(),
            mesh.facet_parts.clone(),
            mesh.part_names.clone(),
        )
    }

    #[test]
    fn a_cell_laid_across_others_is_found() {
        let m = mesh::rectangle(4.0, 1.0, 8, 2);
        let mut coords = m.coords.clone();
        let mut cells = m.cells.clone();
        // A triangle on three new nodes across the middle of the strip, sharing no face.
        let n = coords.len();
        coords.extend([[1.1, 0.2, 0.0], [2.9, 0.3, 0.0], [2.0, 0.8, 0.0]]);
        cells.extend([n, n + 1, n + 2]);
        let e = with_cells(&m, coords, cells).unwrap_err();
        assert!(matches!(e, MeshError::Overlapping { .. }), "{e}");
        assert!(e.to_string().contains("overlap"), "{e}");
    }

    #[test]
    fn a_mesh_given_twice_is_found_in_2d_and_3d() {
        for m in [
            mesh::rectangle(2.0, 1.0, 4, 2),
            mesh::cuboid([1.0, 1.0, 1.0], [2, 2, 2]),
        ] {
            let n = m.n_nodes();
            let mut coords = m.coords.clone();
            coords.extend(m.coords.clone());
            let mut cells = m.cells.clone();
            cells.extend(m.cells.iter().map(|p| p + n));
            let e = with_cells(&m, coords, cells).unwrap_err();
            assert!(matches!(e, MeshError::Overlapping { .. }), "{e}");
        }
    }

    #[test]
    fn valid_meshes_pass_including_thin_and_graded_ones() {
        for m in [
            mesh::rectangle(1000.0, 0.001, 200, 1),
            mesh::annulus(1.0, 2.0, 64, 4),
            mesh::cuboid([4.0, 1.0, 0.25], [16, 4, 2]),
        ] {
            check_overlap(&m).unwrap_or_else(|e| panic!("{e}"));
        }
    }

    /// The cost at 10⁶ cells (`cargo test --release --lib mesh::overlap -- --ignored --nocapture`).
    #[test]
    #[ignore]
    fn cost_at_a_million_tetrahedra() {
        let m = mesh::cuboid([4.0, 1.0, 1.0], [110, 40, 40]);
        let start = std::time::Instant::now();
        check_overlap(&m).unwrap();
        println!("{} cells: {:.3} s", m.n_cells(), start.elapsed().as_secs_f64());
    }
}
