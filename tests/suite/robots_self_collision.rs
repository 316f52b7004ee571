//! The NAO's self-collision model: capsule ends follow the frames they are named after at any
//! posture (forward kinematics of those frames, not of the capsule), the standing distances
//! match a hand calculation, the URDF NAO gives the DH NAO's distances, and a model that cannot
//! hold (an end on a joint, an unknown body, a margin the standing posture breaks) is refused
//! with the field named.

use nalgebra::Vector3;
use taskstack::human::Side;
use taskstack::model::{Model, ModelData};
use taskstack::robots::{BodyCapsule, FramePoint, ProfileError, SelfCollision, nao};

fn data_at(model: &Model, q: &[f64]) -> ModelData {
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    data
}

/// Postures spread over the joint ranges (a fixed low-discrepancy sequence).
fn postures(model: &Model, count: usize) -> Vec<Vec<f64>> {
    (1..=count)
        .map(|k| {
            model
                .variables()
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    let t = ((k * (i + 3)) as f64 * 0.618_033_988_75).fract();
                    v.lower + t * (v.upper - v.lower)
                })
                .collect()
        })
        .collect()
}

#[test]
fn capsule_ends_follow_their_named_frames_at_any_posture() {
    let profile = nao::profile();
    for side in Side::BOTH {
        let model = profile.model(side);
        for body in &profile.self_collision.bodies {
            let capsule = body.capsule(model, &profile.stand).unwrap();
            for q in postures(model, 20) {
                let data = data_at(model, &q);
                for (end, point) in [capsule.a, capsule.b].iter().zip(&body.ends) {
                    let named = model.frame_id(&point.frame).unwrap();
                    let expected = data
                        .frame_placement(named)
                        .transform_point(&Vector3::from(point.offset).into());
                    let got = model.point_position(&data, capsule.frame, end).unwrap();
                    assert!(
                        (got - expected.coords).norm() < 1e-9,
                        "{}: end at {got:?}, {} at {expected:?}",
                        body.name,
                        point.frame
                    );
                }
            }
        }
    }
}

/// Standing, the shins are parallel and 0.1 m apart (the hip width), r = 30 mm each: 40 mm;
/// the feet, r = 35 mm on the soles' x axes 0.1 m apart: 30 mm.
#[test]
fn standing_distances_by_hand() {
    let profile = nao::profile();
    let model = profile.model(Side::Right);
    let pairs = profile
        .self_collision
        .resolve(model, &profile.stand)
        .unwrap();
    let data = data_at(model, &profile.stand);
    let distance = |a: &str, b: &str| {
        let k = (profile.self_collision.pairs.iter())
            .position(|p| p == &[a.to_owned(), b.to_owned()])
            .unwrap();
        let [first, second] = &pairs[k];
        first.distance_to(second, model, &data).unwrap()
    };
    assert!((distance("l_shin", "r_shin") - 0.04).abs() < 1e-9);
    assert!((distance("l_foot", "r_foot") - 0.03).abs() < 1e-9);
}

#[test]
fn the_urdf_nao_has_the_dh_nao_distances() {
    let urdf = format!("{}/tests/data/nao.urdf", env!("CARGO_MANIFEST_DIR"));
    let from_urdf = nao::profile_with(
        Side::BOTH.map(|side| nao::from_urdf_file(&urdf, Some(nao::sole(side))).unwrap()),
    );
    from_urdf.validate().unwrap();
    let dh = nao::profile();
    let (a, b) = (dh.model(Side::Left), from_urdf.model(Side::Left));
    let pairs_dh = dh.self_collision.resolve(a, &dh.stand).unwrap();
    let pairs_urdf = from_urdf.self_collision.resolve(b, &dh.stand).unwrap();
    for q in postures(a, 10) {
        let (da, db) = (data_at(a, &q), data_at(b, &q));
        for ([p, q], [r, s]) in pairs_dh.iter().zip(&pairs_urdf) {
            let (x, y) = (
                p.distance_to(q, a, &da).unwrap(),
                r.distance_to(s, b, &db).unwrap(),
            );
            assert!((x - y).abs() < 1e-6, "DH {x} m, URDF {y} m");
        }
    }
}

fn refused(collision: SelfCollision) -> String {
    let mut profile = nao::profile();
    profile.self_collision = collision;
    match profile.validate() {
        Err(ProfileError::Invalid { field, reason }) => format!("{field}: {reason}"),
        other => panic!("expected Invalid, got {other:?}"),
    }
}

#[test]
fn models_that_cannot_hold_are_refused() {
    let nao = nao::self_collision();
    // The shoulder is 15 mm off the elbow-yaw axis: it moves on the elbow's frame.
    let mut on_a_joint = nao.clone();
    on_a_joint.bodies.push(BodyCapsule {
        name: "l_upper_arm".into(),
        frame: "l_elbow".into(),
        ends: [
            FramePoint::origin("l_shoulder"),
            FramePoint::origin("l_elbow"),
        ],
        radius: 0.02,
    });
    on_a_joint
        .pairs
        .push(["l_upper_arm".into(), "torso".into()]);
    let message = refused(on_a_joint);
    assert!(
        message.contains("l_upper_arm") && message.contains("not fixed"),
        "{message}"
    );

    let mut unknown = nao.clone();
    unknown.pairs.push(["l_forearm".into(), "tail".into()]);
    assert!(refused(unknown).contains("tail"));

    let mut negative = nao.clone();
    negative.bodies[0].radius = -0.01;
    assert!(refused(negative).contains("radius"));

    let too_wide = SelfCollision {
        margin: 0.035,
        ..nao.clone()
    };
    let message = refused(too_wide);
    assert!(message.contains("l_foot and r_foot"), "{message}");

    let nan = SelfCollision {
        margin: f64::NAN,
        ..nao
    };
    assert!(refused(nan).starts_with("self_collision.margin"));
}
