//! Scenes of planar surfaces: the file format, its refusals, and the distances the contact pass
//! uses, checked against hand calculations.

use taskstack::Vector3;
use taskstack::scene::{Scene, SceneError, Surface};

#[test]
fn a_turned_rectangle_measures_how_far_a_point_lies_beyond_its_edges() {
    // 0.8 × 1.2 m turned by 90°: it spans x ∈ [0, 1.2] and y ∈ [-0.4, 0.4] around (0.6, 0).
    let table = Surface::rectangle("table", [0.6, 0.0], [0.8, 1.2], 90.0, 0.72).unwrap();
    let at = |x, y| table.outside_distance(&Vector3::new(x, y, 0.8));
    assert!(at(0.6, 0.0).abs() < 1e-12);
    assert!(at(1.19, 0.39).abs() < 1e-12, "inside near a corner");
    assert!((at(1.5, 0.0) - 0.3).abs() < 1e-12, "beyond the end");
    assert!((at(0.6, 0.7) - 0.3).abs() < 1e-12, "beyond the side");
    assert!(
        (at(1.5, 0.8) - 0.5).abs() < 1e-12,
        "beyond the corner: hypot(0.3, 0.4)"
    );
    assert!((table.height_above(&Vector3::new(0.0, 0.0, 0.8)) - 0.08).abs() < 1e-12);
    let floor = Surface::plane("floor", 0.0).unwrap();
    assert_eq!(
        floor.outside_distance(&Vector3::new(100.0, -50.0, 1.0)),
        0.0
    );
}

#[test]
fn the_file_format_reads_every_field_and_refuses_mistakes() {
    let scene = Scene::from_toml_str(
        "[[surface]]\nname = \"floor\"\nheight = 0.0\n\
         [[surface]]\nname = \"table\"\ncentre = [0.6, 0.0]\nsize = [0.8, 1.2]\nyaw = 90.0\nheight = 0.72\n",
    )
    .unwrap();
    assert_eq!(scene.surfaces().len(), 2);
    assert!(scene.surfaces()[0].is_unbounded());
    assert_eq!(scene.index_of("table"), Some(1));
    assert_eq!(scene.surfaces()[1].height(), 0.72);
    let refused = |text: &str| Scene::from_toml_str(text).unwrap_err();
    let syntax = refused("[[surface]]\nname = \"t\"\nheight = 0.7\ncolour = \"red\"\n");
    assert!(matches!(&syntax, SceneError::Syntax { message, .. } if message.contains("colour")));
    assert!(matches!(
        refused("[[surface]]\nname = \"t\"\nheight = 0.7\nsize = [0.5, -0.1]\n"),
        SceneError::Invalid { surface, .. } if surface == "t"
    ));
    assert!(matches!(
        refused("[[surface]]\nname = \"t\"\nheight = nan\n"),
        SceneError::Invalid { .. }
    ));
    assert!(matches!(
        refused("[[surface]]\nname = \"a\"\nheight = 0.0\n[[surface]]\nname = \"a\"\nheight = 0.5\nsize = [1.0, 1.0]\n"),
        SceneError::Invalid { reason, .. } if reason.contains("name")
    ));
    assert!(matches!(
        refused("[[surface]]\nname = \"a\"\nheight = 0.0\n[[surface]]\nname = \"b\"\nheight = 0.5\n"),
        SceneError::Invalid { reason, .. } if reason.contains("unbounded")
    ));
    assert!(matches!(
        Scene::from_toml_file("no/such/scene.toml").unwrap_err(),
        SceneError::Io { .. }
    ));
}
