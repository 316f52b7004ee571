//! Hand references out of the robot arm's reach: a hand error that is not lateness, and the
//! hand targets the imitation keeps within reach.
//!
//! A hand's scaled reference is placed from the *scaled* shoulder with the robot's segment
//! lengths ([`super::scaler`], eq. 1), so it is always within the arm's length of that point;
//! Poubel's method then hangs the arm from the robot's shoulder (`imitation::poubel::shoulder_anchor`),
//! which leaves the references the robot's elbow cannot fold to.
//! The robot's own shoulder is elsewhere whenever its trunk does not follow the scaled one: the
//! tables hold the torso upright over the stance foot, a robot standing on bent knees carries
//! its hips lower than the scaled hips, and a robot whose waist is not tracked (the G1) keeps
//! its shoulders where its posture puts them. And a human elbow folds further than most robot
//! elbows, so a reference can also lie nearer the shoulder than the robot's hand gets.
//!
//! `Arm` measures each arm in the model, by forward kinematics from the standing posture:
//! its elbow is the variable that changes the shoulder–hand distance `d(θ)` most over its
//! range, and the arm spans `[d_min, d_max]`, the extremes of `d` over that range. Per frame of
//! the clip the meter measures how far each hand's reference lies outside that span around
//! the robot's current shoulder:
//!
//! ```text
//! shortfall = max(0, |p_hand^ref − p_shoulder^robot(q)| − d_max, d_min − |…|)
//! ```
//!
//! A hand's error on such a frame is at least its shortfall whatever the arm does. Positions
//! in the left-rooted model's base frame; the references are moved there from the frame's root.
//!
//! The distance test cannot see the joint ranges. Per frame whose hand is more than 2 mm off,
//! the meter also looks for the least error any posture of the arm gets: the arm's variables
//! (those that move the hand relative to the chest, or the torso, found in the model) are
//! solved for the reference by damped Gauss–Newton steps kept inside the joint ranges,
//! `δq = Jᵀ(JJᵀ + μ²I)⁻¹(p_ref − p_hand)` with `μ` = 5 mm, each step halved until it brings the
//! hand nearer, the rest of the body at the frame's posture; from the frame's posture, from
//! the last frame's best, and from the samples nearest the reference of a grid over the arm's
//! joint ranges (at most 4 096, computed once). A posture counts when it keeps the profile's
//! self-collision pairs at their margin. The least error found, or the frame's own, is an upper
//! bound on the error no arm posture removes (a search can miss a better posture, never invent
//! one): the rest of the hand's error is lateness, or an arm caught in a posture it cannot
//! follow the reference from.
//!
//! Poubel's method aims each hand at its reference pulled along the line to the shoulder until
//! the arm reaches it with its elbow `MIN_ELBOW_BEND` (0.3 rad) from straight
//! (`Arm::within_reach`), and keeps the elbow at least that bent (`Elbow::interval`). A
//! reference nearer than the fully bent elbow brings the hand stays where it is: the bent limit
//! is no singularity, and moving such targets out cost the G1 2 cm of mean hand error on CMU
//! 131_01.

mod posture;

use nalgebra::{IsometryMatrix3, Matrix3, Vector3};

use self::posture::ArmPostures;
use super::output::EFFECTORS;
use super::output::RobotFrame;
use crate::human::{HumanJoint, Side};
use crate::model::{FrameId, Model, ModelData};
use crate::robots::{BipedProfile, RobotPoint};
use crate::tasks::Capsule;

