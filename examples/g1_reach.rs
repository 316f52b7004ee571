//! The Unitree G1 reaching with its right hand while it keeps both feet where they stand and its
//! centre of mass between them: a three-level task stack of ready-made tasks on the G1's URDF.
//!
//! ```text
//! cargo run --release --example g1_reach
//! ```
//!
//! The model is rooted at the right sole (on the floor: x forward, y left, z up, metres). Levels,
//! highest first: the left sole's pose (held where it stands), the CoM ground projection (midway
//! between the feet, 3 cm ahead of the ankles), the right hand's position; a pull toward the zero
//! posture fills the remaining freedom.

use std::fmt::Write as _;

use nalgebra::Vector3;
use taskstack::robots::g1;
use taskstack::solver::Solver;
use taskstack::solver::driver::{DriverSettings, PositionDriver};
use taskstack::tasks::{ComTask, PoseTask, PositionTask, TaskSet, joint_bounds};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut text = String::new();
    let model = g1::right_sole();
    let mut q = vec![0.0; model.nv()];
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &q)?;
    let left_sole = *data.frame_placement(model.frame_id("left_sole")?);
    let between_feet = [0.03, 0.5 * left_sole.translation.y];

    let mut set = TaskSet::new(&model)
        .level(
            "contact",
            vec![Box::new(PoseTask::new(&model, "left_sole", left_sole)?)],
        )
        .level(
            "balance",
            vec![Box::new(ComTask::ground(&model, between_feet)?)],
        )
        .level(
            "reach",
            vec![Box::new(PositionTask::new(
                &model,
                "right_rubber_hand",
                Vector3::zeros(),
            )?)],
        )
        .posture_gradient(0.05, &vec![0.0; model.nv()])?;
    let mut solver = Solver::new(&set.shape())?;
    let settings = DriverSettings {
        max_iterations: 100,
        tolerance: 1e-6,
        // At most 2 cm of task error per iteration: a long linear step drifts the levels above
        // it to second order (the next step corrects them, but an unreachable hand keeps asking).
        max_task_error: 0.02,
        ..DriverSettings::default()
    };
    let mut driver = PositionDriver::new(&solver, settings)?;
    let bounds = joint_bounds(&model)?;

    let _ = writeln!(
        text,
        "target (m)              iterations  contact (m)  CoM (m)    hand (m)"
    );
    for target in [
        [0.35, -0.2, 0.9],
        [0.4, -0.1, 1.1],
        [0.3, -0.35, 0.6],
        [0.9, -0.2, 0.9],
    ] {
        set.task_mut::<PositionTask>("right_rubber_hand")?.target = Vector3::from(target);
        let report = driver.run(&mut solver, &mut set, &mut q, &bounds)?;
        let e = report.task_errors();
        let _ = writeln!(
            text,
            "{:<23} {:>10}  {:>11.1e}  {:>9.1e}  {:>8.4}",
            format!("{target:?}"),
            report.iterations,
            e[0],
            e[1],
            e[2]
        );
    }
    // Out of reach, the hand stops as close as the levels above allow. Each of its steps still
    // moves the feet and CoM a little to second order (the iteration is linearised), so those
    // levels sit within a millimetre rather than 1e-6 m while the hand keeps pulling.
    let _ = writeln!(
        text,
        "(the last target is out of reach: the hand stops short; contact and CoM within 1 mm)"
    );
    // A reader that closed the pipe (`| head`) is not an error of ours.
    match std::io::Write::write_all(&mut std::io::stdout(), text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
