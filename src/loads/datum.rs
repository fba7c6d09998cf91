//! Data with n components: constant, affine in t, or expressions of x, y, z, t.

use super::expression::{Expression, ExpressionError};

/// A piece of data with n components (a scalar is n = 1): a force density, a traction, a
/// pressure, a heat source, an initial field.
#[derive(Debug, Clone, PartialEq)]
pub enum Datum {
    /// f(x, t) = c.
    Constant(Vec<f64>),
    /// f(x, t) = c + t r, componentwise (`constant` and `rate` have the same length).
    Affine { constant: Vec<f64>, rate: Vec<f64> },
    /// f_c(x, t) given by one expression per component.
    Expressions(Vec<Expression>),
}

impl Datum {
    /// A constant datum.
    pub fn constant(values: Vec<f64>) -> Datum {
        Datum::Constant(values)
    }

    /// A constant scalar.
    pub fn scalar(value: f64) -> Datum {
        Datum::Constant(vec![value])
    }

    /// c + t r. Lengths are checked where the datum is used ([`super::Load::new`],
    /// [`super::nodal_values`]).
    pub fn affine(constant: Vec<f64>, rate: Vec<f64>) -> Datum {
        Datum::Affine { constant, rate }
    }

    /// One expression per component.
    pub fn expressions<S: AsRef<str>>(texts: &[S]) -> Result<Datum, ExpressionError> {
        let parsed = texts
            .iter()
            .map(|t| Expression::parse(t.as_ref()))
            .collect::<Result<_, _>>()?;
        Ok(Datum::Expressions(parsed))
    }

    /// A scalar expression.
    pub fn expression(text: &str) -> Result<Datum, ExpressionError> {
        Ok(Datum::Expressions(vec![Expression::parse(text)?]))
    }

    /// Number of components n.
    pub fn n_components(&self) -> usize {
        match self {
            Datum::Constant(c) | Datum::Affine { constant: c, .. } => c.len(),
            Datum::Expressions(e) => e.len(),
        }
    }

    /// Writes f(x, t) into `out` (length n).
    #[inline]
    pub fn eval(&self, x: [f64; 3], t: f64, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.n_components());
        match self {
            Datum::Constant(c) => out.copy_from_slice(c),
            Datum::Affine { constant, rate } => {
                for ((o, c), r) in out.iter_mut().zip(constant).zip(rate) {
                    *o = c + t * r;
                }
            }
            Datum::Expressions(e) => {
                for (o, e) in out.iter_mut().zip(e) {
                    *o = e.eval(x, t);
                }
            }
        }
    }

    /// Whether f depends on the point.
    pub fn uses_space(&self) -> bool {
        match self {
            Datum::Constant(_) | Datum::Affine { .. } => false,
            Datum::Expressions(e) => e.iter().any(Expression::uses_space),
        }
    }

    /// Whether f depends on t (an affine datum with a zero rate does not).
    pub fn uses_time(&self) -> bool {
        match self {
            Datum::Constant(_) => false,
            Datum::Affine { rate, .. } => rate.iter().any(|&r| r != 0.0),
            Datum::Expressions(e) => e.iter().any(Expression::uses_time),
        }
    }

    /// The lengths of an affine datum's constant and rate, when they differ.
    pub(super) fn affine_mismatch(&self) -> Option<(usize, usize)> {
        match self {
            Datum::Affine { constant, rate } if constant.len() != rate.len() => Some((constant.len(), rate.len())),
            _ => None,
        }
    }
}

impl From<f64> for Datum {
    fn from(value: f64) -> Datum {
        Datum::scalar(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_evaluate_and_report_dependencies() {
        let mut out = [0.0; 2];
        let c = Datum::constant(vec![1.0, -2.0]);
        c.eval([0.0; 3], 5.0, &mut out);
        assert_eq!(out, [1.0, -2.0]);
        assert!(!c.uses_space() && !c.uses_time());

        let a = Datum::affine(vec![3.0, 0.0], vec![2.0, -1.0]);
        a.eval([0.0; 3], 0.5, &mut out);
        assert_eq!(out, [4.0, -0.5]);
        assert!(!a.uses_space() && a.uses_time());
        assert!(!Datum::affine(vec![1.0], vec![0.0]).uses_time());

        let e = Datum::expressions(&["x*t", "0"]).unwrap();
        e.eval([2.0, 0.0, 0.0], 3.0, &mut out);
        assert_eq!(out, [6.0, 0.0]);
        assert!(e.uses_space() && e.uses_time());
        assert_eq!(e.n_components(), 2);
        assert_eq!(Datum::from(4.0).n_components(), 1);
    }

    #[test]
    fn bad_expression_is_reported() {
        assert!(matches!(
            Datum::expressions(&["x", "y +"]),
            Err(ExpressionError::Parse { text, .. }) if text == "y +"
        ));
    }
}
