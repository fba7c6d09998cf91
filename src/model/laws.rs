//! The laws on Γ_C as a problem holds them (each friction law with its scale and its contact
//! parts, the heat exchange, the frictional heating and its share), and as a time step reads
//! them: node by node, at the step's time and the nodes' slip distances ([`ContactLaws`]).
//!
//! Depends on: [`super::problem`], [`crate::contact`], [`crate::loads`].

use super::error::ModelError as Error;
use super::problem::Problem;
use crate::contact::{FrictionLaw, FrictionalHeating, LawPoint, NormalForce};
use crate::la::vector::norm2;
use crate::loads::Datum;

/// A friction law with its scale S (a datum of x and t: a number, affine in t, or an
/// expression) on some contact parts: the bound is b(r) = S(x, t) μ(r).
#[derive(Debug)]
pub struct Friction {
    /// S.
    pub scale: Datum,
    /// μ.
    pub law: Box<dyn FrictionLaw>,
    /// The contact parts it holds on (mesh part indices); empty: every contact part not named
    /// by another law.
    pub parts: Vec<usize>,
    /// What scales μ: S (the paper), or the contact pressure (Coulomb; `scale` unused).
    pub normal: NormalForce,
}

/// The frictional heating h_τ and the share of it that enters the body (the paper: 1).
#[derive(Debug)]
pub struct Heating {
    pub law: Box<dyn FrictionalHeating>,
    /// The fraction of the frictional power h_τ that enters the body.
    pub share: f64,
    /// h_τ is the friction's own dissipated power, h_τ(r) = b_i(r) r = |ξ_i| |w_τ − v_F,τ| at
    /// a slipping node (`law` unused): the heat a brake makes, consistent with the friction
    /// law at every node (Coulomb's included).
    pub friction_power: bool,
}

/// The laws of one time step at the contact nodes: x_i, t_n and the slip distances s_i fixed,
/// the scale evaluated once; what the step solvers read instead of the laws themselves.
pub struct ContactLaws<'p> {
    problem: &'p Problem,
    /// t_n.
    pub t: f64,
    points: Vec<LawPoint>,
    /// S(x_i, t_n), or p_i where the law scales with the contact pressure
    /// ([`ContactLaws::set_pressures`]).
    scales: Vec<f64>,
    /// v_F,τ at the contact nodes in their tangent coordinates (node-major, d − 1 per node; 0
    /// on a coordinate held at zero); `None` where the foundation is at rest.
    foundation: Option<Vec<f64>>,
    /// The temperatures at which a nonlinear heat exchange is evaluated this step (`None`
    /// where the exchange is affine, in the step matrix).
    pub exchange_temperature: Option<Vec<f64>>,
}

impl<'p> ContactLaws<'p> {
    /// The laws at time `t` with the slip distances `slip_distance` (one per contact node).
    pub fn new(problem: &'p Problem, t: f64, slip_distance: &[f64]) -> Result<Self, Error> {
        // An empty `slip_distance` (a checkpoint older than it) reads as zeros.
        let points: Vec<LawPoint> = (problem.contact.iter().enumerate())
            .map(|(i, node)| LawPoint {
                x: problem.mesh.coords[node.node],
                t,
                slip_distance: slip_distance.get(i).copied().unwrap_or(0.0),
            })
            .collect();
        let mut scales = Vec::with_capacity(points.len());
        for (i, at) in points.iter().enumerate() {
            let friction = &problem.friction[problem.friction_of_node[i]];
            if friction.normal == NormalForce::Reaction {
                // The pressure comes with each iterate (`set_pressures`); none before.
                scales.push(0.0);
                continue;
            }
            let mut s = [0.0];
            friction.scale.eval(at.x, t, &mut s);
            if !s[0].is_finite() || s[0] < 0.0 {
                return Err(Error::BadFrictionScale {
                    value: s[0],
                    x: at.x,
                    t,
                });
            }
            scales.push(s[0]);
        }
        Ok(ContactLaws {
            problem,
            t,
            points,
            scales,
            foundation: foundation_tangential(problem, t)?,
            exchange_temperature: None,
        })
    }

    /// Whether a law scales with the contact pressure (Coulomb): then the step iterates on it.
    pub fn uses_pressure(&self) -> bool {
        self.problem.pressure.is_some()
    }

