//! The timed step queue: which foot stands and where the ZMP reference is, at any time.
//!
//! A step's double support moves the ZMP reference from where the previous step left it to the
//! centre of the stance sole (a cubic blend, so the reference's speed is continuous), its single
//! support keeps it there while the other foot swings. A step queued to start when the previous
//! one lands continues the walk; after the last queued step the robot stops: the reference
//! returns to the midpoint of the two sole centres over the stop time and stays. A step queued
//! after that waits until the stop is complete, and the walk restarts from the midpoint.

use std::collections::VecDeque;

use nalgebra::Vector2;

use super::LocomotionError;
use super::footstep::{Footstep, GroundPose};
use crate::human::Side;
use crate::robots::outline_bounds;

/// The contact area of each sole (sole frame, m), `[left, right]`: its centre is where the ZMP
/// reference sits in single support.
#[derive(Debug, Clone, PartialEq)]
pub struct SoleCentres {
    centres: [[f64; 2]; 2],
}

impl SoleCentres {
    /// The centres of the bounding rectangles of the outlines `[left, right]` (sole frame, m).
    ///
    /// # Errors
    /// [`LocomotionError::InvalidParameter`] for an outline with fewer than three corners or a
    /// non-finite corner.
    pub fn of_outlines(outlines: [&[[f64; 2]]; 2]) -> Result<Self, LocomotionError> {
        let centre = |outline: &[[f64; 2]]| {
            let ok = outline.len() >= 3 && outline.iter().flatten().all(|v| v.is_finite());
            if !ok {
                return Err(LocomotionError::InvalidParameter {
                    name: "outline",
                    value: outline.len() as f64,
                    reason: "needs three or more finite corners (m)",
                });
            }
            let [lo, hi] = outline_bounds(outline);
            Ok([0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])])
        };
        Ok(Self {
            centres: [centre(outlines[0])?, centre(outlines[1])?],
        })
    }

    /// The centre of the sole on `side` standing at `pose` (m, world).
    pub fn world(&self, side: Side, pose: &GroundPose) -> Vector2<f64> {
        pose.to_world(self.centres[side.index()])
    }

    fn midpoint(&self, feet: &[GroundPose; 2]) -> Vector2<f64> {
        (self.world(Side::Left, &feet[0]) + self.world(Side::Right, &feet[1])) * 0.5
    }
}

/// A queued step with its times on the generator's clock (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct TimedStep {
    pub(super) step: Footstep,
    /// Where the swing sole stands before the step.
    pub(super) from: GroundPose,
    /// The ZMP reference when the double support begins (m, world).
    pub(super) zmp_from: Vector2<f64>,
    /// The stance sole's centre (m, world).
    pub(super) zmp_stance: Vector2<f64>,
    /// Double support begins.
    pub(super) start: f64,
    /// The swing foot leaves the floor.
    pub(super) lift: f64,
    /// The swing foot lands.
    pub(super) land: f64,
}

/// What the feet do at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Support {
    /// Both soles on the floor.
    Double,
    /// One sole on the floor; the foot on `swing` travels, at `phase` ∈ [0, 1] of its swing.
    Single {
        /// The moving foot.
        swing: Side,
        /// Share of the swing done.
        phase: f64,
    },
}

/// The queue of timed steps and the feet they start from.
#[derive(Debug, Clone)]
pub(super) struct Schedule {
    centres: SoleCentres,
    /// Where the soles stand before the first queued step.
    feet: [GroundPose; 2],
    /// Where the soles stand after the last queued step.
    planned: [GroundPose; 2],
    steps: VecDeque<TimedStep>,
    capacity: usize,
    /// Time the reference takes to return to the midpoint after the last step (s).
    stop_duration: f64,
    /// Shortest double support of a step that does not continue a walk (s).
    start_duration: f64,
    /// The last step that landed and left the queue: the reference returns from its stance
    /// centre to the midpoint over the stop time.
    previous: Option<TimedStep>,
}

impl Schedule {
    pub(super) fn new(
        centres: SoleCentres,
        feet: [GroundPose; 2],
        capacity: usize,
        stop_duration: f64,
        start_duration: f64,
    ) -> Self {
        Self {
            centres,
            feet,
            planned: feet,
            steps: VecDeque::with_capacity(capacity),
            capacity,
            stop_duration,
            start_duration,
            previous: None,
        }
    }

    /// Empties the queue with the soles standing at `feet`, as if new (no allocation).
    pub(super) fn restart(&mut self, feet: [GroundPose; 2]) {
        self.feet = feet;
        self.planned = feet;
        self.steps.clear();
        self.previous = None;
    }

    pub(super) fn feet(&self) -> &[GroundPose; 2] {
        &self.feet
    }

    pub(super) fn planned(&self) -> &[GroundPose; 2] {
        &self.planned
    }

    pub(super) fn steps(&self) -> impl ExactSizeIterator<Item = &TimedStep> {
        self.steps.iter()
    }

