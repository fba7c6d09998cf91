//! The iterative back-end: the step problem solved on all unknowns, without condensation onto Γ_C,
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
//! **The linear solves.** The tangential velocity unknowns of Γ_C are ordered last, so that the
//! rows a linearization changes are the last rows of Ã: their ILU(0) rows are refactored in
//! O(n_t) per iteration ([`Ilu0::refactor_from`]) and the preconditioner is the ILU(0) of Ã
//! itself, not of A (a stick row, w_i = 0, is far from A's row; preconditioning Ã with A's
//! factor would leave GMRES a rank-n_t perturbation to find). Before them come the two halves
//! of the mesh and the cross-section between them ([`crate::la::level_bisection`]), so that the ILU(0)
//! sweeps run the halves on the two cores. GMRES starts from the previous
//! iterate (from the previous step's state at the first), so the later iterations of a step
//! need few Krylov iterations, and keeps its vectors over the step's solves ([`Gmres`]: fresh
//! ones were the kernel zeroing pages, 10–20 % of a step at 972k unknowns). Why GMRES +
//! ILU(0) and when it stays bounded: docs/krylov-study.md. Tried and dropped (2026-11-27):
//! starting each solve from the least-squares combination of the last corrections (Fischer's
//! projection), 10 % fewer Krylov iterations at k = 1/64, but fields that move by the Krylov
//! tolerance and a hard step (47k, k = 1/8) that Newton on the law then no longer finishes
//! (docs/performance.md).

use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::amg::VelocityAmg;
use super::contact_condensation::condense;
use super::direct::{contact_tangential_unknowns, SystemStats};
use super::{Criterion, KrylovParams, PreconditionerKind, SolveError, StepError, StepFailure};
use crate::la::{gmres, level_bisection, CsrMatrix, FactorStage, Gmres, Ilu0, LaError, NodeGraph, Part, SolveInfo};
use crate::model::{ordered_rows, Problem, State, StepRhs};

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
    pub(super) augmentation: f64,
}

/// The step matrix with the Γ_C velocity unknowns last, its ILU(0) and the right-hand side:
/// the iterative counterpart of [`super::direct::StepSystem`], set up once per step size.
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
    /// The Krylov solves' relative tolerance ([`KrylovParams::rtol`]).
    pub(super) rtol: f64,
    /// The Newton solves' forcing term ([`KrylovParams::forcing`]).
    pub(super) forcing: f64,
    /// Ã and its Krylov solver, changed in the contact rows by each linearization.
    work: Mutex<(CsrMatrix, KrylovSolver)>,
    /// The AMG coarse correction of the velocities, where the preconditioner has one (`amg`, or
    /// `auto` resolved to it).
    amg: Option<VelocityAmg>,
    stats: Mutex<SystemStats>,
    /// The layers of the body the predicted bounds' sweeps condense through
    /// ([`KrylovParams::condensed_layers`]; 0: none).
    condensed_layers: usize,
    /// The step matrix condensed onto Γ_C through them: in one process computed at the first
    /// sweep, on the ranks at set-up (from the layers' rows, assembled there for it alone).
    condensed: Mutex<Option<Arc<CsrMatrix>>>,
}

/// Where a row of Ã that a linearization changes is kept (in one process: here, every one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub(super) enum RowHere {
    /// This process's (rank's) own row: it linearizes it, and the row's unknowns are its.
    Owned,
    /// A row of another rank that this rank's overlapping block holds: it linearizes it too.
    Overlap,
    /// Another rank's, which this rank leaves to it.
    Elsewhere,
}

/// What solves Ã x = b̃ by GMRES: this process, with the ILU(0) of Ã (and the AMG's coarse
/// correction of the velocities where the system has one), or PETSc over the MPI ranks of a
/// distributed run ([`KrylovParams::distributed`], [`super::ranks`]).
pub(super) enum KrylovSolver {
    /// This process's GMRES (its vectors kept from solve to solve; boxed, as the solver is a
    /// variant of the step's linear system) with the ILU(0) of Ã.
    Process { ilu: Ilu0, gmres: Box<Gmres> },
    /// PETSc's GCR over the ranks.
    #[cfg(feature = "mpi")]
    Ranks(super::ranks::RankKrylov),
}

