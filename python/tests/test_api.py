"""The Python API: scenarios by dotted key, meshes from arrays and files, the documented shapes
and dtypes of every array, bad input raising with the key in the message, step by step equal to
a full run, and a break stopping the time loop."""

import time

import numpy as np
import pytest

import thermocontact as tc
from conftest import COARSE, REPOSITORY

# ---------------------------------------------------------------- scenarios


def test_keys_by_dotted_path_read_and_write_the_toml(coarse):
    assert coarse["mesh.nx"] == 16 and coarse["friction.law"] == "velocity-weakening"
    assert coarse["friction"] == {"law": "velocity-weakening", "bound": 150.0, "a": 1.0, "b": 0.2, "alpha": 100.0}
    coarse["material.thermal_expansion"] = 1e-4
    coarse["output.times"] = np.array([0.5, 1.0])  # NumPy values are taken as lists and numbers
    coarse["mesh.ny"] = np.int64(2)
    assert coarse["material.thermal_expansion"] == 1e-4 and coarse["mesh.ny"] == 2
    assert coarse.output_steps == [8, 16]
    coarse["friction"] = {"law": "tresca", "bound": 100}  # a law's table set whole
    assert coarse["friction"] == {"law": "tresca", "bound": 100.0}
    coarse.update({"friction.law": "velocity-weakening", "friction.bound": 150, "friction.a": 1.0,
                   "friction.b": 0.2, "friction.alpha": 100.0})  # or key by key, at once
    assert coarse["friction.law"] == "velocity-weakening"
    assert "loads.traction" in coarse and coarse["loads.traction.0.part"] == "top"
    with pytest.raises(KeyError):
        coarse["mesh.nothing"]
    # str() is the TOML: loading it gives the same scenario.
    assert tc.Scenario(str(coarse)) == coarse
    copy = coarse.copy()
    copy.update({"time.steps": 8, "time.final_time": 0.5, "output.times": [0.5]})
    assert (copy["time.steps"], coarse["time.steps"]) == (8, 16)
    assert copy.time_step == 0.0625 and copy.dim == 2


def test_scenario_files_load_with_their_mesh():
    scenario = tc.Scenario.load(REPOSITORY / "scenarios" / "brake_shoe.toml", {"time.steps": 4})
    mesh = scenario.mesh
    assert scenario["mesh.file"].endswith("brake_shoe.msh")
    assert set(mesh.part_names) == {"lining", "back", "pivot", "tip"}


@pytest.mark.parametrize(
    "key, value, words",
    [
        ("mesh.nxx", 3, ["mesh.nxx"]),
        ("material.poisson", 0.7, ["material.poisson", "0.7", "Poisson"]),
        ("mesh.nx", "many", ["mesh.nx", "many", "integer"]),
        ("boundary.contact", ["middle"], ["boundary.contact", "middle", "bottom"]),
        ("friction.law", "amontons", ["amontons", "coulomb"]),
        ("time.steps", -4, ["time.steps", "-4"]),
        ("loads.body_force", ["0", "-10*"], ["loads.body_force"]),
        ("mesh.nx", object(), ["mesh.nx", "TOML value"]),
        ("mesh..nx", 1, ["mesh..nx"]),
    ],
)
def test_bad_input_raises_with_the_key_in_the_message(coarse, key, value, words):
    before = coarse.copy()
    with pytest.raises(tc.ScenarioError) as raised:
        coarse[key] = value
    message = str(raised.value)
    assert all(w in message for w in words), message
    assert isinstance(raised.value, ValueError) and isinstance(raised.value, tc.Error)
    assert raised.value.key == key or raised.value.key is None
    assert coarse == before  # a failed set leaves the scenario as it was


def test_invalid_value_errors_carry_key_value_and_expected(coarse):
    with pytest.raises(tc.ScenarioError) as raised:
        coarse["material.young"] = -1.0
    e = raised.value
    assert (e.key, e.value) == ("material.young", "-1.0") and e.expected.startswith("a positive number")


def test_files_that_cannot_be_read_raise_file_errors(tmp_path):
    with pytest.raises(tc.FileError) as raised:
        tc.Scenario.load(tmp_path / "missing.toml")
    assert "missing.toml" in str(raised.value) and isinstance(raised.value, OSError)
    with pytest.raises(tc.MeshError, match="nothing.msh"):
        tc.Mesh.read(tmp_path / "nothing.msh")


# ---------------------------------------------------------------- meshes


