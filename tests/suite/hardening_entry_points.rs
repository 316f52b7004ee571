//! Issue 6, item 2: the rows of the "Bad input" table (`taskstack::solver` module docs) that no
//! other test shows. Each test feeds non-finite or out-of-range input to one public entry point
//! and checks the typed error (by variant and by the name it gives) or the documented graceful
//! behaviour, and that a refused call changed nothing.

use taskstack::human::{HumanFrame, HumanJoint};
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::poubel::PoubelConfig;
use taskstack::imitation::reference::scaler::ScaleError;
use taskstack::imitation::shaping::MotionLimits;
use taskstack::imitation::{ImitationError, ImitationMethod, Imitator, ImitatorConfig, RobotFrame};
use taskstack::io::clip::Clip;
use taskstack::model::ModelError;
use taskstack::robots::nao;
use taskstack::solver::driver::{DriverSettings, PositionDriver, StopReason, TaskModel};
use taskstack::solver::{
    GradientFunction, JointBounds, JointLimitAvoidance, JointTracking, Settings, Solver,
    SolverError, StackShape, TaskStack,
};

const BAD: [f64; 4] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1.0];

fn is_invalid(result: Result<impl Sized, SolverError>, field: &str) -> bool {
    matches!(result, Err(SolverError::InvalidParameter { name, .. }) if name == field)
}

fn shape() -> StackShape {
    StackShape::new(2).with_level("x", &[("x", 1)])
}

#[test]
fn settings_out_of_range_are_refused_by_name_at_construction_and_on_update() {
    type Set = fn(&mut Settings, f64);
    let fields: [(&str, Set); 4] = [
        ("rank_tolerance", |s, v| s.rank_tolerance = v),
        ("damping_threshold", |s, v| s.damping_threshold = v),
        ("max_damping", |s, v| s.max_damping = v),
        ("feasibility_tolerance", |s, v| s.feasibility_tolerance = v),
    ];
    let mut solver = Solver::new(&shape()).unwrap();
    for (name, set) in fields {
        for v in BAD {
            let mut s = Settings::default();
            set(&mut s, v);
            assert!(
                is_invalid(Solver::with_settings(&shape(), s), name),
                "{name} = {v}"
            );
            assert!(is_invalid(solver.set_settings(s), name), "{name} = {v}");
            assert_eq!(*solver.settings(), Settings::default(), "{name} = {v}");
        }
    }
    // rank_tolerance must be > 0, the others may be 0 (no damping, exact feasibility).
    let zero = Settings {
        rank_tolerance: 0.0,
        ..Settings::default()
    };
    assert!(is_invalid(solver.set_settings(zero), "rank_tolerance"));
    let zeros = Settings {
        damping_threshold: 0.0,
        max_damping: 0.0,
        feasibility_tolerance: 0.0,
        ..Settings::default()
    };
    assert!(solver.set_settings(zeros).is_ok());
}

#[test]
fn add_gradient_refuses_non_finite_gain_wrong_length_and_non_finite_q() {
    let mut solver = Solver::new(&shape()).unwrap();
    let tracking = JointTracking::new(&[0.0, 0.0]).unwrap();
    let stack = solver.stack_mut();
    for kappa in [f64::NAN, f64::INFINITY] {
        assert!(matches!(
            stack.add_gradient(kappa, &tracking, &[1.0, 1.0]),
            Err(SolverError::NonFinite { ref what, .. }) if what.contains('κ')
        ));
    }
    assert!(matches!(
        stack.add_gradient(-0.1, &tracking, &[1.0]),
        Err(SolverError::DimensionMismatch {
            expected: 2,
            got: 1,
            ..
        })
    ));
    assert!(matches!(
        stack.add_gradient(-0.1, &tracking, &[1.0, f64::NAN]),
        Err(SolverError::NonFinite { ref what, .. }) if what == "q at index 1"
    ));
    // Nothing was added by the refused calls.
    assert_eq!(stack.gradient(), &[0.0, 0.0]);
    // A valid call: κ ∇f = −0.1 · 2 (q − 0) = [−0.2, −0.4] for q = [1, 2].
    stack.add_gradient(-0.1, &tracking, &[1.0, 2.0]).unwrap();
    assert_eq!(stack.gradient(), &[-0.2, -0.4]);
}

