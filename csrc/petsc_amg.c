/* The thin C layer between thermocontact and PETSc (cargo feature `petsc`): smoothed-aggregation
 * AMG (PCGAMG) on a sparse SPD matrix with a given near-nullspace, set up once, applied as one
 * V-cycle per call.
 *
 * Why C and not Rust declarations of PETSc's API: the ABI of PETSc's types depends on how the
 * library was configured (PetscInt may be 32 or 64 bits, MPI_Comm is a pointer in Open MPI and
 * an int in MPICH, PETSC_COMM_SELF is a macro). Compiled against the installed headers, this
 * file fixes them, and exports plain C types only: int (checked against PetscInt below),
 * double, and an opaque handle. */
#include <petscksp.h>
#include <stdio.h>
#include <string.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#if defined(PETSC_USE_COMPLEX) || !defined(PETSC_USE_REAL_DOUBLE)
#error "thermocontact needs PETSc with real double-precision scalars (Debian: libpetsc-real-dev)"
#endif
#if defined(PETSC_USE_64BIT_INDICES)
#define TC_PETSC_INT_BITS 64
#else
#define TC_PETSC_INT_BITS 32
#endif

/* The first error of the last failing call, for the Rust side's typed error. */
static char tc_message[512];

static PetscErrorCode tc_record_error(MPI_Comm comm, int line, const char *fun, const char *file,
                                      PetscErrorCode n, PetscErrorType p, const char *mess, void *ctx)
{
  (void)comm; (void)ctx;
  if (p == PETSC_ERROR_INITIAL)
    snprintf(tc_message, sizeof tc_message, "%s (%s:%d): %s (PETSc error %d)", fun, file, line,
             mess ? mess : "", (int)n);
  return n;
}

/* glibc's allocation policy back to its steady state, at load time. Debian's PETSc links
 * SuperLU_DIST, whose bundled CombBLAS sets M_MMAP_MAX = 0 and M_TRIM_THRESHOLD = -1 in its static
 * initializers: every allocation then comes from the heap and no freed memory ever returns to
 * the system, so a transient buffer (a rank's rows on their way to PETSc, a block's copy before
 * its factor) stays resident for the whole run. Measured at 972k unknowns on 2 ranks: a rank held
 * 3.2 GiB, 0.43 GiB of it freed buffers. This runs after the shared libraries' initializers (the
 * executable's, or the Python module's, come last) and sets what glibc's dynamic policy settles
 * on: blocks from 32 MiB up mapped on their own (and unmapped when freed), the heap's top
 * trimmed past 64 MiB. */
#if defined(__GLIBC__)
__attribute__((constructor)) static void tc_malloc_defaults(void)
{
  mallopt(M_MMAP_MAX, 65536);
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
}
#endif

const char *tc_petsc_last_error(void) { return tc_message; }

int tc_petsc_int_bits(void) { return TC_PETSC_INT_BITS; }

/* PetscInitialize once per process, without PETSc's signal handlers (thermocontact handles
 * SIGINT/SIGTERM itself: stop after the step, write a checkpoint). PETSC_OPTIONS in the
 * environment still reaches the options database (e.g. "-tc_pc_gamg_threshold 0.02"). */
int tc_petsc_initialize(void)
{
  PetscBool done;
  PetscErrorCode ierr = PetscInitialized(&done);
  if (ierr) return (int)ierr;
  if (done) return 0;
  static char  name[] = "thermocontact", nosig[] = "-no_signal_handler";
  static char *args[] = {name, nosig, NULL};
  int          argc = 2;
  char       **argv = args;
  ierr = PetscInitialize(&argc, &argv, NULL, NULL);
  if (ierr) {
    snprintf(tc_message, sizeof tc_message, "PetscInitialize failed (PETSc error %d)", (int)ierr);
    return (int)ierr;
  }
  ierr = PetscPushErrorHandler(tc_record_error, NULL);
  return (int)ierr;
}

