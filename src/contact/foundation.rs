//! The foundation's motion: the velocity v_F(x, t) of the rigid counter-face that Γ_C slides
//! on (a conveyor or an imposed plate rate, a rotating disc or drum).
//!
//! Friction and frictional heating act on the **relative slip** w_τ − v_F,τ (MODEL.md §6):
//!
//! ```text
//! −ξ_i ∈ ∂j_τ(w_τ,i − v_F,τ,i),   heat h_τ(|w_τ,i − v_F,τ,i|),   stick: w_τ,i = v_F,τ,i
//! ```
//!
//! with v_F,τ,i the tangential part of v_F(x_i, t_n) in contact node i's frame. The normal part
//! of v_F is not used: the contact is bilateral (w·ν = 0), so a foundation that moves along its
//! own surface (a disc about its axis, a belt along itself) is what the model describes; a
//! normal part would be a foundation moving into or away from the body. v_F = 0 is the paper.
//!
//! Depends on: [`crate::loads`] (the data of x and t).

use crate::loads::Datum;

/// How the foundation moves.
#[derive(Debug, Clone, PartialEq)]
pub enum Foundation {
    /// v_F(x, t) as a datum of d components (constant, affine in t, or expressions of
    /// x, y, z, t).
    Velocity(Datum),
    /// A rigid rotation about an axis through `point` with angular velocity ω(t) (a scalar
    /// datum): v_F(x) = ω a × (x − c). In 2D the axis is e_z (`axis` is ignored); ω > 0 turns
    /// counter-clockwise.
    Rotation {
        /// c, a point on the axis (2D: the centre).
        point: [f64; 3],
        /// a, the unit axis (3D).
        axis: [f64; 3],
        /// ω(t) in rad/s.
        angular_velocity: Datum,
    },
}

impl Foundation {
    /// A rotation about `axis` (normalized here) through `point`; a zero axis is `None`.
    pub fn rotation(point: [f64; 3], axis: [f64; 3], angular_velocity: Datum) -> Option<Foundation> {
        let length = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        (length > 0.0 && length.is_finite()).then(|| Foundation::Rotation {
            point,
            axis: axis.map(|a| a / length),
            angular_velocity,
        })
    }

    /// v_F(x, t) in global components (the first `dim` used).
    pub fn velocity(&self, dim: usize, x: [f64; 3], t: f64) -> [f64; 3] {
        match self {
            Foundation::Velocity(datum) => {
                let mut v = [0.0; 3];
                datum.eval(x, t, &mut v[..dim]);
                v
            }
            Foundation::Rotation {
                point,
                axis,
                angular_velocity,
            } => {
                let mut omega = [0.0];
                angular_velocity.eval(x, t, &mut omega);
                let r = [x[0] - point[0], x[1] - point[1], x[2] - point[2]];
                let a = if dim == 2 { [0.0, 0.0, 1.0] } else { *axis };
                let cross = [
                    a[1] * r[2] - a[2] * r[1],
                    a[2] * r[0] - a[0] * r[2],
                    a[0] * r[1] - a[1] * r[0],
                ];
                let mut v = cross.map(|c| omega[0] * c);
                if dim == 2 {
                    v[2] = 0.0;
                }
                v
            }
        }
    }

    /// The number of components its datum must have in dimension `dim`.
    pub fn components(&self, dim: usize) -> usize {
        match self {
            Foundation::Velocity(_) => dim,
            Foundation::Rotation { .. } => 1,
        }
    }

    /// The datum (v_F or ω).
    pub fn datum(&self) -> &Datum {
        match self {
            Foundation::Velocity(datum) => datum,
            Foundation::Rotation { angular_velocity, .. } => angular_velocity,
        }
    }
}

/// How the friction bound scales: by a prescribed datum S (the paper's μ(r)S), or by the
/// contact pressure p (Coulomb: μ(r)p).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum NormalForce {
    /// b(r) = μ(r) S(x, t).
    #[default]
    Prescribed,
    /// b(r) = μ(r) p_i with p_i = max(0, −σ_ν) the contact pressure at node i from the
    /// reaction of the bilateral constraint (`crate::model::ContactPressure`). Where the
    /// constraint pulls (tension, σ_ν > 0) p = 0: no friction, and the bilateral contact still
    /// holds the node (no lift-off).
    Reaction,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rotation_moves_points_along_circles_at_radius_times_omega() {
        let disc = Foundation::rotation([1.0, 2.0, 0.0], [0.0, 0.0, 7.0], Datum::scalar(3.0)).unwrap();
        // 2D: x − c = (0, −1): ω e_z × (0, −1) = ω (1, 0).
        let v = disc.velocity(2, [1.0, 1.0, 0.0], 0.0);
        assert_eq!(v, [3.0, 0.0, 0.0]);
        // 3D about e_z: the same, and a point on the axis is at rest.
        assert_eq!(disc.velocity(3, [1.0, 1.0, 5.0], 0.0), [3.0, 0.0, 0.0]);
        assert_eq!(disc.velocity(3, [1.0, 2.0, -4.0], 0.0), [0.0, 0.0, 0.0]);
        // About e_x through the origin: x = (0, 0, 2) moves along −y at 2ω.
        let drum = Foundation::rotation([0.0; 3], [2.0, 0.0, 0.0], Datum::affine(vec![0.0], vec![1.0])).unwrap();
        let v = drum.velocity(3, [0.0, 0.0, 2.0], 0.5);
        assert!((v[1] + 1.0).abs() < 1e-15 && v[0] == 0.0 && v[2] == 0.0, "{v:?}");
        assert!(Foundation::rotation([0.0; 3], [0.0; 3], Datum::scalar(1.0)).is_none());
    }

    #[test]
    fn a_velocity_datum_is_evaluated_at_x_and_t() {
        let belt = Foundation::Velocity(Datum::expressions(&["10*(1 - t)", "x"]).unwrap());
        assert_eq!(belt.velocity(2, [0.5, 0.0, 0.0], 0.25), [7.5, 0.5, 0.0]);
    }
}
