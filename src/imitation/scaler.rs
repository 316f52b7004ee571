//! Segment-by-segment scaling of the human skeleton to the robot's dimensions (Poubel §II.A,
//! eq. 1, and §III.A), and the human joint angles of the joint-tracking task (eq. 8).
//!
//! # Eq. (1)
//!
//! For every robot point `ℓ` with robot antecedent `a` (the nearest ancestor of `ℓ` in the human
//! segment tree of [`HumanJoint::antecedent`] that the robot also has):
//!
//! ```text
//! p_ℓ^r = p_a^r + L_ℓ^r · (p_ℓ^h − p_a^h) / |p_ℓ^h − p_a^h|
//! ```
//!
//! with `L_ℓ^r = |p_ℓ^r − p_a^r|` measured on the robot model in a reference posture
//! ([`RobotSkeleton`]). The walk starts at a point fixed to the ground and goes up the tree; the
//! edges between the start and the root (MidHip) are walked backwards (`p_a = p_ℓ − L·d`).
//!
//! * **Pairs on the mid-line.** A left/right pair hanging from the same mid-line joint (hips from
//!   MidHip, shoulders from MidShoulder) is placed symmetrically along the human's left−right
//!   line `d = (p_L^h − p_R^h)/|…|`: `p_L = p_a + L_L·d`, `p_R = p_a − L_R·d`. With the trunk one
//!   rigid MidHip→MidShoulder segment this is Poubel's symmetric rigid trunk.
//! * **Single support** (right or left): the support ankle is fixed at its place above the support
//!   sole (`(0, 0, 0.04511)` for the NAO); the support leg is walked backwards to MidHip, then
//!   everything else forwards. The free leg hangs from its hip by eq. (1).
//! * **Double support**: both feet are on the ground, flat. The right sole is the origin; the left
//!   sole's placement is decided when double support *starts* (a foot being put down, or the first
//!   frame) and kept until it ends, since a robot foot on the ground does not slide: its horizontal
//!   position relative to the other sole is the human's ankle-to-ankle vector times `k`, the ratio
//!   of the robot's leg length (hip→knee→ankle) to the human's, clipped to [`FootArea`]; its yaw is
//!   the human's relative foot heading clipped to `±yaw_max`. The legs' closed loop is one segment
//!   from the mid-ankle point to MidHip (robot length measured in the reference posture, direction
//!   the human's), then the hips by the pair rule. **Knees**: each knee is placed from its hip
//!   along the human's thigh direction with the robot's thigh length; the shank then closes the
//!   loop to the fixed ankle and has, in general, neither the robot's length nor the human's
//!   direction (knees are not tracked by the IK; the joint-angle task uses the human directions).
//! * **Flat feet**: a foot on the ground (support foot, both feet in double support) has its toe at
//!   the robot's reference toe offset, rotated by the foot's yaw, not along the human's
//!   ankle→toe direction.
//!
//! # Output frame and heading
//!
//! Points are in metres in the **support sole frame** of the robot: the right sole for right and
//! double support, the left sole for left support (the base frame of `nao::rfoot()` or
//! `nao::lfoot()`), z up. Its x axis is the horizontal projection of the human's support-foot
//! ankle→toe direction: the human foot is what the robot's support sole stands for, so the
//! robot's torso keeps the human's yaw relative to the foot it stands on. When that projection is
//! shorter than [`ScaleConfig::min_segment`] or the toe is missing, the heading is the pelvis
//! heading `(p_LHip − p_RHip) × z` (horizontal), else the previous frame's heading (0 at first).
//!
//! # Missing and zero-length segments
//!
//! A human segment with a missing end or shorter than [`ScaleConfig::min_segment`] keeps the
//! previous frame's direction; before any, the robot's own reference direction. So the output is
//! always complete and finite.
//!
//! # Joint angles ([`NaoJointAngles`]; NAO conventions, checked against the model's FK)
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

use nalgebra::{Matrix3, Rotation3, Vector2, Vector3};
use thiserror::Error;

use super::human::{HumanFrame, HumanJoint};
use super::support::{HumanSupport, Side};
use crate::model::{Model, ModelError};

const COUNT: usize = HumanJoint::COUNT;

