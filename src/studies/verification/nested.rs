//! Exact P1 prolongation between nested rectangle meshes.
//!
//! [`crate::mesh::rectangle`] cuts every cell along its "/" diagonal, so the mesh of
//! (r·n_x) × (r·n_y) cells refines the mesh of n_x × n_y cells for every integer r ≥ 1: each fine
//! triangle lies inside one coarse triangle. A coarse P1 field is then also a fine P1 field, and
//! its fine nodal values are its values at the fine nodes,
//!
//! ```text
//! (P v)(x_q) = Σ_a λ_a(x_q) v(x_a)     (x_a the vertices of the coarse triangle holding x_q),
//! ```
//!
//! so errors measured on the fine mesh are exact norms of the
//! difference of the two P1 fields.

use crate::error::Error;
use crate::mesh::simplex::Simplex;
use crate::model::Problem;
use crate::scenario::Structured;

/// The prolongation P from a coarse to a fine rectangle mesh: per fine node, the three coarse
/// nodes of the coarse triangle holding it and their barycentric weights.
#[derive(Debug, Clone)]
pub struct Prolongation {
    rows: Vec<[(usize, f64); 3]>,
    n_coarse: usize,
}

impl Prolongation {
    /// P from the mesh of `coarse` to the mesh of `fine`. Both must be rectangle meshes of the
    /// same rectangle, with n_x and n_y of the fine mesh the same integer multiple of the coarse
    /// ones (nested meshes); anything else is an error, since interpolation between non-nested
    /// meshes would add an interpolation error to the measured one.
    pub fn new(coarse: &Problem, fine: &Problem) -> Result<Self, Error> {
        let (Some(cs), Some(fs)) = (rectangle_grid(&coarse.mesh), rectangle_grid(&fine.mesh)) else {
            return Err(not_nested(coarse, fine, "structured rectangle meshes in 2D"));
        };
        if cs.lengths != fs.lengths {
            return Err(not_nested(coarse, fine, "the same rectangle in 2D"));
        }
        let (nx, ny) = (cs.cells[0], cs.cells[1]);
        let ratio = fs.cells[0] / nx;
        if ratio == 0 || fs.cells[0] != ratio * nx || fs.cells[1] != ratio * ny {
            return Err(not_nested(
                coarse,
                fine,
                "fine cell counts that are one integer multiple of the coarse ones",
            ));
        }
        let (lx, ly) = (cs.lengths[0], cs.lengths[1]);
        let (dx, dy) = (lx / nx as f64, ly / ny as f64);
        let mesh = &coarse.mesh;
        let rows = fine
            .mesh
            .coords
            .iter()
            .map(|x| {
                let (sx, sy) = (x[0] / dx, x[1] / dy);
                let i = (sx.floor().max(0.0) as usize).min(nx - 1);
                let j = (sy.floor().max(0.0) as usize).min(ny - 1);
                // Cell (i, j) holds triangles 2e (below the diagonal, local ξ ≥ η) and 2e + 1.
                let below = sx - i as f64 >= sy - j as f64;
                let cell = 2 * (j * nx + i) + usize::from(!below);
                let nodes = mesh.cell(cell);
                let verts = mesh.cell_coords(cell);
                let simplex = Simplex::new(2, &verts);
                let mut row = [(0, 0.0); 3];
                for (a, &p) in nodes.iter().enumerate() {
                    // λ_a(x) = λ_a(x₀) + ∇λ_a · (x − x₀), λ_a(x₀) = δ_a0.
                    let base = if a == 0 { 1.0 } else { 0.0 };
                    let g = simplex.grads[a];
                    let lambda = base + g[0] * (x[0] - verts[0][0]) + g[1] * (x[1] - verts[0][1]);
                    debug_assert!(lambda > -1e-9, "fine node outside its coarse triangle");
                    row[a] = (p, lambda);
                }
                row
            })
            .collect();
        Ok(Prolongation {
            rows,
            n_coarse: mesh.n_nodes(),
        })
    }

