//! Translation of a checked scenario into the core's typed parts: the data ([`Datum`]), the
//! mesh, the [`ProblemBuilder`] (initial fields or a checkpoint's, loads, laws), the
//! [`SolverParams`] and the [`OutputPlan`] of a run.

use std::path::Path;

use toml::{Table, Value};

use super::validate::{invalid, MAX_MAGNITUDE};
use super::{
    Affine, DatumSpec, FoundationSpec, FrictionSpec, HeatExchangeSpec, NormalSpec, Scenario, ThermalSpec, Traction,
    THERMAL_CONDITIONS,
};
use crate::contact::{
    Coulomb, ExpressionExchange, ExpressionFriction, ExpressionHeating, Foundation, FrictionLaw, FrictionalHeating,
    HeatExchange, LinearHeating, QuadraticExchange, SlipDistanceWeakening, TabulatedExchange, TabulatedFriction,
    Tresca, VelocityWeakening,
};
use crate::driver::{OutputPlan, Summary};
use crate::error::Error;
use crate::loads::{Datum, Expression};
use crate::material::{Isotropic, Material};
use crate::mesh::{self, Mesh};
use crate::model::{InitialFields, LoadTarget, ModelError, Problem, ProblemBuilder, State, ThermalCondition, TimeGrid};
use crate::step::{KrylovParams, SolverParams};

impl Scenario {
    /// Each friction law with the key that names it in errors (`friction`, or `friction[k]`
    /// for one table per part).
    pub(super) fn friction_keys(&self) -> Vec<(String, &FrictionSpec)> {
        match &self.friction {
            super::FrictionSpecs::One(law) => vec![("friction".to_string(), law)],
            super::FrictionSpecs::Parts(laws) => (laws.iter().enumerate())
                .map(|(k, law)| (format!("friction[{k}]"), law))
                .collect(),
        }
    }

    /// h_τ: λ(t) r, or the expression `frictional_heating.value`.
    pub(super) fn frictional_heating(&self) -> Result<Box<dyn FrictionalHeating>, Error> {
        let h = &self.frictional_heating;
        Ok(match &h.value {
            None => Box::new(LinearHeating::affine(h.constant, h.rate)),
            Some(text) => Box::new(ExpressionHeating::parse(text).map_err(|e| {
                invalid(
                    "frictional_heating.value",
                    text,
                    &format!("an expression of r, x, y, z, t: {e}"),
                )
            })?),
        })
    }
}

/// The condition of one `[[thermal]]` table; errors name `key` (`thermal[i]`) and its keys:
/// an unknown condition (with the list), a key the condition needs and lacks, or one it does
/// not take, a value out of range.
pub(super) fn thermal_condition(key: &str, spec: &ThermalSpec) -> Result<ThermalCondition, Error> {
    let at = |name: &str| format!("{key}.{name}");
    let needs: &[&str] = match spec.condition.as_str() {
        "insulated" => &[],
        "temperature" | "flux" => &["value"],
        "convection" => &["coefficient", "ambient"],
        other => {
            let names: Vec<String> = THERMAL_CONDITIONS.iter().map(|c| format!("\"{c}\"")).collect();
            return Err(invalid(
                &at("condition"),
                &other,
                &format!("one of {}", names.join(", ")),
            ));
        }
    };
    let takes = if needs.is_empty() {
        "no other key".to_string()
    } else {
        needs.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(" and ")
    };
    let given = [
        ("value", spec.value.as_ref().map(|v| v.to_string())),
        ("coefficient", spec.coefficient.map(|v| v.to_string())),
        ("ambient", spec.ambient.map(|v| v.to_string())),
    ];
    for (name, value) in given {
        match (value, needs.contains(&name)) {
            (Some(value), false) => {
                return Err(Error::InvalidValue {
                    key: at(name),
                    value,
                    expected: format!("no `{name}`: condition = \"{}\" takes {takes}", spec.condition),
                })
            }
            (None, true) => {
                return Err(invalid(
                    &at(name),
                    &"(missing)",
                    &format!("a value: condition = \"{}\" takes {takes}", spec.condition),
                ))
            }
            _ => {}
        }
    }
    Ok(match spec.condition.as_str() {
        "insulated" => ThermalCondition::Insulated,
        "temperature" => ThermalCondition::Temperature(datum_of(spec, &at("value"))?),
        "flux" => ThermalCondition::Flux(datum_of(spec, &at("value"))?),
        _ => {
            let (coefficient, ambient) = (spec.coefficient.unwrap_or(0.0), spec.ambient.unwrap_or(0.0));
            if !(coefficient.is_finite() && (0.0..=MAX_MAGNITUDE).contains(&coefficient)) {
                return Err(invalid(
                    &at("coefficient"),
                    &coefficient,
                    "a heat transfer coefficient h ≥ 0 (at most 1e18)",
                ));
            }
            if !(ambient.is_finite() && ambient.abs() <= MAX_MAGNITUDE) {
                return Err(invalid(&at("ambient"), &ambient, "a finite number of magnitude ≤ 1e18"));
            }
            ThermalCondition::Convection { coefficient, ambient }
        }
    })
}

