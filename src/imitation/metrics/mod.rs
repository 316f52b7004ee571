//! What an imitation run achieved, measured frame by frame from the [`RobotFrame`]s.
//!
//! * **Tracking**: distance between each tracked effector (hands, free ankle) and its scaled
//!   reference, in the model root's frame (m), split by single support, double support and the
//!   transition steps ([`SupportKind`]): on every frame whose phase tracks it. The hands'
//!   references are the human's arms hung from the robot's shoulders (Poubel's method:
//!   `imitation::poubel::shoulder_anchor`; Koenemann's: its own arm mapping), so the error is the arms'
//!   copy, not the trunk's.
//! * **Static stability**: the signed distance of the CoM ground projection to the edge of the
//!   support polygon (positive inside, m): the convex hull of the sole outlines
//!   ([`FootFrames::outline`](crate::robots::FootFrames::outline)) of the feet on the ground, a foot being on the ground when all its
//!   outline points are within [`CONTACT_HEIGHT`] of the floor, and the contact points of the
//!   hands held as supports ([`crate::imitation::poubel::hand_support`]).
//! * **Executability**: joint-limit violations, and velocity-limit violations
//!   (`|Δq|/Δt > fraction · v_max`), counted per joint and frame.
//! * **Side slip**: how far a standing foot moved in the world from where it stood at the start
//!   of its stance, model switches included (m, and rad for its orientation). A foot stands
//!   when it is the model root or when the phase keeps it on the ground (both feet in DS and in
//!   the CoM steps of the transitions).
//! * **Locomotion and timing** ([`crate::imitation::metrics::travel`]): travel of the scaled human and of the robot,
//!   steps of both, catch-up time after the clip, the hands' lag; tracking errors over the clip's
//!   own frames apart from the hold that follows it ([`MetricsRecorder::mark_clip_end`]).
//! * **Reach** ([`crate::imitation::reach`]): the clip's frames whose hand reference lay beyond the arm's
//!   reach from the robot's own shoulder, and by how much (m); and per hand the part of its
//!   error that no arm posture within the joint limits (and the self-collision margin)
//!   removes, as far as a multi-start IK of the arm finds: the rest is lateness or an arm
//!   posture that cannot follow the reference.
//! * **Hands held as supports** ([`crate::imitation::poubel::hand_support`]): per hand, the contacts made, the
//!   time from the start of placing to the contact (s, robot clock), and the distance of the
//!   held hand from its contact point (m).
//! * **Self-collision clearance** ([`crate::imitation::metrics::clearance`]): the smallest distance of the
//!   profile's paired bodies over the run (m), and the frames closer than the margin.
//! * **Support changes and transitions**: changes of the human's support and of the robot's
//!   continuous phase (DS, RS, LS); the time from leaving one continuous phase to reaching the
//!   next (s). **Solve time** per frame (µs).

pub mod clearance;
mod series;
pub mod travel;
mod walking;

pub use walking::{WalkMeter, WalkingSummary};

pub use series::{HeldHand, MeanMax, Spread};

use series::{HeldHandTally, Series, TimeHistogram};

use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use crate::imitation::imitator::Imitator;
use crate::imitation::metrics::clearance::{ClearanceMeter, SelfClearance};
use crate::imitation::metrics::travel::{
    FootTiming, HandTiming, HandTrace, Stance, StepCounter, StepFollowing, Travel, TravelRecorder,
    robot_stance,
};
use crate::imitation::output::RobotFrame;
use crate::imitation::phase::{SupportKind, SupportPhase};
use crate::imitation::reach::{HandReach, ReachMeter};
use crate::imitation::reference::support::HumanSupport;
use crate::solver::JointBounds;
use crate::tasks::{convex_hull, hull_margin};

// The old paths of `output::CONTACT_HEIGHT` and `output::sole_on_floor`; kept for one release.
#[doc(hidden)]
pub use crate::imitation::output::{CONTACT_HEIGHT, sole_on_floor};

/// Frames of a run by the kind of the robot's phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SupportFrames {
    /// Frames in RS or LS.
    pub single: usize,
    /// Frames in DS.
    pub double: usize,
    /// Frames in a transition step (CoM to a foot, lift, lower, CoM to the middle).
    pub transitions: usize,
}

