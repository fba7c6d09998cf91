//! Per-node contact frames on Γ_C: the outward normal ν_i from the mesh, an orthonormal tangent
//! basis t_{i,1} … t_{i,d−1}, and which tangent directions the node is free to slide along.
//!
//! The bilateral condition (7), u_ν = 0, and the friction law (8) live in each node's frame:
//! the velocity of a contact node is w_i = Σ_k w_{τ,k} t_{i,k} (no normal component), and its
//! friction stress ξ_i has the same tangent coordinates.
//!
//! **The normal.** ν_i is the facet-measure-weighted mean of the outward unit normals of the Γ_C
//! facets around node i, normalised: ν_i ∝ Σ_F |F| ν_F = Σ_F a_F. On a flat part it is that
//! part's normal exactly; on a curved part it is the standard averaged normal of node-based
//! contact, within O(h) of the exact normal (O(h²) on a uniform mesh of a circle).
//!
//! **Sharp corners.** Where the normals of two Γ_C facets around a node differ by more than
//! [`CORNER_ANGLE_DEGREES`], the node is a corner of Γ_C (e.g. `contact = ["bottom", "right"]` on
//! a rectangle, or an edge between two contact faces of a box). There the averaged normal would
//! let the node move into one of the faces, so instead the node keeps u_ν = 0 of *every* facet
//! around it: w_i · ν_F = 0 for each facet normal ν_F — exactly what a P1 field with u_ν = 0 on
//! each facet must satisfy at their common vertex. In 2D a corner node then cannot move
//! (no tangential unknown, no friction; it still exchanges heat); in 3D a node on an edge
//! between two faces slides along the edge only, and a vertex of three faces is held.
//!
//! **Symmetry planes** through a contact node add w_i · ν_s = 0 the same way.
//!
//! The tangent basis puts the directions a node can slide along first: with r free directions
//! (0 ≤ r ≤ d − 1), t_{i,1…r} span them and the remaining tangents complete the basis of the
//! plane ⊥ ν_i; their coordinates are held at zero (the node has no unknown for them).

/// Facet normals around a contact node that differ by more than this angle make it a corner.
pub const CORNER_ANGLE_DEGREES: f64 = 30.0;

/// The frame of one contact node.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactFrame {
    /// ν_i, the unit outward normal.
    pub normal: [f64; 3],
    /// t_{i,1} … t_{i,d−1}: an orthonormal basis of the plane ⊥ ν_i, free directions first.
    pub tangents: Vec<[f64; 3]>,
    /// How many of the tangents the node may slide along (the rest are held at zero).
    pub n_free: usize,
    /// The facet normals around the node differ by more than [`CORNER_ANGLE_DEGREES`].
    pub corner: bool,
}

/// The frames of the Γ_C nodes: `(node, frame)` in increasing node order.
///
/// `facets` are the boundary facets of Γ_C, each with its area vector |F| ν_F (outward);
/// `planes[p]` the unit normals of symmetry planes through node p (empty for most nodes).
pub fn contact_frames(
    dim: usize,
    n_nodes: usize,
    facets: impl Iterator<Item = (Vec<usize>, [f64; 3])>,
    planes: &[Vec<[f64; 3]>],
) -> Vec<(usize, ContactFrame)> {
    // Per node: Σ_F a_F and the unit normals of its facets.
    let mut sum = vec![[0.0; 3]; n_nodes];
    let mut normals: Vec<Vec<[f64; 3]>> = vec![Vec::new(); n_nodes];
    let mut on = vec![false; n_nodes];
    for (nodes, area) in facets {
        let unit = normalized(area);
        for p in nodes {
            on[p] = true;
            (0..3).for_each(|c| sum[p][c] += area[c]);
            if !normals[p].iter().any(|n| dot(n, &unit) > 1.0 - 1e-12) {
                normals[p].push(unit);
            }
        }
    }
    let cos_corner = CORNER_ANGLE_DEGREES.to_radians().cos();
    (0..n_nodes)
        .filter(|&p| on[p])
        .map(|p| {
            let normal = normalized(sum[p]);
            let corner = normals[p]
                .iter()
                .enumerate()
                .any(|(a, n)| normals[p][a + 1..].iter().any(|m| dot(n, m) < cos_corner));
            // The constraints on w_i: u_ν = 0 along ν_i (or along each facet normal at a
            // corner), and each symmetry plane.
            let mut constraints = if corner { normals[p].clone() } else { vec![normal] };
            constraints.extend_from_slice(&planes[p]);
            let free = orthogonal_complement(dim, &constraints);
            let tangents = complete_tangents(dim, &normal, &free);
            (
                p,
                ContactFrame {
                    normal,
                    tangents,
                    n_free: free.len(),
                    corner,
                },
            )
        })
        .collect()
}

