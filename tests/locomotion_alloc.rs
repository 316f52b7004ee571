//! The pattern generator's tick and the walker's tick allocate nothing after the first ticks:
//! a counting global allocator in its own test binary counts allocations over a whole walk.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use taskstack::locomotion::{GroundPose, WalkParams, WholeBodyWalker, goal_feet, plan_steps};
use taskstack::robots::nao;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn a_walk_allocates_nothing_after_warm_up() {
    let profile = nao::profile();
    let params = WalkParams::for_profile(&profile).unwrap();
    let timing = params.timing;
    let mut walker =
        WholeBodyWalker::new(&profile, params, GroundPose::new(0.0, 0.0, 0.0)).unwrap();
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
    let before = ALLOCATIONS.load(Ordering::SeqCst);
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
    let allocations = ALLOCATIONS.load(Ordering::SeqCst) - before;
    assert!(ticks > 500);
    assert_eq!(allocations, 0, "{allocations} allocations in {ticks} ticks");
}
