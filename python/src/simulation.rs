//! `thermocontact.Simulation`: a scenario made discrete (the core's `Problem`), run whole
//! (`run()`, the command line's `run`: the same driver, the same files when asked) or step by
//! step (`steps()`), with the results as NumPy arrays.
//!
//! **Step by step.** The time loop (`time::march`) runs on a Rust thread that shares the
//! problem; each new state is cloned (the one copy a step costs) and handed over a rendezvous
//! channel, so the loop is at most one step ahead of the script. When the script stops
//! iterating (a `break`, `close()`, or the iterator being dropped) the next hand-over fails and
//! the loop stops with `Error::Interrupted { cause: Interruption::Caller }`. The GIL is released
//! while the script waits for a step, so other Python threads run meanwhile.

use std::path::PathBuf;
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use numpy::ndarray::Array3;
use numpy::{PyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList};
use thermocontact::driver::{self, contact_csv_header, contact_csv_rows, OutputPlan, RunOptions, StopFlag};
use thermocontact::model::State;
use thermocontact::model::StepEnergy;
use thermocontact::model::{contact_rows, ContactRow};
use thermocontact::output::fields;
use thermocontact::step::{SolverParams, StepInfo};
use thermocontact::time::{self, Levels};
use thermocontact::{Error, Interruption, Problem, Scenario};

use crate::errors;
use crate::mesh::{matrix, PyMesh};
use crate::scenario::PyScenario;

/// A scenario made discrete: mesh, spaces, matrices, contact nodes and loads, built once
/// (Simulation(scenario) assembles; the GIL is released meanwhile). Run it whole with run()
/// or step by step with steps(); both may be called any number of times.
#[pyclass(name = "Simulation", module = "thermocontact", frozen)]
pub struct PySimulation {
    scenario: PyScenario,
    problem: Arc<Problem>,
}

impl PySimulation {
    fn params(&self) -> SolverParams {
        self.scenario.inner.solver_params()
    }

    fn plan(&self) -> OutputPlan {
        self.scenario.inner.output_plan()
    }
}

#[pymethods]
impl PySimulation {
    #[new]
    fn new(py: Python<'_>, scenario: PyRef<'_, PyScenario>) -> PyResult<Self> {
        let scenario = scenario.clone();
        let inner: &Scenario = &scenario.inner;
        let problem = py.detach(|| inner.build()).map_err(|e| errors::to_py(py, &e))?;
        Ok(PySimulation {
            scenario,
            problem: Arc::new(problem),
        })
    }

    /// The scenario (a copy).
    #[getter]
    fn scenario(&self) -> PyScenario {
        self.scenario.clone()
    }

    /// The mesh the problem is built on.
    #[getter]
    fn mesh(&self) -> PyMesh {
        PyMesh::wrap(self.problem.mesh.clone())
    }

    /// Space dimension d.
    #[getter]
    fn dim(&self) -> usize {
        self.problem.dim()
    }

    /// Unknowns of a step: free velocity components and free temperatures.
    #[getter]
    fn n_unknowns(&self) -> usize {
        self.problem.n_unknowns()
    }

    /// Number of time steps N.
    #[getter]
    fn n_steps(&self) -> usize {
        self.problem.time.steps
    }

    /// Time step k = T/N.
    #[getter]
    fn time_step(&self) -> f64 {
        self.problem.time_step()
    }

