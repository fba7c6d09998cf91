//! Python bindings of thermocontact: `import thermocontact`.
//!
//! A thin layer over the library's public API, in the floor of the command line (it uses what
//! `main.rs` uses: [`Scenario`](thermocontact::Scenario) to read and check parameters, the
//! driver to run, the time loop to step). Nothing here computes physics; every value crosses
//! as the core holds it, every array leaves Rust without a copy beyond the one a step needs.
//!
//! ```text
//! scenario.rs    Scenario: TOML ⇄ Python, `sc["mesh.nx"] = 64` as `--set mesh.nx=64`
//! mesh.rs        Mesh: from NumPy arrays (checked by Mesh::new), .msh files, generators
//! simulation.rs  Simulation (the Problem), run() → RunResult, steps() → Steps (a thread),
//!                State, Contact, StepInfo
//! errors.rs      thermocontact.Error and its subclasses, with the CLI's messages
//! values.rs      Python values ⇄ TOML values
//! ```

mod errors;
mod mesh;
mod scenario;
mod simulation;
mod values;

use pyo3::prelude::*;

/// Dynamic frictional contact of thermo-viscoelastic bodies with velocity-weakening friction (the
/// scheme of Bartosz, Danan & Szafraniec, Comput. Math. Appl. 73 (2017) 727–746), in Rust.
#[pymodule]
mod _thermocontact {
    use super::*;

    #[pymodule_export]
    use super::mesh::PyMesh;
    #[pymodule_export]
    use super::scenario::PyScenario;
    #[pymodule_export]
    use super::simulation::{PyContact, PyRunResult, PySimulation, PyState, PyStepInfo, PySteps};

    #[pymodule_init]
    fn init(module: &Bound<'_, PyModule>) -> PyResult<()> {
        thermocontact::resources::check_instruction_set().map_err(pyo3::exceptions::PyImportError::new_err)?;
        // As the command line does: measured on 2 cores, faer's sequential kernels beat its
        // rayon ones at these sizes.
        faer::set_global_parallelism(faer::Par::Seq);
        errors::register(module)?;
        module.add("DEFAULT_TOML", thermocontact::scenario::DEFAULT_TOML)?;
        module.add("__version__", env!("CARGO_PKG_VERSION"))?;
        Ok(())
    }
}
