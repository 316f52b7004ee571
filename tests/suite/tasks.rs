//! Ready-made tasks (`tasks`): each task's Jacobian is minus the derivative of its error (a
//! finite difference of the error the task itself reports at its target), a `TaskSet` reaches what
//! it can in priority order on the G1, and bad input gives typed errors.

use faer::Mat;
use nalgebra::{IsometryMatrix3, Rotation3, Vector3};
use taskstack::model::{Axis, Model, ModelError};
use taskstack::robots::{g1, nao};
use taskstack::solver::Solver;
use taskstack::solver::driver::{DriverSettings, PositionDriver};
use taskstack::tasks::{
    ComTask, OrientationTask, PoseTask, PositionTask, PostureTask, Task, TaskError, TaskSet,
    joint_bounds,
};

/// A bent posture inside the NAO's limits.
fn bent(model: &Model) -> Vec<f64> {
    (0..model.nv())
        .map(|k| {
            let v = &model.variables()[k];
            let mid = 0.5 * (v.lower.max(-2.0) + v.upper.min(2.0));
            mid + 0.1 * ((k as f64) * 1.3).sin()
        })
        .collect()
}

/// The task's Jacobian and error at `q`.
fn rows_of(task: &dyn Task, model: &Model, q: &[f64]) -> (Mat<f64>, Vec<f64>) {
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    let mut jacobian = Mat::<f64>::zeros(task.rows(), model.nv());
    let mut error = vec![0.0; task.rows()];
    task.write(model, &data, q, jacobian.as_mut(), &mut error)
        .unwrap();
    (jacobian, error)
}

fn error_of(task: &dyn Task, model: &Model, q: &[f64]) -> Vec<f64> {
    rows_of(task, model, q).1
}

/// `J = −∂e/∂q` by central differences, with the task's target at the current value (e = 0,
/// where the rotation-vector error is exactly linear to first order).
fn check_jacobian(task: &dyn Task, model: &Model, q: &[f64]) {
    let (jacobian, error) = rows_of(task, model, q);
    assert!(error.iter().all(|e| e.abs() < 1e-12), "{error:?}");
    let h = 1e-6;
    for k in 0..model.nv() {
        let (mut plus, mut minus) = (q.to_vec(), q.to_vec());
        plus[k] += h;
        minus[k] -= h;
        let (ep, em) = (error_of(task, model, &plus), error_of(task, model, &minus));
        for r in 0..task.rows() {
            let fd = -(ep[r] - em[r]) / (2.0 * h);
            assert!(
                (jacobian[(r, k)] - fd).abs() < 1e-7,
                "{} row {r} column {k}: {} vs {fd}",
                task.name(),
                jacobian[(r, k)]
            );
        }
    }
}

#[test]
fn jacobians_are_minus_the_error_derivative() {
    let model = nao::rfoot();
    let q = bent(&model);
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &q).unwrap();
    let at = |frame: &str| *data.frame_placement(model.frame_id(frame).unwrap());
    let hand = at("l_hand");
    let offset = Vector3::new(0.01, -0.02, 0.03);
    let point = hand.transform_point(&offset.into()).coords;
    let tasks: Vec<Box<dyn Task>> = vec![
        Box::new(
            PositionTask::new(&model, "l_hand", point)
                .unwrap()
                .with_offset(offset)
                .unwrap(),
        ),
        Box::new(
            PositionTask::new(&model, "r_hand", at("r_hand").translation.vector)
                .unwrap()
                .axes(&[Axis::Z, Axis::X]),
        ),
        Box::new(OrientationTask::new(&model, "torso", at("torso").rotation).unwrap()),
        Box::new(PoseTask::new(&model, "l_sole", at("l_sole")).unwrap()),
        Box::new(ComTask::new(&model, model.com(&data).unwrap()).unwrap()),
        Box::new(
            ComTask::ground(
                &model,
                [model.com(&data).unwrap().x, model.com(&data).unwrap().y],
            )
            .unwrap(),
        ),
        Box::new(PostureTask::new(&model, &["HeadYaw", "LKneePitch"], &[q[0], q[10]]).unwrap()),
    ];
    for task in &tasks {
        check_jacobian(task.as_ref(), &model, &q);
    }
}

