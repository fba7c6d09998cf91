//! Input that cannot crash it: a seeded generator of mutated scenarios (values of every type at
//! their extremes, expressions at and beyond their length and nesting limits). Every case must
//! end in a clean error naming a key, or in a run whose figures are finite; never a panic. The
//! Gmsh reader has its own generator: `tests/fuzz_meshes.rs`.
//!
//! 300 cases here (seconds); for a deeper run,
//! `THERMOCONTACT_FUZZ_CASES=100000 cargo test --release --test fuzz_scenarios`
//! (`THERMOCONTACT_FUZZ_SEED` picks another sequence).

mod common;

use std::panic::{catch_unwind, AssertUnwindSafe};

use common::{fuzz_seeds, panic_message, quietly, Rng};

use thermocontact::Scenario;
use toml::{Table, Value};

const PAPER_3D: &str = include_str!("../scenarios/paper3d.toml");

/// Thermal conditions on the 2D default's parts, one of each kind with data, for the mutations
/// to reach their keys.
const THERMAL: &str = r#"
[[thermal]]
part = "left"
condition = "temperature"
value = { constant = 25.0, rate = 10.0 }
[[thermal]]
part = "right"
condition = "convection"
coefficient = 25.0
ambient = 20.0
[[thermal]]
part = "top"
condition = "flux"
value = "100*t"
"#;

/// Values a user (or an attacker) might type.
fn value(rng: &mut Rng) -> Value {
    let floats = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e300,
        -1e300,
        1e-300,
        0.0,
        -0.0,
        -1.0,
        0.5,
        1.0,
        3.0,
        1e19,
        1e6,
        -7.5,
    ];
    let ints = [i64::MAX, i64::MIN, 0, -1, 1, 2, 3, 7, 100, 100_000, 1 << 40];
    let strings = [
        "",
        "x",
        "nan",
        "1e309",
        "sin(x)/0",
        "x*y*z*t",
        "exp(1000*t)",
        "paper",
        "tresca",
        "bottom",
        "no-such-part",
        "((((",
        "1e-3*x",
    ];
    match rng.below(8) {
        0 | 1 => Value::Float(*rng.pick(&floats)),
        2 => Value::Integer(*rng.pick(&ints)),
        3 => Value::String(rng.pick(&strings).to_string()),
        7 => Value::String(expression(rng)),
        4 => Value::Boolean(rng.below(2) == 0),
        5 => {
            let n = rng.pick(&[0usize, 1, 2, 3, 4]);
            Value::Array((0..*n).map(|_| Value::Float(*rng.pick(&floats))).collect())
        }
        _ => Value::Table(Table::from_iter([("law".to_string(), Value::String("tresca".into()))])),
    }
}

/// Expressions at the edges of their limits (4096 bytes, nesting 100): deep parentheses, signs
/// and powers, long sums and products, just under and over each limit and far beyond.
fn expression(rng: &mut Rng) -> String {
    let depth = *rng.pick(&[10usize, 99, 100, 101, 9_000]);
    let terms = *rng.pick(&[10usize, 1_000, 2_047, 2_049, 52_000]);
    match rng.below(5) {
        0 => format!("{}x{}", "(".repeat(depth), ")".repeat(depth)),
        1 => format!("{}x", "-".repeat(depth)),
        2 => vec!["x"; depth].join("^"),
        3 => vec!["x"; terms].join("+"),
        _ => vec!["1.0001"; terms / 3].join("*") + "*t",
    }
}

/// Every leaf path of a table (array elements by index).
fn leaves(value: &Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match value {
        Value::Table(t) => {
            for (k, v) in t {
                path.push(k.clone());
                leaves(v, path, out);
                path.pop();
            }
        }
        Value::Array(a) if a.iter().any(|v| v.is_table()) => {
            for (i, v) in a.iter().enumerate() {
                path.push(format!("#{i}"));
                leaves(v, path, out);
                path.pop();
            }
        }
        _ => out.push(path.clone()),
    }
}

fn slot<'a>(root: &'a mut Value, path: &[String]) -> &'a mut Value {
    path.iter().fold(root, |v, key| match (v, key.strip_prefix('#')) {
        (Value::Array(a), Some(i)) => &mut a[i.parse::<usize>().unwrap()],
        (Value::Table(t), _) => t.get_mut(key).unwrap(),
        _ => unreachable!("paths come from leaves()"),
    })
}

