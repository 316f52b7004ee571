//! Options shared by `imitate` and `batch`: the robot, the imitator's settings, the hold.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use taskstack::ImitatorConfig;
use taskstack::batch::{ClipSetup, Hold, LookAheadLeads, MAX_HOLD};
use taskstack::imitation::ImitationMethod;
use taskstack::imitation::koenemann::{Calibration, FootRetargeting, KoenemannConfig};
use taskstack::imitation::poubel::PoubelConfig;
use taskstack::imitation::walking::look_ahead::FootLookAhead;
use taskstack::io::skeleton_map::SkeletonMap;
use taskstack::robots::{BipedProfile, g1, nao};
use taskstack::scene::Scene;

/// What each clip gives its run beyond its frames (`imitate` and `batch`).
#[derive(Debug, Clone, Args)]
pub(crate) struct ClipOptions {
    /// Hands as supports (Di Fava et al.): the contacts of the human's hands with the surfaces
    /// of this scene (TOML, the clip's world frame; see `taskstack contacts`) are found first;
    /// a hand the human rests on a surface is placed on it, held there and joins the support
    /// polygon, whose centre the CoM goes to. The human's clock pauses until the hand is
    /// placed, so joints.csv has its own time axis. Poubel et al.'s method only.
    #[arg(long, value_name = "SCENE.toml")]
    scene: Option<PathBuf>,
    /// Offline mode: the whole clip is read first, so the robot knows when the human will lift
    /// each foot, for how long and where it will land. It starts shifting its weight onto the
    /// other foot as long before the human lifts one as its weight shift takes (the foot itself
    /// leaves the ground with the human's), lowers a lifted foot as long before the human's lands
    /// as its lowering takes, and with --walk steps toward where the human's foot will land. It
    /// times its own motions as it goes; --lift-lead and --landing-lead are the first guesses.
    /// Poubel et al.'s method only
    #[arg(long)]
    offline: bool,
    /// Offline mode: the first guess of how long the robot's weight shift takes (s, ≥ 0)
    #[arg(long, value_name = "SECONDS", default_value_t = FootLookAhead::DEFAULT_LIFT_LEAD, requires = "offline", allow_negative_numbers = true)]
    lift_lead: f64,
    /// Offline mode: the first guess of how long the robot's lowering of a foot takes (s, ≥ 0)
    #[arg(long, value_name = "SECONDS", default_value_t = FootLookAhead::DEFAULT_LANDING_LEAD, requires = "offline", allow_negative_numbers = true)]
    landing_lead: f64,
}

impl ClipOptions {
    /// The clip setup of these options with the skeleton `map` (the scene file read here).
    pub(crate) fn setup(&self, map: Option<SkeletonMap>) -> Result<ClipSetup> {
        let scene = (self.scene.as_ref())
            .map(Scene::from_toml_file)
            .transpose()?;
        let look_ahead = self.offline.then_some(LookAheadLeads {
            lift_lead: self.lift_lead,
            landing_lead: self.landing_lead,
        });
        Ok(ClipSetup {
            skeleton_map: map,
            look_ahead,
            scene,
        })
    }
}

