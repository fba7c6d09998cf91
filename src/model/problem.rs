//! The discrete problem: a mesh with its boundary parts, a material, the laws, the loads and the
//! time grid, made discrete — everything that stays fixed during a run.
//!
//! A [`Problem`] is built by a [`ProblemBuilder`] from typed parts; nothing here knows the
//! scenario file (the scenario layer translates TOML into these parts). A Rust user builds one
//! directly:
//!
//! ```
//! use thermocontact::contact::{LinearHeating, QuadraticExchange, VelocityWeakening};
//! use thermocontact::loads::Datum;
//! use thermocontact::material::{Isotropic, Material};
//! use thermocontact::model::{LoadTarget, ProblemBuilder, TimeGrid};
//!
//! let mesh = thermocontact::mesh::rectangle(40.0, 10.0, 16, 4);
//! let material = Material {
//!     density: 100.0,
//!     heat_capacity: 0.1,
//!     viscosity: Isotropic::viscosity(50.0, 200.0),
//!     elasticity: Isotropic::elasticity(10_000.0, 0.3),
//!     expansion: Material::expansion_from(3e-4, 10_000.0, 0.3),
//!     conductivity: 0.5,
//!     reference_temperature: 0.0,
//! };
//! let problem = ProblemBuilder::new(mesh, material, TimeGrid::new(1.0, 8))
//!     .dirichlet(&["left"])
//!     .neumann(&["top", "right"])
//!     .contact(&["bottom"])
//!     .friction(150.0, VelocityWeakening { a: 1.0, b: 0.2, alpha: 100.0 })
//!     .heat_exchange(QuadraticExchange { coefficient: 1.0, foundation_temperature: 0.0 })
//!     .frictional_heating(LinearHeating::affine(0.0, 10.0))
//!     .load(LoadTarget::Traction("top".into()), Datum::affine(vec![0.0, 0.0], vec![0.0, -800.0]))
//!     .build()
//!     .unwrap();
//! assert_eq!(problem.contact.len(), 16);
//! ```

use super::error::ModelError as Error;
use super::laws::{Friction, Heating};
use super::pressure::ContactPressure;
use super::share::ColumnShare;
use super::thermal::{self, ThermalBoundary, ThermalCondition};
use crate::contact::frames::{contact_frames, orthogonal_complement};
use crate::contact::{
    Foundation, FrictionLaw, FrictionalHeating, HeatExchange, LawPoint, LinearHeating, NormalForce, QuadraticExchange,
    Tresca,
};
use crate::fem::assembly::{self, Matrices};
use crate::fem::dofs::{NodeBasis, TemperatureSpace, VelocitySpace};
use crate::loads::{nodal_values, Datum, Load, LoadKind};
use crate::material::{CellMaterials, Material};
use crate::mesh::Mesh;

/// The time grid t_n = n k, n = 0 … N, k = T/N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeGrid {
    /// T, the final time.
    pub final_time: f64,
    /// N, the number of steps.
    pub steps: usize,
}

impl TimeGrid {
    /// N uniform steps up to T.
    pub fn new(final_time: f64, steps: usize) -> Self {
        TimeGrid { final_time, steps }
    }

    /// k = T/N.
    pub fn time_step(&self) -> f64 {
        self.final_time / self.steps as f64
    }

    /// t_n = n k.
    pub fn time(&self, n: usize) -> f64 {
        n as f64 * self.time_step()
    }
}

/// A node of Γ_C that carries friction: not clamped, and free to slide along at least one
/// tangent of its frame.
#[derive(Debug, Clone)]
pub struct ContactNode {
    /// Mesh node.
    pub node: usize,
    /// ℓ_i = ∫_ΓC φ_i, the nodal quadrature weight.
    pub weight: f64,
    /// ν_i, the unit outward normal ([`crate::contact::frames`]).
    pub normal: [f64; 3],
    /// t_{i,1} … t_{i,d−1}: the node's orthonormal tangent basis; w_τ and ξ are coordinates in it.
    pub tangents: Vec<[f64; 3]>,
    /// The velocity unknown of each tangent coordinate (d − 1 entries); `None` where the
    /// coordinate is held at zero (a corner of Γ_C or a symmetry plane through the node).
    pub tangent_dofs: Vec<Option<usize>>,
    /// Temperature unknown, `None` where θ = θ_D (a node also on the closure of Γ_N, or of a
    /// part with a temperature condition).
    pub theta_dof: Option<usize>,
}

/// The boundary parts of each role, as indices into the mesh's parts.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct BoundaryParts {
    /// Γ_D: u = 0, θ = θ_D.
    pub dirichlet: Vec<usize>,
    /// Γ_N: tractions and pressures, θ = θ_D.
    pub neumann: Vec<usize>,
    /// Γ_C: bilateral contact, friction, heat exchange.
    pub contact: Vec<usize>,
    /// Symmetry (roller) planes: w·ν = 0, no shear traction, no heat flux.
    pub symmetry: Vec<usize>,
}

/// Where a load acts.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadTarget {
    /// f₀ over Ω (d components).
    BodyForce,
    /// f₂ on a Neumann part (d global components).
    Traction(String),
    /// A normal pressure p on a Neumann part: the traction −p ν.
    Pressure(String),
    /// g over Ω (one component).
    HeatSource,
}

/// The initial data (10) as full nodal vectors: u₀ and w₀ = u₁ in E^h, θ₀ everywhere.
#[derive(Debug, Clone)]
pub struct InitialFields {
    /// u₀, d per node.
    pub displacement: Vec<f64>,
    /// u₁ (the initial velocity), d per node.
    pub velocity: Vec<f64>,
    /// θ₀, one per node.
    pub temperature: Vec<f64>,
}

