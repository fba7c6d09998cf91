//! A manufactured solution of Problem 2 with exact stick and slip on Γ_C.
//!
//! On Ω = (0, L₁) × (0, L₂) with the paper's layout (Γ_D = left, Γ_N = top ∪ right, Γ_C = bottom,
//! ν = (0, −1), τ = (1, 0)), with ξ = x/L₁, η = y/L₂ and the slip onset time
//! τ_s(x) = t_R + (t_L − t_R)(1 − ξ) (the right end slips first, at t_R):
//!
//! ```text
//! u_x = ξ [A (1 + η) (t − τ_s(x))₊³ + B η t²]
//! u_y = C sin(πξ/2) η t²
//! θ   = θ_D + D sin(πξ) cos(πη/2) t
//! ```
//!
//! * (5) u = 0 on Γ_D (ξ = 0) and (7) u_ν = u_y = 0 on Γ_C (η = 0) hold exactly, for all t.
//! * (6) θ = θ_D on Γ_D ∪ Γ_N (sin πξ = 0 at ξ ∈ {0, 1}, cos(πη/2) = 0 at η = 1).
//! * (10) u(0) = 0, u̇(0) = 0, θ(0) = θ_D: the uniform initial data of a scenario.
//! * On Γ_C the tangential velocity is w_τ(x, t) = 3A ξ (t − τ_s(x))₊²: zero (stick) before
//!   τ_s(x), positive (slip) after; the stick–slip front runs from right to left as in the
//!   paper's Fig. 2. u is C² in (x, t), with bounded third derivatives: the regularity that
//!   Corollary 16 asks for.
//!
//! The data follow from (1)–(4) and (9): f₀ = ρü − Div σ with σ = 𝒜ε(u̇) + ℬε(u) + cθI,
//! g = ρc_p θ̇ − div(K∇θ) − c div u̇, and f₂ = σν on Γ_N. On Γ_C the exact traction σ_τ does not
//! obey the friction law by itself; the family adds a known tangential load f_C on Γ_C, so that
//! (8) reads −(σ_τ − f_C) ∈ ∂j_τ(u̇_τ), and chooses
//!
//! ```text
//! f_C = σ_τ − ξ*,   ξ* = −μ(|w_τ|) S w_τ/|w_τ|       where w_τ ≠ 0 (slip),
//!                   ξ* = −μ(0) S (t/τ_s(x))² sgn A   where w_τ = 0 (stick, |ξ*| ≤ μ(0) S),
//! ```
//!
//! a selection of −∂j_τ(w_τ) that is continuous in time at the onset of slip. Likewise a known
//! heat flux g_C on Γ_C, g_C = K∇θ·ν + ∂j(θ) − h_τ(t, |w_τ|), makes the exact θ satisfy (9)
//! with the added flux. In the weak form both are loads: ∫_ΓC f_C·v and ∫_ΓC g_C η.
//!
//! Everything is computed with the laws and material of the [`Problem`] being solved (its
//! friction bound, heat exchange, frictional heating, 𝒜, ℬ, c, ρ, c_p, K), and all derivatives
//! come from [`Jet`]s, so the data and the discrete problem cannot disagree on a constant.

use std::f64::consts::PI;

use super::errors::{ExactFields, ExactSolution};
use super::jet::Jet;
use super::quadrature;
use crate::error::Error;
use crate::material::Isotropic;
use crate::model::{ExtraLoads, Problem};
use crate::scenario::{DatumSpec, Scenario};

/// The family's scenario overlay (material, laws, layout), `scenarios/manufactured.toml`.
pub const MANUFACTURED_TOML: &str = include_str!("../../../scenarios/manufactured.toml");

/// The manufactured solution's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Manufactured {
    /// L₁, L₂.
    pub lengths: [f64; 2],
    /// A: amplitude of the slip on Γ_C.
    pub slip_amplitude: f64,
    /// B: amplitude of the interior shear that loads Γ_C during stick.
    pub shear_amplitude: f64,
    /// C: amplitude of the normal displacement (zero on Γ_C).
    pub normal_amplitude: f64,
    /// D: amplitude of the temperature change.
    pub temperature_amplitude: f64,
    /// θ_D.
    pub boundary_temperature: f64,
    /// Slip onset times (t_R at x = L₁, t_L at x = 0).
    pub onset: [f64; 2],
}

/// u, u̇ (with derivatives up to second order in space), ü, θ (jets) and θ̇ at one point.
#[derive(Debug, Clone, Copy)]
pub struct Kinematics {
    pub u: [Jet; 2],
    pub w: [Jet; 2],
    pub acceleration: [f64; 2],
    pub theta: Jet,
    pub theta_rate: f64,
}

