//! What makes a run implausible, as data the run's observers check step by step: the rigid
//! motions the constraints leave free, and the temperatures the data make plausible.
//!
//! Depends on: [`super::Problem`], [`crate::la::vector`].
//!
//! **Rigid motions nothing holds.** The rigid motions of Ω (d translations, and d(d − 1)/2
//! rotations about the centroid) that lie in E^h are not restrained by Γ_D, the symmetry planes
//! or the bilateral normal constraint on Γ_C (a flat Γ_C leaves its tangential translations, a
//! cylindrical one the rotation about its axis): only friction, bounded, holds the body against
//! them. [`RigidModes`] finds them once at set-up (the near null space of the part of each
//! motion that E^h's nodal constraints remove, [`FREE_MODE_TOLERANCE`]) and measures how far a displacement has moved along
//! them: the criterion of an unrestrained run is a rigid displacement beyond
//! [`RIGID_DISPLACEMENT_LIMIT`] of the body's size, where the model's small-displacement
//! kinematics (contact frames fixed in the reference configuration) no longer hold.
//!
//! **Plausible temperatures.** The data span the range [θ_min, θ_max] of θ₀, θ_D at the fixed
//! nodes and the foundation's θ_R (an affine exchange); a temperature outside
//! [θ_min − m·s, θ_max + m·s], s = max(θ_max − θ_min, [`TEMPERATURE_SPAN_FLOOR`]) and
//! m = [`TEMPERATURE_SPAN_MULTIPLE`], is beyond what conduction, exchange and frictional heating
//! make of them in a plausible run.

use serde::Serialize;

use super::problem::Problem;
use crate::la::vector::dot;

/// A rigid displacement (root mean square over the mass) above this fraction of the body's
/// size (its bounding box's diagonal) makes a run unrestrained.
pub const RIGID_DISPLACEMENT_LIMIT: f64 = 0.1;

/// A rigid motion (of unit norm) counts as free where the nodal constraints remove less than
/// this of its square norm (1 % of its norm): the normals of a curved Γ_C made of facets are
/// not exactly those of the smooth surface, so the motions a cylinder leaves free are removed
/// in part, by about 10⁻⁶ of their square norm on the pad of `scenarios/pad3d.toml`, where the
/// held ones lose 10⁻³ and more.
pub const FREE_MODE_TOLERANCE: f64 = 1e-4;

/// m: temperatures beyond m spans of the data's range are implausible.
pub const TEMPERATURE_SPAN_MULTIPLE: f64 = 10.0;

/// The smallest span s of the data's temperatures (°C or K): data at one temperature still
/// allow heating by m·s.
pub const TEMPERATURE_SPAN_FLOOR: f64 = 100.0;

/// The rigid motions in E^h, ℳ-orthonormal.
#[derive(Debug, Clone)]
pub struct RigidModes {
    /// What each mode is ("translation along x", "rotation about z", or a combination).
    pub names: Vec<String>,
    /// ℳ r_j for the ℳ-orthonormal modes r_j (full velocity dofs).
    mass_modes: Vec<Vec<f64>>,
    /// ∫ρ.
    total_mass: f64,
    /// The diagonal of the mesh's bounding box.
    pub size: f64,
}

