//! The NAO's human joint angles (Poubel eq. 8): the reference of the joint-tracking gradient,
//! from the human's segment directions ([`SegmentDirections`]). NAO conventions, checked against
//! the model's forward kinematics in `tests/suite/imitation_scaler.rs`.
//!
//! Directions are taken in the human **torso frame** `T`: `z_T` along MidHip→MidShoulder, `y_T`
//! the shoulder line (right→left) made orthogonal to `z_T`, `x_T = y_T × z_T`. NAO's torso is
//! rigid with its hips and shoulders, so for the robot this is exactly its torso frame.
//! `u` = shoulder→elbow, `f` = elbow→wrist, `t` = hip→knee, `s` = knee→ankle (unit, in `T`);
//! `δ` = the angle of NAO's shoulder→elbow vector in the reference posture (the elbow sits
//! 15 mm outward of the shoulder-roll axis: `δ = atan2(±0.015, 0.105)`).
//!
//! | variable | formula | observable from positions |
//! |---|---|---|
//! | ShoulderPitch | `atan2(−u_z, u_x)` | yes |
//! | ShoulderRoll | `atan2(u_y, √(u_x²+u_z²)) − δ` | yes |
//! | ElbowRoll | `∓ atan2(|f'_yz|, f'_x)`, `f' = A⁻¹f`, `A = R_y(pitch)·R_z(roll)` (− left, + right) | yes |
//! | ElbowYaw | left `atan2(−f'_z, −f'_y)`, right `atan2(f'_z, f'_y)` | if the elbow is bent |
//! | HipRoll | `atan2(t_y, −t_z)` | yes if HipYawPitch = 0 |
//! | HipPitch | `atan2(−t_x, √(t_y²+t_z²))` | yes if HipYawPitch = 0 |
//! | KneePitch | `±atan2(|t×s|, t·s)`, sign of `(t×s)·y` | yes |
//! | AnklePitch | `atan2(n_x, n_z)`, `n = (R_x(hr)·R_y(hp+kp))⁻¹·z_world` | no: sole kept parallel to the ground |
//! | AnkleRoll | `atan2(−n_y, √(n_x²+n_z²))` | no: same |
//! | HeadPitch | `atan2(h_x, h_z)`, `h` = Neck→Head in `T` | roughly |
//! | HeadYaw, HipYawPitch, WristYaw | 0 | no |
//!
//! Angles are clipped to the model's limits. Where an angle is undefined (arm along the
//! shoulder-roll axis, straight elbow for ElbowYaw, thigh horizontal for HipRoll) the previous
//! value is kept (0 at first). NAO's forearm at ElbowRoll = 0 is parallel to the upper-arm
//! frame, which is turned by `δ` from shoulder→elbow, so a straight human arm gives
//! |ElbowRoll| = |δ| = 0.1419 (exactly what the robot's own straight-looking arm has). The ankles are not observable: the human ankle and toe points say
//! little about the sole's orientation, so the ankles keep the robot's sole level.

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::human::{HumanJoint, SegmentDirections, Side};
use crate::model::Model;
use crate::robots::ProfileError;
use crate::robots::profile::HumanJointAngles;

/// `v / |v|` if `|v| > min` (and finite).
fn unit(v: Vector3<f64>, min: f64) -> Option<Vector3<f64>> {
    let n = v.norm();
    (n.is_finite() && n > min && n > 0.0).then(|| v / n)
}

/// Human joint angles for the NAO joint-tracking task (eq. 8): the mapping of the module docs'
/// table, in the model's variable order, clipped to its limits. Keeps the previous angles where
/// they are undefined; [`JointAngles::compute`] never allocates.
#[derive(Clone, Debug)]
pub struct JointAngles {
    /// Indices in `q` of the angles set, in [`NaoIndex`] order.
    index: [usize; NaoIndex::COUNT],
    lower: [f64; NaoIndex::COUNT],
    upper: [f64; NaoIndex::COUNT],
    nv: usize,
    /// Shoulder→elbow angle offset in the reference posture (left, right), radians.
    delta: [f64; 2],
    /// Previous unclipped angles.
    previous: [f64; NaoIndex::COUNT],
}

/// The NAO variables [`JointAngles`] sets (the others are set to 0, clipped).
#[derive(Clone, Copy, Debug)]
enum NaoIndex {
    HeadPitch,
    ShoulderPitch(Side),
    ShoulderRoll(Side),
    ElbowYaw(Side),
    ElbowRoll(Side),
    HipRoll(Side),
    HipPitch(Side),
    KneePitch(Side),
    AnklePitch(Side),
    AnkleRoll(Side),
}

