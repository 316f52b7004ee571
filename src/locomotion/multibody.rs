//! The zero-moment point of the whole body along a planned motion: what the cart-table model
//! leaves out (the swing leg's and the arms' momentum, the torso's lean, the CoM's vertical
//! motion), measured on the joint angles the solver produced.
//!
//! # Maths
//!
//! Each tick the model stands on a sole fixed in the world (the root, at `ʷT_b`). With `A_O` the
//! angular-momentum Jacobian about the base origin and `J_c` the CoM's (base axes), the whole
//! body's angular momentum about the **world** origin over the tick from `q_{k−1}` to `q_k` is
//!
//! ```text
//! H_{k−½} = R A_O(q_k) q̇ + o × R m J_c(q_k) q̇,    q̇ = (q_k − q_{k−1}) / Δt
//! ```
//!
//! (`R`, `o` the base's world rotation and origin: the base does not move while it is the root,
//! and a root changes only in double support, when both soles stand). Its rate is the moment of
//! the external forces about the world origin: gravity's at the CoM `c` and the floor's, whose
//! moment about the ZMP `p` (on the floor, z = 0) has no horizontal part. With the floor's
//! vertical force `F_z = m (g + c̈_z)`,
//!
//! ```text
//! p_x = (m g c_x − Ḣ_y) / F_z,    p_y = (m g c_y + Ḣ_x) / F_z
//! ```
//!
//! with `Ḣ_k = (H_{k+½} − H_{k−½}) / Δt` and `c̈_k = (c_{k+1} − 2 c_k + c_{k−1}) / Δt²`: the
//! ZMP of tick `k` is known one tick later. For a CoM at a constant height and no angular
//! momentum this is the cart-table's `c − (z_c / g) c̈`.
//!
//! Units: metres, seconds, kilograms.

use faer::Mat;
use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use super::LocomotionError;
use super::preview::{GRAVITY, positive};
use crate::model::{Model, ModelData, ModelError};

/// The whole-body ZMP of a motion fed one tick at a time (module docs). Allocates in
/// [`MultibodyZmp::new`] only.
#[derive(Debug, Clone)]
pub struct MultibodyZmp {
    dt: f64,
    mass: f64,
    momentum: Mat<f64>,
    com_jacobian: Mat<f64>,
    previous_q: Vec<f64>,
    /// World CoM of ticks `k−2, k−1, k` (oldest first).
    com: [Vector3<f64>; 3],
    /// World angular momentum about the origin over the ticks ending at `k−1` and `k`.
    momentum_world: [Vector3<f64>; 2],
    samples: usize,
}

impl MultibodyZmp {
    /// An estimator for motions of `model` (or a model of the same joints rooted elsewhere)
    /// sampled every `dt` s.
    ///
    /// # Errors
    /// [`LocomotionError::InvalidParameter`] for a `dt` that is not finite and > 0 or a
    /// massless model.
    pub fn new(model: &Model, dt: f64) -> Result<Self, LocomotionError> {
        positive("dt", dt)?;
        positive("model mass", model.total_mass())?;
        let n = model.nv();
        Ok(Self {
            dt,
            mass: model.total_mass(),
            momentum: Mat::zeros(3, n),
            com_jacobian: Mat::zeros(3, n),
            previous_q: vec![0.0; n],
            com: [Vector3::zeros(); 3],
            momentum_world: [Vector3::zeros(); 2],
            samples: 0,
        })
    }

    /// Adds tick `k`: the posture `q` (rad, model variable order) of `model`, whose forward
    /// kinematics `data` holds, its base at `base` in the world. Returns the ZMP of tick `k − 1`
    /// (world, m) once three ticks are in.
    ///
    /// # Errors
    /// [`ModelError`] when `data` is not computed or `q` has the wrong length.
    pub fn push(
        &mut self,
        model: &Model,
        data: &ModelData,
        base: &IsometryMatrix3<f64>,
        q: &[f64],
    ) -> Result<Option<Vector2<f64>>, ModelError> {
        if q.len() != self.previous_q.len() {
            return Err(ModelError::WrongQLength {
                expected: self.previous_q.len(),
                got: q.len(),
            });
        }
        let com = base * nalgebra::Point3::from(model.com(data)?);
        self.com = [self.com[1], self.com[2], com.coords];
        if self.samples > 0 {
            model.angular_momentum_jacobian(data, self.momentum.as_mut())?;
            model.com_jacobian(data, self.com_jacobian.as_mut())?;
            let (mut h, mut p) = (Vector3::zeros(), Vector3::zeros());
            for (k, (now, before)) in q.iter().zip(&self.previous_q).enumerate() {
                let rate = (now - before) / self.dt;
                for r in 0..3 {
                    h[r] += self.momentum[(r, k)] * rate;
                    p[r] += self.com_jacobian[(r, k)] * rate * self.mass;
                }
            }
            let rotation = base.rotation;
            let origin = base.translation.vector;
            let h_world = rotation * h + origin.cross(&(rotation * p));
            self.momentum_world = [self.momentum_world[1], h_world];
        }
        self.previous_q.copy_from_slice(q);
        self.samples += 1;
        if self.samples < 3 {
            return Ok(None);
        }
        let [before, at, after] = self.com;
        let acceleration = (after - 2.0 * at + before) / (self.dt * self.dt);
        let rate = (self.momentum_world[1] - self.momentum_world[0]) / self.dt;
        let weight = self.mass * GRAVITY;
        let vertical = self.mass * (GRAVITY + acceleration.z);
        Ok(Some(Vector2::new(
            (weight * at.x - rate.y) / vertical,
            (weight * at.y + rate.x) / vertical,
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::human::Side;
    use crate::robots::nao;

    /// A still posture: the ZMP is the CoM's ground point.
    #[test]
    fn still_posture_puts_the_zmp_under_the_com() {
        let profile = nao::profile();
        let model = profile.model(Side::Right);
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, &profile.stand).unwrap();
        let base = IsometryMatrix3::translation(0.3, -0.1, 0.0);
        let mut zmp = MultibodyZmp::new(model, 0.01).unwrap();
        let mut last = None;
        for _ in 0..4 {
            last = zmp.push(model, &data, &base, &profile.stand).unwrap();
        }
        let com = model.com(&data).unwrap();
        let p = last.unwrap();
        assert!((p.x - (com.x + 0.3)).abs() < 1e-12 && (p.y - (com.y - 0.1)).abs() < 1e-12);
    }

    /// A tick that is not a positive time is refused, not divided by.
    #[test]
    fn a_bad_tick_is_refused() {
        let profile = nao::profile();
        let model = profile.model(Side::Right);
        for dt in [0.0, -0.01, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                MultibodyZmp::new(model, dt),
                Err(LocomotionError::InvalidParameter { name: "dt", .. })
            ));
        }
    }
}
