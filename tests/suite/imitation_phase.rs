//! The support-phase machine and the paper's task tables (Poubel §III.B, §IV.B, Table I).

use proptest::prelude::*;
use taskstack::human::Side;
use taskstack::imitation::phase::tables::{
    ComGoal, Gradient, GradientKind, TableError, Task, TaskTables,
};
use taskstack::imitation::phase::{
    Landing, Measurements, PhaseConfig, PhaseError, PhaseMachine, Settling, SupportPhase, TakeOff,
};
use taskstack::imitation::reference::support::HumanSupport;
use taskstack::robots::nao;

use HumanSupport as H;
use SupportPhase as P;

/// CoM far from its goal (40 mm > 5 mm tolerance), swing sole on the ground.
const FAR: Measurements = Measurements {
    com_error: 0.040,
    posture_error: 0.0,
    posture_settled: false,
    swing_toe_height: 0.0,
    swing_heel_height: 0.0,
};
/// CoM 1 mm from its goal (< 5 mm), swing sole on the ground.
const COM_OK: Measurements = Measurements {
    com_error: 0.001,
    posture_error: 0.0,
    posture_settled: false,
    swing_toe_height: 0.0,
    swing_heel_height: 0.0,
};
/// Swing sole half-way up (10 mm: neither ≥ ρ − 2 mm = 28 mm nor ≤ 2 mm).
const HALF_UP: Measurements = Measurements {
    com_error: 0.001,
    posture_error: 0.0,
    posture_settled: false,
    swing_toe_height: 0.010,
    swing_heel_height: 0.010,
};
/// Swing sole lifted: toe 30 mm, heel 28.5 mm, both ≥ 28 mm.
const LIFTED: Measurements = Measurements {
    com_error: 0.001,
    posture_error: 0.0,
    posture_settled: false,
    swing_toe_height: 0.030,
    swing_heel_height: 0.0285,
};
/// Swing sole down: 1 mm ≤ 2 mm.
const DOWN: Measurements = Measurements {
    com_error: 0.040,
    posture_error: 0.0,
    posture_settled: false,
    swing_toe_height: 0.001,
    swing_heel_height: 0.001,
};

fn run(machine: &mut PhaseMachine, steps: &[(HumanSupport, Measurements, SupportPhase)]) {
    for (i, (human, measured, expected)) in steps.iter().enumerate() {
        assert_eq!(
            machine.update(*human, measured),
            *expected,
            "step {i}: human {human:?}, {measured:?}"
        );
    }
}

/// The measurements above are written for a 2 mm foot height tolerance.
fn config() -> PhaseConfig {
    PhaseConfig {
        foot_height_tolerance: 0.002,
        ..PhaseConfig::default()
    }
}

fn machine() -> PhaseMachine {
    PhaseMachine::new(config()).unwrap()
}

#[test]
fn a_foot_lifts_only_once_the_torso_leans_over_the_stance_foot() {
    // CoM on its goal, torso 0.05 rad from its lean (> 0.03 rad): the foot stays down, and the
    // same holds for the CoM's return to the middle; within the tolerance both steps end.
    let leaning = Measurements {
        posture_error: 0.05,
        posture_settled: false,
        ..COM_OK
    };
    let leant = Measurements {
        posture_error: 0.02,
        posture_settled: false,
        ..COM_OK
    };
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Right, leaning, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, leaning, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, leant, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Right, LIFTED, P::Right),
            (H::Double, DOWN, P::RightToDouble(Landing::LowerFoot)),
            (H::Double, leaning, P::RightToDouble(Landing::ComToMiddle)),
            (H::Double, leaning, P::RightToDouble(Landing::ComToMiddle)),
            (H::Double, leant, P::Double),
        ],
    );
}

#[test]
fn a_lean_that_cannot_be_reached_does_not_keep_the_robot_waiting() {
    // The torso stopped 0.3 rad short of its lean (a joint limit): the CoM step ends anyway.
    let stuck = Measurements {
        posture_error: 0.3,
        posture_settled: true,
        ..COM_OK
    };
    let moving = Measurements {
        posture_settled: false,
        ..stuck
    };
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Left, moving, P::DoubleToLeft(TakeOff::ComToFoot)),
            (H::Left, moving, P::DoubleToLeft(TakeOff::ComToFoot)),
            (H::Left, stuck, P::DoubleToLeft(TakeOff::LiftFoot)),
        ],
    );
}

