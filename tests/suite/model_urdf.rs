//! The URDF loader (`model::urdf`): options, and each malformed URDF rejected with an error naming
//! the joint, link or frame.

use nalgebra::IsometryMatrix3;
use taskstack::model::{Model, UrdfError, UrdfFrame, UrdfOptions};
use taskstack::robots::nao;

const TREE: &str = include_str!("../data/tree.urdf");
const NAO: &str = include_str!("../data/nao.urdf");

fn load(text: &str) -> Result<Model, UrdfError> {
    Model::from_urdf_str(text, &UrdfOptions::default())
}

fn load_with(options: UrdfOptions) -> Result<Model, UrdfError> {
    Model::from_urdf_str(TREE, &options)
}

#[test]
fn unknown_root_link() {
    let err = load_with(UrdfOptions {
        root_link: Some("flange".into()),
        ..UrdfOptions::default()
    })
    .unwrap_err();
    assert_eq!(err, UrdfError::UnknownRootLink("flange".into()));
    assert!(err.to_string().contains("flange"));
}

#[test]
fn unknown_mimic_target() {
    let text = TREE.replace(r#"<mimic joint="j1""#, r#"<mimic joint="j9""#);
    let err = load(&text).unwrap_err();
    assert_eq!(
        err,
        UrdfError::UnknownMimicTarget {
            joint: "m4".into(),
            target: "j9".into()
        }
    );
    assert!(err.to_string().contains("m4") && err.to_string().contains("j9"));
}

#[test]
fn mimic_of_a_fixed_joint() {
    let text = TREE.replace(r#"<mimic joint="j1""#, r#"<mimic joint="tool_fixed""#);
    assert_eq!(
        load(&text).unwrap_err(),
        UrdfError::BadMimicTarget {
            joint: "m4".into(),
            target: "tool_fixed".into()
        }
    );
}

#[test]
fn unknown_locked_joint() {
    let err = load_with(UrdfOptions {
        locked_joints: vec![("gripper".into(), 0.0)],
        ..UrdfOptions::default()
    })
    .unwrap_err();
    assert_eq!(err, UrdfError::UnknownLockedJoint("gripper".into()));
}

#[test]
fn locking_a_joint_locks_its_mimics() {
    let model = load_with(UrdfOptions {
        locked_joints: vec![("j1".into(), 0.4)],
        ..UrdfOptions::default()
    })
    .unwrap();
    let names: Vec<&str> = model.variables().iter().map(|v| v.name.as_str()).collect();
    assert_eq!(names, ["slide", "j3", "j5"]);
    // j1 and its mimic m4 are folded: base+link1 and link3+link4+tool are single bodies.
    assert_eq!(model.links().len(), 5);
}

#[test]
fn non_finite_number() {
    let text = TREE.replace(
        r#"<origin xyz="0.2 0.05 0" rpy="0 0 0.5"/>"#,
        r#"<origin xyz="0.2 nan 0" rpy="0 0 0.5"/>"#,
    );
    let err = load(&text).unwrap_err();
    assert!(
        matches!(err, UrdfError::NonFinite { ref place, value } if place == "joint `j3` origin" && value.is_nan()),
        "{err}"
    );
    let text = TREE.replace(r#"<mass value="0.3"/>"#, r#"<mass value="inf"/>"#);
    let err = load(&text).unwrap_err();
    assert!(
        matches!(err, UrdfError::NonFinite { ref place, .. } if place == "link `link2` mass"),
        "{err}"
    );
}

#[test]
fn negative_mass() {
    let text = TREE.replace(r#"<mass value="0.3"/>"#, r#"<mass value="-0.3"/>"#);
    assert_eq!(
        load(&text).unwrap_err(),
        UrdfError::NegativeMass {
            link: "link2".into(),
            mass: -0.3
        }
    );
}

#[test]
fn malformed_xml_and_missing_field() {
    let err = load("<robot name=\"x\"><link name=\"a\"></robot>").unwrap_err();
    assert!(matches!(err, UrdfError::Xml(_)), "{err}");
    // A joint without <parent>.
    let text = TREE.replace(
        r#"<parent link="link1"/><child link="link2"/>"#,
        r#"<child link="link2"/>"#,
    );
    assert!(matches!(load(&text).unwrap_err(), UrdfError::Xml(_)));
}

#[test]
fn unknown_link_two_parents_and_loops() {
    let text = TREE.replace(r#"<parent link="link3"/>"#, r#"<parent link="link9"/>"#);
    assert_eq!(
        load(&text).unwrap_err(),
        UrdfError::UnknownJointLink {
            joint: "m4".into(),
            link: "link9".into()
        }
    );
    let text = TREE.replace(r#"<child link="hand2"/>"#, r#"<child link="link2"/>"#);
    assert_eq!(
        load(&text).unwrap_err(),
        UrdfError::TwoParents {
            link: "link2".into(),
            first: "slide".into(),
            second: "m6".into()
        }
    );
    // Re-parenting (hand2 under link4, arm2 under hand2) still gives a tree; `tool` is folded.
    let text = TREE
        .replace(
            r#"<parent link="arm2"/><child link="hand2"/>"#,
            r#"<parent link="link4"/><child link="hand2"/>"#,
        )
        .replace(
            r#"<parent link="base"/><child link="arm2"/>"#,
            r#"<parent link="hand2"/><child link="arm2"/>"#,
        );
    let model = load(&text).unwrap();
    assert_eq!(model.links().len(), 8 - 1);
    let looped = TREE.replace(
        r#"<parent link="base"/><child link="link1"/>"#,
        r#"<parent link="link4"/><child link="link1"/>"#,
    );
    let err = Model::from_urdf_str(
        &looped,
        &UrdfOptions {
            root_link: Some("base".into()),
            ..UrdfOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, UrdfError::NotATree(_)), "{err}");
}

#[test]
fn variable_order_and_frames() {
    let order = |names: &[&str]| UrdfOptions {
        variable_order: Some(names.iter().map(|s| s.to_string()).collect()),
        ..UrdfOptions::default()
    };
    let model = load_with(order(&["j5", "j3", "slide", "j1"])).unwrap();
    assert_eq!(model.variables()[0].name, "j5");
    assert_eq!(
        load_with(order(&["j5", "j3", "slide", "m4"])).unwrap_err(),
        UrdfError::UnknownVariable("m4".into())
    );
    assert_eq!(
        load_with(order(&["j5", "j3", "slide"])).unwrap_err(),
        UrdfError::MissingVariable("j1".into())
    );
    let frame = |name: &str, link: &str| UrdfFrame {
        name: name.into(),
        link: link.into(),
        placement: IsometryMatrix3::identity(),
    };
    let err = load_with(UrdfOptions {
        frames: vec![frame("tip", "link7")],
        ..UrdfOptions::default()
    })
    .unwrap_err();
    assert_eq!(
        err,
        UrdfError::UnknownFrameLink {
            frame: "tip".into(),
            link: "link7".into()
        }
    );
    let err = load_with(UrdfOptions {
        frames: vec![frame("tool", "link4")],
        ..UrdfOptions::default()
    })
    .unwrap_err();
    assert_eq!(err, UrdfError::DuplicateFrame("tool".into()));
}

#[test]
fn nao_urdf_locks_hands_and_fingers_and_reads_from_a_file() {
    let model = nao::from_urdf_file("tests/data/nao.urdf", Some("r_sole")).unwrap();
    assert_eq!(model.nv(), 23);
    // Bodies: torso, neck, head, 2 × 6 leg links, 2 × 5 arm links = 25 (grippers, fingers, soles
    // and sensor frames are folded into them).
    assert_eq!(model.links().len(), 25);
    assert_eq!(model.links()[0].name, "r_sole");
    // Explicitly locking the finger mimics as well is accepted.
    let mut options = nao::urdf_options(None);
    options.locked_joints.push(("LFinger21".into(), 0.0));
    assert_eq!(Model::from_urdf_str(NAO, &options).unwrap().nv(), 23);
    let err = nao::from_urdf_file("tests/data/missing.urdf", None).unwrap_err();
    assert!(matches!(err, UrdfError::Io { ref path, .. } if path == "tests/data/missing.urdf"));
}

#[test]
fn fixed_links_fold_mass_com_and_inertia() {
    // Two 1 kg bodies 1 m apart along x, each with inertia diag(0.1, 0.2, 0.3) about its CoM; the
    // second is turned 90° about z, so in the first's axes its inertia is diag(0.2, 0.1, 0.3).
    // Merged: 2 kg at (0.5, 0, 0); each body is 0.5 m from it along x, adding
    // m (|d|² 1 − d dᵀ) = diag(0, 0.25, 0.25) each: I = diag(0.3, 0.8, 1.1).
    let urdf = r#"<robot name="pair">
        <link name="a"><inertial><mass value="1"/>
            <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial></link>
        <link name="b"><inertial><mass value="1"/>
            <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial></link>
        <joint name="weld" type="fixed"><parent link="a"/><child link="b"/>
            <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/></joint></robot>"#;
    let model = load(urdf).unwrap();
    assert_eq!(model.links().len(), 1);
    let link = &model.links()[0];
    assert_eq!(link.mass, 2.0);
    assert!((link.com - nalgebra::Vector3::new(0.5, 0.0, 0.0)).norm() < 1e-15);
    let expected = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(0.3, 0.8, 1.1));
    assert!(
        (link.inertia.unwrap() - expected).amax() < 1e-15,
        "{}",
        link.inertia.unwrap()
    );
    // Rooted at `b` (x_b = y_a, y_b = −x_a): a's origin, −1 m along x_a, is +1 m along y_b, so the
    // CoM is at (0, 0.5, 0) in b.
    let at_b = Model::from_urdf_str(
        urdf,
        &UrdfOptions {
            root_link: Some("b".into()),
            ..UrdfOptions::default()
        },
    )
    .unwrap();
    assert!((at_b.links()[0].com - nalgebra::Vector3::new(0.0, 0.5, 0.0)).norm() < 1e-15);
    // In b's axes the same sums give diag(0.1 + 0.2 + 0.5, 0.2 + 0.1, 0.3 + 0.3 + 0.5).
    let expected = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(0.8, 0.3, 1.1));
    assert!((at_b.links()[0].inertia.unwrap() - expected).amax() < 1e-15);
}

/// `TREE` behind a free base: a `floating` joint from a massless `world` link to `base`.
fn tree_on_free_base() -> String {
    TREE.replace(
        r#"<robot name="test_tree">"#,
        r#"<robot name="test_tree"><link name="world"/>
        <joint name="free" type="floating"><parent link="world"/><child link="base"/></joint>"#,
    )
}

#[test]
fn a_free_base_is_dropped_and_its_child_is_the_default_root() {
    let plain = load(TREE).unwrap();
    let floating = load(&tree_on_free_base()).unwrap();
    assert_eq!(floating, plain);
    // Rooted elsewhere, the same: the world link and its joint are gone, not re-rooted.
    let at = |text: &str| {
        Model::from_urdf_str(
            text,
            &UrdfOptions {
                root_link: Some("tool".into()),
                ..UrdfOptions::default()
            },
        )
        .unwrap()
    };
    assert_eq!(at(&tree_on_free_base()), at(TREE));
    let err = Model::from_urdf_str(
        &tree_on_free_base(),
        &UrdfOptions {
            root_link: Some("world".into()),
            ..UrdfOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(err, UrdfError::UnknownRootLink("world".into()));
}

#[test]
fn a_floating_joint_inside_the_tree_is_refused() {
    // Between two links with mass it is a real 6-DoF joint, which a fixed-base tree cannot hold.
    let text = TREE.replacen(r#"type="revolute""#, r#"type="floating""#, 1);
    let err = load(&text).unwrap_err();
    assert!(
        matches!(&err, UrdfError::UnsupportedJointType { kind, .. } if kind == "floating"),
        "{err:?}"
    );
    // A world link with mass is a body, not a stand-in for the world.
    let heavy = tree_on_free_base().replace(
        r#"<link name="world"/>"#,
        r#"<link name="world"><inertial><mass value="1.0"/>
        <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>"#,
    );
    let err = load(&heavy).unwrap_err();
    assert_eq!(
        err,
        UrdfError::UnsupportedJointType {
            joint: "free".into(),
            kind: "floating".into()
        }
    );
}