#[test]
fn orientation_error_is_the_rotation_vector_to_the_target() {
    let model = nao::rfoot();
    let q = vec![0.0; model.nv()];
    // At q = 0 the torso is axis-aligned with the base: a target turned 0.3 rad about z is an
    // error of (0, 0, 0.3).
    let target = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3);
    let task = OrientationTask::new(&model, "torso", target).unwrap();
    let e = error_of(&task, &model, &q);
    assert!((e[0]).abs() < 1e-12 && e[1].abs() < 1e-12 && (e[2] - 0.3).abs() < 1e-12);
    // Tiny (where an angle from acos alone is off by ~1e-8) and beyond π/2, about a skew axis.
    let axis = nalgebra::Unit::new_normalize(Vector3::new(1.0, -2.0, 0.5));
    for angle in [1e-9, 2.5, 3.1] {
        let task = OrientationTask::new(&model, "torso", Rotation3::from_axis_angle(&axis, angle))
            .unwrap();
        let e = Vector3::from_vec(error_of(&task, &model, &q));
        assert!(
            (e - axis.into_inner() * angle).norm() < 1e-12 * angle.max(1e-3),
            "{angle}: {e}"
        );
    }
}

#[test]
fn a_task_set_keeps_a_foot_and_the_com_and_reaches_with_a_hand_on_the_g1() {
    let model = g1::right_sole();
    let q0 = vec![0.0; model.nv()];
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &q0).unwrap();
    let left_sole = *data.frame_placement(model.frame_id("left_sole").unwrap());
    // Between the feet, 3 cm in front of the ankles.
    let com = [0.03, 0.5 * left_sole.translation.y];
    let reach = Vector3::new(0.35, -0.2, 0.9);
    let mut set = TaskSet::new(&model)
        .level(
            "contact",
            vec![Box::new(
                PoseTask::new(&model, "left_sole", left_sole).unwrap(),
            )],
        )
        .level(
            "balance",
            vec![Box::new(ComTask::ground(&model, com).unwrap())],
        )
        .level(
            "reach",
            vec![Box::new(
                PositionTask::new(&model, "right_rubber_hand", reach).unwrap(),
            )],
        )
        .posture_gradient(0.05, &q0)
        .unwrap();
    let mut solver = Solver::new(&set.shape()).unwrap();
    let settings = DriverSettings {
        max_iterations: 200,
        tolerance: 1e-8,
        ..DriverSettings::default()
    };
    let mut driver = PositionDriver::new(&solver, settings).unwrap();
    let bounds = joint_bounds(&model).unwrap();
    let mut q = q0.clone();
    let report = driver.run(&mut solver, &mut set, &mut q, &bounds).unwrap();
    let errors = report.task_errors();
    assert!(errors[0] < 1e-6, "contact {errors:?}");
    assert!(errors[1] < 1e-4, "balance {errors:?}");
    assert!(errors[2] < 1e-3, "reach {errors:?}");
    for (k, v) in model.variables().iter().enumerate() {
        assert!(
            q[k] >= v.lower - 1e-12 && q[k] <= v.upper + 1e-12,
            "{}",
            v.name
        );
    }
    // A new target for the hand through task_mut, solved from there.
    set.task_mut::<PositionTask>("right_rubber_hand")
        .unwrap()
        .target
        .z = 0.85;
    let report = driver.run(&mut solver, &mut set, &mut q, &bounds).unwrap();
    assert!(report.task_errors()[2] < 1e-3);
    let hand = model.frame_id("right_rubber_hand").unwrap();
    assert!((set.data().frame_placement(hand).translation.z - 0.85).abs() < 1e-3);
}

