//! Load terms ∫ f · φ_p on cells or boundary parts, integrated into full P1 nodal vectors.

use super::quadrature::{self, Rule};
use super::{Datum, LoadError};
use crate::mesh::simplex::{facet_measure, Simplex};
use crate::mesh::Mesh;

/// Where a load acts and what its datum means.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadKind {
    /// A force density f₀ (d components) over the cells: ∫_Ω f₀ · φ.
    BodyForce,
    /// A traction f₂ (d components, global axes) on boundary parts: ∫_Γ f₂ · φ.
    Traction { parts: Vec<usize> },
    /// A pressure p (1 component) on boundary parts, the traction −p ν with ν the outward unit
    /// normal: ∫_Γ −p ν · φ. Positive p pushes on the body.
    Pressure { parts: Vec<usize> },
    /// A heat source g (1 component) over the cells: ∫_Ω g η.
    HeatSource,
    /// A heat flux q into the body (1 component) on boundary parts: ∫_Γ q η.
    HeatFlux { parts: Vec<usize> },
}

impl LoadKind {
    /// The name used in messages.
    pub fn name(&self) -> &'static str {
        match self {
            LoadKind::BodyForce => "body force",
            LoadKind::Traction { .. } => "traction",
            LoadKind::Pressure { .. } => "pressure",
            LoadKind::HeatSource => "heat source",
            LoadKind::HeatFlux { .. } => "heat flux",
        }
    }

    /// Components of the datum in dimension `dim`.
    pub fn datum_components(&self, dim: usize) -> usize {
        match self {
            LoadKind::BodyForce | LoadKind::Traction { .. } => dim,
            LoadKind::Pressure { .. } | LoadKind::HeatSource | LoadKind::HeatFlux { .. } => 1,
        }
    }

    /// Entries per node of the vector the load adds into: d (velocity) or 1 (temperature).
    pub fn entries_per_node(&self, dim: usize) -> usize {
        match self {
            LoadKind::HeatSource | LoadKind::HeatFlux { .. } => 1,
            _ => dim,
        }
    }

    fn parts(&self) -> Option<&[usize]> {
        match self {
            LoadKind::Traction { parts } | LoadKind::Pressure { parts } | LoadKind::HeatFlux { parts } => Some(parts),
            LoadKind::BodyForce | LoadKind::HeatSource => None,
        }
    }
}

/// A load term built once per run: [`Load::add_to`] adds F(t)_p = ∫ f(·, t) · φ_p.
///
/// Nothing is recomputed that did not change. At construction, by the datum:
/// - independent of t (a constant, or an expression of x only): F is integrated once;
/// - affine, f = c + t r: F_c and F_r are integrated once and F(t) = F_c + t F_r;
/// - an expression of t only: U, the load of the datum 1 in every component, is integrated
///   once and F(t)_(p,c) = f_c(t) U_(p,c) (for a pressure, p(t) U);
/// - an expression of x (and t): integrated at the quadrature points on every call, from
///   cached element measures (and normals), without allocating.
///
/// Data independent of x use the exact P1 integrals: ∫_T φ_p = |T|/(d + 1) on cells,
/// ℓ_p = Σ_F |F|/d on facets, and ∫_F ν φ_p = ν_F |F|/d for a pressure, so that these loads equal
/// [`crate::fem::assembly::body_load`] and [`crate::fem::assembly::traction_load`] to round-off.
/// Data depending on x use rules exact for degree 2 (edge: 2-point Gauss; triangle: the edge
/// midpoints; tetrahedron: 4 points), hence exact for data affine in x.
#[derive(Debug, Clone)]
pub struct Load {
    label: String,
    kind: LoadKind,
    datum: Datum,
    /// Length of the output vector: nodes × entries per node.
    len: usize,
    plan: Plan,
}

#[derive(Debug, Clone)]
enum Plan {
    /// F(t) = F.
    Fixed(Vec<f64>),
    /// F(t) = F_c + t F_r.
    Affine { constant: Vec<f64>, rate: Vec<f64> },
    /// F(t)_(p,c) = s_c(t) U_(p,c); `witness` is a point of the region, for error messages.
    Scaled { unit: Vec<f64>, witness: [f64; 3] },
    /// Quadrature at every call.
    Quadrature(Elements),
}

