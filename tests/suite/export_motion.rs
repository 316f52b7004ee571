//! The motion export (`taskstack::export`): the floating base's pose and the joint angles
//! rebuild the robot, resampling interpolates as the hand calculation says, and `motion.npz`
//! is a zip of `.npy` files laid out as numpy's format description says.

use std::path::PathBuf;

use nalgebra::{IsometryMatrix3, Quaternion, Translation3, UnitQuaternion, Vector3};
use taskstack::batch::imitate_clip;
use taskstack::export::{
    ExportError, MotionRecorder, MotionTrack, NpyArray, write_motion_npz, write_npz,
};
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::io::clip::Clip;
use taskstack::model::Model;
use taskstack::robots::{BipedProfile, g1, nao};
use taskstack::{Imitator, ImitatorConfig};

fn mocap(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/mocap")
        .join(name)
}

/// The motion of `clip` on `profile` (default settings, 1 s hold) and each frame's sole
/// placements as the imitator reported them, `[left, right]`.
fn record(profile: BipedProfile, clip: &str) -> (MotionTrack, Vec<[IsometryMatrix3<f64>; 2]>) {
    let path = mocap(clip);
    let source = Clip::open(&path).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(source.capture()),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(profile, config).unwrap();
    let mut recorder = MotionRecorder::new(&imitator).unwrap();
    let mut soles = Vec::new();
    let mut failed = None;
    imitate_clip(&path, source, &mut imitator, 1.0, |frame| {
        if let Err(e) = recorder.record(frame) {
            failed.get_or_insert(e.to_string());
        }
        soles.push([frame.left_sole, frame.right_sole]);
    })
    .unwrap();
    assert_eq!(failed, None);
    (recorder.finish(), soles)
}

/// Rebuilds each sole from the exported base pose and joint angles with `base_model` (a
/// model rooted at the floating base, built independently of the imitator's sole-rooted
/// models) and checks it against the imitator's soles (within `tolerance`, m), and that a sole
/// the export says is on the floor is within 1 mm of it, and that a sole flat on the floor
/// (within 1 µm) does not move while it stays there.
fn check_rebuild(
    track: &MotionTrack,
    soles: &[[IsometryMatrix3<f64>; 2]],
    base_model: &Model,
    sole_frames: [&str; 2],
    tolerance: f64,
) {
    assert_eq!(track.len(), soles.len());
    let columns: Vec<usize> = (base_model.variables().iter())
        .map(|v| {
            track
                .joint_names
                .iter()
                .position(|n| *n == v.name)
                .expect("joint exported")
        })
        .collect();
    let ids = sole_frames.map(|f| base_model.frame_id(f).unwrap());
    let mut data = base_model.new_data();
    let mut standing: [Option<Vector3<f64>>; 2] = [None, None];
    let mut stood = [0usize; 2];
    for i in 0..track.len() {
        let q: Vec<f64> = columns.iter().map(|&c| track.joints(i)[c]).collect();
        base_model.forward_kinematics(&mut data, &q).unwrap();
        let [x, y, z] = track.root_pos[i];
        let [qx, qy, qz, qw] = track.root_quat[i];
        let unit = UnitQuaternion::from_quaternion(Quaternion::new(qw, qx, qy, qz));
        assert!((unit.into_inner().norm() - 1.0).abs() < 1e-12);
        let world_t_base =
            IsometryMatrix3::from_parts(Translation3::new(x, y, z), unit.to_rotation_matrix());
        for side in 0..2 {
            let sole = world_t_base * data.frame_placement(ids[side]);
            let expected = soles[i][side];
            let gap = (sole.translation.vector - expected.translation.vector).norm();
            assert!(
                gap <= tolerance,
                "frame {i} sole {side}: {gap} m from the imitator's"
            );
            let p = sole.translation.vector;
            if track.contacts[i][side] {
                assert!(
                    p.z.abs() <= 1e-3,
                    "frame {i} sole {side} on the floor at z = {}",
                    p.z
                );
            }
            // Flat on the floor (not lifting or landing through the contact band): it stays.
            if p.z.abs() <= 1e-6 {
                let start = *standing[side].get_or_insert(p);
                let moved = (p - start).norm();
                assert!(
                    moved <= 1e-4,
                    "frame {i}: standing sole {side} moved {moved} m"
                );
                stood[side] += 1;
            } else {
                standing[side] = None;
            }
        }
    }
    assert!(
        stood.iter().all(|&n| n > track.len() / 2),
        "the feet stood: {stood:?}"
    );
}

#[test]
fn the_nao_base_pose_rebuilds_the_soles_with_the_urdf_model() {
    let (track, soles) = record(
        nao::profile(),
        "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh",
    );
    let urdf = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/nao.urdf");
    let torso = nao::from_urdf_file(urdf, Some("torso")).unwrap();
    // The URDF and the DH tables are two derivations of the NAO; their legs agree to 0.1 mm.
    check_rebuild(&track, &soles, &torso, ["l_sole", "r_sole"], 1e-4);
    // One frame on one leg at least (05_02 stands on the right leg).
    assert!(track.contacts.iter().any(|c| c == &[false, true]));
}