#[test]
fn an_error_settles_after_a_quarter_second_without_a_milliradian_of_progress() {
    let mut s = Settling::new();
    // 0.1 s frames. 0.3 → 0.2 is progress; 0.2 → 0.1995 (0.5 mrad) is not, nor is standing
    // still: settled once 0.25 s have passed since the last progress, at the third such frame.
    let steps = [
        (0.3, false),
        (0.2, false),
        (0.1995, false),
        (0.1995, false),
        (0.2, true),
        // 2 mrad of progress restarts the wait.
        (0.197, false),
        (f64::NAN, false),
    ];
    for (i, (error, settled)) in steps.into_iter().enumerate() {
        assert_eq!(s.update(error, 0.1), settled, "step {i}: error {error}");
    }
}

#[test]
fn a_foot_below_the_floor_has_not_landed() {
    // 3 mm below the floor is as far from flat on it as 3 mm above (tolerance 2 mm).
    let below = Measurements {
        swing_toe_height: -0.003,
        swing_heel_height: 0.0,
        ..DOWN
    };
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Right, LIFTED, P::Right),
            (H::Double, below, P::RightToDouble(Landing::LowerFoot)),
            (H::Double, below, P::RightToDouble(Landing::LowerFoot)),
            (H::Double, DOWN, P::RightToDouble(Landing::ComToMiddle)),
        ],
    );
}

#[test]
fn a_step_forward_goes_through_every_step_in_order() {
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Double, FAR, P::Double),
            (H::Right, FAR, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, FAR, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Right, HALF_UP, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Right, LIFTED, P::Right),
            (H::Right, DOWN, P::Right),
            (H::Double, LIFTED, P::RightToDouble(Landing::LowerFoot)),
            (H::Double, HALF_UP, P::RightToDouble(Landing::LowerFoot)),
            (H::Double, DOWN, P::RightToDouble(Landing::ComToMiddle)),
            (H::Double, FAR, P::RightToDouble(Landing::ComToMiddle)),
            (H::Double, COM_OK, P::Double),
        ],
    );
}

#[test]
fn foot_put_back_down_mid_lift_lands_it_then_recentres() {
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Left, COM_OK, P::DoubleToLeft(TakeOff::ComToFoot)),
            (H::Left, COM_OK, P::DoubleToLeft(TakeOff::LiftFoot)),
            (H::Double, HALF_UP, P::LeftToDouble(Landing::LowerFoot)),
            (H::Double, DOWN, P::LeftToDouble(Landing::ComToMiddle)),
            (H::Double, COM_OK, P::Double),
        ],
    );
}

#[test]
fn foot_put_back_down_during_the_com_shift_aborts_to_double_support() {
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Right, FAR, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Double, FAR, P::Double),
        ],
    );
}

#[test]
fn a_closed_lift_gate_holds_the_weight_on_the_stance_foot() {
    let mut m = machine();
    let step = TakeOff::ComToFoot;
    // The shift runs and ends as usual, but the foot stays down while the gate is closed.
    assert_eq!(
        m.update_gated(H::Right, false, &FAR, 0.01),
        P::DoubleToRight(step)
    );
    for _ in 0..3 {
        assert_eq!(
            m.update_gated(H::Right, false, &COM_OK, 0.01),
            P::DoubleToRight(step)
        );
    }
    // Opened: the lift starts at once.
    let lift = P::DoubleToRight(TakeOff::LiftFoot);
    assert_eq!(m.update_gated(H::Right, true, &COM_OK, 0.01), lift);
    // The gate only holds a take-off: a lifted foot, a landing and a recentring go on.
    assert_eq!(m.update_gated(H::Right, false, &LIFTED, 0.01), P::Right);
    let lower = P::RightToDouble(Landing::LowerFoot);
    assert_eq!(m.update_gated(H::Double, false, &LIFTED, 0.01), lower);
    let middle = P::RightToDouble(Landing::ComToMiddle);
    assert_eq!(m.update_gated(H::Double, false, &DOWN, 0.01), middle);
    assert_eq!(m.update_gated(H::Double, false, &COM_OK, 0.01), P::Double);
}

