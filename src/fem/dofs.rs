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
//! Symmetry (roller) planes add w·ν_s = 0 at their nodes, built into the space the same way
//! ([`VelocitySpace::with_planes`]): a node on a plane of a 3D body keeps the 2 velocity
//! coordinates along the plane, on two planes the one along their intersection. This is what
//! makes a 3D slab with w_y = 0 on both y faces a plane-strain model.
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

/// The velocity unknowns of a contact node's tangential coordinates (`None` off Γ_C); unused
/// slots (d = 2, or a coordinate held by a symmetry plane) hold `usize::MAX`.
pub type TangentDofs = Option<[usize; 2]>;

/// A symmetry plane through a contact node whose normal, seen in Γ_C's tangent plane, lies along
/// neither tangent of the basis: w·ν_s = 0 would couple the two tangential coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MisalignedPlane {
    /// The contact node.
    pub node: usize,
    /// The symmetry plane's unit normal ν_s.
    pub normal: [f64; 3],
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
        let planes = vec![Vec::new(); clamped.len()];
        Self::with_planes(dim, clamped, contact, tangents, &planes).expect("no symmetry planes, nothing to misalign")
    }

    /// Builds E^h with, besides the clamped and bilateral constraints, symmetry (roller)
    /// constraints w·ν_s = 0 at every node p for each unit normal ν_s in `planes[p]`.
    ///
    /// The unknowns of a node are the coordinates of its velocity in an orthonormal basis of the
    /// subspace its constraints leave free: all of ℝ^d (no constraint), the plane ⊥ ν_s (one
    /// symmetry plane), the line ⊥ two independent normals in 3D, nothing (fully constrained).
    /// At a contact node the basis stays Γ_C's tangent basis t₁…t_{d−1}, so that the solvers
    /// keep reading w_τ from the unknowns; a symmetry plane there must then have its normal
    /// along ν (no extra constraint) or, within the tangent plane, along one tangent t_k, whose
    /// coordinate is then held at zero: its entry in the returned tangent dofs is `usize::MAX`.
    /// A contact node with every tangential coordinate held carries no friction and gets no
    /// unknowns (like a clamped node). Any other direction is a [`MisalignedPlane`].
    pub fn with_planes(
        dim: usize,
        clamped: &[bool],
        contact: &[bool],
        tangents: &[[f64; 3]],
        planes: &[Vec<[f64; 3]>],
    ) -> Result<(Self, Vec<TangentDofs>), MisalignedPlane> {
        let n_nodes = clamped.len();
        let mut ptr = vec![0];
        let mut entries = Vec::new();
        let mut tangent_dofs = vec![None; n_nodes];
        let mut next = 0;
        let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for p in 0..n_nodes {
            // The orthonormal basis of the node's free velocities, and the tangential slots.
            let mut basis: Vec<[f64; 3]> = Vec::new();
            let mut slots = [usize::MAX; 2];
            if clamped[p] {
            } else if contact[p] {
                let mut held = [false; 2];
                for normal in &planes[p] {
                    let c: Vec<f64> = tangents.iter().map(|t| dot(t, normal)).collect();
                    let size = c.iter().map(|x| x * x).sum::<f64>().sqrt();
                    if size <= 1e-9 {
                        continue; // ν_s ∥ ν: the bilateral condition already says it
                    }
                    let along = (0..dim - 1).find(|&k| c[k].abs() >= (1.0 - 1e-9) * size);
                    match along {
                        Some(k) => held[k] = true,
                        None => {
                            return Err(MisalignedPlane {
                                node: p,
                                normal: *normal,
                            })
                        }
                    }
                }
                if (0..dim - 1).any(|k| !held[k]) {
                    for k in (0..dim - 1).filter(|&k| !held[k]) {
                        slots[k] = next + basis.len();
                        basis.push(tangents[k]);
                    }
                    tangent_dofs[p] = Some(slots);
                }
            } else if planes[p].is_empty() {
                basis = (0..dim)
                    .map(|c| {
                        let mut e = [0.0; 3];
                        e[c] = 1.0;
                        e
                    })
                    .collect();
            } else {
                basis = free_directions(dim, &planes[p]);
            }
            for c in 0..dim {
                for (k, b) in basis.iter().enumerate() {
                    if b[c] != 0.0 {
                        entries.push((next + k, b[c]));
                    }
                }
                ptr.push(entries.len());
            }
            next += basis.len();
        }
        Ok((
            VelocitySpace {
                dim,
                n_free: next,
                ptr,
                entries,
            },
            tangent_dofs,
        ))
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

/// An orthonormal basis of {v ∈ ℝ^d : v·ν = 0 for every ν in `normals`} (unit normals).
fn free_directions(dim: usize, normals: &[[f64; 3]]) -> Vec<[f64; 3]> {
    // Gram–Schmidt on the normals, dropping dependent ones (two planes with one normal).
    let mut span: Vec<[f64; 3]> = Vec::new();
    for n in normals {
        let mut v = *n;
        for s in &span {
            let proj = v[0] * s[0] + v[1] * s[1] + v[2] * s[2];
            (0..3).for_each(|c| v[c] -= proj * s[c]);
        }
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if len > 1e-9 {
            span.push(v.map(|x| x / len));
        }
    }
    match (dim, span.len()) {
        (_, 0) => unreachable!("called with at least one normal"),
        (2, 1) | (3, 1) => tangent_basis(&span[0][..dim]),
        (3, 2) => {
            let (a, b) = (span[0], span[1]);
            vec![[
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]]
        }
        _ => Vec::new(),
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

    #[test]
    fn symmetry_planes_leave_the_velocities_along_them() {
        let tangents = tangent_basis(&[0.0, 0.0, -1.0]); // t₁ = x, t₂ = −y
        let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        // Node 0: on the plane y = const; node 1: on y and x planes; node 2: contact node on a
        // y plane (w_y = −w_τ₂ held); node 3: contact node on a z plane (already w_z = 0).
        let planes = vec![vec![y], vec![y, x], vec![y], vec![z]];
        let (space, tangential) =
            VelocitySpace::with_planes(3, &[false; 4], &[false, false, true, true], &tangents, &planes).unwrap();
        assert_eq!(space.n_free, 2 + 1 + 1 + 2);
        assert_eq!(tangential[2], Some([3, usize::MAX]));
        assert_eq!(tangential[3], Some([4, 5]));
        let w = space.prolong(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        // Node 0 moves in x and z only, node 1 along z only, node 2 along x only.
        assert_eq!(&w[..9], &[1.0, 0.0, -2.0, 0.0, 0.0, -3.0, 4.0, 0.0, 0.0]);
        assert_eq!(&w[9..], &[5.0, -6.0, 0.0]);
        // A plane whose normal is oblique to both tangents cannot be held by one coordinate.
        let oblique = [0.6, 0.8, 0.0];
        let err = VelocitySpace::with_planes(3, &[false], &[true], &tangents, &[vec![oblique]]).unwrap_err();
        assert_eq!(
            err,
            MisalignedPlane {
                node: 0,
                normal: oblique
            }
        );
    }
}
