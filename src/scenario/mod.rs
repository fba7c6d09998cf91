//! Scenario files: every parameter of a run, in TOML.
//!
//! The paper's Section 6 example is built in (`scenarios/paper.toml`, printed by
//! `thermocontact scenario`). A user file is laid over it key by key, then `--set a.b=value`
//! overrides are applied, then the result is checked: unknown keys, wrong types and invalid
//! values are errors that name the dotted key, the value and what was expected.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use toml::{Table, Value};

use crate::contact::{LinearHeating, QuadraticExchange, SlipWeakening, Tresca};
use crate::driver::{OutputPlan, Summary};
use crate::error::Error;
use crate::loads::{Datum, Expression};
use crate::material::{Isotropic, Material};
use crate::mesh::{self, Mesh};
use crate::model::{InitialFields, LoadTarget, ModelError, Problem, ProblemBuilder, TimeGrid};
use crate::step::{KrylovParams, PreconditionerKind};
use crate::model::State;
use crate::step::{LinearKind, SolverKind, SolverParams};

/// The deepest cutback a scenario may ask for: 2^20 substeps of one step is already a
/// different time grid, not a rescue.
pub const MAX_CUTBACK_DEPTH: usize = 20;

/// The default scenario (the paper's example), with comments.
pub const DEFAULT_TOML: &str = include_str!("../../scenarios/paper.toml");

/// A complete, validated scenario.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// The box of the structured generator; absent when the mesh comes from a file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geometry: Option<Geometry>,
    pub mesh: MeshSpec,
    pub time: TimeSpec,
    pub boundary: BoundarySpec,
    pub material: MaterialSpec,
    pub initial: InitialSpec,
    pub loads: Loads,
    pub friction: FrictionSpec,
    pub heat_exchange: HeatExchangeSpec,
    pub frictional_heating: Affine<f64>,
    pub solver: SolverSpec,
    pub output: OutputSpec,
    /// The mesh read from `mesh.file`, kept from validation to the build.
    #[serde(skip)]
    loaded: LoadedMesh,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// Side lengths of the rectangle (2 values) or box (3 values).
    pub lengths: Vec<f64>,
}

/// The mesh: a Gmsh file, or cell counts for the structured generator over `geometry`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// A Gmsh `.msh` file (a path relative to the scenario file; stored resolved).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nx: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ny: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nz: Option<usize>,
}

/// A structured mesh: the box and its cell counts (2 or 3 of each).
#[derive(Debug, Clone, PartialEq)]
pub struct Structured {
    pub lengths: Vec<f64>,
    pub cells: Vec<usize>,
}

impl Structured {
    /// Cells along x.
    pub fn nx(&self) -> usize {
        self.cells[0]
    }

    /// Cells along y.
    pub fn ny(&self) -> usize {
        self.cells[1]
    }
}

/// A mesh read once from a file and shared by the clones of a scenario; equal to any other (the
/// file name is what identifies a scenario).
#[derive(Debug, Clone, Default)]
struct LoadedMesh(Option<Arc<Mesh>>);

impl PartialEq for LoadedMesh {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    pub final_time: f64,
    pub steps: usize,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// Γ_D (may be empty: a body held by friction alone).
    pub dirichlet: Vec<String>,
    pub neumann: Vec<String>,
    pub contact: Vec<String>,
    /// θ_D on Γ_D ∪ Γ_N.
    pub temperature: f64,
    /// Symmetry (roller) planes: w·ν = 0, no shear traction, no heat flux (optional; none in
    /// the default).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub symmetry: Vec<String>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub density: f64,
    pub heat_capacity: f64,
    pub viscosity_mu1: f64,
    pub viscosity_mu2: f64,
    pub young: f64,
    pub poisson: f64,
    pub thermal_expansion: f64,
    pub conductivity: f64,
    pub reference_temperature: f64,
}

/// The initial data (10), each a datum at t = 0 (numbers or expressions of x, y, z).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// A checkpoint of another run on the same mesh whose u, w, θ become u₀, u₁, θ₀ (the data
    /// below are then unused); a path relative to the scenario file, stored resolved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<PathBuf>,
    pub displacement: DatumSpec,
    pub velocity: DatumSpec,
    pub temperature: DatumSpec,
}

/// A datum affine in time: value(t) = constant + rate · t.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Affine<T> {
    pub constant: T,
    pub rate: T,
}

impl Affine<f64> {
    /// The value at time t.
    pub fn at(&self, t: f64) -> f64 {
        self.constant + self.rate * t
    }
}

/// A datum as a scenario writes it: a number or an array of numbers (constant), a
/// `{ constant, rate }` table (affine in t), or a string or an array of strings (expressions in
/// x, y, z, t).
#[derive(Debug, Clone, PartialEq)]
pub enum DatumSpec {
    Numbers(Vec<f64>),
    Affine(Affine<Vec<f64>>),
    Expressions(Vec<String>),
    /// A single number or string, written without brackets.
    Scalar(Box<DatumSpec>),
}

const DATUM_FORMS: &str = "a number or an array of numbers, a { constant, rate } table, or an expression \
     string (or an array of them) in x, y, z, t";

impl<'de> Deserialize<'de> for DatumSpec {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error as _;
        let value = Value::deserialize(deserializer)?;
        let number = |v: &Value| match v {
            Value::Float(x) => Some(*x),
            Value::Integer(i) => Some(*i as f64),
            _ => None,
        };
        let numbers = |v: &Value| match v {
            Value::Array(items) => items.iter().map(number).collect::<Option<Vec<f64>>>(),
            v => number(v).map(|x| vec![x]),
        };
        let spec = match &value {
            Value::Float(_) | Value::Integer(_) => {
                DatumSpec::Scalar(Box::new(DatumSpec::Numbers(numbers(&value).unwrap_or_default())))
            }
            Value::String(text) => DatumSpec::Scalar(Box::new(DatumSpec::Expressions(vec![text.clone()]))),
            Value::Array(items) if items.iter().all(|v| number(v).is_some()) => {
                DatumSpec::Numbers(numbers(&value).unwrap_or_default())
            }
            Value::Array(items) if items.iter().all(Value::is_str) => {
                DatumSpec::Expressions(items.iter().filter_map(|v| v.as_str().map(String::from)).collect())
            }
            Value::Table(table) if table.len() == 2 && table.contains_key("constant") && table.contains_key("rate") => {
                match (numbers(&table["constant"]), numbers(&table["rate"])) {
                    (Some(constant), Some(rate)) if constant.len() == rate.len() => {
                        let affine = DatumSpec::Affine(Affine { constant, rate });
                        if table["constant"].is_array() {
                            affine
                        } else {
                            DatumSpec::Scalar(Box::new(affine))
                        }
                    }
                    _ => {
                        return Err(D::Error::custom(
                            "constant and rate must be numbers (or arrays of equal length)",
                        ))
                    }
                }
            }
            _ => return Err(D::Error::custom(DATUM_FORMS)),
        };
        Ok(spec)
    }
}