#[test]
fn bad_input_gives_typed_errors() {
    let model = nao::rfoot();
    assert_eq!(
        PositionTask::new(&model, "l_paw", Vector3::zeros()).unwrap_err(),
        TaskError::Model(ModelError::UnknownFrame("l_paw".into()))
    );
    assert!(matches!(
        PositionTask::new(&model, "l_hand", Vector3::new(f64::NAN, 0.0, 0.0)),
        Err(TaskError::NonFiniteTarget { .. })
    ));
    assert!(matches!(
        PoseTask::new(
            &model,
            "l_sole",
            IsometryMatrix3::translation(0.0, f64::INFINITY, 0.0)
        ),
        Err(TaskError::NonFiniteTarget { .. })
    ));
    assert!(matches!(
        PostureTask::new(&model, &["HeadYaw"], &[0.0, 1.0]),
        Err(TaskError::WrongLength {
            expected: 1,
            got: 2,
            ..
        })
    ));
    assert!(matches!(
        PostureTask::new(&model, &["Tail"], &[0.0]),
        Err(TaskError::Model(ModelError::UnknownVariable(_)))
    ));
    assert!(matches!(
        TaskSet::new(&model).posture_gradient(0.1, &[0.0; 3]),
        Err(TaskError::WrongLength {
            expected: 23,
            got: 3,
            ..
        })
    ));
    let mut set = TaskSet::new(&model).level(
        "reach",
        vec![Box::new(
            PositionTask::new(&model, "l_hand", Vector3::zeros()).unwrap(),
        )],
    );
    assert!(set.task_mut::<PositionTask>("l_hand").is_ok());
    assert_eq!(
        set.task_mut::<ComTask>("l_hand").unwrap_err(),
        TaskError::UnknownTask("l_hand".into())
    );
}

#[test]
fn the_errors_alone_are_the_errors_of_the_rows() {
    use taskstack::tasks::{
        FramePoint, com_error, com_rows, orientation_error, orientation_rows, point_error,
        point_rows, upright_error, upright_rows,
    };
    let model = nao::rfoot();
    let q = bent(&model);
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &q).unwrap();
    let hand = model.frame_id("l_hand").unwrap();
    let point = FramePoint {
        frame: hand,
        offset: Vector3::new(0.01, -0.02, 0.03),
    };
    let (target, axes) = (Vector3::new(0.1, 0.2, 0.3), [Axis::Z, Axis::X]);
    let turn = Rotation3::from_axis_angle(&Vector3::y_axis(), 0.4);
    let up = Vector3::new(0.0, 0.6, 0.8);
    let mut jacobian = Mat::<f64>::zeros(3, model.nv());
    let (mut rows, mut alone) = ([0.0; 3], [0.0; 3]);
    point_rows(
        &model,
        &data,
        &point,
        &axes,
        &target,
        jacobian.as_mut().subrows_mut(0, 2),
        &mut rows,
    )
    .unwrap();
    point_error(&model, &data, &point, &axes, &target, &mut alone).unwrap();
    assert_eq!(rows, alone);
    orientation_rows(
        &model,
        &data,
        hand,
        &turn,
        jacobian.as_mut().subrows_mut(0, 3),
        &mut rows,
    )
    .unwrap();
    orientation_error(&model, &data, hand, &turn, &mut alone).unwrap();
    assert_eq!(rows, alone);
    upright_rows(
        &model,
        &data,
        hand,
        &up,
        jacobian.as_mut().subrows_mut(0, 2),
        &mut rows,
    )
    .unwrap();
    upright_error(&model, &data, hand, &up, &mut alone).unwrap();
    assert_eq!(rows, alone);
    com_rows(
        &model,
        &data,
        &[0.1, 0.2],
        jacobian.as_mut().subrows_mut(0, 2),
        &mut rows,
    )
    .unwrap();
    com_error(&model, &data, &[0.1, 0.2], &mut alone).unwrap();
    assert_eq!(rows, alone);

    // A frame of another, larger model and data without kinematics are typed errors.
    let g1 = g1::right_sole();
    let last = &g1.frames()[g1.frames().len() - 1];
    let foreign = g1.frame_id(&last.name).unwrap();
    assert!(foreign.index() >= model.frames().len());
    assert!(matches!(
        orientation_error(&model, &data, foreign, &turn, &mut alone),
        Err(ModelError::FrameOutOfRange(_))
    ));
    assert_eq!(
        upright_error(&model, &model.new_data(), hand, &up, &mut alone),
        Err(ModelError::KinematicsNotComputed)
    );
    // Outputs too short, and a CoM with four axes, are typed errors, not panics.
    assert!(matches!(
        orientation_error(&model, &data, hand, &turn, &mut alone[..2]),
        Err(ModelError::OutputShape {
            expected_rows: 3,
            rows: 2,
            ..
        })
    ));
    assert!(matches!(
        point_error(&model, &data, &point, &axes, &target, &mut alone[..1]),
        Err(ModelError::OutputShape {
            expected_rows: 2,
            rows: 1,
            ..
        })
    ));
    assert_eq!(
        com_error(&model, &data, &[0.0; 4], &mut [0.0; 4]),
        Err(ModelError::BadRowCount(4))
    );
}
