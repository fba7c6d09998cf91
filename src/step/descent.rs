//! The globalization of the fast solver: nonsmooth block Gauss–Seidel descent on the energy of
//! the condensed step.
//!
//! With the frictional heat frozen, w₀ = w_τ^free + H h, the condensed step (E1)–(E2) of
//! [`super::newton`] is the stationarity condition of
//!
//! ```text
//! E(w) = ½ (w − w₀)ᵀ K (w − w₀) + Σ_i ℓ_i φ(|w_i|),   φ(s) = ∫₀^s b,   K = D⁻¹,  C = D ℓ,
//! ```
//!
//! where D = E_w A⁻¹ E_wᵀ is the velocity block of the inverse step matrix on Γ_C. D is
//! symmetric positive definite even though A is not: it is the inverse of the Schur complement
//! K_w + G K_θ⁻¹ Gᵀ restricted to Γ_C. E is coercive and, for a velocity-weakening law, nonconvex:
//! a step may have several solutions (conditions (16)–(18) of the paper fail), but every local
//! minimizer of E is one, and a descent method cannot cycle. At a stationary point
//! ξ = ℓ⁻¹ K (w − w₀) is the friction stress and (E1) holds identically.
//!
//! **Method.** One sweep visits the contact nodes in order; node i moves downhill on the
//! majorized block problem
//!
//! ```text
//! w_i ← a minimizer of ½ κ_i |v − (w_i − g_i/κ_i)|² + ℓ_i φ(|v|),   g_i = [K (w − w₀)]_i,  κ_i = λ_max(K_ii),
//! ```
//!
//! which is radial: v = s (w_i − g_i/κ_i)/|·| with s the local minimizer of a scalar function
//! on [0, r] reached downhill from |w_i| ([`radial_minimizer`]: a scan refined by bisection, so a
//! law of any shape works). In 2D κ_i = K_ii and the sweep is block coordinate minimization; in
//! 3D it is block proximal gradient (PALM). Either way E never increases, and the iterates
//! reach a stationary point (Bolte, Sabach, Teboulle, Math. Program. 146 (2014): the energy is
//! analytic here, hence Kurdyka–Łojasiewicz). Stick nodes land on w_i = 0 exactly. The heat is
//! updated after every sweep (it couples into w₀ through H, weakly: thermal expansion of one
//! step's frictional heat). The sweeps converge linearly (on the paper's example about two
//! digits per sweep: the mass term makes K strongly diagonal); where they slow down near a
//! solution, semismooth Newton on the nonmonotone law finishes, and if it fails from there the
//! sweeps go on to the tolerance.
//!
//! **Which solution.** The descent starts from the previous step's velocities and each block
//! goes to the nearest minimizer downhill, as the convexification iteration would for one node
//! ([`radial_minimizer`]); it returns a stationary point reached downhill from the previous
//! step (a local minimizer in practice). That is not always the convexification loop's fixed
//! point when several nodes interact (on the paper's example, solving every step by descent
//! first gives u within 6e-5 in 2D but 3 % apart in 3D): so the fast solver keeps the loop first
//! and descends only where the loop fails.
//!
//! **Rejected alternatives.** Newton with a line search on ‖F‖² (F the Alart–Curnier function):
//! the merit function has stationary points that are not solutions where the law falls
//! steeply, which is exactly where it is needed. Gauss–Seidel on ξ with the Delassus operator C
//! (nonsmooth contact dynamics codes): for a nonconvex φ it minimizes nothing, so it may cycle.
//! Path following in the law's steepness: a sequence of full solves, each as hard as the step.

use faer::linalg::solvers::DenseSolveCore;
use faer::{Mat, Side};

use super::condensed::Condensation;
use super::newton::{CondensedStep, NewtonParams, NewtonResult};
use crate::la::vector::norm2 as norm;
use crate::la::{FactorStage, LaError as Error};
use crate::model::law_scale;

/// Settings of the descent.
#[derive(Debug, Clone, Copy)]
pub struct DescentParams {
    /// Stop when the nodal law holds to this, relative to the smallest friction bound
    /// (ε_conv, as the other solvers' [`super::Criterion::NodalLaw`]).
    pub tolerance: f64,
    /// Cap on sweeps; 0 switches the descent off.
    pub max_sweeps: usize,
    /// Newton is tried once the law residual is below this (relative to the smallest bound).
    pub handover: f64,
    /// The Newton method of the hand-over.
    pub newton: NewtonParams,
    /// With frozen bounds and `lagged` = s > 0: symmetric sweeps (Γ_C's order and back), the
    /// bounds frozen again at the slip after every s of them: the convexification loop itself
    /// run on Γ_C's exact condensed rows, each convex problem solved by s sweeps, which stops at
    /// one of its fixed points ([`super::FastSolver`]). 0, or without frozen bounds: forward sweeps
    /// with the bounds given.
    pub lagged: usize,
}

