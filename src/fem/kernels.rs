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

/// ∇v of the P1 field with nodal values `v[a]` on T: entry \[i\]\[j\] is ∂_j v_i (constant on T).
pub fn gradient_of(t: &Simplex, v: &[[f64; 3]; 4]) -> [[f64; 3]; 3] {
    match t.dim {
        2 => gradient_in::<2>(t, v),
        _ => gradient_in::<3>(t, v),
    }
}

/// [`gradient_of`] in D dimensions (loops the compiler unrolls: the per-cell kernels of a
/// process that keeps no stiffness matrix run once a cell per step).
#[inline(always)]
fn gradient_in<const D: usize>(t: &Simplex, v: &[[f64; 3]; 4]) -> [[f64; 3]; 3] {
    let mut grad = [[0.0; 3]; 3];
    for (a, va) in v.iter().enumerate().take(D + 1) {
        for i in 0..D {
            for j in 0..D {
                grad[i][j] += va[i] * t.grads[a][j];
            }
        }
    }
    grad
}

/// 𝒯ε = λ tr ε I + 2μ ε for the gradient `grad` (ε its symmetric part), in D dimensions.
#[inline(always)]
fn stress_in<const D: usize>(law: Isotropic, grad: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let trace: f64 = (0..D).map(|i| grad[i][i]).sum();
    let mut stress = [[0.0; 3]; 3];
    for i in 0..D {
        for j in 0..D {
            stress[i][j] = 0.5 * law.two_mu * (grad[i][j] + grad[j][i]);
        }
        stress[i][i] += law.lambda * trace;
    }
    stress
}

/// ∫_T 𝒯ε(v) : ε(λ_a e_i) at \[a\]\[i\]: the isotropic stiffness applied to the P1 field with nodal
/// values `v[a]` ([`isotropic_stiffness_columns`] times v, without the 12 × 12 matrix): the
/// matrix-free product of a process that keeps no stiffness matrix (`crate::model::ColumnShare`).
pub fn isotropic_stiffness_product(t: &Simplex, law: Isotropic, v: &[[f64; 3]; 4]) -> [[f64; 3]; 4] {
    match t.dim {
        2 => stiffness_product_in::<2>(t, law, v),
        _ => stiffness_product_in::<3>(t, law, v),
    }
}

/// [`isotropic_stiffness_product`] in D dimensions.
#[inline(always)]
fn stiffness_product_in<const D: usize>(t: &Simplex, law: Isotropic, v: &[[f64; 3]; 4]) -> [[f64; 3]; 4] {
    gradient_stiffness_product_in::<D>(t, law, &gradient_in::<D>(t, v))
}

/// [`isotropic_stiffness_product`] of the field whose gradient is `grad` ([`gradient_of`]):
/// the same numbers, for a caller that takes the field's gradient once for several integrands.
pub fn isotropic_stiffness_product_of_gradient(t: &Simplex, law: Isotropic, grad: &[[f64; 3]; 3]) -> [[f64; 3]; 4] {
    match t.dim {
        2 => gradient_stiffness_product_in::<2>(t, law, grad),
        _ => gradient_stiffness_product_in::<3>(t, law, grad),
    }
}

/// [`isotropic_stiffness_product_of_gradient`] in D dimensions.
#[inline(always)]
fn gradient_stiffness_product_in<const D: usize>(t: &Simplex, law: Isotropic, grad: &[[f64; 3]; 3]) -> [[f64; 3]; 4] {
    let stress = stress_in::<D>(law, grad);
    let mut out = [[0.0; 3]; 4];
    for (a, row) in out.iter_mut().enumerate().take(D + 1) {
        for (i, value) in row.iter_mut().enumerate().take(D) {
            *value = t.measure * (0..D).map(|j| stress[i][j] * t.grads[a][j]).sum::<f64>();
        }
    }
    out
}

#[cfg(test)]
/// ∫_T 𝒯ε(x) : ε(y) for the P1 fields with nodal values `x[a]`, `y[a]`: xᵀ K_T y for the
/// isotropic stiffness K_T.
pub fn isotropic_energy(t: &Simplex, law: Isotropic, x: &[[f64; 3]; 4], y: &[[f64; 3]; 4]) -> f64 {
    t.measure * isotropic_energy_density(t.dim, law, &gradient_of(t, x), &gradient_of(t, y))
}