/// The elements a load integrates over, with what quadrature needs of them.
#[derive(Debug, Clone)]
struct Elements {
    /// Cell indices, or boundary facet indices when `on_facets`.
    ids: Vec<usize>,
    on_facets: bool,
    /// |T| or |F| for each element.
    measures: Vec<f64>,
    /// Outward unit normal of each facet (pressure only; empty otherwise).
    normals: Vec<[f64; 3]>,
    rule: &'static Rule,
}

impl Load {
    /// Checks the datum against the kind and integrates what does not depend on t.
    pub fn new(mesh: &Mesh, kind: LoadKind, datum: Datum, label: String) -> Result<Load, LoadError> {
        let d = mesh.dim;
        check_datum(&datum, kind.datum_components(d), kind.name(), &label)?;
        if let Some(parts) = kind.parts() {
            let n_parts = mesh.part_names.len();
            if let Some(&part) = parts.iter().find(|&&p| p >= n_parts) {
                return Err(LoadError::UnknownPart { label, part, n_parts });
            }
        }
        let elements = Elements::new(mesh, &kind);
        let n = datum.n_components();
        let plan = match &datum {
            Datum::Constant(c) => {
                check_finite(c, &label, elements.witness(mesh), 0.0)?;
                Plan::Fixed(exact_load(mesh, &kind, &elements, c))
            }
            Datum::Affine { constant, rate } => {
                check_finite(constant, &label, elements.witness(mesh), 0.0)?;
                check_finite(rate, &label, elements.witness(mesh), 0.0)?;
                let constant = exact_load(mesh, &kind, &elements, constant);
                if datum.uses_time() {
                    Plan::Affine {
                        constant,
                        rate: exact_load(mesh, &kind, &elements, rate),
                    }
                } else {
                    Plan::Fixed(constant)
                }
            }
            Datum::Expressions(_) if !datum.uses_space() && !datum.uses_time() => {
                let mut value = vec![0.0; n];
                let witness = elements.witness(mesh);
                datum.eval(witness, 0.0, &mut value);
                check_finite(&value, &label, witness, 0.0)?;
                Plan::Fixed(exact_load(mesh, &kind, &elements, &value))
            }
            Datum::Expressions(_) if !datum.uses_space() => Plan::Scaled {
                unit: exact_load(mesh, &kind, &elements, &vec![1.0; n]),
                witness: elements.witness(mesh),
            },
            Datum::Expressions(_) => Plan::Quadrature(elements),
        };
        let mut load = Load {
            len: mesh.n_nodes() * kind.entries_per_node(d),
            label,
            kind,
            datum,
            plan,
        };
        if matches!(load.plan, Plan::Quadrature(_)) && !load.datum.uses_time() {
            // An expression of x only: integrate once, at any t, and keep the vector.
            let mut fixed = vec![0.0; load.len];
            load.add_to(mesh, 0.0, &mut fixed)?;
            load.plan = Plan::Fixed(fixed);
        }
        Ok(load)
    }