    /// The contact pressures p_i at which the laws that scale with it are evaluated.
    pub fn set_pressures(&mut self, pressures: &[f64]) {
        for (i, &p) in pressures.iter().enumerate() {
            if self.problem.friction[self.problem.friction_of_node[i]].normal == NormalForce::Reaction {
                self.scales[i] = p;
            }
        }
    }

    /// w_τ − v_F,τ in place: tangential velocities (node-major tangent coordinates) made
    /// relative to the foundation. Nothing happens where it is at rest.
    pub fn make_relative(&self, w_tau: &mut [f64]) {
        subtract(w_tau, self.foundation.as_deref());
    }

    /// v_F,τ at the contact nodes (node-major tangent coordinates), `None` at rest.
    pub fn foundation(&self) -> Option<&[f64]> {
        self.foundation.as_deref()
    }

    /// The relative slip w_τ − v_F,τ at the contact nodes of a full velocity vector.
    pub fn slip(&self, w_full: &[f64]) -> Vec<f64> {
        let mut w_tau = super::contact_tangential(self.problem, w_full);
        subtract(&mut w_tau, self.foundation.as_deref());
        w_tau
    }

    /// The laws that the step to `state` solved: at its time, with the slip distances before
    /// it (what the outputs report the state against).
    pub fn of_state(problem: &'p Problem, state: &super::State) -> Result<Self, Error> {
        let mut laws = Self::new(problem, state.t, &state.slip_distance_before)?;
        laws.set_pressures(&state.pressure);
        Ok(laws)
    }

    fn law(&self, i: usize) -> &dyn FrictionLaw {
        self.problem.friction[self.problem.friction_of_node[i]].law.as_ref()
    }

    /// Number of contact nodes.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether Γ_C has no contact node.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The point of contact node i.
    pub fn point(&self, i: usize) -> &LawPoint {
        &self.points[i]
    }

    /// b_i(r) at contact node i (a law's negative value counts as 0: no friction).
    #[inline]
    pub fn bound(&self, i: usize, r: f64) -> f64 {
        self.law(i).bound(self.scales[i], &self.points[i], r).max(0.0)
    }

    /// b_i′(r).
    #[inline]
    pub fn bound_derivative(&self, i: usize, r: f64) -> f64 {
        self.law(i).bound_derivative(self.scales[i], &self.points[i], r)
    }

    /// ∫₀^r b_i.
    pub fn potential(&self, i: usize, r: f64) -> f64 {
        self.law(i).potential(self.scales[i], &self.points[i], r)
    }

    /// The friction bounds b_i(|w_i|) for w_τ node-major in tangent coordinates (d − 1 per
    /// node): the bounds a convexification iterate freezes.
    pub fn bounds(&self, w: &[f64]) -> Vec<f64> {
        let td = self.problem.dim() - 1;
        (0..self.len())
            .map(|i| self.bound(i, norm2(&w[i * td..(i + 1) * td])))
            .collect()
    }

    /// The smallest positive bound at rest, min_i b_i(0) > 0 (the scale of the law's
    /// residuals, [`law_scale`]).
    pub fn smallest_bound_at_rest(&self) -> f64 {
        law_scale((0..self.len()).map(|i| self.bound(i, 0.0)))
    }

    /// The largest bound at rest, max_i b_i(0).
    pub fn largest_bound_at_rest(&self) -> f64 {
        (0..self.len()).map(|i| self.bound(i, 0.0)).fold(0.0, f64::max)
    }

    /// max_i S_i m_τ,i: the steepest fall of the friction bounds (m_τ of H(j_τ)(d)), from each
    /// law's [`FrictionLaw::constants`] (one evaluation per law where it does not depend on x).
    pub fn steepest_fall(&self) -> f64 {
        let mut per_law: Vec<Option<f64>> = vec![None; self.problem.friction.len()];
        let mut worst: f64 = 0.0;
        for i in 0..self.len() {
            let k = self.problem.friction_of_node[i];
            let law = self.law(i);
            let m = match per_law[k] {
                Some(m) => m,
                None => {
                    let m = law.constants(&self.points[i]).1;
                    if law.uniform() {
                        per_law[k] = Some(m);
                    }
                    m
                }
            };
            worst = worst.max(self.scales[i] * m);
        }
        worst
    }

    /// The heat entering the body at contact node i slipping at rate r: share · h_τ(x_i, t, r).
    #[inline]
    pub fn heat(&self, i: usize, r: f64) -> f64 {
        let heating = &self.problem.heating;
        if heating.friction_power {
            return heating.share * self.bound(i, r) * r;
        }
        // share = 1 (the paper) multiplies exactly: the same bits as h_τ alone.
        heating.share * heating.law.heat(&self.points[i], r)
    }

