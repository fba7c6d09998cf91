//! The energies of one time step, from the states at t_{n−1} and t_n: what Abaqus users read as
//! ALLKE, ALLSE, ALLVD, ALLFD and ALLWK, and the heat exchanged, each a figure a user can check.
//!
//! Depends on: [`super::Problem`], [`super::State`], [`super::ContactLaws`], [`crate::la`],
//! [`crate::fem::assembly::Matrices`].
//!
//! **The mechanical balance (an identity of the scheme).** Step n of Problem 14 on full nodal
//! vectors (u_n = u_{n−1} + k w_n, θ_n with θ_D at the fixed nodes) is
//!
//! ```text
//! ℳ(w_n − w_{n−1})/k + 𝒦_A w_n + 𝒦_B u_n + G θ_n = F_n + Pᵀ Ξ_n   tested by every v in E^h,
//! ```
//!
//! F_n = [`Problem::force`] (data loads, the reference-temperature load θ_ref G 1, extra loads)
//! and (Pᵀ Ξ_n)·v = Σ_i ℓ_i ξ_i·v_τ,i (nodal quadrature on Γ_C, ξ_i the friction stress on the
//! body in the node's tangent coordinates). w_n lies in E^h, so v = w_n is a test function, and
//! k w_nᵀ(…) splits exactly into
//!
//! ```text
//! ΔK + ΔE + D_num + D_visc + D_fric + W_θ = W_F + W_found
//! K = ½ wᵀℳw, E = ½ uᵀ𝒦_B u                                       kinetic, elastic energy
//! D_num  = ½|w_n − w_{n−1}|²_ℳ + ½|u_n − u_{n−1}|²_{𝒦_B} ≥ 0     backward Euler's dissipation
//! D_visc = k w_nᵀ𝒦_A w_n ≥ 0                                         viscous dissipation
//! D_fric = −k Σ_i ℓ_i ξ_i·(w_τ,i − v_F,i) ≥ 0                        frictional dissipation
//! W_θ    = k w_nᵀ G θ_n                                              work of the thermal stress
//! W_F    = k F_nᵀ w_n                                                work of the loads
//! W_found = k Σ_i ℓ_i ξ_i·v_F,i                                     the foundation's work on the body
//! ```
//!
//! (from wᵀℳ(w − w′) = ½|w|² − ½|w′|² + ½|w − w′|² in the ℳ-norm, and likewise for 𝒦_B with
//! u − u′ = k w). v_F is the foundation's tangential velocity at each contact node (zero for the
//! paper's foundation at rest): friction dissipates on the relative slip w_τ − v_F, and
//! D_fric and W_found together are −k Σ ℓ_i ξ_i·w_τ,i + k Σ ℓ_i ξ_i·v_F,i, so v_F enters in the
//! split only. The residual LHS − RHS is k w_nᵀ r_n for the residual r_n of the step's equations:
//! zero for an exact solve, so it measures how well the step was solved (the convexification
//! loop's and the Krylov solver's tolerances), relative to the largest term ([`StepEnergy::scale`]).
//!
//! **The heat balance (an identity once the Dirichlet heat is defined as a reaction).**
//! H = Σ (ℳ_θ θ)_p = ∫ ρ c_p θ (measured from 0 °C). Summing the heat equation's rows over every
//! node (η = 1, on full vectors):
//!
//! ```text
//! ΔH = Q_src + Q_exch + Q_fric + Q_coup + Q_D + R_θ
//! Q_src  = k Σ (∫ g_n η)                      heat sources (and extra heat loads)
//! Q_exch = k (Σ L_exch(θ_n) − 1ᵀ𝒦_θ θ_n)     exchange with the foundation on Γ_C (the Robin
//!                                             part of 𝒦_θ; conduction sends 1 to 0)
//! Q_fric = k Σ_i ℓ_i share·h_τ(|w_τ,i − v_F,i|)   frictional heat entering the body
//! Q_coup = k 1ᵀGᵀw_n                          the coupling term c ∫ div w
//! Q_D    = k Σ_{θ fixed} r_θ,p                heat through the fixed-temperature boundary: the
//!                                             reaction, the residual of those rows
//! R_θ    = k Σ_{θ free} r_θ,p                 the residual of the solved rows
//! ```
//!
//! with r_θ = ℳ_θ(θ_n − θ_{n−1})/k + 𝒦_θ θ_n − Gᵀw_n − loads − frictional heat on full vectors.
//! Q_D closes the balance by definition at the fixed nodes; R_θ is a check of the solve that
//! can fail (a nonlinear exchange is evaluated at θ_n here, at the last iterate in the step).
//!
//! **What is not an identity.** The sum K + E + H is not conserved by the model: the coupling
//! terms W_θ = k wᵀGθ and Q_coup = k 1ᵀGᵀw differ (the paper's linearized coupling is not
//! energy-consistent), and the frictional heat h_τ is a datum independent of D_fric.

