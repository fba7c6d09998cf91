//! Helpers shared by the integration tests (each test binary uses some of them).
#![allow(dead_code)]

use faer::linalg::solvers::Solve;
use thermocontact::la::CscMatrix;
use thermocontact::material::Material;
use thermocontact::Scenario;

/// The paper's example on a coarse grid (16 × 4 cells, 16 steps) with `key=value` overrides.
pub fn coarse(overrides: &[&str]) -> Scenario {
    let mut all: Vec<String> = ["mesh.nx=16", "mesh.ny=4", "time.steps=16"].map(String::from).to_vec();
    all.extend(overrides.iter().map(|s| s.to_string()));
    Scenario::load(None, &all).unwrap()
}

/// The material of the paper's Section 6 example.
pub fn paper_material() -> Material {
    thermocontact::model::samples::paper_material()
}

/// Solves K_ii x_i = −K_ib x_b (dense) for the nodes not marked fixed; `dofs` per node.
pub fn solve_interior(k: &CscMatrix, fixed: &[bool], dofs: usize, values: &[f64]) -> Vec<f64> {
    let free: Vec<usize> = (0..k.n_rows).filter(|&i| !fixed[i / dofs]).collect();
    let n = free.len();
    let mut a = faer::Mat::<f64>::zeros(n, n);
    let mut b = faer::Mat::<f64>::zeros(n, 1);
    for (r, &i) in free.iter().enumerate() {
        for (j, v) in values.iter().enumerate() {
            if fixed[j / dofs] {
                b[(r, 0)] -= k.get(i, j) * v;
            }
        }
        for (c, &j) in free.iter().enumerate() {
            a[(r, c)] = k.get(i, j);
        }
    }
    let x = a.partial_piv_lu().solve(&b);
    let mut out = values.to_vec();
    for (r, &i) in free.iter().enumerate() {
        out[i] = x[(r, 0)];
    }
    out
}
