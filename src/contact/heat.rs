//! Heat exchange with the foundation and frictional heating on Γ_C, eq. (9):
//! −K∇θ·ν ∈ ∂j(θ) − h_τ(‖u̇_τ‖).
//!
//! H(j)(d) makes ∂j single-valued and Lipschitz but, by Remark 3, possibly nonmonotone. An
//! affine ∂j = k_e (θ − θ_R) enters the step matrix as a Robin term (consistent boundary mass)
//! and a load; any other ∂j is evaluated at the contact nodes (nodal quadrature, as the friction)
//! and iterated with the step ([`crate::step`]).

use super::friction::LawPoint;
use super::table::Table;
use crate::loads::{Expression, ExpressionError};

/// A heat-exchange law: ∂j(θ), the flux into the foundation at temperature θ.
pub trait HeatExchange: Send + Sync + std::fmt::Debug {
    /// ∂j(θ).
    fn flux(&self, at: &LawPoint, theta: f64) -> f64;
    /// (k_e, θ_R) where ∂j is affine, k_e (θ − θ_R); `None` otherwise.
    fn robin(&self) -> Option<(f64, f64)>;
    /// The law's name in the scenario and in summaries.
    fn name(&self) -> &'static str;
    /// m_θ = sup_θ |(∂j)′(θ)| where the law knows it exactly, else the largest difference
    /// quotient on θ ∈ [−10³, 10⁴] in steps of 0.1.
    fn lipschitz(&self, at: &LawPoint) -> f64 {
        const STEPS: usize = 110_000;
        let theta = |k: usize| -1e3 + 11e3 * k as f64 / STEPS as f64;
        (1..=STEPS)
            .map(|k| ((self.flux(at, theta(k)) - self.flux(at, theta(k - 1))) / (theta(k) - theta(k - 1))).abs())
            .fold(0.0, f64::max)
    }
}

/// The paper's quadratic law j(r) = ½ k_e (r − θ_R)²: ∂j(θ) = k_e (θ − θ_R), linear.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadraticExchange {
    /// k_e, the exchange coefficient.
    pub coefficient: f64,
    /// θ_R, the foundation temperature.
    pub foundation_temperature: f64,
}

impl QuadraticExchange {
    /// j(θ).
    pub fn potential(&self, theta: f64) -> f64 {
        0.5 * self.coefficient * (theta - self.foundation_temperature).powi(2)
    }
}

impl HeatExchange for QuadraticExchange {
    fn flux(&self, _: &LawPoint, theta: f64) -> f64 {
        self.coefficient * (theta - self.foundation_temperature)
    }
    fn robin(&self) -> Option<(f64, f64)> {
        Some((self.coefficient, self.foundation_temperature))
    }
    fn name(&self) -> &'static str {
        "linear"
    }
    fn lipschitz(&self, _: &LawPoint) -> f64 {
        self.coefficient.abs()
    }
}

/// ∂j(θ) from a table of fluxes at temperatures: piecewise linear, constant beyond the ends.
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedExchange {
    /// ∂j against θ.
    pub table: Table,
}

impl HeatExchange for TabulatedExchange {
    fn flux(&self, _: &LawPoint, theta: f64) -> f64 {
        self.table.value(theta)
    }
    fn robin(&self) -> Option<(f64, f64)> {
        None
    }
    fn name(&self) -> &'static str {
        "table"
    }
    fn lipschitz(&self, _: &LawPoint) -> f64 {
        self.table.slopes().1
    }
}

/// ∂j(θ) as an expression of `theta` and x, y, z, t.
#[derive(Debug, Clone)]
pub struct ExpressionExchange {
    flux: Expression,
}

impl ExpressionExchange {
    /// The law of the text, an expression of theta, x, y, z and t.
    pub fn parse(text: &str) -> Result<Self, ExpressionError> {
        Ok(ExpressionExchange {
            flux: Expression::parse_with(text, &["theta"])?,
        })
    }
}

impl HeatExchange for ExpressionExchange {
    fn flux(&self, at: &LawPoint, theta: f64) -> f64 {
        self.flux.eval_with(at.x, at.t, [0.0, theta])
    }
    fn robin(&self) -> Option<(f64, f64)> {
        None
    }
    fn name(&self) -> &'static str {
        "expression"
    }
}

