//! Walking settings derived from a robot's profile, by rules stated here, so that any biped
//! gets values for its size.
//!
//! * **CoM height** `z_c`: the CoM's height above the soles in the standing posture, less the
//!   profile's `torso_lowering` (the imitation's knee slack: a straight stance leg cannot carry
//!   the hips forward).
//! * **Step time**: a fixed number of pendulum time constants `1/ω`, `ω = √(g/z_c)`, so a
//!   taller robot steps more slowly: double support `2/ω`, single support `2.5/ω` (NAO 0.32 +
//!   0.40 s, G1 0.51 + 0.64 s). The double support is long enough for the CoM to cross over
//!   the next stance sole before the other foot lifts: the CoM's ground projection then stays
//!   inside the support polygon, not only the ZMP (a swept NAO walk: with `1/ω`-long double
//!   supports the CoM is outside 10–40 % of the time, from `2/ω` never).
//! * **Swing height**: 8 % of the leg length (hip to sole, standing): 2 cm on the NAO.
//! * **Start and stop**: one step time each, for the ZMP to swing onto the first stance sole and
//!   back between the feet.
//! * **Preview window**: 1.6 s (ten time constants of the slowest robot we model); tick 10 ms.

use super::footstep::StepTiming;
use super::generator::WalkSettings;
use super::preview::{GRAVITY, PreviewSettings};
use super::schedule::SoleCentres;
use super::swing::SwingProfile;
use crate::human::{HumanJoint, Side};
use crate::model::ModelData;
use crate::robots::{BipedProfile, ProfileError, RobotPoint};

/// Pendulum time constants in a step's double support (see the module docs).
const DOUBLE_SUPPORT_TIME_CONSTANTS: f64 = 2.0;
/// Pendulum time constants in a step's single support.
const SINGLE_SUPPORT_TIME_CONSTANTS: f64 = 2.5;
/// Swing height per metre of leg.
const SWING_HEIGHT_PER_LEG: f64 = 0.08;
/// Control tick (s).
const TICK: f64 = 0.01;

/// Everything a walk of one robot needs, derived from its profile.
#[derive(Debug, Clone, PartialEq)]
pub struct WalkParams {
    /// Pattern generator settings.
    pub settings: WalkSettings,
    /// The timing of every step.
    pub timing: StepTiming,
    /// The soles' contact-area centres.
    pub centres: SoleCentres,
    /// The CoM height of the standing posture above the soles (m).
    pub standing_com_height: f64,
}

impl WalkParams {
    /// The rules of the module docs applied to `profile`.
    ///
    /// # Errors
    /// [`ProfileError`] when the standing posture's kinematics fail or a frame is missing.
    pub fn for_profile(profile: &BipedProfile) -> Result<Self, ProfileError> {
        let model = profile.model(Side::Right);
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, &profile.stand)?;
        let standing_com_height = model.com(&data)?.z;
        let leg = standing_hip_height(profile, &data)?.unwrap_or(standing_com_height);
        let com_height = standing_com_height - profile.tuning.torso_lowering;
        let time_constant = (com_height / GRAVITY).sqrt();
        let timing = StepTiming {
            double_support: DOUBLE_SUPPORT_TIME_CONSTANTS * time_constant,
            single_support: SINGLE_SUPPORT_TIME_CONSTANTS * time_constant,
        };
        let step_time = timing.duration();
        let outlines = Side::BOTH.map(|s| profile.foot(s).outline.as_slice());
        let centres = SoleCentres::of_outlines(outlines).map_err(|e| ProfileError::Invalid {
            field: "feet.outline".into(),
            reason: e.to_string(),
        })?;
        let settings = WalkSettings {
            com_height,
            dt: TICK,
            preview: PreviewSettings::default(),
            swing: SwingProfile {
                height: SWING_HEIGHT_PER_LEG * leg,
                lift_share: 0.15,
            },
            stop_duration: step_time,
            start_duration: step_time,
            capacity: 64,
        };
        Ok(Self {
            settings,
            timing,
            centres,
            standing_com_height,
        })
    }
}

/// Height of the right hip point above the right sole when standing (m), from the profile's
/// point map (the human's right hip), if it maps one.
fn standing_hip_height(
    profile: &BipedProfile,
    data: &ModelData,
) -> Result<Option<f64>, ProfileError> {
    let model = profile.model(Side::Right);
    let Some((_, point)) = profile.points.iter().find(|(j, _)| *j == HumanJoint::RHip) else {
        return Ok(None);
    };
    let height = |name: &str| -> Result<f64, ProfileError> {
        Ok(data.frame_placement(model.frame_id(name)?).translation.z)
    };
    Ok(Some(match point {
        RobotPoint::Frame(a) => height(a)?,
        RobotPoint::Midpoint(a, b) => 0.5 * (height(a)? + height(b)?),
    }))
}
