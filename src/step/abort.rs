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
//! Checked at each convexification iteration and before each (sub)step of the time loop: each
//! costs at most a few linear solves, so the wait after the request is that of one iteration.
//! The fast solver's direct path has no loop that long (two solves per step), so there the
//! request takes effect at the next step.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

thread_local! {
    static FLAG: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
}

/// While this lives, `flag` set means "cut the current step short" on this thread.
#[must_use = "the flag is current only while the scope lives"]
pub struct AbortScope {
    previous: Option<Arc<AtomicBool>>,
}

/// Makes `flag` the abort request of this thread's steps until the scope is dropped.
pub fn abort_on(flag: Arc<AtomicBool>) -> AbortScope {
    AbortScope {
        previous: FLAG.with(|current| current.replace(Some(flag))),
    }
}

impl Drop for AbortScope {
    fn drop(&mut self) {
        let previous = self.previous.take();
        FLAG.with(|current| *current.borrow_mut() = previous);
    }
}

/// Whether this thread's steps are asked to stop now.
pub fn requested() -> bool {
    FLAG.with(|current| current.borrow().as_ref().is_some_and(|f| f.load(Ordering::SeqCst)))
}

/// [`super::StepError::Aborted`] where a stop now is requested.
pub(crate) fn check() -> Result<(), super::StepError> {
    if requested() {
        Err(super::StepError::Aborted)
    } else {
        Ok(())
    }
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
