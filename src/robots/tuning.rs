//! How the imitation moves a biped of a given size: [`MotionTuning`], the size-dependent
//! numbers, and the rules that carry a tuned robot's numbers to another biped
//! ([`BipedSize`], [`MotionTuning::scaled`]); a profile's sizes come from
//! [`BipedProfile::size`](super::BipedProfile::size).
//!
//! # The scaling rules
//!
//! The NAO's numbers were tuned in physics (the judge's MuJoCo NAO); a biped nobody tuned gets
//! them scaled by the length that decides each one, with the sizes of [`BipedSize`] read off
//! its profile in the standing posture (`h` the CoM height, `w` half the hip spacing, `l` the
//! hip height, `s` the sole's contact width, `a` the arm length, `ω` the upper body's mean
//! rated joint speed, `ω_l` the legs'; primes for the new robot):
//!
//! | value | rule | why |
//! |---|---|---|
//! | `com_acceleration` | `× h / h'` | same ZMP–CoM distance `a·h/g` (cart-table model): 0.3 m/s² at 0.27 m is 8 mm |
//! | `com_speed`, `task_speed` | `× √(h'/h)` | same Froude number `v²/(g h)`: pendulum time scales as `√(h/g)` |
//! | `offset_rate` | `× √(h'/h) · w/w'` | the CoM speed it gives (offset rate × stance width) Froude-scaled |
//! | `offset_acceleration` | `× w h / (w' h')` | the CoM acceleration it gives, as `com_acceleration` |
//! | `torso_lean` | `× atan(w'/h') / atan(w/h)` | the same multiple of the angle under which the stance hip is seen from the CoM |
//! | `support_margin` | `× s'/s` | the same fraction of the sole's width |
//! | `torso_lowering`, `single_support_lowering` | `× l'/l` | the same fraction of the leg |
//! | `tracking_speed`, `stance_tracking_speed` | `× a'/a` | the hands cover the same fraction of the arm per second |
//! | `tracking_acceleration` | `× a'/a` | the hands' speed changes by the same fraction of the arm per second, per second |
//! | `balanced_hands` (speed, acceleration) | `× a'/a` | as the hands' other speeds |
//! | `upper_body_velocity_fraction` | `× ω/ω'`, at most its value | the same joint speeds (rad/s) on faster motors |
//! | `leg_velocity_fraction` | `× (ω_l/ω_l') √(h/h')`, at most its value | the same Froude number: a leg motion of the same shape takes `√(h'/h)` times as long, so its joints turn `√(h/h')` times as fast |
//! | `damping` | `× a'/a` | a hand's Jacobian (m/rad) scales with the arm: the same near-singular poses damped |
//!
//! The rules keep geometric and dynamic similarity; what they cannot see (servo stiffness, the
//! torque-to-weight ratio) is why a profile may give its own values
//! ([`crate::robots::g1::TUNING`] says which of the G1's are measured).

