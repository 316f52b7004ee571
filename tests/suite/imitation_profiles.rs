//! Imitation of other bipeds than the NAO: the Unitree G1 (built-in profile) on every bundled
//! clip, and a synthetic biped described only by a URDF and a profile TOML written for this test
//! (`tests/data/tiny_biped/`), with the invariants the NAO's runs keep: joint angles finite and
//! within their limits, steps within the velocity limits, the CoM over the feet on the ground, the
//! support foot not slipping across model switches.

use taskstack::human::HumanFrame;
use taskstack::imitation::metrics::{ImitationMetrics, MetricsRecorder};
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::robots::{BipedProfile, ProfileError, g1};

const MOCAP: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap/");
const TINY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/tiny_biped/");

/// Imitates `clip` with `profile` and checks every frame's joint angles against the bounds.
fn imitate(profile: BipedProfile, clip: &str) -> ImitationMetrics {
    imitate_with(profile, clip, ImitatorConfig::default())
}

/// [`imitate`] with `config` (its support detection set for the clip).
fn imitate_with(profile: BipedProfile, clip: &str, config: ImitatorConfig) -> ImitationMetrics {
    imitate_held(profile, clip, config, 0.0)
}

/// [`imitate_with`], then the human's last pose held `hold` seconds (120 frames a second).
fn imitate_held(
    profile: BipedProfile,
    clip: &str,
    config: ImitatorConfig,
    hold: f64,
) -> ImitationMetrics {
    let mut source = Clip::open(format!("{MOCAP}{clip}")).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(source.capture()),
        ..config
    };
    let mut imitator = Imitator::new(profile, config).unwrap();
    let mut recorder = MetricsRecorder::new(&imitator);
    let mut frame = HumanFrame::new(0.0);
    let mut step = |frame: &HumanFrame| {
        let r = imitator.step(frame).unwrap().clone();
        assert!(r.q.iter().all(|q| q.is_finite()), "{clip} at {} s", r.time);
        recorder.record(&r);
    };
    while source.read_frame(&mut frame).unwrap() {
        step(&frame);
    }
    let end = frame.time;
    while frame.time < end + hold {
        frame.time += 1.0 / 120.0;
        step(&frame);
    }
    recorder.finish()
}

fn assert_executable(m: &ImitationMetrics, clip: &str) {
    assert_eq!(m.joint_limit_violations, 0, "{clip}");
    assert_eq!(m.velocity_limit_violations, 0, "{clip}");
    assert_eq!(
        m.frames_com_outside, 0,
        "{clip}: CoM left the support polygon"
    );
    assert!(
        m.min_com_margin > 0.005,
        "{clip}: CoM margin {}",
        m.min_com_margin
    );
    // The support foot is the model's root: it moves only through model switches.
    assert!(
        m.max_support_slip < 1e-4,
        "{clip}: slip {}",
        m.max_support_slip
    );
    assert!(
        m.max_support_turn < 1e-3,
        "{clip}: turn {}",
        m.max_support_turn
    );
    assert!(
        m.max_held_foot_slip < 1e-3,
        "{clip}: {}",
        m.max_held_foot_slip
    );
}

fn clips() -> Vec<String> {
    let mut clips: Vec<String> = std::fs::read_dir(MOCAP)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".bvh") || n.ends_with(".csv"))
        .collect();
    clips.sort();
    assert!(clips.len() >= 8);
    clips
}

#[test]
fn g1_imitates_every_bundled_clip_within_its_limits() {
    let profile = g1::profile();
    let mut single_support = 0;
    for clip in clips() {
        let m = imitate(profile.clone(), &clip);
        assert_executable(&m, &clip);
        // No chatter: damped at the NAO's 0.02 m/rad rather than the G1's arm-scaled 0.039
        // (`MotionTuning::damping`), joints turned back at speed on 285 of 3 099 frames of CMU
        // 09_12 and 175 of 994 of 131_01. At most 2 %: Kinect ges01's waving arm, stretched
        // over the head past the G1's shoulder range, turns back on 2 of its 154 frames since
        // the arms hang from the robot's shoulders (1 before).
        assert!(
            m.joint_reversal_frames * 50 <= m.frames,
            "{clip}: {} of {} frames with a joint turning back at speed",
            m.joint_reversal_frames,
            m.frames
        );
        single_support += m.robot_support_changes;
    }
    // The G1 follows the human onto one leg on the clips that have a long stance.
    assert!(single_support >= 2, "{single_support}");
}

