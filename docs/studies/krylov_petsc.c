/* PETSc KSP on the step matrices exported by krylov_study.rs (`--export DIR`); the anchor of
 * docs/krylov-study.md.
 *
 *   apt-get install -y libpetsc-real-dev pkg-config
 *   mpicc -O2 -o /tmp/krylov_petsc docs/studies/krylov_petsc.c $(pkg-config --cflags --libs PETSc)
 *   /tmp/krylov_petsc -mat DIR/A.bin -rhs DIR/rhs.bin -nrhs 3 -label "GMRES+ILU0" \
 *       -ksp_type gmres -ksp_pc_side right -pc_type ilu
 *   /tmp/krylov_petsc -mat DIR/Kw_padded.bin -bs 3 -rhs DIR/rhs_w_padded.bin -nrhs 2 \
 *       -modes DIR/modes.bin -label "CG+GAMG" -ksp_type cg -pc_type gamg
 *
 * Every run: x0 = 0, ||b - A x|| <= rtol ||b|| (unpreconditioned norm), rtol 1e-8 timed over
 * -reps solves (min / median printed), then one solve at 1e-10 for its iteration count. Setup is
 * KSPSetUp (the preconditioner's factorization or hierarchy); its memory is the growth of the
 * peak resident set (getrusage). Serial. */
#include <petscksp.h>
#include <sys/resource.h>

static double maxrss_mib(void)
{
  struct rusage u;
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

static int cmp(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
  char        matf[PETSC_MAX_PATH_LEN], rhsf[PETSC_MAX_PATH_LEN], modesf[PETSC_MAX_PATH_LEN], label[256] = "petsc";
  PetscBool   has_modes = PETSC_FALSE;
  PetscInt    nrhs = 1, reps = 5, bs = 1;
  PetscViewer viewer;
  Mat         A;
  KSP         ksp;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-mat", matf, sizeof matf, NULL));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-rhs", rhsf, sizeof rhsf, NULL));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-modes", modesf, sizeof modesf, &has_modes));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-label", label, sizeof label, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-nrhs", &nrhs, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-reps", &reps, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-bs", &bs, NULL));

  PetscCall(PetscViewerBinaryOpen(PETSC_COMM_WORLD, matf, FILE_MODE_READ, &viewer));
  PetscCall(MatCreate(PETSC_COMM_WORLD, &A));
  PetscCall(MatSetType(A, MATSEQAIJ));
  if (bs > 1) PetscCall(MatSetBlockSize(A, bs));
  PetscCall(MatLoad(A, viewer));
  PetscCall(PetscViewerDestroy(&viewer));
  {
    PetscInt n;
    MatInfo  info;
    PetscCall(MatGetSize(A, &n, NULL));
    PetscCall(MatGetInfo(A, MAT_LOCAL, &info));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s: n %" PetscInt_FMT ", nnz %.0f\n", matf, n, info.nz_used));
  }
  if (has_modes) {
    Vec          modes[6];
    MatNullSpace nsp;
    PetscCall(PetscViewerBinaryOpen(PETSC_COMM_WORLD, modesf, FILE_MODE_READ, &viewer));
    for (int i = 0; i < 6; i++) {
      PetscCall(MatCreateVecs(A, &modes[i], NULL));
      PetscCall(VecLoad(modes[i], viewer));
    }
    PetscCall(PetscViewerDestroy(&viewer));
    PetscCall(MatNullSpaceCreate(PETSC_COMM_WORLD, PETSC_FALSE, 6, modes, &nsp));
    PetscCall(MatSetNearNullSpace(A, nsp));
    PetscCall(MatNullSpaceDestroy(&nsp));
    for (int i = 0; i < 6; i++) PetscCall(VecDestroy(&modes[i]));
  }

  PetscCall(KSPCreate(PETSC_COMM_WORLD, &ksp));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPSetTolerances(ksp, 1e-8, 0.0, 1e30, 5000));
  PetscCall(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  PetscCall(KSPSetFromOptions(ksp));
  double rss0 = maxrss_mib();
  double t0   = MPI_Wtime();
  PetscCall(KSPSetUp(ksp));
  {
    PC pc;
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetUp(pc));
  }
  double setup = MPI_Wtime() - t0;
  double setup_mb = maxrss_mib() - rss0;

  PetscCall(PetscViewerBinaryOpen(PETSC_COMM_WORLD, rhsf, FILE_MODE_READ, &viewer));
  for (PetscInt r = 0; r < nrhs; r++) {
    Vec       b, x, res;
    PetscInt  its = 0, its_tight = 0;
    PetscReal bn, rn, rn_tight;
    double   *times;
    PetscCall(MatCreateVecs(A, &x, &b));
    PetscCall(VecDuplicate(b, &res));
    PetscCall(VecLoad(b, viewer));
    PetscCall(PetscMalloc1(reps, &times));
    PetscCall(KSPSetTolerances(ksp, 1e-8, 0.0, 1e30, 5000));
    for (PetscInt k = 0; k < reps; k++) {
      PetscCall(VecSet(x, 0.0));
      double t = MPI_Wtime();
      PetscCall(KSPSolve(ksp, b, x));
      times[k] = MPI_Wtime() - t;
      PetscCall(KSPGetIterationNumber(ksp, &its));
    }
    PetscCall(MatMult(A, x, res));
    PetscCall(VecAYPX(res, -1.0, b));
    PetscCall(VecNorm(res, NORM_2, &rn));
    PetscCall(VecNorm(b, NORM_2, &bn));
    PetscCall(KSPSetTolerances(ksp, 1e-10, 0.0, 1e30, 5000));
    PetscCall(VecSet(x, 0.0));
    PetscCall(KSPSolve(ksp, b, x));
    PetscCall(KSPGetIterationNumber(ksp, &its_tight));
    PetscCall(MatMult(A, x, res));
    PetscCall(VecAYPX(res, -1.0, b));
    PetscCall(VecNorm(res, NORM_2, &rn_tight));
    qsort(times, reps, sizeof(double), cmp);
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "ROW | %-28s | rhs %" PetscInt_FMT " | setup %7.3f s %7.0f MiB | it(1e-8) %4" PetscInt_FMT " | it(1e-10) %4" PetscInt_FMT
                          " | solve min %7.3f med %7.3f s | res %.1e / %.1e\n",
                          label, r, setup, setup_mb, its, its_tight, times[0], times[reps / 2], (double)(rn / bn), (double)(rn_tight / bn)));
    PetscCall(PetscFree(times));
    PetscCall(VecDestroy(&b));
    PetscCall(VecDestroy(&x));
    PetscCall(VecDestroy(&res));
  }
  PetscCall(PetscViewerDestroy(&viewer));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "peak RSS %.0f MiB\n", maxrss_mib()));
  PetscCall(KSPDestroy(&ksp));
  PetscCall(MatDestroy(&A));
  PetscCall(PetscFinalize());
  return 0;
}