    /// The mesh nodes of the frictional contact nodes, in the order of every contact table
    /// (int64 array).
    #[getter]
    fn contact_nodes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let nodes: Vec<i64> = self.problem.contact.iter().map(|c| c.node as i64).collect();
        PyArray1::from_vec(py, nodes)
    }

    /// The initial state (10): u₀, u₁ and θ₀ at the nodes, no friction stress (n = 0).
    fn initial_state(&self, py: Python<'_>) -> PyResult<PyState> {
        let state = State::initial(&self.problem);
        PyState::new(py, state, None, self.problem.clone(), self.plan().slip_tolerance, None)
    }

    /// run(out=None, progress=False, log=False, overwrite=False) -> RunResult
    ///
    /// Runs all N steps, as `thermocontact run` does (the same driver): with `out`, the same
    /// files in that folder (solution.pvd and .vtu frames, contact CSVs, steps.csv,
    /// summary.json, scenario.toml, as the scenario's `output` table asks); a folder holding
    /// another run's results is refused (FileError) unless `overwrite`. Returns the states at
    /// the output times, the state at T and the summary. `progress` draws the command line's
    /// progress bar on stderr, `log` prints a line per cutback. A step that does not converge
    /// even after the cutbacks raises SolverError (with `out`, the folder keeps what was
    /// computed, as the command line's does). Ctrl-C stops the run after its current step (the
    /// folder then says "interrupted") and raises KeyboardInterrupt. The Python lock is released
    /// while it runs.
    #[pyo3(signature = (out = None, progress = false, log = false, overwrite = false))]
    fn run(
        &self,
        py: Python<'_>,
        out: Option<PathBuf>,
        progress: bool,
        log: bool,
        overwrite: bool,
    ) -> PyResult<PyRunResult> {
        let problem = &*self.problem;
        let (params, plan) = (self.params(), self.plan());
        let stop = StopFlag::new();
        let options = RunOptions {
            out_dir: out,
            progress,
            log,
            overwrite,
            stop: Some(stop.clone()),
            ..RunOptions::default()
        };
        // The run goes on a thread of its own, so that this one can look for Ctrl-C (Python
        // sees signals only on the main thread, between bytecodes) while it waits.
        let (sender, receiver) = std::sync::mpsc::channel();
        let receiver = Mutex::new(receiver);
        let mut interrupted: Option<PyErr> = None;
        let (run, (captured, energies)) = std::thread::scope(|scope| {
            scope.spawn(|| {
                let mut captured: Vec<(State, StepInfo)> = Vec::with_capacity(plan.steps.len());
                let mut energies: Vec<(f64, StepEnergy)> = Vec::with_capacity(problem.time.steps);
                let run = driver::run_observed(problem, &params, &plan, &options, |_, state, info| {
                    energies.push((state.t, info.energy));
                    if plan.steps.contains(&state.n) {
                        captured.push((state.clone(), *info));
                    }
                });
                let _ = sender.send((run, (captured, energies)));
            });
            loop {
                let waited = py.detach(|| {
                    let receiver = receiver.lock().expect("not poisoned");
                    receiver.recv_timeout(Duration::from_millis(100))
                });
                match waited {
                    Ok(done) => break done,
                    Err(RecvTimeoutError::Timeout) => {
                        if let Err(signal) = py.check_signals() {
                            // The run stops after its current step and writes its files.
                            stop.request(Interruption::Interrupt);
                            interrupted.get_or_insert(signal);
                        }
                    }
                    Err(RecvTimeoutError::Disconnected) => {
                        unreachable!("the run's thread sends before it ends (a panic propagates from the scope)")
                    }
                }
            }
        });
        if let Some(signal) = interrupted {
            return Err(signal);
        }
        let mut run = run.map_err(|e| errors::to_py(py, &e))?;
        let summary = serde_json::to_string(&run.summary).expect("a summary serializes");
        let summary = py.import("json")?.call_method1("loads", (summary,))?;
        let mut outputs = Vec::with_capacity(captured.len());
        for (state, info) in captured {
            // The driver recorded the contact table of each output time: reuse it.
            let rows = run
                .summary
                .outputs
                .iter_mut()
                .find(|record| record.n == state.n)
                .map(|record| std::mem::take(&mut record.contact));
            let state = PyState::new(py, state, Some(info), self.problem.clone(), plan.slip_tolerance, rows)?;
            outputs.push(Py::new(py, state)?);
        }
        let last = PyState::new(py, run.state, None, self.problem.clone(), plan.slip_tolerance, None)?;
        Ok(PyRunResult {
            summary: summary.unbind(),
            outputs,
            last: Py::new(py, last)?,
            energy: energy_table(py, &energies)?.into_any().unbind(),
        })
    }

    /// steps() -> Steps: the run step by step, an iterator of State (n = 1 … N) with each
    /// step's solver figures (state.info). Stop it with `break` (or close()): the time loop
    /// stops within one step. A step that does not converge raises SolverError from next().
    ///
    ///     for state in sim.steps():
    ///         print(state.n, state.t, state.info.newton_iterations, state.contact.slip.sum())
    ///         if state.theta.max() > 30:
    ///             break
    fn steps(&self) -> PySteps {
        PySteps::start(self.problem.clone(), self.params(), self.plan().slip_tolerance)
    }

    fn __repr__(&self) -> String {
        format!(
            "<thermocontact.Simulation {}D: {} nodes, {} unknowns, {} contact nodes, {} steps of {}>",
            self.problem.dim(),
            self.problem.mesh.n_nodes(),
            self.problem.n_unknowns(),
            self.problem.contact.len(),
            self.problem.time.steps,
            self.problem.time_step()
        )
    }
}