use std::sync::Arc;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::error::ModelError as Error;
use super::laws::ContactLaws;
use super::problem::Problem;
use super::share::{ColumnShare, RowProducts};
use super::state::State;
use crate::fem::assembly::{Matrices, VectorMass};
use crate::la::vector::{dot, norm2};
use crate::la::CscMatrix;

/// The energies of one step (or of the substeps of a cut-back step, summed), J (in 2D, J per
/// metre of thickness). Levels at t_n; changes and flows over the step; flows into the body
/// positive, dissipations positive.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StepEnergy {
    /// K_n = ½ w_nᵀℳw_n.
    pub kinetic: f64,
    /// E_n = ½ u_nᵀ𝒦_B u_n.
    pub elastic: f64,
    /// H_n = ∫ ρ c_p θ_n.
    pub thermal: f64,
    /// K_n − K_{n−1}, E_n − E_{n−1}, H_n − H_{n−1}.
    pub kinetic_change: f64,
    pub elastic_change: f64,
    pub thermal_change: f64,
    /// D_visc = k w_nᵀ𝒦_A w_n.
    pub viscous: f64,
    /// D_num = ½|Δw|²_ℳ + ½|Δu|²_{𝒦_B}.
    pub numerical: f64,
    /// D_fric = −k Σ ℓ_i ξ_i·(w_τ,i − v_F,i).
    pub frictional: f64,
    /// W_θ = k w_nᵀGθ_n.
    pub thermal_stress: f64,
    /// W_F = k F_nᵀw_n.
    pub loads: f64,
    /// W_found = k Σ ℓ_i ξ_i·v_F,i.
    pub foundation: f64,
    /// ΔK + ΔE + D_num + D_visc + D_fric + W_θ − W_F − W_found.
    pub residual: f64,
    /// The largest term of the balance in absolute value (K_n, E_n, K_{n−1}, E_{n−1} and every
    /// flow): what `residual` is relative to.
    pub scale: f64,
    /// Q_src, Q_exch, Q_fric, Q_coup, Q_D (heat into the body over the step).
    pub heat_sources: f64,
    pub heat_exchange: f64,
    pub heat_friction: f64,
    pub heat_coupling: f64,
    pub heat_dirichlet: f64,
    /// R_θ = ΔH − the heats above.
    pub heat_residual: f64,
    /// The largest of |ΔH| and the heats: what `heat_residual` is relative to.
    pub heat_scale: f64,
}

impl StepEnergy {
    /// |residual| / scale (0 where every term vanishes).
    pub fn relative_residual(&self) -> f64 {
        relative(self.residual, self.scale)
    }

    /// |heat_residual| / heat_scale.
    pub fn relative_heat_residual(&self) -> f64 {
        relative(self.heat_residual, self.heat_scale)
    }

    /// Adds a later substep: its levels, the sums of changes and flows, the larger scale.
    pub fn absorb(&mut self, later: &StepEnergy) {
        let sum = |a: &mut f64, b: f64| *a += b;
        self.kinetic = later.kinetic;
        self.elastic = later.elastic;
        self.thermal = later.thermal;
        for (a, b) in self.flows_mut().into_iter().zip(later.flows()) {
            sum(a, b);
        }
        // The sums' terms count too: a step's changes may exceed each substep's terms.
        self.scale = self.scale.max(later.scale).max(self.largest_mechanical_term());
        self.heat_scale = self.heat_scale.max(later.heat_scale).max(self.largest_heat_term());
    }

    /// The largest term of the mechanical balance in absolute value: K_n, E_n, K_{n−1},
    /// E_{n−1} and every flow.
    fn largest_mechanical_term(&self) -> f64 {
        [
            self.kinetic,
            self.elastic,
            self.kinetic - self.kinetic_change,
            self.elastic - self.elastic_change,
            self.numerical,
            self.viscous,
            self.frictional,
            self.thermal_stress,
            self.loads,
            self.foundation,
        ]
        .into_iter()
        .fold(0.0, |s, v| s.max(v.abs()))
    }

