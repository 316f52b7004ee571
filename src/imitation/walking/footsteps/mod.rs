//! Where the robot puts its feet: the human's footprints, scaled to the robot, become robot
//! steps, taken one at a time at the robot's own pace.
//!
//! # The footprints
//!
//! While a human foot is on the ground its footprint is its ankle's ground point and its heading
//! (ankle → toe, or the hips' heading when the toe is missing or the foot stands on its toes:
//! [`HumanFrame::foot_heading`]), in the human's world. Each foot's move since the start,
//! scaled by the leg ratio `k = robot leg / human leg` and turned into the robot's world, moves
//! the same robot foot from where it started: a human footprint `(p, θ)` of a foot that started
//! at `(p₀, θ₀)` is the robot footprint `(r₀ + R(Δθ)·k·(p − p₀), ρ₀ + θ − θ₀)` for the robot
//! foot that started at `(r₀, ρ₀)`, with `Δθ` the difference of the starting stances' headings
//! (robot − human). So the human's stance width and natural toe-out are not copied, only how
//! the feet move. A robot foot's **target** is its footprint clipped to the
//! step envelope ([`FootArea`]: forward offset, lateral offset that keeps the feet apart and
//! uncrossed, relative yaw) around where the robot's other foot stands.
//!
//! # The steps
//!
//! In double support the robot steps with the foot farthest from its target, once that is more
//! than [`FootstepConfig::distance`] or [`FootstepConfig::heading`] away: it shifts its CoM over
//! the other foot, lifts the foot, carries it flat at the lift height to the target (which keeps
//! following the human until the human's foot is down), lowers it and brings the CoM back to the
//! middle. A human standing on one foot for [`FootstepConfig::stance_time`] makes the robot lift
//! the same foot and stand on one leg until the human puts it down. So each deliberate human
//! step becomes a robot step, steps the robot cannot take yet wait (the targets keep the latest
//! footprints), and when the human stops the robot steps until both feet are on their targets:
//! it stands where the scaled human stands. A step once started is finished: the foot is landed
//! before anything else happens, so no foot on the floor ever moves. Without walking
//! ([`FootstepConfig::follow`] off) a human who now stands on the other leg redirects a robot
//! that is still shifting its weight (both feet down).
//!
//! Units: metres, radians. Frames: the human's world and the robot's world (the right sole at
//! the first frame), both z up.

use nalgebra::Rotation2;

use crate::human::{HumanFrame, Side};
use crate::imitation::phase::SupportPhase;
use crate::imitation::reference::support::HumanSupport;
use crate::imitation::walking::look_ahead::{
    FootLift, FootLookAhead, FootSchedule, MotionTimes, footprint,
};
use crate::robots::{FootArea, SolePlacement};

/// How long after a human foot lands its footprint is still taken (s): the heel strikes first,
/// the sole is flat a moment later.
const LANDING_SETTLE: f64 = 0.2;

