//! The scenario's schema: the serde types of the TOML, one per table, with the datum forms
//! ([`DatumSpec`]) and the accessors every other part of the layer reads (the structured mesh,
//! the space dimension, the time step).

use std::path::PathBuf;
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use toml::Value;

use crate::mesh::Mesh;
use crate::step::{LinearKind, PreconditionerKind, Prediction, SolverKind};

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
    /// Cell regions with their own material (`[[regions]]`); cells in none take `[material]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<RegionSpec>,
    pub initial: InitialSpec,
    pub loads: Loads,
    pub friction: FrictionSpecs,
    /// The foundation's motion (absent: at rest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub foundation: Option<FoundationSpec>,
    pub heat_exchange: HeatExchangeSpec,
    pub frictional_heating: FrictionalHeatingSpec,
    /// Thermal conditions per boundary part (`[[thermal]]`); parts not listed keep the paper's
    /// rule.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub thermal: Vec<ThermalSpec>,
    pub solver: SolverSpec,
    pub output: OutputSpec,
    /// The mesh read from `mesh.file`, kept from validation to the build.
    #[serde(skip)]
    pub(super) loaded: LoadedMesh,
    /// What the scenario asked for that works but should change (a deprecated name), said once
    /// at the start of a run.
    #[serde(skip)]
    pub warnings: Vec<String>,
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
pub(super) struct LoadedMesh(pub(super) Option<Arc<Mesh>>);

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

/// A cell region's material (`[[regions]]`): a Gmsh physical group of cells of the mesh
/// (`part`) and any key of `[material]`; the keys not given are `[material]`'s.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// The cell region's name (the physical group's).
    pub part: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heat_capacity: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscosity_mu1: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscosity_mu2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub young: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal_expansion: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conductivity: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_temperature: Option<f64>,
}