#[derive(Debug, Clone, Args)]
pub(crate) struct ImitationOptions {
    /// The robot: `nao` (NAO H25 V5), `g1` (Unitree G1, 29 DoF) or a biped profile file
    /// (TOML next to a URDF; see `taskstack::robots::BipedProfile::from_toml_file`).
    #[arg(long, value_name = "nao|g1|PROFILE.toml", default_value = "nao")]
    pub(crate) robot: String,
    /// Write the servo commands of joints.csv as planned, not through the sway shaper of a
    /// robot whose profile states its sway period on one foot (the G1: 1.1 s). The shaper
    /// keeps stiff servos from rocking the robot on its stance ankle (more G1 runs stand in
    /// physics) and delays the commands by about half that period (0.52 s on the G1); a
    /// robot with its own balance feedback may want the plan on time.
    #[arg(long)]
    pub(crate) no_sway_shaping: bool,
    /// Let the robot's feet follow the human's footprints: it walks where the human walks, one
    /// step at a time. Without it the robot stands on one leg when the human does, and puts the
    /// foot back where it was.
    #[arg(long)]
    pub(crate) walk: bool,
    /// Experimental: walk with the walking pattern generator (implies `--walk`): dynamic steps
    /// of the robot's own timing (NAO: 1.0 s double + 0.67 s single support) instead of one
    /// quasi-static step at a time; the arms hold still while the robot walks. Not yet the
    /// default: on the bundled clips the physics judge's NAO passes every check on both
    /// models, but the walk is slow (about 2 cm/s) and the G1 falls.
    #[arg(long)]
    pub(crate) dynamic_walk: bool,
    /// Experimental, with --dynamic-walk: the hands follow the human while the robot walks
    /// (an arm step after each walking frame moves the arms alone). The hands come 4–8 cm
    /// nearer the human on the bundled walks, but the walk's plan does not see the arms'
    /// momentum and the physics judge's NAO falls on some walking clips: for kinematic
    /// retargeting, not yet for a robot.
    #[arg(long, requires = "dynamic_walk")]
    pub(crate) walking_arms: bool,
    /// With --walk: a robot foot farther than this from its target footprint (m, ≥ 0) takes a
    /// step. Default 0.02.
    #[arg(long, value_name = "M", value_parser = non_negative, allow_negative_numbers = true)]
    pub(crate) step_distance: Option<f64>,
    /// With --walk: a robot foot turned more than this from its target footprint's heading
    /// (rad, ≥ 0) takes a step. Default 0.087 (5°).
    #[arg(long, value_name = "RAD", value_parser = non_negative, allow_negative_numbers = true)]
    pub(crate) step_heading: Option<f64>,
    /// With --walk (quasi-static steps): a human foot on the ground keeps the footprint it
    /// landed with until it has turned more than this from it (rad, ≥ 0) or moved more than
    /// --step-slide; then it is followed until it lifts (a pivot turn, a shuffle). Default
    /// 0.26 (15°): a standing human's foot jitters by up to 12° in the bundled captures.
    #[arg(long, value_name = "RAD", value_parser = non_negative, allow_negative_numbers = true)]
    pub(crate) step_pivot: Option<f64>,
    /// With --walk: see --step-pivot (m, ≥ 0, in the human's world, unscaled). Default 0.05.
    #[arg(long, value_name = "M", value_parser = non_negative, allow_negative_numbers = true)]
    pub(crate) step_slide: Option<f64>,
    /// Poubel's method: balance that sees the whole body's dynamics, also where it is off by
    /// default. A level below the feet and the CoM keeps the whole body's ZMP (the arms'
    /// acceleration included) inside the support polygon and the floor's vertical moment on
    /// the feet below what friction holds, so fast hands are held back only when they would
    /// tip the robot or turn a foot; the hands then move at the robot profile's balanced
    /// speeds (NAO 1 m/s, 5 m/s², in every phase) unless --tracking-speed and
    /// --tracking-acceleration say otherwise. On by default for a robot profile with balanced
    /// hand speeds (the NAO), but not with --dynamic-walk or a scene's hand supports, where the
    /// judge measured it to hurt.
    #[arg(long, conflicts_with = "no_zmp_balance")]
    pub(crate) zmp_balance: bool,
    /// Poubel's method: the old, slower arms: no ZMP level, the hands at the robot profile's
    /// fixed caps chosen for a static balance (NAO 0.8 m/s on both feet, 0.3 m/s on one,
    /// 2 m/s²), a tenth of a second or more late where the human's arms move fast.
    #[arg(long)]
    pub(crate) no_zmp_balance: bool,
    /// Poubel's method: the solver's damping of near-singular levels (μ in task units per
    /// rad, above 0): a level whose smallest singular value is below MU is damped, up to MU.
    /// Default: the robot profile's (NAO 0.02, G1 0.039). Larger damping stops arms
    /// chattering near a singular pose (an elbow near straight) at the cost of hand tracking;
    /// see --damping-momentum.
    #[arg(long, value_name = "MU", value_parser = positive, allow_negative_numbers = true)]
    pub(crate) damping: Option<f64>,
    /// Poubel's method: share (0–1) of the last frame's joint step that a damped level keeps
    /// in its poorly conditioned directions instead of coming to rest (0, the default, is the
    /// textbook damping). With --damping 0.1 and 0.8 the NAO's joints reverse at speed on a
    /// few frames instead of dozens, with the hands nearer the human than the same damping
    /// toward rest.
    #[arg(long, value_name = "SHARE", default_value_t = 0.0, value_parser = share,
          allow_negative_numbers = true)]
    pub(crate) damping_momentum: f64,
    /// After the clip, hold the human's last pose (frames 1/120 s apart) so the robot can
    /// finish the step it is taking; those frames are in every output. `auto`: until the robot
    /// has finished (a continuous phase, no step pending, on the feet the human stands on) for
    /// 1 s, at most 60 s (the summary and metrics.json's `finished` say when the cap cut it
    /// short); or SECONDS (at most 3600).
    #[arg(long, value_name = "auto|SECONDS", default_value = "auto", value_parser = hold,
          allow_negative_numbers = true)]
    pub(crate) hold: Hold,
    /// Share of each joint's rated velocity the legs may use (0 < F ≤ 1). Default: 0.1 with
    /// Poubel et al.'s method (the paper's), the robot profile's with Koenemann et al.'s,
    /// whose legs copy the human's (NAO 0.1, G1 0.012).
    #[arg(long, value_name = "F", value_parser = fraction, allow_negative_numbers = true)]
    pub(crate) velocity_fraction: Option<f64>,
    /// Share of the rated velocity the arms, head and torso may use (0 < F ≤ 1). Default: the
    /// robot profile's (NAO 0.5, G1 0.1).
    #[arg(long, value_name = "F", value_parser = fraction, allow_negative_numbers = true)]
    pub(crate) upper_body_fraction: Option<f64>,
    /// Poubel's method: fastest speed any task's target moves at (m/s, > 0): the CoM, the
    /// feet, the torso, and the hands where --tracking-speed does not set theirs. Default: the
    /// robot profile's (NAO 0.15).
    #[arg(long, value_name = "M_PER_S", value_parser = positive, allow_negative_numbers = true)]
    pub(crate) task_speed: Option<f64>,
    /// `--method koenemann`: fastest speed of the swing foot's target toward the human's foot
    /// (m/s, > 0). Default: the robot profile's task speed (NAO 0.15).
    #[arg(long, value_name = "M_PER_S", value_parser = positive, allow_negative_numbers = true)]
    pub(crate) swing_speed: Option<f64>,
    /// Fastest speed of the hand targets toward the scaled human (m/s, > 0), in every phase.
    /// Default: the profile's balanced speed where it has one and the ZMP level is on or the
    /// method is Koenemann's (NAO 1, every phase); else the profile's once both feet have
    /// stood for a second / on one foot and while the weight shifts (NAO 0.8 / 0.3, G1
    /// 1.2 / 0.6; --dynamic-walk the second throughout).
    #[arg(long, value_name = "M_PER_S", value_parser = positive, allow_negative_numbers = true)]
    pub(crate) tracking_speed: Option<f64>,
    /// Largest change of the hand targets' speed (m/s², > 0), in every phase: the hands start
    /// and brake instead of reaching their speed in one frame. Default: the profile's, chosen
    /// as --tracking-speed's (NAO 5 balanced, else 2; G1 5).
    #[arg(long, value_name = "M_PER_S2", value_parser = positive, allow_negative_numbers = true)]
    pub(crate) tracking_acceleration: Option<f64>,
    /// Poubel's method: solver iterations per human frame (1–100).
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=100))]
    pub(crate) iterations: u32,
    /// Read BVH clips whose joints do not carry the CMU names through this skeleton map (TOML:
    /// unit scale, up axis, frames to skip, human joint = BVH joint name).
    #[arg(long, value_name = "MAP.toml")]
    pub(crate) skeleton: Option<PathBuf>,
    /// The imitation method: `poubel` (support phases and task tables, Poubel et al. 2014) or
    /// `koenemann` (posture mapping, CoM offset control and foot retargeting, Koenemann et al.
    /// 2014). Same outputs and metrics for both.
    #[arg(long, value_enum, default_value_t = MethodName::Poubel)]
    pub(crate) method: MethodName,
    /// `--method koenemann`: the human's reference posture for the limb ratios. `auto`: the
    /// first frame if it is a T-pose, else an ideal T-pose at the human's limb lengths.
    #[arg(long, value_enum, default_value_t = CalibrationName::Auto)]
    pub(crate) calibration: CalibrationName,
    /// `--method koenemann`: how double support meets the commanded CoM offset.
    /// `shift-both-feet`: the stance is kept (no foot slides); `move-one-foot`: the paper's rule
    /// (a loaded foot slides on a real floor).
    #[arg(long, value_enum, default_value_t = RetargetingName::ShiftBothFeet)]
    pub(crate) retargeting: RetargetingName,
    /// Also write the motion in this layout: `unitree-csv` writes motion_unitree.csv, the
    /// layout of Unitree's retargeted LAFAN1 dataset (per frame, no header: base x y z (m),
    /// base quaternion x y z w, the joint angles (rad) in the robot's URDF order; 30 frames a
    /// second unless --fps).
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub(crate) export: Option<ExportFormat>,
    /// Frame rate of the motion exports (Hz, > 0), resampled from the run's frames. Default:
    /// motion.npz at the clip's own rate (rounded), --export unitree-csv at 30.
    #[arg(long, value_name = "HZ", value_parser = positive, allow_negative_numbers = true)]
    pub(crate) fps: Option<f64>,
}