/// The solver figures of one time step (the core's StepInfo).
#[pyclass(name = "StepInfo", module = "thermocontact", frozen, get_all)]
#[derive(Clone)]
pub struct PyStepInfo {
    /// Outer (convexification) iterations.
    convexification_iterations: usize,
    /// Inner iterations summed over the outer ones (Uzawa, or descent sweeps in 3D).
    inner_iterations: usize,
    /// Last relative increments of u, θ, ξ, ζ: the left sides of (77)–(80).
    increments: [f64; 4],
    /// Semismooth Newton iterations (fast solver).
    newton_iterations: usize,
    /// The fast solver went through the convexification loop in this step.
    fallback: bool,
    /// Sweeps of the fast solver's descent.
    descent_sweeps: usize,
    /// Iterations of the iterative path's Newton on the nonmonotone law, where the
    /// convexification loop failed (0 where the loop solved the step).
    nonmonotone_newton_iterations: usize,
    /// Convexification iterates of the iterative path that started from an Anderson
    /// combination of the bounds (`solver.anderson_depth`).
    anderson_combinations: usize,
    /// Convexification iterates of the iterative path whose bounds the Gauss–Seidel sweeps
    /// over Γ_C predicted (`solver.contact_sweeps`).
    predicted_iterates: usize,
    /// Newton iterations of the iterative path's convex problems cut back along their step,
    /// where the full step raised the friction law's residual.
    backtracked_newton_iterations: usize,
    /// Substeps the step took: 1 without cutback, 2^depth at the deepest cutback.
    substeps: usize,
    /// The deepest cutback of the step (0: none): its shortest substep was k/2^depth.
    cutback_depth: usize,
    /// Krylov (GMRES) iterations of the step's linear solves (iterative path; 0 on the direct
    /// path).
    krylov_iterations: usize,
    /// The step's energies (docs/energy.md): name → value, J (2D: per metre of thickness).
    energy: std::collections::BTreeMap<String, f64>,
}

impl From<StepInfo> for PyStepInfo {
    fn from(info: StepInfo) -> Self {
        PyStepInfo {
            convexification_iterations: info.convexification_iterations,
            inner_iterations: info.inner_iterations,
            increments: info.increments,
            newton_iterations: info.newton_iterations,
            fallback: info.fallback,
            descent_sweeps: info.descent_sweeps,
            nonmonotone_newton_iterations: info.nonmonotone_newton_iterations,
            anderson_combinations: info.anderson_combinations,
            predicted_iterates: info.predicted_iterates,
            backtracked_newton_iterations: info.backtracked_newton_iterations,
            substeps: info.substeps,
            cutback_depth: info.cutback_depth,
            krylov_iterations: info.krylov_iterations,
            energy: match serde_json::to_value(info.energy).expect("energies serialize") {
                serde_json::Value::Object(map) => map
                    .into_iter()
                    .map(|(k, v)| (k, v.as_f64().unwrap_or(f64::NAN)))
                    .collect(),
                _ => unreachable!("a struct serializes to an object"),
            },
        }
    }
}

