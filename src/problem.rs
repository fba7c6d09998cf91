//! The discrete problem: a scenario turned into a mesh, spaces, assembled matrices, loads and
//! laws — everything that stays fixed during a run.

use crate::contact::frames::{contact_frames, orthogonal_complement};
use crate::contact::{
    FrictionLaw, FrictionalHeating, HeatExchange, LinearHeating, QuadraticExchange, SlipWeakening, Tresca,
};
use crate::error::Error;
use crate::fem::assembly::{self, Matrices};
use crate::fem::dofs::{NodeBasis, TemperatureSpace, VelocitySpace};
use crate::material::{Isotropic, Material};
use crate::mesh::{self, Mesh};
use crate::scenario::{FrictionSpec, Scenario};

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
    /// Temperature unknown, `None` where θ = θ_D (a node also on the closure of Γ_N).
    pub theta_dof: Option<usize>,
}

/// Everything fixed during a run.
#[derive(Debug)]
pub struct Problem {
    pub scenario: Scenario,
    pub mesh: Mesh,
    pub material: Material,
    /// E^h.
    pub velocity: VelocitySpace,
    /// V^h.
    pub temperature: TemperatureSpace,
    pub matrices: Matrices,
    /// Frictional contact nodes of Γ_C.
    pub contact: Vec<ContactNode>,
    /// ℓ_p on every node of Γ_C (including clamped ones), zero elsewhere.
    pub contact_weights: Vec<f64>,
    pub friction: Box<dyn FrictionLaw>,
    pub exchange: Box<dyn HeatExchange>,
    pub heating: Box<dyn FrictionalHeating>,
    /// Full velocity loads: F(t) = force_constant + t · force_rate.
    force_constant: Vec<f64>,
    force_rate: Vec<f64>,
    /// Full temperature loads: ∫ g η + k_e θ_R ∫_ΓC η = heat_constant + t · heat_rate.
    heat_constant: Vec<f64>,
    heat_rate: Vec<f64>,
    /// θ_D at Dirichlet nodes, zero elsewhere (full temperature vector).
    pub theta_dirichlet: Vec<f64>,
    /// Space–time dependent loads beyond the scenario's affine ones (the verification family
    /// of [`crate::verification::manufactured`]); `None` for scenario runs.
    pub extra_loads: Option<Box<dyn ExtraLoads>>,
}

/// Loads that vary in space and time, added to the scenario's affine loads: a body force f₀(x, t),
/// tractions f₂(x, t) on Γ_N, a known load on Γ_C, a heat source g(x, t) and a known heat flux on
/// Γ_C. Implementors integrate them into full load vectors (velocity dofs p·d + c, temperature
/// dofs p); [`Problem::force`] and [`Problem::heat_load`] add them, so every solver sees them.
pub trait ExtraLoads: Send + Sync + std::fmt::Debug {
    /// Adds ∫ f₀(t)·φ + ∫_ΓN f₂(t)·φ + ∫_ΓC f_C(t)·φ to a full velocity load vector.
    fn add_force(&self, problem: &Problem, t: f64, force: &mut [f64]);
    /// Adds ∫ g(t) η + ∫_ΓC g_C(t) η to a full temperature load vector.
    fn add_heat(&self, problem: &Problem, t: f64, heat: &mut [f64]);
}

