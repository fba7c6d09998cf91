//! Scenario files: every parameter of a run, in TOML.
//!
//! The paper's Section 6 example is built in (`scenarios/paper.toml`, printed by
//! `thermocontact scenario`). A user file is laid over it key by key, then `--set a.b=value`
//! overrides are applied, then the result is checked: unknown keys, wrong types and invalid
//! values are errors that name the dotted key, the value and what was expected.

use serde::{Deserialize, Serialize};
use toml::{Table, Value};

use crate::error::Error;

/// The default scenario (the paper's example), with comments.
pub const DEFAULT_TOML: &str = include_str!("../scenarios/paper.toml");

/// A complete, validated scenario.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub geometry: Geometry,
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
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// Side lengths of the rectangle (2 values) or box (3 values).
    pub lengths: Vec<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    pub nx: usize,
    pub ny: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nz: Option<usize>,
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
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    pub displacement: Vec<f64>,
    pub velocity: Vec<f64>,
    pub temperature: f64,
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

impl Affine<Vec<f64>> {
    /// The value at time t.
    pub fn at(&self, t: f64) -> Vec<f64> {
        self.constant.iter().zip(&self.rate).map(|(c, r)| c + r * t).collect()
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Traction {
    pub part: String,
    pub constant: Vec<f64>,
    pub rate: Vec<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Loads {
    pub body_force: Affine<Vec<f64>>,
    pub heat_source: Affine<f64>,
    #[serde(default)]
    pub traction: Vec<Traction>,
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

/// Which nonsmooth solver runs each time step.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SolverKind {
    /// Convexification loop + Uzawa augmented Lagrangian (Problem 17).
    Paper,
    /// Semismooth Newton on the condensed nonmonotone law, the paper's solver as fallback.
    Fast,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    pub kind: SolverKind,
    pub tolerance: f64,
    pub max_convexification: usize,
    pub inner_tolerance: f64,
    pub max_inner: usize,
    pub slip_tolerance: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    pub times: Vec<f64>,
    pub vtk: bool,
    pub csv: bool,
}

impl Default for Scenario {
    fn default() -> Self {
        Scenario::load(None, &[]).expect("the built-in scenario is valid")
    }
}

impl Scenario {
    /// Loads a scenario: the built-in default, overlaid by the file's text (if any), overlaid by
    /// `key.path=value` overrides; then validated.
    pub fn load(file_text: Option<&str>, overrides: &[String]) -> Result<Self, Error> {
        let mut table: Table = DEFAULT_TOML.parse().expect("built-in scenario parses");
        if let Some(text) = file_text {
            let user: Table = text
                .parse()
                .map_err(|e: toml::de::Error| Error::Scenario(format!("the file is not valid TOML: {e}")))?;
            overlay(&mut table, user, "")?;
        }
        for assignment in overrides {
            apply_override(&mut table, assignment)?;
        }
        let text = toml::to_string(&table).map_err(|e| Error::Scenario(e.to_string()))?;
        let scenario: Scenario = toml::from_str(&text).map_err(|e| describe(&e, &text))?;
        scenario.validate()?;
        Ok(scenario)
    }

    /// The scenario as TOML (what a run saves beside its results).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scenario serializes")
    }

    /// Space dimension d (2 for a rectangle, 3 for a box).
    pub fn dim(&self) -> usize {
        self.geometry.lengths.len()
    }

    /// Time step k = T/N.
    pub fn time_step(&self) -> f64 {
        self.time.final_time / self.time.steps as f64
    }

    /// Checks every value against its admissible range.
    pub fn validate(&self) -> Result<(), Error> {
        let d = self.geometry.lengths.len();
        if d != 2 && d != 3 {
            return Err(invalid(
                "geometry.lengths",
                &self.geometry.lengths,
                "2 lengths (rectangle) or 3 (box)",
            ));
        }
        for &l in &self.geometry.lengths {
            positive("geometry.lengths", l)?;
        }
        at_least_one("mesh.nx", self.mesh.nx)?;
        at_least_one("mesh.ny", self.mesh.ny)?;
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
        positive("time.final_time", self.time.final_time)?;
        at_least_one("time.steps", self.time.steps)?;

        let parts: &[&str] = if d == 2 {
            &["left", "right", "bottom", "top"]
        } else {
            &["x-", "x+", "y-", "y+", "z-", "z+"]
        };
        let mut seen: Vec<&str> = Vec::new();
        for (key, list) in [
            ("boundary.dirichlet", &self.boundary.dirichlet),
            ("boundary.neumann", &self.boundary.neumann),
            ("boundary.contact", &self.boundary.contact),
            ("boundary.symmetry", &self.boundary.symmetry),
        ] {
            for name in list {
                if !parts.contains(&name.as_str()) {
                    return Err(invalid(key, name, &format!("boundary parts among {parts:?}")));
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
        if self.boundary.dirichlet.is_empty() {
            return Err(invalid("boundary.dirichlet", &"[]", "at least one part (meas Γ_D > 0)"));
        }
        if self.boundary.contact.is_empty() {
            return Err(invalid("boundary.contact", &"[]", "at least one part for Γ_C"));
        }

        let m = &self.material;
        positive("material.density", m.density)?;
        positive("material.heat_capacity", m.heat_capacity)?;
        positive("material.viscosity_mu2", m.viscosity_mu2)?;
        if m.viscosity_mu1 * d as f64 + m.viscosity_mu2 <= 0.0 {
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
        positive("material.conductivity", m.conductivity)?;

        vector("initial.displacement", &self.initial.displacement, d)?;
        vector("initial.velocity", &self.initial.velocity, d)?;
        if self.initial.displacement.iter().any(|&v| v != 0.0) {
            return Err(invalid(
                "initial.displacement",
                &self.initial.displacement,
                "zero (a uniform u₀ must vanish on the clamped part Γ_D)",
            ));
        }
        finite("initial.temperature", self.initial.temperature)?;
        finite("boundary.temperature", self.boundary.temperature)?;

        vector("loads.body_force.constant", &self.loads.body_force.constant, d)?;
        vector("loads.body_force.rate", &self.loads.body_force.rate, d)?;
        finite("loads.heat_source.constant", self.loads.heat_source.constant)?;
        finite("loads.heat_source.rate", self.loads.heat_source.rate)?;
        for (i, t) in self.loads.traction.iter().enumerate() {
            if !self.boundary.neumann.contains(&t.part) {
                return Err(invalid(
                    &format!("loads.traction[{i}].part"),
                    &t.part,
                    &format!("a Neumann part, one of {:?}", self.boundary.neumann),
                ));
            }
            vector(&format!("loads.traction[{i}].constant"), &t.constant, d)?;
            vector(&format!("loads.traction[{i}].rate"), &t.rate, d)?;
        }

        match self.friction {
            FrictionSpec::SlipWeakening { bound, a, b, alpha } => {
                non_negative("friction.bound", bound)?;
                positive("friction.b", b)?;
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
        non_negative("solver.slip_tolerance", s.slip_tolerance)?;

        for &t in &self.output.times {
            if !(t > 0.0 && t <= self.time.final_time * (1.0 + 1e-12)) {
                return Err(invalid(
                    "output.times",
                    &t,
                    &format!("times in (0, T] with T = time.final_time = {}", self.time.final_time),
                ));
            }
        }
        Ok(())
    }

    /// Time levels n (1 ≤ n ≤ N) of the output times, each rounded to the nearest level, sorted
    /// and without repeats.
    pub fn output_steps(&self) -> Vec<usize> {
        let k = self.time_step();
        let mut steps: Vec<usize> = self
            .output
            .times
            .iter()
            .map(|&t| ((t / k).round() as usize).clamp(1, self.time.steps))
            .collect();
        steps.sort_unstable();
        steps.dedup();
        steps
    }
}

fn invalid(key: &str, value: &dyn std::fmt::Debug, expected: &str) -> Error {
    Error::InvalidValue {
        key: key.to_string(),
        value: format!("{value:?}"),
        expected: expected.to_string(),
    }
}

fn finite(key: &str, v: f64) -> Result<(), Error> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(key, &v, "a finite number"))
    }
}

fn positive(key: &str, v: f64) -> Result<(), Error> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(key, &v, "a positive number"))
    }
}

fn non_negative(key: &str, v: f64) -> Result<(), Error> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(invalid(key, &v, "a non-negative number"))
    }
}