struct tc_amg {
  Mat A;
  KSP ksp;
  Vec x, y;
  /* With 64-bit PetscInt: the row pointers and columns converted from the caller's int. */
  PetscInt *row_ptr, *col;
};
typedef struct tc_amg tc_amg;

void tc_amg_destroy(tc_amg *amg)
{
  if (!amg) return;
  KSPDestroy(&amg->ksp);
  MatDestroy(&amg->A);
  VecDestroy(&amg->x);
  VecDestroy(&amg->y);
  PetscFree(amg->row_ptr);
  PetscFree(amg->col);
  free(amg);
}

/* GAMG as one V-cycle (KSPPREONLY) on the SPD matrix A, sequential or distributed, with the
 * n_modes near-nullspace vectors `modes` (this process's entries of each, one after the other,
 * orthonormal), options under `prefix`. The finest level's smoothing: `fine_smooth_its` steps
 * (0: none, the caller smooths there; negative: PETSc's default), unless the option
 * `smooth_option` says otherwise. Also the distributed two-level method's (csrc/petsc_mpi.c). */
PetscErrorCode tc_gamg_on(Mat A, int n_modes, const double *modes, const char *prefix, const char *smooth_option,
                          int fine_smooth_its, KSP *ksp)
{
  MatNullSpace nsp;
  Vec          x, *vecs;
  PetscInt     n;
  PC           pc;
  PetscFunctionBeginUser;
  PetscCall(MatCreateVecs(A, &x, NULL));
  PetscCall(VecGetLocalSize(x, &n));
  PetscCall(VecDuplicateVecs(x, n_modes, &vecs));
  for (int m = 0; m < n_modes; ++m) {
    PetscScalar *v;
    PetscCall(VecGetArrayWrite(vecs[m], &v));
    memcpy(v, modes + (size_t)m * (size_t)n, (size_t)n * sizeof(double));
    PetscCall(VecRestoreArrayWrite(vecs[m], &v));
  }
  PetscCall(MatNullSpaceCreate(PetscObjectComm((PetscObject)A), PETSC_FALSE, n_modes, vecs, &nsp));
  PetscCall(MatSetNearNullSpace(A, nsp));
  PetscCall(MatNullSpaceDestroy(&nsp));
  PetscCall(VecDestroyVecs(n_modes, &vecs));
  PetscCall(VecDestroy(&x));

  PetscCall(KSPCreate(PetscObjectComm((PetscObject)A), ksp));
  PetscCall(KSPSetOptionsPrefix(*ksp, prefix));
  PetscCall(KSPSetOperators(*ksp, A, A));
  PetscCall(KSPSetType(*ksp, KSPPREONLY));
  PetscCall(KSPGetPC(*ksp, &pc));
  PetscCall(PCSetType(pc, PCGAMG));
  PetscCall(KSPSetFromOptions(*ksp));
  PetscCall(KSPSetUp(*ksp));
  {
    PetscInt  levels, its = fine_smooth_its;
    PetscBool set;
    KSP       finest;
    PetscCall(PetscOptionsGetInt(NULL, NULL, smooth_option, &its, &set));
    PetscCall(PCMGGetLevels(pc, &levels));
    if (levels > 1 && its >= 0) {
      PetscCall(PCMGGetSmoother(pc, levels - 1, &finest));
      if (its == 0) PetscCall(KSPSetType(finest, KSPRICHARDSON));
      PetscCall(KSPSetTolerances(finest, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, its));
    }
  }
  PetscFunctionReturn(0);
}

/* Sets up GAMG on the n × n CSR matrix (row_ptr, col, val; sorted columns; n a multiple of bs,
 * the unknowns of a node consecutive) with the n_modes near-nullspace vectors `modes` (n values
 * each, one after the other, orthonormal). The matrix uses the caller's arrays in place (no
 * copy: 0.7 GB at 10⁶ unknowns), which must outlive the handle. */
