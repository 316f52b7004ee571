//! Bad input gets a typed error naming the place; nothing panics.

use taskstack::solver::{
    JointBounds, JointTracking, Settings, Solver, SolverError, StackShape,
    driver::{DriverSettings, PositionDriver},
};

fn solver() -> Solver {
    let shape = StackShape::new(3)
        .with_level("balance", &[("com", 2)])
        .with_level("tracking", &[("hand", 3)]);
    Solver::new(&shape).unwrap()
}

#[test]
fn empty_stack_and_zero_dof_are_rejected() {
    assert_eq!(
        Solver::new(&StackShape::new(3)).unwrap_err(),
        SolverError::EmptyStack
    );
    assert_eq!(
        Solver::new(&StackShape::from_level_rows(0, &[1])).unwrap_err(),
        SolverError::NoDegreesOfFreedom
    );
    let err = Solver::new(
        &StackShape::new(3)
            .with_level("a", &[("x", 1)])
            .with_level("empty", &[]),
    )
    .unwrap_err();
    assert_eq!(
        err,
        SolverError::EmptyLevel {
            level: 1,
            name: "empty".into()
        }
    );
}

#[test]
fn non_finite_jacobian_entry_names_level_row_and_column() {
    let mut s = solver();
    s.stack_mut()
        .level_mut(1)
        .set_row(2, &[0.0, f64::NAN, 0.0], 0.0)
        .unwrap();
    let err = s.solve_unbounded().unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("level 1")
            && msg.contains("\"tracking\"")
            && msg.contains("row 2")
            && msg.contains("column 1"),
        "{msg}"
    );
}

#[test]
fn non_finite_target_and_gradient_are_rejected() {
    let mut s = solver();
    s.stack_mut().level_mut(0).target_mut()[1] = f64::INFINITY;
    assert!(
        s.solve_unbounded()
            .unwrap_err()
            .to_string()
            .contains("desired velocity of level 0")
    );
    let mut s = solver();
    s.stack_mut().gradient_mut()[2] = f64::NAN;
    assert!(
        s.solve_unbounded()
            .unwrap_err()
            .to_string()
            .contains("gradient term at index 2")
    );
}

#[test]
fn wrong_sizes_are_rejected() {
    let mut s = solver();
    let err = s
        .stack_mut()
        .level_mut(0)
        .set_row(0, &[1.0, 2.0], 0.0)
        .unwrap_err();
    assert!(matches!(
        err,
        SolverError::DimensionMismatch {
            expected: 3,
            got: 2,
            ..
        }
    ));
    let err = s
        .stack_mut()
        .level_mut(0)
        .set_row(5, &[1.0, 2.0, 3.0], 0.0)
        .unwrap_err();
    assert!(matches!(
        err,
        SolverError::NoSuchRow {
            row: 5,
            rows: 2,
            ..
        }
    ));
    assert!(matches!(
        s.stack_mut().try_level_mut(7),
        Err(SolverError::NoSuchLevel {
            level: 7,
            levels: 2
        })
    ));
    let bounds = JointBounds::unbounded(3);
    assert!(matches!(
        s.solve(&[0.0; 4], &bounds, 0.1),
        Err(SolverError::DimensionMismatch {
            expected: 3,
            got: 4,
            ..
        })
    ));
    let bounds4 = JointBounds::unbounded(4);
    assert!(matches!(
        s.solve(&[0.0; 3], &bounds4, 0.1),
        Err(SolverError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        s.stack_mut().task_mut("nope"),
        Err(SolverError::NoSuchTask(_))
    ));
}

#[test]
fn bad_q_dt_limits_and_settings_are_rejected() {
    let mut s = solver();
    let bounds = JointBounds::unbounded(3);
    assert!(matches!(
        s.solve(&[0.0, f64::NAN, 0.0], &bounds, 0.1),
        Err(SolverError::NonFinite { .. })
    ));
    for dt in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            s.solve(&[0.0; 3], &bounds, dt),
            Err(SolverError::InvalidParameter { name: "dt", .. })
        ));
    }
    assert!(matches!(
        JointBounds::new(&[0.0, 2.0], &[1.0, 1.0]),
        Err(SolverError::InvertedLimits { joint: 1, .. })
    ));
    assert!(matches!(
        JointBounds::new(&[f64::NAN], &[1.0]),
        Err(SolverError::InvertedLimits { joint: 0, .. })
    ));
    assert!(matches!(
        JointBounds::with_velocity(&[0.0], &[1.0], &[-1.0]),
        Err(SolverError::InvalidParameter {
            name: "velocity limit",
            ..
        })
    ));
    let bad = Settings {
        rank_tolerance: 0.0,
        ..Settings::default()
    };
    assert!(matches!(
        s.set_settings(bad),
        Err(SolverError::InvalidParameter {
            name: "rank_tolerance",
            ..
        })
    ));
    let bad = Settings {
        max_damping: f64::NAN,
        ..Settings::default()
    };
    assert!(s.set_settings(bad).is_err());
    let bad = DriverSettings {
        dt: 0.0,
        ..DriverSettings::default()
    };
    assert!(matches!(
        PositionDriver::new(&s, bad),
        Err(SolverError::InvalidParameter { name: "dt", .. })
    ));
    assert!(JointTracking::new(&[0.0, f64::INFINITY]).is_err());
    let mut t = JointTracking::new(&[0.0, 0.0]).unwrap();
    assert!(t.set_reference(&[0.0]).is_err());
}

