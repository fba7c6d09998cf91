//! The checks of a scenario: every value against its admissible range, each error naming the
//! dotted key, the value and what was expected; the memory estimate of the mesh
//! ([`Error::TooLarge`]); and [`keys_behind`], the keys behind a failed step matrix.

use super::{FrictionSpec, HeatExchangeSpec, Scenario};
use crate::error::Error;
use crate::mesh;
use crate::step::{LinearKind, PreconditionerKind, MAX_OVERLAP};

/// The deepest cutback a scenario may ask for: 2^20 substeps of one step is already a
/// different time grid, not a rescue.
pub const MAX_CUTBACK_DEPTH: usize = 20;

/// The deepest Anderson acceleration a scenario may ask for: the loop's tails are a handful of
/// iterates (depth 2 and 3 took the same iterations on the 3D example, `step::anderson`).
pub const MAX_ANDERSON_DEPTH: usize = 8;

/// The most Gauss–Seidel sweeps over Γ_C `solver.contact_sweeps` takes. Over Γ_C's own rows
/// more gain little (27, 23 and 22 Newton iterations over 4 steps of the 3D example at 291k
/// unknowns with one, two and four forward sweeps, 32 with one or two at 972k; a slab of 104 ×
/// 6 × 6 cells, 16 steps: 382, 349 and 331 with one, two and four symmetric ones); through the
/// body (`solver.condensed_layers`) 8 carry fronts that fewer do not (that slab: 320, 220, 170
/// and 139 with 1, 2, 4 and 8).
pub const MAX_CONTACT_SWEEPS: usize = 8;

/// The most layers of bulk unknowns `solver.condensed_layers` condenses through (two carry what
/// matters: at 47k unknowns and k = 1/8, 105 Newton iterations over 8 steps with 2, 101 with 4,
/// 99 with the whole body; each layer adds about |Γ_C| nodes to the rows condensed once per step
/// size, `step::contact_condensation`).
pub const MAX_CONDENSED_LAYERS: usize = 8;

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

/// The most time steps a run may have (its per-step records stay in memory: ~100 bytes each).
pub const MAX_STEPS: usize = 1_000_000;

/// The constants of a material against their ranges, each error naming `{table}.{key}`.
fn material_in_range(m: &super::MaterialSpec, d: usize, table: &str) -> Result<(), Error> {
    let key = |name: &str| format!("{table}.{name}");
    positive(&key("density"), m.density)?;
    positive(&key("heat_capacity"), m.heat_capacity)?;
    positive(&key("viscosity_mu2"), m.viscosity_mu2)?;
    if !m.viscosity_mu1.is_finite() || m.viscosity_mu1 * d as f64 + m.viscosity_mu2 <= 0.0 {
        return Err(invalid(
            &key("viscosity_mu1"),
            &m.viscosity_mu1,
            "d·μ₁ + μ₂ > 0 (𝒜 coercive)",
        ));
    }
    positive(&key("young"), m.young)?;
    if !(m.poisson > -1.0 && m.poisson < 0.5) {
        return Err(invalid(&key("poisson"), &m.poisson, "a Poisson ratio in (−1, 0.5)"));
    }
    finite(&key("thermal_expansion"), m.thermal_expansion)?;
    finite(&key("reference_temperature"), m.reference_temperature)?;
    positive(&key("conductivity"), m.conductivity)?;
    Ok(())
}

