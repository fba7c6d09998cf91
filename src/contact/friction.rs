//! Friction laws −ξ ∈ ∂j_τ(w_τ) with j_τ(ξ) = ∫₀^|ξ| b(s) ds for a friction bound b(r) ≥ 0.
//!
//! For such a potential the Clarke subdifferential is ∂j_τ(0) = {|ζ| ≤ b(0)} and
//! ∂j_τ(w) = {b(|w|) w/|w|} for w ≠ 0 (eq. (83)): stick inside the disc of radius b(0), slip
//! with a friction stress of size b(|w|) against the slip direction. A decreasing b (velocity
//! weakening) makes j_τ nonconvex; sup −b' is then the constant m_τ of H(j_τ)(d).

use super::table::Table;
use crate::loads::{Expression, ExpressionError};

/// Where and when a law on Γ_C is evaluated: a contact node's position, the time and the
/// node's history (the slip distance s accumulated over the previous steps).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LawPoint {
    /// x_i.
    pub x: [f64; 3],
    /// t_n.
    pub t: f64,
    /// s_i = Σ_{m<n} k ‖w_τ,i^m‖: the slip distance before this step.
    pub slip_distance: f64,
}

/// A friction law given by its coefficient μ, so that the bound is b(r) = S μ(r) at slip rate
/// r = |w_τ| ≥ 0 for the scale S (a datum of x and t, evaluated by the caller).
///
/// Implement it for a law of your own; [`FrictionLaw::bound`] must be ≥ 0,
/// [`FrictionLaw::bound_derivative`] its derivative in r (the Newton solvers' slope) and
/// [`FrictionLaw::potential`] ∫₀^r of it (the descent's energy). The law may depend on x, t and
/// the slip distance, which stay fixed during a step.
pub trait FrictionLaw: Send + Sync + std::fmt::Debug {
    /// b(r) = S μ(r): the size of the friction stress when slipping at rate r.
    fn bound(&self, scale: f64, at: &LawPoint, r: f64) -> f64;
    /// b'(r).
    fn bound_derivative(&self, scale: f64, at: &LawPoint, r: f64) -> f64;
    /// j_τ as a function of r = |ξ|: ∫₀^r b(s) ds.
    fn potential(&self, scale: f64, at: &LawPoint, r: f64) -> f64;
    /// The law's name in the scenario and in summaries.
    fn name(&self) -> &'static str;
    /// (sup_r μ(r), sup_r max(0, −μ′(r))) at `at`: c_τ/S and m_τ/S of H(j_τ). The default
    /// samples r at 0 and at 400 geometric points from 10⁻⁹ to 10⁶ (exact for laws whose
    /// extremes lie at 0 or beyond the range; an estimate otherwise, which the report says).
    fn constants(&self, at: &LawPoint) -> (f64, f64) {
        sampled_constants(self, at)
    }
    /// Whether the law reads the slip distance (then the runs report it).
    fn uses_slip_distance(&self) -> bool {
        false
    }
    /// Whether μ is the same at every point and time (then its constants are computed once).
    fn uniform(&self) -> bool {
        true
    }
}

/// [`FrictionLaw::constants`] by sampling r.
pub fn sampled_constants<L: FrictionLaw + ?Sized>(law: &L, at: &LawPoint) -> (f64, f64) {
    let rates = std::iter::once(0.0).chain((0..400).map(|k| 1e-9 * 10f64.powf(15.0 * k as f64 / 399.0)));
    rates.fold((0.0f64, 0.0f64), |(c, m), r| {
        (c.max(law.bound(1.0, at, r)), m.max(-law.bound_derivative(1.0, at, r)))
    })
}

/// The paper's law (81), velocity weakening: μ(r) = (a − b) e^(−αr) + b, falling from a at
/// rest to b as the slip *rate* grows (LS-DYNA's μ = FD + (FS − FD) e^(−DC·v)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityWeakening {
    /// a = μ(0).
    pub a: f64,
    /// b = μ(∞).
    pub b: f64,
    /// α: the weakening rate.
    pub alpha: f64,
}

/// The former name of [`VelocityWeakening`]: the paper's law weakens with slip rate, and
/// "slip weakening" means weakening with slip distance ([`SlipDistanceWeakening`]).
#[deprecated(note = "the paper's law weakens with slip rate: use VelocityWeakening")]
pub type SlipWeakening = VelocityWeakening;

