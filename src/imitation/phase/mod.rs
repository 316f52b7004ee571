//! The robot's support phase (Poubel §III.B, Table I): double support (DS), right support (RS),
//! left support (LS), and the two-step transitions between DS and a single support, driven by the
//! human's support and ended by what the robot measurably achieved, never by timers.
//!
//! # Phases
//!
//! | Phase | Step | Model root | Ends when |
//! |---|---|---|---|
//! | DS | — | right sole | (continuous) |
//! | RS | — | right sole | (continuous) |
//! | LS | — | left sole | (continuous) |
//! | DS → RS | CoM to RFoot | right sole | `e_c ≤ com_tolerance`, posture reached |
//! | DS → RS | Lift LFoot | right sole | `min(h_toe, h_heel) ≥ ρ − foot_height_tolerance` |
//! | DS → LS | CoM to LFoot | right sole | `e_c ≤ com_tolerance`, posture reached |
//! | DS → LS | Lift RFoot | left sole | `min(h_toe, h_heel) ≥ ρ − foot_height_tolerance` |
//! | RS → DS | Lower LFoot | right sole | `max(|h_toe|, |h_heel|) ≤ foot_height_tolerance` |
//! | RS → DS | CoM to middle | right sole | `e_c ≤ com_tolerance`, posture reached |
//! | LS → DS | Lower RFoot | left sole | `max(|h_toe|, |h_heel|) ≤ foot_height_tolerance` |
//! | LS → DS | CoM to middle | right sole | `e_c ≤ com_tolerance`, posture reached |
//!
//! `e_c` is the horizontal distance (m) between the CoM ground projection and the current step's
//! CoM goal. The posture is reached when the torso is within `posture_tolerance` (rad) of its
//! target orientation, or has come as close as it can ([`Measurements::posture_settled`]: a
//! lean that a wide stance or a joint limit forbids must not keep the robot waiting forever);
//! tables without a torso task (the paper's) always reach it. `h_toe`, `h_heel` are the heights
//! (m) above the ground of the swing foot's toe and heel points ([`SupportPhase::swing_foot`]);
//! a landing ends with the foot flat on the floor, not above it and not below it. A step whose
//! condition is not met is repeated at the next update. A NaN measurement never meets a
//! condition, so it never ends a step.
//!
//! The weight shift onto the support foot ("CoM to RFoot") ends only once its condition has held
//! for [`PhaseConfig::settle_time`] (0 unless the robot's servo commands are shaped): a robot
//! whose commands reach it through the sway shaper ([`crate::robots::sway`]) follows the plan up
//! to the shaper's length later, so the plan's CoM must have been over the support foot that long
//! before the foot lifts. A plan held still for the shaper's length is exactly what the shaped
//! command has reached, so this wait is not a guess. A landing does not wait: the weight moving
//! back while the shaped foot still comes down loads it as soon as it touches (with the same wait
//! after the landing, the G1 bounced off its landing foot on CMU 131_01 and rolled off the other).
//!
//! # Transition graph
//!
//! The input is the human's support `h`; [`HumanSupport::Airborne`] is replaced by the last
//! non-airborne human support (initially DS), so the robot keeps its support during a jump or a
//! lost track. "done" is the current step's end condition. Every (phase, `h`) pair has exactly one
//! successor (below for the right foot; the left foot is the mirror image):
//!
//! | From | `h` = DS | `h` = RS | `h` = LS |
//! |---|---|---|---|
//! | DS | DS | DS → RS: CoM to RFoot | DS → LS: CoM to LFoot |
//! | RS | RS → DS: Lower LFoot | RS | RS → DS: Lower LFoot |
//! | DS → RS: CoM to RFoot | DS (abort) | done and lift ? Lift LFoot : stay | DS (abort) |
//! | DS → RS: Lift LFoot | RS → DS: Lower LFoot | done ? RS : stay | RS → DS: Lower LFoot |
//! | RS → DS: Lower LFoot | done ? CoM to middle : stay | DS → RS: Lift LFoot | done ? CoM to middle : stay |
//! | RS → DS: CoM to middle | done ? DS : stay | DS → RS: CoM to RFoot | done ? DS : stay |
//!
//! "lift" is the lift gate of [`PhaseMachine::update_gated`] (always open for
//! [`PhaseMachine::update`]): a robot that shifted its weight ahead of the human's lift-off
//! ([`crate::imitation::walking::look_ahead`]) waits for it with both feet down.
//!
//! Why these edges:
//! * Aborting "CoM to RFoot" goes straight back to DS: both feet are still on the ground, so the
//!   DS task table (CoM back to the middle) is safe from any CoM position between the feet.
//! * A foot put back down while being lifted is lowered first ("Lower LFoot" then "CoM to
//!   middle"), exactly as a regular landing; a foot lifted again while being lowered is lifted
//!   again ("Lift LFoot"). Both steps keep the CoM at the same goal, so the switch is continuous.
//! * "CoM to middle" interrupted by the human lifting the same foot again moves the CoM back to
//!   the support foot ("CoM to RFoot") before any lift: the foot is on the ground there.
//! * Walking (RS → LS) always goes through DS: the swing foot is landed and the CoM brought to the
//!   middle before the other foot's take-off starts, so the CoM never has to cross a gap without
//!   a foot under it.
//!
//! # Model root
//!
//! [`SupportPhase::model_root`] is the sole the paper roots the kinematic model at in each phase
//! (§IV.B, Table I): the right sole in DS and whenever the right foot is on the ground, the left
//! sole only while the right foot is in the air or being lowered ("Lift RFoot", LS, "Lower
//! RFoot").