def renamed_rectangle(nx=16, ny=4):
    """The default scenario's rectangle, from arrays, with parts named otherwise."""
    r = tc.Mesh.rectangle(40.0, 10.0, nx, ny)
    b = r.boundary
    return tc.Mesh(r.points, r.cells, {"clamp": b["left"], "free": b["right"], "contact": b["bottom"], "load": b["top"]})


RENAMED = {
    "time.steps": 16,
    "boundary.dirichlet": ["clamp"],
    "boundary.neumann": ["load", "free"],
    "boundary.contact": ["contact"],
    "loads.traction": [{"part": "load", "constant": [0.0, 0.0], "rate": [0.0, -800.0]}],
}


def test_a_mesh_from_arrays_runs_as_the_generated_one(coarse):
    mesh = renamed_rectangle()
    assert (mesh.dim, mesh.n_nodes, mesh.n_cells, mesh.part_names) == (2, 85, 128, ["clamp", "free", "contact", "load"])
    scenario = tc.Scenario.default().with_mesh(mesh, RENAMED)
    assert "given in memory" in str(scenario) and scenario.mesh.n_cells == 128
    given = tc.Simulation(scenario).run()
    generated = tc.Simulation(coarse).run()
    assert np.array_equal(given.last.u, generated.last.u)
    assert np.array_equal(given.slip_counts, generated.slip_counts)
    # Keys set later keep the mesh.
    scenario["time.steps"] = 8
    assert tc.Simulation(scenario).n_steps == 8 and scenario.mesh.part_names == mesh.part_names


def test_points_with_a_zero_z_column_and_int32_cells_are_taken():
    r = tc.Mesh.rectangle(2.0, 1.0, 2, 1)
    points = np.column_stack([r.points, np.zeros(r.n_nodes)])
    mesh = tc.Mesh(points, r.cells.astype(np.int32), {k: v.astype(np.uint16) for k, v in r.boundary.items()})
    assert np.array_equal(mesh.points, r.points) and mesh.volume() == pytest.approx(2.0)


@pytest.mark.parametrize(
    "change, words",
    [
        (lambda p, c, b: (p, c[:, :2], b), ["cells", "(m, 3)"]),
        (lambda p, c, b: (p, -c, b), ["negative node index"]),
        (lambda p, c, b: (p, c[:-2], b), ["belong to no cell"]),
        (lambda p, c, b: (p, c, {"left": b["left"][:, :1]}), ["boundary", "left", "(f, 2)"]),
        (lambda p, c, b: (p, c, {"inside": np.array([[0, 4]])}), ["inside"]),
        (lambda p, c, b: (np.column_stack([p, np.ones(len(p))]), c, b), ["off the plane z = 0"]),
        (lambda p, c, b: (p, np.vstack([c, c[:1]]), b), ["cells"]),
    ],
)
def test_bad_meshes_raise_mesh_errors_that_say_what(change, words):
    r = tc.Mesh.rectangle(2.0, 1.0, 2, 1)
    points, cells, boundary = change(r.points, r.cells, r.boundary)
    with pytest.raises(tc.MeshError) as raised:
        tc.Mesh(points, cells, boundary)
    assert all(w in str(raised.value) for w in words), str(raised.value)


def test_generated_meshes_with_degenerate_cells_raise_mesh_errors():
    # Cells 10¹² times longer than wide: an error, not a panic.
    for make in (
        lambda: tc.Mesh.rectangle(1e-6, 1e6, 128, 32),
        lambda: tc.Mesh.box([1e-4, 1.0, 1e4], [4, 2, 2]),
        lambda: tc.Mesh.annulus(1e-6, 1e6, 1, 64),
    ):
        with pytest.raises(tc.MeshError, match="degenerate"):
            make()


def test_meshio_meshes_and_msh_files_round_trip(tmp_path):
    meshio = pytest.importorskip("meshio")
    original = renamed_rectangle(4, 2)
    path = tmp_path / "rectangle.msh"
    original.write_msh(path)
    for mesh in (tc.Mesh.read(path), tc.Mesh.from_meshio(meshio.read(path))):
        assert np.array_equal(mesh.points, original.points)
        assert np.array_equal(mesh.cells, original.cells)
        assert mesh.part_names == original.part_names
        for name, facets in original.boundary.items():
            assert np.array_equal(np.sort(mesh.boundary[name], axis=None), np.sort(facets, axis=None)), name
    # Physical groups only (no cell_sets), and a node in no cell (pruned).
    m = meshio.read(path)
    points = np.vstack([m.points, [[99.0, 99.0, 0.0]]])
    bare = meshio.Mesh(points, m.cells, cell_data={"gmsh:physical": m.cell_data["gmsh:physical"]}, field_data=m.field_data)
    mesh = tc.Mesh.from_meshio(bare)
    assert mesh.n_nodes == original.n_nodes and mesh.part_names == original.part_names
    with pytest.raises(tc.MeshError, match="no cell"):
        tc.Mesh.from_meshio(bare, prune=False)


