//! PETSc's smoothed-aggregation AMG (PCGAMG) through the thin C layer `csrc/petsc_amg.c`
//! (cargo feature `petsc`).
//!
//! **Why PETSc, and why a binding of our own.** docs/krylov-study.md measured the candidates on
//! the velocity block of the 3D step matrix: PETSc's GAMG with the rigid-body modes keeps CG at
//! 8–16 iterations from 98k to 972k unknowns and from k = 1/256 to 1/8; the pure-Rust `kryst`
//! 4.3's smoothed aggregation did not coarsen this matrix (one level, then out of memory at
//! 14k rows), and its classical AMG took 32 s to set up for 3 360 rows. No maintained pure-Rust
//! AMG worked, so the AMG is PETSc's, behind a feature so that the default build needs no
//! system library. The binding is the eight functions of the C layer, compiled against the
//! installed headers (`build.rs`): a
//! generated binding of all of PETSc (`bindgen`, the `petsc-rs` crate) would need libclang at
//! build time and fix PETSc's configuration-dependent types (PetscInt, MPI_Comm) in Rust.
//!
//! PETSc is initialized once per process, without its signal handlers (this crate's own catch
//! SIGINT and SIGTERM to stop after a step), and never finalized (PetscFinalize would end MPI,
//! which cannot be initialized again in the same process). `PETSC_OPTIONS` reaches the AMG
//! under the prefix `tc_`: `PETSC_OPTIONS="-tc_pc_gamg_threshold 0.02"`.

use std::ffi::{c_char, c_double, c_int, CStr};
use std::ptr::NonNull;
use std::sync::{Mutex, OnceLock};

use super::error::{FactorStage, LaError as Error};

#[repr(C)]
struct RawAmg {
    _private: [u8; 0],
}

extern "C" {
    /// PetscInitialize; with the `mpi` feature, MPI_Init_thread first and both finalized at
    /// exit (csrc/petsc_mpi.c).
    #[cfg(not(feature = "mpi"))]
    #[link_name = "tc_petsc_initialize"]
    fn tc_initialize() -> c_int;
    #[cfg(feature = "mpi")]
    #[link_name = "tc_mpi_initialize"]
    fn tc_initialize() -> c_int;
    fn tc_petsc_last_error() -> *const c_char;
    fn tc_petsc_int_bits() -> c_int;
    fn tc_amg_create(
        n: c_int,
        bs: c_int,
        row_ptr: *mut c_int,
        col: *mut c_int,
        val: *mut c_double,
        n_modes: c_int,
        modes: *const c_double,
        fine_smooth_its: c_int,
        out: *mut *mut RawAmg,
    ) -> c_int;
    fn tc_amg_apply(amg: *mut RawAmg, x: *const c_double, y: *mut c_double) -> c_int;
    fn tc_amg_levels(amg: *mut RawAmg) -> c_int;
    fn tc_amg_operator_complexity(amg: *mut RawAmg) -> c_double;
    fn tc_amg_destroy(amg: *mut RawAmg);
}

/// The C layer's record of the last failure.
pub(super) fn last_error(code: c_int) -> String {
    // SAFETY: the C layer returns a pointer to its static, NUL-terminated buffer.
    let text = unsafe { CStr::from_ptr(tc_petsc_last_error()) }.to_string_lossy();
    if text.is_empty() {
        format!("PETSc error {code}")
    } else {
        text.into_owned()
    }
}

fn amg_error(detail: String) -> Error {
    Error::Factorization {
        stage: FactorStage::Multigrid,
        detail,
    }
}

/// Held around every call into PETSc: PETSc is not thread-safe (its options database, logging
/// and memory bookkeeping are process-global), and two runs in one process (tests, Python
/// threads) may set up and apply their AMGs at once.
static PETSC: Mutex<()> = Mutex::new(());

pub(super) fn petsc_lock() -> std::sync::MutexGuard<'static, ()> {
    PETSC.lock().unwrap_or_else(|e| e.into_inner())
}

/// PETSc initialized for this process (once; the outcome is kept). Called under the lock.
/// With the `mpi` feature, MPI first (thread level SERIALIZED) and both finalized at exit
/// (`super::mpi`).
pub(super) fn initialized() -> Result<(), Error> {
    static OUTCOME: OnceLock<Result<(), String>> = OnceLock::new();
    OUTCOME
        .get_or_init(|| {
            // SAFETY: no arguments; the C layer checks PetscInitialized first.
            match unsafe { tc_initialize() } {
                0 => Ok(()),
                code => Err(last_error(code)),
            }
        })
        .clone()
        .map_err(amg_error)
}