    /// Adds F(t), the load at time t, into `out` (full nodal numbering: d entries per node for the
    /// vector kinds, 1 for the heat source). `mesh` must be the mesh the load was built on. On a
    /// [`LoadError::NotFinite`], `out` may hold part of the sum.
    pub fn add_to(&self, mesh: &Mesh, t: f64, out: &mut [f64]) -> Result<(), LoadError> {
        if out.len() != self.len || mesh.n_nodes() * self.kind.entries_per_node(mesh.dim) != self.len {
            return Err(LoadError::OutputLength {
                label: self.label.clone(),
                expected: self.len,
                found: out.len(),
            });
        }
        match &self.plan {
            Plan::Fixed(f) => out.iter_mut().zip(f).for_each(|(o, f)| *o += f),
            Plan::Affine { constant, rate } => {
                for ((o, c), r) in out.iter_mut().zip(constant).zip(rate) {
                    *o += c + t * r;
                }
            }
            Plan::Scaled { unit, witness } => {
                let mut value = [0.0; 3];
                let n = self.datum.n_components();
                self.datum.eval(*witness, t, &mut value[..n]);
                check_finite(&value[..n], &self.label, *witness, t)?;
                let m = self.kind.entries_per_node(mesh.dim);
                // One datum component per output component, or a scalar (pressure) for all.
                let scale: [f64; 3] = std::array::from_fn(|c| value[if n == 1 { 0 } else { c }]);
                for (o, u) in out.chunks_exact_mut(m).zip(unit.chunks_exact(m)) {
                    for c in 0..m {
                        o[c] += scale[c] * u[c];
                    }
                }
            }
            Plan::Quadrature(elements) => self.integrate(mesh, elements, t, out)?,
        }
        Ok(())
    }

    /// ∫ f · φ_p by quadrature, for a datum depending on x.
    fn integrate(&self, mesh: &Mesh, elements: &Elements, t: f64, out: &mut [f64]) -> Result<(), LoadError> {
        let d = mesh.dim;
        let n = self.datum.n_components();
        let rule = elements.rule;
        let mut f = [0.0; 3];
        for (k, &id) in elements.ids.iter().enumerate() {
            let nodes = if elements.on_facets {
                mesh.facet(id)
            } else {
                mesh.cell(id)
            };
            let weight = elements.measures[k] * rule.weight;
            for bary in rule.points {
                let mut x = [0.0; 3];
                for (a, &p) in nodes.iter().enumerate() {
                    for r in 0..3 {
                        x[r] += bary[a] * mesh.coords[p][r];
                    }
                }
                self.datum.eval(x, t, &mut f[..n]);
                check_finite(&f[..n], &self.label, x, t)?;
                for (a, &p) in nodes.iter().enumerate() {
                    let w = weight * bary[a];
                    match self.kind {
                        LoadKind::BodyForce | LoadKind::Traction { .. } => {
                            for c in 0..d {
                                out[p * d + c] += w * f[c];
                            }
                        }
                        LoadKind::Pressure { .. } => {
                            let normal = elements.normals[k];
                            for c in 0..d {
                                out[p * d + c] -= w * f[0] * normal[c];
                            }
                        }
                        LoadKind::HeatSource | LoadKind::HeatFlux { .. } => out[p] += w * f[0],
                    }
                }
            }
        }
        Ok(())
    }

    /// The label given at construction (named in every error).
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The kind of load.
    pub fn kind(&self) -> &LoadKind {
        &self.kind
    }

    /// The datum.
    pub fn datum(&self) -> &Datum {
        &self.datum
    }

    /// Whether F(t) changes with t (if not, a caller may add it once).
    pub fn depends_on_time(&self) -> bool {
        !matches!(self.plan, Plan::Fixed(_))
    }
}

impl Elements {
    fn new(mesh: &Mesh, kind: &LoadKind) -> Elements {
        let d = mesh.dim;
        let mut vertices = [[0.0; 3]; 4];
        match kind.parts() {
            None => {
                let ids: Vec<usize> = (0..mesh.n_cells()).collect();
                let measures = ids
                    .iter()
                    .map(|&e| {
                        for (v, &p) in vertices.iter_mut().zip(mesh.cell(e)) {
                            *v = mesh.coords[p];
                        }
                        Simplex::new(d, &vertices[..=d]).measure
                    })
                    .collect();
                Elements {
                    ids,
                    on_facets: false,
                    measures,
                    normals: Vec::new(),
                    rule: quadrature::degree_two(d + 1),
                }
            }
            Some(parts) => {
                let ids: Vec<usize> = mesh.facets_of(parts).collect();
                let measures = ids
                    .iter()
                    .map(|&f| {
                        for (v, &p) in vertices.iter_mut().zip(mesh.facet(f)) {
                            *v = mesh.coords[p];
                        }
                        // The same measure as `assembly::boundary_weights`, for equal round-off.
                        facet_measure(d, &vertices[..d])
                    })
                    .collect();
                let normals = match kind {
                    LoadKind::Pressure { .. } => ids.iter().map(|&f| mesh.facet_normal(f)).collect(),
                    _ => Vec::new(),
                };
                Elements {
                    ids,
                    on_facets: true,
                    measures,
                    normals,
                    rule: quadrature::degree_two(d),
                }
            }
        }
    }