    /// The largest of |ΔH| and the heats.
    fn largest_heat_term(&self) -> f64 {
        [
            self.thermal_change,
            self.heat_sources,
            self.heat_exchange,
            self.heat_friction,
            self.heat_coupling,
            self.heat_dirichlet,
        ]
        .into_iter()
        .fold(0.0, |s, v| s.max(v.abs()))
    }

    /// The terms that read 𝒦_A, 𝒦_B, G or F besides the mechanical forms: a process holding a
    /// share of the matrices sums them over its own nodes ([`ColumnShare`]).
    fn read_shared_mut(&mut self) -> [&mut f64; 4] {
        [
            &mut self.thermal_stress,
            &mut self.loads,
            &mut self.heat_coupling,
            &mut self.heat_dirichlet,
        ]
    }

    /// The changes, flows and residuals (every field summed over substeps), in a fixed order.
    fn flows(&self) -> [f64; 16] {
        let mut copy = *self;
        copy.flows_mut().map(|v| *v)
    }

    fn flows_mut(&mut self) -> [&mut f64; 16] {
        [
            &mut self.kinetic_change,
            &mut self.elastic_change,
            &mut self.thermal_change,
            &mut self.viscous,
            &mut self.numerical,
            &mut self.frictional,
            &mut self.thermal_stress,
            &mut self.loads,
            &mut self.foundation,
            &mut self.residual,
            &mut self.heat_sources,
            &mut self.heat_exchange,
            &mut self.heat_friction,
            &mut self.heat_coupling,
            &mut self.heat_dirichlet,
            &mut self.heat_residual,
        ]
    }
}

fn relative(value: f64, scale: f64) -> f64 {
    if scale > 0.0 {
        value.abs() / scale
    } else {
        0.0
    }
}

/// K, E and H of a state (the levels at its time): three mat-vecs (E summed over the ranks
/// where a process holds a share of 𝒦_B: collective then, [`ColumnShare`]).
pub fn energy_levels(problem: &Problem, state: &State) -> Result<(f64, f64, f64), Error> {
    let mats = &problem.matrices;
    let elastic = match &problem.columns {
        None => mats.elasticity.quadratic_form(&state.u),
        Some(share) => {
            let mut part = share.stiffness_forms(
                (&problem.mesh, &problem.materials),
                [&state.u],
                [(|m| m.elasticity, 0, 0)],
                RowProducts::default(),
            );
            share.sum(&mut part)?;
            part[0]
        }
    };
    Ok((
        0.5 * mats.mass.quadratic_form(&state.w),
        0.5 * elastic,
        mats.heat_mass.mul(&state.theta).iter().sum(),
    ))
}

/// The energies of the step from `previous` to `state` (module docs), the friction's on the
/// slip relative to the foundation at t_n ([`ContactLaws::slip`]). One pass over the velocity
/// matrices' shared pattern gives every quadratic form of ℳ, 𝒦_A and 𝒦_B
/// (`mechanical_forms`), one gather over G the coupling, one pass over the temperature
/// pattern ℳ_θ and 𝒦_θ; with the loads at t_n and the laws on Γ_C once. Where a process holds
/// a share of the matrices ([`ColumnShare`]) the terms that read 𝒦_A, 𝒦_B, G or F are its own
/// nodes' part, summed over the ranks in one reduction: collective then.
pub fn step_energy(problem: &Problem, previous: &State, state: &State) -> Result<StepEnergy, Error> {
    Ok(step_energy_and_elastic_force(problem, previous, state)?.0)
}

