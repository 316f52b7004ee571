//! Inequality tasks and the contact-normal task: Jacobians against central finite differences of
//! the quantity they bound, distances against hand calculations, and the CoM-in-polygon task
//! holding in a driven solve where the equality stack without it lets the CoM out; the ZMP task
//! against the links' momentum by differences.

use crate::common;

use faer::Mat;
use nalgebra::Vector3;
use taskstack::model::{Model, ModelData, ModelError};
use taskstack::robots::nao;
use taskstack::solver::driver::{DriverSettings, PositionDriver};
use taskstack::solver::{Solver, StackShape};
use taskstack::tasks::{
    Capsule, CapsuleDistanceTask, ComPolygonTask, ContactNormalTask, GRAVITY, InequalityTask,
    PlaneDistanceTask, PositionTask, Task, TaskError, TaskSet, ZmpTask, closest_segment_parameters,
    joint_bounds,
};

/// A bent, asymmetric NAO configuration (no joint at a symmetric zero).
fn bent(model: &Model) -> Vec<f64> {
    (0..model.nv())
        .map(|i| 0.3 * ((i as f64) * 1.7).sin())
        .collect()
}

fn data_at(model: &Model, q: &[f64]) -> ModelData {
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    data
}

/// Central differences of `value(q)` against the first Jacobian row `jacobian`.
fn check_gradient(model: &Model, q: &[f64], jacobian: &[f64], value: impl Fn(&ModelData) -> f64) {
    let h = 1e-6;
    for k in 0..model.nv() {
        let (mut plus, mut minus) = (q.to_vec(), q.to_vec());
        plus[k] += h;
        minus[k] -= h;
        let fd = (value(&data_at(model, &plus)) - value(&data_at(model, &minus))) / (2.0 * h);
        assert!(
            (fd - jacobian[k]).abs() < 1e-6,
            "variable {k}: finite difference {fd}, Jacobian {}",
            jacobian[k]
        );
    }
}

fn inequality_row(task: &dyn InequalityTask, model: &Model, data: &ModelData) -> (Vec<f64>, f64) {
    let mut jacobian = faer::Mat::zeros(task.rows(), model.nv());
    let (mut lower, mut upper) = (vec![0.0; task.rows()], vec![0.0; task.rows()]);
    task.write(model, data, jacobian.as_mut(), &mut lower, &mut upper)
        .unwrap();
    let row = (0..model.nv()).map(|k| jacobian[(0, k)]).collect();
    (row, lower[0])
}

fn forearm(model: &Model, side: &str) -> Capsule {
    Capsule::new(
        model,
        &format!("{side}_elbow"),
        Vector3::zeros(),
        Vector3::new(0.1, 0.0, 0.0),
        0.025,
    )
    .unwrap()
}

#[test]
fn capsule_distance_jacobian_matches_finite_differences() {
    let model = nao::rfoot();
    let q = bent(&model);
    let torso = Capsule::new(
        &model,
        "torso",
        Vector3::new(0.0, 0.0, -0.05),
        Vector3::new(0.0, 0.0, 0.1),
        0.06,
    )
    .unwrap();
    for second in [torso, forearm(&model, "r")] {
        let task =
            CapsuleDistanceTask::new(&model, "arm", forearm(&model, "l"), second, 0.01).unwrap();
        let (row, lower) = inequality_row(&task, &model, &data_at(&model, &q));
        let d = task.distance(&model, &data_at(&model, &q)).unwrap();
        assert!((lower - (0.01 - d)).abs() < 1e-15, "room = margin − d");
        check_gradient(&model, &q, &row, |data| {
            task.distance(&model, data).unwrap()
        });
    }
}