/// Every foot the G1 lifts it puts down again: with its torso carried at the NAO's 0.02 m below
/// standing, the free leg of the G1 (three times as long) ended straight 22 µm above the floor
/// on CMU 05_02 and the landing never finished.
#[test]
fn g1_lands_every_foot_it_lifts() {
    for clip in [
        "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh",
        "cmu_05_12_slow_dance_tendu_arms_high.bvh",
    ] {
        let m = imitate_held(g1::profile(), clip, ImitatorConfig::default(), 8.0);
        assert_executable(&m, clip);
        let sequence = &m.robot_support_sequence;
        assert!(sequence.len() >= 3, "{clip}: {sequence:?}");
        assert_eq!(sequence.last(), Some(&"DS"), "{clip}: {sequence:?}");
    }
}

/// Both methods run on a profile without a self-collision model (the G1's, and the NAO's with
/// its pairs removed): no collision level, no distance IK, no clearance in the metrics.
/// Each method's legs get the velocity fraction its docs give when none is set: Poubel et
/// al.'s the paper's 10 % on every robot, Koenemann et al.'s the profile's own (the G1's
/// 1.2 %, whose legs otherwise turned at up to 2.6 rad/s and fell in the physics judge).
#[test]
fn each_method_gets_its_own_default_leg_velocity_fraction() {
    use taskstack::imitation::koenemann::KoenemannConfig;
    for profile in [taskstack::robots::nao::profile(), g1::profile()] {
        let tuning = profile.tuning;
        let poubel = Imitator::new(profile.clone(), ImitatorConfig::default()).unwrap();
        assert_eq!(poubel.velocity_fraction(), 0.1, "{}", profile.name);
        let config = ImitatorConfig::from(KoenemannConfig::default());
        let koenemann = Imitator::new(profile.clone(), config).unwrap();
        assert_eq!(
            koenemann.velocity_fraction(),
            tuning.leg_velocity_fraction,
            "{}",
            profile.name
        );
    }
    // The G1's own fraction differs from the paper's, so the test tells the two apart.
    const { assert!(g1::TUNING.leg_velocity_fraction < 0.05) };
}

#[test]
fn profiles_without_self_collision_pairs_imitate_with_both_methods() {
    use taskstack::imitation::config::ImitationMethod;
    use taskstack::imitation::koenemann::KoenemannConfig;
    let mut bare_nao = taskstack::robots::nao::profile();
    bare_nao.self_collision = Default::default();
    let clip = "kinect2_labanotation_ges01_wavehand.csv";
    for method in [
        ImitationMethod::default(),
        ImitationMethod::Koenemann(KoenemannConfig::default()),
    ] {
        for profile in [g1::profile(), bare_nao.clone()] {
            let config = ImitatorConfig {
                method: method.clone(),
                ..ImitatorConfig::default()
            };
            let m = imitate_with(profile.clone(), clip, config);
            assert!(m.self_clearance.is_none(), "{}", profile.name);
            assert_eq!(m.joint_limit_violations, 0, "{}", profile.name);
        }
    }
}

#[test]
fn a_biped_described_by_a_profile_file_imitates_without_crate_changes() {
    // No [tuning] table: every size-dependent number comes from the scaling rules.
    let profile = BipedProfile::from_toml_file(format!("{TINY}tiny_biped.toml")).unwrap();
    assert_eq!(profile.name, "tiny_biped");
    assert_eq!(profile.models[0].nv(), 18);
    for clip in clips() {
        let m = imitate(profile.clone(), &clip);
        assert_executable(&m, &clip);
    }
}

