//! A whole robot walking: the footstep planner toward a goal and the walker's joint angles,
//! checked through forward kinematics (independent of the walker's own task errors): soles on
//! the floor still to 1e-6 m and rad, the CoM where the generator put it, the joint limits kept,
//! the ZMP of the realised CoM inside the support, the torso within its lean and a chest
//! leaning with it.

use nalgebra::{Vector2, Vector3};
use taskstack::Side;
use taskstack::locomotion::{
    Footstep, GroundPose, StepPlan, StepTiming, SupportPolygon, WalkParams, WholeBodyWalker,
    goal_feet, plan_steps,
};
use taskstack::robots::{BipedProfile, FootArea, g1, nao};

/// World pose (x, y, z, yaw) of `side`'s sole from the model rooted at `root`, placed at
/// `root_pose`.
fn sole_in_world(
    profile: &BipedProfile,
    q: &[f64],
    root: Side,
    root_pose: &GroundPose,
    side: Side,
) -> ([f64; 3], f64) {
    let model = profile.model(root);
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    let sole = data.frame_placement(model.frame_id(&profile.foot(side).sole).unwrap());
    let xy = root_pose.to_world([sole.translation.x, sole.translation.y]);
    let r = sole.rotation.matrix();
    (
        [xy.x, xy.y, sole.translation.z],
        root_pose.yaw + r[(1, 0)].atan2(r[(0, 0)]),
    )
}

/// The z axis of `frame` in the model rooted at `root` (its root sole is level, so the model's
/// z axis is the world's).
fn z_axis(profile: &BipedProfile, q: &[f64], root: Side, frame: &str) -> Vector3<f64> {
    let model = profile.model(root);
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    let r = data
        .frame_placement(model.frame_id(frame).unwrap())
        .rotation;
    r.matrix().column(2).into_owned()
}

fn com_in_world(profile: &BipedProfile, q: &[f64], root: Side, root_pose: &GroundPose) -> [f64; 3] {
    let model = profile.model(root);
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    let c = model.com(&data).unwrap();
    let xy = root_pose.to_world([c.x, c.y]);
    [xy.x, xy.y, c.z]
}