/// How the imitation moves a robot: the size-dependent defaults of the imitator's settings
/// (`ImitatorConfig`'s `max_task_speed`, `max_tracking_speed`, `upper_body_velocity_fraction`,
/// `motion` and `phase.support_margin` override them) and the executable task tables' torso.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionTuning {
    /// Largest speed a task asks for (m/s): each frame a task's error is clipped to this times
    /// the time step, so the velocity limits are rarely hit.
    pub task_speed: f64,
    /// Largest speed the tasks that follow the human (the hands) ask for in double support,
    /// once the human has stood on both feet for a second (m/s).
    pub tracking_speed: f64,
    /// The same in single support and in the transition steps (m/s): standing on one foot, or
    /// shifting the weight between the feet, the robot has less support to take the arms'
    /// reaction, so the hands may be held slower there.
    pub stance_tracking_speed: f64,
    /// Largest change of the hands' speed toward their targets (m/s²), in every phase: a hand
    /// starts, cruises and brakes instead of reaching its speed in one frame, so the arms'
    /// reaction on the feet stays small at a higher top speed.
    pub tracking_acceleration: f64,
    /// Fraction of the rated velocity of every joint off the sole-to-sole chain (arms, head);
    /// the legs keep the imitator's `velocity_fraction`.
    pub upper_body_velocity_fraction: f64,
    /// Fraction of the rated velocity of the legs' joints (the sole-to-sole chain) in
    /// Koenemann et al.'s method, whose legs copy the human's at the human's speed: this bound
    /// is all that slows them (`ImitatorConfig::velocity_fraction` overrides it). Poubel et
    /// al.'s tasks bound the legs by the CoM's and the feet's speeds, and keep the paper's 10 %.
    pub leg_velocity_fraction: f64,
    /// Whether a lifted foot leaves the ground as slowly as it lands, handing the load it
    /// still carries to the stance foot gradually
    /// (`imitation::shaping::MotionLimits::soft_liftoff`). Not a size: the scaling keeps it.
    pub soft_liftoff: bool,
    /// How far below its standing height the executable task tables keep the torso (m, ≥ 0).
    /// Shifting the hips over one foot with the torso upright lengthens the far leg: at the
    /// standing height the free leg ends up straight, a singular posture it cannot lift from
    /// quickly, and a straight leg cannot reach down the last micrometres of a landing. A robot
    /// starting in its standing posture is lowered along a ramp of `√(6 d / com_acceleration)`
    /// seconds (`imitation::shaping::StartRamp`).
    pub torso_lowering: f64,
    /// How far below its standing height the executable task tables keep the torso while a
    /// foot is lifted or up (m, ≥ 0; at most `torso_lowering` makes sense). A straighter stance
    /// knee needs less torque, so a robot whose knees are weak for its weight rises on one foot
    /// (the NAO: 0); one that rises by its whole lowering as it lifts a foot moves its CoM
    /// up and down by that much within a step, and a robot on stiff servos sways from it (the
    /// G1 stays lowered, [`crate::robots::g1::TUNING`]).
    pub single_support_lowering: f64,
    /// Sideways lean of the torso over the foot the robot stands or is about to stand on in the
    /// executable tables (rad, ≥ 0). With an upright pelvis the stance hip ends up outside the
    /// CoM and its roll servo holds the whole upper body out to the side; leaning brings the
    /// upper body over the hip. Large leans put the swing foot on the floor early when a servo
    /// sags.
    pub torso_lean: f64,
    /// Distance between the CoM goal of a single support and the inner edge of the support
    /// foot's contact area (m, ≥ 0; the sole's middle where it is narrower than twice this):
    /// the least lateral shift that keeps this margin, because the stance hip's roll torque
    /// grows with how far the CoM goes past the hip.
    pub support_margin: f64,
    /// Largest speed of the CoM reference of the executable tables (m/s).
    pub com_speed: f64,
    /// Largest acceleration of the CoM reference (m/s²): in the cart-table model the ZMP is
    /// `h/g` times it away from the CoM.
    pub com_acceleration: f64,
    /// Largest rate of Koenemann's CoM offset (the CoM's place between the feet, 0 at the left
    /// foot, 1 at the right), at the middle (1/s).
    pub offset_rate: f64,
    /// Largest change of that rate (1/s²).
    pub offset_acceleration: f64,
    /// Whether Koenemann's offset ends at each foot's stance point
    /// ([`BipedProfile::stance_point`](super::BipedProfile::stance_point), `support_margin`
    /// from the sole's inner edge, where Poubel et al.'s method puts the CoM on one foot)
    /// instead of at the sole's centre (the paper). Not a size: the scaling keeps it.
    pub offset_to_stance_point: bool,
    /// The hands' speeds in every phase of Poubel et al.'s method when its ZMP level holds the
    /// balance (`PoubelConfig::zmp_balance`: a level that sees the arms' acceleration and
    /// bounds their vertical moment on the feet) and of Koenemann et al.'s method (whose CoM
    /// offset control was measured to keep the NAO up under them), instead of
    /// `tracking_speed`, `stance_tracking_speed` and `tracking_acceleration`; `None`: both
    /// methods keep those. The dynamic walk always keeps those.
    pub balanced_hands: Option<BalancedHands>,
    /// The solver's damping of near-singular levels in Poubel et al.'s method (m/rad: the
    /// damping threshold and the largest damping of
    /// [`Settings`](crate::solver::Settings), in the units of the hands' Jacobian): a level
    /// whose smallest singular value falls below it is damped, up to it. Position rows scale
    /// with the limbs, so a robot twice the NAO's arm length meets the same near-singular
    /// poses (an elbow nearly straight) at twice the singular value: damped at the NAO's
    /// 0.02, the G1's arms reversed at speed on 285 of 3 099 frames of CMU 09_12 and 175 of
    /// 994 of 131_01; at the scaled 0.039 on 2 and 0, the hands as near or nearer.
    pub damping: f64,
}

/// The hands' speeds when the ZMP level holds the balance ([`MotionTuning::balanced_hands`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BalancedHands {
    /// Largest speed of the hand targets toward the human, in every phase (m/s).
    pub tracking_speed: f64,
    /// Largest change of that speed (m/s²).
    pub tracking_acceleration: f64,
}

