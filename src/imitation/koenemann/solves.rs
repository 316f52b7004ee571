//! The IK problems of Koenemann et al.'s method, built once: the hands' (weighted DLS, the
//! paper's) and the one that keeps the arms apart; the legs' with the CoM first (`feet`), one
//! sole held (`stance`) and the held sole alone (`settle`); and the frames they name.

use nalgebra::Vector3;

use super::KoenemannConfig;
use super::goals::{Distances, Goal, GoalIk};
use crate::human::Side;
use crate::imitation::error::ImitationError;
use crate::imitation::phase::solver::own_joints;
use crate::imitation::state::{Shared, effector_ids};
use crate::model::{FrameId, ModelError};
use crate::robots::BipedProfile;
use crate::solver::Method;
use crate::solver::driver::DriverSettings;

/// How far the held sole may be from its place after a frame (m; its orientation's error in
/// radians times [`super::goals::NORMAL_WEIGHT`]: 3.3e-6 rad).
const HOLD_TOLERANCE: f64 = 1e-7;
/// The legs' IK stops when no goal's error changed by more than this fraction of the tolerance
/// in an iteration. A goal the legs cannot meet (a joint at its limit) crept 5 µm an iteration
/// toward it and ran the IK to its cap of 200 on one NAO frame in ten of CMU 05_02 (3.4 ms a
/// frame, 20× the median) to end 0.1 mm closer; a Gauss–Newton step that converges gains far
/// more than 1 % of the tolerance an iteration.
const LEG_STALL_FRACTION: f64 = 0.01;
/// The legs' IK ends at its best iterate after this many iterations without a better one
/// ([`DriverSettings::patience`]): on the G1 it circled through three iterates until its cap
/// of 200 on most frames of CMU 02_10 (6.2 ms a frame), ending on one with the held sole 1.1 mm
/// off.
const LEG_PATIENCE: usize = 10;
/// Frames of one model.
#[derive(Debug)]
pub(super) struct Frames {
    pub(super) torso: FrameId,
    pub(super) soles: [FrameId; 2],
    pub(super) ankles: [FrameId; 2],
    pub(super) hands: [FrameId; 2],
    pub(super) effectors: [FrameId; 4],
}

/// The joints the hands' IK moves: all but a waist's (those that turn the profile's chest
/// but not its torso, [`BipedProfile::chest`]). The hands then turn a robot's upper body at
/// its shoulders, not at a waist that swings the whole trunk: on the G1, with hands at 1.2 m/s
/// moving its waist, the trunk's swing made it fall in the physics judge.
fn arm_joints(shared: &Shared) -> Result<Vec<bool>, ImitationError> {
    let profile = &shared.profile;
    let side = Side::Right;
    match &profile.chest {
        Some(chest) => {
            let (model, data) = (profile.model(side), &shared.data[side.index()]);
            let waist = own_joints(model, data, chest, &profile.torso)?;
            Ok(waist.iter().map(|w| !w).collect())
        }
        None => Ok(vec![true; shared.q.len()]),
    }
}

/// The IKs of Koenemann et al.'s method, built once for the right-rooted model (the root at the
/// start; the goals name frames of both models alike).
#[derive(Debug)]
pub(super) struct Solves {
    pub(super) arms: GoalIk,
    pub(super) arms_apart: Option<GoalIk>,
    pub(super) feet: GoalIk,
    pub(super) stance: GoalIk,
    pub(super) settle: GoalIk,
}

impl Solves {
    pub(super) fn new(
        shared: &Shared,
        f: &Frames,
        method: &KoenemannConfig,
    ) -> Result<Self, ImitationError> {
        let (arms, arms_apart) = Self::arms(shared, f, method)?;
        let (feet, stance, settle) = Self::legs(shared, f, method)?;
        Ok(Solves {
            arms,
            arms_apart,
            feet,
            stance,
            settle,
        })
    }

    /// The hands' IK (weighted DLS, the paper's) and the IK that keeps the arms apart after it.
    fn arms(
        shared: &Shared,
        f: &Frames,
        method: &KoenemannConfig,
    ) -> Result<(GoalIk, Option<GoalIk>), ImitationError> {
        let profile = &shared.profile;
        let arm_settings = arm_settings(method);
        let dls = Method::WeightedDls {
            damping: method.damping,
        };
        let arms = GoalIk::new(
            f.hands.map(torso_point).to_vec(),
            &[],
            Distances::default(),
            arm_joints(shared)?,
            dls,
            arm_settings,
        )?;
        // The upper body drawn toward its standing posture where the hands leave it free.
        let arms = match method.arm_posture_gain {
            0.0 => arms,
            gain => {
                let gains = (shared.legs.iter()).map(|&leg| if leg { 0.0 } else { gain });
                arms.with_posture(profile.stand.clone(), gains.collect())
            }
        };
        // The arms' self-collision pairs: weighted DLS has no inequalities, so a second IK
        // moves the upper body the least that keeps them apart, after the hands' IK.
        let upper_body: Vec<bool> = shared.legs.iter().map(|leg| !leg).collect();
        let upper_distances = Distances::moved_by(profile, &shared.q, &upper_body, 0)?;
        let guard_settings = DriverSettings {
            max_iterations: 4,
            ..arm_settings
        };
        let arms_apart = (!upper_distances.is_empty())
            .then(|| {
                GoalIk::new(
                    Vec::new(),
                    &[],
                    upper_distances,
                    upper_body,
                    Method::Prioritized,
                    guard_settings,
                )
            })
            .transpose()?;
        Ok((arms, arms_apart))
    }