impl KrylovSolver {
    /// The preconditioner brought up to date with Ã, whose rows from `first_changed` on have
    /// changed (the ILU(0) refactored from there; the ranks' rows handed to PETSc again).
    pub(super) fn update(&mut self, a: &CsrMatrix, first_changed: usize) -> Result<(), LaError> {
        match self {
            KrylovSolver::Process { ilu, .. } => ilu.refactor_from(a, first_changed),
            #[cfg(feature = "mpi")]
            KrylovSolver::Ranks(ranks) => ranks.set_matrix(a, first_changed),
        }
    }

    /// Where row `row` of Ã, one a linearization changes (Γ_C's), is kept: every row is this
    /// process's own; on the ranks, a rank's own, its block's overlap or another's
    /// ([`super::ranks::RankKrylov::row_here`]).
    #[cfg_attr(not(feature = "mpi"), allow(unused_variables))]
    pub(super) fn row_here(&self, row: usize) -> RowHere {
        match self {
            KrylovSolver::Process { .. } => RowHere::Owned,
            #[cfg(feature = "mpi")]
            KrylovSolver::Ranks(ranks) => ranks.row_here(row),
        }
    }

    /// Values held at this process's own entries (the others −0.0) made whole: as they are in
    /// one process; summed over the ranks (each entry its owner's, to the bit).
    #[cfg_attr(not(feature = "mpi"), allow(unused_variables))]
    pub(super) fn share_owned_entries(&self, values: &mut [f64]) -> Result<(), LaError> {
        match self {
            KrylovSolver::Process { .. } => Ok(()),
            #[cfg(feature = "mpi")]
            KrylovSolver::Ranks(ranks) => ranks.share_owned_entries(values),
        }
    }

    /// Gives back the memory of the Krylov method's vectors, kept over the solves of a step
    /// ([`Gmres`]; at the end of each, [`StepWork`]); PETSc keeps its own.
    fn release_work(&mut self) {
        match self {
            KrylovSolver::Process { gmres, .. } => gmres.release(),
            #[cfg(feature = "mpi")]
            KrylovSolver::Ranks(_) => {}
        }
    }

    /// Stored entries of Ã and of its factor (this process's ILU(0), or this rank's rows).
    fn nnz(&self) -> usize {
        match self {
            KrylovSolver::Process { ilu, .. } => ilu.nnz(),
            #[cfg(feature = "mpi")]
            KrylovSolver::Ranks(ranks) => ranks.nnz(),
        }
    }
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
    let part = level_bisection(&NodeGraph::of_nodal_matrix(&problem.matrices.heat_mass), &weight);
    let (is_contact, part, node_of) = (&is_contact, &part, &node_of);
    let in_part = |x: Part| (0..n).filter(move |&r| !is_contact[r] && part[node_of[r]] == x);
    let first = in_part(Part::First).count();
    let second = first + in_part(Part::Second).count();
    let first_contact = n - tangential.len();
    // Sized once (kept for the run; collected from filters it would grow by doubling).
    let mut order = Vec::with_capacity(n);
    order.extend(in_part(Part::First).chain(in_part(Part::Second)));
    order.extend(in_part(Part::Separator).chain(tangential));
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
) -> Result<bool, StepError> {
    let b_unordered = rhs.rhs(problem, &State::initial(problem), rhs.time_step(), None)?;
    let b: Vec<f64> = order.iter().map(|&o| b_unordered[o]).collect();
    let mut x = vec![0.0; b.len()];
    let probe = KrylovParams {
        rtol: 1e-8,
        max_iterations: PreconditionerKind::AUTO_AMG_ABOVE,
        ..KrylovParams::default()
    };
    match gmres(a, ilu, &b, &mut x, &probe.gmres()) {
        Ok(_) => Ok(false),
        Err(LaError::KrylovNotConverged { .. }) => Ok(true),
        Err(other) => Err(other.into()),
    }
}

