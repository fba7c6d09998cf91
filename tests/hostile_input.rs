//! Input at the edges (issue 26, in part): an empty contact part, a FIFO or a folder given as a
//! scenario or mesh file, each refused with a message naming it instead of a silent run or a
//! hang.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use thermocontact::mesh;
use thermocontact::model::ProblemBuilder;
use thermocontact::model::TimeGrid;
use thermocontact::Scenario;

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-hostile-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn an_empty_contact_part_is_refused_by_name() {
    let mut mesh = mesh::rectangle(4.0, 1.0, 4, 1);
    mesh.part_names.push("lining".to_string());
    let material = thermocontact::model::samples::paper_material();
    let error = ProblemBuilder::new(mesh, material, TimeGrid::new(1.0, 4))
        .dirichlet(&["left"])
        .contact(&["bottom", "lining"])
        .build()
        .unwrap_err()
        .to_string();
    assert!(error.contains("`lining`") && error.contains("no facets"), "{error}");
}

#[test]
fn a_fifo_or_a_folder_is_not_read_as_a_scenario_or_a_mesh() {
    let dir = scratch("fifo");
    let fifo = dir.join("scenario.toml");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let clock = Instant::now();
    let error = Scenario::load_file(&fifo, &[]).unwrap_err().to_string();
    assert!(
        error.contains("not a regular file") && error.contains("scenario.toml"),
        "{error}"
    );
    let error = mesh::read_msh(&fifo).unwrap_err().to_string();
    assert!(error.contains("not a regular file"), "{error}");
    let error = mesh::read_msh(&dir).unwrap_err().to_string();
    assert!(error.contains("not a regular file"), "{error}");
    assert!(clock.elapsed() < Duration::from_secs(5), "no read blocked");
}

/// Every input file goes through one reader: a FIFO given as a friction table or a checkpoint
/// is refused as promptly as a scenario or a mesh, and a scenario over its size limit is
/// refused before it is read.
#[test]
fn every_input_file_is_a_regular_file_within_its_limit() {
    let dir = scratch("inputs");
    let fifo = dir.join("mu.csv");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let clock = Instant::now();
    let table = format!("friction={{law=\"table\", bound=1.0, file=\"{}\"}}", fifo.display());
    let error = Scenario::load(None, &[table]).unwrap_err().to_string();
    assert!(
        error.contains("not a regular file") && error.contains("friction"),
        "{error}"
    );
    let error = thermocontact::output::checkpoint::read(&fifo).unwrap_err().to_string();
    assert!(
        error.contains("not a regular file") && error.contains("mu.csv"),
        "{error}"
    );
    assert!(clock.elapsed() < Duration::from_secs(5), "no read blocked");

    let big = dir.join("big.toml");
    let limit = thermocontact::scenario::MAX_SCENARIO_BYTES as usize;
    std::fs::write(&big, format!("# {}\n", "x".repeat(limit))).unwrap();
    let error = Scenario::load_file(&big, &[]).unwrap_err().to_string();
    assert!(
        error.contains("big.toml") && error.contains(&limit.to_string()),
        "{error}"
    );
}

/// Messages (issue 26, item 14): an unknown key lists every key its table may hold (the
/// optional ones too) with the nearest spelling; an unknown law names the key and the laws; a
/// datum table names its stray key; a TOML syntax error names the file.
#[test]
fn messages_name_the_key_the_value_and_the_file() {
    let error = |set: &str| Scenario::load(None, &[set.to_string()]).unwrap_err().to_string();
    let e = error("boundary.symetry=[\"x\"]");
    assert!(
        e.contains("`symmetry`") && e.contains("did you mean `boundary.symmetry`?"),
        "{e}"
    );
    let e = error("mesh.fille=\"a.msh\"");
    assert!(
        e.contains("`file`") && e.contains("`nz`") && e.contains("did you mean `mesh.file`?"),
        "{e}"
    );
    for set in ["friction={law=\"tabel\"}", "friction.law=\"tabel\""] {
        let e = error(set);
        assert!(
            e.contains("`friction.law`") && e.contains("\"tabel\"") && e.contains("`table`") && !e.contains("variant"),
            "{e}"
        );
    }
    let e = error("heat_exchange={law=\"lin\"}");
    assert!(
        e.contains("`heat_exchange.law`") && e.contains("`linear`") && !e.contains("variant"),
        "{e}"
    );
    let e = error("friction.bound={constant=1, rate=2, slope=3}");
    assert!(e.contains("`slope`"), "{e}");

    // A 100 kB expression is named with its limit, and not echoed whole.
    let long = vec!["x"; 52_000].join("+");
    let e = error(&format!("loads.body_force=[\"{long}\", \"0\"]"));
    assert!(
        e.contains("`loads.body_force`") && e.contains("4096") && e.len() < 1000,
        "{}",
        e.chars().take(200).collect::<String>()
    );

    let dir = scratch("messages");
    let file = dir.join("broken.toml");
    std::fs::write(&file, "[time]\nsteps = [1,\n").unwrap();
    let e = Scenario::load_file(&file, &[]).unwrap_err().to_string();
    assert!(e.contains("broken.toml") && e.contains("line 2"), "{e}");
}