/// When the robot steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootstepConfig {
    /// Whether the robot's feet follow the human's footprints (walking). Off by default: the
    /// robot then only stands on one leg when the human does, for as long, lifting the foot in
    /// place and putting it back where it was. Walking (`imitate --walk`; the imitator then
    /// uses [`TaskTables::centre_stances_for_walking`](crate::imitation::phase::tables::TaskTables::centre_stances_for_walking))
    /// is not yet the default: in the physics judge the NAO's loaded feet turn over 2° in some
    /// of the quasi-static steps it takes, and the G1's walking steps fall on the judge's weak
    /// model (the CHANGELOG has the runs).
    pub follow: bool,
    /// With `follow`, walk with the pattern generator ([`crate::imitation::walking`]): dynamic steps
    /// (NAO: 1.0 s double + 0.67 s single support while following the human) instead of
    /// quasi-static ones (the CoM moved over the stance foot before each lift). Off by
    /// default: the NAO's walks stand in the physics judge, but the steps are slow (about
    /// 0.02 m/s), the arms hold still while the robot walks (unless `walking_arms`), a pivot
    /// turn is not followed, and the G1 falls at its first steps (see the changelog and
    /// [`crate::imitation::walking`]).
    pub dynamic: bool,
    /// With `dynamic`, the hands follow the scaled human while the robot walks: after each
    /// walking frame an arm step moves the arm joints alone, the hands toward their targets
    /// at their single-support speed, the arms clear of the torso and head
    /// ([`crate::imitation::walking::walking_arms_table`]). Off by default: on the bundled walks the
    /// hands come 4–8 cm nearer the human over the clip, but the walk's plan keeps the CoM's
    /// ZMP in the support and does not see the arms' momentum: the physics judge's NAO falls
    /// on some walking clips with it.
    pub walking_arms: bool,
    /// A foot farther than this from its target (m) is moved by a step. Default 0.02.
    pub distance: f64,
    /// A foot turned more than this from its target's heading (rad) is moved by a step.
    /// Default 0.087 (5°).
    pub heading: f64,
    /// Not walking dynamically, a human foot on the ground keeps the footprint it landed with
    /// until it has turned more than this from it (rad) or moved more than [`Self::slide`];
    /// from then until it lifts, its footprint is followed (a pivot turn, a shuffle).
    /// Default 0.26 (15°): a standing human's foot heading (ankle → toe) rolls and jitters by
    /// up to 12° in the bundled captures, which made the robot step in place on clips where the
    /// human never steps.
    pub pivot: f64,
    /// See [`Self::pivot`] (m, in the human's world, unscaled). Default 0.05: a standing
    /// human's ankle moves by up to 3.2 cm in the bundled captures as the foot rolls.
    pub slide: f64,
    /// A human standing on one foot this long (s) is followed onto one leg. Default 0.3.
    pub stance_time: f64,
    /// Walking dynamically, a human standing on one foot this long (s) is followed onto one
    /// leg; shorter stances are the human's steps, which the walk takes ([`crate::imitation::walking`]).
    /// Default 1.
    pub long_stance_time: f64,
    /// The robot lands a foot that has been this long (s) in single support with the human's
    /// foot down, even if it has not reached its target (5 mm, 2°): a target the legs cannot
    /// reach must not keep the robot on one leg. Default 2.
    pub swing_timeout: f64,
}

impl Default for FootstepConfig {
    fn default() -> Self {
        Self {
            follow: false,
            dynamic: false,
            walking_arms: false,
            distance: 0.02,
            heading: 0.087,
            pivot: 0.26,
            slide: 0.05,
            stance_time: 0.3,
            long_stance_time: 1.0,
            swing_timeout: 2.0,
        }
    }
}

impl FootstepConfig {
    /// The first field that is out of range (name and value).
    pub fn invalid_field(&self) -> Option<(&'static str, f64)> {
        [
            ("footsteps.distance", self.distance),
            ("footsteps.heading", self.heading),
            ("footsteps.pivot", self.pivot),
            ("footsteps.slide", self.slide),
            ("footsteps.stance_time", self.stance_time),
            ("footsteps.long_stance_time", self.long_stance_time),
            ("footsteps.swing_timeout", self.swing_timeout),
        ]
        .into_iter()
        .find(|(_, v)| v.is_nan() || *v < 0.0)
    }
}

pub use crate::locomotion::GroundPose;
use crate::locomotion::footstep::mean_heading;
pub(crate) use crate::locomotion::footstep::wrap_angle as wrap;

/// What the planner looks ahead with.
#[derive(Clone, Debug)]
struct Ahead {
    schedule: FootSchedule,
    times: MotionTimes,
}

/// The feet's targets of a frame, and where the feet are (left, right; robot world).
struct Aims {
    targets: [Option<GroundPose>; 2],
    feet: [GroundPose; 2],
    config: FootstepConfig,
}

impl Aims {
    /// How far `foot` is from its target (m, and rad in heading), if it has one.
    fn error(&self, foot: Side) -> Option<(f64, f64)> {
        let target = self.targets[foot.index()]?;
        let d = self.feet[foot.index()].relative(&target);
        Some((d.xy.norm(), d.yaw.abs()))
    }

