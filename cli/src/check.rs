//! `taskstack check`: plays output folders on the MuJoCo model of their robot and judges them,
//! through the Python package's `taskstack.sim` (`pip install './python[sim]'`).

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use anyhow::Result;
use clap::{Args, ValueEnum};

use crate::Report;

/// Check runs in physics: play each OUT_DIR's joints.csv on a MuJoCo model of its robot.
///
/// The robot (NAO or G1, told by the joint names, or --robot) starts standing in the first
/// posture, holds it 1 s, plays the run (at most 5 s of a final stretch of constant targets: a
/// robot at rest under constant targets stays at rest), holds the last posture --hold s. A run passes when the robot
/// does not fall (base under 60 % of its height or tilted over 45°), no sole on the floor tilts
/// over 5°, no loaded sole (≥ 20 % of the weight) slides over 5 mm or turns over 2°, the measured
/// ZMP (the centre of pressure of the floor's forces on the soles) is at least 2 mm inside the
/// soles in contact ≥ 99 % of the time (a dynamic walk may carry the CoM outside the support;
/// the floor pushes only inside it), the CoM ground point is inside the soles' contact hull
/// ≥ 99 % of the final hold (the robot ends standing), nothing but the soles touches the floor,
/// and no target is outside the joint limits: the checks and thresholds of the physics judge of
/// the project's CI. Writes OUT_DIR/physics.svg (tilt, ZMP and CoM margins and sole forces over
/// time). The models (nominal and weak: half the servo stiffness, 80 % of the torque, floor
/// friction 0.7) are generated from the robots' URDFs; see `taskstack.sim.model`.
///
/// Runs Python: the interpreter in TASKSTACK_PYTHON, else python3, with the package installed
/// with its simulation extra: `pip install './python[sim]'` from the repository.
/// Exit status: 0 every run passes, 1 one fails, 2 bad input or no simulator.
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub(crate) struct CheckArgs {
    /// Output folders of `taskstack imitate`, `batch` clips or `walk` (or joints.csv files).
    #[arg(value_name = "OUT_DIR", required = true)]
    runs: Vec<PathBuf>,
    /// Which physics model.
    #[arg(long, value_enum, default_value_t = PhysicsModel::Both)]
    model: PhysicsModel,
    /// Seconds the last posture is held after the run (0–3600).
    #[arg(long, value_name = "SECONDS", default_value_t = 1.0)]
    hold: f64,
    /// The robot: nao, g1 or a biped profile file (TOML). Default: the built-in robot the
    /// joint names of joints.csv belong to.
    #[arg(long, value_name = "nao|g1|PROFILE.toml")]
    robot: Option<String>,
}

/// The physics models a check plays on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum PhysicsModel {
    /// The nominal robot.
    Nominal,
    /// Half the servo stiffness, 80 % of the torque limits, floor friction 0.7.
    Weak,
    /// Both.
    Both,
}

impl PhysicsModel {
    fn name(self) -> &'static str {
        match self {
            PhysicsModel::Nominal => "nominal",
            PhysicsModel::Weak => "weak",
            PhysicsModel::Both => "both",
        }
    }
}

pub(crate) fn run(args: CheckArgs, report: Report) -> Result<ExitCode> {
    check(
        &args.runs,
        args.model,
        args.hold,
        args.robot.as_deref(),
        report,
    )
}

/// Runs `taskstack.sim` on `runs`; its exit status (0 pass, 1 fail, 2 bad input) is ours.
pub(crate) fn check(
    runs: &[PathBuf],
    model: PhysicsModel,
    hold: f64,
    robot: Option<&str>,
    report: Report,
) -> Result<ExitCode> {
    if let Some(run) = runs.iter().find(|run| !run.exists()) {
        eprintln!(
            "taskstack: error: {}: no such folder or file",
            run.display()
        );
        return Ok(ExitCode::from(2));
    }
    let python = std::env::var_os("TASKSTACK_PYTHON").unwrap_or_else(|| "python3".into());
    // Python exits 1 on a missing module, which would read as a failed run: ask first.
    let probe = Command::new(&python)
        .args(["-c", "import taskstack.sim"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status();
    if !probe.is_ok_and(|s| s.success()) {
        eprintln!(
            "taskstack: error: {} cannot import taskstack.sim: install the Python package with its \
             simulation extra (pip install './python[sim]' from the repository), or set \
             TASKSTACK_PYTHON to a Python that has it",
            Path::new(&python).display()
        );
        return Ok(ExitCode::from(2));
    }
    let mut command = Command::new(&python);
    command.args(["-m", "taskstack.sim", "--model", model.name()]);
    command.arg("--hold").arg(hold.to_string());
    if report.json {
        command.arg("--json");
    }
    if let Some(robot) = robot {
        command.arg("--robot").arg(robot);
    }
    command.args(runs);
    if report.quiet && !report.json {
        command.stdout(std::process::Stdio::null());
    }
    let status = command.status()?;
    Ok(match status.code() {
        Some(0) => ExitCode::SUCCESS,
        Some(1) => ExitCode::FAILURE,
        Some(2) => ExitCode::from(2),
        _ => {
            eprintln!(
                "taskstack: error: {} -m taskstack.sim failed ({status}): is the package installed \
                 with its simulation extra (pip install './python[sim]')?",
                Path::new(&python).display()
            );
            ExitCode::from(2)
        }
    })
}