/// How far one hand's references lay beyond the arm's reach over the frames measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandReach {
    /// The farthest the hand gets from the shoulder point: the elbow at its straightest (m).
    pub reach_m: f64,
    /// The nearest the hand gets to the shoulder point: the elbow at its most bent (m).
    pub min_reach_m: f64,
    /// Frames measured (the clip's frames with a reference for this hand).
    pub frames: usize,
    /// Frames whose reference lay beyond `reach_m` from the robot's shoulder, or nearer than
    /// `min_reach_m`.
    pub unreachable_frames: usize,
    /// Mean shortfall over the unreachable frames (m); `None` without any.
    pub mean_shortfall_m: Option<f64>,
    /// Largest shortfall (m); `None` without any unreachable frame.
    pub max_shortfall_m: Option<f64>,
    /// Mean distance of the hand from its reference over the frames measured (m); `None`
    /// without any.
    pub mean_error_m: Option<f64>,
    /// Mean over the frames measured of the least distance from the reference to which some
    /// posture of the arm within its joint ranges (the rest of the body at the frame's posture,
    /// the profile's self-collision margin kept) brings the hand, as far as a multi-start
    /// search finds (module docs): an upper bound on the error no arm posture removes (m);
    /// `None` without any frame. `mean_error_m` less this is error some posture removes.
    pub mean_least_error_m: Option<f64>,
    /// The largest of those least distances (m); `None` without any frame.
    pub max_least_error_m: Option<f64>,
    /// Frames whose least distance exceeded [`POSTURE_UNREACHABLE`]: the reference lay out of
    /// the arm's joint ranges, whatever its distance from the shoulder.
    pub posture_unreachable_frames: usize,
}

/// A frame whose reference no posture of the arm brings the hand nearer than this (m) counts
/// in [`HandReach::posture_unreachable_frames`].
pub const POSTURE_UNREACHABLE: f64 = 0.01;

/// A hand at most this far from its reference (m) is not searched for a nearer posture: its
/// own distance stands for the least.
const SEARCH_FROM: f64 = 2e-3;

/// How far inside the self-collision margin (or the frame's own clearance, if nearer) a
/// searched posture may end (m): the IK's first-order steps end a hair inside, as the
/// imitation's do.
const MARGIN_SLACK: f64 = 1e-4;

/// One robot arm in a model: the frames of its shoulder point and hand, and how near to and
/// far from the shoulder its elbow can bring the hand.
#[derive(Debug, Clone, Copy)]
pub(super) struct Arm {
    hand: HumanJoint,
    hand_frame: FrameId,
    /// The shoulder point is the mean of these frames' origins (the same frame twice for a
    /// [`RobotPoint::Frame`]).
    shoulder: [FrameId; 2],
    /// The profile's torso frame, and the shoulder point in it in the standing posture: where
    /// the shoulder stands whatever a waist between them does.
    torso: FrameId,
    shoulder_in_torso: Vector3<f64>,
    /// The shoulder–hand distances the elbow spans over its joint range, `[nearest, farthest]`
    /// (m): the arm's reach.
    span: [f64; 2],
    /// The farthest over the interval the imitation keeps the elbow in ([`Elbow::interval`]).
    kept_reach: f64,
    elbow: Option<Elbow>,
}

/// The elbow of an arm: the variable that changes the shoulder–hand distance most over its
/// range, found in the model by forward kinematics (no joint names).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Elbow {
    /// Its variable index.
    pub(super) variable: usize,
    /// The interval the imitation keeps it in (rad): its range less the angles within
    /// [`MIN_ELBOW_BEND`] of the straight arm ([`straight_angle`]; the longer side of what
    /// remains), widened to include the standing posture.
    pub(super) interval: [f64; 2],
}

/// The least bend of the elbow (rad), from the straight arm, that the imitation leaves
/// an arm ([`Elbow::interval`], [`Arm::within_reach`]). A straight elbow is singular: bending
/// it moves the hand across the arm, not along it, so a one-step (Gauss–Newton) IK cannot
/// shorten a straight arm, and an elbow held at its straight limit by the clamping stays
/// there. On the NAO a hand stayed straight-armed 20–30 cm from its reference for seconds
/// (CMU 02_10's right hand, 05_02's left) after the reference had passed out of reach. At
/// 0.3 rad the hand still moves 30 % as fast along the arm as across it, and a two-segment
/// arm of equal segments reaches `1 − cos 0.15 ≈ 1 %` less far.
pub(super) const MIN_ELBOW_BEND: f64 = 0.3;

