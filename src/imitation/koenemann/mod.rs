//! Koenemann, Burget and Bennewitz's real-time whole-body imitation (ICRA 2014) as the
//! imitator's second method ([`ImitationMethod::Koenemann`](super::config::ImitationMethod)).
//!
//! Per human frame:
//!
//! 1. **Posture mapping** ([`mapping`], §III–IV.B, eq. 1–5): the hands relative to the
//!    shoulders and the feet relative to the hips, scaled by the limb ratios from a T-pose
//!    calibration, become targets in the robot's torso frame. The arms follow by weighted
//!    damped least squares ([`Method::WeightedDls`](crate::solver::Method::WeightedDls), at most
//!    4 iterations a frame from the last frame's posture, where the paper runs 30).
//! 2. **CoM control** ([`offset`], §V.A, eq. 6): the robot's CoM offset between its feet moves
//!    toward the human's (or toward the support foot when the human stands on one), its speed
//!    a negative quadratic of the offset, its acceleration bounded.
//! 3. **Support mode** ([`support_mode`], §V.B, Fig. 4): single support only when the human is
//!    on that foot and the robot's offset has reached it.
//! 4. **Retargeting** ([`retarget`], §V.C, eq. 7): in double support the feet move (in the
//!    torso frame) so the CoM's offset is the commanded one, and both soles take the normal
//!    that puts the CoM above that point; in single support the support sole tilts so the CoM
//!    is above its centre. The legs' IK (leg joints only) meets, strictly and in this order:
//!    the other sole held where it stands (double support); the CoM's ground projection at
//!    the point at the commanded offset between the soles (above the support sole's centre in
//!    single support), which is what eq. 7's normal means on the floor; then, as well as it
//!    can, the retargeted soles in the torso frame with their normals (the 5-DoF foot goals of
//!    the paper: turning about the normal is free) and the swing foot, to 1 mm and 0.033 rad.
//!    When the profile has a self-collision model, the leg pairs (shins, feet) are kept apart
//!    by a level of inequalities right below the CoM.
//! 5. **Post-processing** (§V.D): the hands' and the swing foot's targets move at most at a
//!    speed limit, the hands stay out of the torso, the swing foot stays above the floor and
//!    out of the other foot's way (the profile's step envelope), and every joint within its
//!    velocity limit (the legs slowed down together, so their posture keeps its balance).
//!    Last, the upper body's self-collision pairs (forearms, torso, head) are kept apart by an
//!    IK of inequalities alone, within what the velocity limits reach from the frame's start:
//!    the least upper-body motion that restores the margin (weighted DLS has no inequalities).
//!
//! Departures from the paper, each because the physics judge showed the need or the paper is
//! silent: stability is a strict CoM level rather than the soles' normals alone (in torso
//! coordinates the normals' fixed point couples the torso's tilt with its shift and diverged:
//! on CMU 05_02 the offset went to −0.33 with 0.93 commanded), and the legs' levels are solved
//! by the strict hierarchy, exact and a few iterations, where the paper's DLS needs tens; the
//! offset's acceleration is bounded; the feet keep their stance in double support by default
//! ([`FootRetargeting::ShiftBothFeet`]; the paper's one-foot rule slides a loaded foot);
//! a foot coming down after single support lands flat at the touchdown speed of
//! [`MotionLimits`](super::shaping::MotionLimits) before the offset leaves its end; on a
//! robot whose commands are shaped, a foot lifts only once the offset has stayed at the other
//! foot for [`KoenemannConfig::settle_time`], and each leg joint speeds up over
//! [`KoenemannConfig::leg_ramp_time`]; on every robot each leg joint slows down before its
//! target over [`KoenemannConfig::leg_stop_time`], and on a robot whose commands are not
//! shaped every other joint over [`KoenemannConfig::arm_stop_time`]; the offset may end at
//! each foot's stance point rather than its sole's centre
//! ([`MotionTuning::offset_to_stance_point`](crate::robots::MotionTuning::offset_to_stance_point));
//! the legs' share of their rated speed is the
//! profile's ([`MotionTuning::leg_velocity_fraction`](crate::robots::MotionTuning::leg_velocity_fraction)),
//! the paper's robot's 10 % carried to the robot's size; the
//! human's CoM is estimated from the skeleton ([`crate::human::centre_of_mass`]) where the
//! paper had the Xsens suit's.

mod body;
pub(super) mod goals;
pub(super) mod imitator;
pub mod mapping;
pub mod offset;
pub mod retarget;
mod solves;
pub mod support_mode;

pub use mapping::Calibration;
pub use offset::OffsetSpeed;
pub use retarget::FootRetargeting;