/// The rate bounds against central differences of the distance: no variable changes it faster,
/// in several postures; the legs, which carry both arms and the torso, not at all.
#[test]
fn capsule_distance_rates_bound_its_change() {
    let model = nao::rfoot();
    let torso = Capsule::new(&model, "torso", Vector3::zeros(), Vector3::z() * 0.1, 0.06).unwrap();
    let legs: Vec<usize> = (model.variables().iter().enumerate())
        .filter(|(_, v)| {
            v.name.contains("Hip") || v.name.contains("Knee") || v.name.contains("Ankle")
        })
        .map(|(k, _)| k)
        .collect();
    assert_eq!(legs.len(), 11);
    for second in [torso, forearm(&model, "r")] {
        let task =
            CapsuleDistanceTask::new(&model, "arm", forearm(&model, "l"), second, 0.01).unwrap();
        let rates = task.rate_bounds();
        assert_eq!(rates.len(), model.nv());
        assert!(legs.iter().all(|&k| rates[k] == 0.0), "{rates:?}");
        let h = 1e-6;
        for scale in [-1.0, 0.5, 1.0, 2.0] {
            let q: Vec<f64> = bent(&model).iter().map(|v| v * scale).collect();
            for k in 0..model.nv() {
                let (mut plus, mut minus) = (q.clone(), q.clone());
                plus[k] += h;
                minus[k] -= h;
                let distance = |q: &[f64]| task.distance(&model, &data_at(&model, q)).unwrap();
                let rate = (distance(&plus) - distance(&minus)) / (2.0 * h);
                assert!(
                    rate.abs() <= rates[k] + 1e-6,
                    "variable {k}: {rate} > {}",
                    rates[k]
                );
            }
        }
    }
}

/// Standing, the forearms are farther apart than a 10 ms step at the NAO's rated speeds can
/// close: the row is written open and without its Jacobian, and a solve with it is the solve
/// with the full row, bit for bit. A step that could close the gap gets the full row.
#[test]
fn a_pair_no_step_can_bring_to_its_margin_skips_its_jacobian() {
    let model = nao::rfoot();
    let q = nao::profile().stand.clone();
    let data = data_at(&model, &q);
    let margin = 0.01;
    let task = CapsuleDistanceTask::new(
        &model,
        "arms",
        forearm(&model, "l"),
        forearm(&model, "r"),
        margin,
    )
    .unwrap();
    let bounds = joint_bounds(&model).unwrap();
    let dt = 0.01;
    let step: Vec<f64> = bounds.velocity().iter().map(|v| v * dt).collect();
    let reach: f64 = task
        .rate_bounds()
        .iter()
        .zip(&step)
        .map(|(k, s)| k * s)
        .sum();
    let room = task.distance(&model, &data).unwrap() - margin;
    assert!(room > reach && reach > 0.01, "room {room}, reach {reach}");
    let nv = model.nv();
    let write = |step: &[f64]| {
        let (mut jacobian, mut lower, mut upper) = (faer::Mat::zeros(1, nv), [0.0], [0.0]);
        let full = (task.write_for_step(
            &model,
            &data,
            step,
            jacobian.as_mut(),
            &mut lower,
            &mut upper,
        ))
        .unwrap();
        (
            full,
            (0..nv).map(|k| jacobian[(0, k)]).collect::<Vec<f64>>(),
            lower[0],
            upper[0],
        )
    };
    let (full, open_row, lower, upper) = write(&step);
    assert!(!full && lower == f64::NEG_INFINITY && upper == f64::INFINITY);
    assert!(open_row.iter().all(|&c| c == 0.0));
    let (row, room_bound) = inequality_row(&task, &model, &data);
    assert_eq!(
        write(&vec![1.0; nv]),
        (true, row.clone(), room_bound, f64::INFINITY)
    );
    // A step is a magnitude; a NaN one cannot vouch for anything.
    let backward: Vec<f64> = step.iter().map(|s| -s).collect();
    assert!(!write(&backward).0);
    let mut unknown = step.clone();
    unknown[0] = f64::NAN;
    assert_eq!(
        write(&unknown),
        (true, row.clone(), room_bound, f64::INFINITY)
    );
    // The left hand pulled 5 cm toward the right one, below the distance level.
    let mut hand = faer::Mat::<f64>::zeros(3, nv);
    let l_hand = model.frame_id("l_wrist").unwrap();
    model
        .point_jacobian(&data, l_hand, &Vector3::zeros(), hand.as_mut())
        .unwrap();
    let shape = StackShape::new(nv)
        .with_inequality_level("apart", &[("arms", 1)])
        .with_level("hand", &[("l_hand", 3)]);
    let solve = |row: &[f64], lower: f64| {
        let mut solver = Solver::new(&shape).unwrap();
        let stack = solver.stack_mut();
        stack
            .level_mut(0)
            .set_inequality_row(0, row, lower / dt, f64::INFINITY)
            .unwrap();
        let mut level = stack.level_mut(1);
        for r in 0..3 {
            let jacobian: Vec<f64> = (0..nv).map(|k| hand[(r, k)]).collect();
            level
                .set_row(r, &jacobian, if r == 1 { -5.0 } else { 0.0 })
                .unwrap();
        }
        solver.solve(&q, &bounds, dt).unwrap().velocity.to_vec()
    };
    let (with_row, open) = (solve(&row, room_bound), solve(&open_row, lower));
    assert!(with_row.iter().any(|&v| v != 0.0));
    assert_eq!(with_row, open);
}