#[test]
fn a_foot_lifts_once_the_weight_shift_has_held_for_the_settle_time() {
    // 0.05 s at 0.01 s a frame: the frame that reaches the goal counts, so the fifth frame on
    // the goal ends the shift; a frame off the goal starts the count again.
    let mut m = PhaseMachine::new(PhaseConfig {
        settle_time: Some(0.05),
        ..config()
    })
    .unwrap();
    let shift = P::DoubleToRight(TakeOff::ComToFoot);
    assert_eq!(m.update_gated(H::Right, true, &FAR, 0.01), shift);
    for _ in 0..3 {
        assert_eq!(m.update_gated(H::Right, true, &COM_OK, 0.01), shift);
    }
    assert_eq!(m.update_gated(H::Right, true, &FAR, 0.01), shift);
    for _ in 0..4 {
        assert_eq!(m.update_gated(H::Right, true, &COM_OK, 0.01), shift);
    }
    let lift = P::DoubleToRight(TakeOff::LiftFoot);
    assert_eq!(m.update_gated(H::Right, true, &COM_OK, 0.01), lift);
    // The landing does not wait: the weight moves back once the foot is down.
    assert_eq!(m.update_gated(H::Right, true, &LIFTED, 0.01), P::Right);
    let lower = P::RightToDouble(Landing::LowerFoot);
    assert_eq!(m.update_gated(H::Double, true, &LIFTED, 0.01), lower);
    let middle = P::RightToDouble(Landing::ComToMiddle);
    assert_eq!(m.update_gated(H::Double, true, &DOWN, 0.01), middle);
    // A second shift counts from zero, and `update` (a step of any length) ends it at once.
    assert_eq!(m.update_gated(H::Double, true, &COM_OK, 0.01), P::Double);
    assert_eq!(
        m.update_gated(H::Left, true, &FAR, 0.01),
        P::DoubleToLeft(TakeOff::ComToFoot)
    );
    assert_eq!(
        m.update(H::Left, &COM_OK),
        P::DoubleToLeft(TakeOff::LiftFoot)
    );
}

#[test]
fn foot_lifted_again_while_landing_is_lifted_again() {
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Right, LIFTED, P::Right),
            (H::Double, LIFTED, P::RightToDouble(Landing::LowerFoot)),
            (H::Right, HALF_UP, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Double, HALF_UP, P::RightToDouble(Landing::LowerFoot)),
            (H::Double, DOWN, P::RightToDouble(Landing::ComToMiddle)),
            // Lifted again once both feet are down: the CoM goes back over the right foot first.
            (H::Right, DOWN, P::DoubleToRight(TakeOff::ComToFoot)),
        ],
    );
}

#[test]
fn walking_from_right_to_left_support_goes_through_double_support() {
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Right, LIFTED, P::Right),
            (H::Left, LIFTED, P::RightToDouble(Landing::LowerFoot)),
            (H::Left, DOWN, P::RightToDouble(Landing::ComToMiddle)),
            (H::Left, COM_OK, P::Double),
            (H::Left, FAR, P::DoubleToLeft(TakeOff::ComToFoot)),
            (H::Left, COM_OK, P::DoubleToLeft(TakeOff::LiftFoot)),
            (H::Left, LIFTED, P::Left),
        ],
    );
}

#[test]
fn airborne_keeps_the_last_support() {
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Airborne, COM_OK, P::Double),
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Airborne, COM_OK, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Airborne, LIFTED, P::Right),
            (H::Airborne, DOWN, P::Right),
        ],
    );
    assert_eq!(m.human_support(), H::Right);
}

#[test]
fn nan_measurements_never_end_a_step() {
    let nan = Measurements {
        com_error: f64::NAN,
        posture_error: f64::NAN,
        posture_settled: false,
        swing_toe_height: f64::NAN,
        swing_heel_height: f64::NAN,
    };
    let half_nan = Measurements {
        swing_heel_height: f64::NAN,
        ..LIFTED
    };
    let mut m = machine();
    run(
        &mut m,
        &[
            (H::Right, nan, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, nan, P::DoubleToRight(TakeOff::ComToFoot)),
            (H::Right, COM_OK, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Right, half_nan, P::DoubleToRight(TakeOff::LiftFoot)),
            (H::Right, nan, P::DoubleToRight(TakeOff::LiftFoot)),
        ],
    );
}

