//! A function of one variable given by a table of values: piecewise linear between the points,
//! constant beyond the first and the last.
//!
//! Piecewise linear rather than a monotone cubic (Fritsch–Carlson): it keeps every sign of the
//! data's slopes, so a measured μ(v) that weakens and then strengthens stays exactly as measured,
//! its m_τ is the steepest segment's fall (read off the table, not bounded), and its potential
//! ∫μ is exact. The price is a slope that jumps at the points, which the semismooth Newton
//! solvers take like the kinks of the friction law itself.

/// y(x) through the points (x_k, y_k), x strictly increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    x: Vec<f64>,
    y: Vec<f64>,
    /// ∫_{x_0}^{x_k} y, at each point.
    integral: Vec<f64>,
}

/// Why a table is refused: the column and the entry.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TableError {
    #[error("the two columns have {x} and {y} entries (expected the same number, at least one)")]
    Lengths { x: usize, y: usize },
    #[error("entry {index} of the {column} column is {value} (expected a finite number)")]
    NotFinite {
        column: &'static str,
        index: usize,
        value: f64,
    },
    #[error("entry {index} of the {column} column is {value}, not above the entry before it, {before} (expected strictly increasing values)")]
    NotIncreasing {
        column: &'static str,
        index: usize,
        value: f64,
        before: f64,
    },
    #[error("entry {index} of the {column} column is {value} (expected a non-negative value)")]
    Negative {
        column: &'static str,
        index: usize,
        value: f64,
    },
}

impl TableError {
    /// The column the error is about (`None`: the two columns' lengths).
    pub fn column(&self) -> Option<&'static str> {
        match self {
            TableError::Lengths { .. } => None,
            TableError::NotFinite { column, .. }
            | TableError::NotIncreasing { column, .. }
            | TableError::Negative { column, .. } => Some(column),
        }
    }
}

impl Table {
    /// The table through (x_k, y_k); `names` are the two columns' names for errors.
    pub fn new(x: Vec<f64>, y: Vec<f64>, names: [&'static str; 2]) -> Result<Table, TableError> {
        if x.len() != y.len() || x.is_empty() {
            return Err(TableError::Lengths { x: x.len(), y: y.len() });
        }
        for (column, values) in names.iter().zip([&x, &y]) {
            if let Some((index, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(TableError::NotFinite { column, index, value });
            }
        }
        if let Some(k) = (1..x.len()).find(|&k| x[k] <= x[k - 1]) {
            return Err(TableError::NotIncreasing {
                column: names[0],
                index: k,
                value: x[k],
                before: x[k - 1],
            });
        }
        let mut integral = vec![0.0; x.len()];
        for k in 1..x.len() {
            integral[k] = integral[k - 1] + 0.5 * (y[k] + y[k - 1]) * (x[k] - x[k - 1]);
        }
        Ok(Table { x, y, integral })
    }

    /// Refuses a negative value in the second column (a friction coefficient).
    pub fn non_negative(self, column: &'static str) -> Result<Table, TableError> {
        match self.y.iter().enumerate().find(|(_, v)| **v < 0.0) {
            Some((index, &value)) => Err(TableError::Negative { column, index, value }),
            None => Ok(self),
        }
    }

    /// The segment k with x_k ≤ x < x_{k+1} (`None` outside [x_0, x_last)).
    fn segment(&self, x: f64) -> Option<usize> {
        let k = self.x.partition_point(|&xk| xk <= x);
        (k >= 1 && k < self.x.len()).then(|| k - 1)
    }

    /// y(x).
    pub fn value(&self, x: f64) -> f64 {
        match self.segment(x) {
            Some(k) => self.y[k] + self.slope_of(k) * (x - self.x[k]),
            None if x < self.x[0] => self.y[0],
            None => self.y[self.y.len() - 1],
        }
    }

    /// y′(x): the slope of the segment holding x (the right one at a point), 0 outside.
    pub fn slope(&self, x: f64) -> f64 {
        self.segment(x).map_or(0.0, |k| self.slope_of(k))
    }

    /// ∫_{a}^{x} y for the start a given (any, e.g. 0 below the first point).
    pub fn integral(&self, from: f64, to: f64) -> f64 {
        self.primitive(to) - self.primitive(from)
    }

    /// A primitive: ∫_{x_0}^{x} y, extended by the constants outside.
    fn primitive(&self, x: f64) -> f64 {
        match self.segment(x) {
            Some(k) => self.integral[k] + 0.5 * (self.y[k] + self.value(x)) * (x - self.x[k]),
            None if x < self.x[0] => self.y[0] * (x - self.x[0]),
            None => {
                let last = self.x.len() - 1;
                self.integral[last] + self.y[last] * (x - self.x[last])
            }
        }
    }

    fn slope_of(&self, k: usize) -> f64 {
        (self.y[k + 1] - self.y[k]) / (self.x[k + 1] - self.x[k])
    }

    /// The largest value.
    pub fn max_value(&self) -> f64 {
        self.y.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v))
    }

    /// The steepest fall, max(0, −y′), and the largest |y′| over the segments.
    pub fn slopes(&self) -> (f64, f64) {
        (0..self.x.len() - 1).fold((0.0, 0.0), |(fall, steep), k| {
            let s = self.slope_of(k);
            (f64::max(fall, -s), f64::max(steep, s.abs()))
        })
    }

    /// The points' abscissae and values.
    pub fn points(&self) -> (&[f64], &[f64]) {
        (&self.x, &self.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> Table {
        Table::new(vec![0.0, 1.0, 3.0], vec![1.0, 0.5, 0.5], ["x", "y"]).unwrap()
    }

    #[test]
    fn values_slopes_and_integrals() {
        let t = table();
        assert_eq!(t.value(-1.0), 1.0);
        assert_eq!(t.value(0.5), 0.75);
        assert_eq!(t.value(2.0), 0.5);
        assert_eq!(t.value(10.0), 0.5);
        assert_eq!(t.slope(0.5), -0.5);
        assert_eq!(t.slope(1.0), 0.0);
        assert_eq!(t.slope(5.0), 0.0);
        // ∫_0^0.5 = 0.5 (1 + 0.75)/2; ∫_0^5 = 0.75 + 1.0 + 1.0.
        assert!((t.integral(0.0, 0.5) - 0.4375).abs() < 1e-15);
        assert!((t.integral(0.0, 5.0) - 2.75).abs() < 1e-15);
        assert_eq!(t.slopes(), (0.5, 0.5));
        assert_eq!(t.max_value(), 1.0);
    }

    #[test]
    fn bad_tables_name_the_entry() {
        let e = Table::new(vec![0.0, 0.0], vec![1.0, 2.0], ["slip_rate", "coefficient"]).unwrap_err();
        assert!(e.to_string().contains("entry 1 of the slip_rate column") && e.to_string().contains("increasing"));
        let e = Table::new(vec![0.0, 1.0], vec![1.0, f64::NAN], ["slip_rate", "coefficient"]).unwrap_err();
        assert!(e.to_string().contains("coefficient") && e.to_string().contains("finite"));
        let e = Table::new(vec![0.0, 1.0], vec![1.0, -0.1], ["a", "b"])
            .unwrap()
            .non_negative("b")
            .unwrap_err();
        assert!(e.to_string().contains("non-negative"));
        assert!(Table::new(vec![], vec![], ["a", "b"]).is_err());
    }
}