/// The scalar datum `value` of a thermal table (present: checked by the caller).
fn datum_of(spec: &ThermalSpec, key: &str) -> Result<Datum, Error> {
    match &spec.value {
        Some(value) => value.to_datum(key, 1),
        None => Err(Error::MissingKey { key: key.to_string() }),
    }
}

/// The scale (`None` where the law scales with the contact pressure) and the law of one
/// friction table; errors name `key`.
pub(super) fn friction_law(key: &str, spec: &FrictionSpec) -> Result<(Option<Datum>, Box<dyn FrictionLaw>), Error> {
    let scale = match (spec.normal(), spec.bound()) {
        (NormalSpec::Prescribed, Some(bound)) => {
            let scale = bound.to_datum(&format!("{key}.bound"), 1)?;
            if let Datum::Constant(values) = &scale {
                if values[0] < 0.0 {
                    return Err(invalid(&format!("{key}.bound"), &values[0], "a non-negative bound S"));
                }
            }
            Some(scale)
        }
        (NormalSpec::Prescribed, None) => {
            return Err(Error::InvalidValue {
                key: format!("{key}.bound"),
                value: "(missing)".to_string(),
                expected: "the scale S of the bound μ(r) S (a datum), or normal = \"reaction\" for μ(r) p with p the contact pressure"
                    .to_string(),
            })
        }
        (NormalSpec::Reaction, Some(bound)) => {
            return Err(invalid(
                &format!("{key}.bound"),
                bound,
                "no bound with normal = \"reaction\": the bound is μ(r) p with p the contact pressure (remove `bound`, or set normal = \"prescribed\")",
            ))
        }
        (NormalSpec::Reaction, None) => None,
    };
    // The column's key (the file's, where the table came from one).
    let table_error = |from_file: bool, e: crate::contact::TableError| {
        let column = if from_file {
            "file"
        } else {
            e.column().unwrap_or("coefficient")
        };
        invalid(&format!("{key}.{column}"), &e.to_string(), "a valid table")
    };
    let law: Box<dyn FrictionLaw> = match spec {
        FrictionSpec::VelocityWeakening { a, b, alpha, .. } | FrictionSpec::SlipWeakening { a, b, alpha, .. } => {
            Box::new(VelocityWeakening {
                a: *a,
                b: *b,
                alpha: *alpha,
            })
        }
        FrictionSpec::Tresca { .. } => Box::new(Tresca),
        FrictionSpec::Coulomb { coefficient, .. } => Box::new(Coulomb {
            coefficient: *coefficient,
        }),
        FrictionSpec::Table {
            slip_rate,
            coefficient,
            file,
            ..
        } => {
            let (rates, mu) = match file {
                None => (slip_rate.clone(), coefficient.clone()),
                Some(path) => {
                    if !slip_rate.is_empty() || !coefficient.is_empty() {
                        return Err(invalid(
                            &format!("{key}.file"),
                            path,
                            "either a file or slip_rate and coefficient arrays, not both",
                        ));
                    }
                    read_table_csv(path).map_err(|reason| invalid(&format!("{key}.file"), path, &reason))?
                }
            };
            let table = crate::contact::Table::new(rates, mu, ["slip_rate", "coefficient"])
                .and_then(|t| t.non_negative("coefficient"))
                .map_err(|e| table_error(file.is_some(), e))?;
            Box::new(TabulatedFriction { table })
        }
        FrictionSpec::Expression { coefficient, .. } => {
            Box::new(ExpressionFriction::parse(coefficient).map_err(|e| {
                invalid(
                    &format!("{key}.coefficient"),
                    coefficient,
                    &format!("an expression of r, x, y, z, t: {e}"),
                )
            })?)
        }
        FrictionSpec::SlipDistanceWeakening {
            static_coefficient,
            dynamic,
            distance,
            ..
        } => Box::new(SlipDistanceWeakening {
            static_coefficient: *static_coefficient,
            dynamic_coefficient: *dynamic,
            distance: *distance,
        }),
    };
    Ok((scale, law))
}

