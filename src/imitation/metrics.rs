//! What an imitation run achieved, measured frame by frame from the [`RobotFrame`]s.
//!
//! * **Tracking**: distance between each tracked effector (hands, free ankle) and its scaled
//!   reference, in the model root's frame (m), split by single and double support.
//! * **Static stability**: the signed distance of the CoM ground projection to the edge of the
//!   support polygon (positive inside, m): the convex hull of the sole outlines
//!   ([`Foot::sole_outline`]) of the feet on the ground, a foot being on the ground when all its
//!   outline points are within [`CONTACT_HEIGHT`] of the floor.
//! * **Executability**: joint-limit violations, and velocity-limit violations
//!   (`|Δq|/Δt > fraction · v_max`), counted per joint and frame.
//! * **Foot slip**: how far the support foot (the model root) moved in the world between two
//!   frames in which it was on the ground, model switches included (m, and rad for its
//!   orientation).
//! * **Support changes and transitions**: changes of the human's support and of the robot's
//!   continuous phase (DS, RS, LS); the time from leaving one continuous phase to reaching the
//!   next (s). **Solve time** per frame (µs).

use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use super::human::HumanJoint;
use super::imitator::{Imitator, RobotFrame};
use super::phase::SupportPhase;
use super::support::HumanSupport;
use crate::model::{ModelData, ModelError};
use crate::robots::nao::Foot;

/// A foot is on the ground when its outline points are at most this high (m).
pub const CONTACT_HEIGHT: f64 = 1e-3;

/// Mean and maximum of a series.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeanMax {
    /// Mean.
    pub mean: f64,
    /// Maximum.
    pub max: f64,
    /// Number of samples.
    pub count: usize,
}

/// Minimum, median and maximum of a series.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Spread {
    /// Minimum.
    pub min: f64,
    /// Median.
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Maximum.
    pub max: f64,
    /// Number of samples.
    pub count: usize,
}

impl Spread {
    fn of(values: &mut [f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        values.sort_by(f64::total_cmp);
        let at = |p: f64| values[((values.len() - 1) as f64 * p).round() as usize];
        Self {
            min: values[0],
            median: at(0.5),
            p99: at(0.99),
            max: values[values.len() - 1],
            count: values.len(),
        }
    }
}

#[derive(Debug, Clone, Default)]
struct Series {
    sum: f64,
    max: f64,
    count: usize,
}

impl Series {
    fn push(&mut self, v: f64) {
        self.sum += v;
        self.max = self.max.max(v);
        self.count += 1;
    }

    fn summary(&self) -> MeanMax {
        MeanMax {
            mean: if self.count > 0 {
                self.sum / self.count as f64
            } else {
                0.0
            },
            max: self.max,
            count: self.count,
        }
    }
}

/// The effectors whose tracking is measured, with the human joint their reference comes from.
pub const EFFECTORS: [(&str, HumanJoint); 4] = [
    ("l_hand", HumanJoint::LHand),
    ("r_hand", HumanJoint::RHand),
    ("l_ankle", HumanJoint::LAnkle),
    ("r_ankle", HumanJoint::RAnkle),
];

/// Tracking error of one effector.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectorError {
    /// Frame name.
    pub name: &'static str,
    /// Over frames of single support where the effector was tracked (m).
    pub single_support: MeanMax,
    /// Over frames of double support where it was tracked (m).
    pub double_support: MeanMax,
}

/// The metrics of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct ImitationMetrics {
    /// Frames imitated.
    pub frames: usize,
    /// Time from the first to the last frame (s).
    pub duration: f64,
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
    /// Largest move of the support foot between frames it stood on (m).
    pub max_support_slip: f64,
    /// Largest turn of the support foot between frames it stood on (rad).
    pub max_support_turn: f64,
    /// Wall time per frame (µs).
    pub solve_time_us: Spread,
}