impl Problem {
    /// Builds the mesh, spaces, matrices and loads of a scenario.
    pub fn new(scenario: &Scenario) -> Result<Self, Error> {
        scenario.validate()?;
        let d = scenario.dim();
        let mesh = match d {
            2 => mesh::rectangle(
                scenario.geometry.lengths[0],
                scenario.geometry.lengths[1],
                scenario.mesh.nx,
                scenario.mesh.ny,
            ),
            _ => {
                let l = &scenario.geometry.lengths;
                let Some(nz) = scenario.mesh.nz else {
                    return Err(Error::InvalidValue {
                        key: "mesh.nz".into(),
                        value: "(missing)".into(),
                        expected: "a cell count for the box's z direction".into(),
                    });
                };
                mesh::cuboid([l[0], l[1], l[2]], [scenario.mesh.nx, scenario.mesh.ny, nz])
            }
        };
        let parts = |names: &[String]| -> Vec<usize> { names.iter().filter_map(|n| mesh.part_index(n)).collect() };
        let (dirichlet, neumann, contact_parts) = (
            parts(&scenario.boundary.dirichlet),
            parts(&scenario.boundary.neumann),
            parts(&scenario.boundary.contact),
        );
        let m = &scenario.material;
        let material = Material {
            density: m.density,
            heat_capacity: m.heat_capacity,
            viscosity: Isotropic::viscosity(m.viscosity_mu1, m.viscosity_mu2),
            elasticity: Isotropic::elasticity(m.young, m.poisson),
            expansion: Material::expansion_from(m.thermal_expansion, m.young, m.poisson),
            conductivity: m.conductivity,
        };

        // Constraints; Dirichlet wins at corners.
        let clamped = mesh.nodes_on(&dirichlet);
        let planes = symmetry_planes(&mesh, scenario)?;
        let frames = contact_frames(
            d,
            mesh.n_nodes(),
            mesh.facets_of(&contact_parts)
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
        let theta_fixed = mesh.nodes_on(&[dirichlet.clone(), neumann.clone()].concat());
        let temperature = TemperatureSpace::new(&theta_fixed);

        let exchange = QuadraticExchange {
            coefficient: scenario.heat_exchange.coefficient,
            foundation_temperature: scenario.heat_exchange.foundation_temperature,
        };
        let (k_e, theta_r) = exchange.robin();
        let matrices = assembly::assemble_matrices(&mesh, &material, &contact_parts, k_e);

        let contact_weights = assembly::boundary_weights(&mesh, &contact_parts);
        let contact = frames
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

        let loads = &scenario.loads;
        let mut force_constant = assembly::body_load(&mesh, &loads.body_force.constant);
        let mut force_rate = assembly::body_load(&mesh, &loads.body_force.rate);
        for traction in &loads.traction {
            let part = parts(std::slice::from_ref(&traction.part));
            add(
                &mut force_constant,
                &assembly::traction_load(&mesh, &part, &traction.constant),
            );
            add(&mut force_rate, &assembly::traction_load(&mesh, &part, &traction.rate));
        }
        let mut heat_constant = assembly::scalar_body_load(&mesh, loads.heat_source.constant);
        let heat_rate = assembly::scalar_body_load(&mesh, loads.heat_source.rate);
        add(
            &mut heat_constant,
            &contact_weights.iter().map(|w| k_e * theta_r * w).collect::<Vec<_>>(),
        );

        let theta_dirichlet = theta_fixed
            .iter()
            .map(|&f| if f { scenario.boundary.temperature } else { 0.0 })
            .collect();

        let friction: Box<dyn FrictionLaw> = match scenario.friction {
            FrictionSpec::SlipWeakening { bound, a, b, alpha } => Box::new(SlipWeakening {
                scale: bound,
                a,
                b,
                alpha,
            }),
            FrictionSpec::Tresca { bound } => Box::new(Tresca { scale: bound }),
        };
        Ok(Problem {
            scenario: scenario.clone(),
            mesh,
            material,
            velocity,
            temperature,
            matrices,
            contact,
            contact_weights,
            friction,
            exchange: Box::new(exchange),
            heating: Box::new(LinearHeating {
                rate: scenario.frictional_heating.clone(),
            }),
            force_constant,
            force_rate,
            heat_constant,
            heat_rate,
            theta_dirichlet,
            extra_loads: None,
        })
    }

    /// [`Problem::new`] with space–time dependent loads added to the scenario's.
    pub fn with_extra_loads(scenario: &Scenario, loads: Box<dyn ExtraLoads>) -> Result<Self, Error> {
        let mut problem = Problem::new(scenario)?;
        problem.extra_loads = Some(loads);
        Ok(problem)
    }

    /// Space dimension d.
    pub fn dim(&self) -> usize {
        self.mesh.dim
    }

    /// Time step k.
    pub fn time_step(&self) -> f64 {
        self.scenario.time_step()
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
    pub fn force(&self, t: f64) -> Vec<f64> {
        let mut force: Vec<f64> = self
            .force_constant
            .iter()
            .zip(&self.force_rate)
            .map(|(c, r)| c + t * r)
            .collect();
        if let Some(extra) = &self.extra_loads {
            extra.add_force(self, t, &mut force);
        }
        force
    }

    /// ∫ g(t) η + k_e θ_R ∫_ΓC η on full temperature dofs.
    pub fn heat_load(&self, t: f64) -> Vec<f64> {
        let mut heat: Vec<f64> = self
            .heat_constant
            .iter()
            .zip(&self.heat_rate)
            .map(|(c, r)| c + t * r)
            .collect();
        if let Some(extra) = &self.extra_loads {
            extra.add_heat(self, t, &mut heat);
        }
        heat
    }

    /// |Γ_C| by the nodal weights.
    pub fn contact_measure(&self) -> f64 {
        self.contact_weights.iter().sum()
    }
}

/// Per node, the unit normals of the scenario's symmetry planes through it.
fn symmetry_planes(mesh: &Mesh, scenario: &Scenario) -> Result<Vec<Vec<[f64; 3]>>, Error> {
    let mut planes = vec![Vec::new(); mesh.n_nodes()];
    for name in &scenario.boundary.symmetry {
        let normal = mesh
            .part_index(name)
            .and_then(|part| Some((part, mesh.part_normal(part)?)))
            .ok_or_else(|| Error::InvalidValue {
                key: "boundary.symmetry".into(),
                value: name.clone(),
                expected: "a flat boundary part of the mesh".into(),
            })?;
        for (p, on) in mesh.nodes_on(&[normal.0]).into_iter().enumerate() {
            if on {
                planes[p].push(normal.1);
            }
        }
    }
    Ok(planes)
}

fn add(target: &mut [f64], other: &[f64]) {
    target.iter_mut().zip(other).for_each(|(t, o)| *t += o);
}