#[test]
fn the_g1_base_pose_rebuilds_the_soles_with_the_pelvis_model() {
    let (track, soles) = record(g1::profile(), "kinect2_labanotation_ges01_wavehand.csv");
    check_rebuild(
        &track,
        &soles,
        &g1::pelvis(),
        ["left_sole", "right_sole"],
        1e-9,
    );
    assert_eq!(track.joint_names, g1::VARIABLES);
}

#[test]
fn the_first_frame_stands_with_its_right_sole_at_the_origin_and_the_base_up() {
    let (track, soles) = record(
        nao::profile(),
        "cmu_02_10_wash_self_standing_arm_gestures.bvh",
    );
    let right = soles[0][1].translation.vector;
    assert!(right.norm() < 1e-9, "first right sole at {right:?}");
    assert_eq!(track.contacts[0], [true, true]);
    // The NAO's torso origin stands about 0.33 m over the soles (0.32 with the knees bent).
    let z = track.root_pos[0][2];
    assert!((0.28..0.34).contains(&z), "torso at {z} m");
    // Upright: the base's z axis within 10° of the vertical.
    let [qx, qy, qz, qw] = track.root_quat[0];
    let up = UnitQuaternion::from_quaternion(Quaternion::new(qw, qx, qy, qz)) * Vector3::z();
    assert!(up.z > 10f64.to_radians().cos());
}

/// A three-frame track by hand: frames at 0, 0.1 and 0.25 s.
fn hand_track() -> MotionTrack {
    let half_turn =
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
    MotionTrack {
        joint_names: vec!["a".into(), "b".into()],
        time: vec![0.0, 0.1, 0.25],
        dof_pos: vec![0.0, 1.0, 1.0, 3.0, 4.0, 3.0],
        root_pos: vec![[0.0; 3], [0.1, 0.0, 0.3], [0.4, 0.0, 0.3]],
        root_quat: vec![
            [0.0, 0.0, 0.0, 1.0],
            [half_turn.i, half_turn.j, half_turn.k, half_turn.w],
            [half_turn.i, half_turn.j, half_turn.k, half_turn.w],
        ],
        contacts: vec![[true, true], [true, false], [false, true]],
    }
}

#[test]
fn resampling_interpolates_between_the_frames_around_each_sample() {
    let track = hand_track();
    // 20 Hz: samples at 0, 0.05, 0.1, 0.15, 0.2 (0.25 is the last frame's time: included).
    let r = track.resampled(20.0).unwrap();
    assert_eq!(r.len(), 6);
    assert_eq!(r.joints(0), &[0.0, 1.0]);
    // 0.05 s: half-way between frames 0 and 1.
    assert!((r.joints(1)[0] - 0.5).abs() < 1e-12 && (r.joints(1)[1] - 2.0).abs() < 1e-12);
    assert!((r.root_pos[1][0] - 0.05).abs() < 1e-12 && (r.root_pos[1][2] - 0.15).abs() < 1e-12);
    // Half-way along the arc from no turn to a quarter turn about z: an eighth of a turn.
    let [qx, qy, qz, qw] = r.root_quat[1];
    let eighth = (std::f64::consts::PI / 8.0).sin();
    assert!(qx.abs() < 1e-12 && qy.abs() < 1e-12 && (qz - eighth).abs() < 1e-12 && qw > 0.0);
    assert_eq!(r.contacts[1], [true, true], "the earlier frame's contacts");
    // 0.1 s falls on frame 1: its values exactly.
    assert_eq!(r.joints(2), track.joints(1));
    // 0.2 s: two thirds of the way from frame 1 (0.1 s) to frame 2 (0.25 s).
    assert!((r.joints(4)[0] - (1.0 + 3.0 * 2.0 / 3.0)).abs() < 1e-12);
    assert!((r.root_pos[4][0] - 0.3).abs() < 1e-12);
    assert_eq!(r.contacts[4], [true, false]);
    assert_eq!(r.joints(5), track.joints(2));
    assert!(matches!(track.resampled(0.0), Err(ExportError::Rate(_))));
    assert!(matches!(
        track.resampled(f64::NAN),
        Err(ExportError::Rate(_))
    ));
    assert!(matches!(
        MotionTrack::default().resampled(30.0),
        Err(ExportError::Empty)
    ));
}

/// Little-endian integer of `bytes[at..at + n]`.
fn le(bytes: &[u8], at: usize, n: usize) -> u64 {
    (0..n).map(|k| u64::from(bytes[at + k]) << (8 * k)).sum()
}

