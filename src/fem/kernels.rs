//! Element kernels: local P1 matrices on one simplex, knowing nothing of global numbering.
//!
//! Local vector dofs are ordered node-major: (a, i) ↦ a·d + i for node a ≤ d and component
//! i < d. All integrands are polynomials integrated exactly.
//!
//! The assembly takes each kernel one local node's columns at a time (`*_column`), as it sums
//! a node's columns over the node's cells (`super::assembly`); the whole local matrices are
//! those columns side by side, kept for the tests.

use crate::material::Isotropic;
use crate::mesh::simplex::Simplex;

#[cfg(test)]
/// ∫_T λ_a λ_b = |T| (1 + δ_ab) / ((d + 1)(d + 2)): the consistent scalar mass.
pub fn scalar_mass(t: &Simplex) -> [[f64; 4]; 4] {
    full_from_columns(t, scalar_mass_column)
}

/// Column b of the consistent scalar mass: entry a is ∫_T λ_a λ_b.
pub fn scalar_mass_column(t: &Simplex, b: usize) -> [f64; 4] {
    let n = t.dim + 1;
    let scale = t.measure / ((n * (n + 1)) as f64);
    let mut m = [0.0; 4];
    for (a, v) in m.iter_mut().enumerate().take(n) {
        *v = if a == b { 2.0 * scale } else { scale };
    }
    m
}

#[cfg(test)]
/// A scalar kernel's 4 × 4 matrix from its columns.
fn full_from_columns(t: &Simplex, column: impl Fn(&Simplex, usize) -> [f64; 4]) -> [[f64; 4]; 4] {
    let mut m = [[0.0; 4]; 4];
    for b in 0..=t.dim {
        for (row, v) in m.iter_mut().zip(column(t, b)) {
            row[b] = v;
        }
    }
    m
}

#[cfg(test)]
/// ∫_T ∇λ_a · ∇λ_b: the P1 stiffness of −Δ.
pub fn laplacian(t: &Simplex) -> [[f64; 4]; 4] {
    full_from_columns(t, laplacian_column)
}

/// Column b of the P1 stiffness of −Δ: entry a is ∫_T ∇λ_a · ∇λ_b.
pub fn laplacian_column(t: &Simplex, b: usize) -> [f64; 4] {
    let mut m = [0.0; 4];
    for (a, v) in m.iter_mut().enumerate().take(t.dim + 1) {
        *v = t.measure * (0..t.dim).map(|r| t.grads[a][r] * t.grads[b][r]).sum::<f64>();
    }
    m
}

#[cfg(test)]
/// ∫_T 𝒯ε(λ_b e_j) : ε(λ_a e_i) at local entry ((a,i), (b,j)), for an isotropic 𝒯 = (λ, 2μ):
/// |T| [λ ∂_i λ_a ∂_j λ_b + μ (∇λ_a·∇λ_b δ_ij + ∂_j λ_a ∂_i λ_b)].
pub fn isotropic_stiffness(t: &Simplex, law: Isotropic) -> [[f64; 12]; 12] {
    let d = t.dim;
    let mut k = [[0.0; 12]; 12];
    for b in 0..=d {
        let columns = isotropic_stiffness_columns(t, law, b);
        for (row, column) in k.iter_mut().zip(&columns) {
            row[b * d..(b + 1) * d].copy_from_slice(&column[..d]);
        }
    }
    k
}

/// The d columns (b, j) of local node b of the isotropic stiffness: entry `[a·d + i][j]` is
/// ∫_T 𝒯ε(λ_b e_j) : ε(λ_a e_i) = |T| [λ ∂_i λ_a ∂_j λ_b + μ (∇λ_a·∇λ_b δ_ij + ∂_j λ_a ∂_i λ_b)].
pub fn isotropic_stiffness_columns(t: &Simplex, law: Isotropic, b: usize) -> [[f64; 3]; 12] {
    let (d, n) = (t.dim, t.dim + 1);
    let mu = 0.5 * law.two_mu;
    let g = &t.grads;
    let mut k = [[0.0; 3]; 12];
    for a in 0..n {
        let dot: f64 = (0..d).map(|r| g[a][r] * g[b][r]).sum();
        for i in 0..d {
            for j in 0..d {
                let mut v = law.lambda * g[a][i] * g[b][j] + mu * g[a][j] * g[b][i];
                if i == j {
                    v += mu * dot;
                }
                k[a * d + i][j] = t.measure * v;
            }
        }
    }
    k
}

