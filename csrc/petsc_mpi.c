/* The thin C layer between thermocontact and PETSc + MPI on MPI_COMM_WORLD (cargo feature `mpi`):
 * the communicator's rank, size, reductions, broadcast, barrier and abort; the partition of a
 * graph by PETSc's MatPartitioning (PT-Scotch); a distributed AIJ matrix assembled by the COO
 * API with its Krylov solver (GCR, which keeps its residual for the next solve, + block
 * Jacobi/ILU(0), Schwarz sweeps or GAMG), its right-hand side
 * assembled by PETSc (off-process entries sent by VecAssembly) and its solution gathered on rank 0.
 *
 * As csrc/petsc_amg.c: compiled against the installed headers, plain C types across the
 * boundary (int, long long, double, opaque handles), errors recorded by the handler that
 * tc_petsc_initialize pushes (tc_petsc_last_error). */
#include <petscksp.h>
#include <petscmat.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdint.h>
#include <scotch/scotch.h>

int            tc_petsc_initialize(void);
PetscErrorCode tc_gamg_on(Mat A, int n_modes, const double *modes, const char *prefix, const char *smooth_option,
                          int fine_smooth_its, KSP *ksp);

/* A documented user-level function that PETSc 3.18 declares only in its private petscimpl.h
 * (libpetsc exports it; later versions declare it in petscsys.h: a second identical
 * declaration is valid C). */
PETSC_EXTERN PetscErrorCode PetscObjectStateGet(PetscObject, PetscObjectState *);

static int tc_we_initialized_mpi = 0;

/* At exit: PetscFinalize, then MPI_Finalize if this layer started MPI (Open MPI's mpirun
 * reports a rank that exits without it as failed). */
static void tc_mpi_finalize(void)
{
  PetscBool petsc_done = PETSC_FALSE;
  int       mpi_done = 0;
  PetscInitialized(&petsc_done);
  if (petsc_done) PetscFinalize();
  MPI_Finalized(&mpi_done);
  if (tc_we_initialized_mpi && !mpi_done) MPI_Finalize();
}

/* MPI with MPI_THREAD_SERIALIZED (the calls come from one thread at a time, not always the main
 * one: Rust's test harness runs tests on threads), then PETSc on MPI_COMM_WORLD, once. */
int tc_mpi_initialize(void)
{
  int done = 0, provided = 0, ierr;
  MPI_Initialized(&done);
  if (!done) {
    ierr = MPI_Init_thread(NULL, NULL, MPI_THREAD_SERIALIZED, &provided);
    if (ierr != MPI_SUCCESS) return ierr;
    tc_we_initialized_mpi = 1;
    atexit(tc_mpi_finalize);
  }
  return tc_petsc_initialize();
}

int tc_mpi_rank(void)
{
  int rank = 0;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  return rank;
}

int tc_mpi_size(void)
{
  int size = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  return size;
}

static MPI_Op tc_op(int op) { return op == 0 ? MPI_SUM : op == 1 ? MPI_MAX : MPI_MIN; }

/* In-place reductions over all ranks: op 0 sum, 1 max, 2 min. */
int tc_mpi_allreduce_f64(double *values, int n, int op)
{
  return MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_DOUBLE, tc_op(op), PETSC_COMM_WORLD);
}

int tc_mpi_allreduce_u64(unsigned long long *values, int n, int op)
{
  return MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_UNSIGNED_LONG_LONG, tc_op(op), PETSC_COMM_WORLD);
}

/* Rank 0's bytes to every rank (the caller has sized the buffer from a broadcast length). */
int tc_mpi_broadcast(void *bytes, long long n)
{
  char     *p = bytes;
  long long sent = 0;
  while (sent < n) { /* counts are int: chunks of 1 GiB */
    int chunk = (int)(n - sent < (1LL << 30) ? n - sent : (1LL << 30));
    int ierr = MPI_Bcast(p + sent, chunk, MPI_BYTE, 0, PETSC_COMM_WORLD);
    if (ierr != MPI_SUCCESS) return ierr;
    sent += chunk;
  }
  return 0;
}

int tc_mpi_barrier(void) { return MPI_Barrier(PETSC_COMM_WORLD); }

/* Ends every rank: the message once (from the calling rank), then MPI_Abort. */
void tc_mpi_abort(const char *message, int code)
{
  int rank = tc_mpi_rank(), size = tc_mpi_size();
  fprintf(stderr, "thermocontact (rank %d of %d): %s\n", rank, size, message);
  fflush(stderr);
  MPI_Abort(PETSC_COMM_WORLD, code);
}

/* Partition of the graph (xadj, adjncy: CSR adjacency without self-loops, n vertices) into
 * n_parts by PETSc's MatPartitioning of type `type` ("ptscotch"), on this rank alone
 * (PETSC_COMM_SELF). part[v] receives the part of vertex v. The same graph gives the same
 * parts on every call and in every run: Scotch's random generator is reset to a fixed seed
 * first (Debian's Scotch seeds it from the clock, so two runs of one case were split
 * differently and, preconditioned differently, took different Krylov iterations). */
int tc_partition_graph(int n, const int *xadj, const int *adjncy, int n_parts, const char *type, int *part)
{
  Mat             adj;
  MatPartitioning partitioning;
  IS              is;
  const PetscInt *parts;
  PetscInt       *i, *j;
  PetscFunctionBeginUser;
  /* MatCreateMPIAdj takes the arrays over (freed with the matrix): copies from PetscMalloc. */
  PetscCall(PetscMalloc1(n + 1, &i));
  PetscCall(PetscMalloc1(xadj[n], &j));
  for (int v = 0; v <= n; ++v) i[v] = xadj[v];
  for (int e = 0; e < xadj[n]; ++e) j[e] = adjncy[e];
  PetscCall(MatCreateMPIAdj(PETSC_COMM_SELF, n, n, i, j, NULL, &adj));
  PetscCall(MatPartitioningCreate(PETSC_COMM_SELF, &partitioning));
  PetscCall(MatPartitioningSetAdjacency(partitioning, adj));
  PetscCall(MatPartitioningSetNParts(partitioning, n_parts));
  PetscCall(MatPartitioningSetType(partitioning, type));
  PetscCall(MatPartitioningSetFromOptions(partitioning));
  SCOTCH_randomSeed(1);
  SCOTCH_randomReset();
  PetscCall(MatPartitioningApply(partitioning, &is));
  PetscCall(ISGetIndices(is, &parts));
  for (int v = 0; v < n; ++v) part[v] = (int)parts[v];
  PetscCall(ISRestoreIndices(is, &parts));
  PetscCall(ISDestroy(&is));
  PetscCall(MatPartitioningDestroy(&partitioning));
  PetscCall(MatDestroy(&adj));
  PetscFunctionReturn(0);
}