#[pymethods]
impl PyStepInfo {
    /// The figures as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("convexification_iterations", self.convexification_iterations)?;
        d.set_item("inner_iterations", self.inner_iterations)?;
        d.set_item("increments", self.increments)?;
        d.set_item("newton_iterations", self.newton_iterations)?;
        d.set_item("fallback", self.fallback)?;
        d.set_item("descent_sweeps", self.descent_sweeps)?;
        d.set_item("nonmonotone_newton_iterations", self.nonmonotone_newton_iterations)?;
        d.set_item("anderson_combinations", self.anderson_combinations)?;
        d.set_item("predicted_iterates", self.predicted_iterates)?;
        d.set_item("backtracked_newton_iterations", self.backtracked_newton_iterations)?;
        d.set_item("substeps", self.substeps)?;
        d.set_item("cutback_depth", self.cutback_depth)?;
        d.set_item("krylov_iterations", self.krylov_iterations)?;
        d.set_item("energy", self.energy.clone())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "StepInfo(convexification_iterations={}, inner_iterations={}, newton_iterations={}, fallback={}, \
             descent_sweeps={}, nonmonotone_newton_iterations={}, anderson_combinations={}, predicted_iterates={}, \
             backtracked_newton_iterations={}, substeps={}, cutback_depth={}, krylov_iterations={})",
            self.convexification_iterations,
            self.inner_iterations,
            self.newton_iterations,
            if self.fallback { "True" } else { "False" },
            self.descent_sweeps,
            self.nonmonotone_newton_iterations,
            self.anderson_combinations,
            self.predicted_iterates,
            self.backtracked_newton_iterations,
            self.substeps,
            self.cutback_depth,
            self.krylov_iterations
        )
    }
}

/// The state at one time level t_n = n k: fields at the nodes, friction stress at the contact
/// nodes, and (for a step of a run) the step's solver figures.
///
/// u, w     -- (n_nodes, d) float64: displacement and velocity;
/// theta    -- (n_nodes,) float64: temperature;
/// xi       -- (n_contact, d − 1) float64: friction stress in each contact node's tangent
///             coordinates (Simulation.contact_nodes order);
/// contact  -- the contact table (Contact), computed on first access;
/// stress   -- (n_cells, 6) (xx, yy, zz, xy, yz, xz), in 2D as in 3D (2D: plane strain, so
///             σ_zz ≠ 0 and σ_yz = σ_xz = 0): σ = 𝒜ε(w) + ℬε(u) + C(θ − θ_ref) per cell,
///             computed on first access from the arrays;
/// info     -- StepInfo (None for the initial state and the final state of a run).
///
/// The arrays are handed out without copies (the state's own memory); changing them in place
/// changes what contact and stress are computed from, if they have not been yet.
#[pyclass(name = "State", module = "thermocontact", frozen)]
pub struct PyState {
    /// Time level n.
    #[pyo3(get)]
    n: usize,
    /// t_n.
    #[pyo3(get)]
    t: f64,
    #[pyo3(get)]
    u: Py<PyArray2<f64>>,
    #[pyo3(get)]
    w: Py<PyArray2<f64>>,
    #[pyo3(get)]
    theta: Py<PyArray1<f64>>,
    #[pyo3(get)]
    xi: Py<PyArray2<f64>>,
    #[pyo3(get)]
    info: Option<PyStepInfo>,
    /// The slip distances after and before the step (the contact table reads them).
    slip_distance: [Vec<f64>; 2],
    /// The contact pressures (Coulomb friction; empty otherwise).
    pressure: Vec<f64>,
    problem: Arc<Problem>,
    slip_tolerance: f64,
    contact: PyOnceLock<Py<PyContact>>,
    stress: PyOnceLock<Py<PyArray2<f64>>>,
}

impl PyState {
    /// Moves the state's vectors into NumPy arrays; `rows`: its contact table if known.
    fn new(
        py: Python<'_>,
        state: State,
        info: Option<StepInfo>,
        problem: Arc<Problem>,
        slip_tolerance: f64,
        rows: Option<Vec<ContactRow>>,
    ) -> PyResult<Self> {
        let d = problem.dim();
        let contact = PyOnceLock::new();
        if let Some(rows) = rows {
            let table = Py::new(py, PyContact::new(py, d, rows))?;
            let _ = contact.set(py, table);
        }
        Ok(PyState {
            n: state.n,
            t: state.t,
            u: matrix(py, state.u, d).unbind(),
            w: matrix(py, state.w, d).unbind(),
            theta: PyArray1::from_vec(py, state.theta).unbind(),
            xi: matrix(py, state.xi, d - 1).unbind(),
            info: info.map(PyStepInfo::from),
            slip_distance: [state.slip_distance, state.slip_distance_before],
            pressure: state.pressure,
            problem,
            slip_tolerance,
            contact,
            stress: PyOnceLock::new(),
        })
    }