    /// heat(i, to) − heat(i, from).
    #[inline]
    pub fn heat_change(&self, i: usize, from: f64, to: f64) -> f64 {
        let heating = &self.problem.heating;
        if heating.friction_power {
            return self.heat(i, to) - self.heat(i, from);
        }
        // share = 1 (the paper) multiplies exactly: the same bits as h_τ alone.
        heating.share * heating.law.heat_change(&self.points[i], from, to)
    }

    /// ∂/∂r of [`ContactLaws::heat`].
    #[inline]
    pub fn heat_derivative(&self, i: usize, r: f64) -> f64 {
        let heating = &self.problem.heating;
        if heating.friction_power {
            return heating.share * (self.bound_derivative(i, r) * r + self.bound(i, r));
        }
        // share = 1 (the paper) multiplies exactly: the same bits as h_τ alone.
        heating.share * heating.law.heat_derivative(&self.points[i], r)
    }

    /// The frictional heats at the contact nodes for w_τ node-major.
    pub fn heats(&self, w: &[f64]) -> Vec<f64> {
        let td = self.problem.dim() - 1;
        (0..self.len())
            .map(|i| self.heat(i, norm2(&w[i * td..(i + 1) * td])))
            .collect()
    }
}

/// The constants of the theory's hypotheses for the laws of a problem (MODEL.md §6): what the
/// run header prints and `summary.json` records.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize, PartialEq)]
pub struct LawConstants {
    /// One entry per friction law, in the order given.
    pub friction: Vec<FrictionConstants>,
    /// max c_τ and max m_τ over the laws.
    pub c_tau: f64,
    pub m_tau: f64,
    /// The heat exchange's name and m_θ = sup |(∂j)′| (H(j)(d)).
    pub heat_exchange: String,
    pub m_theta: f64,
    /// L_τ = sup_{r, t} |∂h_τ/∂r| (H(h_τ)(b)), share included.
    pub l_tau: f64,
    /// Hypotheses the laws fail, each said in a sentence (computable, so the run goes on).
    pub warnings: Vec<String>,
}

/// The constants of one friction law.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize, PartialEq)]
pub struct FrictionConstants {
    /// The law's name (`velocity-weakening`, `tresca`, `table`, `expression`,
    /// `slip-distance-weakening`).
    pub law: String,
    /// The contact parts it holds on (empty: all not given their own).
    pub parts: Vec<String>,
    /// c_τ = sup b (H(j_τ)(c)).
    pub c_tau: f64,
    /// m_τ = sup max(0, −b′) (H(j_τ)(d)).
    pub m_tau: f64,
}

