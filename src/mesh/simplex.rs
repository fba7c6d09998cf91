//! Geometry of P1 simplices (triangles, tetrahedra) and of their boundary facets.
//!
//! On a simplex with vertices x₀…x_d the P1 basis functions are the barycentric coordinates
//! λ₀…λ_d; their gradients are constant: with J = [x₁ − x₀, …, x_d − x₀], the rows of J⁻¹ are
//! ∇λ₁…∇λ_d and ∇λ₀ = −Σ_k ∇λ_k.

/// A P1 simplex in d = 2 or 3: its measure and the constant gradients of its basis functions.
#[derive(Debug, Clone, Copy)]
pub struct Simplex {
    /// Space dimension d.
    pub dim: usize,
    /// Measure |T| (area or volume).
    pub measure: f64,
    /// ∇λ_a for a = 0..=d (components beyond d are zero).
    pub grads: [[f64; 3]; 4],
}

impl Simplex {
    /// Builds the simplex from its d + 1 vertices.
    ///
    /// ```
    /// use thermocontact::mesh::simplex::Simplex;
    /// let t = Simplex::new(2, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    /// assert!((t.measure - 0.5).abs() < 1e-15);
    /// assert_eq!(t.grads[1][0], 1.0); // λ₁ = x
    /// assert_eq!(t.grads[0][1], -1.0); // λ₀ = 1 − x − y
    /// ```
    pub fn new(dim: usize, vertices: &[[f64; 3]]) -> Self {
        debug_assert_eq!(vertices.len(), dim + 1);
        match dim {
            2 => Self::new_in::<2>(vertices),
            _ => Self::new_in::<3>(vertices),
        }
    }

    /// [`Simplex::new`] in D dimensions (loops the compiler unrolls: the kernels of a process
    /// that keeps no stiffness matrix build each cell's simplex once a step).
    #[inline(always)]
    fn new_in<const D: usize>(vertices: &[[f64; 3]]) -> Self {
        let mut jac = [[0.0; 3]; 3]; // jac[r][c] = (x_{c+1} − x₀)_r
        for c in 0..D {
            for (r, row) in jac.iter_mut().enumerate().take(D) {
                row[c] = vertices[c + 1][r] - vertices[0][r];
            }
        }
        let (det, inv) = invert(D, &jac);
        let factorial = if D == 2 { 2.0 } else { 6.0 };
        let mut grads = [[0.0; 3]; 4];
        for k in 0..D {
            // ∇λ_{k+1} is row k of J⁻¹.
            grads[k + 1][..D].copy_from_slice(&inv[k][..D]);
            for r in 0..D {
                grads[0][r] -= inv[k][r];
            }
        }
        Simplex {
            dim: D,
            measure: det.abs() / factorial,
            grads,
        }
    }

    /// div φ for the vector basis function φ = λ_a e_c: the c-th component of ∇λ_a.
    pub fn div(&self, a: usize, c: usize) -> f64 {
        self.grads[a][c]
    }
}

/// Determinant and inverse of the leading `dim × dim` block.
#[inline(always)]
fn invert(dim: usize, m: &[[f64; 3]; 3]) -> (f64, [[f64; 3]; 3]) {
    let mut inv = [[0.0; 3]; 3];
    if dim == 2 {
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        inv[0][0] = m[1][1] / det;
        inv[0][1] = -m[0][1] / det;
        inv[1][0] = -m[1][0] / det;
        inv[1][1] = m[0][0] / det;
        (det, inv)
    } else {
        let cof = |r: usize, c: usize| {
            let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
            let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
            m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]
        };
        let det = m[0][0] * cof(0, 0) + m[0][1] * cof(0, 1) + m[0][2] * cof(0, 2);
        for r in 0..3 {
            for c in 0..3 {
                inv[c][r] = cof(r, c) / det;
            }
        }
        (det, inv)
    }
}

/// Measure of a boundary facet (edge length in 2D, triangle area in 3D).
pub fn facet_measure(dim: usize, vertices: &[[f64; 3]]) -> f64 {
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    if dim == 2 {
        let e = sub(vertices[1], vertices[0]);
        e[0].hypot(e[1])
    } else {
        let (a, b) = (sub(vertices[1], vertices[0]), sub(vertices[2], vertices[0]));
        let n = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradients_reproduce_affine_functions() {
        let verts = [[0.3, 0.1, 0.0], [2.0, 0.4, 0.0], [0.7, 1.9, 0.0]];
        let t = Simplex::new(2, &verts);
        // f(x) = 3 + 2x − 5y: Σ f(x_a) ∇λ_a = (2, −5)
        let f = |p: [f64; 3]| 3.0 + 2.0 * p[0] - 5.0 * p[1];
        let mut g = [0.0; 2];
        for (a, v) in verts.iter().enumerate() {
            g[0] += f(*v) * t.grads[a][0];
            g[1] += f(*v) * t.grads[a][1];
        }
        assert!((g[0] - 2.0).abs() < 1e-12 && (g[1] + 5.0).abs() < 1e-12);
    }

    #[test]
    fn tetrahedron_measure_and_gradients() {
        let verts = [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 4.0]];
        let t = Simplex::new(3, &verts);
        assert!((t.measure - 4.0).abs() < 1e-12);
        assert!((t.grads[3][2] - 0.25).abs() < 1e-15);
        assert!((t.grads[0][0] + 0.5).abs() < 1e-15);
        assert!((facet_measure(3, &verts[1..]) - 0.5 * (36.0f64 + 64.0 + 144.0).sqrt()).abs() < 1e-12);
    }
}