fn mutate(rng: &mut Rng, root: &mut Value) {
    let mut all = Vec::new();
    leaves(root, &mut Vec::new(), &mut all);
    let path = rng.pick(&all).clone();
    match rng.below(10) {
        // Remove the key.
        0 => {
            if let (Some((last, parents)), false) = (path.split_last(), path.last().unwrap().starts_with('#')) {
                if let Value::Table(t) = slot(root, parents) {
                    t.remove(last);
                }
            }
        }
        // Add a key nobody knows.
        1 => {
            if let Some((_, parents)) = path.split_last() {
                if let Value::Table(t) = slot(root, parents) {
                    t.insert("surprise".into(), value(rng));
                }
            }
        }
        // Same type, an extreme or odd value: what gets past the parser.
        2..=6 => {
            let target = slot(root, &path);
            let new = value(rng);
            let same = matches!(
                (&*target, &new),
                (Value::Float(_), Value::Float(_) | Value::Integer(_))
                    | (Value::Integer(_), Value::Integer(_))
                    | (Value::String(_), Value::String(_))
                    | (Value::Boolean(_), Value::Boolean(_))
                    | (Value::Array(_), Value::Array(_))
            );
            if same {
                *target = new;
            } else if let Value::Array(items) = target {
                if let Some(item) = items.first_mut() {
                    *item = Value::Float(*rng.pick(&[f64::NAN, 1e300, -1.0, 0.0, 1e-300, 2.0]));
                }
            } else if let Value::Float(x) = target {
                *x = *rng.pick(&[f64::NAN, f64::INFINITY, 1e300, -1e300, 1e-300, 0.0, -1.0, 1e17, 2.0]);
            } else if let Value::Integer(i) = target {
                *i = *rng.pick(&[0, -1, 1, 3, 1 << 20, i64::MAX]);
            }
        }
        _ => *slot(root, &path) = value(rng),
    }
}

/// Cases small enough to run (the others are validated only).
fn small(s: &Scenario) -> bool {
    let cells: usize = s
        .structured()
        .map_or(usize::MAX, |m| m.cells.iter().fold(1usize, |p, &n| p.saturating_mul(n)));
    cells <= 2048 && s.time.steps <= 32
}

/// How a case ended.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Outcome {
    Refused,
    TooLargeToRun,
    Failed,
    Ran,
}

fn case(seed: u64) -> Result<Outcome, String> {
    let mut rng = Rng(seed);
    // The complete 2D default or the 3D example, small to start with (the mutations may make
    // it large).
    let three_d = rng.below(4) == 0;
    let scenario = if three_d {
        Scenario::load(
            Some(PAPER_3D),
            &["mesh.nx=4", "mesh.ny=1", "mesh.nz=1", "time.steps=4"].map(String::from),
        )
    } else {
        // A third of the 2D cases with thermal conditions.
        let thermal = rng.below(3) == 0;
        Scenario::load(
            thermal.then_some(THERMAL),
            &["mesh.nx=8", "mesh.ny=2", "time.steps=4"].map(String::from),
        )
    };
    let base: Table = scenario.unwrap().to_toml().parse().unwrap();
    let mut root = Value::Table(base);
    for _ in 0..=rng.below(3) {
        mutate(&mut rng, &mut root);
    }
    let text = toml::to_string(&root).map_err(|e| format!("the generator made no TOML: {e}"))?;
    let outcome = catch_unwind(AssertUnwindSafe(|| -> Result<Outcome, String> {
        let scenario = match Scenario::load(Some(&text), &[]) {
            Ok(s) => s,
            Err(e) if !e.to_string().is_empty() => {
                if std::env::var("FUZZ_DEBUG").is_ok() {
                    eprintln!("{e}");
                }
                return Ok(Outcome::Refused);
            }
            Err(_) => return Err("an empty error message".into()),
        };
        if !small(&scenario) {
            return Ok(Outcome::TooLargeToRun);
        }
        match scenario.run_quiet() {
            Err(e) if e.to_string().is_empty() => Err("an empty error message".into()),
            Err(_) => Ok(Outcome::Failed),
            Ok((summary, state)) => {
                let finite = state
                    .u
                    .iter()
                    .chain(&state.w)
                    .chain(&state.theta)
                    .all(|v| v.is_finite());
                if finite && summary.max_law_residual.is_finite() {
                    Ok(Outcome::Ran)
                } else {
                    Err("a run that completed with non-finite fields".into())
                }
            }
        }
    }));
    match outcome {
        Ok(Ok(outcome)) => Ok(outcome),
        Ok(Err(why)) => Err(format!("seed {seed}: {why}\n{text}")),
        Err(panic) => {
            let message = panic_message(&*panic);
            Err(format!("seed {seed}: panicked: {message}\n{text}"))
        }
    }
}

