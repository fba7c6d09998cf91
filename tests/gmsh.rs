//! Meshes from Gmsh: the reader against files Gmsh 4.15 wrote (tests/meshes, with their .geo),
//! a generated mesh through a file and back, the refusals, and the showcase scenarios.

use std::path::{Path, PathBuf};
use std::process::Command;

use thermocontact::mesh::{self, msh_text, read_msh, Mesh, MeshError};
use thermocontact::step::SolverKind;
use thermocontact::Scenario;

fn meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-gmsh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// The facets of each part as sorted node sets, in coordinates (independent of numbering).
fn parts(mesh: &Mesh) -> Vec<(String, Vec<Vec<[i64; 3]>>)> {
    let key = |x: [f64; 3]| x.map(|c| (c * 1e9).round() as i64);
    let mut out: Vec<(String, Vec<Vec<[i64; 3]>>)> = mesh
        .part_names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let mut facets: Vec<Vec<[i64; 3]>> = (0..mesh.n_facets())
                .filter(|&f| mesh.facet_parts[f] == k)
                .map(|f| {
                    let mut v: Vec<[i64; 3]> = mesh.facet(f).iter().map(|&p| key(mesh.coords[p])).collect();
                    v.sort();
                    v
                })
                .collect();
            facets.sort();
            (name.clone(), facets)
        })
        .collect();
    out.sort();
    out
}

#[test]
fn ascii_binary_and_msh22_files_of_one_mesh_read_the_same() {
    let ascii = read_msh(&meshes().join("annulus_41.msh")).unwrap();
    let binary = read_msh(&meshes().join("annulus_41_binary.msh")).unwrap();
    let old = read_msh(&meshes().join("annulus_22.msh")).unwrap();
    assert_eq!(ascii.dim, 2);
    assert_eq!(ascii.part_names, vec!["inner", "outer"]);
    for other in [&binary, &old] {
        // Gmsh writes 16 significant digits in ASCII, all 17 in binary.
        let worst = other.coords.iter().zip(&ascii.coords).fold(0.0f64, |m, (a, b)| {
            m.max((0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max))
        });
        assert!(worst < 1e-14, "{worst:e}");
        assert_eq!(other.cells, ascii.cells);
        assert_eq!(parts(other), parts(&ascii));
    }
    // The ring's area, to the polygons' error; every facet normal points out of the ring.
    let exact = std::f64::consts::PI * (4.0 - 1.0);
    assert!((ascii.volume() - exact).abs() < 0.05 * exact, "{}", ascii.volume());
    for f in 0..ascii.n_facets() {
        let x = ascii.coords[ascii.facet(f)[0]];
        let n = ascii.facet_normal(f);
        let outward_from_axis = n[0] * x[0] + n[1] * x[1] > 0.0;
        assert_eq!(outward_from_axis, ascii.part_names[ascii.facet_parts[f]] == "outer");
    }
}

#[test]
fn generated_meshes_go_through_a_file_and_back() {
    for mesh in [
        mesh::rectangle(40.0, 10.0, 8, 2),
        mesh::cuboid([2.0, 1.0, 1.0], [2, 1, 1]),
    ] {
        let path = scratch(&format!("roundtrip{}.msh", mesh.dim));
        std::fs::write(&path, msh_text(&mesh)).unwrap();
        let back = read_msh(&path).unwrap();
        assert_eq!(back.coords, mesh.coords);
        assert_eq!(back.cells, mesh.cells);
        assert_eq!(back.part_names, mesh.part_names);
        assert_eq!(parts(&back), parts(&mesh));
    }
}

/// The default scenario's rectangle written as a .msh file and run from it gives the run of the
/// built-in generator (to round-off).
#[test]
fn the_default_rectangle_from_a_file_gives_the_generators_run() {
    let coarse = ["mesh.nx=16", "mesh.ny=4", "time.steps=16"].map(String::from);
    let generated = Scenario::load(None, &coarse).unwrap();
    let path = scratch("default.msh");
    std::fs::write(&path, msh_text(&generated.mesh().unwrap())).unwrap();
    let text = format!("[mesh]\nfile = {:?}\n[time]\nsteps = 16\n", path.to_str().unwrap());
    let from_file = Scenario::load(Some(&text), &[]).unwrap();
    assert!(from_file.structured().is_none());
    // The default's tractions name the rectangle's parts: they are the file's parts too.
    let from_file = Scenario::load(
        Some(&format!(
            "{text}[[loads.traction]]\npart = \"top\"\nconstant = [0.0, 0.0]\nrate = [0.0, -800.0]\n"
        )),
        &[],
    )
    .unwrap();
    let (s1, a) = generated.run_quiet().unwrap();
    let (s2, b) = from_file.run_quiet().unwrap();
    let scale = a.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a.u.iter().zip(&b.u).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(diff <= 1e-12 * scale, "{diff:e}");
    for (o1, o2) in s1.outputs.iter().zip(&s2.outputs) {
        assert_eq!((o1.slip_nodes, o1.stick_nodes), (o2.slip_nodes, o2.stick_nodes));
    }
}

