//! The NAO H25 V5 humanoid: 23 IK variables (NAOqi names), named frames, the models rooted at the
//! right sole ([`rfoot`]), the left sole ([`lfoot`]) and the torso ([`torso`]) from the hand-written
//! modified-DH tables in `robots/nao_dh/` (embedded at compile time), the same robot from its URDF
//! ([`from_urdf_str`]) for cross-checks, and the change of support foot ([`switch_support`]).
//!
//! Frames: x forward, y left, z up; at q = 0 every named frame is axis-aligned with the base.
//! `RHipYawPitch` is not a variable: both HipYawPitch joints are driven by `LHipYawPitch` (one
//! motor). The hands (`LHand`, `RHand`) and their finger mimics are locked at 0.
//!
//! Changing support keeps the world placement continuous: with `ʷT_a` the world placement of the
//! current support sole `a` and `ᵃT_b(q)` the placement of the other sole in the current model,
//! the new base is `ʷT_b = ʷT_a · ᵃT_b(q)`; every frame's world placement is then the same in both
//! models for the same `q`.
//!
//! ```
//! use faer::Mat;
//! use nalgebra::Vector3;
//! use taskstack::robots::nao;
//!
//! let model = nao::rfoot(); // base frame: the right sole
//! let mut data = model.new_data(); // reuse it: no allocation from here on
//! let q = vec![0.0; model.nv()]; // nao::VARIABLES order, radians
//! model.forward_kinematics(&mut data, &q)?;
//! let hand = model.frame_id("l_hand")?;
//! // At q = 0 the hand is 0.4207 m above the sole (torso 0.33301 + shoulder 0.100 − hand 0.01231).
//! assert!((data.frame_placement(hand).translation.z - 0.4207).abs() < 1e-12);
//! let mut jacobian = Mat::<f64>::zeros(3, model.nv());
//! model.point_jacobian(&data, hand, &Vector3::zeros(), jacobian.as_mut())?;
//! let com = model.com(&data)?;
//! assert!(com.z > 0.2 && com.z < 0.35);
//! # Ok::<(), taskstack::model::ModelError>(())
//! ```

use std::path::Path;

use nalgebra::{IsometryMatrix3, Translation3};

pub mod joint_angles;

pub use joint_angles::JointAngles;

use crate::human::{HumanJoint, Side};
use crate::model::{Model, ModelData, ModelError, UrdfError, UrdfFrame, UrdfOptions};
use crate::robots::{
    BalancedHands, BipedProfile, BipedSize, BodyCapsule, FootArea, FootFrames, FramePoint,
    MotionTuning, RobotPoint, SelfCollision,
};

/// The 23 IK variables (NAOqi joint names) in the order of `q` of every NAO model.
pub const VARIABLES: [&str; 23] = [
    "HeadYaw",
    "HeadPitch",
    "LShoulderPitch",
    "LShoulderRoll",
    "LElbowYaw",
    "LElbowRoll",
    "LWristYaw",
    "LHipYawPitch",
    "LHipRoll",
    "LHipPitch",
    "LKneePitch",
    "LAnklePitch",
    "LAnkleRoll",
    "RHipRoll",
    "RHipPitch",
    "RKneePitch",
    "RAnklePitch",
    "RAnkleRoll",
    "RShoulderPitch",
    "RShoulderRoll",
    "RElbowYaw",
    "RElbowRoll",
    "RWristYaw",
];

