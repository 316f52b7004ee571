//! The Unitree G1 humanoid (29 DoF, rev 1.0), from its published URDF (`robots/g1/`, BSD-3-Clause,
//! embedded at compile time): 29 IK variables named as the URDF's revolute joints, every URDF
//! link a named frame, plus the two soles. Models rooted at either sole ([`left_sole`],
//! [`right_sole`]) or at the pelvis ([`pelvis`]).
//!
//! Frames: x forward, y left, z up (the URDF's). A sole frame (`left_sole`, `right_sole`) is
//! [`SOLE_DEPTH`] below its ankle-roll link's origin, with that link's axes: where the four contact
//! spheres of the URDF touch a flat floor. At q = 0 the legs are straight and the soles flat.
//!
//! ```
//! use taskstack::robots::g1;
//!
//! let model = g1::right_sole(); // base frame: the right sole, on the floor
//! let mut data = model.new_data();
//! model.forward_kinematics(&mut data, &vec![0.0; model.nv()])?;
//! let left = data.frame_placement(model.frame_id("left_sole")?).translation;
//! // The feet are level and 2 × 0.118506455 m apart at q = 0 (the lateral offsets of one leg's
//! // joint origins, summed in tests/model_g1.rs).
//! assert!((left.y - 0.23701291).abs() < 1e-9 && left.z.abs() < 1e-9);
//! # Ok::<(), taskstack::model::ModelError>(())
//! ```

use nalgebra::{IsometryMatrix3, Translation3};

use crate::human::{HumanJoint, Side};
use crate::model::{Model, UrdfError, UrdfFrame, UrdfOptions};
use crate::robots::profile_toml::with_fixed_link;
use crate::robots::{BipedProfile, FootArea, FootFrames, MotionTuning, RobotPoint, SelfCollision};

/// The URDF text (`robots/g1/g1_29dof_rev_1_0.urdf`, byte-identical to Unitree's).
pub const URDF: &str = include_str!("../../robots/g1/g1_29dof_rev_1_0.urdf");

/// How far the sole (the floor contact plane) is below an ankle-roll link's origin (m): the
/// URDF's contact spheres are centred 0.03 m below it, radius 0.005 m.
pub const SOLE_DEPTH: f64 = 0.035;

/// The sole rectangle in the sole frame (m): `[[x_min, x_max], [y_min, y_max]]`. Inside the
/// convex hull of the URDF's four contact points (x −0.05 / +0.12, y ±0.025 at the heel, ±0.03 at
/// the toe).
pub const SOLE_RECTANGLE: [[f64; 2]; 2] = [[-0.05, 0.12], [-0.025, 0.025]];

/// The 29 IK variables (URDF joint names) in the order of `q` of every G1 model: legs (left,
/// right), waist, arms (left, right), each from the body outward.
pub const VARIABLES: [&str; 29] = [
    "left_hip_pitch_joint",
    "left_hip_roll_joint",
    "left_hip_yaw_joint",
    "left_knee_joint",
    "left_ankle_pitch_joint",
    "left_ankle_roll_joint",
    "right_hip_pitch_joint",
    "right_hip_roll_joint",
    "right_hip_yaw_joint",
    "right_knee_joint",
    "right_ankle_pitch_joint",
    "right_ankle_roll_joint",
    "waist_yaw_joint",
    "waist_roll_joint",
    "waist_pitch_joint",
    "left_shoulder_pitch_joint",
    "left_shoulder_roll_joint",
    "left_shoulder_yaw_joint",
    "left_elbow_joint",
    "left_wrist_roll_joint",
    "left_wrist_pitch_joint",
    "left_wrist_yaw_joint",
    "right_shoulder_pitch_joint",
    "right_shoulder_roll_joint",
    "right_shoulder_yaw_joint",
    "right_elbow_joint",
    "right_wrist_roll_joint",
    "right_wrist_pitch_joint",
    "right_wrist_yaw_joint",
];

/// The sole frames' names and the ankle-roll links they hang from.
const SOLES: [(&str, &str); 2] = [
    ("left_sole", "left_ankle_roll_link"),
    ("right_sole", "right_ankle_roll_link"),
];

/// Toe and heel points of each sole (`left_toe`, `left_heel`, …), on the sole's x axis (m, sole
/// frame): the toe under the ball of the foot, the heel 1 cm inside the rear contact spheres.
const TOE_HEEL: [(&str, f64); 2] = [("toe", 0.09), ("heel", -0.04)];

