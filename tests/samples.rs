//! The paper's example built in code (`model::samples`) and from the default scenario are one
//! problem: the same states, to the bit, after four steps of the default solver.

use thermocontact::model::{samples, Problem, State};
use thermocontact::time::{self, TimeError};
use thermocontact::{Scenario, SolverParams};

fn first_states(problem: &Problem) -> Vec<State> {
    let mut states = Vec::new();
    time::run::<TimeError>(problem, &SolverParams::default(), |state, _| {
        if state.n <= 4 {
            states.push(state.clone());
        }
        Ok(())
    })
    .unwrap();
    states
}

#[test]
fn the_sample_is_the_default_scenario() {
    let sets = [
        "mesh.nx=16".to_string(),
        "mesh.ny=4".to_string(),
        "time.steps=16".to_string(),
    ];
    let from_toml = Scenario::load(None, &sets).unwrap().build().unwrap();
    let from_builder = samples::paper(16, 4, 16).unwrap();
    let (a, b) = (first_states(&from_toml), first_states(&from_builder));
    assert_eq!(a.len(), 4);
    assert_same_states(&a, &b);
}

#[test]
fn the_3d_sample_is_the_3d_scenario() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/paper3d.toml");
    let sets: Vec<String> = ["mesh.nx=6", "mesh.ny=2", "mesh.nz=2", "time.steps=16"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let from_toml = Scenario::load_file(&path, &sets).unwrap().build().unwrap();
    let from_builder = samples::paper_3d([6, 2, 2], 16).unwrap();
    assert_same_states(&first_states(&from_toml), &first_states(&from_builder));
}

fn assert_same_states(a: &[State], b: &[State]) {
    assert_eq!((a.len(), b.len()), (4, 4));
    for (a, b) in a.iter().zip(b) {
        assert_eq!(a.w, b.w, "w at step {}", a.n);
        assert_eq!(a.theta, b.theta, "θ at step {}", a.n);
        assert_eq!(a.xi, b.xi, "ξ at step {}", a.n);
    }
}
