//! Cutting a step short: a request from outside the time loop (a second Ctrl-C) that the step's
//! loops read between their iterations, so that a long step (a large mesh, a coarse k, deep
//! cutbacks) need not be finished before the run can stop.
//!
//! The request is an atomic flag that the driver makes *current on its thread* for the time of
//! its march ([`abort_on`]); the loops read it there ([`requested`]). A thread-local rather than
//! a field of [`super::SolverParams`]: the settings stay plain data (compared, printed, built
//! from a scenario), and runs on other threads (tests in parallel, a Python caller's) each see
//! only their own flag. A step cut short returns [`super::StepError::Aborted`]; it is not a
//! failure of the step (no cutback retries it), and the driver reports it as the interruption
//! it is, at the last completed step (which it keeps as a checkpoint).
//!
//! Checked before each (sub)step of the time loop, at each convexification iteration and, on
//! the iterative path, before each Newton iteration's solve: the wait after the request is that
//! of one linear solve there, of one iteration of the other loops.
//! The fast solver's direct path has no loop that long (two solves per step), so there the
//! request takes effect at the next step.
//!
//! **Over the ranks** of a distributed run (`abort_on_ranks`, in a build with the `mpi`
//! feature) the ranks reach those checks at the same points (they take the same branches from
//! the same numbers: `crate::step`'s ranks), and each check is one reduction of one integer:
//! every rank leaves the step at the same check when any rank was asked to, so none waits in a
//! collective call for a rank that left. (`mpirun` sends a Ctrl-C on to the ranks as SIGTERM
//! and kills them a second later: cutting the step short is what lets them write the folder in
//! that second.)

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A thread's request flag, and whether its checks agree over the ranks.
type Current = Option<(Arc<AtomicBool>, bool)>;

thread_local! {
    static FLAG: RefCell<Current> = const { RefCell::new(None) };
}

/// While this lives, `flag` set means "cut the current step short" on this thread.
#[must_use = "the flag is current only while the scope lives"]
pub struct AbortScope {
    previous: Current,
}

/// Makes `flag` the abort request of this thread's steps until the scope is dropped.
pub fn abort_on(flag: Arc<AtomicBool>) -> AbortScope {
    AbortScope {
        previous: FLAG.with(|current| current.replace(Some((flag, false)))),
    }
}

/// [`abort_on`] for the steps of a distributed run: each check asks every rank (collective:
/// every rank of MPI's world checks at the same points).
#[cfg(feature = "mpi")]
pub fn abort_on_ranks(flag: Arc<AtomicBool>) -> AbortScope {
    AbortScope {
        previous: FLAG.with(|current| current.replace(Some((flag, true)))),
    }
}

impl Drop for AbortScope {
    fn drop(&mut self) {
        let previous = self.previous.take();
        FLAG.with(|current| *current.borrow_mut() = previous);
    }
}

/// Whether this thread's steps are asked to stop now (by this process's flag).
pub fn requested() -> bool {
    FLAG.with(|current| current.borrow().as_ref().is_some_and(|(f, _)| f.load(Ordering::SeqCst)))
}

/// [`super::StepError::Aborted`] where a stop now is requested (over the ranks: by any rank).
pub(crate) fn check() -> Result<(), super::StepError> {
    let (here, over_ranks) = FLAG.with(|current| match current.borrow().as_ref() {
        Some((f, over_ranks)) => (f.load(Ordering::SeqCst), *over_ranks),
        None => (false, false),
    });
    let anywhere = if over_ranks { any_rank(here)? } else { here };
    if anywhere {
        Err(super::StepError::Aborted)
    } else {
        Ok(())
    }
}

/// Whether `here` holds on any rank (one reduction; collective).
#[cfg(feature = "mpi")]
fn any_rank(here: bool) -> Result<bool, super::StepError> {
    use crate::la::mpi::{Communicator, Reduction};
    let mut flag = [usize::from(here)];
    Communicator::world()?.all_reduce_usize(&mut flag, Reduction::Max)?;
    Ok(flag[0] > 0)
}

#[cfg(not(feature = "mpi"))]
fn any_rank(here: bool) -> Result<bool, super::StepError> {
    Ok(here)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flag_is_current_on_its_thread_for_the_scope_only() {
        let flag = Arc::new(AtomicBool::new(true));
        assert!(!requested());
        {
            let _scope = abort_on(Arc::clone(&flag));
            assert!(requested());
            assert!(std::thread::spawn(|| !requested()).join().unwrap());
        }
        assert!(!requested());
    }
}