#[test]
fn joint_bounds_refuse_nan_inverted_and_empty_ranges_and_accept_infinite_ones() {
    for (lo, hi) in [
        (f64::NAN, 1.0),
        (0.0, f64::NAN),
        (1.0, 0.0),
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    ] {
        assert!(
            matches!(
                JointBounds::new(&[0.0, lo], &[0.0, hi]),
                Err(SolverError::InvertedLimits { joint: 1, .. })
            ),
            "[{lo}, {hi}]"
        );
    }
    for v in [f64::NAN, -1.0] {
        assert!(is_invalid(
            JointBounds::with_velocity(&[0.0], &[1.0], &[v]),
            "velocity limit"
        ));
    }
    assert!(matches!(
        JointBounds::new(&[0.0, 0.0], &[1.0]),
        Err(SolverError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        JointBounds::with_velocity(&[0.0], &[1.0], &[]),
        Err(SolverError::DimensionMismatch { .. })
    ));
    // Infinite limits mean "unbounded"; a zero-width range and infinite velocity are fine.
    let b = JointBounds::with_velocity(
        &[f64::NEG_INFINITY, 0.5],
        &[f64::INFINITY, 0.5],
        &[f64::INFINITY, 0.0],
    )
    .unwrap();
    assert_eq!(b.dof(), 2);
}

#[test]
fn scale_velocity_refuses_non_finite_and_negative_fractions_and_keeps_the_limits() {
    let mut b = JointBounds::with_velocity(&[-1.0], &[1.0], &[2.0]).unwrap();
    for f in BAD {
        assert!(is_invalid(b.scale_velocity(f), "velocity fraction"), "{f}");
        assert_eq!(b.velocity(), &[2.0]);
    }
    b.scale_velocity(0.1).unwrap();
    assert_eq!(b.velocity(), &[2.0 * 0.1]);
}

#[test]
fn clamp_position_clamps_infinities_and_passes_nan_through() {
    let b = JointBounds::new(&[-1.0, -1.0, -1.0], &[1.0, 1.0, 1.0]).unwrap();
    let mut q = [f64::INFINITY, f64::NEG_INFINITY, f64::NAN];
    b.clamp_position(&mut q);
    assert_eq!(&q[..2], &[1.0, -1.0]);
    // Documented: clamping is not validation (`f64::clamp` keeps NaN); solve/run refuse NaN q.
    assert!(q[2].is_nan());
}

#[test]
fn joint_limit_avoidance_ignores_unbounded_and_zero_width_joints() {
    let b = JointBounds::new(&[f64::NEG_INFINITY, 0.5, -1.0], &[f64::INFINITY, 0.5, 3.0]).unwrap();
    let limits = JointLimitAvoidance::new(&b);
    let mut g = [0.0; 3];
    limits
        .add_scaled_gradient(&[7.0, 9.0, 2.0], 1.0, &mut g)
        .unwrap();
    // Joint 2: centre 1, range 4: ∂/∂q ((q − 1)/4)² = 2 (2 − 1)/16 = 0.125.
    assert_eq!(g, [0.0, 0.0, 0.125]);
    assert!(matches!(
        limits.add_scaled_gradient(&[0.0, f64::INFINITY, 0.0], 1.0, &mut g),
        Err(SolverError::NonFinite { .. })
    ));
}

#[test]
fn joint_tracking_refuses_bad_weights_and_references_and_keeps_the_old_reference() {
    assert!(matches!(
        JointTracking::weighted(&[0.0, 0.0], &[1.0, -0.5]),
        Err(SolverError::InvalidParameter {
            name: "joint tracking weight",
            ..
        })
    ));
    for w in [f64::NAN, f64::INFINITY] {
        assert!(matches!(
            JointTracking::weighted(&[0.0, 0.0], &[1.0, w]),
            Err(SolverError::NonFinite { .. })
        ));
    }
    assert!(matches!(
        JointTracking::weighted(&[0.0, 0.0], &[1.0]),
        Err(SolverError::DimensionMismatch { .. })
    ));
    let mut t = JointTracking::new(&[0.25, 0.5]).unwrap();
    for r in [f64::NAN, f64::NEG_INFINITY] {
        assert!(matches!(
            t.set_reference(&[0.0, r]),
            Err(SolverError::NonFinite { .. })
        ));
        assert_eq!(t.reference(), &[0.25, 0.5]);
    }
}

#[test]
fn driver_settings_out_of_range_are_refused_by_name() {
    let solver = Solver::new(&shape()).unwrap();
    let mut driver = PositionDriver::new(&solver, DriverSettings::default()).unwrap();
    type Set = fn(&mut DriverSettings, f64);
    // (field, setter, may it be +∞, may it be 0)
    let fields: [(&str, Set, bool, bool); 6] = [
        ("gain", |s, v| s.gain = v, false, false),
        ("dt", |s, v| s.dt = v, false, false),
        ("tolerance", |s, v| s.tolerance = v, false, true),
        ("stall_tolerance", |s, v| s.stall_tolerance = v, false, true),
        ("max_task_error", |s, v| s.max_task_error = v, true, false),
        ("max_joint_step", |s, v| s.max_joint_step = v, true, false),
    ];
    for (name, set, infinite_ok, zero_ok) in fields {
        let mut values = vec![f64::NAN, f64::NEG_INFINITY, -1.0];
        if !infinite_ok {
            values.push(f64::INFINITY);
        }
        if !zero_ok {
            values.push(0.0);
        }
        for v in values {
            let mut s = DriverSettings::default();
            set(&mut s, v);
            assert!(
                is_invalid(PositionDriver::new(&solver, s), name),
                "{name} = {v}"
            );
            assert!(is_invalid(driver.set_settings(s), name), "{name} = {v}");
            assert_eq!(*driver.settings(), DriverSettings::default());
        }
    }
}

/// One joint, one task `x = q` with target `target`.
struct Line {
    target: f64,
}

impl TaskModel for Line {
    type Error = SolverError;
    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        stack.level_mut(0).set_row(0, &[1.0], self.target - q[0])?;
        stack.clear_gradient();
        Ok(())
    }
}