/// Walks `motion` (forward, left m; turn rad), checks every tick and returns the realised CoM's
/// smallest margin inside the support polygon (m).
fn walk_and_check(profile: &BipedProfile, motion: GroundPose) -> f64 {
    let params = WalkParams::for_profile(profile).unwrap();
    let (dt, height) = (params.settings.dt, params.settings.com_height);
    let mut walker =
        WholeBodyWalker::new(profile, params.clone(), GroundPose::new(0.0, 0.0, 0.0)).unwrap();
    let start = *walker.generator().standing_feet();
    let goal = goal_feet(&start, &motion);
    let steps = plan_steps(&start, &goal, &profile.step_envelope, params.timing, 100);
    for step in &steps {
        walker.push(*step).unwrap();
    }
    let outlines = Side::BOTH.map(|s| profile.foot(s).outline.as_slice());
    let mut polygon = SupportPolygon::new(outlines);
    let variables = profile.model(Side::Right).variables().to_vec();
    let mut previous: Option<[([f64; 3], f64); 2]> = None;
    let mut previous_on_floor = [true, true];
    let mut coms: Vec<[f64; 3]> = Vec::new();
    let mut states = Vec::new();
    let mut ticks = 0;
    let mut largest_sag = 0.0_f64;
    while !walker.generator().is_stopped() || ticks < 100 {
        let frame = *walker.tick().unwrap();
        ticks += 1;
        assert!(ticks < 10_000, "the walk never ends");
        let q = walker.q();
        for (v, &qi) in variables.iter().zip(q) {
            assert!(
                qi >= v.lower && qi <= v.upper,
                "{} = {qi} outside its limits",
                v.name
            );
        }
        // What the servos are told: the angles plus their sag (robots::servo), in the limits.
        let targets = walker.servo_targets();
        for ((v, &qi), &target) in variables.iter().zip(q).zip(targets) {
            assert!(
                target >= v.lower && target <= v.upper,
                "{} target {target}",
                v.name
            );
            if profile.servo_saturation.is_none() {
                assert_eq!(target, qi, "{}", v.name);
            }
            assert!(
                (target - qi).abs() < 0.05,
                "{} sags {} rad",
                v.name,
                target - qi
            );
            largest_sag = largest_sag.max((target - qi).abs());
        }
        let root_pose = walker.generator().standing_feet()[frame.root.index()];
        let soles = Side::BOTH.map(|s| sole_in_world(profile, q, frame.root, &root_pose, s));
        let on_floor = walker.generator().on_floor();
        for side in Side::BOTH {
            let (p, yaw) = soles[side.index()];
            let planned = frame.walk.feet[side.index()];
            for k in 0..3 {
                assert!(
                    (p[k] - planned.position[k]).abs() < 1e-5,
                    "sole off its plan"
                );
            }
            if let Some(before) =
                previous.filter(|_| on_floor[side.index()] && previous_on_floor[side.index()])
            {
                let (b, byaw) = before[side.index()];
                let moved =
                    ((p[0] - b[0]).powi(2) + (p[1] - b[1]).powi(2) + (p[2] - b[2]).powi(2)).sqrt();
                assert!(
                    moved <= 1e-6,
                    "a sole on the floor moved {moved} m at t = {}",
                    frame.walk.time
                );
                assert!((yaw - byaw).abs() <= 1e-6, "a sole on the floor turned");
            }
        }
        previous = Some(soles);
        previous_on_floor = on_floor;
        // The torso leans no further than the lean; on a robot with a waist the chest leans
        // with it (the waist does not carry the CoM).
        let torso = z_axis(profile, q, frame.root, &profile.torso);
        let tilt = torso.z.clamp(-1.0, 1.0).acos();
        assert!(
            tilt <= params.torso_lean + 1e-3,
            "the torso tilts {tilt} rad"
        );
        if let Some(chest) = &profile.chest {
            let chest = z_axis(profile, q, frame.root, chest);
            let bend = chest.angle(&torso);
            assert!(
                bend < 1e-4,
                "the chest bends {bend} rad at t = {}",
                frame.walk.time
            );
        }
        let com = com_in_world(profile, q, frame.root, &root_pose);
        assert!(
            (Vector2::new(com[0], com[1]) - frame.walk.com.xy()).norm() < 1e-4,
            "CoM off its plan"
        );
        coms.push(com);
        states.push(frame.walk);
    }
    // The ZMP of the realised CoM (its second difference), at the walking height, inside the
    // support by 5 mm at every tick once the CoM has come down to it.
    let mut com_margin = f64::INFINITY;
    for k in 1..coms.len() - 1 {
        let c = |i: usize| Vector2::new(coms[i][0], coms[i][1]);
        let zmp = c(k) - (c(k + 1) - 2.0 * c(k) + c(k - 1)) * (height / 9.81 / (dt * dt));
        let margin = polygon.margin(&states[k], zmp);
        assert!(
            margin >= 0.005,
            "ZMP {margin} m inside at t = {}",
            states[k].time
        );
        com_margin = com_margin.min(polygon.margin(&states[k], c(k)));
    }
    // Arrived: both soles on their goals.
    let end = walker.generator().standing_feet();
    for side in Side::BOTH {
        assert!((end[side.index()].xy - goal[side.index()].xy).norm() < 1e-9);
    }
    assert!(steps.len() >= 2);
    if profile.servo_saturation.is_some() {
        // Stiff servos still sag under a stance leg's load: several mrad.
        assert!(largest_sag > 0.003, "largest sag {largest_sag} rad");
    }
    com_margin
}