/// [`step_energy`], and where a process holds a share of the matrices ([`ColumnShare`]) the
/// elastic force 𝒦_B U_n in its rows (its own and Γ_C's nodes' entries; the others partial),
/// which its pass over the cells for the forms makes from the gradients of u it takes anyway:
/// the next step's right-hand side reads it from the state ([`State::elastic_force`]) instead
/// of a pass of its own. Empty where the process holds the whole 𝒦_B.
pub fn step_energy_and_elastic_force(
    problem: &Problem,
    previous: &State,
    state: &State,
) -> Result<(StepEnergy, Vec<f64>), Error> {
    let k = state.t - previous.t;
    let (w, u) = (&state.w, &state.u);
    let share = problem.columns.as_ref();
    let dw: Vec<f64> = w.iter().zip(&previous.w).map(|(a, b)| a - b).collect();
    let du: Vec<f64> = u.iter().zip(&previous.u).map(|(a, b)| a - b).collect();
    // The forms, and Gᵀw, whose rows the heat balance needs too: k wᵀGθ = k θ·(Gᵀw).
    let (mut forms, coupling, elastic_force) = match share {
        None => {
            let mut coupling = vec![0.0; state.theta.len()];
            problem.matrices.coupling.mul_transpose_add(1.0, w, &mut coupling);
            (
                mechanical_forms(&problem.matrices, w, &dw, u, &du),
                coupling,
                Vec::new(),
            )
        }
        Some(share) => shared_mechanical_forms(problem, share, w, &dw, u, &du),
    };
    let force = problem.force(state.t)?;

    let mut e = StepEnergy {
        thermal_stress: k * owned_dot(share, 1, &state.theta, &coupling),
        loads: k * owned_dot(share, problem.dim(), &force, w),
        ..StepEnergy::default()
    };

    // Friction on Γ_C, and the frictional heat it makes, on the relative slip.
    let laws = ContactLaws::of_state(problem, state)?;
    let td = problem.dim() - 1;
    let slip = laws.slip(w);
    let mut friction_heat = vec![0.0; problem.mesh.n_nodes()];
    for (i, node) in problem.contact.iter().enumerate() {
        let range = i * td..(i + 1) * td;
        let (xi, slip) = (&state.xi[range.clone()], &slip[range.clone()]);
        e.frictional -= k * node.weight * dot(xi, slip);
        if let Some(v_f) = laws.foundation() {
            e.foundation += k * node.weight * dot(xi, &v_f[range]);
        }
        friction_heat[node.node] = node.weight * laws.heat(i, norm2(slip));
    }
    heat_balance(problem, previous, state, &friction_heat, &coupling, &mut e)?;
    if let Some(share) = share {
        // The parts of this process's own nodes, summed over the ranks in one reduction.
        let mut all: Vec<f64> = (forms.values_mut().into_iter().chain(e.read_shared_mut()))
            .map(|v| *v)
            .collect();
        share.sum(&mut all)?;
        (forms.values_mut().into_iter().chain(e.read_shared_mut()))
            .zip(all)
            .for_each(|(v, total)| *v = total);
    }
    // ½wᵀℳw − ½w′ᵀℳw′ = wᵀℳΔw − ½ΔwᵀℳΔw, without the difference of two large numbers.
    e.kinetic = 0.5 * forms.w_mass_w;
    e.elastic = 0.5 * forms.u_elastic_u;
    e.kinetic_change = forms.w_mass_dw - 0.5 * forms.dw_mass_dw;
    e.elastic_change = forms.u_elastic_du - 0.5 * forms.du_elastic_du;
    e.numerical = 0.5 * (forms.dw_mass_dw + forms.du_elastic_du);
    e.viscous = k * forms.w_viscous_w;
    e.residual = e.kinetic_change + e.elastic_change + e.numerical + e.viscous + e.frictional + e.thermal_stress
        - e.loads
        - e.foundation;
    e.scale = e.largest_mechanical_term();
    e.heat_residual =
        e.thermal_change - (e.heat_sources + e.heat_exchange + e.heat_friction + e.heat_coupling + e.heat_dirichlet);
    e.heat_scale = e.largest_heat_term();
    Ok((e, elastic_force))
}

/// a·b over the entries of the nodes this process owns (`per_node` entries per node), all
/// where it holds the whole matrices (the same bits as [`dot`] then).
fn owned_dot(share: Option<&ColumnShare>, per_node: usize, a: &[f64], b: &[f64]) -> f64 {
    match share {
        None => dot(a, b),
        Some(share) => (a.iter().zip(b).enumerate())
            .filter(|&(i, _)| share.owns(i / per_node))
            .map(|(_, (x, y))| x * y)
            .sum(),
    }
}