/// The `(name, stored bytes)` of each entry of a zip archive without compression, read through
/// its end record and central directory (zip's APPNOTE 4.3).
fn zip_entries(zip: &[u8]) -> Vec<(String, Vec<u8>)> {
    let end = zip.len() - 22;
    assert_eq!(
        le(zip, end, 4),
        0x0605_4b50,
        "end of central directory record"
    );
    let count = le(zip, end + 10, 2) as usize;
    let mut at = le(zip, end + 16, 4) as usize;
    let mut entries = Vec::new();
    for _ in 0..count {
        assert_eq!(le(zip, at, 4), 0x0201_4b50, "central directory header");
        assert_eq!(le(zip, at + 10, 2), 0, "stored");
        let size = le(zip, at + 20, 4) as usize;
        assert_eq!(le(zip, at + 24, 4) as usize, size);
        let name_len = le(zip, at + 28, 2) as usize;
        let name = String::from_utf8(zip[at + 46..at + 46 + name_len].to_vec()).unwrap();
        let local = le(zip, at + 42, 4) as usize;
        assert_eq!(le(zip, local, 4), 0x0403_4b50, "local file header");
        let data = local + 30 + le(zip, local + 26, 2) as usize + le(zip, local + 28, 2) as usize;
        entries.push((name, zip[data..data + size].to_vec()));
        at += 46 + name_len;
    }
    entries
}

/// The header text and the data of an `.npy` file (format 1.0).
fn npy(bytes: &[u8]) -> (String, &[u8]) {
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = le(bytes, 8, 2) as usize;
    assert_eq!((10 + len) % 64, 0, "header padded to 64 bytes");
    let header = String::from_utf8(bytes[10..10 + len].to_vec()).unwrap();
    assert!(header.ends_with('\n'));
    (header.trim_end().to_owned(), &bytes[10 + len..])
}

#[test]
fn npz_entries_are_npy_files_with_numpy_headers() {
    let mut zip = Vec::new();
    let names = vec!["ab".to_owned(), "Ünï".to_owned(), String::new()];
    write_npz(
        &mut zip,
        &[
            (
                "scalar",
                NpyArray::F64 {
                    shape: &[],
                    data: &[120.0],
                },
            ),
            (
                "grid",
                NpyArray::F64 {
                    shape: &[2, 3],
                    data: &[1.0, 2.0, 3.0, 4.0, 5.0, 6.5],
                },
            ),
            (
                "flags",
                NpyArray::Bool {
                    shape: &[2],
                    data: &[true, false],
                },
            ),
            ("names", NpyArray::Str(&names)),
        ],
    )
    .unwrap();
    let entries = zip_entries(&zip);
    let names_read: Vec<&str> = entries.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names_read,
        ["scalar.npy", "grid.npy", "flags.npy", "names.npy"]
    );
    let (h, d) = npy(&entries[0].1);
    assert_eq!(h, "{'descr': '<f8', 'fortran_order': False, 'shape': (), }");
    assert_eq!(d, 120f64.to_le_bytes());
    let (h, d) = npy(&entries[1].1);
    assert_eq!(
        h,
        "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"
    );
    assert_eq!(d.len(), 48);
    assert_eq!(&d[40..48], 6.5f64.to_le_bytes());
    let (h, d) = npy(&entries[2].1);
    assert_eq!(
        h,
        "{'descr': '|b1', 'fortran_order': False, 'shape': (2,), }"
    );
    assert_eq!(d, [1, 0]);
    let (h, d) = npy(&entries[3].1);
    assert_eq!(
        h,
        "{'descr': '<U3', 'fortran_order': False, 'shape': (3,), }"
    );
    // UTF-32LE, three code points per string, zero-padded.
    assert_eq!(d.len(), 36);
    assert_eq!(&d[12..16], u32::from('Ü').to_le_bytes());
    assert!(d[24..].iter().all(|&b| b == 0));
    // A shape the data does not fill is refused.
    let bad = write_npz(
        Vec::new(),
        &[(
            "x",
            NpyArray::F64 {
                shape: &[3],
                data: &[1.0],
            },
        )],
    );
    assert!(bad.is_err());
}

#[test]
fn motion_npz_holds_the_documented_arrays() {
    let mut zip = Vec::new();
    write_motion_npz(&mut zip, &hand_track(), 10.0).unwrap();
    let entries = zip_entries(&zip);
    let header = |name: &str| {
        let (_, bytes) = entries
            .iter()
            .find(|(n, _)| n == &format!("{name}.npy"))
            .unwrap();
        npy(bytes).0
    };
    let shape = |name: &str| {
        let h = header(name);
        h[h.find("'shape': ").unwrap() + 9..h.rfind(',').unwrap()].to_owned()
    };
    // 10 Hz over 0.25 s: samples at 0, 0.1, 0.2.
    assert_eq!(shape("fps"), "()");
    assert_eq!(shape("time"), "(3,)");
    assert_eq!(shape("dof_pos"), "(3, 2)");
    assert_eq!(shape("root_pos"), "(3, 3)");
    assert_eq!(shape("root_quat"), "(3, 4)");
    assert_eq!(shape("contacts"), "(3, 2)");
    assert_eq!(shape("joint_names"), "(2,)");
    assert!(header("contacts").contains("'|b1'"));
}
