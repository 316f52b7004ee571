//! Footsteps toward a goal, within a robot's step envelope.
//!
//! The feet alternate; each step puts the swing sole as close to its goal placement as the
//! envelope ([`FootArea`], relative to the stance sole) allows, so a long way becomes as many
//! steps as it needs. The first foot to move is the one that leads toward the goal (left for a
//! goal to the left or a left turn), and the plan ends with both soles on their goals.

use super::footstep::{Footstep, GroundPose, StepTiming, mean_heading};
use crate::human::Side;
use crate::robots::{FootArea, SolePlacement};

/// Both soles are on their goals within this (m, rad).
const ARRIVED: f64 = 1e-9;

/// The goal placements of both soles for the midpoint frame of `feet` moved by `motion` (in that
/// frame: forward m, left m, turn rad): each sole keeps its offset from the midpoint.
pub fn goal_feet(feet: &[GroundPose; 2], motion: &GroundPose) -> [GroundPose; 2] {
    let [left, right] = feet;
    let heading = mean_heading(left.yaw, right.yaw);
    let mid = GroundPose {
        xy: (left.xy + right.xy) / 2.0,
        yaw: heading,
    };
    let goal = mid.compose(motion);
    feet.map(|f| goal.compose(&mid.relative(&f)))
}

/// Steps from `feet` to `goal` (`[left, right]`, world), each clipped to `envelope`, at most
/// `max_steps`; every step takes `timing`. Empty when the feet are on their goals.
pub fn plan_steps(
    feet: &[GroundPose; 2],
    goal: &[GroundPose; 2],
    envelope: &FootArea,
    timing: StepTiming,
    max_steps: usize,
) -> Vec<Footstep> {
    let mut steps = Vec::new();
    let plan = StepPlan {
        envelope,
        timing,
        first: None,
        max_steps,
        min_move: GroundPose::new(ARRIVED, 0.0, ARRIVED),
        alternate: false,
    };
    plan.fill(feet, goal, &mut steps);
    steps
}

/// How [`StepPlan::fill`] plans: the envelope, the timing of every step, the foot to move
/// first (`None`: the one that leads toward the goal), the most steps and the smallest move
/// worth a step.
#[derive(Debug, Clone, Copy)]
pub struct StepPlan<'a> {
    /// Where a sole may go relative to the stance sole.
    pub envelope: &'a FootArea,
    /// The timing of every step.
    pub timing: StepTiming,
    /// The foot to move first; `None`: the side the goal lies or turns toward.
    pub first: Option<Side>,
    /// The most steps planned.
    pub max_steps: usize,
    /// A foot whose clipped target is within `min_move.xy.x` metres and `min_move.yaw` radians
    /// of where it stands does not step (`xy.y` is unused): where the envelope stops a foot
    /// short of its goal, the next plan would otherwise repeat a step of a few micrometres.
    pub min_move: GroundPose,
    /// Whether the feet strictly alternate: the plan ends where the next foot would stay,
    /// instead of stepping the same foot twice in a row (the robot would stand on one foot for
    /// two steps' time).
    pub alternate: bool,
}

impl StepPlan<'_> {
    /// Clears `steps` and fills it with the steps from `feet` to `goal` (`[left, right]`,
    /// world) as [`plan_steps`] does; allocates nothing when `steps` has room for
    /// `max_steps`.
    pub fn fill(&self, feet: &[GroundPose; 2], goal: &[GroundPose; 2], steps: &mut Vec<Footstep>) {
        steps.clear();
        let mut now = *feet;
        let mut swing = self.first.unwrap_or_else(|| leading_side(feet, goal));
        let mut skipped = 0;
        let most_skipped = if self.alternate { 1 } else { 2 };
        while steps.len() < self.max_steps && !arrived(&now, goal) && skipped < most_skipped {
            let stance = now[swing.other().index()];
            let wanted = stance.relative(&goal[swing.index()]);
            let clipped = self.envelope.clip(
                swing,
                SolePlacement {
                    xy: wanted.xy,
                    yaw: wanted.yaw,
                },
            );
            let target = stance.compose(&GroundPose {
                xy: clipped.xy,
                yaw: clipped.yaw,
            });
            // A foot already where it can get waits while the other steps.
            let stays = within(&target, &now[swing.index()], &self.min_move);
            if !stays {
                now[swing.index()] = target;
                steps.push(Footstep {
                    side: swing,
                    target,
                    timing: self.timing,
                });
            }
            skipped = if stays { skipped + 1 } else { 0 };
            swing = swing.other();
        }
    }
}

/// The foot that leads toward the goal: the side the goal lies or turns toward.
fn leading_side(feet: &[GroundPose; 2], goal: &[GroundPose; 2]) -> Side {
    let [left, right] = feet;
    let lateral = left.xy - right.xy; // points from the right sole to the left
    let shift = (goal[0].xy + goal[1].xy - left.xy - right.xy) / 2.0;
    let turn = super::footstep::wrap_angle(goal[0].yaw - left.yaw);
    let toward_left = shift.dot(&lateral.normalize()) + 0.05 * turn;
    if toward_left >= 0.0 {
        Side::Left
    } else {
        Side::Right
    }
}

fn arrived(now: &[GroundPose; 2], goal: &[GroundPose; 2]) -> bool {
    let exact = GroundPose::new(ARRIVED, 0.0, ARRIVED);
    now.iter().zip(goal).all(|(a, b)| within(a, b, &exact))
}

/// Whether `a` is within `tolerance.xy.x` metres and `tolerance.yaw` radians of `b`.
fn within(a: &GroundPose, b: &GroundPose, tolerance: &GroundPose) -> bool {
    (a.xy - b.xy).norm() <= tolerance.xy.x
        && super::footstep::wrap_angle(a.yaw - b.yaw).abs() <= tolerance.yaw
}