/// `write_for_step` refuses a step or a Jacobian view of the wrong size.
#[test]
fn write_for_step_checks_its_sizes() {
    let model = nao::rfoot();
    let data = data_at(&model, &bent(&model));
    let task = CapsuleDistanceTask::new(
        &model,
        "arms",
        forearm(&model, "l"),
        forearm(&model, "r"),
        0.01,
    )
    .unwrap();
    let nv = model.nv();
    let (mut lower, mut upper) = ([0.0], [0.0]);
    let mut jacobian = faer::Mat::zeros(1, nv);
    let short = vec![0.0; nv - 1];
    let error = task.write_for_step(
        &model,
        &data,
        &short,
        jacobian.as_mut(),
        &mut lower,
        &mut upper,
    );
    assert!(matches!(error, Err(ModelError::OutputShape { rows, .. }) if rows == nv - 1));
    let mut wide = faer::Mat::zeros(1, nv + 1);
    let step = vec![0.0; nv];
    let error = task.write_for_step(&model, &data, &step, wide.as_mut(), &mut lower, &mut upper);
    assert!(matches!(error, Err(ModelError::OutputShape { cols, .. }) if cols == nv + 1));
    let error = task.write_for_step(&model, &data, &step, jacobian.as_mut(), &mut [], &mut upper);
    assert!(matches!(
        error,
        Err(ModelError::OutputShape { rows: 0, .. })
    ));
}

#[test]
fn plane_distance_and_contact_normal_jacobians_match_finite_differences() {
    let model = nao::rfoot();
    let q = bent(&model);
    // A table top 0.3 m above the right sole, tilted a little.
    let normal = Vector3::new(0.1, 0.0, 1.0);
    let table = PlaneDistanceTask::new(
        &model,
        "l_hand_table",
        forearm(&model, "l"),
        Vector3::new(0.0, 0.0, 0.3),
        normal,
        0.0,
    )
    .unwrap();
    let (row, _) = inequality_row(&table, &model, &data_at(&model, &q));
    check_gradient(&model, &q, &row, |data| {
        table.distance(&model, data).unwrap()
    });

    let palm =
        ContactNormalTask::new(&model, "l_hand", Vector3::new(0.0, 0.0, -1.0), -normal).unwrap();
    let data = data_at(&model, &q);
    let mut jacobian = faer::Mat::zeros(1, model.nv());
    let mut error = [0.0];
    palm.write(&model, &data, &q, jacobian.as_mut(), &mut error)
        .unwrap();
    let phi = palm.alignment(&model, &data).unwrap();
    assert!((error[0] - (1.0 - phi)).abs() < 1e-15);
    let row: Vec<f64> = (0..model.nv()).map(|k| jacobian[(0, k)]).collect();
    check_gradient(&model, &q, &row, |data| {
        palm.alignment(&model, data).unwrap()
    });
}