#[test]
fn driver_run_refuses_bad_q_bounds_and_non_finite_task_errors() {
    let shape = StackShape::new(1).with_level("x", &[("x", 1)]);
    let mut solver = Solver::new(&shape).unwrap();
    let mut driver = PositionDriver::new(&solver, DriverSettings::default()).unwrap();
    let bounds = JointBounds::new(&[-1.0], &[1.0]).unwrap();
    let mut line = Line { target: 0.5 };
    assert!(matches!(
        driver.run(&mut solver, &mut line, &mut [0.0, 0.0], &bounds),
        Err(SolverError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        driver.run(
            &mut solver,
            &mut line,
            &mut [0.0],
            &JointBounds::unbounded(2)
        ),
        Err(SolverError::DimensionMismatch { .. })
    ));
    let mut q = [f64::NAN];
    assert!(matches!(
        driver.run(&mut solver, &mut line, &mut q, &bounds),
        Err(SolverError::NonFinite { ref what, .. }) if what == "q at index 0"
    ));
    // A target at infinity gives an infinite task error: refused, q untouched.
    let mut q = [0.25];
    let mut far = Line {
        target: f64::INFINITY,
    };
    assert!(matches!(
        driver.run(&mut solver, &mut far, &mut q, &bounds),
        Err(SolverError::NonFinite { .. })
    ));
    assert_eq!(q, [0.25]);
    // A far target: steps clipped to max_task_error (0.05) until the limit 1 holds the joint,
    // then the error stops changing: Stalled, at the limit, finite.
    let mut far = Line { target: 1e6 };
    let report = driver.run(&mut solver, &mut far, &mut q, &bounds).unwrap();
    assert_eq!((q, report.stop), ([1.0], StopReason::Stalled));
    assert_eq!(report.task_errors()[0], 1e6 - 1.0);
    // A target so far that a step does not change the error in floating point: Stalled after
    // one step (0.05), still finite and within the limits.
    let mut q = [0.25];
    let mut huge = Line { target: 1e300 };
    let report = driver.run(&mut solver, &mut huge, &mut q, &bounds).unwrap();
    assert_eq!(report.stop, StopReason::Stalled);
    assert!((q[0] - 0.3).abs() < 1e-12 && report.task_errors()[0] == 1e300);
}

#[test]
fn forward_kinematics_refuses_infinite_q_and_leaves_the_data_as_it_was() {
    let model = nao::rfoot();
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &[0.0; 23]).unwrap();
    let com = model.com(&data).unwrap();
    for v in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
        let mut q = [0.0; 23];
        q[22] = v;
        assert!(matches!(
            model.forward_kinematics(&mut data, &q),
            Err(ModelError::NonFiniteQ { index: 22, ref variable, .. }) if variable == "RWristYaw"
        ));
        assert_eq!(model.com(&data).unwrap(), com);
    }
}