impl SupportFrames {
    /// The count of `kind`, mutable.
    fn of_kind(&mut self, kind: SupportKind) -> &mut usize {
        match kind {
            SupportKind::Single => &mut self.single,
            SupportKind::Double => &mut self.double,
            SupportKind::Transition => &mut self.transitions,
        }
    }
}

// The old path of `output::EFFECTORS`; kept for one release.
#[doc(hidden)]
pub use crate::imitation::output::EFFECTORS;

/// Tracking error of one effector.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectorError {
    /// Effector role name ([`EFFECTORS`]).
    pub name: &'static str,
    /// Over frames of single support where the effector was tracked (m).
    pub single_support: MeanMax,
    /// Over frames of double support where it was tracked (m).
    pub double_support: MeanMax,
    /// Over frames of the transition steps where it was tracked (m).
    pub transitions: MeanMax,
}

impl EffectorError {
    /// From its cells in [`SupportKind::index`] order.
    fn of_kinds(name: &'static str, [single, double, transitions]: [MeanMax; 3]) -> Self {
        EffectorError {
            name,
            single_support: single,
            double_support: double,
            transitions,
        }
    }

    /// Mean over every frame where it was tracked, whatever the phase (m); `None` if it was
    /// never tracked.
    pub fn mean(&self) -> Option<f64> {
        let cells = [
            &self.single_support,
            &self.double_support,
            &self.transitions,
        ];
        let count: usize = cells.iter().map(|c| c.count).sum();
        let sum: f64 = cells.iter().map(|c| c.mean * c.count as f64).sum();
        (count > 0).then(|| sum / count as f64)
    }
}

/// The metrics of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct ImitationMetrics {
    /// Frames imitated, the hold after the clip included.
    pub frames: usize,
    /// Time from the first to the last frame, the hold included (s).
    pub duration: f64,
    /// Frames of the clip itself: `frames` less the hold's
    /// ([`MetricsRecorder::mark_clip_end`]; all frames when it was not called).
    pub clip_frames: usize,
    /// Time from the first to the last frame of the clip itself (s).
    pub clip_duration: f64,
    /// Changes of the human's support (airborne frames ignored).
    pub human_support_changes: usize,
    /// Changes of the robot's continuous phase (DS, RS, LS).
    pub robot_support_changes: usize,
    /// The robot's continuous phases in order, e.g. `["DS", "RS", "DS"]`.
    pub robot_support_sequence: Vec<&'static str>,
    /// Durations of completed transitions (s).
    pub transition_durations: Spread,
    /// Tracking error per effector.
    pub effectors: Vec<EffectorError>,
    /// Smallest signed distance of the CoM projection to the support polygon's edge over all
    /// frames (m, positive inside).
    pub min_com_margin: f64,
    /// Frames whose CoM projection was outside the support polygon.
    pub frames_com_outside: usize,
    /// Joint positions outside their limits (joint × frame).
    pub joint_limit_violations: usize,
    /// Joint velocities above the allowed fraction of the rated velocity (joint × frame).
    pub velocity_limit_violations: usize,
    /// Frames in which some joint turned back at speed: it moved at least half its allowed
    /// velocity one way over the previous frame and at least half of it the other way over this
    /// one. A human's joints do not reverse within a frame (1/120 s at these speeds); the
    /// solver's solution does when it chatters (a near-singular level, an acceleration bound
    /// met in full every frame), which a servo either filters or shakes with.
    pub joint_reversal_frames: usize,
    /// Largest move of the support foot (the model root) from where its stance began (m); zero
    /// up to rounding, by construction of the model switches.
    pub max_support_slip: f64,
    /// Largest turn of the support foot from its heading when its stance began (rad).
    pub max_support_turn: f64,
    /// Largest move of the other foot while it stands (DS and the CoM steps), from where its
    /// stance began (m): held there by the IK's contact level, so up to the one-step
    /// linearisation error.
    pub max_held_foot_slip: f64,
    /// Largest turn of the other foot while it stands (rad).
    pub max_held_foot_turn: f64,
    /// Wall time per frame (µs).
    pub solve_time_us: Spread,
    /// Tracking error per effector over the clip's frames only (before
    /// [`MetricsRecorder::mark_clip_end`]; all frames if it was never called).
    pub effectors_clip: Vec<EffectorError>,
    /// The clip's frames in single support (RS or LS), in double support (DS) and in the
    /// transition steps (together `clip_frames`): a cell of [`Self::effectors_clip`] with no
    /// frames is empty because the phase does not track that effector, or because the robot
    /// never was in that support.
    pub clip_support_frames: SupportFrames,
    /// Hand errors over the clip's frames once the best time shift is removed (`l_hand`,
    /// `r_hand`).
    pub hands_clip_lag_removed: Vec<EffectorError>,
    /// The time shift (s) that best aligns the robot's hands with the scaled reference; see
    /// [`ImitationMetrics::hand_timing`] for whether it means the robot is late.
    pub hand_lag_s: f64,
    /// Over the clip's frames, how far the hand references lay beyond the arms' reach from the
    /// robot's shoulders (`[left, right]`; [`crate::imitation::reach`]); `None` when the profile maps no
    /// shoulder or hand.
    pub hand_reach: Option<[HandReach; 2]>,
    /// How long the human's clock was paused in all while hands were placed on their contacts
    /// (s): the robot's run is that much longer than the human's.
    pub human_clock_pause: f64,
    /// The hands held as supports (`[left, right]`); `None` when no hand was placed.
    pub held_hands: Option<[HeldHand; 2]>,
    /// How late the robot lifted each foot after the human lifted the same foot (s; one value
    /// per paired lift, [`crate::imitation::metrics::travel`]), and `human_lifts` how many the human made.
    pub lift_lag: Spread,
    /// How late the robot put each foot down after the human (s), paired as `lift_lag`.
    pub landing_lag: Spread,
    /// The human's lifts of a foot (at least 0.2 s): the events `lift_lag` pairs.
    pub human_lifts: usize,
    /// Travel of the scaled human and of the robot.
    pub travel: Travel,
    /// Steps (a foot off the floor ≥ 0.2 s) of the human and of the robot.
    pub human_steps: usize,
    /// See `human_steps`.
    pub robot_steps: usize,
    /// Human steps the robot had committed to and not taken at the last frame.
    pub queued_steps_at_end: usize,
    /// Seconds after the clip's end until the robot stood where the scaled human stands, or
    /// `None` if it never did (or the clip's end was not marked).
    pub catch_up_s: Option<f64>,
    /// How close the paired bodies came; `None` when the profile has no self-collision pairs.
    pub self_clearance: Option<SelfClearance>,
    /// Whether the robot had finished at the last frame ([`RobotFrame::has_finished`]): in a
    /// continuous phase, no step pending, on the human's feet. False after a hold that ended
    /// before the robot did (a fixed one too short, or the cap of an automatic one).
    pub finished: bool,
    /// The robot's walks ([`crate::imitation::walking`]); `None` when it never walked.
    pub walking: Option<WalkingSummary>,
    /// How the robot followed the human's steps; `None` when the human never stepped.
    pub following: Option<StepFollowing>,
}

