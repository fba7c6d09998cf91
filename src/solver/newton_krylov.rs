//! The iterative path: the step problem solved on all unknowns, without condensation onto Γ_C,
//! each linearization by GMRES preconditioned with ILU(0), or with ILU(0) sweeps around an AMG
//! correction of the velocities where the stiffness weighs ([`super::amg`]) (issue 11).
//!
//! **Why not condense.** The direct path reduces a step to Γ_C through the dense compliance
//! C = E_w A⁻¹ E_wᵀ ℓ ([`super::condensed`]), read from the trailing block of a direct factor.
//! Both grow superlinearly in 3D: the factor's fill (194 M entries at 98k unknowns, no fit at
//! 10⁶) and C itself (n_t², with n_t = 12 480 tangential unknowns at 10⁶ unknowns: 1.2 GB and an
//! O(n_t³) inverse for the descent). Here nothing is condensed and nothing is dense: memory is
//! A, its ILU(0) factor and a few vectors, O(N).
//!
//! **The method: the convexification loop of Problem 17, each convex problem solved by a
//! semismooth Newton method on (x, ξ).** The unknowns are x = (W_n, Θ_n) and the nodal friction
//! stresses ξ_i; with the bounds frozen at g_i = b(|w_i|) of the previous convexification
//! iterate, the convex (Tresca) problem is
//!
//! ```text
//! A x = b + Σ_i ℓ_i ξ_i·t_i + Σ_i ℓ_i h(|w_i|) e_θi        (the step's linear equations)
//! F_i = ξ_i − P_{g_i}(ξ_i − r_i w_i) = 0                     (the nodal law, Alart–Curnier)
//! ```
//!
//! At a Newton iterate the nodes split as in [`super::newton`]: stick where |ξ_i − r_i w_i| ≤ g_i
//! (linearized: w_i = 0, and ξ_i is what the node's rows of A x − b leave over), slip otherwise
//! (linearized: ξ_i = a_i + B_i w_i, substituted into the node's rows as the block −ℓ_i B_i). So
//! each Newton iteration solves one sparse system Ã x = b̃ whose matrix is A with the tangential
//! rows of the contact nodes changed, node by node, inside A's pattern. The linear equations
//! then hold at the new iterate, so the convex problem is solved once its law holds there (to
//! 1 % of the loop's last change, as the fast solver's inner solves): usually after one Newton
//! iteration (1 420 Newton iterations for 1 320 convexification iterates on the 3D example).
//! The frictional heat is taken at the iterate's w (it is weak: α_exp = 3·10⁻⁴ in the paper).
//! The loop stops when w and ξ on Γ_C change by less than ε_conv and the nonmonotone law holds
//! at every node to ε_conv: the fast solver's criteria ([`super::fast`]). Where the step has
//! several solutions this picks the same one as the direct path, the fixed point of the
//! convexification loop from the previous step (`tests/newton_krylov.rs`: the same fields to
//! 10⁻⁶ and the same stick/slip state, 2D and 3D).
//!
//! Tried and dropped, each measured on the 3D example (40 × 10 × 10, 64 steps):
//! - one Newton step per bound update (bounds lagged inside Newton): 21 solves per step against
//!   22, but another solution where the law is steep (one node of 440 on another branch at step
//!   16, the fields then 0.1–1 % from the direct path's);
//! - inexact Krylov solves, the tolerance tied to the loop's change (10⁻⁴ … 10⁻¹⁰): the loop
//!   reached other solutions and failed at step 50 even at k/32;
//! - Anderson acceleration (depth 5) of the friction bounds between convexification iterates:
//!   5 033 iterations instead of 1 320, 29 cutbacks, other solutions (the bound map switches
//!   between stick and slip: it is not smooth);
//! - giving a step up once the loop stalls (its smallest change over the last 40 iterates not
//!   half the smallest before), so that a step the loop cannot solve is cut back after ~80
//!   solves instead of 200+: on the 3D example at 47k unknowns and k = 1/8 the step at k
//!   cycles (period ≈ 25) through all 200 iterates, but one of its k/2 substeps wanders for 115
//!   iterates and then converges in 6. Stopping those too cut Newton iterations 345 → 169 and
//!   raised cutbacks (to k/8, and one more step cut back): 10.9 s → 10.8 s, and other states.
//!
//! **The linear solves.** The tangential velocity unknowns of Γ_C are ordered last, so that the
//! rows a linearization changes are the last rows of Ã: their ILU(0) rows are refactored in
//! O(n_t) per iteration ([`Ilu0::refactor_from`]) and the preconditioner is the ILU(0) of Ã
//! itself, not of A (a stick row, w_i = 0, is far from A's row; preconditioning Ã with A's
//! factor would leave GMRES a rank-n_t perturbation to find). Before them come the two halves
//! of the mesh and the cross-section between them ([`super::bisection`]), so that the ILU(0)
//! sweeps run the halves on the two cores. GMRES starts from the previous
//! iterate (from the previous step's state at the first), so the later iterations of a step
//! need few Krylov iterations. Why GMRES + ILU(0) and when it stays bounded:
//! docs/krylov-study.md.
//!
//! **Rejected.** Condensing matrix-free (C v by one Krylov solve per product) would cost a solve
//! per product of the convexification loop's inner iterations (hundreds per step); the fast
//! solver's descent needs K = C⁻¹, dense. Newton on the nonmonotone law itself (with the slope
//! b′) converges faster where the law is shallow, but cycles where it is steep (steepness ≥ 1,
//! the paper's example), the regime this path is for. The descent of the direct path (where the
//! convexification loop fails) has no counterpart here yet: a step the loop cannot solve is cut
//! back.