/// The motion layouts `--export` writes besides motion.npz.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ExportFormat {
    /// motion_unitree.csv: Unitree's retargeted LAFAN1 layout.
    UnitreeCsv,
}

/// `--calibration` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum CalibrationName {
    /// The first frame if it is a T-pose, else the ideal T-pose.
    Auto,
    /// The first frame with the whole skeleton, whatever its posture.
    FirstFrame,
    /// An ideal T-pose at the human's limb lengths.
    Ideal,
}

/// `--retargeting` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum RetargetingName {
    /// Both feet shift together in the torso frame: the stance is kept.
    ShiftBothFeet,
    /// One foot moves toward the CoM (Koenemann et al.'s Fig. 5).
    MoveOneFoot,
}

/// The imitation methods by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum MethodName {
    /// Poubel et al.: support phases and task tables.
    Poubel,
    /// Koenemann et al.: posture mapping and stabilization.
    Koenemann,
}

impl ImitationOptions {
    /// The robot named by `--robot`.
    pub(crate) fn profile(&self) -> Result<BipedProfile> {
        let mut profile = robot_profile(&self.robot)?;
        if self.no_sway_shaping {
            profile.sway_period = None;
        }
        Ok(profile)
    }

    /// The motion exports asked for.
    pub(crate) fn exports(&self) -> Exports {
        Exports {
            unitree_csv: self.export == Some(ExportFormat::UnitreeCsv),
            fps: self.fps,
        }
    }

