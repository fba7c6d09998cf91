//! Thermal boundary conditions per boundary part, independent of the mechanical roles.
//!
//! The paper (MODEL.md §1, eq. (6)) ties the temperature's boundary conditions to the
//! mechanical roles: θ = θ_D on Γ_D ∪ Γ_N, the heat exchange law on Γ_C, no flux elsewhere (a
//! symmetry plane, a part in no role). A [`ThermalCondition`] given for a part
//! ([`super::ProblemBuilder::thermal`]) replaces that rule on the part:
//!
//! ```text
//! Temperature(θ_D):               θ = θ_D(x, t)                  on the part (Dirichlet)
//! Flux(q):                        −K∇θ·ν = −q                    q the heat flux *into* the body
//! Convection { h, θ_∞ }:          −K∇θ·ν = h (θ − θ_∞)           h ≥ 0
//! Insulated:                      −K∇θ·ν = 0
//! ```
//!
//! In the weak form of the heat equation (MODEL.md §2) a Neumann-type condition adds its
//! boundary integral: a flux the load ∫_part q η; convection the term h ∫_part θ η to the
//! conduction matrix 𝒦_θ (constant, assembled once with the consistent boundary mass, as the
//! linear exchange on Γ_C) and the load h θ_∞ ∫_part η; insulation nothing. A prescribed
//! temperature removes the part's nodes from V^h and takes their nodal values θ_D(x_p, t):
//! the columns of those nodes move to the right-hand side (the lifting,
//! [`super::StepMatrix`]). A θ_D that depends on t is re-evaluated at every step, at its nodes
//! only, and lifted through the few matrix entries of its columns, stored once; a θ_D constant
//! in t costs nothing per step.
//!
//! Rules where conditions meet:
//! - parts not listed keep the paper's rule; listing a part of Γ_D or Γ_N releases the paper's
//!   θ = θ_D there (e.g. a loaded face declared `Insulated`);
//! - Dirichlet wins at corners: a node in the closure of a temperature part (or of a Γ_D, Γ_N
//!   part not listed) is a Dirichlet node; its value is that of the first temperature part
//!   listed that holds it, else the paper's θ_D;
//! - a contact part takes no thermal condition (Γ_C has its own heat exchange law, the
//!   builder's `heat_exchange`): [`super::ModelError::ThermalOnContact`];
//! - a part listed twice is an error, and so are two listed parts sharing a facet (the facet's
//!   flux would count twice).

use super::error::ModelError as Error;
use super::problem::BoundaryParts;
use crate::fem::assembly;
use crate::la::CscMatrix;
use crate::loads::{Datum, Load, LoadKind};
use crate::mesh::Mesh;

/// The thermal boundary condition of one boundary part.
#[derive(Debug, Clone, PartialEq)]
pub enum ThermalCondition {
    /// θ = θ_D(x, t) (a scalar datum: a number, affine in t, or an expression).
    Temperature(Datum),
    /// A prescribed heat flux q(x, t) into the body (a scalar datum): −K∇θ·ν = −q.
    Flux(Datum),
    /// Convection −K∇θ·ν = h (θ − θ_∞) with a constant coefficient h ≥ 0 and ambient θ_∞.
    Convection { coefficient: f64, ambient: f64 },
    /// No heat flux.
    Insulated,
}

impl ThermalCondition {
    /// The name used in messages and scenario files.
    pub fn name(&self) -> &'static str {
        match self {
            ThermalCondition::Temperature(_) => "temperature",
            ThermalCondition::Flux(_) => "flux",
            ThermalCondition::Convection { .. } => "convection",
            ThermalCondition::Insulated => "insulated",
        }
    }
}

/// The thermal conditions made discrete: what a run reads at every step.
#[derive(Debug, Default)]
pub struct ThermalBoundary {
    /// The conditions as given, each with its mesh part.
    pub conditions: Vec<(usize, ThermalCondition)>,
    /// Dirichlet nodes whose θ_D depends on t, each with its datum (an index into
    /// `moving_data`).
    moving: Vec<(usize, usize)>,
    /// The data of the temperature parts that depend on t, each with its label.
    moving_data: Vec<(String, Datum)>,
    /// Whether each node is in `moving` (empty when none is).
    is_moving: Vec<bool>,
    /// Boundary heat loads that depend on t (fluxes); the constant ones are added once into the
    /// problem's constant heat load.
    loads: Vec<Load>,
}