/// K = D⁻¹ on Γ_C and what a sweep needs of it, computed once per step size.
#[derive(Debug, Clone)]
pub struct ContactStiffness {
    /// n_t.
    n_t: usize,
    /// d − 1.
    tangential: usize,
    /// K, n_t × n_t, row-major (symmetric).
    k: Vec<f64>,
    /// ℓ_i per contact node.
    weights: Vec<f64>,
    /// κ_i = λ_max(K_ii) per contact node.
    kappa: Vec<f64>,
    /// (K H)ᵀ, n_h × n_t, row-major: row i is how the gradient moves per unit heat at node i,
    /// so that a sweep updates the heat node by node without a product with H.
    kh: Vec<f64>,
}

impl ContactStiffness {
    /// K from the compliances C = D ℓ (columns scaled by the nodes' ℓ) and H of the
    /// condensation.
    pub fn new(condensation: &Condensation, tangential: usize, weights: &[f64]) -> Result<Self, Error> {
        let (friction, n_t, n_h) = (&condensation.friction, condensation.n_t, condensation.n_h);
        let d = Mat::<f64>::from_fn(n_t, n_t, |r, c| {
            // Symmetrize away the round-off of the column solves.
            0.5 * (friction[r * n_t + c] / weights[c / tangential] + friction[c * n_t + r] / weights[r / tangential])
        });
        let inverse = d
            .llt(Side::Lower)
            .map_err(|_| Error::Factorization {
                stage: FactorStage::Cholesky,
                detail: "not positive definite".into(),
            })?
            .inverse();
        let mut k = vec![0.0; n_t * n_t];
        for r in 0..n_t {
            for c in 0..n_t {
                k[r * n_t + c] = inverse[(r, c)];
            }
        }
        let kappa = (0..weights.len())
            .map(|i| {
                let at = |a: usize, b: usize| k[(i * tangential + a) * n_t + i * tangential + b];
                if tangential == 1 {
                    at(0, 0)
                } else {
                    let (p, q, s) = (at(0, 0), at(1, 1), 0.5 * (at(0, 1) + at(1, 0)));
                    0.5 * (p + q) + (0.25 * (p - q) * (p - q) + s * s).sqrt()
                }
            })
            .collect();
        let h = Mat::<f64>::from_fn(n_t, n_h, |r, c| condensation.heat[r * n_h + c]);
        let kh_mat = &inverse * &h;
        let kh = (0..n_h)
            .flat_map(|i| (0..n_t).map(move |r| (i, r)))
            .map(|(i, r)| kh_mat[(r, i)])
            .collect();
        Ok(ContactStiffness {
            n_t,
            tangential,
            k,
            weights: weights.to_vec(),
            kappa,
            kh,
        })
    }

    /// The friction stress that makes w satisfy the condensed equations (E1) exactly:
    /// ξ = ℓ⁻¹ K (w − w_τ^free − H h(w)), computed afresh (two O(n_t²) products).
    pub fn friction_stress(&self, step: &CondensedStep, w_free: &[f64], w: &[f64]) -> Vec<f64> {
        let mut w0 = vec![0.0; self.n_t];
        let mut y = vec![0.0; self.n_t];
        frozen_start(step, w_free, w, &mut w0);
        self.gradient(w, &w0, &mut y);
        y.iter()
            .enumerate()
            .map(|(j, y)| y / self.weights[j / self.tangential])
            .collect()
    }

    /// y = K (w − w₀).
    fn gradient(&self, w: &[f64], w0: &[f64], y: &mut [f64]) {
        let diff: Vec<f64> = w.iter().zip(w0).map(|(a, b)| a - b).collect();
        for (r, yr) in y.iter_mut().enumerate() {
            *yr = self.k[r * self.n_t..(r + 1) * self.n_t]
                .iter()
                .zip(&diff)
                .map(|(a, b)| a * b)
                .sum();
        }
    }
}

