//! Facet–cell incidence: which cell a boundary facet closes, and the outward orientation of the
//! boundary facets that every normal in the code relies on.

use std::collections::HashMap;

use super::Mesh;

/// The sorted node indices of a facet: the key under which cells and facets meet.
pub(crate) fn facet_key(nodes: &[usize]) -> [usize; 3] {
    let mut key = [usize::MAX; 3];
    key[..nodes.len()].copy_from_slice(nodes);
    key[..nodes.len()].sort_unstable();
    key
}

/// For every facet of every cell: the cells it bounds and, per cell, the vertex opposite to it.
pub(crate) fn cell_facets(mesh: &Mesh) -> HashMap<[usize; 3], Vec<(usize, usize)>> {
    let npc = mesh.nodes_per_cell();
    let mut map: HashMap<[usize; 3], Vec<(usize, usize)>> = HashMap::with_capacity(mesh.n_cells() * npc / 2 + 1);
    for e in 0..mesh.n_cells() {
        let cell = mesh.cell(e);
        for skip in 0..npc {
            let nodes: Vec<usize> = (0..npc).filter(|&a| a != skip).map(|a| cell[a]).collect();
            map.entry(facet_key(&nodes)).or_default().push((e, cell[skip]));
        }
    }
    map
}

/// Reorders the nodes of every boundary facet that lies on a cell face so that its right-hand
/// normal ([`Mesh::facet_normal`]) points out of that cell. Facets that close no cell are left as
/// they are (the mesh checks report them).
pub(crate) fn orient_facets_outward(mesh: &mut Mesh) {
    let incidence = cell_facets(mesh);
    for f in 0..mesh.n_facets() {
        let Some(&[(_, opposite)]) = incidence.get(&facet_key(mesh.facet(f))).map(Vec::as_slice) else {
            continue;
        };
        let normal = mesh.facet_area_vector(f);
        let x0 = mesh.coords[mesh.facet(f)[0]];
        let xo = mesh.coords[opposite];
        let inward: f64 = (0..3).map(|c| normal[c] * (xo[c] - x0[c])).sum();
        if inward > 0.0 {
            let d = mesh.dim;
            mesh.facets.swap(f * d, f * d + 1);
        }
    }
}