    /// Whether `foot` is farther from its target than a step's thresholds.
    fn off(&self, foot: Side) -> bool {
        let c = &self.config;
        self.error(foot)
            .is_some_and(|(d, a)| d > c.distance || a > c.heading)
    }
}

/// What the planner is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Step {
    /// Both feet down, nothing to do or deciding.
    Idle,
    /// Stepping with this foot: shifting, lifting, carrying it to its target; the time (s) spent
    /// in single support with the human's foot down.
    Swing(Side, f64),
    /// The swing foot is on its target and the human's foot is down: landing, back to DS.
    Landing,
}

/// Turns the human's footprints into robot steps (see the module docs).
#[derive(Clone, Debug)]
pub struct FootstepPlanner {
    area: FootArea,
    config: FootstepConfig,
    /// The human's footprint of each foot (left, right; human world): where it landed until
    /// it pivots or slides (see [`FootstepConfig::pivot`]), then its last; looking ahead,
    /// where a foot about to be lifted will land.
    human: [Option<GroundPose>; 2],
    /// Which human feet (left, right) have pivoted or slid since they landed.
    moved: [bool; 2],
    /// Each human foot's footprint where it last landed (left, right; human world): taken over
    /// the first [`LANDING_SETTLE`] seconds on the ground, then kept while the foot stays
    /// down, so a foot pivoting or rolling in place is no step.
    landed: [Option<GroundPose>; 2],
    /// How long each human foot has been on the ground (s).
    down_for: [f64; 2],
    /// The starting footprints (left, right) of the human and of the robot, and the heading
    /// difference of the starting stances (robot − human, rad).
    origin: Option<([GroundPose; 2], [GroundPose; 2], f64)>,
    /// How long the human has stood on one foot (s), and which foot is lifted.
    stance: Option<(Side, f64)>,
    /// Which human feet (left, right) are on the ground at this frame.
    down: [bool; 2],
    step: Step,
    /// The current swing target (robot world), while stepping.
    target: Option<GroundPose>,
    /// Feet off their targets at the last update (0, 1 or 2).
    off_target: usize,
    /// Where the robot's feet stood when the current step began (left, right): the targets
    /// when the feet do not follow the human's.
    home: Option<[GroundPose; 2]>,
    /// The human's foot lifts known in advance and the robot's own motion times (offline mode).
    ahead: Option<Ahead>,
    /// The human's lift the current step follows (looking ahead, without walking).
    following: Option<FootLift>,
    /// Per foot, the start (human clock, s) of the last lift of the human's that a robot step
    /// followed, so that a step landed ahead of the human is not taken again.
    followed: [f64; 2],
}

/// What the planner asks of the phase machine for one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepRequest {
    /// The support to work toward.
    pub support: HumanSupport,
    /// Whether the swing foot may leave the ground: false while the robot shifts its weight
    /// ahead of a human lift-off that has not happened yet ([`crate::imitation::walking::look_ahead`]).
    pub lift: bool,
}

impl FootstepPlanner {
    /// A planner with `config` for a robot with the step envelope `area`.
    pub fn new(config: FootstepConfig, area: FootArea) -> Self {
        Self {
            config,
            area,
            human: [None; 2],
            landed: [None; 2],
            moved: [false; 2],
            down_for: [0.0; 2],
            origin: None,
            stance: None,
            down: [true; 2],
            step: Step::Idle,
            target: None,
            off_target: 0,
            home: None,
            ahead: None,
            following: None,
            followed: [f64::NEG_INFINITY; 2],
        }
    }

    /// The planner looks ahead on the human's clock with `ahead` (see [`crate::imitation::walking::look_ahead`]).
    pub fn with_look_ahead(mut self, ahead: FootLookAhead) -> Self {
        let times = MotionTimes::new(&ahead);
        self.ahead = Some(Ahead {
            schedule: ahead.schedule,
            times,
        });
        self
    }

    /// Looking ahead, the robot's motion times learnt so far (the leads in use).
    pub fn motion_times(&self) -> Option<&MotionTimes> {
        self.ahead.as_ref().map(|a| &a.times)
    }

