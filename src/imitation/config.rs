//! The imitator's settings: what both methods share ([`ImitatorConfig`]) and which method
//! imitates, with that method's own settings ([`ImitationMethod`]), and their validation.

use crate::imitation::error::ImitationError;
use crate::imitation::koenemann::KoenemannConfig;
use crate::imitation::poubel::PoubelConfig;
use crate::imitation::reference::support::SupportConfig;
use crate::imitation::shaping::{HandSpeed, MotionLimits};
use crate::robots::{FootArea, MotionTuning};

/// Which method imitates, with its own settings; what both use is in [`ImitatorConfig`].
// Boxing Poubel's settings (about 450 bytes) would save nothing that matters: a config is
// built once per imitator, and `ImitationMethod::Poubel(PoubelConfig { .. })` reads as written.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum ImitationMethod {
    /// Poubel et al.'s support phases and task tables, one prioritized IK step per frame
    /// (default).
    Poubel(PoubelConfig),
    /// Koenemann et al.'s posture mapping, CoM offset control and foot retargeting.
    Koenemann(KoenemannConfig),
}

impl Default for ImitationMethod {
    fn default() -> Self {
        ImitationMethod::Poubel(PoubelConfig::default())
    }
}

/// Settings of the imitator that mean the same in both methods; each method's own are in
/// [`ImitatorConfig::method`]. Defaults are the paper's where it gives them.
#[derive(Debug, Clone)]
pub struct ImitatorConfig {
    /// The method and its own settings (default: Poubel et al.'s, [`PoubelConfig::default`]).
    pub method: ImitationMethod,
    /// Support detection (default: optical motion capture).
    pub support: SupportConfig,
    /// Where a foot may be put down relative to the other; `None` (default): the profile's
    /// [`BipedProfile::step_envelope`](crate::robots::BipedProfile::step_envelope).
    pub step_envelope: Option<FootArea>,
    /// Human segments shorter than this (m) keep their previous direction in the scaler
    /// (default 1e−9: only coincident points).
    pub min_segment: f64,
    /// Fraction of each leg joint's rated velocity the robot may use: the joints on the chain
    /// between the two soles, which carry the robot and close a loop in double support.
    /// `None` (default): [`PAPER_VELOCITY_FRACTION`] in Poubel et al.'s method, whose tasks
    /// bound the legs by the CoM's and the feet's speeds; the profile's
    /// [`MotionTuning::leg_velocity_fraction`] in Koenemann et al.'s, whose legs copy the
    /// human's and are slowed by this bound alone (at 10 % of the G1's fast motors its legs
    /// turned at up to 2.6 rad/s and it fell in the physics judge).
    pub velocity_fraction: Option<f64>,
    /// Fraction of the rated velocity of every joint off the sole-to-sole chain (arms, head);
    /// `None` (default): the profile's [`MotionTuning::upper_body_velocity_fraction`](crate::robots::MotionTuning::upper_body_velocity_fraction) (0.5 for
    /// the NAO: the arms follow the human closely while the legs keep the paper's 10 %; the
    /// balance level sees the arms' effect on the CoM and the solver slows the arms down when
    /// the legs cannot compensate). Set it to `velocity_fraction` for one fraction everywhere.
    pub upper_body_velocity_fraction: Option<f64>,
    /// Speed and acceleration bounds of the CoM reference and of the swing foot (see
    /// [`crate::imitation::shaping`]); `None` (default): [`MotionLimits::default`] with the profile's
    /// CoM bounds ([`MotionLimits::with_com_of`]).
    pub motion: Option<MotionLimits>,
    /// Largest speed the tasks that follow the human ask for (m/s): the points whose target is
    /// the scaled human ([`PointTarget::Scaled`](crate::imitation::phase::tables::PointTarget::Scaled), the hands
    /// in the default tables), in place of Poubel's
    /// [`PoubelConfig::max_task_speed`], so that the arms can follow the
    /// human more closely while the CoM, the torso and the feet keep their slow, shaped
    /// references (the joint velocity bounds still limit the arms). `Some`: this speed in every
    /// phase. `None` (default): the profile's
    /// [`MotionTuning::tracking_speed`](crate::robots::MotionTuning::tracking_speed) once both
    /// the human and the robot have stood on both feet for a second, and its
    /// [`stance_tracking_speed`](crate::robots::MotionTuning::stance_tracking_speed) otherwise
    /// ([`crate::imitation::shaping::HandSpeed`]; NAO 0.8 and 0.3 m/s, shaped at 2 m/s², G1 1.2 and
    /// 0.6 m/s at 5 m/s²; faster hands turned loaded feet in the physics judge, see
    /// [`crate::robots::nao::TUNING`] and [`crate::robots::g1::TUNING`]), in both methods;
    /// Poubel's with the dynamic walk on ([`FootstepConfig::dynamic`](crate::imitation::walking::footsteps::FootstepConfig::dynamic)) uses the latter
    /// throughout.
    pub max_tracking_speed: Option<f64>,
    /// Largest change of the hands' speed toward their targets (m/s², > 0) in every phase, both
    /// methods ([`crate::imitation::shaping::HandRates`]). `None` (default): the profile's
    /// [`MotionTuning::tracking_acceleration`](crate::robots::MotionTuning::tracking_acceleration).
    pub max_tracking_acceleration: Option<f64>,
    /// Time step assumed for the first frame, and for a frame with the same time as the previous
    /// one (s). Default 1/120 s.
    pub nominal_dt: f64,
    /// Initial posture (model variable order, rad); `None` (default): the profile's
    /// [`BipedProfile::stand`](crate::robots::BipedProfile::stand).
    pub initial_q: Option<Vec<f64>>,
}