impl ImitationMetrics {
    /// The hand lag with the hands' mean error over the clip without and with it removed (both
    /// hands, every phase that tracks them): whether the robot is late
    /// ([`HandTiming::late`]); `None` when no hand was tracked.
    pub fn hand_timing(&self) -> Option<HandTiming> {
        let pooled = |errors: &[EffectorError]| {
            let hands = errors.iter().filter(|e| e.name.ends_with("hand"));
            let cells = hands.flat_map(|e| [e.single_support, e.double_support, e.transitions]);
            let (sum, count) = cells.fold((0.0, 0), |(s, n), c| {
                (s + c.mean * c.count as f64, n + c.count)
            });
            (count > 0).then(|| sum / count as f64)
        };
        Some(HandTiming {
            lag_s: self.hand_lag_s,
            error_m: pooled(&self.effectors_clip)?,
            lag_removed_error_m: pooled(&self.hands_clip_lag_removed)?,
        })
    }
}

/// Accumulates [`ImitationMetrics`] frame by frame.
#[derive(Debug, Clone)]
pub struct MetricsRecorder {
    /// Per phase ([`SupportPhase::index`]), whether its table tracks each of [`EFFECTORS`]
    /// toward the scaled human.
    tracked: [[bool; 4]; SupportPhase::COUNT],
    /// The imitator's joint bounds (position and velocity).
    bounds: JointBounds,
    /// The contact area of each foot (`[left, right]`, sole frame, m).
    outlines: [Vec<[f64; 2]>; 2],
    /// Scratch: the grounded corners of this frame (world xy, m).
    points: Vec<Vector2<f64>>,
    frames: usize,
    first_time: Option<f64>,
    last_time: f64,
    /// The last frame's robot clock minus its human clock (s).
    clock_pause: f64,
    finished: bool,
    last_q: Vec<f64>,
    last_human: Option<HumanSupport>,
    human_changes: usize,
    sequence: Vec<&'static str>,
    transition_start: Option<f64>,
    transitions: Vec<f64>,
    /// Per [`SupportKind`], per effector: the errors over every frame.
    errors: [Vec<Series>; SupportKind::COUNT],
    min_margin: f64,
    outside: usize,
    joint_violations: usize,
    velocity_violations: usize,
    /// Each joint's step over the last frame, as a fraction of its allowed step (velocity
    /// bound × the frame's time); empty before the second frame.
    last_step: Vec<f64>,
    reversal_frames: usize,
    /// Where each foot's current stance began (right, left), `None` while it does not stand.
    anchors: [Option<IsometryMatrix3<f64>>; 2],
    slip: f64,
    turn: f64,
    held_slip: f64,
    held_turn: f64,
    times: TimeHistogram,
    /// The same over the clip's frames.
    errors_clip: [Vec<Series>; SupportKind::COUNT],
    clip_support_frames: SupportFrames,
    hands: HandTrace,
    held: [HeldHandTally; 2],
    clearance: Option<ClearanceMeter>,
    reach: Option<ReachMeter>,
    travel: TravelRecorder,
    human_steps: StepCounter,
    robot_steps: StepCounter,
    feet: FootTiming,
    /// The human's feet off the ground at the last frame (left, right); airborne keeps them.
    human_up: [bool; 2],
    pending: usize,
    /// Frames and last time when the clip ended ([`MetricsRecorder::mark_clip_end`]).
    clip_end: Option<(usize, f64)>,
    walking: WalkMeter,
}