/// The heat terms of [`StepEnergy`] (module docs) but its residual and scale: the heat
/// equation's residual on full vectors, its fixed rows the reaction Q_D; `coupling` = Gᵀw_n.
/// Q_coup and Q_D over the nodes this process owns where it holds a share of G.
fn heat_balance(
    problem: &Problem,
    previous: &State,
    state: &State,
    friction_heat: &[f64],
    coupling: &[f64],
    e: &mut StepEnergy,
) -> Result<(), Error> {
    let k = state.t - previous.t;
    let mats = &problem.matrices;
    let theta = &state.theta;
    let dtheta: Vec<f64> = theta.iter().zip(&previous.theta).map(|(a, b)| a - b).collect();
    let mut sources = vec![0.0; theta.len()];
    problem.add_heat_sources(state.t, &mut sources)?;
    let exchange = problem.exchange_heat(state.t, theta);
    let [heat_mass_theta, heat_mass_dtheta, conduction] = heat_products(mats, theta, &dtheta);
    let mut residual: Vec<f64> = heat_mass_dtheta.iter().map(|r| r / k).collect();
    let rows = (residual.iter_mut())
        .zip(conduction.iter().zip(coupling))
        .zip(sources.iter().zip(&exchange));
    for (p, ((r, (c, g)), (s, x))) in rows.enumerate() {
        *r += c - g - s - x - friction_heat[p];
    }
    let sum = |v: &[f64]| k * v.iter().sum::<f64>();
    let owned = |p: usize| problem.columns.as_ref().is_none_or(|share| share.owns(p));
    e.thermal = heat_mass_theta.iter().sum();
    e.thermal_change = heat_mass_dtheta.iter().sum();
    e.heat_sources = sum(&sources);
    e.heat_exchange = sum(&exchange) - sum(&conduction);
    e.heat_friction = sum(friction_heat);
    e.heat_coupling = k * (0..theta.len()).filter(|&p| owned(p)).map(|p| coupling[p]).sum::<f64>();
    let fixed = |p: usize| problem.temperature.free[p].is_none();
    e.heat_dirichlet = k
        * (0..theta.len())
            .filter(|&p| fixed(p) && owned(p))
            .map(|p| residual[p])
            .sum::<f64>();
    Ok(())
}

/// The quadratic forms of the mechanical balance (ℳ, 𝒦_A, 𝒦_B are symmetric, but the forms are
/// exact without it: xᵀAᵀy = yᵀAx).
struct MechanicalForms {
    w_mass_w: f64,
    w_mass_dw: f64,
    dw_mass_dw: f64,
    w_viscous_w: f64,
    u_elastic_u: f64,
    u_elastic_du: f64,
    du_elastic_du: f64,
}

impl From<[f64; 7]> for MechanicalForms {
    /// The seven forms in the order of [`MechanicalForms::values_mut`].
    fn from(
        [w_mass_w, w_mass_dw, dw_mass_dw, w_viscous_w, u_elastic_u, u_elastic_du, du_elastic_du]: [f64; 7],
    ) -> Self {
        MechanicalForms {
            w_mass_w,
            w_mass_dw,
            dw_mass_dw,
            w_viscous_w,
            u_elastic_u,
            u_elastic_du,
            du_elastic_du,
        }
    }
}

impl MechanicalForms {
    /// The seven forms in their order, to be summed over the ranks.
    fn values_mut(&mut self) -> [&mut f64; 7] {
        [
            &mut self.w_mass_w,
            &mut self.w_mass_dw,
            &mut self.dw_mass_dw,
            &mut self.w_viscous_w,
            &mut self.u_elastic_u,
            &mut self.u_elastic_du,
            &mut self.du_elastic_du,
        ]
    }
}

/// wᵀℳw, wᵀℳΔw, ΔwᵀℳΔw, wᵀ𝒦_A w, uᵀ𝒦_B u, uᵀ𝒦_BΔu, Δuᵀ𝒦_BΔu: one pass over the pattern that
/// the three matrices share (they are clones of one template; three passes where they do not).
/// Measured on the 2D reference run's matrices (256 × 64 cells; release, a loaded machine, the
/// fastest of 200 calls): all of [`step_energy`] 2.7 ms on two threads, 3.4 ms on one, where one
/// mat-vec with ℳ takes 0.36 ms and one with 𝒦_B 0.37–0.72 ms (the ten mat-vecs this
/// replaces: ≈ 3.3 ms and more).
fn mechanical_forms(mats: &Matrices, w: &[f64], dw: &[f64], u: &[f64], du: &[f64]) -> MechanicalForms {
    let (m, a, b) = (&mats.mass, &mats.viscosity, &mats.elasticity);
    let forms = if same_pattern(a, b) {
        let gathers = [(&a.values[..], w), (&b.values, u), (&b.values, du)];
        let mass = (m, [w, dw]);
        column_forms(
            a,
            Some(mass),
            gathers,
            [(0, w), (0, dw), (1, dw), (2, w), (3, u), (3, du), (4, du)],
        )
    } else {
        let (mw, mdw) = (m.mul(w), m.mul(dw));
        let [mw, mdw, dmd] = [dot(&mw, w), dot(&mdw, w), dot(&mdw, dw)];
        let [aw] = column_forms(a, None, [(&a.values[..], w)], [(0, w)]);
        let [bu, bdu, dbd] = column_forms(
            b,
            None,
            [(&b.values[..], u), (&b.values, du)],
            [(0, u), (0, du), (1, du)],
        );
        [mw, mdw, dmd, aw, bu, bdu, dbd]
    };
    MechanicalForms::from(forms)
}

