//! Structured tetrahedral mesh of a box, the 3D counterpart of [`super::rectangle`].

use super::{Mesh, MeshError};

/// Boundary part names of [`cuboid`], in part-index order: the faces x = 0, x = L₁, y = 0,
/// y = L₂, z = 0, z = L₃.
pub fn cuboid_part_names() -> [&'static str; 6] {
    ["x-", "x+", "y-", "y+", "z-", "z+"]
}

/// The Kuhn (Freudenthal) split of a cube into 6 tetrahedra: tetrahedron σ has the vertices
/// 0, e_σ₀, e_σ₀ + e_σ₁, e₀ + e₁ + e₂ (corner offsets in cell units), one per permutation σ of
/// the axes. Odd permutations are listed with their last two vertices swapped, so that every
/// tetrahedron is positively oriented (det[x₁ − x₀, x₂ − x₀, x₃ − x₀] = sign σ · h₁h₂h₃ before
/// the swap).
const KUHN: [[[usize; 3]; 4]; 6] = [
    // even permutations (0 1 2), (1 2 0), (2 0 1)
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 1, 1]],
    [[0, 0, 0], [0, 1, 0], [0, 1, 1], [1, 1, 1]],
    [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1]],
    // odd permutations (0 2 1), (2 1 0), (1 0 2), last two vertices swapped
    [[0, 0, 0], [1, 0, 0], [1, 1, 1], [1, 0, 1]],
    [[0, 0, 0], [0, 0, 1], [1, 1, 1], [0, 1, 1]],
    [[0, 0, 0], [0, 1, 0], [1, 1, 1], [1, 1, 0]],
];

/// Uniform tetrahedral mesh of the box (0, L₁) × (0, L₂) × (0, L₃).
///
/// The box is cut into `n₁ × n₂ × n₃` equal hexahedral cells and every cell into the 6
/// tetrahedra of the Kuhn (Freudenthal) split along its main diagonal from (0, 0, 0) to
/// (1, 1, 1): the tetrahedra {x in the cell : x_σ₀ ≥ x_σ₁ ≥ x_σ₂} (local coordinates) for the
/// 6 permutations σ. All cells are cut the same way, so
///
/// * the mesh is **conforming**: the face shared by two neighbouring cells is cut along the
///   same diagonal from both sides (the diagonal through the face's corner nearest to the
///   origin), and every boundary face of the box is the "/" triangulation of the rectangle;
/// * the meshes are **nested**: the mesh of `2n₁ × 2n₂ × 2n₃` cells refines the mesh of
///   `n₁ × n₂ × n₃` (each Kuhn tetrahedron is the union of 8 Kuhn tetrahedra of the halved
///   cells), as for [`super::rectangle`];
/// * a field that does not depend on y and is P1 on the rectangle mesh of the (x, z) plane is
///   P1 on this mesh (every tetrahedron projects into one triangle of the "/" split), which is
///   what makes the 2D–3D (plane-strain) comparison meaningful.
///
/// Node (i, j, k) sits at (i L₁/n₁, j L₂/n₂, k L₃/n₃) and has index i + (n₁ + 1)(j + (n₂ + 1) k).
/// Boundary parts, named as in [`cuboid_part_names`]: `x-`, `x+`, `y-`, `y+`, `z-`, `z+`; each
/// boundary quadrilateral is two triangles, faces of the adjacent tetrahedra.
///
/// # Panics
///
/// Where [`try_cuboid`] fails: no cell in a direction, or cells so elongated that
/// [`Mesh::new`] finds them degenerate. Input from users goes through [`try_cuboid`].
pub fn cuboid(lengths: [f64; 3], cells: [usize; 3]) -> Mesh {
    try_cuboid(lengths, cells).expect("a generated mesh is valid")
}