#[test]
fn bad_config_is_rejected_naming_the_field() {
    let cases = [
        (
            PhaseConfig {
                com_tolerance: f64::NAN,
                ..PhaseConfig::default()
            },
            "com_tolerance",
        ),
        (
            PhaseConfig {
                lambda: -0.01,
                ..PhaseConfig::default()
            },
            "lambda",
        ),
        (
            PhaseConfig {
                foot_height_tolerance: 0.0,
                ..PhaseConfig::default()
            },
            "foot_height_tolerance",
        ),
        (
            PhaseConfig {
                support_margin: Some(f64::INFINITY),
                ..PhaseConfig::default()
            },
            "support_margin",
        ),
        (
            PhaseConfig {
                posture_tolerance: 0.0,
                ..PhaseConfig::default()
            },
            "posture_tolerance",
        ),
        (
            PhaseConfig {
                settle_time: Some(-0.1),
                ..PhaseConfig::default()
            },
            "settle_time",
        ),
        (
            PhaseConfig {
                settle_time: Some(f64::NAN),
                ..PhaseConfig::default()
            },
            "settle_time",
        ),
        // ρ = 4 mm ≤ 2 × 2 mm: a foot could be "lifted" and "on the ground" at once.
        (
            PhaseConfig {
                rho: 0.004,
                ..config()
            },
            "rho",
        ),
    ];
    for (config, field) in cases {
        match PhaseMachine::new(config) {
            Err(PhaseError::Config(f, _)) => assert_eq!(f, field),
            other => panic!("{field}: expected a config error, got {other:?}"),
        }
    }
}

#[test]
fn paper_defaults_are_the_papers_values() {
    let c = PhaseConfig::default();
    assert_eq!((c.lambda, c.rho), (0.015, 0.030));
}

fn level_rows(tables: &TaskTables, phase: SupportPhase) -> Vec<usize> {
    tables.table(phase).shape(23).level_rows().collect()
}

fn tracks_a_hand(tables: &TaskTables, phase: SupportPhase) -> bool {
    tables.table(phase).levels.iter().any(|l| {
        l.tasks
            .iter()
            .any(|t| matches!(t, Task::Point { frame, .. } if frame.ends_with("_hand")))
    })
}

#[test]
fn paper_tables_have_table_one_row_counts() {
    let tables = TaskTables::paper(&nao::profile());
    // Table I: X'_c is 2×1 everywhere; X_t is 9×1 in RS and LS, 11×1 in DS, 5×1 in transitions.
    assert_eq!(level_rows(&tables, P::Right), vec![2, 9]);
    assert_eq!(level_rows(&tables, P::Left), vec![2, 9]);
    assert_eq!(level_rows(&tables, P::Double), vec![2, 11]);
    for phase in SupportPhase::ALL.into_iter().filter(|p| p.is_transition()) {
        assert_eq!(level_rows(&tables, phase), vec![2, 5], "{phase}");
        assert!(!tracks_a_hand(&tables, phase), "{phase}: hands are free");
    }
    for phase in [P::Right, P::Left, P::Double] {
        assert!(tracks_a_hand(&tables, phase), "{phase}");
    }
    for table in tables.iter() {
        table.validate().unwrap();
        assert_eq!(
            table.levels[0].tasks.len(),
            1,
            "{}: balance first",
            table.phase
        );
        assert!(matches!(table.levels[0].tasks[0], Task::ComXY(_)));
        assert_eq!(
            table.gradients,
            vec![
                Gradient {
                    kind: GradientKind::JointLimits,
                    kappa: -0.10
                },
                Gradient {
                    kind: GradientKind::HumanJoints,
                    kappa: -0.02
                },
            ]
        );
        assert!(table.clamping);
    }
    assert_eq!(tables.iter().count(), 11);
}

