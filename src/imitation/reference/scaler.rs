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
//!   sole (the profile's ankle frame in its sole frame); the support leg is walked backwards to MidHip, then
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
//! double support, the left sole for left support (the base frame of the profile's right- or
//! left-rooted model), z up. Its x axis is the horizontal projection of the human's support-foot
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

use nalgebra::{Rotation3, Vector2, Vector3};
use thiserror::Error;

use crate::human::{HumanFrame, HumanJoint, SegmentDirections, Side};
use crate::imitation::reference::support::HumanSupport;
use crate::model::{Model, ModelData, ModelError};
use crate::robots::{BipedProfile, FootArea, RobotPoint, SolePlacement};

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

/// True for the left member of a left/right pair.
fn is_left(joint: HumanJoint) -> bool {
    joint.mirror() != joint && joint.name().starts_with('L')
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

/// The position (m, model root frame) of each mapped human joint's robot point, for the forward
/// kinematics in `data`. Errors: unknown frames, a joint mapped twice, a leg joint or MidHip
/// unmapped.
pub(crate) fn reference_points(
    model: &Model,
    data: &ModelData,
    points: &[(HumanJoint, RobotPoint)],
) -> Result<[Option<Vector3<f64>>; COUNT], ScaleError> {
    let origin = |name: &str| -> Result<Vector3<f64>, ModelError> {
        Ok(data
            .frame_placement(model.frame_id(name)?)
            .translation
            .vector)
    };
    let mut reference = [None; COUNT];
    for (joint, point) in points {
        let joint = *joint;
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
    Ok(reference)
}

impl RobotSkeleton {
    /// Measures `model` at `q_reference` (one value per variable, radians) with the map
    /// `points` (human joint → robot point) and the sole frames `soles` (`[left, right]`).
    /// Errors: unknown frame names, wrong or non-finite `q_reference`, a required joint (MidHip,
    /// hips, knees, ankles) unmapped, a joint mapped twice.
    pub fn new(
        model: &Model,
        points: &[(HumanJoint, RobotPoint)],
        soles: [&str; 2],
        q_reference: &[f64],
    ) -> Result<Self, ScaleError> {
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, q_reference)?;
        let reference = reference_points(model, &data, points)?;
        use HumanJoint::*;
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

        let mut placements = [nalgebra::IsometryMatrix3::identity(); 2];
        let mut ankle_in_sole = [Vector3::zeros(); 2];
        let mut toe_in_sole = [None; 2];
        for side in [Side::Left, Side::Right] {
            let k = side.index();
            placements[k] = *data.frame_placement(model.frame_id(soles[k])?);
            let to_sole = placements[k].inverse();
            ankle_in_sole[k] = (to_sole * nalgebra::Point3::from(point(side.ankle()))).coords;
            toe_in_sole[k] =
                reference[side.toe().index()].map(|p| (to_sole * nalgebra::Point3::from(p)).coords);
        }
        let left_in_right = placements[1].inverse() * placements[0];
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

    /// [`RobotSkeleton::new`] for a biped profile, measured on its right-rooted model at `q = 0`.
    pub fn of(profile: &BipedProfile) -> Result<Self, ScaleError> {
        let model = profile.model(Side::Right);
        let soles = Side::BOTH.map(|side| profile.foot(side).sole.as_str());
        RobotSkeleton::new(model, &profile.points, soles, &vec![0.0; model.nv()])
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

    /// Height of the ankle point above its sole (metres).
    pub fn ankle_height(&self, side: Side) -> f64 {
        self.ankle_in_sole[side.index()].z
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
    /// Scaling into a robot's step envelope `area`, `min_segment` 1e−9 m.
    pub const fn new(area: FootArea) -> Self {
        ScaleConfig {
            area,
            min_segment: 1e-9,
        }
    }

    fn validate(&self) -> Result<(), ScaleError> {
        if self.area.invalid_field().is_some() {
            return Err(ScaleError::BadConfig(
                "area: finite bounds, x_min ≤ x_max, lateral_min ≤ lateral_max, yaw_max ≥ 0",
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
    directions: SegmentDirections,
    soles: [Option<SolePlacement>; 2],
}

impl ScaledSkeleton {
    fn empty() -> Self {
        ScaledSkeleton {
            time: 0.0,
            stance: Stance::Double,
            points: [None; COUNT],
            directions: SegmentDirections::default(),
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
        self.directions.get(joint)
    }

    /// Every segment's direction ([`ScaledSkeleton::direction`]): the input of a robot's
    /// [`crate::robots::HumanJointAngles`].
    pub fn directions(&self) -> &SegmentDirections {
        &self.directions
    }

    /// Placement (horizontal position in metres, yaw in radians) of the sole of a foot on the
    /// ground, in the output frame; `None` for a foot in the air. The base foot is at the origin.
    pub fn sole(&self, side: Side) -> Option<SolePlacement> {
        self.soles[side.index()]
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

    /// Heading of the human's `side` foot (rad about z, human world frame) as of the last
    /// frame: the scaled points' frame has its x axis along the base foot's heading.
    pub fn foot_heading(&self, side: Side) -> f64 {
        self.headings[side.index()]
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
    // Kept as one pass (~95 lines): eq. 1 places the stance leg backwards from the support
    // ankle, then every other joint forwards from MidHip; the order of placement is the method.
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
        let rotation = Rotation3::from_axis_angle(&Vector3::z_axis(), -self.headings[base.index()]);

        let out = &mut self.out;
        out.time = frame.time;
        out.stance = stance;
        out.points = [None; COUNT];
        out.directions = SegmentDirections::default();
        for &joint in self.skeleton.joints() {
            if self.skeleton.antecedent(joint).is_some() {
                out.directions
                    .set(joint, Some(rotation * self.directions[joint.index()]));
            }
        }
        let dir =
            |out: &ScaledSkeleton, j: HumanJoint| out.directions.get(j).unwrap_or_else(Vector3::z);
        let sk = &self.skeleton;
        let set = |out: &mut ScaledSkeleton, j: HumanJoint, p: Vector3<f64>| {
            out.points[j.index()] = Some(p)
        };

        let base_ankle = sk.ankle_in_sole[base.index()];
        set(out, base.ankle(), base_ankle);
        out.soles = [None; 2];
        out.soles[base.index()] = Some(SolePlacement {
            xy: Vector2::zeros(),
            yaw: 0.0,
        });
        match stance {
            Stance::Right | Stance::Left => {
                // The support leg, walked backwards from the ankle to MidHip.
                let mut p = base_ankle;
                for j in [base.ankle(), base.knee(), base.hip()] {
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
                    + placement.rotation() * sk.ankle_in_sole[left.index()];
                set(out, HumanJoint::LAnkle, left_ankle);
                out.soles[left.index()] = Some(placement);
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
            if let (Some(sole), Some(toe_offset)) =
                (out.soles[side.index()], sk.toe_in_sole[side.index()])
            {
                let p = Vector3::new(sole.xy.x, sole.xy.y, 0.0) + sole.rotation() * toe_offset;
                set(out, side.toe(), p);
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
                let heading = self.headings[support.index()];
                let rotation = Rotation3::from_axis_angle(&Vector3::z_axis(), -heading);
                let delta = rotation * (sign * self.ratio * left_minus_right);
                let yaw = wrap_angle(self.headings[landing.index()] - heading);
                let yaw_rotation = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
                let sk = &self.skeleton;
                // Ankle-to-ankle as the human's, then back to the sole origin.
                let landing_ankle = sk.ankle_in_sole[support.index()] + delta;
                let sole = landing_ankle - yaw_rotation * sk.ankle_in_sole[landing.index()];
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
        // Any slope: a foot on its toes still turns the frame. With the footprints' 45° limit
        // ([`crate::imitation::walking::footsteps::footprint`]) the heading jumped between the foot and the pelvis
        // on the frames where a foot point dips past it: the references of six bundled clips
        // moved, and Kinect ges02's hands came 0.5–0.8 cm further off.
        let pelvis = frame.pelvis_heading(min);
        for side in [Side::Left, Side::Right] {
            if let Some(h) = frame.foot_heading(side, min, f64::INFINITY).or(pelvis) {
                self.headings[side.index()] = h;
            }
        }
        let mut human_leg = 0.0;
        let mut legs = 0;
        for side in [Side::Left, Side::Right] {
            if let (Some(h), Some(k), Some(a)) = (
                frame.get(side.hip()),
                frame.get(side.knee()),
                frame.get(side.ankle()),
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