    /// The core's State, from the arrays (for the derived quantities).
    fn core_state(&self, py: Python<'_>) -> PyResult<State> {
        let vector = |array: &Bound<'_, PyAny>| -> PyResult<Vec<f64>> {
            let array = array.cast::<numpy::PyArrayDyn<f64>>()?;
            Ok(array.readonly().as_array().iter().copied().collect())
        };
        Ok(State {
            n: self.n,
            t: self.t,
            u: vector(self.u.bind(py).as_any())?,
            w: vector(self.w.bind(py).as_any())?,
            theta: vector(self.theta.bind(py).as_any())?,
            xi: vector(self.xi.bind(py).as_any())?,
            slip_distance: self.slip_distance[0].clone(),
            slip_distance_before: self.slip_distance[1].clone(),
            pressure: self.pressure.clone(),
            elastic_force: Vec::new(),
        })
    }
}

#[pymethods]
impl PyState {
    /// The contact table at this state (Contact).
    #[getter]
    fn contact(&self, py: Python<'_>) -> PyResult<Py<PyContact>> {
        self.contact
            .get_or_try_init(py, || {
                let state = self.core_state(py)?;
                let rows = contact_rows(&self.problem, &state, self.slip_tolerance);
                Py::new(py, PyContact::new(py, self.problem.dim(), rows))
            })
            .map(|c| c.clone_ref(py))
    }

    /// σ per cell: (n_cells, 3) (xx, yy, xy) in 2D, (n_cells, 6) (xx, yy, zz, xy, yz, xz) in 3D.
    #[getter]
    fn stress(&self, py: Python<'_>) -> PyResult<Py<PyArray2<f64>>> {
        self.stress
            .get_or_try_init(py, || -> PyResult<_> {
                let state = self.core_state(py)?;
                let problem = &*self.problem;
                let values = py.detach(|| fields::cell_stress(problem, &state));
                Ok(matrix(py, values, fields::STRESS_COMPONENTS.len()).unbind())
            })
            .map(|s| s.clone_ref(py))
    }

    fn __repr__(&self) -> String {
        format!("<thermocontact.State n = {}, t = {}>", self.n, self.t)
    }
}

/// The contact table of a state: one row per frictional contact node (Γ_C without its clamped
/// nodes), in Simulation.contact_nodes order. Arrays (c contact nodes, d dimensions):
///
/// node     -- (c,) int64 mesh node;          x        -- (c, d) position;
/// normal   -- (c, d) outward normal ν;        tangents -- (c, d − 1, d) tangent basis;
/// w_tau    -- (c, d − 1) slip relative to the foundation, w_τ − v_F,τ, in the node's tangent
///             coordinates (the tangential velocity where the foundation is at rest);
/// xi       -- (c, d − 1) friction stress ξ, likewise;
/// bound    -- (c,) friction bound μ(|w_τ|) S; slip -- (c,) bool, |w_τ| > slip tolerance;
/// theta    -- (c,) temperature; slip_distance -- (c,) where a law weakens with it, else None;
/// pressure -- (c,) contact pressure p where a law scales with it (Coulomb), else None.
///
/// table() is the table of the command line's contact_NNNN.csv (columns: Contact.columns).
#[pyclass(name = "Contact", module = "thermocontact", frozen)]
pub struct PyContact {
    #[pyo3(get)]
    node: Py<PyArray1<i64>>,
    #[pyo3(get)]
    x: Py<PyArray2<f64>>,
    #[pyo3(get)]
    normal: Py<PyArray2<f64>>,
    #[pyo3(get)]
    tangents: Py<PyAny>,
    #[pyo3(get)]
    w_tau: Py<PyArray2<f64>>,
    #[pyo3(get)]
    xi: Py<PyArray2<f64>>,
    #[pyo3(get)]
    bound: Py<PyArray1<f64>>,
    #[pyo3(get)]
    slip: Py<PyArray1<bool>>,
    #[pyo3(get)]
    theta: Py<PyArray1<f64>>,
    /// s, the slip distance so far, where a friction law weakens with it (`None` otherwise).
    #[pyo3(get)]
    slip_distance: Option<Py<PyArray1<f64>>>,
    /// p, the contact pressure, where a friction law scales with it (`None` otherwise).
    #[pyo3(get)]
    pressure: Option<Py<PyArray1<f64>>>,
    dim: usize,
    rows: Vec<ContactRow>,
}

