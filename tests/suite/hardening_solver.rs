//! Singularity and reachability torture (issue 6, item 3).
//!
//! On the NAO rooted at the right sole, a stack like the paper's (level 0: left sole position;
//! level 1: CoM xy; level 2: both hands; level 3: the left hand again) is driven by the
//! [`PositionDriver`] from stretched legs, arms at their limits, or random postures toward
//! targets up to kilometres away, with random gains, time steps and step limits, and with every
//! joint clamped. Then one more velocity solve at the final posture is checked against an
//! independent recomputation: every output finite, every joint within its limits, each level's
//! reported residual equal to `‖J_j q̇ − ẋ_j‖` recomputed here, `feasible` agreeing with it, and
//! contradictory levels never both reported feasible. At the solver level, random stacks mixing
//! magnitudes from 1e−150 to 1e150 in one matrix, duplicate rows, all-zero levels and n = 1.
//!
//! Long run: `PROPTEST_CASES=10000 cargo test --release --test hardening_solver`.

use faer::Mat;
use nalgebra::Vector3;
use proptest::prelude::*;
use taskstack::model::{FrameId, Model, ModelData, ModelError};
use taskstack::robots::nao;
use taskstack::solver::driver::{DriverSettings, PositionDriver, TaskModel};
use taskstack::solver::{JointBounds, Solver, SolverError, StackShape, TaskStack};

fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// The message of a solver or model error (shown when a run fails).
#[derive(Debug)]
struct EvalError(#[allow(dead_code)] String);

impl From<SolverError> for EvalError {
    fn from(e: SolverError) -> Self {
        EvalError(e.to_string())
    }
}

impl From<ModelError> for EvalError {
    fn from(e: ModelError) -> Self {
        EvalError(e.to_string())
    }
}

/// The NAO with position targets (metres, base frame = right sole frame) for the four levels.
struct Nao {
    model: Model,
    data: ModelData,
    l_sole: FrameId,
    l_hand: FrameId,
    r_hand: FrameId,
    sole_target: Vector3<f64>,
    com_target: [f64; 2],
    hand_targets: [Vector3<f64>; 2],
    /// Level 3's target for the left hand.
    second_hand_target: Vector3<f64>,
}

const LEVEL_ROWS: [usize; 4] = [3, 2, 6, 3];

impl Nao {
    fn new() -> Self {
        let model = nao::rfoot();
        let data = model.new_data();
        let id = |name| model.frame_id(name).unwrap();
        let (l_sole, l_hand, r_hand) = (id("l_sole"), id("l_hand"), id("r_hand"));
        Nao {
            model,
            data,
            l_sole,
            l_hand,
            r_hand,
            sole_target: Vector3::zeros(),
            com_target: [0.0; 2],
            hand_targets: [Vector3::zeros(); 2],
            second_hand_target: Vector3::zeros(),
        }
    }

    /// Positions at `q` of the left sole, CoM xy, left and right hand.
    fn positions(&mut self, q: &[f64]) -> [Vector3<f64>; 4] {
        self.model.forward_kinematics(&mut self.data, q).unwrap();
        let zero = Vector3::zeros();
        let at = |f| self.model.point_position(&self.data, f, &zero).unwrap();
        [
            at(self.l_sole),
            self.model.com(&self.data).unwrap(),
            at(self.l_hand),
            at(self.r_hand),
        ]
    }

    fn bounds(&self) -> JointBounds {
        let v = self.model.variables();
        let lower: Vec<f64> = v.iter().map(|v| v.lower).collect();
        let upper: Vec<f64> = v.iter().map(|v| v.upper).collect();
        let speed: Vec<f64> = v.iter().map(|v| v.velocity).collect();
        JointBounds::with_velocity(&lower, &upper, &speed).unwrap()
    }
}

impl TaskModel for Nao {
    type Error = EvalError;

    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), EvalError> {
        let m = &self.model;
        m.forward_kinematics(&mut self.data, q)?;
        let zero = Vector3::zeros();
        let mut point = |level: usize, row: usize, frame: FrameId, target: &Vector3<f64>| {
            let mut l = stack.level_mut(level);
            m.point_jacobian(
                &self.data,
                frame,
                &zero,
                l.jacobian_mut().subrows_mut(row, 3),
            )?;
            let x = m.point_position(&self.data, frame, &zero)?;
            for r in 0..3 {
                l.target_mut()[row + r] = target[r] - x[r];
            }
            Ok::<(), EvalError>(())
        };
        point(0, 0, self.l_sole, &self.sole_target)?;
        point(2, 0, self.l_hand, &self.hand_targets[0])?;
        point(2, 3, self.r_hand, &self.hand_targets[1])?;
        point(3, 0, self.l_hand, &self.second_hand_target)?;
        let mut l = stack.level_mut(1);
        m.com_jacobian_rows(&self.data, 2, l.jacobian_mut())?;
        let c = m.com(&self.data)?;
        l.target_mut()[0] = self.com_target[0] - c.x;
        l.target_mut()[1] = self.com_target[1] - c.y;
        stack.clear_gradient();
        Ok(())
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Checks the last solve of `solver` at `q` against an independent recomputation from the stack:
/// finite velocity; `q + q̇ Δt` within the position limits and `|q̇|` within the velocity limits;
/// each level's residual `‖J q̇ − ẋ‖`, rank and feasibility. Returns the recomputed residuals.
fn check_solve(solver: &Solver, q: &[f64], bounds: &JointBounds, dt: f64) -> Vec<f64> {
    let v = solver.velocity();
    let report = solver.report();
    assert!(v.iter().all(|x| x.is_finite()), "velocity {v:?}");
    for i in 0..v.len() {
        let next = q[i] + v[i] * dt;
        assert!(
            next >= bounds.lower()[i] && next <= bounds.upper()[i],
            "joint {i}: q + q̇Δt = {next} outside [{}, {}]",
            bounds.lower()[i],
            bounds.upper()[i]
        );
        assert!(
            v[i].abs() <= bounds.velocity()[i] * (1.0 + 1e-12),
            "joint {i}: |q̇| = {} above {}",
            v[i].abs(),
            bounds.velocity()[i]
        );
    }
    let stack = solver.stack();
    let tol = solver.settings().feasibility_tolerance;
    let mut residuals = Vec::new();
    for (j, level) in report.levels().iter().enumerate() {
        let jac = stack.jacobian(j);
        let target = stack.target(j);
        let r: Vec<f64> = (0..jac.nrows())
            .map(|row| (0..jac.ncols()).map(|c| jac[(row, c)] * v[c]).sum::<f64>() - target[row])
            .collect();
        let residual = norm(&r);
        let scale = 1.0 + norm(target);
        assert!(level.residual.is_finite() && level.damping.is_finite() && level.damping >= 0.0);
        assert!(level.rank <= level.rows && level.rows == jac.nrows());
        // The report's residual is the one recomputed here (up to rounding of the products).
        let rounding = 1e-9 * (scale + residual);
        assert!(
            (level.residual - residual).abs() <= rounding,
            "level {j}: reported residual {} vs recomputed {residual}",
            level.residual
        );
        // Away from the threshold, `feasible` agrees with the recomputed residual.
        let threshold = tol * scale;
        if (residual - threshold).abs() > 1e-3 * threshold + rounding {
            assert_eq!(
                level.feasible,
                residual <= threshold,
                "level {j}: {level:?}"
            );
        }
        residuals.push(residual);
    }
    assert_eq!(
        report.first_infeasible_level(),
        report.levels().iter().position(|l| !l.feasible)
    );
    residuals
}

#[derive(Debug, Clone, Copy)]
enum Posture {
    Random,
    /// Both knees at 0 (the legs fully stretched: the sole's Jacobian loses the vertical).
    StretchedLegs,
    /// Every arm joint at one of its limits.
    ArmsAtLimits,
}

#[derive(Debug, Clone)]
struct Torture {
    posture: Posture,
    unit: Vec<f64>,
    /// log10 of how far the targets are moved (metres).
    log_distance: f64,
    directions: Vec<f64>,
    contradictory: bool,
    log_gain: f64,
    log_dt: f64,
    max_task_error: f64,
    max_joint_step: f64,
}

fn torture() -> impl Strategy<Value = Torture> {
    (
        prop_oneof![
            Just(Posture::Random),
            Just(Posture::StretchedLegs),
            Just(Posture::ArmsAtLimits)
        ],
        proptest::collection::vec(0.0..=1.0f64, 23),
        -3.0..3.5f64,
        proptest::collection::vec(-1.0..1.0f64, 15),
        any::<bool>(),
        (-6.0..6.0f64, -6.0..3.0f64),
        proptest::sample::select(vec![0.05, 1e3, f64::INFINITY]),
        proptest::sample::select(vec![0.05, 1.0, f64::INFINITY]),
    )
        .prop_map(
            |(posture, unit, log_distance, directions, contradictory, (lg, ldt), mte, mjs)| {
                Torture {
                    posture,
                    unit,
                    log_distance,
                    directions,
                    contradictory,
                    log_gain: lg,
                    log_dt: ldt,
                    max_task_error: mte,
                    max_joint_step: mjs,
                }
            },
        )
}

const ARM_JOINTS: [usize; 10] = [2, 3, 4, 5, 6, 18, 19, 20, 21, 22];
const KNEES: [usize; 2] = [10, 15];

fn start_posture(nao: &Nao, t: &Torture) -> Vec<f64> {
    let vars = nao.model.variables();
    let mut q: Vec<f64> = vars
        .iter()
        .zip(&t.unit)
        .map(|(v, u)| v.lower + u * (v.upper - v.lower))
        .collect();
    match t.posture {
        Posture::Random => {}
        Posture::StretchedLegs => {
            for k in KNEES {
                q[k] = 0.0_f64.clamp(vars[k].lower, vars[k].upper);
            }
        }
        Posture::ArmsAtLimits => {
            for k in ARM_JOINTS {
                q[k] = if t.unit[k] < 0.5 {
                    vars[k].lower
                } else {
                    vars[k].upper
                };
            }
        }
    }
    q
}

/// Builds the stack and targets of `t`; returns (nao, solver, q, the left-hand contradiction).
fn setup(t: &Torture) -> (Nao, Solver, Vec<f64>, f64) {
    let mut nao = Nao::new();
    let q = start_posture(&nao, t);
    let [sole, com, l_hand, r_hand] = nao.positions(&q);
    let distance = 10f64.powf(t.log_distance);
    let d = |k: usize| {
        let v = Vector3::new(
            t.directions[3 * k],
            t.directions[3 * k + 1],
            t.directions[3 * k + 2],
        );
        v * distance / v.norm().max(1e-3)
    };
    nao.sole_target = sole + d(0);
    let c = com + d(1);
    nao.com_target = [c.x, c.y];
    nao.hand_targets = [l_hand + d(2), r_hand + d(3)];
    // Level 3 asks the left hand to be elsewhere (0.1–1 m away) or at the same target.
    let offset = if t.contradictory {
        let v = d(4);
        v / v.norm().max(1e-300) * (0.1 + 0.9 * t.unit[0])
    } else {
        Vector3::zeros()
    };
    nao.second_hand_target = nao.hand_targets[0] + offset;
    let shape = StackShape::from_level_rows(23, &LEVEL_ROWS);
    let solver = Solver::new(&shape).unwrap();
    (nao, solver, q, offset.norm())
}

fn run_torture(t: &Torture, bounds_of: impl Fn(&Nao, &[f64]) -> JointBounds) {
    let (mut nao, mut solver, mut q, contradiction) = setup(t);
    let bounds = bounds_of(&nao, &q);
    let settings = DriverSettings {
        gain: 10f64.powf(t.log_gain),
        dt: 10f64.powf(t.log_dt),
        max_task_error: t.max_task_error,
        max_joint_step: t.max_joint_step,
        ..DriverSettings::default()
    };
    let mut driver = PositionDriver::new(&solver, settings).unwrap();
    let report = driver
        .run(&mut solver, &mut nao, &mut q, &bounds)
        .expect("finite input is solved");
    assert!(report.task_errors().iter().all(|e| e.is_finite()));
    for (i, x) in q.iter().enumerate() {
        assert!(
            *x >= bounds.lower()[i] && *x <= bounds.upper()[i],
            "joint {i} = {x} outside its limits"
        );
    }
    // One more velocity solve at the final posture with the raw task errors as velocities.
    nao.evaluate(&q, solver.stack_mut()).unwrap();
    solver.solve(&q, &bounds, settings.dt).unwrap();
    let residuals = check_solve(&solver, &q, &bounds, settings.dt);
    let levels = solver.report().levels();
    if contradiction > 0.0 {
        // Level 2 holds the left hand at A, level 3 asks B, |B − A| ≥ 0.1 m: they cannot both
        // hold, and if level 2 does, level 3 misses by |B − A| (up to level 2's tolerance).
        assert!(!(levels[2].feasible && levels[3].feasible), "{levels:?}");
        if levels[2].feasible {
            assert!(
                (residuals[3] - contradiction).abs() <= 1e-6 * (1.0 + residuals[3]),
                "level 3 residual {} vs contradiction {contradiction}",
                residuals[3]
            );
        }
    } else if levels[2].feasible {
        // The same target twice: level 3 is level 2's left-hand rows, met with it.
        assert!(levels[3].feasible, "{levels:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(150)))]

    #[test]
    fn nao_driven_anywhere_stays_finite_and_within_limits(t in torture()) {
        run_torture(&t, |nao, _| nao.bounds());
    }

    #[test]
    fn nao_with_every_joint_clamped_does_not_move(t in torture(), zero_width in any::<bool>()) {
        // Either zero-width position ranges at the start posture, or (almost) zero speed limits.
        let bounds_of = |nao: &Nao, q: &[f64]| {
            if zero_width {
                JointBounds::new(q, q).unwrap()
            } else {
                let b = nao.bounds();
                JointBounds::with_velocity(b.lower(), b.upper(), &[1e-300; 23]).unwrap()
            }
        };
        run_torture(&t, bounds_of);
        // And directly: one solve with a far target moves nothing, and level 0 gives way.
        let (mut nao, mut solver, q, _) = setup(&Torture { log_distance: 0.0, ..t.clone() });
        let bounds = bounds_of(&nao, &q);
        nao.evaluate(&q, solver.stack_mut()).unwrap();
        solver.solve(&q, &bounds, 0.01).unwrap();
        check_solve(&solver, &q, &bounds, 0.01);
        prop_assert!(solver.velocity().iter().all(|v| v.abs() <= 1e-300));
        prop_assert_eq!(solver.report().first_infeasible_level(), Some(0));
        prop_assert!(solver.report().levels()[0].residual > 0.5);
    }
}

#[test]
fn targets_a_kilometre_away_are_reported_infeasible_from_the_top() {
    let t = Torture {
        posture: Posture::StretchedLegs,
        unit: vec![0.5; 23],
        log_distance: 3.0,
        directions: vec![
            0.0, 0.0, -1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 0.0,
        ],
        contradictory: true,
        log_gain: 0.0,
        log_dt: 0.0,
        max_task_error: 0.05,
        max_joint_step: 0.05,
    };
    let (mut nao, mut solver, mut q, _) = setup(&t);
    let bounds = nao.bounds();
    let mut driver = PositionDriver::new(&solver, DriverSettings::default()).unwrap();
    let report = driver.run(&mut solver, &mut nao, &mut q, &bounds).unwrap();
    // A sole 1 km below the ground cannot be reached: the error stays about 1 km.
    assert!(
        report.task_errors()[0] > 999.0,
        "{:?}",
        report.task_errors()
    );
    nao.evaluate(&q, solver.stack_mut()).unwrap();
    solver.solve(&q, &bounds, 1.0).unwrap();
    check_solve(&solver, &q, &bounds, 1.0);
    assert_eq!(solver.report().first_infeasible_level(), Some(0));
}

// ---------------------------------------------------------------------------------------------
// Random stacks at the solver level.

#[derive(Debug, Clone)]
struct RandomStack {
    n: usize,
    rows: Vec<usize>,
    /// Per entry: (mantissa in [−1, 1], log10 magnitude in [−150, 150], zero?).
    entries: Vec<(f64, f64, bool)>,
    /// Levels set entirely to zero (Jacobian and target).
    zero_levels: Vec<bool>,
    /// Rows copied from the row above (within the stack).
    duplicate: Vec<bool>,
    bounds: Vec<(f64, f64, f64)>,
    log_dt: f64,
}

fn random_stack() -> impl Strategy<Value = RandomStack> {
    (1usize..8, proptest::collection::vec(1usize..5, 1..5)).prop_flat_map(|(n, rows)| {
        let total: usize = rows.iter().sum();
        let levels = rows.len();
        (
            Just(n),
            Just(rows),
            proptest::collection::vec(
                (
                    -1.0..1.0f64,
                    -150.0..150.0f64,
                    proptest::bool::weighted(0.1),
                ),
                total * (n + 1),
            ),
            proptest::collection::vec(proptest::bool::weighted(0.15), levels),
            proptest::collection::vec(proptest::bool::weighted(0.2), total),
            proptest::collection::vec((-1.0..0.0f64, 0.0..1.0f64, -3.0..3.0f64), n),
            -6.0..2.0f64,
        )
            .prop_map(
                |(n, rows, entries, zero_levels, duplicate, bounds, log_dt)| RandomStack {
                    n,
                    rows,
                    entries,
                    zero_levels,
                    duplicate,
                    bounds,
                    log_dt,
                },
            )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(1000)))]

    #[test]
    fn random_extreme_stacks_give_finite_bounded_velocities(s in random_stack()) {
        let shape = StackShape::from_level_rows(s.n, &s.rows);
        let mut solver = Solver::new(&shape).unwrap();
        let mut stacked = Mat::<f64>::zeros(s.rows.iter().sum(), s.n + 1);
        let mut row = 0;
        for (level, &m) in s.rows.iter().enumerate() {
            for r in 0..m {
                for c in 0..=s.n {
                    let (mantissa, log, zero) = s.entries[row * (s.n + 1) + c];
                    stacked[(row, c)] = if s.zero_levels[level] || zero {
                        0.0
                    } else if s.duplicate[row] && row > 0 {
                        stacked[(row - 1, c)]
                    } else {
                        mantissa * 10f64.powf(log)
                    };
                }
                let values: Vec<f64> = (0..s.n).map(|c| stacked[(row, c)]).collect();
                solver
                    .stack_mut()
                    .level_mut(level)
                    .set_row(r, &values, stacked[(row, s.n)])
                    .unwrap();
                row += 1;
            }
        }
        // Limits around q = 0, speeds 10^±3, so that clamping happens often.
        let q = vec![0.0; s.n];
        let lower: Vec<f64> = s.bounds.iter().map(|b| b.0).collect();
        let upper: Vec<f64> = s.bounds.iter().map(|b| b.1).collect();
        let speed: Vec<f64> = s.bounds.iter().map(|b| 10f64.powf(b.2)).collect();
        let bounds = JointBounds::with_velocity(&lower, &upper, &speed).unwrap();
        let dt = 10f64.powf(s.log_dt);
        solver.solve(&q, &bounds, dt).expect("finite input is solved");
        let v = solver.velocity().to_vec();
        prop_assert!(v.iter().all(|x| x.is_finite()), "{v:?}");
        for i in 0..s.n {
            let next = q[i] + v[i] * dt;
            prop_assert!(next >= lower[i] && next <= upper[i]);
            prop_assert!(v[i].abs() <= speed[i] * (1.0 + 1e-12));
        }
        let report = solver.report();
        let mut rank_total = 0;
        for (level, l) in report.levels().iter().enumerate() {
            prop_assert!(
                l.residual.is_finite() && l.damping.is_finite(),
                "level {}: {:?}, q̇ = {:?}, stack {:?}",
                level,
                l,
                v,
                stacked
            );
            prop_assert!(l.rank <= l.rows);
            if s.zero_levels[level] {
                // An all-zero level uses no direction and is met by any q̇.
                prop_assert_eq!(l.rank, 0);
                prop_assert!(l.feasible);
            }
            rank_total += l.rank;
        }
        // Ranks of the levels share the n degrees of freedom.
        prop_assert!(rank_total <= s.n);
        // The unbounded solve too.
        let v = solver.solve_unbounded().unwrap().velocity.to_vec();
        prop_assert!(v.iter().all(|x| x.is_finite()), "{v:?}");
    }
}