/// What the builder takes from the thermal conditions.
pub(super) struct ThermalSetup {
    /// The Dirichlet nodes of V^h.
    pub fixed: Vec<bool>,
    /// θ_D at t = 0 at the Dirichlet nodes, zero elsewhere.
    pub values: Vec<f64>,
    /// The per-step part.
    pub boundary: ThermalBoundary,
    /// Constant boundary heat loads (convection h θ_∞ ∫η, fluxes constant in t), if any.
    pub constant_load: Option<Vec<f64>>,
}

/// Resolves the conditions given per part (names as in the mesh) against the mechanical roles:
/// the Dirichlet nodes, their values, the boundary loads. With no conditions this is the
/// paper's rule, computed as it always was. Each condition comes with the label that names its
/// datum in errors.
pub(super) fn resolve(
    mesh: &Mesh,
    parts: &BoundaryParts,
    given: Vec<(String, ThermalCondition, String)>,
    boundary_temperature: f64,
) -> Result<ThermalSetup, Error> {
    let labels: Vec<String> = given.iter().map(|(_, _, label)| label.clone()).collect();
    let conditions = checked_conditions(mesh, parts, given)?;
    let listed: Vec<usize> = conditions.iter().map(|(p, _)| *p).collect();
    let mut fixed_parts: Vec<usize> = [parts.dirichlet.clone(), parts.neumann.clone()]
        .concat()
        .into_iter()
        .filter(|p| !listed.contains(p))
        .collect();
    fixed_parts.extend(
        conditions
            .iter()
            .filter(|(_, c)| matches!(c, ThermalCondition::Temperature(_)))
            .map(|(p, _)| *p),
    );
    let fixed = mesh.nodes_on(&fixed_parts);
    let mut values: Vec<f64> = fixed
        .iter()
        .map(|&f| if f { boundary_temperature } else { 0.0 })
        .collect();

    let mut boundary = ThermalBoundary::default();
    let mut taken = vec![false; mesh.n_nodes()];
    for ((part, condition), label) in conditions.iter().zip(&labels) {
        if let ThermalCondition::Temperature(datum) = condition {
            let prescribed = Prescribed {
                part: *part,
                datum,
                label,
            };
            prescribed.apply(mesh, &mut taken, &mut values, &mut boundary)?;
        }
    }
    if !boundary.moving.is_empty() {
        boundary.is_moving = vec![false; mesh.n_nodes()];
        boundary.moving.iter().for_each(|&(p, _)| boundary.is_moving[p] = true);
    }

    let mut constant_load: Option<Vec<f64>> = None;
    for ((part, condition), label) in conditions.iter().zip(labels) {
        let datum = match condition {
            ThermalCondition::Flux(q) => q.clone(),
            ThermalCondition::Convection { coefficient, ambient } => Datum::scalar(coefficient * ambient),
            ThermalCondition::Temperature(_) | ThermalCondition::Insulated => continue,
        };
        let load = Load::new(mesh, LoadKind::HeatFlux { parts: vec![*part] }, datum, label)?;
        if load.depends_on_time() {
            boundary.loads.push(load);
        } else {
            let sum = constant_load.get_or_insert_with(|| vec![0.0; mesh.n_nodes()]);
            load.add_to(mesh, 0.0, sum)?;
        }
    }
    boundary.conditions = conditions;
    Ok(ThermalSetup {
        fixed,
        values,
        boundary,
        constant_load,
    })
}