impl RigidModes {
    /// The rigid motions of the problem's body that E^h contains (none where Γ_D holds it).
    ///
    /// The part of a motion that the nodal constraints remove is node-local (P Pᵀ per node), so
    /// the Gram matrix of those parts is summed node by node from the motions' values there:
    /// no vector of the mesh's size is made but one per free mode (its ℳ r, kept) and one for
    /// the mass. At 10⁶ unknowns the twelve whole vectors this took before were 72 MB on top
    /// of a set-up's peak.
    pub fn of(problem: &Problem) -> Self {
        let mesh = &problem.mesh;
        let d = mesh.dim;
        let (lo, hi) = bounding_box(mesh);
        let size = (0..d).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt();
        let centre: Vec<f64> = (0..d).map(|c| 0.5 * (lo[c] + hi[c])).collect();
        let motions = RigidMotions::new(mesh, &centre);
        let gram = removed_gram(problem, &motions);
        let (values, vectors) = symmetric_eigen(gram);
        let mass = &problem.matrices.mass;
        let mut modes: Vec<Vec<f64>> = Vec::new();
        let mut mass_modes: Vec<Vec<f64>> = Vec::new();
        let mut names = Vec::new();
        for (value, v) in values.iter().zip(&vectors) {
            if *value > FREE_MODE_TOLERANCE {
                continue;
            }
            let mut r = motions.combination(mesh, v);
            // ℳ-orthonormal against the modes before (Gram–Schmidt).
            for (q, mq) in modes.iter().zip(&mass_modes) {
                let c = dot(&r, mq);
                r.iter_mut().zip(q).for_each(|(a, b)| *a -= c * b);
            }
            let mr = mass.mul(&r);
            let norm = dot(&r, &mr).sqrt();
            if norm <= 0.0 {
                continue;
            }
            names.push(mode_name(v, &motions.names));
            modes.push(r.iter().map(|a| a / norm).collect());
            mass_modes.push(mr.iter().map(|a| a / norm).collect());
        }
        let ones: Vec<f64> = (0..mesh.n_nodes() * d)
            .map(|i| if i % d == 0 { 1.0 } else { 0.0 })
            .collect();
        RigidModes {
            names,
            mass_modes,
            total_mass: mass.quadratic_form(&ones),
            size,
        }
    }

    /// Whether every rigid motion is held by the constraints.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The rigid part of a displacement u along the free modes: its root mean square over the
    /// mass, (Σ_j (r_jᵀℳu)² / ∫ρ)^½.
    pub fn rigid_displacement(&self, u: &[f64]) -> f64 {
        let squares: f64 = self.mass_modes.iter().map(|mr| dot(mr, u).powi(2)).sum();
        (squares / self.total_mass.max(f64::MIN_POSITIVE)).sqrt()
    }

    /// The limit of [`RigidModes::rigid_displacement`]: [`RIGID_DISPLACEMENT_LIMIT`] × size.
    pub fn limit(&self) -> f64 {
        RIGID_DISPLACEMENT_LIMIT * self.size
    }
}

/// The temperatures the data make plausible (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TemperatureRange {
    /// θ_min, θ_max of the data.
    pub data_min: f64,
    pub data_max: f64,
    /// The plausible range [θ_min − m·s, θ_max + m·s].
    pub low: f64,
    pub high: f64,
}

impl TemperatureRange {
    /// From θ₀, θ_D at the fixed nodes and an affine exchange's θ_R.
    pub fn of(problem: &Problem) -> Self {
        let fixed = (problem.temperature.free.iter().zip(&problem.theta_dirichlet))
            .filter(|(free, _)| free.is_none())
            .map(|(_, &theta)| theta);
        let foundation = problem
            .exchange
            .robin()
            .filter(|&(k_e, _)| k_e > 0.0)
            .map(|(_, theta_r)| theta_r);
        let data = problem
            .initial
            .temperature
            .iter()
            .copied()
            .chain(fixed)
            .chain(foundation);
        let (data_min, data_max) = data.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        let span = (data_max - data_min).max(TEMPERATURE_SPAN_FLOOR);
        TemperatureRange {
            data_min,
            data_max,
            low: data_min - TEMPERATURE_SPAN_MULTIPLE * span,
            high: data_max + TEMPERATURE_SPAN_MULTIPLE * span,
        }
    }

    /// The node with the temperature farthest outside the range, and its value (none inside).
    pub fn worst_outside(&self, theta: &[f64]) -> Option<(usize, f64)> {
        let beyond = |v: f64| (self.low - v).max(v - self.high);
        (theta.iter().enumerate())
            .filter(|(_, &v)| !(self.low..=self.high).contains(&v))
            .max_by(|a, b| beyond(*a.1).total_cmp(&beyond(*b.1)))
            .map(|(p, &v)| (p, v))
    }
}

fn bounding_box(mesh: &crate::mesh::Mesh) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in &mesh.coords {
        for c in 0..3 {
            lo[c] = lo[c].min(x[c]);
            hi[c] = hi[c].max(x[c]);
        }
    }
    (lo, hi)
}

