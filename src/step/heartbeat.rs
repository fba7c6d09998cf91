//! Progress inside a long step: the outer loops report their iteration and worst criterion, and
//! a step that has run longer than [`AFTER`] prints it, at most once per [`EVERY`].
//!
//! At 291k unknowns one step took 95 s with no line printed: the driver's lines come between
//! steps. The outer loops (`convexification::convexify`, the fixed point on the contact pressure
//! in `select`) call `outer` once per iteration, right after their criteria are computed. Like
//! [`super::abort`], the sink is current *on the driver's thread* for the time of its march
//! ([`report_to`]); without one (tests, studies, a Python caller) `outer` returns at once. With
//! one, it costs a clock read and a comparison per outer iteration (tens of nanoseconds, against
//! at least one linear solve per iteration): the line is formatted only when it is due.
//!
//! The line names the step being solved ([`step_started`], set by the driver before each step),
//! the loop and its iteration, the worst criterion of the iterate (value over tolerance, as a
//! failure reports it: [`super::worst_criterion`]) and the step's time so far:
//!
//! ```text
//!   step 12 (t = 0.1875): convexification iteration 40, max |Δw_τ| / max |w_τ| = 3.2e-4 (tolerance 1.0e-6), 14.2 s
//! ```
//!
//! A step shorter than [`AFTER`] prints nothing, so short runs' logs are unchanged. Rejected: a
//! timer thread that prints on its own (it would need the loops' figures shared across threads,
//! and would print between iterations that never end); a callback in
//! [`super::SolverParams`] (the settings stay plain data, as for `abort`).

use std::cell::RefCell;
use std::time::{Duration, Instant};

use super::Criterion;

/// How long a step runs before its first progress line.
pub const AFTER: Duration = Duration::from_secs(3);

/// The least time between two progress lines of a step.
pub const EVERY: Duration = Duration::from_secs(5);

/// Where a step's progress lines go, and when.
struct Heartbeat {
    sink: Box<dyn FnMut(&str)>,
    pace: Pace,
    /// "step 12 (t = 0.1875)".
    label: String,
}

thread_local! {
    static HEARTBEAT: RefCell<Option<Heartbeat>> = const { RefCell::new(None) };
}

/// The rate limit of the lines: the first when the step has run `after`, then at most one per
/// `every`. Clock-free (the caller passes `now`), so a test can drive it.
#[derive(Debug, Clone, Copy)]
pub struct Pace {
    after: Duration,
    every: Duration,
    started: Instant,
    last: Option<Instant>,
}

impl Pace {
    /// The pace of a step started at `started`.
    pub fn new(after: Duration, every: Duration, started: Instant) -> Self {
        Pace {
            after,
            every,
            started,
            last: None,
        }
    }

    /// A new step starts at `now`.
    pub fn restart(&mut self, now: Instant) {
        self.started = now;
        self.last = None;
    }

    /// Whether a line is due at `now` (and if so, it counts as printed).
    pub fn due(&mut self, now: Instant) -> bool {
        let due = match self.last {
            None => now.duration_since(self.started) >= self.after,
            Some(last) => now.duration_since(last) >= self.every,
        };
        if due {
            self.last = Some(now);
        }
        due
    }

    /// Seconds since the step started.
    pub fn elapsed(&self, now: Instant) -> f64 {
        now.duration_since(self.started).as_secs_f64()
    }
}

/// While this lives, long steps on this thread report to `sink`: the first line after `after`,
/// then at most one per `every`.
#[must_use = "the sink is current only while the scope lives"]
pub struct HeartbeatScope {
    previous: Option<Heartbeat>,
}

/// Makes `sink` the receiver of this thread's progress lines until the scope is dropped.
pub fn report_to(sink: Box<dyn FnMut(&str)>, after: Duration, every: Duration) -> HeartbeatScope {
    let beat = Heartbeat {
        sink,
        pace: Pace::new(after, every, Instant::now()),
        label: String::new(),
    };
    HeartbeatScope {
        previous: HEARTBEAT.with(|current| current.replace(Some(beat))),
    }
}

impl Drop for HeartbeatScope {
    fn drop(&mut self) {
        let previous = self.previous.take();
        HEARTBEAT.with(|current| *current.borrow_mut() = previous);
    }
}

