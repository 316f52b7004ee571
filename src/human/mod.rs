//! The human skeleton as seen by the imitation pipeline: named joint positions at one instant.
//!
//! # Frame
//!
//! Positions are in **metres**, in a right-handed world frame with **z up**. The horizontal axes
//! are fixed by the motion source, not by the human's heading, because the human turns freely
//! during a clip. Readers choose them so that in the source's reference posture the human faces
//! +x with +y on their left (x forward, y left, z up):
//!
//! * BVH ([`crate::io::bvh`]), Y-up files: `(x, y, z) = s·(Z_bvh, X_bvh, Y_bvh)`; the CMU T-pose
//!   faces +Z_bvh with +X_bvh on the subject's left, so it faces +x here.
//! * Kinect v2 ([`crate::io::kinect`]): `(x, y, z) = (−Z_cam, −X_cam, Y_cam)`; a subject facing
//!   the sensor faces +x.
//!
//! # Segment tree
//!
//! The joints form a tree rooted at [`HumanJoint::MidHip`] ([`HumanJoint::antecedent`]):
//! the trunk is one rigid MidHip→MidShoulder segment (Poubel §II.A), the legs hang from MidHip
//! through the hip joint centres, and the neck and arms hang from MidShoulder. A scaler that starts
//! from a support foot walks this tree with the edges on the path to the foot reversed; segment
//! `j` is the vector `p_j − p_antecedent(j)` ([`HumanFrame::segment`]).
//!
//! # Missing joints
//!
//! A joint the source did not report (Kinect "not tracked", or a joint the BVH name map does not
//! cover) is `None`. Positions stored in a frame are always finite: [`HumanFrame::set`] refuses
//! non-finite values by storing `None`.

use nalgebra::Vector3;

mod com;

pub use com::centre_of_mass;

/// A named point of the human skeleton. Left and right are the human's own sides.
///
/// The discriminant is the joint's index in [`HumanJoint::ALL`] and in a [`HumanFrame`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum HumanJoint {
    /// Root of the capture skeleton (BVH root `Hips`, Kinect `SpineBase`); a point of the pelvis.
    Pelvis,
    /// Midpoint of the two hip joint centres; root of the segment tree. Readers derive it from
    /// [`HumanJoint::LHip`] and [`HumanJoint::RHip`] when the source has no such point.
    MidHip,
    /// Left hip joint centre.
    LHip,
    /// Right hip joint centre.
    RHip,
    /// Left knee joint centre.
    LKnee,
    /// Right knee joint centre.
    RKnee,
    /// Left ankle joint centre.
    LAnkle,
    /// Right ankle joint centre.
    RAnkle,
    /// Left toe joint (ball of the foot; CMU `LeftToeBase`, Kinect `FootLeft`).
    LToe,
    /// Right toe joint (ball of the foot; CMU `RightToeBase`, Kinect `FootRight`).
    RToe,
    /// Top of the spine, between the shoulders (CMU `Spine1`/`Chest2`, Kinect `SpineShoulder`).
    MidShoulder,
    /// Neck (CMU `Neck1`/`Neck`, Kinect `Neck`).
    Neck,
    /// Head (CMU `Head` joint at the top of the neck, Kinect `Head` centre).
    Head,
    /// Left shoulder (glenohumeral) joint centre.
    LShoulder,
    /// Right shoulder (glenohumeral) joint centre.
    RShoulder,
    /// Left elbow joint centre.
    LElbow,
    /// Right elbow joint centre.
    RElbow,
    /// Left wrist joint centre.
    LWrist,
    /// Right wrist joint centre.
    RWrist,
    /// A point of the left hand beyond the wrist (knuckles; Kinect `HandLeft`).
    LHand,
    /// A point of the right hand beyond the wrist (knuckles; Kinect `HandRight`).
    RHand,
}

impl HumanJoint {
    /// Number of joints.
    pub const COUNT: usize = 21;

    /// Every joint, in index order.
    pub const ALL: [HumanJoint; HumanJoint::COUNT] = [
        HumanJoint::Pelvis,
        HumanJoint::MidHip,
        HumanJoint::LHip,
        HumanJoint::RHip,
        HumanJoint::LKnee,
        HumanJoint::RKnee,
        HumanJoint::LAnkle,
        HumanJoint::RAnkle,
        HumanJoint::LToe,
        HumanJoint::RToe,
        HumanJoint::MidShoulder,
        HumanJoint::Neck,
        HumanJoint::Head,
        HumanJoint::LShoulder,
        HumanJoint::RShoulder,
        HumanJoint::LElbow,
        HumanJoint::RElbow,
        HumanJoint::LWrist,
        HumanJoint::RWrist,
        HumanJoint::LHand,
        HumanJoint::RHand,
    ];

