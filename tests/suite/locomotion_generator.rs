//! The walking pattern generator against independent computations: the preview gains against a
//! finite-horizon LQ solved densely here, and the ZMP of the produced CoM (recomputed from its
//! finite-difference second derivative) inside the support polygon at every tick, on a straight
//! walk, a turn, a side step, a stop and an online queue.

use nalgebra::{DMatrix, DVector, Matrix3, Vector2, Vector3};
use taskstack::Side;
use taskstack::locomotion::{
    CartTable, Footstep, GroundPose, LocomotionError, PatternGenerator, PreviewGains,
    PreviewSettings, SoleCentres, StepTiming, Support, SwingProfile, WalkSettings, WalkState,
};
use taskstack::robots::nao;
use taskstack::tasks::convex_hull;

const COM_HEIGHT: f64 = 0.25;
const DT: f64 = 0.005;
const TIMING: StepTiming = StepTiming {
    double_support: 0.15,
    single_support: 0.35,
};

/// The dense finite-horizon LQ: minimise `Σ_{i=1..N} Q (C x_i − r_i)² + Σ_{i=0..N} R u_i² +
/// x_{N+1}ᵀ P x_{N+1}` over `u_0 … u_N`, which is the infinite-horizon problem with a reference
/// that is zero after `N` ticks (the tail's optimal cost is `xᵀPx`). Returns `u_0`.
fn dense_first_jerk(
    m: &CartTable,
    p: &Matrix3<f64>,
    q: f64,
    r: f64,
    x0: Vector3<f64>,
    refs: &[f64],
) -> f64 {
    let n = refs.len();
    let vars = n + 1;
    // x_i = A^i x0 + Σ_{k<i} A^{i-1-k} B u_k, as (free part, input matrix rows).
    let mut powers = vec![Matrix3::identity()];
    for i in 1..=n + 1 {
        powers.push(m.a * powers[i - 1]);
    }
    let mut hessian = DMatrix::<f64>::identity(vars, vars) * r;
    let mut gradient = DVector::<f64>::zeros(vars);
    for i in 1..=n + 1 {
        let free = powers[i] * x0;
        let mut inputs = DMatrix::<f64>::zeros(3, vars);
        for k in 0..i {
            let column = powers[i - 1 - k] * m.b;
            inputs.set_column(k, &DVector::from_column_slice(column.as_slice()));
        }
        if i <= n {
            let g = inputs.transpose() * DVector::from_column_slice(m.c.as_slice());
            let a = m.c.dot(&free) - refs[i - 1];
            hessian += &g * g.transpose() * q;
            gradient += &g * (a * q);
        } else {
            let pd = DMatrix::from_column_slice(3, 3, p.as_slice());
            hessian += inputs.transpose() * &pd * &inputs;
            gradient += inputs.transpose() * pd * DVector::from_column_slice(free.as_slice());
        }
    }
    let u = hessian
        .cholesky()
        .expect("positive definite")
        .solve(&(-gradient));
    u[0]
}

#[test]
fn preview_gains_equal_the_dense_finite_horizon_lq() {
    for (height, dt, horizon) in [(0.26, 0.01, 1.0), (0.68, 0.01, 1.6), (0.25, 0.02, 0.8)] {
        let model = CartTable::new(height, dt).unwrap();
        let settings = PreviewSettings {
            q: 1.0,
            r: 1e-6,
            horizon,
        };
        let gains = PreviewGains::new(model, settings).unwrap();
        let n = gains.window();
        // A state and a reference that are not special: an offset CoM moving, a stepping ZMP.
        let x0 = Vector3::new(0.012, -0.05, 0.3);
        let refs: Vec<f64> = (0..n)
            .map(|j| 0.04 * ((j as f64 * 0.13).sin()) + 0.01)
            .collect();
        let dense = dense_first_jerk(&model, gains.riccati(), 1.0, 1e-6, x0, &refs);
        let preview = gains.jerk(&x0, &refs);
        assert!(
            (dense - preview).abs() <= 1e-6 * dense.abs().max(1.0),
            "z_c {height}: dense {dense} vs preview {preview}"
        );
        // The Riccati solution satisfies its equation.
        let (a, b, c) = (model.a, model.b, model.c);
        let p = gains.riccati();
        let rhs = a.transpose() * p * a + c * c.transpose()
            - (a.transpose() * p * b) * (b.transpose() * p * a)
                / (1e-6 + (b.transpose() * p * b)[0]);
        assert!((rhs - p).abs().max() <= 1e-9 * p.abs().max());
    }
}

