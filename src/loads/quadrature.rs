//! Quadrature rules exact for polynomials of degree 2 on simplices, in barycentric coordinates.
//!
//! ∫_T f φ_a with f affine and φ_a = λ_a P1 is a polynomial of degree 2, so these rules give the
//! exact P1 load of affine data; for other data they are the usual O(h²) approximation.

/// A rule with equal weights: ∫_T g ≈ |T| · weight · Σ_q g(Σ_a λ_qa x_a).
#[derive(Debug)]
pub(super) struct Rule {
    /// Barycentric coordinates of the points; entries beyond the simplex's d + 1 vertices are 0.
    pub points: &'static [[f64; 4]],
    /// Weight of each point relative to the measure (1 / number of points).
    pub weight: f64,
}

/// Edge: 2-point Gauss, λ = (1 ± 1/√3)/2.
const GAUSS_EDGE: Rule = Rule {
    points: &[
        [0.788_675_134_594_812_9, 0.211_324_865_405_187_13, 0.0, 0.0],
        [0.211_324_865_405_187_13, 0.788_675_134_594_812_9, 0.0, 0.0],
    ],
    weight: 0.5,
};

/// Triangle: the three edge midpoints.
const TRIANGLE_MIDPOINTS: Rule = Rule {
    points: &[[0.5, 0.5, 0.0, 0.0], [0.0, 0.5, 0.5, 0.0], [0.5, 0.0, 0.5, 0.0]],
    weight: 1.0 / 3.0,
};

/// Tetrahedron: 4 points, a = (5 + 3√5)/20 on one vertex and b = (5 − √5)/20 on the others.
const TETRAHEDRON_4: Rule = {
    const A: f64 = 0.585_410_196_624_968_5;
    const B: f64 = 0.138_196_601_125_010_5;
    Rule {
        points: &[[A, B, B, B], [B, A, B, B], [B, B, A, B], [B, B, B, A]],
        weight: 0.25,
    }
};

/// The rule for a simplex with `n_vertices` vertices (2: edge, 3: triangle, 4: tetrahedron).
pub(super) fn degree_two(n_vertices: usize) -> &'static Rule {
    match n_vertices {
        2 => &GAUSS_EDGE,
        3 => &TRIANGLE_MIDPOINTS,
        4 => &TETRAHEDRON_4,
        _ => panic!("no simplex has {n_vertices} vertices in 1 to 3 dimensions"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫_T λ^α / |T| = α! d! / (|α| + d)! over the reference simplex of dimension d.
    fn exact_moment(alpha: &[usize]) -> f64 {
        let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
        let d = alpha.len() - 1;
        let total: usize = alpha.iter().sum();
        alpha.iter().map(|&a| fact(a)).product::<f64>() * fact(d) / fact(total + d)
    }

    #[test]
    fn rules_integrate_degree_two_exactly() {
        for n in 2..=4 {
            let rule = degree_two(n);
            for q in rule.points {
                assert!((q[..n].iter().sum::<f64>() - 1.0).abs() < 1e-15);
            }
            // Every barycentric monomial λ_a λ_b and λ_a (and 1).
            for a in 0..=n {
                for b in a..=n {
                    let mut alpha = vec![0; n];
                    if a < n {
                        alpha[a] += 1;
                    }
                    if b < n {
                        alpha[b] += 1;
                    }
                    let monomial = |q: &[f64; 4]| (if a < n { q[a] } else { 1.0 }) * (if b < n { q[b] } else { 1.0 });
                    let approx: f64 = rule.points.iter().map(|q| rule.weight * monomial(q)).sum();
                    let exact = exact_moment(&alpha);
                    assert!(
                        (approx - exact).abs() < 1e-15,
                        "n = {n}, a = {a}, b = {b}: {approx} vs {exact}"
                    );
                }
            }
        }
    }
}