    fn nodes<'m>(&self, mesh: &'m Mesh, k: usize) -> &'m [usize] {
        if self.on_facets {
            mesh.facet(self.ids[k])
        } else {
            mesh.cell(self.ids[k])
        }
    }

    /// A point of the region (its first vertex; the origin if the region is empty), named when
    /// a datum that does not depend on x is not finite.
    fn witness(&self, mesh: &Mesh) -> [f64; 3] {
        if self.ids.is_empty() {
            [0.0; 3]
        } else {
            mesh.coords[self.nodes(mesh, 0)[0]]
        }
    }
}

/// The exact P1 load of a datum constant in x with value `value`: the nodal weights
/// w_p = ∫ φ_p (|T|/(d + 1) per cell vertex, |F|/d per facet vertex) times the value, or
/// −p Σ_F ν_F |F|/d for a pressure.
fn exact_load(mesh: &Mesh, kind: &LoadKind, elements: &Elements, value: &[f64]) -> Vec<f64> {
    let d = mesh.dim;
    let m = kind.entries_per_node(d);
    let mut out = vec![0.0; mesh.n_nodes() * m];
    if let LoadKind::Pressure { .. } = kind {
        for (k, &measure) in elements.measures.iter().enumerate() {
            let share = measure / d as f64;
            let normal = elements.normals[k];
            for &p in elements.nodes(mesh, k) {
                for c in 0..d {
                    out[p * d + c] -= value[0] * normal[c] * share;
                }
            }
        }
        return out;
    }
    let n_vertices = if elements.on_facets { d } else { d + 1 };
    let mut weights = vec![0.0; mesh.n_nodes()];
    for (k, &measure) in elements.measures.iter().enumerate() {
        let share = measure / n_vertices as f64;
        for &p in elements.nodes(mesh, k) {
            weights[p] += share;
        }
    }
    for (p, w) in weights.iter().enumerate() {
        for c in 0..m {
            out[p * m + c] = value[c] * w;
        }
    }
    out
}

fn check_datum(datum: &Datum, expected: usize, kind: &'static str, label: &str) -> Result<(), LoadError> {
    if let Some((constant, rate)) = datum.affine_mismatch() {
        return Err(LoadError::AffineLengths {
            label: label.to_string(),
            constant,
            rate,
        });
    }
    if datum.n_components() != expected {
        return Err(LoadError::ComponentCount {
            label: label.to_string(),
            kind,
            expected,
            found: datum.n_components(),
        });
    }
    Ok(())
}

fn check_finite(values: &[f64], label: &str, x: [f64; 3], t: f64) -> Result<(), LoadError> {
    match values.iter().find(|v| !v.is_finite()) {
        None => Ok(()),
        Some(&value) => Err(LoadError::NotFinite {
            label: label.to_string(),
            x,
            t,
            value,
        }),
    }
}

