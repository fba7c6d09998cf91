//! Material regions (issue 25, item 3): cells of a Gmsh physical group of dimension d take their
//! own material. Two closed forms of layered bodies (steady conduction through two
//! conductivities, a bar of two Young's moduli under axial traction), the bits of a run whose one
//! region repeats `[material]`, the reader and writer of cell regions, and the errors.

use thermocontact::contact::{QuadraticExchange, Tresca};
use thermocontact::driver::{run_quiet, OutputPlan};
use thermocontact::loads::Datum;
use thermocontact::material::{Isotropic, Material};
use thermocontact::mesh::{self, msh_text, read_msh, CellRegion, Mesh};
use thermocontact::model::{LoadTarget, ModelError, ProblemBuilder, TimeGrid};
use thermocontact::{Scenario, SolverParams};

/// A material with no thermal expansion (the fields decouple), ρ and c_p small against the
/// steps (the motion overdamped: its slowest mode relaxes in μ₂/E).
fn material(conductivity: f64, young: f64) -> Material {
    Material {
        density: 1e-4,
        heat_capacity: 1e-3,
        viscosity: Isotropic::viscosity(0.0, 1.0),
        elasticity: Isotropic::elasticity(young, 0.0),
        expansion: 0.0,
        conductivity,
        reference_temperature: 0.0,
    }
}

/// The rectangle [0, length] × [0, height] in `nx` × `ny` cells with the regions `first`
/// (x < interface) and `second` (x > interface): the interface on a column of nodes.
fn layered(length: f64, height: f64, nx: usize, ny: usize, interface: f64) -> Mesh {
    let m = mesh::rectangle(length, height, nx, ny);
    let (mut first, mut second) = (Vec::new(), Vec::new());
    for e in 0..m.n_cells() {
        let x = m.cell_coords(e).iter().map(|p| p[0]).sum::<f64>() / 3.0;
        if x < interface { &mut first } else { &mut second }.push(e as u32);
    }
    m.with_regions(vec![
        CellRegion {
            name: "first".into(),
            cells: first,
        },
        CellRegion {
            name: "second".into(),
            cells: second,
        },
    ])
    .unwrap()
}

/// Steady conduction through two layers, θ = 0 on the left face (Γ_D) and the exchange
/// k_e (θ − θ_R) on the right face (Γ_C), the rest insulated: the flux through the series of
/// resistances a/k₁ + (L − a)/k₂ + 1/k_e is q = θ_R / (a/k₁ + (L − a)/k₂ + 1/k_e), and θ is
/// piecewise linear, q x/k₁ up to the interface, then of slope q/k₂. The P1 space holds that
/// profile (the interface is a column of nodes), so the discrete steady state is it to round-off:
/// checked at every node to 10⁻⁹ of θ_R. (One conductivity for both layers would miss the
/// interface temperature by 45 %.)
#[test]
fn steady_conduction_through_two_layers_matches_the_series_resistances() {
    // The structured rectangle with its layers, and Gmsh's unstructured one (tests/meshes/layers.geo).
    for mesh in [
        layered(2.0, 0.5, 16, 2, 0.5),
        read_msh(&meshes().join("layers_41.msh")).unwrap(),
    ] {
        conduction_through_layers(mesh);
    }
}

fn conduction_through_layers(mesh: Mesh) {
    let (length, interface, k1, k2, k_e, theta_r) = (2.0, 0.5, 1.0, 4.0, 2.0, 10.0);
    // Diffusion time ρ c_p L²/k ≈ 4·10⁻⁷ against steps of 0.05: steady after a step or two.
    let problem = ProblemBuilder::new(mesh, material(k1, 100.0), TimeGrid::new(1.0, 20))
        .region("second", material(k2, 100.0))
        .dirichlet(&["left"])
        .contact(&["right"])
        .friction(0.0, Tresca)
        .heat_exchange(QuadraticExchange {
            coefficient: k_e,
            foundation_temperature: theta_r,
        })
        .build()
        .unwrap();
    let (_, state) = run_quiet(&problem, &SolverParams::default(), &OutputPlan::default()).unwrap();
    let q = theta_r / (interface / k1 + (length - interface) / k2 + 1.0 / k_e);
    let exact = |x: f64| {
        if x <= interface {
            q * x / k1
        } else {
            q * interface / k1 + q * (x - interface) / k2
        }
    };
    let mut worst: f64 = 0.0;
    for (p, x) in problem.mesh.coords.iter().enumerate() {
        worst = worst.max((state.theta[p] - exact(x[0])).abs());
    }
    assert!(worst < 1e-9 * theta_r, "max |θ − θ_exact| = {worst:e}");
    let at_interface = (problem.mesh.coords.iter().zip(&state.theta))
        .find(|(x, _)| (x[0] - interface).abs() < 1e-12)
        .map(|(_, t)| *t)
        .unwrap();
    assert!(
        (at_interface - q * interface / k1).abs() < 1e-9 * theta_r,
        "θ(a) = {at_interface}"
    );
}

