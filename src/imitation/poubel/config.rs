//! The settings of Poubel et al.'s method alone ([`PoubelConfig`]): phases, task tables, the
//! solver, the robot's steps, the ZMP balance, the hands as supports and the offline
//! look-ahead. What both methods share is in [`ImitatorConfig`](crate::imitation::ImitatorConfig).

use crate::imitation::error::ImitationError;
use crate::imitation::phase::PhaseConfig;
use crate::imitation::phase::tables::TaskTables;
use crate::imitation::poubel::hand_support::HandSupportConfig;
use crate::imitation::walking::footsteps::FootstepConfig;
use crate::imitation::walking::look_ahead::FootLookAhead;
use crate::robots::MotionTuning;
use crate::solver::Settings;

/// Settings of Poubel et al.'s method (the default,
/// [`ImitationMethod::Poubel`](crate::imitation::ImitationMethod::Poubel)). Defaults are the
/// paper's where it gives them.
#[derive(Debug, Clone)]
pub struct PoubelConfig {
    /// Phase machine: λ, ρ and the step-end tolerances.
    pub phase: PhaseConfig,
    /// The task tables; `None` (default): [`TaskTables::executable`] for the profile, Table I
    /// with the feet held fully while they stand, the CoM at the middle of the contact area and
    /// an upright torso.
    pub tables: Option<TaskTables>,
    /// Gauss–Newton steps per frame (default 1, as the paper: one IK per time step). Each step
    /// is limited to the velocity budget of the whole frame divided by this count.
    pub iterations_per_frame: usize,
    /// Largest speed any task asks for (m/s): each frame every task's error (CoM, feet, torso,
    /// hands unless [`ImitatorConfig::max_tracking_speed`](crate::imitation::ImitatorConfig::max_tracking_speed) gives theirs) is clipped to
    /// `max_task_speed · dt`, so the velocity limits are rarely hit and the clamping loop does
    /// not have to take the tasks apart. `None` (default): the profile's
    /// [`MotionTuning::task_speed`] (0.15 m/s for the NAO, about what 10 % of its rated joint
    /// velocities give at its hands). Koenemann et al.'s method has no task errors to clip;
    /// its swing foot's speed is [`KoenemannConfig::swing_speed`](crate::imitation::koenemann::KoenemannConfig::swing_speed).
    pub max_task_speed: Option<f64>,
    /// When and where the robot steps: the human's footprints, scaled, clipped to the step
    /// envelope, taken one step at a time (see [`crate::imitation::walking::footsteps`]).
    pub footsteps: FootstepConfig,
    /// Fraction of each leg joint's rated velocity while the robot walks
    /// ([`crate::imitation::walking`]): the walk's timing is the pattern generator's, and a
    /// swing leg that lags its plan lands late. Default 1 (the NAO's swing knee reaches
    /// 0.97–1.0 of its rated speed in 5 cm steps of 1 s);
    /// [`ImitatorConfig::velocity_fraction`](crate::imitation::ImitatorConfig::velocity_fraction) still bounds the support phases.
    pub walking_velocity_fraction: f64,
    /// Numerical settings of the solver. The method turns [`Settings::scale_to_fit`] on for
    /// tables without inequality rows (when the velocity limits bind, the whole step slows
    /// down uniformly instead of the clamping loop pinning joints the balance level needs) and
    /// [`Settings::warm_start`] on (each frame's active-set solve starts from the last frame's
    /// active bounds). [`Settings::max_passes`] bounds a frame's solve (default: the method's
    /// own cap). Measured on the NAO over the bundled clips: most frames take one pass (about
    /// 6 µs of a 16 µs step), one frame in a hundred 7–11 (arm limits, lifts, landings), the
    /// slowest 21–31. A budget of 8 cuts the p99 step by 20–40 % and the robot still stands in
    /// the physics judge, but a solve cut short leaves the higher levels part of their motion:
    /// on CMU 07_04 with `--walk` the robot, its lifts cut frame after frame, walked 0.07 of
    /// 0.88 m (0.55 m unbounded), and with 6 a loaded foot turned 2.6° on CMU 09_12. Hence no
    /// budget by default. Its [`Settings::damping_threshold`] and [`Settings::max_damping`]
    /// are replaced by [`PoubelConfig::damping`].
    pub solver: Settings,
    /// The solver's damping of near-singular levels (> 0; task units per rad, m/rad for the
    /// hands): the damping threshold and the largest damping of `solver`. `None` (default):
    /// the profile's [`MotionTuning::damping`] (NAO 0.02, G1 0.039: it scales with the arm).
    pub damping: Option<f64>,
    /// The share (0–1) of the last frame's joint step that a damped level keeps (the support
    /// phases). A level whose smallest singular value falls below the damping
    /// ([`PoubelConfig::damping`]; an elbow near straight, a wrist turn that hardly moves the
    /// hand point) is damped, and its poorly conditioned directions are damped toward this
    /// share of the last step
    /// ([`crate::solver::driver::PositionDriver::set_step_reference`]) instead of toward rest:
    /// such a direction then keeps moving the way it moved rather than reversing at speed from
    /// frame to frame, while the well-conditioned directions are solved exactly either way. A
    /// level holding inequality rows at their bounds is damped toward rest whatever this says.
    /// Default 0 (toward rest, the textbook damping). Pair it with a larger damping: see the
    /// CHANGELOG for measurements.
    pub damping_momentum: f64,
    /// Balance that sees the arms' dynamics (the support phases; not the dynamic walk's
    /// frames): every table gets a ZMP level below the feet and the CoM
    /// ([`TaskTables::add_zmp_balance`]), which keeps the ZMP of the CoM and the arms'
    /// acceleration (from the model's masses and inertias) inside the support polygon and the
    /// arms' vertical moment on the feet below what friction holds; the hands then move at the
    /// profile's [`MotionTuning::balanced_hands`] speeds where it has them (the NAO: 1 m/s,
    /// 5 m/s²; not in a dynamic walk) unless [`ImitatorConfig::max_tracking_speed`](crate::imitation::ImitatorConfig::max_tracking_speed) /
    /// [`ImitatorConfig::max_tracking_acceleration`](crate::imitation::ImitatorConfig::max_tracking_acceleration) say otherwise.
    ///
    /// `None` (default): on where [`PoubelConfig::zmp_balance_on`] says it is measured to help
    /// (a profile with balanced hands, the robot not walking dynamically, no hand supports);
    /// `Some(false)`: the old, slower arms (fixed caps chosen for the static check; the
    /// hands 1–3 cm farther from the human on the clips where the arms move fast, a
    /// tenth of a second or more late), for comparison or a robot whose masses are not known
    /// well. With hands at 1 m/s (10 m/s²), the level is what keeps the arms' reaction from
    /// turning the NAO's loaded feet in the physics judge (CMU 131_01 without it: 2.3–2.8°);
    /// at 1.5 m/s and 20 m/s² it no longer does. The price at 1 m/s: the arms turn back at
    /// speed on 4–86 frames a clip (0–14 at the default speeds) and the step is slower.
    pub zmp_balance: Option<bool>,
    /// Hands as supports, from a recording's contact list (see
    /// [`crate::imitation::poubel::hand_support`]). `None` (default): the hands only follow
    /// the human.
    pub hand_supports: Option<HandSupportConfig>,
    /// The offline mode's look-ahead for the feet: the recording's foot lifts, known in advance
    /// (see [`crate::imitation::walking::look_ahead`]). `None` (default): online, the robot
    /// reacts to the human's feet as it sees them.
    pub look_ahead: Option<FootLookAhead>,
}