/// The d translations and d(d − 1)/2 rotations about `centre`, each scaled to unit Euclidean
/// norm as a full nodal vector, evaluated node by node.
struct RigidMotions {
    dim: usize,
    centre: Vec<f64>,
    /// The rotations' planes (a, b): velocity (−(x_b − c_b), x_a − c_a) in components (a, b).
    planes: Vec<(usize, usize)>,
    /// 1 / the full vector's norm, per motion (translations first).
    scale: Vec<f64>,
    names: Vec<String>,
}

impl RigidMotions {
    fn new(mesh: &crate::mesh::Mesh, centre: &[f64]) -> Self {
        let d = mesh.dim;
        let axes = ["x", "y", "z"];
        let mut names: Vec<String> = (0..d).map(|c| format!("translation along {}", axes[c])).collect();
        let planes: &[(usize, usize, &str)] = if d == 2 {
            &[(0, 1, "z")]
        } else {
            &[(1, 2, "x"), (2, 0, "y"), (0, 1, "z")]
        };
        names.extend(planes.iter().map(|(_, _, axis)| format!("rotation about {axis}")));
        let mut motions = RigidMotions {
            dim: d,
            centre: centre.to_vec(),
            planes: planes.iter().map(|&(a, b, _)| (a, b)).collect(),
            scale: vec![1.0; names.len()],
            names,
        };
        let mut squares = vec![0.0; motions.len()];
        let mut value = [0.0; 3];
        for x in &mesh.coords {
            for (j, square) in squares.iter_mut().enumerate() {
                motions.at(j, x, &mut value);
                *square += value[..d].iter().map(|v| v * v).sum::<f64>();
            }
        }
        for (scale, square) in motions.scale.iter_mut().zip(&squares) {
            *scale = 1.0 / square.sqrt().max(f64::MIN_POSITIVE);
        }
        motions
    }

    fn len(&self) -> usize {
        self.names.len()
    }

    /// Motion j at the point x (unscaled: unit entries, rotations in metres per radian).
    fn at(&self, j: usize, x: &[f64; 3], value: &mut [f64; 3]) {
        *value = [0.0; 3];
        if j < self.dim {
            value[j] = 1.0;
        } else {
            let (a, b) = self.planes[j - self.dim];
            value[a] = -(x[b] - self.centre[b]);
            value[b] = x[a] - self.centre[a];
        }
    }

    /// Σ_j c_j r_j as a full nodal vector.
    fn combination(&self, mesh: &crate::mesh::Mesh, coefficients: &[f64]) -> Vec<f64> {
        let d = self.dim;
        let mut r = vec![0.0; mesh.n_nodes() * d];
        let mut value = [0.0; 3];
        for (p, x) in mesh.coords.iter().enumerate() {
            for (j, c) in coefficients.iter().enumerate() {
                self.at(j, x, &mut value);
                for k in 0..d {
                    r[p * d + k] += c * self.scale[j] * value[k];
                }
            }
        }
        r
    }
}

/// G_ij = Σ_p (r_i − P Pᵀ r_i)_p · (r_j − P Pᵀ r_j)_p over the nodes p: the Gram matrix of the
/// parts of the (unit) motions that E^h's nodal constraints remove. P Pᵀ acts on each node's
/// d components alone (E^h's bases are per node), so each node's part comes from the motions'
/// values there.
fn removed_gram(problem: &Problem, motions: &RigidMotions) -> Vec<Vec<f64>> {
    let (mesh, space) = (&problem.mesh, &problem.velocity);
    let (d, m) = (mesh.dim, motions.len());
    let mut gram = vec![vec![0.0; m]; m];
    let mut removed = vec![[0.0; 3]; m];
    let mut value = [0.0; 3];
    for (p, x) in mesh.coords.iter().enumerate() {
        for (j, part) in removed.iter_mut().enumerate() {
            motions.at(j, x, &mut value);
            value.iter_mut().for_each(|v| *v *= motions.scale[j]);
            let kept = space.node_projection(p, &value);
            for k in 0..d {
                part[k] = value[k] - kept[k];
            }
        }
        for i in 0..m {
            for j in 0..m {
                gram[i][j] += (0..d).map(|k| removed[i][k] * removed[j][k]).sum::<f64>();
            }
        }
    }
    gram
}

