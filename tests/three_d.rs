//! Three dimensions: the tetrahedral P1 matrices (patch test, the six rigid-body modes, mass
//! sums), the disc friction law in the tangent plane of Γ_C, the plane-strain consistency of a
//! 3D slab with the 2D example, and the 3D scenario through the command line.

mod common;
use common::{paper_material, solve_interior};

use std::path::PathBuf;
use std::process::Command;

use thermocontact::contact::friction::{law_residual, project_to_ball, FrictionLaw, LawPoint, VelocityWeakening};
use thermocontact::fem::assembly::{assemble_matrices, boundary_weights};
use thermocontact::mesh::{cuboid, Mesh};
use thermocontact::model::contact_rows;
use thermocontact::model::State;
use thermocontact::step::StepSystem;
use thermocontact::step::{LinearSystem, StepSolver};
use thermocontact::Scenario;

const PAPER3D: &str = include_str!("../scenarios/paper3d.toml");

/// A 4 × 3 × 3 mesh of (0, 3) × (0, 2) × (0, 2) whose interior nodes are moved off the grid.
fn distorted_box() -> (Mesh, Vec<bool>) {
    let mut mesh = cuboid([3.0, 2.0, 2.0], [4, 3, 3]);
    let boundary = mesh.nodes_on(&[0, 1, 2, 3, 4, 5]);
    for (p, x) in mesh.coords.iter_mut().enumerate() {
        if !boundary[p] {
            let s = (p as f64 * 12.9898).sin() * 43758.5453;
            let r = s - s.floor() - 0.5;
            x[0] += 0.12 * r;
            x[1] -= 0.1 * (r * 1.7).sin();
            x[2] += 0.1 * (r * 2.3).cos() - 0.05;
        }
    }
    (mesh, boundary)
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn patch_test_3d_reproduces_affine_displacement_and_temperature() {
    let (mesh, boundary) = distorted_box();
    let m = assemble_matrices(&mesh, &paper_material(), &[], 0.0);
    let affine = |x: &[f64; 3]| {
        [
            0.1 + 0.3 * x[0] - 0.2 * x[1] + 0.05 * x[2],
            -0.4 + 0.05 * x[0] + 0.25 * x[1] - 0.1 * x[2],
            0.2 - 0.15 * x[0] + 0.1 * x[1] + 0.35 * x[2],
        ]
    };
    let u_exact: Vec<f64> = mesh.coords.iter().flat_map(affine).collect();
    let guess: Vec<f64> = u_exact
        .iter()
        .enumerate()
        .map(|(i, v)| if boundary[i / 3] { *v } else { 0.0 })
        .collect();
    let u = solve_interior(&m.elasticity, &boundary, 3, &guess);
    let err = max_abs_diff(&u, &u_exact);
    assert!(err < 1e-12, "elastic patch test error {err:e}");

    let theta_exact: Vec<f64> = mesh
        .coords
        .iter()
        .map(|x| 25.0 - 3.0 * x[0] + 7.0 * x[1] - 2.0 * x[2])
        .collect();
    let guess: Vec<f64> = theta_exact
        .iter()
        .zip(&boundary)
        .map(|(t, &b)| if b { *t } else { 0.0 })
        .collect();
    let theta = solve_interior(&m.conduction, &boundary, 1, &guess);
    let err = max_abs_diff(&theta, &theta_exact);
    assert!(err < 1e-12, "thermal patch test error {err:e}");

    // A constant temperature exerts no net force on interior nodes: ∫ cθ div φ_p = 0.
    let force = m.coupling.mul(&vec![25.0; mesh.n_nodes()]);
    for (p, b) in boundary.iter().enumerate() {
        if !b {
            assert!((0..3).all(|c| force[3 * p + c].abs() < 1e-10));
        }
    }
}

/// The kernel of the 3D elastic (and viscous, and strain Gram) stiffness of a free body is
/// exactly the six rigid-body modes: 3 translations and 3 infinitesimal rotations ω × x.
#[test]
fn six_rigid_body_modes_span_the_kernel_of_the_3d_stiffness() {
    let (mesh, _) = distorted_box();
    let m = assemble_matrices(&mesh, &paper_material(), &[], 0.0);
    type Mode = fn(&[f64; 3]) -> [f64; 3];
    let modes: [Mode; 6] = [
        |_| [1.0, 0.0, 0.0],
        |_| [0.0, 1.0, 0.0],
        |_| [0.0, 0.0, 1.0],
        |x| [0.0, -x[2], x[1]],
        |x| [x[2], 0.0, -x[0]],
        |x| [-x[1], x[0], 0.0],
    ];
    let scale = m.elasticity.values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let grams = thermocontact::fem::assembly::NormGrams::assemble(&mesh);
    for mode in &modes {
        let r: Vec<f64> = mesh.coords.iter().flat_map(mode).collect();
        for k in [&m.elasticity, &m.viscosity, &grams.strain] {
            let worst = k.mul(&r).iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(worst < 1e-12 * scale, "rigid mode not in the kernel: {worst:e}");
        }
    }
    // Exactly six: the seventh smallest eigenvalue is well away from zero.
    let n = m.elasticity.n_rows;
    let mut dense = faer::Mat::<f64>::zeros(n, n);
    for (r, c, v) in m.elasticity.triplets() {
        dense[(r, c)] = v;
    }
    let eig = dense.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
    let largest = eig[n - 1];
    assert!(eig[..6].iter().all(|l| l.abs() < 1e-10 * largest), "{:?}", &eig[..7]);
    assert!(eig[6] > 1e-4 * largest, "a seventh zero mode: {:?}", &eig[..7]);
}

#[test]
fn masses_volume_and_contact_weights_sum_in_3d() {
    let mesh = cuboid([40.0, 10.0, 10.0], [8, 2, 2]);
    let m = assemble_matrices(&mesh, &paper_material(), &[], 0.0);
    for c in 0..3 {
        let e: Vec<f64> = (0..mesh.n_nodes() * 3)
            .map(|i| if i % 3 == c { 1.0 } else { 0.0 })
            .collect();
        assert!((m.mass.quadratic_form(&e) - 100.0 * 4000.0).abs() < 1e-7);
    }
    let ones = vec![1.0; mesh.n_nodes()];
    assert!((m.heat_mass.quadratic_form(&ones) - 10.0 * 4000.0).abs() < 1e-8);
    // A uniform velocity has no divergence: G^T (1, 1, 1) = 0.
    let mut div = vec![0.0; mesh.n_nodes()];
    m.coupling
        .mul_transpose_add(1.0, &vec![1.0; 3 * mesh.n_nodes()], &mut div);
    assert!(div.iter().all(|v| v.abs() < 1e-10));
    // ℓ_p on the bottom face z = 0 sums to its area; the corner at the origin lies on both
    // triangles of its cell face (a third of each), an interior node on 6 triangles (one face).
    let bottom = mesh.part_index("z-").unwrap();
    let w = boundary_weights(&mesh, &[bottom]);
    assert!((w.iter().sum::<f64>() - 400.0).abs() < 1e-10);
    let cell_face = 5.0 * 5.0;
    assert!((w[0] - cell_face / 3.0).abs() < 1e-12, "{}", w[0]);
    assert!((w[1 + 9] - cell_face).abs() < 1e-12, "{}", w[10]);
}

/// The nodal law −ξ ∈ ∂j_τ(w) in the tangent plane: ξ in the disc |ξ| ≤ μ(0)S when w = 0, on its
/// boundary and opposite to the slip direction, ξ = −μ(|w|)S w/|w|, when w ≠ 0.
#[test]
fn disc_friction_law_sticks_inside_and_slips_against_the_direction() {
    let paper = VelocityWeakening {
        a: 1.0,
        b: 0.2,
        alpha: 100.0,
    };
    let at = LawPoint::default();
    let bound = |r: f64| paper.bound(150.0, &at, r);
    let law = &bound;
    // Stick: anywhere inside the disc of radius 150, not outside.
    assert_eq!(law_residual(law, &[0.0, 0.0], &[100.0, -100.0], 1e-12), 0.0);
    assert!(law_residual(law, &[0.0, 0.0], &[120.0, -100.0], 1e-12) > 1.0);
    // Slip along (3, −4)/5 at rate 0.01: ξ = −μ(0.01) S (3, −4)/5, and no other direction.
    let (w, b) = ([0.006, -0.008], bound(0.01));
    assert!(law_residual(law, &w, &[-0.6 * b, 0.8 * b], 1e-12) < 1e-12);
    assert!(law_residual(law, &w, &[-0.8 * b, 0.6 * b], 1e-12) > 0.2 * b);
    assert!(law_residual(law, &w, &[-0.6 * bound(0.0), 0.8 * bound(0.0)], 1e-12) > 1.0);
    // The fixed-point form ξ = P_g(ξ − r w) projects onto the disc, radially.
    let mut trial = [300.0, -400.0];
    project_to_ball(&mut trial, b);
    assert!((trial[0] - 0.6 * b).abs() < 1e-12 && (trial[1] + 0.8 * b).abs() < 1e-12);
}

/// The 3D example pushed obliquely (top traction with x and y parts): on Γ_C the solver's ξ
/// obeys the disc law at every node and step, and the slip directions are genuinely 2D.
#[test]
fn oblique_3d_run_obeys_the_disc_law_at_every_contact_node() {
    let scenario = Scenario::load(
        Some(PAPER3D),
        &[
            "mesh.nx=8".into(),
            "mesh.ny=2".into(),
            "mesh.nz=2".into(),
            "time.steps=8".into(),
            "loads.traction=[{part=\"z+\", constant=[0.0, 0.0, 0.0], rate=[300.0, 200.0, -800.0]}]".into(),
            // The fast solver enforces the nodal law itself to ε_conv; the paper's criteria
            // (77)–(80) are global relative increments, with the bound one iterate behind.
            "solver.kind=fast".into(),
        ],
    )
    .unwrap();
    let problem = scenario.build().unwrap();
    let system = StepSystem::new(&problem).unwrap();
    let solver = StepSolver::new(&problem, LinearSystem::Direct(system), &scenario.solver_params()).unwrap();
    let bound = |r: f64| problem.friction_bound([0.0; 3], 0.0, r);
    let law = &bound;
    let tol = scenario.solver.slip_tolerance;
    let mut state = State::initial(&problem);
    let (mut slip, mut stick, mut oblique) = (0, 0, 0);
    for _ in 0..scenario.time.steps {
        state = solver.step(&state, state.t + problem.time_step()).unwrap().0;
        for row in contact_rows(&problem, &state, tol) {
            let residual = law_residual(law, &row.w_tau, &row.xi, tol);
            assert!(
                residual <= 1e-6 * bound(0.0),
                "law violated at node {} (n = {}): {residual:e}",
                row.node,
                state.n
            );
            let speed = row.w_tau[0].hypot(row.w_tau[1]);
            let size = row.xi[0].hypot(row.xi[1]);
            if row.slip {
                slip += 1;
                let cosine = (row.xi[0] * row.w_tau[0] + row.xi[1] * row.w_tau[1]) / (size * speed);
                assert!(cosine < -1.0 + 1e-6, "ξ not opposite to the slip: cos = {cosine}");
                assert!((size - row.bound).abs() <= 1e-6 * row.bound);
                if row.w_tau[0].abs().min(row.w_tau[1].abs()) > 0.1 * speed {
                    oblique += 1;
                }
            } else {
                stick += 1;
                assert!(size <= bound(0.0) * (1.0 + 1e-9));
            }
        }
    }
    assert!(slip > 0 && stick > 0, "{slip} slip, {stick} stick");
    assert!(oblique > 0, "no slip direction with both tangential components");
}

/// Plane strain from 3D: the slab (0, 40) × (0, W) × (0, 10) with symmetry planes y = 0 and
/// y = W (w_y = 0, no shear traction, no heat flux) is the 2D example. Both are discretized on
/// meshes with the same (x, z) grid (16 × 4 cells, 2 cells across W = 5), so the two discrete
/// solutions differ only as two discretizations of one plane-strain problem (tetrahedra and
/// triangles resolve the same fields differently; the middle y layer may move in y). The data
/// are the paper's with θ_D = θ₀ = 25 °C, compatible at t = 0. Stated tolerances at T = 1 s:
///
/// * displacement: max over nodes |u₃ − u₂| ≤ 5 % of max |u₂| (measured 3.5 %; 2.3 % on
///   32 × 8 cells);
/// * velocity across the slab: max |w_y| ≤ 2 % of max |w| (measured 0.8 %);
/// * temperature: ‖θ₃ − θ₂‖_L²(Ω) ≤ 3 % of ‖θ₂‖_L²(Ω) (measured 1.4 %); pointwise the two differ by up to
///   4 °C at the contact node next to the clamped corner, where the heat exchange with the
///   foundation builds a layer √(kT/ρc_p) ≈ 0.2 m thin, far below h = 2.5 m;
/// * contact: the fraction of slipping contact nodes within 0.1 at every output time.
#[test]
fn plane_strain_slab_reproduces_the_2d_example() {
    let (nx, nz, steps) = (16, 4, 16);
    let common = [
        format!("mesh.nx={nx}"),
        format!("time.steps={steps}"),
        "boundary.temperature=25.0".to_string(),
    ];
    let mut flat: Vec<String> = common.to_vec();
    flat.push(format!("mesh.ny={nz}"));
    let scenario_2d = Scenario::load(None, &flat).unwrap();
    let mut slab = common.to_vec();
    slab.extend(
        [
            "mesh.ny=2",
            &format!("mesh.nz={nz}"),
            "geometry.lengths=[40.0, 5.0, 10.0]",
            "boundary.neumann=[\"x+\", \"z+\"]",
            "boundary.symmetry=[\"y-\", \"y+\"]",
        ]
        .map(String::from),
    );
    let scenario_3d = Scenario::load(Some(PAPER3D), &slab).unwrap();
    let (summary_2d, last_2d) = scenario_2d.run_quiet().unwrap();
    let (summary_3d, last_3d) = scenario_3d.run_quiet().unwrap();
    let problem_2d = scenario_2d.build().unwrap();
    let problem_3d = scenario_3d.build().unwrap();

    let max_abs = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0f64, |a, x| a.max(x.abs()));
    let w_y = max_abs(&mut last_3d.w.chunks_exact(3).map(|v| v[1]));
    let w_scale = max_abs(&mut last_3d.w.iter().copied());
    // Node (i, k) of the 2D mesh is node (i, j, k) of the slab for every j; θ₂ extruded.
    let (mut du, mut theta_2d_extruded) = (0.0f64, vec![0.0; problem_3d.mesh.n_nodes()]);
    for (p, x) in problem_3d.mesh.coords.iter().enumerate() {
        let q = problem_2d
            .mesh
            .coords
            .iter()
            .position(|y| (y[0] - x[0]).abs() < 1e-9 && (y[1] - x[2]).abs() < 1e-9)
            .unwrap();
        du = du.max((last_3d.u[3 * p] - last_2d.u[2 * q]).abs());
        du = du.max((last_3d.u[3 * p + 2] - last_2d.u[2 * q + 1]).abs());
        theta_2d_extruded[p] = last_2d.theta[q];
    }
    let u_scale = max_abs(&mut last_2d.u.iter().copied());
    let heat_mass = &problem_3d.matrices.heat_mass; // ρc_p ∫ θη: the L² norm up to a factor
    let diff: Vec<f64> = last_3d
        .theta
        .iter()
        .zip(&theta_2d_extruded)
        .map(|(a, b)| a - b)
        .collect();
    let dtheta = (heat_mass.quadratic_form(&diff) / heat_mass.quadratic_form(&theta_2d_extruded)).sqrt();
    eprintln!(
        "plane strain: max |u₃ − u₂| = {du:.3e} of max |u₂| = {u_scale:.3e}; max |w_y| = {w_y:.3e} of \
         max |w| = {w_scale:.3e}; ‖θ₃ − θ₂‖/‖θ₂‖ = {dtheta:.3e}"
    );
    assert!(du <= 0.05 * u_scale, "displacements differ by {du:e} of {u_scale:e}");
    assert!(w_y <= 0.02 * w_scale, "the slab moves across: {w_y:e} of {w_scale:e}");
    assert!(dtheta <= 0.03, "temperatures differ by {dtheta:e} (relative L²)");
    for (a, b) in summary_2d.outputs.iter().zip(&summary_3d.outputs) {
        let fraction =
            |o: &thermocontact::driver::OutputRecord| o.slip_nodes as f64 / (o.slip_nodes + o.stick_nodes) as f64;
        eprintln!(
            "t = {}: slip fraction 2D {:.3}, 3D {:.3}",
            a.t,
            fraction(a),
            fraction(b)
        );
        assert!((fraction(a) - fraction(b)).abs() <= 0.1, "t = {}", a.t);
    }
}

