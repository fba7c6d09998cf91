//! The iterative linear solver (GMRES + ILU(0), `la`) against the direct LDLᵀ on
//! the step matrix of a small 3D problem (the 3D example of `model::samples`, coarsened), at the paper's
//! time step and at a large one.

use thermocontact::la::{gmres, GmresParams, Ilu0};
use thermocontact::model::{rows_of_symmetric_form, samples, State};
use thermocontact::step::StepSystem;

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

#[test]
fn iterative_and_direct_solves_agree_on_a_3d_step_matrix() {
    for steps in [64, 8] {
        let problem = samples::paper_3d([12, 4, 4], steps).unwrap();
        let system = StepSystem::new(&problem).unwrap();
        let n_w = system.n_w();
        let a = rows_of_symmetric_form(system.matrix(), n_w);
        let ilu = Ilu0::new(&a).unwrap();
        let params = GmresParams {
            rtol: 1e-12,
            ..GmresParams::default()
        };

        // The first step's right-hand side, and a unit tangential load at a contact node.
        let k = problem.time_step();
        let free = system.rhs(&problem, &State::initial(&problem), k).unwrap();
        let mut unit = vec![0.0; system.n_unknowns()];
        unit[problem.contact[problem.contact.len() / 2].tangent_dofs[0].unwrap()] = 1.0;
        for b in [free, unit] {
            let mut reference = b.clone();
            system.solve_in_place(&mut reference).unwrap();
            let mut xi = vec![0.0; b.len()];
            let info = gmres(&a, &ilu, &b, &mut xi, &params).unwrap();
            assert!(info.iterations > 0 && info.iterations < 100, "k = 1/{steps}: {info:?}");
            let diff = max_rel_diff(&reference, &xi);
            assert!(
                diff < 1e-8,
                "k = 1/{steps}: GMRES + ILU(0) differs by {diff:e} ({info:?})"
            );
        }
    }
}