impl Manufactured {
    /// The family's scenario, with `overrides` (e.g. the mesh and time step of a level) applied.
    pub fn scenario(overrides: &[String]) -> Result<Scenario, Error> {
        Scenario::load(Some(MANUFACTURED_TOML), overrides)
    }

    /// The exact solution for a scenario with the family's layout; errors name what differs.
    pub fn new(scenario: &Scenario) -> Result<Self, Error> {
        let b = &scenario.boundary;
        let strings = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let l = &scenario.loads;
        // Zero data in any form (a number, an array, or an affine table of zeros).
        let zero = |d: &DatumSpec| match d {
            DatumSpec::Scalar(inner) => {
                matches!(inner.as_ref(), DatumSpec::Numbers(v) if v.iter().all(|&x| x == 0.0))
                    || matches!(inner.as_ref(), DatumSpec::Affine(a) if a.constant.iter().chain(&a.rate).all(|&x| x == 0.0))
            }
            DatumSpec::Numbers(v) => v.iter().all(|&x| x == 0.0),
            DatumSpec::Affine(a) => a.constant.iter().chain(&a.rate).all(|&x| x == 0.0),
            DatumSpec::Expressions(_) => false,
        };
        let no_loads = zero(&l.body_force)
            && zero(&l.heat_source)
            && l.pressure.is_empty()
            && l.traction.iter().all(|t| {
                t.value.as_ref().is_none_or(zero) && t.constant.iter().chain(&t.rate).flatten().all(|&v| v == 0.0)
            });
        let structured = scenario.structured().filter(|s| s.lengths.len() == 2);
        let mut neumann = b.neumann.clone();
        neumann.sort();
        // (key, holds, the scenario's value, what the family needs)
        let checks: [(&str, bool, String, &str); 6] = [
            (
                "geometry.lengths",
                structured.is_some(),
                format!("{:?}", scenario.structured().map(|s| s.lengths)),
                "a structured rectangle (2 lengths)",
            ),
            (
                "boundary.dirichlet",
                b.dirichlet == strings(&["left"]),
                format!("{:?}", b.dirichlet),
                "[\"left\"]",
            ),
            (
                "boundary.neumann",
                neumann == strings(&["right", "top"]),
                format!("{:?}", b.neumann),
                "[\"top\", \"right\"]",
            ),
            (
                "boundary.contact",
                b.contact == strings(&["bottom"]),
                format!("{:?}", b.contact),
                "[\"bottom\"]",
            ),
            (
                "initial",
                zero(&scenario.initial.velocity)
                    && zero(&scenario.initial.displacement)
                    && scenario.initial.temperature.as_scalar() == Some(b.temperature),
                format!(
                    "u₀ = {}, u₁ = {}, θ₀ = {}, θ_D = {}",
                    scenario.initial.displacement,
                    scenario.initial.velocity,
                    scenario.initial.temperature,
                    b.temperature
                ),
                "u₁ = 0 and θ₀ = θ_D (the exact initial data)",
            ),
            (
                "loads",
                no_loads,
                "non-zero affine loads".into(),
                "no affine loads (the exact solution supplies f₀, g and f₂)",
            ),
        ];
        if let Some((key, _, value, expected)) = checks.into_iter().find(|c| !c.1) {
            return Err(Error::InvalidValue {
                key: key.to_string(),
                value,
                expected: format!("{expected} for the manufactured solution"),
            });
        }
        let lengths = structured.map(|s| s.lengths).unwrap_or_default();
        Ok(Manufactured {
            lengths: [lengths[0], lengths[1]],
            slip_amplitude: 0.5,
            shear_amplitude: 0.2,
            normal_amplitude: 0.2,
            temperature_amplitude: 2.0,
            boundary_temperature: b.temperature,
            onset: [0.2, 0.8],
        })
    }

    /// τ_s(x) = t_R + (t_L − t_R)(1 − x/L₁), the time at which the point x of Γ_C starts to slip.
    pub fn slip_onset(&self, x: f64) -> f64 {
        self.onset[0] + (self.onset[1] - self.onset[0]) * (1.0 - x / self.lengths[0])
    }