use std::sync::Mutex;
use std::time::Instant;

use super::amg::VelocityAmg;
use super::bisection::{level_bisection, Part};
use super::krylov::{gmres_from_residual, CsrMatrix, Ilu0, KrylovParams, PreconditionerKind, SolveInfo};
use super::matrix::{assemble_by_columns, StepRhs};
use super::newton::{max_diff, node_law_residual, slip_linearization};
use super::system::{contact_tangential_unknowns, norm2 as norm, State, SystemStats};
use super::{worst_criterion, Criterion, SolveError, StepFailure, StepInfo};
use crate::error::{Error, FactorStage};
use crate::fem::sparse::NodeGraph;
use crate::problem::Problem;

/// The rows of one contact node in the iterative path's ordering.
#[derive(Debug, Clone)]
pub(super) struct NodeRows {
    /// (tangent coordinate k, row of its velocity unknown) for the coordinates that are not
    /// held; the held ones keep w = ξ = 0.
    pub(super) tangent: Vec<(usize, usize)>,
    /// The row of the node's temperature unknown, if θ is not prescribed there.
    pub(super) theta: Option<usize>,
    /// ℓ_i.
    pub(super) weight: f64,
    /// r_i of the Alart–Curnier function: the node's own stiffness A_rr / ℓ_i, the inverse of
    /// its local compliance (any r > 0 has the same solutions; this one shapes the iteration
    /// like the fast solver's 1/λ_max(C)).
    augmentation: f64,
}

/// The step matrix with the Γ_C velocity unknowns last, its ILU(0) and the right-hand side:
/// the iterative counterpart of [`super::system::StepSystem`], set up once per step size.
pub struct KrylovSystem {
    pub(super) rhs: StepRhs,
    /// Row i of the ordered system is unknown `order[i]`.
    pub(super) order: Vec<usize>,
    /// The first row of the Γ_C tangential velocities.
    pub(super) first_contact: usize,
    pub(super) nodes: Vec<NodeRows>,
    /// The contact rows' values of A, rows `first_contact..n` one after the other
    /// ([`CsrMatrix::values_from`]).
    pub(super) base: Vec<f64>,
    /// Ã and its ILU(0), changed in the contact rows by each linearization.
    work: Mutex<(CsrMatrix, Ilu0)>,
    /// The AMG coarse correction of the velocities, where the preconditioner has one (`amg`, or
    /// `auto` resolved to it).
    amg: Option<VelocityAmg>,
    pub(super) params: KrylovParams,
    stats: Mutex<SystemStats>,
}

