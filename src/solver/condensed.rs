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
//! matrices computed once per run with blocks of right-hand sides; the nonsmooth iterations then
//! cost dense products on Γ_C only, and the full fields need one solve per outer iterate.

use super::system::{add_contact_terms, tangential_velocities, StepSystem};
use crate::problem::Problem;

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
    /// Computes C and H with block solves, in chunks that keep the block under ~256 MB.
    pub fn new(problem: &Problem, system: &StepSystem) -> Self {
        let tangential = problem.dim() - 1;
        let n_contact = problem.contact.len();
        let n_t = n_contact * tangential;
        let n_cols = n_t + n_contact;
        let n = system.n_unknowns();
        let n_w = problem.n_w();
        let chunk = ((256usize << 20) / (8 * n.max(1))).clamp(1, 256);
        let mut friction = vec![0.0; n_t * n_t];
        let mut heat = vec![0.0; n_t * n_contact];
        let mut block = Vec::new();
        let mut start = 0;
        while start < n_cols {
            let width = chunk.min(n_cols - start);
            block.clear();
            block.resize(n * width, 0.0);
            for (j, col) in block.chunks_exact_mut(n).enumerate() {
                let (xi, h) = unit_load(start + j, n_contact, tangential);
                add_contact_terms(problem, n_w, &xi, &h, col);
            }
            system.solve_block_in_place(&mut block, width);
            for (j, col) in block.chunks_exact(n).enumerate() {
                let w = tangential_velocities(problem, col);
                let global = start + j;
                for i in 0..n_contact {
                    for k in 0..tangential {
                        let row = i * tangential + k;
                        if global < n_t {
                            friction[row * n_t + global] = w[i][k];
                        } else {
                            heat[row * n_contact + (global - n_t)] = w[i][k];
                        }
                    }
                }
            }
            start += width;
        }
        Condensation {
            n_t,
            n_h: n_contact,
            friction,
            heat,
        }
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
        if self.n_t == 0 {
            return 0.0;
        }
        let mut v: Vec<f64> = (0..self.n_t).map(|i| 1.0 + 0.1 * (i % 7) as f64).collect();
        let mut y = vec![0.0; self.n_t];
        let mut estimate = 0.0;
        for _ in 0..200 {
            let norm = dot(&v, &v).sqrt();
            v.iter_mut().for_each(|x| *x /= norm);
            for (r, yr) in y.iter_mut().enumerate() {
                *yr = dot(&self.friction[r * self.n_t..(r + 1) * self.n_t], &v);
            }
            let new = dot(&y, &y).sqrt();
            let settled = (new - estimate).abs() <= 1e-6 * new;
            estimate = new;
            std::mem::swap(&mut v, &mut y);
            if settled {
                break;
            }
        }
        estimate
    }
}

/// The unit load of column `col`: a unit ξ component (col < n_t) or a unit nodal heat.
fn unit_load(col: usize, n_contact: usize, tangential: usize) -> (Vec<[f64; 2]>, Vec<f64>) {
    let mut xi = vec![[0.0; 2]; n_contact];
    let mut heat = vec![0.0; n_contact];
    let n_t = n_contact * tangential;
    if col < n_t {
        xi[col / tangential][col % tangential] = 1.0;
    } else {
        heat[col - n_t] = 1.0;
    }
    (xi, heat)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