/// The loader options of every G1 model rooted at the URDF link or sole `root_link` (`None`: the
/// pelvis): variables in [`VARIABLES`] order, every link a named frame, and the toe and heel
/// points of both soles.
pub fn urdf_options(root_link: Option<&str>) -> UrdfOptions {
    let frames = SOLES
        .iter()
        .zip(["left", "right"])
        .flat_map(|((sole, _), side)| {
            TOE_HEEL.iter().map(move |(point, x)| UrdfFrame {
                name: format!("{side}_{point}"),
                link: (*sole).to_owned(),
                placement: IsometryMatrix3::from(Translation3::new(*x, 0.0, 0.0)),
            })
        })
        .collect();
    UrdfOptions {
        root_link: root_link.map(str::to_owned),
        variable_order: Some(VARIABLES.iter().map(|v| v.to_string()).collect()),
        link_frames: true,
        frames,
        ..UrdfOptions::default()
    }
}

/// A standing posture (order of [`VARIABLES`], rad): knees bent 0.3 rad with hip and ankle pitch
/// sharing the bend so that the soles stay flat (hip + knee + ankle pitch = 0), arms slightly
/// out with the elbows bent.
pub const STAND: [f64; 29] = [
    -0.1, 0.0, 0.0, 0.3, -0.2, 0.0, // left leg
    -0.1, 0.0, 0.0, 0.3, -0.2, 0.0, // right leg
    0.0, 0.0, 0.0, // waist
    0.2, 0.2, 0.0, 0.6, 0.0, 0.0, 0.0, // left arm
    0.2, -0.2, 0.0, 0.6, 0.0, 0.0, 0.0, // right arm
];

/// How fast the imitation may move the G1, tuned in physics (the judge's MuJoCo G1, nominal
/// and weak servos; the runs measured are in the CHANGELOG).
///
/// * The hands follow the human at up to 1.2 m/s on both feet and 0.6 m/s on one foot or while
///   the weight shifts, their speed changing by at most 5 m/s², with the chest held
///   ([`BipedProfile::chest`]; without it the hands' reaction slid the loaded feet). Faster
///   (1 m/s on one foot, 10 m/s², 3 m/s on both feet) the arms' reaction turned or tilted loaded
///   feet; at 6 m/s² Kinect ges01's right arm, held at the shoulder roll's limit by its IK (a
///   local minimum), turned back at speed on more frames than the crate's tests allow. The
///   URDF's velocity limits are the motors' no-load speeds (20–37 rad/s): 10 % of them is
///   already more than the NAO's arms get at 50 %.
/// * The torso is carried 0.05 m below its standing height, not the NAO's 0.02 m: with legs
///   three times as long, at 0.02 m the free leg ended straight 22 µm above the floor on CMU
///   05_02 and the landing never finished.
/// * The lean, the support margin and the CoM reference's bounds are the NAO's, not what the
///   scaling rules of [`crate::robots::tuning`] give (0.23 rad, 14 mm, 0.08 m/s, 0.12 m/s²):
///   the rules' values did no better in the judge, and with the Froude-scaled 0.08 m/s the
///   falls came earlier. The G1 falls for what the rules cannot see: its servos sag under the
///   weight on one leg (the judge's README).
/// * Koenemann's CoM offset moves at the rules' 1.0 /s and 1.0 /s² (0.24 m/s², ZMP 17 mm from
///   the CoM): at the NAO's 1.5 /s and 6 /s² (1.4 m/s² of the CoM on the G1's 0.23 m stance)
///   every bundled clip fell within 2 s.
/// * The G1 stays lowered on one foot (`single_support_lowering` = `torso_lowering`, 0.05 m):
///   rising by it while the foot lifts, as the NAO does, moved its CoM 4 cm up and down within
///   each step, and the G1 rocked on its stance foot.
/// * Koenemann's legs move at the rules' 1.2 % of their rated speed (0.1 × 5.38 / 27.33 rad/s,
///   the NAO's and the G1's mean leg ratings, × √(0.27 / 0.69 m), their CoM heights): the same
///   joint speeds at the same Froude number. At the NAO's 10 % the G1's legs copied the human's
///   knee bends and pelvis turns at up to 2.6 rad/s (hip yaw, CMU 02_10) and it fell. With the
///   weight shift's wait of [`SWAY_PERIOD`] before a lift (`KoenemannConfig::settle_time`),
///   Koenemann's offset ending at the stance points (`offset_to_stance_point`, where Poubel's
///   method puts the CoM on one foot: with the CoM over a sole's centre the weak model rolled
///   outward over it, the uncompensated half of its servos' sag) and the legs ramped over a
///   sway period (`KoenemannConfig::leg_ramp_time`), every bundled clip stands in the judge.
/// * A lifted foot leaves the ground as slowly as it lands (`soft_liftoff`): lifted at once,
///   the foot's last 20–30 N went to the stance foot within a few hundredths of a second and
///   the G1 tipped onto the stance sole's inner edge (CMU 131_01). The NAO keeps its quick
///   lift: at full joint speed its single supports with a soft one meet a stance knee at its
///   limit that the crate's stress test catches (the closing note of issue 30).
/// * The solver's damping is the rules' 0.039 m/rad (the NAO's 0.02 × the arm lengths' ratio,
///   0.375 / 0.191 m): at the NAO's value the G1's arms and waist reversed at speed on 285 of
///   3 099 frames of CMU 09_12 (hold 0), at this one on 2, the hands as near.
pub const TUNING: MotionTuning = MotionTuning {
    task_speed: 0.15,
    tracking_speed: 1.2,
    stance_tracking_speed: 0.6,
    tracking_acceleration: 5.0,
    upper_body_velocity_fraction: 0.1,
    leg_velocity_fraction: 0.012,
    soft_liftoff: true,
    torso_lowering: 0.05,
    single_support_lowering: 0.05,
    torso_lean: 0.25,
    support_margin: 0.015,
    com_speed: 0.05,
    com_acceleration: 0.3,
    offset_rate: 1.0,
    offset_acceleration: 1.0,
    offset_to_stance_point: true,
    balanced_hands: None,
    damping: 0.039,
};