/// Everything fixed during a run.
#[derive(Debug)]
pub struct Problem {
    pub mesh: Mesh,
    /// The mesh parts of each boundary role.
    pub parts: BoundaryParts,
    /// The body's material: that of every cell in no region given one
    /// ([`ProblemBuilder::region`]), of every cell when none is.
    pub material: Material,
    /// The material of each cell (one, the body's, without regions).
    pub materials: CellMaterials,
    /// The time grid.
    pub time: TimeGrid,
    /// E^h.
    pub velocity: VelocitySpace,
    /// V^h.
    pub temperature: TemperatureSpace,
    pub matrices: Matrices,
    /// Frictional contact nodes of Γ_C.
    pub contact: Vec<ContactNode>,
    /// ℓ_p on every node of Γ_C (including clamped ones), zero elsewhere.
    pub contact_weights: Vec<f64>,
    /// The friction laws, each on its contact parts.
    pub friction: Vec<Friction>,
    /// The law of each contact node: an index into `friction`.
    pub friction_of_node: Vec<usize>,
    /// The foundation's motion (`None`: at rest, the paper).
    pub foundation: Option<Foundation>,
    /// The rows of the contact pressure where a law scales with it ([`ContactPressure`]).
    pub pressure: Option<ContactPressure>,
    /// The heat exchange ∂j.
    pub exchange: Box<dyn HeatExchange>,
    /// The thermal conditions given per part ([`ThermalCondition`]), and what changes with t.
    pub thermal: ThermalBoundary,
    /// h_τ and its share.
    pub heating: Heating,
    /// Loads on the velocity equation: F(t) = Σ ∫ f·φ.
    forces: Vec<Load>,
    /// Loads on the temperature equation: ∫ g η.
    heat_sources: Vec<Load>,
    /// k_e θ_R ∫_ΓC η: the foundation's part of the heat exchange, plus the thermal conditions'
    /// boundary loads constant in t (h θ_∞ ∫η of convection, constant fluxes).
    exchange_load: Vec<f64>,
    /// θ_ref G 1 on full velocity dofs: the thermal stress C(θ − θ_ref) has a constant part
    /// −Cθ_ref, which moves to the right-hand side as a load (zero for the paper's θ_ref = 0).
    reference_load: Vec<f64>,
    /// θ_D at Dirichlet nodes at t = 0, zero elsewhere (full temperature vector); where a
    /// temperature condition depends on t, [`Problem::theta_dirichlet_at`] has its values.
    pub theta_dirichlet: Vec<f64>,
    /// u₀, u₁, θ₀.
    pub initial: InitialFields,
    /// Space–time dependent loads given as code rather than data (the verification family of
    /// [`crate::studies::verification::manufactured`]); `None` otherwise.
    pub extra_loads: Option<Box<dyn ExtraLoads>>,
    /// Wall time the builder took, in seconds (reported as the run's assembly time).
    pub build_seconds: f64,
    /// The mesh's partition over the ranks of a distributed run, once computed
    /// ([`Problem::partition`]).
    #[cfg(feature = "mpi")]
    partition: std::sync::OnceLock<crate::partition::MeshPartition>,
    /// This process's share of 𝒦_A, 𝒦_B and G (the columns its rows read, assembled only while
    /// its step matrix is summed; its products and energies over its cells) where it keeps
    /// none of them, as a rank of a distributed run does (`ProblemBuilder::on_ranks`, feature
    /// `mpi`; [`Problem::matrices`] then holds them empty); `None`: the whole matrices.
    pub columns: Option<ColumnShare>,
}

/// Loads that vary in space and time given as code, added to the data loads: a body force
/// f₀(x, t), tractions f₂(x, t) on Γ_N, a known load on Γ_C, a heat source g(x, t) and a known
/// heat flux on Γ_C. Implementors integrate them into full load vectors (velocity dofs p·d + c,
/// temperature dofs p); [`Problem::force`] and [`Problem::heat_load`] add them, so every solver
/// sees them.
pub trait ExtraLoads: Send + Sync + std::fmt::Debug {
    /// Adds ∫ f₀(t)·φ + ∫_ΓN f₂(t)·φ + ∫_ΓC f_C(t)·φ to a full velocity load vector.
    fn add_force(&self, problem: &Problem, t: f64, force: &mut [f64]);
    /// Adds ∫ g(t) η + ∫_ΓC g_C(t) η to a full temperature load vector.
    fn add_heat(&self, problem: &Problem, t: f64, heat: &mut [f64]);
}