impl Serialize for DatumSpec {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            DatumSpec::Numbers(v) => v.serialize(serializer),
            DatumSpec::Expressions(v) => v.serialize(serializer),
            DatumSpec::Affine(a) => a.serialize(serializer),
            DatumSpec::Scalar(inner) => match inner.as_ref() {
                DatumSpec::Numbers(v) if v.len() == 1 => v[0].serialize(serializer),
                DatumSpec::Expressions(v) if v.len() == 1 => v[0].serialize(serializer),
                DatumSpec::Affine(a) if a.constant.len() == 1 => Affine {
                    constant: a.constant[0],
                    rate: a.rate[0],
                }
                .serialize(serializer),
                other => other.serialize(serializer),
            },
        }
    }
}

impl DatumSpec {
    /// A constant datum.
    pub fn numbers(values: &[f64]) -> Self {
        DatumSpec::Numbers(values.to_vec())
    }

    /// A constant scalar, written without brackets.
    pub fn scalar(value: f64) -> Self {
        DatumSpec::Scalar(Box::new(DatumSpec::Numbers(vec![value])))
    }

    /// The values of a constant datum (`None` for affine data and expressions).
    pub fn constant(&self) -> Option<&[f64]> {
        match self {
            DatumSpec::Numbers(v) => Some(v),
            DatumSpec::Scalar(inner) => inner.constant(),
            _ => None,
        }
    }

    /// The value of a constant scalar datum.
    pub fn as_scalar(&self) -> Option<f64> {
        self.constant().filter(|v| v.len() == 1).map(|v| v[0])
    }

    /// The datum of the core, with `n` components, its expressions compiled; errors name `key`.
    pub fn to_datum(&self, key: &str, n: usize) -> Result<Datum, Error> {
        let expected = || {
            if n == 1 {
                "one component (a scalar)".to_string()
            } else {
                format!("{n} components (one per space dimension)")
            }
        };
        let count = |len: usize| {
            if len == n {
                Ok(())
            } else {
                Err(invalid(key, &self.to_string(), &expected()))
            }
        };
        let finite = |values: &[f64]| {
            if values.iter().all(|v| v.is_finite() && v.abs() <= MAX_MAGNITUDE) {
                Ok(())
            } else {
                Err(invalid(key, &self.to_string(), "finite numbers of magnitude ≤ 1e18"))
            }
        };
        match self {
            DatumSpec::Scalar(inner) => inner.to_datum(key, n),
            DatumSpec::Numbers(values) => {
                count(values.len())?;
                finite(values)?;
                Ok(Datum::Constant(values.clone()))
            }
            DatumSpec::Affine(Affine { constant, rate }) => {
                count(constant.len())?;
                finite(constant)?;
                finite(rate)?;
                Ok(Datum::affine(constant.clone(), rate.clone()))
            }
            DatumSpec::Expressions(texts) => {
                count(texts.len())?;
                let compiled = texts
                    .iter()
                    .map(|text| {
                        Expression::parse(text).map_err(|e| Error::InvalidValue {
                            key: key.to_string(),
                            value: format!("{text:?}"),
                            expected: format!("an expression of x, y, z, t; {e}"),
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(Datum::Expressions(compiled))
            }
        }
    }
}

impl std::fmt::Display for DatumSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let text = toml::Value::try_from(self).map(|v| v.to_string()).unwrap_or_default();
        f.write_str(&text)
    }
}

/// A traction f₂ on a Neumann part: `value` (any datum form), or the affine `constant` + `rate`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Traction {
    pub part: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<DatumSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub constant: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate: Option<Vec<f64>>,
}

impl Traction {
    /// The keys the entry sets, as a user would list them: "{part, constant}".
    fn given_keys(&self) -> String {
        let given = [
            ("part", true),
            ("value", self.value.is_some()),
            ("constant", self.constant.is_some()),
            ("rate", self.rate.is_some()),
        ];
        let names: Vec<&str> = given.iter().filter(|(_, set)| *set).map(|(name, _)| *name).collect();
        format!("{{{}}}", names.join(", "))
    }

    /// The traction as one datum form; errors name `key`.
    fn datum_spec(&self, key: &str) -> Result<DatumSpec, Error> {
        match (&self.value, &self.constant, &self.rate) {
            (Some(value), None, None) => Ok(value.clone()),
            (None, Some(constant), Some(rate)) => Ok(DatumSpec::Affine(Affine {
                constant: constant.clone(),
                rate: rate.clone(),
            })),
            _ => Err(Error::InvalidValue {
                key: key.to_string(),
                value: self.given_keys(),
                expected: "either `value` or both `constant` and `rate`".to_string(),
            }),
        }
    }
}

/// A normal pressure p on a Neumann part: the traction −p ν.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Pressure {
    pub part: String,
    pub value: DatumSpec,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Loads {
    pub body_force: DatumSpec,
    pub heat_source: DatumSpec,
    #[serde(default)]
    pub traction: Vec<Traction>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pressure: Vec<Pressure>,
}

/// The friction law on Γ_C.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "law", rename_all = "kebab-case", deny_unknown_fields)]
pub enum FrictionSpec {
    /// μ(r) = (a − b) e^(−αr) + b, bound μ(r) S (eq. (81)–(83)).
    SlipWeakening { bound: f64, a: f64, b: f64, alpha: f64 },
    /// Constant bound S.
    Tresca { bound: f64 },
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HeatExchangeSpec {
    pub coefficient: f64,
    pub foundation_temperature: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    pub kind: SolverKind,
    pub tolerance: f64,
    pub max_convexification: usize,
    pub inner_tolerance: f64,
    pub max_inner: usize,
    pub max_sweeps: usize,
    pub cutback: bool,
    pub max_cutback_depth: usize,
    pub slip_tolerance: f64,
    pub linear: LinearKind,
    pub krylov_tolerance: f64,
    pub max_krylov: usize,
    pub preconditioner: PreconditionerKind,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    pub times: Vec<f64>,
    pub every: usize,
    pub checkpoint_every: usize,
    pub vtk: bool,
    pub compress: bool,
    pub csv: bool,
}

impl Default for Scenario {
    fn default() -> Self {
        Scenario::load(None, &[]).expect("the built-in scenario is valid")
    }
}

impl Scenario {
    /// Loads a scenario: the built-in default, overlaid by the file's text (if any), overlaid by
    /// `key.path=value` overrides; then validated. A relative `mesh.file` is taken relative to
    /// the current directory.
    pub fn load(file_text: Option<&str>, overrides: &[String]) -> Result<Self, Error> {
        Self::load_in(file_text, overrides, None, None)
    }