#[test]
fn unreadable_and_unsupported_files_are_refused_naming_the_file() {
    let missing = meshes().join("no_such_mesh.msh");
    let e = read_msh(&missing).unwrap_err();
    assert!(
        matches!(e, MeshError::Read { .. }) && e.to_string().contains("no_such_mesh.msh"),
        "{e}"
    );

    let e = read_msh(&meshes().join("annulus_order2.msh")).unwrap_err().to_string();
    assert!(
        e.contains("annulus_order2.msh") && e.contains("second-order") && e.contains("ElementOrder"),
        "{e}"
    );
    let e = read_msh(&meshes().join("annulus_quads.msh")).unwrap_err().to_string();
    assert!(e.contains("quadrangle") && e.contains("simplices"), "{e}");

    let text = msh_text(&mesh::rectangle(1.0, 1.0, 1, 1));
    let cases = [
        ("version.msh", text.replace("4.1 0 8", "3.0 0 8"), "MSH version 3.0"),
        (
            "notmsh.msh",
            "solid cube\nfacet normal 0 0 1\n".into(),
            "not a Gmsh mesh",
        ),
        ("truncated.msh", text[..text.len() - 40].to_string(), "truncated"),
        // Node 3 moved across the diagonal 1–4: the two triangles overlap.
        (
            "tangled.msh",
            text.replace("0.0 1.0 0.0\n", "0.6 0.2 0.0\n"),
            "same side",
        ),
        // Node 3 moved onto the diagonal 1–4: the second triangle is flat.
        (
            "degenerate.msh",
            text.replace("0.0 1.0 0.0\n", "0.5 0.5 0.0\n"),
            "degenerate",
        ),
        // A node tag defined twice (the later definition would move the node).
        (
            "duplicate.msh",
            text.replace(
                "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n",
                "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n3\n",
            ),
            "defined twice",
        ),
        // A node that only a facet uses: not in any cell.
        (
            "unused.msh",
            text.replace(
                "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n",
                "$Nodes\n1 5 1 5\n2 1 0 5\n1\n2\n3\n4\n5\n",
            )
            .replace("1.0 1.0 0.0\n", "1.0 1.0 0.0\n9.0 9.0 0.0\n")
            .replace("4 4 3\n", "4 4 5\n"),
            "belong to no cell",
        ),
    ];
    for (name, body, expected) in cases {
        let path = scratch(name);
        std::fs::write(&path, body).unwrap();
        let e = read_msh(&path).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains(expected), "{name}: {e}");
    }
    // Counts larger than the rest of the file could hold: refused before anything is reserved.
    for (name, body) in [
        (
            "many_nodes.msh",
            text.replace("$Nodes\n1 4 1 4\n", "$Nodes\n1 400000000000 1 4\n"),
        ),
        (
            "many_elements.msh",
            text.replace("\n2 1 2 2\n", "\n2 1 2 2000000000000\n"),
        ),
        (
            "huge_count.msh",
            text.replace("$Nodes\n1 4 1 4\n", "$Nodes\n1 18446744073709551615 1 4\n"),
        ),
    ] {
        let path = scratch(name);
        std::fs::write(&path, &body).unwrap();
        let e = read_msh(&path).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains("remain in the file"), "{name}: {e}");
    }
    // Valid input: a file without its final newline reads as with it.
    let path = scratch("no_final_newline.msh");
    std::fs::write(&path, text.trim_end()).unwrap();
    let without = read_msh(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(without.n_nodes(), 4);
}