/// Frictional heating h_τ(x, t, r) ≥ 0 at slip rate r.
pub trait FrictionalHeating: Send + Sync + std::fmt::Debug {
    /// h_τ(x, t, r).
    fn heat(&self, at: &LawPoint, r: f64) -> f64;
    /// ∂h_τ/∂r (the Newton solvers' slope).
    fn heat_derivative(&self, at: &LawPoint, r: f64) -> f64;
    /// h_τ(to) − h_τ(from) (a law may compute it more exactly than the difference).
    fn heat_change(&self, at: &LawPoint, from: f64, to: f64) -> f64 {
        self.heat(at, to) - self.heat(at, from)
    }
    /// L_τ = sup_r |∂h_τ/∂r| at `at`, sampled as the friction laws' constants where not known.
    fn lipschitz(&self, at: &LawPoint) -> f64 {
        let rates = std::iter::once(0.0).chain((0..400).map(|k| 1e-9 * 10f64.powf(15.0 * k as f64 / 399.0)));
        rates.map(|r| self.heat_derivative(at, r).abs()).fold(0.0, f64::max)
    }
}

/// h_τ(t, r) = λ(t) r with λ(t) = λ₀ + λ₁ t affine in t (the paper: λ = 10 t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearHeating {
    /// λ₀.
    pub constant: f64,
    /// λ₁.
    pub rate: f64,
}

impl LinearHeating {
    /// λ(t) = constant + rate · t.
    pub fn affine(constant: f64, rate: f64) -> Self {
        LinearHeating { constant, rate }
    }
}

impl FrictionalHeating for LinearHeating {
    fn heat(&self, at: &LawPoint, r: f64) -> f64 {
        (self.constant + self.rate * at.t) * r
    }
    fn heat_derivative(&self, at: &LawPoint, _r: f64) -> f64 {
        self.constant + self.rate * at.t
    }
    fn heat_change(&self, at: &LawPoint, from: f64, to: f64) -> f64 {
        (self.constant + self.rate * at.t) * (to - from)
    }
    fn lipschitz(&self, at: &LawPoint) -> f64 {
        (self.constant + self.rate * at.t).abs()
    }
}

/// h_τ(x, t, r) as an expression of r and x, y, z, t; its r-derivative exact, by automatic
/// differentiation as [`super::ExpressionFriction`]'s.
#[derive(Debug, Clone)]
pub struct ExpressionHeating {
    value: Expression,
    derivative: Expression,
}

impl ExpressionHeating {
    /// The law of the text, an expression of r, x, y, z and t.
    pub fn parse(text: &str) -> Result<Self, ExpressionError> {
        let value = Expression::parse_with(text, &["r"])?;
        let derivative = value.derivative("r");
        Ok(ExpressionHeating { value, derivative })
    }
}

impl FrictionalHeating for ExpressionHeating {
    fn heat(&self, at: &LawPoint, r: f64) -> f64 {
        self.value.eval_with(at.x, at.t, [r, 0.0])
    }
    fn heat_derivative(&self, at: &LawPoint, r: f64) -> f64 {
        self.derivative.eval_with(at.x, at.t, [r, 0.0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_heat_laws() {
        let at = LawPoint {
            t: 0.5,
            ..Default::default()
        };
        let j = QuadraticExchange {
            coefficient: 2.0,
            foundation_temperature: 0.0,
        };
        assert_eq!(j.flux(&at, 25.0), 50.0);
        assert_eq!(j.potential(3.0), 9.0);
        assert_eq!(j.lipschitz(&at), 2.0);
        let h = LinearHeating::affine(0.0, 10.0);
        assert!((h.heat(&at, 0.2) - 1.0).abs() < 1e-15);
        assert_eq!(h.heat_derivative(&at, 0.2), 5.0);
        let e = ExpressionHeating::parse("10*t*r").unwrap();
        assert!((e.heat(&at, 0.2) - 1.0).abs() < 1e-15 && (e.heat_derivative(&at, 0.2) - 5.0).abs() < 1e-14);
    }

    #[test]
    fn a_nonmonotone_exchange_and_its_constant() {
        // ∂j(θ) = θ/2 − 5 sin(θ/5): slope ½ − cos(θ/5) ∈ [−½, 3/2], nonmonotone.
        let j = ExpressionExchange::parse("0.5*theta - 5*sin(theta/5)").unwrap();
        let at = LawPoint::default();
        assert!((j.flux(&at, 0.0)).abs() < 1e-15);
        assert!(j.flux(&at, 2.0) < 0.0, "falls near 0");
        assert!((j.lipschitz(&at) - 1.5).abs() < 1e-3);
        assert!(j.robin().is_none());
        assert!(ExpressionExchange::parse("r*theta").is_err());
    }
}