/// The unknowns in the order of the ILU(0) sweeps, where the two domains end, and the first
/// row of the Γ_C tangential velocities: the two parts of the mesh's [`level_bisection`] (each
/// with its velocities, then its temperatures, in their own numbering), the separator's
/// unknowns, then the Γ_C tangential velocities, last so that a linearization changes only the
/// last rows. The parts share no entry of A, so [`Ilu0::with_domains`] sweeps them on two
/// threads.
fn sweep_order(problem: &Problem) -> (Vec<usize>, [usize; 2], usize) {
    let n_w = problem.velocity.n_free;
    let n = n_w + problem.temperature.n_free;
    let tangential: Vec<usize> = contact_tangential_unknowns(problem).collect();
    let mut is_contact = vec![false; n];
    tangential.iter().for_each(|&r| is_contact[r] = true);
    let mesh = &problem.mesh;
    let mut node_of = vec![0; n];
    let mut weight = vec![0; mesh.n_nodes()];
    for (p, w) in weight.iter_mut().enumerate() {
        let theta = problem.temperature.free[p].map(|r| n_w + r);
        for r in problem.velocity.node_unknowns(p).chain(theta) {
            node_of[r] = p;
            *w += usize::from(!is_contact[r]);
        }
    }
    let graph = NodeGraph::new(mesh.n_nodes(), &mesh.cells, mesh.nodes_per_cell());
    let part = level_bisection(&graph, &weight);
    let (is_contact, part, node_of) = (&is_contact, &part, &node_of);
    let in_part = |x: Part| (0..n).filter(move |&r| !is_contact[r] && part[node_of[r]] == x);
    let first = in_part(Part::First).count();
    let second = first + in_part(Part::Second).count();
    let first_contact = n - tangential.len();
    let order = (in_part(Part::First).chain(in_part(Part::Second)))
        .chain(in_part(Part::Separator))
        .chain(tangential)
        .collect();
    (order, [first, second], first_contact)
}

/// Whether ILU(0) alone needs more than [`PreconditionerKind::AUTO_AMG_ABOVE`] GMRES iterations
/// for the first step's system (from the initial state, from zero, to 10⁻⁸): the probe of
/// `solver.preconditioner = "auto"`, capped there so that it costs at most that many.
fn ilu_needs_amg(
    problem: &Problem,
    rhs: &StepRhs,
    order: &[usize],
    (a, ilu): (&CsrMatrix, &Ilu0),
) -> Result<bool, Error> {
    let b_unordered = rhs.rhs(problem, &State::initial(problem), rhs.step_size())?;
    let b: Vec<f64> = order.iter().map(|&o| b_unordered[o]).collect();
    let mut x = vec![0.0; b.len()];
    let probe = KrylovParams {
        rtol: 1e-8,
        max_iterations: PreconditionerKind::AUTO_AMG_ABOVE,
        ..KrylovParams::default()
    };
    match gmres_from_residual(a, ilu, &b, &mut x, &mut Vec::new(), &probe) {
        Ok(_) => Ok(false),
        Err(Error::KrylovNotConverged { .. }) => Ok(true),
        Err(other) => Err(other),
    }
}