/// [`mechanical_forms`]' parts on a process that keeps no stiffness matrix ([`ColumnShare`]):
/// ℳ's forms over the entries of its own nodes (ℳ is whole on every process), 𝒦_A's and 𝒦_B's
/// over the cells it owns, from the kernels ([`ColumnShare::stiffness_forms`]); with Gᵀw and
/// 𝒦_B u in its rows, from the same pass over its cells.
fn shared_mechanical_forms(
    problem: &Problem,
    share: &ColumnShare,
    w: &[f64],
    dw: &[f64],
    u: &[f64],
    du: &[f64],
) -> (MechanicalForms, Vec<f64>, Vec<f64>) {
    let [mw, mdw, dmd] = share.mass_forms(&problem.matrices.mass, [w, dw], [(0, 0), (0, 1), (1, 1)]);
    let mut coupling = vec![0.0; problem.mesh.n_nodes()];
    let mut elastic_force = vec![0.0; u.len()];
    let [aw, bu, bdu, dbd] = share.stiffness_forms(
        (&problem.mesh, &problem.materials),
        [w, u, du],
        [
            (|m| m.viscosity, 0, 0),
            (|m| m.elasticity, 1, 1),
            (|m| m.elasticity, 1, 2),
            (|m| m.elasticity, 2, 2),
        ],
        RowProducts {
            coupling: Some((0, &mut coupling)),
            product: Some((|m| m.elasticity, 1, &mut elastic_force)),
        },
    );
    (
        MechanicalForms::from([mw, mdw, dmd, aw, bu, bdu, dbd]),
        coupling,
        elastic_force,
    )
}

fn same_pattern(a: &CscMatrix, b: &CscMatrix) -> bool {
    Arc::ptr_eq(&a.col_ptr, &b.col_ptr) && Arc::ptr_eq(&a.row_idx, &b.row_idx)
}

/// Columns per block of [`column_forms`]: the blocks' sums are added in a fixed order, so the
/// result does not depend on the number of threads.
const BLOCK: usize = 4096;