static PetscErrorCode tc_setup(tc_amg *amg, int n, int bs, PetscInt *row_ptr, PetscInt *col, double *val,
                               int n_modes, const double *modes, int fine_smooth_its)
{
  PetscFunctionBeginUser;
  PetscCall(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, n, n, row_ptr, col, val, &amg->A));
  PetscCall(MatSetBlockSize(amg->A, bs));
  PetscCall(MatSetOption(amg->A, MAT_SPD, PETSC_TRUE));
  PetscCall(MatSetOption(amg->A, MAT_SPD_ETERNAL, PETSC_TRUE));

  PetscCall(VecCreateSeq(PETSC_COMM_SELF, n, &amg->x));
  PetscCall(VecSetBlockSize(amg->x, bs));
  PetscCall(VecDuplicate(amg->x, &amg->y));
  PetscCall(tc_gamg_on(amg->A, n_modes, modes, "tc_", "-tc_amg_fine_smooth_its", fine_smooth_its, &amg->ksp));
  PetscFunctionReturn(0);
}

int tc_amg_create(int n, int bs, int *row_ptr, int *col, double *val, int n_modes, const double *modes,
                  int fine_smooth_its, tc_amg **out)
{
  PetscErrorCode ierr;
  tc_message[0] = '\0';
  *out = NULL;
  tc_amg *amg = calloc(1, sizeof *amg);
  if (!amg) {
    snprintf(tc_message, sizeof tc_message, "out of memory");
    return PETSC_ERR_MEM;
  }
#if TC_PETSC_INT_BITS == 64
  /* The index arrays are int; a 64-bit PetscInt needs them converted (and kept). */
  ierr = PetscMalloc1(n + 1, &amg->row_ptr);
  if (!ierr) ierr = PetscMalloc1(row_ptr[n], &amg->col);
  if (!ierr) {
    for (int i = 0; i <= n; ++i) amg->row_ptr[i] = row_ptr[i];
    for (int p = 0; p < row_ptr[n]; ++p) amg->col[p] = col[p];
    ierr = tc_setup(amg, n, bs, amg->row_ptr, amg->col, val, n_modes, modes, fine_smooth_its);
  }
#else
  ierr = tc_setup(amg, n, bs, row_ptr, col, val, n_modes, modes, fine_smooth_its);
#endif
  if (ierr) {
    tc_amg_destroy(amg);
    return (int)ierr;
  }
  *out = amg;
  return 0;
}

/* y = B⁻¹ x, B⁻¹ one V-cycle. */
int tc_amg_apply(tc_amg *amg, const double *x, double *y)
{
  PC pc;
  PetscErrorCode ierr;
  tc_message[0] = '\0';
  ierr = KSPGetPC(amg->ksp, &pc);
  if (!ierr) ierr = VecPlaceArray(amg->x, (PetscScalar *)x);
  if (!ierr) ierr = VecPlaceArray(amg->y, y);
  if (!ierr) ierr = PCApply(pc, amg->x, amg->y);
  VecResetArray(amg->x);
  VecResetArray(amg->y);
  return (int)ierr;
}

/* The operator complexity: stored entries of all levels' matrices over the finest's. */
double tc_amg_operator_complexity(tc_amg *amg)
{
  PC       pc;
  PetscInt levels = 0;
  double   total = 0, finest = 0;
  if (KSPGetPC(amg->ksp, &pc) || PCMGGetLevels(pc, &levels)) return -1;
  for (PetscInt l = 0; l < levels; ++l) {
    KSP     smoother;
    Mat     op;
    MatInfo info;
    if (PCMGGetSmoother(pc, l, &smoother) || KSPGetOperators(smoother, &op, NULL) ||
        MatGetInfo(op, MAT_LOCAL, &info))
      return -1;
    total += info.nz_used;
    if (l == levels - 1) finest = info.nz_used;
  }
  return finest > 0 ? total / finest : -1;
}

/* The number of levels of the hierarchy. */
int tc_amg_levels(tc_amg *amg)
{
  PC       pc;
  PetscInt levels = 0;
  if (KSPGetPC(amg->ksp, &pc) || PCMGGetLevels(pc, &levels)) return -1;
  return (int)levels;
}