    /// [`Scenario::load`] on a mesh given in memory (built by a program, e.g. from arrays): the
    /// mesh replaces the structured generator as a `mesh.file` does — the default's geometry,
    /// cell counts and tractions (on the rectangle's parts) go — and the boundary parts named in
    /// the text and overrides are checked against the mesh's. The text may hold no `geometry`
    /// and no `mesh` keys. The mesh is not part of [`Scenario::to_toml`]: load that text again
    /// with the same mesh.
    ///
    /// ```
    /// use thermocontact::{mesh, Scenario};
    /// let m = mesh::rectangle(40.0, 10.0, 8, 2); // parts left, right, bottom, top
    /// let s = Scenario::load_with_mesh(None, &["time.steps=4".into()], m).unwrap();
    /// assert_eq!((s.dim(), s.structured(), s.time.steps), (2, None, 4));
    /// ```
    pub fn load_with_mesh(
        file_text: Option<&str>,
        overrides: &[String],
        mesh: impl Into<Arc<Mesh>>,
    ) -> Result<Self, Error> {
        Self::load_in(file_text, overrides, None, Some(mesh.into()))
    }

    /// [`Scenario::load`] from a file: a relative `mesh.file` in it is taken relative to the
    /// file's folder.
    pub fn load_file(path: &Path, overrides: &[String]) -> Result<Self, Error> {
        // A scenario is a page of settings; data arrays belong in mesh files. Parsing holds
        // ~60× the text in memory, so a huge file is refused before it is read.
        if let Ok(meta) = std::fs::metadata(path) {
            if meta.len() > MAX_SCENARIO_BYTES {
                return Err(Error::Scenario(format!(
                    "{} has {} bytes; a scenario file has at most {MAX_SCENARIO_BYTES}",
                    path.display(),
                    meta.len()
                )));
            }
        }
        let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::load_in(Some(&text), overrides, path.parent(), None)
    }

    fn load_in(
        file_text: Option<&str>,
        overrides: &[String],
        folder: Option<&Path>,
        given: Option<Arc<Mesh>>,
    ) -> Result<Self, Error> {
        let mut table: Table = DEFAULT_TOML.parse().expect("built-in scenario parses");
        if given.is_some() {
            drop_generator(&mut table);
        }
        if let Some(text) = file_text {
            let mut user: Table = text
                .parse()
                .map_err(|e: toml::de::Error| Error::Scenario(format!("the file is not valid TOML: {e}")))?;
            resolve_mesh_file(&mut user, folder);
            if given.is_some() {
                refuse_mesh_keys(&user)?;
            }
            overlay(&mut table, user, "")?;
        }
        // All overrides form one table laid over at once, so that `friction.law=tresca` and
        // `friction.bound=100` together switch the law (one at a time, the second would meet
        // the first's table, which the switch has emptied).
        let mut assigned = Table::new();
        for assignment in overrides {
            merge(&mut assigned, parse_override(assignment)?);
        }
        if given.is_some() {
            refuse_mesh_keys(&assigned)?;
        }
        overlay(&mut table, assigned, "")?;
        let text = toml::to_string(&table).map_err(|e| Error::Scenario(e.to_string()))?;
        let mut scenario: Scenario = toml::from_str(&text).map_err(|e| describe(&e, &text))?;
        if let Some(mesh) = given {
            scenario.loaded = LoadedMesh(Some(mesh));
        }
        if let Some(from) = &mut scenario.initial.from {
            *from = std::path::absolute(&*from).unwrap_or_else(|_| from.clone());
        }
        if let Some(file) = &mut scenario.mesh.file {
            *file = std::path::absolute(&*file).unwrap_or_else(|_| file.clone());
            let mesh = mesh::read_msh(file).map_err(Error::Mesh)?;
            scenario.loaded = LoadedMesh(Some(Arc::new(mesh)));
        }
        scenario.validate()?;
        Ok(scenario)
    }

    /// The scenario as TOML (what a run saves beside its results).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scenario serializes")
    }

    /// The structured mesh's box and cell counts; `None` for a mesh from a file.
    pub fn structured(&self) -> Option<Structured> {
        let lengths = self.geometry.as_ref()?.lengths.clone();
        let mut cells = vec![self.mesh.nx?, self.mesh.ny?];
        cells.extend(self.mesh.nz);
        Some(Structured { lengths, cells })
    }

    /// Sets the structured mesh's cell counts (nz only for a box).
    pub fn set_cells(&mut self, nx: usize, ny: usize) {
        self.mesh.nx = Some(nx);
        self.mesh.ny = Some(ny);
    }

    /// The mesh: read from `mesh.file` (once, when the scenario was loaded) or generated.
    pub fn mesh(&self) -> Result<Mesh, Error> {
        if let Some(mesh) = &self.loaded.0 {
            return Ok(mesh.as_ref().clone());
        }
        if let Some(file) = &self.mesh.file {
            return mesh::read_msh(file).map_err(Error::Mesh);
        }
        let s = self.structured().ok_or_else(|| {
            invalid(
                "mesh",
                &"(no file, no cell counts)",
                "`file` or the cell counts nx, ny (and nz) with geometry.lengths",
            )
        })?;
        let generated = match (s.lengths.as_slice(), s.cells.as_slice()) {
            ([lx, ly], [nx, ny]) => mesh::try_rectangle(*lx, *ly, *nx, *ny),
            ([lx, ly, lz], [nx, ny, nz]) => mesh::try_cuboid([*lx, *ly, *lz], [*nx, *ny, *nz]),
            _ => {
                return Err(invalid(
                    "geometry.lengths",
                    &s.lengths,
                    "2 lengths with mesh.nx, mesh.ny (rectangle) or 3 with mesh.nx, mesh.ny, mesh.nz (box)",
                ))
            }
        };
        // Validation bounds the cells' shape; this catches what it does not foresee (a scenario
        // changed after validation), naming the keys rather than panicking.
        generated.map_err(|e| Error::InvalidValue {
            key: "geometry.lengths".to_string(),
            value: format!("{:?} with the cell counts {:?}", s.lengths, s.cells),
            expected: format!(
                "a box whose generated mesh is valid (change geometry.lengths or mesh.nx, mesh.ny, mesh.nz): {e}"
            ),
        })
    }

    /// Space dimension d (2 for a rectangle or a 2D mesh, 3 for a box or a 3D mesh).
    pub fn dim(&self) -> usize {
        match (&self.loaded.0, &self.geometry) {
            (Some(mesh), _) => mesh.dim,
            (None, Some(g)) => g.lengths.len(),
            (None, None) => 0,
        }
    }

    /// Time step k = T/N.
    pub fn time_step(&self) -> f64 {
        self.time.final_time / self.time.steps as f64
    }

    /// The names of the mesh's boundary parts.
    fn part_names(&self) -> Vec<String> {
        match (&self.loaded.0, self.dim()) {
            (Some(mesh), _) => mesh.part_names.clone(),
            (None, 2) => mesh::rectangle_part_names().map(String::from).to_vec(),
            (None, _) => mesh::cuboid_part_names().map(String::from).to_vec(),
        }
    }