/// Samples of a variable's range when looking for the elbow.
const ELBOW_SAMPLES: usize = 64;

/// A change of the shoulder–hand distance (m) below this is rounding: the variable does not
/// lie between the shoulder and the hand.
const OFF_CHAIN: f64 = 1e-9;

impl Arm {
    /// The `side` arm of `profile` in `model`, measured in `profile`'s standing posture; `None`
    /// when its hand or shoulder is not mapped or a frame is unknown.
    pub(super) fn of(profile: &BipedProfile, model: &Model, side: Side) -> Option<Self> {
        let (hand, shoulder) = match side {
            Side::Left => (EFFECTORS[0].1, HumanJoint::LShoulder),
            Side::Right => (EFFECTORS[1].1, HumanJoint::RShoulder),
        };
        let frame = |name: &str| model.frame_id(name).ok();
        let shoulder = match &profile.points.iter().find(|(j, _)| *j == shoulder)?.1 {
            RobotPoint::Frame(a) => [frame(a)?; 2],
            RobotPoint::Midpoint(a, b) => [frame(a)?, frame(b)?],
        };
        let mut arm = Self {
            hand,
            hand_frame: frame(&profile.hands[side.index()])?,
            shoulder,
            torso: frame(&profile.torso)?,
            shoulder_in_torso: Vector3::zeros(),
            span: [0.0; 2],
            kept_reach: 0.0,
            elbow: None,
        };
        arm.measure(model, &profile.stand)?;
        Some(arm)
    }