    /// The skeleton map of `--skeleton`, read once for every clip.
    pub(crate) fn skeleton_map(&self) -> Result<Option<SkeletonMap>> {
        self.skeleton
            .as_ref()
            .map(|path| {
                SkeletonMap::from_toml_file(path)
                    .with_context(|| format!("--skeleton {}", path.display()))
            })
            .transpose()
    }

    /// The imitator settings of these options (support detection is set per clip); an option
    /// of the other method is an error.
    pub(crate) fn imitator_config(&self) -> Result<ImitatorConfig> {
        let (method, others) = match self.method {
            MethodName::Poubel => (
                ImitationMethod::Poubel(self.poubel()),
                self.koenemann_given(),
            ),
            MethodName::Koenemann => {
                let koenemann = KoenemannConfig {
                    calibration: match self.calibration {
                        CalibrationName::Auto => Calibration::Auto,
                        CalibrationName::FirstFrame => Calibration::FirstFrame,
                        CalibrationName::Ideal => Calibration::Ideal,
                    },
                    retargeting: match self.retargeting {
                        RetargetingName::ShiftBothFeet => FootRetargeting::ShiftBothFeet,
                        RetargetingName::MoveOneFoot => FootRetargeting::MoveOneFoot,
                    },
                    swing_speed: self.swing_speed,
                    ..KoenemannConfig::default()
                };
                (ImitationMethod::Koenemann(koenemann), self.poubel_given())
            }
        };
        if let Some(option) = others.first() {
            let method = format!("{:?}", self.method).to_lowercase();
            let message = format!("{option} is not an option of --method {method}");
            return Err(UsageError(message).into());
        }
        Ok(ImitatorConfig {
            method,
            velocity_fraction: self.velocity_fraction,
            upper_body_velocity_fraction: self.upper_body_fraction,
            max_tracking_speed: self.tracking_speed,
            max_tracking_acceleration: self.tracking_acceleration,
            ..ImitatorConfig::default()
        })
    }

