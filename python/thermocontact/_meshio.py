"""Mesh.from_meshio: a meshio.Mesh (as meshio reads it, or as pygmsh generates it) as a
thermocontact Mesh.

Cells are the mesh's triangle blocks (2D) or tetra blocks (3D). Boundary parts are its named
sets of facets (line blocks in 2D, triangle blocks in 3D):

* ``cell_sets`` (pygmsh, and meshio >= 5 for Gmsh files): name -> one index array per cell block;
* otherwise the Gmsh physical groups: ``field_data`` (name -> [tag, dim]) with
  ``cell_data["gmsh:physical"]`` (the tag of every element, per block).

Sets without facets (a domain group, say) are skipped. With ``prune``, nodes that no cell uses
(Gmsh lists geometry points such as a circle's centre) are dropped and the rest renumbered, as
the .msh reader does. Everything is then checked by the core (Mesh(...)), which refuses points
that are not real numbers and cells that are not integers, naming them. Something that is not a
meshio mesh is a TypeError naming the argument, not an AttributeError from deep inside.
"""

import numpy as np

_CELL = {2: "triangle", 3: "tetra"}
_FACET = {2: "line", 3: "triangle"}


def _blocks(mesh):
    """(type, data) of each cell block (meshio 4 and 5 spell them differently)."""
    try:
        return [(block.type, np.asarray(block.data)) for block in mesh.cells]
    except (AttributeError, TypeError):
        raise TypeError(
            f"Mesh.from_meshio: mesh.cells is {_describe(mesh.cells)}, expected meshio cell blocks "
            "(each with .type and .data)"
        ) from None


def _describe(value):
    """'an int (42)': the type and, if short, the repr of a value."""
    name = type(value).__name__
    article = "an" if name[:1] in "aeiou" else "a"
    text = repr(value)
    return f"{article} {name} ({text})" if len(text) <= 40 else f"{article} {name}"


def from_meshio(mesh, prune=True):
    from ._thermocontact import Mesh, MeshError

    if not (hasattr(mesh, "points") and hasattr(mesh, "cells")):
        raise TypeError(
            f"Mesh.from_meshio: mesh is {_describe(mesh)}, expected a meshio.Mesh (with .points and .cells)"
        )
    blocks = _blocks(mesh)
    types = {t for t, _ in blocks}
    dim = 3 if "tetra" in types else 2 if "triangle" in types else None
    if dim is None:
        raise MeshError(
            f"invalid mesh: the meshio mesh has no triangle or tetra cells (its blocks: {sorted(types)}); "
            "thermocontact solves on linear triangles (2D) and tetrahedra (3D)"
        )
    cells = np.concatenate([data for t, data in blocks if t == _CELL[dim]])
    facet_type = _FACET[dim]

    boundary = {}
    cell_sets = getattr(mesh, "cell_sets", None) or {}
    for name, per_block in cell_sets.items():
        if name.startswith("gmsh:"):
            continue
        parts = [
            data[np.asarray(index, dtype=np.int64)]
            for (t, data), index in zip(blocks, per_block)
            if t == facet_type and index is not None and len(index) > 0
        ]
        if parts:
            boundary[name] = np.concatenate(parts)
    if not boundary:
        physical = (getattr(mesh, "cell_data", None) or {}).get("gmsh:physical")
        field_data = getattr(mesh, "field_data", None) or {}
        if physical is not None:
            for name, (tag, group_dim) in ((n, tuple(v)[:2]) for n, v in field_data.items()):
                if group_dim != dim - 1:
                    continue
                parts = [
                    data[np.asarray(tags) == tag]
                    for (t, data), tags in zip(blocks, physical)
                    if t == facet_type
                ]
                parts = [p for p in parts if len(p) > 0]
                if parts:
                    boundary[name] = np.concatenate(parts)

    # No dtype here: Mesh(...) refuses complex points by name, where a cast would drop the
    # imaginary part with only a warning.
    points = np.asarray(mesh.points)
    if dim == 2 and points.ndim == 2 and points.shape[1] == 3:
        if np.any(points[:, 2] != 0.0):
            raise MeshError("invalid mesh: a triangle mesh with nodes off the plane z = 0")
        points = points[:, :2]
    # Cells that are not integers are left for Mesh(...) to refuse by name.
    if prune and cells.dtype.kind in "iu":
        used = np.zeros(len(points), dtype=bool)
        used[cells.ravel()] = True
        if not used.all():
            renumber = np.cumsum(used) - 1
            points = points[used]
            cells = renumber[cells]
            boundary = {name: renumber[facets] for name, facets in boundary.items()}
    return Mesh(points, cells, boundary)
