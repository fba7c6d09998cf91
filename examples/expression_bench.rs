//! What expressions cost: one evaluation, and one `Load::add_to` per time step.
//!
//! ```text
//! cargo run --release --example expression_bench
//! ```
//!
//! 1. ns per [`Expression::eval`] of `-20*t*y/sqrt(x^2+y^2)` and `800*t` (2·10⁶ points, best of
//!    5), next to the same formulas written in Rust;
//! 2. ns per evaluation of sums `x+y+x+y+…` and products `x*y*x*y*…` of n = 64, 256, 1024
//!    and 2000 terms (2000 terms are 3999 bytes, within the 4096-byte limit): the cost should
//!    grow linearly with n;
//! 3. the time of one [`Load::add_to`] on `mesh::rectangle(40, 10, 256, 64)` (16 705 nodes,
//!    32 768 triangles) for a body force depending on x and t (quadrature on every call), on t
//!    only (a cached unit load scaled per step), and constant (a cached vector added).
//!
//! The machine is shared, so the numbers move by ±20 %; the best of several runs is printed.

use std::hint::black_box;
use std::time::Instant;

use thermocontact::loads::{Datum, Expression, Load, LoadKind};
use thermocontact::mesh;

/// The best wall time of `reps` runs of `f`, in seconds.
fn best_of(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let n = 2_000_000;
    let points: Vec<([f64; 3], f64)> = (0..n)
        .map(|i| {
            let s = i as f64 / n as f64;
            ([40.0 * s + 0.1, 10.0 * (1.0 - s) + 0.1, 0.0], 0.001 * (i % 1000) as f64)
        })
        .collect();
    type Native = fn([f64; 3], f64) -> f64;
    let cases: [(&str, Native); 2] = [
        ("-20*t*y/sqrt(x^2+y^2)", |x, t| {
            -20.0 * t * x[1] / (x[0].powi(2) + x[1].powi(2)).sqrt()
        }),
        ("800*t", |_, t| 800.0 * t),
    ];
    println!("evaluation, ns per call (Expression / Rust):");
    for (text, native) in cases {
        let e = Expression::parse(text).expect("valid expression");
        let mut sum = 0.0;
        let ours = best_of(5, || {
            sum = points.iter().map(|(x, t)| e.eval(black_box(*x), black_box(*t))).sum();
        });
        let mut check = 0.0;
        let rust = best_of(5, || {
            check = points.iter().map(|(x, t)| native(black_box(*x), black_box(*t))).sum();
        });
        assert!((sum - check).abs() <= 1e-9 * check.abs(), "{text}: {sum} vs {check}");
        println!(
            "  {text:24} {:6.1} / {:4.1}",
            ours / n as f64 * 1e9,
            rust / n as f64 * 1e9
        );
    }

    println!("scaling, ns per call (and per term) for n terms:");
    let few = &points[..20_000];
    for n in [64, 256, 1024, 2000] {
        let mut row = format!("  n = {n:4}");
        for op in ["+", "*"] {
            let text = (0..n).map(|k| ["x", "y"][k % 2]).collect::<Vec<_>>().join(op);
            let e = Expression::parse(&text).expect("within the limits");
            let mut sum = 0.0;
            let seconds = best_of(5, || {
                sum = few.iter().map(|(x, t)| e.eval(black_box(*x), black_box(*t))).sum();
            });
            black_box(sum);
            let ns = seconds / few.len() as f64 * 1e9;
            row += &format!("   {op} {ns:9.0} ({:5.2})", ns / n as f64);
        }
        println!("{row}");
    }

    let mesh = mesh::rectangle(40.0, 10.0, 256, 64);
    println!(
        "add_to of a body force on rectangle(40, 10, 256, 64): {} nodes, {} cells",
        mesh.n_nodes(),
        mesh.n_cells()
    );
    let data = [
        (
            "x and t (quadrature)",
            Datum::expressions(&["0", "-20*t*y/sqrt(x^2+y^2)"]),
        ),
        ("t only (scaled copy)", Datum::expressions(&["0", "-800*t"])),
        ("constant (cached)", Ok(Datum::constant(vec![0.0, -800.0]))),
    ];
    let mut out = vec![0.0; 2 * mesh.n_nodes()];
    for (name, datum) in data {
        let load = Load::new(&mesh, LoadKind::BodyForce, datum.expect("valid"), name.into()).expect("valid load");
        let mut step = 0;
        let seconds = best_of(20, || {
            step += 1;
            load.add_to(&mesh, 0.01 * step as f64, &mut out).expect("finite");
        });
        println!("  {name:24} {:8.3} ms", seconds * 1e3);
    }
    black_box(&out);
}
