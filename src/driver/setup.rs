//! Setting a run up: the state it starts from (fresh, or a checkpoint's with its tally), the
//! layout of its frames (whole, or a rank's piece) and the solver (the step matrix factored or
//! preconditioned, the step solver set up on it).

use std::time::Instant;

use super::files::identity;
use super::ranks::Ranks;
use super::snapshot::Layout;
use super::summary::{Tally, Timings};
use super::{OutputPlan, Restart};
use crate::error::Error;
use crate::model::Problem;
use crate::model::State;
use crate::output::checkpoint::CheckpointError;
use crate::step::{LinearSystem, SolverParams, StepSolver};
use crate::time::Levels;

/// The starting state and the run's tally: fresh, or `restart`'s checkpoint's (checked against
/// the problem and the plan), with the restart counted.
pub(super) fn start(problem: &Problem, plan: &OutputPlan, restart: Option<&Restart>) -> Result<(State, Tally), Error> {
    let Some(Restart { path, checkpoint }) = restart else {
        return Ok((State::initial(problem), Tally::new()));
    };
    checkpoint.check(
        path,
        &identity(problem, plan),
        problem.time.steps,
        &State::initial(problem),
    )?;
    let mut tally: Tally = serde_json::from_value(checkpoint.record.clone()).map_err(|_| CheckpointError::Damaged {
        path: path.clone(),
        reason: "its record of the run is not valid",
    })?;
    tally.restarts.push(checkpoint.state.n);
    Ok((checkpoint.state.clone(), tally))
}

/// The solver's levels (k, and k/2, k/4, … as cutbacks need them), and the set-up's timings:
/// the problem's assembly, the factorization (or preconditioner), the step solver's set-up.
pub(super) fn levels<'p>(problem: &'p Problem, params: &SolverParams) -> Result<(Levels<'p>, Timings), Error> {
    let clock = Instant::now();
    let linear = LinearSystem::new(problem, problem.time_step(), params)?;
    let factorization = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let levels = Levels::new(problem, params, StepSolver::new(problem, linear, params)?);
    let timings = Timings {
        assembly: problem.build_seconds,
        factorization,
        solver_setup: clock.elapsed().as_secs_f64(),
        ..Timings::default()
    };
    Ok((levels, timings))
}

/// How this process writes its frames (with the seconds it took): whole (one process, or no
/// folder), or, as rank r of a distributed run with a folder, the piece of the cells of its
/// part of the run's partition ([`Ranks::own_cells`]: computed by the problem's build on ranks,
/// or here, collectively).
pub(super) fn layout(problem: &Problem, ranks: Option<Ranks>, folder: bool) -> Result<(Layout, f64), Error> {
    let Some(ranks) = ranks.filter(|_| folder) else {
        return Ok((Layout::Whole, 0.0));
    };
    let clock = Instant::now();
    let grid = crate::output::Grid {
        dim: problem.dim(),
        points: &problem.mesh.coords,
        cells: &problem.mesh.cells,
    };
    let layout = Layout::Piece {
        rank: ranks.rank,
        n_ranks: ranks.size,
        piece: crate::output::GridPiece::new(&grid, ranks.own_cells(problem)?),
    };
    Ok((layout, clock.elapsed().as_secs_f64()))
}