pub(crate) mod solver;
pub mod tables;
pub(crate) mod zmp_balance;

use std::fmt;

use crate::human::Side;
use crate::imitation::reference::support::HumanSupport;

/// The steps of a take-off (DS to a single support), in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TakeOff {
    /// Move the CoM ground projection over the future support foot; both feet flat on the ground.
    ComToFoot,
    /// Lift the swing foot, parallel to the ground, to the height ρ.
    LiftFoot,
}

/// The steps of a landing (a single support back to DS), in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Landing {
    /// Lower the swing foot, parallel to the ground, until it is on the ground.
    LowerFoot,
    /// Move the CoM ground projection back to the middle between the ankles.
    ComToMiddle,
}

/// The robot's support phase: a continuous support or one step of a transition (a row of
/// Poubel's Table I).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SupportPhase {
    /// Double support (DS).
    Double,
    /// Right support (RS): the left foot is free.
    Right,
    /// Left support (LS): the right foot is free.
    Left,
    /// Transition DS → RS (the left foot takes off).
    DoubleToRight(TakeOff),
    /// Transition DS → LS (the right foot takes off).
    DoubleToLeft(TakeOff),
    /// Transition RS → DS (the left foot lands).
    RightToDouble(Landing),
    /// Transition LS → DS (the right foot lands).
    LeftToDouble(Landing),
}

/// What a phase is for the metrics: a continuous single or double support, or a transition step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SupportKind {
    /// RS or LS.
    Single,
    /// DS.
    Double,
    /// One of the eight transition steps.
    Transition,
}

impl SupportKind {
    /// Number of kinds.
    pub const COUNT: usize = 3;

    /// 0 single, 1 double, 2 transition.
    pub const fn index(self) -> usize {
        self as usize
    }
}

impl SupportPhase {
    /// The phase's [`SupportKind`].
    pub const fn kind(self) -> SupportKind {
        match self {
            SupportPhase::Right | SupportPhase::Left => SupportKind::Single,
            SupportPhase::Double => SupportKind::Double,
            _ => SupportKind::Transition,
        }
    }