impl PyContact {
    fn new(py: Python<'_>, dim: usize, rows: Vec<ContactRow>) -> Self {
        let c = rows.len();
        let t = dim - 1;
        let column = |f: &dyn Fn(&ContactRow) -> f64| PyArray1::from_vec(py, rows.iter().map(f).collect()).unbind();
        let vectors = |f: &dyn Fn(&ContactRow) -> Vec<f64>, width: usize| {
            matrix(py, rows.iter().flat_map(f).collect(), width).unbind()
        };
        let tangents: Vec<f64> = rows
            .iter()
            .flat_map(|r| r.tangents.iter().flat_map(|v| v[..dim].to_vec()).collect::<Vec<_>>())
            .collect();
        let tangents = Array3::from_shape_vec((c, t, dim), tangents).expect("d − 1 tangents of d components");
        PyContact {
            node: PyArray1::from_vec(py, rows.iter().map(|r| r.node as i64).collect()).unbind(),
            x: vectors(&|r| r.x[..dim].to_vec(), dim),
            normal: vectors(&|r| r.normal[..dim].to_vec(), dim),
            tangents: PyArray::from_owned_array(py, tangents).into_any().unbind(),
            w_tau: vectors(&|r| r.w_tau.clone(), t),
            xi: vectors(&|r| r.xi.clone(), t),
            bound: column(&|r| r.bound),
            slip: PyArray1::from_vec(py, rows.iter().map(|r| r.slip).collect()).unbind(),
            theta: column(&|r| r.theta),
            slip_distance: (rows.first().is_some_and(|r| r.slip_distance.is_some()))
                .then(|| column(&|r| r.slip_distance.unwrap_or(0.0))),
            pressure: (rows.first().is_some_and(|r| r.pressure.is_some()))
                .then(|| column(&|r| r.pressure.unwrap_or(0.0))),
            dim,
            rows,
        }
    }
}

impl PyContact {
    /// Whether the rows carry the slip distance (a law weakens with it).
    fn with_slip_distance(&self) -> bool {
        self.rows.first().is_some_and(|r| r.slip_distance.is_some())
    }

    /// The columns of table(), as in the contact CSV files.
    fn header(&self) -> Vec<&'static str> {
        let pressure = self.rows.first().is_some_and(|r| r.pressure.is_some());
        contact_csv_header(self.dim, self.with_slip_distance(), pressure)
    }
}

#[pymethods]
impl PyContact {
    /// Number of slipping nodes.
    #[getter]
    fn slip_count(&self) -> usize {
        self.rows.iter().filter(|r| r.slip).count()
    }

    /// Column names of table(), as in the contact CSV files.
    #[getter]
    fn columns(&self) -> Vec<&'static str> {
        self.header()
    }

    /// The table of the command line's contact_NNNN.csv: (c, len(columns)) float64, slip as
    /// 1.0 / 0.0.
    fn table<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let rows = contact_csv_rows(self.dim, &self.rows);
        matrix(py, rows.concat(), self.header().len())
    }

    fn __len__(&self) -> usize {
        self.rows.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<thermocontact.Contact {} nodes: {} slip, {} stick>",
            self.rows.len(),
            self.slip_count(),
            self.rows.len() - self.slip_count()
        )
    }
}

