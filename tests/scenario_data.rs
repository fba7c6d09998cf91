//! Data in a scenario: every datum form gives the same run where it means the same load, and
//! every input error names the key, exits non-zero and writes nothing.

use std::path::PathBuf;
use std::process::Command;

use thermocontact::mesh::Mesh;
use thermocontact::Scenario;

fn coarse(overrides: &[&str]) -> Result<Scenario, thermocontact::Error> {
    let mut all: Vec<String> = ["mesh.nx=16", "mesh.ny=4", "time.steps=16"].map(String::from).to_vec();
    all.extend(overrides.iter().map(|s| s.to_string()));
    Scenario::load(None, &all)
}

fn final_u(scenario: &Scenario) -> Vec<f64> {
    scenario.run_quiet().unwrap().1.u
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// The top traction (0, −800 t) written as the affine table, as expressions, and as a normal
/// pressure 800 t on the top (ν = (0, 1), traction −p ν) gives one run.
#[test]
fn affine_expression_and_pressure_forms_of_one_load_give_one_run() {
    let affine = coarse(&[]).unwrap();
    let expression =
        coarse(&[r#"loads.traction=[{part="top", value=["0", "-800*t"]}, {part="right", value=[0, 0]}]"#]).unwrap();
    let pressure = Scenario::load(
        Some(
            r#"
[mesh]
nx = 16
ny = 4
[time]
steps = 16
[[loads.traction]]
part = "right"
value = [0.0, 0.0]
[[loads.pressure]]
part = "top"
value = "800*t"
"#,
        ),
        &[],
    )
    .unwrap();
    let u = final_u(&affine);
    let scale = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(scale > 0.0);
    for (name, other) in [("expressions", &expression), ("pressure", &pressure)] {
        let d = max_diff(&u, &final_u(other));
        assert!(d <= 1e-12 * scale, "{name}: differs by {d:e}");
    }
    // A body force that depends on x changes the run (the expression is really evaluated).
    let varying = coarse(&[r#"loads.body_force=["0", "-10*x/20"]"#]).unwrap();
    assert!(max_diff(&u, &final_u(&varying)) > 1e-6 * scale);
}

/// Initial data as expressions: u₁ must lie in E^h (zero on Γ_D, tangential on Γ_C).
#[test]
fn initial_data_as_expressions_are_checked_against_the_constraints() {
    let s = coarse(&[
        r#"initial.temperature="25 + x/40""#,
        r#"initial.velocity=["0.01*x/40", "0"]"#,
    ])
    .unwrap();
    let (_, last) = s.run_quiet().unwrap();
    assert_eq!(last.n, 16);
    let e = coarse(&[r#"initial.velocity=["0.01", "0"]"#])
        .unwrap()
        .build()
        .unwrap_err()
        .to_string();
    assert!(e.contains("initial.velocity") && e.contains("Γ_D"), "{e}");
    let e = coarse(&[r#"initial.velocity=["0", "0.01*x"]"#])
        .unwrap()
        .build()
        .unwrap_err()
        .to_string();
    assert!(e.contains("initial.velocity") && e.contains("normal"), "{e}");
}

/// Every bad datum is refused when the scenario is read, naming the key.
#[test]
fn bad_data_name_their_key() {
    let cases: [(&str, &str); 8] = [
        // A law switched without its parameter: the missing key by its full name.
        ("friction.law=tresca", "friction.bound"),
        (r#"loads.body_force=["0", "-10*"]"#, "loads.body_force"),
        (r#"loads.body_force=["0", "q*t"]"#, "loads.body_force"),
        (r#"loads.body_force=[0, 0, 1]"#, "loads.body_force"),
        (r#"loads.heat_source=true"#, "loads.heat_source"),
        (r#"loads.traction=[{part="top", value="800*t"}]"#, "loads.traction[0]"),
        (
            r#"loads.pressure=[{part="bottom", value="1"}]"#,
            "loads.pressure[0].part",
        ),
        (r#"initial.temperature=["1", "2"]"#, "initial.temperature"),
    ];
    for (set, key) in cases {
        let e = coarse(&[set]).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(key), "{set}: {e}");
    }
    // Non-finite values show up where they are evaluated, named by the key and the point.
    let s = coarse(&[r#"loads.body_force=["0", "1/(x-20)"]"#]).unwrap();
    let e = s.run_quiet().map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("loads.body_force") && e.contains("not finite"), "{e}");
}

/// Old keys and geometry beside a mesh file get messages that say what to do.
#[test]
fn removed_and_conflicting_mesh_keys_are_explained() {
    let e = coarse(&["boundary.contact_normal=[0.0, -1.0]"])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("boundary.contact_normal") && e.contains("from the mesh"),
        "{e}"
    );
    let e = Scenario::load(Some("[mesh]\nfile = \"part.msh\"\nnx = 4\n"), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("mesh.nx") && e.contains("mesh.file"), "{e}");
    let e = Scenario::load(Some("[mesh]\nfile = \"/nonexistent/part.msh\"\n"), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/part.msh"), "{e}");
    let e = coarse(&[r#"boundary.contact=["bottom", "middle"]"#])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("boundary.contact") && e.contains("middle") && e.contains("\"top\""),
        "{e}"
    );
}

/// A mesh given in memory (`Scenario::load_with_mesh`) with parts named its own way runs as the
/// generated mesh it copies; the scenario's boundary parts are checked against it, and mesh keys
/// beside it are refused by name.
#[test]
fn a_mesh_given_in_memory_runs_like_the_generated_one() {
    let generated = thermocontact::mesh::rectangle(40.0, 10.0, 16, 4);
    let renamed = ["clamp", "free", "contact", "load"].map(String::from).to_vec();
    let mesh = Mesh::new(
        2,
        generated.coords.clone(),
        generated.cells.clone(),
        generated.facets.clone(),
        generated.facet_parts.clone(),
        renamed,
    )
    .unwrap();
    let text = r#"
        [time]
        steps = 16
        [boundary]
        dirichlet = ["clamp"]
        neumann = ["load", "free"]
        contact = ["contact"]
        [[loads.traction]]
        part = "load"
        constant = [0.0, 0.0]
        rate = [0.0, -800.0]
    "#;
    let given = Scenario::load_with_mesh(Some(text), &[], mesh.clone()).unwrap();
    assert_eq!((given.dim(), given.structured()), (2, None));
    assert_eq!(final_u(&given), final_u(&coarse(&[]).unwrap()));
    // Its TOML holds no mesh: loaded again with the same mesh, it is the same scenario.
    let again = Scenario::load_with_mesh(Some(&given.to_toml()), &[], mesh.clone()).unwrap();
    assert_eq!(again, given);

    let e = Scenario::load_with_mesh(Some(text), &[r#"boundary.contact=["bottom"]"#.into()], mesh.clone())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("boundary.contact") && e.contains("bottom") && e.contains("\"clamp\""),
        "{e}"
    );
    let e = Scenario::load_with_mesh(Some(text), &["mesh.nz=4".into()], mesh.clone())
        .unwrap_err()
        .to_string();
    assert!(e.contains("mesh.nz") && e.contains("in memory"), "{e}");
    let e = Scenario::load_with_mesh(Some(text), &["mesh.nx=4".into()], mesh.clone())
        .unwrap_err()
        .to_string();
    assert!(e.contains("mesh.nx") && e.contains("in memory"), "{e}");
    let e = Scenario::load_with_mesh(Some(&format!("{text}\n[geometry]\nlengths = [1.0, 1.0]")), &[], mesh)
        .unwrap_err()
        .to_string();
    assert!(e.contains("geometry") && e.contains("in memory"), "{e}");
}

/// Γ_D may be empty: the paper's example held by friction alone still runs.
#[test]
fn an_empty_dirichlet_boundary_is_accepted() {
    let s = coarse(&["boundary.dirichlet=[]", r#"boundary.neumann=["top", "right", "left"]"#]).unwrap();
    let (summary, last) = s.run_quiet().unwrap();
    assert_eq!(last.n, 16);
    assert!(summary.outputs.iter().all(|o| o.slip_nodes + o.stick_nodes == 17));
}

/// An input error on the command line exits non-zero, names the key and writes nothing.
#[test]
fn command_line_input_errors_write_nothing() {
    let out = std::env::temp_dir().join(format!("thermocontact-data-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    for set in [
        r#"loads.body_force=["0", "-10*"]"#,
        "boundary.contact_normal=[0.0, 1.0]",
        r#"boundary.contact=["nowhere"]"#,
    ] {
        let result = Command::new(env!("CARGO_BIN_EXE_thermocontact"))
            .args(["run", "--quiet", "--set", set, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(!result.status.success(), "{set}");
        let stderr = String::from_utf8_lossy(&result.stderr);
        let key = set.split('=').next().unwrap();
        assert!(stderr.contains(key), "{set}: {stderr}");
        assert!(!PathBuf::from(&out).exists(), "{set}: output written");
    }
}

/// θ_ref is the stress-free temperature: raising every temperature datum (θ_D, θ₀, θ_R) and θ_ref
/// by the same s leaves the mechanics unchanged and shifts θ by s (the equations see θ only
/// through θ − θ_ref and its gradients), while θ_ref alone changes the run.
#[test]
fn the_reference_temperature_shifts_with_the_temperatures() {
    let (_, base) = coarse(&[]).unwrap().run_quiet().unwrap();
    let shifted = [
        "boundary.temperature=35",
        "initial.temperature=35",
        "heat_exchange.foundation_temperature=10",
        "material.reference_temperature=10",
    ];
    let (_, moved) = coarse(&shifted).unwrap().run_quiet().unwrap();
    let scale = base.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(scale > 1e-6, "the default run moves");
    assert!(
        max_diff(&base.u, &moved.u) < 1e-9 * scale,
        "u: {}",
        max_diff(&base.u, &moved.u)
    );
    let theta: Vec<f64> = base.theta.iter().map(|t| t + 10.0).collect();
    assert!(
        max_diff(&theta, &moved.theta) < 1e-9,
        "θ: {}",
        max_diff(&theta, &moved.theta)
    );
    // θ_ref alone takes the initial thermal stress Cθ₀ away: the slip it drives changes u.
    let alone = final_u(&coarse(&["material.reference_temperature=25"]).unwrap());
    assert!(max_diff(&base.u, &alone) > 1e-3 * scale, "θ_ref is used");
}