/// The conditions with their parts: parts of the mesh, none twice, none of Γ_C, no two sharing
/// a facet.
fn checked_conditions(
    mesh: &Mesh,
    parts: &BoundaryParts,
    given: Vec<(String, ThermalCondition, String)>,
) -> Result<Vec<(usize, ThermalCondition)>, Error> {
    let mut conditions: Vec<(usize, ThermalCondition)> = Vec::with_capacity(given.len());
    for (name, condition, _) in given {
        let part = mesh.part_index(&name).ok_or_else(|| Error::UnknownPart {
            role: "a thermal condition".to_string(),
            name: name.clone(),
            known: mesh.part_names.clone(),
        })?;
        if conditions.iter().any(|(p, _)| *p == part) {
            return Err(Error::ThermalPartTwice { part: name });
        }
        if parts.contact.contains(&part) {
            return Err(Error::ThermalOnContact { part: name });
        }
        if mesh.facets_of(&[part]).next().is_none() {
            return Err(Error::EmptyPart {
                role: "thermal",
                part: name,
            });
        }
        let datum = match &condition {
            ThermalCondition::Temperature(d) | ThermalCondition::Flux(d) => Some(d),
            _ => None,
        };
        if let Some(datum) = datum.filter(|d| d.n_components() != 1) {
            return Err(Error::ThermalDatum {
                part: name,
                condition: condition.name(),
                found: datum.n_components(),
            });
        }
        if let ThermalCondition::Convection { coefficient, ambient } = condition {
            if !(coefficient >= 0.0 && coefficient.is_finite() && ambient.is_finite()) {
                return Err(Error::BadConvection {
                    part: name,
                    coefficient,
                    ambient,
                });
            }
        }
        conditions.push((part, condition));
    }
    let listed: Vec<usize> = conditions.iter().map(|(p, _)| *p).collect();
    if let Some((first, second)) = super::problem::first_shared_facet(mesh, &listed) {
        return Err(Error::PartsShareFacets {
            first: mesh.part_names[first].clone(),
            second: mesh.part_names[second].clone(),
        });
    }
    Ok(conditions)
}

/// A temperature condition: its part, θ_D and the label naming it.
struct Prescribed<'a> {
    part: usize,
    datum: &'a Datum,
    label: &'a str,
}

impl Prescribed<'_> {
    /// θ_D at the part's nodes not taken by an earlier temperature part (`taken`), at t = 0;
    /// the nodes of a datum that depends on t are recorded for the steps.
    fn apply(
        &self,
        mesh: &Mesh,
        taken: &mut [bool],
        values: &mut [f64],
        boundary: &mut ThermalBoundary,
    ) -> Result<(), Error> {
        let moving = self.datum.uses_time();
        if moving {
            boundary.moving_data.push((self.label.to_string(), self.datum.clone()));
        }
        let mut value = [0.0];
        for (p, on) in mesh.nodes_on(&[self.part]).into_iter().enumerate() {
            if !on || taken[p] {
                continue;
            }
            taken[p] = true;
            self.datum.eval(mesh.coords[p], 0.0, &mut value);
            finite_temperature(self.label, mesh.coords[p], 0.0, value[0])?;
            values[p] = value[0];
            if moving {
                boundary.moving.push((p, boundary.moving_data.len() - 1));
            }
        }
        Ok(())
    }
}

fn finite_temperature(label: &str, x: [f64; 3], t: f64, value: f64) -> Result<(), Error> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(Error::ThermalNotFinite {
            label: label.to_string(),
            x,
            t,
            value,
        })
    }
}

impl ThermalBoundary {
    /// Whether some θ_D depends on t.
    pub fn has_moving_temperature(&self) -> bool {
        !self.moving.is_empty()
    }

    /// Whether node p's θ_D depends on t.
    pub fn is_moving(&self, p: usize) -> bool {
        self.is_moving.get(p).copied().unwrap_or(false)
    }

    /// Overwrites θ_D(x_p, t) at the nodes whose θ_D depends on t.
    pub fn update_temperatures(&self, mesh: &Mesh, t: f64, values: &mut [f64]) -> Result<(), Error> {
        let mut value = [0.0];
        for &(p, k) in &self.moving {
            let (label, datum) = &self.moving_data[k];
            datum.eval(mesh.coords[p], t, &mut value);
            finite_temperature(label, mesh.coords[p], t, value[0])?;
            values[p] = value[0];
        }
        Ok(())
    }

    /// Adds the boundary heat loads that depend on t (∫_part q(t) η) into a full temperature
    /// load vector.
    pub fn add_loads(&self, mesh: &Mesh, t: f64, heat: &mut [f64]) -> Result<(), Error> {
        for load in &self.loads {
            load.add_to(mesh, t, heat)?;
        }
        Ok(())
    }

    /// Adds h ∫_part θ η of every convection part to `conduction` (full temperature dofs), in
    /// the order the conditions were given.
    pub(super) fn add_convection(&self, mesh: &Mesh, conduction: &mut CscMatrix) {
        for (part, condition) in &self.conditions {
            if let ThermalCondition::Convection { coefficient, .. } = condition {
                assembly::add_boundary_mass(mesh, &[*part], *coefficient, conduction);
            }
        }
    }
}
