//! A graph of nodes coupled through cells, and its two-way split by breadth-first levels, for the parallel ILU(0)
//! sweeps of the iterative path ([`super::ilu::Ilu0::with_domains`]).
//!
//! A triangular sweep is sequential: row i needs every earlier row it is coupled to. If the
//! unknowns are ordered as two parts that share no matrix entry, then a separator, then the rest
//! (the Γ_C rows of the iterative path), the two parts' rows depend only on their own
//! part, and each sweep runs the parts on the two cores at once. The factor is the ILU(0) of A
//! in that order: nothing is dropped between the parts, the separator's rows see both.
//!
//! The split is the breadth-first level structure from a pseudo-peripheral node (the last node
//! reached from node 0): nodes in levels before the middle one form the first part, the middle
//! level is the separator, the later levels (and other connected components) the second part.
//! Consecutive levels are the only ones that share cells, so the parts share none. On a mesh
//! elongated along one axis, as the paper's slab, the middle level is a cross-section: 1 % of
//! the nodes of the 3D example at 156 × 39 × 39 cells. A graph partitioner (METIS) finds smaller
//! separators on compact meshes, but two parts need no more than this: the separator's rows are
//! a small sequential remainder, and the ordering inside the parts is kept.

use super::sparse::CscMatrix;

/// Node adjacency through cells (each node is its own neighbour), sorted per node.
#[derive(Debug, Clone)]
pub struct NodeGraph {
    ptr: Vec<usize>,
    adj: Vec<usize>,
}

impl NodeGraph {
    /// Builds the graph of a mesh given as flat cell connectivity: each node's neighbours are
    /// gathered from the list of its cells, marked so that each is taken once, then sorted.
    /// (Lists of every cell's nodes per node, sorted with their repeats, took 0.3 s at 10⁵
    /// nodes.)
    pub fn new(n_nodes: usize, cells: &[usize], nodes_per_cell: usize) -> Self {
        Self::from_node_cells(&NodeCells::new(n_nodes, cells, nodes_per_cell), cells, nodes_per_cell)
    }

    /// [`NodeGraph::new`] from the cells of each node, already listed.
    pub fn from_node_cells(node_cells: &NodeCells, cells: &[usize], nodes_per_cell: usize) -> Self {
        let n_nodes = node_cells.n_nodes();
        let mut mark = vec![usize::MAX; n_nodes];
        let mut ptr = Vec::with_capacity(n_nodes + 1);
        let mut adj = Vec::new();
        ptr.push(0);
        for p in 0..n_nodes {
            let start = adj.len();
            mark[p] = p;
            adj.push(p);
            for &e in node_cells.of(p) {
                for &q in &cells[e * nodes_per_cell..(e + 1) * nodes_per_cell] {
                    if mark[q] != p {
                        mark[q] = p;
                        adj.push(q);
                    }
                }
            }
            adj[start..].sort_unstable();
            ptr.push(adj.len());
        }
        NodeGraph { ptr, adj }
    }

    /// The graph of a scalar nodal matrix's pattern ([`CscMatrix::from_graph`] with one row and
    /// column per node): the graph it was made from, without going through the cells again.
    pub fn of_nodal_matrix(matrix: &CscMatrix) -> Self {
        assert_eq!(matrix.n_rows, matrix.n_cols, "one row and one column per node");
        NodeGraph {
            ptr: matrix.col_ptr.to_vec(),
            adj: matrix.row_idx.iter().map(|&r| r as usize).collect(),
        }
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.ptr.len() - 1
    }

    /// Sorted neighbours of node `q`.
    pub fn neighbours(&self, q: usize) -> &[usize] {
        &self.adj[self.ptr[q]..self.ptr[q + 1]]
    }
}

/// The cells of each node, in increasing order, from flat cell connectivity.
#[derive(Debug, Clone)]
pub struct NodeCells {
    ptr: Vec<usize>,
    cells: Vec<usize>,
}

impl NodeCells {
    /// Lists the cells of every node (`nodes_per_cell` nodes per cell in `cells`).
    pub fn new(n_nodes: usize, cells: &[usize], nodes_per_cell: usize) -> Self {
        let mut ptr = vec![0usize; n_nodes + 1];
        cells.iter().for_each(|&p| ptr[p + 1] += 1);
        for p in 0..n_nodes {
            ptr[p + 1] += ptr[p];
        }
        let mut of = vec![0usize; cells.len()];
        let mut fill = ptr.clone();
        for (e, cell) in cells.chunks_exact(nodes_per_cell).enumerate() {
            for &p in cell {
                of[fill[p]] = e;
                fill[p] += 1;
            }
        }
        NodeCells { ptr, cells: of }
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.ptr.len() - 1
    }

    /// The cells of node `p`, in increasing order.
    pub fn of(&self, p: usize) -> &[usize] {
        &self.cells[self.ptr[p]..self.ptr[p + 1]]
    }
}

