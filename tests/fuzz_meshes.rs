//! Mesh files that cannot crash it: a seeded generator of mutated Gmsh files (truncations, byte
//! flips, counts and tags made extreme, lines deleted or repeated, node tags defined twice,
//! empty physical groups, a cell laid across others). Every case must end in a clean error
//! naming the file, or in a valid mesh with finite coordinates; never a panic, and never a
//! reservation from a count the file cannot hold (the process's peak memory stays small).
//!
//! 400 cases here (a second or two); for a deeper run,
//! `THERMOCONTACT_FUZZ_CASES=200000 cargo test --release --test fuzz_meshes`
//! (`THERMOCONTACT_FUZZ_SEED` picks another sequence). The scenario generator is
//! `tests/fuzz_scenarios.rs`.

mod common;

use std::panic::{catch_unwind, AssertUnwindSafe};

use common::{fuzz_seeds, panic_message, quietly, Rng};
use std::path::{Path, PathBuf};

use thermocontact::mesh::{self, msh_text, read_msh};

fn meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes")
}

/// The files mutated: Gmsh's own (MSH 4.1 ASCII and binary, 2.2, a 3D one) and a generated
/// rectangle.
fn originals() -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = [
        "annulus_41.msh",
        "annulus_41_binary.msh",
        "annulus_22.msh",
        "pad3d_coarse.msh",
    ]
    .iter()
    .map(|name| (name.to_string(), std::fs::read(meshes().join(name)).unwrap()))
    .collect();
    files.push((
        "rectangle.msh".into(),
        msh_text(&mesh::rectangle(4.0, 1.0, 8, 2)).into_bytes(),
    ));
    files
}

/// The byte ranges of the whitespace-separated tokens of `text`.
fn tokens(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        while i < text.len() && text[i].is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while i < text.len() && !text[i].is_ascii_whitespace() {
            i += 1;
        }
        if i > start {
            out.push((start, i));
        }
    }
    out
}

/// The line ranges (with their newline).
fn lines(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &b) in text.iter().enumerate() {
        if b == b'\n' {
            out.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < text.len() {
        out.push((start, text.len()));
    }
    out
}

fn splice(text: &[u8], (a, b): (usize, usize), with: &[u8]) -> Vec<u8> {
    [&text[..a], with, &text[b..]].concat()
}

/// One mutation of `text` (`ascii`: whether its body is text).
fn mutate(rng: &mut Rng, text: &[u8], ascii: bool, name: &str) -> Vec<u8> {
    let integers = [
        "0",
        "-1",
        "1",
        "2",
        "3",
        "1000000",
        "4294967296",
        "9223372036854775807",
        "18446744073709551615",
        "99999999999999999999999",
        "1e300",
        "nan",
    ];
    if text.is_empty() {
        return b"$MeshFormat\n".to_vec();
    }
    match rng.below(if ascii { 9 } else { 3 }) {
        // Truncated anywhere.
        0 => text[..rng.below(text.len())].to_vec(),
        // A byte changed.
        1 => {
            let mut t = text.to_vec();
            let i = rng.below(t.len());
            t[i] = (rng.next() & 0xff) as u8;
            t
        }
        // A run of bytes repeated.
        2 => {
            let a = rng.below(text.len());
            let b = (a + 1 + rng.below(64)).min(text.len());
            [&text[..b], &text[a..]].concat()
        }
        // A token (a count, a tag, a coordinate) made extreme.
        3 | 4 => {
            let all = tokens(text);
            if all.is_empty() {
                return text.to_vec();
            }
            let token = all[rng.below(all.len())];
            splice(text, token, integers[rng.below(integers.len())].as_bytes())
        }
        // A line deleted or repeated.
        5 => {
            let all = lines(text);
            let line = all[rng.below(all.len())];
            if rng.below(2) == 0 {
                splice(text, line, b"")
            } else {
                splice(text, (line.0, line.0), &text[line.0..line.1])
            }
        }
        // One node's tag made another's (4.1: tags are the lines of one token in $Nodes).
        6 => {
            let Some(nodes) = text.windows(7).position(|w| w == b"$Nodes\n") else {
                return text.to_vec();
            };
            let single: Vec<(usize, usize)> = lines(text)
                .into_iter()
                .filter(|&(a, b)| a > nodes + 7 && !text[a..b].trim_ascii().contains(&b' ') && text[a] != b'$')
                .take(200)
                .collect();
            if single.len() < 2 {
                return text.to_vec();
            }
            let (from, to) = (single[rng.below(single.len())], single[rng.below(single.len())]);
            splice(text, to, &text[from.0..from.1])
        }
        // An empty physical group, named.
        7 => {
            let t = String::from_utf8_lossy(text).into_owned();
            match t.split_once("$PhysicalNames\n") {
                Some((head, rest)) => {
                    let (count, tail) = rest.split_once('\n').unwrap_or((rest, ""));
                    let n: usize = count.trim().parse().unwrap_or(0);
                    format!("{head}$PhysicalNames\n{}\n1 999 \"empty\"\n{tail}", n + 1).into_bytes()
                }
                None => text.to_vec(),
            }
        }
        // A cell laid across others (the generated rectangle's cell block: `2 1 2 N`).
        _ => {
            let t = String::from_utf8_lossy(text).into_owned();
            if name != "rectangle.msh" {
                return text.to_vec();
            }
            let cells = mesh::rectangle(4.0, 1.0, 8, 2).n_cells();
            let (a, b, c) = (1 + rng.below(27), 1 + rng.below(27), 1 + rng.below(27));
            t.replace(
                &format!("\n2 1 2 {cells}\n"),
                &format!("\n2 1 2 {}\n9999 {a} {b} {c}\n", cells + 1),
            )
            .into_bytes()
        }
    }
}

/// How a case ended.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Outcome {
    Refused,
    Read,
}