    /// Which feet (`[left, right]`) stand on the floor: the support, and both while the free
    /// foot is on the ground (DS and the CoM steps of the transitions).
    pub const fn standing_feet(self) -> [bool; 2] {
        match self {
            SupportPhase::Double
            | SupportPhase::DoubleToRight(TakeOff::ComToFoot)
            | SupportPhase::DoubleToLeft(TakeOff::ComToFoot)
            | SupportPhase::RightToDouble(Landing::ComToMiddle)
            | SupportPhase::LeftToDouble(Landing::ComToMiddle) => [true, true],
            SupportPhase::Right
            | SupportPhase::DoubleToRight(TakeOff::LiftFoot)
            | SupportPhase::RightToDouble(Landing::LowerFoot) => [false, true],
            SupportPhase::Left
            | SupportPhase::DoubleToLeft(TakeOff::LiftFoot)
            | SupportPhase::LeftToDouble(Landing::LowerFoot) => [true, false],
        }
    }

    /// Number of phases (3 continuous supports + 8 transition steps).
    pub const COUNT: usize = 11;

    /// Every phase, in the row order of Table I.
    pub const ALL: [SupportPhase; SupportPhase::COUNT] = [
        SupportPhase::Right,
        SupportPhase::Left,
        SupportPhase::Double,
        SupportPhase::DoubleToRight(TakeOff::ComToFoot),
        SupportPhase::DoubleToRight(TakeOff::LiftFoot),
        SupportPhase::DoubleToLeft(TakeOff::ComToFoot),
        SupportPhase::DoubleToLeft(TakeOff::LiftFoot),
        SupportPhase::RightToDouble(Landing::LowerFoot),
        SupportPhase::RightToDouble(Landing::ComToMiddle),
        SupportPhase::LeftToDouble(Landing::LowerFoot),
        SupportPhase::LeftToDouble(Landing::ComToMiddle),
    ];

    /// Index of this phase in [`SupportPhase::ALL`].
    pub const fn index(self) -> usize {
        match self {
            SupportPhase::Right => 0,
            SupportPhase::Left => 1,
            SupportPhase::Double => 2,
            SupportPhase::DoubleToRight(TakeOff::ComToFoot) => 3,
            SupportPhase::DoubleToRight(TakeOff::LiftFoot) => 4,
            SupportPhase::DoubleToLeft(TakeOff::ComToFoot) => 5,
            SupportPhase::DoubleToLeft(TakeOff::LiftFoot) => 6,
            SupportPhase::RightToDouble(Landing::LowerFoot) => 7,
            SupportPhase::RightToDouble(Landing::ComToMiddle) => 8,
            SupportPhase::LeftToDouble(Landing::LowerFoot) => 9,
            SupportPhase::LeftToDouble(Landing::ComToMiddle) => 10,
        }
    }

    /// The sole the kinematic model is rooted at in this phase (the paper's choice, see the
    /// module docs): `Side::Left` in LS, "Lift RFoot" and "Lower RFoot", `Side::Right` otherwise.
    pub const fn model_root(self) -> Side {
        match self {
            SupportPhase::Left
            | SupportPhase::DoubleToLeft(TakeOff::LiftFoot)
            | SupportPhase::LeftToDouble(Landing::LowerFoot) => Side::Left,
            SupportPhase::Double
            | SupportPhase::Right
            | SupportPhase::DoubleToRight(_)
            | SupportPhase::DoubleToLeft(TakeOff::ComToFoot)
            | SupportPhase::RightToDouble(_)
            | SupportPhase::LeftToDouble(Landing::ComToMiddle) => Side::Right,
        }
    }

    /// The foot that leaves or reaches the ground in a transition (the left foot in DS ↔ RS, the
    /// right foot in DS ↔ LS), or the free foot in a single support; `None` in DS.
    pub const fn swing_foot(self) -> Option<Side> {
        match self {
            SupportPhase::Double => None,
            SupportPhase::Right
            | SupportPhase::DoubleToRight(_)
            | SupportPhase::RightToDouble(_) => Some(Side::Left),
            SupportPhase::Left | SupportPhase::DoubleToLeft(_) | SupportPhase::LeftToDouble(_) => {
                Some(Side::Right)
            }
        }
    }