fn continuous_name(phase: SupportPhase) -> Option<&'static str> {
    match phase {
        SupportPhase::Double => Some("DS"),
        SupportPhase::Right => Some("RS"),
        SupportPhase::Left => Some("LS"),
        _ => None,
    }
}

/// The tracking errors of [`EFFECTORS`] from their series per [`SupportKind`].
fn effector_errors(series: &[Vec<Series>; SupportKind::COUNT]) -> Vec<EffectorError> {
    (EFFECTORS.iter().enumerate())
        .map(|(e, (name, _))| {
            EffectorError::of_kinds(name, series.each_ref().map(|s| s[e].summary()))
        })
        .collect()
}

/// Signed distance of `p` to the boundary of the convex hull of `points` (positive inside).
pub fn convex_margin(points: &[Vector2<f64>], p: Vector2<f64>) -> f64 {
    let mut corners: Vec<[f64; 2]> = points.iter().map(|v| [v.x, v.y]).collect();
    let mut hull = Vec::with_capacity(corners.len());
    convex_hull(&mut corners, &mut hull);
    hull_margin(&hull, p)
}

/// The angle of a rotation, accurate near zero (`acos` of the trace loses half the digits).
fn rotation_angle(r: &nalgebra::Rotation3<f64>) -> f64 {
    let m = r.matrix();
    let sin = 0.5
        * Vector3::new(
            m[(2, 1)] - m[(1, 2)],
            m[(0, 2)] - m[(2, 0)],
            m[(1, 0)] - m[(0, 1)],
        )
        .norm();
    let cos = 0.5 * (m.trace() - 1.0);
    sin.atan2(cos)
}

