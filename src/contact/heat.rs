//! Heat exchange with the foundation and frictional heating on Γ_C, eq. (9):
//! −K∇θ·ν ∈ ∂j(θ) − h_τ(‖u̇_τ‖).

/// A heat-exchange potential j whose derivative is affine, ∂j(θ) = k_e (θ − θ_R).
///
/// H(j)(d) makes ∂j single-valued and Lipschitz (Remark 3); an affine ∂j enters the step matrix
/// as a Robin term k_e ∫_ΓC θ η and a load k_e θ_R ∫_ΓC η, assembled with the consistent
/// boundary mass.
pub trait HeatExchange: Send + Sync + std::fmt::Debug {
    /// j(r).
    fn potential(&self, r: f64) -> f64;
    /// ∂j(r).
    fn derivative(&self, r: f64) -> f64;
    /// (k_e, θ_R) of the affine derivative.
    fn robin(&self) -> (f64, f64);
}

/// The paper's quadratic law j(r) = ½ k_e (r − θ_R)².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadraticExchange {
    /// k_e, the exchange coefficient.
    pub coefficient: f64,
    /// θ_R, the foundation temperature.
    pub foundation_temperature: f64,
}

impl HeatExchange for QuadraticExchange {
    fn potential(&self, r: f64) -> f64 {
        0.5 * self.coefficient * (r - self.foundation_temperature).powi(2)
    }
    fn derivative(&self, r: f64) -> f64 {
        self.coefficient * (r - self.foundation_temperature)
    }
    fn robin(&self) -> (f64, f64) {
        (self.coefficient, self.foundation_temperature)
    }
}

/// Frictional heating h_τ(t, r) ≥ 0 at slip rate r.
pub trait FrictionalHeating: Send + Sync + std::fmt::Debug {
    /// h_τ(t, r).
    fn heat(&self, t: f64, r: f64) -> f64;
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
    fn heat(&self, t: f64, r: f64) -> f64 {
        (self.constant + self.rate * t) * r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_heat_laws() {
        let j = QuadraticExchange {
            coefficient: 2.0,
            foundation_temperature: 0.0,
        };
        assert_eq!(j.derivative(25.0), 50.0);
        assert_eq!(j.potential(3.0), 9.0);
        let h = LinearHeating::affine(0.0, 10.0);
        assert!((h.heat(0.5, 0.2) - 1.0).abs() < 1e-15);
    }
}