impl KrylovSystem {
    /// Assembles the step matrix of step size k in the order with the Γ_C tangential
    /// velocities last, as A's rows (no symmetric form, no triplets: [`assemble_by_columns`]),
    /// and factors its ILU(0).
    pub fn new(problem: &Problem, k: f64, params: KrylovParams) -> Result<Self, Error> {
        let n_w = problem.velocity.n_free;
        let n = n_w + problem.temperature.n_free;
        if u32::try_from(n).is_err() {
            return Err(Error::Factorization {
                stage: FactorStage::IncompleteLu,
                detail: format!("{n} unknowns exceed 32-bit indices"),
            });
        }
        let (order, parts, first_contact) = sweep_order(problem);
        let mut position = vec![0; n];
        order.iter().enumerate().for_each(|(new, &old)| position[old] = new);

        // Row j of P A Pᵀ is column j of P S Pᵀ, negated for a temperature unknown.
        let mut ptr = Vec::with_capacity(n + 1);
        let (mut col, mut val) = (Vec::new(), Vec::new());
        ptr.push(0);
        let mut j = 0;
        let rhs = assemble_by_columns(problem, k, &order, |column| {
            let sign = if order[j] < n_w { 1.0 } else { -1.0 };
            col.extend(column.iter().map(|&(c, _)| c as u32));
            val.extend(column.iter().map(|&(_, v)| sign * v));
            ptr.push(col.len());
            j += 1;
        });
        let a = CsrMatrix::from_rows(n, ptr, col, val);
        let base = a.values_from(first_contact).to_vec();
        let nodes = (problem.contact.iter())
            .map(|node| {
                let tangent: Vec<(usize, usize)> = (node.tangent_dofs.iter().enumerate())
                    .filter_map(|(k, dof)| dof.map(|r| (k, position[r])))
                    .collect();
                let stiffness =
                    tangent.iter().map(|&(_, row)| a.diagonal(row)).sum::<f64>() / tangent.len().max(1) as f64;
                NodeRows {
                    tangent,
                    theta: node.theta_dof.map(|r| position[n_w + r]),
                    weight: node.weight,
                    augmentation: if node.weight > 0.0 && stiffness > 0.0 {
                        stiffness / node.weight
                    } else {
                        1.0
                    },
                }
            })
            .collect();
        let ilu = Ilu0::with_domains(&a, parts)?;
        let with_amg = match params.preconditioner {
            PreconditionerKind::Ilu => false,
            PreconditionerKind::Amg => true,
            PreconditionerKind::Auto => VelocityAmg::AVAILABLE && ilu_needs_amg(problem, &rhs, &order, (&a, &ilu))?,
        };
        let amg = if with_amg {
            Some(VelocityAmg::new(problem, &a, &order)?)
        } else {
            None
        };
        Ok(KrylovSystem {
            rhs,
            order,
            first_contact,
            nodes,
            base,
            work: Mutex::new((a, ilu)),
            amg,
            params,
            stats: Mutex::new(SystemStats::default()),
        })
    }

    /// The step size k.
    pub fn step_size(&self) -> f64 {
        self.rhs.step_size()
    }

    /// Stored entries of A and of its ILU(0) factor (the same pattern).
    pub fn factor_nnz(&self) -> usize {
        self.lock().1.nnz()
    }

    /// The preconditioner set up: [`PreconditionerKind::Ilu`] or [`PreconditionerKind::Amg`]
    /// (`auto` resolved).
    pub fn preconditioner(&self) -> PreconditionerKind {
        if self.amg.is_some() {
            PreconditionerKind::Amg
        } else {
            PreconditionerKind::Ilu
        }
    }

    /// The AMG coarse correction, if the preconditioner has one.
    pub fn amg(&self) -> Option<&VelocityAmg> {
        self.amg.as_ref()
    }

    /// Solves Ã x = b̃ by GMRES from x with this system's preconditioner (see
    /// [`gmres_from_residual`] for `residual`).
    pub(super) fn gmres(
        &self,
        (a, ilu): (&CsrMatrix, &Ilu0),
        rhs: &[f64],
        x: &mut [f64],
        residual: &mut Vec<f64>,
    ) -> Result<SolveInfo, Error> {
        match &self.amg {
            None => gmres_from_residual(a, ilu, rhs, x, residual, &self.params),
            Some(amg) => gmres_from_residual(a, &amg.with(a, ilu), rhs, x, residual, &self.params),
        }
    }

    /// The step's right-hand side b (its linear part, without the contact terms) from
    /// `previous` to time `t`, in the unknowns' numbering: with [`KrylovSystem::solve`], the
    /// first step's system of studies and tests.
    pub fn rhs(&self, problem: &Problem, previous: &State, t: f64) -> Result<Vec<f64>, Error> {
        self.rhs.rhs(problem, previous, t)
    }