/// Errors of the scaler and the joint-angle mapping.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ScaleError {
    /// A frame, a variable or `q` of the robot model is wrong (names the frame or variable).
    #[error("robot model: {0}")]
    Model(#[from] ModelError),
    /// The mapping has no robot point for a joint the scaler needs.
    #[error("the robot mapping has no point for human joint {0}, which the scaler needs")]
    MissingJoint(&'static str),
    /// The mapping gives two robot points for one human joint.
    #[error("the robot mapping maps human joint {0} twice")]
    DuplicateJoint(&'static str),
    /// A configuration value is out of range (names the field).
    #[error("scaler configuration: {0}")]
    BadConfig(&'static str),
    /// The frame's time is NaN or infinite.
    #[error("frame time is not finite: {0}")]
    NonFiniteTime(f64),
    /// The output slice does not have one entry per model variable.
    #[error("joint-angle output has {got} entries, the model has {expected} variables")]
    WrongLength {
        /// Number of variables of the model.
        expected: usize,
        /// Length of the given slice.
        got: usize,
    },
}

/// A robot point that stands for a human joint: a named frame's origin, or the midpoint of two.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RobotPoint<'a> {
    /// Origin of the named frame.
    Frame(&'a str),
    /// Midpoint of the origins of two named frames.
    Midpoint(&'a str, &'a str),
}

/// Which robot point stands for which human joint, and the robot's sole frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RobotMapping<'a> {
    /// Human joint → robot point. MidHip, both hips, knees and ankles are required.
    pub points: &'a [(HumanJoint, RobotPoint<'a>)],
    /// Name of the right sole frame (the base of the right-support model; z up, x forward).
    pub right_sole: &'a str,
    /// Name of the left sole frame.
    pub left_sole: &'a str,
}

/// The NAO's mapping. Its `head` frame is the neck joint (HeadYaw/HeadPitch), so it stands for
/// the human Neck, and the `gaze` point for the Head. The NAO has no pelvis point apart from its
/// hips, so [`HumanJoint::Pelvis`] is not mapped.
pub const NAO_MAPPING: RobotMapping<'static> = RobotMapping {
    points: &[
        (HumanJoint::MidHip, RobotPoint::Midpoint("l_hip", "r_hip")),
        (HumanJoint::LHip, RobotPoint::Frame("l_hip")),
        (HumanJoint::RHip, RobotPoint::Frame("r_hip")),
        (HumanJoint::LKnee, RobotPoint::Frame("l_knee")),
        (HumanJoint::RKnee, RobotPoint::Frame("r_knee")),
        (HumanJoint::LAnkle, RobotPoint::Frame("l_ankle")),
        (HumanJoint::RAnkle, RobotPoint::Frame("r_ankle")),
        (HumanJoint::LToe, RobotPoint::Frame("l_toe")),
        (HumanJoint::RToe, RobotPoint::Frame("r_toe")),
        (
            HumanJoint::MidShoulder,
            RobotPoint::Midpoint("l_shoulder", "r_shoulder"),
        ),
        (HumanJoint::Neck, RobotPoint::Frame("head")),
        (HumanJoint::Head, RobotPoint::Frame("gaze")),
        (HumanJoint::LShoulder, RobotPoint::Frame("l_shoulder")),
        (HumanJoint::RShoulder, RobotPoint::Frame("r_shoulder")),
        (HumanJoint::LElbow, RobotPoint::Frame("l_elbow")),
        (HumanJoint::RElbow, RobotPoint::Frame("r_elbow")),
        (HumanJoint::LWrist, RobotPoint::Frame("l_wrist")),
        (HumanJoint::RWrist, RobotPoint::Frame("r_wrist")),
        (HumanJoint::LHand, RobotPoint::Frame("l_hand")),
        (HumanJoint::RHand, RobotPoint::Frame("r_hand")),
    ],
    right_sole: "r_sole",
    left_sole: "l_sole",
};

const fn side_index(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

const fn ankle(side: Side) -> HumanJoint {
    match side {
        Side::Left => HumanJoint::LAnkle,
        Side::Right => HumanJoint::RAnkle,
    }
}

const fn knee(side: Side) -> HumanJoint {
    match side {
        Side::Left => HumanJoint::LKnee,
        Side::Right => HumanJoint::RKnee,
    }
}

const fn hip(side: Side) -> HumanJoint {
    match side {
        Side::Left => HumanJoint::LHip,
        Side::Right => HumanJoint::RHip,
    }
}

const fn toe(side: Side) -> HumanJoint {
    match side {
        Side::Left => HumanJoint::LToe,
        Side::Right => HumanJoint::RToe,
    }
}

/// True for the left member of a left/right pair.
fn is_left(joint: HumanJoint) -> bool {
    joint.mirror() != joint && joint.name().starts_with('L')
}

/// Placement of a sole on the ground relative to another sole: horizontal position (metres) and
/// yaw (radians) in that sole's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolePlacement {
    /// x, y of the sole origin (metres).
    pub xy: Vector2<f64>,
    /// Rotation about z (radians).
    pub yaw: f64,
}