    /// The foot the plan holds off the ground: the free foot in RS and LS, the swing foot while
    /// it is lifted or lowered; `None` while both soles are planned on the floor (DS, and the
    /// CoM shifts of the transitions).
    pub const fn airborne_foot(self) -> Option<Side> {
        match self {
            SupportPhase::Right
            | SupportPhase::DoubleToRight(TakeOff::LiftFoot)
            | SupportPhase::RightToDouble(Landing::LowerFoot) => Some(Side::Left),
            SupportPhase::Left
            | SupportPhase::DoubleToLeft(TakeOff::LiftFoot)
            | SupportPhase::LeftToDouble(Landing::LowerFoot) => Some(Side::Right),
            _ => None,
        }
    }

    /// The take-off step, in a transition from DS to a single support.
    pub const fn take_off(self) -> Option<TakeOff> {
        match self {
            SupportPhase::DoubleToRight(step) | SupportPhase::DoubleToLeft(step) => Some(step),
            _ => None,
        }
    }

    /// Whether the CoM shifts toward a foot with both feet still down ("CoM to foot").
    pub fn shifts_weight(self) -> bool {
        self.take_off() == Some(TakeOff::ComToFoot)
    }

    /// The landing step, in a transition from a single support to DS.
    pub const fn landing(self) -> Option<Landing> {
        match self {
            SupportPhase::RightToDouble(step) | SupportPhase::LeftToDouble(step) => Some(step),
            _ => None,
        }
    }

    /// Whether this is one of the 8 transition steps (not DS, RS or LS).
    pub const fn is_transition(self) -> bool {
        !matches!(
            self,
            SupportPhase::Double | SupportPhase::Right | SupportPhase::Left
        )
    }

    /// The "Support" column of Table I: `"DS"`, `"RS"`, `"LS"`, `"DS to RS"`, ….
    pub const fn support_name(self) -> &'static str {
        match self {
            SupportPhase::Double => "DS",
            SupportPhase::Right => "RS",
            SupportPhase::Left => "LS",
            SupportPhase::DoubleToRight(_) => "DS to RS",
            SupportPhase::DoubleToLeft(_) => "DS to LS",
            SupportPhase::RightToDouble(_) => "RS to DS",
            SupportPhase::LeftToDouble(_) => "LS to DS",
        }
    }

    /// The "Step" column of Table I (`"CoM to RFoot"`, `"Lift LFoot"`, …); `None` for DS, RS, LS.
    pub const fn step_name(self) -> Option<&'static str> {
        match self {
            SupportPhase::Double | SupportPhase::Right | SupportPhase::Left => None,
            SupportPhase::DoubleToRight(TakeOff::ComToFoot) => Some("CoM to RFoot"),
            SupportPhase::DoubleToRight(TakeOff::LiftFoot) => Some("Lift LFoot"),
            SupportPhase::DoubleToLeft(TakeOff::ComToFoot) => Some("CoM to LFoot"),
            SupportPhase::DoubleToLeft(TakeOff::LiftFoot) => Some("Lift RFoot"),
            SupportPhase::RightToDouble(Landing::LowerFoot) => Some("Lower LFoot"),
            SupportPhase::LeftToDouble(Landing::LowerFoot) => Some("Lower RFoot"),
            SupportPhase::RightToDouble(Landing::ComToMiddle)
            | SupportPhase::LeftToDouble(Landing::ComToMiddle) => Some("CoM to middle"),
        }
    }
}

impl fmt::Display for SupportPhase {
    /// `"DS"`, `"RS"`, `"LS"`, or e.g. `"DS to RS: CoM to RFoot"`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.step_name() {
            Some(step) => write!(f, "{}: {step}", self.support_name()),
            None => f.write_str(self.support_name()),
        }
    }
}