/// A bar of two materials, clamped at x = 0, on a frictionless roller (Γ_C, bottom), pulled by
/// the traction p on x = L, Poisson ratio 0 (uniaxial): in the static limit (the viscosity damps
/// the motion, ρ small: steps of 0.1 against the relaxation time μ₂/E = 10⁻²) u_x = p x/E₁ up to the
/// interface, and the elongation is the series springs' p (a/E₁ + (L − a)/E₂). Checked at every
/// node to 10⁻⁹ of the elongation.
#[test]
fn a_bar_of_two_materials_stretches_as_two_springs_in_series() {
    let (length, interface, e1, e2, p) = (4.0, 1.5, 100.0, 300.0, 2.0);
    let mesh = layered(length, 0.5, 16, 2, interface);
    let problem = ProblemBuilder::new(mesh, material(1.0, e1), TimeGrid::new(4.0, 40))
        .region("second", material(1.0, e2))
        .dirichlet(&["left"])
        .neumann(&["right"])
        .contact(&["bottom"])
        .friction(0.0, Tresca)
        .load(LoadTarget::Traction("right".into()), Datum::Constant(vec![p, 0.0]))
        .build()
        .unwrap();
    let (_, state) = run_quiet(&problem, &SolverParams::default(), &OutputPlan::default()).unwrap();
    let elongation = p * (interface / e1 + (length - interface) / e2);
    let exact = |x: f64| {
        if x <= interface {
            p * x / e1
        } else {
            p * interface / e1 + p * (x - interface) / e2
        }
    };
    let mut worst: f64 = 0.0;
    for (node, x) in problem.mesh.coords.iter().enumerate() {
        worst = worst.max((state.u[2 * node] - exact(x[0])).abs());
        worst = worst.max(state.u[2 * node + 1].abs());
    }
    assert!(
        worst < 1e-9 * elongation,
        "max |u − u_exact| = {worst:e} (δ = {elongation})"
    );
}

/// A scenario on the layered mesh, with `extra` TOML after the default's keys.
fn scenario(mesh: &Mesh, extra: &str, overrides: &[&str]) -> Result<Scenario, thermocontact::Error> {
    let text = format!(
        "[boundary]\ndirichlet = [\"left\"]\nneumann = [\"top\", \"right\"]\ncontact = [\"bottom\"]\n\
         [[loads.traction]]\npart = \"top\"\nconstant = [0.0, 0.0]\nrate = [0.0, -800.0]\n\
         [material]\nreference_temperature = 5.0\n{extra}"
    );
    let mut all = vec!["time.steps=6".to_string()];
    all.extend(overrides.iter().map(|s| s.to_string()));
    Scenario::load_with_mesh(Some(&text), &all, mesh.clone())
}

/// Bits of a run's fields.
fn bits(state: &thermocontact::model::State) -> Vec<u64> {
    state
        .u
        .iter()
        .chain(&state.w)
        .chain(&state.theta)
        .map(|v| v.to_bits())
        .collect()
}

/// `[[regions]]` whose materials repeat `[material]` (both regions, so covering every cell;
/// one region over part of the body) give the bits of the run without them, θ_ref ≠ 0 (the
/// reference load) included; a region with another conductivity does not (the test can fail).
#[test]
fn regions_that_repeat_the_material_give_the_same_bits() {
    let mesh = layered(40.0, 10.0, 16, 4, 10.0);
    let (_, plain) = scenario(&mesh, "", &[]).unwrap().run_quiet().unwrap();
    for extra in [
        "[[regions]]\npart = \"first\"\n[[regions]]\npart = \"second\"\nreference_temperature = 5.0\n",
        "[[regions]]\npart = \"second\"\n",
    ] {
        let (_, same) = scenario(&mesh, extra, &[]).unwrap().run_quiet().unwrap();
        assert_eq!(bits(&plain), bits(&same), "{extra}");
    }
    let other = "[[regions]]\npart = \"second\"\nconductivity = 0.2\n";
    let (_, changed) = scenario(&mesh, other, &[]).unwrap().run_quiet().unwrap();
    assert_ne!(bits(&plain), bits(&changed));
}

