"""The paper's Section 6 example from Python: the slip count on Γ_C against time.

What it solves: the built-in default scenario, Bartosz, Danan & Szafraniec (2017), Section 6 — a
40 m × 10 m viscoelastic plate clamped on the left, pressed by a traction (0, −800 t) N/m on the
top, in bilateral contact with velocity-weakening friction and frictional heating on the bottom
(Γ_C). It runs the scenario step by step (Simulation.steps()), counts the slipping contact nodes
at every step, and draws that count against time with the paper's counts as crosses (Fig. 2:
4 nodes at t = 0.25 s, 30 at t = 1 s).

    python python/examples/paper_example.py                 # 128 × 32 cells, 64 steps (~1 s)
    python python/examples/paper_example.py --nx 64         # a coarser mesh (ny = nx / 4)
    python python/examples/paper_example.py --out slip.png  # where the figure goes

Read first: thermocontact.Scenario (the keys), Simulation.steps (the loop), State.contact.
Things to try: --set material.thermal_expansion=1e-3 (the paper's Fig. 3: 33 nodes at T),
--set solver.kind=paper (the paper's own solver: the same counts, slower).
"""

import argparse
import json

import numpy as np

import thermocontact as tc

# The paper's slip counts for α_exp = 3·10⁻⁴ (Section 6, Fig. 2).
PAPER = {0.25: 4, 1.0: 30}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nx", type=int, default=128, help="cells along x (ny = nx / 4); default 128")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="any scenario key, e.g. --set time.steps=32 (the value as JSON, else a string)")
    parser.add_argument("--out", default="slip_count.png", help="figure file (PNG or SVG)")
    args = parser.parse_args()

    scenario = tc.Scenario.default()
    overrides = {"mesh.nx": args.nx, "mesh.ny": max(1, args.nx // 4)}
    for assignment in args.set:
        key, _, raw = assignment.partition("=")
        try:
            overrides[key] = json.loads(raw)
        except json.JSONDecodeError:
            overrides[key] = raw
    scenario.update(overrides)
    print(repr(scenario))

    # Step by step: every state with its step's solver figures.
    sim = tc.Simulation(scenario)
    times, slipping, newton = [0.0], [0], 0
    for state in sim.steps():
        times.append(state.t)
        slipping.append(state.contact.slip_count)
        newton += state.info.newton_iterations
    times, slipping = np.array(times), np.array(slipping)
    n_contact = len(sim.contact_nodes)
    print(f"{sim.n_steps} steps, {n_contact} contact nodes, {newton} Newton iterations")
    for t, count in PAPER.items():
        computed = slipping[np.argmin(abs(times - t))]
        print(f"t = {t:4}: {computed:3} slip nodes (the paper: {count})")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
    ax.step(times, slipping, where="post", label="thermocontact")
    ax.plot(list(PAPER), list(PAPER.values()), "x", color="C3", markersize=9, mew=2, label="the paper (Fig. 2)")
    ax.set(xlabel="t [s]", ylabel="slip nodes on $\\Gamma_C$", ylim=(0, n_contact),
           title=f"Slip count, α_exp = {scenario['material.thermal_expansion']:g} 1/°C, "
                 f"{scenario['mesh.nx']} × {scenario['mesh.ny']} cells")
    ax.legend()
    fig.savefig(args.out, dpi=150)
    print(f"figure written to {args.out}")


if __name__ == "__main__":
    main()