impl Default for ImitatorConfig {
    fn default() -> Self {
        Self {
            method: ImitationMethod::default(),
            support: SupportConfig::optical(),
            step_envelope: None,
            min_segment: 1e-9,
            velocity_fraction: None,
            upper_body_velocity_fraction: None,
            motion: None,
            max_tracking_speed: None,
            max_tracking_acceleration: None,
            nominal_dt: 1.0 / 120.0,
            initial_q: None,
        }
    }
}

/// Poubel et al.'s fraction of each leg joint's rated velocity (§IV: 10 %).
pub const PAPER_VELOCITY_FRACTION: f64 = 0.1;

impl ImitatorConfig {
    /// [`ImitatorConfig::velocity_fraction`], or the method's default for a robot of `tuning`.
    pub(super) fn velocity_fraction_for(&self, tuning: &MotionTuning) -> f64 {
        match (self.velocity_fraction, &self.method) {
            (Some(fraction), _) => fraction,
            (None, ImitationMethod::Koenemann(_)) => tuning.leg_velocity_fraction,
            (None, ImitationMethod::Poubel(_)) => PAPER_VELOCITY_FRACTION,
        }
    }

    /// [`ImitatorConfig::motion`], or the default with the CoM bounds of `tuning`.
    pub(super) fn motion_for(&self, tuning: &MotionTuning) -> MotionLimits {
        self.motion
            .unwrap_or_else(|| MotionLimits::with_com_of(tuning))
    }

    /// The hands' speeds: [`ImitatorConfig::max_tracking_speed`] in every phase, or `tuning`'s
    /// (with `balanced`, the ZMP level on, [`MotionTuning::balanced_hands`] in every phase where
    /// the profile has them; else the double-support and stance speeds); the acceleration of
    /// [`ImitatorConfig::max_tracking_acceleration`] or `tuning`'s, chosen the same way.
    pub(super) fn hand_speed_for(&self, tuning: &MotionTuning, balanced: bool) -> HandSpeed {
        let hands = tuning.balanced_hands.filter(|_| balanced);
        let acceleration = (self.max_tracking_acceleration)
            .unwrap_or(hands.map_or(tuning.tracking_acceleration, |h| h.tracking_acceleration));
        let (double, stance) = match (self.max_tracking_speed, hands) {
            (Some(speed), _) => (speed, speed),
            (None, Some(h)) => (h.tracking_speed, h.tracking_speed),
            (None, None) => (tuning.tracking_speed, tuning.stance_tracking_speed),
        };
        HandSpeed {
            double,
            stance,
            acceleration,
        }
    }

    /// Checks the shared settings and the method's (the phase, table, support and solver
    /// settings are checked by their owners): every speed, fraction and time finite and
    /// > 0. The error names the field.
    pub(super) fn validate(&self) -> Result<(), ImitationError> {
        let invalid = |name, value, reason| {
            Err(ImitationError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        let positive = [
            (
                "velocity_fraction",
                self.velocity_fraction,
                "must be finite and > 0",
            ),
            (
                "nominal_dt",
                Some(self.nominal_dt),
                "must be finite and > 0 s",
            ),
            (
                "max_tracking_speed",
                self.max_tracking_speed,
                "must be finite and > 0 m/s",
            ),
            (
                "max_tracking_acceleration",
                self.max_tracking_acceleration,
                "must be finite and > 0 m/s²",
            ),
            (
                "upper_body_velocity_fraction",
                self.upper_body_velocity_fraction,
                "must be finite and > 0",
            ),
        ];
        ImitationError::check_positive(&positive)?;
        if let Some((name, value)) = self.motion.and_then(|m| m.invalid_field()) {
            return invalid(name, value, "motion limits must be finite and > 0");
        }
        match &self.method {
            ImitationMethod::Poubel(poubel) => poubel.validate(),
            ImitationMethod::Koenemann(k) => match k.invalid_field() {
                Some((name, value, reason)) => invalid(name, value, reason),
                None => Ok(()),
            },
        }
    }

    /// Poubel et al.'s settings, if that is the method.
    pub fn poubel(&self) -> Option<&PoubelConfig> {
        match &self.method {
            ImitationMethod::Poubel(poubel) => Some(poubel),
            ImitationMethod::Koenemann(_) => None,
        }
    }

    /// Poubel et al.'s settings, if that is the method: to change one in place
    /// (`config.poubel_mut().map(|p| p.zmp_balance = Some(false))`).
    pub fn poubel_mut(&mut self) -> Option<&mut PoubelConfig> {
        match &mut self.method {
            ImitationMethod::Poubel(poubel) => Some(poubel),
            ImitationMethod::Koenemann(_) => None,
        }
    }
}

/// The default shared settings with Poubel et al.'s method set so.
impl From<PoubelConfig> for ImitatorConfig {
    fn from(poubel: PoubelConfig) -> Self {
        Self {
            method: ImitationMethod::Poubel(poubel),
            ..Self::default()
        }
    }
}

/// The default shared settings with Koenemann et al.'s method set so.
impl From<KoenemannConfig> for ImitatorConfig {
    fn from(koenemann: KoenemannConfig) -> Self {
        Self {
            method: ImitationMethod::Koenemann(koenemann),
            ..Self::default()
        }
    }
}
