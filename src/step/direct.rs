//! The direct path: the step matrix of Problem 14 ([`crate::model::StepMatrix`]) factored once per run,
//! its contact unknowns last, and the one-solve step skeleton the condensed solvers share
//! ([`StepSystem::free_step`], [`StepSystem::loaded_state`]).

use std::sync::Mutex;
use std::time::Instant;

use serde::Serialize;

use super::StepError as Error;
use crate::la::{CscMatrix, LaError, QuasiDefiniteLdlt};
use crate::model::{Problem, State, StepMatrix, StepRhs};

/// Work done with a [`StepSystem`].
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct SystemStats {
    /// Full solves, forward and backward over all of L, by faer's solve (a block of m columns
    /// counts m): [`StepSystem::solve_in_place`] and [`StepSystem::solve_symmetric_block_in_place`].
    pub solves: usize,
    /// Sweeps over all of L done on their own: the forward sweep of [`StepSystem::free_step`] and
    /// the backward sweep of [`StepSystem::loaded_state`]. Two cost one full solve.
    pub sweeps: usize,
    /// Sweeps over the trailing (contact) block of L only: the backward sweep of `free_step`, the
    /// forward sweep of `loaded_state`, two per column of [`StepSystem::contact_inverse`].
    pub trailing_sweeps: usize,
    /// Seconds in sparse triangular sweeps (full solves, sweeps and trailing sweeps, with their
    /// permutations).
    pub solve_seconds: f64,
    /// Seconds building right-hand sides.
    pub rhs_seconds: f64,
    /// Krylov iterations of the iterative path's solves (each solve counts once in `solves`).
    pub krylov_iterations: usize,
}

impl SystemStats {
    /// The work of both.
    pub fn plus(self, other: SystemStats) -> SystemStats {
        SystemStats {
            solves: self.solves + other.solves,
            sweeps: self.sweeps + other.sweeps,
            trailing_sweeps: self.trailing_sweeps + other.trailing_sweeps,
            solve_seconds: self.solve_seconds + other.solve_seconds,
            rhs_seconds: self.rhs_seconds + other.rhs_seconds,
            krylov_iterations: self.krylov_iterations + other.krylov_iterations,
        }
    }

    /// The work done since `earlier`.
    pub fn since(self, earlier: SystemStats) -> SystemStats {
        SystemStats {
            solves: self.solves - earlier.solves,
            sweeps: self.sweeps - earlier.sweeps,
            trailing_sweeps: self.trailing_sweeps - earlier.trailing_sweeps,
            solve_seconds: self.solve_seconds - earlier.solve_seconds,
            rhs_seconds: self.rhs_seconds - earlier.rhs_seconds,
            krylov_iterations: self.krylov_iterations - earlier.krylov_iterations,
        }
    }

    /// Sweeps over all of L, a full solve counting two.
    pub fn full_sweeps(&self) -> usize {
        2 * self.solves + self.sweeps
    }

    /// Full solves and their equivalents (two sweeps over all of L make one), rounded up.
    pub fn solve_equivalents(&self) -> usize {
        self.full_sweeps().div_ceil(2)
    }
}

/// The factored step matrix and the right-hand side of Problem 14.
pub struct StepSystem {
    /// S = J A, the symmetric form of the reduced step matrix.
    matrix: CscMatrix,
    /// The right-hand side and the state of a solution.
    operator: StepRhs,
    /// Work counters: solves (right-hand sides) and seconds spent in them and in `rhs`.
    stats: Mutex<SystemStats>,
    factor: QuasiDefiniteLdlt,
    n_w: usize,
}

impl StepSystem {
    /// Assembles the reduced step matrix for the problem's time step k and factors it.
    pub fn new(problem: &Problem) -> Result<Self, Error> {
        Self::with_step(problem, problem.time_step())
    }

    /// The same for a step size k of one's own (the substeps of a cut-back step).
    pub fn with_step(problem: &Problem, k: f64) -> Result<Self, Error> {
        Self::factored(problem, StepMatrix::assemble(problem, k))
    }