fn frames(n: usize) -> Vec<HumanFrame> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/mocap/cmu_07_04_slow_walk.bvh"
    );
    Clip::open(path)
        .unwrap()
        .take(n)
        .collect::<Result<_, _>>()
        .unwrap()
}

fn imitator() -> Imitator {
    Imitator::new(nao::profile(), ImitatorConfig::default()).unwrap()
}

fn run(imitator: &mut Imitator, frames: &[HumanFrame]) -> Vec<RobotFrame> {
    frames
        .iter()
        .map(|f| imitator.step(f).unwrap().clone())
        .collect()
}

/// Koenemann et al.'s settings out of range are refused by name, before any frame.
#[test]
fn koenemann_config_out_of_range_is_refused_by_name() {
    type Set = fn(&mut KoenemannConfig, f64);
    let fields: [(&str, Set, &[f64]); 6] = [
        (
            "koenemann.damping",
            |k, v| k.damping = v,
            &[f64::NAN, 0.0, -1.0],
        ),
        (
            "koenemann.tolerance",
            |k, v| k.tolerance = v,
            &[f64::INFINITY, 0.0],
        ),
        (
            "koenemann.offset_tolerance",
            |k, v| k.offset_tolerance = v,
            &[f64::NAN, -0.1, 0.5],
        ),
        (
            "koenemann.arm_posture_gain",
            |k, v| k.arm_posture_gain = v,
            &[f64::NAN, -0.01, 1.5],
        ),
        (
            "koenemann.settle_time",
            |k, v| k.settle_time = Some(v),
            &[f64::NAN, f64::INFINITY, -0.1],
        ),
        (
            "koenemann.leg_ramp_time",
            |k, v| k.leg_ramp_time = Some(v),
            &[f64::NAN, f64::INFINITY, -0.1],
        ),
    ];
    for (name, set, values) in fields {
        for &v in values {
            let mut k = KoenemannConfig::default();
            set(&mut k, v);
            let c = ImitatorConfig {
                method: ImitationMethod::Koenemann(k),
                ..ImitatorConfig::default()
            };
            let err = Imitator::new(nao::profile(), c).err();
            assert!(
                matches!(err, Some(ImitationError::InvalidParameter { name: n, .. }) if n == name),
                "{name} = {v}: {err:?}"
            );
        }
    }
    // The ends of the posture gain's range are settings, not errors.
    for gain in [0.0, 1.0] {
        let k = KoenemannConfig {
            arm_posture_gain: gain,
            ..KoenemannConfig::default()
        };
        let c = ImitatorConfig {
            method: ImitationMethod::Koenemann(k),
            ..ImitatorConfig::default()
        };
        assert!(Imitator::new(nao::profile(), c).is_ok(), "gain {gain}");
    }
}

#[test]
fn imitator_config_out_of_range_is_refused_by_name() {
    type Set = fn(&mut ImitatorConfig, f64);
    let fields: [(&str, Set); 12] = [
        ("velocity_fraction", |c, v| c.velocity_fraction = Some(v)),
        ("nominal_dt", |c, v| c.nominal_dt = v),
        ("poubel.max_task_speed", |c, v| {
            poubel(c).max_task_speed = Some(v)
        }),
        ("poubel.damping", |c, v| poubel(c).damping = Some(v)),
        ("koenemann.swing_speed", |c, v| {
            c.method = ImitationMethod::Koenemann(KoenemannConfig {
                swing_speed: Some(v),
                ..KoenemannConfig::default()
            })
        }),
        ("max_tracking_speed", |c, v| c.max_tracking_speed = Some(v)),
        ("upper_body_velocity_fraction", |c, v| {
            c.upper_body_velocity_fraction = Some(v)
        }),
        ("com_speed", |c, v| motion(c).com_speed = v),
        ("com_acceleration", |c, v| motion(c).com_acceleration = v),
        ("foot_speed", |c, v| motion(c).foot_speed = v),
        ("touchdown_speed", |c, v| motion(c).touchdown_speed = v),
        ("landing_time", |c, v| motion(c).landing_time = v),
    ];
    // Each setter with each bad value must be refused, naming the field.
    let refused = |name: &str, set: Set, values: &[f64]| {
        for &v in values {
            let mut c = ImitatorConfig::default();
            set(&mut c, v);
            let err = Imitator::new(nao::profile(), c).err();
            assert!(
                matches!(err, Some(ImitationError::InvalidParameter { name: n, .. }) if n == name),
                "{name} = {v}: {err:?}"
            );
        }
    };
    for (name, set) in fields {
        refused(name, set, &[f64::NAN, f64::INFINITY, 0.0, -1.0]);
    }
    // Footstep thresholds may be 0 (step at once) but not negative or NaN.
    let steps: [(&str, Set); 6] = [
        ("footsteps.distance", |c, v| {
            poubel(c).footsteps.distance = v
        }),
        ("footsteps.heading", |c, v| poubel(c).footsteps.heading = v),
        ("footsteps.pivot", |c, v| poubel(c).footsteps.pivot = v),
        ("footsteps.slide", |c, v| poubel(c).footsteps.slide = v),
        ("footsteps.stance_time", |c, v| {
            poubel(c).footsteps.stance_time = v
        }),
        ("footsteps.swing_timeout", |c, v| {
            poubel(c).footsteps.swing_timeout = v
        }),
    ];
    for (name, set) in steps {
        refused(name, set, &[f64::NAN, -1.0]);
    }
    let mut c = ImitatorConfig::default();
    poubel(&mut c).iterations_per_frame = 0;
    assert!(matches!(
        Imitator::new(nao::profile(), c),
        Err(ImitationError::InvalidParameter {
            name: "poubel.iterations_per_frame",
            ..
        })
    ));
    let c = ImitatorConfig {
        initial_q: Some(vec![0.0; 22]),
        ..ImitatorConfig::default()
    };
    assert!(matches!(
        Imitator::new(nao::profile(), c),
        Err(ImitationError::Solver(SolverError::DimensionMismatch {
            expected: 23,
            got: 22,
            ..
        }))
    ));
}