#[test]
fn com_polygon_rows_match_finite_differences_and_spare_rows_are_open() {
    let model = nao::rfoot();
    let q = bent(&model);
    let square = [[-0.04, -0.03], [0.06, -0.03], [0.06, 0.03], [-0.04, 0.03]];
    let task = ComPolygonTask::new(&model, 6, &square, 0.005).unwrap();
    let data = data_at(&model, &q);
    let mut jacobian = faer::Mat::zeros(6, model.nv());
    let (mut lower, mut upper) = ([0.0; 6], [0.0; 6]);
    task.write(&model, &data, jacobian.as_mut(), &mut lower, &mut upper)
        .unwrap();
    let c = model.com(&data).unwrap();
    // Edge 1 runs from (0.06, −0.03) to (0.06, 0.03): outward normal +x, offset 0.06. By hand:
    // room = 0.06 − 0.005 − c_x.
    assert!((upper[1] - (0.055 - c[0])).abs() < 1e-15);
    let row: Vec<f64> = (0..model.nv()).map(|k| jacobian[(1, k)]).collect();
    check_gradient(&model, &q, &row, |data| model.com(data).unwrap()[0]);
    // Edge 2 (top, from (0.06, 0.03) to (−0.04, 0.03)): normal +y.
    let row: Vec<f64> = (0..model.nv()).map(|k| jacobian[(2, k)]).collect();
    check_gradient(&model, &q, &row, |data| model.com(data).unwrap()[1]);
    for spare in 4..6 {
        assert_eq!(
            (lower[spare], upper[spare]),
            (f64::NEG_INFINITY, f64::INFINITY)
        );
        assert!((0..model.nv()).all(|k| jacobian[(spare, k)] == 0.0));
    }
    assert!(lower[..4].iter().all(|l| *l == f64::NEG_INFINITY));
}

#[test]
fn bad_polygons_and_geometry_are_refused() {
    let model = nao::rfoot();
    let square = [[-0.04, -0.03], [0.06, -0.03], [0.06, 0.03], [-0.04, 0.03]];
    let clockwise: Vec<[f64; 2]> = square.iter().rev().copied().collect();
    assert!(matches!(
        ComPolygonTask::new(&model, 4, &clockwise, 0.0),
        Err(TaskError::InvalidPolygon { .. })
    ));
    assert!(matches!(
        ComPolygonTask::new(&model, 4, &square, -0.01),
        Err(TaskError::InvalidPolygon { .. })
    ));
    assert!(matches!(
        ComPolygonTask::new(&model, 3, &square, 0.0),
        Err(TaskError::WrongLength { .. })
    ));
    let mut task = ComPolygonTask::new(&model, 4, &square, 0.0).unwrap();
    assert!(
        task.set_polygon(&[[0.0, 0.0], [f64::NAN, 0.0], [0.0, 1.0]], 0.0)
            .is_err()
    );
    assert_eq!(
        task.vertices(),
        &square,
        "a refused polygon leaves the task as it was"
    );
    assert!(matches!(
        Capsule::new(&model, "l_hand", Vector3::zeros(), Vector3::zeros(), -1.0),
        Err(TaskError::InvalidGeometry { .. })
    ));
    assert!(
        Capsule::new(
            &model,
            "no_such_frame",
            Vector3::zeros(),
            Vector3::zeros(),
            0.1
        )
        .is_err()
    );
    assert!(matches!(
        PlaneDistanceTask::new(
            &model,
            "floor",
            forearm(&model, "l"),
            Vector3::zeros(),
            Vector3::zeros(),
            0.0
        ),
        Err(TaskError::InvalidGeometry { .. })
    ));
}