/// Parameters of the phase machine and of the paper's task tables. Lengths in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseConfig {
    /// A CoM step ends when the CoM ground projection is within this distance of its goal.
    /// Default 5 mm: a third of λ, so at the end of "CoM to RFoot" the CoM is at least 10 mm in
    /// front of the support ankle, inside a 160 × 90 mm sole centred 20 mm ahead of the ankle
    /// by more than 25 mm in every direction; and well above the millimetre
    /// residual a converged solve leaves, so the step does end.
    pub com_tolerance: f64,
    /// Offset λ of the CoM goal from the support ankle toward the foot centre (x of the sole)
    /// while a foot is lifted or lowered. Paper: 15 mm.
    pub lambda: f64,
    /// Height ρ of the swing sole (toe and heel points) above the ground at which a lift ends.
    /// Paper: 30 mm.
    pub rho: f64,
    /// A lift ends when both sole points are within this of ρ; a lowering ends when both are
    /// within this of the ground. Default 1 µm: a foot that lands becomes a support, and the
    /// model rooted at it takes its sole as the ground, so a landing must end flat — any tilt
    /// left is handed on to the world and adds up over steps (at 0.1 mm, 50 steps of a walk at
    /// full speed tilted the world enough to lift the soles off the floor by millimetres). The
    /// IK closes the last millimetres in a few frames.
    pub foot_height_tolerance: f64,
    /// Distance (m) between the CoM goal of a single support and the inner edge of the support
    /// foot's contact area (its middle where the area is narrower than twice this) in the
    /// executable tables. `None` (default): the profile's
    /// [`MotionTuning::support_margin`](crate::robots::MotionTuning::support_margin) (20 mm for
    /// the NAO).
    pub support_margin: Option<f64>,
    /// A CoM step also waits until the torso is within this angle (rad) of its target
    /// orientation: a foot lifts only once the torso leans over the stance foot, because until
    /// then the stance hip's roll servo holds the upper body out to the side (on a small robot
    /// beyond its torque limit when the servos are weak). Default 0.03 rad.
    pub posture_tolerance: f64,
    /// How long (s) the end of a weight shift onto the support foot must have held before the
    /// foot lifts (module docs). `None` (default): the profile's sway period
    /// ([`BipedProfile::sway_period`](crate::robots::BipedProfile::sway_period)), the length
    /// of the shaper its servo commands are played through, or 0 when they are not shaped (the
    /// NAO). Measured on the G1 (CMU 07_04): without the wait its right foot left the floor
    /// while the shaped command still held its CoM 21 mm inside the plan's, on the edge of the
    /// left sole, and it rolled off that foot.
    pub settle_time: Option<f64>,
}

impl Default for PhaseConfig {
    /// The paper's λ = 15 mm and ρ = 30 mm, with a 5 mm CoM and a 1 µm foot height tolerance,
    /// the profile's support margin and settle time and a 0.03 rad posture tolerance.
    fn default() -> Self {
        Self {
            com_tolerance: 0.005,
            lambda: 0.015,
            rho: 0.030,
            foot_height_tolerance: 0.000001,
            support_margin: None,
            posture_tolerance: 0.03,
            settle_time: None,
        }
    }
}

impl PhaseConfig {
    /// Checks every field: tolerances finite and > 0, λ, the support margin and the settle time
    /// finite and ≥ 0, ρ finite and more than twice the foot height tolerance (so a lifted foot
    /// is never also "on the ground").
    pub fn validate(&self) -> Result<(), PhaseError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.com_tolerance) {
            return Err(PhaseError::Config(
                "com_tolerance",
                "must be finite and > 0",
            ));
        }
        if !positive(self.posture_tolerance) {
            return Err(PhaseError::Config(
                "posture_tolerance",
                "must be finite and > 0",
            ));
        }
        if !(self.lambda.is_finite() && self.lambda >= 0.0) {
            return Err(PhaseError::Config("lambda", "must be finite and ≥ 0"));
        }
        if (self.support_margin).is_some_and(|m| !(m.is_finite() && m >= 0.0)) {
            return Err(PhaseError::Config(
                "support_margin",
                "must be finite and ≥ 0",
            ));
        }
        if (self.settle_time).is_some_and(|t| !(t.is_finite() && t >= 0.0)) {
            return Err(PhaseError::Config("settle_time", "must be finite and ≥ 0"));
        }
        if !positive(self.foot_height_tolerance) {
            return Err(PhaseError::Config(
                "foot_height_tolerance",
                "must be finite and > 0",
            ));
        }
        if !(self.rho.is_finite() && self.rho > 2.0 * self.foot_height_tolerance) {
            return Err(PhaseError::Config(
                "rho",
                "must be finite and > 2 × foot_height_tolerance",
            ));
        }
        Ok(())
    }
}

