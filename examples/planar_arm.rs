//! A redundant planar arm (5 revolute joints in the x–y plane) driven by the position-level IK:
//!
//! * level 1: the tip reaches a target (x, y), metres;
//! * level 2: the elbow (end of link 2) stays at a height y, metres — it gives way when it
//!   conflicts with level 1;
//! * gradient: joint-limit avoidance (κ = −0.10), in the null space of both levels.
//!
//! Prints, for each target, what each priority level achieved, the iterations and the clamped
//! joints. Run: `cargo run --release --example planar_arm`.

use std::fmt::Write as _;

use taskstack::solver::driver::{DriverSettings, PositionDriver, TaskModel};
use taskstack::solver::{
    JointBounds, JointLimitAvoidance, Solver, SolverError, StackShape, TaskStack,
};

/// Link lengths, metres.
const LINKS: [f64; 5] = [0.30, 0.25, 0.20, 0.15, 0.10];
/// The elbow is the end of this link (0-based).
const ELBOW: usize = 1;

struct PlanarArm {
    tip_target: [f64; 2],
    elbow_height: f64,
    limits: JointLimitAvoidance,
}

impl PlanarArm {
    /// Position of the end of link `k`, and the absolute angle of every link up to it.
    fn point(q: &[f64], k: usize) -> [f64; 2] {
        let mut angle = 0.0;
        let mut p = [0.0, 0.0];
        for i in 0..=k {
            angle += q[i];
            p[0] += LINKS[i] * angle.cos();
            p[1] += LINKS[i] * angle.sin();
        }
        p
    }

    /// ∂p_k/∂q_j = Σ_{i=j..k} l_i (−sin θ_i, cos θ_i) for j ≤ k, 0 beyond.
    fn jacobian_column(q: &[f64], k: usize, j: usize) -> [f64; 2] {
        if j > k {
            return [0.0, 0.0];
        }
        let mut angle: f64 = q[..j].iter().sum();
        let mut column = [0.0, 0.0];
        for i in j..=k {
            angle += q[i];
            column[0] -= LINKS[i] * angle.sin();
            column[1] += LINKS[i] * angle.cos();
        }
        column
    }
}

impl TaskModel for PlanarArm {
    type Error = SolverError;

    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        let tip = LINKS.len() - 1;
        let p = Self::point(q, tip);
        let (mut jac, error) = stack.task_mut("tip")?;
        for j in 0..q.len() {
            let c = Self::jacobian_column(q, tip, j);
            jac[(0, j)] = c[0];
            jac[(1, j)] = c[1];
        }
        error[0] = self.tip_target[0] - p[0];
        error[1] = self.tip_target[1] - p[1];

        let (mut jac, error) = stack.task_mut("elbow_height")?;
        for j in 0..q.len() {
            jac[(0, j)] = Self::jacobian_column(q, ELBOW, j)[1];
        }
        error[0] = self.elbow_height - Self::point(q, ELBOW)[1];

        stack.clear_gradient();
        stack.add_gradient(-0.10, &self.limits, q)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut text = String::new();
    let n = LINKS.len();
    let shape = StackShape::new(n)
        .with_level("reach", &[("tip", 2)])
        .with_level("posture", &[("elbow_height", 1)]);
    let mut solver = Solver::new(&shape)?;
    let bounds = JointBounds::new(&[-1.5, -2.0, -2.0, -2.0, -0.5], &[1.5, 2.0, 2.0, 2.0, 0.5])?;
    // Larger steps than the default (0.05 rad) reach the far targets in fewer iterations; 0.1 rad
    // still lets the tip hold while the elbow task, infeasible near the stretched arm, pulls at
    // it (the second-order effect of a step grows with its square).
    let settings = DriverSettings {
        max_joint_step: 0.1,
        max_iterations: 200,
        ..DriverSettings::default()
    };
    let mut driver = PositionDriver::new(&solver, settings)?;
    let mut arm = PlanarArm {
        tip_target: [0.0; 2],
        elbow_height: 0.35,
        limits: JointLimitAvoidance::new(&bounds),
    };
    let mut q = vec![0.3, 0.4, 0.3, 0.2, 0.1];

    let _ = writeln!(
        text,
        "5-link planar arm, link lengths {LINKS:?} m; levels: 1 tip (x, y), 2 elbow height"
    );
    let _ = writeln!(
        text,
        "joint limits (rad): lower {:?}, upper {:?}\n",
        bounds.lower(),
        bounds.upper()
    );
    let targets = [
        ([0.55, 0.45], 0.35),
        ([0.70, 0.10], 0.35),
        ([0.40, 0.55], 0.45),
        ([0.95, 0.10], 0.30),
        ([1.20, 0.00], 0.30),
    ];
    for (tip, elbow) in targets {
        arm.tip_target = tip;
        arm.elbow_height = elbow;
        let report = driver.run(&mut solver, &mut arm, &mut q, &bounds)?;
        let tip_at = PlanarArm::point(&q, LINKS.len() - 1);
        let elbow_at = PlanarArm::point(&q, ELBOW)[1];
        let _ = writeln!(
            text,
            "tip target ({:.3}, {:.3}) m, elbow height {:.3} m: {:?} after {} iterations",
            tip[0], tip[1], elbow, report.stop, report.iterations
        );
        let _ = writeln!(
            text,
            "  level 1 tip         at ({:.4}, {:.4}) m, error {:.2e} m",
            tip_at[0],
            tip_at[1],
            report.task_errors()[0]
        );
        let _ = writeln!(
            text,
            "  level 2 elbow height {:.4} m,          error {:.2e} m",
            elbow_at,
            report.task_errors()[1]
        );
        let last = solver.report();
        let clamped = last.clamped_joints();
        let _ = writeln!(
            text,
            "  last step: level ranks {:?}, clamped joints {:?}, q = {:.3?} rad\n",
            last.levels().iter().map(|l| l.rank).collect::<Vec<_>>(),
            clamped,
            q
        );
    }
    // A reader that closed the pipe (`| head`) is not an error of ours.
    match std::io::Write::write_all(&mut std::io::stdout(), text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