impl FrictionLaw for VelocityWeakening {
    fn bound(&self, scale: f64, _: &LawPoint, r: f64) -> f64 {
        scale * ((self.a - self.b) * (-self.alpha * r).exp() + self.b)
    }
    fn bound_derivative(&self, scale: f64, _: &LawPoint, r: f64) -> f64 {
        -scale * self.alpha * (self.a - self.b) * (-self.alpha * r).exp()
    }
    fn potential(&self, scale: f64, _: &LawPoint, r: f64) -> f64 {
        let decay = if self.alpha > 0.0 {
            (1.0 - (-self.alpha * r).exp()) / self.alpha
        } else {
            r
        };
        scale * ((self.a - self.b) * decay + self.b * r)
    }
    fn name(&self) -> &'static str {
        "velocity-weakening"
    }
    /// c = max(a, b); m = α (a − b) where a > b (the fall is steepest at rest).
    fn constants(&self, _: &LawPoint) -> (f64, f64) {
        (self.a.max(self.b), (self.alpha * (self.a - self.b)).max(0.0))
    }
}

/// Tresca friction: μ ≡ 1, the bound is the scale S (j_τ(ξ) = S|ξ|, convex).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tresca;

impl FrictionLaw for Tresca {
    fn bound(&self, scale: f64, _: &LawPoint, _r: f64) -> f64 {
        scale
    }
    fn bound_derivative(&self, _: f64, _: &LawPoint, _r: f64) -> f64 {
        0.0
    }
    fn potential(&self, scale: f64, _: &LawPoint, r: f64) -> f64 {
        scale * r
    }
    fn name(&self) -> &'static str {
        "tresca"
    }
    fn constants(&self, _: &LawPoint) -> (f64, f64) {
        (1.0, 0.0)
    }
}

/// Coulomb friction: a constant coefficient μ, the bound μ p with p the contact pressure
/// (used with [`super::NormalForce::Reaction`], which makes the scale the pressure; with a
/// prescribed scale S it is Tresca with the bound μ S).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coulomb {
    /// μ.
    pub coefficient: f64,
}

impl FrictionLaw for Coulomb {
    fn bound(&self, scale: f64, _: &LawPoint, _r: f64) -> f64 {
        self.coefficient * scale
    }
    fn bound_derivative(&self, _: f64, _: &LawPoint, _r: f64) -> f64 {
        0.0
    }
    fn potential(&self, scale: f64, _: &LawPoint, r: f64) -> f64 {
        self.coefficient * scale * r
    }
    fn name(&self) -> &'static str {
        "coulomb"
    }
    fn constants(&self, _: &LawPoint) -> (f64, f64) {
        (self.coefficient, 0.0)
    }
}

/// μ(r) from a table of coefficients at slip rates (a tribometer's curve): piecewise linear,
/// constant beyond the first and last rates ([`Table`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedFriction {
    /// μ against r.
    pub table: Table,
}

impl FrictionLaw for TabulatedFriction {
    fn bound(&self, scale: f64, _: &LawPoint, r: f64) -> f64 {
        scale * self.table.value(r)
    }
    fn bound_derivative(&self, scale: f64, _: &LawPoint, r: f64) -> f64 {
        scale * self.table.slope(r)
    }
    fn potential(&self, scale: f64, _: &LawPoint, r: f64) -> f64 {
        scale * self.table.integral(0.0, r)
    }
    fn name(&self) -> &'static str {
        "table"
    }
    fn constants(&self, _: &LawPoint) -> (f64, f64) {
        (self.table.max_value(), self.table.slopes().0)
    }
}

/// μ(r) as an expression of the slip rate r and of x, y, z, t. Its derivative in r is exact:
/// forward-mode automatic differentiation of the expression ([`Expression::derivative`]), for
/// every function, `abs` (0 at its kink), `min`, `max` (the first argument's derivative on a
/// tie) and `atan2` included.
#[derive(Debug, Clone)]
pub struct ExpressionFriction {
    coefficient: Expression,
    derivative: Expression,
}

impl ExpressionFriction {
    /// The law μ(r, x, y, z, t) = `coefficient`.
    pub fn new(coefficient: Expression) -> Self {
        let derivative = coefficient.derivative("r");
        ExpressionFriction {
            coefficient,
            derivative,
        }
    }

    /// The law of the text, an expression of r, x, y, z and t.
    pub fn parse(text: &str) -> Result<Self, ExpressionError> {
        Ok(Self::new(Expression::parse_with(text, &["r"])?))
    }

    /// μ(r).
    fn mu(&self, at: &LawPoint, r: f64) -> f64 {
        self.coefficient.eval_with(at.x, at.t, [r, 0.0])
    }

    /// The expression's text.
    pub fn text(&self) -> &str {
        self.coefficient.text()
    }
}