/// [`cuboid`], with the checks of [`Mesh::new`] returned as an error: a cell count of 0, a
/// non-finite or non-positive length, or cells so elongated (a tetrahedron's volume ≤ 1e-12 ×
/// its longest edge³; for cells of sides h, h, H that is H/h beyond about 4·10⁵) that they count
/// as degenerate.
pub fn try_cuboid(lengths: [f64; 3], cells: [usize; 3]) -> Result<Mesh, MeshError> {
    let nodes = super::structured::grid_nodes("a box", &cells, 6, 24)?;
    let [n1, n2, n3] = cells;
    let node = |ijk: [usize; 3]| ijk[0] + (n1 + 1) * (ijk[1] + (n2 + 1) * ijk[2]);
    let mut coords = Vec::with_capacity(nodes);
    for k in 0..=n3 {
        for j in 0..=n2 {
            for i in 0..=n1 {
                coords.push([
                    lengths[0] * i as f64 / n1 as f64,
                    lengths[1] * j as f64 / n2 as f64,
                    lengths[2] * k as f64 / n3 as f64,
                ]);
            }
        }
    }
    let mut tets = Vec::with_capacity(24 * n1 * n2 * n3);
    for k in 0..n3 {
        for j in 0..n2 {
            for i in 0..n1 {
                for tet in &KUHN {
                    for corner in tet {
                        tets.push(node([i + corner[0], j + corner[1], k + corner[2]]));
                    }
                }
            }
        }
    }

    // Boundary triangles: on the face normal to axis a, the quadrilateral with lowest corner o
    // is cut along its diagonal o → o + e_b + e_c, as the Kuhn tetrahedra cut it.
    let mut facets = Vec::new();
    let mut facet_parts = Vec::new();
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for (side, level) in [(0, 0), (1, cells[a])] {
            for q in 0..cells[c] {
                for p in 0..cells[b] {
                    let corner = |db: usize, dc: usize| {
                        let mut ijk = [0; 3];
                        ijk[a] = level;
                        ijk[b] = p + db;
                        ijk[c] = q + dc;
                        node(ijk)
                    };
                    facets.extend_from_slice(&[corner(0, 0), corner(1, 0), corner(1, 1)]);
                    facets.extend_from_slice(&[corner(0, 0), corner(1, 1), corner(0, 1)]);
                    facet_parts.extend([2 * a + side; 2]);
                }
            }
        }
    }
    Mesh::checked(
        3,
        coords,
        tets,
        facets,
        facet_parts,
        cuboid_part_names().iter().map(|s| s.to_string()).collect(),
        super::check::Overlaps::Skip,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::simplex::{facet_measure, Simplex};
    use std::collections::HashMap;

    #[test]
    fn cuboid_counts_volume_and_orientation() {
        let mesh = cuboid([40.0, 5.0, 10.0], [4, 2, 3]);
        assert_eq!(mesh.n_nodes(), 5 * 3 * 4);
        assert_eq!(mesh.n_cells(), 6 * 4 * 2 * 3);
        assert_eq!(mesh.n_facets(), 4 * (4 * 2 + 2 * 3 + 4 * 3));
        assert!((mesh.volume() - 2000.0).abs() < 1e-9);
        // Every tetrahedron positively oriented, all of the same volume h₁h₂h₃/6.
        for e in 0..mesh.n_cells() {
            let x = mesh.cell_coords(e);
            let v = |r: usize| [x[r][0] - x[0][0], x[r][1] - x[0][1], x[r][2] - x[0][2]];
            let (a, b, c) = (v(1), v(2), v(3));
            let det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]);
            assert!(
                (det / 6.0 - 10.0 * 2.5 * (10.0 / 3.0) / 6.0).abs() < 1e-9,
                "cell {e}: det {det}"
            );
        }
        // Face areas per part.
        let areas = [50.0, 50.0, 400.0, 400.0, 200.0, 200.0];
        for (part, area) in areas.iter().enumerate() {
            let sum: f64 = mesh
                .facets_of(&[part])
                .map(|f| facet_measure(3, &mesh.facet(f).iter().map(|&i| mesh.coords[i]).collect::<Vec<_>>()))
                .sum();
            assert!((sum - area).abs() < 1e-9, "part {}: {sum}", mesh.part_names[part]);
        }
    }

    /// Conformity: every interior triangle is shared by exactly two tetrahedra, every boundary
    /// triangle belongs to one tetrahedron and is listed once as a boundary facet.
    #[test]
    fn cuboid_is_conforming_and_its_facets_are_tetrahedron_faces() {
        let mesh = cuboid([1.0, 2.0, 3.0], [3, 2, 2]);
        let mut faces: HashMap<[usize; 3], usize> = HashMap::new();
        for e in 0..mesh.n_cells() {
            let t = mesh.cell(e);
            for skip in 0..4 {
                let mut f: Vec<usize> = (0..4).filter(|&a| a != skip).map(|a| t[a]).collect();
                f.sort_unstable();
                *faces.entry([f[0], f[1], f[2]]).or_default() += 1;
            }
            assert!(Simplex::new(3, &mesh.cell_coords(e)).measure > 0.0);
        }
        let mut boundary: Vec<[usize; 3]> = (0..mesh.n_facets())
            .map(|f| {
                let mut v = mesh.facet(f).to_vec();
                v.sort_unstable();
                [v[0], v[1], v[2]]
            })
            .collect();
        for f in &boundary {
            assert_eq!(faces.get(f), Some(&1), "boundary facet {f:?} is not a tetrahedron face");
        }
        let n_boundary = boundary.len();
        boundary.sort_unstable();
        boundary.dedup();
        assert_eq!(boundary.len(), n_boundary);
        for (f, count) in &faces {
            assert!(
                *count == 2 || boundary.binary_search(f).is_ok(),
                "face {f:?} seen {count}×"
            );
        }
    }

    #[test]
    fn elongated_or_uncountable_boxes_are_errors() {
        let e = try_cuboid([1e-4, 1.0, 1e4], [4, 2, 2]).unwrap_err();
        assert!(matches!(e, MeshError::Degenerate { .. }), "{e}");
        let e = try_cuboid([1.0; 3], [usize::MAX, 1, 1]).unwrap_err();
        assert!(e.to_string().contains("too many"), "{e}");
        assert!(try_cuboid([1.0; 3], [1, 0, 1]).is_err());
        // The worst shape at an aspect ratio of 1e4 (two short sides) is still a valid mesh.
        assert!(try_cuboid([1e-3, 1e-3, 10.0], [1, 1, 1]).is_ok());
    }

    /// 10¹² nodes, countable but beyond any machine (issue 26): an error before any allocation.
    #[test]
    fn boxes_beyond_the_memory_are_errors_before_allocating() {
        let e = try_cuboid([1.0; 3], [10_000; 3]).unwrap_err();
        assert!(matches!(e, MeshError::TooLarge { .. }), "{e}");
        assert!(e.to_string().contains("10000 × 10000 × 10000 cells"), "{e}");
    }

    #[test]
    fn cuboid_facets_point_outward() {
        let mesh = cuboid([1.0, 2.0, 3.0], [2, 2, 2]);
        for f in 0..mesh.n_facets() {
            let part = mesh.facet_parts[f];
            let mut expected = [0.0; 3];
            expected[part / 2] = if part.is_multiple_of(2) { -1.0 } else { 1.0 };
            let n = mesh.facet_normal(f);
            assert!(
                (0..3).all(|c| (n[c] - expected[c]).abs() < 1e-14),
                "{n:?} vs {expected:?}"
            );
        }
    }

    /// Nestedness: every vertex of the fine mesh's tetrahedra lies in one coarse tetrahedron's
    /// closure together with the fine tetrahedron's centroid (each fine tetrahedron sits inside a
    /// coarse one).
    #[test]
    fn refined_cuboid_is_nested() {
        let coarse = cuboid([1.0, 1.0, 1.0], [1, 1, 1]);
        let fine = cuboid([1.0, 1.0, 1.0], [2, 2, 2]);
        let barycentric = |e: usize, x: [f64; 3]| {
            let t = Simplex::new(3, &coarse.cell_coords(e));
            let x0 = coarse.coords[coarse.cell(e)[0]];
            let mut l = [0.0; 4];
            for a in 1..4 {
                l[a] = (0..3).map(|r| t.grads[a][r] * (x[r] - x0[r])).sum();
            }
            l[0] = 1.0 - l[1] - l[2] - l[3];
            l
        };
        for f in 0..fine.n_cells() {
            let verts = fine.cell_coords(f);
            let centroid = [0, 1, 2].map(|r| verts.iter().map(|v| v[r]).sum::<f64>() / 4.0);
            let host = (0..coarse.n_cells())
                .find(|&e| barycentric(e, centroid).iter().all(|&l| l > 1e-12))
                .expect("the centroid lies inside a coarse tetrahedron");
            for v in &verts {
                assert!(barycentric(host, *v).iter().all(|&l| l > -1e-12));
            }
        }
    }
}
