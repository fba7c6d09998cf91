//! A process that links PETSc returns the memory it frees to the system (cargo feature
//! `petsc`). Debian's PETSc links SuperLU_DIST, whose bundled CombBLAS turns glibc's mapped
//! allocations off when it is loaded (`mallopt(M_MMAP_MAX, 0)`, `mallopt(M_TRIM_THRESHOLD, -1)`):
//! every buffer freed stays resident for the rest of the run. `csrc/petsc_amg.c` sets glibc's
//! policy back at load time.
//!
//! Run without the test harness (Cargo.toml): the allocation is the main thread's, from the heap
//! that policy governs (a harness thread's arena maps large blocks whatever the policy), and no
//! other test allocates while it reads its own resident memory.

use thermocontact::model::samples;
use thermocontact::step::{KrylovParams, KrylovSystem, PreconditionerKind};

/// VmRSS of this process, in MiB.
fn resident_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmRSS:")).unwrap();
    line.split_whitespace().nth(1).unwrap().parse::<f64>().unwrap() / 1024.0
}

fn main() {
    a_freed_buffer_leaves_the_process_with_petsc_in_use();
    println!("test a_freed_buffer_leaves_the_process_with_petsc_in_use ... ok");
}

fn a_freed_buffer_leaves_the_process_with_petsc_in_use() {
    // PETSc in use: the AMG of a small step matrix.
    let problem = samples::paper_3d([8, 2, 2], 64).unwrap();
    let params = KrylovParams {
        preconditioner: PreconditionerKind::Amg,
        ..KrylovParams::default()
    };
    let system = KrylovSystem::new(&problem, problem.time_step(), params).unwrap();
    assert_eq!(system.preconditioner(), PreconditionerKind::Amg);
    let before = resident_mib();
    let buffer = vec![1u8; 256 << 20];
    let held = resident_mib();
    assert_eq!(std::hint::black_box(&buffer)[(128 << 20) + 7], 1);
    drop(buffer);
    let after = resident_mib();
    assert!(
        held - before >= 250.0,
        "the buffer was not resident: {before:.0} → {held:.0} MiB"
    );
    assert!(
        held - after >= 250.0,
        "256 MiB freed, but the process still holds {:.0} MiB of it ({before:.0} → {held:.0} → {after:.0} MiB)",
        after - before
    );
}