#[test]
fn closest_segment_points_by_hand() {
    // Crossed segments one unit apart: the closest points are both middles.
    let (s, t) = closest_segment_parameters(
        &Vector3::new(-1.0, 0.0, 0.0),
        &Vector3::new(1.0, 0.0, 0.0),
        &Vector3::new(0.0, -1.0, 1.0),
        &Vector3::new(0.0, 1.0, 1.0),
    );
    assert!((s - 0.5).abs() < 1e-15 && (t - 0.5).abs() < 1e-15);
    // A point beyond the end of a segment: the end, t = 1.
    let (s, t) = closest_segment_parameters(
        &Vector3::new(3.0, 0.0, 0.0),
        &Vector3::new(3.0, 0.0, 0.0),
        &Vector3::new(0.0, 0.0, 0.0),
        &Vector3::new(1.0, 0.0, 0.0),
    );
    assert_eq!((s, t), (0.0, 1.0));
    // Parallel segments overlapping on [0.5, 1]: some pair at distance 0.3 (any s on the overlap).
    let (p1, q1) = (Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0));
    let (p2, q2) = (Vector3::new(0.5, 0.3, 0.0), Vector3::new(1.5, 0.3, 0.0));
    let (s, t) = closest_segment_parameters(&p1, &q1, &p2, &q2);
    let gap = (p1 + (q1 - p1) * s) - (p2 + (q2 - p2) * t);
    assert!((gap.norm() - 0.3).abs() < 1e-15, "{gap}");
}

/// The right hand sent far forward: with the CoM kept inside a rectangle under the right sole
/// (shrunk by 1 cm) at the top, the CoM stays inside; without that level the hand drags it out.
#[test]
fn com_polygon_level_keeps_the_com_inside_while_a_hand_reaches() {
    let model = nao::rfoot();
    let square = [[-0.03, -0.02], [0.05, -0.02], [0.05, 0.02], [-0.03, 0.02]];
    let margin = 0.01;
    let far = Vector3::new(0.4, -0.1, 0.25);
    let run = |with_polygon: bool| {
        let hand: Box<dyn Task> = Box::new(PositionTask::new(&model, "r_hand", far).unwrap());
        let mut set = if with_polygon {
            let polygon = ComPolygonTask::new(&model, 4, &square, margin).unwrap();
            TaskSet::new(&model)
                .inequality_level("balance", vec![Box::new(polygon)])
                .level("reach", vec![hand])
        } else {
            TaskSet::new(&model).level("reach", vec![hand])
        };
        let mut solver = Solver::new(&set.shape()).unwrap();
        let settings = DriverSettings {
            max_iterations: 200,
            ..DriverSettings::default()
        };
        let mut driver = PositionDriver::new(&solver, settings).unwrap();
        let mut q = nao::profile().stand.clone();
        driver
            .run(
                &mut solver,
                &mut set,
                &mut q,
                &joint_bounds(&model).unwrap(),
            )
            .unwrap();
        let c = model.com(&data_at(&model, &q)).unwrap();
        (c, solver.report().active_inequalities().len())
    };
    let (free, _) = run(false);
    assert!(
        free[0] > 0.05 - margin + 0.005,
        "without the level the CoM leaves: {free}"
    );
    let (held, active) = run(true);
    assert!(
        held[0] <= 0.05 - margin + 1e-4,
        "CoM x {} past the shrunk edge",
        held[0]
    );
    assert!(held[1].abs() <= 0.02 - margin + 1e-4 && held[0] >= -0.03 + margin - 1e-4);
    assert!(active > 0, "the front edge is active");
}

/// A stack of one distance inequality alone, started 2 cm inside the margin: the driver keeps
/// iterating while the violation shrinks (no equality error to watch) and ends with the bodies
/// at the margin, a few iterations later.
#[test]
fn an_inequality_only_stack_is_driven_out_of_violation() {
    let model = nao::rfoot();
    let mut q = nao::profile().stand.clone();
    let r_elbow_roll = model.variable_index("RElbowRoll").unwrap();
    let r_shoulder_roll = model.variable_index("RShoulderRoll").unwrap();
    q[r_elbow_roll] = 1.5;
    q[r_shoulder_roll] = 0.3;
    let torso = Capsule::new(
        &model,
        "torso",
        Vector3::new(0.0, 0.0, -0.045),
        Vector3::new(0.0, 0.0, 0.06),
        0.055,
    )
    .unwrap();
    let margin = 0.01;
    let forearm = forearm(&model, "r");
    let task = CapsuleDistanceTask::new(&model, "apart", forearm, torso, margin).unwrap();
    let start = task.distance(&model, &data_at(&model, &q)).unwrap();
    assert!(start < margin - 0.015, "starts inside the margin: {start}");
    let mut set = TaskSet::new(&model).inequality_level("apart", vec![Box::new(task)]);
    let mut solver = Solver::new(&set.shape()).unwrap();
    let mut driver = PositionDriver::new(&solver, DriverSettings::default()).unwrap();
    let report = driver
        .run(
            &mut solver,
            &mut set,
            &mut q,
            &joint_bounds(&model).unwrap(),
        )
        .unwrap()
        .clone();
    let task: &mut CapsuleDistanceTask = set.inequality_mut("apart").unwrap();
    let end = task.distance(&model, &data_at(&model, &q)).unwrap();
    assert!(report.iterations > 1, "{report:?}");
    assert!(end >= margin - 1e-4, "ends {end} m apart, {report:?}");
}