fn case(seed: u64, originals: &[(String, Vec<u8>)], dir: &Path) -> Result<Outcome, String> {
    let mut rng = Rng(seed);
    let (name, original) = &originals[rng.below(originals.len())];
    let ascii = !name.contains("binary");
    let mut text = original.clone();
    for _ in 0..=rng.below(2) {
        text = catch_unwind(AssertUnwindSafe(|| mutate(&mut rng, &text, ascii, name)))
            .map_err(|_| format!("seed {seed}: the generator panicked"))?;
    }
    let path = dir.join(format!("case{seed}-{name}"));
    std::fs::write(&path, &text).unwrap();
    let outcome = catch_unwind(AssertUnwindSafe(|| match read_msh(&path) {
        Err(e) if e.to_string().contains(&*path.to_string_lossy()) => Ok(Outcome::Refused),
        Err(e) => Err(format!("an error that does not name the file: {e}")),
        Ok(mesh) if mesh.coords.iter().flatten().all(|c| c.is_finite()) && mesh.n_cells() > 0 => Ok(Outcome::Read),
        Ok(_) => Err("a mesh with non-finite coordinates or no cell".into()),
    }));
    let _ = std::fs::remove_file(&path);
    match outcome {
        Ok(Ok(outcome)) => Ok(outcome),
        Ok(Err(why)) => Err(format!("seed {seed} ({name}): {why}")),
        Err(panic) => {
            let message = panic_message(&*panic);
            Err(format!("seed {seed} ({name}): panicked: {message}"))
        }
    }
}

#[test]
fn mutated_mesh_files_end_in_a_clean_error_or_a_valid_mesh() {
    let seeds = fuzz_seeds(400);
    let cases = seeds.end - seeds.start;
    let dir = std::env::temp_dir().join(format!("thermocontact-fuzz-meshes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let originals = originals();
    let results: Vec<Result<Outcome, String>> = quietly(|| seeds.map(|s| case(s, &originals, &dir)).collect());
    let _ = std::fs::remove_dir_all(&dir);
    let count = |o: Outcome| results.iter().filter(|r| r.as_ref().ok() == Some(&o)).count();
    let (refused, read) = (count(Outcome::Refused), count(Outcome::Read));
    eprintln!("{cases} mutated files: {refused} refused, {read} read as valid meshes");
    let failures: Vec<&String> = results.iter().filter_map(|r| r.as_ref().err()).collect();
    assert!(
        failures.is_empty(),
        "{} of {cases} cases failed; the first:\n{}",
        failures.len(),
        failures[0]
    );
    // Not vacuous: both ends are reached.
    assert!(
        refused * 4 >= cases as usize && read * 20 >= cases as usize,
        "{refused} refused, {read} read"
    );
    // No count was trusted beyond what its file holds: the files are ≤ 22 kB.
    if let Some(peak) = thermocontact::resources::peak_memory_mib() {
        assert!(peak < 1024.0, "peak memory {peak} MiB");
    }
}