/// The step matrix of step size k on this rank of a distributed run and its Krylov solver over
/// the ranks (the system's row of each unknown: `position`, the inverse of `order`): Ã's rows
/// this rank owns handed to PETSc, and of Ã itself only the rows from `first_contact` on kept
/// (those each linearization changes, on every rank) and the contact nodes' temperature rows,
/// the others left empty; the preconditioner from `params.preconditioner`: for `ilu` restricted additive
/// Schwarz with each rank's overlapped block's ILU(0) (block Jacobi with its own block's where
/// `params.overlap` is 0), those sweeps around PETSc's GAMG on the velocity block for `amg`
/// (the serial path's two-level method), and for `auto` the serial rule's probe with the `ilu`
/// one (the first step's system from zero to 10⁻⁸, `amg` where it needs more than
/// [`PreconditionerKind::AUTO_AMG_ABOVE`] iterations).
#[cfg(feature = "mpi")]
fn ranks_system(
    problem: &Problem,
    k: f64,
    (order, position, first_contact): (&[usize], &[usize], usize),
    params: &KrylovParams,
) -> Result<(CsrMatrix, StepRhs, KrylovSolver, Option<CsrMatrix>), StepError> {
    use super::ranks::{RankKrylov, RankRows};
    use crate::la::mpi::{DistributedKrylov, DistributedPreconditioner};
    let krylov = |preconditioner, rtol, max_iterations| DistributedKrylov {
        preconditioner,
        rtol,
        max_iterations,
        restart: params.restart,
    };
    // The one-level sweeps: the blocks overlapping or not; `amg` adds GAMG on the velocity
    // block between two of them (`RankKrylov::set_velocity_amg`).
    let first = if params.overlap > 0 {
        DistributedPreconditioner::SchwarzShell
    } else {
        DistributedPreconditioner::BlockJacobiShell
    };
    let rows = RankRows::new(problem, order)?;
    // The contact nodes' temperature rows: a linearization changes their right-hand side (the
    // frictional heat), and the Newton method recomputes their residual from Ã's rows.
    let n_w = problem.velocity.n_free;
    let theta_rows: Vec<usize> = (problem.contact.iter())
        .filter_map(|node| node.theta_dof.map(|r| position[n_w + r]))
        .collect();
    // The predicted bounds' condensation, on every rank the same, from the rows of its layers
    // of the body, assembled for it alone (the problem's share reads them:
    // `ProblemBuilder::contact_layers`).
    let layer_rows = condensation_rows(problem, position, params.condensed_layers)?;
    let assembled = rows.assembled(first_contact, &[&theta_rows[..], &layer_rows].concat());
    let (a, rhs) = crate::model::ordered_rows_at(problem, k, order, &assembled);
    let n = order.len();
    let condensed = match params.condensed_layers {
        0 => None,
        layers => Some(condense(|r| a.row(r), n, first_contact, layers)?),
    };
    let (mut ranks, a) = RankKrylov::new(
        rows,
        (a, first_contact, &theta_rows),
        krylov(first, params.rtol, params.max_iterations),
    )?;
    if params.preconditioner == PreconditionerKind::Amg {
        ranks.set_velocity_amg(problem, k, order)?;
    } else if params.preconditioner == PreconditionerKind::Auto {
        let b_unordered = rhs.rhs(problem, &State::initial(problem), rhs.time_step(), None)?;
        let b: Vec<f64> = order.iter().map(|&o| b_unordered[o]).collect();
        let mut x = vec![0.0; b.len()];
        let probe = krylov(first, 1e-8, PreconditionerKind::AUTO_AMG_ABOVE);
        let needs_amg = match ranks.probe(&probe, &b, &mut x) {
            Ok(_) => false,
            Err(LaError::KrylovNotConverged { .. }) => true,
            Err(other) => return Err(other.into()),
        };
        if needs_amg {
            ranks.set_velocity_amg(problem, k, order)?;
        }
    }
    Ok((a, rhs, KrylovSolver::Ranks(ranks), condensed))
}

/// The system rows (`position` of each unknown) of the nodes within `layers` hops of Γ_C, which
/// a rank assembles for the condensation; an error where the problem's share does not read
/// their columns (built without [`crate::model::ProblemBuilder::contact_layers`] of as many).
#[cfg(feature = "mpi")]
fn condensation_rows(problem: &Problem, position: &[usize], layers: usize) -> Result<Vec<usize>, StepError> {
    if layers == 0 {
        return Ok(Vec::new());
    }
    let mesh = &problem.mesh;
    let mut contact = vec![false; mesh.n_nodes()];
    problem.contact.iter().for_each(|node| contact[node.node] = true);
    let around = crate::model::nodes_within(mesh, contact, layers);
    if let Some(share) = &problem.columns {
        let read = crate::model::nodes_within(mesh, around.clone(), 1);
        if read.iter().zip(share.kept()).any(|(&needed, &kept)| needed && !kept) {
            return Err(LaError::Factorization {
                stage: FactorStage::CondensedLayers,
                detail: format!(
                    "solver.condensed_layers = {layers} reads rows of the body this rank's share of the problem \
                     does not hold: build the problem with ProblemBuilder::contact_layers({layers})"
                ),
            }
            .into());
        }
    }
    let mut unknowns = Vec::new();
    (0..mesh.n_nodes())
        .filter(|&p| around[p])
        .for_each(|p| crate::model::node_unknowns(problem, p, &mut unknowns));
    Ok(unknowns.into_iter().map(|u| position[u]).collect())
}