/// A free mode's name: the motion it is, or the combination of those it mostly is.
fn mode_name(coefficients: &[f64], names: &[String]) -> String {
    let total: f64 = coefficients.iter().map(|c| c * c).sum();
    let parts: Vec<&str> = (coefficients.iter().zip(names))
        .filter(|(c, _)| c.powi(2) > 1e-3 * total)
        .map(|(_, n)| n.as_str())
        .collect();
    match parts.as_slice() {
        [one] => one.to_string(),
        many => format!("a combination of {}", many.join(" and ")),
    }
}

/// Eigenvalues and unit eigenvectors of a small symmetric matrix (cyclic Jacobi rotations).
fn symmetric_eigen(mut a: Vec<Vec<f64>>) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = a.len();
    // v[i] is the i-th eigenvector (a row), built from the identity.
    let mut v: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
        .collect();
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j].powi(2))
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
                for k in 0..n {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vpk, vqk) = (v[p][k], v[q][k]);
                    v[p][k] = c * vpk - s * vqk;
                    v[q][k] = s * vpk + c * vqk;
                }
            }
        }
    }
    ((0..n).map(|i| a[i][i]).collect(), v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::samples;

    /// The node-by-node Gram matrix against the one of whole vectors (r − P Pᵀ r by E^h's
    /// restriction and prolongation, then dot products), on the 2D and 3D examples: clamped
    /// (their Gram matrices are far from singular) and with the clamp on the contact face only.
    #[test]
    fn the_gram_matrix_node_by_node_is_that_of_whole_vectors() {
        let problems = [
            samples::paper(8, 2, 2).unwrap(),
            samples::paper_3d([6, 2, 2], 2).unwrap(),
            samples::paper_3d_builder([6, 2, 2], 2).dirichlet(&[]).build().unwrap(),
        ];
        for problem in &problems {
            let (mesh, space) = (&problem.mesh, &problem.velocity);
            let (lo, hi) = bounding_box(mesh);
            let centre: Vec<f64> = (0..mesh.dim).map(|c| 0.5 * (lo[c] + hi[c])).collect();
            let motions = RigidMotions::new(mesh, &centre);
            let m = motions.len();
            let removed: Vec<Vec<f64>> = (0..m)
                .map(|j| {
                    let unit: Vec<f64> = (0..m).map(|i| f64::from(u8::from(i == j))).collect();
                    let r = motions.combination(mesh, &unit);
                    assert!((dot(&r, &r) - 1.0).abs() < 1e-12, "motion {j} is not of unit norm");
                    let kept = space.prolong(&space.restrict_values(&r));
                    r.iter().zip(&kept).map(|(a, b)| a - b).collect()
                })
                .collect();
            let gram = removed_gram(problem, &motions);
            for i in 0..m {
                for j in 0..m {
                    let whole = dot(&removed[i], &removed[j]);
                    assert!(
                        (gram[i][j] - whole).abs() < 1e-13,
                        "G[{i}][{j}] = {} against {whole}",
                        gram[i][j]
                    );
                }
            }
        }
    }

    #[test]
    fn jacobi_finds_the_null_space() {
        // (1, −1, 0) spans the null space.
        let (values, vectors) = symmetric_eigen(vec![vec![1.0, 1.0, 0.0], vec![1.0, 1.0, 0.0], vec![0.0, 0.0, 3.0]]);
        let zero = values.iter().position(|v| v.abs() < 1e-12).expect("a zero eigenvalue");
        let v = &vectors[zero];
        assert!((v[0] + v[1]).abs() < 1e-12 && v[2].abs() < 1e-12 && (v[0].abs() - 0.5f64.sqrt()).abs() < 1e-12);
        let mut sorted = values.clone();
        sorted.sort_by(f64::total_cmp);
        assert!(
            (sorted[1] - 2.0).abs() < 1e-12 && (sorted[2] - 3.0).abs() < 1e-12,
            "{values:?}"
        );
    }
}