impl Problem {
    /// c_τ, m_τ, m_θ and L_τ of the problem's laws: each over the contact nodes of its parts
    /// and the times 0, T/4, …, T (the scale and an expression may depend on x and t), the
    /// slip rates by [`FrictionLaw::constants`].
    pub fn law_constants(&self) -> LawConstants {
        let final_time = self.time.final_time;
        let times: Vec<f64> = (0..=4).map(|k| final_time * k as f64 / 4.0).collect();
        let mut out = LawConstants {
            heat_exchange: self.exchange.name().to_string(),
            ..Default::default()
        };
        for (k, friction) in self.friction.iter().enumerate() {
            let (mut c_tau, mut m_tau) = (0.0f64, 0.0f64);
            let mut uniform: Option<(f64, f64)> = None;
            for (i, node) in self.contact.iter().enumerate() {
                if self.friction_of_node[i] != k {
                    continue;
                }
                for &t in &times {
                    let at = LawPoint {
                        x: self.mesh.coords[node.node],
                        t,
                        slip_distance: 0.0,
                    };
                    let mut s = [0.0];
                    friction.scale.eval(at.x, t, &mut s);
                    let (c, m) = match uniform {
                        Some(cm) => cm,
                        None => {
                            let cm = friction.law.constants(&at);
                            if friction.law.uniform() {
                                uniform = Some(cm);
                            }
                            cm
                        }
                    };
                    c_tau = c_tau.max(s[0] * c);
                    m_tau = m_tau.max(s[0] * m);
                }
            }
            // H(j_τ)(c): a bounded subgradient. A bound still growing between r = 10³ and 10⁶
            // (the laws' rates are far below) does not have one; a negative one is no bound.
            if let Some(i) = (0..self.contact.len()).find(|&i| self.friction_of_node[i] == k) {
                let at = LawPoint {
                    x: self.mesh.coords[self.contact[i].node],
                    t: final_time,
                    slip_distance: 0.0,
                };
                let (far, farther) = (friction.law.bound(1.0, &at, 1e3), friction.law.bound(1.0, &at, 1e6));
                if !farther.is_finite() || farther > 2.0 * far.abs() + 1e-300 {
                    out.warnings.push(format!(
                        "friction law {} ({}): μ grows without bound (μ(10³) = {far:e}, μ(10⁶) = {farther:e}), so H(j_τ)(c), a bounded subgradient, fails; the run goes on",
                        k + 1,
                        friction.law.name()
                    ));
                }
                if let Some(r) = [0.0, 1e-3, 1e-2, 0.1, 1.0, 10.0, 1e3]
                    .into_iter()
                    .find(|&r| friction.law.bound(1.0, &at, r) < 0.0)
                {
                    out.warnings.push(format!(
                        "friction law {} ({}): μ({r}) < 0, which no friction law has (the solvers take a negative bound as 0)",
                        k + 1,
                        friction.law.name()
                    ));
                }
            }
            out.friction.push(FrictionConstants {
                law: friction.law.name().to_string(),
                parts: self.part_names(&friction.parts).into_iter().map(String::from).collect(),
                c_tau,
                m_tau,
            });
            out.c_tau = out.c_tau.max(c_tau);
            out.m_tau = out.m_tau.max(m_tau);
        }
        let first = self.contact.first().map_or([0.0; 3], |n| self.mesh.coords[n.node]);
        for &t in &times {
            let at = LawPoint {
                x: first,
                t,
                slip_distance: 0.0,
            };
            out.m_theta = out.m_theta.max(self.exchange.lipschitz(&at));
            out.l_tau = out.l_tau.max(self.heating.share * self.heating.law.lipschitz(&at));
        }
        out
    }
}

/// v_F,τ(x_i, t) at the contact nodes in their tangent coordinates (node-major, d − 1 per node;
/// 0 on a coordinate held at zero, which cannot follow the foundation); `None` where the
/// foundation is at rest.
pub fn foundation_tangential(problem: &Problem, t: f64) -> Result<Option<Vec<f64>>, Error> {
    let Some(foundation) = &problem.foundation else {
        return Ok(None);
    };
    let d = problem.dim();
    let mut v_tau = Vec::with_capacity(problem.contact.len() * (d - 1));
    for node in &problem.contact {
        let x = problem.mesh.coords[node.node];
        let v = foundation.velocity(d, x, t);
        if v.iter().any(|c| !c.is_finite()) {
            return Err(Error::BadFoundationVelocity { value: v, x, t });
        }
        for (tangent, dof) in node.tangents.iter().zip(&node.tangent_dofs) {
            v_tau.push(dof.map_or(0.0, |_| (0..d).map(|c| tangent[c] * v[c]).sum()));
        }
    }
    Ok(Some(v_tau))
}

/// The scale of the nodal law's residuals: the smallest *positive* bound (a node without
/// friction, e.g. where the contact pressure vanishes under Coulomb friction, would make any
/// residual infinitely large), or the smallest positive number where no bound is positive
/// (frictionless contact, whose law residual |ξ| must then vanish).
pub fn law_scale(bounds: impl IntoIterator<Item = f64>) -> f64 {
    let smallest = (bounds.into_iter()).filter(|&g| g > 0.0).fold(f64::INFINITY, f64::min);
    if smallest.is_finite() {
        smallest
    } else {
        f64::MIN_POSITIVE
    }
}

/// The relative slip w_τ − v_F,τ(t) at the contact nodes of a full velocity vector, without the
/// laws of a step (an invalid v_F, which fails the step's laws first, reads as at rest).
pub fn relative_slip(problem: &Problem, w_full: &[f64], t: f64) -> Vec<f64> {
    let mut w_tau = super::contact_tangential(problem, w_full);
    subtract(&mut w_tau, foundation_tangential(problem, t).ok().flatten().as_deref());
    w_tau
}

/// w −= v where the foundation moves (`Some`): nothing at rest, so the paper's bits stay.
fn subtract(w_tau: &mut [f64], foundation: Option<&[f64]>) {
    if let Some(v) = foundation {
        w_tau.iter_mut().zip(v).for_each(|(w, v)| *w -= v);
    }
}
