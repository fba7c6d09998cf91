//! Assembly checks: patch tests, rigid-body modes, mass sums, the thermal coupling G and the Γ_C
//! weights. Each compares assembled matrices against a property P1 must have exactly.

mod common;
use common::{paper_material, solve_interior};

use thermocontact::fem::assembly::{assemble_matrices, boundary_weights};
use thermocontact::mesh::{rectangle, Mesh};
use thermocontact::Scenario;

/// A 6 × 4 mesh of (0, 3) × (0, 2) whose interior nodes are moved off the grid, so that the
/// patch tests do not profit from symmetry.
fn distorted_mesh() -> (Mesh, Vec<bool>) {
    let mut mesh = rectangle(3.0, 2.0, 6, 4);
    let boundary = mesh.nodes_on(&[0, 1, 2, 3]);
    for (p, x) in mesh.coords.iter_mut().enumerate() {
        if !boundary[p] {
            let s = (p as f64 * 12.9898).sin() * 43758.5453;
            let r = s - s.floor() - 0.5;
            x[0] += 0.15 * r;
            x[1] -= 0.12 * (r * 1.7).sin();
        }
    }
    (mesh, boundary)
}

#[test]
fn patch_test_reproduces_affine_displacement_and_temperature() {
    let (mesh, boundary) = distorted_mesh();
    let m = assemble_matrices(&mesh, &paper_material(), &[], 0.0);
    let u_exact: Vec<f64> = mesh
        .coords
        .iter()
        .flat_map(|x| [0.1 + 0.3 * x[0] - 0.2 * x[1], -0.4 + 0.05 * x[0] + 0.25 * x[1]])
        .collect();
    let mut guess = u_exact.clone();
    for (p, b) in boundary.iter().enumerate() {
        if !b {
            guess[2 * p] = 0.0;
            guess[2 * p + 1] = 0.0;
        }
    }
    let u = solve_interior(&m.elasticity, &boundary, 2, &guess);
    let err = u.iter().zip(&u_exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(err < 1e-12, "elastic patch test error {err:e}");

    let theta_exact: Vec<f64> = mesh.coords.iter().map(|x| 25.0 - 3.0 * x[0] + 7.0 * x[1]).collect();
    let guess: Vec<f64> = theta_exact
        .iter()
        .zip(&boundary)
        .map(|(t, &b)| if b { *t } else { 0.0 })
        .collect();
    let theta = solve_interior(&m.conduction, &boundary, 1, &guess);
    let err = theta
        .iter()
        .zip(&theta_exact)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-12, "thermal patch test error {err:e}");

    // A constant temperature exerts no net force on interior nodes: ∫ cθ div φ_p = 0.
    let force = m.coupling.mul(&vec![25.0; mesh.n_nodes()]);
    for (p, b) in boundary.iter().enumerate() {
        if !b {
            assert!(force[2 * p].abs() < 1e-10 && force[2 * p + 1].abs() < 1e-10);
        }
    }
}

#[test]
fn rigid_body_modes_are_in_the_kernel_of_the_stiffness() {
    let (mesh, _) = distorted_mesh();
    let m = assemble_matrices(&mesh, &paper_material(), &[], 0.0);
    type Mode = fn(&[f64; 3]) -> [f64; 2];
    let modes: [Mode; 3] = [|_| [1.0, 0.0], |_| [0.0, 1.0], |x| [-x[1], x[0]]];
    let scale = m.elasticity.values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let grams = thermocontact::fem::assembly::NormGrams::assemble(&mesh);
    for mode in &modes {
        let r: Vec<f64> = mesh.coords.iter().flat_map(mode).collect();
        for k in [&m.elasticity, &m.viscosity, &grams.strain] {
            let kr = k.mul(&r);
            let worst = kr.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(worst < 1e-12 * scale, "rigid mode not in kernel: {worst:e}");
        }
    }
    // A stretch is not a rigid mode: it must not vanish.
    let stretch: Vec<f64> = mesh.coords.iter().flat_map(|x| [x[0], 0.0]).collect();
    assert!(m.elasticity.quadratic_form(&stretch) > 1.0);
}

#[test]
fn masses_sum_to_density_times_area() {
    let mesh = rectangle(40.0, 10.0, 16, 4);
    let m = assemble_matrices(&mesh, &paper_material(), &[], 0.0);
    for c in 0..2 {
        let e: Vec<f64> = (0..mesh.n_nodes() * 2)
            .map(|i| if i % 2 == c { 1.0 } else { 0.0 })
            .collect();
        assert!((m.mass.quadratic_form(&e) - 100.0 * 400.0).abs() < 1e-8);
    }
    let ones = vec![1.0; mesh.n_nodes()];
    assert!((m.heat_mass.quadratic_form(&ones) - 10.0 * 400.0).abs() < 1e-9);
}

#[test]
fn coupling_matches_a_hand_computed_element() {
    // One cell (0,1)²: triangles (0,1,3) and (0,3,2) with nodes 0=(0,0), 1=(1,0), 2=(0,1), 3=(1,1).
    let mesh = rectangle(1.0, 1.0, 1, 1);
    let mut material = paper_material();
    material.expansion = 2.0;
    let m = assemble_matrices(&mesh, &material, &[], 0.0);
    // G_(0,x),0 = ∫ c ψ₀ ∂_x φ₀: only triangle (0,1,3) has ∂_x φ₀ = −1 (area ½, ∫ψ₀ = 1/6):
    // 2 · (−1) · 1/6; triangle (0,3,2) has φ₀ = 1 − y, ∂_x φ₀ = 0.
    assert!((m.coupling.get(0, 0) + 2.0 / 6.0).abs() < 1e-15);
    // G_(3,y),1: node 3 = (1,1) on triangle (0,1,3) has φ₃ = y, ∂_y φ₃ = 1; ∫ψ₁ = 1/6 there.
    assert!((m.coupling.get(7, 1) - 2.0 / 6.0).abs() < 1e-15);
    // A uniform velocity has zero divergence: every column of G sums to zero per component.
    for q in 0..4 {
        for c in 0..2 {
            let sum: f64 = (0..4).map(|p| m.coupling.get(2 * p + c, q)).sum();
            assert!(sum.abs() < 1e-15);
        }
    }
}

#[test]
fn contact_weights_sum_to_the_contact_length() {
    let mesh = rectangle(40.0, 10.0, 40, 10);
    let bottom = mesh.part_index("bottom").unwrap();
    let w = boundary_weights(&mesh, &[bottom]);
    assert!((w.iter().sum::<f64>() - 40.0).abs() < 1e-12);
    assert!((w[0] - 0.5).abs() < 1e-15 && (w[1] - 1.0).abs() < 1e-15);
    let problem = Scenario::default().build().unwrap();
    assert!((problem.contact_measure() - 40.0).abs() < 1e-12);
    // The clamped corner (0, 0) carries no friction; the corner (40, 0) is a contact node with a
    // prescribed temperature.
    assert_eq!(Some(problem.contact.len()), Scenario::default().mesh.nx);
    assert!(problem.contact.last().unwrap().theta_dof.is_none());
}