    /// The swing foot and its target (robot world), while the robot steps.
    pub fn target(&self) -> Option<(Side, GroundPose)> {
        match self.step {
            Step::Swing(foot, _) => Some((foot, self.target?)),
            Step::Idle | Step::Landing => None,
        }
    }

    /// Feet not on their targets after the last update: steps still to take.
    pub fn steps_pending(&self) -> usize {
        self.off_target
    }

    /// One frame. `human` is the detected human support, `ratio` the leg ratio, `feet` the
    /// robot's sole poses (left, right; robot world) and `phase` its phase at the previous
    /// frame, `dt` the frame's time step (s). Returns the support the phase machine should work
    /// toward and whether the swing foot may lift.
    pub fn update(
        &mut self,
        frame: &HumanFrame,
        human: HumanSupport,
        ratio: f64,
        feet: [GroundPose; 2],
        phase: SupportPhase,
        dt: f64,
    ) -> StepRequest {
        let now = frame.time;
        if let Some(ahead) = &mut self.ahead {
            ahead.times.observe(phase, dt);
        }
        let aims = self.track(frame, human, ratio, feet, dt);
        self.advance(now, phase, dt, &aims);
        if self.step == Step::Idle {
            self.following = None;
        }
        let (support, lift) = match self.step {
            Step::Swing(foot, _) => {
                let stance = foot.other();
                let support = HumanSupport::from_feet(stance == Side::Left, stance == Side::Right);
                (support, self.may_lift(foot, now))
            }
            Step::Idle | Step::Landing => (HumanSupport::Double, true),
        };
        if let Some(ahead) = &mut self.ahead {
            ahead.times.requested(lift);
        }
        StepRequest { support, lift }
    }

    /// One frame while the walk follower steps: the human's footprints and the feet off their
    /// targets are updated, the planner's own steps wait (it stays idle).
    pub(crate) fn watch(
        &mut self,
        frame: &HumanFrame,
        human: HumanSupport,
        ratio: f64,
        feet: [GroundPose; 2],
        dt: f64,
    ) {
        self.track(frame, human, ratio, feet, dt);
    }

    /// The human's footprints and one-leg stance from this frame, then the feet's targets and
    /// how many feet are off them.
    fn track(
        &mut self,
        frame: &HumanFrame,
        human: HumanSupport,
        ratio: f64,
        feet: [GroundPose; 2],
        dt: f64,
    ) -> Aims {
        self.observe(frame, human, dt);
        let aims = self.aims(feet, ratio);
        self.off_target = Side::BOTH.iter().filter(|&&f| aims.off(f)).count();
        aims
    }

    /// How long the human has stood on both feet (s; 0 while a foot is up).
    pub(crate) fn double_support_time(&self) -> f64 {
        self.down_for[0].min(self.down_for[1])
    }

    /// Whether the planner is idle: no step of its own under way.
    pub(crate) fn is_idle(&self) -> bool {
        self.step == Step::Idle
    }

    /// Where the human's feet stand, scaled and in the robot's world (`[left, right]`; walking
    /// dynamically, where they last landed, see `scaled_footprint`), not clipped: the goals of
    /// a walk. `None` before both human feet have been seen on the ground.
    pub(crate) fn goals(&self, ratio: f64) -> Option<[GroundPose; 2]> {
        let [left, right] = Side::BOTH.map(|f| self.scaled_footprint(f, ratio));
        Some([left?, right?])
    }

    /// The feet's targets this frame: where they stood when the current step began (without
    /// walking) or the scaled human footprints (walking).
    fn aims(&mut self, feet: [GroundPose; 2], ratio: f64) -> Aims {
        if self.origin.is_none()
            && Side::BOTH.iter().all(|&f| self.has_settled(f))
            && let [Some(l), Some(r)] = *self.prints()
        {
            let heading = |[l, r]: [GroundPose; 2]| wrap(r.yaw + 0.5 * wrap(l.yaw - r.yaw));
            self.origin = Some(([l, r], feet, wrap(heading(feet) - heading([l, r]))));
        }
        if self.step == Step::Idle || self.home.is_none() {
            self.home = Some(feet);
        }
        let targets = match self.home {
            Some(home) if !self.config.follow => home.map(Some),
            _ => Side::BOTH.map(|f| self.target_of(f, feet, ratio)),
        };
        Aims {
            targets,
            feet,
            config: self.config,
        }
    }

