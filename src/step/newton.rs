//! The fast solver: a semismooth Newton method on the condensed nonmonotone contact problem.
//!
//! With the compliances of [`super::condensed`], one time step reduces to finding the
//! tangential velocities w and friction stresses ξ at the contact nodes such that
//!
//! ```text
//! (E1)  w − w_free − C ξ − H h(w) = 0                  (the linear step problem, condensed)
//! (E2)  F_i = ξ_i − P_{b(|w_i|)}(ξ_i − r w_i) = 0       (the nodal friction law, eq. (83))
//! ```
//!
//! where b(r) = μ(r) S is the friction bound of the *nonmonotone* law itself (not frozen, as
//! in the convexification loop) and P_g projects onto the ball of radius g. F is the
//! Alart–Curnier function of the law: piecewise smooth, so Newton's method with its generalized
//! Jacobian converges locally quadratically. At each iterate the nodes split by
//! q_i = ξ_i − r w_i: stick where |q_i| ≤ b(|w_i|) (linearized: w_i = 0), slip otherwise
//! (linearized: ξ_i affine in w_i, eliminated node by node). The unknowns left are ξ at stick
//! nodes and w at slip nodes: one dense n_t × n_t LU per iteration, n_t = (d − 1)·#Γ_C nodes.
//!
//! Where the law falls steeply (m_τ large against ρ/k and the viscosity, conditions (16)–(18))
//! the step problem may have several solutions and Newton may cycle; the step then goes through
//! the convexification loop of Problem 17 ([`super::fast`]), each convex problem solved by the
//! sweeps of [`super::descent`] (by this Newton method with frozen bounds where the descent is
//! switched off), and the step is counted.

use std::cell::RefCell;

use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::Mat;

use super::condensed::Condensation;
use crate::la::vector::{max_abs_diff as max_diff, norm2 as norm};
use crate::model::ContactLaws;

/// Settings of the semismooth Newton method.
#[derive(Debug, Clone, Copy)]
pub struct NewtonParams {
    /// Relative tolerance on the Newton update (w against max |w|, ξ against max bound).
    pub tolerance: f64,
    /// Iteration cap; past it the step goes through the convexification loop.
    pub max_iterations: usize,
}

/// The condensed contact problem of one time step.
pub struct CondensedStep<'a> {
    pub condensation: &'a Condensation,
    /// The step's laws: the friction bounds and the frictional heat at each contact node (where
    /// θ is prescribed the heat has no effect: the corresponding columns of H vanish).
    pub laws: &'a ContactLaws<'a>,
    /// d − 1.
    pub tangential: usize,
    /// Augmentation parameter r of the Alart–Curnier function (any r > 0 gives the same
    /// solutions; it only shapes the iteration).
    pub augmentation: f64,
    /// The last LU of J with its active-set key (2D convex subproblems only, where J depends on
    /// nothing but the stick set and the slip directions: the convexification iterates of one
    /// step mostly share it).
    pub lu_cache: RefCell<Option<(Vec<i8>, PartialPivLu<f64>)>>,
}

/// The outcome of a Newton solve.
#[derive(Debug, Clone)]
pub struct NewtonResult {
    /// Tangential velocities (flat, node-major).
    pub w: Vec<f64>,
    /// Friction stresses (flat, node-major).
    pub xi: Vec<f64>,
    /// Iterations used.
    pub iterations: usize,
}