/// Walking, the CoM goes over the centre of the support sole's FSR rectangle (computed here from
/// the NAO's sensor positions, not by the crate), and the collision level comes before balance;
/// the tables are otherwise the executable ones.
#[test]
fn walking_tables_centre_the_stance_and_keep_bodies_apart_first() {
    let profile = nao::profile();
    let executable = TaskTables::executable(&PhaseConfig::default(), &profile);
    let mut walking = executable.clone();
    walking.centre_stances_for_walking(&profile);
    let names = |t: &taskstack::imitation::phase::tables::TaskTable| -> Vec<String> {
        t.levels.iter().map(|l| l.name.clone()).collect()
    };
    // The left sole's FSRs span x ∈ [−30.25, 70.25] mm, y ∈ [−23.1, 29.9] mm.
    let centre = |side: Side| match side {
        Side::Left => [0.02, 0.0034],
        Side::Right => [0.02, -0.0034],
    };
    for (before, after) in executable.iter().zip(walking.iter()) {
        let level = |t: &taskstack::imitation::phase::tables::TaskTable, name: &str| {
            names(t).iter().position(|n| n == name)
        };
        assert!(level(before, "collision") > level(before, "balance"));
        assert_eq!(level(after, "collision"), level(before, "balance"));
        assert_eq!(level(after, "balance"), level(before, "collision"));
        let goal = |t: &taskstack::imitation::phase::tables::TaskTable| {
            t.levels
                .iter()
                .flat_map(|l| &l.tasks)
                .find_map(|task| match task {
                    Task::ComXY(goal) => Some(*goal),
                    _ => None,
                })
        };
        let root = after.model_root;
        match (goal(before), goal(after)) {
            (Some(ComGoal::SupportPoint(_)), Some(ComGoal::SupportPoint(p))) => {
                let c = centre(root);
                assert!(
                    (p[0] - c[0]).abs() < 1e-9 && (p[1] - c[1]).abs() < 1e-9,
                    "{p:?}"
                );
            }
            (Some(ComGoal::OtherPoint(_)), Some(ComGoal::OtherPoint(p))) => {
                let c = centre(root.other());
                assert!(
                    (p[0] - c[0]).abs() < 1e-9 && (p[1] - c[1]).abs() < 1e-9,
                    "{p:?}"
                );
            }
            (b, a) => assert_eq!(b, a, "{}", after.phase),
        }
    }
}

#[test]
fn paper_model_roots_follow_section_iv_b() {
    let tables = TaskTables::paper(&nao::profile());
    // LFoot only while the right foot is off the ground or being lowered (Table I "Model").
    let left_rooted = [
        P::Left,
        P::DoubleToLeft(TakeOff::LiftFoot),
        P::LeftToDouble(Landing::LowerFoot),
    ];
    for phase in SupportPhase::ALL {
        let expected = if left_rooted.contains(&phase) {
            Side::Left
        } else {
            Side::Right
        };
        assert_eq!(tables.table(phase).model_root, expected, "{phase}");
    }
}

#[test]
fn overrides_are_validated() {
    let mut tables = TaskTables::paper(&nao::profile());
    let mut ds = tables.table(P::Double).clone();
    let first = ds.levels[1].tasks[0].clone();
    ds.levels[1].tasks.push(first);
    assert!(matches!(
        tables.set(ds),
        Err(TableError::DuplicateTask { task, .. }) if task == "l_hand"
    ));
    let mut rs = tables.table(P::Right).clone();
    rs.gradients[1].kappa = f64::NAN;
    assert!(matches!(
        tables.set(rs.clone()),
        Err(TableError::NotFinite { field: "kappa", .. })
    ));
    rs.gradients.clear();
    rs.clamping = false;
    tables.set(rs.clone()).unwrap();
    assert_eq!(tables.table(P::Right), &rs);
    // The other tables are untouched.
    assert_eq!(
        tables.table(P::Left),
        TaskTables::paper(&nao::profile()).table(P::Left)
    );
}

#[test]
fn phases_print_like_table_one() {
    assert_eq!(P::Double.to_string(), "DS");
    assert_eq!(
        P::DoubleToLeft(TakeOff::ComToFoot).to_string(),
        "DS to LS: CoM to LFoot"
    );
    assert_eq!(
        P::LeftToDouble(Landing::ComToMiddle).to_string(),
        "LS to DS: CoM to middle"
    );
    let row = TaskTables::paper(&nao::profile())
        .table(P::Right)
        .to_string();
    assert!(
        row.starts_with("| RS |  | RFoot | (9×1) p(l_hand) ← LHand"),
        "{row}"
    );
}