/// The reference load θ_ref G 1 assembled cell by cell equals the one-material product when the
/// regions' materials differ only in what the load does not see (c_p).
#[test]
fn the_reference_load_per_cell_matches_the_one_material_product() {
    let mesh = layered(4.0, 1.0, 8, 2, 1.0);
    let mut base = material(1.0, 100.0);
    base.expansion = -7.5;
    base.reference_temperature = 3.0;
    let mut other = base;
    other.heat_capacity = 2.0;
    let build = |regions: bool| {
        let mut b = ProblemBuilder::new(mesh.clone(), base, TimeGrid::new(1.0, 1))
            .dirichlet(&["left"])
            .contact(&["bottom"]);
        if regions {
            b = b.region("second", other);
        }
        b.build().unwrap()
    };
    let (one, two) = (build(false), build(true));
    assert!(two.materials.uniform_material().is_none());
    let (f1, f2) = (one.force(0.0).unwrap(), two.force(0.0).unwrap());
    let scale = f1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(scale > 0.0);
    for (a, b) in f1.iter().zip(&f2) {
        assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
    }
}

#[test]
fn a_region_the_mesh_lacks_is_an_error_listing_the_mesh_regions() {
    let mesh = layered(4.0, 1.0, 8, 2, 1.0);
    let e = ProblemBuilder::new(mesh.clone(), material(1.0, 1.0), TimeGrid::new(1.0, 1))
        .region("lining", material(2.0, 1.0))
        .dirichlet(&["left"])
        .build()
        .unwrap_err();
    assert!(matches!(e, ModelError::UnknownRegion { .. }), "{e}");
    let e = e.to_string();
    assert!(
        e.contains("lining") && e.contains("first") && e.contains("second"),
        "{e}"
    );

    let e = scenario(&mesh, "[[regions]]\npart = \"lining\"\n", &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("regions[0].part") && e.contains("lining") && e.contains("second"),
        "{e}"
    );
    // The generators' meshes have none.
    let e = Scenario::load(Some("[[regions]]\npart = \"lining\"\n"), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("regions[0].part") && e.contains("has none"), "{e}");
}

#[test]
fn a_cell_in_two_regions_given_materials_is_an_error_naming_it() {
    let m = mesh::rectangle(4.0, 1.0, 4, 1);
    let all: Vec<u32> = (0..m.n_cells() as u32).collect();
    let mesh = m
        .with_regions(vec![
            CellRegion {
                name: "lining".into(),
                cells: all[..5].to_vec(),
            },
            CellRegion {
                name: "backplate".into(),
                cells: all[4..].to_vec(),
            },
        ])
        .unwrap();
    let e = ProblemBuilder::new(mesh.clone(), material(1.0, 1.0), TimeGrid::new(1.0, 1))
        .region("lining", material(2.0, 1.0))
        .region("backplate", material(3.0, 1.0))
        .build()
        .unwrap_err();
    assert!(
        matches!(&e, ModelError::CellInTwoRegions { cell: 4, first, second, .. } if first == "lining" && second == "backplate"),
        "{e}"
    );
    // One of the two given a material is fine: the other merely exists in the file.
    ProblemBuilder::new(mesh.clone(), material(1.0, 1.0), TimeGrid::new(1.0, 1))
        .region("lining", material(2.0, 1.0))
        .dirichlet(&["left"])
        .contact(&["bottom"])
        .build()
        .unwrap();
    let extra = "[[regions]]\npart = \"lining\"\n[[regions]]\npart = \"backplate\"\nyoung = 2e5\n";
    let e = scenario(&mesh, extra, &[]).unwrap().build().unwrap_err().to_string();
    assert!(
        e.contains("regions[1].part") && e.contains("cell 4") && e.contains("lining") && e.contains("backplate"),
        "{e}"
    );
}