/// The energies of each step as a dict of float64 arrays over n = 1 … N: "t", and every figure
/// of the core's StepEnergy (docs/energy.md) for the step alone (levels at t_n, the step's
/// changes, flows and residuals; the cumulative sums are np.cumsum of them, as steps.csv has).
fn energy_table<'py>(py: Python<'py>, energies: &[(f64, StepEnergy)]) -> PyResult<Bound<'py, PyDict>> {
    let table = PyDict::new(py);
    table.set_item("t", PyArray1::from_vec(py, energies.iter().map(|(t, _)| *t).collect()))?;
    let rows: Vec<serde_json::Map<String, serde_json::Value>> = (energies.iter())
        .map(|(_, e)| match serde_json::to_value(e).expect("energies serialize") {
            serde_json::Value::Object(map) => map,
            _ => unreachable!("a struct serializes to an object"),
        })
        .collect();
    let names: Vec<String> = serde_json::to_value(StepEnergy::default())
        .ok()
        .and_then(|v| v.as_object().map(|m| m.keys().cloned().collect()))
        .unwrap_or_default();
    for name in names {
        let column: Vec<f64> = rows.iter().map(|row| row[&name].as_f64().unwrap_or(f64::NAN)).collect();
        table.set_item(name, PyArray1::from_vec(py, column))?;
    }
    Ok(table)
}

/// What run() returns: the states at the output times, the state at T, the summary and the
/// energies of every step.
#[pyclass(name = "RunResult", module = "thermocontact", frozen)]
pub struct PyRunResult {
    summary: Py<PyAny>,
    outputs: Vec<Py<PyState>>,
    last: Py<PyState>,
    energy: Py<PyAny>,
}

#[pymethods]
impl PyRunResult {
    /// Everything summary.json holds, as a dict (sizes, iterations, cutbacks, timings, per
    /// output time the slip and stick counts and extrema).
    #[getter]
    fn summary(&self, py: Python<'_>) -> Py<PyAny> {
        self.summary.clone_ref(py)
    }

    /// The states at the output times (the scenario's output.times), in time order.
    #[getter]
    fn outputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, self.outputs.iter().map(|s| s.clone_ref(py)))
    }

    /// The state at T.
    #[getter]
    fn last(&self, py: Python<'_>) -> Py<PyState> {
        self.last.clone_ref(py)
    }

    /// The energies of every step n = 1 … N: a dict of float64 arrays ("t", "kinetic",
    /// "elastic", "thermal", "viscous", "numerical", "frictional", "loads", "residual",
    /// "heat_sources", …; docs/energy.md), each step's own figures. summary["energy"] has the
    /// run's totals, summary["warnings"] the warnings.
    #[getter]
    fn energy(&self, py: Python<'_>) -> Py<PyAny> {
        self.energy.clone_ref(py)
    }

    /// The output times t_n (float64 array).
    #[getter]
    fn times<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.outputs.iter().map(|s| s.get().t).collect())
    }

    /// Slipping contact nodes at each output time (int64 array).
    #[getter]
    fn slip_counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let counts = self
            .outputs
            .iter()
            .map(|s| Ok(s.get().contact(py)?.get().slip_count() as i64))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(PyArray1::from_vec(py, counts))
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let status = self.summary.bind(py).get_item("status")?;
        Ok(format!(
            "<thermocontact.RunResult {status}, {} output times, last t = {}>",
            self.outputs.len(),
            self.last.get().t
        ))
    }
}

/// What the time loop's thread hands over: a new state with its step's figures, or the error
/// that stopped the loop.
type Message = Result<(State, StepInfo), Error>;

/// How the loop's thread ended.
#[derive(Debug, Clone, Copy)]
struct Outcome {
    /// "completed", "interrupted" or "failed".
    status: &'static str,
    /// The last completed time level and its time.
    last_step: usize,
    last_time: f64,
}

/// The run step by step: an iterator of State (see Simulation.steps). Also a context manager
/// (`with sim.steps() as steps:` closes it on leaving).
#[pyclass(name = "Steps", module = "thermocontact", frozen)]
pub struct PySteps {
    // Locked only with the Python lock released (in `detach`), so that a thread waiting for a
    // step never holds the lock another thread needs to close.
    receiver: Mutex<Option<Receiver<Message>>>,
    worker: Mutex<Option<JoinHandle<Outcome>>>,
    outcome: Mutex<Option<Outcome>>,
    problem: Arc<Problem>,
    slip_tolerance: f64,
}