/// Named frames of every NAO model, each with the URDF link it is fixed to and its offset in that
/// link's frame (metres; the orientation is the link's). Hands: NAOqi's HandOffsetX 0.05775 and
/// HandOffsetZ 0.01231 (both hands); soles 0.04511 m (FootHeight) under the ankles; toes/heels
/// ± 0.05 m along the foot's x; gaze (0.05871, 0, 0.06364) from the head.
pub const FRAMES: [(&str, &str, [f64; 3]); 23] = [
    ("torso", "torso", [0.0, 0.0, 0.0]),
    ("head", "Head", [0.0, 0.0, 0.0]),
    ("gaze", "Head", [0.05871, 0.0, 0.06364]),
    ("l_shoulder", "LShoulder", [0.0, 0.0, 0.0]),
    ("l_elbow", "LElbow", [0.0, 0.0, 0.0]),
    ("l_wrist", "l_wrist", [0.0, 0.0, 0.0]),
    ("l_hand", "l_wrist", [0.05775, 0.0, -0.01231]),
    ("r_shoulder", "RShoulder", [0.0, 0.0, 0.0]),
    ("r_elbow", "RElbow", [0.0, 0.0, 0.0]),
    ("r_wrist", "r_wrist", [0.0, 0.0, 0.0]),
    ("r_hand", "r_wrist", [0.05775, 0.0, -0.01231]),
    ("l_hip", "LHip", [0.0, 0.0, 0.0]),
    ("l_knee", "LTibia", [0.0, 0.0, 0.0]),
    ("l_ankle", "l_ankle", [0.0, 0.0, 0.0]),
    ("l_sole", "l_sole", [0.0, 0.0, 0.0]),
    ("l_toe", "l_sole", [0.05, 0.0, 0.0]),
    ("l_heel", "l_sole", [-0.05, 0.0, 0.0]),
    ("r_hip", "RHip", [0.0, 0.0, 0.0]),
    ("r_knee", "RTibia", [0.0, 0.0, 0.0]),
    ("r_ankle", "r_ankle", [0.0, 0.0, 0.0]),
    ("r_sole", "r_sole", [0.0, 0.0, 0.0]),
    ("r_toe", "r_sole", [0.05, 0.0, 0.0]),
    ("r_heel", "r_sole", [-0.05, 0.0, 0.0]),
];

/// URDF joints that are not IK variables, locked at 0 (their finger mimics follow).
pub const LOCKED_JOINTS: [&str; 2] = ["LHand", "RHand"];

/// DH table of the NAO rooted at the right sole (`robots/nao_dh/nao_rfoot.toml`).
pub const RFOOT_DH: &str = include_str!("../../../robots/nao_dh/nao_rfoot.toml");
/// DH table of the NAO rooted at the left sole (`robots/nao_dh/nao_lfoot.toml`).
pub const LFOOT_DH: &str = include_str!("../../../robots/nao_dh/nao_lfoot.toml");
/// DH table of the NAO rooted at the torso (`robots/nao_dh/nao_torso.toml`).
pub const TORSO_DH: &str = include_str!("../../../robots/nao_dh/nao_torso.toml");

/// The NAOqi StandInit-like posture (both feet flat: hip + knee + ankle pitch = 0), in the
/// order of [`VARIABLES`] (rad).
pub const STAND: [f64; 23] = [
    0.0, 0.0, 1.4, 0.3, -1.39, -1.0, 0.0, 0.0, 0.0, -0.35, 0.7, -0.35, 0.0, 0.0, -0.35, 0.7, -0.35,
    0.0, 1.4, -0.3, 1.39, 1.0, 0.0,
];

/// Where the NAO may put a foot down: x ∈ [−0.04, 0.05], lateral ∈ [0.095, 0.12], |yaw| ≤ 0.15.
/// The lateral bounds come from its 0.1 m hip width (the feet stay 95 mm apart, uncrossed); the
/// forward ones from stepping with the torso 20 mm below its standing height and the CoM over
/// the stance foot: at 8 cm (NAOqi's largest step) the swing knee is straight when the foot
/// lands, and double support with the feet that far apart leaves the legs no posture to hold
/// the torso with.
pub const STEP_ENVELOPE: FootArea = FootArea {
    x_min: -0.04,
    x_max: 0.05,
    lateral_min: 0.095,
    lateral_max: 0.12,
    yaw_max: 0.15,
};

/// The sole's outline: the four foot pressure sensors (front left, front right, rear right,
/// rear left: clockwise seen from above) in the sole frame, metres, from the URDF's
/// `LFoot/FSR/*` and `RFoot/FSR/*` fixed joints (ankle offsets with z = −0.04511 dropped).
/// Their convex hull is the support area the foot gives.
pub fn sole_outline(side: Side) -> [[f64; 2]; 4] {
    match side {
        Side::Left => [
            [0.07025, 0.0299],
            [0.07025, -0.0231],
            [-0.02965, -0.0191],
            [-0.03025, 0.0299],
        ],
        Side::Right => [
            [0.07025, 0.0231],
            [0.07025, -0.0299],
            [-0.02965, -0.0299],
            [-0.03025, 0.0191],
        ],
    }
}

/// Name of the sole frame of `side` (`l_sole`, `r_sole`).
pub fn sole(side: Side) -> &'static str {
    side.pick("l_sole", "r_sole")
}