/// ℳ and the two vectors y_0, y_1 of its gathers (ℳᵀy_0)_c, (ℳᵀy_1)_c in [`column_forms`].
type MassGathers<'a> = (&'a VectorMass, [&'a [f64]; 2]);

/// For matrices A_g on the pattern of `pattern` and `forms[f]` = (g, x_f): the forms
/// x_fᵀ A_gᵀ y_g = y_gᵀ A_g x_f, each column's gathers (A_gᵀ y_g)_c read once for all its forms.
/// The gathers are ℳ's with `mass` = (ℳ, [y_0, y_1]) (g = 0, 1: ℳ's entries read through the
/// vector pattern, [`VectorMass::column`]), then `stored[g]` = (values of A_g, y_g) on
/// the pattern. Blocks of columns in parallel.
fn column_forms<const G: usize, const F: usize>(
    pattern: &CscMatrix,
    mass: Option<MassGathers>,
    stored: [(&[f64], &[f64]); G],
    forms: [(usize, &[f64]); F],
) -> [f64; F] {
    let n = pattern.n_cols;
    let (col_ptr, row_idx) = (&pattern.col_ptr[..], &pattern.row_idx[..]);
    let first_stored = if mass.is_some() { 2 } else { 0 };
    // The sums of a column sit side by side in 8 slots: ℳ's two and the stored matrices'.
    const { assert!(G + 2 <= 8, "at most six gathers beside ℳ's") };
    let block = |first: usize| {
        let mut sums = [0.0; F];
        for c in first..(first + BLOCK).min(n) {
            // The sums side by side: independent chains of multiply-adds (one sum after the
            // other waits on each add, and was slower than the separate mat-vecs).
            let mut column = [0.0; 8];
            let (start, end) = (col_ptr[c], col_ptr[c + 1]);
            let gather = |column: &mut [f64; 8], k: usize, r: usize| {
                for (s, (values, y)) in column[first_stored..].iter_mut().zip(&stored) {
                    *s += values[k] * y[r];
                }
            };
            match mass {
                Some((m, [y0, y1])) => {
                    let mass_column = m.column(c);
                    for (t, k) in (start..end).enumerate() {
                        let r = row_idx[k] as usize;
                        let value = mass_column.entry(t);
                        column[0] += value * y0[r];
                        column[1] += value * y1[r];
                        gather(&mut column, k, r);
                    }
                }
                None => (start..end).for_each(|k| gather(&mut column, k, row_idx[k] as usize)),
            }
            for (sum, &(g, x)) in sums.iter_mut().zip(&forms) {
                *sum += x[c] * column[g];
            }
        }
        sums
    };
    let blocks: Vec<[f64; F]> = (0..n)
        .step_by(BLOCK)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(block)
        .collect();
    blocks.iter().fold([0.0; F], |mut total, sums| {
        total.iter_mut().zip(sums).for_each(|(t, s)| *t += s);
        total
    })
}

/// ℳ_θθ, ℳ_θΔθ and 𝒦_θθ, in one pass where ℳ_θ and 𝒦_θ share a pattern (the same
/// arithmetic as three [`CscMatrix::mul`]s).
fn heat_products(mats: &Matrices, theta: &[f64], dtheta: &[f64]) -> [Vec<f64>; 3] {
    let (m, c) = (&mats.heat_mass, &mats.conduction);
    if !same_pattern(m, c) {
        return [m.mul(theta), m.mul(dtheta), c.mul(theta)];
    }
    let mut out = [vec![0.0; m.n_rows], vec![0.0; m.n_rows], vec![0.0; m.n_rows]];
    let [m_theta, m_dtheta, c_theta] = &mut out;
    for (col, (&t, &dt)) in theta.iter().zip(dtheta).enumerate() {
        for k in m.col_ptr[col]..m.col_ptr[col + 1] {
            let r = m.row_idx[k] as usize;
            m_theta[r] += m.values[k] * t;
            m_dtheta[r] += m.values[k] * dt;
            c_theta[r] += c.values[k] * t;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one-pass forms agree with mat-vecs and dots (to rounding), over more than one
    /// block of columns; the heat pass gives the mat-vecs' bits.
    #[test]
    fn one_pass_forms_are_the_mat_vecs() {
        let problem = super::super::samples::paper(96, 24, 4).unwrap();
        let mats = &problem.matrices;
        let n = mats.mass.n_rows();
        assert!(n > BLOCK && same_pattern(&mats.viscosity, &mats.elasticity));
        let rough = |seed: usize, len: usize| -> Vec<f64> {
            (0..len)
                .map(|i| (((i + seed) * 7919) % 1000) as f64 / 500.0 - 1.0)
                .collect()
        };
        let (w, dw, u, du) = (rough(1, n), rough(2, n), rough(3, n), rough(4, n));
        let f = mechanical_forms(mats, &w, &dw, &u, &du);
        let close = |a: f64, b: f64| assert!((a - b).abs() <= 1e-13 * b.abs().max(1e-300), "{a} against {b}");
        close(f.w_mass_w, mats.mass.quadratic_form(&w));
        close(f.w_mass_dw, dot(&w, &mats.mass.mul(&dw)));
        close(f.dw_mass_dw, mats.mass.quadratic_form(&dw));
        close(f.w_viscous_w, mats.viscosity.quadratic_form(&w));
        close(f.u_elastic_u, mats.elasticity.quadratic_form(&u));
        close(f.u_elastic_du, dot(&u, &mats.elasticity.mul(&du)));
        close(f.du_elastic_du, mats.elasticity.quadratic_form(&du));
        let m = mats.heat_mass.n_cols;
        let (theta, dtheta) = (rough(5, m), rough(6, m));
        let [a, b, c] = heat_products(mats, &theta, &dtheta);
        assert_eq!(a, mats.heat_mass.mul(&theta));
        assert_eq!(b, mats.heat_mass.mul(&dtheta));
        assert_eq!(c, mats.conduction.mul(&theta));
    }
}