/// Errors of the phase machine.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PhaseError {
    /// A [`PhaseConfig`] field is out of range.
    #[error("phase config: {0} {1}")]
    Config(&'static str, &'static str),
}

/// What the robot achieved at the last solve, in the current phase (metres, radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurements {
    /// Horizontal distance between the CoM ground projection and the current phase's CoM goal.
    pub com_error: f64,
    /// Angle (rad) between the torso and its target orientation; 0 when the phase's table
    /// has no torso task.
    pub posture_error: f64,
    /// Whether the torso has stopped approaching its target orientation in this step (the
    /// higher levels or the joint limits keep it where it is), so that waiting longer for
    /// [`PhaseConfig::posture_tolerance`] is pointless.
    pub posture_settled: bool,
    /// Height above the ground of the swing foot's toe point ([`SupportPhase::swing_foot`]),
    /// negative below it; ignored in DS.
    pub swing_toe_height: f64,
    /// Height above the ground of the swing foot's heel point, negative below it; ignored in
    /// DS.
    pub swing_heel_height: f64,
}

impl Measurements {
    /// Before the first solve: the CoM infinitely far from any goal (no step ends on it), the
    /// torso on target, the feet on the ground.
    pub const AT_START: Self = Self {
        com_error: f64::INFINITY,
        posture_error: 0.0,
        posture_settled: false,
        swing_toe_height: 0.0,
        swing_heel_height: 0.0,
    };
}

/// Whether an error has stopped shrinking: it has not come down by [`Settling::PROGRESS`] below
/// its smallest value for [`Settling::PATIENCE`]. The imitator watches the torso's posture error
/// with it ([`Measurements::posture_settled`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settling {
    best: f64,
    waited: f64,
}

impl Settling {
    /// Progress that counts (rad): 1 mrad.
    pub const PROGRESS: f64 = 1e-3;
    /// How long the error may stay without progress before it counts as settled (s).
    pub const PATIENCE: f64 = 0.25;

    /// Watching starts (at a new step): nothing has settled yet.
    pub fn new() -> Self {
        Self {
            best: f64::INFINITY,
            waited: 0.0,
        }
    }

    /// Records `error` after `dt` seconds; returns whether it has settled. A NaN error never
    /// settles.
    pub fn update(&mut self, error: f64, dt: f64) -> bool {
        if error.is_nan() {
            *self = Self::new();
            return false;
        }
        if error < self.best - Self::PROGRESS || self.best.is_infinite() {
            self.best = error;
            self.waited = 0.0;
        } else {
            self.waited += dt;
        }
        self.waited >= Self::PATIENCE
    }
}

impl Default for Settling {
    fn default() -> Self {
        Self::new()
    }
}

/// How long a condition has held without a break (s), against a wait (s): the settle time of
/// a weight shift, in either method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HoldTimer {
    wait: f64,
    held: f64,
}

impl HoldTimer {
    /// Nothing held yet, against `wait` seconds.
    pub(crate) fn new(wait: f64) -> Self {
        Self { wait, held: 0.0 }
    }

    /// Counts `dt` while `holds`, restarting at a break; whether the condition holds and has
    /// held for the wait.
    pub(crate) fn hold(&mut self, holds: bool, dt: f64) -> bool {
        self.held = if holds { self.held + dt } else { 0.0 };
        holds && self.held >= self.wait
    }