impl SolePlacement {
    fn rotation(&self) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Vector3::z_axis(), self.yaw)
    }

    /// The other sole seen from this one: the inverse rigid motion.
    fn inverse(&self) -> SolePlacement {
        let (s, c) = self.yaw.sin_cos();
        let xy = self.xy;
        SolePlacement {
            xy: Vector2::new(-(c * xy.x + s * xy.y), s * xy.x - c * xy.y),
            yaw: -self.yaw,
        }
    }
}

/// The robot's segment lengths and foot geometry, measured on a model in a reference posture.
///
/// Positions are in the model's base frame (metres). For each mapped joint its *robot
/// antecedent* is the nearest ancestor (in [`HumanJoint::antecedent`]) that is mapped too.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotSkeleton {
    reference: [Option<Vector3<f64>>; COUNT],
    antecedent: [Option<HumanJoint>; COUNT],
    length: [f64; COUNT],
    /// Mapped joints by depth in the tree (antecedents first), then the unmapped ones.
    order: [HumanJoint; COUNT],
    mapped: usize,
    /// Per side (left, right): ankle point in its own sole frame (metres).
    ankle_in_sole: [Vector3<f64>; 2],
    /// Per side: toe point in its own sole frame, if the toe is mapped.
    toe_in_sole: [Option<Vector3<f64>>; 2],
    /// Left sole in the right sole frame in the reference posture.
    left_in_right: SolePlacement,
    /// |MidHip − mid-ankle point| in the reference posture (metres).
    loop_length: f64,
    /// Mean of the two legs' hip→knee→ankle lengths (metres).
    leg_length: f64,
}

impl RobotSkeleton {
    /// Measures `model` at `q_reference` (one value per variable, radians) with `mapping`.
    /// Errors: unknown frame names, wrong or non-finite `q_reference`, a required joint (MidHip,
    /// hips, knees, ankles) unmapped, a joint mapped twice.
    pub fn new(
        model: &Model,
        mapping: &RobotMapping<'_>,
        q_reference: &[f64],
    ) -> Result<Self, ScaleError> {
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, q_reference)?;
        let origin = |name: &str| -> Result<Vector3<f64>, ModelError> {
            Ok(data
                .frame_placement(model.frame_id(name)?)
                .translation
                .vector)
        };
        let mut reference = [None; COUNT];
        for &(joint, point) in mapping.points {
            if reference[joint.index()].is_some() {
                return Err(ScaleError::DuplicateJoint(joint.name()));
            }
            reference[joint.index()] = Some(match point {
                RobotPoint::Frame(a) => origin(a)?,
                RobotPoint::Midpoint(a, b) => (origin(a)? + origin(b)?) * 0.5,
            });
        }
        use HumanJoint::*;
        for joint in [MidHip, LHip, RHip, LKnee, RKnee, LAnkle, RAnkle] {
            if reference[joint.index()].is_none() {
                return Err(ScaleError::MissingJoint(joint.name()));
            }
        }
        let point = |j: HumanJoint| reference[j.index()].unwrap_or_else(Vector3::zeros);

        let mut antecedent = [None; COUNT];
        let mut length = [0.0; COUNT];
        let mut depth = [usize::MAX; COUNT];
        for joint in HumanJoint::ALL {
            if reference[joint.index()].is_none() {
                continue;
            }
            let mut ancestor = joint.antecedent();
            let mut d = 0;
            while let Some(a) = ancestor {
                d += 1;
                if reference[a.index()].is_some() && antecedent[joint.index()].is_none() {
                    antecedent[joint.index()] = Some(a);
                }
                ancestor = a.antecedent();
            }
            depth[joint.index()] = d;
            if let Some(a) = antecedent[joint.index()] {
                length[joint.index()] = (point(joint) - point(a)).norm();
            }
        }
        let mut order = HumanJoint::ALL;
        order.sort_by_key(|j| depth[j.index()]);
        let mapped = reference.iter().filter(|p| p.is_some()).count();