/// Builds a [`Problem`] from typed parts. Boundary parts are named as in the mesh; defaults: no
/// parts in any role, θ_D = 0, Tresca friction with bound 0, no heat exchange, no frictional
/// heating (share 1), no loads, zero initial data.
pub struct ProblemBuilder {
    mesh: Mesh,
    material: Material,
    /// (cell region, its material), in the order given.
    regions: Vec<(String, Material)>,
    time: TimeGrid,
    dirichlet: Vec<String>,
    neumann: Vec<String>,
    contact: Vec<String>,
    symmetry: Vec<String>,
    boundary_temperature: f64,
    /// Thermal conditions per part (part, condition, label), in the order given.
    thermal: Vec<(String, ThermalCondition, String)>,
    /// (part name or `None` for all, scale, law, what scales the law).
    friction: Vec<GivenFriction>,
    foundation: Option<Foundation>,
    exchange: Box<dyn HeatExchange>,
    heating: Box<dyn FrictionalHeating>,
    heat_share: f64,
    friction_power: bool,
    loads: Vec<(LoadTarget, Datum, String)>,
    initial: [(Datum, &'static str); 3],
    /// Nodal initial fields that replace the three data above (a checkpoint of another run).
    initial_fields: Option<(InitialFields, &'static str)>,
    extra_loads: Option<Box<dyn ExtraLoads>>,
    /// Whose share of the matrices to assemble ([`ProblemBuilder::owned_nodes`],
    /// [`ProblemBuilder::on_ranks`]); `None`: the whole.
    share: Option<ShareOf>,
    /// The layers of nodes around Γ_C whose rows a share assembles too
    /// ([`ProblemBuilder::contact_layers`]).
    contact_layers: usize,
}

/// The process a [`ProblemBuilder`] assembles a share of the matrices for.
enum ShareOf {
    /// The nodes given, the energies' parts not summed (tests).
    Nodes(Vec<bool>),
    /// This rank of a distributed run: its nodes those the run's partition gives it.
    #[cfg(feature = "mpi")]
    Rank(crate::la::mpi::Communicator),
}

/// A friction law as given to the builder: (part name or `None` for all, scale, law, what
/// scales the law).
type GivenFriction = (Option<String>, Datum, Box<dyn FrictionLaw>, NormalForce);

/// Names of the initial data, in the order of [`ProblemBuilder`]'s `initial` slots.
const INITIAL_NAMES: [&str; 3] = [
    "initial displacement u₀",
    "initial velocity u₁",
    "initial temperature θ₀",
];

impl ProblemBuilder {
    /// A problem on `mesh` with `material` over the time grid `time`.
    pub fn new(mesh: Mesh, material: Material, time: TimeGrid) -> Self {
        let d = mesh.dim;
        ProblemBuilder {
            mesh,
            material,
            regions: Vec::new(),
            time,
            dirichlet: Vec::new(),
            neumann: Vec::new(),
            contact: Vec::new(),
            symmetry: Vec::new(),
            boundary_temperature: 0.0,
            thermal: Vec::new(),
            friction: Vec::new(),
            foundation: None,
            exchange: Box::new(QuadraticExchange {
                coefficient: 0.0,
                foundation_temperature: 0.0,
            }),
            heating: Box::new(LinearHeating::affine(0.0, 0.0)),
            heat_share: 1.0,
            friction_power: false,
            loads: Vec::new(),
            initial: [
                (Datum::Constant(vec![0.0; d]), INITIAL_NAMES[0]),
                (Datum::Constant(vec![0.0; d]), INITIAL_NAMES[1]),
                (Datum::Constant(vec![0.0]), INITIAL_NAMES[2]),
            ],
            initial_fields: None,
            extra_loads: None,
            share: None,
            contact_layers: 0,
        }
    }

    /// This rank's share of the matrices in a distributed run over `comm` (more than one rank):
    /// the mesh is partitioned at the start of [`ProblemBuilder::build`] (collective; the
    /// partition kept as [`Problem::partition`]'s), and 𝒦_A, 𝒦_B and G are not kept: their
    /// columns the rank's rows read are assembled while its step matrix is summed, its
    /// products and energies are sums over its cells ([`ColumnShare`]); the energies' parts are
    /// summed over the ranks. One rank: the whole problem.
    #[cfg(feature = "mpi")]
    pub fn on_ranks(mut self, comm: crate::la::mpi::Communicator) -> Self {
        self.share = (comm.size() > 1).then_some(ShareOf::Rank(comm));
        self
    }

    /// A share of the matrices (`ProblemBuilder::on_ranks`) that also reads the rows of the
    /// nodes within `layers` hops of Γ_C: what the predicted bounds' sweeps through the body
    /// condense (`solver.condensed_layers`, the same number; `KrylovParams::condensed_layers`).
    /// No effect on the whole problem.
    pub fn contact_layers(mut self, layers: usize) -> Self {
        self.contact_layers = layers;
        self
    }

    /// The share of the matrices of a process owning the nodes `owned` ([`ColumnShare`]),
    /// its energies its own part alone: what a rank holds, without ranks (for tests of the
    /// share against the whole problem).
    pub fn owned_nodes(mut self, owned: Vec<bool>) -> Self {
        self.share = Some(ShareOf::Nodes(owned));
        self
    }

    /// The cells of the mesh's cell region `name` (a Gmsh physical group of dimension d) take
    /// `material`; cells in no region given a material keep the builder's. A region given again
    /// takes the later material. A region the mesh lacks, or a cell in two regions given
    /// materials, is an error of [`ProblemBuilder::build`].
    pub fn region(mut self, name: &str, material: Material) -> Self {
        self.regions.retain(|(given, _)| given != name);
        self.regions.push((name.to_string(), material));
        self
    }

    /// Γ_D: the clamped parts (may be empty: in dynamics the mass term keeps the step matrix
    /// definite, so a body held by friction alone is well posed).
    pub fn dirichlet(mut self, parts: &[&str]) -> Self {
        self.dirichlet = strings(parts);
        self
    }

    /// Γ_N: the loaded parts (θ = θ_D there too, eq. (6)).
    pub fn neumann(mut self, parts: &[&str]) -> Self {
        self.neumann = strings(parts);
        self
    }

    /// Γ_C: the contact parts, flat or curved; normals come from the mesh.
    pub fn contact(mut self, parts: &[&str]) -> Self {
        self.contact = strings(parts);
        self
    }

    /// Symmetry (roller) planes: flat parts with w·ν = 0.
    pub fn symmetry(mut self, parts: &[&str]) -> Self {
        self.symmetry = strings(parts);
        self
    }

    /// θ_D on Γ_D ∪ Γ_N (on the parts given no [`ProblemBuilder::thermal`] condition).
    pub fn boundary_temperature(mut self, theta: f64) -> Self {
        self.boundary_temperature = theta;
        self
    }

    /// The thermal condition of the boundary part `part`, replacing the paper's rule there
    /// (θ = θ_D on Γ_D ∪ Γ_N, insulated elsewhere; see [`ThermalCondition`] and the module
    /// [`super::thermal`] for the rules at corners). A contact part, or a part given twice, is
    /// an error at [`ProblemBuilder::build`].
    ///
    /// ```
    /// use thermocontact::material::{Isotropic, Material};
    /// use thermocontact::model::{ProblemBuilder, ThermalCondition, TimeGrid};
    ///
    /// let mesh = thermocontact::mesh::rectangle(1.0, 0.2, 8, 2);
    /// let material = Material {
    ///     density: 1.0,
    ///     heat_capacity: 1.0,
    ///     viscosity: Isotropic::viscosity(1.0, 1.0),
    ///     elasticity: Isotropic::elasticity(100.0, 0.3),
    ///     expansion: 0.0,
    ///     conductivity: 2.0,
    ///     reference_temperature: 0.0,
    /// };
    /// let problem = ProblemBuilder::new(mesh, material, TimeGrid::new(1.0, 1))
    ///     .dirichlet(&["left"])
    ///     .neumann(&["top"])
    ///     .contact(&["bottom"])
    ///     .thermal("top", ThermalCondition::Insulated)
    ///     .thermal("right", ThermalCondition::Convection { coefficient: 25.0, ambient: 20.0 })
    ///     .build()
    ///     .unwrap();
    /// // θ = θ_D on the left only: the top's nodes, off its corner with the left, are unknowns.
    /// assert_eq!(problem.temperature.free.iter().filter(|f| f.is_none()).count(), 3);
    /// ```
    pub fn thermal(self, part: &str, condition: ThermalCondition) -> Self {
        let label = format!("the {} on `{part}`", condition.name());
        self.labelled_thermal(part, condition, label)
    }

    /// [`ProblemBuilder::thermal`], its datum named `label` in errors (the scenario passes its
    /// key).
    pub fn labelled_thermal(mut self, part: &str, condition: ThermalCondition, label: String) -> Self {
        self.thermal.push((part.to_string(), condition, label));
        self
    }

    /// The friction law on every contact part not given its own ([`ProblemBuilder::friction_on`]):
    /// the bound S(x, t) μ(r), the scale S a datum (a number, affine in t, an expression).
    pub fn friction(mut self, scale: impl Into<Datum>, law: impl FrictionLaw + 'static) -> Self {
        self.friction.retain(|(part, ..)| part.is_some());
        self.friction
            .push((None, scale.into(), Box::new(law), NormalForce::Prescribed));
        self
    }

    /// [`ProblemBuilder::friction`] (`part` `None`) or [`ProblemBuilder::friction_on`], the law
    /// boxed.
    pub fn friction_boxed(mut self, part: Option<&str>, scale: Datum, law: Box<dyn FrictionLaw>) -> Self {
        if part.is_none() {
            self.friction.retain(|(part, ..)| part.is_some());
        }
        self.friction
            .push((part.map(String::from), scale, law, NormalForce::Prescribed));
        self
    }

    /// Coulomb friction on the contact part `part` (`None`: every part not given its own): the
    /// bound μ(r) p_i with p_i the contact pressure at node i, from the reaction of the
    /// bilateral constraint ([`NormalForce::Reaction`], [`ContactPressure`]); `law` gives μ
    /// (e.g. [`crate::contact::Coulomb`] for a constant coefficient).
    pub fn friction_from_pressure(mut self, part: Option<&str>, law: Box<dyn FrictionLaw>) -> Self {
        if part.is_none() {
            self.friction.retain(|(part, ..)| part.is_some());
        }
        self.friction
            .push((part.map(String::from), Datum::scalar(1.0), law, NormalForce::Reaction));
        self
    }

    /// The foundation's motion (default: at rest, the paper): friction and frictional heating
    /// act on the slip relative to it ([`crate::contact::foundation`]).
    pub fn foundation(mut self, foundation: Foundation) -> Self {
        self.foundation = Some(foundation);
        self
    }

    /// [`ProblemBuilder::heat_exchange`], the law boxed.
    pub fn heat_exchange_boxed(mut self, law: Box<dyn HeatExchange>) -> Self {
        self.exchange = law;
        self
    }

    /// [`ProblemBuilder::frictional_heating`], the law boxed.
    pub fn frictional_heating_boxed(mut self, law: Box<dyn FrictionalHeating>) -> Self {
        self.heating = law;
        self
    }

    /// The friction law on the contact part `part` (a node shared by two parts takes the law
    /// given first).
    pub fn friction_on(mut self, part: &str, scale: impl Into<Datum>, law: impl FrictionLaw + 'static) -> Self {
        self.friction.push((
            Some(part.to_string()),
            scale.into(),
            Box::new(law),
            NormalForce::Prescribed,
        ));
        self
    }

    /// The heat exchange with the foundation on Γ_C (linear: [`QuadraticExchange`]; or a table
    /// or expression of θ, possibly nonmonotone).
    pub fn heat_exchange(mut self, law: impl HeatExchange + 'static) -> Self {
        self.exchange = Box::new(law);
        self
    }

    /// The fraction of the frictional power that enters the body (default 1, as in the paper).
    pub fn heat_share(mut self, share: f64) -> Self {
        self.heat_share = share;
        self
    }

    /// The frictional heating as the friction's dissipated power, h_τ(r) = b_i(r) r at each
    /// contact node (times the share): the heat a brake makes ([`Heating::friction_power`]).
    pub fn frictional_heating_from_friction(mut self) -> Self {
        self.friction_power = true;
        self
    }

    /// The frictional heating h_τ on Γ_C.
    pub fn frictional_heating(mut self, law: impl FrictionalHeating + 'static) -> Self {
        self.heating = Box::new(law);
        self
    }

    /// Adds a load; its label names it in errors (defaults to the target).
    pub fn load(self, target: LoadTarget, datum: Datum) -> Self {
        let label = format!("{target:?}");
        self.labelled_load(target, datum, label)
    }

    /// Adds a load named `label` in errors (the scenario passes its key).
    pub fn labelled_load(mut self, target: LoadTarget, datum: Datum, label: String) -> Self {
        self.loads.push((target, datum, label));
        self
    }

    /// u₀ (d components), named `label` in errors.
    pub fn initial_displacement(mut self, datum: Datum, label: &'static str) -> Self {
        self.initial[0] = (datum, label);
        self
    }

    /// u₁ (d components), named `label` in errors.
    pub fn initial_velocity(mut self, datum: Datum, label: &'static str) -> Self {
        self.initial[1] = (datum, label);
        self
    }

    /// θ₀ (one component), named `label` in errors.
    /// u₀, u₁ and θ₀ as nodal values (d, d and 1 per node; e.g. the state of another run),
    /// replacing the three initial data; `label` names them in errors.
    pub fn initial_fields(mut self, fields: InitialFields, label: &'static str) -> Self {
        self.initial_fields = Some((fields, label));
        self
    }

    pub fn initial_temperature(mut self, datum: Datum, label: &'static str) -> Self {
        self.initial[2] = (datum, label);
        self
    }

    /// Loads given as code (see [`ExtraLoads`]).
    pub fn extra_loads(mut self, loads: Box<dyn ExtraLoads>) -> Self {
        self.extra_loads = Some(loads);
        self
    }

    /// Makes the problem discrete: spaces, matrices, contact frames, loads, initial fields.
    pub fn build(self) -> Result<Problem, Error> {
        let clock = std::time::Instant::now();
        let mesh = self.mesh;
        let d = mesh.dim;
        let find = |role: &'static str, names: &[String]| -> Result<Vec<usize>, Error> {
            names.iter().map(|name| part_of(&mesh, role, name)).collect()
        };
        let parts = BoundaryParts {
            dirichlet: find("dirichlet", &self.dirichlet)?,
            neumann: find("neumann", &self.neumann)?,
            contact: find("contact", &self.contact)?,
            symmetry: find("symmetry", &self.symmetry)?,
        };
        no_shared_facets(&mesh, &parts)?;
        // A contact or symmetry part carries conditions on its facets: one without any (an
        // empty physical group) would silently impose nothing.
        for (role, list) in [("contact", &parts.contact), ("symmetry", &parts.symmetry)] {
            if let Some(&p) = list.iter().find(|&&p| mesh.facets_of(&[p]).next().is_none()) {
                return Err(Error::EmptyPart {
                    role,
                    part: mesh.part_names[p].clone(),
                });
            }
        }
        let material = self.material;
        let materials = cell_materials(&mesh, material, &self.regions)?;

        // Constraints per node; Dirichlet wins at corners.
        let clamped = mesh.nodes_on(&parts.dirichlet);
        let planes = symmetry_planes(&mesh, &parts.symmetry)?;
        let frames = contact_frames(
            d,
            mesh.n_nodes(),
            mesh.facets_of(&parts.contact)
                .map(|f| (mesh.facet(f).to_vec(), mesh.facet_area_vector(f))),
            &planes,
        );
        let mut bases: Vec<NodeBasis> = (0..mesh.n_nodes())
            .map(|p| match (clamped[p], planes[p].is_empty()) {
                (true, _) => NodeBasis::Held,
                (false, true) => NodeBasis::Cartesian,
                (false, false) => NodeBasis::Along(orthogonal_complement(d, &planes[p])),
            })
            .collect();
        for (p, frame) in &frames {
            if !clamped[*p] {
                bases[*p] = NodeBasis::Along(frame.tangents[..frame.n_free].to_vec());
            }
        }
        let velocity = VelocitySpace::new(d, &bases);
        let thermal = thermal::resolve(&mesh, &parts, self.thermal, self.boundary_temperature)?;
        let temperature = TemperatureSpace::new(&thermal.fixed);

        let (k_e, theta_r) = self.exchange.robin().unwrap_or((0.0, 0.0));
        #[cfg(feature = "mpi")]
        let partition = std::sync::OnceLock::new();
        // A share's rows beside its own: Γ_C's and the layers around them it is asked for.
        let share_rows = || super::nodes_within(&mesh, mesh.nodes_on(&parts.contact), self.contact_layers);
        let columns = match self.share {
            None => None,
            Some(ShareOf::Nodes(owned)) => {
                if owned.len() != mesh.n_nodes() {
                    return Err(Error::OwnedNodes {
                        found: owned.len(),
                        nodes: mesh.n_nodes(),
                    });
                }
                Some(ColumnShare::new(&mesh, owned, &share_rows()))
            }
            #[cfg(feature = "mpi")]
            Some(ShareOf::Rank(comm)) => {
                let split = crate::partition::MeshPartition::on_root(&comm, &mesh).map_err(|e| Error::Ranks {
                    operation: "the partition of the mesh",
                    detail: e.to_string(),
                })?;
                let owned = split.node_owner.iter().map(|&r| r == comm.rank()).collect();
                let share = ColumnShare::new(&mesh, owned, &share_rows());
                let _ = partition.set(split);
                Some(share.over_ranks(comm))
            }
        };
        // A share keeps none of 𝒦_A, 𝒦_B and G ([`ColumnShare`]): of them the build assembles only
        // the columns the contact pressure's rows read (Γ_C's nodes and their neighbours), where
        // a law scales with the pressure.
        let with_pressure = self.friction.iter().any(|f| f.3 == NormalForce::Reaction);
        let pressure_columns = columns.as_ref().map(|_| {
            let rows = if with_pressure {
                mesh.nodes_on(&parts.contact)
            } else {
                vec![false; mesh.n_nodes()]
            };
            super::share::columns_read_by(&mesh, &rows)
        });
        let mut matrices =
            assembly::assemble_columns(&mesh, &materials, (&parts.contact, k_e), pressure_columns.as_deref());
        thermal.boundary.add_convection(&mesh, &mut matrices.conduction);
        let contact_weights = assembly::boundary_weights(&mesh, &parts.contact);
        let contact: Vec<ContactNode> = frames
            .into_iter()
            .filter(|(p, frame)| !clamped[*p] && frame.n_free > 0)
            .map(|(p, frame)| ContactNode {
                node: p,
                weight: contact_weights[p],
                normal: frame.normal,
                tangent_dofs: (0..d - 1)
                    .map(|k| (k < frame.n_free).then(|| velocity.unknown(p, k)))
                    .collect(),
                tangents: frame.tangents,
                theta_dof: temperature.free[p],
            })
            .collect();

        let (friction, friction_of_node) = friction_of_nodes(&mesh, &parts, self.friction, &contact)?;
        if let Some(foundation) = &self.foundation {
            let found = foundation.datum().n_components();
            if found != foundation.components(d) {
                return Err(Error::FoundationComponents {
                    found,
                    expected: foundation.components(d),
                });
            }
        }
        let pressure = (friction.iter().any(|f| f.normal == NormalForce::Reaction))
            .then(|| ContactPressure::new(&mesh, &matrices, &contact));

        let mut forces = Vec::new();
        let mut heat_sources = Vec::new();
        for (target, datum, label) in self.loads {
            let (kind, list) = match &target {
                LoadTarget::BodyForce => (LoadKind::BodyForce, &mut forces),
                LoadTarget::Traction(name) => (
                    LoadKind::Traction {
                        parts: vec![load_part(&mesh, &parts, &label, name)?],
                    },
                    &mut forces,
                ),
                LoadTarget::Pressure(name) => (
                    LoadKind::Pressure {
                        parts: vec![load_part(&mesh, &parts, &label, name)?],
                    },
                    &mut forces,
                ),
                LoadTarget::HeatSource => (LoadKind::HeatSource, &mut heat_sources),
            };
            list.push(Load::new(&mesh, kind, datum, label)?);
        }
        let mut exchange_load: Vec<f64> = contact_weights.iter().map(|w| k_e * theta_r * w).collect();
        if let Some(boundary_load) = &thermal.constant_load {
            exchange_load.iter_mut().zip(boundary_load).for_each(|(e, b)| *e += b);
        }
        let reference_load = match materials.uniform_material().filter(|_| columns.is_none()) {
            // One material: G carries its c, and θ_ref G 1 is one product (the bits of before).
            Some(uniform) => {
                let mut load = vec![0.0; mesh.n_nodes() * d];
                let theta_ref = uniform.reference_temperature;
                if theta_ref != 0.0 {
                    matrices
                        .coupling
                        .mul_add(theta_ref, &vec![1.0; mesh.n_nodes()], &mut load);
                }
                load
            }
            None => assembly::reference_load(&mesh, &materials),
        };
        if columns.is_some() {
            // A share keeps none of 𝒦_A, 𝒦_B and G past the pressure's rows: its step matrices
            // assemble the columns they read for the while (`step_matrix`), its right-hand sides
            // and energies are summed over its cells ([`ColumnShare`]).
            for m in [
                &mut matrices.viscosity,
                &mut matrices.elasticity,
                &mut matrices.coupling,
            ] {
                *m = crate::la::CscMatrix::empty(m.n_rows, m.n_cols);
            }
        }

        let initial = match self.initial_fields {
            None => {
                let [(u0, u0_label), (u1, u1_label), (theta0, theta0_label)] = self.initial;
                InitialFields {
                    displacement: admissible(&mesh, &velocity, nodal_values(&mesh, &u0, 0.0, u0_label)?, u0_label)?,
                    velocity: admissible(&mesh, &velocity, nodal_values(&mesh, &u1, 0.0, u1_label)?, u1_label)?,
                    temperature: nodal_values(&mesh, &theta0, 0.0, theta0_label)?,
                }
            }
            Some((fields, label)) => {
                let n = mesh.n_nodes();
                let sizes = [
                    fields.displacement.len(),
                    fields.velocity.len(),
                    fields.temperature.len(),
                ];
                if sizes != [n * d, n * d, n] {
                    return Err(Error::InitialFieldSizes {
                        label: label.to_string(),
                        found: sizes.to_vec(),
                        expected: vec![n * d, n * d, n],
                    });
                }
                InitialFields {
                    displacement: admissible(&mesh, &velocity, fields.displacement, label)?,
                    velocity: admissible(&mesh, &velocity, fields.velocity, label)?,
                    temperature: fields.temperature,
                }
            }
        };

        Ok(Problem {
            mesh,
            parts,
            material,
            materials,
            time: self.time,
            velocity,
            temperature,
            matrices,
            contact,
            contact_weights,
            friction,
            friction_of_node,
            foundation: self.foundation,
            pressure,
            exchange: self.exchange,
            thermal: thermal.boundary,
            heating: Heating {
                law: self.heating,
                share: self.heat_share,
                friction_power: self.friction_power,
            },
            forces,
            heat_sources,
            exchange_load,
            reference_load,
            theta_dirichlet: thermal.values,
            initial,
            extra_loads: self.extra_loads,
            build_seconds: clock.elapsed().as_secs_f64(),
            #[cfg(feature = "mpi")]
            partition,
            columns,
        })
    }
}

impl Problem {
    /// The mesh's partition over the ranks of `comm` ([`MeshPartition::on_root`]: PT-Scotch on
    /// rank 0, broadcast), computed on the first call and kept: the solver's layout of the
    /// unknowns ([`crate::step`]'s distributed Krylov solves, at each step size) and the
    /// frames' pieces (`driver`) share one partition, computed once per run. The first call is
    /// collective: every rank makes it at the same point. (PT-Scotch's split differs from call
    /// to call, and costs 4.4 s at 10⁶ unknowns: docs/distributed.md.)
    ///
    /// [`MeshPartition::on_root`]: crate::partition::MeshPartition::on_root
    #[cfg(feature = "mpi")]
    pub fn partition(
        &self,
        comm: &crate::la::mpi::Communicator,
    ) -> Result<&crate::partition::MeshPartition, crate::la::LaError> {
        if let Some(partition) = self.partition.get() {
            assert_eq!(partition.n_parts, comm.size(), "a partition into one part per rank");
            return Ok(partition);
        }
        let partition = crate::partition::MeshPartition::on_root(comm, &self.mesh)?;
        Ok(self.partition.get_or_init(|| partition))
    }

    /// Space dimension d.
    pub fn dim(&self) -> usize {
        self.mesh.dim
    }

    /// Time step k.
    pub fn time_step(&self) -> f64 {
        self.time.time_step()
    }

    /// Number of velocity unknowns.
    pub fn n_w(&self) -> usize {
        self.velocity.n_free
    }

    /// Number of unknowns of the coupled step system (velocity then temperature).
    pub fn n_unknowns(&self) -> usize {
        self.velocity.n_free + self.temperature.n_free
    }

    /// F(t): ⟨f(t), φ⟩ = ∫ f₀ · φ + ∫_ΓN f₂ · φ on full velocity dofs.
    pub fn force(&self, t: f64) -> Result<Vec<f64>, Error> {
        let mut force = self.reference_load.clone();
        for load in &self.forces {
            load.add_to(&self.mesh, t, &mut force)?;
        }
        if let Some(extra) = &self.extra_loads {
            extra.add_force(self, t, &mut force);
        }
        Ok(force)
    }

    /// ∫ g(t) η + k_e θ_R ∫_ΓC η + the thermal conditions' boundary loads (∫ q(t) η of a flux,
    /// h θ_∞ ∫ η of convection) on full temperature dofs; for a nonlinear heat exchange,
    /// −ℓ_p ∂j(θ_p) at the nodes of Γ_C evaluated at the temperatures `exchange_at` instead
    /// (nodal quadrature, the friction's).
    pub fn heat_load(&self, t: f64, exchange_at: &[f64]) -> Result<Vec<f64>, Error> {
        let mut heat = self.exchange_heat(t, exchange_at);
        self.add_heat_sources(t, &mut heat)?;
        Ok(heat)
    }

    /// The heat exchange's part of [`Problem::heat_load`]: k_e θ_R ∫_ΓC η for an affine
    /// exchange (its −k_e θ part is in 𝒦_θ), −ℓ_p ∂j(θ_p) at the nodes of Γ_C at the
    /// temperatures `exchange_at` for a nonlinear one.
    pub fn exchange_heat(&self, t: f64, exchange_at: &[f64]) -> Vec<f64> {
        let mut heat = self.exchange_load.clone();
        if self.exchange.robin().is_none() {
            for (p, &weight) in self.contact_weights.iter().enumerate() {
                if weight > 0.0 {
                    let at = LawPoint {
                        x: self.mesh.coords[p],
                        t,
                        slip_distance: 0.0,
                    };
                    heat[p] -= weight * self.exchange.flux(&at, exchange_at[p]);
                }
            }
        }
        heat
    }

    /// Adds the heat sources' part of [`Problem::heat_load`], ∫ g(t) η and the extra heat
    /// loads, to a full temperature vector.
    pub fn add_heat_sources(&self, t: f64, heat: &mut [f64]) -> Result<(), Error> {
        for load in &self.heat_sources {
            load.add_to(&self.mesh, t, heat)?;
        }
        self.thermal.add_loads(&self.mesh, t, heat)?;
        if let Some(extra) = &self.extra_loads {
            extra.add_heat(self, t, heat);
        }
        Ok(())
    }

    /// θ_D(x_p, t) at the Dirichlet nodes, zero elsewhere: [`Problem::theta_dirichlet`]
    /// itself (borrowed) unless a temperature condition depends on t.
    pub fn theta_dirichlet_at(&self, t: f64) -> Result<std::borrow::Cow<'_, [f64]>, Error> {
        if !self.thermal.has_moving_temperature() {
            return Ok(std::borrow::Cow::Borrowed(&self.theta_dirichlet));
        }
        let mut values = self.theta_dirichlet.clone();
        self.thermal.update_temperatures(&self.mesh, t, &mut values)?;
        Ok(std::borrow::Cow::Owned(values))
    }

    /// The friction bound b(r) at the point x and time t of the law for every part (the first
    /// law given where each part has its own), slip distance 0: for uniform laws, what the
    /// studies and figures scale by (the paper's μ(0)S = 150).
    pub fn friction_bound(&self, x: [f64; 3], t: f64, r: f64) -> f64 {
        let friction = self
            .friction
            .iter()
            .find(|f| f.parts.is_empty())
            .unwrap_or(&self.friction[0]);
        let mut scale = [0.0];
        friction.scale.eval(x, t, &mut scale);
        let at = LawPoint {
            x,
            t,
            slip_distance: 0.0,
        };
        friction.law.bound(scale[0], &at, r)
    }

    /// Whether a friction law weakens with the slip distance (then the outputs carry it).
    pub fn uses_slip_distance(&self) -> bool {
        self.friction.iter().any(|f| f.law.uses_slip_distance())
    }

    /// |Γ_C| by the nodal weights.
    pub fn contact_measure(&self) -> f64 {
        self.contact_weights.iter().sum()
    }

    /// The names of the mesh parts of a role, e.g. `problem.part_names(&problem.parts.neumann)`.
    pub fn part_names(&self, parts: &[usize]) -> Vec<&str> {
        parts.iter().map(|&p| self.mesh.part_names[p].as_str()).collect()
    }
}

/// The friction laws with their parts, and the law of each contact node: the first law listed
/// whose parts hold the node, else the law for all parts. A contact part no law covers is an
/// error (a problem without any friction law gets Tresca with bound 0: frictionless).
fn friction_of_nodes(
    mesh: &Mesh,
    parts: &BoundaryParts,
    given: Vec<GivenFriction>,
    contact: &[ContactNode],
) -> Result<(Vec<Friction>, Vec<usize>), Error> {
    let mut laws = Vec::new();
    let mut catch_all = None;
    for (part, scale, law, normal) in given {
        if scale.n_components() != 1 {
            return Err(Error::FrictionScaleComponents {
                found: scale.n_components(),
            });
        }
        let parts_of_law = match part {
            None => {
                catch_all = Some(laws.len());
                Vec::new()
            }
            Some(name) => {
                let index = part_of(mesh, "friction", &name)?;
                if !parts.contact.contains(&index) {
                    return Err(Error::FrictionOffContact {
                        part: name,
                        contact: parts.contact.iter().map(|&p| mesh.part_names[p].clone()).collect(),
                    });
                }
                vec![index]
            }
        };
        laws.push(Friction {
            scale,
            law,
            parts: parts_of_law,
            normal,
        });
    }
    if laws.is_empty() {
        catch_all = Some(0);
        laws.push(Friction {
            scale: Datum::scalar(0.0),
            law: Box::new(Tresca),
            parts: Vec::new(),
            normal: NormalForce::Prescribed,
        });
    }
    let mut on_part: Vec<Option<usize>> = vec![None; mesh.part_names.len()];
    for (k, law) in laws.iter().enumerate() {
        for &p in &law.parts {
            on_part[p].get_or_insert(k);
        }
    }
    if catch_all.is_none() {
        if let Some(&p) = parts.contact.iter().find(|&&p| on_part[p].is_none()) {
            return Err(Error::NoFrictionLaw {
                part: mesh.part_names[p].clone(),
            });
        }
    }
    // The parts of each node, from the facets of Γ_C.
    let mut node_law: Vec<Option<usize>> = vec![None; mesh.n_nodes()];
    for f in mesh.facets_of(&parts.contact) {
        if let Some(k) = on_part[mesh.facet_parts[f]] {
            for &p in mesh.facet(f) {
                node_law[p] = Some(node_law[p].map_or(k, |j: usize| j.min(k)));
            }
        }
    }
    let of_node = contact
        .iter()
        .map(|node| node_law[node.node].or(catch_all).expect("every contact part has a law"))
        .collect();
    Ok((laws, of_node))
}

/// The material of each cell: the builder's, and each given region's on its cells. A region
/// the mesh lacks, or a cell in two of the given regions, is an error naming them.
fn cell_materials(mesh: &Mesh, base: Material, regions: &[(String, Material)]) -> Result<CellMaterials, Error> {
    if regions.is_empty() {
        return Ok(CellMaterials::uniform(base));
    }
    if regions.len() >= usize::from(u16::MAX) {
        return Err(Error::TooManyRegions { count: regions.len() });
    }
    let mut of_cell = vec![0u16; mesh.n_cells()];
    let mut materials = vec![base];
    for (name, material) in regions {
        let index = mesh.region_index(name).ok_or_else(|| Error::UnknownRegion {
            name: name.clone(),
            known: mesh.region_names(),
        })?;
        let k = materials.len() as u16;
        for &e in &mesh.regions[index].cells {
            let slot = &mut of_cell[e as usize];
            if *slot != 0 {
                let cell = e as usize;
                let vertices = mesh.cell_coords(cell);
                let n = vertices.len() as f64;
                return Err(Error::CellInTwoRegions {
                    cell,
                    centre: [0, 1, 2].map(|c| vertices.iter().map(|x| x[c]).sum::<f64>() / n),
                    first: regions[usize::from(*slot) - 1].0.clone(),
                    second: name.clone(),
                });
            }
            *slot = k;
        }
        materials.push(*material);
    }
    Ok(CellMaterials { materials, of_cell })
}

fn strings(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

fn part_of(mesh: &Mesh, role: &'static str, name: &str) -> Result<usize, Error> {
    mesh.part_index(name).ok_or_else(|| Error::UnknownPart {
        role: role.to_string(),
        name: name.to_string(),
        known: mesh.part_names.clone(),
    })
}

/// A load's part: a part of the mesh, and a Neumann part (a traction elsewhere would fight the
/// constraint or the law that holds there).
fn load_part(mesh: &Mesh, parts: &BoundaryParts, label: &str, name: &str) -> Result<usize, Error> {
    let part = mesh.part_index(name).ok_or_else(|| Error::UnknownPart {
        role: label.to_string(),
        name: name.to_string(),
        known: mesh.part_names.clone(),
    })?;
    if !parts.neumann.contains(&part) {
        return Err(Error::LoadOffNeumann {
            label: label.to_string(),
            part: name.to_string(),
            neumann: parts.neumann.iter().map(|&p| mesh.part_names[p].clone()).collect(),
        });
    }
    Ok(part)
}

/// The datum at the nodes at t = 0, which must lie in E^h: zero on Γ_D, no normal component on
/// Γ_C, none across a symmetry plane. Data that do not are an error rather than silently
/// projected.
/// Nodal values `full` (d per node) as an element of E^h, or the node where they leave it.
fn admissible(mesh: &Mesh, space: &VelocitySpace, full: Vec<f64>, label: &str) -> Result<Vec<f64>, Error> {
    let projected = space.prolong(&space.restrict_values(&full));
    let scale = full.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let d = mesh.dim;
    for (p, (a, b)) in full.chunks_exact(d).zip(projected.chunks_exact(d)).enumerate() {
        let off: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt();
        if off > 1e-9 * scale.max(f64::MIN_POSITIVE) {
            return Err(Error::InitialNotAdmissible {
                label: label.to_string(),
                node: p,
                x: mesh.coords[p],
                value: a.to_vec(),
            });
        }
    }
    Ok(projected)
}

/// The parts given roles share no facet (a facet in two physical groups would otherwise count
/// twice in Γ_C's weights or carry two boundary conditions).
fn no_shared_facets(mesh: &Mesh, parts: &BoundaryParts) -> Result<(), Error> {
    let roles = [&parts.dirichlet, &parts.neumann, &parts.contact, &parts.symmetry];
    let used: Vec<usize> = roles.into_iter().flatten().copied().collect();
    match first_shared_facet(mesh, &used) {
        Some((first, second)) => Err(Error::PartsShareFacets {
            first: mesh.part_names[first].clone(),
            second: mesh.part_names[second].clone(),
        }),
        None => Ok(()),
    }
}

/// Two of `parts` that share a facet (the same vertices in two physical groups), if any.
pub(super) fn first_shared_facet(mesh: &Mesh, parts: &[usize]) -> Option<(usize, usize)> {
    let mut keys: Vec<([usize; 3], usize)> = mesh
        .facets_of(parts)
        .map(|f| (crate::mesh::topology::facet_key(mesh.facet(f)), mesh.facet_parts[f]))
        .collect();
    keys.sort_unstable();
    keys.windows(2).find(|w| w[0].0 == w[1].0).map(|w| (w[0].1, w[1].1))
}

/// Per node, the unit normals of the symmetry planes through it.
fn symmetry_planes(mesh: &Mesh, parts: &[usize]) -> Result<Vec<Vec<[f64; 3]>>, Error> {
    let mut planes = vec![Vec::new(); mesh.n_nodes()];
    for &part in parts {
        let normal = mesh.part_normal(part).ok_or_else(|| Error::CurvedSymmetryPart {
            part: mesh.part_names[part].clone(),
        })?;
        for (p, on) in mesh.nodes_on(&[part]).into_iter().enumerate() {
            if on {
                planes[p].push(normal);
            }
        }
    }
    Ok(planes)
}
