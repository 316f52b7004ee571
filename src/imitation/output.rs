//! What the imitator gives per frame ([`RobotFrame`]).

use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use crate::human::{HumanJoint, Side};
use crate::imitation::phase::SupportPhase;
use crate::imitation::reference::support::HumanSupport;
use crate::locomotion::{Footstep, WalkState};
use crate::robots::BipedProfile;
use crate::scene::SurfaceShape;
use crate::solver::driver::{DriverReport, StopReason};
use crate::solver::{LevelReport, SolveReport};

/// A foot is on the ground when its outline points are at most this high (m).
pub const CONTACT_HEIGHT: f64 = 1e-3;

/// Whether a sole is on the floor: every point of its `outline` (sole frame, m) within
/// [`CONTACT_HEIGHT`] of the floor with the sole at `sole` (world).
pub fn sole_on_floor(outline: &[[f64; 2]], sole: &IsometryMatrix3<f64>) -> bool {
    outline
        .iter()
        .all(|&[x, y]| sole.transform_point(&[x, y, 0.0].into()).z.abs() <= CONTACT_HEIGHT)
}

/// Steps queued ahead of the robot: the generator previews about one and a half steps, so two
/// queued steps are all it looks at; more would commit the robot to footprints the human may
/// still change.
pub(crate) const QUEUE_AHEAD: usize = 2;

/// The effectors whose positions each [`RobotFrame`] reports and whose tracking the metrics
/// measure, by role name (the robot frames are the profile's hands and feet's ankles), with the
/// human joint their reference comes from: the order of [`RobotFrame::effectors`].
pub const EFFECTORS: [(&str, HumanJoint); 4] = [
    ("l_hand", HumanJoint::LHand),
    ("r_hand", HumanJoint::RHand),
    ("l_ankle", HumanJoint::LAnkle),
    ("r_ankle", HumanJoint::RAnkle),
];

/// The robot frames of [`EFFECTORS`] in `profile`: its hands, then its feet's ankles.
pub(super) fn effector_frames(profile: &BipedProfile) -> [&str; 4] {
    let [left_hand, right_hand] = &profile.hands;
    let [left_ankle, right_ankle] = &profile.feet;
    [left_hand, right_hand, &left_ankle.ankle, &right_ankle.ankle].map(String::as_str)
}

/// One robot output frame.
#[derive(Debug, Clone)]
pub struct RobotFrame {
    /// The robot's clock (s): the human frame's time plus every pause of the human's clock so
    /// far (each frame fed again at the same time adds the configured `nominal_dt`); equal to
    /// `human_time` when nothing paused.
    pub time: f64,
    /// Time of the human frame (s).
    pub human_time: f64,
    /// Whether the imitator waits for a hand to be placed before its contact (Algorithm 1 of
    /// [`crate::imitation::poubel::hand_support`]): the caller should feed the same human frame again, so that
    /// the human's clock pauses while the robot's runs on.
    pub awaiting_contact: bool,
    /// Each hand's support (`[left, right]`, robot world frame) while it is placed or held.
    pub hand_supports: [Option<HandPlacement>; 2],
    /// Joint angles in the model's variable order (rad); names in [`Imitator::variable_names`](crate::imitation::imitator::Imitator::variable_names).
    pub q: Vec<f64>,
    /// What to command the robot's position servos (model variable order, rad): `q` plus the
    /// deflection under which servos of the profile's stiffness hold this posture's static load
    /// ([`BipedProfile::servo_saturation`], [`crate::robots::servo`]), inside the joint
    /// limits; equal to `q` when the profile states no stiffness. When the profile states its
    /// sway period ([`BipedProfile::sway_period`]) these commands are then played through the
    /// sway shaper ([`crate::robots::sway`]): they follow `q` about half that period later.
    /// `joints.csv` holds these.
    pub servo_targets: Vec<f64>,
    /// The human's support at this frame.
    pub human_support: HumanSupport,
    /// The robot's phase or transition step.
    pub phase: SupportPhase,
    /// The sole the model was rooted at.
    pub root: Side,
    /// World placement of the right sole.
    pub right_sole: IsometryMatrix3<f64>,
    /// World placement of the left sole.
    pub left_sole: IsometryMatrix3<f64>,
    /// Whole-body centre of mass in the world frame (m).
    pub com: Vector3<f64>,
    /// Error norm of each task of the phase's table after the step, in stack order (m).
    pub task_errors: Vec<f64>,
    /// Number of tasks of this phase (the first entries of `task_errors`).
    pub task_count: usize,
    /// Per-level outcome of the last solve (first `level_count` entries).
    pub levels: Vec<LevelReport>,
    /// Number of levels of this phase.
    pub level_count: usize,
    /// Joints clamped in the last solve (variable indices; first `clamped_count` entries).
    pub clamped: Vec<usize>,
    /// Number of clamped joints.
    pub clamped_count: usize,
    /// Why the per-frame iteration stopped.
    pub stop: StopReason,
    /// Prioritized passes (one projection and factorization of every level) the last solve
    /// took: its active-set steps, or its clamping iterations when the phase has no
    /// inequality rows. The step's time grows with it: this is what a slow frame is made of.
    pub solve_passes: usize,
    /// Whether the last solve's active-set method converged (`false` when it met an active
    /// set again or reached its cap; its iterate still keeps every joint limit).
    pub solve_converged: bool,
    /// The scaled human reference of this frame, in the model root's frame (m): the targets of
    /// the `Scaled` tasks come from here.
    pub reference: [Option<Vector3<f64>>; HumanJoint::COUNT],
    /// World placement of the model root (the support sole) this frame.
    pub world_t_root: IsometryMatrix3<f64>,
    /// Wall time of the step (µs): detection, scaling, IK.
    pub micros: f64,
    /// Where the human stands: the midpoint of the ankles on the ground plane (human world
    /// frame, m) and the heading of the hips (rad about z, 0 facing +x); `None` when the frame
    /// lacks the ankles or hips. Not scaled: see `leg_ratio`.
    pub human_stance: Option<(Vector2<f64>, f64)>,
    /// Robot leg length / human leg length, the scale from the human's world to the robot's.
    pub leg_ratio: f64,
    /// Positions of the robot's hands and ankles (the frames of the profile's `hands` and of its
    /// feet's `ankle`) in the model root's frame (m), in [`EFFECTORS`] order: compare with
    /// `reference` of the same human joint.
    pub effectors: [Vector3<f64>; 4],
    /// Feet not on their targets after this frame: the steps the robot still has to take
    /// (0, 1 or 2).
    pub pending_steps: usize,
    /// The walking pattern generator's state while the robot walks ([`crate::imitation::walking`]):
    /// the planned CoM, ZMP and soles (world frame); `None` while it stands.
    pub walk: Option<WalkState>,
    /// The walk's footsteps not yet landed, the one under way first (world frame); empty while
    /// the robot stands.
    pub footsteps: Vec<Footstep>,
}