impl MetricsRecorder {
    /// A recorder for the runs of `imitator`: which effectors each phase tracks,
    /// joint bounds and feet are read once here.
    pub fn new(imitator: &Imitator) -> Self {
        let profile = imitator.profile();
        let tracked = SupportPhase::ALL.map(|phase| imitator.tracked_effectors(phase));
        Self {
            tracked,
            bounds: imitator.bounds().clone(),
            outlines: profile.feet.each_ref().map(|f| f.outline.clone()),
            points: Vec::new(),
            frames: 0,
            first_time: None,
            last_time: 0.0,
            clock_pause: 0.0,
            finished: true,
            last_q: Vec::new(),
            last_human: None,
            human_changes: 0,
            sequence: Vec::new(),
            transition_start: None,
            transitions: Vec::new(),
            errors: std::array::from_fn(|_| vec![Series::default(); EFFECTORS.len()]),
            min_margin: f64::INFINITY,
            outside: 0,
            joint_violations: 0,
            velocity_violations: 0,
            last_step: Vec::new(),
            reversal_frames: 0,
            anchors: [None; 2],
            slip: 0.0,
            turn: 0.0,
            held_slip: 0.0,
            held_turn: 0.0,
            times: TimeHistogram::default(),
            errors_clip: std::array::from_fn(|_| vec![Series::default(); EFFECTORS.len()]),
            clip_support_frames: SupportFrames::default(),
            hands: HandTrace::default(),
            held: Default::default(),
            // The imitator validated its profile, so its pairs resolve.
            clearance: ClearanceMeter::new(profile).ok().flatten(),
            reach: ReachMeter::new(profile),
            travel: TravelRecorder::default(),
            human_steps: StepCounter::default(),
            robot_steps: StepCounter::default(),
            feet: FootTiming::default(),
            human_up: [false; 2],
            pending: 0,
            clip_end: None,
            walking: WalkMeter::new(profile),
        }
    }

    /// The clip's last frame has been recorded; the frames that follow are a hold (the human's
    /// last pose repeated) and count for the catch-up time, not for the clip's tracking errors.
    pub fn mark_clip_end(&mut self) {
        self.clip_end.get_or_insert((self.frames, self.last_time));
        self.travel.mark_clip_end(self.last_time);
    }

    /// The last recorded clip frame's least hand errors (`[left, right]`, m; see
    /// [`ReachMeter::last_least_errors`]); `None` for a hand without a reference, for every hand
    /// after the clip's end and on a profile that maps no hands.
    pub fn last_least_hand_errors(&self) -> [Option<f64>; 2] {
        match (&self.reach, self.travel.clip_ended()) {
            (Some(reach), false) => reach.last_least_errors(),
            _ => [None; 2],
        }
    }

    /// Records one frame, as returned by [`Imitator::step`].
    pub fn record(&mut self, frame: &RobotFrame) {
        self.record_tracking(frame);
        if !self.travel.clip_ended() {
            self.trace_hands(frame);
            if let Some(reach) = &mut self.reach {
                reach.record(frame);
            }
        }
        self.record_balance(frame);
        self.record_limits(frame);
        if let Some(meter) = &mut self.clearance {
            // The frame's q has the model's length: the imitator wrote it.
            meter.record(&frame.q).ok();
        }
        let standing = frame.phase.standing_feet();
        self.record_slip(frame, standing);

        // Travel and steps.
        let human = frame
            .human_stance
            .map(|(point, heading)| Stance { point, heading });
        let robot = robot_stance(&frame.right_sole, &frame.left_sole);
        let double = frame.phase == SupportPhase::Double;
        self.travel
            .record(human, frame.leg_ratio, robot, double, frame.time);
        let human_off = frame.human_support != HumanSupport::Double;
        self.human_steps.record(human_off, frame.time);
        self.robot_steps
            .record(!(standing[0] && standing[1]), frame.time);
        self.human_up = match frame.human_support {
            HumanSupport::Airborne => self.human_up,
            support => support.feet().map(|down| !down),
        };
        (self.feet).record(self.human_up, standing.map(|s| !s), frame.time);
        self.pending = frame.pending_steps;

        self.record_supports(frame);
        self.walking.record(frame);
        self.first_time.get_or_insert(frame.time);
        self.last_time = frame.time;
        self.clock_pause = frame.time - frame.human_time;
        self.finished = frame.has_finished();
        self.last_q.clear();
        self.last_q.extend_from_slice(&frame.q);
        self.times.record(frame.micros);
        self.frames += 1;
    }

    /// Tracking errors of the effectors the phase tracks, against their scaled references.
    fn record_tracking(&mut self, frame: &RobotFrame) {
        let kind = frame.phase.kind();
        let tracked = self.tracked[frame.phase.index()];
        let in_clip = !self.travel.clip_ended();
        let (all, clip) = (
            &mut self.errors[kind.index()],
            &mut self.errors_clip[kind.index()],
        );
        *self.clip_support_frames.of_kind(kind) += usize::from(in_clip);
        for (e, (_, joint)) in EFFECTORS.iter().enumerate() {
            let Some(reference) = frame.reference[joint.index()].filter(|_| tracked[e]) else {
                continue;
            };
            let error = (frame.effectors[e] - reference).norm();
            all[e].push(error);
            if in_clip {
                clip[e].push(error);
            }
        }
    }