/// Where a descent starts.
#[derive(Debug, Clone)]
pub struct Start<'a> {
    /// Tangential velocities on Γ_C (flat, node-major).
    pub w: Vec<f64>,
    /// The ξ a descent of the same step returned with these `w`, if they are its result: the
    /// gradient K (w − w₀) = ℓ ξ is then known and not recomputed (one O(n_t²) product saved per
    /// convexification iterate). `None` otherwise.
    pub xi: Option<&'a [f64]>,
}

impl Start<'_> {
    /// From velocities alone.
    pub fn at(w: Vec<f64>) -> Self {
        Start { w, xi: None }
    }
}

/// How a descent ended without reaching the tolerance.
#[derive(Debug, Clone, Copy)]
pub struct DescentStall {
    /// Sweeps done.
    pub sweeps: usize,
    /// The nodal law residual at the last iterate, relative to the smallest bound.
    pub law_residual: f64,
}

/// Runs the descent from `w` (the previous step's tangential velocities) on the condensed
/// step; returns a state that satisfies (E1)–(E2) to the tolerance, with `iterations` = sweeps
/// (the Newton iterations of the hand-over are added to `newton_iterations`).
///
/// With `frozen` bounds g_i the law is the convex Tresca law of a convexification iterate
/// (Problem 17): the energy is then convex, its minimizer unique, and the descent is an inner
/// solver of the paper's loop that needs no dense factorization (no hand-over to Newton).
pub fn descend(
    step: &CondensedStep,
    stiffness: &ContactStiffness,
    w_free: &[f64],
    start: Start,
    frozen: Option<&[f64]>,
    params: &DescentParams,
    newton_iterations: &mut usize,
) -> Result<NewtonResult, DescentStall> {
    let t = stiffness.tangential;
    let n_t = stiffness.n_t;
    let n_nodes = stiffness.weights.len();
    let laws = step.laws;
    let mut w = start.w;
    let bound_at = |w: &[f64], i: usize| laws.bound(i, norm(&w[i * t..(i + 1) * t]));
    // Lagged bounds are frozen again after every `params.lagged` sweeps (`DescentParams::lagged`).
    let given = frozen;
    let mut lagged = given.filter(|_| params.lagged > 0).map(<[f64]>::to_vec);
    // The backward pass of a lagged sweep (none otherwise).
    let back = if lagged.is_some() { n_nodes } else { 0 };
    // The residual's scale: the smallest friction bound at the iterate (as the other solvers').
    let g_min = |w: &[f64], frozen: Option<&[f64]>| match frozen {
        Some(g) => law_scale(g.iter().copied()),
        None => law_scale((0..n_nodes).map(|i| bound_at(w, i))),
    };
    let mut w0 = vec![0.0; n_t];
    let mut y = vec![0.0; n_t];
    let mut xi = vec![0.0; n_t];
    match start.xi {
        Some(xi) => y
            .iter_mut()
            .enumerate()
            .for_each(|(j, y)| *y = stiffness.weights[j / t] * xi[j]),
        None => {
            frozen_start(step, w_free, &w, &mut w0);
            stiffness.gradient(&w, &w0, &mut y);
        }
    }
    let mut newton_tried_at = f64::INFINITY;
    let mut residual = f64::INFINITY;
    for sweep in 1..=params.max_sweeps {
        let frozen = lagged.as_deref().or(given);
        for i in (0..n_nodes).chain((0..back).rev()) {
            let range = i * t..(i + 1) * t;
            let kappa = stiffness.kappa[i];
            let mut v = [0.0; 2];
            for (k, j) in range.clone().enumerate() {
                v[k] = w[j] - y[j] / kappa;
            }
            let r = norm(&v[..t]);
            let ell = stiffness.weights[i];
            let speed = norm(&w[range.clone()]);
            let s = match frozen {
                // Tresca: the shrinkage argmin ½κ(s − r)² + ℓ g s.
                Some(g) => (r - ell * g[i] / kappa).max(0.0),
                None => radial_minimizer(|s| laws.bound(i, s), kappa, ell, r, speed),
            };
            let scale = if r > 0.0 { s / r } else { 0.0 };
            for (k, j) in range.clone().enumerate() {
                let delta = scale * v[k] - w[j];
                if delta != 0.0 {
                    // y += K[:, j] δ (K symmetric: row j).
                    let row = &stiffness.k[j * n_t..(j + 1) * n_t];
                    y.iter_mut().zip(row).for_each(|(yr, kr)| *yr += kr * delta);
                    w[j] += delta;
                }
            }
            // The node's frictional heat moves w₀ by H Δh_i, the gradient by −(K H)_i Δh_i.
            let heat_change = laws.heat_change(i, speed, norm(&w[range]));
            if heat_change != 0.0 {
                let row = &stiffness.kh[i * n_t..(i + 1) * n_t];
                y.iter_mut().zip(row).for_each(|(yr, kr)| *yr -= kr * heat_change);
            }
        }
        // ξ = ℓ⁻¹ K (w − w₀): (E1) then holds up to round-off, the law measures stationarity.
        let xi_of = |y: &[f64], xi: &mut [f64]| {
            for (j, x) in xi.iter_mut().enumerate() {
                *x = y[j] / stiffness.weights[j / t];
            }
        };
        xi_of(&y, &mut xi);
        if let Some(bounds) = lagged.as_mut().filter(|_| sweep % params.lagged == 0) {
            bounds.iter_mut().enumerate().for_each(|(i, g)| *g = bound_at(&w, i));
        }
        let frozen = lagged.as_deref().or(given);
        if frozen.is_none() && step.law_residual(&w, &xi, frozen) / g_min(&w, frozen) <= params.tolerance {
            // Converged on the updated gradient: confirm on a fresh one (no drift of the
            // updates), and carry it on if not. (A convex subproblem's result is an iterate of
            // the convexification loop, which confirms only the state it accepts:
            // [`ContactStiffness::friction_stress`].)
            frozen_start(step, w_free, &w, &mut w0);
            stiffness.gradient(&w, &w0, &mut y);
            xi_of(&y, &mut xi);
        }
        let previous = residual;
        residual = step.law_residual(&w, &xi, frozen) / g_min(&w, frozen);
        if residual <= params.tolerance {
            return Ok(NewtonResult {
                w,
                xi,
                iterations: sweep,
            });
        }
        // Where the sweeps slow down near a solution, Newton finishes (again only after a
        // tenfold improvement since its last try).
        let slow = residual > 0.3 * previous;
        if frozen.is_none() && slow && residual <= params.handover && residual <= 0.1 * newton_tried_at {
            newton_tried_at = residual;
            if let Some(result) = step.solve(w_free, w.clone(), xi.clone(), None, params.newton) {
                *newton_iterations += result.iterations;
                let law_residual = step.law_residual(&result.w, &result.xi, None) / g_min(&result.w, None);
                if law_residual <= params.tolerance {
                    return Ok(NewtonResult {
                        iterations: sweep,
                        ..result
                    });
                }
            } else {
                *newton_iterations += params.newton.max_iterations;
            }
        }
    }
    Err(DescentStall {
        sweeps: params.max_sweeps,
        law_residual: residual,
    })
}