/// Valid meshes that earlier readers refused: sparse or offset node and element tags (each tag
/// plus 100 000), and a mesh scaled by 10⁻¹⁰⁰ (products of two signed measures underflow;
/// their signs do not).
#[test]
fn offset_tags_and_tiny_scales_read_as_the_same_mesh() {
    // Gmsh's own file, its $Nodes and $Elements rewritten with every tag + 100 000.
    let text = std::fs::read_to_string(meshes().join("annulus_41.msh")).unwrap();
    let shift = |token: &str| (token.parse::<u64>().unwrap() + 100_000).to_string();
    let shift_all = |line: &str| line.split_whitespace().map(shift).collect::<Vec<_>>().join(" ");
    let mut lines = text.lines();
    let mut out: Vec<String> = Vec::new();
    while let Some(line) = lines.next() {
        out.push(line.to_string());
        let (is_nodes, is_elements) = (line == "$Nodes", line == "$Elements");
        if !(is_nodes || is_elements) {
            continue;
        }
        let header: Vec<&str> = lines.next().unwrap().split_whitespace().collect();
        // numBlocks numItems minTag maxTag: the tags shift.
        out.push(format!(
            "{} {} {} {}",
            header[0],
            header[1],
            shift(header[2]),
            shift(header[3])
        ));
        for _ in 0..header[0].parse::<usize>().unwrap() {
            let block = lines.next().unwrap();
            out.push(block.to_string());
            let n: usize = block.split_whitespace().nth(3).unwrap().parse().unwrap();
            if is_nodes {
                (0..n).for_each(|_| out.push(shift_all(lines.next().unwrap())));
                (0..n).for_each(|_| out.push(lines.next().unwrap().to_string()));
            } else {
                (0..n).for_each(|_| out.push(shift_all(lines.next().unwrap())));
            }
        }
    }
    let path = scratch("offset_tags.msh");
    std::fs::write(&path, out.join("\n") + "\n").unwrap();
    let reference = read_msh(&meshes().join("annulus_41.msh")).unwrap();
    let read = read_msh(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(parts(&read), parts(&reference));
    assert_eq!(
        (read.n_cells(), read.coords.clone()),
        (reference.n_cells(), reference.coords.clone())
    );

    let rectangle = mesh::rectangle(2.0, 1.0, 4, 2);
    let tiny = Mesh::new(
        2,
        rectangle.coords.iter().map(|x| x.map(|c| c * 1e-100)).collect(),
        rectangle.cells.clone(),
        rectangle.facets.clone(),
        rectangle.facet_parts.clone(),
        rectangle.part_names.clone(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(tiny.facets, rectangle.facets);
}

/// A part named in a scenario that the mesh does not have: the message lists the mesh's parts.
#[test]
fn a_part_the_mesh_lacks_is_named_with_the_parts_it_has() {
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/brake_shoe.toml");
    let e = Scenario::load_file(&scenario, &[r#"boundary.contact=["drum"]"#.into()])
        .unwrap_err()
        .to_string();
    for expected in ["boundary.contact", "drum", "lining", "pivot"] {
        assert!(e.contains(expected), "{e}");
    }
}

/// The showcase meshes: their parts, and their measures against the geometry's.
#[test]
fn showcase_meshes_have_their_parts_and_measures() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/meshes");
    let shoe = read_msh(&dir.join("brake_shoe.msh")).unwrap();
    assert_eq!(shoe.dim, 2);
    assert_eq!(shoe.part_names, vec!["lining", "tip", "back", "pivot"]);
    let sector = |angle: f64| 0.5 * angle * (13.0f64.powi(2) - 10.0f64.powi(2));
    let area = sector(2.0 * std::f64::consts::PI / 3.0);
    assert!((shoe.volume() - area).abs() < 0.01 * area, "{}", shoe.volume());
    let pad = read_msh(&dir.join("pad3d.msh")).unwrap();
    assert_eq!(pad.dim, 3);
    assert_eq!(pad.part_names, vec!["contact", "tip", "back", "pivot", "sides"]);
    let volume = 4.0 * sector(std::f64::consts::PI / 3.0);
    assert!((pad.volume() - volume).abs() < 0.01 * volume, "{}", pad.volume());
}

/// A curved 3D contact face from Gmsh runs with both solvers, and they agree.
#[test]
fn a_curved_3d_gmsh_case_runs_with_both_solvers_and_they_agree() {
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pad3d.toml");
    let mesh = meshes().join("pad3d_coarse.msh");
    let load = |kind: SolverKind| {
        let file = format!("mesh.file={:?}", mesh.to_str().unwrap());
        let kind = format!("solver.kind={}", kind.name());
        Scenario::load_file(&scenario, &[file, kind, "time.steps=8".into()]).unwrap()
    };
    let (paper_summary, paper) = load(SolverKind::Paper).run_quiet().unwrap();
    let (fast_summary, fast) = load(SolverKind::Fast).run_quiet().unwrap();
    let slips: Vec<usize> = paper_summary.outputs.iter().map(|o| o.slip_nodes).collect();
    assert!(slips.iter().any(|&s| s > 0), "the pad slips: {slips:?}");
    for (p, f) in paper_summary.outputs.iter().zip(&fast_summary.outputs) {
        assert_eq!((p.slip_nodes, p.stick_nodes), (f.slip_nodes, f.stick_nodes));
    }
    let scale = paper.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let du = paper
        .u
        .iter()
        .zip(&fast.u)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(du < 1e-5 * scale, "displacements differ by {du:e} (scale {scale:e})");
    let dt = paper
        .theta
        .iter()
        .zip(&fast.theta)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(dt < 1e-5 * 25.0, "temperatures differ by {dt:e}");
}

/// `thermocontact run scenarios/brake_shoe.toml` writes the VTK series, the contact CSVs with
/// each node's normal (radial on the lining), and a summary with slip counts.
#[test]
fn the_2d_showcase_runs_from_the_command_line() {
    let out = scratch("shoe-out");
    let _ = std::fs::remove_dir_all(&out);
    let scenario = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/brake_shoe.toml");
    let result = Command::new(env!("CARGO_BIN_EXE_thermocontact"))
        .args(["run", scenario, "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let last = summary["outputs"].as_array().unwrap().last().unwrap().clone();
    assert!(last["slip_nodes"].as_u64().unwrap() > 0, "{last}");
    assert_eq!(
        std::fs::read_to_string(out.join("solution.pvd"))
            .unwrap()
            .matches("<DataSet")
            .count(),
        4
    );
    let csv = std::fs::read_to_string(out.join("contact_0040.csv")).unwrap();
    for row in csv.lines().skip(1) {
        let v: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
        // The lining is the circle r = 10 about the origin: ν = −x/r (towards the axis).
        let r = v[0].hypot(v[1]);
        assert!(
            (v[2] + v[0] / r).abs() < 0.02 && (v[3] + v[1] / r).abs() < 0.02,
            "{row}"
        );
    }
}

/// Parts that share facets (one facet in two physical groups) cannot both take roles, and a
/// symmetry plane must be flat.
#[test]
fn overlapping_parts_and_curved_symmetry_planes_are_refused() {
    use thermocontact::model::{ProblemBuilder, TimeGrid};
    let r = mesh::rectangle(4.0, 1.0, 4, 1);
    let bottom = r.part_index("bottom").unwrap();
    let mut facets = r.facets.clone();
    let mut facet_parts = r.facet_parts.clone();
    for f in (0..r.n_facets()).filter(|&f| r.facet_parts[f] == bottom) {
        facets.extend_from_slice(r.facet(f));
        facet_parts.push(4);
    }
    let mut names = r.part_names.clone();
    names.push("bottom again".into());
    let twice = Mesh::new(2, r.coords.clone(), r.cells.clone(), facets, facet_parts, names).unwrap();
    let material = thermocontact::material::Material {
        density: 1.0,
        heat_capacity: 1.0,
        viscosity: thermocontact::material::Isotropic::viscosity(1.0, 1.0),
        elasticity: thermocontact::material::Isotropic::elasticity(1.0, 0.3),
        expansion: 0.0,
        conductivity: 1.0,
        reference_temperature: 0.0,
    };
    let e = ProblemBuilder::new(twice, material, TimeGrid::new(1.0, 1))
        .contact(&["bottom", "bottom again"])
        .build()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`bottom`") && e.contains("`bottom again`") && e.contains("share"),
        "{e}"
    );

    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/brake_shoe.toml");
    let s = Scenario::load_file(
        &scenario,
        &[
            r#"boundary.neumann=["tip"]"#.into(),
            r#"boundary.symmetry=["back"]"#.into(),
            "loads.pressure=[]".into(),
        ],
    )
    .unwrap();
    let e = s.build().unwrap_err().to_string();
    assert!(e.contains("boundary.symmetry") && e.contains("back"), "{e}");
}
