//! Condensation of the step problem onto the contact unknowns (the Delassus operator).
//!
//! The step matrix A is constant and the only nonlinear terms are the nodal friction stresses ξ
//! and the nodal frictional heats h on Γ_C. By linearity the tangential velocities at the
//! contact nodes are
//!
//! ```text
//! w_τ = w_τ^free + C ξ + H h,    C = E_w A⁻¹ E_wᵀ ℓ,   H = E_w A⁻¹ E_θᵀ ℓ,
//! ```
//!
//! where w_τ^free solves the step without contact terms, E_w picks the tangential velocity
//! unknowns of the contact nodes and E_θ their temperature unknowns. C and H are small dense
//! matrices computed once per run; the nonsmooth iterations then cost dense products on Γ_C
//! only, and the full fields need half a solve per outer iterate
//! ([`super::direct::StepSystem::loaded_state`]).
//!
//! The factorization orders the contact unknowns last ([`crate::la::QuasiDefiniteLdlt`]), so the block of S⁻¹
//! = (J A)⁻¹ on them is (L₂₂ D₂ L₂₂ᵀ)⁻¹ and C, H cost two dense triangular solves with the
//! m × m trailing block of the factor (milliseconds). The alternative it replaces, n_t full
//! solves with unit right-hand sides, cost ½–1 s in 2D at 49k unknowns and 12 s in 3D at 47k;
//! it remains as the test oracle in `tests/step.rs`.

use super::direct::StepSystem;
use super::StepError as Error;
use crate::la::vector::{dot, largest_eigenvalue};
use crate::model::Problem;

/// The contact compliances C (friction → w_τ) and H (heat → w_τ), dense, row-major.
#[derive(Debug, Clone)]
pub struct Condensation {
    /// Number of tangential contact unknowns: n_contact (d − 1).
    pub n_t: usize,
    /// Number of contact nodes: columns of H.
    pub n_h: usize,
    /// C, n_t × n_t, row-major: w_τ (flat, node-major) per unit ξ component.
    pub friction: Vec<f64>,
    /// H, n_t × n_h, row-major: w_τ per unit nodal heat (zero columns where θ is prescribed).
    pub heat: Vec<f64>,
}

impl Condensation {
    /// Computes C and H from the block of S⁻¹ on the contact unknowns
    /// ([`StepSystem::contact_inverse`]).
    ///
    /// A⁻¹ = S⁻¹ J, J = diag(I, −I); with X = S⁻¹ E_wᵀ, symmetry of S gives both blocks:
    /// C = E_w X ℓ and H = −(E_θ X)ᵀ ℓ.
    pub fn new(problem: &Problem, system: &StepSystem) -> Result<Self, Error> {
        let tangential = problem.dim() - 1;
        let n_contact = problem.contact.len();
        let n_t = n_contact * tangential;
        let n_w = system.n_w();
        let mut friction = vec![0.0; n_t * n_t];
        let mut heat = vec![0.0; n_t * n_contact];
        // `None` where the tangential coordinate is held at zero (no unknown).
        let tangent_dof = |col: usize| problem.contact[col / tangential].tangent_dofs[col % tangential];
        // (flat tangential index, unknown) and (contact node, temperature unknown).
        let tangent: Vec<(usize, usize)> = (0..n_t).filter_map(|c| tangent_dof(c).map(|d| (c, d))).collect();
        let thetas: Vec<(usize, usize)> = (problem.contact.iter().enumerate())
            .filter_map(|(i, node)| node.theta_dof.map(|r| (i, n_w + r)))
            .collect();
        let rows: Vec<usize> = tangent.iter().chain(&thetas).map(|&(_, unknown)| unknown).collect();
        let cols: Vec<usize> = tangent.iter().map(|&(_, unknown)| unknown).collect();
        let block = system.contact_inverse(&rows, &cols)?;
        for (j, &(col, _)) in tangent.iter().enumerate() {
            let column = &block[j * rows.len()..(j + 1) * rows.len()];
            let weight = problem.contact[col / tangential].weight;
            for (&(row, _), x) in tangent.iter().zip(column) {
                friction[row * n_t + col] = x * weight;
            }
            // (E_θ X)[i][col] is the entry H[col][i] up to −ℓ_i.
            for (&(i, _), x) in thetas.iter().zip(&column[tangent.len()..]) {
                heat[col * n_contact + i] = -x * problem.contact[i].weight;
            }
        }
        // A coordinate held at zero (a symmetry plane, or an edge of Γ_C in 3D) gets an
        // artificial compliance of the mean size, w_c = c̄ ξ_c: every solution of the friction law then has w_c = ξ_c = 0 (the
        // plane carries the reaction), and the Newton matrices stay regular.
        let constrained: Vec<usize> = (0..n_t).filter(|&c| tangent_dof(c).is_none()).collect();
        if !constrained.is_empty() {
            let free: Vec<usize> = (0..n_t).filter(|&c| tangent_dof(c).is_some()).collect();
            let mean = free.iter().map(|&c| friction[c * n_t + c]).sum::<f64>() / free.len().max(1) as f64;
            for c in constrained {
                friction[c * n_t + c] = if mean > 0.0 { mean } else { 1.0 };
            }
        }
        Ok(Condensation {
            n_t,
            n_h: n_contact,
            friction,
            heat,
        })
    }

    /// w = w_free + C ξ + H h, all node-major flat vectors.
    pub fn velocities(&self, w_free: &[f64], xi: &[f64], heat: &[f64], w: &mut [f64]) {
        for r in 0..self.n_t {
            let c_row = &self.friction[r * self.n_t..(r + 1) * self.n_t];
            let h_row = &self.heat[r * self.n_h..(r + 1) * self.n_h];
            w[r] = w_free[r] + dot(c_row, xi) + dot(h_row, heat);
        }
    }

    /// The largest eigenvalue of C in modulus, by power iteration (C is nearly symmetric
    /// positive definite: the symmetric part of A is).
    pub fn friction_spectral_bound(&self) -> f64 {
        let products = |v: &[f64], y: &mut [f64]| -> Result<(), std::convert::Infallible> {
            for (r, yr) in y.iter_mut().enumerate() {
                *yr = dot(&self.friction[r * self.n_t..(r + 1) * self.n_t], v);
            }
            Ok(())
        };
        match largest_eigenvalue(self.n_t, products) {
            Ok(lambda) => lambda,
            Err(never) => match never {},
        }
    }
}