impl FrictionLaw for ExpressionFriction {
    fn bound(&self, scale: f64, at: &LawPoint, r: f64) -> f64 {
        scale * self.mu(at, r)
    }
    fn bound_derivative(&self, scale: f64, at: &LawPoint, r: f64) -> f64 {
        scale * self.derivative.eval_with(at.x, at.t, [r, 0.0])
    }
    /// ∫₀^r by Gauss–Legendre (5 points) on 16 equal panels.
    fn potential(&self, scale: f64, at: &LawPoint, r: f64) -> f64 {
        const NODES: [f64; 5] = [
            -0.906_179_845_938_664,
            -0.538_469_310_105_683,
            0.0,
            0.538_469_310_105_683,
            0.906_179_845_938_664,
        ];
        const WEIGHTS: [f64; 5] = [
            0.236_926_885_056_189,
            0.478_628_670_499_366,
            0.568_888_888_888_889,
            0.478_628_670_499_366,
            0.236_926_885_056_189,
        ];
        let panels = 16;
        let h = r / panels as f64;
        let sum: f64 = (0..panels)
            .flat_map(|p| {
                let mid = (p as f64 + 0.5) * h;
                NODES.iter().zip(WEIGHTS).map(move |(x, w)| (mid + 0.5 * h * x, w))
            })
            .map(|(s, w)| w * self.mu(at, s))
            .sum();
        scale * 0.5 * h * sum
    }
    fn name(&self) -> &'static str {
        "expression"
    }
    fn uniform(&self) -> bool {
        !["x", "y", "z", "t"].iter().any(|v| self.coefficient.uses(v))
    }
}

/// Slip weakening in the sense of contact and fault mechanics: μ falls linearly with the slip
/// *distance* s from μ_s to μ_d over D_c, μ = μ_s − (μ_s − μ_d) min(s/D_c, 1). s is the
/// history variable of the previous steps (explicit), so within a step the law is Tresca with
/// the bound S μ(s_i): convex, and m_τ = 0 for the step problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlipDistanceWeakening {
    /// μ_s, the static coefficient (s = 0).
    pub static_coefficient: f64,
    /// μ_d, the dynamic coefficient (s ≥ D_c).
    pub dynamic_coefficient: f64,
    /// D_c, the critical slip distance.
    pub distance: f64,
}

impl SlipDistanceWeakening {
    /// μ(s).
    pub fn coefficient(&self, s: f64) -> f64 {
        let (mu_s, mu_d) = (self.static_coefficient, self.dynamic_coefficient);
        mu_s - (mu_s - mu_d) * (s / self.distance).min(1.0)
    }
}

