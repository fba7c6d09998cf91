//! The discrete spaces E^h (velocity) and V^h (temperature) as maps from full nodal dofs to the
//! unknowns actually solved for.
//!
//! E^h = {v P1 : v = 0 on Γ_D, v_ν = 0 on Γ_C}. A clamped node has no unknown; a contact node
//! has d − 1 unknowns, the coordinates of its velocity in an orthonormal tangent basis
//! t₁…t_{d−1} of the (planar) Γ_C, so the bilateral condition (7) holds exactly for any normal ν;
//! every other node has d unknowns. Full dof (node p, component c) is then a linear combination
//! of unknowns: the prolongation P, stored row by row. Dirichlet wins at corners: a node in the
//! closure of Γ_D is clamped even when it also lies on Γ_C.
//!
//! V^h: temperature unknowns at nodes off the closure of Γ_D ∪ Γ_N; the others hold θ_D.

/// Vector P1 velocity space with the clamped and bilateral constraints built in.
#[derive(Debug, Clone)]
pub struct VelocitySpace {
    /// Space dimension d.
    pub dim: usize,
    /// Number of unknowns.
    pub n_free: usize,
    /// Row pointers of P (one row per full dof p·d + c).
    ptr: Vec<usize>,
    /// (unknown, coefficient) entries of P.
    entries: Vec<(usize, f64)>,
}

/// An orthonormal tangent basis of a plane with unit normal ν (d − 1 vectors).
pub fn tangent_basis(normal: &[f64]) -> Vec<[f64; 3]> {
    if normal.len() == 2 {
        // Rotate ν by +90°: ν = (0, −1) gives t = (1, 0), the x direction of the paper.
        return vec![[-normal[1], normal[0], 0.0]];
    }
    let n = [normal[0], normal[1], normal[2]];
    // Start from the coordinate axis least aligned with ν.
    let axis = (0..3).min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs())).unwrap_or(0);
    let mut t1 = [0.0; 3];
    t1[axis] = 1.0;
    let dot = t1[0] * n[0] + t1[1] * n[1] + t1[2] * n[2];
    for c in 0..3 {
        t1[c] -= dot * n[c];
    }
    let len = (t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]).sqrt();
    t1.iter_mut().for_each(|x| *x /= len);
    let t2 = [
        n[1] * t1[2] - n[2] * t1[1],
        n[2] * t1[0] - n[0] * t1[2],
        n[0] * t1[1] - n[1] * t1[0],
    ];
    vec![t1, t2]
}

impl VelocitySpace {
    /// Builds E^h from the clamped and contact node markers and the tangent basis of Γ_C.
    /// Returns the space and, per node, the indices of its tangential unknowns (contact nodes).
    pub fn new(
        dim: usize,
        clamped: &[bool],
        contact: &[bool],
        tangents: &[[f64; 3]],
    ) -> (Self, Vec<Option<[usize; 2]>>) {
        let n_nodes = clamped.len();
        let mut ptr = vec![0];
        let mut entries = Vec::new();
        let mut tangent_dofs = vec![None; n_nodes];
        let mut next = 0;
        for p in 0..n_nodes {
            if clamped[p] {
                for _ in 0..dim {
                    ptr.push(entries.len());
                }
            } else if contact[p] {
                let mut dofs = [usize::MAX; 2];
                for (k, dof) in dofs.iter_mut().enumerate().take(dim - 1) {
                    *dof = next + k;
                }
                for c in 0..dim {
                    for (k, t) in tangents.iter().enumerate() {
                        if t[c] != 0.0 {
                            entries.push((next + k, t[c]));
                        }
                    }
                    ptr.push(entries.len());
                }
                tangent_dofs[p] = Some(dofs);
                next += dim - 1;
            } else {
                for c in 0..dim {
                    entries.push((next + c, 1.0));
                    ptr.push(entries.len());
                }
                next += dim;
            }
        }
        (
            VelocitySpace {
                dim,
                n_free: next,
                ptr,
                entries,
            },
            tangent_dofs,
        )
    }

    /// Number of full dofs d·N.
    pub fn n_full(&self) -> usize {
        self.ptr.len() - 1
    }

    /// The unknowns (with coefficients) that full dof `dof` is made of.
    #[inline]
    pub fn row(&self, dof: usize) -> &[(usize, f64)] {
        &self.entries[self.ptr[dof]..self.ptr[dof + 1]]
    }

    /// Full nodal vector P x from the unknowns x.
    pub fn prolong(&self, x: &[f64]) -> Vec<f64> {
        (0..self.n_full())
            .map(|i| self.row(i).iter().map(|&(j, a)| a * x[j]).sum())
            .collect()
    }

    /// reduced += Pᵀ full: a full load vector seen by the unknowns.
    pub fn restrict_add(&self, full: &[f64], reduced: &mut [f64]) {
        for (i, &f) in full.iter().enumerate() {
            for &(j, a) in self.row(i) {
                reduced[j] += a * f;
            }
        }
    }

    /// Unknowns of a full nodal vector (exact when the vector lies in E^h).
    pub fn restrict_values(&self, full: &[f64]) -> Vec<f64> {
        // Pᵀ P is the identity (orthonormal tangents, unit entries elsewhere).
        let mut x = vec![0.0; self.n_free];
        self.restrict_add(full, &mut x);
        x
    }
}

/// Scalar P1 temperature space with θ = θ_D on the closure of Γ_D ∪ Γ_N.
#[derive(Debug, Clone)]
pub struct TemperatureSpace {
    /// Unknown index of each node, `None` at Dirichlet nodes.
    pub free: Vec<Option<usize>>,
    /// Number of unknowns.
    pub n_free: usize,
}

impl TemperatureSpace {
    /// Builds V^h from the Dirichlet node markers.
    pub fn new(dirichlet: &[bool]) -> Self {
        let mut next = 0;
        let free = dirichlet
            .iter()
            .map(|&d| {
                (!d).then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        TemperatureSpace { free, n_free: next }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_bases_are_orthonormal() {
        assert_eq!(tangent_basis(&[0.0, -1.0]), vec![[1.0, 0.0, 0.0]]);
        let n = [0.6, 0.0, -0.8];
        let t = tangent_basis(&n);
        let dot = |a: &[f64; 3], b: &[f64]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        assert!(dot(&t[0], &n).abs() < 1e-15 && dot(&t[1], &n).abs() < 1e-15);
        assert!(dot(&t[0], &t[1]).abs() < 1e-15);
        assert!((dot(&t[0], &t[0]) - 1.0).abs() < 1e-15 && (dot(&t[1], &t[1]) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn constraints_shape_the_space() {
        // Node 0 clamped, node 1 in contact (normal −y), node 2 free.
        let (space, tangential) = VelocitySpace::new(
            2,
            &[true, false, false],
            &[true, true, false],
            &tangent_basis(&[0.0, -1.0]),
        );
        assert_eq!(space.n_free, 3);
        assert_eq!(tangential[1], Some([0, usize::MAX]));
        assert_eq!(space.prolong(&[2.0, 3.0, 4.0]), vec![0.0, 0.0, 2.0, 0.0, 3.0, 4.0]);
        assert_eq!(
            space.restrict_values(&[0.0, 0.0, 2.0, 0.0, 3.0, 4.0]),
            vec![2.0, 3.0, 4.0]
        );
    }
}