    /// Solves A x = b with the step matrix itself (its Γ_C rows as assembled, no contact
    /// linearization), b and x in the unknowns' numbering, x holding the initial guess: one
    /// solve of the constant matrix with this system's preconditioner, for studies and tests.
    pub fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<SolveInfo, Error> {
        let mut guard = self.lock();
        let (a, ilu) = &mut *guard;
        a.values_from_mut(self.first_contact).copy_from_slice(&self.base);
        ilu.refactor_from(a, self.first_contact)?;
        let b_ordered: Vec<f64> = self.order.iter().map(|&o| b[o]).collect();
        let mut x_ordered: Vec<f64> = self.order.iter().map(|&o| x[o]).collect();
        let info = self.gmres((a, ilu), &b_ordered, &mut x_ordered, &mut Vec::new())?;
        self.order.iter().zip(&x_ordered).for_each(|(&o, v)| x[o] = *v);
        Ok(info)
    }

    /// The work counters so far.
    pub fn stats(&self) -> SystemStats {
        *self.stats.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub(super) fn lock(&self) -> std::sync::MutexGuard<'_, (CsrMatrix, Ilu0)> {
        self.work.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub(super) fn count(&self, update: impl FnOnce(&mut SystemStats)) {
        update(&mut self.stats.lock().unwrap_or_else(|e| e.into_inner()));
    }
}

/// How one node is linearized.
enum Linearized {
    /// w_i = 0; ξ_i from the node's rows.
    Stick,
    /// ξ_i = a + B w_i (in the node's free tangent coordinates).
    Slip([f64; 2], [[f64; 2]; 2]),
}

/// Newton iterations per convex problem before its convexification iterate moves on anyway
/// (the next iterate starts from where this one stopped).
const MAX_NEWTON_PER_CONVEX_PROBLEM: usize = 20;

/// One step's linear algebra: Ã (A with its contact rows linearized), its ILU(0) and b̃.
struct Linearization<'s> {
    system: &'s KrylovSystem,
    a: &'s mut CsrMatrix,
    ilu: &'s mut Ilu0,
    /// b without the contact terms, in the system's order.
    b: &'s [f64],
    /// λ(t_n) of h(t_n, r) = λ r.
    heat_rate: f64,
    /// d − 1.
    td: usize,
    rhs: Vec<f64>,
    /// b̃ − Ã x after the last solve (empty before the step's first).
    residual: Vec<f64>,
    nodes: Vec<Linearized>,
}

