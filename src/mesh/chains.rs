//! Boundary curves of a 2D mesh as ordered node chains with their arc length: the outline of Ω
//! (every boundary edge of the cells) and the pieces of a boundary part such as Γ_C.
//!
//! Figures need both: the outline to draw the body whatever the mesh covers with physical groups
//! (a Gmsh file may name only some of its boundary), and Γ_C in order along the curve to put the
//! friction arrows at even steps and to plot θ, w_τ, ξ against arc length on any contact curve,
//! not against x·τ, which only orders the nodes of a straight Γ_C.
//!
//! Orientation: cells are positively oriented and boundary facets run so that their right-hand
//! normal points out of Ω, so chains run with Ω on their left (counter-clockwise around the body,
//! clockwise around a hole). A chain of n edges lists n + 1 nodes; a closed one repeats its first
//! node at the end.

use std::collections::BTreeMap;

use super::Mesh;

/// One connected piece of a boundary curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Chain {
    /// Nodes in order along the curve.
    pub nodes: Vec<usize>,
    /// Arc length s at each node, from 0 at the first.
    pub arc: Vec<f64>,
    /// The last node is the first: the chain goes round a whole boundary component.
    pub closed: bool,
}

impl Chain {
    /// Arc length of the whole chain.
    pub fn length(&self) -> f64 {
        self.arc.last().copied().unwrap_or(0.0)
    }

    /// The distinct nodes: all of them, less the repeated first node of a closed chain.
    pub fn distinct_nodes(&self) -> &[usize] {
        if self.closed {
            &self.nodes[..self.nodes.len() - 1]
        } else {
            &self.nodes
        }
    }
}

/// The outline of a 2D mesh: the edges that bound one cell only, chained.
pub fn outline(mesh: &Mesh) -> Vec<Chain> {
    assert_eq!(mesh.dim, 2, "outline: a 2D mesh");
    let mut edges: Vec<[usize; 2]> = (0..mesh.n_cells())
        .flat_map(|e| {
            let c = mesh.cell(e);
            [[c[0], c[1]], [c[1], c[2]], [c[2], c[0]]]
        })
        .collect();
    // An interior edge appears once each way; a boundary edge once.
    let mut undirected: Vec<[usize; 2]> = edges.iter().map(|&[a, b]| [a.min(b), a.max(b)]).collect();
    undirected.sort_unstable();
    let once = |key: [usize; 2]| {
        let start = undirected.partition_point(|e| *e < key);
        undirected[start..].partition_point(|e| *e == key) == 1
    };
    edges.retain(|&[a, b]| once([a.min(b), a.max(b)]));
    chain(mesh, &edges)
}

/// The facets of the given parts, chained: one [`Chain`] per connected piece.
pub fn part_chains(mesh: &Mesh, parts: &[usize]) -> Vec<Chain> {
    assert_eq!(mesh.dim, 2, "part_chains: a 2D mesh");
    let edges: Vec<[usize; 2]> = mesh
        .facets_of(parts)
        .map(|f| {
            let e = mesh.facet(f);
            [e[0], e[1]]
        })
        .collect();
    chain(mesh, &edges)
}