    /// The step's state machine (see the module docs), at human time `now` with the robot in
    /// `phase`.
    fn advance(&mut self, now: f64, phase: SupportPhase, dt: f64, aims: &Aims) {
        match self.step {
            Step::Idle if phase == SupportPhase::Double => {
                self.following = self.stance_ahead(now);
                self.step = match self.following {
                    Some(lift) => {
                        self.followed[lift.foot.index()] = lift.start;
                        Step::Swing(lift.foot, 0.0)
                    }
                    None => self.choose(aims),
                };
                if let Step::Swing(foot, _) = self.step {
                    self.target = aims.targets[foot.index()];
                }
            }
            // A followed stance that the human ends before the robot's foot is off the ground is
            // given up (the phase machine aborts the weight shift): a foot lifted after the
            // human's is down again would imitate nothing.
            Step::Swing(..)
                if phase.shifts_weight() && self.following.is_some_and(|l| l.end <= now) =>
            {
                self.step = Step::Idle;
            }
            // Without walking the robot imitates the human's one-leg stances: if the human now
            // stands on the other leg and the robot's foot is still down, it takes the human's
            // current stance instead (the phase machine aborts the weight shift). A walking robot
            // finishes the step it chose: its targets, not the stances, decide. (Looking ahead,
            // the stance is known before it starts.)
            Step::Swing(foot, _)
                if !self.config.follow
                    && self.ahead.is_none()
                    && phase.shifts_weight()
                    && matches!(self.stance, Some((lifted, t))
                        if lifted == foot.other() && t >= self.config.stance_time) =>
            {
                self.step = Step::Swing(foot.other(), 0.0);
                self.target = aims.targets[foot.other().index()];
            }
            Step::Swing(foot, waited) => {
                self.target = aims.targets[foot.index()];
                let there = aims
                    .error(foot)
                    .is_none_or(|(d, a)| d <= 0.005 && a <= 0.035);
                let human_down = self.down[foot.index()] || self.lands_soon(foot, now);
                let single = matches!(phase, SupportPhase::Right | SupportPhase::Left);
                let waited = if single && human_down {
                    waited + dt
                } else {
                    waited
                };
                self.step =
                    if single && human_down && (there || waited >= self.config.swing_timeout) {
                        Step::Landing
                    } else {
                        Step::Swing(foot, waited)
                    };
            }
            Step::Landing if phase == SupportPhase::Double => self.step = Step::Idle,
            Step::Idle | Step::Landing => {}
        }
    }

    /// Whether the swing foot may leave the ground. Online, always. Looking ahead, a followed
    /// stance lifts with the human's foot; a walking step waits for a lift of the human's foot
    /// that is coming within the lift lead.
    fn may_lift(&self, foot: Side, now: f64) -> bool {
        let Some(ahead) = &self.ahead else {
            return true;
        };
        let down = self.down[foot.index()];
        if let Some(lift) = self.following {
            return now >= lift.start && !down;
        }
        let coming = ahead.schedule.lift_within(foot, now, ahead.times.shift);
        !(down && coming.is_some_and(|l| l.start > now))
    }

    /// Whether the human's `foot` is up at `now` and will be down within the landing lead.
    fn lands_soon(&self, foot: Side, now: f64) -> bool {
        let Some(ahead) = &self.ahead else {
            return false;
        };
        // A lift "within 0 s" of now is the one under way.
        let under_way = ahead.schedule.lift_within(foot, now, 0.0);
        under_way.is_some_and(|l| l.end <= now + ahead.times.lowering)
    }