impl Scenario {
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
        self.validate_boundary()?;
        self.validate_material(d)?;
        self.validate_data(d)?;
        self.validate_laws()?;
        self.validate_thermal()?;
        self.validate_solver()?;
        self.validate_output()
    }

    /// The boundary parts: the mesh's, each in at most one list, and Γ_C not empty.
    fn validate_boundary(&self) -> Result<(), Error> {
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
        Ok(())
    }

    /// The material constants, `[material]`'s and each region's (its own keys and those it
    /// inherits, named by the region's key), and the regions' parts: cell regions of the mesh,
    /// each given once.
    fn validate_material(&self, d: usize) -> Result<(), Error> {
        material_in_range(&self.material, d, "material")?;
        let known = self.loaded.0.as_ref().map(|m| m.region_names()).unwrap_or_default();
        for (i, region) in self.regions.iter().enumerate() {
            let key = format!("regions[{i}]");
            if !known.contains(&region.part) {
                let expected = if known.is_empty() {
                    "a cell region of the mesh, but it has none (regions are the physical groups of dimension d of a mesh.file)".to_string()
                } else {
                    format!("a cell region of the mesh, among {known:?}")
                };
                return Err(invalid(&format!("{key}.part"), &region.part, &expected));
            }
            if self.regions[..i].iter().any(|r| r.part == region.part) {
                return Err(invalid(
                    &format!("{key}.part"),
                    &region.part,
                    "each region in one [[regions]] table",
                ));
            }
            material_in_range(&region.material(&self.material), d, &key)?;
        }
        Ok(())
    }

    /// The initial data, the boundary temperature and the loads (with their parts).
    fn validate_data(&self, d: usize) -> Result<(), Error> {
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
        Ok(())
    }

    /// The friction laws, the heat exchange and the frictional heating: each built once (the
    /// build's own constructors), so a table, a file or an expression that would fail the run
    /// fails here, naming its key.
    fn validate_laws(&self) -> Result<(), Error> {
        for (key, spec) in self.friction_keys() {
            let at = |name: &str| format!("{key}.{name}");
            match spec {
                FrictionSpec::VelocityWeakening { a, b, alpha, .. }
                | FrictionSpec::SlipWeakening { a, b, alpha, .. } => {
                    positive(&at("b"), *b)?;
                    finite(&at("a"), *a)?;
                    if a < b {
                        return Err(invalid(&at("a"), a, &format!("a ≥ b = {b} (μ decreasing)")));
                    }
                    non_negative(&at("alpha"), *alpha)?;
                }
                FrictionSpec::SlipDistanceWeakening {
                    static_coefficient,
                    dynamic,
                    distance,
                    ..
                } => {
                    non_negative(&at("static"), *static_coefficient)?;
                    non_negative(&at("dynamic"), *dynamic)?;
                    positive(&at("distance"), *distance)?;
                }
                FrictionSpec::Coulomb { coefficient, .. } => non_negative(&at("coefficient"), *coefficient)?,
                FrictionSpec::Tresca { .. } | FrictionSpec::Table { .. } | FrictionSpec::Expression { .. } => {}
            }
            if let (super::FrictionSpecs::Parts(_), None) = (&self.friction, spec.part()) {
                let others = self.friction.laws().iter().filter(|l| l.part().is_none()).count();
                if others > 1 {
                    return Err(invalid(
                        &at("part"),
                        &"(none)",
                        "a part for every [[friction]] table but one",
                    ));
                }
            }
            super::build::friction_law(&key, spec)?;
        }
        match &self.heat_exchange {
            HeatExchangeSpec::Linear {
                coefficient,
                foundation_temperature,
            } => {
                non_negative("heat_exchange.coefficient", *coefficient)?;
                finite("heat_exchange.foundation_temperature", *foundation_temperature)?;
            }
            HeatExchangeSpec::Table { .. } | HeatExchangeSpec::Expression { .. } => {}
        }
        super::build::heat_exchange(&self.heat_exchange)?;
        finite("frictional_heating.constant", self.frictional_heating.constant)?;
        finite("frictional_heating.rate", self.frictional_heating.rate)?;
        let share = self.frictional_heating.share;
        if !(0.0..=1.0).contains(&share) {
            return Err(invalid("frictional_heating.share", &share, "a fraction in [0, 1]"));
        }
        self.frictional_heating()?;
        Ok(())
    }

    /// The thermal conditions: each on a boundary part of the mesh that is not a contact part,
    /// no part twice, each condition with its keys (built once, as the run would).
    fn validate_thermal(&self) -> Result<(), Error> {
        let parts = self.part_names();
        for (i, spec) in self.thermal.iter().enumerate() {
            let key = format!("thermal[{i}].part");
            if !parts.contains(&spec.part) {
                return Err(invalid(
                    &key,
                    &spec.part,
                    &format!("a boundary part of the mesh, among {parts:?}"),
                ));
            }
            if self.boundary.contact.contains(&spec.part) {
                return Err(invalid(
                    &key,
                    &spec.part,
                    "a part that is not in boundary.contact (Γ_C has its own heat exchange law, [heat_exchange])",
                ));
            }
            if let Some(j) = self.thermal[..i].iter().position(|t| t.part == spec.part) {
                return Err(invalid(
                    &key,
                    &spec.part,
                    &format!("each part in at most one [[thermal]] table (thermal[{j}] has it already)"),
                ));
            }
            super::build::thermal_condition(&format!("thermal[{i}]"), spec)?;
        }
        Ok(())
    }

    /// The solver settings.
    fn validate_solver(&self) -> Result<(), Error> {
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
        if !(s.krylov_forcing >= 0.0 && s.krylov_forcing < 1.0) {
            return Err(invalid(
                "solver.krylov_forcing",
                &s.krylov_forcing,
                "a fraction in [0, 1) of the residual a Newton iteration's solve starts from (0: every solve to solver.krylov_tolerance)",
            ));
        }
        at_least_one("solver.max_krylov", s.max_krylov)?;
        if s.anderson_depth > MAX_ANDERSON_DEPTH {
            return Err(invalid(
                "solver.anderson_depth",
                &s.anderson_depth,
                &format!("at most {MAX_ANDERSON_DEPTH} (0 turns the acceleration off)"),
            ));
        }
        if s.contact_sweeps > MAX_CONTACT_SWEEPS {
            return Err(invalid(
                "solver.contact_sweeps",
                &s.contact_sweeps,
                &format!("at most {MAX_CONTACT_SWEEPS} (0: the paper's loop, without predicted bounds)"),
            ));
        }
        if s.condensed_layers > MAX_CONDENSED_LAYERS {
            return Err(invalid(
                "solver.condensed_layers",
                &s.condensed_layers,
                &format!("at most {MAX_CONDENSED_LAYERS} (0: the sweeps over Γ_C's own rows, the body held)"),
            ));
        }
        if s.overlap > MAX_OVERLAP {
            return Err(invalid(
                "solver.overlap",
                &s.overlap,
                "0 (block Jacobi over the ranks) or 1 (restricted additive Schwarz)",
            ));
        }
        if s.preconditioner == PreconditionerKind::Amg && !cfg!(feature = "petsc") {
            return Err(invalid(
                "solver.preconditioner",
                &"amg",
                "\"ilu\": this build has no AMG (build thermocontact with `--features petsc`, which needs PETSc)",
            ));
        }
        Ok(())
    }

    /// The output times.
    fn validate_output(&self) -> Result<(), Error> {
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
        // The contact nodes are not known before the mesh: the unknowns decide (the direct
        // path's memory, the larger, where the cost model would take it).
        let size = crate::step::ProblemSize {
            dim: d,
            unknowns: unknowns as usize,
            contact_nodes: 0,
            steps: self.time.steps,
        };
        let linear = (self.solver.linear).resolve(&size, self.solver.kind, available);
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
}