impl FrictionLaw for SlipDistanceWeakening {
    fn bound(&self, scale: f64, at: &LawPoint, _r: f64) -> f64 {
        scale * self.coefficient(at.slip_distance)
    }
    fn bound_derivative(&self, _: f64, _: &LawPoint, _r: f64) -> f64 {
        0.0
    }
    fn potential(&self, scale: f64, at: &LawPoint, r: f64) -> f64 {
        scale * self.coefficient(at.slip_distance) * r
    }
    fn name(&self) -> &'static str {
        "slip-distance-weakening"
    }
    fn constants(&self, _: &LawPoint) -> (f64, f64) {
        (self.static_coefficient.max(self.dynamic_coefficient), 0.0)
    }
    fn uses_slip_distance(&self) -> bool {
        true
    }
    fn uniform(&self) -> bool {
        false
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

/// Residual of the nodal law −ξ ∈ ∂j_τ(w) at one node with bound b(r) = `bound(r)`: zero
/// exactly when the law holds.
///
/// Stick (|w| ≤ `slip_tol`): how far |ξ| exceeds b(0). Slip: |ξ + b(|w|) w/|w||.
pub fn law_residual(bound: impl Fn(f64) -> f64, w: &[f64], xi: &[f64], slip_tol: f64) -> f64 {
    let speed = w.iter().map(|x| x * x).sum::<f64>().sqrt();
    if speed <= slip_tol {
        let size = xi.iter().map(|x| x * x).sum::<f64>().sqrt();
        (size - bound(0.0)).max(0.0)
    } else {
        let b = bound(speed);
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

    const PAPER: VelocityWeakening = VelocityWeakening {
        a: 1.0,
        b: 0.2,
        alpha: 100.0,
    };
    const S: f64 = 150.0;
    const AT: LawPoint = LawPoint {
        x: [0.0; 3],
        t: 0.0,
        slip_distance: 0.0,
    };

    fn bound_of<'l>(law: &'l dyn FrictionLaw) -> impl Fn(f64) -> f64 + 'l {
        move |r| law.bound(S, &AT, r)
    }

    #[test]
    fn velocity_weakening_values() {
        assert!((PAPER.bound(S, &AT, 0.0) - 150.0).abs() < 1e-12);
        assert!((PAPER.bound(S, &AT, 1.0) - 30.0).abs() < 1e-10);
        assert!((PAPER.bound_derivative(S, &AT, 0.0) + 150.0 * 100.0 * 0.8).abs() < 1e-9);
        // j_τ' = b: central difference of the potential.
        let (r, h) = (0.013, 1e-6);
        let fd = (PAPER.potential(S, &AT, r + h) - PAPER.potential(S, &AT, r - h)) / (2.0 * h);
        assert!((fd - PAPER.bound(S, &AT, r)).abs() < 1e-6);
        assert_eq!(PAPER.potential(S, &AT, 0.0), 0.0);
        // m_τ = α (a − b) per unit scale, and the sampled estimate finds it.
        assert_eq!(PAPER.constants(&AT), (1.0, 80.0));
        let (c, m) = sampled_constants(&PAPER, &AT);
        assert!((c - 1.0).abs() < 1e-12 && (m - 80.0).abs() < 1e-6, "{c} {m}");
    }

    #[test]
    fn the_paper_law_as_an_expression_and_a_table() {
        let expression = ExpressionFriction::parse("(1 - 0.2)*exp(-100*r) + 0.2").unwrap();
        let rates: Vec<f64> = (0..=8000).map(|k| 0.4 * k as f64 / 8000.0).collect();
        let mu = rates.iter().map(|&r| PAPER.bound(1.0, &AT, r)).collect();
        let table = TabulatedFriction {
            table: Table::new(rates, mu, ["slip_rate", "coefficient"]).unwrap(),
        };
        for r in [0.0, 1e-4, 0.0137, 0.05, 0.3] {
            let exact = PAPER.bound(S, &AT, r);
            assert!((expression.bound(S, &AT, r) - exact).abs() <= 1e-12 * exact);
            let slope = PAPER.bound_derivative(S, &AT, r);
            assert!((expression.bound_derivative(S, &AT, r) - slope).abs() <= 1e-10 * slope.abs().max(1.0));
            let p = PAPER.potential(S, &AT, r);
            assert!((expression.potential(S, &AT, r) - p).abs() <= 1e-10 * p.max(1.0), "{r}");
            // Piecewise linear through 2001 points 5·10⁻⁵ apart: error ≤ h² max|b''|/8.
            let interpolation = 5e-5f64.powi(2) * S * 0.8 * 1e4 / 8.0;
            assert!((table.bound(S, &AT, r) - exact).abs() <= interpolation, "{r}");
        }
        // Beyond the table's last rate (0.4) μ stays at its last value.
        assert_eq!(table.bound(S, &AT, 5.0), table.bound(S, &AT, 0.4));
        // abs, which exmex did not differentiate: the exact slope, at r = 0 the right one.
        let kinked = ExpressionFriction::parse("0.8*exp(-100*abs(r)) + 0.2").unwrap();
        for r in [0.0, 1e-9, 0.002, 0.03, 0.3] {
            let slope = PAPER.bound_derivative(S, &AT, r);
            let error = (kinked.bound_derivative(S, &AT, r) - slope).abs();
            assert!(error <= 1e-14 * slope.abs(), "{r}: {error}");
        }
    }

    #[test]
    fn slip_distance_weakening_reads_the_history() {
        let law = SlipDistanceWeakening {
            static_coefficient: 0.6,
            dynamic_coefficient: 0.4,
            distance: 0.01,
        };
        let at = |s| LawPoint { slip_distance: s, ..AT };
        assert_eq!(law.bound(100.0, &at(0.0), 3.0), 60.0);
        assert!((law.bound(100.0, &at(0.005), 0.0) - 50.0).abs() < 1e-12);
        assert!((law.bound(100.0, &at(0.5), 0.0) - 40.0).abs() < 1e-12);
        assert_eq!(law.bound_derivative(100.0, &at(0.005), 1.0), 0.0);
        assert!(law.uses_slip_distance() && !PAPER.uses_slip_distance());
    }

    #[test]
    fn local_law_stick_and_slip() {
        let tresca = |_r: f64| 2.0;
        // Stick: any ξ inside the disc.
        assert_eq!(law_residual(tresca, &[0.0, 0.0], &[1.0, -1.0], 1e-12), 0.0);
        assert!(law_residual(tresca, &[0.0, 0.0], &[2.0, 1.0], 1e-12) > 0.2);
        // Slip: ξ = −b w/|w|, right direction and size.
        let b = bound_of(&PAPER);
        assert!(law_residual(&b, &[0.3, 0.4], &[-0.6 * b(0.5), -0.8 * b(0.5)], 1e-12) < 1e-12);
        assert!(law_residual(&b, &[0.3, 0.4], &[0.6 * b(0.5), 0.8 * b(0.5)], 1e-12) > 1.0);
        // 2D: slip to the left gets a positive friction stress.
        assert!(law_residual(&b, &[-0.1], &[b(0.1)], 1e-12) < 1e-12);
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