    /// Finds the shoulder in the torso frame, the elbow and the spans from `stand` (see
    /// [`Elbow`]); `None` when the forward kinematics fails (a posture of the wrong length).
    fn measure(&mut self, model: &Model, stand: &[f64]) -> Option<()> {
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, stand).ok()?;
        let torso = data.frame_placement(self.torso);
        self.shoulder_in_torso =
            (torso.inverse_transform_point(&self.shoulder_point(&data).into())).coords;
        let standing = self.hand_distance(&data);
        let mut q = stand.to_vec();
        let mut distance = |q: &[f64]| {
            model.forward_kinematics(&mut data, q).ok()?;
            Some(self.hand_distance(&data))
        };
        let (mut elbow, mut widest) = (None, 0.0);
        for (k, v) in model.variables().iter().enumerate() {
            if !(v.lower.is_finite() && v.upper.is_finite() && v.upper > v.lower) {
                continue;
            }
            // `(angle, distance)` with the variable at the fraction `t` of its range.
            let mut at = |t: f64| {
                q[k] = v.lower + t * (v.upper - v.lower);
                Some((q[k], distance(&q)?))
            };
            // A variable off the shoulder–hand chain moves both rigidly: the ends and the
            // middle of its range leave the distance as it stands, and it is not swept.
            let mut moves = false;
            for t in [0.0, 0.5, 1.0] {
                moves |= (at(t)?.1 - standing).abs() > OFF_CHAIN;
            }
            if !moves {
                q[k] = stand[k];
                continue;
            }
            let mut samples = [(0.0, 0.0); ELBOW_SAMPLES];
            for (i, sample) in samples.iter_mut().enumerate() {
                *sample = at(i as f64 / (ELBOW_SAMPLES - 1) as f64)?;
            }
            q[k] = stand[k];
            let [near, far] = span(&samples, [v.lower, v.upper]);
            if far - near > widest {
                widest = far - near;
                elbow = Some((k, samples, [near, far]));
            }
        }
        let Some((variable, samples, full_span)) = elbow else {
            (self.span, self.kept_reach) = ([standing; 2], standing);
            return Some(());
        };
        let v = &model.variables()[variable];
        let straight = straight_angle(&samples)?;
        // The range less the angles within MIN_ELBOW_BEND of straight: the longer side.
        let (near, far) = (straight - MIN_ELBOW_BEND, straight + MIN_ELBOW_BEND);
        let above = [v.lower.max(far), v.upper];
        let below = [v.lower, v.upper.min(near)];
        let mut interval = match above[1] - above[0] >= below[1] - below[0] {
            true => above,
            false => below,
        };
        interval = [
            interval[0].min(stand[variable]),
            interval[1].max(stand[variable]),
        ];
        if interval[0] >= interval[1] {
            interval = [v.lower, v.upper];
        }
        self.span = full_span;
        self.kept_reach = span(&samples, interval)[1];
        self.elbow = Some(Elbow { variable, interval });
        Some(())
    }

    /// The nearest the hand gets to the shoulder point (m): the elbow at its most bent.
    pub(super) fn nearest(&self) -> f64 {
        self.span[0]
    }

    /// The elbow, when the arm has one.
    pub(super) fn elbow(&self) -> Option<Elbow> {
        self.elbow
    }

    /// The shoulder point of the kinematics in `data` (model base frame, m).
    fn shoulder_point(&self, data: &ModelData) -> Vector3<f64> {
        let [a, b] = self
            .shoulder
            .map(|f| data.frame_placement(f).translation.vector);
        (a + b) * 0.5
    }

    /// The shoulder point of the standing posture carried by the torso of the kinematics in
    /// `data` (model base frame, m): the shoulder point itself when no joint lies between
    /// them, and for a robot with a waist where the shoulder stands with the waist at rest.
    pub(super) fn torso_shoulder_point(&self, data: &ModelData) -> Vector3<f64> {
        let torso = data.frame_placement(self.torso);
        torso.transform_point(&self.shoulder_in_torso.into()).coords
    }

    /// The distance from the shoulder point to the hand in `data` (m).
    fn hand_distance(&self, data: &ModelData) -> f64 {
        (data.frame_placement(self.hand_frame).translation.vector - self.shoulder_point(data))
            .norm()
    }

    /// How far `target` (model base frame, m) lies outside the arm's reach from the shoulder
    /// point of the kinematics in `data`, beyond it or nearer than the bent elbow brings the
    /// hand (m; negative within it).
    fn shortfall(&self, data: &ModelData, target: &Vector3<f64>) -> f64 {
        let d = (target - self.shoulder_point(data)).norm();
        (d - self.span[1]).max(self.span[0] - d)
    }

    /// `target` (model base frame, m) pulled along the line to the shoulder point of `data`
    /// until the arm reaches it with its elbow in [`Elbow::interval`]; unchanged when it is
    /// that near.
    pub(super) fn within_reach(&self, data: &ModelData, target: Vector3<f64>) -> Vector3<f64> {
        let shoulder = self.shoulder_point(data);
        let arm = target - shoulder;
        let distance = arm.norm();
        match distance > self.kept_reach {
            true => shoulder + arm * (self.kept_reach / distance),
            false => target,
        }
    }
}

/// The angle at which the arm is straight (rad): a revolute joint between two rigid segments
/// puts their far ends `d(θ)` apart with `d² = A + B cos θ + C sin θ` (the law of cosines), so
/// a least-squares fit of `d²` over `samples` (`(θ, d)`) gives it as `atan2(C, B)`, the angle of
/// the largest `d`, whether or not the joint's range reaches it. Wrapped to the turn nearest
/// the samples' middle; `None` when the fit is singular (fewer than three distinct angles).
fn straight_angle(samples: &[(f64, f64)]) -> Option<f64> {
    let mut normal = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    for &(angle, d) in samples {
        let row = Vector3::new(1.0, angle.cos(), angle.sin());
        normal += row * row.transpose();
        rhs += row * (d * d);
    }
    let [_, b, c] = normal.cholesky()?.solve(&rhs).into();
    let middle = 0.5 * (samples.first()?.0 + samples.last()?.0);
    let straight = c.atan2(b);
    let turns = ((middle - straight) / std::f64::consts::TAU).round();
    Some(straight + turns * std::f64::consts::TAU)
}

/// The nearest and farthest distance among `samples` (`(angle, distance)`) whose angle lies in
/// `interval`.
fn span(samples: &[(f64, f64)], [lo, hi]: [f64; 2]) -> [f64; 2] {
    let kept = samples.iter().filter(|(a, _)| (lo..=hi).contains(a));
    kept.fold([f64::INFINITY, f64::NEG_INFINITY], |[n, f], &(_, d)| {
        [n.min(d), f.max(d)]
    })
}