#[test]
fn profile_errors_name_the_field() {
    let urdf = std::fs::read_to_string(format!("{TINY}tiny_biped.urdf")).unwrap();
    let toml = std::fs::read_to_string(format!("{TINY}tiny_biped.toml")).unwrap();
    let load = |text: &str| BipedProfile::from_toml_str(text, &urdf).unwrap_err();

    let err = load(&toml.replace("torso = ", "torsoo = "));
    assert!(matches!(err, ProfileError::Syntax { .. }), "{err}");
    assert!(err.to_string().contains("torsoo"), "{err}");

    let err = load(&toml.replace("LElbow =", "LeftElbow ="));
    assert!(err.to_string().contains("points.LeftElbow"), "{err}");

    let err = load(&toml.replace("LKnee = \"l_shank\"", "LKnee = \"l_shin\""));
    assert!(err.to_string().contains("l_shin"), "{err}");

    let err = load(&toml.replace("l_knee = 0.4", "l_knee = 3.0"));
    assert!(err.to_string().contains("l_knee"), "{err}");

    let err = load(&toml.replace("lateral_min = 0.08", "lateral_min = 0.2"));
    assert!(
        err.to_string().contains("step_envelope.lateral_min"),
        "{err}"
    );

    // A [tuning] table: the torso may be carried lower, not higher, than standing.
    let tuned = |lowering: f64| format!("{toml}\n[tuning]\ntorso_lowering = {lowering}\n");
    let profile = BipedProfile::from_toml_str(&tuned(0.03), &urdf).unwrap();
    assert_eq!(profile.tuning.torso_lowering, 0.03);
    let err = load(&tuned(-0.01));
    assert!(err.to_string().contains("tuning.torso_lowering"), "{err}");
    let on_one_foot =
        |lowering: f64| format!("{toml}\n[tuning]\nsingle_support_lowering = {lowering}\n");
    let profile = BipedProfile::from_toml_str(&on_one_foot(0.02), &urdf).unwrap();
    assert_eq!(profile.tuning.single_support_lowering, 0.02);
    let err = load(&on_one_foot(-0.02));
    assert!(
        err.to_string().contains("tuning.single_support_lowering"),
        "{err}"
    );
    // The lift-off (a flag, kept by the scaling: the NAO's quick lift without the key).
    let lift = |soft: &str| format!("{toml}\n[tuning]\nsoft_liftoff = {soft}\n");
    let profile = BipedProfile::from_toml_str(&lift("true"), &urdf).unwrap();
    assert!(profile.tuning.soft_liftoff);
    let untuned = BipedProfile::from_toml_str(&toml, &urdf).unwrap();
    assert!(!untuned.tuning.soft_liftoff);
    let err = load(&lift("1.5"));
    assert!(err.to_string().contains("soft_liftoff"), "{err}");
    // Where Koenemann's offset ends (a flag too: the NAO's sole centres without the key).
    let ends = |flag: &str| format!("{toml}\n[tuning]\noffset_to_stance_point = {flag}\n");
    let profile = BipedProfile::from_toml_str(&ends("true"), &urdf).unwrap();
    assert!(profile.tuning.offset_to_stance_point);
    assert!(!untuned.tuning.offset_to_stance_point);
    let err = load(&ends("\"yes\""));
    assert!(err.to_string().contains("offset_to_stance_point"), "{err}");
    // The hands under the ZMP level: the NAO's scaled without the key, none with `false`, a
    // speed of the table's own, a bad one refused by name.
    let balanced = |keys: &str| format!("{toml}\n[tuning]\n{keys}\n");
    assert!(untuned.tuning.balanced_hands.is_some());
    let off = BipedProfile::from_toml_str(&balanced("balanced_hands = false"), &urdf).unwrap();
    assert_eq!(off.tuning.balanced_hands, None);
    let own = balanced("balanced_tracking_speed = 0.4");
    let own = BipedProfile::from_toml_str(&own, &urdf).unwrap();
    let (own, scaled) = (own.tuning.balanced_hands, untuned.tuning.balanced_hands);
    assert_eq!(own.map(|h| h.tracking_speed), Some(0.4));
    assert_eq!(
        own.map(|h| h.tracking_acceleration),
        scaled.map(|h| h.tracking_acceleration)
    );
    let err = load(&balanced("balanced_tracking_acceleration = -1.0"));
    assert!(
        err.to_string().contains("balanced_tracking_acceleration"),
        "{err}"
    );

    // The servos' stiffness, a key before the first table.
    let servos = |saturation: f64| format!("servo_saturation = {saturation}\n{toml}");
    let profile = BipedProfile::from_toml_str(&servos(0.02), &urdf).unwrap();
    assert_eq!(profile.servo_saturation, Some(0.02));
    let err = load(&servos(-0.02));
    assert!(err.to_string().contains("servo_saturation"), "{err}");
    let sway = |period: f64| format!("sway_period = {period}\n{toml}");
    let profile = BipedProfile::from_toml_str(&sway(0.9), &urdf).unwrap();
    assert_eq!(profile.sway_period, Some(0.9));
    assert_eq!(
        BipedProfile::from_toml_str(&toml, &urdf)
            .unwrap()
            .sway_period,
        None
    );
    let err = load(&sway(0.0));
    assert!(err.to_string().contains("sway_period"), "{err}");

    // A chest: optional, a frame of the model other than the torso.
    assert_eq!(
        BipedProfile::from_toml_str(&toml, &urdf).unwrap().chest,
        None
    );
    let chest = |frame: &str| toml.replace("torso = ", &format!("chest = \"{frame}\"\ntorso = "));
    let profile = BipedProfile::from_toml_str(&chest("l_shoulder_a"), &urdf).unwrap();
    assert_eq!(profile.chest.as_deref(), Some("l_shoulder_a"));
    let err = load(&chest("ribcage"));
    assert!(err.to_string().contains("ribcage"), "{err}");
    let err = load(&chest("pelvis"));
    assert!(err.to_string().contains("profile field chest"), "{err}");

    let missing = BipedProfile::from_toml_file(format!("{TINY}nowhere.toml")).unwrap_err();
    assert!(matches!(missing, ProfileError::Io { .. }), "{missing}");
}

