//! `taskstack::problem`: malformed benchmark files are typed errors naming the field at fault,
//! never panics; a frame past the file's count is refused.

use serde_json::Value;
use taskstack::problem::{Problem, ProblemError, Runner};

fn bundled() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/bench/problem_rs.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The field named by the error of reading `doc`.
fn failing_field(doc: &Value) -> String {
    match Problem::from_json(&doc.to_string()) {
        Err(ProblemError::Invalid { field, .. }) => field,
        other => panic!("expected an invalid-field error, got {other:?}"),
    }
}

#[test]
fn the_bundled_file_reads() {
    let problem = Problem::from_json(&bundled().to_string()).unwrap();
    assert_eq!(problem.q_init.len(), 23);
    assert!(problem.frames > 0);
}

#[test]
fn malformed_fields_are_named() {
    let mut doc = bundled();
    doc["schema"] = "other/1".into();
    assert_eq!(failing_field(&doc), "schema");

    let mut doc = bundled();
    doc["q_init"].as_array_mut().unwrap().pop();
    assert_eq!(failing_field(&doc), "q_init");

    let mut doc = bundled();
    doc["joint_limits"]["lower"][0] = "low".into();
    assert_eq!(failing_field(&doc), "joint_limits.lower");

    let mut doc = bundled();
    let first = doc["points"]
        .as_object()
        .unwrap()
        .keys()
        .next()
        .unwrap()
        .clone();
    doc["points"][&first]["offset"] = serde_json::json!([0.0, 0.0]);
    assert_eq!(failing_field(&doc), format!("points.{first}.offset"));

    let mut doc = bundled();
    doc["frames"]["count"] = "many".into();
    assert_eq!(failing_field(&doc), "frames.count");

    let mut doc = bundled();
    doc["tasks"][0]["kind"] = "dance".into();
    assert!(failing_field(&doc).ends_with(".kind"));
}

#[test]
fn not_json_and_unknown_joints_are_errors() {
    assert!(matches!(
        Problem::from_json("{ not json"),
        Err(ProblemError::Json(_))
    ));
    let mut doc = bundled();
    doc["joint_order"][0] = "Tail".into();
    assert!(matches!(
        Problem::from_json(&doc.to_string()),
        Err(ProblemError::Model(_))
    ));
}

#[test]
fn a_frame_past_the_count_is_refused() {
    let problem = Problem::from_json(&bundled().to_string()).unwrap();
    let mut runner = Runner::new(&problem).unwrap();
    let mut q = problem.q_init.clone();
    assert!(runner.solve_frame(problem.frames, &mut q).is_err());
    assert!(runner.solve_frame(0, &mut q).is_ok());
}

/// With the CoM task as an inequality (inside the support polygon shrunk by 1 cm), every frame of
/// the RS and DS files converges: the point tasks within 1e-4 m, and the CoM at least
/// 1 cm − 1e-4 m inside the hull of the soles on the ground.
#[test]
fn com_polygon_variant_converges_with_the_com_inside() {
    use nalgebra::{Point3, Vector2};
    use taskstack::human::Side;
    use taskstack::imitation::metrics::convex_margin;
    use taskstack::robots::nao;
    use taskstack::solver::driver::StopReason;
    let model = nao::rfoot();
    for name in ["problem_rs", "problem_ds"] {
        let path = format!(
            "{}/tests/data/bench/{name}.json",
            env!("CARGO_MANIFEST_DIR")
        );
        let mut problem = Problem::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
        problem.com_polygon_margin = Some(0.01);
        let mut data = model.new_data();
        model
            .forward_kinematics(&mut data, &problem.q_init)
            .unwrap();
        let mut corners = Vec::new();
        for side in [Side::Left, Side::Right] {
            let sole = model.frame_id(nao::sole(side)).unwrap();
            let placement = model
                .placement_in_world(&data, &Default::default(), sole)
                .unwrap();
            if placement.translation.vector.z.abs() < 1e-3 {
                for [x, y] in nao::sole_outline(side) {
                    let p = placement.transform_point(&Point3::new(x, y, 0.0));
                    corners.push(Vector2::new(p.x, p.y));
                }
            }
        }
        assert_eq!(corners.len(), if name == "problem_rs" { 4 } else { 8 });
        let mut runner = Runner::new(&problem).unwrap();
        let mut q = problem.q_init.clone();
        for frame in 0..problem.frames {
            let result = runner.solve_frame(frame, &mut q).unwrap();
            assert_eq!(result.stop, StopReason::Converged, "{name} frame {frame}");
            model.forward_kinematics(&mut data, &q).unwrap();
            let com = model.com(&data).unwrap();
            let margin = convex_margin(&corners, com.xy());
            assert!(
                margin >= 0.01 - 1e-4,
                "{name} frame {frame}: CoM {margin} m inside"
            );
        }
    }
}