    /// Looking ahead without walking: the human lift to follow now, if any (see
    /// [`crate::imitation::walking::look_ahead`]): the earliest of each foot's first lift that starts within the
    /// lift lead, is not followed yet, is worth following, and leaves no longer one of the other
    /// foot out.
    fn stance_ahead(&self, now: f64) -> Option<FootLift> {
        let ahead = self.ahead.as_ref().filter(|_| !self.config.follow)?;
        let (schedule, lead) = (&ahead.schedule, ahead.times.shift);
        // The robot can stand on one leg for the stance time of it.
        let worth = |l: &FootLift| {
            l.start > self.followed[l.foot.index()]
                && l.end - l.start.max(now + lead) >= self.config.stance_time
        };
        let next = |foot: Side| {
            let soon = schedule.lifts_after(foot, now).iter();
            soon.take_while(|l| l.start <= now + lead)
                .find(|l| worth(l))
        };
        let unrivalled = |l: &&FootLift| {
            let busy_until = l.end + lead + ahead.times.lowering;
            let rivals = schedule.lifts_after(l.foot.other(), now).iter();
            !(rivals.take_while(|o| o.start < busy_until))
                .any(|o| o.duration() > l.duration() && worth(o))
        };
        let [left, right] = Side::BOTH.map(|f| next(f).filter(unrivalled));
        match (left, right) {
            (Some(l), Some(r)) => Some(if l.start <= r.start { *l } else { *r }),
            (l, r) => l.or(r).copied(),
        }
    }

    /// The next step from double support: the human's one-leg stance (online: once it has
    /// lasted [`FootstepConfig::stance_time`], walking dynamically
    /// [`FootstepConfig::long_stance_time`]), or the foot farthest off its target (walking
    /// dynamically, the [`crate::imitation::walking`] follower steps toward the targets instead).
    fn choose(&self, aims: &Aims) -> Step {
        let dynamic = self.config.follow && self.config.dynamic;
        let stance_time = match dynamic {
            true => self.config.long_stance_time,
            false => self.config.stance_time,
        };
        if self.ahead.is_none()
            && let Some((lifted, t)) = self.stance
            && t >= stance_time
        {
            return Step::Swing(lifted, 0.0);
        }
        if dynamic {
            return Step::Idle;
        }
        let cost = |f: Side| {
            aims.error(f).map_or(0.0, |(d, a)| {
                d / self.config.distance + a / self.config.heading
            })
        };
        match (aims.off(Side::Right), aims.off(Side::Left)) {
            (false, false) => Step::Idle,
            (true, false) => Step::Swing(Side::Right, 0.0),
            (false, true) => Step::Swing(Side::Left, 0.0),
            (true, true) if cost(Side::Right) >= cost(Side::Left) => Step::Swing(Side::Right, 0.0),
            (true, true) => Step::Swing(Side::Left, 0.0),
        }
    }

    /// Updates the human footprints and the one-leg stance from this frame.
    fn observe(&mut self, frame: &HumanFrame, human: HumanSupport, dt: f64) {
        let down = human.feet();
        self.down = down;
        for foot in Side::BOTH {
            let i = foot.index();
            self.down_for[i] = if down[i] { self.down_for[i] + dt } else { 0.0 };
            if down[i]
                && let Some(print) = footprint(frame, foot)
            {
                if self.landed[i].is_none() || self.down_for[i] <= LANDING_SETTLE {
                    self.landed[i] = Some(print);
                }
                self.human[i] = Some(self.unless_moved(foot, print));
            }
            self.moved[i] &= down[i];
            // Looking ahead, a foot about to be lifted (or in the air) aims at where it lands.
            let ahead = self.ahead.as_ref();
            let lift = ahead.and_then(|a| a.schedule.lift_within(foot, frame.time, a.times.shift));
            if let Some(landing) = lift.and_then(|l| l.landing) {
                self.human[foot.index()] = Some(landing);
            }
        }
        let lifted = match human {
            HumanSupport::Right => Some(Side::Left),
            HumanSupport::Left => Some(Side::Right),
            HumanSupport::Double | HumanSupport::Airborne => None,
        };
        self.stance = match (lifted, self.stance) {
            (Some(f), Some((g, t))) if f == g => Some((f, t + dt)),
            (Some(f), _) => Some((f, dt)),
            (None, _) => None,
        };
    }