/// The joint error (rad) at which the G1's position servos reach their torque limit: 35 mrad,
/// so stiffness = URDF effort / 0.035 (hip roll and knee 3971, hip pitch and yaw 2514, ankles
/// 1000, arms 714 N·m/rad). These are the gains of a stiff whole-body position hold, the recipe
/// of the physics models that check this crate's G1 outputs (`taskstack check`), not
/// Unitree's deployment gains (40–300 N·m/rad, made for a balancing policy that closes the
/// loop on the IMU; played open loop, the G1 does not stand on them). A robot run at other
/// gains should set its own ([`BipedProfile::servo_saturation`]).
pub const SERVO_SATURATION: f64 = 0.035;

/// The period (s) of the G1's sway on one foot that its servo commands are shaped not to excite
/// ([`crate::robots::sway`]): 1.1 s. On one foot the G1 rocks on its stance ankle roll (35 kg
/// at 0.6 m over a servo of 1000 N·m/rad: `2π √(m h² / (k − m g h))` = 0.79 s; logged in the
/// physics model, 0.85 s with its pelvis and arms' own inertia). Servos vary: at half the
/// stiffness (the physics check's weak model, 70 mrad) the period is 1.4 s. The shaper is
/// centred between the two (their geometric mean, 1.1 s), where it leaves either mode under
/// 20 % of the sway an unshaped command excites (module docs of [`crate::robots::sway`]);
/// shaping `joints.csv` offline with 0.85, 1.1 and 1.3 s and judging the bundled runs, 1.1 s
/// stood best: a local best, and the verdicts of single runs jump between neighbouring periods.
pub const SWAY_PERIOD: f64 = 1.1;

/// Where the G1 may put a foot down relative to the other sole: x ∈ [−0.10, 0.15] m, lateral
/// ∈ [0.20, 0.30] m, |yaw| ≤ 0.3 rad. The NAO's envelope scaled by the legs' length ratio
/// (about 3), with the lateral bounds around the G1's 0.237 m stance width so that the feet
/// (0.05 m wide) never cross.
pub const STEP_ENVELOPE: FootArea = FootArea {
    x_min: -0.10,
    x_max: 0.15,
    lateral_min: 0.20,
    lateral_max: 0.30,
    yaw_max: 0.3,
};

/// The links standing for the human's joints: hips at the hip-roll links (where the pitch and
/// roll axes meet), knees, ankles at the ankle-roll links, shoulders at the shoulder-roll links,
/// elbows, wrists at the wrist-roll links, hands at the rubber hands, the head at `head_link`.
/// The G1 has no neck joint, so [`HumanJoint::Neck`] is not mapped.
pub fn points() -> Vec<(HumanJoint, RobotPoint)> {
    use HumanJoint::*;
    let frame = |name: &str| RobotPoint::Frame(name.to_owned());
    let pair = |part: &str| {
        [Side::Left, Side::Right].map(|side| format!("{}_{part}", side.pick("left", "right")))
    };
    let mid = |part: &str| {
        let [l, r] = pair(part);
        RobotPoint::Midpoint(l, r)
    };
    let mut points = vec![
        (MidHip, mid("hip_roll_link")),
        (MidShoulder, mid("shoulder_roll_link")),
        (Head, frame("head_link")),
    ];
    for (joints, part) in [
        ([LHip, RHip], "hip_roll_link"),
        ([LKnee, RKnee], "knee_link"),
        ([LAnkle, RAnkle], "ankle_roll_link"),
        ([LToe, RToe], "toe"),
        ([LShoulder, RShoulder], "shoulder_roll_link"),
        ([LElbow, RElbow], "elbow_link"),
        ([LWrist, RWrist], "wrist_roll_link"),
        ([LHand, RHand], "rubber_hand"),
    ] {
        for (joint, name) in joints.into_iter().zip(pair(part)) {
            points.push((joint, RobotPoint::Frame(name)));
        }
    }
    points
}