fn nao_centres() -> (SoleCentres, [Vec<[f64; 2]>; 2]) {
    let outlines = Side::BOTH.map(|s| nao::sole_outline(s).to_vec());
    let centres = SoleCentres::of_outlines([&outlines[0], &outlines[1]]).unwrap();
    (centres, outlines)
}

fn settings() -> WalkSettings {
    WalkSettings {
        com_height: COM_HEIGHT,
        dt: DT,
        preview: PreviewSettings::default(),
        swing: SwingProfile {
            height: 0.02,
            lift_share: 0.15,
        },
        stop_duration: 0.5,
        start_duration: 0.5,
        capacity: 16,
    }
}

fn standing() -> [GroundPose; 2] {
    [
        GroundPose::new(0.0, 0.05, 0.0),
        GroundPose::new(0.0, -0.05, 0.0),
    ]
}

fn generator() -> PatternGenerator {
    let (centres, _) = nao_centres();
    let feet = standing();
    let mid = (centres.world(Side::Left, &feet[0]) + centres.world(Side::Right, &feet[1])) / 2.0;
    PatternGenerator::new(settings(), centres, feet, mid).unwrap()
}

/// Signed distance of `p` inside the convex polygon `hull` (counter-clockwise), m.
fn margin(hull: &[[f64; 2]], p: Vector2<f64>) -> f64 {
    (0..hull.len())
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
            let edge = Vector2::new(b[0] - a[0], b[1] - a[1]);
            let normal = Vector2::new(-edge.y, edge.x).normalize();
            normal.dot(&(p - Vector2::new(a[0], a[1])))
        })
        .fold(f64::INFINITY, f64::min)
}

/// The support polygon of a state (world): the hull of the outlines of the soles on the floor.
fn polygon(state: &WalkState, outlines: &[Vec<[f64; 2]>; 2]) -> Vec<[f64; 2]> {
    let mut points = Vec::new();
    for side in Side::BOTH {
        if matches!(state.support, Support::Single { swing, .. } if swing == side) {
            continue;
        }
        let foot = state.feet[side.index()];
        let pose = GroundPose::new(foot.position[0], foot.position[1], foot.yaw);
        points.extend(outlines[side.index()].iter().map(|&c| {
            let w = pose.to_world(c);
            [w.x, w.y]
        }));
    }
    let mut hull = Vec::new();
    convex_hull(&mut points, &mut hull);
    hull
}

/// Runs the generator to rest, pushing `steps` up front; checks every tick and returns the
/// states.
fn walk(generator: &mut PatternGenerator, steps: &[Footstep]) -> Vec<WalkState> {
    for step in steps {
        generator.push(*step).unwrap();
    }
    run_to_rest(generator, |_| {})
}

fn run_to_rest(
    generator: &mut PatternGenerator,
    mut before_tick: impl FnMut(&mut PatternGenerator),
) -> Vec<WalkState> {
    let mut states = vec![*generator.state()];
    while !generator.is_stopped() || states.len() < 200 {
        before_tick(generator);
        states.push(*generator.tick());
        assert!(states.len() < 100_000, "the walk never stops");
    }
    for _ in 0..400 {
        states.push(*generator.tick());
    }
    check_walk(&states);
    states
}

