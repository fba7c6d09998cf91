//! Second-order jets in the plane: a value with its gradient and Hessian in (x, y), carried
//! through arithmetic by the chain rule (forward-mode automatic differentiation).
//!
//! The manufactured solutions write u, u̇, ü and θ, θ̇ once as formulas in jets; the data of the
//! problem, f₀ = ρü − Div σ, g = ρc_p θ̇ − div(K∇θ) − c div u̇ and the tractions σν, then come
//! from exact derivatives instead of hand-derived ones that could silently disagree.

use std::ops::{Add, Mul, Neg, Sub};

/// f(x, y) with ∇f and ∇²f at one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jet {
    /// f.
    pub value: f64,
    /// (∂_x f, ∂_y f).
    pub grad: [f64; 2],
    /// ∂_i ∂_j f.
    pub hess: [[f64; 2]; 2],
}

impl Jet {
    /// A constant.
    pub fn constant(value: f64) -> Self {
        Jet {
            value,
            grad: [0.0; 2],
            hess: [[0.0; 2]; 2],
        }
    }

    /// The coordinate function x at x = `x`.
    pub fn x(x: f64) -> Self {
        Jet {
            value: x,
            grad: [1.0, 0.0],
            hess: [[0.0; 2]; 2],
        }
    }

    /// The coordinate function y at y = `y`.
    pub fn y(y: f64) -> Self {
        Jet {
            value: y,
            grad: [0.0, 1.0],
            hess: [[0.0; 2]; 2],
        }
    }

    /// φ ∘ f from φ(v), φ'(v), φ''(v) at v = f:
    /// ∇(φ∘f) = φ' ∇f, ∇²(φ∘f) = φ' ∇²f + φ'' ∇f ∇fᵀ.
    pub fn compose(self, phi: f64, dphi: f64, ddphi: f64) -> Self {
        let mut hess = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                hess[i][j] = dphi * self.hess[i][j] + ddphi * self.grad[i] * self.grad[j];
            }
        }
        Jet {
            value: phi,
            grad: [dphi * self.grad[0], dphi * self.grad[1]],
            hess,
        }
    }

    /// sin f.
    pub fn sin(self) -> Self {
        let (s, c) = self.value.sin_cos();
        self.compose(s, c, -s)
    }

    /// cos f.
    pub fn cos(self) -> Self {
        let (s, c) = self.value.sin_cos();
        self.compose(c, -s, -c)
    }

    /// e^f.
    pub fn exp(self) -> Self {
        let e = self.value.exp();
        self.compose(e, e, e)
    }

    /// fⁿ for an integer n ≥ 0.
    pub fn powi(self, n: i32) -> Self {
        let v = self.value;
        let nf = n as f64;
        let d = if n >= 1 { nf * v.powi(n - 1) } else { 0.0 };
        let dd = if n >= 2 { nf * (nf - 1.0) * v.powi(n - 2) } else { 0.0 };
        self.compose(v.powi(n), d, dd)
    }

    /// (f)₊ⁿ = max(f, 0)ⁿ for n ≥ 2: C^{n−1}, so ∇ and ∇² are exact on both sides of f = 0.
    pub fn positive_part_pow(self, n: i32) -> Self {
        debug_assert!(n >= 2, "the positive part needs n ≥ 2 for a Hessian");
        if self.value <= 0.0 {
            return Jet::constant(0.0);
        }
        self.powi(n)
    }

    /// Δf = ∂_xx f + ∂_yy f.
    pub fn laplacian(&self) -> f64 {
        self.hess[0][0] + self.hess[1][1]
    }
}

impl Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        let mut hess = self.hess;
        for i in 0..2 {
            for j in 0..2 {
                hess[i][j] += o.hess[i][j];
            }
        }
        Jet {
            value: self.value + o.value,
            grad: [self.grad[0] + o.grad[0], self.grad[1] + o.grad[1]],
            hess,
        }
    }
}

impl Neg for Jet {
    type Output = Jet;
    fn neg(self) -> Jet {
        self * -1.0
    }
}

impl Sub for Jet {
    type Output = Jet;
    fn sub(self, o: Jet) -> Jet {
        self + (-o)
    }
}

impl Mul for Jet {
    type Output = Jet;
    /// (fg)'' = f''g + f'g'ᵀ + g'f'ᵀ + fg''.
    fn mul(self, o: Jet) -> Jet {
        let mut hess = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                hess[i][j] = self.hess[i][j] * o.value
                    + self.grad[i] * o.grad[j]
                    + o.grad[i] * self.grad[j]
                    + self.value * o.hess[i][j];
            }
        }
        Jet {
            value: self.value * o.value,
            grad: [
                self.grad[0] * o.value + self.value * o.grad[0],
                self.grad[1] * o.value + self.value * o.grad[1],
            ],
            hess,
        }
    }
}

impl Mul<f64> for Jet {
    type Output = Jet;
    fn mul(self, s: f64) -> Jet {
        Jet {
            value: self.value * s,
            grad: [self.grad[0] * s, self.grad[1] * s],
            hess: [
                [self.hess[0][0] * s, self.hess[0][1] * s],
                [self.hess[1][0] * s, self.hess[1][1] * s],
            ],
        }
    }
}

impl Add<f64> for Jet {
    type Output = Jet;
    fn add(self, s: f64) -> Jet {
        Jet {
            value: self.value + s,
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A composite function and its derivatives by central differences.
    fn sample(x: f64, y: f64) -> Jet {
        let (x, y) = (Jet::x(x), Jet::y(y));
        (x * y.sin() + (x * 0.5 - y).exp() * 0.3).cos() * (x + 1.0).powi(3) + (x - y * 2.0 + 0.1).positive_part_pow(3)
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let (x, y, h) = (0.7, 0.2, 1e-4);
        let f = |x: f64, y: f64| sample(x, y).value;
        let jet = sample(x, y);
        let gx = (f(x + h, y) - f(x - h, y)) / (2.0 * h);
        let gy = (f(x, y + h) - f(x, y - h)) / (2.0 * h);
        let hxx = (f(x + h, y) - 2.0 * f(x, y) + f(x - h, y)) / (h * h);
        let hyy = (f(x, y + h) - 2.0 * f(x, y) + f(x, y - h)) / (h * h);
        let hxy = (f(x + h, y + h) - f(x + h, y - h) - f(x - h, y + h) + f(x - h, y - h)) / (4.0 * h * h);
        let scale = 1.0 + jet.value.abs();
        assert!((jet.grad[0] - gx).abs() < 1e-6 * scale, "{} vs {gx}", jet.grad[0]);
        assert!((jet.grad[1] - gy).abs() < 1e-6 * scale);
        assert!(
            (jet.hess[0][0] - hxx).abs() < 1e-4 * scale,
            "{} vs {hxx}",
            jet.hess[0][0]
        );
        assert!((jet.hess[1][1] - hyy).abs() < 1e-4 * scale);
        assert!((jet.hess[0][1] - hxy).abs() < 1e-4 * scale);
        assert_eq!(jet.hess[0][1], jet.hess[1][0]);
    }

    #[test]
    fn positive_part_vanishes_with_its_derivatives() {
        let j = (Jet::x(0.3) + -0.5).positive_part_pow(3);
        assert_eq!(j, Jet::constant(0.0));
        let j = (Jet::x(0.7) + -0.5).positive_part_pow(3);
        assert!((j.value - 0.008).abs() < 1e-15 && (j.grad[0] - 0.12).abs() < 1e-14);
        assert!((j.hess[0][0] - 1.2).abs() < 1e-13);
    }
}