fn at_least_one(key: &str, v: usize) -> Result<(), Error> {
    if v >= 1 {
        Ok(())
    } else {
        Err(invalid(key, &v, "an integer ≥ 1"))
    }
}

fn vector(key: &str, v: &[f64], dim: usize) -> Result<(), Error> {
    if v.len() != dim {
        return Err(invalid(key, &v, &format!("{dim} components (one per space dimension)")));
    }
    for &x in v {
        finite(key, x)?;
    }
    Ok(())
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
        expected: message,
    }
}

/// Keys a scenario may hold that the default (a 2D scenario) does not: they are taken as given
/// and checked when the scenario is read.
const OPTIONAL_KEYS: &[&str] = &["mesh.nz", "boundary.symmetry"];

/// Lays `user` over `base`, key by key. A key unknown to the base is an error naming its path. A
/// table whose `law` changes is replaced whole, since its keys depend on the law.
fn overlay(base: &mut Table, user: Table, prefix: &str) -> Result<(), Error> {
    for (key, value) in user {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
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

/// Applies `a.b.c=value`; the value is read as TOML, or as a plain string if it is not TOML.
fn apply_override(table: &mut Table, assignment: &str) -> Result<(), Error> {
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
    let mut nested = Table::new();
    let keys: Vec<&str> = path.split('.').collect();
    // Build {a = {b = {c = value}}} and overlay it, so overrides get the same checks as files.
    let mut current = value;
    for key in keys.iter().rev() {
        let mut t = Table::new();
        t.insert(key.to_string(), current);
        current = Value::Table(t);
    }
    if let Value::Table(t) = current {
        nested = t;
    }
    overlay(table, nested, "")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_the_paper_example() {
        let s = Scenario::default();
        assert_eq!(s.geometry.lengths, vec![40.0, 10.0]);
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
        assert_eq!(s.loads.traction[0].rate, vec![0.0, -800.0]);
        assert_eq!(s.output_steps(), vec![16, 32, 48, 64]);
    }

    #[test]
    fn overrides_and_files_overlay_the_default() {
        let s = Scenario::load(Some("[mesh]\nnx = 8\n[time]\nfinal_time = 2"), &["mesh.ny=2".into()]).unwrap();
        assert_eq!((s.mesh.nx, s.mesh.ny), (8, 2));
        assert_eq!(s.time.final_time, 2.0);
        let t = Scenario::load(None, &["friction={law=\"tresca\", bound=3.0}".into()]).unwrap();
        assert_eq!(t.friction, FrictionSpec::Tresca { bound: 3.0 });
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
        let e = Scenario::load(None, &["friction={law=\"tresca\", bound=3.0, a=1.0}".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("friction") && e.contains('a'), "{e}");
    }
}