    /// The exact fields and their derivatives at (x, y) and t.
    pub fn kinematics(&self, x: f64, y: f64, t: f64) -> Kinematics {
        let [l1, l2] = self.lengths;
        let (a, b, c, d) = (
            self.slip_amplitude,
            self.shear_amplitude,
            self.normal_amplitude,
            self.temperature_amplitude,
        );
        let xi = Jet::x(x) * (1.0 / l1);
        let eta = Jet::y(y) * (1.0 / l2);
        let onset = (-xi + 1.0) * (self.onset[1] - self.onset[0]) + self.onset[0];
        // t − τ_s(x) and its positive powers: s = (·)₊³, ṡ = 3(·)₊², s̈ = 6(·)₊.
        let lag = -onset + t;
        let s = lag.positive_part_pow(3);
        let s_rate = lag.positive_part_pow(2) * 3.0;
        let s_acc = 6.0 * lag.value.max(0.0);
        let shear = eta + 1.0;
        let sine = (xi * (0.5 * PI)).sin();
        let ux = xi * (shear * s * a + eta * (b * t * t));
        let wx = xi * (shear * s_rate * a + eta * (2.0 * b * t));
        let ax = xi.value * (shear.value * s_acc * a + eta.value * 2.0 * b);
        let uy = sine * eta * (c * t * t);
        let wy = sine * eta * (2.0 * c * t);
        let ay = sine.value * eta.value * 2.0 * c;
        let profile = (xi * PI).sin() * (eta * (0.5 * PI)).cos();
        Kinematics {
            u: [ux, uy],
            w: [wx, wy],
            acceleration: [ax, ay],
            theta: profile * (d * t) + self.boundary_temperature,
            theta_rate: profile.value * d,
        }
    }

    /// σ = 𝒜ε(w) + ℬε(u) + cθ I, eq. (1).
    pub fn stress(&self, problem: &Problem, k: &Kinematics) -> [[f64; 2]; 2] {
        let m = &problem.material;
        let law = |tensor: Isotropic, v: &[Jet; 2]| {
            let mut strain = [[0.0; 3]; 3];
            for i in 0..2 {
                for j in 0..2 {
                    strain[i][j] = 0.5 * (v[i].grad[j] + v[j].grad[i]);
                }
            }
            tensor.apply(2, &strain)
        };
        let (viscous, elastic) = (law(m.viscosity, &k.w), law(m.elasticity, &k.u));
        let mut sigma = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                sigma[i][j] = viscous[i][j] + elastic[i][j];
            }
            sigma[i][i] += m.expansion * k.theta.value;
        }
        sigma
    }

    /// f₀ = ρü − Div σ, eq. (2). For an isotropic (λ, 2μ):
    /// Div(λ tr ε(v) I + 2μ ε(v)) = (λ + μ) ∇div v + μ Δv.
    pub fn body_force(&self, problem: &Problem, x: [f64; 3], t: f64) -> [f64; 2] {
        let m = &problem.material;
        let k = self.kinematics(x[0], x[1], t);
        let div_of = |tensor: Isotropic, v: &[Jet; 2], i: usize| {
            let mu = 0.5 * tensor.two_mu;
            let grad_div = v[0].hess[i][0] + v[1].hess[i][1];
            (tensor.lambda + mu) * grad_div + mu * v[i].laplacian()
        };
        let mut f = [0.0; 2];
        for (i, fi) in f.iter_mut().enumerate() {
            let div_sigma =
                div_of(m.viscosity, &k.w, i) + div_of(m.elasticity, &k.u, i) + m.expansion * k.theta.grad[i];
            *fi = m.density * k.acceleration[i] - div_sigma;
        }
        f
    }

    /// g = ρc_p θ̇ − div(K∇θ) − c div w, eq. (3).
    pub fn heat_source(&self, problem: &Problem, x: [f64; 3], t: f64) -> f64 {
        let m = &problem.material;
        let k = self.kinematics(x[0], x[1], t);
        let div_w = k.w[0].grad[0] + k.w[1].grad[1];
        m.density * m.heat_capacity * k.theta_rate - m.conductivity * k.theta.laplacian() - m.expansion * div_w
    }

    /// w_τ on Γ_C at x and t (tangent τ of the bottom face).
    fn slip_rate(&self, _problem: &Problem, k: &Kinematics) -> f64 {
        CONTACT_TANGENT[0] * k.w[0].value + CONTACT_TANGENT[1] * k.w[1].value
    }

    /// ξ*, the exact friction stress on Γ_C: −μ(|w_τ|)S sgn w_τ in slip, and in stick a value
    /// inside the disc that reaches −μ(0)S sgn A at the onset of slip.
    pub fn friction_stress(&self, problem: &Problem, x: f64, slip_rate: f64, t: f64) -> f64 {
        if slip_rate != 0.0 {
            -problem.friction_bound([x, 0.0, 0.0], t, slip_rate.abs()) * slip_rate.signum()
        } else {
            let ramp = (t / self.slip_onset(x)).min(1.0);
            -problem.friction_bound([x, 0.0, 0.0], t, 0.0) * ramp * ramp * self.slip_amplitude.signum()
        }
    }

    /// f_C = σν − ξ* τ on Γ_C: the known load that makes the exact traction obey the law.
    pub fn contact_load(&self, problem: &Problem, x: [f64; 3], t: f64) -> [f64; 2] {
        let k = self.kinematics(x[0], x[1], t);
        let (normal, tangent) = (CONTACT_NORMAL, CONTACT_TANGENT);
        let traction = apply(&self.stress(problem, &k), normal);
        let xi = self.friction_stress(problem, x[0], self.slip_rate(problem, &k), t);
        [traction[0] - xi * tangent[0], traction[1] - xi * tangent[1]]
    }

    /// g_C = K∇θ·ν + ∂j(θ) − h_τ(t, |w_τ|) on Γ_C: the known heat flux that makes (9) exact.
    pub fn contact_heat_flux(&self, problem: &Problem, x: [f64; 3], t: f64) -> f64 {
        let k = self.kinematics(x[0], x[1], t);
        let normal = CONTACT_NORMAL;
        let flux = problem.material.conductivity * (k.theta.grad[0] * normal[0] + k.theta.grad[1] * normal[1]);
        let at = crate::contact::LawPoint {
            x,
            t,
            slip_distance: 0.0,
        };
        let heating = &problem.heating;
        let heat = heating.share * heating.law.heat(&at, self.slip_rate(problem, &k).abs());
        flux + problem.exchange.flux(&at, k.theta.value) - heat
    }
}