/// Which part of the split a node belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    First,
    Second,
    Separator,
}

/// The part of every node. `weight[p]` is what node p costs in the sweeps (its unknowns); the
/// middle level is where the first part's weight reaches half of the total.
pub fn level_bisection(graph: &NodeGraph, weight: &[usize]) -> Vec<Part> {
    let n = graph.n_nodes();
    if n == 0 {
        return Vec::new();
    }
    let (_, far) = levels_from(graph, 0);
    let (level, _) = levels_from(graph, far);
    let depth = level.iter().flatten().max().map_or(0, |&d| d + 1);
    let mut per_level = vec![0usize; depth];
    for (p, l) in level.iter().enumerate() {
        if let Some(l) = l {
            per_level[*l] += weight[p];
        }
    }
    let total: usize = weight.iter().sum();
    let mut below = 0;
    let middle = per_level
        .iter()
        .position(|&w| {
            below += w;
            2 * below >= total
        })
        .unwrap_or(0);
    level
        .iter()
        .map(|l| match l {
            Some(l) if *l < middle => Part::First,
            Some(l) if *l == middle => Part::Separator,
            _ => Part::Second,
        })
        .collect()
}

/// Breadth-first levels of the nodes reachable from `start` (`None` for the others), and the
/// node reached last.
fn levels_from(graph: &NodeGraph, start: usize) -> (Vec<Option<usize>>, usize) {
    let mut level = vec![None; graph.n_nodes()];
    let mut queue = std::collections::VecDeque::from([start]);
    level[start] = Some(0);
    let mut last = start;
    while let Some(p) = queue.pop_front() {
        last = p;
        let next = level[p].map(|l| l + 1);
        for &q in graph.neighbours(p) {
            if level[q].is_none() {
                level[q] = next;
                queue.push_back(q);
            }
        }
    }
    (level, last)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangles of an nx × ny grid of squares, node (i, j) = j (nx + 1) + i.
    fn grid(nx: usize, ny: usize) -> NodeGraph {
        let node = |i: usize, j: usize| j * (nx + 1) + i;
        let mut cells = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1));
                cells.extend([a, b, c, a, c, d]);
            }
        }
        NodeGraph::new((nx + 1) * (ny + 1), &cells, 3)
    }

    /// Each node's neighbours are the sorted, distinct nodes of its cells and itself, and the
    /// pattern of a scalar matrix made from the graph gives the graph back.
    #[test]
    fn neighbours_are_the_nodes_of_the_cells() {
        let cells = [0, 1, 2, 1, 3, 2, 2, 3, 4];
        let g = NodeGraph::new(6, &cells, 3);
        for p in 0..6 {
            let mut expected: Vec<usize> = (cells.chunks(3).filter(|c| c.contains(&p)).flatten().copied())
                .chain([p])
                .collect();
            expected.sort_unstable();
            expected.dedup();
            assert_eq!(g.neighbours(p), &expected[..], "node {p}");
        }
        let node_cells = NodeCells::new(6, &cells, 3);
        for p in 0..6 {
            let expected: Vec<usize> = (0..3).filter(|&e| cells[3 * e..3 * e + 3].contains(&p)).collect();
            assert_eq!(node_cells.of(p), &expected[..], "node {p}");
        }
        let again = NodeGraph::of_nodal_matrix(&CscMatrix::from_graph(&g, 1, 1));
        assert_eq!((again.ptr, again.adj), (g.ptr, g.adj));
    }

    #[test]
    fn the_parts_share_no_cell_and_are_balanced() {
        let g = grid(40, 10);
        let part = level_bisection(&g, &vec![1; g.n_nodes()]);
        for p in 0..g.n_nodes() {
            for &q in g.neighbours(p) {
                assert!(
                    !(part[p] == Part::First && part[q] == Part::Second),
                    "nodes {p} and {q} share a cell across the split"
                );
            }
        }
        let count = |x: Part| part.iter().filter(|&&y| y == x).count();
        let (first, second, separator) = (count(Part::First), count(Part::Second), count(Part::Separator));
        assert!(first.abs_diff(second) <= 2 * separator, "{first} {second} {separator}");
        // The middle level of the elongated grid is a cross-section, not a diagonal of it.
        assert!(separator <= 2 * 11, "{separator}");
    }

    #[test]
    fn another_component_goes_to_the_second_part() {
        // Two triangles with no node in common.
        let g = NodeGraph::new(6, &[0, 1, 2, 3, 4, 5], 3);
        let part = level_bisection(&g, &[1; 6]);
        let component = |p: usize| if p < 3 { 0 } else { 1 };
        for p in 0..6 {
            for &q in g.neighbours(p) {
                assert_eq!(component(p), component(q));
                assert!(!(part[p] == Part::First && part[q] == Part::Second));
            }
        }
        assert!(level_bisection(&NodeGraph::new(0, &[], 3), &[]).is_empty());
    }
}
