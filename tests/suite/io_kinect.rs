//! Kinect v2 CSV reader on the two Labanotation clips (`tests/data/mocap/README.md`) and on
//! hand-written lines.

use std::io::Cursor;

use proptest::prelude::*;
use taskstack::human::{HumanFrame, HumanJoint as J};
use taskstack::io::kinect::{KINECT_FIELDS, KinectConfig, KinectError, KinectReader};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap/");
const WAVE: &str = "kinect2_labanotation_ges01_wavehand.csv";
const BALANCE: &str = "kinect2_labanotation_ges02_balancinghands.csv";

fn read_clip(name: &str) -> Vec<HumanFrame> {
    KinectReader::open(format!("{DATA}{name}"), KinectConfig::default())
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

fn parse_str(text: &str, config: KinectConfig) -> Result<Vec<HumanFrame>, KinectError> {
    KinectReader::new(Cursor::new(text.as_bytes().to_vec()), "test.csv", config).collect()
}

/// A synthetic line: timestamp `t` (100 ns), joint k at camera (k, 10 + k, 100 + k) with state
/// `states[k]`, trailing comma as the KinectReader tool writes it.
fn line(t: u64, states: [u8; 25]) -> String {
    let mut s = t.to_string();
    for (k, state) in states.iter().enumerate() {
        s += &format!(",{},{},{},{}", k, 10 + k, 100 + k, state);
    }
    s + ",\n"
}

/// README: 154 and 161 frames, 5.17 s and 5.40 s, median spacing 33 ms, 2 dropped frames each.
#[test]
fn clips_have_the_readme_frame_counts_and_durations() {
    for (name, frames, duration) in [(WAVE, 154, 5.17), (BALANCE, 161, 5.40)] {
        let clip = read_clip(name);
        assert_eq!(clip.len(), frames, "{name}");
        assert_eq!(clip[0].time, 0.0);
        let last = clip.last().unwrap().time;
        assert!((last - duration).abs() < 0.01, "{name}: {last} s");
        let mut gaps: Vec<f64> = clip.windows(2).map(|w| w[1].time - w[0].time).collect();
        gaps.sort_by(f64::total_cmp);
        assert!(
            (gaps[gaps.len() / 2] - 0.033).abs() < 0.001,
            "{name}: median gap"
        );
        assert_eq!(
            gaps.iter().filter(|&&g| g > 0.05).count(),
            2,
            "{name}: dropped frames"
        );
    }
}

/// Camera → human frame: the subject faces the sensor (~2.7 m away), so it stands at x ≈ −2.7
/// facing +x, its left side towards +y, upright along z. In the wave clip the RIGHT hand goes
/// above the head (README) and the left does not.
#[test]
fn camera_axes_map_to_a_subject_facing_x_with_left_at_y() {
    for name in [WAVE, BALANCE] {
        for f in read_clip(name) {
            let p = |j| f.get(j).unwrap();
            assert!((p(J::Pelvis).x + 2.7).abs() < 0.1, "{name}: distance");
            assert!(p(J::LShoulder).y > p(J::RShoulder).y, "{name}: left is +y");
            assert!(p(J::LHip).y > p(J::RHip).y, "{name}: left is +y");
            assert!(p(J::Head).z > p(J::Neck).z && p(J::Neck).z > p(J::Pelvis).z);
            assert!(p(J::Pelvis).z > p(J::LKnee).z && p(J::LKnee).z > p(J::LAnkle).z);
            // Feet point towards the sensor: the foot joint is in front of (larger x) the ankle.
            assert!(p(J::LToe).x > p(J::LAnkle).x && p(J::RToe).x > p(J::RAnkle).x);
            let mid = (p(J::LHip) + p(J::RHip)) / 2.0;
            assert!((p(J::MidHip) - mid).norm() < 1e-12, "MidHip derived");
        }
    }
    let wave = read_clip(WAVE);
    let above = |j| {
        wave.iter()
            .any(|f| f.get(j).unwrap().z > f.get(J::Head).unwrap().z)
    };
    assert!(above(J::RHand));
    assert!(!above(J::LHand));
}

#[test]
fn synthetic_line_maps_positions_and_states() {
    let mut states = [2u8; 25];
    states[13] = 0; // KneeLeft not tracked
    states[17] = 1; // KneeRight inferred
    let text = line(1_000_000, states) + &line(1_330_000, [2; 25]);
    let frames = parse_str(&text, KinectConfig::default()).unwrap();
    assert_eq!(frames.len(), 2);
    assert_eq!(frames[0].time, 0.0);
    assert!((frames[1].time - 0.033).abs() < 1e-12);
    // SpineBase (k = 0) at camera (0, 10, 100) → (−100, −0, 10).
    assert_eq!(
        frames[0].get(J::Pelvis).unwrap(),
        nalgebra::Vector3::new(-100.0, -0.0, 10.0)
    );
    // SpineShoulder (k = 20) at camera (20, 30, 120) → (−120, −20, 30).
    assert_eq!(
        frames[0].get(J::MidShoulder).unwrap(),
        nalgebra::Vector3::new(-120.0, -20.0, 30.0)
    );
    assert_eq!(frames[0].get(J::LKnee), None);
    assert!(frames[0].get(J::RKnee).is_some());
    assert!(frames[1].get(J::LKnee).is_some());
    let strict = KinectConfig {
        keep_inferred: false,
        ..KinectConfig::default()
    };
    let frames = parse_str(&text, strict).unwrap();
    assert_eq!(frames[0].get(J::RKnee), None);
    // Without the trailing comma and with blank lines the lines still parse.
    let text = line(5, [2; 25]).replace(",\n", "\n\n\n") + &line(6, [2; 25]);
    assert_eq!(parse_str(&text, KinectConfig::default()).unwrap().len(), 2);
}

fn error_of(text: &str) -> KinectError {
    parse_str(text, KinectConfig::default()).unwrap_err()
}

#[test]
fn wrong_field_count_is_reported_with_its_line() {
    let short = line(2, [2; 25]).replacen(",0,10,100,2", "", 1);
    let text = line(1, [2; 25]) + &short;
    let e = error_of(&text);
    assert!(
        matches!(
            e,
            KinectError::FieldCount {
                line: 2,
                expected: KINECT_FIELDS,
                found: 97,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().starts_with("test.csv:2:"), "{e}");
}

#[test]
fn bad_values_are_reported_with_their_field() {
    // Field 1 + 4·13 + 2 = 55 is KneeLeft Y.
    let text = line(1, [2; 25]).replace(",13,23,113,", ",13,x23,113,");
    let e = error_of(&text);
    assert!(
        matches!(&e, KinectError::Value { line: 1, field: 55, what, text, .. }
            if what == "KneeLeft Y" && text == "x23"),
        "{e:?}"
    );
    let mut states = [2u8; 25];
    states[3] = 7;
    assert!(matches!(
        error_of(&line(1, states)),
        KinectError::Value { field: 17, .. }
    ));
    let text = line(1, [2; 25]).replace(",13,23,113,", ",13,NaN,113,");
    assert!(matches!(
        error_of(&text),
        KinectError::Value { field: 55, .. }
    ));
}

#[test]
fn time_going_back_or_overflowing_is_reported() {
    let text = line(10, [2; 25]) + &line(5, [2; 25]);
    assert!(matches!(
        error_of(&text),
        KinectError::TimeGoesBack { line: 2, .. }
    ));
    // (1e308 − (−1e308))·1e−7 overflows to infinity.
    let text =
        line(1, [2; 25]).replacen('1', "-1e308", 1) + &line(1, [2; 25]).replacen('1', "1e308", 1);
    assert!(matches!(
        error_of(&text),
        KinectError::Value {
            line: 2,
            field: 1,
            ..
        }
    ));
}

#[test]
fn overlong_lines_are_refused() {
    let config = KinectConfig {
        max_line_bytes: 100,
        ..KinectConfig::default()
    };
    let e = parse_str(&line(1, [2; 25]), config).unwrap_err();
    assert!(matches!(
        e,
        KinectError::LineTooLong {
            line: 1,
            limit: 100,
            ..
        }
    ));
}

fn small_real_file() -> String {
    let text = std::fs::read_to_string(format!("{DATA}{WAVE}")).unwrap();
    text.lines().take(4).map(|l| format!("{l}\n")).collect()
}

fn read_all(bytes: Vec<u8>) {
    for frame in KinectReader::new(Cursor::new(bytes), "fuzz.csv", KinectConfig::default()) {
        match frame {
            Ok(f) => assert!(
                f.time.is_finite()
                    && f.joints()
                        .all(|(_, p)| p.is_none_or(|p| p.iter().all(|c| c.is_finite())))
            ),
            Err(e) => assert!(e.to_string().starts_with("fuzz.csv")),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn truncated_files_never_panic(cut in 0.0f64..1.0) {
        let text = small_real_file();
        read_all(text.as_bytes()[..(cut * text.len() as f64) as usize].to_vec());
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
        "1e308", "-1e308", "9999999999999999999999999", "1e-320", "nan", "-inf", "",
    ])) {
        let text = small_real_file();
        let mut fields: Vec<&str> = text.split(',').collect();
        let k = ((at * fields.len() as f64) as usize).min(fields.len() - 1);
        fields[k] = huge;
        read_all(fields.join(",").into_bytes());
    }
}