/// The datum at every node at time t, `n_components` entries per node (node-major): initial
/// fields u₀, u₁, θ₀. `label` names the field in errors.
pub fn nodal_values(mesh: &Mesh, datum: &Datum, t: f64, label: &str) -> Result<Vec<f64>, LoadError> {
    if let Some((constant, rate)) = datum.affine_mismatch() {
        return Err(LoadError::AffineLengths {
            label: label.to_string(),
            constant,
            rate,
        });
    }
    let n = datum.n_components();
    let mut values = vec![0.0; mesh.n_nodes() * n];
    if n == 0 {
        return Ok(values);
    }
    for (x, out) in mesh.coords.iter().zip(values.chunks_exact_mut(n)) {
        datum.eval(*x, t, out);
        check_finite(out, label, *x, t)?;
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::{assembly, kernels};
    use crate::mesh::{cuboid, rectangle};

    fn load(mesh: &Mesh, kind: LoadKind, datum: Datum) -> Load {
        Load::new(mesh, kind, datum, "test load".into()).unwrap_or_else(|e| panic!("{e}"))
    }

    fn at(load: &Load, mesh: &Mesh, t: f64) -> Vec<f64> {
        let mut out = vec![0.0; load.len];
        load.add_to(mesh, t, &mut out).unwrap_or_else(|e| panic!("{e}"));
        out
    }

    /// Σ_p F_(p,c) for each component c.
    fn totals(f: &[f64], m: usize) -> Vec<f64> {
        (0..m).map(|c| f.iter().skip(c).step_by(m).sum()).collect()
    }

    fn assert_close(a: &[f64], b: &[f64], tol: f64) {
        assert_eq!(a.len(), b.len());
        let scale = b.iter().fold(1.0f64, |s, v| s.max(v.abs()));
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert!((x - y).abs() <= tol * scale, "entry {i}: {x} vs {y}");
        }
    }

    fn part(mesh: &Mesh, name: &str) -> usize {
        mesh.part_index(name).unwrap()
    }

    #[test]
    fn constant_body_force_sums_to_force_times_volume_and_equals_assembly() {
        for (mesh, f) in [
            (rectangle(40.0, 10.0, 8, 3), vec![1.5, -2.0]),
            (cuboid([2.0, 1.0, 3.0], [2, 3, 2]), vec![0.5, -1.0, 4.0]),
        ] {
            let l = load(&mesh, LoadKind::BodyForce, Datum::constant(f.clone()));
            assert!(!l.depends_on_time());
            let got = at(&l, &mesh, 3.0);
            let volume = mesh.volume();
            for (total, fc) in totals(&got, mesh.dim).iter().zip(&f) {
                assert!(
                    (total - fc * volume).abs() < 1e-12 * volume,
                    "{total} vs {}",
                    fc * volume
                );
            }
            assert_close(&got, &assembly::body_load(&mesh, &f), 1e-15);
        }
    }

    #[test]
    fn constant_heat_source_equals_assembly() {
        let mesh = cuboid([1.0, 2.0, 1.0], [2, 2, 3]);
        let got = at(&load(&mesh, LoadKind::HeatSource, Datum::scalar(7.0)), &mesh, 0.0);
        assert_close(&got, &assembly::scalar_body_load(&mesh, 7.0), 1e-15);
    }

    #[test]
    fn constant_traction_equals_assembly() {
        let mesh = rectangle(40.0, 10.0, 8, 3);
        let parts = vec![part(&mesh, "top"), part(&mesh, "right")];
        let f = [0.0, -3.0];
        let l = load(
            &mesh,
            LoadKind::Traction { parts: parts.clone() },
            Datum::constant(f.to_vec()),
        );
        assert_close(&at(&l, &mesh, 1.0), &assembly::traction_load(&mesh, &parts, &f), 1e-15);

        let mesh = cuboid([2.0, 1.0, 3.0], [2, 3, 2]);
        let parts = vec![part(&mesh, "z+")];
        let f = [1.0, 2.0, -3.0];
        let l = load(
            &mesh,
            LoadKind::Traction { parts: parts.clone() },
            Datum::constant(f.to_vec()),
        );
        assert_close(&at(&l, &mesh, 1.0), &assembly::traction_load(&mesh, &parts, &f), 1e-15);
    }

    #[test]
    fn affine_and_expression_of_t_agree() {
        let mesh = rectangle(40.0, 10.0, 8, 3);
        let t = 0.7;
        let top = vec![part(&mesh, "top")];
        let cases = [
            (
                LoadKind::BodyForce,
                vec![3.0, -1.0],
                vec![2.0, 0.5],
                vec!["3+2*t", "-1+0.5*t"],
            ),
            (
                LoadKind::Traction { parts: top.clone() },
                vec![3.0, 0.0],
                vec![2.0, 1.0],
                vec!["3+2*t", "t"],
            ),
            (LoadKind::Pressure { parts: top }, vec![3.0], vec![2.0], vec!["3+2*t"]),
            (LoadKind::HeatSource, vec![3.0], vec![2.0], vec!["3+2*t"]),
        ];
        for (kind, constant, rate, texts) in cases {
            let affine = load(&mesh, kind.clone(), Datum::affine(constant, rate));
            assert!(matches!(affine.plan, Plan::Affine { .. }));
            let expected = at(&affine, &mesh, t);
            // t only: integrated once with value 1, scaled at each t.
            let scaled = load(&mesh, kind.clone(), Datum::expressions(&texts).unwrap());
            assert!(matches!(scaled.plan, Plan::Scaled { .. }), "{kind:?}");
            assert_close(&at(&scaled, &mesh, t), &expected, 1e-13);
            // The same data written to depend on x: quadrature on every call, exact for affine data.
            let texts: Vec<String> = texts.iter().map(|s| format!("{s} + 0*x")).collect();
            let quadrature = load(&mesh, kind.clone(), Datum::expressions(&texts).unwrap());
            assert!(matches!(quadrature.plan, Plan::Quadrature(_)));
            assert_close(&at(&quadrature, &mesh, t), &expected, 1e-13);
        }
    }

    /// F_a = Σ_T Σ_b M^T_ab f(x_b): the exact P1 load of a datum affine in x.
    fn exact_p1_load(mesh: &Mesh, f: impl Fn([f64; 3]) -> f64) -> Vec<f64> {
        let mut out = vec![0.0; mesh.n_nodes()];
        for e in 0..mesh.n_cells() {
            let mass = kernels::scalar_mass(&Simplex::new(mesh.dim, &mesh.cell_coords(e)));
            for (a, &p) in mesh.cell(e).iter().enumerate() {
                for (b, &q) in mesh.cell(e).iter().enumerate() {
                    out[p] += mass[a][b] * f(mesh.coords[q]);
                }
            }
        }
        out
    }

    #[test]
    fn expression_linear_in_x_is_integrated_exactly() {
        let (lx, ly) = (40.0, 10.0);
        let mesh = rectangle(lx, ly, 8, 3);
        let g = load(&mesh, LoadKind::HeatSource, Datum::expression("x").unwrap());
        assert!(!g.depends_on_time(), "an expression of x alone is integrated once");
        let got = at(&g, &mesh, 0.0);
        let integral: f64 = got.iter().sum();
        assert!((integral - lx * lx / 2.0 * ly).abs() < 1e-10, "∫ x = {integral}");
        assert_close(&got, &exact_p1_load(&mesh, |x| x[0]), 1e-14);

        // Vector, time-dependent: ∫ (x t, 2y − 1) = (t lx² ly / 2, lx ly² − lx ly).
        let f = load(
            &mesh,
            LoadKind::BodyForce,
            Datum::expressions(&["x*t", "2*y - 1"]).unwrap(),
        );
        let sums = totals(&at(&f, &mesh, 0.5), 2);
        assert!((sums[0] - 0.5 * lx * lx * ly / 2.0).abs() < 1e-10);
        assert!((sums[1] - (lx * ly * ly - lx * ly)).abs() < 1e-10);

        let mesh = cuboid([2.0, 1.0, 3.0], [2, 3, 2]);
        let g = load(
            &mesh,
            LoadKind::HeatSource,
            Datum::expression("x + 2*y - z + 1").unwrap(),
        );
        assert_close(
            &at(&g, &mesh, 0.0),
            &exact_p1_load(&mesh, |x| x[0] + 2.0 * x[1] - x[2] + 1.0),
            1e-14,
        );
    }

    #[test]
    fn uniform_pressure_on_a_closed_boundary_has_no_resultant() {
        for mesh in [rectangle(40.0, 10.0, 8, 3), cuboid([2.0, 1.0, 3.0], [2, 3, 2])] {
            let all: Vec<usize> = (0..mesh.part_names.len()).collect();
            for datum in [Datum::scalar(5.0), Datum::expression("5 + 0*x").unwrap()] {
                let p = load(&mesh, LoadKind::Pressure { parts: all.clone() }, datum);
                for total in totals(&at(&p, &mesh, 0.0), mesh.dim) {
                    assert!(total.abs() < 1e-12, "∮ ν ≠ 0: {total}");
                }
            }
        }
    }

    #[test]
    fn uniform_pressure_on_top_pushes_down() {
        let (lx, p) = (40.0, 5.0);
        let mesh = rectangle(lx, 10.0, 8, 3);
        let top = vec![part(&mesh, "top")];
        let exact = at(
            &load(&mesh, LoadKind::Pressure { parts: top.clone() }, Datum::scalar(p)),
            &mesh,
            0.0,
        );
        let sums = totals(&exact, 2);
        assert!(sums[0].abs() < 1e-12 && (sums[1] + p * lx).abs() < 1e-12, "{sums:?}");
        // −p ν ℓ_p node by node.
        let weights = assembly::boundary_weights(&mesh, &top);
        let expected: Vec<f64> = weights.iter().flat_map(|w| [0.0, -p * w]).collect();
        assert_close(&exact, &expected, 1e-15);
    }

    #[test]
    fn varying_pressure_matches_a_hand_integral() {
        // p = y on `right` (x = lx, ν = e_x): F_(j,x) = −∫ y φ_j, with φ_j the hat of node j at
        // y_j = j h: −h y_j inside, −h²/6 at y = 0 and −h (3 ly − h)/6 at y = ly; F_(j,y) = 0.
        let (lx, ly, ny) = (40.0, 10.0, 5);
        let mesh = rectangle(lx, ly, 4, ny);
        let right = vec![part(&mesh, "right")];
        let got = at(
            &load(
                &mesh,
                LoadKind::Pressure { parts: right },
                Datum::expression("y").unwrap(),
            ),
            &mesh,
            0.0,
        );
        let h = ly / ny as f64;
        for (p, x) in mesh.coords.iter().enumerate() {
            let expected = if x[0] < lx {
                0.0
            } else if x[1] == 0.0 {
                -h * h / 6.0
            } else if x[1] == ly {
                -h * (3.0 * ly - h) / 6.0
            } else {
                -h * x[1]
            };
            assert!(
                (got[2 * p] - expected).abs() < 1e-12,
                "node {p} at {x:?}: {} vs {expected}",
                got[2 * p]
            );
            assert!(got[2 * p + 1].abs() < 1e-12);
        }
        assert!((totals(&got, 2)[0] + ly * ly / 2.0).abs() < 1e-12);
    }

    #[test]
    fn non_finite_values_name_the_label_and_the_point() {
        // Nodes (and vertical edges) at x = 20: the edge midpoints hit the pole.
        let mesh = rectangle(40.0, 10.0, 4, 2);
        let g = Load::new(
            &mesh,
            LoadKind::HeatSource,
            Datum::expression("t/(x-20)").unwrap(),
            "g".into(),
        )
        .unwrap();
        match g.add_to(&mesh, 1.0, &mut vec![0.0; mesh.n_nodes()]) {
            Err(LoadError::NotFinite { label, x, t, value }) => {
                assert_eq!(label, "g");
                assert_eq!((x[0], t), (20.0, 1.0));
                assert!(value.is_infinite());
            }
            other => panic!("expected NotFinite, got {other:?}"),
        }
        // Without t the load is integrated at construction, which reports it.
        let err = Load::new(
            &mesh,
            LoadKind::HeatSource,
            Datum::expression("1/(x-20)").unwrap(),
            "g".into(),
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("`g`") && err.to_string().contains("20"),
            "{err}"
        );
        let err = Load::new(
            &mesh,
            LoadKind::BodyForce,
            Datum::expressions(&["0", "sqrt(x-100)"]).unwrap(),
            "gravity".into(),
        )
        .unwrap_err();
        assert!(matches!(err, LoadError::NotFinite { ref label, value, .. } if label == "gravity" && value.is_nan()));
        // A t-only datum that blows up at some t.
        let s = Load::new(
            &mesh,
            LoadKind::HeatSource,
            Datum::expression("1/(t-2)").unwrap(),
            "s".into(),
        )
        .unwrap();
        assert!(s.add_to(&mesh, 1.0, &mut vec![0.0; mesh.n_nodes()]).is_ok());
        assert!(matches!(
            s.add_to(&mesh, 2.0, &mut vec![0.0; mesh.n_nodes()]),
            Err(LoadError::NotFinite { t: 2.0, .. })
        ));
        // Nodal values too.
        let err = nodal_values(&mesh, &Datum::expression("1/(x-20)").unwrap(), 0.0, "theta0").unwrap_err();
        assert!(matches!(err, LoadError::NotFinite { ref label, x, .. } if label == "theta0" && x[0] == 20.0));
    }

    #[test]
    fn wrong_component_count_names_the_label() {
        let mesh = rectangle(4.0, 1.0, 2, 1);
        let err = Load::new(&mesh, LoadKind::BodyForce, Datum::scalar(1.0), "f0".into()).unwrap_err();
        assert_eq!(
            err,
            LoadError::ComponentCount {
                label: "f0".into(),
                kind: "body force",
                expected: 2,
                found: 1
            }
        );
        assert!(err.to_string().contains("`f0`"));
        let top = vec![part(&mesh, "top")];
        let err = Load::new(
            &mesh,
            LoadKind::Pressure { parts: top.clone() },
            Datum::constant(vec![1.0, 2.0]),
            "p".into(),
        );
        assert!(matches!(
            err,
            Err(LoadError::ComponentCount {
                expected: 1,
                found: 2,
                ..
            })
        ));
        let err = Load::new(
            &mesh,
            LoadKind::Traction { parts: top },
            Datum::affine(vec![1.0, 2.0], vec![1.0]),
            "f2".into(),
        );
        assert!(matches!(
            err,
            Err(LoadError::AffineLengths {
                constant: 2,
                rate: 1,
                ..
            })
        ));
        let err = Load::new(
            &mesh,
            LoadKind::Traction { parts: vec![7] },
            Datum::constant(vec![0.0, 1.0]),
            "f2".into(),
        );
        assert!(matches!(
            err,
            Err(LoadError::UnknownPart {
                part: 7,
                n_parts: 4,
                ..
            })
        ));
    }

    #[test]
    fn output_of_the_wrong_length_is_refused() {
        let mesh = rectangle(4.0, 1.0, 2, 1);
        let g = load(&mesh, LoadKind::HeatSource, Datum::scalar(1.0));
        let err = g.add_to(&mesh, 0.0, &mut vec![0.0; 2 * mesh.n_nodes()]).unwrap_err();
        assert!(matches!(
            err,
            LoadError::OutputLength {
                expected: 6,
                found: 12,
                ..
            }
        ));
    }

    #[test]
    fn add_to_accumulates() {
        let mesh = rectangle(4.0, 1.0, 2, 1);
        let g = load(&mesh, LoadKind::HeatSource, Datum::expression("x*t").unwrap());
        let once = at(&g, &mesh, 2.0);
        let mut twice = once.clone();
        g.add_to(&mesh, 2.0, &mut twice).unwrap();
        assert_close(&twice, &once.iter().map(|v| 2.0 * v).collect::<Vec<_>>(), 1e-15);
    }

    #[test]
    fn nodal_values_sample_every_node() {
        let mesh = cuboid([1.0, 2.0, 3.0], [1, 2, 1]);
        let u0 = nodal_values(&mesh, &Datum::expressions(&["x", "t*y", "1"]).unwrap(), 2.0, "u0").unwrap();
        for (p, x) in mesh.coords.iter().enumerate() {
            assert_eq!(&u0[3 * p..3 * p + 3], &[x[0], 2.0 * x[1], 1.0]);
        }
        let theta0 = nodal_values(&mesh, &Datum::affine(vec![1.0], vec![3.0]), 0.5, "theta0").unwrap();
        assert!(theta0.iter().all(|&v| v == 2.5));
    }
}