/// Settings of Koenemann et al.'s method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KoenemannConfig {
    /// The human's reference posture (default: the first frame if it is a T-pose).
    pub calibration: Calibration,
    /// How double support meets the commanded offset (default: both feet shift, no slide).
    pub retargeting: FootRetargeting,
    /// The offset's speed limit; `None` (default): [`OffsetSpeed::default`]'s border with the
    /// profile's [`MotionTuning::offset_rate`](crate::robots::MotionTuning::offset_rate) and
    /// [`MotionTuning::offset_acceleration`](crate::robots::MotionTuning::offset_acceleration).
    pub offset_speed: Option<OffsetSpeed>,
    /// The offset counts as at a foot within this of 0 or 1. Default 0.05.
    pub offset_tolerance: f64,
    /// Damping `λ` of the arms' least-squares IK (m). Default 0.01 (the paper's 0.3 is for its
    /// own scaling of the Jacobian, which it does not give).
    pub damping: f64,
    /// Largest number of iterations of the arms' IK per frame. Default 4 (the paper: 30); see
    /// [`KoenemannConfig::max_leg_iterations`].
    pub arm_iterations: usize,
    /// Largest number of iterations of the legs' stabilizing IK per frame (the paper runs it
    /// to tolerance: 1784 at worst). Default 4: each IK starts from the last frame's posture,
    /// so a goal it does not meet in a frame it goes on approaching in the next, and every
    /// frame costs about the same. With the arms' 30 and the legs' 200 one frame in a hundred
    /// cost 3–12 times the median (the arms at their cap on half of CMU 02_10's frames, the
    /// legs 30–96 iterations where single support leaves their lowest goals out of reach); at
    /// 4 and 4 the p99 fell 2–8 times on the slow clips (NAO ≤ 262 µs, G1 ≤ 425 µs) with
    /// medians no higher, and the same runs stand in the physics judge (the closing note of
    /// issue 32).
    pub max_leg_iterations: usize,
    /// Largest speed of the swing foot's target toward the human's foot (m/s, > 0). `None`
    /// (default): the profile's [`MotionTuning::task_speed`](crate::robots::MotionTuning::task_speed)
    /// (NAO 0.15 m/s), the speed Poubel et al.'s method gives its tasks.
    pub swing_speed: Option<f64>,
    /// Tolerance of the legs' IK (m; a normal's error counts 0.033 rad as 1 mm). Default 1e-3.
    pub tolerance: f64,
    /// Share of the way toward the profile's standing posture
    /// ([`BipedProfile::stand`](crate::robots::BipedProfile::stand)) that each joint of the
    /// upper body takes per iteration of the arms' IK where the hands leave it free (a gradient
    /// term `g (q_stand − q)`, 1/iteration; 0: none). Three hand coordinates leave an arm's
    /// joints free in two directions, and without a pull the IK let them drift into corners
    /// of their limits where it stalls: on CMU 05_02 the NAO's left arm stuck with shoulder
    /// pitch, shoulder roll and elbow roll at their limits for 1.5 s while the hand's target
    /// moved 8–19 cm away. Default 0.01 (up to 4.8 per second: four iterations a frame at
    /// 120 Hz): the NAO's mean hand error over its bundled clips 1.7–7.4 cm (were 1.7–8.6;
    /// Kinect ges01 6.4 → 2.9, CMU 02_10 3.3 → 2.0), and every run that stood in the physics
    /// judge still stands. In [0, 1].
    pub arm_posture_gain: f64,
    /// How long the offset must have stayed at the support foot's end (within
    /// [`KoenemannConfig::offset_tolerance`]) before the other foot lifts (s). `None` (default):
    /// the profile's sway period
    /// ([`BipedProfile::sway_period`](crate::robots::BipedProfile::sway_period)), 0 for a robot
    /// whose commands are not shaped. A robot whose commands reach it through the sway shaper
    /// follows the plan's weight shift up to one period late; lifting the moment the plan's
    /// offset arrives lifts the foot while the robot's weight is still half on it (the same
    /// wait as Poubel's [`PhaseConfig::settle_time`](crate::imitation::phase::PhaseConfig::settle_time)).
    pub settle_time: Option<f64>,
    /// The time (s) in which each leg joint may go from rest to its velocity limit, and back:
    /// its change of speed is bounded by that limit over this time (and it slows down before
    /// its target over [`Self::leg_stop_time`], at least this). `None` (default): the
    /// profile's sway period
    /// ([`BipedProfile::sway_period`](crate::robots::BipedProfile::sway_period)), no ramp for a
    /// robot whose commands are not shaped (0 likewise). The legs otherwise start and stop at
    /// their velocity limit within a frame: on the G1 the CoM crossed to a foot at 0.18 m/s
    /// and stopped within 0.2 s over it, a ZMP beyond the sole's edge.
    pub leg_ramp_time: Option<f64>,
    /// The time (s) in which each leg joint may slow down from its velocity limit to rest
    /// before its target, at least `leg_ramp_time` (it only bounds the slowing down: a leg
    /// still starts at once when `leg_ramp_time` is 0). `None` (default): the larger of the
    /// resolved `leg_ramp_time` and [`LEG_STOP_TIME_CONSTANTS`] time constants `√(h/g)` of
    /// the linear inverted pendulum at the robot's standing CoM height `h` (NAO 0.50 s; G1
    /// its 1.1 s ramp, above its 0.80 s). Without it a leg joint on the NAO reached its IK
    /// target at its velocity limit and, when the target crossed it, turned back at that
    /// limit within one frame: the body bobbed, the feet unloaded and the contact area
    /// collapsed (the physics judge's NAO; the CHANGELOG has the runs).
    pub leg_stop_time: Option<f64>,
    /// The time (s) in which every other joint (arms, head, waist) may slow down from its
    /// velocity limit to rest before its target (it still starts at once). `None` (default):
    /// [`ARM_STOP_TIME_CONSTANTS`] pendulum time constants `√(h/g)` (NAO 0.10 s) on a robot
    /// whose commands are not shaped, 0 on one whose commands pass the sway shaper
    /// ([`BipedProfile::sway_period`](crate::robots::BipedProfile::sway_period), the G1),
    /// which spreads each command's stop over a sway period already. Without it the NAO's
    /// arms, following a dancer's at their velocity limit, stopped within a frame, and their
    /// reaction unloaded a sole edge (CMU 05_12, in the physics judge).
    pub arm_stop_time: Option<f64>,
}