impl Linearization<'_> {
    /// One Newton iteration of the convex problem with the bounds `frozen`, from (w, ξ) (x the
    /// unknowns they come from, updated in place): linearize, solve Ã x = b̃ by GMRES from x,
    /// and return the new (w, ξ).
    fn newton_iteration(
        &mut self,
        x: &mut [f64],
        w: &[f64],
        xi: &[f64],
        frozen: &[f64],
        info: &mut StepInfo,
    ) -> Result<(Vec<f64>, Vec<f64>), SolveError> {
        let sys = self.system;
        let (td, n) = (self.td, sys.order.len());
        let a = &mut *self.a;
        let rhs = &mut self.rhs;
        rhs.copy_from_slice(self.b);
        a.values_from_mut(sys.first_contact).copy_from_slice(&sys.base);
        self.nodes.clear();
        for (i, node) in sys.nodes.iter().enumerate() {
            let range = i * td..(i + 1) * td;
            if let Some(row) = node.theta {
                rhs[row] += node.weight * self.heat_rate * norm(&w[range.clone()]);
            }
            let m = node.tangent.len();
            let (mut wi, mut xii, mut q) = ([0.0; 2], [0.0; 2], [0.0; 2]);
            for (j, &(k, _)) in node.tangent.iter().enumerate() {
                wi[j] = w[range.start + k];
                xii[j] = xi[range.start + k];
                q[j] = xii[j] - node.augmentation * wi[j];
            }
            let bound = frozen[i];
            let q_norm = norm(&q[..m]);
            if q_norm <= bound {
                for &(_, row) in &node.tangent {
                    let diagonal = a.row(row).0.binary_search(&(row as u32)).expect("a diagonal entry");
                    for (p, v) in a.row_values_mut(row).iter_mut().enumerate() {
                        if p != diagonal {
                            *v = 0.0;
                        }
                    }
                    rhs[row] = 0.0;
                }
                self.nodes.push(Linearized::Stick);
            } else {
                let (a_i, b_i) =
                    slip_linearization(&wi[..m], &xii[..m], &q[..m], q_norm, bound, 0.0, node.augmentation, m);
                for (j, &(_, row)) in node.tangent.iter().enumerate() {
                    rhs[row] += node.weight * a_i[j];
                    for (l, &(_, col)) in node.tangent.iter().enumerate() {
                        let p = a
                            .row(row)
                            .0
                            .binary_search(&(col as u32))
                            .expect("a node's tangent unknowns couple");
                        a.row_values_mut(row)[p] -= node.weight * b_i[j][l];
                    }
                }
                self.nodes.push(Linearized::Slip(a_i, b_i));
            }
        }
        let clock = Instant::now();
        self.ilu.refactor_from(a, sys.first_contact)?;
        // The previous solve left r = b̃ − Ã x for this x; only the Γ_C rows and the contact
        // nodes' temperature rows of Ã and b̃ changed since, so only they are recomputed (a
        // product with Ã saved per iteration).
        if self.residual.len() == n {
            let theta_rows = sys.nodes.iter().filter_map(|node| node.theta);
            for row in (sys.first_contact..n).chain(theta_rows) {
                self.residual[row] = rhs[row] - a.row_dot(row, a.row(row).1, x);
            }
        }
        info.newton_iterations += 1;
        info.krylov_iterations += krylov_solve(sys, (a, self.ilu), rhs, x, &mut self.residual, clock)?;

        // The new iterate: w from x, ξ from the linearization (slip) or the rows (stick).
        let new_w = tangential(&sys.nodes, td, x, w.len());
        let mut new_xi = vec![0.0; xi.len()];
        for (i, (node, lin)) in sys.nodes.iter().zip(&self.nodes).enumerate() {
            let start = i * td;
            match lin {
                Linearized::Stick => {
                    // The node's rows of A (not Ã) leave ℓ_i ξ_i over.
                    for &(k, row) in &node.tangent {
                        let values = &sys.base[a.offset_from(sys.first_contact, row)];
                        new_xi[start + k] = (a.row_dot(row, values, x) - self.b[row]) / node.weight;
                    }
                }
                Linearized::Slip(a_i, b_i) => {
                    for (j, &(k, _)) in node.tangent.iter().enumerate() {
                        new_xi[start + k] = a_i[j]
                            + (node.tangent.iter().enumerate())
                                .map(|(l, &(kl, _))| b_i[j][l] * new_w[start + kl])
                                .sum::<f64>();
                    }
                }
            }
        }
        Ok((new_w, new_xi))
    }
}

/// Solves Ã x = b̃ by GMRES from x (`residual`: b̃ − Ã x on entry when it has n entries, and
/// after), counts the solve from `clock` on, and returns its Krylov iterations. A solve at its
/// cap is a step failure of the linear solve, with its residual history.
pub(super) fn krylov_solve(
    sys: &KrylovSystem,
    (a, ilu): (&CsrMatrix, &Ilu0),
    rhs: &[f64],
    x: &mut [f64],
    residual: &mut Vec<f64>,
    clock: Instant,
) -> Result<usize, SolveError> {
    let solved = sys.gmres((a, ilu), rhs, x, residual);
    sys.count(|s| {
        s.solves += 1;
        s.krylov_iterations += solved.as_ref().map_or(0, |i| i.iterations);
        s.solve_seconds += clock.elapsed().as_secs_f64();
    });
    match solved {
        Ok(solve) => Ok(solve.iterations),
        Err(Error::KrylovNotConverged {
            iterations,
            rtol,
            residual,
            history,
            ..
        }) => Err(SolveError::NotConverged(StepFailure {
            solver: "iterative",
            loop_name: "GMRES",
            iterations,
            criterion: Criterion::LinearResidual,
            value: residual,
            tolerance: rtol,
            residual_history: history,
        })),
        Err(other) => Err(other.into()),
    }
}