    /// The legs' IKs: the feet following the human (`feet`), one sole held while the other
    /// follows (`stance`), and the held sole alone (`settle`).
    fn legs(
        shared: &Shared,
        f: &Frames,
        method: &KoenemannConfig,
    ) -> Result<(GoalIk, GoalIk, GoalIk), ImitationError> {
        let profile = &shared.profile;
        let leg_settings = leg_settings(method);
        let orientation = Goal::RootOrientation {
            frame: f.soles[0],
            target: Default::default(),
        };
        let com = Goal::RootCom {
            target: Default::default(),
        };
        let feet_goals = vec![
            com,
            torso_point(f.soles[0]),
            torso_normal(f.soles[0]),
            torso_point(f.soles[1]),
            torso_normal(f.soles[1]),
        ];
        // The CoM first, strictly: statically stable by construction. Below it the prioritized
        // solver's least squares stand in for the paper's DLS: they are exact where the goals
        // agree and converge in a few iterations where DLS needs tens (see `taskstack solve`).
        // The legs alone: the CoM rows would move the arms and head too.
        let legs = shared.legs.clone();
        // The legs' self-collision pairs below the CoM (feet) or the held sole (stance), above
        // the goals the feet follow the human with.
        let feet = GoalIk::new(
            feet_goals,
            &[1, 2],
            Distances::moved_by(profile, &shared.q, &legs, 1)?,
            legs.clone(),
            Method::Prioritized,
            leg_settings,
        )?;
        // The held sole above all: the closed chain of double support must not give way.
        let hold = Goal::RootPoint {
            frame: f.soles[1],
            offset: Vector3::zeros(),
            target: Vector3::zeros(),
        };
        let settle_goals = vec![hold, orientation];
        let settle_settings = DriverSettings {
            tolerance: HOLD_TOLERANCE,
            stall_tolerance: 0.01 * HOLD_TOLERANCE,
            max_iterations: 10,
            ..leg_settings
        };
        let settle = GoalIk::new(
            settle_goals,
            &[],
            Distances::default(),
            legs.clone(),
            Method::Prioritized,
            settle_settings,
        )?;
        let stance_goals = vec![
            hold,
            orientation,
            com,
            torso_point(f.soles[0]),
            torso_normal(f.soles[0]),
        ];
        let stance = GoalIk::new(
            stance_goals,
            &[2, 1],
            Distances::moved_by(profile, &shared.q, &legs, 2)?,
            legs,
            Method::Prioritized,
            leg_settings,
        )?;
        Ok((feet, stance, settle))
    }
}

/// The hands' IK settings: a few iterations a frame, steps of at most 0.1 rad.
fn arm_settings(method: &KoenemannConfig) -> DriverSettings {
    DriverSettings {
        gain: 1.0,
        dt: 1.0,
        tolerance: 1e-4,
        stall_tolerance: 1e-7,
        max_iterations: method.arm_iterations,
        max_task_error: 0.05,
        max_joint_step: 0.1,
        patience: 0,
    }
}

/// The legs' IK settings: the method's tolerance and iterations, steps of at most 0.05 rad.
fn leg_settings(method: &KoenemannConfig) -> DriverSettings {
    DriverSettings {
        tolerance: method.tolerance,
        stall_tolerance: LEG_STALL_FRACTION * method.tolerance,
        patience: LEG_PATIENCE,
        max_iterations: method.max_leg_iterations,
        max_task_error: 0.02,
        max_joint_step: 0.05,
        ..arm_settings(method)
    }
}

/// A goal on the origin of `frame`, in the torso's frame.
fn torso_point(frame: FrameId) -> Goal {
    Goal::TorsoPoint {
        frame,
        offset: Vector3::zeros(),
        target: Vector3::zeros(),
    }
}

/// A goal on the z axis of `frame` (a sole's normal), in the torso's frame.
fn torso_normal(frame: FrameId) -> Goal {
    Goal::TorsoNormal {
        frame,
        normal: Vector3::z(),
    }
}

pub(super) fn frames(profile: &BipedProfile, root: Side) -> Result<Frames, ModelError> {
    let model = profile.model(root);
    let id = |name: &str| model.frame_id(name);
    let [lf, rf] = &profile.feet;
    let [lh, rh] = &profile.hands;
    Ok(Frames {
        torso: id(&profile.torso)?,
        soles: [id(&lf.sole)?, id(&rf.sole)?],
        ankles: [id(&lf.ankle)?, id(&rf.ankle)?],
        hands: [id(lh)?, id(rh)?],
        effectors: effector_ids(profile)?[root.index()],
    })
}