/// An orthonormal basis of the plane ⊥ ν (d − 1 vectors), for a unit ν.
///
/// 2D: ν turned by +90°, so ν = (0, −1) gives t = (1, 0), the x direction of the paper's Γ_C. 3D:
/// t₁ from the coordinate axis least aligned with ν, t₂ = ν × t₁.
pub fn tangent_basis(dim: usize, normal: &[f64; 3]) -> Vec<[f64; 3]> {
    if dim == 2 {
        return vec![[-normal[1], normal[0], 0.0]];
    }
    let axis = (0..3)
        .min_by(|&a, &b| normal[a].abs().total_cmp(&normal[b].abs()))
        .unwrap_or(0);
    let mut t1 = [0.0; 3];
    t1[axis] = 1.0;
    let along = dot(&t1, normal);
    (0..3).for_each(|c| t1[c] -= along * normal[c]);
    let t1 = normalized(t1);
    vec![t1, cross(normal, &t1)]
}

/// An orthonormal basis of {v ∈ ℝ^d : v · n = 0 for every n in `normals`} (unit normals).
pub fn orthogonal_complement(dim: usize, normals: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let span = gram_schmidt(normals);
    match (dim, span.len()) {
        (_, 0) => (0..dim).map(axis).collect(),
        (2, 1) | (3, 1) => tangent_basis(dim, &span[0]),
        (3, 2) => vec![normalized(cross(&span[0], &span[1]))],
        _ => Vec::new(),
    }
}

/// Tangents ⊥ ν: the free directions `free` (already ⊥ ν, orthonormal) first, then the plane
/// ⊥ ν completed.
fn complete_tangents(dim: usize, normal: &[f64; 3], free: &[[f64; 3]]) -> Vec<[f64; 3]> {
    match (dim, free.len()) {
        (2, 1) | (3, 2) => free.to_vec(),
        (3, 1) => vec![free[0], cross(normal, &free[0])],
        _ => tangent_basis(dim, normal),
    }
}

/// Independent directions of `vectors`, orthonormalised (dependent ones dropped).
fn gram_schmidt(vectors: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut span: Vec<[f64; 3]> = Vec::new();
    for v in vectors {
        let mut r = *v;
        for s in &span {
            let proj = dot(&r, s);
            (0..3).for_each(|c| r[c] -= proj * s[c]);
        }
        let len = dot(&r, &r).sqrt();
        if len > 1e-9 {
            span.push(r.map(|x| x / len));
        }
    }
    span
}