    /// Poubel et al.'s settings of these options.
    fn poubel(&self) -> PoubelConfig {
        let mut poubel = PoubelConfig {
            max_task_speed: self.task_speed,
            iterations_per_frame: self.iterations as usize,
            zmp_balance: self.zmp_balance_choice(),
            damping_momentum: self.damping_momentum,
            damping: self.damping,
            ..PoubelConfig::default()
        };
        let steps = &mut poubel.footsteps;
        steps.follow = self.walk || self.dynamic_walk;
        steps.dynamic = self.dynamic_walk;
        steps.walking_arms = self.walking_arms;
        for (option, field) in [
            (self.step_distance, &mut steps.distance),
            (self.step_heading, &mut steps.heading),
            (self.step_pivot, &mut steps.pivot),
            (self.step_slide, &mut steps.slide),
        ] {
            if let Some(value) = option {
                *field = value;
            }
        }
        poubel
    }

    /// `--zmp-balance` / `--no-zmp-balance`, or the profile's default (`None`).
    fn zmp_balance_choice(&self) -> Option<bool> {
        match (self.zmp_balance, self.no_zmp_balance) {
            (true, _) => Some(true),
            (_, true) => Some(false),
            (false, false) => None,
        }
    }

    /// The options of Poubel's method given away from their defaults.
    fn poubel_given(&self) -> Vec<&'static str> {
        let steps = [
            self.step_distance,
            self.step_heading,
            self.step_pivot,
            self.step_slide,
        ];
        [
            (self.walk, "--walk"),
            (self.dynamic_walk, "--dynamic-walk"),
            (self.walking_arms, "--walking-arms"),
            (steps.iter().any(Option::is_some), "--step-*"),
            (self.zmp_balance, "--zmp-balance"),
            (self.no_zmp_balance, "--no-zmp-balance"),
            (self.damping.is_some(), "--damping"),
            (self.damping_momentum != 0.0, "--damping-momentum"),
            (self.task_speed.is_some(), "--task-speed"),
            (self.iterations != 1, "--iterations"),
        ]
        .into_iter()
        .filter_map(|(given, name)| given.then_some(name))
        .collect()
    }

    /// The options of Koenemann's method given away from their defaults.
    fn koenemann_given(&self) -> Vec<&'static str> {
        [
            (self.calibration != CalibrationName::Auto, "--calibration"),
            (
                self.retargeting != RetargetingName::ShiftBothFeet,
                "--retargeting",
            ),
            (self.swing_speed.is_some(), "--swing-speed"),
        ]
        .into_iter()
        .filter_map(|(given, name)| given.then_some(name))
        .collect()
    }
}

/// The robot of a `--robot` option: `nao`, `g1` or a profile file.
pub(crate) fn robot_profile(robot: &str) -> Result<BipedProfile> {
    Ok(match robot {
        "nao" => nao::profile(),
        "g1" => g1::profile(),
        path => BipedProfile::from_toml_file(path)
            .with_context(|| format!("--robot {path}: not nao, g1 or a readable profile"))?,
    })
}

fn number(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!("`{text}` is not finite"))
    }
}

pub(crate) fn positive(text: &str) -> Result<f64, String> {
    let value = number(text)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(format!("{value} is not > 0"))
    }
}

pub(crate) fn non_negative(text: &str) -> Result<f64, String> {
    let value = number(text)?;
    if value >= 0.0 {
        Ok(value)
    } else {
        Err(format!("{value} is not ≥ 0"))
    }
}

fn at_most_one(value: f64) -> Result<f64, String> {
    if value <= 1.0 {
        Ok(value)
    } else {
        Err(format!("{value} is not ≤ 1"))
    }
}

/// A share of a rated velocity: in (0, 1].
fn fraction(text: &str) -> Result<f64, String> {
    positive(text).and_then(at_most_one)
}

/// A share that may be none: in [0, 1].
fn share(text: &str) -> Result<f64, String> {
    non_negative(text).and_then(at_most_one)
}

fn hold(text: &str) -> Result<Hold, String> {
    if text == "auto" {
        return Ok(Hold::UntilFinished);
    }
    let value = number(text)?;
    if (0.0..=MAX_HOLD).contains(&value) {
        Ok(Hold::Fixed(value))
    } else {
        Err(format!("{value} s is not within 0–{MAX_HOLD} s"))
    }
}

/// Options that parse but do not go together (exit code 2, as clap's own usage errors).
#[derive(Debug)]
pub(crate) struct UsageError(pub(crate) String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// The motion exports beside `joints.csv`.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Exports {
    /// Also write `motion_unitree.csv` (Unitree's LAFAN1 layout).
    pub(crate) unitree_csv: bool,
    /// Their frame rate (Hz); `None`: motion.npz at the clip's own rate, the Unitree CSV at 30.
    pub(crate) fps: Option<f64>,
}