/// Accumulates [`ImitationMetrics`] frame by frame.
pub struct MetricsRecorder {
    data: [ModelData; 2],
    frames: usize,
    first_time: Option<f64>,
    last_time: f64,
    last_q: Vec<f64>,
    last_human: Option<HumanSupport>,
    human_changes: usize,
    sequence: Vec<&'static str>,
    transition_start: Option<f64>,
    transitions: Vec<f64>,
    single: Vec<Series>,
    double: Vec<Series>,
    min_margin: f64,
    outside: usize,
    joint_violations: usize,
    velocity_violations: usize,
    /// The previous frame's sole placements (right, left) and which were on the ground.
    last_feet: Option<[IsometryMatrix3<f64>; 2]>,
    last_grounded: [bool; 2],
    slip: f64,
    turn: f64,
    times: Vec<f64>,
}

fn continuous_name(phase: SupportPhase) -> Option<&'static str> {
    match phase {
        SupportPhase::Double => Some("DS"),
        SupportPhase::Right => Some("RS"),
        SupportPhase::Left => Some("LS"),
        _ => None,
    }
}

fn foot_index(foot: Foot) -> usize {
    match foot {
        Foot::Right => 0,
        Foot::Left => 1,
    }
}

/// Signed distance of `p` to the boundary of the convex hull of `points` (positive inside).
/// `points` is reordered.
pub fn convex_margin(points: &mut [Vector2<f64>], p: Vector2<f64>) -> f64 {
    // Andrew's monotone chain, lower then upper hull, counter-clockwise.
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>| (a - o).perp(&(b - o));
    let mut hull = [Vector2::zeros(); 16];
    let mut k = 0;
    for &pt in points.iter() {
        while k >= 2 && cross(hull[k - 2], hull[k - 1], pt) <= 0.0 {
            k -= 1;
        }
        hull[k] = pt;
        k += 1;
    }
    let lower = k + 1;
    for &pt in points.iter().rev().skip(1) {
        while k >= lower && cross(hull[k - 2], hull[k - 1], pt) <= 0.0 {
            k -= 1;
        }
        hull[k] = pt;
        k += 1;
    }
    let n = k.saturating_sub(1);
    if n < 3 {
        return f64::NEG_INFINITY;
    }
    (0..n)
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % n]);
            let edge = b - a;
            edge.perp(&(p - a)) / edge.norm()
        })
        .fold(f64::INFINITY, f64::min)
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
    /// A recorder for the runs of `imitator`.
    pub fn new(imitator: &Imitator) -> Self {
        let models = imitator.models();
        Self {
            data: [models.right.new_data(), models.left.new_data()],
            frames: 0,
            first_time: None,
            last_time: 0.0,
            last_q: Vec::new(),
            last_human: None,
            human_changes: 0,
            sequence: Vec::new(),
            transition_start: None,
            transitions: Vec::new(),
            single: vec![Series::default(); EFFECTORS.len()],
            double: vec![Series::default(); EFFECTORS.len()],
            min_margin: f64::INFINITY,
            outside: 0,
            joint_violations: 0,
            velocity_violations: 0,
            last_feet: None,
            last_grounded: [false; 2],
            slip: 0.0,
            turn: 0.0,
            times: Vec::new(),
        }
    }

    /// Records one frame, as returned by [`Imitator::step`].
    pub fn record(&mut self, imitator: &Imitator, frame: &RobotFrame) -> Result<(), ModelError> {
        let root_model = imitator.models().rooted_at(frame.root);
        let data = &mut self.data[foot_index(frame.root)];
        root_model.forward_kinematics(data, &frame.q)?;

        // Tracking, against the references of the tasks this phase tracks.
        let table = imitator.table(frame.phase);
        let single = matches!(frame.phase, SupportPhase::Right | SupportPhase::Left);
        let double = frame.phase == SupportPhase::Double;
        for (e, (name, joint)) in EFFECTORS.iter().enumerate() {
            let tracked = table.levels.iter().flat_map(|l| &l.tasks).any(|t| {
                matches!(t, super::tables::Task::Point { frame: f, target: super::tables::PointTarget::Scaled(j), .. }
                    if f == name && j == joint)
            });
            if !tracked || !(single || double) {
                continue;
            }
            let (Some(reference), Ok(id)) =
                (frame.reference[joint.index()], root_model.frame_id(name))
            else {
                continue;
            };
            let error = (data.frame_placement(id).translation.vector - reference).norm();
            if single {
                self.single[e].push(error);
            } else {
                self.double[e].push(error);
            }
        }

        // Support polygon from the feet on the ground (world frame = root frame moved by
        // world_t_root; heights are the same since the root sole is on the floor).
        let mut points = [Vector2::zeros(); 8];
        let mut count = 0;
        let mut on_ground = [false; 2];
        for foot in [Foot::Right, Foot::Left] {
            let sole = if foot == Foot::Right {
                &frame.right_sole
            } else {
                &frame.left_sole
            };
            let outline = foot
                .sole_outline()
                .map(|[x, y]| sole.transform_point(&Vector3::new(x, y, 0.0).into()));
            let grounded = outline.iter().all(|p| p.z.abs() <= CONTACT_HEIGHT);
            on_ground[foot_index(foot)] = grounded;
            if grounded {
                for p in outline {
                    points[count] = p.xy().coords;
                    count += 1;
                }
            }
        }
        let margin = convex_margin(&mut points[..count], frame.com.xy());
        self.min_margin = self.min_margin.min(margin);
        if margin < 0.0 {
            self.outside += 1;
        }

        // Limits.
        let bounds = imitator.bounds();
        for (i, &q) in frame.q.iter().enumerate() {
            if q < bounds.lower()[i] || q > bounds.upper()[i] || !q.is_finite() {
                self.joint_violations += 1;
            }
        }
        if !self.last_q.is_empty() {
            let dt = frame.time - self.last_time;
            for (i, (&q, &p)) in frame.q.iter().zip(&self.last_q).enumerate() {
                let allowed = bounds.velocity()[i] * dt;
                if (q - p).abs() > allowed * (1.0 + 1e-9) + 1e-12 {
                    self.velocity_violations += 1;
                }
            }
        }

        // Slip of the support foot: where it was at the previous frame, if it stood then.
        let root = foot_index(frame.root);
        let placement = [frame.right_sole, frame.left_sole];
        if let Some(before) = self.last_feet.filter(|_| self.last_grounded[root]) {
            let (now, then) = (placement[root], before[root]);
            self.slip = self
                .slip
                .max((now.translation.vector - then.translation.vector).norm());
            self.turn = self
                .turn
                .max(rotation_angle(&(then.rotation.inverse() * now.rotation)));
        }
        self.last_feet = Some(placement);
        self.last_grounded = on_ground;

        // Support changes and transitions.
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
            Some(name) => {
                if self.sequence.last() != Some(&name) {
                    self.sequence.push(name);
                    if let Some(start) = self.transition_start.take() {
                        self.transitions.push(frame.time - start);
                    }
                }
            }
            None => {
                if self.transition_start.is_none() {
                    self.transition_start = Some(self.last_time);
                }
            }
        }

        self.first_time.get_or_insert(frame.time);
        self.last_time = frame.time;
        self.last_q.clear();
        self.last_q.extend_from_slice(&frame.q);
        self.times.push(frame.micros);
        self.frames += 1;
        Ok(())
    }

    /// The metrics of the frames recorded so far.
    pub fn finish(&self) -> ImitationMetrics {
        let mut times = self.times.clone();
        let mut transitions = self.transitions.clone();
        ImitationMetrics {
            frames: self.frames,
            duration: self.last_time - self.first_time.unwrap_or(self.last_time),
            human_support_changes: self.human_changes,
            robot_support_changes: self.sequence.len().saturating_sub(1),
            robot_support_sequence: self.sequence.clone(),
            transition_durations: Spread::of(&mut transitions),
            effectors: EFFECTORS
                .iter()
                .enumerate()
                .map(|(e, (name, _))| EffectorError {
                    name,
                    single_support: self.single[e].summary(),
                    double_support: self.double[e].summary(),
                })
                .collect(),
            min_com_margin: self.min_margin,
            frames_com_outside: self.outside,
            joint_limit_violations: self.joint_violations,
            velocity_limit_violations: self.velocity_violations,
            max_support_slip: self.slip,
            max_support_turn: self.turn,
            solve_time_us: Spread::of(&mut times),
        }
    }
}