fn axis(c: usize) -> [f64; 3] {
    let mut e = [0.0; 3];
    e[c] = 1.0;
    e
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalized(v: [f64; 3]) -> [f64; 3] {
    let len = dot(&v, &v).sqrt();
    v.map(|x| x / len)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh;

    fn frames_of(mesh: &mesh::Mesh, parts: &[&str]) -> Vec<(usize, ContactFrame)> {
        let parts: Vec<usize> = parts.iter().map(|n| mesh.part_index(n).unwrap()).collect();
        let planes = vec![Vec::new(); mesh.n_nodes()];
        let facets = mesh
            .facets_of(&parts)
            .map(|f| (mesh.facet(f).to_vec(), mesh.facet_area_vector(f)));
        contact_frames(mesh.dim, mesh.n_nodes(), facets, &planes)
    }

    #[test]
    fn tangent_bases_are_orthonormal() {
        assert_eq!(tangent_basis(2, &[0.0, -1.0, 0.0]), vec![[1.0, 0.0, 0.0]]);
        let n = [0.6, 0.0, -0.8];
        let t = tangent_basis(3, &n);
        assert!(dot(&t[0], &n).abs() < 1e-15 && dot(&t[1], &n).abs() < 1e-15);
        assert!(dot(&t[0], &t[1]).abs() < 1e-15);
        assert!((dot(&t[0], &t[0]) - 1.0).abs() < 1e-15 && (dot(&t[1], &t[1]) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn a_flat_face_has_its_outward_normal_at_every_node() {
        let mesh = mesh::rectangle(4.0, 1.0, 4, 2);
        let frames = frames_of(&mesh, &["top"]);
        assert_eq!(frames.len(), 5);
        for (_, frame) in &frames {
            assert_eq!(frame.normal, [0.0, 1.0, 0.0]);
            assert_eq!(frame.tangents, vec![[-1.0, 0.0, 0.0]]);
            assert_eq!((frame.n_free, frame.corner), (1, false));
        }
    }

    #[test]
    fn a_corner_between_two_contact_parts_is_held_in_2d() {
        let mesh = mesh::rectangle(4.0, 1.0, 4, 2);
        let frames = frames_of(&mesh, &["bottom", "right"]);
        let corner: Vec<&ContactFrame> = frames.iter().filter(|(_, f)| f.corner).map(|(_, f)| f).collect();
        assert_eq!(corner.len(), 1);
        assert_eq!(corner[0].n_free, 0);
        // Σ |F| ν_F over the bottom edge (length 1) and the right edge (length 0.5).
        let len = 1.25f64.sqrt();
        assert!((corner[0].normal[0] - 0.5 / len).abs() < 1e-15 && (corner[0].normal[1] + 1.0 / len).abs() < 1e-15);
        assert!(frames.iter().filter(|(_, f)| !f.corner).all(|(_, f)| f.n_free == 1));
    }

    #[test]
    fn an_edge_between_two_contact_faces_slides_along_the_edge_in_3d() {
        let mesh = mesh::cuboid([2.0, 1.0, 1.0], [2, 1, 1]);
        let frames = frames_of(&mesh, &["z-", "y-"]);
        for (p, frame) in &frames {
            let x = mesh.coords[*p];
            let on_edge = x[1] == 0.0 && x[2] == 0.0;
            assert_eq!(frame.corner, on_edge, "node {p} at {x:?}");
            if on_edge {
                assert_eq!(frame.n_free, 1);
                assert!((frame.tangents[0][0].abs() - 1.0).abs() < 1e-15, "{:?}", frame.tangents);
            } else {
                assert_eq!(frame.n_free, 2);
            }
        }
    }

    #[test]
    fn normals_on_a_polygonal_circle_point_radially() {
        // A regular 40-gon around the origin, as the Γ_C of a disc: the averaged normal at a
        // vertex is exactly radial.
        let n = 40;
        let x: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let a = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                [a.cos(), a.sin(), 0.0]
            })
            .collect();
        let facets = (0..n).map(|i| {
            let (a, b) = (x[i], x[(i + 1) % n]);
            (vec![i, (i + 1) % n], [b[1] - a[1], a[0] - b[0], 0.0])
        });
        let frames = contact_frames(2, n, facets, &vec![Vec::new(); n]);
        for (p, frame) in frames {
            assert!(!frame.corner);
            assert!((frame.normal[0] - x[p][0]).abs() < 1e-14 && (frame.normal[1] - x[p][1]).abs() < 1e-14);
        }
    }
}
