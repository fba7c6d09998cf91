//! What a run will need, estimated before anything is allocated, and what the machine has.
//!
//! The memory of a run is that of the direct LDLᵀ factor of the step matrix (the rest is a
//! small multiple of the mesh). Its entries per unknown were measured on the structured meshes
//! of the examples (`summary.json`'s `factor_nnz`, docs/performance.md): in 2D about 126 at 49k
//! unknowns, growing like N^0.1 (nested-dissection-like fill, N log N); in 3D 757 at 17.6k,
//! 1 300 at 47k and 2 416 at 291k, i.e. about 1 300 (N / 47 000)^{1/3}. A run's peak is about
//! 18–28 bytes per factor entry (values, indices, the matrices, the cutback levels' factors).
//! The estimate is for refusing runs that cannot fit, not a promise: within 1.5× of the
//! measured peaks. The iterative path (`crate::step::iterative`) has no fill: its memory is
//! linear in the unknowns.
//!
//! Depends on: nothing of this crate (the bottom layer, beside `mesh`).

/// Bytes of peak memory per factor entry (measured: 164 MiB for 6.2 M entries in 2D, 28 bytes;
/// 1.05 GB for 61 M in 3D with cutback levels, 18 bytes).
const BYTES_PER_ENTRY: f64 = 24.0;

/// Peak bytes per unknown of the iterative path in 3D (`solver.linear = "iterative"`): the
/// mesh, the problem's matrices, A in CSR and its ILU(0) factor, the assembly's triplets, a
/// few vectors; linear in N. Measured (`/usr/bin/time -v`, VmHWM): 496 MiB at 98 334
/// unknowns, 5.3 kB per unknown.
const ITERATIVE_BYTES_PER_UNKNOWN: f64 = 5_300.0;

/// Estimated peak memory of a run with `unknowns` unknowns on the iterative path, bytes.
pub fn estimated_memory_iterative(unknowns: f64) -> f64 {
    32.0 * (1u64 << 20) as f64 + ITERATIVE_BYTES_PER_UNKNOWN * unknowns
}

/// Estimated entries of the direct LDLᵀ factor of a step matrix with `unknowns` unknowns in
/// `dim` dimensions, on a compact body (the fill of the sparse part; the dense block of the
/// contact unknowns that the direct path orders last comes on top: `crate::step::LinearKind`).
pub fn estimated_factor_entries(dim: usize, unknowns: f64) -> f64 {
    let per_unknown = if dim == 3 {
        1300.0 * (unknowns / 47_000.0).cbrt()
    } else {
        126.0 * (unknowns / 49_000.0).max(1e-6).powf(0.1)
    };
    per_unknown * unknowns
}

/// Estimated peak memory of a run on the direct path with `unknowns` unknowns in `dim`
/// dimensions, bytes.
pub fn estimated_memory(dim: usize, unknowns: f64) -> f64 {
    // Small problems: the process itself and the mesh.
    32.0 * (1u64 << 20) as f64 + BYTES_PER_ENTRY * estimated_factor_entries(dim, unknowns)
}

/// Checks that this CPU has the instructions this build was compiled for, so that a binary
/// built for x86-64-v3 (the repository's `.cargo/config.toml`: AVX2 and FMA) says what is
/// missing on an older CPU instead of stopping with SIGILL at its first AVX2 instruction. The
/// command line and the Python module call it first thing. Without AVX2 in the build there is
/// nothing to check.
pub fn check_instruction_set() -> Result<(), String> {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "xsave"))]
    {
        use std::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
        let leaf1 = __cpuid(1);
        let has = |reg: u32, bit: u32| reg & (1 << bit) != 0;
        let avx2 = __cpuid(0).eax >= 7 && has(__cpuid_count(7, 0).ebx, 5);
        let (fma, osxsave, avx) = (has(leaf1.ecx, 12), has(leaf1.ecx, 27), has(leaf1.ecx, 28));
        // SAFETY: XGETBV exists where CPUID reports OSXSAVE (checked first).
        let ymm_saved = osxsave && unsafe { _xgetbv(0) } & 0b110 == 0b110;
        if !(avx && avx2 && fma && ymm_saved) {
            return Err(
                "this build of thermocontact targets x86-64-v3 (AVX2 and FMA: the repository's \
                        .cargo/config.toml), which this CPU or its operating system does not offer; \
                        rebuild with RUSTFLAGS=\"-C target-cpu=native\" cargo build --release"
                    .into(),
            );
        }
    }
    Ok(())
}

/// The machine's memory (Linux: `MemTotal` of /proc/meminfo), bytes.
pub fn machine_memory() -> Option<f64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// `bytes` for a person: "3.2 GiB".
pub fn human(bytes: f64) -> String {
    const GIB: f64 = (1u64 << 30) as f64;
    const MIB: f64 = (1u64 << 20) as f64;
    if bytes >= 1024.0 * GIB {
        format!("{:.1e} GiB", bytes / GIB)
    } else if bytes >= GIB {
        format!("{:.1} GiB", bytes / GIB)
    } else {
        format!("{:.0} MiB", bytes / MIB)
    }
}

/// Peak resident memory of this process so far (Linux: VmHWM), in MiB.
pub fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// Reads an input file (a scenario, a mesh, a table, a checkpoint) of at most `max_bytes`:
/// regular files only (a FIFO would block forever, a device such as /dev/zero never end), and
/// never more than `max_bytes`, even when the file grows while it is read. The errors are
/// [`std::io::Error`]s that say which limit: callers name the file (or key).
pub fn read_input(path: &std::path::Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "not a regular file (a folder, a FIFO or a device)",
        ));
    }
    let too_large = |bytes: u64| {
        Error::new(
            ErrorKind::InvalidInput,
            format!("{bytes} bytes, more than the {max_bytes} read from a file of this kind"),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)?.take(max_bytes + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// The largest mesh or checkpoint file read: an eighth of the machine's memory (4 GiB where it
/// is unknown), since reading holds the file and a few times its size while the mesh is built.
pub fn max_data_file_bytes() -> u64 {
    machine_memory().map_or(4 << 30, |m| (m / 8.0) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimate is within 1.5× of the peaks measured on this machine.
    #[test]
    fn the_estimate_matches_the_measured_peaks() {
        const MIB: f64 = (1u64 << 20) as f64;
        for (dim, unknowns, measured_mib) in [(2, 49_344.0, 164.0), (3, 46_970.0, 1_050.0)] {
            let ratio = estimated_memory(dim, unknowns) / (measured_mib * MIB);
            assert!((1.0 / 1.5..=1.5).contains(&ratio), "{dim}D, {unknowns}: ratio {ratio}");
        }
        assert!(estimated_memory(3, 1e6) > estimated_memory(3, 5e5) * 2.0);
        assert_eq!(human(3.0 * (1u64 << 30) as f64), "3.0 GiB");
    }
}