/// The frames standing for the human's joints. The NAO's `head` frame is the neck joint
/// (HeadYaw/HeadPitch), so it stands for the human Neck, and the `gaze` point for the Head. The
/// NAO has no pelvis point apart from its hips, so [`HumanJoint::Pelvis`] is not mapped.
pub fn points() -> Vec<(HumanJoint, RobotPoint)> {
    use HumanJoint::*;
    let frame = |name: &str| RobotPoint::Frame(name.to_owned());
    let mid = |a: &str, b: &str| RobotPoint::Midpoint(a.to_owned(), b.to_owned());
    vec![
        (MidHip, mid("l_hip", "r_hip")),
        (LHip, frame("l_hip")),
        (RHip, frame("r_hip")),
        (LKnee, frame("l_knee")),
        (RKnee, frame("r_knee")),
        (LAnkle, frame("l_ankle")),
        (RAnkle, frame("r_ankle")),
        (LToe, frame("l_toe")),
        (RToe, frame("r_toe")),
        (MidShoulder, mid("l_shoulder", "r_shoulder")),
        (Neck, frame("head")),
        (Head, frame("gaze")),
        (LShoulder, frame("l_shoulder")),
        (RShoulder, frame("r_shoulder")),
        (LElbow, frame("l_elbow")),
        (RElbow, frame("r_elbow")),
        (LWrist, frame("l_wrist")),
        (RWrist, frame("r_wrist")),
        (LHand, frame("l_hand")),
        (RHand, frame("r_hand")),
    ]
}

/// Smallest distance the NAO's paired bodies keep ([`self_collision`]), m.
pub const SELF_COLLISION_MARGIN: f64 = 0.01;

/// The NAO's bodies for self-collision avoidance, sized by hand from the H25 V5 link lengths
/// (upper arm 105 mm, forearm 55.95 mm, hand 57.75 mm, tibia 102.9 mm, foot about 160 × 90 mm)
/// and its outer shell: the forearms with the hands (elbow to hand point, r = 25 mm), the torso
/// (vertical, 85 mm below to 60 mm above the torso frame, r = 55 mm), the head (a sphere of
/// r = 60 mm, 55 mm above the neck joint), the shins (knee to ankle, r = 30 mm) and the feet
/// (heel to toe 20 mm above the sole, r = 35 mm). Standing, the closest pairs (shins, feet) are
/// 30–40 mm apart.
///
/// Paired: each forearm with the torso, the head and the other forearm; the shins with each
/// other and with the other foot; the feet with each other. The thighs have no frame of their
/// own in the model and are left out.
pub fn self_collision() -> SelfCollision {
    let point = |frame: &str, offset| FramePoint {
        frame: frame.to_owned(),
        offset,
    };
    let body = |name: &str, frame: &str, ends: [FramePoint; 2], radius| BodyCapsule {
        name: name.to_owned(),
        frame: frame.to_owned(),
        ends,
        radius,
    };
    let mut bodies = vec![
        body(
            "torso",
            "torso",
            [
                point("torso", [0.0, 0.0, -0.045]),
                point("torso", [0.0, 0.0, 0.06]),
            ],
            0.055,
        ),
        body(
            "head",
            "head",
            [
                point("head", [0.0, 0.0, 0.055]),
                point("head", [0.0, 0.0, 0.055]),
            ],
            0.06,
        ),
    ];
    for side in Side::BOTH {
        let p = side.pick("l_", "r_");
        let frame = |name: &str| format!("{p}{name}");
        bodies.push(body(
            &frame("forearm"),
            &frame("wrist"),
            [
                FramePoint::origin(&frame("elbow")),
                FramePoint::origin(&frame("hand")),
            ],
            0.025,
        ));
        bodies.push(body(
            &frame("shin"),
            &frame("knee"),
            [
                FramePoint::origin(&frame("knee")),
                FramePoint::origin(&frame("ankle")),
            ],
            0.03,
        ));
        let sole = frame("sole");
        bodies.push(body(
            &frame("foot"),
            &sole,
            [
                point(&sole, [-0.02, 0.0, 0.02]),
                point(&sole, [0.06, 0.0, 0.02]),
            ],
            0.035,
        ));
    }
    let pair = |a: &str, b: &str| [a.to_owned(), b.to_owned()];
    SelfCollision {
        bodies,
        pairs: vec![
            pair("l_forearm", "torso"),
            pair("r_forearm", "torso"),
            pair("l_forearm", "head"),
            pair("r_forearm", "head"),
            pair("l_forearm", "r_forearm"),
            pair("l_shin", "r_shin"),
            pair("l_foot", "r_foot"),
            pair("l_shin", "r_foot"),
            pair("r_shin", "l_foot"),
        ],
        margin: SELF_COLLISION_MARGIN,
    }
}

