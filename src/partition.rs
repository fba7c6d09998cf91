//! The partition of a mesh over the ranks of a distributed run (cargo feature `mpi`): which rank
//! each cell goes to, which rank owns each node, the ghost nodes of a rank, and the global
//! numbering of the unknowns in which each rank's are consecutive (PETSc's layout).
//!
//! **The cells** are split by PETSc's `MatPartitioning` with PT-Scotch on the mesh's dual graph
//! (cells adjacent through a facet), on rank 0, into as many parts as ranks
//! ([`MeshPartition::on_root`] broadcasts the cells' parts). PT-Scotch rather than METIS through
//! a crate: it ships inside Debian's PETSc (`PETSC_HAVE_PTSCOTCH`), so the `mpi` feature needs
//! no system library beyond PETSc and Open MPI, and no `bindgen`/libclang (the METIS crates
//! generate their bindings); Debian's PETSc has no (Par)METIS. Its default imbalance is 1 %.
//!
//! **The nodes**: a node belongs to the lowest rank among the ranks of its cells (every node is
//! owned once); a rank's **ghosts** are the nodes of its cells that another rank owns: what it
//! reads and does not own when it assembles its cells.
//!
//! **The unknowns** ([`DofLayout`]): rank 0's owned nodes first, ascending, then rank 1's, …;
//! at each node its unknowns in the order the caller gives (velocities, then temperature). Rank
//! r's unknowns are the consecutive range `first[r]..first[r + 1]`, as PETSc's distributed
//! matrices and vectors lay out their rows; a node's unknowns stay together (its block in block
//! Jacobi / ILU(0) and GAMG).
//!
//! Depends on: [`crate::mesh`] (cells, the facet–cell incidence), [`crate::la`] (PETSc's
//! partitioner, the communicator). Its own room because it needs both (the mesh is below `la`,
//! and `la` knows no mesh); `model` and the layers above use it.

use std::ops::Range;

use crate::la::mpi::{partition_graph, Communicator};
use crate::la::LaError;
use crate::mesh::topology::cell_faces;
use crate::mesh::Mesh;

/// The cells of a mesh split over `n_parts` ranks, and the nodes' owners.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeshPartition {
    /// Number of parts (ranks).
    pub n_parts: usize,
    /// The part of each cell.
    pub cell_part: Vec<usize>,
    /// The owner of each node: the lowest part among its cells'.
    pub node_owner: Vec<usize>,
}

/// The dual graph of the mesh: cells adjacent through a facet, as adjacency lists
/// `adjacency[xadj[e]..xadj[e + 1]]` (each cell's neighbours ascending).
pub fn dual_graph(mesh: &Mesh) -> (Vec<usize>, Vec<usize>) {
    let faces = cell_faces(mesh);
    let mut degree = vec![0usize; mesh.n_cells() + 1];
    let shared: Vec<(usize, usize)> = faces
        .windows(2)
        .filter(|pair| pair[0].key == pair[1].key)
        .map(|pair| (pair[0].cell, pair[1].cell))
        .collect();
    for &(a, b) in &shared {
        degree[a + 1] += 1;
        degree[b + 1] += 1;
    }
    for e in 0..mesh.n_cells() {
        degree[e + 1] += degree[e];
    }
    let xadj = degree;
    let mut fill = xadj.clone();
    let mut adjacency = vec![0; xadj[mesh.n_cells()]];
    for &(a, b) in &shared {
        adjacency[fill[a]] = b;
        fill[a] += 1;
        adjacency[fill[b]] = a;
        fill[b] += 1;
    }
    for e in 0..mesh.n_cells() {
        adjacency[xadj[e]..xadj[e + 1]].sort_unstable();
    }
    (xadj, adjacency)
}

impl MeshPartition {
    /// The cells split into `n_parts` by PT-Scotch on the dual graph, on this process alone.
    pub fn new(mesh: &Mesh, n_parts: usize) -> Result<Self, LaError> {
        let (xadj, adjacency) = dual_graph(mesh);
        let cell_part = partition_graph(&xadj, &adjacency, n_parts)?;
        Ok(Self::from_cell_parts(mesh, n_parts, cell_part))
    }

    /// The partition computed on rank 0 into one part per rank, the cells' parts broadcast: the
    /// same on every rank (each rank holds the mesh; only rank 0's is read).
    pub fn on_root(comm: &Communicator, mesh: &Mesh) -> Result<Self, LaError> {
        let mut bytes = Vec::new();
        if comm.is_root() {
            let parts = Self::new(mesh, comm.size())?.cell_part;
            bytes = parts.iter().flat_map(|&p| (p as u32).to_le_bytes()).collect();
        }
        comm.broadcast_bytes(&mut bytes)?;
        let cell_part = bytes
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
            .collect::<Vec<_>>();
        assert_eq!(
            cell_part.len(),
            mesh.n_cells(),
            "rank 0's mesh has as many cells as this rank's"
        );
        Ok(Self::from_cell_parts(mesh, comm.size(), cell_part))
    }

    /// The partition with these cells' parts: each node owned by the lowest part among its
    /// cells' (part 0 for a node in no cell).
    pub fn from_cell_parts(mesh: &Mesh, n_parts: usize, cell_part: Vec<usize>) -> Self {
        assert!(cell_part.iter().all(|&p| p < n_parts), "parts below {n_parts}");
        let mut node_owner = vec![usize::MAX; mesh.n_nodes()];
        for (e, &part) in cell_part.iter().enumerate() {
            for &p in mesh.cell(e) {
                node_owner[p] = node_owner[p].min(part);
            }
        }
        node_owner.iter_mut().filter(|o| **o == usize::MAX).for_each(|o| *o = 0);
        MeshPartition {
            n_parts,
            cell_part,
            node_owner,
        }
    }