/// Without the `mpi` feature there are no ranks: a distributed system is refused.
#[cfg(not(feature = "mpi"))]
fn ranks_system(
    _problem: &Problem,
    _k: f64,
    _system: (&[usize], &[usize], usize),
    _params: &KrylovParams,
) -> Result<(CsrMatrix, StepRhs, KrylovSolver, Option<CsrMatrix>), StepError> {
    Err(LaError::Petsc {
        operation: "MPI_Init",
        detail: "this build has no MPI: build thermocontact with `--features mpi` for a distributed run".into(),
    }
    .into())
}

impl KrylovSystem {
    /// Assembles the step matrix of step size k in the order with the Γ_C tangential
    /// velocities last, as A's rows (no symmetric form, no triplets: [`ordered_rows`]),
    /// and factors its ILU(0).
    pub fn new(problem: &Problem, k: f64, params: KrylovParams) -> Result<Self, StepError> {
        let n_w = problem.velocity.n_free;
        let n = n_w + problem.temperature.n_free;
        if u32::try_from(n).is_err() {
            return Err(LaError::Factorization {
                stage: FactorStage::IncompleteLu,
                detail: format!("{n} unknowns exceed 32-bit indices"),
            }
            .into());
        }
        let (order, parts, first_contact) = sweep_order(problem);
        let mut position = vec![0; n];
        order.iter().enumerate().for_each(|(new, &old)| position[old] = new);

        let (a, rhs, solver, amg, condensed) = if params.distributed {
            let (a, rhs, solver, condensed) = ranks_system(problem, k, (&order, &position, first_contact), &params)?;
            (a, rhs, solver, None, condensed)
        } else {
            let (a, rhs) = ordered_rows(problem, k, &order);
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
            let gmres = Box::new(Gmres::new(params.gmres()));
            (a, rhs, KrylovSolver::Process { ilu, gmres }, amg, None)
        };
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
        Ok(KrylovSystem {
            rhs,
            order,
            first_contact,
            nodes,
            base,
            rtol: params.rtol,
            forcing: params.forcing,
            work: Mutex::new((a, solver)),
            amg,
            stats: Mutex::new(SystemStats::default()),
            condensed_layers: params.condensed_layers,
            condensed: Mutex::new(condensed.map(Arc::new)),
        })
    }

    /// A condensed onto Γ_C's tangential unknowns through [`KrylovParams::condensed_layers`]
    /// layers of the body next to Γ_C ([`super::contact_condensation`]), once per step size;
    /// `None` where the setting is 0. In one process from `a` (Ã: its bulk rows are A's, its
    /// Γ_C rows A's in `base`) at the first call; on the ranks the set-up's.
    pub(super) fn condensed_rows(&self, a: &CsrMatrix) -> Result<Option<Arc<CsrMatrix>>, LaError> {
        if self.condensed_layers == 0 {
            return Ok(None);
        }
        let mut cached = self.condensed.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(rows) = cached.as_ref() {
            return Ok(Some(Arc::clone(rows)));
        }
        let first = self.first_contact;
        let row = |r: usize| {
            if r >= first {
                (a.row(r).0, &self.base[a.offset_from(first, r)])
            } else {
                a.row(r)
            }
        };
        let rows = Arc::new(condense(row, self.order.len(), first, self.condensed_layers)?);
        *cached = Some(Arc::clone(&rows));
        Ok(Some(rows))
    }

    /// The step size k.
    pub fn time_step(&self) -> f64 {
        self.rhs.time_step()
    }

    /// Stored entries of A and of its ILU(0) factor (the same pattern); in a distributed run,
    /// this rank's.
    pub fn factor_nnz(&self) -> usize {
        self.lock().1.nnz()
    }

