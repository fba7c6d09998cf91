//! Stopping a run from outside: a flag that signal handlers (or a caller on another thread)
//! set, and that the run reads after each step.
//!
//! The flag is a plain atomic integer, so a signal handler may set it (an allocation or a lock
//! there is undefined behaviour). The run then finishes the step it is on, writes its files and
//! returns [`Error::Interrupted`] ([`Stop`], the run's observer of
//! the flag).
//!
//! A second, more urgent request ([`StopFlag::request_now`], the CLI's second Ctrl-C) also cuts
//! the step it is on short ([`crate::step::abort`], read inside the step's loops): the run then
//! ends at the last *completed* step, and still writes its files (the checkpoint of that step,
//! the frames, `summary.json` saying `interrupted`), so that the folder continues with
//! `--restart` as after a single request. Ending the process instead would leave `running`, no
//! checkpoint and perhaps a half-written frame.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use crate::error::{Error, Interruption};
use crate::model::State;
use crate::step::StepError;

/// A request to stop a run after the current step (or, [`StopFlag::request_now`], within it);
/// clones share the flag.
#[derive(Debug, Clone, Default)]
pub struct StopFlag(Arc<AtomicUsize>, Arc<AtomicBool>);

const CAUSES: [Interruption; 3] = [Interruption::Interrupt, Interruption::Terminate, Interruption::Caller];

impl StopFlag {
    /// A flag that nobody has set.
    pub fn new() -> Self {
        StopFlag::default()
    }

    /// Asks the run to stop, for `cause` (the first request wins).
    pub fn request(&self, cause: Interruption) {
        let _ = self
            .0
            .compare_exchange(0, Self::code(cause), Ordering::SeqCst, Ordering::SeqCst);
    }

    /// Asks the run to stop within the current step, for `cause` (if no request came before):
    /// the step is cut short and the run ends at the last completed one.
    pub fn request_now(&self, cause: Interruption) {
        self.request(cause);
        self.1.store(true, Ordering::SeqCst);
    }

    /// The flag that cuts the current step short, for [`crate::step::abort::abort_on`] (and a
    /// signal handler: storing `true` is the request).
    pub fn now(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.1)
    }

    /// Why the run was asked to stop, if it was.
    pub fn requested(&self) -> Option<Interruption> {
        match self.0.load(Ordering::SeqCst) {
            0 => None,
            code => CAUSES.get(code - 1).copied(),
        }
    }

    /// The flag's integer, for a signal handler: storing [`StopFlag::code`]`(cause)` in it is a
    /// request (`signal_hook::flag::register_usize`).
    pub fn atomic(&self) -> Arc<AtomicUsize> {
        Arc::clone(&self.0)
    }

    /// The value that stands for `cause` in [`StopFlag::atomic`].
    pub fn code(cause: Interruption) -> usize {
        CAUSES.iter().position(|&c| c == cause).expect("every cause is listed") + 1
    }
}

/// The stop observer: the run's flag (if it has one), read after each step.
///
/// **Over ranks** (a distributed run, `mpirun`): each rank has its own flag, set by the signal
/// it receives (Open MPI's `mpirun` passes a Ctrl-C on as SIGTERM to every rank, then SIGKILL
/// after `odls_base_sigkill_timeout`, 1 s by default), maybe during different steps. So the
/// ranks agree after each step (the largest request over the ranks, one reduction of one
/// integer) and stop after the same one; a step cut short is cut at the same check on every
/// rank ([`crate::step::abort`]'s checks agree over the ranks too).
pub(super) struct Stop<'a> {
    pub flag: Option<&'a StopFlag>,
    /// The run's steps are collective over the ranks of MPI's world.
    pub over_ranks: bool,
}

impl Stop<'_> {
    /// The scope in which the flag cuts a step short from outside ([`crate::step::abort`]):
    /// over ranks, the ranks agree at each check.
    pub fn cutting_steps_short(&self) -> Option<crate::step::abort::AbortScope> {
        let now = self.flag?.now();
        #[cfg(feature = "mpi")]
        if self.over_ranks {
            return Some(crate::step::abort::abort_on_ranks(now));
        }
        Some(crate::step::abort::abort_on(now))
    }

    /// Why the run was asked to stop, if it was: over ranks, the request of any rank.
    fn requested(&self) -> Result<Option<Interruption>, Error> {
        let local = self.flag.and_then(StopFlag::requested);
        if !self.over_ranks {
            return Ok(local);
        }
        #[cfg(feature = "mpi")]
        {
            use crate::la::mpi::{Communicator, Reduction};
            let comm = Communicator::world().map_err(crate::step::StepError::from)?;
            let mut code = [local.map_or(0, StopFlag::code)];
            comm.all_reduce_usize(&mut code, Reduction::Max)
                .map_err(crate::step::StepError::from)?;
            Ok(CAUSES.get(code[0].wrapping_sub(1)).copied())
        }
        #[cfg(not(feature = "mpi"))]
        Ok(local)
    }

    /// The error that ended the march at `last`, as the run reports it: a step cut short
    /// ([`StepError::Aborted`]) is the interruption it was asked for (over ranks: by any rank;
    /// collective then, as every rank's step is cut short at the same check), after `last`.
    pub fn reported(&self, error: Error, last: &State) -> Error {
        match error {
            Error::Step(StepError::Aborted) => Error::Interrupted {
                step: last.n,
                time: last.t,
                cause: self.requested().ok().flatten().unwrap_or(Interruption::Caller),
            },
            other => other,
        }
    }

    /// After the step that reached `state`: [`Error::Interrupted`] where a stop was requested.
    pub fn step(&self, state: &State) -> Result<(), Error> {
        match self.requested()? {
            Some(cause) => Err(Error::Interrupted {
                step: state.n,
                time: state.t,
                cause,
            }),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_request_wins_and_codes_round_trip() {
        let flag = StopFlag::new();
        assert_eq!(flag.requested(), None);
        for cause in CAUSES {
            let f = StopFlag::new();
            f.atomic().store(StopFlag::code(cause), Ordering::SeqCst);
            assert_eq!(f.requested(), Some(cause));
        }
        let shared = flag.clone();
        shared.request(Interruption::Terminate);
        flag.request(Interruption::Interrupt);
        assert_eq!(flag.requested(), Some(Interruption::Terminate));
    }
}