/// The documented graph (module docs of `imitation::phase`), written out independently: every
/// phase with its possible successors, itself included.
fn allowed(from: SupportPhase, to: SupportPhase) -> bool {
    use Landing::{ComToMiddle, LowerFoot};
    use TakeOff::{ComToFoot, LiftFoot};
    let edges: &[(SupportPhase, &[SupportPhase])] = &[
        (
            P::Double,
            &[
                P::Double,
                P::DoubleToRight(ComToFoot),
                P::DoubleToLeft(ComToFoot),
            ],
        ),
        (P::Right, &[P::Right, P::RightToDouble(LowerFoot)]),
        (P::Left, &[P::Left, P::LeftToDouble(LowerFoot)]),
        (
            P::DoubleToRight(ComToFoot),
            &[P::Double, P::DoubleToRight(LiftFoot)],
        ),
        (
            P::DoubleToLeft(ComToFoot),
            &[P::Double, P::DoubleToLeft(LiftFoot)],
        ),
        (
            P::DoubleToRight(LiftFoot),
            &[P::Right, P::RightToDouble(LowerFoot)],
        ),
        (
            P::DoubleToLeft(LiftFoot),
            &[P::Left, P::LeftToDouble(LowerFoot)],
        ),
        (
            P::RightToDouble(LowerFoot),
            &[P::RightToDouble(ComToMiddle), P::DoubleToRight(LiftFoot)],
        ),
        (
            P::LeftToDouble(LowerFoot),
            &[P::LeftToDouble(ComToMiddle), P::DoubleToLeft(LiftFoot)],
        ),
        (
            P::RightToDouble(ComToMiddle),
            &[P::Double, P::DoubleToRight(ComToFoot)],
        ),
        (
            P::LeftToDouble(ComToMiddle),
            &[P::Double, P::DoubleToLeft(ComToFoot)],
        ),
    ];
    from == to
        || edges
            .iter()
            .any(|(f, targets)| *f == from && targets.contains(&to))
}

fn human() -> impl Strategy<Value = HumanSupport> {
    prop_oneof![
        Just(H::Double),
        Just(H::Right),
        Just(H::Left),
        Just(H::Airborne)
    ]
}