/// The invariants of a walk: ZMP from the CoM's second difference ≥ 5 mm inside the support,
/// standing feet still, swing feet landing with zero speed, the CoM at rest at the end.
fn check_walk(states: &[WalkState]) {
    let (_, outlines) = nao_centres();
    let mut worst = f64::INFINITY;
    for k in 1..states.len() - 1 {
        let c = |i: usize| states[i].com.xy();
        let acceleration = (c(k + 1) - 2.0 * c(k) + c(k - 1)) / (DT * DT);
        let zmp = c(k) - acceleration * (COM_HEIGHT / 9.81);
        let m = margin(&polygon(&states[k], &outlines), zmp);
        worst = worst.min(m);
        assert!(
            m >= 0.005,
            "tick {k} (t = {:.3} s): ZMP {m:.4} m inside the support",
            states[k].time
        );
        // The central difference is the model's c̈ plus T·Δu/6 where the jerk u jumps.
        assert!(
            (states[k].zmp - zmp).norm() < 1e-3,
            "the reported ZMP is the CoM's: {} m off at t = {:.3} s",
            (states[k].zmp - zmp).norm(),
            states[k].time
        );
        for side in Side::BOTH {
            let on_floor = |s: &WalkState| !matches!(s.support, Support::Single { swing, .. } if swing == side);
            let (before, now) = (
                states[k - 1].feet[side.index()],
                states[k].feet[side.index()],
            );
            if on_floor(&states[k - 1]) && on_floor(&states[k]) {
                assert_eq!(before, now, "a sole on the floor moved at tick {k}");
            }
            if !on_floor(&states[k - 1]) && on_floor(&states[k]) {
                let speed = (0..3)
                    .map(|i| (now.position[i] - before.position[i]).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    / DT;
                assert!(speed < 1e-3, "a foot landed at {speed} m/s");
            }
        }
    }
    let last = states.last().unwrap();
    assert!(last.com_velocity.norm() < 1e-3, "the CoM comes to rest");
    let mid = (last.feet[0].position[0] + last.feet[1].position[0]) / 2.0;
    assert!(
        (last.com.x - mid - 0.02).abs() < 0.01,
        "the CoM rests between the feet"
    );
    assert!(worst < 0.05, "the check saw single support");
}

fn step(side: Side, x: f64, y: f64, yaw: f64) -> Footstep {
    Footstep {
        side,
        target: GroundPose::new(x, y, yaw),
        timing: TIMING,
    }
}

#[test]
fn a_straight_walk_keeps_the_zmp_inside_and_arrives() {
    let mut g = generator();
    let steps: Vec<Footstep> = (1..=8)
        .map(|i| {
            let side = if i % 2 == 1 { Side::Left } else { Side::Right };
            let y = if side == Side::Left { 0.05 } else { -0.05 };
            step(side, 0.06 * i as f64, y, 0.0)
        })
        .chain([step(Side::Left, 0.48, 0.05, 0.0)])
        .collect();
    let states = walk(&mut g, &steps);
    let last = states.last().unwrap();
    assert!(
        (last.feet[0].position[0] - 0.48).abs() < 1e-12
            && (last.feet[1].position[0] - 0.48).abs() < 1e-12
    );
    assert!(
        (last.com.x - 0.50).abs() < 0.01,
        "CoM over the final feet: {}",
        last.com.x
    );
    // 9 steps of 0.5 s, the first from rest with a 0.5 s double support instead of 0.15 s: the
    // last foot lands at 0.35 + 9 × 0.5 = 4.85 s.
    let end = states
        .iter()
        .rposition(|s| matches!(s.support, Support::Single { .. }))
        .unwrap();
    assert!((states[end].time - 4.85).abs() < 0.01);
}

#[test]
fn a_turn_in_place_and_a_side_step_keep_the_zmp_inside() {
    // Turn 0.6 rad to the left in place, in four steps about the midpoint.
    let mut g = generator();
    let mut steps = Vec::new();
    for i in 1..=4 {
        let yaw = 0.15 * i as f64;
        for side in [Side::Left, Side::Right] {
            let lateral = if side == Side::Left { 0.05 } else { -0.05 };
            steps.push(step(side, -lateral * yaw.sin(), lateral * yaw.cos(), yaw));
        }
    }
    let states = walk(&mut g, &steps);
    let last = states.last().unwrap();
    assert!((last.feet[0].yaw - 0.6).abs() < 1e-12 && (last.feet[1].yaw - 0.6).abs() < 1e-12);
    // Side steps: 4 cm to the right, leading with the right foot.
    let mut g = generator();
    let steps: Vec<Footstep> = (1..=3)
        .flat_map(|i| {
            let y = -0.04 * i as f64;
            [
                step(Side::Right, 0.0, y - 0.05, 0.0),
                step(Side::Left, 0.0, y + 0.05, 0.0),
            ]
        })
        .collect();
    let states = walk(&mut g, &steps);
    assert!((states.last().unwrap().com.y + 0.12).abs() < 0.005);
}

#[test]
fn an_online_queue_fed_step_by_step_walks_and_stops() {
    // Steps arrive one at a time, each when the queue has at most one step left; then nothing.
    let mut g = generator();
    let mut next = 1;
    let states = run_to_rest(&mut g, |g| {
        if next <= 6 && g.queued() <= 1 {
            let side = if next % 2 == 1 {
                Side::Left
            } else {
                Side::Right
            };
            let y = if side == Side::Left { 0.05 } else { -0.05 };
            g.push(step(side, 0.05 * next as f64, y, 0.0)).unwrap();
            next += 1;
        }
    });
    assert_eq!(next, 7);
    let singles = states.windows(2).filter(|w| {
        !matches!(w[0].support, Support::Single { .. })
            && matches!(w[1].support, Support::Single { .. })
    });
    assert_eq!(singles.count(), 6, "six lift-offs");
    // A step queued after the robot stopped starts from rest and is as safe.
    let more = [step(Side::Left, 0.35, 0.05, 0.0)];
    let after = walk(&mut g, &more);
    assert!(after.iter().any(|s| matches!(
        s.support,
        Support::Single {
            swing: Side::Left,
            ..
        }
    )));
}

#[test]
fn the_swing_sole_lifts_carries_and_lands_flat() {
    let profile = SwingProfile {
        height: 0.03,
        lift_share: 0.2,
    };
    let (from, to) = (
        GroundPose::new(0.0, 0.1, 0.0),
        GroundPose::new(0.08, 0.12, 0.3),
    );
    let at = |tau: f64| profile.at(&from, &to, tau);
    assert_eq!(at(0.0).position, [0.0, 0.1, 0.0]);
    assert!((at(1.0).position[0] - 0.08).abs() < 1e-15 && (at(1.0).yaw - 0.3).abs() < 1e-15);
    assert!(
        (at(0.5).position[2] - 0.03).abs() < 1e-15,
        "peak at mid-swing"
    );
    // No horizontal motion while the sole rises off the floor (τ ≤ lift share).
    assert_eq!(at(0.2).position[0], 0.0);
    assert!(at(0.2).position[2] > 0.005);
    // Zero vertical speed at touchdown (central difference at τ = 1).
    let h = 1e-4;
    assert!((at(1.0).position[2] - at(1.0 - h).position[2]).abs() / h < 1e-6);
}

#[test]
fn bad_input_is_refused_with_a_typed_error() {
    let (centres, _) = nao_centres();
    let bad_height = WalkSettings {
        com_height: f64::NAN,
        ..settings()
    };
    let err = PatternGenerator::new(bad_height, centres.clone(), standing(), Vector2::zeros())
        .unwrap_err();
    assert!(matches!(
        err,
        LocomotionError::InvalidParameter {
            name: "com_height",
            ..
        }
    ));
    let bad_swing = WalkSettings {
        swing: SwingProfile {
            height: 0.02,
            lift_share: 0.5,
        },
        ..settings()
    };
    assert!(
        PatternGenerator::new(bad_swing, centres.clone(), standing(), Vector2::zeros()).is_err()
    );
    let err = PatternGenerator::new(settings(), centres, standing(), Vector2::new(f64::NAN, 0.0))
        .unwrap_err();
    assert_eq!(err, LocomotionError::NonFinite("initial feet or CoM"));
    assert!(SoleCentres::of_outlines([&[[0.0, 0.0]], &[[0.0, 0.0]]]).is_err());

    let mut g = generator();
    let nan = Footstep {
        target: GroundPose::new(f64::NAN, 0.0, 0.0),
        ..step(Side::Left, 0.0, 0.0, 0.0)
    };
    assert!(matches!(g.push(nan), Err(LocomotionError::NonFinite(_))));
    let zero = Footstep {
        timing: StepTiming {
            double_support: 0.0,
            single_support: 0.3,
        },
        ..step(Side::Left, 0.0, 0.05, 0.0)
    };
    assert!(matches!(
        g.push(zero),
        Err(LocomotionError::InvalidParameter { .. })
    ));
    for _ in 0..16 {
        g.push(step(Side::Left, 0.0, 0.05, 0.0)).unwrap();
    }
    assert_eq!(
        g.push(step(Side::Left, 0.0, 0.05, 0.0)),
        Err(LocomotionError::QueueFull { capacity: 16 })
    );
    assert!(matches!(
        PreviewGains::new(
            CartTable::new(0.25, 0.01).unwrap(),
            PreviewSettings {
                r: -1.0,
                ..PreviewSettings::default()
            }
        ),
        Err(LocomotionError::InvalidParameter { name: "r", .. })
    ));
}

#[test]
fn cancelled_steps_are_not_taken_and_the_walk_stops_safely() {
    let mut g = generator();
    for i in 1..=6 {
        let side = if i % 2 == 1 { Side::Left } else { Side::Right };
        let y = if side == Side::Left { 0.05 } else { -0.05 };
        g.push(step(side, 0.05 * i as f64, y, 0.0)).unwrap();
    }
    // The first step (from rest: 0.5 s double support) lands at 0.85 s, the second swings from
    // 1.0 to 1.35 s. Cancelled at 1.2 s: the second step finishes, the third (toward whose
    // stance the CoM is already heading) is kept, the other three are dropped, and the robot
    // stops where the third step put its feet.
    let mut cancelled = 0;
    let states = run_to_rest(&mut g, |g| {
        if cancelled == 0 && g.state().time >= 1.2 {
            cancelled = g.cancel_pending();
        }
    });
    assert_eq!(cancelled, 3);
    let last = states.last().unwrap();
    assert!(
        (last.feet[0].position[0] - 0.15).abs() < 1e-12
            && (last.feet[1].position[0] - 0.10).abs() < 1e-12
    );
    assert_eq!(g.planned_feet(), g.standing_feet());
}

/// `restart` puts a generator that has walked back where a new one starts: the same state, and
/// the same walk from there, tick for tick; a non-finite pose is refused and leaves it as it was.
#[test]
fn a_restarted_generator_walks_like_a_new_one() {
    let feet = [
        GroundPose::new(0.3, 0.15, 0.2),
        GroundPose::new(0.32, 0.05, 0.2),
    ];
    let com = Vector2::new(0.33, 0.1);
    let (centres, _) = nao_centres();
    let mut fresh = PatternGenerator::new(settings(), centres, feet, com).unwrap();
    let mut used = generator();
    walk(&mut used, &[step(Side::Left, 0.04, 0.1, 0.0)]);
    let before = *used.state();
    let bad = [GroundPose::new(f64::NAN, 0.0, 0.0), feet[1]];
    assert!(used.restart(bad, com).is_err());
    assert_eq!(*used.state(), before);
    used.restart(feet, com).unwrap();
    assert_eq!(used.state(), fresh.state());
    assert_eq!(used.queued(), 0);
    assert!(used.is_stopped());
    let next = step(Side::Right, 0.36, 0.05, 0.2);
    let (a, b) = (walk(&mut used, &[next]), walk(&mut fresh, &[next]));
    assert_eq!(a, b);
}