/* A distributed square matrix (rows [first, first + n_owned) on this rank, global size n_global)
 * with its pattern from COO pairs, the right-hand side, solution and Krylov solver. */
struct tc_dist {
  Mat        A;
  Vec        b, x;
  KSP        ksp;
  PetscCount n_coo;
  /* The scatter of x to every rank and its whole copy, made at the first tc_dist_all_gather. */
  VecScatter to_all;
  Vec        whole;
  /* The scatter of the entries of x this rank selected (tc_dist_select) and their copy. */
  VecScatter to_selected;
  Vec        selected;
  /* The caller's preconditioner of this rank's block (preconditioner 2), set for the length of
   * one tc_dist_solve_from: z = M_r^-1 r on the owned entries, 0 on success. */
  int (*block_apply)(void *ctx, const double *r, double *z, int n);
  void *block_ctx;
  /* Restricted additive Schwarz (preconditioner 3, tc_dist_set_overlap): the scatter of the
   * overlap's entries (rows of other ranks that this rank's rows read) from a vector of A's
   * layout, their copy, and the overlapped block's input [owned, overlap] and output. */
  VecScatter   to_overlap;
  Vec          overlap;
  PetscInt     n_overlap;
  PetscScalar *overlap_in, *overlap_out;
  /* The coarse correction of preconditioner 4 (tc_dist_set_velocity_amg): GAMG on the
   * velocity block in the nodes' padded numbering, its vectors, the slot of each of this rank's
   * velocity rows (local row, local slot), and two vectors of A's layout. */
  Mat       velocity;
  KSP       amg;
  Vec       coarse_in, coarse_out, residual, sweep;
  PetscInt  n_slots;
  PetscInt *slot_row, *slot;
  /* The operator the Krylov solver multiplies by: a MATSHELL over A (tc_dist_product) that
   * answers a product with x while x is still the zero a correction solve set it to (x's
   * state then: x_zero_state, x_zero_known) by zero, without reading A. */
  Mat              product;
  PetscObjectState x_zero_state;
  PetscBool        x_zero_known;
  /* The relative tolerance and iteration cap of tc_dist_krylov, and the final residual's
   * vector and a work vector for KSPBuildResidual (made at the first solve that asks). */
  PetscReal rtol;
  PetscInt  max_its;
  Vec       final_residual, work;
  /* GCR's restart as set up (restart) and as asked (restart_max), and the preconditioner's
   * code: tc_dist_krylov_setup starts below the asked restart and the first solve that needs
   * more sets the solver up again with it (tc_dist_solve_from). */
  PetscInt restart, restart_max;
  int      preconditioner;
};
typedef struct tc_dist tc_dist;

void tc_dist_destroy(tc_dist *dist)
{
  if (!dist) return;
  VecScatterDestroy(&dist->to_all);
  VecDestroy(&dist->whole);
  VecScatterDestroy(&dist->to_selected);
  VecDestroy(&dist->selected);
  VecScatterDestroy(&dist->to_overlap);
  VecDestroy(&dist->overlap);
  free(dist->overlap_in);
  free(dist->overlap_out);
  KSPDestroy(&dist->amg);
  MatDestroy(&dist->velocity);
  VecDestroy(&dist->coarse_in);
  VecDestroy(&dist->coarse_out);
  VecDestroy(&dist->residual);
  VecDestroy(&dist->sweep);
  PetscFree2(dist->slot_row, dist->slot);
  KSPDestroy(&dist->ksp);
  MatDestroy(&dist->product);
  VecDestroy(&dist->final_residual);
  VecDestroy(&dist->work);
  MatDestroy(&dist->A);
  VecDestroy(&dist->b);
  VecDestroy(&dist->x);
  free(dist);
}

/* The pattern once: n_coo (row, col) pairs in global numbering, any rank may name any row
 * (PETSc sends the off-process ones and sums repeated pairs). bs: unknowns per block (for GAMG). */
static PetscErrorCode tc_dist_setup(tc_dist *dist, int n_owned, int n_global, int bs, long long n_coo,
                                    const int *rows, const int *cols)
{
  PetscInt *i, *j;
  PetscFunctionBeginUser;
  PetscCall(MatCreate(PETSC_COMM_WORLD, &dist->A));
  PetscCall(MatSetSizes(dist->A, n_owned, n_owned, n_global, n_global));
  PetscCall(MatSetType(dist->A, MATAIJ));
  if (bs > 1) PetscCall(MatSetBlockSize(dist->A, bs));
  /* MatSetPreallocationCOO may reorder the index arrays it is given: copies. */
  PetscCall(PetscMalloc2(n_coo, &i, n_coo, &j));
  for (long long e = 0; e < n_coo; ++e) {
    i[e] = rows[e];
    j[e] = cols[e];
  }
  PetscCall(MatSetPreallocationCOO(dist->A, (PetscCount)n_coo, i, j));
  /* tc_dist_set_rows changes values, never the pattern. */
  PetscCall(MatSetOption(dist->A, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE));
  PetscCall(PetscFree2(i, j));
  dist->n_coo = (PetscCount)n_coo;
  PetscCall(MatCreateVecs(dist->A, &dist->x, &dist->b));
  PetscFunctionReturn(0);
}

int tc_dist_create(int n_owned, int n_global, int bs, long long n_coo, const int *rows, const int *cols,
                   tc_dist **out)
{
  PetscErrorCode ierr;
  *out = NULL;
  tc_dist *dist = calloc(1, sizeof *dist);
  if (!dist) return PETSC_ERR_MEM;
  ierr = tc_dist_setup(dist, n_owned, n_global, bs, n_coo, rows, cols);
  if (ierr) {
    tc_dist_destroy(dist);
    return (int)ierr;
  }
  *out = dist;
  return 0;
}

/* The matrix from this rank's rows split as PETSc keeps them (n_owned rows): the diagonal
 * block (row pointers di, columns dj local to the rank's first column, values da) and the rest
 * (oi, oj in global columns, oa), columns ascending within a row. The arrays are PETSc's storage
 * from here on, not copied (MatCreateMPIAIJWithSplitArrays): the caller keeps them, unchanged,
 * until tc_dist_destroy, and its values change through tc_dist_set_rows only. Needs 32-bit
 * PetscInt (the arrays are the caller's ints). */