impl RobotFrame {
    /// Whether the robot has done what the human asks of its feet: it is in a continuous phase
    /// (DS, RS or LS, not a transition step), no step is pending, and it stands on the feet the
    /// human stands on (any, while the human is airborne).
    pub fn has_finished(&self) -> bool {
        let same_support = match self.human_support {
            HumanSupport::Double => self.phase == SupportPhase::Double,
            HumanSupport::Right => self.phase == SupportPhase::Right,
            HumanSupport::Left => self.phase == SupportPhase::Left,
            HumanSupport::Airborne => true,
        };
        !self.phase.is_transition()
            && self.pending_steps == 0
            && same_support
            && self.walk.is_none()
    }

    /// The frame before the first step: posture `q` with the right sole at the world origin
    /// and the left sole at `left_sole`; room for `[tasks, levels]` task errors and level
    /// reports (the largest table's), so that stepping never allocates.
    pub(super) fn at_start(
        q: &[f64],
        left_sole: IsometryMatrix3<f64>,
        [tasks, levels]: &[usize; 2],
    ) -> Self {
        RobotFrame {
            time: 0.0,
            human_time: 0.0,
            awaiting_contact: false,
            hand_supports: [None; 2],
            q: q.to_vec(),
            servo_targets: q.to_vec(),
            human_support: HumanSupport::Double,
            phase: SupportPhase::Double,
            root: Side::Right,
            // The world is the right sole's frame at the start.
            right_sole: IsometryMatrix3::identity(),
            left_sole,
            com: Vector3::zeros(),
            task_errors: vec![0.0; *tasks],
            task_count: 0,
            levels: vec![LevelReport::default(); *levels],
            level_count: 0,
            clamped: vec![0; q.len()],
            clamped_count: 0,
            stop: StopReason::Converged,
            solve_passes: 0,
            solve_converged: true,
            reference: [None; HumanJoint::COUNT],
            world_t_root: IsometryMatrix3::identity(),
            micros: 0.0,
            human_stance: None,
            leg_ratio: 1.0,
            effectors: [Vector3::zeros(); 4],
            pending_steps: 0,
            walk: None,
            footsteps: Vec::with_capacity(QUEUE_AHEAD),
        }
    }

    /// Copies the driver's stop reason and task errors, then the solve's levels and clamped
    /// joints.
    pub(super) fn record(&mut self, driver: &DriverReport, solve: &SolveReport) {
        self.stop = driver.stop;
        let errors = driver.task_errors();
        self.task_count = errors.len().min(self.task_errors.len());
        self.task_errors[..self.task_count].copy_from_slice(&errors[..self.task_count]);
        self.record_solve(solve);
    }

    /// Copies the per-level outcome and the clamped joints of a solve.
    pub(super) fn record_solve(&mut self, report: &SolveReport) {
        let levels = report.levels();
        self.level_count = levels.len().min(self.levels.len());
        self.levels[..self.level_count].copy_from_slice(&levels[..self.level_count]);
        let clamped = report.clamped_joints();
        self.clamped_count = clamped.len().min(self.clamped.len());
        self.clamped[..self.clamped_count].copy_from_slice(&clamped[..self.clamped_count]);
        self.solve_passes = report.active_set_iterations() + report.clamping_iterations();
        self.solve_converged = report.converged();
    }
}

/// Where a robot hand is placed: its contact point and the surface under it (robot world
/// frame, robot scale, m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandPlacement {
    /// The point the hand goes to and is held at.
    pub point: Vector3<f64>,
    /// The surface, mapped to the robot (see the module docs).
    pub surface: SurfaceShape,
    /// Whether the contact is on (the hand supports the robot), not still being placed.
    pub holding: bool,
}