    /// The CoM's margin inside the support polygon of the feet on the ground (world frame =
    /// root frame moved by `world_t_root`; heights are the same since the root sole is on the
    /// floor).
    fn record_balance(&mut self, frame: &RobotFrame) {
        self.points.clear();
        let soles = [&frame.left_sole, &frame.right_sole];
        for (outline, sole) in self.outlines.iter().zip(soles) {
            let corner = |&[x, y]: &[f64; 2]| sole.transform_point(&Vector3::new(x, y, 0.0).into());
            if sole_on_floor(outline, sole) {
                self.points
                    .extend(outline.iter().map(|c| corner(c).xy().coords));
            }
        }
        let held = frame.hand_supports.iter().flatten().filter(|h| h.holding);
        self.points.extend(held.map(|h| h.point.xy()));
        for (side, tally) in self.held.iter_mut().enumerate() {
            let hand = frame
                .world_t_root
                .transform_point(&frame.effectors[side].into());
            tally.record(frame.hand_supports[side], hand.coords, frame.time);
        }
        let margin = convex_margin(&self.points, frame.com.xy());
        self.min_margin = self.min_margin.min(margin);
        if margin < 0.0 {
            self.outside += 1;
        }
    }

    /// Joint-limit and velocity-limit violations.
    fn record_limits(&mut self, frame: &RobotFrame) {
        let bounds = &self.bounds;
        for (i, &q) in frame.q.iter().enumerate() {
            if q < bounds.lower()[i] || q > bounds.upper()[i] || !q.is_finite() {
                self.joint_violations += 1;
            }
        }
        if self.last_q.is_empty() {
            return;
        }
        let dt = frame.time - self.last_time;
        let first_step = self.last_step.is_empty();
        self.last_step.resize(frame.q.len(), 0.0);
        let mut reversed = false;
        for (i, (&q, &p)) in frame.q.iter().zip(&self.last_q).enumerate() {
            let allowed = bounds.velocity()[i] * dt;
            if (q - p).abs() > allowed * (1.0 + 1e-9) + 1e-12 {
                self.velocity_violations += 1;
            }
            let step = if allowed > 0.0 {
                (q - p) / allowed
            } else {
                0.0
            };
            let last = std::mem::replace(&mut self.last_step[i], step);
            reversed |= !first_step && step.abs() >= 0.5 && last.abs() >= 0.5 && step * last < 0.0;
        }
        self.reversal_frames += usize::from(reversed);
    }

    /// Slip of the `standing` feet: how far each moved since its stance began.
    fn record_slip(&mut self, frame: &RobotFrame, standing: [bool; 2]) {
        let placement = [frame.left_sole, frame.right_sole];
        for foot in 0..2 {
            if !standing[foot] {
                self.anchors[foot] = None;
                continue;
            }
            let then = *self.anchors[foot].get_or_insert(placement[foot]);
            let now = placement[foot];
            let slip = (now.translation.vector - then.translation.vector).norm();
            let turn = rotation_angle(&(then.rotation.inverse() * now.rotation));
            let (max_slip, max_turn) = if foot == frame.root.index() {
                (&mut self.slip, &mut self.turn)
            } else {
                (&mut self.held_slip, &mut self.held_turn)
            };
            *max_slip = max_slip.max(slip);
            *max_turn = max_turn.max(turn);
        }
    }

    /// Changes of the human's support and of the robot's continuous phase; transition times.
    fn record_supports(&mut self, frame: &RobotFrame) {
        if frame.human_support != HumanSupport::Airborne {
            if self.last_human.is_some_and(|h| h != frame.human_support) {
                self.human_changes += 1;
            }
            self.last_human = Some(frame.human_support);
        }
        if self.frames == 0 {
            // The robot starts in a continuous phase even if its first frame is a transition.
            let origin = match frame.phase {
                SupportPhase::DoubleToRight(_) | SupportPhase::DoubleToLeft(_) => Some("DS"),
                SupportPhase::RightToDouble(_) => Some("RS"),
                SupportPhase::LeftToDouble(_) => Some("LS"),
                _ => None,
            };
            self.sequence.extend(origin);
        }
        match continuous_name(frame.phase) {
            Some(name) if self.sequence.last() != Some(&name) => {
                self.sequence.push(name);
                if let Some(start) = self.transition_start.take() {
                    self.transitions.push(frame.time - start);
                }
            }
            Some(_) => {}
            None => {
                self.transition_start.get_or_insert(self.last_time);
            }
        }
    }