    /// Checks every value against its admissible range.
    pub fn validate(&self) -> Result<(), Error> {
        if self.mesh.file.is_none() && self.loaded.0.is_none() {
            self.validate_structured()?;
        }
        let d = self.dim();
        positive("time.final_time", self.time.final_time)?;
        at_least_one("time.steps", self.time.steps)?;
        if self.time.steps > MAX_STEPS {
            return Err(invalid("time.steps", &self.time.steps, "at most 1 000 000 steps"));
        }
        self.fits_in_memory()?;

        let parts = self.part_names();
        let mut seen: Vec<&str> = Vec::new();
        for (key, list) in [
            ("boundary.dirichlet", &self.boundary.dirichlet),
            ("boundary.neumann", &self.boundary.neumann),
            ("boundary.contact", &self.boundary.contact),
            ("boundary.symmetry", &self.boundary.symmetry),
        ] {
            for name in list {
                if !parts.contains(name) {
                    return Err(invalid(
                        key,
                        name,
                        &format!("boundary parts of the mesh, among {parts:?}"),
                    ));
                }
                if seen.contains(&name.as_str()) {
                    return Err(invalid(
                        key,
                        name,
                        "each boundary part in at most one of dirichlet, neumann, contact, symmetry",
                    ));
                }
                seen.push(name);
            }
        }
        if self.boundary.contact.is_empty() {
            return Err(invalid("boundary.contact", &"[]", "at least one part for Γ_C"));
        }

        let m = &self.material;
        positive("material.density", m.density)?;
        positive("material.heat_capacity", m.heat_capacity)?;
        positive("material.viscosity_mu2", m.viscosity_mu2)?;
        if !m.viscosity_mu1.is_finite() || m.viscosity_mu1 * d as f64 + m.viscosity_mu2 <= 0.0 {
            return Err(invalid(
                "material.viscosity_mu1",
                &m.viscosity_mu1,
                "d·μ₁ + μ₂ > 0 (𝒜 coercive)",
            ));
        }
        positive("material.young", m.young)?;
        if !(m.poisson > -1.0 && m.poisson < 0.5) {
            return Err(invalid("material.poisson", &m.poisson, "a Poisson ratio in (−1, 0.5)"));
        }
        finite("material.thermal_expansion", m.thermal_expansion)?;
        finite("material.reference_temperature", m.reference_temperature)?;
        positive("material.conductivity", m.conductivity)?;

        self.initial.displacement.to_datum("initial.displacement", d)?;
        self.initial.velocity.to_datum("initial.velocity", d)?;
        self.initial.temperature.to_datum("initial.temperature", 1)?;
        finite("boundary.temperature", self.boundary.temperature)?;

        self.loads.body_force.to_datum("loads.body_force", d)?;
        self.loads.heat_source.to_datum("loads.heat_source", 1)?;
        for (i, t) in self.loads.traction.iter().enumerate() {
            let key = format!("loads.traction[{i}]");
            self.neumann_part(&format!("{key}.part"), &t.part)?;
            t.datum_spec(&key)?.to_datum(&key, d)?;
        }
        for (i, p) in self.loads.pressure.iter().enumerate() {
            let key = format!("loads.pressure[{i}]");
            self.neumann_part(&format!("{key}.part"), &p.part)?;
            p.value.to_datum(&format!("{key}.value"), 1)?;
        }

        match self.friction {
            FrictionSpec::SlipWeakening { bound, a, b, alpha } => {
                non_negative("friction.bound", bound)?;
                positive("friction.b", b)?;
                finite("friction.a", a)?;
                if a < b {
                    return Err(invalid("friction.a", &a, &format!("a ≥ b = {b} (μ decreasing)")));
                }
                non_negative("friction.alpha", alpha)?;
            }
            FrictionSpec::Tresca { bound } => non_negative("friction.bound", bound)?,
        }
        non_negative("heat_exchange.coefficient", self.heat_exchange.coefficient)?;
        finite(
            "heat_exchange.foundation_temperature",
            self.heat_exchange.foundation_temperature,
        )?;
        finite("frictional_heating.constant", self.frictional_heating.constant)?;
        finite("frictional_heating.rate", self.frictional_heating.rate)?;

        let s = &self.solver;
        positive("solver.tolerance", s.tolerance)?;
        at_least_one("solver.max_convexification", s.max_convexification)?;
        positive("solver.inner_tolerance", s.inner_tolerance)?;
        at_least_one("solver.max_inner", s.max_inner)?;
        if s.max_cutback_depth > MAX_CUTBACK_DEPTH {
            return Err(invalid(
                "solver.max_cutback_depth",
                &s.max_cutback_depth,
                &format!("at most {MAX_CUTBACK_DEPTH} (2^{MAX_CUTBACK_DEPTH} substeps of k/2^{MAX_CUTBACK_DEPTH})"),
            ));
        }
        non_negative("solver.slip_tolerance", s.slip_tolerance)?;
        if !(s.krylov_tolerance > 0.0 && s.krylov_tolerance < 1.0) {
            return Err(invalid(
                "solver.krylov_tolerance",
                &s.krylov_tolerance,
                "a relative residual in (0, 1)",
            ));
        }
        at_least_one("solver.max_krylov", s.max_krylov)?;
        if s.preconditioner == PreconditionerKind::Amg && !cfg!(feature = "petsc") {
            return Err(invalid(
                "solver.preconditioner",
                &"amg",
                "\"ilu\": this build has no AMG (build thermocontact with `--features petsc`, which needs PETSc)",
            ));
        }
        if self.output.times.len() > MAX_OUTPUT_TIMES {
            return Err(invalid(
                "output.times",
                &format!("{} times", self.output.times.len()),
                "at most 100 000 output times (each one a frame)",
            ));
        }
        for &t in &self.output.times {
            if !(t >= 0.0 && t <= self.time.final_time * (1.0 + 1e-12)) {
                return Err(invalid(
                    "output.times",
                    &t,
                    &format!(
                        "times in [0, T] (0: the initial state) with T = time.final_time = {}",
                        self.time.final_time
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Refuses a mesh whose run cannot fit in the machine's memory, before it is generated
    /// ([`crate::resources`]).
    fn fits_in_memory(&self) -> Result<(), Error> {
        let d = self.dim();
        let (nodes, keys) = match (&self.loaded.0, self.structured()) {
            (Some(mesh), _) => {
                let source = match &self.mesh.file {
                    Some(_) => "mesh.file",
                    None => "the mesh given in memory",
                };
                (mesh.n_nodes() as f64, source.to_string())
            }
            (None, Some(s)) => {
                let names = ["mesh.nx", "mesh.ny", "mesh.nz"];
                let nodes = s.cells.iter().map(|&n| n as f64 + 1.0).product();
                (nodes, names[..s.cells.len()].join(" × "))
            }
            (None, None) => return Ok(()),
        };
        let unknowns = (d + 1) as f64 * nodes;
        // Without /proc/meminfo, a bound no machine passes.
        let available = crate::resources::machine_memory().unwrap_or(1e15);
        let linear = (self.solver.linear).resolve(d, unknowns as usize, self.solver.kind, available);
        let needed = match linear {
            LinearKind::Iterative => crate::resources::estimated_memory_iterative(unknowns),
            _ => crate::resources::estimated_memory(d, unknowns),
        };
        if needed > available {
            let direct = linear != LinearKind::Iterative;
            return Err(Error::TooLarge {
                keys,
                path: if direct {
                    "direct factorization"
                } else {
                    "iterative solver"
                },
                hint: if direct && d == 3 {
                    " or solver.linear = \"iterative\" (memory linear in the unknowns)"
                } else {
                    ""
                },
                unknowns,
                needed: crate::resources::human(needed),
                available: crate::resources::human(available),
            });
        }
        Ok(())
    }

    fn validate_structured(&self) -> Result<(), Error> {
        let Some(geometry) = &self.geometry else {
            return Err(invalid(
                "geometry.lengths",
                &"(missing)",
                "the box of the structured mesh (or a mesh.file)",
            ));
        };
        let d = geometry.lengths.len();
        if d != 2 && d != 3 {
            return Err(invalid(
                "geometry.lengths",
                &geometry.lengths,
                "2 lengths (rectangle) or 3 (box)",
            ));
        }
        for &l in &geometry.lengths {
            if !(l >= LENGTH_RANGE.0 && l <= LENGTH_RANGE.1) {
                return Err(invalid("geometry.lengths", &l, "lengths in [1e-6, 1e6]"));
            }
        }
        for (key, count) in [("mesh.nx", self.mesh.nx), ("mesh.ny", self.mesh.ny)] {
            match count {
                Some(n) => at_least_one(key, n)?,
                None => return Err(invalid(key, &"(missing)", "a cell count (or a mesh.file)")),
            }
        }
        match (d, self.mesh.nz) {
            (3, None) => {
                return Err(invalid(
                    "mesh.nz",
                    &"(missing)",
                    "a cell count for the box's z direction",
                ))
            }
            (3, Some(nz)) => at_least_one("mesh.nz", nz)?,
            (2, Some(nz)) => return Err(invalid("mesh.nz", &nz, "no nz for a rectangle (2 lengths)")),
            _ => {}
        }
        self.validate_cell_shape()
    }

    /// The structured mesh's cells no more elongated than [`MAX_CELL_ASPECT`]: within the
    /// length range, a box of 1e-6 × 1e6 would otherwise give cells that the mesh's check finds
    /// degenerate (or a step matrix singular in floating point).
    fn validate_cell_shape(&self) -> Result<(), Error> {
        let Some(s) = self.structured() else {
            return Ok(());
        };
        let sides: Vec<f64> = s.lengths.iter().zip(&s.cells).map(|(&l, &n)| l / n as f64).collect();
        let longest = sides.iter().cloned().fold(0.0, f64::max);
        let shortest = sides.iter().cloned().fold(f64::INFINITY, f64::min);
        let ratio = longest / shortest;
        if ratio <= MAX_CELL_ASPECT {
            return Ok(());
        }
        let names = &["mesh.nx", "mesh.ny", "mesh.nz"][..s.cells.len()];
        let counts: Vec<String> = s.cells.iter().map(usize::to_string).collect();
        let sizes: Vec<String> = sides.iter().map(|h| format!("{h:.3e}")).collect();
        Err(Error::InvalidValue {
            key: "geometry.lengths".to_string(),
            value: format!(
                "{:?} with {} = {}, cells of {}",
                s.lengths,
                names.join(" × "),
                counts.join(" × "),
                sizes.join(" × ")
            ),
            expected: format!(
                "cells whose longest side is at most {MAX_CELL_ASPECT:e} times their shortest, not {ratio:.1e} times: \
                 change geometry.lengths or the cell counts {}",
                names.join(", ")
            ),
        })
    }

    fn neumann_part(&self, key: &str, part: &str) -> Result<(), Error> {
        if self.boundary.neumann.iter().any(|p| p == part) {
            Ok(())
        } else {
            Err(invalid(
                key,
                &part,
                &format!("a Neumann part, one of {:?}", self.boundary.neumann),
            ))
        }
    }

    /// Time levels n (0 ≤ n ≤ N) of the output: the output times, each rounded to the nearest
    /// level (a time that rounds to 0 is the initial state), and every `output.every`-th level;
    /// sorted and without repeats.
    pub fn output_steps(&self) -> Vec<usize> {
        let k = self.time_step();
        let n_steps = self.time.steps;
        let mut steps: Vec<usize> = self
            .output
            .times
            .iter()
            .map(|&t| ((t / k).round() as usize).min(n_steps))
            .collect();
        if let Some(frames) = n_steps.checked_div(self.output.every) {
            steps.extend((1..=frames).map(|i| i * self.output.every));
        }
        steps.sort_unstable();
        steps.dedup();
        steps
    }

    /// The material of the scenario.
    pub fn material(&self) -> Material {
        let m = &self.material;
        Material {
            density: m.density,
            heat_capacity: m.heat_capacity,
            viscosity: Isotropic::viscosity(m.viscosity_mu1, m.viscosity_mu2),
            elasticity: Isotropic::elasticity(m.young, m.poisson),
            expansion: Material::expansion_from(m.thermal_expansion, m.young, m.poisson),
            conductivity: m.conductivity,
            reference_temperature: m.reference_temperature,
        }
    }

    /// The scenario's problem, ready for a builder's last touches (extra loads).
    pub fn builder(&self) -> Result<ProblemBuilder, Error> {
        let mesh = self.mesh()?;
        let initial = match &self.initial.from {
            Some(path) => Some(initial_state(path, &mesh)?),
            None => None,
        };
        let d = mesh.dim;
        let b = &self.boundary;
        let h = &self.heat_exchange;
        let mut builder = ProblemBuilder::new(
            mesh,
            self.material(),
            TimeGrid::new(self.time.final_time, self.time.steps),
        )
        .dirichlet(&names(&b.dirichlet))
        .neumann(&names(&b.neumann))
        .contact(&names(&b.contact))
        .symmetry(&names(&b.symmetry))
        .boundary_temperature(b.temperature)
        .heat_exchange(QuadraticExchange {
            coefficient: h.coefficient,
            foundation_temperature: h.foundation_temperature,
        })
        .frictional_heating(LinearHeating::affine(
            self.frictional_heating.constant,
            self.frictional_heating.rate,
        ))
        .initial_displacement(
            self.initial.displacement.to_datum("initial.displacement", d)?,
            "initial.displacement",
        )
        .initial_velocity(
            self.initial.velocity.to_datum("initial.velocity", d)?,
            "initial.velocity",
        )
        .initial_temperature(
            self.initial.temperature.to_datum("initial.temperature", 1)?,
            "initial.temperature",
        );
        if let Some(fields) = initial {
            builder = builder.initial_fields(fields, "initial.from");
        }
        builder = match self.friction {
            FrictionSpec::SlipWeakening { bound, a, b, alpha } => builder.friction(SlipWeakening {
                scale: bound,
                a,
                b,
                alpha,
            }),
            FrictionSpec::Tresca { bound } => builder.friction(Tresca { scale: bound }),
        };
        let loads = &self.loads;
        builder = builder
            .labelled_load(
                LoadTarget::BodyForce,
                loads.body_force.to_datum("loads.body_force", d)?,
                "loads.body_force".into(),
            )
            .labelled_load(
                LoadTarget::HeatSource,
                loads.heat_source.to_datum("loads.heat_source", 1)?,
                "loads.heat_source".into(),
            );
        for (i, t) in loads.traction.iter().enumerate() {
            let key = format!("loads.traction[{i}]");
            let datum = t.datum_spec(&key)?.to_datum(&key, d)?;
            builder = builder.labelled_load(LoadTarget::Traction(t.part.clone()), datum, key);
        }
        for (i, p) in loads.pressure.iter().enumerate() {
            let key = format!("loads.pressure[{i}].value");
            let datum = p.value.to_datum(&key, 1)?;
            builder = builder.labelled_load(LoadTarget::Pressure(p.part.clone()), datum, key);
        }
        Ok(builder)
    }

    /// The discrete problem of the scenario.
    pub fn build(&self) -> Result<Problem, Error> {
        self.builder()?.build().map_err(|e| match e {
            ModelError::CurvedSymmetryPart { part } => invalid("boundary.symmetry", &part, "flat parts (a symmetry plane)"),
            other => other.into(),
        })
    }

    /// The solver settings of the scenario.
    pub fn solver_params(&self) -> SolverParams {
        let s = &self.solver;
        SolverParams {
            kind: s.kind,
            tolerance: s.tolerance,
            max_convexification: s.max_convexification,
            inner_tolerance: s.inner_tolerance,
            max_inner: s.max_inner,
            max_sweeps: s.max_sweeps,
            cutback: s.cutback,
            max_cutback_depth: s.max_cutback_depth,
            linear: s.linear,
            krylov: KrylovParams {
                rtol: s.krylov_tolerance,
                max_iterations: s.max_krylov,
                preconditioner: s.preconditioner,
                ..KrylovParams::default()
            },
        }
    }

    /// What a run of the scenario writes, and when.
    pub fn output_plan(&self) -> OutputPlan {
        OutputPlan {
            steps: self.output_steps(),
            vtk: self.output.vtk,
            compress: self.output.compress,
            csv: self.output.csv,
            slip_tolerance: self.solver.slip_tolerance,
            record: Some(self.to_toml()),
            fingerprint: Some(self.fingerprint()),
            checkpoint_every: (self.output.checkpoint_every > 0).then_some(self.output.checkpoint_every),
        }
    }

    /// SHA-256 of everything that defines the problem: the scenario without `[output]` and
    /// `[solver]` (a run may be continued with other output times or solver settings, e.g. a
    /// larger `solver.max_sweeps` after a failure) and without `mesh.file`'s path (the mesh has
    /// a fingerprint of its own).
    pub fn fingerprint(&self) -> String {
        let mut table: Table = self.to_toml().parse().expect("a scenario's TOML parses");
        table.remove("output");
        table.remove("solver");
        if let Some(Value::Table(mesh)) = table.get_mut("mesh") {
            mesh.remove("file");
        }
        crate::output::checkpoint::text_fingerprint(&table.to_string())
    }

    /// Builds and runs the scenario without writing files (tests and studies); returns the
    /// summary and the state at T.
    pub fn run_quiet(&self) -> Result<(Summary, State), Error> {
        let problem = self.build()?;
        crate::driver::run_quiet(&problem, &self.solver_params(), &self.output_plan())
    }
}

fn names(list: &[String]) -> Vec<&str> {
    list.iter().map(String::as_str).collect()
}

/// Takes a relative `mesh.file` of a scenario file relative to the file's folder.
/// u, w, θ of the checkpoint at `path` (`initial.from`), which must be of a run on `mesh`.
fn initial_state(path: &Path, mesh: &Mesh) -> Result<InitialFields, Error> {
    let checkpoint = crate::output::checkpoint::read(path)?;
    if checkpoint.identity.mesh != crate::output::checkpoint::mesh_fingerprint(mesh) {
        return Err(invalid(
            "initial.from",
            &path.display().to_string(),
            "a checkpoint of a run on this scenario's mesh (its mesh differs)",
        ));
    }
    let state = checkpoint.state;
    Ok(InitialFields {
        displacement: state.u,
        velocity: state.w,
        temperature: state.theta,
    })
}

/// Paths in a scenario file (`mesh.file`, `initial.from`) are relative to its folder.
fn resolve_mesh_file(user: &mut Table, folder: Option<&Path>) {
    let Some(folder) = folder else {
        return;
    };
    for (table, key) in [("mesh", "file"), ("initial", "from")] {
        if let Some(Value::Table(t)) = user.get_mut(table) {
            if let Some(Value::String(file)) = t.get_mut(key) {
                if Path::new(file.as_str()).is_relative() {
                    *file = folder.join(file.as_str()).to_string_lossy().into_owned();
                }
            }
        }
    }
}

fn invalid(key: &str, value: &dyn std::fmt::Debug, expected: &str) -> Error {
    Error::InvalidValue {
        key: key.to_string(),
        value: format!("{value:?}"),
        expected: expected.to_string(),
    }
}

/// The largest magnitude a scenario number may have. Every datum enters the step matrix or its
/// right-hand side multiplied by others (ρ/k, k·E, lengths to the power d); beyond this the
/// products overflow or swamp each other and the step matrix turns singular in floating point.
/// Any consistent unit system (SI, mm–t–s) stays far inside.
pub const MAX_MAGNITUDE: f64 = 1e18;

/// The sane range of the box's lengths [m, or the unit of the lengths].
pub const LENGTH_RANGE: (f64, f64) = (1e-6, 1e6);

/// The most elongated cell of a structured mesh: its longest side over its shortest. Far
/// inside what [`Mesh::new`](crate::mesh::Mesh::new) accepts (about 4·10⁵ for the worst
/// tetrahedra of a box), and beyond any mesh a sane model needs.
pub const MAX_CELL_ASPECT: f64 = 1e4;

/// The most output times a scenario may list.
pub const MAX_OUTPUT_TIMES: usize = 100_000;

/// The largest scenario file read (1 MiB).
pub const MAX_SCENARIO_BYTES: u64 = 1 << 20;

/// The most time steps a run may have (its per-step records stay in memory: ~100 bytes each).
pub const MAX_STEPS: usize = 1_000_000;

fn finite(key: &str, v: f64) -> Result<(), Error> {
    if v.is_finite() && v.abs() <= MAX_MAGNITUDE {
        Ok(())
    } else {
        Err(invalid(key, &v, "a finite number of magnitude ≤ 1e18"))
    }
}

fn positive(key: &str, v: f64) -> Result<(), Error> {
    if v.is_finite() && v > 0.0 && v <= MAX_MAGNITUDE {
        Ok(())
    } else {
        Err(invalid(key, &v, "a positive number ≤ 1e18"))
    }
}

fn non_negative(key: &str, v: f64) -> Result<(), Error> {
    if (0.0..=MAX_MAGNITUDE).contains(&v) {
        Ok(())
    } else {
        Err(invalid(key, &v, "a non-negative number ≤ 1e18"))
    }
}

fn at_least_one(key: &str, v: usize) -> Result<(), Error> {
    if v >= 1 {
        Ok(())
    } else {
        Err(invalid(key, &v, "an integer ≥ 1"))
    }
}

/// Turns a deserialization error into one that names the dotted key it failed at, found from
/// the error's span in the (re-serialized) scenario text.
fn describe(e: &toml::de::Error, text: &str) -> Error {
    let message = e.message().trim().to_string();
    let Some(span) = e.span() else {
        return Error::Scenario(message);
    };
    let before = &text[..span.start.min(text.len())];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[line_start..].find('\n').map_or(text.len(), |i| line_start + i);
    let line = &text[line_start..line_end];
    let header = |l: &str| {
        l.trim()
            .strip_prefix('[')
            .map(|t| t.trim_matches(|c| c == '[' || c == ']').to_string())
    };
    if let Some(table) = header(line) {
        // The error is about the table as a whole (a key it lacks or must not have).
        if let Some(field) = missing_field(&message) {
            return Error::MissingKey {
                key: format!("{table}.{field}"),
            };
        }
        return Error::Scenario(format!("in `{table}`: {message}"));
    }
    let table = before[..line_start].lines().rev().find_map(header);
    let Some((key, value)) = line.split_once('=') else {
        return Error::Scenario(message);
    };
    let key = match table {
        Some(t) => format!("{t}.{}", key.trim()),
        None => key.trim().to_string(),
    };
    Error::InvalidValue {
        key,
        value: value.trim().to_string(),
        expected: plain(&message),
    }
}

/// The field of serde's "missing field `bound`".
fn missing_field(message: &str) -> Option<&str> {
    message.strip_prefix("missing field `")?.strip_suffix('`')
}

/// serde's "invalid value: integer `-1`, expected usize" as what a user should write.
fn plain(message: &str) -> String {
    match message.rsplit_once(", expected ") {
        Some((_, "usize" | "u64" | "u32")) => "a non-negative integer".into(),
        Some((_, "a string")) => "a string".into(),
        Some((_, "a boolean")) => "true or false".into(),
        Some((_, expected)) if message.starts_with("invalid ") => expected.to_string(),
        _ => message.to_string(),
    }
}

/// Keys a scenario may hold that the default (a 2D scenario) does not: they are taken as given
/// and checked when the scenario is read.
const OPTIONAL_KEYS: &[&str] = &[
    "mesh.nz",
    "mesh.file",
    "boundary.symmetry",
    "loads.pressure",
    "initial.from",
];

/// Data keys: a number, an array, a `{ constant, rate }` table or expression strings may replace
/// any of these forms ([`DatumSpec`] checks the new value).
const DATUM_KEYS: &[&str] = &[
    "loads.body_force",
    "loads.heat_source",
    "initial.displacement",
    "initial.velocity",
    "initial.temperature",
];

/// Keys that existed once, with what replaced them.
const REMOVED_KEYS: &[(&str, &str)] = &[(
    "boundary.contact_normal",
    "each contact node's outward normal now comes from the mesh; remove the key",
)];

/// Lays `user` over `base`, key by key. A key unknown to the base is an error naming its path. A
/// table whose `law` changes is replaced whole, since its keys depend on the law; a `mesh.file`
/// replaces the structured generator (the base's geometry and cell counts go).
fn overlay(base: &mut Table, user: Table, prefix: &str) -> Result<(), Error> {
    if prefix.is_empty() {
        take_mesh_file(base, &user)?;
    }
    for (key, value) in user {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        if let Some((_, instead)) = REMOVED_KEYS.iter().find(|(removed, _)| *removed == path) {
            return Err(Error::RemovedKey {
                key: path,
                instead: instead.to_string(),
            });
        }
        if prefix == "mesh" && base.contains_key("file") && ["nx", "ny", "nz"].contains(&key.as_str()) {
            return Err(invalid(
                &path,
                &value.to_string(),
                "no cell counts beside mesh.file (they belong to the structured generator)",
            ));
        }
        if prefix.is_empty() && key == "geometry" && !base.contains_key("geometry") {
            return Err(invalid(
                "geometry",
                &value.to_string(),
                "no geometry beside mesh.file (the mesh file gives the geometry)",
            ));
        }
        if !base.contains_key(&key) && OPTIONAL_KEYS.contains(&path.as_str()) {
            base.insert(key, value);
            continue;
        }
        let Some(slot) = base.get_mut(&key) else {
            let known: Vec<&String> = base.keys().collect();
            return Err(Error::UnknownKey {
                key: path,
                expected: format!("{known:?}"),
            });
        };
        if DATUM_KEYS.contains(&path.as_str()) {
            *slot = value;
            continue;
        }
        match (slot, value) {
            (Value::Table(b), Value::Table(u)) => {
                let tag = ["law"].into_iter().find(|t| b.contains_key(*t));
                let replaced = tag.is_some_and(|t| u.get(t).is_some_and(|v| Some(v) != b.get(t)));
                if replaced {
                    *b = u;
                } else {
                    overlay(b, u, &path)?;
                }
            }
            (slot, value) => {
                check_type(&path, slot, &value)?;
                *slot = coerce(slot, value);
            }
        }
    }
    Ok(())
}

/// A user table that sets `mesh.file` replaces the generator: the base's geometry, cell counts
/// and tractions (on the generator's parts) go, and the user may not give the first two beside
/// the file.
fn take_mesh_file(base: &mut Table, user: &Table) -> Result<(), Error> {
    let Some(Value::Table(mesh)) = user.get("mesh") else {
        return Ok(());
    };
    if !mesh.contains_key("file") {
        return Ok(());
    }
    if let Some(key) = ["nx", "ny", "nz"].into_iter().find(|k| mesh.contains_key(*k)) {
        return Err(invalid(
            &format!("mesh.{key}"),
            &mesh[key].to_string(),
            "no cell counts beside mesh.file (they belong to the structured generator)",
        ));
    }
    if let Some(geometry) = user.get("geometry") {
        return Err(invalid(
            "geometry",
            &geometry.to_string(),
            "no geometry beside mesh.file (the mesh file gives the geometry)",
        ));
    }
    drop_generator(base);
    Ok(())
}

/// Removes the structured generator from `base` for a mesh from elsewhere (a file, or given in
/// memory): its geometry and cell counts, and the tractions on the rectangle's parts.
/// A mesh given in memory ([`Scenario::load_with_mesh`]) replaces `mesh.file` and the
/// generator, so the user's scenario may not set them: refused here, by key, because the
/// generator's keys are gone from the base table and the overlay would only say "unknown".
fn refuse_mesh_keys(user: &Table) -> Result<(), Error> {
    let expected = "no mesh keys beside a mesh given in memory (it replaces mesh.file and the generator)";
    if let Some(geometry) = user.get("geometry") {
        return Err(invalid("geometry", &geometry.to_string(), expected));
    }
    if let Some(Value::Table(mesh)) = user.get("mesh") {
        if let Some((key, value)) = mesh.iter().next() {
            return Err(invalid(&format!("mesh.{key}"), &value.to_string(), expected));
        }
    }
    Ok(())
}

fn drop_generator(base: &mut Table) {
    base.remove("geometry");
    base.insert("mesh".into(), Value::Table(Table::new()));
    // The default's tractions act on the rectangle's parts: another mesh has its own.
    if let Some(Value::Table(loads)) = base.get_mut("loads") {
        loads.insert("traction".into(), Value::Array(Vec::new()));
    }
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "a string",
        Value::Integer(_) => "an integer",
        Value::Float(_) => "a number",
        Value::Boolean(_) => "true or false",
        Value::Datetime(_) => "a date",
        Value::Array(_) => "an array",
        Value::Table(_) => "a table",
    }
}

fn check_type(path: &str, base: &Value, user: &Value) -> Result<(), Error> {
    let compatible = matches!(
        (base, user),
        (Value::Float(_), Value::Integer(_))
            | (Value::String(_), Value::String(_))
            | (Value::Integer(_), Value::Integer(_))
            | (Value::Float(_), Value::Float(_))
            | (Value::Boolean(_), Value::Boolean(_))
            | (Value::Array(_), Value::Array(_))
            | (Value::Table(_), Value::Table(_))
    );
    if compatible {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            key: path.to_string(),
            value: user.to_string(),
            expected: type_name(base).to_string(),
        })
    }
}

/// Integers written where the default holds a float become floats (`final_time = 1`).
fn coerce(base: &Value, user: Value) -> Value {
    match (base, user) {
        (Value::Float(_), Value::Integer(i)) => Value::Float(i as f64),
        (Value::Array(b), Value::Array(u)) if b.first().is_some_and(|v| v.is_float()) => {
            Value::Array(u.into_iter().map(|v| coerce(&Value::Float(0.0), v)).collect())
        }
        (_, user) => user,
    }
}

/// Reads `a.b.c=value` as the nested table {a = {b = {c = value}}}; the value is read as TOML,
/// or as a plain string if it is not TOML.
fn parse_override(assignment: &str) -> Result<Table, Error> {
    let Some((path, raw)) = assignment.split_once('=') else {
        return Err(Error::InvalidValue {
            key: assignment.to_string(),
            value: String::new(),
            expected: "an override of the form key.path=value".into(),
        });
    };
    let (path, raw) = (path.trim(), raw.trim());
    let value = match format!("v = {raw}").parse::<Table>() {
        Ok(mut t) => t.remove("v").expect("the key just written"),
        Err(_) => Value::String(raw.to_string()),
    };
    let (parents, last) = match path.rsplit_once('.') {
        Some((parents, last)) => (parents.split('.').collect(), last),
        None => (Vec::new(), path),
    };
    let mut table = Table::from_iter([(last.to_string(), value)]);
    for key in parents.into_iter().rev() {
        table = Table::from_iter([(key.to_string(), Value::Table(table))]);
    }
    Ok(table)
}

/// Lays the override table `later` into `earlier`: tables merge key by key, anything else is
/// replaced (the later override wins).
fn merge(earlier: &mut Table, later: Table) {
    for (key, value) in later {
        match (earlier.get_mut(&key), value) {
            (Some(Value::Table(e)), Value::Table(l)) => merge(e, l),
            (_, value) => {
                earlier.insert(key, value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_the_paper_example() {
        let s = Scenario::default();
        assert_eq!(s.structured().unwrap().lengths, vec![40.0, 10.0]);
        assert_eq!(s.material.density, 100.0);
        assert_eq!(
            s.friction,
            FrictionSpec::SlipWeakening {
                bound: 150.0,
                a: 1.0,
                b: 0.2,
                alpha: 100.0
            }
        );
        assert_eq!(s.loads.traction[0].rate, Some(vec![0.0, -800.0]));
        assert_eq!(s.output_steps(), vec![16, 32, 48, 64]);
    }

    #[test]
    fn overrides_and_files_overlay_the_default() {
        let s = Scenario::load(Some("[mesh]\nnx = 8\n[time]\nfinal_time = 2"), &["mesh.ny=2".into()]).unwrap();
        assert_eq!((s.mesh.nx, s.mesh.ny), (Some(8), Some(2)));
        assert_eq!(s.time.final_time, 2.0);
        let t = Scenario::load(None, &["friction={law=\"tresca\", bound=3.0}".into()]).unwrap();
        assert_eq!(t.friction, FrictionSpec::Tresca { bound: 3.0 });
        let t = Scenario::load(None, &["friction.law=tresca".into(), "friction.bound=100".into()]).unwrap();
        assert_eq!(t.friction, FrictionSpec::Tresca { bound: 100.0 });
        let back = Scenario::load(
            None,
            &[
                "friction.law=tresca".into(),
                "friction.bound=100".into(),
                "friction={law=\"slip-weakening\", bound=150.0, a=1.0, b=0.2, alpha=100.0}".into(),
                "friction.alpha=50".into(),
            ],
        )
        .unwrap();
        assert_eq!(
            back.friction,
            FrictionSpec::SlipWeakening {
                bound: 150.0,
                a: 1.0,
                b: 0.2,
                alpha: 50.0
            }
        );
        let p = Scenario::load(None, &["solver.kind=paper".into()]).unwrap();
        assert_eq!(p.solver.kind, SolverKind::Paper);
    }

    #[test]
    fn bad_keys_and_values_are_named() {
        let e = Scenario::load(Some("[mesh]\nnxx = 3"), &[]).unwrap_err().to_string();
        assert!(e.contains("mesh.nxx"), "{e}");
        let e = Scenario::load(None, &["material.poisson=0.7".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("material.poisson") && e.contains("0.7"), "{e}");
        let e = Scenario::load(None, &["mesh.nx=\"many\"".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("mesh.nx") && e.contains("integer"), "{e}");
        let e = Scenario::load(None, &["boundary.contact=[\"middle\"]".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("boundary.contact") && e.contains("middle"), "{e}");
        let e = Scenario::load(None, &["friction.law=coulomb".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("coulomb"), "{e}");
        let e = Scenario::load(Some("[time]\nsteps = -4"), &[]).unwrap_err().to_string();
        assert!(e.contains("time.steps") && e.contains("-4"), "{e}");
        assert!(e.ends_with("(expected a non-negative integer)"), "{e}");
        let e = Scenario::load(None, &["friction={law=\"tresca\", bound=3.0, a=1.0}".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("friction") && e.contains('a'), "{e}");
    }
}