/// The NAO's right sole as a rectangle (m, sole frame, counter-clockwise).
const SOLE: [[f64; 2]; 4] = [[-0.05, -0.04], [0.1, -0.04], [0.1, 0.04], [-0.05, 0.04]];

/// The ZMP task's rows at `q` for a frame that started at `start` after joint velocity
/// `velocity`, `dt` s long: the Jacobian and the upper room of every row.
fn zmp_rows(
    model: &Model,
    start: &[f64],
    velocity: &[f64],
    q: &[f64],
    dt: f64,
) -> (Mat<f64>, Vec<f64>, Vec<f64>) {
    let mut task = ZmpTask::new(model, 4, &SOLE, 0.01, 0.5).unwrap();
    task.begin_frame(start, velocity, dt).unwrap();
    let mut jacobian = Mat::zeros(task.rows(), model.nv());
    let (mut lower, mut upper) = (vec![0.0; task.rows()], vec![0.0; task.rows()]);
    task.write(
        model,
        &data_at(model, q),
        q,
        jacobian.as_mut(),
        &mut lower,
        &mut upper,
    )
    .unwrap();
    (jacobian, lower, upper)
}

#[test]
fn zmp_rows_match_the_momentum_of_the_links() {
    let model = nao::rfoot();
    let q0 = bent(&model);
    let dt = 0.01;
    let velocity: Vec<f64> = (0..model.nv())
        .map(|i| 0.5 * ((i as f64) * 0.9).cos())
        .collect();
    // At the frame's start the joints stop: Ḣ = −H₋/Δt, H₋ the links' momentum at `velocity`.
    let (_, lower, upper) = zmp_rows(&model, &q0, &velocity, &q0, dt);
    let h_rate = -common::momentum_by_differences(&model, &q0, &velocity) / dt;
    let weight = model.total_mass() * GRAVITY;
    let c = model.com(&data_at(&model, &q0)).unwrap();
    let zmp = [c.x - h_rate.y / weight, c.y + h_rate.x / weight];
    // Edge 0 runs from (−0.05, −0.04) to (0.1, −0.04): outward normal −y, offset 0.04.
    let expected = 0.04 - 0.01 + zmp[1];
    assert!(
        (upper[0] - expected).abs() < 1e-6,
        "{} vs {expected}",
        upper[0]
    );
    // Edge 1 (x = 0.1, normal +x): room 0.1 − 0.01 − p_x.
    assert!((upper[1] - (0.09 - zmp[0])).abs() < 1e-6);
    assert!(
        (upper[4] - (0.5 - h_rate.z)).abs() < 1e-4 && (lower[4] - (-0.5 - h_rate.z)).abs() < 1e-4
    );
    assert!(lower[..4].iter().all(|l| *l == f64::NEG_INFINITY));
}