/// Step `n`, ending at time `t`, starts now: its lines are timed from here.
pub fn step_started(n: usize, t: f64) {
    HEARTBEAT.with(|current| {
        if let Some(beat) = current.borrow_mut().as_mut() {
            beat.label = format!("step {n} (t = {t})");
            beat.pace.restart(Instant::now());
        }
    });
}

/// Iteration `m` of the outer loop `loop_name` ended with the stop criteria `checks`
/// (criterion, value, tolerance): a progress line where one is due.
pub(crate) fn outer(loop_name: &str, m: usize, checks: &[(Criterion, f64, f64)]) {
    if checks.is_empty() {
        return;
    }
    HEARTBEAT.with(|current| {
        let mut current = current.borrow_mut();
        let Some(beat) = current.as_mut() else { return };
        let now = Instant::now();
        if beat.pace.due(now) {
            let text = line(&beat.label, loop_name, m, checks, beat.pace.elapsed(now));
            (beat.sink)(&text);
        }
    });
}

/// The (sub)step from `from` to `to` did not converge (`failure`) and is cut back into two of
/// depth `depth` (substeps of k/2^depth): a line at once, whatever the pace, so that a log says
/// why a step was cut back (the loop, the criterion and by how much, a cycle's period).
pub(crate) fn cut_back(from: f64, to: f64, depth: usize, failure: &super::StepFailure) {
    HEARTBEAT.with(|current| {
        let mut current = current.borrow_mut();
        let Some(beat) = current.as_mut() else { return };
        let text = format!(
            "  {}: from t = {from} to {to}: {failure}; cut back to substeps of k/{}",
            beat.label,
            1usize << depth
        );
        (beat.sink)(&text);
    });
}

/// The progress line of iteration `m` of `loop_name` in the step `label`, `seconds` into it.
pub fn line(label: &str, loop_name: &str, m: usize, checks: &[(Criterion, f64, f64)], seconds: f64) -> String {
    let (criterion, value, tolerance) = super::worst_criterion(checks);
    format!(
        "  {label}: {loop_name} iteration {m}, {} = {value:.1e} (tolerance {tolerance:.1e}), {seconds:.1} s",
        criterion.describe()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    #[test]
    fn the_first_line_comes_after_the_threshold_then_at_most_one_per_interval() {
        let t0 = Instant::now();
        let s = Duration::from_secs;
        let mut pace = Pace::new(s(3), s(5), t0);
        let due: Vec<bool> = [1, 2, 3, 4, 7, 8, 9, 13].iter().map(|&t| pace.due(t0 + s(t))).collect();
        assert_eq!(due, [false, false, true, false, false, true, false, true]);
        pace.restart(t0 + s(20));
        assert!(!pace.due(t0 + s(22)), "a new step waits for the threshold again");
        assert!(pace.due(t0 + s(23)));
        assert_eq!(pace.elapsed(t0 + s(24)), 4.0);
    }

    #[test]
    fn the_line_names_the_step_the_loop_and_the_worst_criterion() {
        let checks = [(Criterion::IncrementW, 3.2e-4, 1e-6), (Criterion::NodalLaw, 2e-6, 1e-6)];
        assert_eq!(
            line("step 12 (t = 0.1875)", "convexification", 40, &checks, 14.23),
            "  step 12 (t = 0.1875): convexification iteration 40, max |Δw_τ| / max |w_τ| = 3.2e-4 (tolerance 1.0e-6), 14.2 s"
        );
    }

    #[test]
    fn a_zero_threshold_prints_every_iteration_and_none_without_a_sink() {
        let lines = Arc::new(Mutex::new(Vec::new()));
        let checks = [(Criterion::IncrementPressure, 0.5, 1e-6)];
        outer("contact pressure", 1, &checks);
        {
            let sink = Arc::clone(&lines);
            let _scope = report_to(
                Box::new(move |l| sink.lock().unwrap().push(l.to_string())),
                Duration::ZERO,
                Duration::ZERO,
            );
            step_started(3, 0.5);
            outer("contact pressure", 1, &checks);
            outer("contact pressure", 2, &checks);
        }
        outer("contact pressure", 3, &checks);
        let lines = lines.lock().unwrap();
        assert_eq!(lines.len(), 2);
        assert!(lines[1].starts_with(
            "  step 3 (t = 0.5): contact pressure iteration 2, max |Δp| / max p (contact pressure) = 5.0e-1"
        ));
    }
}
