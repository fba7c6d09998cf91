//! A structured annulus: the ring a ≤ r ≤ b in 2D, for curved contact boundaries with known
//! answers (a ring on a shaft: `tests/curved.rs`).

use super::{Mesh, MeshError};

/// Boundary part names of [`annulus`], in part-index order.
pub fn annulus_part_names() -> [&'static str; 2] {
    ["inner", "outer"]
}

/// Triangulation of the annulus a ≤ r ≤ b with `n_radial` cells across and `n_around` cells
/// around: node (i, j) sits at radius a + i (b − a)/n_radial and angle 2π j/n_around, and every
/// polar cell is cut along the same diagonal, so the mesh is invariant under the rotation by
/// 2π/n_around (every node of a circle sees the same mesh around it).
///
/// Boundary parts: `inner` (r = a) and `outer` (r = b). The circles are approximated by regular
/// polygons through the nodes.
///
/// # Panics
///
/// Where [`try_annulus`] fails. Input from users goes through [`try_annulus`].
pub fn annulus(inner_radius: f64, outer_radius: f64, n_radial: usize, n_around: usize) -> Mesh {
    try_annulus(inner_radius, outer_radius, n_radial, n_around).expect("a generated mesh is valid")
}

/// [`annulus`], with its conditions (0 < a < b, a cell across, three around), the size checks
/// of every generator (countable, within the machine's memory) and the checks of [`Mesh::new`] (cells so thin that they count as degenerate, as a ring of b/a ≈ 10¹² makes
/// them) returned as an error.
pub fn try_annulus(inner_radius: f64, outer_radius: f64, n_radial: usize, n_around: usize) -> Result<Mesh, MeshError> {
    if !(n_radial > 0 && n_around >= 3 && 0.0 < inner_radius && inner_radius < outer_radius) {
        return Err(MeshError::Invalid(format!(
            "an annulus of radii {inner_radius}, {outer_radius} in {n_radial} × {n_around} cells: it needs \
             0 < a < b, a cell across and three around"
        )));
    }
    // The checks of the rectangle of n_radial × n_around cells, whose nodes are a few more.
    super::structured::grid_nodes("an annulus", &[n_radial, n_around], 2, 6)?;
    let node = |i: usize, j: usize| i + (j % n_around) * (n_radial + 1);
    let mut coords = Vec::with_capacity((n_radial + 1) * n_around);
    for j in 0..n_around {
        let angle = std::f64::consts::TAU * j as f64 / n_around as f64;
        for i in 0..=n_radial {
            let r = inner_radius + (outer_radius - inner_radius) * i as f64 / n_radial as f64;
            coords.push([r * angle.cos(), r * angle.sin(), 0.0]);
        }
    }
    let mut cells = Vec::with_capacity(6 * n_radial * n_around);
    for j in 0..n_around {
        for i in 0..n_radial {
            let (a, b, c, d) = (node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1));
            cells.extend_from_slice(&[a, b, c]);
            cells.extend_from_slice(&[a, c, d]);
        }
    }
    let mut facets = Vec::with_capacity(4 * n_around);
    let mut facet_parts = Vec::with_capacity(2 * n_around);
    for j in 0..n_around {
        facets.extend_from_slice(&[node(0, j), node(0, j + 1)]);
        facet_parts.push(0);
        facets.extend_from_slice(&[node(n_radial, j), node(n_radial, j + 1)]);
        facet_parts.push(1);
    }
    Mesh::checked(
        2,
        coords,
        cells,
        facets,
        facet_parts,
        annulus_part_names().iter().map(|s| s.to_string()).collect(),
        super::check::Overlaps::Skip,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_or_impossible_rings_are_errors() {
        let e = try_annulus(1e-6, 1e6, 1, 64).unwrap_err();
        assert!(matches!(e, MeshError::Degenerate { .. }), "{e}");
        assert!(try_annulus(2.0, 1.0, 1, 64).is_err());
        assert!(try_annulus(1.0, 2.0, 1, 2).is_err());
        // Uncountable (the node count overflowed) or beyond the memory (issue 26): errors
        // before any allocation.
        let e = try_annulus(1.0, 2.0, usize::MAX, 64).unwrap_err();
        assert!(e.to_string().contains("too many"), "{e}");
        let e = try_annulus(1.0, 2.0, 1 << 20, 1 << 20).unwrap_err();
        assert!(matches!(e, MeshError::TooLarge { .. }), "{e}");
    }

    #[test]
    fn annulus_area_and_outward_normals() {
        let (a, b, n) = (1.0, 2.0, 64);
        let mesh = annulus(a, b, 4, n);
        assert_eq!(mesh.n_nodes(), 5 * n);
        // The polygons' area: ½ n sin(2π/n) (b² − a²).
        let exact = 0.5 * n as f64 * (std::f64::consts::TAU / n as f64).sin() * (b * b - a * a);
        assert!((mesh.volume() - exact).abs() < 1e-12 * exact);
        for f in 0..mesh.n_facets() {
            let x = mesh.coords[mesh.facet(f)[0]];
            let n = mesh.facet_normal(f);
            let radial = n[0] * x[0] + n[1] * x[1];
            // Outward: away from the axis on the outer circle, towards it on the inner one.
            assert_eq!(radial > 0.0, mesh.facet_parts[f] == 1, "facet {f}");
        }
    }
}