/// The CSR arrays are a matrix PETSc can use in place: row pointers from 0, non-decreasing, to
/// the entry count; columns in range and increasing within each row; n a multiple of the block
/// size; each mode n values. PETSc checks none of this on arrays it is handed.
fn check_csr(row_ptr: &[i32], col: &[i32], val: &[f64], block_size: usize, modes: &[Vec<f64>]) -> Result<(), Error> {
    let n = row_ptr.len().saturating_sub(1);
    let refuse = |what: String| Err(amg_error(format!("the matrix given to GAMG: {what}")));
    if row_ptr.first() != Some(&0) || row_ptr.windows(2).any(|w| w[0] > w[1]) {
        return refuse("row pointers do not rise from 0".into());
    }
    let nnz = row_ptr[n] as usize;
    if col.len() != nnz || val.len() != nnz {
        return refuse(format!(
            "{nnz} entries by the row pointers, {} columns, {} values",
            col.len(),
            val.len()
        ));
    }
    if i32::try_from(n).is_err() {
        return refuse(format!("{n} rows exceed 32-bit indices"));
    }
    for i in 0..n {
        let row = &col[row_ptr[i] as usize..row_ptr[i + 1] as usize];
        if row.iter().any(|&c| c < 0 || c as usize >= n) || row.windows(2).any(|w| w[0] >= w[1]) {
            return refuse(format!("row {i} has columns {row:?} (expected increasing, below {n})"));
        }
    }
    if block_size == 0 || !n.is_multiple_of(block_size) {
        return refuse(format!("{n} rows are not blocks of {block_size}"));
    }
    if let Some(m) = modes.iter().position(|m| m.len() != n) {
        return refuse(format!(
            "near-nullspace vector {m} has {} values for {n} rows",
            modes[m].len()
        ));
    }
    Ok(())
}

/// The handle, used under [`PETSC`] only (a V-cycle also writes into the handle's work
/// vectors).
struct Handle(NonNull<RawAmg>);

// SAFETY: the handle is only used under the process-wide lock, one call at a time; PETSc's
// sequential objects have no thread affinity.
unsafe impl Send for Handle {}
unsafe impl Sync for Handle {}

/// The finest level's smoothing in the V-cycle (`-tc_amg_fine_smooth_its N` overrides it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FineSmoothing {
    /// PETSc's default smoother (Chebyshev with Jacobi).
    Petsc,
    /// None: the caller smooths on the finest level (restriction, coarse levels, prolongation).
    None,
}

/// A GAMG hierarchy of one SPD matrix, applied as one V-cycle.
pub struct Gamg {
    handle: Handle,
    /// The matrix's CSR arrays, which PETSc's matrix uses in place (dropped after the handle).
    _csr: (Vec<i32>, Vec<i32>, Vec<f64>),
    n: usize,
    levels: usize,
    operator_complexity: f64,
}

impl Gamg {
    /// Sets up GAMG on the n × n CSR matrix (`row_ptr`, `col`, `val`; each row's columns
    /// increasing) whose unknowns come in blocks of `block_size` per node, with the
    /// near-nullspace `modes` (orthonormal, n values each) and `fine_smoothing` on the finest
    /// level (PETSc's own, or none where the caller smooths there). PETSc works on the arrays in
    /// place.
    pub fn new(
        row_ptr: Vec<i32>,
        mut col: Vec<i32>,
        mut val: Vec<f64>,
        block_size: usize,
        modes: &[Vec<f64>],
        fine_smoothing: FineSmoothing,
    ) -> Result<Self, Error> {
        let mut row_ptr = row_ptr;
        check_csr(&row_ptr, &col, &val, block_size, modes)?;
        let _petsc = petsc_lock();
        initialized()?;
        let n = row_ptr.len() - 1;
        // SAFETY: no arguments.
        let int_bits = unsafe { tc_petsc_int_bits() };
        let flat: Vec<f64> = modes.iter().flatten().copied().collect();
        let mut raw = std::ptr::null_mut();
        // SAFETY: `check_csr` checked the arrays (lengths, ranges, order); the matrix keeps
        // pointers into them, and they live in the returned value until after the handle is
        // destroyed (Drop). `raw` is written on success.
        let code = unsafe {
            tc_amg_create(
                n as c_int,
                block_size as c_int,
                row_ptr.as_mut_ptr(),
                col.as_mut_ptr(),
                val.as_mut_ptr(),
                modes.len() as c_int,
                flat.as_ptr(),
                match fine_smoothing {
                    FineSmoothing::Petsc => -1,
                    FineSmoothing::None => 0,
                },
                &mut raw,
            )
        };
        let Some(handle) = NonNull::new(raw).filter(|_| code == 0) else {
            return Err(amg_error(format!(
                "{} (PETSc with {int_bits}-bit indices)",
                last_error(code)
            )));
        };
        // SAFETY: a live handle.
        let (levels, complexity) = unsafe {
            (
                tc_amg_levels(handle.as_ptr()),
                tc_amg_operator_complexity(handle.as_ptr()),
            )
        };
        Ok(Gamg {
            handle: Handle(handle),
            _csr: (row_ptr, col, val),
            n,
            levels: usize::try_from(levels).unwrap_or(0),
            operator_complexity: complexity,
        })
    }