/// The default [`KoenemannConfig::arm_stop_time`] in time constants of the linear inverted
/// pendulum at the robot's CoM height: the shortest stop that keeps the NAO's arms' reaction
/// off its loaded feet with room to spare (at 0.3 a loaded foot turned 2.0° on CMU 05_02 in
/// the physics judge, its limit; 0.3° at 0.6); the hands' mean error over the clip grows with
/// it, by up to 0.4 cm at 0.6.
pub const ARM_STOP_TIME_CONSTANTS: f64 = 0.6;

/// The default [`KoenemannConfig::leg_stop_time`] in time constants of the linear inverted
/// pendulum at the robot's CoM height: on the NAO in the physics judge, shorter stops (0.3–2.1
/// time constants) left more legs turning back at speed and more runs falling or rocking,
/// longer ones (4.0) no better (the CHANGELOG has the runs).
pub const LEG_STOP_TIME_CONSTANTS: f64 = 3.0;

impl Default for KoenemannConfig {
    fn default() -> Self {
        KoenemannConfig {
            calibration: Calibration::Auto,
            retargeting: FootRetargeting::ShiftBothFeet,
            offset_speed: None,
            offset_tolerance: 0.05,
            damping: 0.01,
            arm_iterations: 4,
            max_leg_iterations: 4,
            swing_speed: None,
            tolerance: 1e-3,
            arm_posture_gain: 0.01,
            settle_time: None,
            leg_ramp_time: None,
            leg_stop_time: None,
            arm_stop_time: None,
        }
    }
}

impl KoenemannConfig {
    /// The first invalid field, with its value and why.
    pub(super) fn invalid_field(&self) -> Option<(&'static str, f64, &'static str)> {
        if let Some((name, value)) = self.offset_speed.and_then(|s| s.invalid_field()) {
            return Some((
                name,
                value,
                "must be > 0 (max finite, border at most 1, acceleration may be infinite)",
            ));
        }
        let positive = [
            ("koenemann.damping", Some(self.damping)),
            ("koenemann.tolerance", Some(self.tolerance)),
            ("koenemann.swing_speed", self.swing_speed),
        ];
        if let Some((name, v)) = (positive.into_iter())
            .find_map(|(name, v)| Some((name, v.filter(|v| !(v.is_finite() && *v > 0.0))?)))
        {
            return Some((name, v, "must be finite and > 0"));
        }
        let times = [
            ("koenemann.settle_time", self.settle_time),
            ("koenemann.leg_ramp_time", self.leg_ramp_time),
            ("koenemann.leg_stop_time", self.leg_stop_time),
            ("koenemann.arm_stop_time", self.arm_stop_time),
        ];
        if let Some((name, t)) = (times.into_iter()).find_map(|(name, t)| {
            t.filter(|t| !(t.is_finite() && *t >= 0.0))
                .map(|t| (name, t))
        }) {
            return Some((name, t, "must be finite and >= 0"));
        }
        if !(0.0..=1.0).contains(&self.arm_posture_gain) {
            return Some((
                "koenemann.arm_posture_gain",
                self.arm_posture_gain,
                "must be in [0, 1]",
            ));
        }
        if !(0.0..0.5).contains(&self.offset_tolerance) {
            return Some((
                "koenemann.offset_tolerance",
                self.offset_tolerance,
                "must be in [0, 0.5)",
            ));
        }
        let counts = [
            ("koenemann.arm_iterations", self.arm_iterations),
            ("koenemann.max_leg_iterations", self.max_leg_iterations),
        ];
        counts
            .into_iter()
            .find(|(_, n)| *n == 0)
            .map(|(name, n)| (name, n as f64, "must be >= 1"))
    }
}