/// w_τ at the contact nodes, node-major in tangent coordinates (`len` values), from x in the
/// system's order (0 at held coordinates).
pub(super) fn tangential(nodes: &[NodeRows], td: usize, x: &[f64], len: usize) -> Vec<f64> {
    let mut w = vec![0.0; len];
    for (i, node) in nodes.iter().enumerate() {
        for &(k, row) in &node.tangent {
            w[i * td + k] = x[row];
        }
    }
    w
}

/// The Newton–Krylov step solver on a [`KrylovSystem`].
pub struct NewtonKrylov<'a> {
    problem: &'a Problem,
    system: KrylovSystem,
    /// ε_conv.
    tolerance: f64,
    /// Cap on Newton iterations per step.
    max_iterations: usize,
}

impl<'a> NewtonKrylov<'a> {
    /// The solver of `problem` on `system`, stopping at `tolerance` (ε_conv) within
    /// `max_iterations` Newton iterations per step.
    pub fn new(problem: &'a Problem, system: KrylovSystem, tolerance: f64, max_iterations: usize) -> Self {
        NewtonKrylov {
            problem,
            system,
            tolerance,
            max_iterations,
        }
    }

    /// The ordered step matrix and its preconditioner.
    pub fn system(&self) -> &KrylovSystem {
        &self.system
    }

    /// One step of the system's size k, from `previous` to the state at time `t`: the
    /// convexification loop, each convex problem solved by Newton iterations.
    pub fn step(&self, previous: &State, t: f64) -> Result<(State, StepInfo), SolveError> {
        let problem = self.problem;
        let sys = &self.system;
        let td = problem.dim() - 1;
        let n = sys.order.len();
        let clock = Instant::now();
        let b_unordered = sys.rhs.rhs(problem, previous, t)?;
        let b: Vec<f64> = sys.order.iter().map(|&o| b_unordered[o]).collect();
        let x_previous = sys.rhs.unknowns_of(problem, previous);
        let mut x: Vec<f64> = sys.order.iter().map(|&o| x_previous[o]).collect();
        sys.count(|s| s.rhs_seconds += clock.elapsed().as_secs_f64());

        let friction = problem.friction.as_ref();
        let bounds_at = |w: &[f64]| -> Vec<f64> {
            (0..problem.contact.len())
                .map(|i| friction.bound(norm(&w[i * td..(i + 1) * td])))
                .collect()
        };
        let mut w = self.tangential(&x);
        let mut xi = previous.xi.clone();
        let mut info = StepInfo::default();
        let mut checks = Vec::new();
        let mut guard = sys.lock();
        let (a, ilu) = &mut *guard;
        let mut solve = Linearization {
            system: sys,
            a,
            ilu,
            b: &b,
            heat_rate: problem.heating.heat(t, 1.0),
            td,
            rhs: vec![0.0; n],
            residual: Vec::new(),
            nodes: Vec::with_capacity(sys.nodes.len()),
        };
        // The convex problems are solved to 1 % of the loop's last change (they only need to
        // be exact once the loop is), never looser than 1e-4 nor tighter than 1e-10.
        let mut inner_tolerance: f64 = 1e-4;
        for m in 1..=self.max_iterations {
            let frozen = bounds_at(&w);
            let g_scale = frozen.iter().fold(0.0f64, |s, v| s.max(*v)).max(f64::MIN_POSITIVE);
            let (w_outer, xi_outer) = (w.clone(), xi.clone());
            let mut inner_converged = false;
            for _ in 0..MAX_NEWTON_PER_CONVEX_PROBLEM {
                (w, xi) = solve.newton_iteration(&mut x, &w, &xi, &frozen, &mut info)?;
                // The linear equations hold at the new iterate (up to the Krylov tolerance and
                // the lagged heat), so the convex problem is solved where its law holds: no
                // second solve to see the update vanish.
                if self.law_residual(&w, &xi, &frozen) <= inner_tolerance * g_scale {
                    inner_converged = true;
                    break;
                }
            }
            info.convexification_iterations = m;
            let bounds = bounds_at(&w);
            let g_min = bounds.iter().fold(f64::INFINITY, |s, v| s.min(*v));
            let w_scale = w.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            let law = self.law_residual(&w, &xi, &bounds);
            checks = vec![
                (
                    Criterion::IncrementW,
                    max_diff(&w, &w_outer) / w_scale.max(f64::MIN_POSITIVE),
                    self.tolerance,
                ),
                (
                    Criterion::IncrementXiNodal,
                    max_diff(&xi, &xi_outer) / g_scale,
                    self.tolerance,
                ),
                (Criterion::NodalLaw, law / g_min.max(f64::MIN_POSITIVE), self.tolerance),
            ];
            let change = checks.iter().fold(0.0f64, |m, c| m.max(c.1));
            inner_tolerance = (0.01 * change).clamp(1e-10, inner_tolerance);
            if inner_converged && checks.iter().all(|&(_, value, tol)| value <= tol) {
                drop(guard);
                let mut x_unknowns = vec![0.0; n];
                sys.order.iter().zip(&x).for_each(|(&o, v)| x_unknowns[o] = *v);
                let state = sys.rhs.state_from(problem, previous, t, &x_unknowns, xi);
                return Ok((state, info));
            }
        }
        let (criterion, value, tolerance) = worst_criterion(&checks);
        Err(SolveError::NotConverged(StepFailure {
            solver: "iterative",
            loop_name: "convexification",
            iterations: self.max_iterations,
            criterion,
            value,
            tolerance,
            residual_history: Vec::new(),
        }))
    }