# ---------------------------------------------------------------- runs


def check_state(state, n_nodes, n_cells, n_contact, d):
    assert state.u.shape == (n_nodes, d) and state.u.dtype == np.float64
    assert state.w.shape == (n_nodes, d) and state.w.dtype == np.float64
    assert state.theta.shape == (n_nodes,) and state.theta.dtype == np.float64
    assert state.xi.shape == (n_contact, d - 1) and state.xi.dtype == np.float64
    assert state.stress.shape == (n_cells, 6) and state.stress.dtype == np.float64
    c = state.contact
    assert len(c) == n_contact
    assert c.node.shape == (n_contact,) and c.node.dtype == np.int64
    for name in ("x", "normal"):
        assert getattr(c, name).shape == (n_contact, d) and getattr(c, name).dtype == np.float64
    assert c.tangents.shape == (n_contact, d - 1, d)
    for name in ("w_tau", "xi"):
        assert getattr(c, name).shape == (n_contact, d - 1) and getattr(c, name).dtype == np.float64
    for name in ("bound", "theta"):
        assert getattr(c, name).shape == (n_contact,) and getattr(c, name).dtype == np.float64
    assert c.slip.shape == (n_contact,) and c.slip.dtype == np.bool_
    assert c.table().shape == (n_contact, len(c.columns)) and c.slip_count == int(c.slip.sum())
    assert np.array_equal(c.xi, state.xi) and np.array_equal(c.theta, state.theta[c.node])


@pytest.mark.parametrize("d", [2, 3])
def test_arrays_have_the_documented_shapes_and_dtypes(d):
    if d == 2:
        scenario = tc.Scenario(overrides=COARSE)
    else:
        overrides = {"mesh.nx": 4, "mesh.ny": 2, "mesh.nz": 2, "time.steps": 4}
        scenario = tc.Scenario.load(REPOSITORY / "scenarios" / "paper3d.toml", overrides)
    sim = tc.Simulation(scenario)
    mesh = sim.mesh
    n_contact = len(sim.contact_nodes)
    assert mesh.points.shape == (mesh.n_nodes, d) and mesh.points.dtype == np.float64
    assert mesh.cells.shape == (mesh.n_cells, d + 1) and mesh.cells.dtype == np.int64
    assert all(f.shape[1] == d and f.dtype == np.int64 for f in mesh.boundary.values())
    result = sim.run()
    assert len(result.outputs) == len(scenario.output_steps) and result.times.dtype == np.float64
    assert result.summary["status"] == "completed" and result.summary["dim"] == d
    assert result.slip_counts.dtype == np.int64
    for state in [*result.outputs, result.last, sim.initial_state()]:
        check_state(state, mesh.n_nodes, mesh.n_cells, n_contact, d)
    assert result.outputs[0].info.substeps >= 1 and result.last.info is None
    assert np.array_equal(result.last.contact.node, sim.contact_nodes)


def test_step_by_step_equals_a_full_run(coarse):
    sim = tc.Simulation(coarse)
    result = sim.run()
    states = list(sim.steps())
    assert [s.n for s in states] == list(range(1, 17))
    assert [s.t for s in states] == [n * 0.0625 for n in range(1, 17)]
    by_level = {s.n: s for s in states}
    for output in result.outputs:
        state = by_level[output.n]
        for name in ("u", "w", "theta", "xi", "stress"):
            assert np.array_equal(getattr(state, name), getattr(output, name)), name
        assert np.array_equal(state.contact.table(), output.contact.table())
        assert state.info.to_dict() == output.info.to_dict()
    assert np.array_equal(states[-1].u, result.last.u)
    summary = result.summary
    assert sum(s.info.convexification_iterations for s in states) == summary["convexification_iterations"]
    assert sum(s.info.newton_iterations for s in states) == summary["newton_iterations"]
    assert [s.contact.slip_count for s in states if s.n in (4, 8, 12, 16)] == [
        o["slip_nodes"] for o in summary["outputs"]
    ]