/// The G1's biped profile over models rooted at its left and right soles (`[left, right]`;
/// [`profile`] uses the bundled URDF).
///
/// The tables hold the **pelvis** upright (its "torso" frame): the pelvis carries the upper body
/// over the legs, as the NAO's rigid torso does; the waist joints follow the joint-tracking
/// gradient toward [`STAND`]. The G1 has no human joint-angle map yet, so the arms' redundancy
/// is also resolved toward [`STAND`].
pub fn profile_with(models: [Model; 2]) -> BipedProfile {
    let foot = |side: Side| {
        let s = side.pick("left", "right");
        let [[x_min, x_max], [y_min, y_max]] = SOLE_RECTANGLE;
        FootFrames {
            sole: format!("{s}_sole"),
            ankle: format!("{s}_ankle_roll_link"),
            toe: format!("{s}_toe"),
            heel: format!("{s}_heel"),
            outline: vec![
                [x_max, y_max],
                [x_max, y_min],
                [x_min, y_min],
                [x_min, y_max],
            ],
        }
    };
    BipedProfile {
        name: "g1".to_owned(),
        models,
        feet: Side::BOTH.map(foot),
        hands: [
            "left_rubber_hand".to_owned(),
            "right_rubber_hand".to_owned(),
        ],
        torso: "pelvis".to_owned(),
        chest: Some("torso_link".to_owned()),
        points: points(),
        stand: STAND.to_vec(),
        step_envelope: STEP_ENVELOPE,
        tuning: TUNING,
        joint_angles: None,
        // Not modelled yet: the G1's bodies need sizing from its collision geometry.
        self_collision: SelfCollision::default(),
        servo_saturation: Some(SERVO_SATURATION),
        sway_period: Some(SWAY_PERIOD),
    }
}

/// The Unitree G1's biped profile from the bundled URDF.
pub fn profile() -> BipedProfile {
    profile_with([left_sole(), right_sole()])
}

/// A G1 from URDF text (e.g. [`URDF`], or a variant with other masses), with the two sole links
/// added ([`SOLE_DEPTH`] under the ankle-roll links), rooted at `root_link` (a URDF link,
/// `"left_sole"` or `"right_sole"`; `None`: the pelvis).
///
/// # Errors
/// Malformed URDF text, a root link that does not exist, or a URDF whose joints are not the
/// G1's 29 ([`UrdfError::UnknownVariable`] for a missing one, [`UrdfError::MissingVariable`] for
/// an extra one).
pub fn from_urdf_str(text: &str, root_link: Option<&str>) -> Result<Model, UrdfError> {
    Model::from_urdf_str(&urdf_with_soles(text)?, &urdf_options(root_link))
}

/// G1 URDF text with the two sole links (`left_sole`, `right_sole`: fixed, [`SOLE_DEPTH`]
/// under the ankle-roll links, axes as theirs) added: the description every G1 model is built
/// from, and what a physics model of the G1 needs to put its soles where the profile's are.
///
/// # Errors
/// [`UrdfError::Xml`] when the text has no closing `</robot>` tag.
pub fn urdf_with_soles(text: &str) -> Result<String, UrdfError> {
    let mut text = text.to_owned();
    for (sole, ankle) in SOLES {
        text = with_fixed_link(&text, sole, ankle, [0.0, 0.0, -SOLE_DEPTH])?;
    }
    Ok(text)
}

fn built_in(root_link: &str) -> Model {
    from_urdf_str(URDF, Some(root_link)).expect("the bundled G1 URDF is valid (tests/model_g1.rs)")
}

/// The G1 rooted at its left sole.
pub fn left_sole() -> Model {
    built_in("left_sole")
}

/// The G1 rooted at its right sole.
pub fn right_sole() -> Model {
    built_in("right_sole")
}

/// The G1 rooted at its pelvis (the URDF's own root).
pub fn pelvis() -> Model {
    built_in("pelvis")
}