    /// Factors an assembled step matrix, the contact unknowns last.
    pub fn factored(problem: &Problem, operator: StepMatrix) -> Result<Self, Error> {
        let StepMatrix { matrix, rhs: operator } = operator;
        let n_w = operator.n_w();
        let factor = QuasiDefiniteLdlt::with_trailing(&matrix, &contact_unknowns(problem, n_w))?;
        Ok(StepSystem {
            matrix,
            operator,
            factor,
            n_w,
            stats: Mutex::new(SystemStats::default()),
        })
    }

    /// S = J A, the symmetric form of the reduced step matrix.
    pub fn matrix(&self) -> &CscMatrix {
        &self.matrix
    }

    /// The step size k the matrix was made for.
    pub fn time_step(&self) -> f64 {
        self.operator.time_step()
    }

    /// Number of unknowns.
    pub fn n_unknowns(&self) -> usize {
        self.operator.n_unknowns()
    }

    /// The right-hand side of step n without the contact terms ([`StepRhs::rhs`]).
    pub fn rhs(&self, problem: &Problem, previous: &State, t: f64) -> Result<Vec<f64>, Error> {
        self.rhs_exchanging(problem, previous, t, None)
    }

    /// [`StepSystem::rhs`] with a nonlinear heat exchange evaluated at `exchange_at`.
    fn rhs_exchanging(
        &self,
        problem: &Problem,
        previous: &State,
        t: f64,
        exchange_at: Option<&[f64]>,
    ) -> Result<Vec<f64>, Error> {
        let clock = Instant::now();
        let rhs = self.operator.rhs(problem, previous, t, exchange_at)?;
        self.count(|s| s.rhs_seconds += clock.elapsed().as_secs_f64());
        Ok(rhs)
    }