impl PySteps {
    fn start(problem: Arc<Problem>, params: SolverParams, slip_tolerance: f64) -> Self {
        let (sender, receiver) = sync_channel::<Message>(0);
        let shared = problem.clone();
        let worker = std::thread::spawn(move || {
            let problem = &*shared;
            let fail = |error: Error, last_step, last_time, sender: &std::sync::mpsc::SyncSender<Message>| {
                let _ = sender.send(Err(error));
                Outcome {
                    status: "failed",
                    last_step,
                    last_time,
                }
            };
            let levels = match Levels::build(problem, &params) {
                Ok(levels) => levels,
                Err(error) => return fail(error.into(), 0, 0.0, &sender),
            };
            let marched = time::march(problem, &levels, |state, info| {
                sender.send(Ok((state.clone(), *info))).map_err(|_| Error::Interrupted {
                    step: state.n,
                    time: state.t,
                    cause: Interruption::Caller,
                })
            });
            match marched {
                Ok(last) => Outcome {
                    status: "completed",
                    last_step: last.n,
                    last_time: last.t,
                },
                Err(stopped) => match stopped.error {
                    Error::Interrupted { step, time, .. } => Outcome {
                        status: "interrupted",
                        last_step: step,
                        last_time: time,
                    },
                    error => fail(error, stopped.last.n, stopped.last.t, &sender),
                },
            }
        });
        PySteps {
            receiver: Mutex::new(Some(receiver)),
            worker: Mutex::new(Some(worker)),
            outcome: Mutex::new(None),
            problem,
            slip_tolerance,
        }
    }

    /// Drops the receiver (the loop stops at its next hand-over) and waits for the thread.
    fn finish(&self) -> Result<(), String> {
        drop(self.receiver.lock().expect("not poisoned").take());
        let worker = self.worker.lock().expect("not poisoned").take();
        if let Some(worker) = worker {
            let outcome = worker.join().map_err(|panic| {
                let message = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                format!("the time loop panicked: {message}")
            })?;
            *self.outcome.lock().expect("not poisoned") = Some(outcome);
        }
        Ok(())
    }

    fn outcome(&self, py: Python<'_>) -> Option<Outcome> {
        py.detach(|| *self.outcome.lock().expect("not poisoned"))
    }
}

#[pymethods]
impl PySteps {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&self, py: Python<'_>) -> PyResult<Option<PyState>> {
        let received = py.detach(|| {
            let receiver = self.receiver.lock().expect("not poisoned");
            receiver.as_ref().map(|r| r.recv())
        });
        match received {
            Some(Ok(Ok((state, info)))) => Ok(Some(PyState::new(
                py,
                state,
                Some(info),
                self.problem.clone(),
                self.slip_tolerance,
                None,
            )?)),
            Some(Ok(Err(error))) => {
                py.detach(|| self.finish())
                    .map_err(pyo3::exceptions::PyRuntimeError::new_err)?;
                Err(errors::to_py(py, &error))
            }
            // The loop ended (the sender is gone), or the iterator was closed.
            Some(Err(_)) | None => {
                py.detach(|| self.finish())
                    .map_err(pyo3::exceptions::PyRuntimeError::new_err)?;
                Ok(None)
            }
        }
    }

    /// Stops the run (if it is still going) and waits for its thread: at most the step being
    /// computed is finished. Then status is "interrupted" (or "completed" / "failed" if it had
    /// ended already).
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        py.detach(|| self.finish())
            .map_err(pyo3::exceptions::PyRuntimeError::new_err)
    }

    fn __enter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }

    /// "running" until the loop's thread has ended and been waited for (by the end of the
    /// iteration, an error, or close()); then "completed", "interrupted" or "failed".
    #[getter]
    fn status(&self, py: Python<'_>) -> &'static str {
        self.outcome(py).map_or("running", |o| o.status)
    }

    /// The last time level the loop completed (None while running). After a break and close(),
    /// at most one step beyond the last one handed out.
    #[getter]
    fn last_step(&self, py: Python<'_>) -> Option<usize> {
        self.outcome(py).map(|o| o.last_step)
    }

    /// t of last_step (None while running).
    #[getter]
    fn last_time(&self, py: Python<'_>) -> Option<f64> {
        self.outcome(py).map(|o| o.last_time)
    }
}