#[test]
fn bad_region_tables_are_errors_naming_the_key() {
    let mesh = layered(4.0, 1.0, 8, 2, 1.0);
    for (extra, key, expected) in [
        (
            "[[regions]]\npart = \"first\"\ndensty = 3.0\n",
            "regions[0].densty",
            "regions[0].density",
        ),
        (
            "[[regions]]\npart = \"first\"\n[[regions]]\npart = \"second\"\ndensity = -1.0\n",
            "regions[1].density",
            "-1",
        ),
        (
            "[[regions]]\npart = \"first\"\nyoung = \"steel\"\n",
            "regions[0].young",
            "a number",
        ),
        ("[[regions]]\nconductivity = 3.0\n", "regions[0].part", "part"),
        ("[[regions]]\npart = 3\n", "regions[0].part", "a string"),
        (
            "[[regions]]\npart = \"first\"\npoisson = 0.6\n",
            "regions[0].poisson",
            "Poisson ratio",
        ),
        (
            "[[regions]]\npart = \"first\"\n[[regions]]\npart = \"first\"\n",
            "regions[1].part",
            "one [[regions]] table",
        ),
    ] {
        let e = scenario(&mesh, extra, &[]).unwrap_err().to_string();
        assert!(e.contains(key) && e.contains(expected), "{extra}: {e}");
    }
    // And on the command line.
    let e = scenario(&mesh, "", &["regions=3"]).unwrap_err().to_string();
    assert!(e.contains("regions") && e.contains("array of tables"), "{e}");
    let e = scenario(&mesh, "", &["regions=[{part = \"first\", conductivty = 2.0}]"])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("regions[0].conductivty") && e.contains("regions[0].conductivity"),
        "{e}"
    );
}

#[test]
fn several_cell_regions_without_regions_tables_give_a_warning() {
    let mesh = layered(4.0, 1.0, 8, 2, 1.0);
    let s = scenario(&mesh, "", &[]).unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(
        s.warnings[0].contains("2 cell regions") && s.warnings[0].contains("[[regions]]"),
        "{:?}",
        s.warnings
    );
    let s = scenario(&mesh, "[[regions]]\npart = \"first\"\n", &[]).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // One region, or none (the generators): nothing to warn about.
    let one = mesh::rectangle(4.0, 1.0, 8, 2)
        .with_regions(vec![CellRegion {
            name: "pad".into(),
            cells: vec![0, 1],
        }])
        .unwrap();
    assert!(scenario(&one, "", &[]).unwrap().warnings.is_empty());
    assert!(Scenario::load(None, &[]).unwrap().warnings.is_empty());
}

/// Regions are part of the problem: `--restart` compares the fingerprints.
#[test]
fn regions_change_the_scenario_fingerprint() {
    let mesh = layered(4.0, 1.0, 8, 2, 1.0);
    let a = scenario(&mesh, "", &[]).unwrap();
    let b = scenario(&mesh, "[[regions]]\npart = \"first\"\nconductivity = 2.0\n", &[]).unwrap();
    assert_ne!(a.fingerprint(), b.fingerprint());
    let keys = thermocontact::scenario::differing_keys(&a.to_toml(), &b.to_toml());
    assert!(keys.iter().any(|k| k.starts_with("regions")), "{keys:?}");
}

fn meshes() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/meshes")
}

