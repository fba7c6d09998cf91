//! The constitutive tensors of eq. (1) and (3): viscosity 𝒜, elasticity ℬ, thermal expansion
//! C and conductivity K, all isotropic as in the paper's Section 6.
//!
//! Depends on: nothing of this crate.

use serde::Serialize;

/// An isotropic fourth-order tensor in Lamé form: 𝒯ε = λ (tr ε) I + 2μ ε.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Isotropic {
    /// λ: coefficient of (tr ε) I.
    pub lambda: f64,
    /// 2μ: coefficient of ε.
    pub two_mu: f64,
}

impl Isotropic {
    /// The paper's viscosity (𝒜ε)_αβ = μ₁ tr ε δ_αβ + μ₂ ε_αβ.
    pub fn viscosity(mu1: f64, mu2: f64) -> Self {
        Isotropic {
            lambda: mu1,
            two_mu: mu2,
        }
    }

    /// The paper's elasticity (ℬε)_αβ = Eκ/((1+κ)(1−2κ)) tr ε δ_αβ + E/(1+κ) ε_αβ.
    ///
    /// This is the plane-strain (and 3D) Lamé form; the paper's text says "plane stress" but
    /// writes this tensor, and we use the tensor as written (docs/model.md §4).
    pub fn elasticity(young: f64, poisson: f64) -> Self {
        Isotropic {
            lambda: young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)),
            two_mu: young / (1.0 + poisson),
        }
    }

    /// 𝒯ε for a symmetric d × d strain (stored as a full 3 × 3 array).
    pub fn apply(&self, dim: usize, strain: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let trace: f64 = (0..dim).map(|i| strain[i][i]).sum();
        let mut stress = [[0.0; 3]; 3];
        for i in 0..dim {
            for j in 0..dim {
                stress[i][j] = self.two_mu * strain[i][j];
            }
            stress[i][i] += self.lambda * trace;
        }
        stress
    }
}

/// The material data of the body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Material {
    /// ρ, density.
    pub density: f64,
    /// c_p, heat capacity.
    pub heat_capacity: f64,
    /// 𝒜, viscosity tensor.
    pub viscosity: Isotropic,
    /// ℬ, elasticity tensor.
    pub elasticity: Isotropic,
    /// c in C = c I, the thermal expansion tensor; the paper's C = −α_exp E/(1−2κ) I.
    pub expansion: f64,
    /// k in K∇θ = k∇θ, the conductivity.
    pub conductivity: f64,
    /// θ_ref, the stress-free temperature: the thermal stress is C(θ − θ_ref). The paper writes
    /// Cθ, i.e. θ_ref = 0, so that a body at its initial temperature θ₀ ≠ 0 carries the thermal
    /// stress Cθ₀ from t = 0 (which is what drives the slip in the paper's example).
    pub reference_temperature: f64,
}

impl Material {
    /// The paper's expansion coefficient c = −α_exp E/(1 − 2κ).
    pub fn expansion_from(alpha_exp: f64, young: f64, poisson: f64) -> f64 {
        -alpha_exp * young / (1.0 - 2.0 * poisson)
    }
}

/// The material of each cell of a body made of several (a friction lining on a steel
/// backplate): the materials, and one small index per cell into them.
#[derive(Debug, Clone, PartialEq)]
pub struct CellMaterials {
    /// The materials; the first is the body's, that of every cell no other is given to.
    pub materials: Vec<Material>,
    /// The index into `materials` of each cell; empty when every cell takes the first (2 bytes
    /// per cell otherwise: at most 65 536 materials).
    pub of_cell: Vec<u16>,
}

impl CellMaterials {
    /// One material for every cell.
    pub fn uniform(material: Material) -> Self {
        CellMaterials {
            materials: vec![material],
            of_cell: Vec::new(),
        }
    }

    /// The material of cell `e`.
    pub fn of(&self, e: usize) -> &Material {
        &self.materials[self.of_cell.get(e).map_or(0, |&k| usize::from(k))]
    }

    /// The body's material (of the cells no other is given to).
    pub fn base(&self) -> &Material {
        &self.materials[0]
    }

    /// The one material of every cell, when the materials are all equal (also when several
    /// equal ones were given): what the computations that hold for one material use.
    pub fn uniform_material(&self) -> Option<&Material> {
        let first = &self.materials[0];
        self.materials.iter().all(|m| m == first).then_some(first)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_constants() {
        let b = Isotropic::elasticity(10_000.0, 0.3);
        assert!((b.lambda - 5769.230769230769).abs() < 1e-9);
        assert!((b.two_mu - 7692.307692307692).abs() < 1e-9);
        assert!((Material::expansion_from(3e-4, 10_000.0, 0.3) + 7.5).abs() < 1e-12);
    }
}