impl MotionTuning {
    /// The first field out of range (speeds, accelerations and the fraction finite and > 0;
    /// lowering, lean and margin finite and ≥ 0), with its value and the requirement.
    pub fn invalid_field(&self) -> Option<(&'static str, f64, &'static str)> {
        let positive = [
            ("task_speed", self.task_speed),
            ("tracking_speed", self.tracking_speed),
            ("stance_tracking_speed", self.stance_tracking_speed),
            ("tracking_acceleration", self.tracking_acceleration),
            (
                "upper_body_velocity_fraction",
                self.upper_body_velocity_fraction,
            ),
            ("leg_velocity_fraction", self.leg_velocity_fraction),
            ("com_speed", self.com_speed),
            ("com_acceleration", self.com_acceleration),
            ("offset_rate", self.offset_rate),
            ("offset_acceleration", self.offset_acceleration),
            ("damping", self.damping),
        ];
        let balanced = self.balanced_hands.map(|b| {
            [
                ("balanced_tracking_speed", b.tracking_speed),
                ("balanced_tracking_acceleration", b.tracking_acceleration),
            ]
        });
        let non_negative = [
            ("torso_lowering", self.torso_lowering),
            ("single_support_lowering", self.single_support_lowering),
            ("torso_lean", self.torso_lean),
            ("support_margin", self.support_margin),
        ];
        let bad = |ok: fn(f64) -> bool, need| {
            move |(name, v): (&'static str, f64)| {
                (!(v.is_finite() && ok(v))).then_some((name, v, need))
            }
        };
        (positive.into_iter().chain(balanced.into_iter().flatten()))
            .find_map(bad(|v| v > 0.0, "finite and > 0"))
            .or_else(|| {
                non_negative
                    .into_iter()
                    .find_map(bad(|v| v >= 0.0, "finite and ≥ 0"))
            })
    }

    /// These values, tuned on a robot of size `from`, carried to a robot of size `to` by the
    /// rules of the module docs.
    pub fn scaled(&self, from: &BipedSize, to: &BipedSize) -> MotionTuning {
        let froude = (to.com_height / from.com_height).sqrt();
        let arm = to.arm_length / from.arm_length;
        let stance_angle = |s: &BipedSize| s.half_stance.atan2(s.com_height);
        MotionTuning {
            task_speed: self.task_speed * froude,
            tracking_speed: self.tracking_speed * arm,
            stance_tracking_speed: self.stance_tracking_speed * arm,
            tracking_acceleration: self.tracking_acceleration * arm,
            upper_body_velocity_fraction: (self.upper_body_velocity_fraction
                * from.upper_body_speed
                / to.upper_body_speed)
                .min(self.upper_body_velocity_fraction),
            soft_liftoff: self.soft_liftoff,
            leg_velocity_fraction: (self.leg_velocity_fraction * from.leg_speed
                / to.leg_speed
                / froude)
                .min(self.leg_velocity_fraction),
            torso_lowering: self.torso_lowering * to.hip_height / from.hip_height,
            single_support_lowering: self.single_support_lowering * to.hip_height / from.hip_height,
            torso_lean: self.torso_lean * stance_angle(to) / stance_angle(from),
            support_margin: self.support_margin * to.sole_width / from.sole_width,
            com_speed: self.com_speed * froude,
            com_acceleration: self.com_acceleration * from.com_height / to.com_height,
            offset_rate: self.offset_rate * froude * (from.half_stance / to.half_stance),
            offset_acceleration: self.offset_acceleration
                * ((from.half_stance * from.com_height) / (to.half_stance * to.com_height)),
            offset_to_stance_point: self.offset_to_stance_point,
            balanced_hands: self.balanced_hands.map(|b| BalancedHands {
                tracking_speed: b.tracking_speed * arm,
                tracking_acceleration: b.tracking_acceleration * arm,
            }),
            damping: self.damping * arm,
        }
    }
}

/// The sizes of a biped that the scaling rules use, read off its profile in the standing
/// posture ([`BipedProfile::size`](super::BipedProfile::size); metres, rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BipedSize {
    /// Height of the CoM above the soles (m).
    pub com_height: f64,
    /// Half the distance between the hip points ([`crate::human::HumanJoint::LHip`] and
    /// `RHip`) (m).
    pub half_stance: f64,
    /// Mean height of the hip points above the soles (m).
    pub hip_height: f64,
    /// Lateral width of the soles' contact areas (m, mean of both feet).
    pub sole_width: f64,
    /// Distance from the left shoulder point to the left hand frame (m); the torso frame stands
    /// in for a profile without a shoulder point.
    pub arm_length: f64,
    /// Mean rated speed of the joints off the sole-to-sole chain (rad/s); the legs' where the
    /// robot has no such joints.
    pub upper_body_speed: f64,
    /// Mean rated speed of the joints on the sole-to-sole chain, the legs (rad/s).
    pub leg_speed: f64,
}