#[test]
fn imitator_refuses_bad_frame_times_without_changing_its_state() {
    let clip = frames(40);
    let mut reference = imitator();
    let expected = run(&mut reference, &clip);

    let mut imitator = imitator();
    let mut bad = clip[0];
    bad.time = f64::NAN;
    // First frame with a NaN time: the scaler's finiteness check.
    assert!(matches!(
        imitator.step(&bad),
        Err(ImitationError::Scale(ScaleError::NonFiniteTime(_)))
    ));
    let mut got = run(&mut imitator, &clip[..20]);
    let previous = clip[19].time;
    for time in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, previous - 1e-3] {
        let mut bad = clip[20];
        bad.time = time;
        let err = imitator.step(&bad).err();
        // +∞ is caught as non-finite; NaN and −∞ compare as "not after the previous frame"
        // (`Imitator::step` orders its time checks that way), an earlier time likewise.
        let typed = matches!(
            err,
            Some(ImitationError::Scale(ScaleError::NonFiniteTime(_)))
                | Some(ImitationError::TimeGoesBack { .. })
        );
        assert!(typed, "time {time}: {err:?}");
        if time == previous - 1e-3 {
            assert!(matches!(err, Some(ImitationError::TimeGoesBack { .. })));
        }
    }
    got.extend(run(&mut imitator, &clip[20..]));
    // The refused frames changed nothing: bit-identical to a run that never saw them.
    for (g, e) in got.iter().zip(&expected) {
        assert_eq!(g.q, e.q, "t = {}", e.time);
    }
}

#[test]
fn imitator_treats_non_finite_joint_positions_as_missing() {
    let clip = frames(30);
    let hands = [HumanJoint::LHand, HumanJoint::RHand, HumanJoint::LElbow];
    let spoilt: Vec<HumanFrame> = clip
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let mut f = *f;
            if i >= 10 {
                for (k, joint) in hands.iter().enumerate() {
                    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][k];
                    f.set(*joint, Some(nalgebra::Vector3::new(0.1, bad, 0.3)));
                    assert_eq!(f.get(*joint), None);
                }
            }
            f
        })
        .collect();
    let missing: Vec<HumanFrame> = clip
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let mut f = *f;
            if i >= 10 {
                for joint in hands {
                    f.set(joint, None);
                }
            }
            f
        })
        .collect();
    let a = run(&mut imitator(), &spoilt);
    let b = run(&mut imitator(), &missing);
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.q, y.q);
        assert!(x.q.iter().all(|q| q.is_finite()));
    }
}

/// The config's motion limits, the defaults put in first when it has none.
fn poubel(c: &mut ImitatorConfig) -> &mut PoubelConfig {
    c.poubel_mut()
        .expect("the default method is Poubel et al.'s")
}

fn motion(c: &mut ImitatorConfig) -> &mut MotionLimits {
    c.motion.get_or_insert_with(MotionLimits::default)
}
