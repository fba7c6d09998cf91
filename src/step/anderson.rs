//! Anderson acceleration of the convexification loop's friction bounds, in the loop's linear
//! tail only.
//!
//! The loop is a fixed-point iteration on the bounds, g ← T(g) = b(|w(g)|), w(g) the solution
//! of the convex problem with the bounds frozen at g. Where the stick/slip split no longer
//! changes, T is smooth and the loop converges linearly: on the 3D example with S = 8 (a slip
//! zone that the mesh resolves) the nonmonotone law's residual falls about 3.2× per iterate for
//! eight iterates in every step, on every mesh from 134k to 1.05M unknowns. Anderson's method
//! of depth m (type II, Walker and Ni 2011) takes the next bounds as the combination of the last
//! m + 1 images T(g_j) whose residuals f_j = T(g_j) − g_j combine to the least norm:
//!
//! ```text
//! γ = argmin ‖f_m − ΔF γ‖₂,   ΔF = [f_{j+1} − f_j],   g_{m+1} = T(g_m) − ΔT γ,   ΔT = [T(g_{j+1}) − T(g_j)]
//! ```
//!
//! Its fixed points are the loop's, and in a contracting tail it reaches the same one.
//!
//! **Only in the tail.** Applied from a step's first iterate (the iterative path's first
//! Anderson, [`super::newton_krylov`]'s header), it cycled or reached other solutions: while
//! nodes change between stick and slip, T is not smooth, and near a fixed point that the loop
//! repels it leaves along another direction. So a combination is taken only
//! - between iterates with the same stick/slip split (the history is cleared at every change),
//! - in the loop's linear tail: it starts where the law's residual fell by more than 1.5× in
//!   each of two plain iterates, by factors within 2× of each other, or in each of three by
//!   factors within 2 % of each other however slowly (a slow linear contraction, one factor
//!   dominating), and lasts while the residual keeps falling by more than 1.5× per iterate,
//!
//! and a split that changes right after a combination ends the acceleration for the step (the
//! loop goes on plain). The bounds are kept non-negative.
//!
//! Measured (release, k = 1/64, 4 steps, Newton iterations per step; the same slip counts at
//! every step): the 3D example with S = 8 at 134k unknowns, depth 0 (off), 1, 2, 3, 5: 14.75,
//! 13.0, 12.25, 11.75, 13.0 (depth 5 combines too early in the first step), the iterates per
//! step 11.75 → 9.25 at depth 2; at k = 1/8 (47k) 17.6 → 14.25; the example itself (S = 150)
//! at 47k and k = 1/8 88.5 → 80.75. At k = 1/64 the example's tails are short (its steps
//! converge 50–100× per iterate once the split settles): the rule does not fire and the
//! iterates are the plain loop's (5.75 and 9.5 at 47k and 291k). Without the rule (Anderson
//! from every iterate with an unchanged split) depth 2 cost 6.5 instead of 5.75 there, and
//! from the first iterate it cycled (the header of [`super::newton_krylov`]). Depth 2 is the
//! default (`solver.anderson_depth`; 0 turns it off).
//!
//! **Slow tails (2026-11-29, fourth session).** Traced on a thin slab at k = 1/8 (104 × 6 × 6
//! cells, 8 sweeps through two layers), the longest step (153 iterates) was a tail falling
//! 1.105× per iterate for 140 iterates, the same factor to three digits: a contraction with one
//! dominant factor, where Anderson's combination gains most, but slower than the 1.5× the rule
//! asked for. Three plain falls within 2 % of each other now start the tail too. Measured
//! (release, the same build with and without; Newton iterations): the 3D example on the
//! iterative path (40 × 10 × 10 cells, 64 steps, the paper's loop) 1 256 → 1 024, Krylov
//! iterations 2 219 → 1 869, the same slip counts at every step, the contact fields within
//! 5·10⁻⁶ of their largest (the plain loop stops once its increments fall below ε_conv = 10⁻⁶,
//! which in a tail contracting 0.9 per iterate leaves it up to 10⁻⁵ from the fixed point);
//! `own_laws3d.toml` 4 005 → 2 772 (within 10⁻⁵); 64 × 16 × 16 cells at k = 1/8 (8 steps)
//! 531 → 486 (within 1.6·10⁻⁶), 80 × 4 × 4 at k = 1/8 1 326 → 1 234 (3.7·10⁻⁸); the thin
//! slab 1 180 → 767 and 11.7 → 5.3 s, no step cut back (one before), its slip counts other
//! from step 6 on (it has several solutions per step at k = 1/8; with the paper's loop 3 757
//! → 3 444, steps 7–9 on others); the 2D example and the pad: the same bytes (their tails are
//! fast). The window: within 0.5 %, 1 071, 2 903 and 509 of the first three; within 5 %,
//! 1 007, 2 728 and 486; 2 % kept, a looser window taking falls that are not one rate.
//!
//! Depends on: [`crate::la::vector`] (dot products).