/// 𝒯ε(x) : ε(y) for the gradients ∇x, ∇y ([`gradient_of`]) in d dimensions: the integrand of
/// ∫_T 𝒯ε(x) : ε(y) = xᵀ K_T y, for a caller that takes each field's gradient once for several forms.
pub fn isotropic_energy_density(d: usize, law: Isotropic, grad_x: &[[f64; 3]; 3], grad_y: &[[f64; 3]; 3]) -> f64 {
    match d {
        2 => energy_density_in::<2>(law, grad_x, grad_y),
        _ => energy_density_in::<3>(law, grad_x, grad_y),
    }
}

/// [`isotropic_energy_density`] in D dimensions.
#[inline(always)]
fn energy_density_in<const D: usize>(law: Isotropic, grad_x: &[[f64; 3]; 3], grad_y: &[[f64; 3]; 3]) -> f64 {
    let stress = stress_in::<D>(law, grad_x);
    let mut sum = 0.0;
    for i in 0..D {
        for j in 0..D {
            sum += stress[i][j] * 0.5 * (grad_y[i][j] + grad_y[j][i]);
        }
    }
    sum
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

    /// Nodal values of a P1 vector field on a simplex.
    type Field = [[f64; 3]; 4];

    /// Two rough P1 fields on a tetrahedron and on a triangle.
    fn rough_fields() -> Vec<(Simplex, Field, Field)> {
        let tet = Simplex::new(3, &[[0.1, 0.0, 0.2], [1.3, 0.1, 0.0], [0.2, 0.9, 0.1], [0.3, 0.2, 1.1]]);
        let x = [[0.3, -1.2, 0.5], [0.8, 0.1, -0.4], [-0.6, 0.7, 0.9], [0.2, -0.3, 1.5]];
        let y = [[-0.7, 0.4, 0.2], [0.5, 1.1, -0.9], [0.3, -0.2, 0.6], [1.4, 0.8, -0.1]];
        let planar = |v: [[f64; 3]; 4]| v.map(|[a, b, _]| [a, b, 0.0]);
        let tri = Simplex::new(2, &[[0.0, 0.1, 0.0], [1.2, 0.0, 0.0], [0.3, 0.8, 0.0]]);
        vec![(tet, x, y), (tri, planar(x), planar(y))]
    }

    /// The matrix-free kernels are the assembled stiffness and coupling applied to the field
    /// (to rounding): K_T v, xᵀ K_T y, and Σ_b (Gᵀ v)_b from the gradient.
    #[test]
    fn matrix_free_kernels_apply_the_local_matrices() {
        let law = Isotropic {
            lambda: 1.7,
            two_mu: 0.9,
        };
        for (t, x, y) in rough_fields() {
            let d = t.dim;
            let k = isotropic_stiffness(&t, law);
            let flat = |v: &Field| -> Vec<f64> { (0..=d).flat_map(|a| v[a][..d].to_vec()).collect() };
            let (xf, yf) = (flat(&x), flat(&y));
            let product = isotropic_stiffness_product(&t, law, &y);
            let mut energy = 0.0;
            for (r, row) in k.iter().enumerate().take((d + 1) * d) {
                let ky: f64 = (0..(d + 1) * d).map(|c| row[c] * yf[c]).sum();
                assert!((product[r / d][r % d] - ky).abs() <= 1e-14, "d = {d}, row {r}");
                energy += xf[r] * ky;
            }
            assert!((isotropic_energy(&t, law, &x, &y) - energy).abs() <= 1e-14 * energy.abs().max(1.0));
            // Σ_b (Gᵀx)_b = ∫_T div x = |T| tr ∇x, the coupling of `crate::model::ColumnShare`.
            let g = divergence_coupling(&t);
            let gtv: f64 = (0..=d)
                .map(|b| (0..(d + 1) * d).map(|r| g[r][b] * xf[r]).sum::<f64>())
                .sum();
            let grad = gradient_of(&t, &x);
            let div: f64 = (0..d).map(|i| grad[i][i]).sum();
            assert!((t.measure * div - gtv).abs() <= 1e-14, "d = {d}");
        }
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
