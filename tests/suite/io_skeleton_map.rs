//! BVH clips with a skeleton of their own, read through a skeleton map file: a CMU clip whose
//! joints were renamed reads back the frames the built-in CMU names give; bad maps are errors
//! naming the field.

use taskstack::io::clip::Clip;
use taskstack::io::skeleton_map::{SkeletonMap, SkeletonMapError};

const CLIP: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"
);

/// The CMU-MB names this test maps, as `HumanJoint name = BVH name`.
const PAIRS: [(&str, &str); 20] = [
    ("Pelvis", "Hips"),
    ("LHip", "LeftUpLeg"),
    ("RHip", "RightUpLeg"),
    ("LKnee", "LeftLeg"),
    ("RKnee", "RightLeg"),
    ("LAnkle", "LeftFoot"),
    ("RAnkle", "RightFoot"),
    ("LToe", "LeftToeBase"),
    ("RToe", "RightToeBase"),
    ("MidShoulder", "Spine1"),
    ("Neck", "Neck1"),
    ("Head", "Head"),
    ("LShoulder", "LeftArm"),
    ("RShoulder", "RightArm"),
    ("LElbow", "LeftForeArm"),
    ("RElbow", "RightForeArm"),
    ("LWrist", "LeftHand"),
    ("RWrist", "RightHand"),
    ("LHand", "LeftHandIndex1"),
    ("RHand", "RightHandIndex1"),
];

/// The clip with every joint renamed `X` → `my_X`, so that the CMU name tables no longer match.
fn renamed_clip(dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(CLIP).unwrap();
    let renamed: String = text
        .lines()
        .map(|line| {
            let trimmed = line.trim_start();
            for keyword in ["ROOT ", "JOINT "] {
                if let Some(name) = trimmed.strip_prefix(keyword) {
                    let indent = &line[..line.len() - trimmed.len()];
                    return format!("{indent}{keyword}my_{name}\n");
                }
            }
            format!("{line}\n")
        })
        .collect();
    let path = dir.join("renamed.bvh");
    std::fs::write(&path, renamed).unwrap();
    path
}

fn map_text(skip: usize) -> String {
    let joints: String = PAIRS
        .iter()
        .map(|(human, bvh)| format!("{human} = \"my_{bvh}\"\n"))
        .collect();
    format!("scale = 0.056444\nup = \"y\"\nskip_frames = {skip}\n[joints]\n{joints}")
}

#[test]
fn a_renamed_skeleton_reads_back_the_cmu_frames() {
    let dir = std::env::temp_dir().join(format!("taskstack-skeleton-map-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let clip = renamed_clip(&dir);
    // Without a map the renamed skeleton is unknown.
    assert!(Clip::open(&clip).is_err());
    let map_path = dir.join("map.toml");
    // The CMU-MB release starts with a T-pose frame, which `Clip::open` skips.
    std::fs::write(&map_path, map_text(1)).unwrap();
    let map = SkeletonMap::from_toml_file(&map_path).unwrap();
    let mapped: Vec<_> = Clip::open_mapped(&clip, &map)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    let reference: Vec<_> = Clip::open(CLIP).unwrap().collect::<Result<_, _>>().unwrap();
    assert_eq!(mapped.len(), reference.len());
    assert!(mapped.len() > 100);
    for (a, b) in mapped.iter().zip(&reference) {
        assert_eq!(a, b, "frame at {} s", b.time);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

fn invalid_field(text: &str) -> String {
    match SkeletonMap::from_toml_str(text, "map.toml") {
        Err(SkeletonMapError::Invalid { field, .. }) => field,
        other => panic!("expected an invalid field, got {other:?}"),
    }
}

#[test]
fn bad_maps_name_the_field() {
    assert_eq!(invalid_field("[joints]\nLElbw = \"a\"\n"), "joints.LElbw");
    assert_eq!(
        invalid_field("[joints]\nLElbow = \"a\"\nRElbow = \"a\"\n"),
        "joints.RElbow"
    );
    assert_eq!(
        invalid_field("scale = -1.0\n[joints]\nHead = \"h\"\n"),
        "scale"
    );
    assert_eq!(invalid_field("up = \"x\"\n[joints]\nHead = \"h\"\n"), "up");
    assert_eq!(invalid_field("[joints]\n"), "joints");
    assert!(matches!(
        SkeletonMap::from_toml_str("scael = 1.0\n[joints]\nHead = \"h\"\n", "map.toml"),
        Err(SkeletonMapError::Syntax { .. })
    ));
    assert!(matches!(
        SkeletonMap::from_toml_file("/no/such/map.toml"),
        Err(SkeletonMapError::Io { .. })
    ));
}