static PetscErrorCode tc_dist_setup_split(tc_dist *dist, int n_owned, int n_global, int *di, int *dj, double *da,
                                          int *oi, int *oj, double *oa)
{
  PetscFunctionBeginUser;
#if defined(PETSC_USE_64BIT_INDICES)
  (void)dist; (void)n_owned; (void)n_global; (void)di; (void)dj; (void)da; (void)oi; (void)oj; (void)oa;
  SETERRQ(PETSC_COMM_SELF, PETSC_ERR_SUP, "the split arrays need PETSc with 32-bit indices");
#else
  PetscCall(MatCreateMPIAIJWithSplitArrays(PETSC_COMM_WORLD, n_owned, n_owned, n_global, n_global, di, dj, da, oi,
                                           oj, oa, &dist->A));
  PetscCall(MatSetOption(dist->A, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE));
  PetscCall(MatCreateVecs(dist->A, &dist->x, &dist->b));
#endif
  PetscFunctionReturn(0);
}

int tc_dist_create_split(int n_owned, int n_global, int *di, int *dj, double *da, int *oi, int *oj, double *oa,
                         tc_dist **out)
{
  PetscErrorCode ierr;
  *out = NULL;
  tc_dist *dist = calloc(1, sizeof *dist);
  if (!dist) return PETSC_ERR_MEM;
  ierr = tc_dist_setup_split(dist, n_owned, n_global, di, dj, da, oi, oj, oa);
  if (ierr) {
    tc_dist_destroy(dist);
    return (int)ierr;
  }
  *out = dist;
  return 0;
}

/* The values of the COO pairs, in their order (repeated pairs summed); collective. The Krylov
 * solver, if set up, stays: its preconditioner is set up again on the new values at the next
 * solve (PCSetUp sees the matrix's state change; the pattern is the same). */
int tc_dist_set_values(tc_dist *dist, const double *values)
{
  return (int)MatSetValuesCOO(dist->A, values, INSERT_VALUES);
}

/* The caller's preconditioner of this rank's block on the n entries of r into z. */
static PetscErrorCode tc_dist_call_block(tc_dist *dist, const PetscScalar *r, PetscScalar *z, PetscInt n)
{
  int code;
  PetscFunctionBeginUser;
  PetscCheck(dist->block_apply, PETSC_COMM_SELF, PETSC_ERR_ORDER, "no block preconditioner given for this solve");
  code = dist->block_apply(dist->block_ctx, r, z, (int)n);
  PetscCheck(code == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "the block preconditioner of this rank failed (%d)", code);
  PetscFunctionReturn(0);
}

/* PCApply of block Jacobi with the caller's preconditioner of each rank's block: the owned
 * entries of r through dist->block_apply. */
static PetscErrorCode tc_dist_block_apply(PC pc, Vec r, Vec z)
{
  tc_dist           *dist;
  const PetscScalar *rv;
  PetscScalar       *zv;
  PetscInt           n;
  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &dist));
  PetscCall(VecGetLocalSize(r, &n));
  PetscCall(VecGetArrayRead(r, &rv));
  PetscCall(VecGetArrayWrite(z, &zv));
  PetscErrorCode applied = tc_dist_call_block(dist, rv, zv, n);
  PetscCall(VecRestoreArrayWrite(z, &zv));
  PetscCall(VecRestoreArrayRead(r, &rv));
  PetscCall(applied);
  PetscFunctionReturn(0);
}

/* PCApply of restricted additive Schwarz with the caller's preconditioner of each rank's
 * overlapped block: r's owned entries and its overlap's (scattered from their ranks) in one
 * local vector [owned, overlap], dist->block_apply on it, and of the result the owned entries
 * only (restricted: no sum over the ranks that share an overlap). */
static PetscErrorCode tc_dist_overlap_apply(PC pc, Vec r, Vec z)
{
  tc_dist           *dist;
  const PetscScalar *rv, *gv;
  PetscScalar       *zv;
  PetscInt           n;
  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &dist));
  PetscCheck(dist->to_overlap, PETSC_COMM_SELF, PETSC_ERR_ORDER, "no overlap set (tc_dist_set_overlap)");
  PetscCall(VecScatterBegin(dist->to_overlap, r, dist->overlap, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(dist->to_overlap, r, dist->overlap, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetLocalSize(r, &n));
  PetscCall(VecGetArrayRead(r, &rv));
  memcpy(dist->overlap_in, rv, (size_t)n * sizeof(PetscScalar));
  PetscCall(VecRestoreArrayRead(r, &rv));
  PetscCall(VecGetArrayRead(dist->overlap, &gv));
  memcpy(dist->overlap_in + n, gv, (size_t)dist->n_overlap * sizeof(PetscScalar));
  PetscCall(VecRestoreArrayRead(dist->overlap, &gv));
  PetscCall(tc_dist_call_block(dist, dist->overlap_in, dist->overlap_out, n + dist->n_overlap));
  PetscCall(VecGetArrayWrite(z, &zv));
  memcpy(zv, dist->overlap_out, (size_t)n * sizeof(PetscScalar));
  PetscCall(VecRestoreArrayWrite(z, &zv));
  PetscFunctionReturn(0);
}

/* r − A z into dist->residual. */
static PetscErrorCode tc_dist_residual(tc_dist *dist, Vec r, Vec z)
{
  PetscFunctionBeginUser;
  PetscCall(MatMult(dist->A, z, dist->residual));
  PetscCall(VecAYPX(dist->residual, -1.0, r));
  PetscFunctionReturn(0);
}

/* PCApply of the two-level method: restricted additive Schwarz sweeps around GAMG's V-cycle on
 * the velocity block (the serial path's `amg`, src/step/amg.rs):
 *   z = S r;  z += Rᵀ B⁻¹ R (r − A z);  z += S (r − A z)
 * with S the Schwarz sweep, R this rank's velocity rows to their padded slots. */
static PetscErrorCode tc_dist_two_level_apply(PC pc, Vec r, Vec z)
{
  tc_dist           *dist;
  const PetscScalar *t;
  PetscScalar       *c, *zv;
  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &dist));
  PetscCheck(dist->amg, PETSC_COMM_SELF, PETSC_ERR_ORDER, "no velocity AMG set (tc_dist_set_velocity_amg)");
  PetscCall(tc_dist_overlap_apply(pc, r, z));
  PetscCall(tc_dist_residual(dist, r, z));
  PetscCall(VecZeroEntries(dist->coarse_in));
  PetscCall(VecGetArrayRead(dist->residual, &t));
  PetscCall(VecGetArray(dist->coarse_in, &c));
  for (PetscInt e = 0; e < dist->n_slots; ++e) c[dist->slot[e]] = t[dist->slot_row[e]];
  PetscCall(VecRestoreArray(dist->coarse_in, &c));
  PetscCall(VecRestoreArrayRead(dist->residual, &t));
  PetscCall(KSPSolve(dist->amg, dist->coarse_in, dist->coarse_out));
  PetscCall(VecGetArrayRead(dist->coarse_out, &t));
  PetscCall(VecGetArray(z, &zv));
  for (PetscInt e = 0; e < dist->n_slots; ++e) zv[dist->slot_row[e]] += t[dist->slot[e]];
  PetscCall(VecRestoreArray(z, &zv));
  PetscCall(VecRestoreArrayRead(dist->coarse_out, &t));
  PetscCall(tc_dist_residual(dist, r, z));
  PetscCall(tc_dist_overlap_apply(pc, dist->residual, dist->sweep));
  PetscCall(VecAXPY(z, 1.0, dist->sweep));
  PetscFunctionReturn(0);
}