/// How the imitation moves the NAO, tuned in physics (the judge's MuJoCo NAO, nominal and weak
/// servos; the runs measured are in the CHANGELOG); the reference the scaling rules of
/// [`crate::robots::tuning`] carry to other bipeds.
///
/// * Tasks at up to 0.15 m/s (about what 10 % of the rated joint speeds give at the hands), the
///   arms at half their rated speeds (4–8 rad/s).
/// * The hands at up to 0.8 m/s on both feet and 0.3 m/s on one foot, while the weight shifts
///   and until the human has stood on both feet for a second (the imitation's
///   `SETTLED_DOUBLE_SUPPORT`), their speed shaped at 2 m/s² (the imitation's `HandRates`: a
///   hand starts and brakes instead of reaching its speed within a frame). The arms' reaction
///   is what limits them: faster or unshaped hands turned loaded feet by more than 2° and let
///   the weak model's stance foot roll onto an edge, on one foot most of all; slower ones left
///   the hands tenths of a second late.
/// * With the ZMP level (`PoubelConfig::zmp_balance`) the hands at 1 m/s and 5 m/s² in every
///   phase (`balanced_hands`): the level keeps the arms' reaction inside the support, which the
///   fixed caps above do without it. At 10 m/s² the judge failed 2 of the 16 runs of the
///   bundled clips at the automatic hold (CMU 131_01 nominal: a loaded foot turned 2.7°; Kinect
///   ges01 weak: the measured ZMP within 2 mm of an edge 1.4 % of the time); at 5 m/s² all 16
///   pass, the hands 0.0–0.6 cm farther than at 10 m/s² (bar Kinect ges01, 0.9 cm) and still
///   1.0–3.1 cm nearer than without the level on the clips where the arms move fast; faster
///   still (1.5 m/s, 20 m/s²), loaded feet turned. Koenemann et al.'s method moves the hands at
///   these speeds too: its CoM offset control keeps the NAO up under them without a ZMP level
///   (16 of 16 bundled runs pass at 1 m/s and 5 m/s², and at 2 m/s and 10 m/s² with less
///   margin: Kinect ges01's ZMP inside 99.1 % of the time), the hands 0.5–4.5 cm nearer.
/// * The torso 0.02 m low: with 0.1 m shanks both knees end up straight at the standing height.
/// * A 0.25 rad lean over the stance foot: upright, the stance hip-roll servo holds the upper
///   body at 88 % of its rated torque (beyond a weak servo's limit); leaning 0.25 rad lowers the
///   static hip-roll torque from 2.55 to 1.7 N·m (0.15 rad was not enough for the weak model).
/// * The single-support CoM goal 20 mm from the sole's inner edge (6.5 mm inside the centre of
///   its 53 mm-wide contact area): at the centre the hip-roll servo works at 88 % of its rating;
///   at 15 mm the weak model's stance foot rolled onto its inner edge in single support (the
///   CoM 10 mm inside that edge when it did).
/// * The CoM reference at up to 0.05 m/s and 0.3 m/s²: the ZMP within 8 mm of the CoM at its
///   0.27 m height.
/// * Koenemann's CoM offset at up to 1.5 /s and 6 /s²: a shift from the middle to a foot in
///   about 0.6 s, 0.15 m/s and 0.6 m/s² of the CoM on the 0.1 m stance.
pub const TUNING: MotionTuning = MotionTuning {
    task_speed: 0.15,
    tracking_speed: 0.8,
    stance_tracking_speed: 0.3,
    tracking_acceleration: 2.0,
    upper_body_velocity_fraction: 0.5,
    leg_velocity_fraction: 0.1,
    soft_liftoff: false,
    torso_lowering: 0.02,
    single_support_lowering: 0.0,
    torso_lean: 0.25,
    support_margin: 0.020,
    com_speed: 0.05,
    com_acceleration: 0.3,
    offset_rate: 1.5,
    offset_acceleration: 6.0,
    offset_to_stance_point: false,
    balanced_hands: Some(BalancedHands {
        tracking_speed: 1.0,
        tracking_acceleration: 5.0,
    }),
    damping: 0.02,
};

/// The NAO's sizes ([`BipedProfile::size`] of its profile, rounded to 0.1 mm and 0.01 rad/s; a test
/// recomputes them): what the scaling rules scale from.
pub const SIZE: BipedSize = BipedSize {
    com_height: 0.2725,
    half_stance: 0.05,
    hip_height: 0.2357,
    sole_width: 0.053,
    arm_length: 0.1907,
    upper_body_speed: 10.55,
    leg_speed: 5.38,
};