    fn tangential(&self, x: &[f64]) -> Vec<f64> {
        let td = self.problem.dim() - 1;
        tangential(&self.system.nodes, td, x, self.problem.contact.len() * td)
    }

    /// max_i |ξ_i − P_{g_i}(ξ_i − r_i w_i)| (stress units) for the bounds g: with g = b(|w|) the
    /// nonmonotone law itself.
    fn law_residual(&self, w: &[f64], xi: &[f64], bounds: &[f64]) -> f64 {
        let td = self.problem.dim() - 1;
        (self.system.nodes.iter().enumerate()).fold(0.0, |worst, (i, node)| {
            let range = i * td..(i + 1) * td;
            worst.max(node_law_residual(
                &w[range.clone()],
                &xi[range],
                bounds[i],
                node.augmentation,
            ))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::matrix::StepMatrix;
    use crate::Scenario;

    /// The iterative path's A, assembled column by column in its own order, is the direct
    /// path's S = J A permuted and sign-flipped: the same matrix, entry for entry.
    #[test]
    fn the_ordered_assembly_is_the_step_matrix_permuted() {
        let sets = ["mesh.nx=4".into(), "mesh.ny=2".into(), "mesh.nz=2".into()];
        let text = include_str!("../../scenarios/paper3d.toml");
        let problem = Scenario::load(Some(text), &sets).unwrap().build().unwrap();
        let k = problem.time_step();
        let system = KrylovSystem::new(&problem, k, KrylovParams::default()).unwrap();
        let s = StepMatrix::assemble(&problem, k).matrix;
        let expected = CsrMatrix::from_symmetric_form_ordered(&s, problem.velocity.n_free, &system.order);
        let (a, _) = &*system.lock();
        assert!(system.first_contact < a.n() && a.n() == s.n_rows);
        for i in 0..a.n() {
            let ((c1, v1), (c2, v2)) = (a.row(i), expected.row(i));
            assert_eq!(c1, c2, "row {i}");
            for (x, y) in v1.iter().zip(v2) {
                assert!((x - y).abs() <= 1e-12 * y.abs().max(1.0), "row {i}: {x} {y}");
            }
        }
    }
}