/* GAMG on the velocity block for preconditioner 4: this rank's n_owned rows of it (row_ptr,
 * global columns, values; block size bs, a node's bs slots consecutive), its n_modes
 * near-nullspace vectors (this rank's n_owned entries of each, one after the other), and the
 * slot of each of this rank's n_slots velocity rows of A (slot_row[e]: A's local row, slot[e]:
 * the block's local row). The finest level does no smoothing: the Schwarz sweeps are its
 * smoother (the serial path's rule; options under -tc_dist_amg_, -tc_dist_amg_fine_smooth_its).
 * Collective. */
static PetscErrorCode tc_dist_velocity_amg_setup(tc_dist *dist, int n_owned, int bs, const int *row_ptr,
                                                 const int *col, const double *val, int n_modes,
                                                 const double *modes, int n_slots, const int *slot_row,
                                                 const int *slot)
{
  PetscInt *i, *j;
  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(n_owned + 1, &i, row_ptr[n_owned], &j));
  for (int r = 0; r <= n_owned; ++r) i[r] = row_ptr[r];
  for (int e = 0; e < row_ptr[n_owned]; ++e) j[e] = col[e];
  PetscCall(MatCreate(PETSC_COMM_WORLD, &dist->velocity));
  PetscCall(MatSetSizes(dist->velocity, n_owned, n_owned, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatSetBlockSize(dist->velocity, bs));
  PetscCall(MatSetType(dist->velocity, MATMPIAIJ));
  PetscCall(MatMPIAIJSetPreallocationCSR(dist->velocity, i, j, val));
  PetscCall(PetscFree2(i, j));
  PetscCall(MatSetOption(dist->velocity, MAT_SPD, PETSC_TRUE));
  PetscCall(MatCreateVecs(dist->velocity, &dist->coarse_in, &dist->coarse_out));
  PetscCall(tc_gamg_on(dist->velocity, n_modes, modes, "tc_dist_amg_", "-tc_dist_amg_fine_smooth_its", 0, &dist->amg));
  PetscCall(VecDuplicate(dist->x, &dist->residual));
  PetscCall(VecDuplicate(dist->x, &dist->sweep));
  PetscCall(PetscMalloc2(n_slots, &dist->slot_row, n_slots, &dist->slot));
  for (int e = 0; e < n_slots; ++e) {
    dist->slot_row[e] = slot_row[e];
    dist->slot[e]     = slot[e];
  }
  dist->n_slots = n_slots;
  PetscFunctionReturn(0);
}

int tc_dist_set_velocity_amg(tc_dist *dist, int n_owned, int bs, const int *row_ptr, const int *col,
                             const double *val, int n_modes, const double *modes, int n_slots, const int *slot_row,
                             const int *slot)
{
  return (int)tc_dist_velocity_amg_setup(dist, n_owned, bs, row_ptr, col, val, n_modes, modes, n_slots, slot_row,
                                         slot);
}

/* An index set on this rank of n indices given as ints (PetscInt may be wider). */
static PetscErrorCode tc_is_of_ints(int n, const int *indices, IS *is)
{
  PetscInt *idx;
  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(n, &idx));
  for (int e = 0; e < n; ++e) idx[e] = indices[e];
  PetscCall(ISCreateGeneral(PETSC_COMM_SELF, n, idx, PETSC_OWN_POINTER, is));
  PetscFunctionReturn(0);
}

/* The overlap of this rank's block for restricted additive Schwarz: the global rows `overlap`
 * (n, ascending, none of this rank's) whose entries each application brings from their ranks;
 * made once, replaces an earlier one; collective (the scatter's set-up). */
static PetscErrorCode tc_dist_overlap_setup(tc_dist *dist, int n, const int *overlap)
{
  IS       is;
  PetscInt n_owned;
  PetscFunctionBeginUser;
  PetscCall(VecScatterDestroy(&dist->to_overlap));
  PetscCall(VecDestroy(&dist->overlap));
  free(dist->overlap_in);
  free(dist->overlap_out);
  dist->overlap_in = dist->overlap_out = NULL;
  PetscCall(VecGetLocalSize(dist->x, &n_owned));
  PetscCall(tc_is_of_ints(n, overlap, &is));
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, n, &dist->overlap));
  PetscCall(VecScatterCreate(dist->x, is, dist->overlap, NULL, &dist->to_overlap));
  PetscCall(ISDestroy(&is));
  dist->n_overlap   = n;
  dist->overlap_in  = malloc(((size_t)n_owned + (size_t)n + 1) * sizeof(PetscScalar));
  dist->overlap_out = malloc(((size_t)n_owned + (size_t)n + 1) * sizeof(PetscScalar));
  PetscCheck(dist->overlap_in && dist->overlap_out, PETSC_COMM_SELF, PETSC_ERR_MEM, "the overlapped block's vectors");
  PetscFunctionReturn(0);
}

int tc_dist_set_overlap(tc_dist *dist, int n, const int *overlap)
{
  return (int)tc_dist_overlap_setup(dist, n, overlap);
}

/* The rows `rows` (n_rows global indices, ascending) of A restricted to the columns `cols`
 * (n_cols global indices, ascending), any rank's, by MatCreateSubMatrices; collective. `*sub`
 * receives them as a sequential matrix (columns numbered by their position in `cols`) and
 * `*nnz` its entries, for tc_dist_take_rows. */