    /// Index of this joint in [`HumanJoint::ALL`] and in a [`HumanFrame`].
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The joint's name, as spelled in the enum (`"LAnkle"`, …).
    pub const fn name(self) -> &'static str {
        match self {
            HumanJoint::Pelvis => "Pelvis",
            HumanJoint::MidHip => "MidHip",
            HumanJoint::LHip => "LHip",
            HumanJoint::RHip => "RHip",
            HumanJoint::LKnee => "LKnee",
            HumanJoint::RKnee => "RKnee",
            HumanJoint::LAnkle => "LAnkle",
            HumanJoint::RAnkle => "RAnkle",
            HumanJoint::LToe => "LToe",
            HumanJoint::RToe => "RToe",
            HumanJoint::MidShoulder => "MidShoulder",
            HumanJoint::Neck => "Neck",
            HumanJoint::Head => "Head",
            HumanJoint::LShoulder => "LShoulder",
            HumanJoint::RShoulder => "RShoulder",
            HumanJoint::LElbow => "LElbow",
            HumanJoint::RElbow => "RElbow",
            HumanJoint::LWrist => "LWrist",
            HumanJoint::RWrist => "RWrist",
            HumanJoint::LHand => "LHand",
            HumanJoint::RHand => "RHand",
        }
    }

    /// The joint named `name` (as [`HumanJoint::name`] spells it), if any.
    pub fn from_name(name: &str) -> Option<HumanJoint> {
        HumanJoint::ALL.into_iter().find(|j| j.name() == name)
    }

    /// The joint this one hangs from in the segment tree rooted at [`HumanJoint::MidHip`]
    /// (`None` for MidHip). See the module docs.
    pub const fn antecedent(self) -> Option<HumanJoint> {
        use HumanJoint::*;
        match self {
            MidHip => None,
            Pelvis | LHip | RHip | MidShoulder => Some(MidHip),
            LKnee => Some(LHip),
            RKnee => Some(RHip),
            LAnkle => Some(LKnee),
            RAnkle => Some(RKnee),
            LToe => Some(LAnkle),
            RToe => Some(RAnkle),
            Neck | LShoulder | RShoulder => Some(MidShoulder),
            Head => Some(Neck),
            LElbow => Some(LShoulder),
            RElbow => Some(RShoulder),
            LWrist => Some(LElbow),
            RWrist => Some(RElbow),
            LHand => Some(LWrist),
            RHand => Some(RWrist),
        }
    }

    /// The same joint on the other side of the body (itself for joints on the mid-line).
    pub const fn mirror(self) -> HumanJoint {
        use HumanJoint::*;
        match self {
            LHip => RHip,
            RHip => LHip,
            LKnee => RKnee,
            RKnee => LKnee,
            LAnkle => RAnkle,
            RAnkle => LAnkle,
            LToe => RToe,
            RToe => LToe,
            LShoulder => RShoulder,
            RShoulder => LShoulder,
            LElbow => RElbow,
            RElbow => LElbow,
            LWrist => RWrist,
            RWrist => LWrist,
            LHand => RHand,
            RHand => LHand,
            other => other,
        }
    }
}

/// The kind of system a motion was captured with. Readers say which (`crate::io::clip::Clip`)
/// so that consumers can pick thresholds suited to its rate and noise (e.g. the support
/// detector's `SupportConfig::for_capture`) without the reader knowing about them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CaptureSystem {
    /// Marker-based optical motion capture (CMU: 120 Hz, millimetre noise).
    Optical,
    /// A depth camera's skeleton tracker (Kinect v2: 30 Hz, centimetre noise).
    DepthCamera,
}

/// One instant of human motion: a timestamp and the position of every [`HumanJoint`], each
/// possibly missing. Fixed-size storage; copying or filling a frame never allocates.
///
/// Frame and units: see the module docs (metres, right-handed, z up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HumanFrame {
    /// Time of the frame in seconds, counted from the first frame of its source.
    pub time: f64,
    positions: [Option<Vector3<f64>>; HumanJoint::COUNT],
}

impl HumanFrame {
    /// A frame at `time` (seconds) with every joint missing.
    pub fn new(time: f64) -> Self {
        HumanFrame {
            time,
            positions: [None; HumanJoint::COUNT],
        }
    }

    /// Position of `joint` in metres, or `None` if it is missing.
    pub fn get(&self, joint: HumanJoint) -> Option<Vector3<f64>> {
        self.positions[joint.index()]
    }

    /// Sets the position of `joint` (metres). A `None` or a non-finite position marks the joint
    /// missing, so a frame never holds NaN or infinity.
    pub fn set(&mut self, joint: HumanJoint, position: Option<Vector3<f64>>) {
        self.positions[joint.index()] = position.filter(|p| p.iter().all(|c| c.is_finite()));
    }