    /// Adds this frame's hands and their references (world frame) to the lag trace.
    fn trace_hands(&mut self, frame: &RobotFrame) {
        let world = |p: &Vector3<f64>| frame.world_t_root.transform_point(&(*p).into()).coords;
        let robot = [world(&frame.effectors[0]), world(&frame.effectors[1])];
        let reference = [EFFECTORS[0].1, EFFECTORS[1].1]
            .map(|joint| frame.reference[joint.index()].as_ref().map(world));
        (self.hands).record(frame.time, robot, reference, frame.phase.kind());
    }

    /// The metrics of the frames recorded so far.
    pub fn finish(&self) -> ImitationMetrics {
        let mut transitions = self.transitions.clone();
        // The lag search is quadratic in the clip's frames: once.
        let (lag_errors, hand_lag_s) = self.hands.lag_removed();
        let first_time = self.first_time.unwrap_or(self.last_time);
        let (clip_frames, clip_end) = self.clip_end.unwrap_or((self.frames, self.last_time));
        let ((mut lift_lag, human_lifts), (mut landing_lag, _)) = self.feet.lags();
        ImitationMetrics {
            frames: self.frames,
            duration: self.last_time - first_time,
            clip_frames,
            clip_duration: clip_end - first_time,
            human_support_changes: self.human_changes,
            robot_support_changes: self.sequence.len().saturating_sub(1),
            robot_support_sequence: self.sequence.clone(),
            transition_durations: Spread::of(&mut transitions),
            effectors: effector_errors(&self.errors),
            min_com_margin: self.min_margin,
            frames_com_outside: self.outside,
            joint_limit_violations: self.joint_violations,
            velocity_limit_violations: self.velocity_violations,
            joint_reversal_frames: self.reversal_frames,
            max_support_slip: self.slip,
            max_support_turn: self.turn,
            max_held_foot_slip: self.held_slip,
            max_held_foot_turn: self.held_turn,
            solve_time_us: self.times.spread(),
            effectors_clip: effector_errors(&self.errors_clip),
            clip_support_frames: self.clip_support_frames,
            hands_clip_lag_removed: {
                let cell = |(mean, max, count): (f64, f64, usize)| MeanMax { mean, max, count };
                EFFECTORS[..2]
                    .iter()
                    .zip(lag_errors)
                    .map(|((name, _), cells)| EffectorError::of_kinds(name, cells.map(cell)))
                    .collect()
            },
            hand_lag_s,
            hand_reach: self.reach.as_ref().map(ReachMeter::reach),
            human_clock_pause: self.clock_pause,
            held_hands: (self.held.iter().any(|h| h.placed))
                .then(|| self.held.each_ref().map(HeldHandTally::summary)),
            finished: self.finished,
            walking: self.walking.finish(),
            following: self.feet.following(),
            lift_lag: Spread::of(&mut lift_lag),
            landing_lag: Spread::of(&mut landing_lag),
            human_lifts,
            travel: self.travel.travel(),
            human_steps: self.human_steps.steps(),
            robot_steps: self.robot_steps.steps(),
            queued_steps_at_end: self.pending,
            catch_up_s: self.travel.catch_up(),
            self_clearance: self.clearance.as_ref().and_then(ClearanceMeter::clearance),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_time_quantiles_match_the_exact_order_statistics() {
        // 10 001 times spread over four decades, in a scrambled order.
        let mut exact: Vec<f64> = (0..=10_000)
            .map(|i| 10f64.powf(((i * 7919) % 10_001) as f64 / 2500.0))
            .collect();
        let mut histogram = TimeHistogram::default();
        for &t in &exact {
            histogram.record(t);
        }
        let spread = histogram.spread();
        let reference = Spread::of(&mut exact);
        assert_eq!(spread.count, reference.count);
        assert_eq!((spread.min, spread.max), (reference.min, reference.max));
        for (got, want) in [
            (spread.median, reference.median),
            (spread.p99, reference.p99),
        ] {
            assert!((got / want - 1.0).abs() <= 5e-4, "{got} vs {want}");
        }
        assert_eq!(TimeHistogram::default().spread(), Spread::default());
    }
}