/// Measures [`HandReach`] frame by frame (see the module docs).
#[derive(Debug, Clone)]
pub struct ReachMeter {
    model: Model,
    data: ModelData,
    /// The soles in the left-rooted model (`[left, right]`): where a frame's root is.
    soles: [FrameId; 2],
    arms: [Arm; 2],
    postures: [ArmPostures; 2],
    apart: KeptApart,
    tallies: [Tally; 2],
    /// The last recorded frame's least error per hand (m; `None` without a reference).
    last_least: [Option<f64>; 2],
}

/// The profile's self-collision pairs, and the distance each must keep in a searched posture:
/// its margin, or as far as the frame's own posture had it where that was nearer, less
/// [`MARGIN_SLACK`].
#[derive(Debug, Clone)]
struct KeptApart {
    pairs: Vec<[Capsule; 2]>,
    margin: f64,
    floors: Vec<f64>,
}

impl KeptApart {
    /// Sets the floors from the frame whose forward kinematics is in `data`.
    fn at_frame(&mut self, model: &Model, data: &ModelData) {
        for (floor, pair) in self.floors.iter_mut().zip(&self.pairs) {
            *floor = self.margin.min(pair_distance(pair, model, data)) - MARGIN_SLACK;
        }
    }

    /// Whether the posture whose forward kinematics is in `data` keeps every pair at its floor.
    fn keeps(&self, model: &Model, data: &ModelData) -> bool {
        let mut pairs = self.pairs.iter().zip(&self.floors);
        pairs.all(|(pair, &floor)| pair_distance(pair, model, data) >= floor)
    }
}

/// The distance between a pair of capsules (m; −∞ when the kinematics is missing).
fn pair_distance([a, b]: &[Capsule; 2], model: &Model, data: &ModelData) -> f64 {
    a.distance_to(b, model, data).unwrap_or(f64::NEG_INFINITY)
}

/// One hand's sums over the frames measured.
#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    frames: usize,
    unreachable: usize,
    shortfall_sum: f64,
    shortfall_max: f64,
    error_sum: f64,
    least_sum: f64,
    least_max: f64,
    posture_unreachable: usize,
}

impl ReachMeter {
    /// A meter for `profile`'s arms; `None` when a hand or shoulder is not mapped or the profile
    /// cannot be measured (the imitator validated its profile, so that is the unmapped case).
    pub fn new(profile: &BipedProfile) -> Option<Self> {
        let model = profile.models[Side::Left.index()].clone();
        let arm = |side| Arm::of(profile, &model, side);
        let arms = [arm(Side::Left)?, arm(Side::Right)?];
        let frame = |name: &str| model.frame_id(name).ok();
        let upper_body = frame(profile.chest.as_ref().unwrap_or(&profile.torso))?;
        let postures =
            |arm: &Arm| ArmPostures::of(&model, &profile.stand, upper_body, arm.hand_frame);
        let postures = [postures(&arms[0])?, postures(&arms[1])?];
        let pairs = profile
            .self_collision
            .resolve(&model, &profile.stand)
            .ok()?;
        Some(Self {
            data: model.new_data(),
            soles: [
                frame(&profile.foot(Side::Left).sole)?,
                frame(&profile.foot(Side::Right).sole)?,
            ],
            arms,
            postures,
            apart: KeptApart {
                floors: vec![0.0; pairs.len()],
                pairs,
                margin: profile.self_collision.margin,
            },
            model,
            tallies: [Tally::default(); 2],
            last_least: [None; 2],
        })
    }

