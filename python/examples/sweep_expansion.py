"""A parameter sweep over the thermal expansion coefficient α_exp (the paper's Fig. 3 and more).

What it solves: the paper's Section 6 example for several α_exp (`material.thermal_expansion`,
1/°C). Thermal expansion couples the frictional heating back into the stresses; the paper shows
5 slip nodes at t = 1 s for α_exp = 1·10⁻⁴ and 33 for 1·10⁻³ (30 for the default 3·10⁻⁴). For
each value it prints the slip count at every output time, the temperature range and the largest
displacement at T, and draws the slip count at T against α_exp.

    python python/examples/sweep_expansion.py                     # 7 values, 64 × 16 cells (~2 s)
    python python/examples/sweep_expansion.py --nx 128            # the default mesh
    python python/examples/sweep_expansion.py --values 1e-4,1e-3  # the paper's Fig. 3 only

Read first: Scenario.copy / item assignment, RunResult (summary, slip_counts, last).
Things to try: sweep another key the same way (`friction.alpha`, `frictional_heating.rate`).
"""

import argparse

import numpy as np

import thermocontact as tc


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nx", type=int, default=64, help="cells along x (ny = nx / 4); default 64")
    parser.add_argument("--values", default="1e-5,3e-5,1e-4,3e-4,6e-4,1e-3,2e-3",
                        help="α_exp values [1/°C], comma-separated")
    parser.add_argument("--out", default="sweep_expansion.png", help="figure file ('' for none)")
    args = parser.parse_args()

    base = tc.Scenario(overrides={"mesh.nx": args.nx, "mesh.ny": max(1, args.nx // 4)})
    values = [float(v) for v in args.values.split(",")]
    print(f"{'α_exp':>8} | slip nodes at t = {base['output.times']} | θ range at T [°C] | max |u| [m]")
    at_end = []
    for alpha in values:
        scenario = base.copy()
        scenario["material.thermal_expansion"] = alpha
        result = tc.Simulation(scenario).run()
        last = result.outputs[-1]
        at_end.append(last.contact.slip_count)
        print(f"{alpha:8.0e} | {str(result.slip_counts.tolist()):>30} | "
              f"{last.theta.min():6.2f} … {last.theta.max():6.2f} | {np.linalg.norm(last.u, axis=1).max():.4f}")

    if args.out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 3.5), layout="constrained")
        ax.semilogx(values, at_end, "o-", label="thermocontact")
        ax.plot([1e-4, 3e-4, 1e-3], [5, 30, 33], "x", color="C3", markersize=9, mew=2, label="the paper")
        ax.set(xlabel="α_exp [1/°C]", ylabel="slip nodes at T", title=f"{args.nx} × {max(1, args.nx // 4)} cells")
        ax.legend()
        fig.savefig(args.out, dpi=150)
        print(f"figure written to {args.out}")


if __name__ == "__main__":
    main()