/// ∫_T λ_b div(λ_a e_i) = ∂_i λ_a |T| / (d + 1) at local entry ((a,i), b): the coupling
/// G_ij = ∫ c ψ_j div φ_i for C = c I, without the factor c.
pub fn divergence_coupling(t: &Simplex) -> [[f64; 4]; 12] {
    let mut m = [[0.0; 4]; 12];
    for b in 0..=t.dim {
        for (row, v) in m.iter_mut().zip(divergence_coupling_column(t, b)) {
            row[b] = v;
        }
    }
    m
}

/// Column b of [`divergence_coupling`] (the same for every b: ψ_b integrates to |T| / (d + 1)).
pub fn divergence_coupling_column(t: &Simplex, _b: usize) -> [f64; 12] {
    let (d, n) = (t.dim, t.dim + 1);
    let mut m = [0.0; 12];
    for a in 0..n {
        for i in 0..d {
            m[a * d + i] = t.grads[a][i] * t.measure / n as f64;
        }
    }
    m
}

/// ∫_T ε(v) : ε(v) for the P1 field with nodal values `v[a]` (components beyond d unused): ε is
/// constant on T, ε_ij = ½ Σ_a (v_a,i ∂_j λ_a + v_a,j ∂_i λ_a).
pub fn strain_squared(t: &Simplex, v: &[[f64; 3]; 4]) -> f64 {
    let d = t.dim;
    let mut grad = [[0.0; 3]; 3]; // ∂_j v_i
    for (a, va) in v.iter().enumerate().take(d + 1) {
        for i in 0..d {
            for j in 0..d {
                grad[i][j] += va[i] * t.grads[a][j];
            }
        }
    }
    let mut sum = 0.0;
    for i in 0..d {
        for j in 0..d {
            let e = 0.5 * (grad[i][j] + grad[j][i]);
            sum += e * e;
        }
    }
    t.measure * sum
}

/// ∫_T |∇θ|² for the P1 field with nodal values `theta[a]`.
pub fn gradient_squared(t: &Simplex, theta: &[f64; 4]) -> f64 {
    let d = t.dim;
    let mut grad = [0.0; 3];
    for (a, &value) in theta.iter().enumerate().take(d + 1) {
        for (g, &da) in grad.iter_mut().zip(&t.grads[a]).take(d) {
            *g += value * da;
        }
    }
    t.measure * grad[..d].iter().map(|g| g * g).sum::<f64>()
}

/// ∫_F λ_a λ_b on a boundary facet with `n` = d vertices and measure `measure`.
pub fn facet_mass(n: usize, measure: f64) -> [[f64; 3]; 3] {
    let scale = measure / ((n * (n + 1)) as f64);
    let mut m = [[0.0; 3]; 3];
    for (a, row) in m.iter_mut().enumerate().take(n) {
        for (b, v) in row.iter_mut().enumerate().take(n) {
            *v = if a == b { 2.0 * scale } else { scale };
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_triangle() -> Simplex {
        Simplex::new(2, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    }

    #[test]
    fn mass_sums_to_measure() {
        let t = unit_triangle();
        let m = scalar_mass(&t);
        let total: f64 = m.iter().flatten().sum();
        assert!((total - 0.5).abs() < 1e-15);
        assert!((m[0][0] - 1.0 / 12.0).abs() < 1e-15);
    }

    #[test]
    fn laplacian_rows_sum_to_zero() {
        let l = laplacian(&unit_triangle());
        for row in l.iter().take(3) {
            assert!(row.iter().sum::<f64>().abs() < 1e-15);
        }
        assert!((l[0][0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn coupling_by_hand() {
        // On the unit triangle ∇λ₀ = (−1, −1), |T| = 1/2: entry ((0, x), b) = −1 · (1/2)/3.
        let g = divergence_coupling(&unit_triangle());
        assert!((g[0][2] + 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(g[3][1], 0.0); // (1, y): ∂_y λ₁ = 0
        assert!((g[5][1] - 1.0 / 6.0).abs() < 1e-15); // (2, y): ∂_y λ₂ = 1
    }
}