/// The frame of the family's Γ_C, the bottom face y = 0: outward normal ν = (0, −1) and the
/// tangent the contact frames give it (ν turned by +90°, [`crate::contact::frames`]).
const CONTACT_NORMAL: [f64; 2] = [0.0, -1.0];
const CONTACT_TANGENT: [f64; 2] = [1.0, 0.0];

fn apply(sigma: &[[f64; 2]; 2], nu: [f64; 2]) -> [f64; 2] {
    [
        sigma[0][0] * nu[0] + sigma[0][1] * nu[1],
        sigma[1][0] * nu[0] + sigma[1][1] * nu[1],
    ]
}

/// Outward unit normal of a rectangle part.
fn outward_normal(part: &str) -> [f64; 2] {
    match part {
        "left" => [-1.0, 0.0],
        "right" => [1.0, 0.0],
        "bottom" => [0.0, -1.0],
        _ => [0.0, 1.0],
    }
}

impl ExactSolution for Manufactured {
    fn fields(&self, x: [f64; 3], t: f64) -> ExactFields {
        let k = self.kinematics(x[0], x[1], t);
        ExactFields {
            u: [k.u[0].value, k.u[1].value],
            grad_u: [k.u[0].grad, k.u[1].grad],
            w: [k.w[0].value, k.w[1].value],
            theta: k.theta.value,
            grad_theta: k.theta.grad,
        }
    }
}

impl ExtraLoads for Manufactured {
    fn add_force(&self, problem: &Problem, t: f64, force: &mut [f64]) {
        let mesh = &problem.mesh;
        quadrature::vector_body_load(mesh, |x| self.body_force(problem, x, t), force);
        for &part in &problem.parts.neumann {
            let normal = outward_normal(&mesh.part_names[part]);
            quadrature::vector_boundary_load(
                mesh,
                &[part],
                |x| apply(&self.stress(problem, &self.kinematics(x[0], x[1], t)), normal),
                force,
            );
        }
        quadrature::vector_boundary_load(
            mesh,
            &problem.parts.contact,
            |x| self.contact_load(problem, x, t),
            force,
        );
    }

