//! A [`BipedProfile`] from a small TOML file next to the robot's URDF.
//!
//! Lengths in metres, angles in radians, frames as in the URDF (x forward, y left, z up). Every
//! field but `variables`, `locked`, `chest`, `stand`, `servo_saturation`, `sway_period`,
//! `frames` and `tuning` is required; an unknown field is an error (it is a typo more often
//! than not).
//!
//! ```toml
//! name = "tiny"
//! urdf = "tiny.urdf"                 # relative to this file
//! variables = ["l_hip", "l_knee"]    # optional: the order of q (default: the URDF's joints)
//! locked = { gripper = 0.0 }         # optional: joints fixed at a value
//! hands = ["l_hand", "r_hand"]       # frames (links or `frames` below) tracking the hands
//! torso = "base"                     # the frame held upright at its standing height
//! chest = "chest"                    # optional: the upper body's frame above a waist
//!                                    # (BipedProfile::chest)
//! stand = { l_knee = 0.3, r_knee = 0.3 }  # standing posture; joints not named are 0
//! servo_saturation = 0.035           # optional: rad of error at which a position servo gives
//!                                    # its URDF effort (BipedProfile::servo_saturation)
//! sway_period = 1.1                  # optional: s, the sway on one foot that the servo
//!                                    # commands are shaped not to excite (robots::sway)
//!
//! [feet.left]
//! link = "l_foot"                    # the URDF link the sole hangs from
//! sole = [0.0, 0.0, -0.02]           # sole origin in that link (on the floor, link's axes)
//! ankle = "l_foot"                   # the ankle point
//! toe = 0.06                         # toe and heel points on the sole's x axis
//! heel = -0.03
//! outline = [[0.08, 0.03], [0.08, -0.03], [-0.04, -0.03], [-0.04, 0.03]]  # contact area
//!
//! [feet.right]                       # the same for the right foot
//! # …
//!
//! [step_envelope]                    # where a foot may go relative to the other sole
//! x_min = -0.05
//! x_max = 0.08
//! lateral_min = 0.12
//! lateral_max = 0.18
//! yaw_max = 0.2
//!
//! [points]                           # human joint (HumanJoint::name) → frame or [frame, frame]
//! MidHip = ["l_hip_link", "r_hip_link"]
//! LHip = "l_hip_link"
//! # … RHip, LKnee, RKnee, LAnkle, RAnkle are required; the others are optional
//!
//! [frames]                           # optional extra frames: a link and an offset
//! l_hand = { link = "l_forearm", xyz = [0.1, 0.0, 0.0] }
//!
//! [tuning]                           # optional, each field too (default: the NAO's values
//!                                    # scaled to this robot's size, crate::robots::tuning)
//! task_speed = 0.15                  # m/s
//! tracking_speed = 0.8               # m/s, the hands while both feet stand (settled)
//! stance_tracking_speed = 0.3        # m/s, the hands on one foot and while the weight shifts
//! tracking_acceleration = 2.0        # m/s², the hands' change of speed
//! upper_body_velocity_fraction = 0.5
//! leg_velocity_fraction = 0.1        # Koenemann's legs, of their rated speed
//! soft_liftoff = false               # a lifted foot leaves the ground as slowly as it lands
//! torso_lowering = 0.02              # m, the torso below its standing height
//! single_support_lowering = 0.0      # m, the same while a foot is lifted or up
//! torso_lean = 0.25                  # rad, over the stance foot
//! support_margin = 0.020             # m, CoM goal from the sole's inner edge
//! com_speed = 0.05                   # m/s, the CoM reference
//! com_acceleration = 0.3             # m/s²
//! offset_rate = 1.5                  # 1/s, Koenemann's CoM offset between the feet
//! offset_acceleration = 6.0          # 1/s²
//! offset_to_stance_point = false     # Koenemann's offset ends where Poubel's CoM stands on a foot
//! balanced_hands = true              # with the ZMP level (--zmp-balance), the hands at:
//! balanced_tracking_speed = 1.0      # m/s, in every phase
//! balanced_tracking_acceleration = 10.0  # m/s²
//! damping = 0.02                     # m/rad, the solver's damping of near-singular levels
//! ```
//!
//! The soles become links named `left_sole` and `right_sole` (added to the URDF text before it
//! is loaded), the toe and heel points frames named `left_toe`, `left_heel`, `right_toe`,
//! `right_heel`. A profile loaded from a file has no human joint-angle map.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{IsometryMatrix3, Translation3};
use serde::Deserialize;

