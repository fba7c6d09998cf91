//! Scenario files: every parameter of a run, in TOML.
//!
//! The paper's Section 6 example is built in (`scenarios/paper.toml`, printed by
//! `thermocontact scenario`). A user file is laid over it key by key, then `--set a.b=value`
//! overrides are applied, then the result is checked: unknown keys, wrong types and invalid
//! values are errors that name the dotted key, the value and what was expected.
//!
//! Depends on: [`crate::driver`] (a quiet run, the output plan), [`crate::error`],
//! [`crate::output`] (checkpoints and fingerprints), [`crate::step`] (solver settings, the
//! step's errors), [`crate::model`] (the problem builder), [`crate::contact`],
//! [`crate::loads`], [`crate::material`], [`crate::mesh`], [`crate::la`] (the errors of a
//! failed step matrix), [`crate::resources`] (the memory estimate).
//!
//! - `schema`: the serde types of the TOML ([`Scenario`] and its tables, [`DatumSpec`]);
//! - `load`: the text or file laid over the built-in default ([`DEFAULT_TOML`]), the
//!   `--set key=value` overrides, unknown and removed keys;
//! - `validate`: the checks, each naming its key (ranges, the memory estimate), and
//!   [`keys_behind`] a failed step matrix — the one place that names keys;
//! - `build`: the translation into a [`crate::ProblemBuilder`], [`crate::SolverParams`] and
//!   a [`crate::driver::OutputPlan`] (initial fields from data or a checkpoint).

mod build;
mod load;
mod schema;
mod validate;

pub use build::differing_keys;
pub use load::{DEFAULT_TOML, MAX_SCENARIO_BYTES};
pub use schema::{
    Affine, BoundarySpec, DatumSpec, FoundationSpec, FrictionSpec, FrictionSpecs, FrictionalHeatingSpec, Geometry,
    HeatExchangeSpec, InitialSpec, Loads, MaterialSpec, MeshSpec, NormalSpec, OutputSpec, Pressure, RegionSpec,
    Scenario, SolverSpec, Structured, ThermalSpec, TimeSpec, Traction, THERMAL_CONDITIONS,
};
pub use validate::{
    keys_behind, LENGTH_RANGE, MAX_CELL_ASPECT, MAX_CUTBACK_DEPTH, MAX_MAGNITUDE, MAX_OUTPUT_TIMES, MAX_STEPS,
};

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
            FrictionSpecs::One(FrictionSpec::VelocityWeakening {
                part: None,
                bound: Some(DatumSpec::Scalar(Box::new(DatumSpec::Numbers(vec![150.0])))),
                normal: None,
                a: 1.0,
                b: 0.2,
                alpha: 100.0
            })
        );
        assert_eq!(s.loads.traction[0].rate, Some(vec![0.0, -800.0]));
        assert_eq!(s.output_steps(), vec![16, 32, 48, 64]);
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
        let e = Scenario::load(None, &["friction.law=amontons".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("amontons") && e.contains("coulomb"), "{e}");
        // A known law without its keys names the missing one.
        let e = Scenario::load(None, &["friction.law=coulomb".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("friction.coefficient"), "{e}");
        let e = Scenario::load(Some("[time]\nsteps = -4"), &[]).unwrap_err().to_string();
        assert!(e.contains("time.steps") && e.contains("-4"), "{e}");
        assert!(e.ends_with("(expected a non-negative integer)"), "{e}");
        let e = Scenario::load(None, &["friction={law=\"tresca\", bound=3.0, a=1.0}".into()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("friction") && e.contains('a'), "{e}");
    }
}