pub(super) fn invalid(key: &str, value: &dyn std::fmt::Debug, expected: &str) -> Error {
    Error::InvalidValue {
        key: key.to_string(),
        value: format!("{value:?}"),
        expected: expected.to_string(),
    }
}

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

/// The keys behind the step matrix, named for an error of its linear algebra.
const STEP_MATRIX_KEYS: &str = "It is built from material.density, material.young, material.poisson, \
     material.viscosity_mu1, material.viscosity_mu2, material.conductivity, material.heat_capacity, \
     material.thermal_expansion (and these keys of [[regions]]), heat_exchange.coefficient, the mesh's cell sizes \
     and time.steps (k): check their magnitudes";

/// The keys of a step's data (its right-hand side and contact terms), named first for a
/// non-finite solve: the scenario's numbers are bounded (magnitudes ≤ 10¹⁸) where expressions
/// are not, so an overflow past 10³⁰⁸ more often comes from the data than from the matrix.
const STEP_DATA_KEYS: &str = "The step's data come from loads.body_force, loads.traction, loads.pressure, \
     loads.heat_source, initial.displacement, initial.velocity, initial.temperature, friction.bound, \
     frictional_heating and heat_exchange (their expressions too); its matrix";

/// The scenario keys behind an error, as a hint to append to its message: for a failed
/// factorization or a non-finite solve of the step matrix, the keys the matrix is built from;
/// `None` for any other error. The scenario layer is the one place that names keys.
pub fn keys_behind(error: &Error) -> Option<String> {
    use crate::la::LaError;
    use crate::step::StepError;
    match error {
        Error::Step(StepError::La(LaError::Factorization { .. })) => Some(STEP_MATRIX_KEYS.to_string()),
        Error::Step(StepError::La(LaError::NonFiniteSolution { .. })) => Some(format!(
            "{STEP_DATA_KEYS} {}",
            STEP_MATRIX_KEYS.strip_prefix("It ").unwrap_or(STEP_MATRIX_KEYS)
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::la::{FactorStage, LaError};
    use crate::step::StepError;

    #[test]
    fn keys_behind_names_the_keys_of_a_failed_step_matrix() {
        let expected = "It is built from material.density, material.young, material.poisson, material.viscosity_mu1, \
                        material.viscosity_mu2, material.conductivity, material.heat_capacity, \
                        material.thermal_expansion (and these keys of [[regions]]), heat_exchange.coefficient, \
                        the mesh's cell sizes and time.steps (k): check their magnitudes";
        let factorization = Error::Step(StepError::La(LaError::Factorization {
            stage: FactorStage::Numeric,
            detail: "zero pivot".into(),
        }));
        assert_eq!(keys_behind(&factorization).as_deref(), Some(expected));
        let non_finite = Error::Step(StepError::La(LaError::NonFiniteSolution {
            non_finite: 3,
            unknowns: 12,
        }));
        // A non-finite solve names the data first (a load's expression may overflow), then the
        // matrix.
        let named = keys_behind(&non_finite).unwrap();
        assert!(
            named.starts_with("The step's data come from loads.body_force"),
            "{named}"
        );
        assert!(named.ends_with(&expected[3..]), "{named}");
        let krylov = Error::Step(StepError::La(LaError::KrylovNotConverged {
            method: "GMRES",
            iterations: 10,
            rtol: 1e-8,
            residual: 1e-3,
            history: Vec::new(),
        }));
        assert_eq!(keys_behind(&krylov), None);
        assert_eq!(keys_behind(&Error::Scenario("bad".into())), None);
        assert_eq!(keys_behind(&invalid("time.steps", &0, "an integer ≥ 1")), None);
    }
}