def test_predicted_bounds_are_counted_step_by_step(coarse):
    # solver.contact_sweeps on the iterative path: each step reports its iterates with predicted
    # bounds, and they sum to the summary's; the plain loop predicts none.
    coarse.update({"solver.linear": "iterative", "solver.contact_sweeps": 1})
    states = list(tc.Simulation(coarse).steps())
    predicted = sum(s.info.predicted_iterates for s in states)
    assert predicted > 0 and predicted == sum(s.info.to_dict()["predicted_iterates"] for s in states)
    assert predicted < sum(s.info.convexification_iterations for s in states)
    coarse["solver.contact_sweeps"] = 0
    assert all(s.info.predicted_iterates == 0 for s in tc.Simulation(coarse).steps())


def test_breaking_out_of_steps_stops_the_time_loop():
    # 4000 steps: minutes if the loop went on; a break must stop it within a step.
    sim = tc.Simulation(tc.Scenario(overrides={**COARSE, "time.steps": 4000, "output.times": [1.0]}))
    steps = sim.steps()
    clock = time.perf_counter()
    for state in steps:
        if state.n == 3:
            break
    steps.close()
    assert time.perf_counter() - clock < 5.0
    assert steps.status == "interrupted" and steps.last_step in (3, 4)
    assert list(steps) == []  # a closed iterator is exhausted
    # A dropped iterator stops its loop too (nothing to wait for: the next one runs at once).
    for state in sim.steps():
        break
    with sim.steps() as steps:
        assert next(steps).n == 1
    assert steps.status == "interrupted"


def test_a_completed_iteration_reports_its_end(coarse):
    steps = tc.Simulation(coarse).steps()
    assert steps.status == "running"
    assert sum(1 for _ in steps) == 16
    assert (steps.status, steps.last_step, steps.last_time) == ("completed", 16, 1.0)


def test_a_step_that_does_not_converge_raises_a_solver_error(coarse):
    # The paper's solver with one convexification iterate and no cutback cannot converge.
    coarse.update({"solver.kind": "paper", "solver.max_convexification": 1, "solver.cutback": False})
    sim = tc.Simulation(coarse)
    with pytest.raises(tc.SolverError) as raised:
        sim.run()
    assert raised.value.step >= 1 and "did not converge" in str(raised.value)
    steps = sim.steps()
    with pytest.raises(tc.SolverError):
        list(steps)
    assert steps.status == "failed"


def test_run_writes_the_cli_files_and_the_module_function_runs_the_default(tmp_path, coarse):
    result = tc.run(coarse, out=tmp_path)
    names = {p.name for p in tmp_path.iterdir()}
    assert {"summary.json", "scenario.toml", "solution.pvd", "contact_0016.csv"} <= names
    assert tc.Scenario((tmp_path / "scenario.toml").read_text()) == coarse
    assert result.summary["outputs"][-1]["n"] == 16


def test_a_folder_with_another_runs_results_needs_overwrite(tmp_path, coarse):
    sim = tc.Simulation(coarse)
    sim.run(out=tmp_path)
    with pytest.raises(tc.FileError):
        sim.run(out=tmp_path)
    assert sim.run(out=tmp_path, overwrite=True).summary["status"] == "completed"


def test_ctrl_c_stops_a_run_after_its_step_and_raises_keyboard_interrupt(tmp_path):
    import json
    import signal
    import subprocess
    import sys

    # The child turns Ctrl-C into KeyboardInterrupt whatever it inherits: Python installs that
    # handler only where SIGINT is not ignored, and a suite started in the background of a
    # non-interactive shell (`cmd &`) ignores it; the child would then ignore the signal and
    # finish its 100 000 steps (exit 0, no output: how this test failed in such runs).
    script = f"""
import signal
signal.signal(signal.SIGINT, signal.default_int_handler)
import thermocontact as tc
sc = tc.Scenario(overrides={{**{COARSE!r}, "time.steps": 100000, "output.times": [1.0]}})
print("running", flush=True)
try:
    tc.Simulation(sc).run(out={str(tmp_path)!r})
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
"""
    import tempfile

    # The child's stderr goes to a file (a pipe left unread could stall its log lines), read
    # back to say why where the child ends without the exception.
    with tempfile.TemporaryFile(mode="w+") as stderr:
        child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=stderr, text=True)
        assert child.stdout.readline().strip() == "running"
        time.sleep(1.0)
        child.send_signal(signal.SIGINT)
        out, _ = child.communicate(timeout=30)
        stderr.seek(0)
        assert "KeyboardInterrupt" in out, f"exit code {child.returncode}, stderr: {stderr.read()[-3000:]}"
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "interrupted" and 0 < summary["failure"]["last_step"] < 100000


