//! Helpers shared by the integration tests (each test binary uses some of them).
#![allow(dead_code)]

use faer::linalg::solvers::Solve;
use thermocontact::la::CscMatrix;
use thermocontact::material::Material;
use thermocontact::Scenario;

/// The paper's example on a coarse grid (16 × 4 cells, 16 steps) with `key=value` overrides.
pub fn coarse(overrides: &[&str]) -> Scenario {
    let mut all: Vec<String> = ["mesh.nx=16", "mesh.ny=4", "time.steps=16"].map(String::from).to_vec();
    all.extend(overrides.iter().map(|s| s.to_string()));
    Scenario::load(None, &all).unwrap()
}

/// The material of the paper's Section 6 example.
pub fn paper_material() -> Material {
    thermocontact::model::samples::paper_material()
}

/// Solves K_ii x_i = −K_ib x_b (dense) for the nodes not marked fixed; `dofs` per node.
pub fn solve_interior(k: &CscMatrix, fixed: &[bool], dofs: usize, values: &[f64]) -> Vec<f64> {
    let free: Vec<usize> = (0..k.n_rows).filter(|&i| !fixed[i / dofs]).collect();
    let n = free.len();
    let mut a = faer::Mat::<f64>::zeros(n, n);
    let mut b = faer::Mat::<f64>::zeros(n, 1);
    for (r, &i) in free.iter().enumerate() {
        for (j, v) in values.iter().enumerate() {
            if fixed[j / dofs] {
                b[(r, 0)] -= k.get(i, j) * v;
            }
        }
        for (c, &j) in free.iter().enumerate() {
            a[(r, c)] = k.get(i, j);
        }
    }
    let x = a.partial_piv_lu().solve(&b);
    let mut out = values.to_vec();
    for (r, &i) in free.iter().enumerate() {
        out[i] = x[(r, 0)];
    }
    out
}

/// The command-line binary of this build.
pub fn bin() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_thermocontact"))
}

/// A run folder's `summary.json`.
pub fn summary(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

/// The lines of `steps.csv` without the `seconds` column (the one that depends on the machine).
pub fn steps_without_seconds(dir: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("steps.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let seconds = header.iter().position(|c| *c == "seconds").unwrap();
    text.lines()
        .map(|line| {
            let mut cells: Vec<&str> = line.split(',').collect();
            cells.remove(seconds);
            cells.join(",")
        })
        .collect()
}

/// The files `names` are the same bytes in the folders `a` and `b`.
pub fn same_bytes(a: &std::path::Path, b: &std::path::Path, names: &[String]) {
    for name in names {
        let (x, y) = (
            std::fs::read(a.join(name)).unwrap(),
            std::fs::read(b.join(name)).unwrap(),
        );
        assert!(x == y, "{name} differs between {} and {}", a.display(), b.display());
    }
}

/// No half-written file (`*.tmp-*`, `output::write_atomic`'s) is left in `dir`.
pub fn assert_no_temporary_files(dir: &std::path::Path) {
    let temporary: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(temporary.is_empty(), "{temporary:?}");
}

/// Waits until `path` exists (a process writes it), at most two minutes.
pub fn wait_for(path: &std::path::Path) {
    let start = std::time::Instant::now();
    while !path.exists() {
        assert!(
            start.elapsed() < std::time::Duration::from_secs(120),
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// SplitMix64: a tiny, well-mixed and reproducible sequence for the seeded generators of
/// mutated input (`tests/fuzz_*.rs`), without a dependency.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in 0..n (0 for n = 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// The seeds of a generator's cases: `THERMOCONTACT_FUZZ_CASES` of them (else `default`) from
/// `THERMOCONTACT_FUZZ_SEED` (else 1).
pub fn fuzz_seeds(default: u64) -> std::ops::Range<u64> {
    let var = |name: &str| std::env::var(name).ok().and_then(|s| s.parse::<u64>().ok());
    let first = var("THERMOCONTACT_FUZZ_SEED").unwrap_or(1);
    first..first + var("THERMOCONTACT_FUZZ_CASES").unwrap_or(default)
}

/// `f` with the panic hook silenced (the generators catch panics and report them with their
/// case).
pub fn quietly<T>(f: impl FnOnce() -> T) -> T {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let out = f();
    std::panic::set_hook(hook);
    out
}

/// The message of a caught panic.
pub fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_default()
}