        let sole_names = [mapping.left_sole, mapping.right_sole];
        let mut soles = [nalgebra::IsometryMatrix3::identity(); 2];
        let mut ankle_in_sole = [Vector3::zeros(); 2];
        let mut toe_in_sole = [None; 2];
        for side in [Side::Left, Side::Right] {
            let k = side_index(side);
            soles[k] = *data.frame_placement(model.frame_id(sole_names[k])?);
            let to_sole = soles[k].inverse();
            ankle_in_sole[k] = (to_sole * nalgebra::Point3::from(point(ankle(side)))).coords;
            toe_in_sole[k] =
                reference[toe(side).index()].map(|p| (to_sole * nalgebra::Point3::from(p)).coords);
        }
        let left_in_right = soles[1].inverse() * soles[0];
        let (_, _, yaw) = left_in_right.rotation.euler_angles();
        let left_in_right = SolePlacement {
            xy: left_in_right.translation.vector.xy(),
            yaw,
        };
        let mid_ankle = (point(LAnkle) + point(RAnkle)) * 0.5;
        let loop_length = (point(MidHip) - mid_ankle).norm();
        let leg_length = 0.5
            * (length[LKnee.index()]
                + length[LAnkle.index()]
                + length[RKnee.index()]
                + length[RAnkle.index()]);
        Ok(RobotSkeleton {
            reference,
            antecedent,
            length,
            order,
            mapped,
            ankle_in_sole,
            toe_in_sole,
            left_in_right,
            loop_length,
            leg_length,
        })
    }

    /// [`RobotSkeleton::new`] at the model's zero posture (`q = 0`).
    pub fn at_zero(model: &Model, mapping: &RobotMapping<'_>) -> Result<Self, ScaleError> {
        RobotSkeleton::new(model, mapping, &vec![0.0; model.nv()])
    }

    /// The NAO (`nao::rfoot()`, [`NAO_MAPPING`], `q = 0`).
    pub fn nao() -> Self {
        // The embedded model and mapping are part of the crate and covered by the tests.
        RobotSkeleton::at_zero(&crate::robots::nao::rfoot(), &NAO_MAPPING)
            .unwrap_or_else(|e| panic!("NAO mapping: {e}"))
    }

    /// Whether the robot has a point for `joint`.
    pub fn has(&self, joint: HumanJoint) -> bool {
        self.reference[joint.index()].is_some()
    }

    /// The robot point of `joint` in the reference posture, in the model's base frame (metres).
    pub fn reference(&self, joint: HumanJoint) -> Option<Vector3<f64>> {
        self.reference[joint.index()]
    }

    /// The robot antecedent of `joint` (its nearest mapped ancestor).
    pub fn antecedent(&self, joint: HumanJoint) -> Option<HumanJoint> {
        self.antecedent[joint.index()]
    }

    /// Length (metres) of the robot segment from the robot antecedent of `joint` to `joint`.
    pub fn length(&self, joint: HumanJoint) -> Option<f64> {
        self.antecedent[joint.index()].map(|_| self.length[joint.index()])
    }

    /// Height of the ankle point above its sole (metres; 0.04511 for the NAO).
    pub fn ankle_height(&self, side: Side) -> f64 {
        self.ankle_in_sole[side_index(side)].z
    }

    /// Length (metres) of the double-support leg loop segment: mid-ankle point to MidHip.
    pub fn loop_length(&self) -> f64 {
        self.loop_length
    }

    /// Mapped joints, antecedents before their descendants.
    pub fn joints(&self) -> &[HumanJoint] {
        &self.order[..self.mapped]
    }
}

/// Where a foot may be put down, relative to the other (support) sole: the sole origin's
/// forward offset `x` and its lateral offset towards the foot's own side (metres), and its yaw
/// (radians). For the left foot relative to the right sole, lateral = y; mirrored for the right.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootArea {
    /// Smallest forward offset (metres).
    pub x_min: f64,
    /// Largest forward offset (metres).
    pub x_max: f64,
    /// Smallest lateral offset (metres), so the feet do not collide.
    pub lateral_min: f64,
    /// Largest lateral offset (metres).
    pub lateral_max: f64,
    /// Largest |yaw| of the foot relative to the support sole (radians).
    pub yaw_max: f64,
}

impl FootArea {
    /// For the NAO: x ∈ [−0.04, 0.05], lateral ∈ [0.095, 0.12], |yaw| ≤ 0.15. The lateral bounds
    /// come from its 0.1 m hip width (the feet stay 95 mm apart, uncrossed); the forward ones
    /// from stepping with the torso 20 mm below its standing height (`TORSO_LOWERING`) and the
    /// CoM over the stance foot: at 8 cm (NAOqi's largest step) the swing knee is straight when the foot
    /// lands, and double support with the feet that far apart leaves the legs no posture to
    /// hold the torso with.
    pub const fn nao() -> Self {
        FootArea {
            x_min: -0.04,
            x_max: 0.05,
            lateral_min: 0.095,
            lateral_max: 0.12,
            yaw_max: 0.15,
        }
    }