impl Default for PoubelConfig {
    fn default() -> Self {
        Self {
            phase: PhaseConfig::default(),
            tables: None,
            iterations_per_frame: 1,
            max_task_speed: None,
            footsteps: FootstepConfig::default(),
            walking_velocity_fraction: 1.0,
            solver: Settings::default(),
            damping: None,
            damping_momentum: 0.0,
            zmp_balance: None,
            hand_supports: None,
            look_ahead: None,
        }
    }
}

impl PoubelConfig {
    /// Whether the ZMP level is on for a robot of `tuning`: [`PoubelConfig::zmp_balance`], or
    /// by default where the judge measured it to help: the profile has
    /// [`MotionTuning::balanced_hands`] (their masses and speeds measured together: the NAO),
    /// the robot does not follow the human's steps dynamically (the level models a robot
    /// standing in place; in a dynamic walk it turned a loaded NAO foot 2.5–4.0° on CMU 09_12
    /// and let the weak model's ZMP leave the soles on 05_12) and the hands are no supports
    /// (its polygon is the feet's; with the hands on a stool the weak model's ZMP left it).
    pub fn zmp_balance_on(&self, tuning: &MotionTuning) -> bool {
        self.zmp_balance.unwrap_or_else(|| {
            tuning.balanced_hands.is_some()
                && !(self.footsteps.follow && self.footsteps.dynamic)
                && self.hand_supports.is_none()
        })
    }

    /// `solver` with the damping of [`PoubelConfig::damping`], or `tuning`'s.
    pub(super) fn solver_for(&self, tuning: &MotionTuning) -> Settings {
        let damping = self.damping.unwrap_or(tuning.damping);
        Settings {
            damping_threshold: damping,
            max_damping: damping,
            ..self.solver
        }
    }

    /// Checks the method's own settings (the phase, table and solver settings are checked by
    /// their owners): speeds and fractions finite and > 0, footstep thresholds ≥ 0, at least
    /// one iteration per frame, the damping momentum a share. The error names the field
    /// (`poubel.` and the field's name).
    pub(crate) fn validate(&self) -> Result<(), ImitationError> {
        let invalid = |name, value, reason| {
            Err(ImitationError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        let positive = [
            (
                "poubel.walking_velocity_fraction",
                Some(self.walking_velocity_fraction),
                "must be finite and > 0",
            ),
            (
                "poubel.max_task_speed",
                self.max_task_speed,
                "must be finite and > 0 m/s",
            ),
            ("poubel.damping", self.damping, "must be finite and > 0"),
        ];
        ImitationError::check_positive(&positive)?;
        if let Some((name, value)) = self.footsteps.invalid_field() {
            return invalid(name, value, "must be >= 0");
        }
        if self.iterations_per_frame == 0 {
            return invalid("poubel.iterations_per_frame", 0.0, "must be >= 1");
        }
        if !(0.0..=1.0).contains(&self.damping_momentum) {
            let reason = "must be in [0, 1]";
            return invalid("poubel.damping_momentum", self.damping_momentum, reason);
        }
        if let Some(hands) = &self.hand_supports {
            hands.validate()?;
        }
        if let Some((name, value)) = (self.look_ahead.as_ref()).and_then(|a| a.invalid_field()) {
            return invalid(name, value, "must be finite and >= 0 s");
        }
        Ok(())
    }
}