#[test]
fn the_nao_walks_forward_sideways_and_turns() {
    let profile = nao::profile();
    walk_and_check(&profile, GroundPose::new(0.3, 0.0, 0.0));
    walk_and_check(&profile, GroundPose::new(0.0, -0.12, 0.0));
    walk_and_check(&profile, GroundPose::new(0.0, 0.0, 0.5));
}

#[test]
fn the_g1_walks_forward() {
    walk_and_check(&g1::profile(), GroundPose::new(0.4, 0.0, 0.0));
}

#[test]
fn derived_settings_follow_the_robots_size() {
    let (nao, g1) = (
        WalkParams::for_profile(&nao::profile()).unwrap(),
        WalkParams::for_profile(&g1::profile()).unwrap(),
    );
    // Sole widths from the outlines: NAO FSR rectangle 53 mm, G1 contact spheres 50 mm.
    for (p, profile, sole_width) in [(&nao, nao::profile(), 0.053), (&g1, g1::profile(), 0.05)] {
        // Single support 3.5 pendulum time constants √(z_c/g), z_c the standing CoM height,
        // the swing carried over all but 5 % of it at each end; double support 3 or more, in
        // halves.
        let tau = (p.settings.com_height / 9.81).sqrt();
        assert_eq!(p.settings.com_height, p.standing_com_height);
        assert!((p.timing.single_support - 3.5 * tau).abs() < 1e-12);
        assert_eq!(p.settings.swing.lift_share, 0.05);
        let halves = p.timing.double_support / tau * 2.0;
        assert!(halves >= 6.0 - 1e-9 && (halves - halves.round()).abs() < 1e-9);
        // A straight walk of the envelope's longest steps keeps the planned CoM inside the
        // support by 15 % of the sole width, checked here through FK.
        let asked = 0.15 * sole_width;
        let margin = walk_and_check(&profile, GroundPose::new(0.3, 0.0, 0.0));
        assert!(
            margin >= asked - 2e-4,
            "CoM {margin} m inside, asked {asked}"
        );
    }
    assert!(
        (nao.timing.duration() - 1.08).abs() < 0.01,
        "NAO steps of 1.08 s: 3 + 3.5 time constants of 0.167 s"
    );
    assert!(
        g1.timing.double_support > 1.5 * g1.timing.single_support,
        "the G1's wide stance"
    );
    assert!(g1.settings.swing.height > 2.0 * nao.settings.swing.height);
    // The NAO's hips are 0.1 m apart (HipOffsetY 0.05): lean atan(0.05 / z_c).
    assert!((nao.torso_lean - (0.05 / nao.settings.com_height).atan()).abs() < 1e-3);
    // Landing clearance 0.6 % of the leg and the swing height 12 % of it: a twentieth of the
    // swing height (NAO about 1.5 mm), lowered in two time constants.
    for p in [&nao, &g1] {
        assert!((p.landing_clearance - p.settings.swing.height * 0.006 / 0.12).abs() < 1e-12);
        let tau = (p.settings.com_height / 9.81).sqrt();
        assert!((p.landing_preload_time - 2.0 * tau).abs() < 1e-12);
    }
    assert!(
        (0.0013..0.0017).contains(&nao.landing_clearance),
        "{}",
        nao.landing_clearance
    );
}

fn envelope() -> FootArea {
    nao::STEP_ENVELOPE
}