/// Gmsh's files of tests/meshes/layers.geo: the two surfaces are the regions `first` and
/// `second` in MSH 4.1 ASCII and binary and MSH 2.2, each cell in the layer of its centre.
#[test]
fn gmsh_cell_groups_are_read_as_regions_in_every_format() {
    let reference = read_msh(&meshes().join("layers_41.msh")).unwrap();
    for file in ["layers_41.msh", "layers_41_binary.msh", "layers_22.msh"] {
        let m = read_msh(&meshes().join(file)).unwrap();
        assert_eq!(m.region_names(), vec!["first", "second"], "{file}");
        assert_eq!(m.n_cells(), reference.n_cells(), "{file}");
        let counted: usize = m.regions.iter().map(|r| r.cells.len()).sum();
        assert_eq!(counted, m.n_cells(), "{file}: every cell in one region");
        for (r, region) in m.regions.iter().enumerate() {
            for &e in &region.cells {
                let x = m.cell_coords(e as usize).iter().map(|p| p[0]).sum::<f64>() / 3.0;
                assert_eq!(x < 0.5, r == 0, "{file}: cell {e} at x = {x}");
            }
        }
    }
    // Every cell also in the group `slab` (layers_overlap.geo): MSH 2.2 lists such cells twice,
    // MSH 4.1 once on an entity of two groups; both read as the same cells.
    for file in ["layers_overlap_22.msh", "layers_overlap_41.msh"] {
        let m = read_msh(&meshes().join(file)).unwrap();
        assert_eq!(m.n_cells(), reference.n_cells(), "{file}");
        assert_eq!(m.region_names(), vec!["first", "second", "slab"], "{file}");
        assert_eq!(m.regions[2].cells.len(), m.n_cells(), "{file}");
        // A scenario giving materials to `slab` and `first`: refused naming a cell and both.
        let text = format!(
            "[mesh]\nfile = {:?}\n[[regions]]\npart = \"slab\"\n[[regions]]\npart = \"first\"\nyoung = 2e4\n",
            meshes().join(file).to_str().unwrap()
        );
        let e = Scenario::load(Some(&text), &[])
            .unwrap()
            .build()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("regions[1].part") && e.contains("cell") && e.contains("`slab`") && e.contains("`first`"),
            "{e}"
        );
        // Without [[regions]]: a warning that the three merge.
        let text = format!("[mesh]\nfile = {:?}\n", meshes().join(file).to_str().unwrap());
        let s = Scenario::load(Some(&text), &[]).unwrap();
        assert!(
            s.warnings.iter().any(|w| w.contains("3 cell regions")),
            "{:?}",
            s.warnings
        );
    }
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-regions-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// The writer keeps the regions (also overlapping ones, and cells in none), the reader finds
/// them again: the same regions, by the cells' nodes.
#[test]
fn cell_regions_go_through_a_file_and_back() {
    let m = mesh::rectangle(4.0, 1.0, 4, 2);
    let regions = vec![
        CellRegion {
            name: "lining".into(),
            cells: vec![0, 1, 2, 3, 4],
        },
        CellRegion {
            name: "backplate".into(),
            cells: vec![4, 5, 6, 9],
        },
    ];
    let mesh = m.with_regions(regions).unwrap();
    let path = scratch("regions.msh");
    std::fs::write(&path, msh_text(&mesh)).unwrap();
    let back = read_msh(&path).unwrap();
    // The cells in no region come back as the region `domain`.
    assert_eq!(back.region_names(), vec!["lining", "backplate", "domain"]);
    let sorted_cells = |m: &Mesh, r: usize| {
        let mut cells: Vec<Vec<usize>> = (m.regions[r].cells.iter())
            .map(|&e| {
                let mut c = m.cell(e as usize).to_vec();
                c.sort();
                c
            })
            .collect();
        cells.sort();
        cells
    };
    for r in 0..2 {
        assert_eq!(sorted_cells(&back, r), sorted_cells(&mesh, r), "region {r}");
    }
    assert_eq!(back.n_cells(), mesh.n_cells());
    // A mesh without regions comes back with one, `domain`, of every cell (the writer gives
    // every element a physical group), as msh_text wrote it before regions existed.
    let plain = mesh::rectangle(4.0, 1.0, 4, 2);
    std::fs::write(&path, msh_text(&plain)).unwrap();
    let back = read_msh(&path).unwrap();
    assert_eq!(back.region_names(), vec!["domain"]);
    assert_eq!(back.regions[0].cells.len(), plain.n_cells());
}

/// MSH 2.2 as Gmsh writes a cell in two physical groups: once per group. The repeats are one
/// cell, in both regions; cells of no group are kept.
#[test]
fn msh22_cells_listed_once_per_group_are_one_cell_in_both_regions() {
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n\
                $PhysicalNames\n3\n1 1 \"edge\"\n2 2 \"lining\"\n2 3 \"backplate\"\n$EndPhysicalNames\n\
                $Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n\
                $Elements\n5\n1 1 2 1 1 1 2\n2 2 2 2 1 1 2 3\n3 2 2 3 1 1 2 3\n4 2 2 0 1 1 3 4\n5 2 2 3 1 1 3 4\n$EndElements\n";
    let path = scratch("two_groups22.msh");
    std::fs::write(&path, text).unwrap();
    let m = read_msh(&path).unwrap();
    assert_eq!(m.n_cells(), 2);
    assert_eq!(m.region_names(), vec!["lining", "backplate"]);
    assert_eq!(m.regions[0].cells, vec![0]);
    assert_eq!(m.regions[1].cells, vec![0, 1]);
    assert_eq!(m.part_names, vec!["edge"]);
}