/// The NAO's biped profile over the given models rooted at the left and right soles (the
/// embedded DH models in [`profile`]; the URDF ones for a cross-check).
pub fn profile_with(models: [Model; 2]) -> BipedProfile {
    let foot = |side: Side| {
        let p = side.pick("l_", "r_");
        FootFrames {
            sole: sole(side).to_owned(),
            ankle: format!("{p}ankle"),
            toe: format!("{p}toe"),
            heel: format!("{p}heel"),
            outline: sole_outline(side).to_vec(),
        }
    };
    BipedProfile {
        name: "nao".to_owned(),
        models,
        feet: Side::BOTH.map(foot),
        hands: ["l_hand".to_owned(), "r_hand".to_owned()],
        torso: "torso".to_owned(),
        chest: None,
        points: points(),
        stand: STAND.to_vec(),
        step_envelope: STEP_ENVELOPE,
        tuning: TUNING,
        joint_angles: Some(JointAngles::boxed),
        self_collision: self_collision(),
        // The NAO's DH tables state no torque limits. Its servos, stiff for their load
        // (the physics check's NAO reaches its torque limit at 5 mrad), sag a few mrad at most.
        servo_saturation: None,
        sway_period: None,
    }
}

/// The NAO H25 V5's biped profile from the embedded DH tables.
pub fn profile() -> BipedProfile {
    profile_with([lfoot(), rfoot()])
}

fn embedded(text: &str, origin: &str) -> Model {
    // The embedded tables are part of the crate and loaded by the tests; failing here is a build
    // defect, not bad user input.
    Model::from_dh_str(text, origin).unwrap_or_else(|e| panic!("embedded NAO table: {e}"))
}

/// The NAO rooted at the right sole (base frame = `r_sole`), from the embedded DH table.
pub fn rfoot() -> Model {
    embedded(RFOOT_DH, "robots/nao_dh/nao_rfoot.toml")
}

/// The NAO rooted at the left sole (base frame = `l_sole`), from the embedded DH table.
pub fn lfoot() -> Model {
    embedded(LFOOT_DH, "robots/nao_dh/nao_lfoot.toml")
}

/// The NAO rooted at the torso (base frame = URDF `torso`), from the embedded DH table.
pub fn torso() -> Model {
    embedded(TORSO_DH, "robots/nao_dh/nao_torso.toml")
}

/// URDF loading options for the NAO: base at `root_link` (`None`: the URDF's root), hands locked at
/// 0, variables in [`VARIABLES`] order, exactly the named frames of [`FRAMES`].
pub fn urdf_options(root_link: Option<&str>) -> UrdfOptions {
    UrdfOptions {
        root_link: root_link.map(str::to_owned),
        locked_joints: LOCKED_JOINTS.iter().map(|j| (j.to_string(), 0.0)).collect(),
        variable_order: Some(VARIABLES.iter().map(|v| v.to_string()).collect()),
        frames: FRAMES
            .iter()
            .map(|&(name, link, [x, y, z])| UrdfFrame {
                name: name.to_owned(),
                link: link.to_owned(),
                placement: IsometryMatrix3::from(Translation3::new(x, y, z)),
            })
            .collect(),
        link_frames: false,
    }
}

/// The NAO from URDF text (e.g. `nao.urdf` of NAO H25 V5), rooted at the URDF link `root_link`
/// (`"r_sole"`, `"l_sole"`, `"torso"`; `None`: the URDF's root), with the NAO named frames.
pub fn from_urdf_str(text: &str, root_link: Option<&str>) -> Result<Model, UrdfError> {
    Model::from_urdf_str(text, &urdf_options(root_link))
}

/// [`from_urdf_str`] on a file.
pub fn from_urdf_file(path: impl AsRef<Path>, root_link: Option<&str>) -> Result<Model, UrdfError> {
    Model::from_urdf_file(path, &urdf_options(root_link))
}

/// Change of support: the world placement of the sole of `new_support`, given a model and its
/// forward kinematics at the current `q` and the world placement `world_t_base` of that model's
/// base (the current support sole). Use it as the new model's base placement: `ʷT_b = ʷT_a · ᵃT_b(q)`.
pub fn switch_support(
    model: &Model,
    data: &ModelData,
    world_t_base: &IsometryMatrix3<f64>,
    new_support: Side,
) -> Result<IsometryMatrix3<f64>, ModelError> {
    let sole = model.frame_id(sole(new_support))?;
    model.placement_in_world(data, world_t_base, sole)
}