use crate::la::vector::dot;

/// Anderson acceleration of the bounds, for one step's convexification loop.
#[derive(Debug, Clone)]
pub(super) struct TailAnderson {
    /// m: the combination takes the last m + 1 iterates (0: off).
    depth: usize,
    /// The split of the iterates in the history (true: slip).
    split: Vec<bool>,
    /// (g_j, T(g_j)), oldest first.
    history: Vec<(Vec<f64>, Vec<f64>)>,
    /// The bounds the next convex problem takes instead of T(g_m).
    next: Option<Vec<f64>>,
    /// The law's residual at the last iterate, and the factor it fell by.
    last_law: f64,
    last_ratio: f64,
    /// The fall before that.
    prev_ratio: f64,
    /// In the loop's linear tail (below).
    in_tail: bool,
    /// The last iterate started from a combination.
    combined_last: bool,
    /// A split changed right after a combination: no more for this step.
    ended: bool,
    /// Combinations taken.
    combinations: usize,
}

/// The smallest fall of the law's residual per iterate that counts as converging.
const CONVERGING: f64 = 1.5;

/// Two successive falls within this factor of each other: a linear rate.
const STEADY: f64 = 2.0;

/// Three successive falls, however slow, within this factor of each other: a slow linear rate,
/// one factor dominating the contraction (where the combination gains most).
const SLOW_STEADY: f64 = 1.02;

impl TailAnderson {
    /// Off at depth 0.
    pub(super) fn new(depth: usize) -> Self {
        TailAnderson {
            depth,
            split: Vec::new(),
            history: Vec::new(),
            next: None,
            last_law: f64::INFINITY,
            last_ratio: 0.0,
            prev_ratio: 0.0,
            in_tail: false,
            combined_last: false,
            ended: false,
            combinations: 0,
        }
    }

    /// The bounds the next convex problem freezes, where a combination gave them (taken: the
    /// next call returns `None` until the next record).
    pub(super) fn take_bounds(&mut self) -> Option<Vec<f64>> {
        self.next.take()
    }

    /// Combinations taken so far in this step.
    pub(super) fn combinations(&self) -> usize {
        self.combinations
    }

    /// Records an iterate: the bounds `frozen` it was solved with, their image `image` = b(|w|)
    /// at its solution, the solution's split and the nonmonotone law's residual there; prepares
    /// the next bounds where the tail rule holds.
    pub(super) fn record(&mut self, split: Vec<bool>, frozen: Vec<f64>, image: Vec<f64>, law: f64) {
        if self.depth == 0 || self.ended {
            return;
        }
        let mut ratio = self.last_law / law;
        if split != self.split {
            if self.combined_last {
                self.ended = true;
                self.next = None;
                self.history.clear();
                return;
            }
            self.split = split;
            self.in_tail = false;
            // A fall across a split change is no rate of the new split's tail.
            ratio = 0.0;
        } else if self.in_tail {
            // In the tail the law keeps falling (faster after a combination).
            self.in_tail = ratio > CONVERGING;
        } else {
            // The tail starts with two plain falls at one rate.
            // The tail starts with two plain falls at one rate, or with three at one rate
            // however slow (a contraction with one dominant factor).
            let falls = [self.prev_ratio, self.last_ratio, ratio];
            let (slowest, fastest) = (falls.iter()).fold((f64::INFINITY, 0.0f64), |(s, f), &r| (s.min(r), f.max(r)));
            self.in_tail = (ratio > CONVERGING
                && self.last_ratio > CONVERGING
                && (ratio / self.last_ratio).max(self.last_ratio / ratio) < STEADY)
                || (slowest > 1.0 && fastest <= SLOW_STEADY * slowest);
        }
        self.prev_ratio = self.last_ratio;
        (self.last_law, self.last_ratio) = (law, ratio);
        self.combined_last = false;
        if !self.in_tail {
            // Out of the tail only the last iterate is kept: the one it may start from.
            self.history.clear();
        }
        self.history.push((frozen, image));
        if self.history.len() > self.depth + 1 {
            self.history.remove(0);
        }
        if self.in_tail && self.history.len() >= 2 {
            let mut next = combination(&self.history);
            next.iter_mut().for_each(|g| *g = g.max(0.0));
            self.next = Some(next);
            self.combined_last = true;
            self.combinations += 1;
        }
    }
}