    /// Starts the count again.
    pub(crate) fn restart(&mut self) {
        self.held = 0.0;
    }
}

/// The support phase state machine (see the module docs for the graph).
///
/// ```
/// use taskstack::imitation::phase::{Measurements, PhaseConfig, PhaseMachine, SupportPhase, TakeOff};
/// use taskstack::imitation::reference::support::HumanSupport;
///
/// let mut machine = PhaseMachine::new(PhaseConfig::default())?;
/// let far = Measurements {
///     com_error: 0.04,
///     posture_error: 0.0,
///     posture_settled: false,
///     swing_toe_height: 0.0,
///     swing_heel_height: 0.0,
/// };
/// // The human lifts the left foot: the robot first moves its CoM over the right foot.
/// assert_eq!(
///     machine.update(HumanSupport::Right, &far),
///     SupportPhase::DoubleToRight(TakeOff::ComToFoot)
/// );
/// # Ok::<(), taskstack::imitation::phase::PhaseError>(())
/// ```
#[derive(Clone, Debug)]
pub struct PhaseMachine {
    config: PhaseConfig,
    phase: SupportPhase,
    human: HumanSupport,
    /// How long the weight shift's end condition has held, against the settle time.
    settle: HoldTimer,
}

impl PhaseMachine {
    /// A machine in DS (the human is assumed to start standing on both feet).
    pub fn new(config: PhaseConfig) -> Result<Self, PhaseError> {
        config.validate()?;
        Ok(Self {
            config,
            phase: SupportPhase::Double,
            human: HumanSupport::Double,
            settle: HoldTimer::new(config.settle_time.unwrap_or(0.0)),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &PhaseConfig {
        &self.config
    }

    /// The current phase.
    pub fn phase(&self) -> SupportPhase {
        self.phase
    }

    /// The last non-airborne human support the machine was given (DS before any).
    pub fn human_support(&self) -> HumanSupport {
        self.human
    }

    /// Advances by one time step: `human` is the human's support in the new frame, `measured`
    /// what the robot achieved at the last solve (in the current phase). Returns the new phase.
    /// The step is taken as long enough for any [`PhaseConfig::settle_time`].
    pub fn update(&mut self, human: HumanSupport, measured: &Measurements) -> SupportPhase {
        self.update_gated(human, true, measured, f64::INFINITY)
    }

    /// [`PhaseMachine::update`] after `dt` seconds, with the swing foot allowed to leave the
    /// ground only if `lift`: otherwise a finished "CoM to foot" step waits with the weight on
    /// the support foot (the robot shifts its weight ahead of a human lift-off it knows is
    /// coming, [`crate::imitation::walking::look_ahead`]). A weight shift ends once its condition has held for
    /// [`PhaseConfig::settle_time`] (counting this `dt`).
    pub fn update_gated(
        &mut self,
        human: HumanSupport,
        lift: bool,
        measured: &Measurements,
        dt: f64,
    ) -> SupportPhase {
        if human != HumanSupport::Airborne {
            self.human = human;
        }
        let mut done = Done::new(measured, &self.config, lift);
        if let SupportPhase::DoubleToRight(TakeOff::ComToFoot)
        | SupportPhase::DoubleToLeft(TakeOff::ComToFoot) = self.phase
        {
            done.com = self.settle.hold(done.com, dt);
        }
        let next = next_phase(self.phase, self.human, &done);
        if next != self.phase {
            self.settle.restart();
        }
        self.phase = next;
        self.phase
    }
}

/// Which foot the human stands on alone, if any (`None` for DS and airborne).
fn human_single(human: HumanSupport) -> Option<Side> {
    match human {
        HumanSupport::Right => Some(Side::Right),
        HumanSupport::Left => Some(Side::Left),
        HumanSupport::Double | HumanSupport::Airborne => None,
    }
}

fn take_off(support: Side, step: TakeOff) -> SupportPhase {
    match support {
        Side::Right => SupportPhase::DoubleToRight(step),
        Side::Left => SupportPhase::DoubleToLeft(step),
    }
}

fn landing(support: Side, step: Landing) -> SupportPhase {
    match support {
        Side::Right => SupportPhase::RightToDouble(step),
        Side::Left => SupportPhase::LeftToDouble(step),
    }
}

fn single(support: Side) -> SupportPhase {
    match support {
        Side::Right => SupportPhase::Right,
        Side::Left => SupportPhase::Left,
    }
}

/// End conditions of the current step, from the measurements and the lift gate. NaN never
/// meets a condition.
struct Done {
    com: bool,
    lifted: bool,
    grounded: bool,
    /// The lift gate: the swing foot may leave the ground.
    may_lift: bool,
}

impl Done {
    fn new(m: &Measurements, config: &PhaseConfig, lift: bool) -> Self {
        let (toe, heel) = (m.swing_toe_height, m.swing_heel_height);
        let lift_goal = config.rho - config.foot_height_tolerance;
        Self {
            com: m.com_error <= config.com_tolerance
                && (m.posture_error <= config.posture_tolerance || m.posture_settled),
            may_lift: lift,
            lifted: toe >= lift_goal && heel >= lift_goal,
            grounded: toe.abs() <= config.foot_height_tolerance
                && heel.abs() <= config.foot_height_tolerance,
        }
    }
}

/// The transition function of the graph in the module docs. `human` is the last non-airborne
/// human support (an airborne value would count as DS).
fn next_phase(phase: SupportPhase, human: HumanSupport, done: &Done) -> SupportPhase {
    let wanted = human_single(human);
    match phase {
        SupportPhase::Double => match wanted {
            Some(foot) => take_off(foot, TakeOff::ComToFoot),
            None => SupportPhase::Double,
        },
        SupportPhase::Right => after_single(Side::Right, wanted),
        SupportPhase::Left => after_single(Side::Left, wanted),
        SupportPhase::DoubleToRight(step) => after_take_off(Side::Right, step, wanted, done),
        SupportPhase::DoubleToLeft(step) => after_take_off(Side::Left, step, wanted, done),
        SupportPhase::RightToDouble(step) => after_landing(Side::Right, step, wanted, done),
        SupportPhase::LeftToDouble(step) => after_landing(Side::Left, step, wanted, done),
    }
}

/// Successor of single support on `support`: stay while the human stands on that foot alone,
/// otherwise land the free foot (also when the human switched straight to the other foot).
fn after_single(support: Side, wanted: Option<Side>) -> SupportPhase {
    if wanted == Some(support) {
        single(support)
    } else {
        landing(support, Landing::LowerFoot)
    }
}

/// Successor of a take-off step toward single support on `support`.
fn after_take_off(support: Side, step: TakeOff, wanted: Option<Side>, done: &Done) -> SupportPhase {
    let stays = wanted == Some(support);
    match step {
        TakeOff::ComToFoot if !stays => SupportPhase::Double,
        TakeOff::ComToFoot if done.com && done.may_lift => take_off(support, TakeOff::LiftFoot),
        TakeOff::LiftFoot if !stays => landing(support, Landing::LowerFoot),
        TakeOff::LiftFoot if done.lifted => single(support),
        TakeOff::ComToFoot | TakeOff::LiftFoot => take_off(support, step),
    }
}

/// Successor of a landing step from single support on `support`.
fn after_landing(support: Side, step: Landing, wanted: Option<Side>, done: &Done) -> SupportPhase {
    let lifts_again = wanted == Some(support);
    match step {
        Landing::LowerFoot if lifts_again => take_off(support, TakeOff::LiftFoot),
        Landing::LowerFoot if done.grounded => landing(support, Landing::ComToMiddle),
        Landing::ComToMiddle if lifts_again => take_off(support, TakeOff::ComToFoot),
        Landing::ComToMiddle if done.com => SupportPhase::Double,
        Landing::LowerFoot | Landing::ComToMiddle => landing(support, step),
    }
}