/// Chains directed edges: each open chain from a node that no edge enters, then the closed loops
/// that remain. A node where the boundary touches itself (two edges leave it) ends the chain that
/// reaches it; its other edge starts a chain of its own.
fn chain(mesh: &Mesh, edges: &[[usize; 2]]) -> Vec<Chain> {
    let mut next: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    let mut entered: BTreeMap<usize, usize> = BTreeMap::new();
    for &[a, b] in edges {
        next.entry(a).or_default().push(b);
        *entered.entry(b).or_default() += 1;
    }
    let mut chains = Vec::new();
    let mut follow = |start: usize, next: &mut BTreeMap<usize, Vec<usize>>| {
        let mut nodes = vec![start];
        let mut current = start;
        while let Some(n) = next.get_mut(&current).and_then(|out| out.pop()) {
            nodes.push(n);
            current = n;
            if n == start {
                break;
            }
        }
        let arc = nodes
            .iter()
            .scan((0.0, start), |(s, previous), &p| {
                let (a, b) = (mesh.coords[*previous], mesh.coords[p]);
                *s += (a[0] - b[0]).hypot(a[1] - b[1]);
                *previous = p;
                Some(*s)
            })
            .collect();
        let closed = nodes.len() > 1 && nodes.first() == nodes.last();
        chains.push(Chain { nodes, arc, closed });
    };
    let starts: Vec<usize> = next.keys().copied().filter(|p| !entered.contains_key(p)).collect();
    for start in starts {
        while next.get(&start).is_some_and(|out| !out.is_empty()) {
            follow(start, &mut next);
        }
    }
    while let Some(start) = next.iter().find(|(_, out)| !out.is_empty()).map(|(&p, _)| p) {
        follow(start, &mut next);
    }
    chains
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{annulus, rectangle};

    #[test]
    fn the_outline_of_a_rectangle_is_one_closed_counter_clockwise_chain() {
        let mesh = rectangle(4.0, 1.0, 4, 2);
        let chains = outline(&mesh);
        assert_eq!(chains.len(), 1);
        let c = &chains[0];
        assert!(c.closed);
        assert_eq!(c.distinct_nodes().len(), 2 * (4 + 2));
        assert!((c.length() - 10.0).abs() < 1e-12);
        // Counter-clockwise: the signed area of the polygon is the rectangle's.
        let area: f64 = c
            .nodes
            .windows(2)
            .map(|w| {
                let (a, b) = (mesh.coords[w[0]], mesh.coords[w[1]]);
                0.5 * (a[0] * b[1] - b[0] * a[1])
            })
            .sum();
        assert!((area - 4.0).abs() < 1e-12, "area {area}");
    }

    #[test]
    fn the_bottom_runs_in_x_with_arc_length_x() {
        let mesh = rectangle(4.0, 1.0, 8, 2);
        let bottom = mesh.part_index("bottom").unwrap();
        let chains = part_chains(&mesh, &[bottom]);
        assert_eq!(chains.len(), 1);
        let c = &chains[0];
        assert!(!c.closed);
        assert_eq!(c.nodes.len(), 9);
        for (&p, &s) in c.nodes.iter().zip(&c.arc) {
            assert_eq!(mesh.coords[p][1], 0.0);
            assert!((mesh.coords[p][0] - s).abs() < 1e-12);
        }
    }

    #[test]
    fn two_parts_meeting_at_a_corner_make_one_chain_and_apart_two() {
        let mesh = rectangle(4.0, 1.0, 4, 2);
        let part = |n: &str| mesh.part_index(n).unwrap();
        let corner = part_chains(&mesh, &[part("bottom"), part("right")]);
        assert_eq!(corner.len(), 1);
        assert!((corner[0].length() - 5.0).abs() < 1e-12);
        let apart = part_chains(&mesh, &[part("left"), part("right")]);
        assert_eq!(apart.len(), 2);
    }

    #[test]
    fn the_annulus_has_two_closed_chains_and_the_hole_runs_clockwise() {
        let (a, b) = (1.0, 2.0);
        let mesh = annulus(a, b, 4, 32);
        let chains = outline(&mesh);
        assert_eq!(chains.len(), 2);
        assert!(chains.iter().all(|c| c.closed));
        let inner = part_chains(&mesh, &[mesh.part_index("inner").unwrap()]);
        assert_eq!(inner.len(), 1);
        // A polygon inscribed in the circle: a little shorter than 2πa.
        let polygon = 2.0 * 32.0 * a * (std::f64::consts::PI / 32.0).sin();
        assert!((inner[0].length() - polygon).abs() < 1e-12);
        // Ω on the left of the hole's boundary: the chain turns clockwise.
        let c = &inner[0];
        let turn: f64 = c
            .nodes
            .windows(2)
            .map(|w| {
                let (p, q) = (mesh.coords[w[0]], mesh.coords[w[1]]);
                p[0] * q[1] - q[0] * p[1]
            })
            .sum();
        assert!(turn < 0.0);
    }
}