/// Anderson's combination of `history` ((g_j, T(g_j)), at least two): T(g_m) − ΔT γ with γ the
/// least-squares coefficients of f_m on ΔF, by modified Gram–Schmidt on ΔF's columns (a column
/// that adds nothing new is dropped).
fn combination(history: &[(Vec<f64>, Vec<f64>)]) -> Vec<f64> {
    let m = history.len() - 1;
    let difference = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
    // f_j = T(g_j) − g_j, then the columns of ΔF and ΔT, oldest first.
    let residuals: Vec<Vec<f64>> = history.iter().map(|(g, t)| difference(t, g)).collect();
    let df: Vec<Vec<f64>> = (1..=m).map(|j| difference(&residuals[j], &residuals[j - 1])).collect();
    let dt: Vec<Vec<f64>> = (1..=m).map(|j| difference(&history[j].1, &history[j - 1].1)).collect();
    let last = &residuals[m];
    // QR of ΔF by modified Gram–Schmidt; R upper triangular, Q's columns in `q`.
    let mut q: Vec<Vec<f64>> = Vec::with_capacity(m);
    let mut r = vec![vec![0.0; m]; m];
    let mut kept: Vec<usize> = Vec::with_capacity(m);
    for (j, column) in df.iter().enumerate() {
        let mut v = column.clone();
        let norm0 = dot(&v, &v).sqrt();
        for (i, qi) in q.iter().enumerate() {
            let c = dot(qi, &v);
            r[i][j] = c;
            v.iter_mut().zip(qi).for_each(|(x, y)| *x -= c * y);
        }
        let norm = dot(&v, &v).sqrt();
        if norm <= 1e-10 * norm0 || norm == 0.0 {
            continue;
        }
        r[q.len()][j] = norm;
        v.iter_mut().for_each(|x| *x /= norm);
        q.push(v);
        kept.push(j);
    }
    // γ on the kept columns: R γ = Qᵀ f_m, back substitution.
    let rhs: Vec<f64> = q.iter().map(|qi| dot(qi, last)).collect();
    let mut gamma = vec![0.0; kept.len()];
    for i in (0..kept.len()).rev() {
        let tail: f64 = (i + 1..kept.len()).map(|l| r[i][kept[l]] * gamma[l]).sum();
        gamma[i] = (rhs[i] - tail) / r[i][kept[i]];
    }
    let mut next = history[m].1.clone();
    for (g, &j) in gamma.iter().zip(&kept) {
        next.iter_mut().zip(&dt[j]).for_each(|(x, d)| *x -= g * d);
    }
    next
}

#[cfg(test)]
mod tests {
    use super::*;

    /// T(g) = g* + A (g − g*), fixed point g* = (1, 2, 3).
    fn affine_map(a: [[f64; 3]; 3], g: &[f64]) -> Vec<f64> {
        let star = [1.0, 2.0, 3.0];
        (0..3)
            .map(|i| star[i] + (0..3).map(|j| a[i][j] * (g[j] - star[j])).sum::<f64>())
            .collect()
    }

    /// [`affine_map`] with A symmetric, eigenvalues 0.3 and 0.25.
    fn linear_map(g: &[f64]) -> Vec<f64> {
        affine_map([[0.3, 0.0, 0.0], [0.0, 0.275, 0.025], [0.0, 0.025, 0.275]], g)
    }

    /// [`affine_map`] with eigenvalues 0.9, 0.89 and 0.87: a slow contraction, one factor
    /// dominating (the thin slab's tail at k = 1/8 fell 1.105× per iterate).
    fn slow_map(g: &[f64]) -> Vec<f64> {
        affine_map([[0.9, 0.0, 0.0], [0.0, 0.88, 0.01], [0.0, 0.01, 0.88]], g)
    }

    fn error(g: &[f64]) -> f64 {
        [1.0, 2.0, 3.0]
            .iter()
            .zip(g)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    }

    /// Iterates g ← T(g) (with `anderson`'s combinations where it gives them) until the error
    /// is below 1e-12; the iterations taken.
    fn iterate(anderson: &mut TailAnderson) -> usize {
        iterate_map(anderson, linear_map)
    }