impl CondensedStep<'_> {
    fn nodes(&self) -> usize {
        self.condensation.n_h
    }

    fn heat(&self, w: &[f64]) -> Vec<f64> {
        (0..self.nodes())
            .map(|i| self.laws.heat(i, norm(&w[self.range(i)])))
            .collect()
    }

    fn range(&self, i: usize) -> std::ops::Range<usize> {
        i * self.tangential..(i + 1) * self.tangential
    }

    /// Solves (E1)–(E2) from the initial guess (w, ξ); `None` if Newton does not converge.
    ///
    /// With `frozen` bounds g_i the law is the convex Tresca law of Problem 17 (b ≡ g_i, b' = 0):
    /// the inner problem of a convexification iterate.
    pub fn solve(
        &self,
        w_free: &[f64],
        mut w: Vec<f64>,
        mut xi: Vec<f64>,
        frozen: Option<&[f64]>,
        params: NewtonParams,
    ) -> Option<NewtonResult> {
        let t = self.tangential;
        let n_t = self.condensation.n_t;
        let n_nodes = self.nodes();
        let r = self.augmentation;
        let (c, h) = (&self.condensation.friction, &self.condensation.heat);
        let g_scale = self.laws.largest_bound_at_rest().max(f64::MIN_POSITIVE);
        for iteration in 1..=params.max_iterations {
            // Active sets and the per-node elimination ξ_i = a_i + B_i w_i at slip nodes.
            let mut stick = vec![false; n_nodes];
            let mut a = vec![0.0; n_t];
            let mut b = vec![[[0.0; 2]; 2]; n_nodes];
            for i in 0..n_nodes {
                let range = self.range(i);
                let (wi, xii) = (&w[range.clone()], &xi[range.clone()]);
                let speed = norm(wi);
                let (bound, slope) = match frozen {
                    Some(g) => (g[i], 0.0),
                    None => (self.laws.bound(i, speed), self.laws.bound_derivative(i, speed)),
                };
                let mut q = [0.0; 2];
                for k in 0..t {
                    q[k] = xii[k] - r * wi[k];
                }
                let q_norm = norm(&q[..t]);
                if q_norm <= bound {
                    stick[i] = true;
                    continue;
                }
                let (a_i, b_i) = slip_linearization(wi, xii, &q[..t], q_norm, bound, slope, r, t);
                a[range].copy_from_slice(&a_i[..t]);
                b[i] = b_i;
            }
            // Assemble J z = rhs for z = (ξ at stick nodes, w at slip nodes), flat indices.
            let heat = self.heat(&w);
            let heat_slope: Vec<f64> = (0..n_nodes)
                .map(|j| self.laws.heat_derivative(j, norm(&w[self.range(j)])))
                .collect();
            let mut jac = Mat::<f64>::zeros(n_t, n_t);
            let mut rhs = Mat::<f64>::zeros(n_t, 1);
            for row in 0..n_t {
                let mut value = w_free[row];
                for j in 0..n_nodes {
                    let cols = self.range(j);
                    if stick[j] {
                        for col in cols {
                            jac[(row, col)] -= c[row * n_t + col];
                        }
                    } else {
                        // −C (a + B w): constant part to the right side, linear part to J.
                        let wj = &w[cols.clone()];
                        let speed = norm(wj);
                        let h_rj = h[row * n_nodes + j];
                        value += h_rj * heat[j];
                        for (kc, col) in cols.clone().enumerate() {
                            let c_rc = c[row * n_t + col];
                            value += c_rc * a[col];
                            for (kw, col_w) in cols.clone().enumerate() {
                                jac[(row, col_w)] -= c_rc * b[j][kc][kw];
                            }
                        }
                        // Heat linearized at w: H h(w) + H h'(w)(w⁺ − w).
                        if speed > 0.0 {
                            for (k, col_w) in cols.enumerate() {
                                let dh = heat_slope[j] * wj[k] / speed;
                                jac[(row, col_w)] -= h_rj * dh;
                                value -= h_rj * dh * wj[k];
                            }
                        }
                    }
                }
                if !stick[row / t] {
                    jac[(row, row)] += 1.0;
                }
                rhs[(row, 0)] = value;
            }
            // In 2D with frozen bounds J is fixed by the stick set and the slip signs.
            let key: Option<Vec<i8>> = (frozen.is_some() && t == 1).then(|| {
                (0..n_nodes)
                    .map(|i| {
                        if stick[i] {
                            2
                        } else {
                            w[i].partial_cmp(&0.0).map_or(0, |o| o as i8)
                        }
                    })
                    .collect()
            });
            let mut cache = self.lu_cache.borrow_mut();
            let reusable = matches!((&*cache, &key), (Some((cached, _)), Some(key)) if cached == key);
            if !reusable {
                *cache = Some((key.unwrap_or_default(), jac.partial_piv_lu()));
            }
            let z = cache.as_ref().expect("just filled").1.solve(&rhs);
            drop(cache);
            if !(0..n_t).all(|i| z[(i, 0)].is_finite()) {
                return None;
            }
            // Unpack and measure the update.
            let (mut dw, mut dxi): (f64, f64) = (0.0, 0.0);
            for i in 0..n_nodes {
                let range = self.range(i);
                let mut new_w = [0.0; 2];
                let mut new_xi = [0.0; 2];
                if stick[i] {
                    for (k, idx) in range.clone().enumerate() {
                        new_xi[k] = z[(idx, 0)];
                    }
                } else {
                    for (k, idx) in range.clone().enumerate() {
                        new_w[k] = z[(idx, 0)];
                    }
                    for k in 0..t {
                        new_xi[k] = a[i * t + k] + (0..t).map(|m| b[i][k][m] * new_w[m]).sum::<f64>();
                    }
                }
                for (k, idx) in range.enumerate() {
                    dw = dw.max((new_w[k] - w[idx]).abs());
                    dxi = dxi.max((new_xi[k] - xi[idx]).abs());
                    w[idx] = new_w[k];
                    xi[idx] = new_xi[k];
                }
            }
            // Converged when the new point satisfies (E1)–(E2) to the tolerance: no further LU.
            let w_scale = w
                .iter()
                .chain(w_free)
                .fold(0.0f64, |m, v| m.max(v.abs()))
                .max(f64::MIN_POSITIVE);
            let (e1, e2) = self.residuals(w_free, &w, &xi, frozen);
            let small_update = dw <= params.tolerance * w_scale && dxi <= params.tolerance * g_scale;
            if (e1 <= params.tolerance * w_scale && e2 <= params.tolerance * g_scale) || small_update {
                return Some(NewtonResult {
                    w,
                    xi,
                    iterations: iteration,
                });
            }
        }
        None
    }

    /// max |E1| (velocity units) and max |E2| (stress units) at (w, ξ).
    pub fn residuals(&self, w_free: &[f64], w: &[f64], xi: &[f64], frozen: Option<&[f64]>) -> (f64, f64) {
        let mut w_lin = vec![0.0; w.len()];
        self.condensation.velocities(w_free, xi, &self.heat(w), &mut w_lin);
        (max_diff(&w_lin, w), self.law_residual(w, xi, frozen))
    }

    /// max |E2| (stress units) at (w, ξ): the nodal law alone, O(n_t).
    pub fn law_residual(&self, w: &[f64], xi: &[f64], frozen: Option<&[f64]>) -> f64 {
        let mut e2: f64 = 0.0;
        for i in 0..self.nodes() {
            let range = self.range(i);
            let bound = match frozen {
                Some(g) => g[i],
                None => self.laws.bound(i, norm(&w[range.clone()])),
            };
            e2 = e2.max(node_law_residual(
                &w[range.clone()],
                &xi[range],
                bound,
                self.augmentation,
            ));
        }
        e2
    }
}