/// w₀ = w_τ^free + H h(w): the velocities of the step without friction, with the heat of w.
fn frozen_start(step: &CondensedStep, w_free: &[f64], w: &[f64], w0: &mut [f64]) {
    let t = step.tangential;
    let c = step.condensation;
    let heat: Vec<f64> = (0..c.n_h)
        .map(|i| step.laws.heat(i, norm(&w[i * t..(i + 1) * t])))
        .collect();
    for (r, w0) in w0.iter_mut().enumerate() {
        let row = &c.heat[r * c.n_h..(r + 1) * c.n_h];
        *w0 = w_free[r] + row.iter().zip(&heat).map(|(a, b)| a * b).sum::<f64>();
    }
}

/// The local minimizer over s ∈ [0, r] of f(s) = ½ κ (s − r)² + ℓ φ(s) (φ' = b ≥ 0, the
/// node's `bound`) reached
/// downhill from `current`: where f'(current) > 0 the nearest root of
/// f'(s) = κ (s − r) + ℓ b(s) below it (or 0), where f'(current) < 0 the nearest root above it
/// (f'(r) = ℓ b(r) ≥ 0, so one exists). Each root is bracketed by a 32-interval scan and
/// refined by bisection to the last bit, so a law of any shape works.
///
/// Downhill, not global: for one node this is where the convexification iteration
/// s ← max(r − ℓ b(s)/κ, 0) of Problem 17 goes from the same start (a sticking node whose
/// 0 is a local minimizer stays stuck, a slipping one settles on the nearest stable slip
/// rate), so the descent continues the solution the paper's solver would. The global
/// minimizer of each block would jump to the deepest basin and pick another solution of a
/// step with several (1–4 % apart in u on the paper's example).
pub fn radial_minimizer(bound: impl Fn(f64) -> f64, kappa: f64, ell: f64, r: f64, current: f64) -> f64 {
    if r <= 0.0 {
        return 0.0;
    }
    let df = |s: f64| kappa * (s - r) + ell * bound(s);
    let start = current.clamp(0.0, r);
    let slope = df(start);
    if slope == 0.0 {
        return start;
    }
    // Walk from `start` towards `end` until f' changes sign, then bisect.
    let end = if slope > 0.0 { 0.0 } else { r };
    const INTERVALS: usize = 32;
    let mut near = start;
    for j in 1..=INTERVALS {
        let far = start + (end - start) * j as f64 / INTERVALS as f64;
        let crossed = if slope > 0.0 { df(far) < 0.0 } else { df(far) >= 0.0 };
        if crossed {
            // f' ≥ 0 on the upper end of the bracket, < 0 on the lower one.
            let (mut a, mut b) = if slope > 0.0 { (far, near) } else { (near, far) };
            loop {
                let m = 0.5 * (a + b);
                if m <= a || m >= b {
                    break;
                }
                if df(m) < 0.0 {
                    a = m;
                } else {
                    b = m;
                }
            }
            return if df(a).abs() < df(b).abs() { a } else { b };
        }
        near = far;
    }
    // f' > 0 all the way down: the minimizer is s = 0. (Upwards a crossing always exists.)
    end
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::friction::{FrictionLaw, LawPoint, Tresca, VelocityWeakening};

    #[test]
    fn the_radial_minimizer_goes_downhill_to_the_nearest_local_minimum() {
        // Steep weakening: f has a local minimum at 0 and another one near r.
        let velocity_weakening = VelocityWeakening {
            a: 1.0,
            b: 0.05,
            alpha: 1000.0,
        };
        let at = LawPoint::default();
        let bound = |s: f64| velocity_weakening.bound(150.0, &at, s);
        let law = &bound;
        let (kappa, ell) = (1.0e4, 1.0);
        let f = |s: f64, r: f64| 0.5 * kappa * (s - r) * (s - r) + ell * velocity_weakening.potential(150.0, &at, s);
        let df = |s: f64, r: f64| kappa * (s - r) + ell * bound(s);
        for r in [1e-4, 1e-3, 5e-3, 1e-2, 1.2e-2, 2e-2, 0.1] {
            for current in [0.0, 0.25 * r, 0.5 * r, r] {
                let s = radial_minimizer(law, kappa, ell, r, current);
                assert!((0.0..=r).contains(&s));
                // Never uphill, and no lower point between the start and s (the nearest basin).
                assert!(f(s, r) <= f(current, r), "r = {r}, from {current}: uphill");
                let (lo, hi) = if s < current { (s, current) } else { (current, s) };
                for j in 0..=1000 {
                    let p = lo + (hi - lo) * j as f64 / 1000.0;
                    assert!(
                        f(p, r) >= f(s, r) - 1e-12 * f(0.0, r).abs(),
                        "r = {r}, from {current}: passed a lower point"
                    );
                }
                // A local minimizer: a root of f' (to round-off) or 0 with f'(0) ≥ 0.
                if s > 0.0 {
                    assert!(
                        df(s, r).abs() <= 1e-9 * (kappa * r + ell * bound(0.0)),
                        "r = {r}: f'(s) = {}",
                        df(s, r)
                    );
                } else {
                    assert!(df(0.0, r) >= 0.0);
                }
            }
        }
        // A sticking node whose 0 is a local minimizer stays stuck, though slipping is lower.
        let r = 1.2e-2;
        assert!(df(0.0, r) > 0.0);
        assert_eq!(radial_minimizer(law, kappa, ell, r, 0.0), 0.0);
        assert!(radial_minimizer(law, kappa, ell, r, r) > 0.0);
    }

    #[test]
    fn with_tresca_the_radial_minimizer_is_the_shrinkage() {
        let at = LawPoint::default();
        // argmin ½κ(s − r)² + ℓ g s = max(r − ℓ g/κ, 0).
        for r in [0.0, 0.1, 0.5, 2.0] {
            let s = radial_minimizer(|s| Tresca.bound(3.0, &at, s), 2.0, 1.0, r, 0.0);
            assert!((s - (r - 1.5f64).max(0.0)).abs() < 1e-12, "r = {r}: {s}");
        }
    }
}
