"""Shared fixtures of the Python test suite.

The comparisons with the command line run the `thermocontact` binary of the same checkout: the
path in the environment variable THERMOCONTACT_CLI, else target/release/thermocontact or
target/debug/thermocontact of the repository (both are built by cargo: `cargo build --release`,
or `cargo test`, which builds the binary for its CLI tests). Without one, those tests are skipped;
with THERMOCONTACT_REQUIRE_CLI=1 (as in .ci/run) a missing binary is an error instead.
"""

import os
import pathlib
import subprocess

import pytest

import thermocontact as tc

REPOSITORY = pathlib.Path(__file__).resolve().parents[2]

# The paper's example on a coarse grid: 16 × 4 cells, 16 steps (a run takes milliseconds).
COARSE = {"mesh.nx": 16, "mesh.ny": 4, "time.steps": 16}


def _find_cli():
    given = os.environ.get("THERMOCONTACT_CLI")
    if given:
        return pathlib.Path(given).resolve()
    for profile in ("release", "debug"):
        candidate = REPOSITORY / "target" / profile / "thermocontact"
        if candidate.is_file():
            return candidate
    return None


@pytest.fixture(scope="session")
def cli():
    """A function running the command line: cli("run", "--set", ...) -> CompletedProcess."""
    binary = _find_cli()
    if binary is None or not binary.is_file():
        message = f"no thermocontact binary (THERMOCONTACT_CLI={os.environ.get('THERMOCONTACT_CLI')!r})"
        if os.environ.get("THERMOCONTACT_REQUIRE_CLI") == "1":
            pytest.fail(message)
        pytest.skip(message)

    def run(*args, check=True):
        return subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True, check=check)

    return run


@pytest.fixture
def coarse():
    """The paper's example on the coarse grid."""
    return tc.Scenario(overrides=COARSE)


def sets(overrides):
    """--set arguments of a dict of overrides."""
    args = []
    for key, value in overrides.items():
        args += ["--set", f"{key}={value}"]
    return args