    /// The preconditioner set up: [`PreconditionerKind::Ilu`] or [`PreconditionerKind::Amg`]
    /// (`auto` resolved; in a distributed run, ILU(0) on the ranks' blocks, alone or around GAMG
    /// on the velocity block).
    pub fn preconditioner(&self) -> PreconditionerKind {
        #[cfg(feature = "mpi")]
        if let KrylovSolver::Ranks(ranks) = &self.lock().1 {
            return match ranks.preconditioner() {
                crate::la::mpi::DistributedPreconditioner::Gamg => PreconditionerKind::Amg,
                crate::la::mpi::DistributedPreconditioner::BlockJacobiIlu0
                | crate::la::mpi::DistributedPreconditioner::BlockJacobiShell
                | crate::la::mpi::DistributedPreconditioner::SchwarzShell => PreconditionerKind::Ilu,
                crate::la::mpi::DistributedPreconditioner::SchwarzAmgShell => PreconditionerKind::Amg,
            };
        }
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
    /// [`Gmres::solve_inexact`] for `residual` and `forcing`; 0: to the system's rtol).
    pub(super) fn gmres(
        &self,
        (a, solver): (&CsrMatrix, &mut KrylovSolver),
        rhs: &[f64],
        x: &mut [f64],
        residual: &mut Vec<f64>,
        forcing: f64,
    ) -> Result<SolveInfo, LaError> {
        match (solver, &self.amg) {
            (KrylovSolver::Process { ilu, gmres }, None) => gmres.solve_inexact(a, &*ilu, rhs, x, residual, forcing),
            (KrylovSolver::Process { ilu, gmres }, Some(amg)) => {
                gmres.solve_inexact(a, &amg.with(a, ilu), rhs, x, residual, forcing)
            }
            // At this rank's own rows (`RankKrylov::solve`).
            #[cfg(feature = "mpi")]
            (KrylovSolver::Ranks(ranks), _) => ranks.solve(rhs, x, residual, forcing),
        }
    }

    /// x (the system's order) whole after the solves of a step: in a distributed run each solve
    /// leaves x the iterate only where the Newton iterations read it ([`super::ranks::RankKrylov::solve`]),
    /// and this gathers the rest (collective); in one process x is whole already.
    pub(super) fn whole(&self, solver: &mut KrylovSolver, x: &mut [f64]) -> Result<(), LaError> {
        match solver {
            KrylovSolver::Process { .. } => {
                let _ = x; // whole already (read only by the ranks' arm)
                Ok(())
            }
            #[cfg(feature = "mpi")]
            KrylovSolver::Ranks(ranks) => ranks.gather_whole(x),
        }
    }

    /// The start of a step from `previous` to time `t`, in this system's order: b (its linear
    /// part, without the contact terms; a nonlinear heat exchange at `exchange_at`) and the
    /// previous step's unknowns, the first iterate.
    pub(super) fn start(
        &self,
        problem: &Problem,
        previous: &State,
        t: f64,
        exchange_at: Option<&[f64]>,
    ) -> Result<(Vec<f64>, Vec<f64>), StepError> {
        let clock = Instant::now();
        let b_unordered = self.rhs.rhs(problem, previous, t, exchange_at)?;
        let b: Vec<f64> = self.order.iter().map(|&o| b_unordered[o]).collect();
        let x_previous = self.rhs.unknowns_of(problem, previous);
        let x: Vec<f64> = self.order.iter().map(|&o| x_previous[o]).collect();
        self.count(|s| s.rhs_seconds += clock.elapsed().as_secs_f64());
        Ok((b, x))
    }

    /// The step's right-hand side b (its linear part, without the contact terms) from
    /// `previous` to time `t`, in the unknowns' numbering: with [`KrylovSystem::solve`], the
    /// first step's system of studies and tests.
    pub fn rhs(&self, problem: &Problem, previous: &State, t: f64) -> Result<Vec<f64>, StepError> {
        Ok(self.rhs.rhs(problem, previous, t, None)?)
    }

    /// Solves A x = b with the step matrix itself (its Γ_C rows as assembled, no contact
    /// linearization), b and x in the unknowns' numbering, x holding the initial guess: one
    /// solve of the constant matrix with this system's preconditioner, for studies and tests.
    pub fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<SolveInfo, LaError> {
        let mut guard = self.lock();
        let (a, solver) = &mut *guard;
        a.values_from_mut(self.first_contact).copy_from_slice(&self.base);
        solver.update(a, self.first_contact)?;
        let b_ordered: Vec<f64> = self.order.iter().map(|&o| b[o]).collect();
        let mut x_ordered: Vec<f64> = self.order.iter().map(|&o| x[o]).collect();
        let info = self.gmres((a, solver), &b_ordered, &mut x_ordered, &mut Vec::new(), 0.0)?;
        self.order.iter().zip(&x_ordered).for_each(|(&o, v)| x[o] = *v);
        Ok(info)
    }

    /// The work counters so far.
    pub fn stats(&self) -> SystemStats {
        *self.stats.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub(super) fn lock(&self) -> std::sync::MutexGuard<'_, (CsrMatrix, KrylovSolver)> {
        self.work.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Ã and its Krylov solver for the solves of one step: when the step lets them go, however
    /// it ends, the solver gives its vectors back ([`KrylovSolver::release_work`]), so that they
    /// are not held while the step's output is written.
    pub(super) fn lock_for_step(&self) -> StepWork<'_> {
        StepWork(self.lock())
    }

    pub(super) fn count(&self, update: impl FnOnce(&mut SystemStats)) {
        update(&mut self.stats.lock().unwrap_or_else(|e| e.into_inner()));
    }
}

/// Ã and its Krylov solver held for one step ([`KrylovSystem::lock_for_step`]).
pub(super) struct StepWork<'s>(std::sync::MutexGuard<'s, (CsrMatrix, KrylovSolver)>);