/// The heat exchange of the scenario.
pub(super) fn heat_exchange(spec: &HeatExchangeSpec) -> Result<Box<dyn HeatExchange>, Error> {
    Ok(match spec {
        HeatExchangeSpec::Linear {
            coefficient,
            foundation_temperature,
        } => Box::new(QuadraticExchange {
            coefficient: *coefficient,
            foundation_temperature: *foundation_temperature,
        }),
        HeatExchangeSpec::Table { temperature, flux } => Box::new(TabulatedExchange {
            table: crate::contact::Table::new(temperature.clone(), flux.clone(), ["temperature", "flux"]).map_err(
                |e| {
                    let key = format!("heat_exchange.{}", e.column().unwrap_or("flux"));
                    invalid(&key, &e.to_string(), "a valid table of flux against temperature")
                },
            )?,
        }),
        HeatExchangeSpec::Expression { flux } => Box::new(ExpressionExchange::parse(flux).map_err(|e| {
            invalid(
                "heat_exchange.flux",
                flux,
                &format!("an expression of theta, x, y, z, t: {e}"),
            )
        })?),
    })
}

/// The two columns of a CSV file (slip rate, coefficient), one row per line; the first line
/// that is not a comment may be a header; `#` starts a comment.
fn read_table_csv(path: &Path) -> Result<(Vec<f64>, Vec<f64>), String> {
    let bytes = crate::resources::read_input(path, 16 << 20)
        .map_err(|e| format!("a readable regular CSV file of at most 16 MiB ({e})"))?;
    let text = String::from_utf8(bytes).map_err(|_| "a CSV file of UTF-8 text".to_string())?;
    let (mut x, mut y) = (Vec::new(), Vec::new());
    let mut header_seen = false;
    for (number, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split([',', ';', '\t']).map(str::trim).collect();
        let values: Option<Vec<f64>> = fields.iter().map(|f| f.parse().ok()).collect();
        match values {
            Some(v) if v.len() == 2 => {
                x.push(v[0]);
                y.push(v[1]);
            }
            None if x.is_empty() && !header_seen => header_seen = true,
            _ => return Err(format!("two numbers per line (line {} reads `{line}`)", number + 1)),
        }
    }
    Ok((x, y))
}

