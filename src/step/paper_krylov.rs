//! The paper's solver on the iterative path: the loop of Problem 17 (`paper::paper_step`)
//! with each Uzawa iterate's w(ξ, h) from one Krylov solve of the whole step, A x = b + Σ_i ℓ_i
//! ξ_i·t_i + Σ_i ℓ_i h_i e_θi, instead of a product with the condensed compliance C.
//!
//! Nothing is condensed, so it runs where the direct factor does not fit; its iterates are the
//! direct path's to the Krylov tolerance (`tests/newton_krylov.rs`). It pays a solve per Uzawa
//! iterate (29 559 of them on the 3D example, against 1 258 Newton iterations for the fast
//! solver's counterpart, [`super::newton_krylov`]): it is there to run the paper's own algorithm
//! at scale, as a reference for the fast one, not for speed. Each solve starts from the previous
//! one's solution, and the matrix is A itself (never linearized), so its ILU(0) is the one
//! factored with the system.
//!
//! The augmentation r = 1/λ_max(C) is found as on the direct path, by power iteration from the
//! same start, each product C v one Krylov solve (A x = Σ_i ℓ_i v_i·t_i, then w_τ of x).

use std::time::Instant;

use super::iterative::{krylov_solve, tangential, KrylovSolver, KrylovSystem};
use super::paper::{paper_step, LoadedStep, PaperParams};
use super::StepError as Error;
use super::{SolveError, StepInfo};
use crate::fem::assembly::NormGrams;
use crate::la::vector::largest_eigenvalue_within;
use crate::la::CsrMatrix;
use crate::model::Problem;
use crate::model::{ContactLaws, State};

/// The paper's solver on a [`KrylovSystem`].
pub struct PaperKrylov<'a> {
    problem: &'a Problem,
    /// The norms of the stop criteria (77)–(78), evaluated at every iterate.
    grams: NormGrams,
    system: KrylovSystem,
    params: PaperParams,
    /// The Uzawa step r = 1/λ_max(C).
    pub augmentation: f64,
}

impl<'a> PaperKrylov<'a> {
    /// The problem and ε_conv.
    pub(super) fn problem_and_tolerance(&self) -> (&'a Problem, f64) {
        (self.problem, self.params.tolerance)
    }

    /// The solver on `system` (its matrix is A, as set up: this solver never linearizes it);
    /// finds r by power iteration.
    pub fn new(problem: &'a Problem, system: KrylovSystem, params: PaperParams) -> Result<Self, Error> {
        let lambda_max = spectral_bound(problem, &system)?;
        Ok(PaperKrylov {
            problem,
            grams: NormGrams::assemble(&problem.mesh),
            system,
            params,
            augmentation: if lambda_max > 0.0 { 1.0 / lambda_max } else { 1.0 },
        })
    }

    /// The ordered step matrix and its preconditioner.
    pub fn system(&self) -> &KrylovSystem {
        &self.system
    }

    /// One step of the system's size k, from `previous` to the state at time `laws.t`.
    pub fn step(&self, previous: &State, laws: &ContactLaws) -> Result<(State, StepInfo), SolveError> {
        let (problem, sys) = (self.problem, &self.system);
        let t = laws.t;
        let (b, x) = sys.start(problem, previous, t, laws.exchange_temperature.as_deref())?;
        let mut guard = sys.lock_for_step();
        let (a, solver) = &mut *guard;
        let mut loaded = KrylovStep {
            problem,
            system: sys,
            a,
            solver,
            previous,
            t,
            rhs: vec![0.0; b.len()],
            change: vec![0.0; b.len()],
            y: vec![0.0; b.len()],
            b,
            x,
            residual: Vec::new(),
            krylov_iterations: 0,
        };
        let k = sys.time_step();
        let (state, mut info) = paper_step(
            (problem, &self.grams),
            &self.params,
            self.augmentation,
            "paper",
            (previous, k, laws),
            &mut loaded,
        )?;
        info.krylov_iterations = loaded.krylov_iterations;
        Ok((state, info))
    }
}

/// One step's Krylov answers to the paper's loop.
struct KrylovStep<'s> {
    problem: &'s Problem,
    system: &'s KrylovSystem,
    a: &'s CsrMatrix,
    solver: &'s mut KrylovSolver,
    previous: &'s State,
    t: f64,
    /// b without the contact terms, in the system's order.
    b: Vec<f64>,
    /// b̃ of the last solve.
    rhs: Vec<f64>,
    /// The last solve's solution, the next one's start.
    x: Vec<f64>,
    /// b̃ − A x after the last solve (empty before the first).
    residual: Vec<f64>,
    /// Work vectors of a solve: its right-hand side b̃ − A x and its solution y.
    change: Vec<f64>,
    y: Vec<f64>,
    krylov_iterations: usize,
}