    fn add_heat(&self, problem: &Problem, t: f64, heat: &mut [f64]) {
        let mesh = &problem.mesh;
        quadrature::scalar_body_load(mesh, |x| self.heat_source(problem, x, t), heat);
        quadrature::scalar_boundary_load(
            mesh,
            &problem.parts.contact,
            |x| self.contact_heat_flux(problem, x, t),
            heat,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setup() -> (Manufactured, Problem) {
        let scenario = Manufactured::scenario(&[]).unwrap();
        let exact = Manufactured::new(&scenario).unwrap();
        let problem = scenario.build().unwrap();
        (exact, problem)
    }

    /// The boundary and initial conditions hold exactly, and w_τ has a stick and a slip phase.
    #[test]
    fn exact_solution_satisfies_the_constraints() {
        let (m, _) = setup();
        let [l1, l2] = m.lengths;
        for &t in &[0.0, 0.3, 0.7, 1.0] {
            for i in 0..=8 {
                let s = i as f64 / 8.0;
                let left = m.kinematics(0.0, s * l2, t);
                assert_eq!([left.u[0].value, left.u[1].value], [0.0, 0.0]);
                assert!((left.theta.value - 5.0).abs() < 1e-14);
                let bottom = m.kinematics(s * l1, 0.0, t);
                assert_eq!(bottom.u[1].value, 0.0, "u_ν = 0 on Γ_C");
                assert_eq!(bottom.w[1].value, 0.0);
                for theta in [
                    m.kinematics(l1, s * l2, t).theta.value,
                    m.kinematics(s * l1, l2, t).theta.value,
                ] {
                    assert!((theta - 5.0).abs() < 1e-12, "θ = θ_D on Γ_N");
                }
            }
        }
        let start = m.kinematics(2.5, 0.4, 0.0);
        assert_eq!(start.u[0].value, 0.0);
        assert_eq!(start.w[0].value, 0.0);
        assert_eq!(start.theta.value, 5.0);
        // At x = 3: onset 0.35. Stick before, slip after.
        assert_eq!(m.kinematics(3.0, 0.0, 0.3).w[0].value, 0.0);
        assert!(m.kinematics(3.0, 0.0, 0.5).w[0].value > 0.0);
    }

    /// The friction stress obeys the nodal law −ξ* ∈ ∂j_τ(w_τ), continuously at slip onset.
    #[test]
    fn friction_stress_is_a_selection_of_the_law() {
        let (m, p) = setup();
        let law = |r: f64| p.friction_bound([0.0; 3], 0.0, r);
        for (x, t) in [(3.0, 0.2), (3.0, 0.349), (3.0, 0.36), (1.0, 0.9), (3.9, 1.0)] {
            let w = m.kinematics(x, 0.0, t).w[0].value;
            let xi = m.friction_stress(&p, x, w, t);
            let r = crate::contact::friction::law_residual(law, &[w], &[xi], 0.0);
            assert!(r < 1e-12, "law residual {r} at x = {x}, t = {t}");
        }
        let before = m.friction_stress(&p, 3.0, 0.0, 0.35 - 1e-9);
        let after_w = m.kinematics(3.0, 0.0, 0.35 + 1e-6).w[0].value;
        let after = m.friction_stress(&p, 3.0, after_w, 0.35 + 1e-6);
        assert!((before - after).abs() < 1e-5, "{before} vs {after}");
    }

    /// f₀ = ρü − Div σ, checked independently of the jets' Hessians with central differences
    /// of σ (which uses first derivatives only).
    #[test]
    fn body_force_matches_a_finite_difference_divergence() {
        let (m, p) = setup();
        let (x, y, t, h) = (2.7, 0.45, 0.8, 1e-5);
        let sigma = |x: f64, y: f64| m.stress(&p, &m.kinematics(x, y, t));
        let f = m.body_force(&p, [x, y, 0.0], t);
        let k = m.kinematics(x, y, t);
        for i in 0..2 {
            let div = (sigma(x + h, y)[i][0] - sigma(x - h, y)[i][0]) / (2.0 * h)
                + (sigma(x, y + h)[i][1] - sigma(x, y - h)[i][1]) / (2.0 * h);
            let expected = p.material.density * k.acceleration[i] - div;
            assert!(
                (f[i] - expected).abs() < 1e-5 * (1.0 + expected.abs()),
                "{f:?} vs {expected}"
            );
        }
        // ü by differences of u̇.
        let dt = 1e-5;
        let a_fd = (m.kinematics(x, y, t + dt).w[0].value - m.kinematics(x, y, t - dt).w[0].value) / (2.0 * dt);
        assert!((a_fd - k.acceleration[0]).abs() < 1e-6);
    }

    #[test]
    fn other_layouts_are_rejected_by_name() {
        let s = Manufactured::scenario(&[
            "boundary.contact=[\"bottom\", \"top\"]".into(),
            "boundary.neumann=[\"right\"]".into(),
        ])
        .unwrap();
        let err = Manufactured::new(&s).unwrap_err().to_string();
        assert!(err.contains("boundary.neumann"), "{err}");
        let s = Manufactured::scenario(&["initial.temperature=25.0".into()]).unwrap();
        assert!(Manufactured::new(&s).is_err());
    }
}
