"""thermocontact: dynamic frictional contact of thermo-viscoelastic bodies with velocity-weakening
friction, the finite-element scheme of Bartosz, Danan & Szafraniec, Comput. Math. Appl. 73 (2017)
727-746, computed in Rust, driven from Python with NumPy arrays in and out.

    import thermocontact as tc

    sc = tc.Scenario.default()                  # the paper's Section 6 example
    sc["mesh.nx"], sc["mesh.ny"] = 64, 16       # any key by dotted path, checked as --set is
    sim = tc.Simulation(sc)                     # assembles the discrete problem
    result = sim.run()                          # all N steps (out="dir" writes the CLI's files)
    result.outputs[-1].u                        # (n_nodes, 2) displacement at T
    result.summary["outputs"][-1]["slip_nodes"]

    for state in sim.steps():                   # step by step; break stops the time loop
        print(state.n, state.info.newton_iterations, state.contact.slip_count)

Classes: Scenario, Mesh, Simulation, RunResult, Steps, State, Contact, StepInfo; errors:
Error and its subclasses ScenarioError, MeshError, SolverError, FileError, Interrupted, each with
the message the command line prints.
"""

from ._thermocontact import (
    DEFAULT_TOML,
    Contact,
    Error,
    FileError,
    Interrupted,
    Mesh,
    MeshError,
    RunResult,
    Scenario,
    ScenarioError,
    Simulation,
    SolverError,
    State,
    StepInfo,
    Steps,
    __version__,
)

__all__ = [
    "DEFAULT_TOML",
    "Contact",
    "Error",
    "FileError",
    "Interrupted",
    "Mesh",
    "MeshError",
    "RunResult",
    "Scenario",
    "ScenarioError",
    "Simulation",
    "SolverError",
    "State",
    "StepInfo",
    "Steps",
    "__version__",
    "run",
]


def run(scenario=None, *, out=None, progress=False, log=False):
    """Builds and runs a scenario (the default one if None): Simulation(scenario).run(...).

    out -- a folder for the command line's files (VTK, contact CSVs, summary.json), or None;
    progress, log -- the command line's progress bar and cutback lines on stderr.
    Returns a RunResult.
    """
    if scenario is None:
        scenario = Scenario.default()
    return Simulation(scenario).run(out=out, progress=progress, log=log)
