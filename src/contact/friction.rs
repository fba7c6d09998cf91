//! Friction laws −ξ ∈ ∂j_τ(w_τ) with j_τ(ξ) = ∫₀^|ξ| b(s) ds for a friction bound b(r) ≥ 0.
//!
//! For such a potential the Clarke subdifferential is ∂j_τ(0) = {|ζ| ≤ b(0)} and
//! ∂j_τ(w) = {b(|w|) w/|w|} for w ≠ 0 (eq. (83)): stick inside the disc of radius b(0), slip
//! with a friction stress of size b(|w|) against the slip direction. A decreasing b (slip
//! weakening) makes j_τ nonconvex; −b' is then the constant m_τ of H(j_τ)(d).

/// A friction law given by its bound b(r) = μ(r) S at slip rate r = |w_τ| ≥ 0.
pub trait FrictionLaw: Send + Sync + std::fmt::Debug {
    /// b(r): the size of the friction stress when slipping at rate r.
    fn bound(&self, r: f64) -> f64;
    /// b'(r).
    fn bound_derivative(&self, r: f64) -> f64;
    /// j_τ as a function of r = |ξ|: ∫₀^r b(s) ds.
    fn potential(&self, r: f64) -> f64;
}

/// The slip-weakening law of eq. (81): b(r) = S ((a − b) e^(−αr) + b).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlipWeakening {
    /// S: the bound's scale.
    pub scale: f64,
    /// a = μ(0).
    pub a: f64,
    /// b = μ(∞).
    pub b: f64,
    /// α: the weakening rate.
    pub alpha: f64,
}

impl FrictionLaw for SlipWeakening {
    fn bound(&self, r: f64) -> f64 {
        self.scale * ((self.a - self.b) * (-self.alpha * r).exp() + self.b)
    }
    fn bound_derivative(&self, r: f64) -> f64 {
        -self.scale * self.alpha * (self.a - self.b) * (-self.alpha * r).exp()
    }
    fn potential(&self, r: f64) -> f64 {
        let decay = if self.alpha > 0.0 {
            (1.0 - (-self.alpha * r).exp()) / self.alpha
        } else {
            r
        };
        self.scale * ((self.a - self.b) * decay + self.b * r)
    }
}

/// Tresca friction: a constant bound S (j_τ(ξ) = S|ξ|, convex).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tresca {
    /// S: the bound.
    pub scale: f64,
}

impl FrictionLaw for Tresca {
    fn bound(&self, _r: f64) -> f64 {
        self.scale
    }
    fn bound_derivative(&self, _r: f64) -> f64 {
        0.0
    }
    fn potential(&self, r: f64) -> f64 {
        self.scale * r
    }
}

/// Projection of `v` onto the closed ball of radius `radius` (the disc in 3D, an interval in 2D).
///
/// The nodal friction law with a frozen bound g reads ξ = P_g(ξ − r w) for any r > 0: this
/// fixed-point form is what the augmented-Lagrangian solvers iterate.
pub fn project_to_ball(v: &mut [f64], radius: f64) {
    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm > radius {
        let scale = if norm > 0.0 { radius / norm } else { 0.0 };
        v.iter_mut().for_each(|x| *x *= scale);
    }
}

/// Residual of the nodal law −ξ ∈ ∂j_τ(w) at one node: zero exactly when the law holds.
///
/// Stick (|w| ≤ `slip_tol`): how far |ξ| exceeds b(0). Slip: |ξ + b(|w|) w/|w||.
pub fn law_residual(law: &dyn FrictionLaw, w: &[f64], xi: &[f64], slip_tol: f64) -> f64 {
    let speed = w.iter().map(|x| x * x).sum::<f64>().sqrt();
    if speed <= slip_tol {
        let size = xi.iter().map(|x| x * x).sum::<f64>().sqrt();
        (size - law.bound(0.0)).max(0.0)
    } else {
        let b = law.bound(speed);
        w.iter()
            .zip(xi)
            .map(|(wi, xi)| (xi + b * wi / speed).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PAPER: SlipWeakening = SlipWeakening {
        scale: 150.0,
        a: 1.0,
        b: 0.2,
        alpha: 100.0,
    };

    #[test]
    fn slip_weakening_values() {
        assert!((PAPER.bound(0.0) - 150.0).abs() < 1e-12);
        assert!((PAPER.bound(1.0) - 30.0).abs() < 1e-10);
        assert!((PAPER.bound_derivative(0.0) + 150.0 * 100.0 * 0.8).abs() < 1e-9);
        // j_τ' = b: central difference of the potential.
        let (r, h) = (0.013, 1e-6);
        let fd = (PAPER.potential(r + h) - PAPER.potential(r - h)) / (2.0 * h);
        assert!((fd - PAPER.bound(r)).abs() < 1e-6);
        assert_eq!(PAPER.potential(0.0), 0.0);
    }

    #[test]
    fn local_law_stick_and_slip() {
        let tresca = Tresca { scale: 2.0 };
        // Stick: any ξ inside the disc.
        assert_eq!(law_residual(&tresca, &[0.0, 0.0], &[1.0, -1.0], 1e-12), 0.0);
        assert!(law_residual(&tresca, &[0.0, 0.0], &[2.0, 1.0], 1e-12) > 0.2);
        // Slip: ξ = −b w/|w|, right direction and size.
        assert!(
            law_residual(
                &PAPER,
                &[0.3, 0.4],
                &[-0.6 * PAPER.bound(0.5), -0.8 * PAPER.bound(0.5)],
                1e-12
            ) < 1e-12
        );
        assert!(
            law_residual(
                &PAPER,
                &[0.3, 0.4],
                &[0.6 * PAPER.bound(0.5), 0.8 * PAPER.bound(0.5)],
                1e-12
            ) > 1.0
        );
        // 2D: slip to the left gets a positive friction stress.
        assert!(law_residual(&PAPER, &[-0.1], &[PAPER.bound(0.1)], 1e-12) < 1e-12);
    }

    #[test]
    fn projection_gives_the_multiplier_bound() {
        let mut v = [3.0, 4.0];
        project_to_ball(&mut v, 1.0);
        assert!((v[0] - 0.6).abs() < 1e-15 && (v[1] - 0.8).abs() < 1e-15);
        let mut inside = [0.1];
        project_to_ball(&mut inside, 1.0);
        assert_eq!(inside, [0.1]);
        let mut neg = [-5.0];
        project_to_ball(&mut neg, 2.0);
        assert_eq!(neg, [-2.0]);
    }
}