impl KrylovStep<'_> {
    /// x solving A x = b + Σ_i ℓ_i (ξ_i·t_i + h_i e_θi), from the previous x.
    ///
    /// Solved for the change: A y = d with d = b̃ − A x (the last solve's residual plus the
    /// change of b̃), y from 0, then x += y. GMRES's tolerance is relative to its right-hand
    /// side, so each solve is accurate relative to the change of the loads, not to the whole
    /// of b̃: the Uzawa iterates' changes shrink to 10⁻¹⁰ of the bounds, below the error of a
    /// whole solve to 10⁻¹⁰ of ‖b̃‖ (measured: the inner loop then stalls at 10⁻⁶).
    fn solve(&mut self, xi: &[f64], heat: &[f64]) -> Result<(), SolveError> {
        let sys = self.system;
        let td = self.problem.dim() - 1;
        let clock = Instant::now();
        // `change` takes b̃ − A x: the last residual minus the last b̃ (or −A x at the first
        // solve), plus the new b̃, which `rhs` then keeps.
        let change = &mut self.change;
        if self.residual.is_empty() {
            self.a.mul(&self.x, change);
            change.iter_mut().for_each(|v| *v = -*v);
        } else {
            (change.iter_mut().zip(&self.residual).zip(&self.rhs)).for_each(|((c, r), old)| *c = r - old);
        }
        self.rhs.copy_from_slice(&self.b);
        for (i, node) in sys.nodes.iter().enumerate() {
            for &(k, row) in &node.tangent {
                self.rhs[row] += node.weight * xi[i * td + k];
            }
            if let Some(row) = node.theta {
                self.rhs[row] += node.weight * heat[i];
            }
        }
        change.iter_mut().zip(&self.rhs).for_each(|(c, new)| *c += new);
        self.y.fill(0.0);
        self.residual.clone_from(change);
        let (iterations, _) = krylov_solve(
            sys,
            (self.a, self.solver),
            (change, 0.0),
            &mut self.y,
            &mut self.residual,
            clock,
        )?;
        self.krylov_iterations += iterations;
        // The state reads every row of the sum (over the ranks: gathered whole).
        self.system.whole(self.solver, &mut self.y)?;
        self.x.iter_mut().zip(&self.y).for_each(|(x, y)| *x += y);
        Ok(())
    }
}

impl LoadedStep for KrylovStep<'_> {
    fn velocities(&mut self, xi: &[f64], heat: &[f64], w: &mut [f64]) -> Result<(), SolveError> {
        self.solve(xi, heat)?;
        let td = self.problem.dim() - 1;
        w.copy_from_slice(&tangential(&self.system.nodes, td, &self.x, w.len()));
        Ok(())
    }

    fn state(&mut self, xi: Vec<f64>, heat: &[f64]) -> Result<State, SolveError> {
        self.solve(&xi, heat)?;
        let sys = self.system;
        let mut x_unknowns = vec![0.0; self.x.len()];
        sys.order.iter().zip(&self.x).for_each(|(&o, v)| x_unknowns[o] = *v);
        Ok(sys.rhs.state_from(self.problem, self.previous, self.t, &x_unknowns, xi))
    }
}

/// λ_max(C) by the direct path's power iteration ([`largest_eigenvalue`]), each product C v
/// one Krylov solve: A x = Σ_i ℓ_i v_i·t_i, then w_τ of x. A solve at its cap is the Krylov
/// error it was.
fn spectral_bound(problem: &Problem, sys: &KrylovSystem) -> Result<f64, Error> {
    spectral_bound_within(problem, sys, 1e-6, 200)
}

/// [`spectral_bound`] to a relative `tolerance` within `max_products` Krylov solves.
pub(super) fn spectral_bound_within(
    problem: &Problem,
    sys: &KrylovSystem,
    tolerance: f64,
    max_products: usize,
) -> Result<f64, Error> {
    let td = problem.dim() - 1;
    let mut guard = sys.lock();
    let (a, solver) = &mut *guard;
    let n = sys.order.len();
    let (mut rhs, mut x, mut residual) = (vec![0.0; n], vec![0.0; n], Vec::new());
    largest_eigenvalue_within(problem.contact.len() * td, tolerance, max_products, |v, y| {
        rhs.fill(0.0);
        for (i, node) in sys.nodes.iter().enumerate() {
            for &(k, row) in &node.tangent {
                rhs[row] = node.weight * v[i * td + k];
            }
        }
        residual.clear();
        sys.gmres((a, &mut *solver), &rhs, &mut x, &mut residual, 0.0)?;
        y.copy_from_slice(&tangential(&sys.nodes, td, &x, y.len()));
        Ok(())
    })
}
