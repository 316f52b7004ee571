//! The pattern generator's tick and the walker's tick allocate nothing after the first ticks:
//! a counting global allocator (per thread, `alloc_counter`) counts allocations over a whole walk.

use taskstack::locomotion::{GroundPose, WalkParams, WholeBodyWalker, goal_feet, plan_steps};
use taskstack::robots::{BipedProfile, g1, nao};

use crate::alloc_counter;
use alloc_counter::allocations;

#[test]
fn a_walk_allocates_nothing_after_warm_up() {
    // The G1's profile states its servos: its ticks also compute the servo targets.
    for profile in [nao::profile(), g1::profile()] {
        walk_without_allocating(&profile);
    }
}

fn walk_without_allocating(profile: &BipedProfile) {
    let params = WalkParams::for_profile(profile).unwrap();
    let timing = params.timing;
    let mut walker = WholeBodyWalker::new(profile, params, GroundPose::new(0.0, 0.0, 0.0)).unwrap();
    let start = *walker.generator().standing_feet();
    let goal = goal_feet(&start, &GroundPose::new(0.2, 0.05, 0.3));
    let steps = plan_steps(&start, &goal, &profile.step_envelope, timing, 100);
    let (first, rest) = steps.split_at(2);
    for step in first {
        walker.push(*step).unwrap();
    }
    for _ in 0..3 {
        walker.tick().unwrap();
    }
    // Every later tick (both roots, single and double support), and steps queued on the way.
    let before = allocations();
    let mut queued = rest.iter();
    let mut ticks = 0;
    while !walker.generator().is_stopped() || queued.len() > 0 {
        if walker.generator().queued() < 2
            && let Some(step) = queued.next()
        {
            walker.push(*step).unwrap();
        }
        walker.tick().unwrap();
        ticks += 1;
    }
    let allocations = allocations() - before;
    assert!(ticks > 500);
    assert_eq!(
        allocations, 0,
        "{}: {allocations} allocations in {ticks} ticks",
        profile.name
    );
}
