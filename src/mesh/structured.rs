//! Structured generators.

use super::{Mesh, MeshError};

/// The nodes of a structured grid of `cells` cells per direction, each cut into
/// `simplices_per_cell` triangles or tetrahedra, checked before anything is allocated: at least
/// one cell per direction; the nodes times `per_node` (a bound on the entries the generator
/// stores per node) countable in a `usize`; and the mesh within the machine's memory
/// ([`super::check::fits_in_memory`], the check every constructor shares). `what` names the grid
/// in the error, with its article ("a rectangle").
pub(super) fn grid_nodes(
    what: &str,
    cells: &[usize],
    simplices_per_cell: usize,
    per_node: usize,
) -> Result<usize, MeshError> {
    let shape = cells.iter().map(usize::to_string).collect::<Vec<_>>().join(" × ");
    let what = format!("{what} of {shape} cells");
    if cells.contains(&0) {
        return Err(MeshError::Invalid(format!(
            "{what}: it needs at least one cell per direction"
        )));
    }
    let counted = cells
        .iter()
        .try_fold(1usize, |nodes, &n| nodes.checked_mul(n.checked_add(1)?));
    let nodes = counted
        .filter(|n| n.checked_mul(per_node).is_some())
        .ok_or_else(|| MeshError::Invalid(format!("{what}: too many to count")))?;
    // Fewer than the nodes times `per_node`, which is countable.
    let simplices = cells.iter().product::<usize>().saturating_mul(simplices_per_cell);
    super::check::fits_in_memory(&what, cells.len(), nodes, simplices)?;
    Ok(nodes)
}

/// Boundary part names of [`rectangle`], in part-index order.
pub fn rectangle_part_names() -> [&'static str; 4] {
    ["left", "right", "bottom", "top"]
}

/// Uniform triangulation of the rectangle (0, lx) × (0, ly).
///
/// The rectangle is cut into `nx × ny` equal cells; each cell is split into two triangles along
/// its diagonal from the lower-left to the upper-right corner ("/" pattern). Node (i, j) sits at
/// (i·lx/nx, j·ly/ny) and has index `i + j (nx + 1)`. Because every cell is cut the same way,
/// the mesh of `2nx × 2ny` refines the mesh of `nx × ny` exactly (nested meshes), which the
/// convergence study relies on for exact P1 prolongation.
///
/// Boundary parts: `left` (x = 0), `right` (x = lx), `bottom` (y = 0), `top` (y = ly).
///
/// # Panics
///
/// Where [`try_rectangle`] fails: no cell in a direction, or cells so elongated that
/// [`Mesh::new`] finds them degenerate. Input from users goes through [`try_rectangle`].
pub fn rectangle(lx: f64, ly: f64, nx: usize, ny: usize) -> Mesh {
    try_rectangle(lx, ly, nx, ny).expect("a generated mesh is valid")
}

/// [`rectangle`], with the checks of [`Mesh::new`] returned as an error: a cell count of 0, a
/// non-finite or non-positive length, or cells so elongated (a cell's area ≤ 1e-12 × its
/// longest edge², an aspect ratio beyond about 5·10¹¹) that they count as degenerate.
pub fn try_rectangle(lx: f64, ly: f64, nx: usize, ny: usize) -> Result<Mesh, MeshError> {
    let nodes = grid_nodes("a rectangle", &[nx, ny], 2, 6)?;
    let node = |i: usize, j: usize| i + j * (nx + 1);
    let mut coords = Vec::with_capacity(nodes);
    for j in 0..=ny {
        for i in 0..=nx {
            coords.push([lx * i as f64 / nx as f64, ly * j as f64 / ny as f64, 0.0]);
        }
    }
    let mut cells = Vec::with_capacity(6 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1));
            // Both triangles counter-clockwise.
            cells.extend_from_slice(&[a, b, c]);
            cells.extend_from_slice(&[a, c, d]);
        }
    }
    let mut facets = Vec::new();
    let mut facet_parts = Vec::new();
    let mut push = |p: usize, q: usize, part: usize| {
        facets.extend_from_slice(&[p, q]);
        facet_parts.push(part);
    };
    for j in 0..ny {
        push(node(0, j), node(0, j + 1), 0);
        push(node(nx, j), node(nx, j + 1), 1);
    }
    for i in 0..nx {
        push(node(i, 0), node(i + 1, 0), 2);
        push(node(i, ny), node(i + 1, ny), 3);
    }
    Mesh::checked(
        2,
        coords,
        cells,
        facets,
        facet_parts,
        rectangle_part_names().iter().map(|s| s.to_string()).collect(),
        super::check::Overlaps::Skip,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangle_counts_and_area() {
        let mesh = rectangle(40.0, 10.0, 8, 2);
        assert_eq!(mesh.n_nodes(), 27);
        assert_eq!(mesh.n_cells(), 32);
        assert_eq!(mesh.n_facets(), 2 * 8 + 2 * 2);
        assert!((mesh.volume() - 400.0).abs() < 1e-10);
        let bottom = mesh.part_index("bottom").unwrap();
        assert_eq!(mesh.nodes_on(&[bottom]).iter().filter(|&&b| b).count(), 9);
    }

    #[test]
    fn elongated_or_uncountable_rectangles_are_errors() {
        let e = try_rectangle(1e-6, 1e6, 128, 32).unwrap_err();
        assert!(matches!(e, MeshError::Degenerate { .. }), "{e}");
        let e = try_rectangle(1.0, 1.0, usize::MAX, 2).unwrap_err();
        assert!(e.to_string().contains("too many"), "{e}");
        assert!(try_rectangle(1.0, 1.0, 0, 2).is_err());
        assert!(try_rectangle(1e-3, 10.0, 1, 1).is_ok(), "an aspect ratio of 1e4");
    }

    /// 10¹⁰ nodes (issue 26): refused before the 240 GB of coordinates are asked for, which
    /// aborted the process (and a Python interpreter with it).
    #[test]
    fn rectangles_beyond_the_memory_are_errors_before_allocating() {
        let e = try_rectangle(1.0, 1.0, 100_000, 100_000).unwrap_err();
        assert!(matches!(e, MeshError::TooLarge { .. }), "{e}");
        let message = e.to_string();
        assert!(
            message.contains("100000 × 100000 cells") && message.contains("memory"),
            "{message}"
        );
        // 2 × 10¹¹ cells: countable, but far beyond any machine (every size of the message is
        // a count, not an allocation).
        let e = try_rectangle(1.0, 1.0, 1 << 20, 1 << 20).unwrap_err();
        assert!(matches!(e, MeshError::TooLarge { .. }), "{e}");
    }

    #[test]
    fn rectangle_facets_point_outward() {
        let mesh = rectangle(4.0, 2.0, 4, 2);
        let expected = [[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0]];
        for f in 0..mesh.n_facets() {
            let n = mesh.facet_normal(f);
            let e = expected[mesh.facet_parts[f]];
            assert!(
                (n[0] - e[0]).abs() < 1e-14 && (n[1] - e[1]).abs() < 1e-14,
                "{n:?} vs {e:?}"
            );
        }
        assert!((mesh.facet_measure(0) - 1.0).abs() < 1e-14);
    }
}