    /// Marks every joint missing and sets the time (seconds); used to reuse a frame.
    pub fn clear(&mut self, time: f64) {
        self.time = time;
        self.positions = [None; HumanJoint::COUNT];
    }

    /// Every joint with its position (metres) or `None`, in index order.
    pub fn joints(&self) -> impl Iterator<Item = (HumanJoint, Option<Vector3<f64>>)> + '_ {
        HumanJoint::ALL
            .into_iter()
            .zip(self.positions.iter().copied())
    }

    /// The segment ending at `joint`: `p_joint − p_antecedent(joint)` in metres, or `None` if
    /// either end is missing or `joint` is the tree root ([`HumanJoint::MidHip`]).
    pub fn segment(&self, joint: HumanJoint) -> Option<Vector3<f64>> {
        let parent = joint.antecedent()?;
        Some(self.get(joint)? - self.get(parent)?)
    }

    /// The heading of `side`'s foot (rad about z from x): the horizontal direction from its
    /// ankle to its toe, when the toe is more than `min_reach` (m) from the ankle horizontally
    /// and no farther below or above it than `max_slope` times that (1: 45°; infinite: any
    /// slope). `None` otherwise, or when either point is missing. A foot on its toes (relevé,
    /// the end of a push-off) has its toe nearly under the ankle, and the little horizontal
    /// distance left points anywhere: CMU 05_02's left foot in relevé, its toe 5.7 cm behind
    /// and 11.5 cm below the ankle (a slope of 1.9), read as pointing backward, 2.2–3.1 rad
    /// from the pelvis.
    pub fn foot_heading(&self, side: Side, min_reach: f64, max_slope: f64) -> Option<f64> {
        let d = self.get(side.toe())? - self.get(side.ankle())?;
        let ahead = d.xy().norm();
        (ahead > min_reach && d.z.abs() <= max_slope * ahead).then(|| d.y.atan2(d.x))
    }

    /// The pelvis' heading (rad about z from x): the horizontal normal `(p_LHip − p_RHip) × z`
    /// of the hip line, when it is longer than `min_width` (m); `None` without both hips.
    pub fn pelvis_heading(&self, min_width: f64) -> Option<f64> {
        let left = self.get(HumanJoint::LHip)? - self.get(HumanJoint::RHip)?;
        (left.xy().norm() > min_width).then(|| (-left.x).atan2(left.y))
    }

    /// Sets [`HumanJoint::MidHip`] to the midpoint of the two hips when it is missing and both
    /// hips are present. Readers call this for sources that have no mid-hip point.
    pub fn derive_mid_hip(&mut self) {
        if self.get(HumanJoint::MidHip).is_none()
            && let (Some(l), Some(r)) = (self.get(HumanJoint::LHip), self.get(HumanJoint::RHip))
        {
            self.set(HumanJoint::MidHip, Some((l + r) * 0.5));
        }
    }
}

/// The unit direction of each human segment (the segment ending at a joint, from its antecedent
/// in the tree a scaler walks), in the frame the scaler outputs (a robot's support sole frame);
/// `None` for a segment without a direction (MidHip, a joint the robot has no point for).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentDirections([Option<Vector3<f64>>; HumanJoint::COUNT]);

impl Default for SegmentDirections {
    fn default() -> Self {
        SegmentDirections([None; HumanJoint::COUNT])
    }
}

impl SegmentDirections {
    /// The direction of the segment ending at `joint` (unit vector), if any.
    pub fn get(&self, joint: HumanJoint) -> Option<Vector3<f64>> {
        self.0[joint.index()]
    }

    /// Sets the direction of the segment ending at `joint`.
    pub fn set(&mut self, joint: HumanJoint, direction: Option<Vector3<f64>>) {
        self.0[joint.index()] = direction;
    }
}

/// A side of the body: the human's own left or right, and the robot's (a robot's left foot
/// stands for the human's left foot). Per-side arrays in the crate are indexed by
/// [`Side::index`]: `[left, right]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    /// Left.
    Left,
    /// Right.
    Right,
}

impl Side {
    /// Both sides in index order: `[Side::Left, Side::Right]`.
    pub const BOTH: [Side; 2] = [Side::Left, Side::Right];

    /// 0 for the left side, 1 for the right: the index of per-side arrays.
    pub const fn index(self) -> usize {
        match self {
            Side::Left => 0,
            Side::Right => 1,
        }
    }

    /// The other side.
    pub const fn other(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }

    /// This side's hip joint centre.
    pub const fn hip(self) -> HumanJoint {
        match self {
            Side::Left => HumanJoint::LHip,
            Side::Right => HumanJoint::RHip,
        }
    }