#[test]
fn symmetry_planes_shape_the_space_and_bad_ones_are_named() {
    let slab = Scenario::load(
        Some(PAPER3D),
        &[
            "mesh.nx=4".into(),
            "mesh.ny=2".into(),
            "mesh.nz=2".into(),
            "boundary.neumann=[\"x+\", \"z+\"]".into(),
            "boundary.symmetry=[\"y-\", \"y+\"]".into(),
        ],
    )
    .unwrap();
    assert_eq!(Scenario::load(Some(&slab.to_toml()), &[]).unwrap(), slab);
    let problem = slab.build().unwrap();
    // Nodes: 5 × 3 × 3 = 45; clamped x = 0: 9; contact (z = 0, x > 0): 12 of which 8 on a
    // y face (1 unknown: w_x) and 4 inside (2); symmetry-only nodes (y face, z > 0, x > 0):
    // 16 (2 unknowns); the rest: 8 interior-in-y nodes (3 unknowns).
    assert_eq!(problem.contact.len(), 12);
    assert_eq!(problem.velocity.n_free, 8 + 2 * 4 + 2 * 16 + 3 * 8);
    let held = problem.contact.iter().filter(|c| c.tangent_dofs[1].is_none()).count();
    assert_eq!(held, 8);
    // A held node slides along x, the line the contact face and the symmetry plane share.
    for c in problem.contact.iter().filter(|c| c.tangent_dofs[1].is_none()) {
        assert!((c.tangents[0][0].abs() - 1.0).abs() < 1e-15, "{:?}", c.tangents);
    }

    let e = Scenario::load(Some(PAPER3D), &["boundary.symmetry=[\"z-\"]".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("boundary.symmetry") && e.contains("z-"), "{e}");
    let e = Scenario::load(Some(PAPER3D), &["initial.velocity=[0.0, 0.0]".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("initial.velocity") && e.contains("3 components"), "{e}");
    let e = Scenario::load(Some(&PAPER3D.replace("nz = 10", "")), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("mesh.nz"), "{e}");
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thermocontact-3d-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `thermocontact run scenarios/paper3d.toml` (coarsened) writes tetrahedral VTK files, contact
/// CSVs with two tangential components, and a summary whose slip counts match the CSVs.
#[test]
fn paper3d_scenario_runs_from_the_command_line() {
    let out = scratch("run");
    let scenario = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/paper3d.toml");
    let result = Command::new(env!("CARGO_BIN_EXE_thermocontact"))
        .args(["run", scenario, "--quiet", "--set", "mesh.nx=8", "--set", "mesh.ny=2"])
        .args(["--set", "mesh.nz=2", "--set", "time.steps=8", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(stdout.contains("slip") && stdout.contains("stick"), "{stdout}");
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["dim"], 3);
    assert_eq!(summary["elements"], 6 * 8 * 2 * 2);
    for o in summary["outputs"].as_array().unwrap() {
        let n = o["n"].as_u64().unwrap();
        let csv = std::fs::read_to_string(out.join(format!("contact_{n:04}.csv"))).unwrap();
        assert!(
            csv.starts_with("x,y,z,nu_x,nu_y,nu_z,t1_x,t1_y,t1_z,w_tau1,w_tau2,xi1,xi2,bound,slip,theta\n"),
            "{csv}"
        );
        let slip = csv
            .lines()
            .skip(1)
            .filter(|l| l.split(',').nth(14) == Some("1"))
            .count();
        assert_eq!(slip as u64, o["slip_nodes"].as_u64().unwrap());
        assert_eq!(
            csv.lines().count() - 1,
            (o["slip_nodes"].as_u64().unwrap() + o["stick_nodes"].as_u64().unwrap()) as usize
        );
        let vtu = out.join(format!("solution_{n:04}.vtu"));
        let vtk = vtkio::Vtk::import(&vtu).unwrap();
        let vtkio::model::DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
            panic!("not an unstructured grid");
        };
        let piece = pieces[0].load_piece_data(None).unwrap();
        assert!(piece.cells.types.iter().all(|t| *t == vtkio::model::CellType::Tetra));
        assert_eq!(piece.cells.types.len(), 6 * 8 * 2 * 2);
    }
    // The resolved 3D scenario is saved and loads back to the same scenario.
    let saved = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    let expected = Scenario::load(
        Some(PAPER3D),
        &["mesh.nx=8", "mesh.ny=2", "mesh.nz=2", "time.steps=8"].map(String::from),
    )
    .unwrap();
    assert_eq!(Scenario::load(Some(&saved), &[]).unwrap(), expected);
    std::fs::remove_dir_all(&out).ok();
}