    /// P v for a nodal field with `components` values per node (1 for θ, d for u and w).
    pub fn apply(&self, coarse: &[f64], components: usize) -> Vec<f64> {
        debug_assert_eq!(coarse.len(), self.n_coarse * components);
        let mut fine = vec![0.0; self.rows.len() * components];
        for (q, row) in self.rows.iter().enumerate() {
            for c in 0..components {
                fine[q * components + c] = row.iter().map(|&(p, l)| l * coarse[p * components + c]).sum();
            }
        }
        fine
    }
}

/// The rectangle and cell counts of a mesh made by [`crate::mesh::rectangle`], recognised by
/// regenerating it; `None` for any other mesh.
fn rectangle_grid(mesh: &crate::mesh::Mesh) -> Option<Structured> {
    if mesh.dim != 2 {
        return None;
    }
    let max = |c: usize| mesh.coords.iter().map(|x| x[c]).fold(f64::NEG_INFINITY, f64::max);
    let (lx, ly) = (max(0), max(1));
    let nx = mesh.coords.iter().filter(|x| x[1] == 0.0).count().checked_sub(1)?;
    let ny = (mesh.n_nodes() / (nx + 1)).checked_sub(1)?;
    if nx == 0 || ny == 0 {
        return None;
    }
    let regenerated = crate::mesh::rectangle(lx, ly, nx, ny);
    let same = regenerated.cells == mesh.cells
        && regenerated.n_nodes() == mesh.n_nodes()
        && regenerated
            .coords
            .iter()
            .zip(&mesh.coords)
            .all(|(a, b)| (a[0] - b[0]).abs() <= 1e-12 * lx && (a[1] - b[1]).abs() <= 1e-12 * ly);
    same.then(|| Structured {
        lengths: vec![lx, ly],
        cells: vec![nx, ny],
    })
}

fn not_nested(coarse: &Problem, fine: &Problem, expected: &str) -> Error {
    let describe = |p: &Problem| match rectangle_grid(&p.mesh) {
        Some(g) => format!("{:?} m with {} × {} cells", g.lengths, g.cells[0], g.cells[1]),
        None => format!("an unstructured mesh of {} nodes", p.mesh.n_nodes()),
    };
    Error::InvalidValue {
        key: "mesh".into(),
        value: format!("coarse {}, fine {}", describe(coarse), describe(fine)),
        expected: format!("nested meshes: {expected}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scenario;

    fn problem(nx: usize, ny: usize) -> Problem {
        let s = Scenario::load(None, &[format!("mesh.nx={nx}"), format!("mesh.ny={ny}")]).unwrap();
        s.build().unwrap()
    }

    /// A coarse P1 field and its prolongation are the same function: the fine nodal values at
    /// coarse nodes are copied, and the E-norm and V-norm (exact cell sums) agree.
    #[test]
    fn prolongation_preserves_p1_fields_and_their_norms() {
        let (coarse, fine) = (problem(8, 2), problem(24, 6));
        let p = Prolongation::new(&coarse, &fine).unwrap();
        let field: Vec<f64> = (0..coarse.mesh.n_nodes() * 2)
            .map(|i| ((i * 37) % 11) as f64 - 5.0)
            .collect();
        let prolonged = p.apply(&field, 2);
        let (ne, nf) = (
            crate::model::norms::energy(&coarse.mesh, &field),
            crate::model::norms::energy(&fine.mesh, &prolonged),
        );
        assert!((ne - nf).abs() < 1e-12 * ne, "{ne} vs {nf}");
        let theta: Vec<f64> = field.iter().step_by(2).cloned().collect();
        let (gc, gf) = (
            crate::model::norms::gradient(&coarse.mesh, &theta),
            crate::model::norms::gradient(&fine.mesh, &p.apply(&theta, 1)),
        );
        assert!((gc - gf).abs() < 1e-12 * gc);
        // Coarse node (i, j) is fine node (3i, 3j).
        let (cnx, fnx) = (9, 25);
        assert_eq!(prolonged[(3 * 2 + 3 * fnx) * 2 + 1], field[(2 + cnx) * 2 + 1]);
    }

    #[test]
    fn prolongation_rejects_meshes_that_are_not_nested() {
        let err = Prolongation::new(&problem(8, 2), &problem(12, 4)).unwrap_err();
        assert!(err.to_string().contains("nested"), "{err}");
    }
}