/// max_k |ξ_k − P_g(ξ − r w)_k| at one node: the Alart–Curnier residual of the law with bound
/// g (stress units).
pub(super) fn node_law_residual(w: &[f64], xi: &[f64], bound: f64, r: f64) -> f64 {
    let mut q = [0.0; 2];
    for k in 0..w.len() {
        q[k] = xi[k] - r * w[k];
    }
    crate::contact::project_to_ball(&mut q[..w.len()], bound);
    (0..w.len()).fold(0.0, |worst, k| worst.max((xi[k] - q[k]).abs()))
}

/// At a slip node (|q| > b(|w|)), linearizes F = ξ − b(|w|) q/|q| = 0 around (w, ξ) and solves it
/// for ξ⁺ = a + B w⁺.
///
/// ∂F/∂ξ = I − (b/|q|)(I − n nᵀ), ∂F/∂w = −b'(|w|) n (w/|w|)ᵀ + (b r/|q|)(I − n nᵀ), n = q/|q|;
/// ∂F/∂ξ is invertible because |q| > b. Where w = 0 the slip direction is taken as −n.
#[allow(clippy::too_many_arguments)]
pub(super) fn slip_linearization(
    w: &[f64],
    xi: &[f64],
    q: &[f64],
    q_norm: f64,
    bound: f64,
    slope: f64,
    r: f64,
    t: usize,
) -> ([f64; 2], [[f64; 2]; 2]) {
    let speed = norm(w);
    let mut n = [0.0; 2];
    let mut dir = [0.0; 2];
    for k in 0..t {
        n[k] = q[k] / q_norm;
        dir[k] = if speed > 0.0 { w[k] / speed } else { -n[k] };
    }
    let mut a_xi = [[0.0; 2]; 2];
    let mut a_w = [[0.0; 2]; 2];
    for k in 0..t {
        for m in 0..t {
            let proj = if k == m { 1.0 } else { 0.0 } - n[k] * n[m];
            a_xi[k][m] = if k == m { 1.0 } else { 0.0 } - bound / q_norm * proj;
            a_w[k][m] = -slope * n[k] * dir[m] + bound * r / q_norm * proj;
        }
    }
    // F at the current point.
    let mut f = [0.0; 2];
    for k in 0..t {
        f[k] = xi[k] - bound * n[k];
    }
    let inv = invert_small(&a_xi, t);
    // ξ⁺ = ξ − A_ξ⁻¹ (F + A_w (w⁺ − w)) = [ξ − A_ξ⁻¹F + A_ξ⁻¹A_w w] − A_ξ⁻¹A_w w⁺
    let mut a = [0.0; 2];
    let mut b = [[0.0; 2]; 2];
    for k in 0..t {
        a[k] = xi[k];
        for m in 0..t {
            a[k] -= inv[k][m] * f[m];
            let mut inv_aw = 0.0;
            for l in 0..t {
                inv_aw += inv[k][l] * a_w[l][m];
            }
            a[k] += inv_aw * w[m];
            b[k][m] = -inv_aw;
        }
    }
    (a, b)
}

/// max_i |a_i − b_i|.
fn invert_small(m: &[[f64; 2]; 2], t: usize) -> [[f64; 2]; 2] {
    if t == 1 {
        [[1.0 / m[0][0], 0.0], [0.0, 0.0]]
    } else {
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        [[m[1][1] / det, -m[0][1] / det], [-m[1][0] / det, m[0][0] / det]]
    }
}
