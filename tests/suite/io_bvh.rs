//! BVH reader on the CMU clips (`tests/data/mocap/README.md`) and on hand-written files.

use std::io::Cursor;

use nalgebra::Vector3;
use proptest::prelude::*;
use taskstack::human::{HumanFrame, HumanJoint as J};
use taskstack::io::bvh::{BvhConfig, BvhError, BvhNames, BvhReader, UpAxis};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap/");

const CMU_MB: [&str; 5] = [
    "cmu_02_10_wash_self_standing_arm_gestures.bvh",
    "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh",
    "cmu_05_12_slow_dance_tendu_arms_high.bvh",
    "cmu_07_04_slow_walk.bvh",
    "cmu_09_12_walk_forward_backward_sideways.bvh",
];
const CMU_MAX: &str = "cmu_131_01_start_walk_stop_maxskel.bvh";

fn open(name: &str) -> BvhReader<std::io::BufReader<std::fs::File>> {
    BvhReader::open(format!("{DATA}{name}"), BvhConfig::cmu()).expect("header parses")
}

fn parse_str(text: &str, config: BvhConfig) -> Result<Vec<HumanFrame>, BvhError> {
    BvhReader::new(Cursor::new(text.as_bytes().to_vec()), "test.bvh", config)?.collect()
}

fn p(frame: &HumanFrame, joint: J) -> Vector3<f64> {
    frame
        .get(joint)
        .unwrap_or_else(|| panic!("{joint:?} missing"))
}

/// Angle in degrees between `v` and `axis`.
fn angle_deg(v: Vector3<f64>, axis: Vector3<f64>) -> f64 {
    v.angle(&axis).to_degrees()
}

/// Headers of the README: 31 joints, 96 channels, 120 fps, frame counts of the per-file table.
#[test]
fn cmu_headers_match_the_readme() {
    let frames = [2401, 1124, 1355, 450, 1919, 994];
    for (name, expected) in CMU_MB.iter().chain([&CMU_MAX]).zip(frames) {
        let reader = open(name);
        assert_eq!(reader.skeleton().joints().len(), 31, "{name}");
        assert_eq!(reader.skeleton().channel_count(), 96, "{name}");
        assert_eq!(reader.declared_frames(), expected, "{name}");
        assert!((reader.frame_time() - 1.0 / 120.0).abs() < 1e-6, "{name}");
    }
}

/// README: "Frame 0 is a synthetic T-pose … facing +Z, arms 8° below horizontal, legs vertical",
/// "ground ≈ Y = 0 (the T-pose toes sit at Y ≈ −0.01 m)". In the human frame (x forward, y left,
/// z up) the subject faces +x, its left arm points to +y, its right arm to −y.
#[test]
fn cmu_mb_frame_0_is_a_t_pose_standing_on_the_floor() {
    for name in CMU_MB {
        let f = open(name).next().unwrap().unwrap();
        assert_eq!(f.time, 0.0);
        assert!(
            f.joints().all(|(_, p)| p.is_some()),
            "{name}: joint missing"
        );
        for (ankle, toe) in [(J::LAnkle, J::LToe), (J::RAnkle, J::RToe)] {
            // Toes near the floor. The root of the T-pose is copied from the first captured frame
            // and these floors are uneven by several cm (README), so: within 5 cm of z = 0.
            // Ankles a few cm higher, no more than a human ankle's 12 cm.
            assert!(p(&f, toe).z.abs() < 0.05, "{name}: toe z {}", p(&f, toe).z);
            assert!((0.0..0.12).contains(&p(&f, ankle).z), "{name}: ankle z");
            // Facing +x: the toes are in front of the ankles.
            assert!(p(&f, toe).x - p(&f, ankle).x > 0.05, "{name}: facing");
        }
        // Legs vertical (README: "legs vertical"; 3° allows for the skeleton's bone offsets).
        for (a, b) in [
            (J::LHip, J::LKnee),
            (J::LKnee, J::LAnkle),
            (J::RHip, J::RKnee),
            (J::RKnee, J::RAnkle),
        ] {
            let down = angle_deg(p(&f, b) - p(&f, a), -Vector3::z());
            assert!(down < 3.0, "{name}: {a:?}→{b:?} {down}° from vertical");
        }
        // Arms 8° below horizontal (±3°), pointing sideways (within 10° of ±y).
        for (a, b, side) in [
            (J::LShoulder, J::LElbow, 1.0),
            (J::LElbow, J::LWrist, 1.0),
            (J::RShoulder, J::RElbow, -1.0),
            (J::RElbow, J::RWrist, -1.0),
        ] {
            let v = p(&f, b) - p(&f, a);
            let below = (-v.z / v.norm()).asin().to_degrees();
            assert!(
                (below - 8.0).abs() < 3.0,
                "{name}: {a:?}→{b:?} {below}° below"
            );
            let sideways = angle_deg(Vector3::new(v.x, v.y, 0.0), Vector3::y() * side);
            assert!(sideways < 10.0, "{name}: {a:?}→{b:?} {sideways}° from ±y");
        }
        // Upright: pelvis at 0.90–0.98 m (README), head above neck above mid-shoulder above hips.
        assert!(
            (0.85..1.05).contains(&p(&f, J::Pelvis).z),
            "{name}: pelvis height"
        );
        let chain = [J::MidHip, J::MidShoulder, J::Neck, J::Head];
        assert!(chain.windows(2).all(|w| p(&f, w[1]).z > p(&f, w[0]).z));
        // MidHip is derived as the midpoint of the hips.
        let mid = (p(&f, J::LHip) + p(&f, J::RHip)) / 2.0;
        assert!((p(&f, J::MidHip) - mid).norm() < 1e-12);
    }
}