# ---------------------------------------------------------------- the user's laws


def test_own_laws_by_scenario_keys(coarse):
    # One law per contact part (a list of tables), slip-distance weakening, a nonmonotone heat
    # exchange: the same keys as the TOML, the slip distance in the contact table.
    coarse["friction"] = [{"law": "slip-distance-weakening", "part": "bottom", "bound": 150.0,
                           "static": 1.0, "dynamic": 0.2, "distance": 0.002}]
    coarse["heat_exchange"] = {"law": "expression", "flux": "2*theta - 60*sin(theta/20)"}
    coarse["frictional_heating.share"] = 0.5
    result = tc.Simulation(coarse).run()
    contact = result.last.contact
    assert "slip_distance" in contact.columns
    assert contact.slip_distance.shape == (len(contact),)
    assert (contact.slip_distance >= 0).all() and contact.slip_distance.max() > 0
    assert contact.table().shape == (len(contact), len(contact.columns))
    assert result.summary["laws"]["friction"][0]["law"] == "slip-distance-weakening"
    assert result.summary["exchange_iterations"] >= coarse["time.steps"]
    # The paper's law has no slip-distance column.
    assert tc.Simulation(tc.Scenario.default()).n_steps > 0
    with pytest.raises(tc.ScenarioError) as error:
        coarse["friction"] = {"law": "table", "bound": 1.0, "slip_rate": [0.0, 0.0], "coefficient": [1.0, 0.5]}
    assert "friction.slip_rate" in str(error.value)


def test_energies_balance_at_every_step(coarse):
    # docs/energy.md: ΔK + ΔE + D_num + D_visc + D_fric + W_θ − W_F − W_found is the residual,
    # at most 1e-12 of the step's largest term on the direct path (measured: 5e-16).
    result = tc.Simulation(coarse).run()
    e = result.energy
    assert len(e["t"]) == 16 and e["kinetic"].dtype == np.float64
    lhs = e["kinetic_change"] + e["elastic_change"] + e["numerical"] + e["viscous"] + e["frictional"]
    balance = lhs + e["thermal_stress"] - e["loads"] - e["foundation"]
    assert np.all(np.abs(balance - e["residual"]) <= 1e-12 * e["scale"])
    assert np.all(np.abs(e["residual"]) <= 1e-12 * e["scale"])
    summary = result.summary
    assert summary["outcome"] == "completed" and summary["warnings"] == []
    assert summary["energy"]["max_energy_residual"] <= 1e-12
    first = result.outputs[0]
    assert first.info.energy["kinetic"] == e["kinetic"][first.n - 1]


def test_the_brake_reports_the_contact_pressure_and_the_relative_slip():
    # scenarios/brake_pad.toml, its first 0.2 s: Coulomb friction on a turning drum. The contact
    # table has the pressure (where a law scales with it) and the slip relative to the drum.
    overrides = {"time.final_time": 0.2, "time.steps": 4, "output.times": [0.2]}
    scenario = tc.Scenario.load(REPOSITORY / "scenarios" / "brake_pad.toml", overrides)
    result = tc.Simulation(scenario).run()
    contact = result.last.contact
    assert contact.pressure is not None and contact.pressure.shape == (len(contact),)
    assert np.all(contact.pressure >= 0.0) and contact.pressure.max() > 1e5
    assert "pressure" in contact.columns and contact.table().shape[1] == len(contact.columns)
    # The drum's surface moves at ω R = 60 (1 − 0.2/3) · 0.15 = 8.4 m/s; the held pad barely moves.
    assert np.allclose(np.abs(contact.w_tau[:, 0]), 8.4, rtol=1e-3)
    assert contact.slip_count == len(contact)
    mu = 0.35 + 0.1 * np.exp(-np.abs(contact.w_tau[:, 0]) / 2)
    assert np.allclose(np.abs(contact.xi[:, 0]), mu * contact.pressure, rtol=1e-5)
    # The paper's example has no pressure column.
    assert tc.Simulation(tc.Scenario(overrides=COARSE)).run().last.contact.pressure is None
