//! The crate root: the re-exported types are enough to solve for a link without naming `nalgebra`
//! in the user's own `Cargo.toml`, and every module error converts into `taskstack::Error`.

use taskstack::robots::nao;
use taskstack::solver::driver::{DriverSettings, PositionDriver};
use taskstack::{Error, PositionTask, Solver, TaskSet, Vector3};

fn reach() -> Result<f64, Error> {
    let model = nao::rfoot();
    let hand = PositionTask::new(&model, "l_hand", Vector3::new(0.1, 0.1, 0.3))?;
    let mut set = TaskSet::new(&model).level("reach", vec![Box::new(hand)]);
    let mut solver = Solver::new(&set.shape())?;
    let mut driver = PositionDriver::new(&solver, DriverSettings::default())?;
    let mut q = nao::STAND.to_vec();
    let bounds = taskstack::tasks::joint_bounds(&model)?;
    let report = driver.run(&mut solver, &mut set, &mut q, &bounds)?;
    Ok(report.task_errors()[0])
}

#[test]
fn module_errors_convert_into_the_crate_error() {
    let error = reach().unwrap();
    assert!(error < 1e-3, "hand error {error} m");
    let model = nao::rfoot();
    let unknown = || -> Result<(), Error> {
        PositionTask::new(&model, "no_such_frame", Vector3::zeros())?;
        Ok(())
    };
    let err = unknown().unwrap_err();
    assert!(matches!(err, Error::Task(_)), "{err:?}");
    assert!(err.to_string().contains("no_such_frame"), "{err}");
}
