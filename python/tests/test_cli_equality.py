"""A run from Python is the command line's run: the same summary, the same files byte for byte,
and arrays equal to what the files hold (CSV numbers round-trip exactly, VTU arrays are binary).
"""

import json

import numpy as np
import pytest

import thermocontact as tc
from conftest import COARSE, REPOSITORY, sets

# The summary's entries that measure the machine or name the run, not the computation.
MACHINE = {"timings", "peak_memory_mib", "run_id"}
# Files that hold such entries (compared apart) or the folder's lock.
APART = {"summary.json", "steps.csv", ".thermocontact.lock"}


def computed(summary):
    return {k: v for k, v in summary.items() if k not in MACHINE}


def files(folder):
    return sorted(p.name for p in folder.iterdir())


def compare_with_cli(cli, tmp_path, scenario, cli_args):
    """Runs `scenario` from Python with output files and the CLI with `cli_args`; checks that
    both wrote the same files, and that the arrays handed out equal the files."""
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    cli("run", *cli_args, "--quiet", "--out", cli_dir)
    result = tc.Simulation(scenario).run(out=py_dir)

    assert files(py_dir) == files(cli_dir)
    cli_summary = json.loads((cli_dir / "summary.json").read_text())
    py_summary = json.loads((py_dir / "summary.json").read_text())
    assert computed(py_summary) == computed(cli_summary)
    assert computed(result.summary) == computed(py_summary)
    for name in files(cli_dir):
        if name not in APART:
            assert (py_dir / name).read_bytes() == (cli_dir / name).read_bytes(), name
    # steps.csv: every column but the step's wall time; and the figures of each step handed
    # out by steps() are the same.
    steps = {}
    for folder in (cli_dir, py_dir):
        lines = (folder / "steps.csv").read_text().splitlines()
        header = lines[0].split(",")
        keep = [i for i, column in enumerate(header) if column != "seconds"]
        steps[folder] = [[line.split(",")[i] for i in keep] for line in lines]
    assert steps[py_dir] == steps[cli_dir]
    columns = ["convexification", "inner", "newton", "descent_sweeps", "substeps", "cutback_depth"]
    table = {row[0]: dict(zip(steps[cli_dir][0], row)) for row in steps[cli_dir][1:]}
    for state in tc.Simulation(scenario).steps():
        info = state.info
        figures = [info.convexification_iterations, info.inner_iterations, info.newton_iterations,
                   info.descent_sweeps, info.substeps, info.cutback_depth]
        assert [int(table[str(state.n)][c]) for c in columns] == figures, state.n

    for state in result.outputs:
        csv = cli_dir / f"contact_{state.n:04d}.csv"
        header = csv.read_text().splitlines()[0].split(",")
        assert header == state.contact.columns
        table = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
        assert np.array_equal(table, state.contact.table())
    return result, cli_dir


def test_the_paper_example_on_a_coarse_grid_equals_the_cli(cli, tmp_path, coarse):
    result, cli_dir = compare_with_cli(cli, tmp_path, coarse, sets(COARSE))
    assert [o["n"] for o in result.summary["outputs"]] == [4, 8, 12, 16]
    meshio = pytest.importorskip("meshio")
    for state in result.outputs:
        frame = meshio.read(cli_dir / f"solution_{state.n:04d}.vtu")
        # 2D vectors are written as 3-vectors with z = 0.
        assert np.array_equal(frame.point_data["displacement"][:, :2], state.u)
        assert np.array_equal(frame.point_data["velocity"][:, :2], state.w)
        assert np.array_equal(frame.point_data["temperature"].ravel(), state.theta)
        assert np.array_equal(frame.cell_data["stress"][0], state.stress)


def test_a_scenario_file_with_a_gmsh_mesh_equals_the_cli(cli, tmp_path):
    path = REPOSITORY / "scenarios" / "brake_shoe.toml"
    overrides = {"time.steps": 8}
    scenario = tc.Scenario.load(path, overrides)
    compare_with_cli(cli, tmp_path, scenario, [path, *sets(overrides)])


def test_the_3d_example_equals_the_cli(cli, tmp_path):
    path = REPOSITORY / "scenarios" / "paper3d.toml"
    overrides = {"mesh.nx": 8, "mesh.ny": 2, "mesh.nz": 2, "time.steps": 4}
    scenario = tc.Scenario.load(path, overrides)
    result, _ = compare_with_cli(cli, tmp_path, scenario, [path, *sets(overrides)])
    assert result.last.stress.shape[1] == 6


def test_errors_carry_the_cli_message(cli):
    for key, value in [("material.poisson", "0.7"), ("mesh.nxx", "3"), ("boundary.contact", '["middle"]')]:
        completed = cli("run", "--quiet", "--out", "/nonexistent/never", "--set", f"{key}={value}", check=False)
        assert completed.returncode != 0
        with pytest.raises(tc.ScenarioError) as raised:
            tc.Scenario(overrides={key: json.loads(value)})
        assert f"error: {raised.value}" in completed.stderr
