//! The discrete spaces E^h (velocity) and V^h (temperature) as maps from full nodal dofs to the
//! unknowns actually solved for.
//!
//! E^h = {v P1 : v = 0 on Γ_D, v_ν = 0 on Γ_C}, with symmetry (roller) planes adding v·ν_s = 0.
//! Every node carries the coordinates of its velocity in an orthonormal basis of the directions
//! its constraints leave free ([`NodeBasis`]): all of ℝ^d (no constraint, the Cartesian
//! components), nothing (clamped: a node in the closure of Γ_D, which wins at corners), or given
//! directions — at a contact node the tangents t_{i,k} of its frame that it may slide along
//! ([`crate::contact::frames`]), so that (7) holds exactly for each node's own normal; at a node on
//! symmetry planes the directions along them. Full dof (node p, component c) is then a linear
//! combination of unknowns: the prolongation P, stored row by row. This is what makes a 3D slab
//! with w_y = 0 on both y faces a plane-strain model.
//!
//! V^h: temperature unknowns at nodes off the closure of Γ_D ∪ Γ_N (the paper's rule; per-part
//! thermal conditions change which parts hold θ_D: `crate::model::thermal`); the others hold θ_D.

/// The free velocities of one node.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeBasis {
    /// Unconstrained: d unknowns, the Cartesian components.
    Cartesian,
    /// Held (clamped): no unknown.
    Held,
    /// Unknowns along these orthonormal directions, in this order.
    Along(Vec<[f64; 3]>),
}

/// Vector P1 velocity space with the clamped, bilateral and symmetry constraints built in.
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
    /// The first unknown of each node (its unknowns are consecutive, in its basis order).
    first: Vec<usize>,
}

impl VelocitySpace {
    /// Builds E^h from each node's basis of free velocities.
    pub fn new(dim: usize, bases: &[NodeBasis]) -> Self {
        let mut ptr = Vec::with_capacity(bases.len() * dim + 1);
        ptr.push(0);
        let mut entries = Vec::with_capacity(bases.len() * dim);
        let mut first = Vec::with_capacity(bases.len());
        let mut next = 0;
        for basis in bases {
            first.push(next);
            match basis {
                NodeBasis::Cartesian => {
                    for c in 0..dim {
                        entries.push((next + c, 1.0));
                        ptr.push(entries.len());
                    }
                    next += dim;
                }
                NodeBasis::Held => ptr.extend(std::iter::repeat_n(entries.len(), dim)),
                NodeBasis::Along(directions) => {
                    for c in 0..dim {
                        for (k, b) in directions.iter().enumerate() {
                            if b[c] != 0.0 {
                                entries.push((next + k, b[c]));
                            }
                        }
                        ptr.push(entries.len());
                    }
                    next += directions.len();
                }
            }
        }
        VelocitySpace {
            dim,
            n_free: next,
            ptr,
            entries,
            first,
        }
    }

    /// The unknown of node p's k-th basis direction.
    pub fn unknown(&self, node: usize, k: usize) -> usize {
        self.first[node] + k
    }

    /// The unknowns of node p (consecutive; empty at a held node).
    pub fn node_unknowns(&self, node: usize) -> std::ops::Range<usize> {
        let end = self.first.get(node + 1).copied().unwrap_or(self.n_free);
        self.first[node]..end
    }

    /// (P Pᵀ v) at node p for a velocity v there (d components): the part of v that E^h keeps
    /// at the node. P Pᵀ acts on each node's components alone, as the node's unknowns are its
    /// own (`node_unknowns`): [`VelocitySpace::prolong`] of [`VelocitySpace::restrict_values`]
    /// node by node, without vectors of the mesh's size.
    pub fn node_projection(&self, node: usize, v: &[f64; 3]) -> [f64; 3] {
        let unknowns = self.node_unknowns(node);
        let mut reduced = [0.0; 3];
        for c in 0..self.dim {
            for &(j, a) in self.row(node * self.dim + c) {
                reduced[j - unknowns.start] += a * v[c];
            }
        }
        let mut kept = [0.0; 3];
        for (c, kept) in kept.iter_mut().enumerate().take(self.dim) {
            *kept = (self.row(node * self.dim + c).iter())
                .map(|&(j, a)| a * reduced[j - unknowns.start])
                .sum();
        }
        kept
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
        // Pᵀ P is the identity (orthonormal bases per node).
        let mut x = vec![0.0; self.n_free];
        self.restrict_add(full, &mut x);
        x
    }
}

/// Scalar P1 temperature space with θ = θ_D at the given Dirichlet nodes (the closure of
/// Γ_D ∪ Γ_N in the paper).
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
    fn constraints_shape_the_space() {
        // Node 0 clamped, node 1 slides along x (a contact node of a face with normal −y),
        // node 2 free.
        let space = VelocitySpace::new(
            2,
            &[
                NodeBasis::Held,
                NodeBasis::Along(vec![[1.0, 0.0, 0.0]]),
                NodeBasis::Cartesian,
            ],
        );
        assert_eq!(space.n_free, 3);
        assert_eq!(space.unknown(1, 0), 0);
        assert_eq!(space.unknown(2, 1), 2);
        assert_eq!(space.prolong(&[2.0, 3.0, 4.0]), vec![0.0, 0.0, 2.0, 0.0, 3.0, 4.0]);
        assert_eq!(
            space.restrict_values(&[0.0, 0.0, 2.0, 0.0, 3.0, 4.0]),
            vec![2.0, 3.0, 4.0]
        );
    }

    #[test]
    fn oblique_directions_prolong_and_restrict_exactly() {
        let (c, s) = (0.6, 0.8);
        let space = VelocitySpace::new(3, &[NodeBasis::Along(vec![[c, s, 0.0], [0.0, 0.0, 1.0]])]);
        let w = space.prolong(&[2.0, -1.0]);
        assert_eq!(w, vec![2.0 * c, 2.0 * s, -1.0]);
        let back = space.restrict_values(&w);
        assert!((back[0] - 2.0).abs() < 1e-15 && (back[1] + 1.0).abs() < 1e-15);
    }
}