/// A rigid skeleton: every bone's length is the scaled length of its OFFSET in the header
/// (an independent source), in every frame of every clip, to 1e-6 m.
#[test]
fn bone_lengths_stay_those_of_the_header_in_every_frame() {
    for name in CMU_MB.iter().chain([&CMU_MAX]) {
        let mut reader = open(name);
        let expected: Vec<Option<(usize, f64)>> = reader
            .skeleton()
            .joints()
            .iter()
            .map(|j| j.parent.map(|parent| (parent, 0.056444 * j.offset.norm())))
            .collect();
        let mut frame = HumanFrame::new(0.0);
        let mut frames = 0;
        while reader.read_frame(&mut frame).unwrap() {
            let positions = reader.joint_positions();
            for (j, bone) in expected.iter().enumerate() {
                if let Some((parent, length)) = *bone {
                    let measured = (positions[j] - positions[parent]).norm();
                    assert!(
                        (measured - length).abs() < 1e-6,
                        "{name} frame {frames}: bone {j} is {measured} m, header says {length} m"
                    );
                }
            }
            frames += 1;
        }
        assert_eq!(frames, reader.declared_frames(), "{name}");
    }
}

/// The human segments that are single bones keep their length too (thigh, shank, upper arm,
/// forearm), measured on the `HumanFrame`s the iterator yields.
#[test]
fn human_limb_segments_are_rigid() {
    let limbs = [
        J::LKnee,
        J::RKnee,
        J::LAnkle,
        J::RAnkle,
        J::LElbow,
        J::RElbow,
        J::LWrist,
        J::RWrist,
    ];
    for name in CMU_MB.iter().chain([&CMU_MAX]) {
        let frames: Vec<HumanFrame> = open(name).map(Result::unwrap).collect();
        for joint in limbs {
            let first = frames[0].segment(joint).unwrap().norm();
            assert!(first > 0.1, "{name}: {joint:?} {first}");
            for f in &frames {
                let length = f.segment(joint).unwrap().norm();
                assert!(
                    (length - first).abs() < 1e-6,
                    "{name}: {joint:?} at {}",
                    f.time
                );
            }
        }
    }
}

/// Frame k is at k·Frame Time.
#[test]
fn frame_times_count_from_zero() {
    let frames: Vec<HumanFrame> = open(CMU_MB[3]).map(Result::unwrap).collect();
    assert_eq!(frames.len(), 450);
    for (k, f) in frames.iter().enumerate() {
        assert!((f.time - k as f64 * 0.0083333).abs() < 1e-12);
    }
}

