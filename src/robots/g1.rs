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

use crate::model::{Model, UrdfError, UrdfOptions};

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

/// The loader options of every G1 model rooted at the URDF link or sole `root_link` (`None`: the
/// pelvis): variables in [`VARIABLES`] order, every link a named frame.
pub fn urdf_options(root_link: Option<&str>) -> UrdfOptions {
    UrdfOptions {
        root_link: root_link.map(str::to_owned),
        variable_order: Some(VARIABLES.iter().map(|v| v.to_string()).collect()),
        link_frames: true,
        ..UrdfOptions::default()
    }
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
    let soles: String = SOLES
        .iter()
        .map(|(sole, ankle)| {
            format!(
                r#"<link name="{sole}"/><joint name="{sole}_joint" type="fixed"><origin xyz="0 0 {z}" rpy="0 0 0"/><parent link="{ankle}"/><child link="{sole}"/></joint>"#,
                z = -SOLE_DEPTH
            )
        })
        .collect();
    let Some(end) = text.rfind("</robot>") else {
        return Err(UrdfError::Xml("no closing </robot> tag".to_owned()));
    };
    let text = format!("{}{soles}{}", &text[..end], &text[end..]);
    Model::from_urdf_str(&text, &urdf_options(root_link))
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