#[test]
fn a_rejected_solve_keeps_the_previous_result() {
    let mut s = solver();
    s.stack_mut()
        .level_mut(0)
        .set_row(0, &[1.0, 0.0, 0.0], 1.0)
        .unwrap();
    s.solve_unbounded().unwrap();
    let before = s.velocity().to_vec();
    s.stack_mut().level_mut(0).target_mut()[0] = f64::NAN;
    assert!(s.solve_unbounded().is_err());
    assert_eq!(s.velocity(), &before[..]);
}

fn inequality_solver() -> Solver {
    let shape = StackShape::new(3)
        .with_inequality_level("balance", &[("com_in_polygon", 2)])
        .with_level("tracking", &[("hand", 3)]);
    Solver::new(&shape).unwrap()
}

#[test]
fn bad_inequality_rows_name_level_and_row() {
    let mut solver = inequality_solver();
    let mut level = solver.stack_mut().level_mut(0);
    assert!(matches!(
        level.set_inequality_row(2, &[1.0, 0.0, 0.0], 0.0, 1.0),
        Err(SolverError::NoSuchRow {
            level: 0,
            row: 2,
            rows: 2,
            ..
        })
    ));
    assert!(matches!(
        level.set_inequality_row(0, &[1.0, 0.0], 0.0, 1.0),
        Err(SolverError::DimensionMismatch {
            expected: 3,
            got: 2,
            ..
        })
    ));
    // Inverted, NaN and empty (+∞ lower) bounds are refused by the next solve.
    level
        .set_inequality_row(1, &[1.0, 0.0, 0.0], 1.0, -1.0)
        .unwrap();
    assert_eq!(
        solver.solve_unbounded().unwrap_err(),
        SolverError::InvertedBounds {
            level: 0,
            name: "balance".into(),
            row: 1,
            lower: 1.0,
            upper: -1.0
        }
    );
    let mut level = solver.stack_mut().level_mut(0);
    level
        .set_inequality_row(1, &[1.0, 0.0, 0.0], f64::INFINITY, f64::INFINITY)
        .unwrap();
    assert!(matches!(
        solver.solve_unbounded(),
        Err(SolverError::InvertedBounds { row: 1, .. })
    ));
    let mut level = solver.stack_mut().level_mut(0);
    level
        .set_inequality_row(1, &[1.0, 0.0, 0.0], f64::NAN, 1.0)
        .unwrap();
    let err = solver.solve_unbounded().unwrap_err();
    assert!(
        err.to_string().contains("inequality bounds of level 0"),
        "{err}"
    );
    let mut level = solver.stack_mut().level_mut(0);
    level
        .set_inequality_row(1, &[1.0, f64::NAN, 0.0], -1.0, 1.0)
        .unwrap();
    let err = solver.solve_unbounded().unwrap_err();
    assert!(
        err.to_string()
            .contains("inequality Jacobian of level 0 (\"balance\") at row 1, column 1"),
        "{err}"
    );
    // Unbounded sides are fine: the default rows (−∞, +∞) and a one-sided row.
    let mut level = solver.stack_mut().level_mut(0);
    level
        .set_inequality_row(1, &[1.0, 0.0, 0.0], f64::NEG_INFINITY, 1.0)
        .unwrap();
    assert!(solver.solve_unbounded().is_ok());
    assert!(matches!(
        solver.stack_mut().inequality_task_mut("hand"),
        Err(SolverError::NoSuchTask(_))
    ));
}

#[test]
fn scaling_and_weighted_dls_are_refused_with_inequality_rows() {
    let shape = StackShape::new(3).with_inequality_level("balance", &[("com", 2)]);
    let scale = Settings {
        scale_to_fit: true,
        ..Settings::default()
    };
    assert!(matches!(
        Solver::with_settings(&shape, scale),
        Err(SolverError::InvalidParameter {
            name: "scale_to_fit",
            ..
        })
    ));
    let mut solver = inequality_solver();
    assert!(solver.set_settings(scale).is_err());
    assert!(
        !solver.settings().scale_to_fit,
        "the previous settings are kept"
    );
}