    /// [`iterate`] with the map `map`.
    fn iterate_map(anderson: &mut TailAnderson, map: fn(&[f64]) -> Vec<f64>) -> usize {
        let mut g = vec![0.0, 0.0, 0.0];
        for n in 1..=200 {
            let image = map(&g);
            let law = error(&image) + error(&g);
            anderson.record(vec![true; 3], g.clone(), image.clone(), law);
            g = anderson.take_bounds().unwrap_or(image);
            if error(&g) < 1e-12 {
                return n;
            }
        }
        200
    }

    /// On a linear contraction with two rates, depth 2 takes the exact fixed point once its
    /// history spans them (Anderson on a linear map is GMRES on I − A): far fewer iterations
    /// than the plain iteration's ~20.
    #[test]
    fn depth_two_solves_a_linear_contraction_in_a_few_iterations() {
        let plain = iterate(&mut TailAnderson::new(0));
        let accelerated = iterate(&mut TailAnderson::new(2));
        assert!(plain >= 18, "plain iteration: {plain}");
        assert!(accelerated <= 7, "Anderson: {accelerated} (plain {plain})");
    }

    /// A slow contraction (the residual falling about 1.11× per iterate) is a tail too once
    /// three falls agree within 2 %: tens of iterations where the plain iteration takes hundreds.
    /// Three slow falls that do not agree do not start it.
    #[test]
    fn a_slow_steady_tail_is_accelerated_and_an_unsteady_one_is_not() {
        let plain = iterate_map(&mut TailAnderson::new(0), slow_map);
        let accelerated = iterate_map(&mut TailAnderson::new(2), slow_map);
        assert_eq!(plain, 200, "the plain iteration should not reach 1e-12 in 200");
        assert!(accelerated <= 30, "Anderson: {accelerated} (measured 27)");
        let mut anderson = TailAnderson::new(2);
        let (g, image) = (vec![1.0; 3], vec![0.9; 3]);
        let mut law = 1.0;
        for fall in [1.1, 1.2, 1.1, 1.15] {
            law /= fall;
            anderson.record(vec![true; 3], g.clone(), image.clone(), law);
            assert!(anderson.take_bounds().is_none(), "fall {fall}");
        }
        for _ in 0..2 {
            law /= 1.1;
            anderson.record(vec![true; 3], g.clone(), image.clone(), law);
            assert!(anderson.take_bounds().is_none());
        }
        // The third fall of 1.1 in a row.
        anderson.record(vec![true; 3], vec![0.95; 3], vec![0.94; 3], law / 1.1);
        assert!(anderson.take_bounds().is_some());
    }

    /// Not before the rate is steady, not across a split change, and never again in the step
    /// once the split changes right after a combination.
    #[test]
    fn combinations_only_in_a_steady_tail_with_one_split() {
        let mut anderson = TailAnderson::new(2);
        let g = vec![1.0; 3];
        let image = vec![0.9; 3];
        // Falls of 2×, then 10×: not steady.
        for law in [1.0, 0.5, 0.05] {
            anderson.record(vec![true; 3], g.clone(), image.clone(), law);
            assert!(anderson.take_bounds().is_none(), "law {law}");
        }
        // 10× again: the tail starts, with the last iterate and this one.
        anderson.record(vec![true; 3], vec![0.95; 3], vec![0.94; 3], 0.005);
        assert!(anderson.take_bounds().is_some());
        assert_eq!(anderson.combinations(), 1);
        // The split changes right after it: ended for the step.
        anderson.record(vec![false; 3], g.clone(), image.clone(), 0.0005);
        for law in [5e-5, 5e-6, 5e-7] {
            anderson.record(vec![false; 3], g.clone(), image.clone(), law);
            assert!(anderson.take_bounds().is_none());
        }
        assert_eq!(anderson.combinations(), 1);
        // A split change without a combination before it only restarts the tail.
        let mut anderson = TailAnderson::new(2);
        for (law, slip) in [(1.0, true), (0.1, true), (0.01, false), (0.001, false)] {
            anderson.record(vec![slip; 3], g.clone(), image.clone(), law);
            assert!(anderson.take_bounds().is_none(), "law {law}");
        }
        anderson.record(vec![false; 3], vec![0.95; 3], vec![0.94; 3], 0.0001);
        assert!(anderson.take_bounds().is_some());
    }
}