/// CMU-MAX (131_01, no T-pose): names detected automatically; standing in the first second
/// (README): upper arms hanging, wrists below elbows and shoulders, feet low, head high. (The
/// exact per-joint order is checked by hand computation in the test after this one.)
#[test]
fn cmu_max_skeleton_stands_with_arms_down() {
    let frames: Vec<HumanFrame> = open(CMU_MAX).map(Result::unwrap).take(120).collect();
    for f in &frames {
        assert!(f.joints().all(|(_, p)| p.is_some()));
        for (shoulder, elbow, wrist) in [
            (J::LShoulder, J::LElbow, J::LWrist),
            (J::RShoulder, J::RElbow, J::RWrist),
        ] {
            assert!(angle_deg(p(f, elbow) - p(f, shoulder), -Vector3::z()) < 45.0);
            assert!(p(f, wrist).z < p(f, elbow).z);
            assert!(p(f, shoulder).z - p(f, wrist).z > 0.2);
        }
        assert!(p(f, J::LToe).z < 0.15 && p(f, J::RToe).z < 0.15);
        assert!(p(f, J::Head).z > 1.2 && p(f, J::Head).z > p(f, J::MidShoulder).z);
    }
}

const TWO_JOINTS: &str = "HIERARCHY
ROOT Base
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Tip
  {
    OFFSET 0 0 1
    CHANNELS 3 Xrotation Zrotation Yrotation
    End Site
    {
      OFFSET 0 0 2
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.5
1 2 3 90 90 0 0 0 0
0 0 0 0 90 0 0 90 0
";

fn two_joint_map() -> BvhNames {
    BvhNames::Custom(vec![
        ("Base".to_owned(), J::Pelvis),
        ("Tip".to_owned(), J::Head),
    ])
}

/// Hand-computed FK with per-joint order. Rz(90°): x→y, y→−x; Rx(90°): y→z, z→−y.
/// Frame 0, root `Zrotation Xrotation` = Rz(90)·Rx(90): Tip = (1,2,3) + Rz·Rx·(0,0,1)
/// = (1,2,3) + Rz·(0,−1,0) = (1,2,3) + (1,0,0) = (2,2,3). Frame 1, root Rx(90): Tip = (0,−1,0).
/// With Z up kept and scale 2: (4,4,6) and (0,−2,0).
#[test]
fn forward_kinematics_honours_each_joints_channel_order() {
    let config = BvhConfig {
        scale: 2.0,
        up: UpAxis::Z,
        names: two_joint_map(),
        ..BvhConfig::cmu()
    };
    let frames = parse_str(TWO_JOINTS, config).unwrap();
    assert_eq!(frames.len(), 2);
    assert!((p(&frames[0], J::Head) - Vector3::new(4.0, 4.0, 6.0)).norm() < 1e-12);
    assert!((p(&frames[0], J::Pelvis) - Vector3::new(2.0, 4.0, 6.0)).norm() < 1e-12);
    assert!((p(&frames[1], J::Head) - Vector3::new(0.0, -2.0, 0.0)).norm() < 1e-12);
    assert_eq!(frames[1].time, 0.5);
    // Unmapped joints are missing, not invented.
    assert_eq!(frames[0].get(J::LHand), None);
}

/// Y up: file (X, Y, Z) → (Z, X, Y). Frame 1's tip at file (0,−1,0) becomes (0, 0, −1).
#[test]
fn y_up_files_are_mapped_to_z_up() {
    let config = BvhConfig {
        scale: 1.0,
        up: UpAxis::Y,
        names: two_joint_map(),
        ..BvhConfig::cmu()
    };
    let frames = parse_str(TWO_JOINTS, config).unwrap();
    assert!((p(&frames[1], J::Head) - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
    assert!((p(&frames[0], J::Pelvis) - Vector3::new(3.0, 1.0, 2.0)).norm() < 1e-12);
}

fn custom_config() -> BvhConfig {
    BvhConfig {
        names: two_joint_map(),
        ..BvhConfig::cmu()
    }
}

fn error_of(text: &str) -> BvhError {
    match parse_str(text, custom_config()) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

fn assert_names_place(error: &BvhError, line: usize) {
    let message = error.to_string();
    assert!(
        message.starts_with(&format!("test.bvh:{line}:")),
        "message `{message}` should start with test.bvh:{line}:"
    );
}

#[test]
fn truncated_header_is_reported() {
    let cut = &TWO_JOINTS[..TWO_JOINTS.find("    End Site").unwrap()];
    let e = error_of(cut);
    assert!(
        matches!(e, BvhError::TruncatedHeader { line: 9, .. }),
        "{e:?}"
    );
    assert_names_place(&e, 9);
}

#[test]
fn truncated_motion_is_reported() {
    let cut = TWO_JOINTS.replace("0 0 0 0 90 0 0 90 0\n", "");
    let e = error_of(&cut);
    assert!(
        matches!(
            e,
            BvhError::TruncatedMotion {
                declared: 2,
                found: 1,
                line: 19,
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn wrong_channel_count_is_reported() {
    let text = TWO_JOINTS.replace(
        "CHANNELS 3 Xrotation Zrotation Yrotation",
        "CHANNELS 3 Xrotation Zrotation",
    );
    let e = error_of(&text);
    assert!(
        matches!(&e, BvhError::ChannelCount { line: 9, joint, declared: 3, listed: 2, .. } if joint == "Tip"),
        "{e:?}"
    );
    assert_names_place(&e, 9);
    let text = TWO_JOINTS.replace("CHANNELS 3 Xrotation", "CHANNELS 7 Xrotation");
    assert!(matches!(
        error_of(&text),
        BvhError::ChannelCount { declared: 7, .. }
    ));
}

#[test]
fn motion_line_with_wrong_value_count_is_reported() {
    let text = TWO_JOINTS.replace("0 0 0 0 90 0 0 90 0", "0 0 0 0 90 0 0 90");
    let e = error_of(&text);
    assert!(
        matches!(
            e,
            BvhError::FrameValueCount {
                line: 20,
                expected: 9,
                found: 8,
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn unknown_rotation_order_is_reported() {
    let text = TWO_JOINTS.replace(
        "Xrotation Zrotation Yrotation",
        "Xrotation Zrotation Xrotation",
    );
    let e = error_of(&text);
    assert!(
        matches!(&e, BvhError::RotationOrder { line: 9, order, .. } if order == "Xrotation Zrotation Xrotation"),
        "{e:?}"
    );
}

#[test]
fn unknown_channel_name_is_reported() {
    let text = TWO_JOINTS.replace(
        "Xrotation Zrotation Yrotation",
        "Xrotation Wrotation Yrotation",
    );
    let e = error_of(&text);
    assert!(
        matches!(&e, BvhError::UnknownChannel { line: 9, channel, .. } if channel == "Wrotation"),
        "{e:?}"
    );
}

#[test]
fn non_numeric_values_are_reported_with_their_channel() {
    let text = TWO_JOINTS.replace("1 2 3 90 90 0 0 0 0", "1 2 3 90 ninety 0 0 0 0");
    let e = error_of(&text);
    assert!(
        matches!(&e, BvhError::Number { line: 19, field, text, .. }
            if field == "value 5 (Base Xrotation)" && text == "ninety"),
        "{e:?}"
    );
    let text = TWO_JOINTS.replace("OFFSET 0 0 1", "OFFSET 0 0 1e999");
    assert!(matches!(error_of(&text), BvhError::Number { line: 8, .. }));
    let text = TWO_JOINTS.replace("Frame Time: 0.5", "Frame Time: -0.5");
    assert!(matches!(error_of(&text), BvhError::Number { line: 18, .. }));
    // Frame 1 at 1 × 1e308 s is finite, a frame 2 would not be: the time is checked too.
    let text = TWO_JOINTS
        .replace("Frame Time: 0.5", "Frame Time: 1e308")
        .replace("Frames: 2", "Frames: 3")
        + "0 0 0 0 0 0 0 0 0\n";
    let mut frames = BvhReader::new(Cursor::new(text), "test.bvh", custom_config()).unwrap();
    assert!(frames.next().unwrap().is_ok() && frames.next().unwrap().is_ok());
    assert!(matches!(
        frames.next(),
        Some(Err(BvhError::Number { line: 21, .. }))
    ));
}

/// A header may claim any number of frames: nothing is allocated from it, and the file simply
/// ends early (no memory blow-up, no panic).
#[test]
fn huge_frame_counts_are_not_trusted() {
    let text = TWO_JOINTS.replace("Frames: 2", "Frames: 1000000000000");
    let mut reader =
        BvhReader::new(Cursor::new(text.into_bytes()), "test.bvh", custom_config()).unwrap();
    assert_eq!(reader.declared_frames(), 1_000_000_000_000);
    assert!(reader.next().unwrap().is_ok());
    assert!(reader.next().unwrap().is_ok());
    assert!(matches!(
        reader.next(),
        Some(Err(BvhError::TruncatedMotion { found: 2, .. }))
    ));
    assert!(reader.next().is_none(), "finished after an error");
    let text = TWO_JOINTS.replace("Frames: 2", "Frames: 99999999999999999999999");
    assert!(matches!(error_of(&text), BvhError::Number { line: 17, .. }));
}

#[test]
fn name_maps_must_match_the_skeleton() {
    let config = BvhConfig {
        names: BvhNames::Custom(vec![("Elbow".to_owned(), J::LElbow)]),
        ..BvhConfig::cmu()
    };
    let e = parse_str(TWO_JOINTS, config).unwrap_err();
    assert!(matches!(&e, BvhError::NameMap { name, human: J::LElbow, .. } if name == "Elbow"));
    let e = parse_str(TWO_JOINTS, BvhConfig::cmu()).unwrap_err();
    assert!(matches!(&e, BvhError::UnknownSkeleton { root, .. } if root == "Base"));
    let e = parse_str(
        TWO_JOINTS,
        BvhConfig {
            names: BvhNames::CmuMax,
            ..BvhConfig::cmu()
        },
    )
    .unwrap_err();
    assert!(matches!(e, BvhError::NameMap { .. }));
}

#[test]
fn joint_count_is_capped() {
    let config = BvhConfig {
        max_joints: 1,
        ..custom_config()
    };
    let e = parse_str(TWO_JOINTS, config).unwrap_err();
    assert!(
        matches!(
            e,
            BvhError::Limit {
                line: 6,
                limit: 1,
                ..
            }
        ),
        "{e:?}"
    );
}

/// Header of a real CMU-MB file plus its first three frames.
fn small_real_file() -> String {
    let text = std::fs::read_to_string(format!("{DATA}{}", CMU_MB[1])).unwrap();
    let motion = text.find("MOTION").unwrap();
    let header = &text[..motion];
    let frames: Vec<&str> = text[motion..].lines().skip(3).take(3).collect();
    format!(
        "{header}MOTION\nFrames: 3\nFrame Time: .0083333\n{}\n",
        frames.join("\n")
    )
}

fn read_all(bytes: Vec<u8>) {
    // Must return (Ok or a typed error), never panic; positions, if any, are finite.
    if let Ok(reader) = BvhReader::new(Cursor::new(bytes), "fuzz.bvh", BvhConfig::cmu()) {
        for frame in reader {
            match frame {
                Ok(f) => assert!(
                    f.joints()
                        .all(|(_, p)| p.is_none_or(|p| p.iter().all(|c| c.is_finite())))
                ),
                Err(e) => assert!(e.to_string().starts_with("fuzz.bvh")),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn truncated_files_never_panic(cut in 0.0f64..1.0) {
        let text = small_real_file();
        let at = (cut * text.len() as f64) as usize;
        read_all(text.as_bytes()[..at].to_vec());
    }

    #[test]
    fn byte_flips_never_panic(flips in prop::collection::vec((0.0f64..1.0, any::<u8>()), 1..8)) {
        let mut bytes = small_real_file().into_bytes();
        let n = bytes.len();
        for (at, byte) in flips {
            bytes[((at * n as f64) as usize).min(n - 1)] = byte;
        }
        read_all(bytes);
    }

    #[test]
    fn huge_numbers_never_panic(at in 0.0f64..1.0, huge in prop::sample::select(vec![
        "1e308", "-1e308", "1e300", "9999999999999999999999999", "1e-320", "nan", "inf", "18446744073709551616",
    ])) {
        let text = small_real_file();
        // Replace the number token nearest to a random place.
        let tokens: Vec<&str> = text.split(' ').collect();
        let k = ((at * tokens.len() as f64) as usize).min(tokens.len() - 1);
        let mut mutated: Vec<&str> = tokens.clone();
        mutated[k] = huge;
        read_all(mutated.join(" ").into_bytes());
    }
}
