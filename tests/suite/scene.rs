//! Scenes of planar surfaces: the file format, its refusals, and the distances the contact pass
//! uses, checked against hand calculations.

use taskstack::nalgebra::{Vector2, Vector3};
use taskstack::scene::{Scene, SceneError, Surface};

#[test]
fn a_turned_rectangle_measures_how_far_a_point_lies_beyond_its_edges() {
    // 0.8 × 1.2 m turned by 90°: it spans x ∈ [0, 1.2] and y ∈ [-0.4, 0.4] around (0.6, 0).
    let table = Surface::rectangle("table", [0.6, 0.0], [0.8, 1.2], 90.0, 0.72).unwrap();
    let at = |x, y| table.shape().outside_distance(&Vector3::new(x, y, 0.8));
    assert!(at(0.6, 0.0).abs() < 1e-12);
    assert!(at(1.19, 0.39).abs() < 1e-12, "inside near a corner");
    assert!((at(1.5, 0.0) - 0.3).abs() < 1e-12, "beyond the end");
    assert!((at(0.6, 0.7) - 0.3).abs() < 1e-12, "beyond the side");
    assert!(
        (at(1.5, 0.8) - 0.5).abs() < 1e-12,
        "beyond the corner: hypot(0.3, 0.4)"
    );
    assert!((table.shape().height_above(&Vector3::new(0.0, 0.0, 0.8)) - 0.08).abs() < 1e-12);
    let floor = Surface::plane("floor", 0.0).unwrap();
    assert_eq!(
        floor
            .shape()
            .outside_distance(&Vector3::new(100.0, -50.0, 1.0)),
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
    assert!(scene.surfaces()[0].shape().is_unbounded());
    assert_eq!(scene.index_of("table"), Some(1));
    assert_eq!(scene.surfaces()[1].shape().height(), 0.72);
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

/// A 0.4 × 0.2 m rectangle turned 90° about its centre (1, 2): along x it spans 0.2 m, along y
/// 0.4 m. With a 5 cm margin the room left is x ∈ [0.95, 1.05], y ∈ [1.85, 2.15].
#[test]
fn nearest_inside_keeps_a_margin_from_the_edges_of_a_turned_rectangle() {
    let table = Surface::rectangle("table", [1.0, 2.0], [0.4, 0.2], 90.0, 0.7).unwrap();
    let shape = table.shape();
    let near = |x, y| shape.nearest_inside(Vector2::new(x, y), 0.05);
    assert!((near(1.0, 2.1) - Vector2::new(1.0, 2.1)).norm() < 1e-12);
    assert!((near(1.5, 2.0) - Vector2::new(1.05, 2.0)).norm() < 1e-12);
    assert!((near(0.0, 3.0) - Vector2::new(0.95, 2.15)).norm() < 1e-12);
    // A margin wider than the half-width leaves the centre line.
    let thin = shape.nearest_inside(Vector2::new(2.0, 2.0), 0.15);
    assert!((thin - Vector2::new(1.0, 2.0)).norm() < 1e-12);
    let floor = Surface::plane("floor", 0.0).unwrap();
    assert_eq!(
        floor.shape().nearest_inside(Vector2::new(9.0, 9.0), 0.1),
        Vector2::new(9.0, 9.0)
    );
}

/// The similarity that takes (1, 0) to (0, 0), halves and turns 90°: the centre (3, 0), 2 m
/// from the anchor along x, lands 1 m from the image along y, at (0, 1); sizes halve; the yaw
/// gains 90°.
#[test]
fn a_mapped_surface_is_turned_scaled_and_moved_about_the_anchor() {
    let table = Surface::rectangle("table", [3.0, 0.0], [0.8, 0.4], 0.0, 0.7).unwrap();
    let half_pi = std::f64::consts::FRAC_PI_2;
    let mapped =
        (table.shape()).mapped(Vector2::new(1.0, 0.0), Vector2::zeros(), 0.5, half_pi, 0.2);
    assert!((mapped.centre() - Vector2::new(0.0, 1.0)).norm() < 1e-12);
    assert!((mapped.half_size().unwrap() - Vector2::new(0.2, 0.1)).norm() < 1e-12);
    assert!((mapped.yaw() - half_pi).abs() < 1e-12);
    assert_eq!(mapped.height(), 0.2);
    // (0, 1.15) is 0.15 m along the mapped rectangle's first axis (now y): inside; 0.25: not.
    assert_eq!(mapped.outside_distance(&Vector3::new(0.0, 1.15, 0.0)), 0.0);
    assert!((mapped.outside_distance(&Vector3::new(0.0, 1.25, 0.0)) - 0.05).abs() < 1e-12);
}

/// A 0.4 × 0.2 m rectangle centred at (1, 2), turned 90°: its long side runs along y, so its
/// corners (by hand) are (1 ∓ 0.1, 2 ± 0.2); the floor has none.
#[test]
fn a_turned_rectangle_lists_its_corners() {
    let stool = Surface::rectangle("stool", [1.0, 2.0], [0.4, 0.2], 90.0, 0.45).unwrap();
    let corners = stool.shape().corners().unwrap();
    let expected = [[0.9, 2.2], [0.9, 1.8], [1.1, 1.8], [1.1, 2.2]];
    for (c, e) in corners.iter().zip(expected) {
        assert!((c - Vector2::from(e)).norm() < 1e-12, "{c} vs {e:?}");
    }
    assert!(
        Surface::plane("floor", 0.0)
            .unwrap()
            .shape()
            .corners()
            .is_none()
    );
}