    /// The cells of `part`, ascending.
    pub fn cells_of(&self, part: usize) -> Vec<usize> {
        (0..self.cell_part.len())
            .filter(|&e| self.cell_part[e] == part)
            .collect()
    }

    /// The nodes `part` owns, ascending.
    pub fn owned_nodes(&self, part: usize) -> Vec<usize> {
        (0..self.node_owner.len())
            .filter(|&p| self.node_owner[p] == part)
            .collect()
    }

    /// The ghosts of `part`: the nodes of its cells that another part owns, ascending.
    pub fn ghost_nodes(&self, mesh: &Mesh, part: usize) -> Vec<usize> {
        let mut ghosts: Vec<usize> = self
            .cells_of(part)
            .into_iter()
            .flat_map(|e| mesh.cell(e).iter().copied())
            .filter(|&p| self.node_owner[p] != part)
            .collect();
        ghosts.sort_unstable();
        ghosts.dedup();
        ghosts
    }
}

/// The global numbering of the unknowns in which each rank's are consecutive: `order[g]` is the
/// unknown at global index g, `index_of[u]` the global index of unknown u, and rank r owns
/// `first[r]..first[r + 1]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DofLayout {
    /// The unknown at each global index.
    pub order: Vec<usize>,
    /// The global index of each unknown.
    pub index_of: Vec<usize>,
    /// Where each rank's indices start (n_parts + 1 entries, the last the number of unknowns).
    pub first: Vec<usize>,
}

impl DofLayout {
    /// The layout of `n_unknowns` unknowns attached to the nodes by `unknowns_of(node, out)`
    /// (which appends the node's unknowns to `out`, in their order): each unknown once.
    pub fn new(partition: &MeshPartition, n_unknowns: usize, unknowns_of: impl Fn(usize, &mut Vec<usize>)) -> Self {
        let mut order = Vec::with_capacity(n_unknowns);
        let mut first = vec![0];
        for part in 0..partition.n_parts {
            for p in partition.owned_nodes(part) {
                unknowns_of(p, &mut order);
            }
            first.push(order.len());
        }
        assert_eq!(order.len(), n_unknowns, "every unknown at one node");
        let mut index_of = vec![usize::MAX; n_unknowns];
        for (g, &u) in order.iter().enumerate() {
            assert_eq!(index_of[u], usize::MAX, "unknown {u} at two nodes");
            index_of[u] = g;
        }
        DofLayout { order, index_of, first }
    }

    /// The global indices rank `part` owns.
    pub fn owned(&self, part: usize) -> Range<usize> {
        self.first[part]..self.first[part + 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{cuboid, rectangle};

    /// The dual graph of a 2 × 1 rectangle of 4 triangles is a path (each diagonal and the
    /// middle edge shared once).
    #[test]
    fn the_dual_graph_links_cells_through_facets() {
        let mesh = rectangle(2.0, 1.0, 2, 1);
        let (xadj, adjacency) = dual_graph(&mesh);
        assert_eq!(xadj.len(), 5);
        assert_eq!(adjacency.len(), 6, "3 interior edges, listed from both sides");
        let cube = cuboid([1.0; 3], [1, 1, 1]);
        let (xadj, _) = dual_graph(&cube);
        assert_eq!(
            xadj[6],
            2 * 6,
            "the Kuhn split of a cube: 6 tetrahedra around a cycle of 6 faces"
        );
    }

    /// PT-Scotch splits the same mesh the same way on every call, so that two runs of one case
    /// on P ranks take the same steps. Its threaded algorithms moved a few cells of 2 600 from
    /// call to call (this test fails with `SCOTCH_PTHREAD_NUMBER=2`), and a second call in one
    /// process drew other random numbers without the generator's reset.
    #[cfg(feature = "mpi")]
    #[test]
    fn the_same_mesh_is_split_the_same_way_every_time() {
        let mesh = cuboid([40.0, 10.0, 10.0], [24, 6, 6]);
        for parts in [2, 3] {
            let first = MeshPartition::new(&mesh, parts).unwrap();
            for _ in 0..3 {
                let again = MeshPartition::new(&mesh, parts).unwrap();
                for r in 0..parts {
                    assert_eq!(again.cells_of(r), first.cells_of(r), "part {r} of {parts}");
                }
            }
        }
    }

    /// With the cells' parts given, a node shared by parts 1 and 2 belongs to 1, and the
    /// ghosts of part 2 are its nodes that 0 or 1 own.
    #[test]
    fn nodes_go_to_the_lowest_part_of_their_cells() {
        let mesh = rectangle(3.0, 1.0, 3, 1);
        let cell_part: Vec<usize> = (0..mesh.n_cells()).map(|e| e / 2).collect();
        let partition = MeshPartition::from_cell_parts(&mesh, 3, cell_part);
        let owned: usize = (0..3).map(|r| partition.owned_nodes(r).len()).sum();
        assert_eq!(owned, mesh.n_nodes());
        for r in 0..3 {
            for p in partition.ghost_nodes(&mesh, r) {
                assert!(partition.node_owner[p] < r, "ghost {p} of {r} owned by a lower part");
            }
        }
        assert!(partition.ghost_nodes(&mesh, 0).is_empty());
        let layout = DofLayout::new(&partition, 2 * mesh.n_nodes(), |p, out| out.extend([2 * p, 2 * p + 1]));
        assert_eq!(layout.first[3], 2 * mesh.n_nodes());
        for r in 0..3 {
            for g in layout.owned(r) {
                assert_eq!(partition.node_owner[layout.order[g] / 2], r);
                assert_eq!(layout.index_of[layout.order[g]], g);
            }
        }
    }
}