impl RegionSpec {
    /// The region's material: its keys, the others `base`'s.
    pub fn material(&self, base: &MaterialSpec) -> MaterialSpec {
        MaterialSpec {
            density: self.density.unwrap_or(base.density),
            heat_capacity: self.heat_capacity.unwrap_or(base.heat_capacity),
            viscosity_mu1: self.viscosity_mu1.unwrap_or(base.viscosity_mu1),
            viscosity_mu2: self.viscosity_mu2.unwrap_or(base.viscosity_mu2),
            young: self.young.unwrap_or(base.young),
            poisson: self.poisson.unwrap_or(base.poisson),
            thermal_expansion: self.thermal_expansion.unwrap_or(base.thermal_expansion),
            conductivity: self.conductivity.unwrap_or(base.conductivity),
            reference_temperature: self.reference_temperature.unwrap_or(base.reference_temperature),
        }
    }
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
            Value::Table(table) => {
                // Name what is wrong with the table: a key that is not `constant` or `rate`, or
                // one of the two missing.
                let message = match table.keys().find(|k| !["constant", "rate"].contains(&k.as_str())) {
                    Some(extra) => format!("`{extra}` is not a key of a {{ constant, rate }} table"),
                    None => "a { constant, rate } table needs both `constant` and `rate`".to_string(),
                };
                return Err(D::Error::custom(message));
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

/// The friction laws on Γ_C: one table for every contact part (`[friction]`), or one per part
/// (`[[friction]]`, each with `part`; one without `part` covers the rest).
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum FrictionSpecs {
    One(FrictionSpec),
    Parts(Vec<FrictionSpec>),
}

impl<'de> Deserialize<'de> for FrictionSpecs {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error as _;
        match Value::deserialize(deserializer)? {
            Value::Array(items) => {
                let laws = (items.into_iter().enumerate())
                    .map(|(k, item)| {
                        FrictionSpec::deserialize(item)
                            .map_err(|e| D::Error::custom(format!("[[friction]] number {}: {e}", k + 1)))
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(FrictionSpecs::Parts(laws))
            }
            value => FrictionSpec::deserialize(value)
                .map(FrictionSpecs::One)
                .map_err(D::Error::custom),
        }
    }
}

impl FrictionSpecs {
    /// The laws, in the order given.
    pub fn laws(&self) -> &[FrictionSpec] {
        match self {
            FrictionSpecs::One(law) => std::slice::from_ref(law),
            FrictionSpecs::Parts(laws) => laws,
        }
    }

    /// The laws, mutable.
    pub fn laws_mut(&mut self) -> &mut [FrictionSpec] {
        match self {
            FrictionSpecs::One(law) => std::slice::from_mut(law),
            FrictionSpecs::Parts(laws) => laws,
        }
    }
}

/// A friction law on Γ_C: the bound S(x, t) μ(r) at slip rate r.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "law", rename_all = "kebab-case", deny_unknown_fields)]
pub enum FrictionSpec {
    /// The paper's law (81)–(83): μ(r) = (a − b) e^(−αr) + b.
    VelocityWeakening {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bound: Option<DatumSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        normal: Option<NormalSpec>,
        a: f64,
        b: f64,
        alpha: f64,
    },
    /// The former name of `velocity-weakening`, accepted with a warning.
    SlipWeakening {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bound: Option<DatumSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        normal: Option<NormalSpec>,
        a: f64,
        b: f64,
        alpha: f64,
    },
    /// μ ≡ 1: the bound S.
    Tresca {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bound: Option<DatumSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        normal: Option<NormalSpec>,
    },
    /// μ at slip rates, piecewise linear (inline, or the two columns of a CSV file).
    Table {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bound: Option<DatumSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        normal: Option<NormalSpec>,
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        slip_rate: Vec<f64>,
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        coefficient: Vec<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        file: Option<PathBuf>,
    },
    /// μ as an expression of r, x, y, z, t.
    Expression {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bound: Option<DatumSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        normal: Option<NormalSpec>,
        coefficient: String,
    },
    /// Coulomb's law: a constant μ (`coefficient`), the bound μ p with p the contact pressure
    /// (`normal` defaults to "reaction" for it).
    Coulomb {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bound: Option<DatumSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        normal: Option<NormalSpec>,
        coefficient: f64,
    },
    /// μ = μ_s − (μ_s − μ_d) min(s/D_c, 1) of the slip distance s.
    SlipDistanceWeakening {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bound: Option<DatumSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        normal: Option<NormalSpec>,
        #[serde(rename = "static")]
        static_coefficient: f64,
        dynamic: f64,
        distance: f64,
    },
}

impl FrictionSpec {
    /// The contact part the law is given for (`None`: every part not given its own).
    pub fn part(&self) -> Option<&str> {
        match self {
            FrictionSpec::VelocityWeakening { part, .. }
            | FrictionSpec::SlipWeakening { part, .. }
            | FrictionSpec::Tresca { part, .. }
            | FrictionSpec::Table { part, .. }
            | FrictionSpec::Expression { part, .. }
            | FrictionSpec::Coulomb { part, .. }
            | FrictionSpec::SlipDistanceWeakening { part, .. } => part.as_deref(),
        }
    }

    /// The scale S (absent where the law scales with the contact pressure).
    pub fn bound(&self) -> Option<&DatumSpec> {
        match self {
            FrictionSpec::VelocityWeakening { bound, .. }
            | FrictionSpec::SlipWeakening { bound, .. }
            | FrictionSpec::Tresca { bound, .. }
            | FrictionSpec::Table { bound, .. }
            | FrictionSpec::Expression { bound, .. }
            | FrictionSpec::Coulomb { bound, .. }
            | FrictionSpec::SlipDistanceWeakening { bound, .. } => bound.as_ref(),
        }
    }

    /// What scales μ: `normal` as given, else "reaction" for `coulomb` and "prescribed" for
    /// the others.
    pub fn normal(&self) -> NormalSpec {
        match self {
            FrictionSpec::VelocityWeakening { normal, .. }
            | FrictionSpec::SlipWeakening { normal, .. }
            | FrictionSpec::Tresca { normal, .. }
            | FrictionSpec::Table { normal, .. }
            | FrictionSpec::Expression { normal, .. }
            | FrictionSpec::SlipDistanceWeakening { normal, .. } => normal.unwrap_or(NormalSpec::Prescribed),
            FrictionSpec::Coulomb { normal, .. } => normal.unwrap_or(NormalSpec::Reaction),
        }
    }
}

/// What scales a friction law's coefficient μ (`friction.normal`).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum NormalSpec {
    /// The bound is μ(r) S with S = `bound` (the paper).
    Prescribed,
    /// The bound is μ(r) p with p the contact pressure (Coulomb).
    Reaction,
}

/// The foundation's motion (`[foundation]`; absent: at rest, the paper): a velocity datum, or
/// a rigid rotation (2D: `center`; 3D: `axis_point` and `axis`) with `angular_velocity`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FoundationSpec {
    /// v_F(x, t), d components.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<DatumSpec>,
    /// The centre of a rotation in 2D.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<Vec<f64>>,
    /// A point on the axis of a rotation in 3D.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis_point: Option<Vec<f64>>,
    /// The axis of a rotation in 3D (any length; ω turns right-handed about it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<Vec<f64>>,
    /// ω(t) of a rotation, rad/s (a scalar datum).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angular_velocity: Option<DatumSpec>,
}

/// The heat exchange with the foundation, ∂j(θ) on Γ_C.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "law", rename_all = "kebab-case", deny_unknown_fields)]
pub enum HeatExchangeSpec {
    /// k_e (θ − θ_R): the paper's.
    Linear {
        coefficient: f64,
        foundation_temperature: f64,
    },
    /// The flux at temperatures, piecewise linear.
    Table { temperature: Vec<f64>, flux: Vec<f64> },
    /// The flux as an expression of theta, x, y, z, t.
    Expression { flux: String },
}

/// h_τ = λ(t) r with λ = constant + rate·t, or `value`, an expression of r, x, y, z, t; and
/// the share of it that enters the body.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FrictionalHeatingSpec {
    pub constant: f64,
    pub rate: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<String>,
    pub share: f64,
    /// h_τ = b(r) r, the friction's dissipated power (`constant`, `rate` and `value` unused).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub friction_power: bool,
}

/// A thermal condition on one boundary part (`[[thermal]]`): `condition` is one of
/// [`THERMAL_CONDITIONS`], with its keys: `value` (a datum) for "temperature" and "flux",
/// `coefficient` and `ambient` for "convection", none for "insulated". The condition is a
/// string rather than a tag so that a wrong one is named with its key and the list.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    pub part: String,
    pub condition: String,
    /// θ_D (temperature) or the heat flux into the body (flux).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<DatumSpec>,
    /// h of convection.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coefficient: Option<f64>,
    /// θ_∞ of convection.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient: Option<f64>,
}

/// The values of `thermal.condition`.
pub const THERMAL_CONDITIONS: [&str; 4] = ["insulated", "temperature", "flux", "convection"];

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
    pub krylov_forcing: f64,
    pub max_krylov: usize,
    pub preconditioner: PreconditionerKind,
    pub overlap: usize,
    pub anderson_depth: usize,
    pub contact_sweeps: usize,
    pub prediction: Prediction,
    pub condensed_layers: usize,
    pub backtracking: bool,
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

impl Scenario {
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
}