impl NaoIndex {
    const COUNT: usize = 19;
    const PER_SIDE: [fn(Side) -> NaoIndex; 9] = [
        NaoIndex::ShoulderPitch,
        NaoIndex::ShoulderRoll,
        NaoIndex::ElbowYaw,
        NaoIndex::ElbowRoll,
        NaoIndex::HipRoll,
        NaoIndex::HipPitch,
        NaoIndex::KneePitch,
        NaoIndex::AnklePitch,
        NaoIndex::AnkleRoll,
    ];

    fn slot(self) -> usize {
        let (k, side) = match self {
            NaoIndex::HeadPitch => return 0,
            NaoIndex::ShoulderPitch(s) => (0, s),
            NaoIndex::ShoulderRoll(s) => (1, s),
            NaoIndex::ElbowYaw(s) => (2, s),
            NaoIndex::ElbowRoll(s) => (3, s),
            NaoIndex::HipRoll(s) => (4, s),
            NaoIndex::HipPitch(s) => (5, s),
            NaoIndex::KneePitch(s) => (6, s),
            NaoIndex::AnklePitch(s) => (7, s),
            NaoIndex::AnkleRoll(s) => (8, s),
        };
        1 + 9 * side.index() + k
    }

    fn name(self) -> String {
        let (part, side) = match self {
            NaoIndex::HeadPitch => return "HeadPitch".into(),
            NaoIndex::ShoulderPitch(s) => ("ShoulderPitch", s),
            NaoIndex::ShoulderRoll(s) => ("ShoulderRoll", s),
            NaoIndex::ElbowYaw(s) => ("ElbowYaw", s),
            NaoIndex::ElbowRoll(s) => ("ElbowRoll", s),
            NaoIndex::HipRoll(s) => ("HipRoll", s),
            NaoIndex::HipPitch(s) => ("HipPitch", s),
            NaoIndex::KneePitch(s) => ("KneePitch", s),
            NaoIndex::AnklePitch(s) => ("AnklePitch", s),
            NaoIndex::AnkleRoll(s) => ("AnkleRoll", s),
        };
        format!("{}{part}", if side == Side::Left { "L" } else { "R" })
    }

    fn all() -> impl Iterator<Item = NaoIndex> {
        std::iter::once(NaoIndex::HeadPitch).chain(
            [Side::Left, Side::Right]
                .into_iter()
                .flat_map(|s| NaoIndex::PER_SIDE.into_iter().map(move |f| f(s))),
        )
    }
}

/// An orthonormal frame (columns x, y, z) with `z` along `z_hint` and `y` closest to `y_hint`;
/// falls back to the output frame's axes for degenerate hints.
fn torso_frame(z_hint: Vector3<f64>, y_hint: Vector3<f64>) -> Matrix3<f64> {
    let z = unit(z_hint, 1e-12).unwrap_or_else(Vector3::z);
    let y = [y_hint, Vector3::y(), Vector3::x()]
        .into_iter()
        .find_map(|h| unit(h - h.dot(&z) * z, 1e-9))
        .unwrap_or_else(Vector3::y);
    Matrix3::from_columns(&[y.cross(&z), y, z])
}

impl JointAngles {
    /// The mapping for a NAO `model` (any root; variables named as in `nao::VARIABLES`, frames
    /// `l/r_shoulder`, `l/r_elbow`). Errors name the missing variable or frame.
    pub fn new(model: &Model) -> Result<Self, ProfileError> {
        let mut index = [0; NaoIndex::COUNT];
        let mut lower = [0.0; NaoIndex::COUNT];
        let mut upper = [0.0; NaoIndex::COUNT];
        for v in NaoIndex::all() {
            let i = model.variable_index(&v.name())?;
            index[v.slot()] = i;
            lower[v.slot()] = model.variables()[i].lower;
            upper[v.slot()] = model.variables()[i].upper;
        }
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, &vec![0.0; model.nv()])?;
        let mut delta = [0.0; 2];
        for (side, (shoulder, elbow)) in [
            (Side::Left, ("l_shoulder", "l_elbow")),
            (Side::Right, ("r_shoulder", "r_elbow")),
        ] {
            let ps = data.frame_placement(model.frame_id(shoulder)?);
            let pe = data.frame_placement(model.frame_id(elbow)?);
            // At q = 0 the arm points along the shoulder frame's x (NAO convention).
            let u = ps.rotation.inverse() * (pe.translation.vector - ps.translation.vector);
            delta[side.index()] = u.y.atan2(u.x);
        }
        Ok(JointAngles {
            index,
            lower,
            upper,
            nv: model.nv(),
            delta,
            previous: [0.0; NaoIndex::COUNT],
        })
    }

    /// [`JointAngles::new`] boxed: the NAO profile's [`crate::robots::JointAnglesFactory`].
    pub fn boxed(model: &Model) -> Result<Box<dyn HumanJointAngles>, ProfileError> {
        Ok(Box::new(JointAngles::new(model)?))
    }
}