impl std::ops::Deref for StepWork<'_> {
    type Target = (CsrMatrix, KrylovSolver);

    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

impl std::ops::DerefMut for StepWork<'_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.0
    }
}

impl Drop for StepWork<'_> {
    fn drop(&mut self) {
        self.0 .1.release_work();
    }
}

/// Solves Ã x = b̃ by GMRES (GCR over the ranks) from x (`residual`: b̃ − Ã x on entry when it
/// has n entries, and after; over the ranks at each rank's own rows) to the system's rtol or,
/// if looser, `forcing` times the residual it starts from (a Newton correction's forcing term,
/// [`Gmres::solve_inexact`]; 0: rtol), counts the solve from `clock` on, and returns its Krylov
/// iterations and whether it reached rtol. A solve at its cap is a step failure of the linear
/// solve, with its residual history.
pub(super) fn krylov_solve(
    sys: &KrylovSystem,
    (a, solver): (&CsrMatrix, &mut KrylovSolver),
    (rhs, forcing): (&[f64], f64),
    x: &mut [f64],
    residual: &mut Vec<f64>,
    clock: Instant,
) -> Result<(usize, bool), SolveError> {
    let loop_name = match solver {
        KrylovSolver::Process { .. } => "GMRES",
        #[cfg(feature = "mpi")]
        KrylovSolver::Ranks(_) => "GCR",
    };
    let solved = sys.gmres((a, solver), rhs, x, residual, forcing);
    sys.count(|s| {
        s.solves += 1;
        // A solve at its cap did its iterations too.
        s.krylov_iterations += match &solved {
            Ok(info) => info.iterations,
            Err(LaError::KrylovNotConverged { iterations, .. }) => *iterations,
            Err(_) => 0,
        };
        s.solve_seconds += clock.elapsed().as_secs_f64();
    });
    match solved {
        Ok(solve) => Ok((solve.iterations, forcing == 0.0 || solve.residual <= sys.rtol)),
        Err(LaError::KrylovNotConverged {
            iterations,
            rtol,
            residual,
            history,
            ..
        }) => Err(SolveError::NotConverged(StepFailure {
            solver: "iterative",
            loop_name,
            iterations,
            criterion: Criterion::LinearResidual,
            value: residual,
            tolerance: rtol,
            residual_history: history,
            cycle: None,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::StepMatrix;

    /// The iterative path's A, assembled column by column in its own order, is the direct
    /// path's S = J A permuted and sign-flipped: the same matrix, entry for entry.
    #[test]
    fn the_ordered_assembly_is_the_step_matrix_permuted() {
        let problem = crate::model::samples::paper_3d([4, 2, 2], 64).unwrap();
        let k = problem.time_step();
        let system = KrylovSystem::new(&problem, k, KrylovParams::default()).unwrap();
        let s = StepMatrix::assemble(&problem, k).matrix;
        let expected = crate::model::rows_of_symmetric_form_ordered(&s, problem.velocity.n_free, &system.order);
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
