"""Input that cannot crash it (issue 26): arguments that are not what they should be raise an
error naming the argument, the value and what was expected; none truncates, casts silently,
overflows the stack or aborts the interpreter.

The calls that used to kill the interpreter (a self-referencing scenario value, a mesh of 10¹⁰
nodes) run in a child interpreter, so that a regression fails this test instead of ending the
test session.
"""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import thermocontact as tc


def run_isolated(code):
    """Runs `code` in a fresh interpreter; returns the CompletedProcess (a crash is a negative
    return code or an abort message, not an exception here)."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.fixture
def rectangle():
    return tc.Mesh.rectangle(2.0, 1.0, 2, 1)


# Finding 4: cells that are not integers, points that are not real.


def test_fractional_cell_indices_are_refused_not_truncated(rectangle):
    cells = rectangle.cells.astype(np.float64)
    cells[0, 1] += 0.7
    with pytest.raises(tc.MeshError) as raised:
        tc.Mesh(rectangle.points, cells, rectangle.boundary)
    message = str(raised.value)
    assert "cells" in message and "1.7" in message and "integer" in message, message


def test_fractional_boundary_indices_are_refused(rectangle):
    boundary = {name: facets.astype(np.float64) + 0.5 for name, facets in rectangle.boundary.items()}
    with pytest.raises(tc.MeshError, match=r"boundary\[.*\]: \d+\.5 at \[0, 0\].*integer"):
        tc.Mesh(rectangle.points, rectangle.cells, boundary)


def test_integral_float_cells_are_accepted(rectangle):
    # As numpy.loadtxt gives them: every value an integer.
    mesh = tc.Mesh(rectangle.points, rectangle.cells.astype(np.float64), rectangle.boundary)
    assert np.array_equal(mesh.cells, rectangle.cells)


@pytest.mark.parametrize("dtype", [bool, complex, str, object])
def test_cells_of_other_dtypes_are_type_errors(rectangle, dtype):
    cells = rectangle.cells.astype(dtype)
    with pytest.raises(TypeError) as raised:
        tc.Mesh(rectangle.points, cells, rectangle.boundary)
    message = str(raised.value)
    assert "cells" in message and "dtype" in message and "integer node indices" in message, message


@pytest.mark.parametrize("dtype, word", [(complex, "complex128"), (bool, "bool"), (str, "<U")])
def test_points_that_are_not_real_are_type_errors(rectangle, dtype, word):
    points = rectangle.points.astype(dtype)
    with pytest.raises(TypeError) as raised:
        tc.Mesh(points, rectangle.cells, rectangle.boundary)
    message = str(raised.value)
    assert "points" in message and word in message and "real coordinates" in message, message


def test_integer_points_are_accepted():
    points = np.array([[0, 0], [1, 0], [0, 1]])
    mesh = tc.Mesh(points, [[0, 1, 2]])
    assert mesh.points.dtype == np.float64 and mesh.volume() == pytest.approx(0.5)


def test_arrays_of_the_wrong_rank_name_the_argument(rectangle):
    with pytest.raises(tc.MeshError, match="points.*shape.*2D"):
        tc.Mesh(42, rectangle.cells)
    with pytest.raises(tc.MeshError, match="cells.*shape.*2D"):
        tc.Mesh(rectangle.points, [0, 1, 2])


def test_complex_meshio_points_are_refused():
    meshio = pytest.importorskip("meshio")
    r = tc.Mesh.rectangle(2.0, 1.0, 2, 1)
    m = meshio.Mesh(r.points.astype(complex), [("triangle", r.cells)])
    with pytest.raises(TypeError, match="points.*complex"):
        tc.Mesh.from_meshio(m)


# Finding 6: scenario values nested without end.


def test_self_referencing_and_very_deep_scenario_values_are_scenario_errors_not_crashes():
    result = run_isolated(
        """
        import thermocontact as tc
        sc = tc.Scenario.default()
        a = []
        a.append(a)
        d = {}
        d["x"] = d
        deep = 0
        for _ in range(100_000):
            deep = [deep]
        for value in (a, d, deep):
            try:
                sc["friction.slip_rate"] = value
            except tc.ScenarioError as e:
                assert e.key == "friction.slip_rate", e.key
                assert "64 levels" in str(e), str(e)
                print("refused")
        """
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.split() == ["refused"] * 3, result.stdout


def test_the_nesting_limit_is_64_levels():
    def nested(levels):
        value = 0.0
        for _ in range(levels):
            value = [value]
        return value

    sc = tc.Scenario.default()
    with pytest.raises(tc.ScenarioError) as raised:
        sc["friction.slip_rate"] = nested(66)
    assert raised.value.key == "friction.slip_rate" and "64 levels" in str(raised.value)
    # 60 levels pass the limit and meet the ordinary checks of the key (a list of numbers).
    with pytest.raises(tc.ScenarioError) as raised:
        sc["friction.slip_rate"] = nested(60)
    assert "levels" not in str(raised.value)


# Finding 7: meshes larger than the machine, refused before the allocation.


def test_a_mesh_beyond_the_memory_is_an_error_naming_the_arguments_not_an_abort():
    result = run_isolated(
        """
        import thermocontact as tc
        for make in (
            lambda: tc.Mesh.rectangle(1, 1, 10**5, 10**5),
            lambda: tc.Mesh.box([1, 1, 1], [10**4, 10**4, 10**4]),
            lambda: tc.Mesh.annulus(1, 2, 10**5, 10**5),
        ):
            try:
                make()
            except tc.MeshError as e:
                print(str(e))
        """
    )
    assert result.returncode == 0, result.stderr[-2000:]
    lines = result.stdout.splitlines()
    assert len(lines) == 3, result.stdout
    for line, call in zip(lines, ["Mesh.rectangle(", "Mesh.box(", "Mesh.annulus("]):
        assert call in line and "memory" in line and "fewer cells" in line, line
    assert "nx=100000" in lines[0] and "cells=[10000, 10000, 10000]" in lines[1]


def test_a_count_beyond_every_index_is_an_error():
    with pytest.raises(tc.MeshError, match="too many"):
        tc.Mesh.rectangle(1.0, 1.0, 2**62, 2**62)


# Finding 14: argument errors that name the argument.


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda: tc.Mesh.rectangle(1, 1, -1, 1), ["Mesh.rectangle", "nx = -1", "positive integer"]),
        (lambda: tc.Mesh.rectangle(1, 1, 4, 0), ["Mesh.rectangle", "ny = 0", "positive integer"]),
        (lambda: tc.Mesh.rectangle(1, 1, 4, 10**30), ["Mesh.rectangle", "ny = 1000000000000000000000000000000"]),
        (lambda: tc.Mesh.rectangle(-1, 1, 4, 4), ["Mesh.rectangle", "lx = -1", "positive finite length"]),
        (lambda: tc.Mesh.rectangle(1, float("nan"), 4, 4), ["Mesh.rectangle", "ly = NaN", "length"]),
        (lambda: tc.Mesh.box([1, 1, 1], [2, -2, 2]), ["Mesh.box", "cells[1] = -2", "positive integer"]),
        (lambda: tc.Mesh.box([1, 0, 1], [2, 2, 2]), ["Mesh.box", "lengths[1] = 0", "positive"]),
        (lambda: tc.Mesh.annulus(2, 1, 2, 8), ["Mesh.annulus", "outer_radius = 1", "inner_radius = 2"]),
        (lambda: tc.Mesh.annulus(1, 2, 2, 2), ["Mesh.annulus", "n_around = 2", "≥ 3"]),
    ],
)
def test_out_of_range_generator_arguments_are_named(make, words):
    with pytest.raises(tc.MeshError) as raised:
        make()
    assert isinstance(raised.value, ValueError)
    assert all(w in str(raised.value) for w in words), str(raised.value)


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda: tc.Mesh.rectangle(1, 1, 2.5, 1), ["Mesh.rectangle", "nx is a float (2.5)", "positive integer"]),
        (lambda: tc.Mesh.rectangle(1, 1, True, 1), ["Mesh.rectangle", "nx is a bool", "positive integer"]),
        (lambda: tc.Mesh.rectangle("1", 1, 2, 1), ["Mesh.rectangle", "lx is a str ('1')", "length"]),
        (lambda: tc.Mesh.rectangle(1j, 1, 2, 1), ["Mesh.rectangle", "lx is a complex", "length"]),
        (lambda: tc.Mesh.box([1, 1], [2, 2, 2]), ["Mesh.box", "lengths is a list ([1, 1])", "3 numbers"]),
        (lambda: tc.Mesh.box([1, 1, 1], 8), ["Mesh.box", "cells is an int (8)", "3 numbers"]),
        (lambda: tc.Mesh.from_meshio(42), ["Mesh.from_meshio", "mesh is an int (42)", "meshio.Mesh"]),
    ],
)
def test_generator_arguments_of_the_wrong_type_are_named_type_errors(make, words):
    with pytest.raises(TypeError) as raised:
        make()
    assert all(w in str(raised.value) for w in words), str(raised.value)


def test_numpy_integers_and_integral_lengths_are_taken():
    mesh = tc.Mesh.rectangle(np.float32(2.0), 1, np.int64(4), np.uint8(2))
    assert mesh.n_cells == 16
    assert tc.Mesh.box((1, 1, 1), np.array([1, 2, 1])).n_cells == 12


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda: tc.Scenario(overrides=42), ["Scenario", "overrides is an int (42)", "mapping"]),
        (lambda: tc.Scenario(overrides={1: 2}), ["Scenario", "key that is an int (1)", "dotted key"]),
        (lambda: tc.Scenario.default().update([("mesh.nx", 4)]), ["Scenario.update", "overrides is a list"]),
    ],
)
def test_scenario_overrides_that_are_not_mappings_are_named(make, words):
    with pytest.raises(TypeError) as raised:
        make()
    assert all(w in str(raised.value) for w in words), str(raised.value)
