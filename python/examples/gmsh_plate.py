"""A mesh built with Gmsh's Python API and run: the paper's plate with a hole.

What it solves: the paper's Section 6 example (material, friction, heat exchange, the top
traction (0, −800 t) N/m) on a 40 m × 10 m plate with a circular hole of radius `--radius`
centred at (20, 5), meshed by Gmsh (`pip install gmsh`). The mesh goes to thermocontact as NumPy
arrays (points, triangles, and the boundary edges of each physical group), with no file in
between; the scenario names the parts as the physical groups do. It prints the run's summary
and draws the temperature at T on the deformed mesh.

    python python/examples/gmsh_plate.py                 # mesh size 1 m (~2 000 triangles, ~1 s)
    python python/examples/gmsh_plate.py --size 0.5      # finer
    python python/examples/gmsh_plate.py --out plate.png

Read first: gmsh_mesh() (Gmsh → arrays), Mesh(points, cells, boundary), Scenario.with_mesh.
A meshio mesh (meshio.read("part.msh"), or pygmsh's generate_mesh()) goes the same way through
thermocontact.Mesh.from_meshio(m). Things to try: a traction on the hole (`loads.pressure`),
contact on the hole instead of the bottom (a curved Γ_C: each node has its own normal).
"""

import argparse

import numpy as np

import thermocontact as tc


def gmsh_mesh(size, radius):
    """The plate with a hole, meshed by Gmsh: (points, triangles, {group: edges})."""
    import gmsh

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.add("plate")
        plate = gmsh.model.occ.addRectangle(0, 0, 0, 40, 10)
        hole = gmsh.model.occ.addDisk(20, 5, 0, radius, radius)
        body, _ = gmsh.model.occ.cut([(2, plate)], [(2, hole)])
        gmsh.model.occ.synchronize()
        # Physical groups by where each boundary curve lies.
        groups = {"clamp": [], "load": [], "contact": [], "free": [], "hole": []}
        for _, curve in gmsh.model.getBoundary(body, oriented=False):
            x, y, _ = gmsh.model.occ.getCenterOfMass(1, curve)
            name = ("clamp" if np.isclose(x, 0) else "free" if np.isclose(x, 40) else
                    "contact" if np.isclose(y, 0) else "load" if np.isclose(y, 10) else "hole")
            groups[name].append(curve)
        group_tags = {name: gmsh.model.addPhysicalGroup(1, curves, name=name) for name, curves in groups.items()}
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.mesh.generate(2)

        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        index = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
        index[node_tags.astype(np.int64)] = np.arange(len(node_tags))
        points = coords.reshape(-1, 3)[:, :2]
        _, triangle_nodes = gmsh.model.mesh.getElementsByType(2)  # 3-node triangles
        triangles = index[triangle_nodes.astype(np.int64)].reshape(-1, 3)
        boundary = {}
        for name, tag in group_tags.items():
            edges = []
            for curve in gmsh.model.getEntitiesForPhysicalGroup(1, tag):
                _, _, nodes = gmsh.model.mesh.getElements(1, curve)
                edges.append(index[nodes[0].astype(np.int64)].reshape(-1, 2))
            boundary[name] = np.concatenate(edges)
    finally:
        gmsh.finalize()
    # Only the nodes of triangles (Gmsh may list others), renumbered.
    used = np.zeros(len(points), dtype=bool)
    used[triangles.ravel()] = True
    renumber = np.cumsum(used) - 1
    return points[used], renumber[triangles], {k: renumber[v] for k, v in boundary.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=float, default=1.0, help="largest mesh size [m]; default 1")
    parser.add_argument("--radius", type=float, default=2.5, help="radius of the hole [m]; default 2.5")
    parser.add_argument("--out", default="gmsh_plate.png", help="figure file ('' for none)")
    args = parser.parse_args()

    points, triangles, boundary = gmsh_mesh(args.size, args.radius)
    mesh = tc.Mesh(points, triangles, boundary)
    print(mesh)
    scenario = tc.Scenario.default().with_mesh(mesh, {
        "boundary.dirichlet": ["clamp"],
        "boundary.neumann": ["load", "free", "hole"],
        "boundary.contact": ["contact"],
        "loads.traction": [{"part": "load", "constant": [0.0, 0.0], "rate": [0.0, -800.0]}],
    })
    sim = tc.Simulation(scenario)
    print(sim)
    result = sim.run()
    for record in result.summary["outputs"]:
        print(f"t = {record['t']:4}: {record['slip_nodes']:3} slip, {record['stick_nodes']:3} stick, "
              f"θ in [{record['min_temperature']:.2f}, {record['max_temperature']:.2f}] °C")
    timings = result.summary["timings"]
    print(f"{sim.n_unknowns} unknowns, {timings['total']:.2f} s "
          f"(assembly {timings['assembly']:.2f}, factorization {timings['factorization']:.2f}, "
          f"time stepping {timings['time_stepping']:.2f})")

    if args.out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.tri import Triangulation

        last = result.last
        deformed = mesh.points + last.u
        fig, ax = plt.subplots(figsize=(8, 2.8), layout="constrained")
        shading = ax.tripcolor(Triangulation(*deformed.T, mesh.cells), last.theta, shading="gouraud", cmap="inferno")
        contact = last.contact
        ax.plot(*deformed[contact.node[contact.slip]].T, "o", color="C0", ms=3, label="slip")
        ax.plot(*deformed[contact.node[~contact.slip]].T, "s", color="C2", ms=3, label="stick")
        fig.colorbar(shading, label="θ [°C]")
        ax.set(aspect="equal", title=f"t = {last.t} s: temperature on x + u", xlabel="x [m]", ylabel="y [m]")
        ax.legend(loc="upper right", fontsize=8)
        fig.savefig(args.out, dpi=150)
        print(f"figure written to {args.out}")


if __name__ == "__main__":
    main()