impl DatumSpec {
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

impl FoundationSpec {
    /// The foundation's motion in dimension `d`: `velocity`, or a rotation about `center`
    /// (2D) or `axis_point` and `axis` (3D) at `angular_velocity`; errors name the key.
    pub(super) fn to_foundation(&self, d: usize) -> Result<Foundation, Error> {
        let point = |key: &str, values: &[f64]| -> Result<[f64; 3], Error> {
            if values.len() != d || values.iter().any(|v| !v.is_finite()) {
                return Err(invalid(key, &format!("{values:?}"), &format!("{d} finite coordinates")));
            }
            let mut p = [0.0; 3];
            p[..d].copy_from_slice(values);
            Ok(p)
        };
        let rotation_keys = [
            ("center", self.center.is_some()),
            ("axis_point", self.axis_point.is_some()),
            ("axis", self.axis.is_some()),
            ("angular_velocity", self.angular_velocity.is_some()),
        ];
        let given: Vec<&str> = rotation_keys.iter().filter(|(_, set)| *set).map(|(k, _)| *k).collect();
        match (&self.velocity, &self.angular_velocity) {
            (Some(velocity), None) if given.is_empty() => {
                Ok(Foundation::Velocity(velocity.to_datum("foundation.velocity", d)?))
            }
            (None, Some(omega)) => {
                let omega = omega.to_datum("foundation.angular_velocity", 1)?;
                let (centre, axis) = match (d, &self.center, &self.axis_point, &self.axis) {
                    (2, Some(c), None, None) => (point("foundation.center", c)?, [0.0, 0.0, 1.0]),
                    (3, None, Some(c), Some(a)) => (point("foundation.axis_point", c)?, point("foundation.axis", a)?),
                    _ => {
                        let expected = if d == 2 {
                            "a rotation in 2D is `center` (2 coordinates) with `angular_velocity`"
                        } else {
                            "a rotation in 3D is `axis_point` and `axis` (3 coordinates each) with `angular_velocity`"
                        };
                        return Err(invalid("foundation", &format!("{{{}}}", given.join(", ")), expected));
                    }
                };
                Foundation::rotation(centre, axis, omega)
                    .ok_or_else(|| invalid("foundation.axis", &format!("{axis:?}"), "a non-zero axis"))
            }
            _ => {
                let mut keys = given.clone();
                if self.velocity.is_some() {
                    keys.insert(0, "velocity");
                }
                Err(invalid(
                    "foundation",
                    &format!("{{{}}}", keys.join(", ")),
                    "either `velocity` (a datum per component) or a rotation: `center` (2D) or `axis_point` and `axis` (3D), with `angular_velocity`",
                ))
            }
        }
    }
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
    pub(super) fn datum_spec(&self, key: &str) -> Result<DatumSpec, Error> {
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

impl Scenario {
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

    /// The material of the scenario (`[material]`: of the cells in no `[[regions]]`).
    pub fn material(&self) -> Material {
        material_of(&self.material)
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
        .heat_exchange_boxed(heat_exchange(h)?)
        .frictional_heating_boxed(self.frictional_heating()?)
        .heat_share(self.frictional_heating.share)
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
        for region in &self.regions {
            builder = builder.region(&region.part, material_of(&region.material(&self.material)));
        }
        for (key, spec) in self.friction_keys() {
            builder = match friction_law(&key, spec)? {
                (Some(scale), law) => builder.friction_boxed(spec.part(), scale, law),
                (None, law) => builder.friction_from_pressure(spec.part(), law),
            };
        }
        if self.frictional_heating.friction_power {
            if let Some(value) = &self.frictional_heating.value {
                return Err(invalid(
                    "frictional_heating.value",
                    value,
                    "no value with friction_power = true (the heat is the friction's power b(r) r)",
                ));
            }
            builder = builder.frictional_heating_from_friction();
        }
        if let Some(foundation) = &self.foundation {
            builder = builder.foundation(foundation.to_foundation(d)?);
        }
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
        for (i, spec) in self.thermal.iter().enumerate() {
            let key = format!("thermal[{i}]");
            let condition = thermal_condition(&key, spec)?;
            builder = builder.labelled_thermal(&spec.part, condition, format!("{key}.value"));
        }
        Ok(builder)
    }

    /// The discrete problem of the scenario.
    pub fn build(&self) -> Result<Problem, Error> {
        self.build_from(self.builder()?)
    }

    /// [`Scenario::build`] (or, `continued`, [`Scenario::build_continued`]) on rank
    /// `comm.rank()` of a distributed run: its share of the matrices
    /// ([`ProblemBuilder::on_ranks`]; collective).
    #[cfg(feature = "mpi")]
    pub fn build_on_ranks(&self, continued: bool, comm: crate::la::mpi::Communicator) -> Result<Problem, Error> {
        let mut scenario = self.clone();
        if continued {
            scenario.initial.from = None;
        }
        let layers = scenario.solver.condensed_layers;
        scenario.build_from(scenario.builder()?.on_ranks(comm).contact_layers(layers))
    }

    /// The problem of `builder`, its errors named by the scenario's keys.
    fn build_from(&self, builder: ProblemBuilder) -> Result<Problem, Error> {
        builder.build().map_err(|e| match e {
            ModelError::CurvedSymmetryPart { part } => {
                invalid("boundary.symmetry", &part, "flat parts (a symmetry plane)")
            }
            e @ ModelError::CellInTwoRegions { .. } => self.region_error(e),
            other => other.into(),
        })
    }

    /// A cell in two regions given materials, named by the later region's key.
    fn region_error(&self, e: ModelError) -> Error {
        let ModelError::CellInTwoRegions { second, .. } = &e else {
            return e.into();
        };
        let i = self.regions.iter().position(|r| &r.part == second).unwrap_or(0);
        invalid(
            &format!("regions[{i}].part"),
            second,
            &format!("regions that share no cell: {e}"),
        )
    }

    /// The problem of a run continued from its own checkpoint (`--restart`): [`Scenario::build`]
    /// without reading `initial.from`. The continued run starts from its checkpoint, not from
    /// the initial fields, and the checkpoint `initial.from` names may be gone by then (a run
    /// that completes removes its checkpoint). The path still belongs to the scenario's
    /// fingerprint, so the restart stays tied to the same initial state's name.
    pub fn build_continued(&self) -> Result<Problem, Error> {
        let mut continued = self.clone();
        continued.initial.from = None;
        continued.build()
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
                forcing: s.krylov_forcing,
                max_iterations: s.max_krylov,
                preconditioner: s.preconditioner,
                overlap: s.overlap,
                condensed_layers: s.condensed_layers,
                ..KrylovParams::default()
            },
            anderson_depth: s.anderson_depth,
            contact_sweeps: s.contact_sweeps,
            prediction: s.prediction,
            backtracking: s.backtracking,
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
        let table = problem_table(self.to_toml().parse().expect("a scenario's TOML parses"));
        crate::output::checkpoint::text_fingerprint(&table.to_string())
    }

    /// Builds and runs the scenario without writing files (tests and studies); returns the
    /// summary and the state at T.
    pub fn run_quiet(&self) -> Result<(Summary, State), Error> {
        let problem = self.build()?;
        crate::driver::run_quiet(&problem, &self.solver_params(), &self.output_plan())
    }
}

/// The part of a scenario's table that [`Scenario::fingerprint`] covers: all but `[output]`,
/// `[solver]` and `mesh.file`.
fn problem_table(mut table: Table) -> Table {
    table.remove("output");
    table.remove("solver");
    if let Some(Value::Table(mesh)) = table.get_mut("mesh") {
        mesh.remove("file");
    }
    table
}

/// The keys of the problem (what [`Scenario::fingerprint`] covers) whose values differ between
/// two scenarios as TOML (`before`: a run's `scenario.toml`), each as `key: before → after`
/// (`absent` where one has no such key), so that a refused restart names them rather than two
/// digests. A text that does not parse yields no keys.
pub fn differing_keys(before: &str, after: &str) -> Vec<String> {
    let (Ok(before), Ok(after)) = (before.parse::<Table>(), after.parse::<Table>()) else {
        return Vec::new();
    };
    let mut keys = Vec::new();
    differing(&problem_table(before), &problem_table(after), "", &mut keys);
    keys
}

fn differing(before: &Table, after: &Table, prefix: &str, keys: &mut Vec<String>) {
    let mut names: Vec<&String> = before.keys().chain(after.keys()).collect();
    names.sort();
    names.dedup();
    let show = |v: Option<&Value>| v.map_or("absent".to_string(), |v| v.to_string());
    for name in names {
        let key = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        match (before.get(name), after.get(name)) {
            (Some(Value::Table(b)), Some(Value::Table(a))) => differing(b, a, &key, keys),
            (b, a) if b != a => keys.push(format!("{key}: {} → {}", show(b), show(a))),
            _ => {}
        }
    }
}

/// The material of a `[material]` table (or of a region's, completed by `[material]`).
fn material_of(m: &super::MaterialSpec) -> Material {
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

fn names(list: &[String]) -> Vec<&str> {
    list.iter().map(String::as_str).collect()
}

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