    /// y = B⁻¹ x by one V-cycle.
    pub fn apply(&self, x: &[f64], y: &mut [f64]) -> Result<(), Error> {
        assert!(x.len() == self.n && y.len() == self.n, "vectors of the AMG's size");
        let _petsc = petsc_lock();
        // SAFETY: a live handle used by this thread alone (the lock); x and y have n entries.
        match unsafe { tc_amg_apply(self.handle.0.as_ptr(), x.as_ptr(), y.as_mut_ptr()) } {
            0 => Ok(()),
            code => Err(amg_error(last_error(code))),
        }
    }

    /// Levels of the hierarchy.
    pub fn levels(&self) -> usize {
        self.levels
    }

    /// Stored entries of all levels' matrices over the finest level's.
    pub fn operator_complexity(&self) -> f64 {
        self.operator_complexity
    }
}

impl Drop for Gamg {
    fn drop(&mut self) {
        let _petsc = petsc_lock();
        // SAFETY: the handle is live and dropped once.
        unsafe { tc_amg_destroy(self.handle.0.as_ptr()) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// GAMG on the 1D Laplacian (plus a small shift) with the constant as near-nullspace: a
    /// multilevel hierarchy, and stationary iteration with its V-cycle (PETSc's smoothing on
    /// every level) converges fast.
    #[test]
    fn gamg_solves_a_laplacian() {
        let n = 2000;
        let (mut row_ptr, mut col, mut val) = (vec![0], Vec::new(), Vec::new());
        for i in 0..n {
            if i > 0 {
                col.push(i as i32 - 1);
                val.push(-1.0);
            }
            col.push(i as i32);
            val.push(2.0 + 1e-6);
            if i + 1 < n {
                col.push(i as i32 + 1);
                val.push(-1.0);
            }
            row_ptr.push(col.len() as i32);
        }
        let mode = vec![1.0 / (n as f64).sqrt(); n];
        let amg = Gamg::new(
            row_ptr.clone(),
            col.clone(),
            val.clone(),
            1,
            &[mode],
            FineSmoothing::Petsc,
        )
        .unwrap();
        assert!(amg.levels() >= 3, "{} levels", amg.levels());
        assert!(amg.operator_complexity() > 1.0 && amg.operator_complexity() < 2.0);
        let a_mul = |x: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    (row_ptr[i]..row_ptr[i + 1])
                        .map(|p| val[p as usize] * x[col[p as usize] as usize])
                        .sum()
                })
                .collect()
        };
        let b: Vec<f64> = (0..n).map(|i| ((i * 7) % 13) as f64 - 6.0).collect();
        let (mut x, mut e) = (vec![0.0; n], vec![0.0; n]);
        let norm = |v: &[f64]| v.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut r = b.clone();
        for _ in 0..30 {
            amg.apply(&r, &mut e).unwrap();
            x.iter_mut().zip(&e).for_each(|(x, e)| *x += e);
            r = b.iter().zip(a_mul(&x)).map(|(b, ax)| b - ax).collect();
        }
        assert!(norm(&r) < 1e-6 * norm(&b), "relative residual {}", norm(&r) / norm(&b));
    }

    /// A malformed matrix (a column beyond its size, PETSc would read past the vector) is a
    /// typed error naming the row, not a crash.
    #[test]
    fn a_malformed_matrix_is_a_typed_error() {
        let error = Gamg::new(vec![0, 1], vec![5], vec![1.0], 1, &[vec![1.0]], FineSmoothing::None)
            .err()
            .expect("refused");
        match error {
            Error::Factorization {
                stage: FactorStage::Multigrid,
                detail,
            } => assert!(detail.contains("row 0 has columns [5]"), "{detail}"),
            other => panic!("{other}"),
        }
        let unsorted = Gamg::new(
            vec![0, 2, 3],
            vec![1, 0, 1],
            vec![1.0; 3],
            1,
            &[vec![1.0; 2]],
            FineSmoothing::None,
        );
        assert!(unsorted.is_err());
        let ragged = Gamg::new(
            vec![0, 1, 2],
            vec![0, 1],
            vec![1.0; 2],
            3,
            &[vec![1.0; 2]],
            FineSmoothing::None,
        );
        assert!(ragged.is_err());
    }
}