    /// Records one frame of the clip.
    pub fn record(&mut self, frame: &RobotFrame) {
        let Self {
            model,
            data,
            soles,
            arms,
            postures,
            apart,
            tallies,
            last_least,
        } = self;
        *last_least = [None; 2];
        if model.forward_kinematics(data, &frame.q).is_err() {
            return;
        }
        let base_t_root: IsometryMatrix3<f64> = *data.frame_placement(soles[frame.root.index()]);
        let mut searches = [None; 2];
        for (k, (arm, tally)) in arms.iter().zip(tallies.iter_mut()).enumerate() {
            let reference = frame.reference[arm.hand.index()];
            let Some(reference) = reference.filter(|r| r.iter().all(|v| v.is_finite())) else {
                postures[k].forget();
                continue;
            };
            let reference = base_t_root.transform_point(&reference.into()).coords;
            let shortfall = arm.shortfall(data, &reference);
            tally.frames += 1;
            if shortfall > 0.0 {
                tally.unreachable += 1;
                tally.shortfall_sum += shortfall;
                tally.shortfall_max = tally.shortfall_max.max(shortfall);
            }
            let hand = data.frame_placement(arm.hand_frame).translation.vector;
            searches[k] = Some((reference, (reference - hand).norm()));
        }
        // The floors only for a frame with a hand to search: most frames have none.
        if searches
            .iter()
            .flatten()
            .any(|&(_, error)| error > SEARCH_FROM)
        {
            apart.at_frame(model, data);
        }
        for (k, search) in searches.iter().enumerate() {
            let Some((reference, error)) = *search else {
                continue;
            };
            let least = match error > SEARCH_FROM {
                true => postures[k]
                    .least_error(model, data, &frame.q, &reference, |m, d| apart.keeps(m, d))
                    .map_or(error, |found| found.min(error)),
                false => error,
            };
            last_least[k] = Some(least);
            let tally = &mut tallies[k];
            tally.error_sum += error;
            tally.least_sum += least;
            tally.least_max = tally.least_max.max(least);
            tally.posture_unreachable += usize::from(least > POSTURE_UNREACHABLE);
        }
    }

    /// The last recorded frame's least hand errors (`[left, right]`, m): the part of each
    /// hand's error no arm posture within the limits removes (its error itself when below
    /// the search's threshold); `None` for a hand without a reference.
    pub fn last_least_errors(&self) -> [Option<f64>; 2] {
        self.last_least
    }

    /// The reach of both hands (`[left, right]`) over the frames recorded.
    pub fn reach(&self) -> [HandReach; 2] {
        std::array::from_fn(|k| {
            let t = self.tallies[k];
            let any = t.unreachable > 0;
            let measured = t.frames > 0;
            HandReach {
                reach_m: self.arms[k].span[1],
                min_reach_m: self.arms[k].span[0],
                frames: t.frames,
                unreachable_frames: t.unreachable,
                mean_shortfall_m: any.then(|| t.shortfall_sum / t.unreachable as f64),
                max_shortfall_m: any.then_some(t.shortfall_max),
                mean_error_m: measured.then(|| t.error_sum / t.frames as f64),
                mean_least_error_m: measured.then(|| t.least_sum / t.frames as f64),
                max_least_error_m: measured.then_some(t.least_max),
                posture_unreachable_frames: t.posture_unreachable,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An arm of 0.10 m and 0.12 m segments, straight at 1.44 rad, sampled over [−1, 1] rad
    /// only: the distances from the law of cosines, `d² = a² + b² + 2ab cos(θ − θ₀)`.
    #[test]
    fn the_straight_angle_is_found_outside_the_sampled_range() {
        let (a, b, straight) = (0.10, 0.12, 1.44);
        let samples: Vec<(f64, f64)> = (0..ELBOW_SAMPLES)
            .map(|i| {
                let angle = -1.0 + 2.0 * i as f64 / (ELBOW_SAMPLES - 1) as f64;
                let d2 = a * a + b * b + 2.0 * a * b * (angle - straight).cos();
                (angle, d2.sqrt())
            })
            .collect();
        let found = straight_angle(&samples).unwrap();
        assert!((found - straight).abs() < 1e-9, "{found}");
        // Fewer than three distinct angles cannot fix the fit.
        assert!(straight_angle(&samples[..1]).is_none());
    }
}