    /// Clips the placement of the foot on `side` relative to the other sole.
    pub fn clip(&self, side: Side, placement: SolePlacement) -> SolePlacement {
        let sign = if side == Side::Left { 1.0 } else { -1.0 };
        SolePlacement {
            xy: Vector2::new(
                placement.xy.x.clamp(self.x_min, self.x_max),
                sign * (sign * placement.xy.y).clamp(self.lateral_min, self.lateral_max),
            ),
            yaw: placement.yaw.clamp(-self.yaw_max, self.yaw_max),
        }
    }
}

/// Settings of the [`Scaler`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleConfig {
    /// Where a foot may be put down.
    pub area: FootArea,
    /// Human segments shorter than this (metres) keep the previous direction. Default 1e−9:
    /// only coincident points; it is absolute so that scaling stays invariant to the human's size.
    pub min_segment: f64,
}

impl ScaleConfig {
    /// NAO defaults: [`FootArea::nao`], `min_segment` 1e−9 m.
    pub const fn nao() -> Self {
        ScaleConfig {
            area: FootArea::nao(),
            min_segment: 1e-9,
        }
    }

    fn validate(&self) -> Result<(), ScaleError> {
        let a = &self.area;
        let ok = |v: f64| v.is_finite();
        if ![a.x_min, a.x_max, a.lateral_min, a.lateral_max, a.yaw_max]
            .into_iter()
            .all(ok)
        {
            return Err(ScaleError::BadConfig("area bounds must be finite"));
        }
        if a.x_min > a.x_max || a.lateral_min > a.lateral_max || a.yaw_max < 0.0 {
            return Err(ScaleError::BadConfig(
                "area: x_min ≤ x_max, lateral_min ≤ lateral_max, yaw_max ≥ 0",
            ));
        }
        if !(self.min_segment.is_finite() && self.min_segment >= 0.0) {
            return Err(ScaleError::BadConfig("min_segment must be finite and ≥ 0"));
        }
        Ok(())
    }
}

/// Which robot feet are on the ground while scaling.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stance {
    /// Both feet; output in the right sole frame.
    Double,
    /// The right foot; output in the right sole frame.
    Right,
    /// The left foot; output in the left sole frame.
    Left,
}

impl Stance {
    /// The foot whose sole is the output frame.
    pub const fn base(self) -> Side {
        match self {
            Stance::Double | Stance::Right => Side::Right,
            Stance::Left => Side::Left,
        }
    }

    /// The stance for a human support phase; `Airborne` gives `None` (keep the last stance).
    pub const fn from_support(support: HumanSupport) -> Option<Stance> {
        match support {
            HumanSupport::Double => Some(Stance::Double),
            HumanSupport::Right => Some(Stance::Right),
            HumanSupport::Left => Some(Stance::Left),
            HumanSupport::Airborne => None,
        }
    }
}

/// One scaled frame: the robot points standing for the human joints, in the support sole frame
/// (metres, z up; see the module docs for the heading).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaledSkeleton {
    /// Time of the human frame (seconds).
    pub time: f64,
    /// The stance used.
    pub stance: Stance,
    points: [Option<Vector3<f64>>; COUNT],
    directions: [Option<Vector3<f64>>; COUNT],
    soles: [Option<SolePlacement>; 2],
}

impl ScaledSkeleton {
    fn empty() -> Self {
        ScaledSkeleton {
            time: 0.0,
            stance: Stance::Double,
            points: [None; COUNT],
            directions: [None; COUNT],
            soles: [None; 2],
        }
    }

    /// The robot point standing for `joint` (metres, output frame), `None` if the robot has none.
    pub fn get(&self, joint: HumanJoint) -> Option<Vector3<f64>> {
        self.points[joint.index()]
    }

    /// Every joint with its robot point or `None`, in [`HumanJoint::ALL`] order.
    pub fn points(&self) -> impl Iterator<Item = (HumanJoint, Option<Vector3<f64>>)> + '_ {
        HumanJoint::ALL.into_iter().zip(self.points.iter().copied())
    }

    /// The human unit direction used for the segment ending at `joint` (from its robot
    /// antecedent; for mid-line pairs the ±left−right line), rotated into the output frame.
    /// `None` for MidHip and unmapped joints.
    pub fn direction(&self, joint: HumanJoint) -> Option<Vector3<f64>> {
        self.directions[joint.index()]
    }

    /// Placement (horizontal position in metres, yaw in radians) of the sole of a foot on the
    /// ground, in the output frame; `None` for a foot in the air. The base foot is at the origin.
    pub fn sole(&self, side: Side) -> Option<SolePlacement> {
        self.soles[side_index(side)]
    }

    /// The foot whose sole is the origin of the output frame.
    pub fn base(&self) -> Side {
        self.stance.base()
    }
}