#[test]
fn mutated_scenarios_end_in_a_clean_error_or_a_finite_run() {
    let seeds = fuzz_seeds(300);
    let cases = seeds.end - seeds.start;
    // Panics are caught and reported with their case; the default hook is quiet meanwhile.
    let results: Vec<Result<Outcome, String>> = quietly(|| seeds.map(case).collect());
    let count = |o: Outcome| results.iter().filter(|r| r.as_ref().ok() == Some(&o)).count();
    let (refused, large, failed, ran) = (
        count(Outcome::Refused),
        count(Outcome::TooLargeToRun),
        count(Outcome::Failed),
        count(Outcome::Ran),
    );
    eprintln!("{cases} cases: {refused} refused, {large} valid but too large to run here, {failed} stopped with an error, {ran} ran");
    // Not a vacuous test: a good share of the mutants pass validation and run.
    assert!(ran * 10 >= cases as usize, "only {ran} of {cases} cases ran");
    let failures: Vec<&String> = results.iter().filter_map(|r| r.as_ref().err()).collect();
    assert!(
        failures.is_empty(),
        "{} of {cases} cases failed; the first:\n{}",
        failures.len(),
        failures[0]
    );
}

/// Boxes at the ends of the length range, with few and many cells: the lengths alone pass, but
/// cells longer than wide by 10⁸ and more are degenerate for the mesh (these panicked). Each
/// case ends in a clean error naming `geometry.lengths` and the cell counts, or in a finite run.
#[test]
fn elongated_boxes_end_in_a_clean_error_or_a_finite_run() {
    let ends = [1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4, 1e6];
    let mut cases: Vec<(Vec<f64>, Vec<usize>)> = vec![
        // The cases found by hand: the default 128 × 32 cells, and a small box.
        (vec![1e-6, 1e6], vec![128, 32]),
        (vec![1e-4, 1.0, 1e4], vec![4, 2, 2]),
    ];
    for &a in &ends {
        for &b in &ends {
            for cells in [[1, 1], [8, 2], [2, 8]] {
                cases.push((vec![a, b], cells.to_vec()));
            }
            for &c in &[1e-6, 1.0, 1e6] {
                cases.push((vec![a, b, c], vec![2, 1, 1]));
            }
        }
    }
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let (mut refused, mut ran, mut failed) = (0, 0, 0);
    let mut problems = Vec::new();
    for (lengths, cells) in &cases {
        let names = ["mesh.nx", "mesh.ny", "mesh.nz"];
        let mut overrides = vec![format!("geometry.lengths={lengths:?}"), "time.steps=2".to_string()];
        overrides.extend(cells.iter().zip(names).map(|(n, key)| format!("{key}={n}")));
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            let base = if lengths.len() == 3 { Some(PAPER_3D) } else { None };
            match Scenario::load(base, &overrides) {
                Err(e) => Err(e.to_string()),
                Ok(scenario) => Ok(scenario.run_quiet().map(|(_, state)| {
                    state
                        .u
                        .iter()
                        .chain(&state.w)
                        .chain(&state.theta)
                        .all(|v| v.is_finite())
                })),
            }
        }));
        match outcome {
            Err(_) => problems.push(format!("{overrides:?}: panicked")),
            Ok(Err(message)) => {
                let named = message.contains("geometry.lengths") && message.contains("mesh.nx");
                if named {
                    refused += 1;
                } else {
                    problems.push(format!("{overrides:?}: refused without naming the keys: {message}"));
                }
            }
            Ok(Ok(Ok(true))) => ran += 1,
            Ok(Ok(Ok(false))) => problems.push(format!("{overrides:?}: non-finite fields")),
            Ok(Ok(Err(e))) if !e.to_string().is_empty() => failed += 1,
            Ok(Ok(Err(_))) => problems.push(format!("{overrides:?}: an empty error message")),
        }
    }
    std::panic::set_hook(hook);
    eprintln!(
        "{} boxes: {refused} refused, {failed} stopped with an error, {ran} ran",
        cases.len()
    );
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(refused > 0 && ran > 0, "{refused} refused, {ran} ran");
}
