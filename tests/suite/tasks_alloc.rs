//! A warmed-up solve of a `TaskSet` (ready-made tasks) allocates nothing on the heap: the suite's
//! counting allocator counts the allocations of the test's own thread during the solves (the
//! test harness's threads allocate now and then while they wait).

use nalgebra::Vector3;
use taskstack::robots::nao;
use taskstack::solver::Solver;
use taskstack::solver::driver::{DriverSettings, PositionDriver};
use taskstack::tasks::{ComTask, OrientationTask, PoseTask, PositionTask, TaskSet, joint_bounds};

use crate::alloc_counter::allocations;

#[test]
fn a_warmed_up_task_set_solve_does_not_allocate() {
    let model = nao::rfoot();
    let mut data = model.new_data();
    let mut q = vec![0.0; model.nv()];
    model.forward_kinematics(&mut data, &q).unwrap();
    let at = |frame: &str| *data.frame_placement(model.frame_id(frame).unwrap());
    let mut set = TaskSet::new(&model)
        .level(
            "contact",
            vec![Box::new(
                PoseTask::new(&model, "l_sole", at("l_sole")).unwrap(),
            )],
        )
        .level(
            "balance",
            vec![Box::new(ComTask::ground(&model, [0.0, 0.05]).unwrap())],
        )
        .level(
            "tracking",
            vec![
                Box::new(
                    PositionTask::new(&model, "r_hand", Vector3::new(0.15, -0.1, 0.3)).unwrap(),
                ),
                Box::new(OrientationTask::new(&model, "torso", at("torso").rotation).unwrap()),
            ],
        )
        .posture_gradient(0.1, &vec![0.0; model.nv()])
        .unwrap();
    let mut solver = Solver::new(&set.shape()).unwrap();
    let mut driver = PositionDriver::new(&solver, DriverSettings::default()).unwrap();
    let bounds = joint_bounds(&model).unwrap();
    driver.run(&mut solver, &mut set, &mut q, &bounds).unwrap();

    let before = allocations();
    for k in 0..20 {
        set.task_mut::<PositionTask>("r_hand").unwrap().target.z = 0.25 + 0.005 * k as f64;
        driver.run(&mut solver, &mut set, &mut q, &bounds).unwrap();
    }
    let after = allocations();
    assert_eq!(
        after - before,
        0,
        "heap allocations during warmed-up task-set solves"
    );
}