/// Streaming segment-by-segment scaler (see the module docs). Keeps the previous frame's
/// directions; [`Scaler::scale`] never allocates.
#[derive(Clone, Debug)]
pub struct Scaler {
    skeleton: RobotSkeleton,
    config: ScaleConfig,
    /// Human unit directions per joint, human world frame (previous frame's until updated).
    directions: [Vector3<f64>; COUNT],
    /// Human mid-ankle → MidHip unit direction, human world frame.
    loop_direction: Vector3<f64>,
    /// Per side (left, right): heading of the human foot (radians about z).
    headings: [f64; 2],
    /// Robot leg length / human leg length.
    ratio: f64,
    /// Human ankle-to-ankle vector (left − right), world frame, metres.
    ankles: Option<Vector3<f64>>,
    last_stance: Option<Stance>,
    left_in_right: SolePlacement,
    out: ScaledSkeleton,
}

/// `v / |v|` if `|v| > min` (and finite).
fn unit(v: Vector3<f64>, min: f64) -> Option<Vector3<f64>> {
    let n = v.norm();
    (n.is_finite() && n > min && n > 0.0).then(|| v / n)
}

fn wrap_angle(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

impl Scaler {
    /// A scaler to `skeleton` with `config`. Errors: a non-finite or inconsistent configuration.
    pub fn new(skeleton: RobotSkeleton, config: ScaleConfig) -> Result<Self, ScaleError> {
        config.validate()?;
        let mut directions = [Vector3::z(); COUNT];
        for &joint in skeleton.joints() {
            if let (Some(a), Some(p)) = (skeleton.antecedent(joint), skeleton.reference(joint)) {
                let from = skeleton.reference(a).unwrap_or(p);
                directions[joint.index()] = unit(p - from, 0.0).unwrap_or_else(Vector3::z);
            }
        }
        let point = |j| skeleton.reference(j).unwrap_or_else(Vector3::zeros);
        let mid_ankle = (point(HumanJoint::LAnkle) + point(HumanJoint::RAnkle)) * 0.5;
        let loop_direction =
            unit(point(HumanJoint::MidHip) - mid_ankle, 0.0).unwrap_or_else(Vector3::z);
        let left_in_right = skeleton.left_in_right;
        Ok(Scaler {
            skeleton,
            config,
            directions,
            loop_direction,
            headings: [0.0; 2],
            ratio: 1.0,
            ankles: None,
            last_stance: None,
            left_in_right,
            out: ScaledSkeleton::empty(),
        })
    }

    /// The robot skeleton.
    pub fn skeleton(&self) -> &RobotSkeleton {
        &self.skeleton
    }

    /// Robot leg length / human leg length (1 until a frame with both legs has been seen).
    pub fn leg_ratio(&self) -> f64 {
        self.ratio
    }

    /// The configuration.
    pub fn config(&self) -> &ScaleConfig {
        &self.config
    }

    /// The last scaled frame.
    pub fn scaled(&self) -> &ScaledSkeleton {
        &self.out
    }

    /// Scales one human frame for the human's `support` phase (`Airborne`: keep the last stance;
    /// double support before any). Error: the frame time is not finite.
    pub fn scale(
        &mut self,
        frame: &HumanFrame,
        support: HumanSupport,
    ) -> Result<&ScaledSkeleton, ScaleError> {
        if !frame.time.is_finite() {
            return Err(ScaleError::NonFiniteTime(frame.time));
        }
        let stance = Stance::from_support(support)
            .or(self.last_stance)
            .unwrap_or(Stance::Double);
        self.update_directions(frame);
        let base = stance.base();
        if stance == Stance::Double && self.last_stance != Some(Stance::Double) {
            self.left_in_right = self.landing(self.last_stance);
        }
        let rotation =
            Rotation3::from_axis_angle(&Vector3::z_axis(), -self.headings[side_index(base)]);

        let out = &mut self.out;
        out.time = frame.time;
        out.stance = stance;
        out.points = [None; COUNT];
        out.directions = [None; COUNT];
        for &joint in self.skeleton.joints() {
            if self.skeleton.antecedent(joint).is_some() {
                out.directions[joint.index()] = Some(rotation * self.directions[joint.index()]);
            }
        }
        let dir = |out: &ScaledSkeleton, j: HumanJoint| {
            out.directions[j.index()].unwrap_or_else(Vector3::z)
        };
        let sk = &self.skeleton;
        let set = |out: &mut ScaledSkeleton, j: HumanJoint, p: Vector3<f64>| {
            out.points[j.index()] = Some(p)
        };

        let base_ankle = sk.ankle_in_sole[side_index(base)];
        set(out, ankle(base), base_ankle);
        out.soles = [None; 2];
        out.soles[side_index(base)] = Some(SolePlacement {
            xy: Vector2::zeros(),
            yaw: 0.0,
        });
        match stance {
            Stance::Right | Stance::Left => {
                // The support leg, walked backwards from the ankle to MidHip.
                let mut p = base_ankle;
                for j in [ankle(base), knee(base), hip(base)] {
                    p -= sk.length[j.index()] * dir(out, j);
                    set(
                        out,
                        sk.antecedent[j.index()].unwrap_or(HumanJoint::MidHip),
                        p,
                    );
                }
            }
            Stance::Double => {
                let placement = self.left_in_right;
                let left = Side::Left;
                let left_ankle = Vector3::new(placement.xy.x, placement.xy.y, 0.0)
                    + placement.rotation() * sk.ankle_in_sole[side_index(left)];
                set(out, HumanJoint::LAnkle, left_ankle);
                out.soles[side_index(left)] = Some(placement);
                let mid_ankle = (left_ankle + base_ankle) * 0.5;
                set(
                    out,
                    HumanJoint::MidHip,
                    mid_ankle + sk.loop_length * (rotation * self.loop_direction),
                );
            }
        }
        // Flat toes of the feet on the ground.
        for side in [Side::Left, Side::Right] {
            if let (Some(sole), Some(toe_offset)) = (
                out.soles[side_index(side)],
                sk.toe_in_sole[side_index(side)],
            ) {
                let p = Vector3::new(sole.xy.x, sole.xy.y, 0.0) + sole.rotation() * toe_offset;
                set(out, toe(side), p);
            }
        }
        // Everything else forwards from MidHip.
        for &j in sk.joints() {
            if out.points[j.index()].is_some() {
                continue;
            }
            if let Some(a) = sk.antecedent[j.index()]
                && let Some(pa) = out.points[a.index()]
            {
                set(out, j, pa + sk.length[j.index()] * dir(out, j));
            }
        }
        self.last_stance = Some(stance);
        Ok(&self.out)
    }

    /// Placement of the left sole in the right sole frame for a foot being put down after
    /// `previous` (the right foot after left support; else the left foot).
    fn landing(&self, previous: Option<Stance>) -> SolePlacement {
        let (landing, support) = match previous {
            Some(Stance::Left) => (Side::Right, Side::Left),
            _ => (Side::Left, Side::Right),
        };
        let reference = if landing == Side::Left {
            self.skeleton.left_in_right
        } else {
            self.skeleton.left_in_right.inverse()
        };
        let placement = match self.ankles {
            None => reference,
            Some(left_minus_right) => {
                let sign = if landing == Side::Left { 1.0 } else { -1.0 };
                let heading = self.headings[side_index(support)];
                let rotation = Rotation3::from_axis_angle(&Vector3::z_axis(), -heading);
                let delta = rotation * (sign * self.ratio * left_minus_right);
                let yaw = wrap_angle(self.headings[side_index(landing)] - heading);
                let yaw_rotation = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
                let sk = &self.skeleton;
                // Ankle-to-ankle as the human's, then back to the sole origin.
                let landing_ankle = sk.ankle_in_sole[side_index(support)] + delta;
                let sole = landing_ankle - yaw_rotation * sk.ankle_in_sole[side_index(landing)];
                SolePlacement { xy: sole.xy(), yaw }
            }
        };
        let clipped = self.config.area.clip(landing, placement);
        if landing == Side::Left {
            clipped
        } else {
            clipped.inverse()
        }
    }

    /// Updates the per-joint human directions, the leg-loop direction, foot headings, the leg
    /// ratio and the ankle-to-ankle vector from `frame`, keeping previous values where the frame
    /// has no usable data.
    fn update_directions(&mut self, frame: &HumanFrame) {
        let min = self.config.min_segment;
        let sk = &self.skeleton;
        for &joint in sk.joints() {
            let Some(a) = sk.antecedent[joint.index()] else {
                continue;
            };
            let pair_line = if joint.mirror() != joint && a.mirror() == a {
                let (l, r) = if is_left(joint) {
                    (joint, joint.mirror())
                } else {
                    (joint.mirror(), joint)
                };
                let sign = if is_left(joint) { 1.0 } else { -1.0 };
                match (frame.get(l), frame.get(r)) {
                    (Some(pl), Some(pr)) if sk.antecedent[joint.mirror().index()] == Some(a) => {
                        unit(pl - pr, min).map(|d| sign * d)
                    }
                    _ => None,
                }
            } else {
                None
            };
            let own = || match (frame.get(joint), frame.get(a)) {
                (Some(p), Some(pa)) => unit(p - pa, min),
                _ => None,
            };
            if let Some(d) = pair_line.or_else(own) {
                self.directions[joint.index()] = d;
            }
        }
        use HumanJoint::*;
        let (la, ra) = (frame.get(LAnkle), frame.get(RAnkle));
        if let (Some(la), Some(ra), Some(mh)) = (la, ra, frame.get(MidHip))
            && let Some(d) = unit(mh - (la + ra) * 0.5, min)
        {
            self.loop_direction = d;
        }
        if let (Some(la), Some(ra)) = (la, ra) {
            self.ankles = Some(la - ra);
        }
        let pelvis = match (frame.get(LHip), frame.get(RHip)) {
            (Some(l), Some(r)) => {
                let h = l - r;
                let forward = Vector3::new(h.y, -h.x, 0.0);
                (forward.norm() > min).then(|| forward.y.atan2(forward.x))
            }
            _ => None,
        };
        for side in [Side::Left, Side::Right] {
            let foot = match (frame.get(ankle(side)), frame.get(toe(side))) {
                (Some(a), Some(t)) => {
                    let v = t - a;
                    (v.xy().norm() > min).then(|| v.y.atan2(v.x))
                }
                _ => None,
            };
            if let Some(h) = foot.or(pelvis) {
                self.headings[side_index(side)] = h;
            }
        }
        let mut human_leg = 0.0;
        let mut legs = 0;
        for side in [Side::Left, Side::Right] {
            if let (Some(h), Some(k), Some(a)) = (
                frame.get(hip(side)),
                frame.get(knee(side)),
                frame.get(ankle(side)),
            ) {
                human_leg += (k - h).norm() + (a - k).norm();
                legs += 1;
            }
        }
        if legs > 0 && human_leg / legs as f64 > min {
            let ratio = sk.leg_length / (human_leg / legs as f64);
            if ratio.is_finite() {
                self.ratio = ratio;
            }
        }
    }
}

/// Human joint angles for the NAO joint-tracking task (eq. 8): the mapping of the module docs'
/// table, in the model's variable order, clipped to its limits. Keeps the previous angles where
/// they are undefined; [`NaoJointAngles::compute`] never allocates.
#[derive(Clone, Debug)]
pub struct NaoJointAngles {
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

/// The NAO variables [`NaoJointAngles`] sets (the others are set to 0, clipped).
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
        1 + 9 * side_index(side) + k
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

impl NaoJointAngles {
    /// The mapping for a NAO `model` (any root; variables named as in `nao::VARIABLES`, frames
    /// `l/r_shoulder`, `l/r_elbow`). Errors name the missing variable or frame.
    pub fn new(model: &Model) -> Result<Self, ScaleError> {
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
            delta[side_index(side)] = u.y.atan2(u.x);
        }
        Ok(NaoJointAngles {
            index,
            lower,
            upper,
            nv: model.nv(),
            delta,
            previous: [0.0; NaoIndex::COUNT],
        })
    }

    /// Writes the human joint angles (radians, clipped to the limits) of `scaled` into `q`
    /// (model variable order); variables without a mapping are set to 0 clipped to their limits.
    /// Error: `q` has the wrong length.
    pub fn compute(&mut self, scaled: &ScaledSkeleton, q: &mut [f64]) -> Result<(), ScaleError> {
        if q.len() != self.nv {
            return Err(ScaleError::WrongLength {
                expected: self.nv,
                got: q.len(),
            });
        }
        use HumanJoint::*;
        let d = |j: HumanJoint| scaled.direction(j).unwrap_or_else(Vector3::zeros);
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
                Some(u.y.atan2(u_xz) - self.delta[side_index(side)]),
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

            let t = to_torso * d(knee(side));
            let s = to_torso * d(ankle(side));
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