use super::error::ProfileError;
use super::nao;
use super::profile::{BipedProfile, FootArea, FootFrames, RobotPoint};
use super::self_collision::SelfCollision;
use super::tuning::{BalancedHands, MotionTuning};
use crate::human::{HumanJoint, Side};
use crate::model::{Model, UrdfError, UrdfFrame, UrdfOptions};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    name: String,
    urdf: String,
    variables: Option<Vec<String>>,
    #[serde(default)]
    locked: BTreeMap<String, f64>,
    hands: [String; 2],
    torso: String,
    chest: Option<String>,
    #[serde(default)]
    stand: BTreeMap<String, f64>,
    servo_saturation: Option<f64>,
    sway_period: Option<f64>,
    feet: Feet,
    step_envelope: Envelope,
    points: BTreeMap<String, Point>,
    #[serde(default)]
    frames: BTreeMap<String, ExtraFrame>,
    tuning: Option<Tuning>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Tuning {
    task_speed: Option<f64>,
    tracking_speed: Option<f64>,
    stance_tracking_speed: Option<f64>,
    tracking_acceleration: Option<f64>,
    upper_body_velocity_fraction: Option<f64>,
    leg_velocity_fraction: Option<f64>,
    soft_liftoff: Option<bool>,
    torso_lowering: Option<f64>,
    single_support_lowering: Option<f64>,
    torso_lean: Option<f64>,
    support_margin: Option<f64>,
    com_speed: Option<f64>,
    com_acceleration: Option<f64>,
    offset_rate: Option<f64>,
    offset_acceleration: Option<f64>,
    offset_to_stance_point: Option<bool>,
    balanced_hands: Option<bool>,
    balanced_tracking_speed: Option<f64>,
    balanced_tracking_acceleration: Option<f64>,
    damping: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Feet {
    left: Foot,
    right: Foot,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Foot {
    link: String,
    sole: [f64; 3],
    ankle: String,
    toe: f64,
    heel: f64,
    outline: Vec<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Envelope {
    x_min: f64,
    x_max: f64,
    lateral_min: f64,
    lateral_max: f64,
    yaw_max: f64,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Point {
    Frame(String),
    Midpoint([String; 2]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExtraFrame {
    link: String,
    xyz: [f64; 3],
}

fn invalid(field: impl Into<String>, reason: impl Into<String>) -> ProfileError {
    ProfileError::Invalid {
        field: field.into(),
        reason: reason.into(),
    }
}

fn offset_frame(name: String, link: &str, [x, y, z]: [f64; 3]) -> UrdfFrame {
    UrdfFrame {
        name,
        link: link.to_owned(),
        placement: IsometryMatrix3::from(Translation3::new(x, y, z)),
    }
}

/// `text` with a fixed link `name` added under `parent` at `xyz` (m), before `</robot>`.
pub(crate) fn with_fixed_link(
    text: &str,
    name: &str,
    parent: &str,
    [x, y, z]: [f64; 3],
) -> Result<String, UrdfError> {
    let Some(end) = text.rfind("</robot>") else {
        return Err(UrdfError::Xml("no closing </robot> tag".to_owned()));
    };
    Ok(format!(
        r#"{}<link name="{name}"/><joint name="{name}_joint" type="fixed"><origin xyz="{x} {y} {z}" rpy="0 0 0"/><parent link="{parent}"/><child link="{name}"/></joint>{}"#,
        &text[..end],
        &text[end..]
    ))
}

impl BipedProfile {
    /// Loads a profile from a TOML file (format in [`crate::robots::profile_toml`]); the URDF
    /// path in it is relative to the file. The profile is validated.
    ///
    /// # Errors
    /// The file or the URDF cannot be read ([`ProfileError::Io`], [`ProfileError::Urdf`]),
    /// malformed TOML or an unknown field ([`ProfileError::Syntax`], naming line and field), a
    /// value out of range or a frame missing from the model ([`ProfileError::Invalid`],
    /// [`ProfileError::Model`]).
    pub fn from_toml_file(path: impl AsRef<Path>) -> Result<Self, ProfileError> {
        let path = path.as_ref();
        let file = parse(&read_file(path)?, &path.display().to_string())?;
        let urdf_path = path.parent().unwrap_or(Path::new("")).join(&file.urdf);
        build(file, &read_file(&urdf_path)?)
    }

    /// What a physics model of the robot of the profile file at `path` is generated from: the
    /// URDF text its models are built from (the file's URDF with the two sole links added) and
    /// the loader options of the model rooted at the URDF's own root (the floating base), with
    /// the profile's locked joints and variable order.
    ///
    /// # Errors
    /// As [`BipedProfile::from_toml_file`].
    pub fn physics_source(path: impl AsRef<Path>) -> Result<(String, UrdfOptions), ProfileError> {
        let path = path.as_ref();
        let file = parse(&read_file(path)?, &path.display().to_string())?;
        let urdf_path = path.parent().unwrap_or(Path::new("")).join(&file.urdf);
        let (text, frames) = with_sole_links(&file, &read_file(&urdf_path)?)?;
        Ok((text, loader_options(&file, frames, None)))
    }

    /// [`BipedProfile::from_toml_file`] from the profile's text and its URDF's text (the
    /// profile's `urdf` field is ignored).
    pub fn from_toml_str(profile: &str, urdf: &str) -> Result<Self, ProfileError> {
        build(parse(profile, "<text>")?, urdf)
    }
}

fn read_file(path: &Path) -> Result<String, ProfileError> {
    std::fs::read_to_string(path).map_err(|e| ProfileError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}

fn parse(text: &str, path: &str) -> Result<File, ProfileError> {
    toml::from_str(text).map_err(|e: toml::de::Error| ProfileError::Syntax {
        path: path.to_owned(),
        message: e.to_string(),
    })
}

/// The URDF text with the two sole links added, and the profile's frames (toe and heel points,
/// the file's `frames`).
fn with_sole_links(file: &File, urdf: &str) -> Result<(String, Vec<UrdfFrame>), ProfileError> {
    let feet = [&file.feet.left, &file.feet.right];
    let mut text = urdf.to_owned();
    let mut frames: Vec<UrdfFrame> = Vec::new();
    for (side, foot) in Side::BOTH.into_iter().zip(feet) {
        let sole = format!("{}_sole", side.pick("left", "right"));
        text = with_fixed_link(&text, &sole, &foot.link, foot.sole)?;
        for (point, x) in [("toe", foot.toe), ("heel", foot.heel)] {
            let name = format!("{}_{point}", side.pick("left", "right"));
            frames.push(offset_frame(name, &sole, [x, 0.0, 0.0]));
        }
    }
    for (name, f) in &file.frames {
        frames.push(offset_frame(name.clone(), &f.link, f.xyz));
    }
    Ok((text, frames))
}

/// The loader options of the profile's models, rooted at `root` (`None`: the URDF's root).
fn loader_options(file: &File, frames: Vec<UrdfFrame>, root: Option<&str>) -> UrdfOptions {
    UrdfOptions {
        root_link: root.map(str::to_owned),
        locked_joints: file.locked.iter().map(|(j, v)| (j.clone(), *v)).collect(),
        variable_order: file.variables.clone(),
        frames,
        link_frames: true,
    }
}

fn build(file: File, urdf: &str) -> Result<BipedProfile, ProfileError> {
    let feet = [&file.feet.left, &file.feet.right];
    let (text, frames) = with_sole_links(&file, urdf)?;
    let options = |root: &str| loader_options(&file, frames.clone(), Some(root));
    let models = [
        Model::from_urdf_str(&text, &options("left_sole"))?,
        Model::from_urdf_str(&text, &options("right_sole"))?,
    ];
    let stand = standing_posture(&models[0], &file.stand)?;
    let points = file
        .points
        .into_iter()
        .map(|(joint, point)| {
            let joint = HumanJoint::from_name(&joint)
                .ok_or_else(|| invalid(format!("points.{joint}"), "not a human joint name"))?;
            let point = match point {
                Point::Frame(f) => RobotPoint::Frame(f),
                Point::Midpoint([a, b]) => RobotPoint::Midpoint(a, b),
            };
            Ok((joint, point))
        })
        .collect::<Result<Vec<_>, ProfileError>>()?;
    let foot = |side: Side, f: &Foot| {
        let s = side.pick("left", "right");
        FootFrames {
            sole: format!("{s}_sole"),
            ankle: f.ankle.clone(),
            toe: format!("{s}_toe"),
            heel: format!("{s}_heel"),
            outline: f.outline.clone(),
        }
    };
    let e = file.step_envelope;
    let mut profile = BipedProfile {
        name: file.name,
        models,
        feet: [foot(Side::Left, feet[0]), foot(Side::Right, feet[1])],
        hands: file.hands,
        torso: file.torso,
        chest: file.chest,
        points,
        stand,
        step_envelope: FootArea {
            x_min: e.x_min,
            x_max: e.x_max,
            lateral_min: e.lateral_min,
            lateral_max: e.lateral_max,
            yaw_max: e.yaw_max,
        },
        joint_angles: None,
        tuning: nao::TUNING,
        self_collision: SelfCollision::default(),
        servo_saturation: file.servo_saturation,
        sway_period: file.sway_period,
    };
    profile.validate()?;
    let scaled = nao::TUNING.scaled(&nao::SIZE, &profile.size()?);
    profile.tuning = tuning(file.tuning, scaled);
    profile.validate()?;
    Ok(profile)
}

/// The `[tuning]` table over `scaled`, the NAO's values scaled to this robot's size.
fn tuning(file: Option<Tuning>, scaled: MotionTuning) -> MotionTuning {
    let Some(t) = file else { return scaled };
    MotionTuning {
        task_speed: t.task_speed.unwrap_or(scaled.task_speed),
        tracking_speed: t.tracking_speed.unwrap_or(scaled.tracking_speed),
        stance_tracking_speed: (t.stance_tracking_speed).unwrap_or(scaled.stance_tracking_speed),
        tracking_acceleration: (t.tracking_acceleration).unwrap_or(scaled.tracking_acceleration),
        upper_body_velocity_fraction: (t.upper_body_velocity_fraction)
            .unwrap_or(scaled.upper_body_velocity_fraction),
        leg_velocity_fraction: (t.leg_velocity_fraction).unwrap_or(scaled.leg_velocity_fraction),
        soft_liftoff: t.soft_liftoff.unwrap_or(scaled.soft_liftoff),
        torso_lowering: t.torso_lowering.unwrap_or(scaled.torso_lowering),
        single_support_lowering: (t.single_support_lowering)
            .unwrap_or(scaled.single_support_lowering),
        torso_lean: t.torso_lean.unwrap_or(scaled.torso_lean),
        support_margin: t.support_margin.unwrap_or(scaled.support_margin),
        com_speed: t.com_speed.unwrap_or(scaled.com_speed),
        com_acceleration: t.com_acceleration.unwrap_or(scaled.com_acceleration),
        offset_rate: t.offset_rate.unwrap_or(scaled.offset_rate),
        offset_acceleration: t.offset_acceleration.unwrap_or(scaled.offset_acceleration),
        offset_to_stance_point: (t.offset_to_stance_point).unwrap_or(scaled.offset_to_stance_point),
        balanced_hands: balanced_hands(&t, &scaled),
        damping: t.damping.unwrap_or(scaled.damping),
    }
}

/// The `[tuning]` table's hands under the ZMP level over `scaled`'s: none with
/// `balanced_hands = false`; else `scaled`'s, or with `balanced_hands = true` and none there
/// its ordinary speeds, each overridden where the table gives it.
fn balanced_hands(t: &Tuning, scaled: &MotionTuning) -> Option<BalancedHands> {
    let base = match (t.balanced_hands, scaled.balanced_hands) {
        (Some(false), _) | (None, None) => return None,
        (_, Some(balanced)) => balanced,
        (Some(true), None) => BalancedHands {
            tracking_speed: scaled.tracking_speed,
            tracking_acceleration: scaled.tracking_acceleration,
        },
    };
    Some(BalancedHands {
        tracking_speed: t.balanced_tracking_speed.unwrap_or(base.tracking_speed),
        tracking_acceleration: (t.balanced_tracking_acceleration)
            .unwrap_or(base.tracking_acceleration),
    })
}

/// The standing posture: the named joints at their values, the others at 0.
fn standing_posture(
    model: &Model,
    named: &BTreeMap<String, f64>,
) -> Result<Vec<f64>, ProfileError> {
    let mut q = vec![0.0; model.nv()];
    for (joint, &value) in named {
        let i = model
            .variable_index(joint)
            .map_err(|_| invalid(format!("stand.{joint}"), "not a variable of the model"))?;
        q[i] = value;
    }
    Ok(q)
}