#[test]
fn zmp_jacobian_is_the_derivative_of_its_rows() {
    let model = nao::rfoot();
    let q0 = bent(&model);
    let (dt, rest) = (0.01, vec![0.0; model.nv()]);
    let (jacobian, _, _) = zmp_rows(&model, &q0, &rest, &q0, dt);
    for k in [0, 5, 12, 20] {
        let h = 1e-7;
        let mut q = q0.clone();
        q[k] += h;
        let (_, _, upper_plus) = zmp_rows(&model, &q0, &rest, &q, dt);
        q[k] -= 2.0 * h;
        let (_, _, upper_minus) = zmp_rows(&model, &q0, &rest, &q, dt);
        for r in 0..5 {
            // The room shrinks as the row's value grows.
            let fd = -(upper_plus[r] - upper_minus[r]) / (2.0 * h);
            let scale = jacobian[(r, k)].abs().max(1.0);
            assert!(
                (fd - jacobian[(r, k)]).abs() < 1e-4 * scale,
                "row {r} var {k}: {fd} vs {}",
                jacobian[(r, k)]
            );
        }
    }
}

#[test]
fn zmp_task_rejects_bad_input() {
    let model = nao::rfoot();
    let n = model.nv();
    assert!(matches!(
        ZmpTask::new(&model, 3, &SOLE[..3], 0.0, 1.0),
        Err(TaskError::InvalidGeometry { .. })
    ));
    assert!(matches!(
        ZmpTask::new(&model, 4, &SOLE, 0.0, f64::NAN),
        Err(TaskError::InvalidGeometry { .. })
    ));
    let mut task = ZmpTask::new(&model, 4, &SOLE, 0.0, 1.0).unwrap();
    assert!(
        task.begin_frame(&vec![0.0; n], &vec![0.0; n - 1], 0.01)
            .is_err()
    );
    assert!(
        task.begin_frame(&vec![f64::NAN; n], &vec![0.0; n], 0.01)
            .is_err()
    );
    assert!(task.begin_frame(&vec![0.0; n], &vec![0.0; n], 0.0).is_err());
    let mut jacobian = Mat::zeros(task.rows(), n);
    let (mut lower, mut upper) = (vec![0.0; 5], vec![0.0; 5]);
    let data = data_at(&model, &vec![0.0; n]);
    let short = vec![0.0; n - 1];
    assert!(
        task.write(
            &model,
            &data,
            &short,
            jacobian.as_mut(),
            &mut lower,
            &mut upper
        )
        .is_err()
    );
    let (q, mut small) = (vec![0.0; n], Mat::zeros(4, n));
    let written = task.write(&model, &data, &q, small.as_mut(), &mut lower, &mut upper);
    assert!(matches!(written, Err(ModelError::OutputShape { .. })));
}

/// Seeing no joint's momentum, the ZMP rows are the CoM's: the room of an edge is its offset less
/// the margin and the CoM's reach toward it, however fast the joints moved before; a mask of
/// the wrong length is refused.
#[test]
fn zmp_task_seeing_no_joint_is_the_com_polygon() {
    let model = nao::rfoot();
    let (q0, n) = (bent(&model), model.nv());
    let velocity = vec![1.0; n];
    let mut task = (ZmpTask::new(&model, 4, &SOLE, 0.01, 0.5).unwrap())
        .seeing(vec![false; n])
        .unwrap();
    task.begin_frame(&q0, &velocity, 0.01).unwrap();
    let mut jacobian = Mat::zeros(task.rows(), n);
    let (mut lower, mut upper) = (vec![0.0; 5], vec![0.0; 5]);
    let data = data_at(&model, &q0);
    (task.write(
        &model,
        &data,
        &q0,
        jacobian.as_mut(),
        &mut lower,
        &mut upper,
    ))
    .unwrap();
    let c = model.com(&data).unwrap();
    assert!((upper[0] - (0.04 - 0.01 + c.y)).abs() < 1e-12);
    assert!((upper[1] - (0.1 - 0.01 - c.x)).abs() < 1e-12);
    assert_eq!((lower[4], upper[4]), (-0.5, 0.5));
    assert!((0..n).all(|k| jacobian[(4, k)] == 0.0));
    let task = ZmpTask::new(&model, 4, &SOLE, 0.01, 0.5).unwrap();
    assert!(matches!(
        task.seeing(vec![true; n - 1]),
        Err(TaskError::Solver(_))
    ));
}