    /// This side's knee.
    pub const fn knee(self) -> HumanJoint {
        match self {
            Side::Left => HumanJoint::LKnee,
            Side::Right => HumanJoint::RKnee,
        }
    }

    /// This side's ankle.
    pub const fn ankle(self) -> HumanJoint {
        match self {
            Side::Left => HumanJoint::LAnkle,
            Side::Right => HumanJoint::RAnkle,
        }
    }

    /// This side's toe.
    pub const fn toe(self) -> HumanJoint {
        match self {
            Side::Left => HumanJoint::LToe,
            Side::Right => HumanJoint::RToe,
        }
    }

    /// `left` on the left side, `right` on the right.
    pub fn pick<T>(self, left: T, right: T) -> T {
        match self {
            Side::Left => left,
            Side::Right => right,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_joint_reaches_mid_hip_through_its_antecedents() {
        for joint in HumanJoint::ALL {
            let mut current = joint;
            let mut steps = 0;
            while let Some(parent) = current.antecedent() {
                current = parent;
                steps += 1;
                assert!(steps < HumanJoint::COUNT, "cycle from {joint:?}");
            }
            assert_eq!(current, HumanJoint::MidHip);
        }
    }

    #[test]
    fn indices_names_and_mirrors_are_consistent() {
        for (k, joint) in HumanJoint::ALL.into_iter().enumerate() {
            assert_eq!(joint.index(), k);
            assert_eq!(HumanJoint::from_name(joint.name()), Some(joint));
            assert_eq!(joint.mirror().mirror(), joint);
            // A limb's antecedent mirrors with it (the tree is left/right symmetric).
            assert_eq!(
                joint.mirror().antecedent(),
                joint.antecedent().map(HumanJoint::mirror)
            );
        }
    }

    #[test]
    fn non_finite_positions_are_stored_as_missing() {
        let mut frame = HumanFrame::new(0.0);
        frame.set(HumanJoint::Head, Some(Vector3::new(0.0, f64::NAN, 1.0)));
        assert_eq!(frame.get(HumanJoint::Head), None);
        frame.set(HumanJoint::Neck, Some(Vector3::new(0.0, 0.0, 1.5)));
        frame.set(HumanJoint::Head, Some(Vector3::new(0.0, 0.0, 1.7)));
        let segment = frame.segment(HumanJoint::Head).unwrap();
        assert!((segment - Vector3::new(0.0, 0.0, 0.2)).norm() < 1e-12);
        assert_eq!(frame.segment(HumanJoint::MidHip), None);
    }

    /// A foot's heading within the slope limit, none past it, none without a toe; the pelvis'
    /// heading is the hip line's normal. The numbers: a toe 0.1 m ahead along (cos 0.5,
    /// sin 0.5) and 0.09 m below the ankle (slope 0.9), then 0.11 m below (slope 1.1).
    #[test]
    fn foot_and_pelvis_headings() {
        let mut frame = HumanFrame::new(0.0);
        let ankle = Vector3::new(0.2, 0.1, 0.08);
        let ahead = Vector3::new(0.5f64.cos(), 0.5f64.sin(), 0.0) * 0.1;
        frame.set(HumanJoint::LAnkle, Some(ankle));
        assert_eq!(frame.foot_heading(Side::Left, 0.03, 1.0), None);
        frame.set(HumanJoint::LToe, Some(ankle + ahead - Vector3::z() * 0.09));
        let heading = frame.foot_heading(Side::Left, 0.03, 1.0).unwrap();
        assert!((heading - 0.5).abs() < 1e-12);
        frame.set(HumanJoint::LToe, Some(ankle + ahead - Vector3::z() * 0.11));
        assert_eq!(frame.foot_heading(Side::Left, 0.03, 1.0), None);
        let any_slope = frame.foot_heading(Side::Left, 0.03, f64::INFINITY).unwrap();
        assert!((any_slope - 0.5).abs() < 1e-12);
        assert_eq!(frame.foot_heading(Side::Left, 0.2, f64::INFINITY), None);
        // Hips 0.2 m apart along (−sin 0.3, cos 0.3): facing 0.3 rad.
        let (s, c) = 0.3f64.sin_cos();
        frame.set(HumanJoint::LHip, Some(Vector3::new(-0.1 * s, 0.1 * c, 0.9)));
        frame.set(HumanJoint::RHip, Some(Vector3::new(0.1 * s, -0.1 * c, 0.9)));
        assert!((frame.pelvis_heading(0.0).unwrap() - 0.3).abs() < 1e-12);
        assert_eq!(frame.pelvis_heading(0.3), None);
    }
}