    /// Whether the human's `foot` has a footprint that no longer settles: it landed, and has
    /// stood [`LANDING_SETTLE`] or been lifted since. The starting stances are taken from
    /// such footprints, as the steps' targets are: a heading taken in the first frames of a
    /// noisy capture (the Kinect clips' feet turn 6° in their first 0.1 s) would otherwise
    /// read as a turn.
    fn has_settled(&self, foot: Side) -> bool {
        let i = foot.index();
        self.landed[i].is_some() && (!self.down[i] || self.down_for[i] > LANDING_SETTLE)
    }

    /// The footprint `foot` landed with, until `print` (its footprint now, on the ground) has
    /// turned or moved from it by more than [`FootstepConfig::pivot`] or
    /// [`FootstepConfig::slide`]; from then until the foot lifts, `print`.
    fn unless_moved(&mut self, foot: Side, print: GroundPose) -> GroundPose {
        let i = foot.index();
        let Some(landed) = self.landed[i] else {
            return print;
        };
        let (c, d) = (&self.config, landed.relative(&print));
        self.moved[i] |= d.yaw.abs() > c.pivot || d.xy.norm() > c.slide;
        if self.moved[i] { print } else { landed }
    }

    /// The target of `foot` (robot world): its scaled human footprint, clipped to the envelope
    /// around the robot's other foot.
    fn target_of(&self, foot: Side, feet: [GroundPose; 2], ratio: f64) -> Option<GroundPose> {
        let scaled = self.scaled_footprint(foot, ratio)?;
        let other = feet[foot.other().index()];
        let local = other.relative(&scaled);
        let clipped = self.area.clip(
            foot,
            SolePlacement {
                xy: local.xy,
                yaw: local.yaw,
            },
        );
        Some(other.compose(&GroundPose {
            xy: clipped.xy,
            yaw: clipped.yaw,
        }))
    }

    /// Walking dynamically, where the foot last landed, turned as much as the human's mean foot
    /// heading turned since the start (a toe-out of the human's walk that was not there at the
    /// start does not splay the robot's feet); else the foot's last footprint.
    fn scaled_footprint(&self, foot: Side, ratio: f64) -> Option<GroundPose> {
        if !self.walks_dynamically() {
            return self.scaled(self.human[foot.index()]?, foot, ratio);
        }
        let ([left, right], (human0, _, _)) = (self.landed, self.origin?);
        let start = mean_heading(human0[0].yaw, human0[1].yaw);
        let turned = wrap(mean_heading(left?.yaw, right?.yaw) - start);
        let print = GroundPose {
            yaw: human0[foot.index()].yaw + turned,
            ..self.landed[foot.index()]?
        };
        self.scaled(print, foot, ratio)
    }

    fn walks_dynamically(&self) -> bool {
        self.config.follow && self.config.dynamic
    }

    /// The footprints the feet's targets come from: where the human's feet landed when walking
    /// dynamically (looking ahead, `human` holds where a foot about to lift will land), else
    /// their last footprints.
    fn prints(&self) -> &[Option<GroundPose>; 2] {
        match self.walks_dynamically() {
            true => &self.landed,
            false => &self.human,
        }
    }

    /// `print`, a footprint of the human's `foot`, scaled by `ratio` and moved into the robot's
    /// world (see the module docs); `None` before the starting stances are known.
    fn scaled(&self, print: GroundPose, foot: Side, ratio: f64) -> Option<GroundPose> {
        let (human0, robot0, turn) = self.origin?;
        let (h0, r0) = (human0[foot.index()], robot0[foot.index()]);
        Some(GroundPose {
            xy: r0.xy + Rotation2::new(turn) * ((print.xy - h0.xy) * ratio),
            yaw: wrap(r0.yaw + print.yaw - h0.yaw),
        })
    }
}

#[cfg(test)]
mod tests;