/// The G1 starts standing in its profile's posture and the tables keep its pelvis 5 cm lower:
/// the lowering comes in along a ramp whose vertical acceleration stays near the CoM's bound
/// (0.3 m/s²) instead of a 0.15 m/s step in the first frame (4.6 m/s² on this 30 Hz clip before
/// the ramp), which set the judge's G1 rocking on its soles. The pelvis height is read off every frame's joint angles
/// through the model's forward kinematics.
#[test]
fn g1_lowers_its_torso_smoothly_at_the_start() {
    use taskstack::human::Side;
    let profile = g1::profile();
    let model = profile.model(Side::Right).clone();
    let mut data = model.new_data();
    let pelvis = model.frame_id(&profile.torso).unwrap();
    let lowering = profile.tuning.torso_lowering;
    let mut source = Clip::open(format!(
        "{MOCAP}kinect2_labanotation_ges02_balancinghands.csv"
    ))
    .unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(source.capture()),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(profile, config).unwrap();
    let mut frame = HumanFrame::new(0.0);
    let mut samples = Vec::new();
    while source.read_frame(&mut frame).unwrap() && samples.len() < 60 {
        let r = imitator.step(&frame).unwrap();
        assert_eq!(r.root, Side::Right, "the clip stands on both feet");
        model.forward_kinematics(&mut data, &r.q).unwrap();
        samples.push((r.time, data.frame_placement(pelvis).translation.z));
    }
    let start = model
        .forward_kinematics(&mut data, &g1::STAND)
        .map(|_| data.frame_placement(pelvis).translation.z)
        .unwrap();
    let (t_end, z_end) = *samples.last().unwrap();
    assert!(t_end > 1.5, "{t_end}");
    assert!(
        (start - z_end - lowering).abs() < 2e-3,
        "lowered {} of {lowering}",
        start - z_end
    );
    let accel = samples
        .windows(3)
        .map(|w| {
            let (h1, h2) = (w[1].0 - w[0].0, w[2].0 - w[1].0);
            let (v1, v2) = ((w[1].1 - w[0].1) / h1, (w[2].1 - w[1].1) / h2);
            ((v2 - v1) / (0.5 * (h1 + h2))).abs()
        })
        .fold(0.0, f64::max);
    assert!(accel < 0.6, "largest vertical acceleration {accel} m/s²");
}