#[test]
fn the_planner_reaches_the_goal_within_the_envelope() {
    let timing = StepTiming {
        double_support: 0.3,
        single_support: 0.4,
    };
    let feet = [
        GroundPose::new(0.0, 0.05, 0.0),
        GroundPose::new(0.0, -0.05, 0.0),
    ];
    for (motion, first) in [
        (GroundPose::new(0.5, 0.0, 0.0), None),
        (GroundPose::new(-0.2, 0.0, 0.0), None),
        (GroundPose::new(0.0, 0.15, 0.0), Some(Side::Left)),
        (GroundPose::new(0.0, -0.15, 0.0), Some(Side::Right)),
        (GroundPose::new(0.0, 0.0, 0.9), Some(Side::Left)),
        (GroundPose::new(0.0, 0.0, -0.9), Some(Side::Right)),
        (GroundPose::new(0.4, 0.2, -0.6), None),
    ] {
        let goal = goal_feet(&feet, &motion);
        let steps = plan_steps(&feet, &goal, &envelope(), timing, 100);
        if let Some(first) = first {
            assert_eq!(
                steps[0].side, first,
                "the foot toward the goal leads ({motion:?})"
            );
        }
        let mut now = feet;
        for Footstep { side, target, .. } in &steps {
            let stance = now[side.other().index()];
            let rel = stance.relative(target);
            let lateral = if *side == Side::Left {
                rel.xy.y
            } else {
                -rel.xy.y
            };
            let e = envelope();
            assert!(rel.xy.x >= e.x_min - 1e-12 && rel.xy.x <= e.x_max + 1e-12);
            assert!(lateral >= e.lateral_min - 1e-12 && lateral <= e.lateral_max + 1e-12);
            assert!(rel.yaw.abs() <= e.yaw_max + 1e-12);
            now[side.index()] = *target;
        }
        for side in Side::BOTH {
            assert!(
                (now[side.index()].xy - goal[side.index()].xy).norm() < 1e-9,
                "{motion:?}"
            );
        }
    }
    // 0.5 m at most 5 cm a step: at least 10 steps, and no step is wasted standing still.
    let goal = goal_feet(&feet, &GroundPose::new(0.5, 0.0, 0.0));
    let steps = plan_steps(&feet, &goal, &envelope(), timing, 100);
    assert!(
        steps.len() >= 10 && steps.len() <= 12,
        "{} steps",
        steps.len()
    );
    assert!(plan_steps(&feet, &feet, &envelope(), timing, 100).is_empty());
}

/// [`StepPlan`]: a foot whose clipped target is within `min_move` of where it stands does not
/// step; with `alternate` the plan ends where the next foot would stay instead of stepping the
/// same foot twice; the given first foot moves first; `fill` reuses its buffer.
#[test]
fn step_plans_skip_small_moves_and_alternate_on_request() {
    let timing = StepTiming {
        double_support: 0.5,
        single_support: 0.5,
    };
    let feet = [
        GroundPose::new(0.0, 0.1, 0.0),
        GroundPose::new(0.0, 0.0, 0.0),
    ];
    let plan = |first, alternate, min_move| StepPlan {
        envelope: &nao::STEP_ENVELOPE,
        timing,
        first,
        max_steps: 4,
        min_move,
        alternate,
    };
    let exact = GroundPose::new(1e-9, 0.0, 1e-9);
    let mut steps = Vec::with_capacity(4);
    // Only the right foot is off its goal (0.3 m forward, beyond the envelope's 5 cm from the
    // left): left first, it stays, so the right steps as far as the envelope allows.
    let goal = [feet[0], GroundPose::new(0.3, 0.0, 0.0)];
    plan(Some(Side::Left), false, exact).fill(&feet, &goal, &mut steps);
    assert_eq!(steps[0].side, Side::Right);
    assert!((steps[0].target.xy.x - 0.05).abs() < 1e-12, "{steps:?}");
    // Alternating, the left would have to move first: it stays, so nothing is planned.
    plan(Some(Side::Left), true, exact).fill(&feet, &goal, &mut steps);
    assert!(steps.is_empty(), "{steps:?}");
    // A goal 1 cm off is no step with a 2 cm minimum move, one step without it.
    let near = [feet[0], GroundPose::new(0.01, 0.0, 0.0)];
    let two_cm = GroundPose::new(0.02, 0.0, 0.087);
    plan(None, false, two_cm).fill(&feet, &near, &mut steps);
    assert!(steps.is_empty(), "{steps:?}");
    plan(None, false, exact).fill(&feet, &near, &mut steps);
    assert_eq!(steps.len(), 1);
    assert_eq!(steps[0].side, Side::Right);
}