impl HumanJointAngles for JointAngles {
    // One function on purpose (~95 lines): one block per NAO chain (head, each arm, each leg),
    // each the closed-form angles of that chain from the human's segment directions, in the
    // order of the variables; the blocks share the torso frame and the keep-last rule.
    fn compute(
        &mut self,
        directions: &SegmentDirections,
        q: &mut [f64],
    ) -> Result<(), ProfileError> {
        if q.len() != self.nv {
            return Err(ProfileError::WrongLength {
                expected: self.nv,
                got: q.len(),
            });
        }
        use HumanJoint::*;
        let d = |j: HumanJoint| directions.get(j).unwrap_or_else(Vector3::zeros);
        let torso = torso_frame(d(MidShoulder), d(LShoulder));
        let to_torso = torso.transpose();
        let up = to_torso * Vector3::z();
        let mut a = self.previous;
        fn keep(a: &mut [f64; NaoIndex::COUNT], slot: NaoIndex, value: Option<f64>) {
            if let Some(v) = value.filter(|v| v.is_finite()) {
                a[slot.slot()] = v;
            }
        }
        let defined = |n: f64| (n > 1e-9).then_some(());
        let head = to_torso * d(Head);
        keep(&mut a, NaoIndex::HeadPitch, Some(head.x.atan2(head.z)));
        for side in [Side::Left, Side::Right] {
            let (elbow, wrist) = match side {
                Side::Left => (LElbow, LWrist),
                Side::Right => (RElbow, RWrist),
            };
            let sign = if side == Side::Left { -1.0 } else { 1.0 };
            let u = to_torso * d(elbow);
            let f = to_torso * d(wrist);
            let u_xz = u.x.hypot(u.z);
            keep(
                &mut a,
                NaoIndex::ShoulderPitch(side),
                defined(u_xz).map(|_| (-u.z).atan2(u.x)),
            );
            keep(
                &mut a,
                NaoIndex::ShoulderRoll(side),
                Some(u.y.atan2(u_xz) - self.delta[side.index()]),
            );
            let pitch = a[NaoIndex::ShoulderPitch(side).slot()];
            let roll = a[NaoIndex::ShoulderRoll(side).slot()];
            let arm = Rotation3::from_axis_angle(&Vector3::y_axis(), pitch)
                * Rotation3::from_axis_angle(&Vector3::z_axis(), roll);
            let fl = arm.inverse() * f;
            let f_yz = fl.y.hypot(fl.z);
            keep(
                &mut a,
                NaoIndex::ElbowRoll(side),
                Some(sign * f_yz.atan2(fl.x)),
            );
            keep(
                &mut a,
                NaoIndex::ElbowYaw(side),
                defined(f_yz).map(|_| (sign * fl.z).atan2(sign * fl.y)),
            );

            let t = to_torso * d(side.knee());
            let s = to_torso * d(side.ankle());
            let t_yz = t.y.hypot(t.z);
            keep(
                &mut a,
                NaoIndex::HipRoll(side),
                defined(t_yz).map(|_| t.y.atan2(-t.z)),
            );
            keep(&mut a, NaoIndex::HipPitch(side), Some((-t.x).atan2(t_yz)));
            let hr = a[NaoIndex::HipRoll(side).slot()];
            let hp = a[NaoIndex::HipPitch(side).slot()];
            // The knee axis is within 90° of the torso's y axis for every hip angle within NAO's
            // limits (HipYawPitch turns it at most 0.71 rad), so `t × s` along +y is flexion.
            let cross = t.cross(&s);
            let bend = cross.norm().atan2(t.dot(&s));
            let kp = if cross.y < 0.0 { -bend } else { bend };
            keep(&mut a, NaoIndex::KneePitch(side), Some(kp));
            let shank = Rotation3::from_axis_angle(&Vector3::x_axis(), hr)
                * Rotation3::from_axis_angle(&Vector3::y_axis(), hp + kp);
            let n = shank.inverse() * up;
            keep(&mut a, NaoIndex::AnklePitch(side), Some(n.x.atan2(n.z)));
            keep(
                &mut a,
                NaoIndex::AnkleRoll(side),
                Some((-n.y).atan2(n.x.hypot(n.z))),
            );
        }
        self.previous = a;
        // HeadYaw, HipYawPitch and WristYaw: 0 (inside the NAO's limits).
        q.fill(0.0);
        for slot in 0..NaoIndex::COUNT {
            q[self.index[slot]] = a[slot].clamp(self.lower[slot], self.upper[slot]);
        }
        Ok(())
    }
}