static PetscErrorCode tc_dist_fetch_setup(tc_dist *dist, int n_rows, const int *rows, int n_cols, const int *cols,
                                          Mat *sub, long long *nnz)
{
  IS              is[2];
  Mat            *subs;
  PetscInt        n;
  const PetscInt *ia, *ja;
  PetscBool       done;
  PetscFunctionBeginUser;
  PetscCall(tc_is_of_ints(n_rows, rows, &is[0]));
  PetscCall(tc_is_of_ints(n_cols, cols, &is[1]));
  PetscCall(MatCreateSubMatrices(dist->A, 1, &is[0], &is[1], MAT_INITIAL_MATRIX, &subs));
  PetscCall(ISDestroy(&is[0]));
  PetscCall(ISDestroy(&is[1]));
  *sub = subs[0];
  PetscCall(PetscFree(subs));
  PetscCall(MatGetRowIJ(*sub, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "the fetched rows' structure is not available");
  *nnz = (long long)ia[n];
  PetscCall(MatRestoreRowIJ(*sub, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

int tc_dist_fetch_rows(tc_dist *dist, int n_rows, const int *rows, int n_cols, const int *cols, void **sub,
                       long long *nnz)
{
  Mat m = NULL;
  int ierr = (int)tc_dist_fetch_setup(dist, n_rows, rows, n_cols, cols, &m, nnz);
  *sub = m;
  return ierr;
}

/* The rows of tc_dist_fetch_rows as CSR (ptr: n_rows + 1 offsets, cols and values: nnz each),
 * then the sequential matrix destroyed. */
static PetscErrorCode tc_dist_take_setup(Mat sub, long long *ptr, int *cols, double *values)
{
  PetscInt           n;
  const PetscInt    *ia, *ja;
  const PetscScalar *a;
  PetscBool          done;
  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(sub, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "the fetched rows' structure is not available");
  PetscCall(MatSeqAIJGetArrayRead(sub, &a));
  for (PetscInt i = 0; i <= n; ++i) ptr[i] = ia[i];
  for (PetscInt e = 0; e < ia[n]; ++e) {
    cols[e]   = (int)ja[e];
    values[e] = a[e];
  }
  PetscCall(MatSeqAIJRestoreArrayRead(sub, &a));
  PetscCall(MatRestoreRowIJ(sub, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

int tc_dist_take_rows(void *sub, long long *ptr, int *cols, double *values)
{
  Mat m    = sub;
  int ierr = (int)tc_dist_take_setup(m, ptr, cols, values);
  MatDestroy(&m);
  return ierr;
}

/* The values of n_rows of this rank's rows (global rows[r], its entries ptr[r]..ptr[r + 1] of
 * cols and values), every entry in the pattern, the other rows unchanged; collective (the
 * assembly). For the few rows a linearization changes: MatSetValuesCOO sets every value. */
int tc_dist_set_rows(tc_dist *dist, int n_rows, const int *rows, const long long *ptr, const int *cols,
                     const double *values)
{
  PetscFunctionBeginUser;
  for (int r = 0; r < n_rows; ++r) {
    PetscInt row = rows[r], n = (PetscInt)(ptr[r + 1] - ptr[r]);
    PetscCall(MatSetValues(dist->A, 1, &row, n, &cols[ptr[r]], &values[ptr[r]], INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(dist->A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(dist->A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* y = A x, or y = 0 without reading A where x is the solver's x still at the zero that
 * tc_dist_solve_from set it to (its object state unchanged since): the initial residual
 * b − A·0 of a correction solve, free. Every rank takes the same branch (the same calls change
 * x's state alike on every rank), so the product's scatter is entered by all or none. */
static PetscErrorCode tc_dist_product(Mat product, Vec x, Vec y)
{
  tc_dist         *dist;
  PetscObjectState state;
  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(product, &dist));
  if (dist->x_zero_known && x == dist->x) {
    PetscCall(PetscObjectStateGet((PetscObject)x, &state));
    if (state == dist->x_zero_state) {
      PetscCall(VecZeroEntries(y));
      PetscFunctionReturn(0);
    }
  }
  PetscCall(MatMult(dist->A, x, y));
  PetscFunctionReturn(0);
}

/* GCR's restart until a solve needs more (tc_dist_krylov_setup). PETSc's GCR allocates its
 * 2 restart directions when it is set up, where the solves of a run's Newton iterations mostly
 * take a few Krylov iterations each (2.4 on average at 972k unknowns, none more than 9): at
 * restart 30, 60 vectors of a rank's rows (220 MiB per rank at 972k on 2 ranks) of which a few
 * are ever written. Up to this many iterations GCR(10) and GCR(30) make the same iterates. */
#define TC_GCR_FIRST_RESTART 10

/* The Krylov solver of tc_dist_krylov_setup's settings, GCR with `restart`: made again, its
 * directions allocated. */
static PetscErrorCode tc_dist_krylov_make(tc_dist *dist, PetscInt restart)
{
  PC       pc;
  PetscInt m, n;
  int      preconditioner = dist->preconditioner;
  PetscFunctionBeginUser;
  dist->restart = restart;
  if (!dist->product) {
    PetscCall(MatGetLocalSize(dist->A, &m, &n));
    PetscCall(MatCreateShell(PETSC_COMM_WORLD, m, n, PETSC_DETERMINE, PETSC_DETERMINE, dist, &dist->product));
    PetscCall(MatShellSetOperation(dist->product, MATOP_MULT, (void (*)(void))tc_dist_product));
  }
  PetscCall(KSPDestroy(&dist->ksp));
  PetscCall(KSPCreate(PETSC_COMM_WORLD, &dist->ksp));
  PetscCall(KSPSetOptionsPrefix(dist->ksp, "tc_dist_"));
  PetscCall(KSPSetOperators(dist->ksp, dist->product, dist->A));
  PetscCall(KSPSetType(dist->ksp, KSPGCR));
  PetscCall(KSPGCRSetRestart(dist->ksp, dist->restart));
  PetscCall(KSPSetTolerances(dist->ksp, dist->rtol, 0.0, PETSC_DEFAULT, dist->max_its));
  PetscCall(KSPSetNormType(dist->ksp, KSP_NORM_UNPRECONDITIONED));
  PetscCall(KSPSetPCSide(dist->ksp, PC_RIGHT));
  PetscCall(KSPGetPC(dist->ksp, &pc));
  if (preconditioner == 1) {
    PetscCall(PCSetType(pc, PCGAMG));
  } else if (preconditioner == 2) {
    PetscCall(PCSetType(pc, PCSHELL));
    PetscCall(PCShellSetContext(pc, dist));
    PetscCall(PCShellSetApply(pc, tc_dist_block_apply));
    PetscCall(PCShellSetName(pc, "block Jacobi, each rank's block by thermocontact's ILU(0)"));
  } else if (preconditioner == 3) {
    PetscCall(PCSetType(pc, PCSHELL));
    PetscCall(PCShellSetContext(pc, dist));
    PetscCall(PCShellSetApply(pc, tc_dist_overlap_apply));
    PetscCall(PCShellSetName(pc, "restricted additive Schwarz, overlap 1, each rank's block by thermocontact's ILU(0)"));
  } else if (preconditioner == 4) {
    PetscCall(PCSetType(pc, PCSHELL));
    PetscCall(PCShellSetContext(pc, dist));
    PetscCall(PCShellSetApply(pc, tc_dist_two_level_apply));
    PetscCall(PCShellSetName(pc, "restricted additive Schwarz sweeps around GAMG on the velocity block"));
  } else {
    /* Block Jacobi, one block per rank, each ILU(0) (PETSc's default sub-solver). */
    PetscCall(PCSetType(pc, PCBJACOBI));
  }
  PetscCall(KSPSetFromOptions(dist->ksp));
  PetscCall(KSPSetUp(dist->ksp));
  PetscFunctionReturn(0);
}

/* The Krylov solver on the current values: GCR(restart) (PETSc's KSPGCR: GMRES's iterates in
 * exact arithmetic, with its residual and solution kept explicitly, so that a solve ends without
 * a last preconditioner application and hands its residual over, tc_dist_solve_from) on A
 * through tc_dist_product, with block Jacobi + ILU(0)
 * (preconditioner 0), GAMG (1), block Jacobi with the caller's block preconditioner (2, a
 * PCSHELL, given to each tc_dist_solve_from) or restricted additive Schwarz with the caller's
 * preconditioner of the overlapped block (3, a PCSHELL: tc_dist_set_overlap first), relative tolerance rtol, at most max_its
 * iterations; options under the prefix tc_dist_ (PETSC_OPTIONS="-tc_dist_ksp_monitor"). */
static PetscErrorCode tc_dist_krylov_setup(tc_dist *dist, int preconditioner, double rtol, int max_its, int restart)
{
  PetscFunctionBeginUser;
  dist->preconditioner = preconditioner;
  dist->rtol           = rtol;
  dist->max_its        = max_its;
  dist->restart_max    = restart;
  PetscCall(tc_dist_krylov_make(dist, PetscMin(restart, TC_GCR_FIRST_RESTART)));
  PetscFunctionReturn(0);
}

int tc_dist_krylov(tc_dist *dist, int preconditioner, double rtol, int max_its, int restart)
{
  return (int)tc_dist_krylov_setup(dist, preconditioner, rtol, max_its, restart);
}

/* b = 0, then b[index[e]] += value[e] for this rank's n entries (any rank may name any row),
 * assembled by PETSc. */
int tc_dist_set_rhs(tc_dist *dist, long long n, const int *index, const double *value)
{
  PetscFunctionBeginUser;
  PetscCall(VecZeroEntries(dist->b));
  for (long long e = 0; e < n; ++e) {
    PetscInt i = index[e];
    PetscCall(VecSetValues(dist->b, 1, &i, &value[e], ADD_VALUES));
  }
  PetscCall(VecAssemblyBegin(dist->b));
  PetscCall(VecAssemblyEnd(dist->b));
  PetscFunctionReturn(0);
}

/* This rank's entries of v from `from`, and into `to`. */
static PetscErrorCode tc_vec_set_owned(Vec v, const double *from)
{
  PetscScalar *a;
  PetscInt     n;
  PetscFunctionBeginUser;
  PetscCall(VecGetLocalSize(v, &n));
  PetscCall(VecGetArrayWrite(v, &a));
  memcpy(a, from, (size_t)n * sizeof(double));
  PetscCall(VecRestoreArrayWrite(v, &a));
  PetscFunctionReturn(0);
}

static PetscErrorCode tc_vec_get_owned(Vec v, double *to)
{
  const PetscScalar *a;
  PetscInt           n;
  PetscFunctionBeginUser;
  PetscCall(VecGetLocalSize(v, &n));
  PetscCall(VecGetArrayRead(v, &a));
  memcpy(to, a, (size_t)n * sizeof(double));
  PetscCall(VecRestoreArrayRead(v, &a));
  PetscFunctionReturn(0);
}

/* What the last solve did: its iterations, its final relative residual ||b − Ax|| / bnorm and
 * its converged reason (> 0: converged). PETSc's GCR ends at its iteration cap with the
 * positive KSP_CONVERGED_ITS: reported as KSP_DIVERGED_ITS, not converged. */
static PetscErrorCode tc_dist_outcome(tc_dist *dist, PetscReal bnorm, int *iterations, double *residual, int *reason)
{
  PetscInt           its;
  PetscReal          rnorm;
  KSPConvergedReason why;
  PetscFunctionBeginUser;
  PetscCall(KSPGetIterationNumber(dist->ksp, &its));
  PetscCall(KSPGetResidualNorm(dist->ksp, &rnorm));
  PetscCall(KSPGetConvergedReason(dist->ksp, &why));
  if (why == KSP_CONVERGED_ITS) why = KSP_DIVERGED_ITS;
  *iterations = (int)its;
  *residual   = bnorm > 0 ? rnorm / bnorm : rnorm;
  *reason     = (int)why;
  PetscFunctionReturn(0);
}

/* Solves A x = b from x = 0; the owned part of x into `owned` (n_owned values); iterations,
 * the final relative residual ‖b − Ax‖/‖b‖ and the converged reason (> 0: converged). */
int tc_dist_solve(tc_dist *dist, double *owned, int *iterations, double *residual, int *reason)
{
  PetscReal bnorm;
  PetscFunctionBeginUser;
  /* From zero: GCR with the asked restart from the start. */
  if (dist->restart < dist->restart_max) PetscCall(tc_dist_krylov_make(dist, dist->restart_max));
  PetscCall(VecZeroEntries(dist->x));
  PetscCall(KSPSetTolerances(dist->ksp, dist->rtol, 0.0, PETSC_DEFAULT, dist->max_its));
  PetscCall(KSPSolve(dist->ksp, dist->b, dist->x));
  PetscCall(VecNorm(dist->b, NORM_2, &bnorm));
  PetscCall(tc_dist_outcome(dist, bnorm, iterations, residual, reason));
  PetscCall(tc_vec_get_owned(dist->x, owned));
  PetscFunctionReturn(0);
}

/* The final residual's vector and the work vector, made at the first solve that needs them. */
static PetscErrorCode tc_dist_work_vectors(tc_dist *dist)
{
  PetscFunctionBeginUser;
  if (!dist->final_residual) {
    PetscCall(VecDuplicate(dist->b, &dist->final_residual));
    PetscCall(VecDuplicate(dist->b, &dist->work));
  }
  PetscFunctionReturn(0);
}

/* KSPSolve from the x and b set, with a nonzero guess (the caller's block preconditioner set
 * in dist for its length); x's known zero forgotten after. */
static PetscErrorCode tc_dist_ksp_solve(tc_dist *dist)
{
  PetscErrorCode solved;
  PetscFunctionBeginUser;
  PetscCall(KSPSetInitialGuessNonzero(dist->ksp, PETSC_TRUE));
  solved             = KSPSolve(dist->ksp, dist->b, dist->x);
  dist->x_zero_known = PETSC_FALSE;
  PetscCall(solved);
  PetscCall(KSPSetInitialGuessNonzero(dist->ksp, PETSC_FALSE));
  PetscFunctionReturn(0);
}

/* The correction d of A d = b from d = 0 into x (b the residual carried in), stopped at
 * ||b − A d|| <= target or after max_its iterations: the first product, with x still zero,
 * answered without A (tc_dist_product). */
static PetscErrorCode tc_dist_correction(tc_dist *dist, PetscReal target, PetscInt max_its)
{
  PetscFunctionBeginUser;
  PetscCall(VecZeroEntries(dist->x));
  PetscCall(PetscObjectStateGet((PetscObject)dist->x, &dist->x_zero_state));
  dist->x_zero_known = PETSC_TRUE;
  PetscCall(KSPSetTolerances(dist->ksp, 0.0, target, PETSC_DEFAULT, max_its));
  PetscCall(tc_dist_ksp_solve(dist));
  PetscFunctionReturn(0);
}

/* v += the n_owned values `from` at this rank's entries (x = guess + correction). */
static PetscErrorCode tc_dist_add_owned(Vec v, const double *from)
{
  PetscInt     n;
  PetscScalar *a;
  PetscFunctionBeginUser;
  PetscCall(VecGetLocalSize(v, &n));
  PetscCall(VecGetArray(v, &a));
  for (PetscInt i = 0; i < n; ++i) a[i] += from[i];
  PetscCall(VecRestoreArray(v, &a));
  PetscFunctionReturn(0);
}

static PetscErrorCode tc_dist_solve_from_set(tc_dist *dist, const double *rhs, const double *carried, double *owned,
                                             double *final_residual, double forcing, int *iterations, double *residual,
                                             int *reason);

/* Solves A x = b with this rank's owned entries of b (`rhs`) and of the initial guess (`owned`,
 * overwritten by the solution): no off-process entries, so no assembly. `carried`: NULL, or
 * this rank's entries of b − A x for that guess, which the solve then starts from instead of a
 * product with A (it solves A d = b − A x from d = 0, tc_dist_product, and adds d to x, to the
 * same tolerance on ||b||). `forcing` > 0: an inexact Newton method's forcing term, the solve
 * also stopping at ||b − Ax|| <= forcing ||b − A x0|| (the looser of that and rtol ||b||, as
 * the serial GMRES); 0: rtol alone, as before. `final_residual`: NULL, or where this rank's entries of the
 * solution's residual b − A x go (the solver's own, kept explicitly by GCR: no product; it may
 * be `carried`'s buffer, read before it is written). `block_apply` and
 * `block_ctx`: the block preconditioner of preconditioner 2 for this solve (NULL otherwise).
 * Iterations, the final relative residual ||b - Ax|| / ||b|| and the converged reason as
 * tc_dist_solve. While GCR runs below the asked restart (TC_GCR_FIRST_RESTART), a solve that
 * has not converged at the restart goes on from where it stopped with the asked restart, which
 * the later solves keep. */
int tc_dist_solve_from(tc_dist *dist, const double *rhs, const double *carried, double *owned, double *final_residual,
                       int (*block_apply)(void *, const double *, double *, int), void *block_ctx, double forcing,
                       int *iterations, double *residual, int *reason)
{
  PetscErrorCode solved;
  dist->block_apply = block_apply;
  dist->block_ctx   = block_ctx;
  solved = tc_dist_solve_from_set(dist, rhs, carried, owned, final_residual, forcing, iterations, residual, reason);
  dist->block_apply = NULL;
  dist->block_ctx   = NULL;
  return (int)solved;
}

/* tc_dist_solve_from with the block preconditioner set. */
static PetscErrorCode tc_dist_solve_from_set(tc_dist *dist, const double *rhs, const double *carried, double *owned,
                                             double *final_residual, double forcing, int *iterations, double *residual,
                                             int *reason)
{
  PetscReal bnorm, rnorm, target;
  PetscInt  cap, first;
  Vec       r;
  PetscBool capped;
  PetscFunctionBeginUser;
  PetscCall(tc_vec_set_owned(dist->b, rhs));
  PetscCall(VecNorm(dist->b, NORM_2, &bnorm));
  /* Below the asked restart a solve stops at the restart; one that has not converged by then
   * goes on from there with the asked restart (tc_dist_krylov_make), to the same tolerance. */
  capped = dist->restart < dist->restart_max && dist->restart < dist->max_its;
  cap    = capped ? dist->restart : dist->max_its;
  target = dist->rtol * bnorm;
  /* A zero b leaves the tolerance on ||b|| at zero: solved from the guess, as before. */
  if (carried && bnorm > 0) {
    PetscCall(tc_vec_set_owned(dist->b, carried));
    rnorm = 0;
    if (forcing > 0) PetscCall(VecNorm(dist->b, NORM_2, &rnorm));
    target = PetscMax(dist->rtol * bnorm, forcing * rnorm);
    PetscCall(tc_dist_correction(dist, target, cap));
  } else {
    carried = NULL;
    PetscCall(tc_vec_set_owned(dist->x, owned));
    if (forcing > 0) {
      /* PETSc's relative test from a nonzero guess is on ||b||, not on the guess's residual:
       * that residual computed here (one product), and the test made absolute. */
      PetscCall(tc_dist_work_vectors(dist));
      PetscCall(MatMult(dist->A, dist->x, dist->work));
      PetscCall(VecAYPX(dist->work, -1.0, dist->b));
      PetscCall(VecNorm(dist->work, NORM_2, &rnorm));
      target = PetscMax(dist->rtol * bnorm, forcing * rnorm);
      PetscCall(KSPSetTolerances(dist->ksp, 0.0, target, PETSC_DEFAULT, cap));
    } else PetscCall(KSPSetTolerances(dist->ksp, dist->rtol, 0.0, PETSC_DEFAULT, cap));
    PetscCall(tc_dist_ksp_solve(dist));
  }
  PetscCall(tc_dist_outcome(dist, bnorm, iterations, residual, reason));
  if (carried) PetscCall(tc_dist_add_owned(dist->x, owned));
  PetscCall(tc_vec_get_owned(dist->x, owned));
  if (capped && *reason == KSP_DIVERGED_ITS) {
    /* On from x with the asked restart: A d = b − A x from d = 0, b − A x GCR's own. */
    first = *iterations;
    PetscCall(tc_dist_work_vectors(dist));
    PetscCall(KSPBuildResidual(dist->ksp, dist->work, dist->final_residual, &r));
    PetscCall(VecCopy(r, dist->b));
    PetscCall(tc_dist_krylov_make(dist, dist->restart_max));
    PetscCall(tc_dist_correction(dist, target, dist->max_its - first));
    PetscCall(tc_dist_outcome(dist, bnorm, iterations, residual, reason));
    *iterations += (int)first;
    PetscCall(tc_dist_add_owned(dist->x, owned));
    PetscCall(tc_vec_get_owned(dist->x, owned));
  }
  if (final_residual) {
    PetscCall(tc_dist_work_vectors(dist));
    PetscCall(KSPBuildResidual(dist->ksp, dist->work, dist->final_residual, &r));
    PetscCall(tc_vec_get_owned(r, final_residual));
    /* An inexact solve's caller decides by the residual whether it reached rtol: the one
     * handed over, not the method's estimate. */
    if (forcing > 0) {
      PetscCall(VecNorm(r, NORM_2, &rnorm));
      *residual = bnorm > 0 ? rnorm / bnorm : rnorm;
    }
  }
  PetscFunctionReturn(0);
}

/* The solution through `scatter` into this rank's vector `to`, and its values into `out`;
 * collective. */
static PetscErrorCode tc_dist_scatter_copy(tc_dist *dist, VecScatter scatter, Vec to, double *out)
{
  PetscFunctionBeginUser;
  PetscCall(VecScatterBegin(scatter, dist->x, to, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(scatter, dist->x, to, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(tc_vec_get_owned(to, out));
  PetscFunctionReturn(0);
}

/* The whole solution on every rank (n_global values into `all`), by PETSc's scatter to all,
 * made once and kept; collective. */
int tc_dist_all_gather(tc_dist *dist, double *all)
{
  PetscFunctionBeginUser;
  if (!dist->to_all) PetscCall(VecScatterCreateToAll(dist->x, &dist->to_all, &dist->whole));
  PetscCall(tc_dist_scatter_copy(dist, dist->to_all, dist->whole, all));
  PetscFunctionReturn(0);
}

/* Selects the n entries of the solution at the global indices `indices` (each rank its own,
 * any rank's entries) for tc_dist_gather_selected: PETSc's scatter from x to a sequential vector
 * on this rank, made here once; collective. */
static PetscErrorCode tc_dist_select_setup(tc_dist *dist, int n, const int *indices)
{
  IS        from;
  PetscInt *idx;
  PetscFunctionBeginUser;
  PetscCall(VecScatterDestroy(&dist->to_selected));
  PetscCall(VecDestroy(&dist->selected));
  PetscCall(PetscMalloc1(n, &idx));
  for (int e = 0; e < n; ++e) idx[e] = indices[e];
  PetscCall(ISCreateGeneral(PETSC_COMM_SELF, n, idx, PETSC_OWN_POINTER, &from));
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, n, &dist->selected));
  PetscCall(VecScatterCreate(dist->x, from, dist->selected, NULL, &dist->to_selected));
  PetscCall(ISDestroy(&from));
  PetscFunctionReturn(0);
}

int tc_dist_select(tc_dist *dist, int n, const int *indices)
{
  return (int)tc_dist_select_setup(dist, n, indices);
}

/* The selected entries of the last solution (tc_dist_select) into `out`, in the order they were
 * selected; collective. */
int tc_dist_gather_selected(tc_dist *dist, double *out)
{
  PetscFunctionBeginUser;
  PetscCheck(dist->to_selected, PETSC_COMM_SELF, PETSC_ERR_ORDER, "no entries selected (tc_dist_select)");
  PetscCall(tc_dist_scatter_copy(dist, dist->to_selected, dist->selected, out));
  PetscFunctionReturn(0);
}

/* The whole solution on rank 0 (n_global values into `all` there; `all` unused elsewhere),
 * by PETSc's scatter to zero; collective. */
int tc_dist_gather(tc_dist *dist, double *all)
{
  VecScatter         scatter;
  Vec                whole;
  const PetscScalar *x;
  PetscInt           n;
  PetscFunctionBeginUser;
  PetscCall(VecScatterCreateToZero(dist->x, &scatter, &whole));
  PetscCall(VecScatterBegin(scatter, dist->x, whole, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(scatter, dist->x, whole, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetLocalSize(whole, &n));
  if (n > 0) {
    PetscCall(VecGetArrayRead(whole, &x));
    memcpy(all, x, (size_t)n * sizeof(double));
    PetscCall(VecRestoreArrayRead(whole, &x));
  }
  PetscCall(VecScatterDestroy(&scatter));
  PetscCall(VecDestroy(&whole));
  PetscFunctionReturn(0);
}

/* A vector with ghost entries (VecGhost): n_owned owned entries (PETSc's layout), then copies of
 * the n_ghost global entries `ghosts`, refreshed from their owners by tc_ghost_update. */
int tc_ghost_create(int n_owned, int n_ghost, const int *ghosts, Vec *out)
{
  PetscInt *g;
  PetscFunctionBeginUser;
  *out = NULL;
  PetscCall(PetscMalloc1(n_ghost, &g));
  for (int i = 0; i < n_ghost; ++i) g[i] = ghosts[i];
  PetscCall(VecCreateGhost(PETSC_COMM_WORLD, n_owned, PETSC_DECIDE, n_ghost, g, out));
  PetscCall(PetscFree(g));
  PetscFunctionReturn(0);
}

/* The owned entries from `owned`, then every ghost from its owner (VecGhostUpdate, forward). */
int tc_ghost_set_and_update(Vec v, const double *owned)
{
  PetscFunctionBeginUser;
  PetscCall(tc_vec_set_owned(v, owned));
  PetscCall(VecGhostUpdateBegin(v, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGhostUpdateEnd(v, INSERT_VALUES, SCATTER_FORWARD));
  PetscFunctionReturn(0);
}

/* The local form: owned entries then ghosts (n_local values into `local`). */
int tc_ghost_local(Vec v, double *local, int n_local)
{
  Vec                form;
  const PetscScalar *x;
  PetscInt           n;
  PetscFunctionBeginUser;
  PetscCall(VecGhostGetLocalForm(v, &form));
  PetscCall(VecGetLocalSize(form, &n));
  PetscCheck(n == n_local, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "local form of %d entries, %d expected", (int)n, n_local);
  PetscCall(VecGetArrayRead(form, &x));
  memcpy(local, x, (size_t)n * sizeof(double));
  PetscCall(VecRestoreArrayRead(form, &x));
  PetscCall(VecGhostRestoreLocalForm(v, &form));
  PetscFunctionReturn(0);
}

void tc_ghost_destroy(Vec v) { VecDestroy(&v); }
