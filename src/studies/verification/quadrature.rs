//! Quadrature for data and errors given as functions (2D): a degree-5 rule on triangles and
//! 3-point Gauss–Legendre (degree 5) on edges.
//!
//! The scheme's own matrices integrate polynomials exactly and need no rule; these rules serve
//! the verification family, whose loads f₀, g, f₂ and errors ‖u − u^{hk}‖ are smooth functions
//! (up to the C² stick–slip front). Degree 5 makes the quadrature error O(h⁶) per cell on smooth
//! integrands: far below the O(h) errors measured.

use crate::mesh::simplex::{facet_measure, Simplex};
use crate::mesh::Mesh;

/// The 7-point degree-5 rule on a triangle (Strang–Fix / Dunavant): barycentric coordinates
/// and weights relative to the area (they sum to 1).
pub fn triangle_rule() -> [([f64; 3], f64); 7] {
    let r = 15f64.sqrt();
    let (b1, b2) = ((6.0 + r) / 21.0, (6.0 - r) / 21.0);
    let (a1, a2) = (1.0 - 2.0 * b1, 1.0 - 2.0 * b2);
    let (w1, w2) = ((155.0 + r) / 1200.0, (155.0 - r) / 1200.0);
    [
        ([1.0 / 3.0; 3], 9.0 / 40.0),
        ([a1, b1, b1], w1),
        ([b1, a1, b1], w1),
        ([b1, b1, a1], w1),
        ([a2, b2, b2], w2),
        ([b2, a2, b2], w2),
        ([b2, b2, a2], w2),
    ]
}

/// 3-point Gauss–Legendre on an edge: the position s ∈ (0, 1) from the first vertex and the
/// weight relative to the length (they sum to 1).
pub fn edge_rule() -> [(f64, f64); 3] {
    let r = 0.5 * 0.6f64.sqrt();
    [(0.5 - r, 5.0 / 18.0), (0.5, 8.0 / 18.0), (0.5 + r, 5.0 / 18.0)]
}

/// A quadrature point of a cell: its position, the weight (area share) and the values of the
/// cell's P1 basis functions λ_a there.
#[derive(Debug, Clone, Copy)]
pub struct CellPoint {
    pub x: [f64; 3],
    pub weight: f64,
    pub basis: [f64; 3],
}

/// Calls `visit(e, simplex, point)` for every quadrature point of every cell of a 2D mesh.
pub fn for_each_cell_point(mesh: &Mesh, mut visit: impl FnMut(usize, &Simplex, &CellPoint)) {
    debug_assert_eq!(mesh.dim, 2, "the verification quadrature is 2D");
    let rule = triangle_rule();
    for e in 0..mesh.n_cells() {
        let verts = mesh.cell_coords(e);
        let simplex = Simplex::new(2, &verts);
        for (bary, w) in rule {
            let mut x = [0.0; 3];
            for (a, v) in verts.iter().enumerate() {
                for c in 0..2 {
                    x[c] += bary[a] * v[c];
                }
            }
            let point = CellPoint {
                x,
                weight: w * simplex.measure,
                basis: bary,
            };
            visit(e, &simplex, &point);
        }
    }
}

/// ∫_Ω f · φ_(p,c) for every full velocity dof (p, c) of a 2D mesh.
pub fn vector_body_load(mesh: &Mesh, f: impl Fn([f64; 3]) -> [f64; 2], load: &mut [f64]) {
    for_each_cell_point(mesh, |e, _, point| {
        let value = f(point.x);
        for (a, &p) in mesh.cell(e).iter().enumerate() {
            for c in 0..2 {
                load[p * 2 + c] += point.weight * point.basis[a] * value[c];
            }
        }
    });
}

/// ∫_Ω g η_p for every node p of a 2D mesh.
pub fn scalar_body_load(mesh: &Mesh, g: impl Fn([f64; 3]) -> f64, load: &mut [f64]) {
    for_each_cell_point(mesh, |e, _, point| {
        let value = g(point.x);
        for (a, &p) in mesh.cell(e).iter().enumerate() {
            load[p] += point.weight * point.basis[a] * value;
        }
    });
}

/// ∫_{parts} f · φ_(p,c) over the boundary edges of the given parts.
pub fn vector_boundary_load(mesh: &Mesh, parts: &[usize], f: impl Fn([f64; 3]) -> [f64; 2], load: &mut [f64]) {
    for_each_edge_point(mesh, parts, |nodes, x, weight, basis| {
        let value = f(x);
        for (a, &p) in nodes.iter().enumerate() {
            for c in 0..2 {
                load[p * 2 + c] += weight * basis[a] * value[c];
            }
        }
    });
}

/// ∫_{parts} g η_p over the boundary edges of the given parts.
pub fn scalar_boundary_load(mesh: &Mesh, parts: &[usize], g: impl Fn([f64; 3]) -> f64, load: &mut [f64]) {
    for_each_edge_point(mesh, parts, |nodes, x, weight, basis| {
        let value = g(x);
        for (a, &p) in nodes.iter().enumerate() {
            load[p] += weight * basis[a] * value;
        }
    });
}

fn for_each_edge_point(mesh: &Mesh, parts: &[usize], mut visit: impl FnMut(&[usize], [f64; 3], f64, [f64; 2])) {
    let rule = edge_rule();
    for f in mesh.facets_of(parts) {
        let nodes = mesh.facet(f);
        let (p, q) = (mesh.coords[nodes[0]], mesh.coords[nodes[1]]);
        let length = facet_measure(2, &[p, q]);
        for (s, w) in rule {
            let x = [p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1]), 0.0];
            visit(nodes, x, w * length, [1.0 - s, s]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::rectangle;

    #[test]
    fn rules_integrate_quintics_exactly() {
        // ∫_T λ₀^a λ₁^b λ₂^c = 2|T| a! b! c! / (a + b + c + 2)!; here a = b = 2, c = 1.
        let exact = 2.0 * 2.0 * 2.0 / 5040.0;
        let approx: f64 = triangle_rule()
            .iter()
            .map(|(l, w)| w * l[0].powi(2) * l[1].powi(2) * l[2])
            .sum();
        assert!((approx - exact).abs() < 1e-15, "{approx} vs {exact}");
        // ∫₀¹ s⁵ = 1/6.
        let edge: f64 = edge_rule().iter().map(|(s, w)| w * s.powi(5)).sum();
        assert!((edge - 1.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn loads_of_constants_match_the_nodal_shares() {
        let mesh = rectangle(4.0, 1.0, 8, 2);
        let mut load = vec![0.0; mesh.n_nodes() * 2];
        vector_body_load(&mesh, |_| [1.0, -2.0], &mut load);
        let expected = crate::fem::assembly::body_load(&mesh, &[1.0, -2.0]);
        for (a, b) in load.iter().zip(&expected) {
            assert!((a - b).abs() < 1e-14);
        }
        let bottom = mesh.part_index("bottom").unwrap();
        let mut flux = vec![0.0; mesh.n_nodes()];
        scalar_boundary_load(&mesh, &[bottom], |x| x[0], &mut flux);
        // ∫₀⁴ x dx = 8.
        assert!((flux.iter().sum::<f64>() - 8.0).abs() < 1e-13);
    }
}