    /// The work counters so far.
    pub fn stats(&self) -> SystemStats {
        *self.stats.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn count(&self, update: impl FnOnce(&mut SystemStats)) {
        update(&mut self.stats.lock().unwrap_or_else(|e| e.into_inner()));
    }

    /// Number of velocity unknowns (the first block of x).
    pub fn n_w(&self) -> usize {
        self.n_w
    }

    /// Stored entries of the LDLᵀ factor.
    pub fn factor_nnz(&self) -> usize {
        self.factor.factor_nnz()
    }

    /// The LDLᵀ factor of S, the contact unknowns last.
    pub fn factor(&self) -> &QuasiDefiniteLdlt {
        &self.factor
    }

    /// Solves A x = b in place (as S x = J b); a non-finite result is an error, never passed on.
    pub fn solve_in_place(&self, b: &mut [f64]) -> Result<(), Error> {
        let clock = Instant::now();
        b[self.n_w..].iter_mut().for_each(|v| *v = -*v);
        self.factor.solve_in_place(b, 1);
        self.count(|s| {
            s.solves += 1;
            s.solve_seconds += clock.elapsed().as_secs_f64();
        });
        Ok(finite(b)?)
    }

    /// Solves the symmetric system S X = B in place for a column-major block of right-hand sides
    /// (S = J A; see [`crate::la::QuasiDefiniteLdlt`]).
    pub fn solve_symmetric_block_in_place(&self, block: &mut [f64], n_cols: usize) -> Result<(), Error> {
        let clock = Instant::now();
        self.factor.solve_in_place(block, n_cols);
        self.count(|s| {
            s.solves += n_cols;
            s.solve_seconds += clock.elapsed().as_secs_f64();
        });
        Ok(finite(block)?)
    }

    /// Entries of S⁻¹ (S = J A) between contact unknowns (tangential velocities and temperatures
    /// of Γ_C nodes), column-major |rows| × |cols|, from the trailing block of the factor alone
    /// ([`crate::la::QuasiDefiniteLdlt`]).
    ///
    /// # Panics
    /// If an unknown is not a contact unknown.
    pub fn contact_inverse(&self, rows: &[usize], cols: &[usize]) -> Result<Vec<f64>, Error> {
        let clock = Instant::now();
        let factor = &self.factor;
        let t0 = factor.trailing_start();
        let m = factor.n() - t0;
        let positions: Vec<usize> = cols.iter().map(|&c| factor.position(c)).collect();
        let block = factor.trailing_inverse(&positions);
        let row_positions: Vec<usize> = rows
            .iter()
            .map(|&r| {
                let p = factor.position(r);
                assert!(p >= t0, "unknown {r} is not a contact unknown");
                p - t0
            })
            .collect();
        let out: Vec<f64> = block
            .chunks_exact(m.max(1))
            .take(cols.len())
            .flat_map(|column| row_positions.iter().map(move |&p| column[p]))
            .collect();
        self.count(|s| {
            s.trailing_sweeps += 2 * cols.len();
            s.solve_seconds += clock.elapsed().as_secs_f64();
        });
        finite(&out)?;
        Ok(out)
    }

    /// The first half of every step solver's step: the right-hand side b without contact terms,
    /// z = D⁻¹ L⁻¹ P J b over all of L, and x = L⁻ᵀ z on the contact unknowns only (the trailing
    /// block; [`crate::la::QuasiDefiniteLdlt`]), whose tangential velocities are w_τ^free of the condensed
    /// problem. A nonlinear heat exchange is evaluated at `exchange_at` (default Θ_{n−1}).
    pub fn free_step(
        &self,
        problem: &Problem,
        previous: &State,
        t: f64,
        exchange_at: Option<&[f64]>,
    ) -> Result<FreeStep, Error> {
        let mut x = self.rhs_exchanging(problem, previous, t, exchange_at)?;
        let clock = Instant::now();
        let factor = &self.factor;
        let n = self.n_unknowns();
        let t0 = factor.trailing_start();
        x[self.n_w..].iter_mut().for_each(|v| *v = -*v);
        let mut forward = vec![0.0; n];
        let mut work = vec![0.0; n];
        let mut scratch = vec![0.0; factor.scratch_len()];
        factor.permute(&x, &mut forward);
        factor.forward(&mut forward, &mut scratch, 0);
        factor.diagonal(&mut forward, 0);
        work[t0..].copy_from_slice(&forward[t0..]);
        factor.backward(&mut work, &mut scratch, t0);
        self.count(|s| {
            s.sweeps += 1;
            s.trailing_sweeps += 1;
            s.solve_seconds += clock.elapsed().as_secs_f64();
        });
        finite(&forward)?;
        let w_free = problem
            .contact
            .iter()
            .flat_map(|node| {
                node.tangent_dofs
                    .iter()
                    .map(|dof| dof.map_or(0.0, |r| work[factor.position(r)]))
            })
            .collect();
        Ok(FreeStep {
            w_free,
            forward,
            work,
            x,
            scratch,
        })
    }

    /// The second half: the full fields at time t with the contact terms ξ and h added to the
    /// right-hand side. The terms live on the contact unknowns, so their forward sweep runs over
    /// the trailing block only; added to the free step's z, one backward sweep over all of L
    /// gives x. May be called again on the same `free` (other ξ, h).
    pub fn loaded_state(
        &self,
        problem: &Problem,
        previous: &State,
        t: f64,
        free: &mut FreeStep,
        xi: Vec<f64>,
        heat: &[f64],
    ) -> Result<State, Error> {
        let clock = Instant::now();
        let factor = &self.factor;
        let t0 = factor.trailing_start();
        let FreeStep {
            forward,
            work,
            x,
            scratch,
            ..
        } = free;
        // J times the contact terms, permuted: on the trailing block.
        work[t0..].fill(0.0);
        for (unknown, value) in contact_terms(problem, self.n_w, &xi, heat) {
            let sign = if unknown < self.n_w { 1.0 } else { -1.0 };
            work[factor.position(unknown)] += sign * value;
        }
        factor.forward(work, scratch, t0);
        factor.diagonal(work, t0);
        work[..t0].copy_from_slice(&forward[..t0]);
        for (w, f) in work[t0..].iter_mut().zip(&forward[t0..]) {
            *w += f;
        }
        factor.backward(work, scratch, 0);
        factor.unpermute(work, x);
        self.count(|s| {
            s.sweeps += 1;
            s.trailing_sweeps += 1;
            s.solve_seconds += clock.elapsed().as_secs_f64();
        });
        finite(x)?;
        Ok(self.state_from(problem, previous, t, x, xi))
    }

    /// The new state at time t from the solution x of the step from `previous`.
    pub fn state_from(&self, problem: &Problem, previous: &State, t: f64, x: &[f64], xi: Vec<f64>) -> State {
        self.operator.state_from(problem, previous, t, x, xi)
    }
}

/// The state of a step between [`StepSystem::free_step`] and [`StepSystem::loaded_state`]: w_τ^free
/// and the free right-hand side's forward sweep.
pub struct FreeStep {
    /// w_τ^free on Γ_C in the nodes' tangent coordinates.
    pub w_free: Vec<f64>,
    /// z = D⁻¹ L⁻¹ P J b of the right-hand side b without contact terms (positions of the
    /// factor's order).
    forward: Vec<f64>,
    /// Work vector in the factor's order.
    work: Vec<f64>,
    /// The loaded solution after [`StepSystem::loaded_state`] (unknowns' order).
    x: Vec<f64>,
    /// Scratch of the sweeps.
    scratch: Vec<f64>,
}

/// `Ok` when every value is finite.
fn finite(x: &[f64]) -> Result<(), LaError> {
    match x.iter().filter(|v| !v.is_finite()).count() {
        0 => Ok(()),
        non_finite => Err(LaError::NonFiniteSolution {
            non_finite,
            unknowns: x.len(),
        }),
    }
}

/// Adds the contact terms Σ ℓ_i ξ_i · v_τ (velocity rows) and Σ ℓ_i h_i η (temperature rows of
/// free contact nodes) to a right-hand side; ξ node-major in tangent coordinates.
pub fn add_contact_terms(problem: &Problem, n_w: usize, xi: &[f64], heat: &[f64], rhs: &mut [f64]) {
    for (unknown, value) in contact_terms(problem, n_w, xi, heat) {
        rhs[unknown] += value;
    }
}

/// The contact terms as (unknown, value) pairs.
fn contact_terms<'a>(
    problem: &'a Problem,
    n_w: usize,
    xi: &'a [f64],
    heat: &'a [f64],
) -> impl Iterator<Item = (usize, f64)> + 'a {
    let tangential = problem.dim() - 1;
    problem.contact.iter().enumerate().flat_map(move |(i, node)| {
        // A held coordinate has no unknown to load.
        let friction = (node.tangent_dofs.iter().enumerate())
            .filter_map(move |(k, dof)| dof.map(|r| (r, node.weight * xi[i * tangential + k])));
        let heat = node.theta_dof.map(|r| (n_w + r, node.weight * heat[i]));
        friction.chain(heat)
    })
}

/// Tangential velocities w_τ at the contact nodes in tangent coordinates, node-major, read
/// from x (zero for a held coordinate).
pub fn tangential_velocities(problem: &Problem, x: &[f64]) -> Vec<f64> {
    problem
        .contact
        .iter()
        .flat_map(|node| node.tangent_dofs.iter().map(|dof| dof.map_or(0.0, |r| x[r])))
        .collect()
}

/// The tangential velocity unknowns of the Γ_C nodes, node by node (held coordinates have none).
pub(super) fn contact_tangential_unknowns(problem: &Problem) -> impl Iterator<Item = usize> + '_ {
    (problem.contact.iter()).flat_map(|node| node.tangent_dofs.iter().flatten().copied())
}

/// The unknowns that contact terms touch, ordered last in the factorization: the tangential
/// velocity unknowns of the Γ_C nodes, then their temperature unknowns.
fn contact_unknowns(problem: &Problem, n_w: usize) -> Vec<usize> {
    let tangential = contact_tangential_unknowns(problem);
    let temperature = problem
        .contact
        .iter()
        .filter_map(|node| node.theta_dof.map(|r| n_w + r));
    tangential.chain(temperature).collect()
}