    /// Appends `step`, starting no earlier than `now` (s); returns its queued times.
    pub(super) fn push(&mut self, step: Footstep, now: f64) -> Result<TimedStep, LocomotionError> {
        if self.steps.len() == self.capacity {
            return Err(LocomotionError::QueueFull {
                capacity: self.capacity,
            });
        }
        step.timing.validate()?;
        if !step.target.is_finite() {
            return Err(LocomotionError::NonFinite("footstep target"));
        }
        let stance = step.side.other();
        let zmp_stance = self.centres.world(stance, &self.planned[stance.index()]);
        let (start, zmp_from, double_support) = match self.steps.back() {
            Some(last) if last.land >= now => (last.land, last.zmp_stance, 0.0),
            _ => {
                let start = now.max(self.previous.map_or(now, |p| p.land));
                (start, self.reference(start), self.start_duration)
            }
        };
        let double_support = step.timing.double_support.max(double_support);
        let timed = TimedStep {
            step,
            from: self.planned[step.side.index()],
            zmp_from,
            zmp_stance,
            start,
            lift: start + double_support,
            land: start + double_support + step.timing.single_support,
        };
        self.planned[step.side.index()] = step.target;
        self.steps.push_back(timed);
        Ok(timed)
    }

    /// Drops the queued steps whose double support has not begun by `now` (s), but the one
    /// after a step under way: a robot moving toward its next stance needs it to stop inside
    /// its support. Returns how many were dropped.
    pub(super) fn cancel_pending(&mut self, now: f64) -> usize {
        let before = self.steps.len();
        let begun = self.steps.iter().take_while(|s| s.start <= now).count();
        let under_way = begun > 0 && self.steps[begun - 1].land > now;
        self.steps
            .truncate((begun + usize::from(under_way)).min(before));
        self.planned = self.feet;
        for step in &self.steps {
            self.planned[step.step.side.index()] = step.step.target;
        }
        before - self.steps.len()
    }

    /// Drops the steps that landed before `now` (s), moving their feet.
    pub(super) fn retire(&mut self, now: f64) {
        while let Some(first) = self.steps.front().copied() {
            if first.land > now {
                break;
            }
            self.feet[first.step.side.index()] = first.step.target;
            self.previous = Some(first);
            self.steps.pop_front();
        }
    }

    /// The time (s) by which every queued step has landed and the ZMP reference has come to
    /// rest between the feet.
    pub(super) fn rest_time(&self) -> f64 {
        (self.steps.back().or(self.previous.as_ref()))
            .map_or(f64::NEG_INFINITY, |last| last.land + self.stop_duration)
    }

    /// The ZMP reference (m, world) at `t`, no earlier than the first queued step's start.
    fn reference(&self, t: f64) -> Vector2<f64> {
        let mut feet = self.feet;
        let mut cursor = 0;
        while let Some(step) = self.steps.get(cursor).filter(|s| s.land <= t) {
            feet[step.step.side.index()] = step.step.target;
            cursor += 1;
        }
        self.reference_at(t, cursor, &feet)
    }

    /// The ZMP references (m, world) at `t0 + j·dt`, `j = 1..=x.len()`, into `x` and `y`.
    pub(super) fn fill_reference(&self, t0: f64, dt: f64, x: &mut [f64], y: &mut [f64]) {
        let mut cursor = 0;
        let mut feet = self.feet;
        for (j, (rx, ry)) in x.iter_mut().zip(y.iter_mut()).enumerate() {
            let t = t0 + (j + 1) as f64 * dt;
            while let Some(step) = self.steps.get(cursor).filter(|s| s.land <= t) {
                feet[step.step.side.index()] = step.step.target;
                cursor += 1;
            }
            let p = self.reference_at(t, cursor, &feet);
            (*rx, *ry) = (p.x, p.y);
        }
    }

    /// The ZMP reference at `t`, with `cursor` the first step not landed by `t` and `feet` the
    /// soles after the landed ones.
    fn reference_at(&self, t: f64, cursor: usize, feet: &[GroundPose; 2]) -> Vector2<f64> {
        match self.steps.get(cursor) {
            Some(step) if t >= step.start => {
                let share = ((t - step.start) / (step.lift - step.start)).min(1.0);
                step.zmp_from + (step.zmp_stance - step.zmp_from) * smooth(share)
            }
            Some(_) | None => {
                // Resting, or stopping after a landing: the blend toward the midpoint.
                let rest = self.centres.midpoint(feet);
                let landed = match cursor {
                    0 => self.previous.as_ref(),
                    _ => self.steps.get(cursor - 1),
                };
                match landed {
                    Some(landed) if t < landed.land + self.stop_duration => {
                        let share = (t - landed.land) / self.stop_duration;
                        landed.zmp_stance + (rest - landed.zmp_stance) * smooth(share)
                    }
                    _ => rest,
                }
            }
        }
    }

    /// What the feet do at `now` (s) and where they are (world).
    pub(super) fn support_at(&self, now: f64) -> (Support, Option<&TimedStep>) {
        match self.steps.front() {
            Some(step) if now >= step.lift && now < step.land => {
                let phase = (now - step.lift) / (step.land - step.lift);
                let support = Support::Single {
                    swing: step.step.side,
                    phase,
                };
                (support, Some(step))
            }
            _ => (Support::Double, None),
        }
    }
}

/// `3s² − 2s³` of `s` clamped to [0, 1]: from 0 to 1 with zero slope at both ends.
pub(crate) fn smooth(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}