fn measurement() -> impl Strategy<Value = Measurements> {
    let length = prop_oneof![
        Just(0.0),
        Just(0.001),
        Just(0.030),
        Just(f64::NAN),
        Just(f64::INFINITY),
        -0.01..0.06f64,
    ];
    (
        length.clone(),
        length.clone(),
        length.clone(),
        length,
        any::<bool>(),
    )
        .prop_map(|(c, p, t, h, settled)| Measurements {
            com_error: c,
            posture_error: p,
            posture_settled: settled,
            swing_toe_height: t,
            swing_heel_height: h,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_human_sequences_stay_on_the_graph(
        steps in proptest::collection::vec((human(), measurement()), 1..80)
    ) {
        let tables = TaskTables::paper(&nao::profile());
        let config = config();
        let mut m = PhaseMachine::new(config).unwrap();
        let mut last_human = H::Double;
        for (human, measured) in steps {
            let from = m.phase();
            let to = m.update(human, &measured);
            if human != H::Airborne {
                last_human = human;
            }
            prop_assert!(allowed(from, to), "{from} → {to} on {human:?}, {measured:?}");
            prop_assert_eq!(m.phase(), to);
            let table = tables.table(to);
            prop_assert_eq!(table.phase, to);
            prop_assert_eq!(table.model_root, to.model_root());
            // The tracked foot is never the model root (it is fixed to the world).
            let root_ankle = match to.model_root() { Side::Right => "r_ankle", Side::Left => "l_ankle" };
            let tracks_root = table.levels.iter().flat_map(|l| &l.tasks).any(
                |t| matches!(t, Task::Point { frame, .. } if frame == root_ankle)
            );
            prop_assert!(!tracks_root, "{to} tracks its own root ankle");
            // A single support is entered only on the human's word and a measured lift.
            let lift_goal = config.rho - config.foot_height_tolerance;
            if matches!(to, P::Right | P::Left) && from != to {
                prop_assert_eq!(last_human, if to == P::Right { H::Right } else { H::Left });
                prop_assert!(measured.swing_toe_height >= lift_goal);
                prop_assert!(measured.swing_heel_height >= lift_goal);
            }
            // Double support is reached only while the human stands on both feet or switches
            // feet (never while they stand on the foot the robot was moving to).
            if to == P::Double && from != P::Double {
                let toward = match from {
                    P::DoubleToRight(_) | P::RightToDouble(_) => H::Right,
                    _ => H::Left,
                };
                prop_assert_ne!(last_human, toward);
            }
        }
    }
}

/// The docs include `src/imitation/phase/tables/table1.md`; it must be exactly the rendering of the data.
#[test]
fn checked_in_table_matches_the_data() {
    assert_eq!(
        include_str!("../../src/imitation/phase/tables/table1.md"),
        TaskTables::paper(&nao::profile()).to_string(),
        "regenerate with `cargo run --example table1 > src/imitation/phase/tables/table1.md`"
    );
}

/// The executable tables keep the NAO's self-collision pairs apart in a level of inequalities
/// right below balance (contact and balance first: a foot on the ground never slides to make
/// room), one row per pair; without pairs in the profile there is no such level. A negative
/// margin is refused.
#[test]
fn executable_tables_keep_the_bodies_apart_below_balance() {
    use taskstack::imitation::phase::tables::Constraint;
    let profile = nao::profile();
    let tables = TaskTables::executable(&PhaseConfig::default(), &profile);
    let pairs = profile.self_collision.pairs.len();
    for table in tables.iter() {
        let names: Vec<&str> = table.levels.iter().map(|l| l.name.as_str()).collect();
        let balance = names.iter().position(|n| *n == "balance").unwrap();
        assert_eq!(
            names[balance + 1],
            "collision",
            "{}: {names:?}",
            table.phase
        );
        let level = &table.levels[balance + 1];
        assert!(level.tasks.is_empty());
        assert_eq!(level.constraints.len(), pairs);
        let shape = table.shape(23);
        assert_eq!(shape.levels()[balance + 1].inequality_rows(), pairs);
        assert!(table.to_string().contains("d(l_forearm, torso) ≥ 10 mm"));
    }
    let mut bare = profile.clone();
    bare.self_collision.pairs.clear();
    let tables = TaskTables::executable(&PhaseConfig::default(), &bare);
    assert!(
        tables
            .iter()
            .all(|t| t.levels.iter().all(|l| l.name != "collision"))
    );

    let mut table = TaskTables::executable(&PhaseConfig::default(), &profile)
        .table(P::Right)
        .clone();
    let level = table
        .levels
        .iter_mut()
        .find(|l| l.name == "collision")
        .unwrap();
    let Constraint::Distance { margin, .. } = &mut level.constraints[0] else {
        panic!("the collision level holds distances");
    };
    *margin = -0.01;
    assert!(matches!(
        table.validate(),
        Err(TableError::InvalidMargin { .. })
    ));
}

/// The ZMP balance adds a "dynamics" level to every table right below the feet, the CoM and
/// the collision level, with room for both soles' outlines; a bound that is not > 0 is refused.
#[test]
fn zmp_balance_sits_below_the_feet_and_the_com() {
    use taskstack::imitation::phase::tables::Constraint;
    let profile = nao::profile();
    let mut tables = TaskTables::executable(&PhaseConfig::default(), &profile);
    tables.add_zmp_balance(&profile);
    for phase in SupportPhase::ALL {
        let table = tables.table(phase);
        table.validate().unwrap();
        let names: Vec<&str> = table.levels.iter().map(|l| l.name.as_str()).collect();
        let at = names.iter().position(|n| *n == "dynamics").unwrap();
        assert_eq!(names[at - 1], "collision", "{phase:?}: {names:?}");
        assert_eq!(names[at + 1], "posture", "{phase:?}: {names:?}");
        let Constraint::Zmp {
            margin,
            max_yaw_moment,
            vertices,
        } = table.levels[at].constraints[0]
        else {
            panic!("{phase:?}: not a ZMP row");
        };
        // Two four-corner outlines; μ 0.5 × a fifth of the weight × the corners' mean lever.
        assert_eq!((margin, vertices), (0.0, 8));
        assert!((0.1..1.0).contains(&max_yaw_moment), "{max_yaw_moment} N·m");
    }
    let mut rs = tables.table(P::Right).clone();
    let level = rs.levels.iter_mut().find(|l| l.name == "dynamics").unwrap();
    if let Constraint::Zmp { max_yaw_moment, .. } = &mut level.constraints[0] {
        *max_yaw_moment = 0.0;
    }
    assert!(matches!(
        rs.validate(),
        Err(TableError::InvalidZmpBound { .. })
    ));
}
