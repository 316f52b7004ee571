//! Did the robot go where the human went, step when the human stepped, and follow with its
//! hands in time? The locomotion and timing part of the [metrics](crate::imitation::metrics).
//!
//! * **Travel**: start-to-end displacement of the scaled human's stance (the ankles' midpoint
//!   times the leg ratio) and of the robot's mid-feet point, and the difference of their heading
//!   changes (rad, wrapped to ±π).
//!   At the end, the robot's **travel error**: its distance from where the scaled human stands
//!   (the human's displacement, scaled, turned into the robot's world by the initial heading
//!   difference).
//! * **Catch-up**: after the clip's last frame, the time until the robot stands in double
//!   support where the scaled human stands (within [`CATCH_UP_DISTANCE`] and
//!   [`CATCH_UP_HEADING`]) and stays there. The **step catch-up** ([`StepFollowing`]) is
//!   simpler: from the human's last landing of a foot to the robot's.
//! * **Steps**: episodes of at least [`MIN_STEP_TIME`] with a foot off the floor, for the human
//!   (single-support episodes) and for the robot (a swing foot, from the plan's phases).
//! * **Foot lag**: each human lift-off (landing) of a foot lifted at least [`MIN_STEP_TIME`] is
//!   paired with the first robot lift-off (landing) of the same foot not yet paired, from
//!   [`MAX_LAG`] before it up to the human's next lift-off (landing) of that foot; the lag is the
//!   robot's time minus the human's (s, negative when the robot is early). A robot that skips a
//!   human step leaves it unpaired. The robot's foot is off the ground from its lift to its
//!   landing (the phases with that foot swinging).
//! * **Hand lag**: the time shift (0 … [`MAX_LAG`]) that best aligns the robot's hands with the
//!   scaled reference over the clip, and the errors once it is removed: a robot that follows
//!   the right path late has a small lag-removed error and a large lag.

use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use crate::human::Side;
use crate::imitation::phase::SupportKind;
use crate::imitation::walking::footsteps::wrap;

/// Largest distance (m) between the robot's and the scaled human's stance at which the robot has
/// caught up.
pub const CATCH_UP_DISTANCE: f64 = 0.03;
/// Largest heading difference (rad) at which the robot has caught up (5°).
pub const CATCH_UP_HEADING: f64 = 0.087;
/// Shortest time (s) a foot is off the floor for a step to count.
pub const MIN_STEP_TIME: f64 = 0.2;
/// Largest hand lag searched (s).
pub const MAX_LAG: f64 = 2.0;

/// Start-to-end displacement of the scaled human and of the robot.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Travel {
    /// The scaled human's stance (m).
    pub scaled_human_m: f64,
    /// The robot's mid-feet point (m).
    pub robot_m: f64,
    /// Robot heading change minus human heading change at the end (rad, ±π).
    pub heading_error_rad: f64,
    /// The robot's distance from where the scaled human stands at the end (m): the robot's
    /// displacement minus the scaled human's, turned into the robot's world by the initial
    /// heading difference.
    pub error_m: f64,
}

/// How the robot followed the human's steps (present when the human lifted a foot for at
/// least [`MIN_STEP_TIME`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepFollowing {
    /// The human's lifts of a foot (the steps).
    pub human_steps: usize,
    /// Those the robot matched: a lift of the same foot paired with it (see the foot lag).
    pub matched_steps: usize,
    /// From the human's last landing of a foot to the robot's last landing (s): how long the
    /// robot went on stepping after the human stopped. Negative when the robot's last step
    /// ended first (it left the human's last steps out: see `matched_steps` and
    /// [`Travel::error_m`]); `None` when the robot never put a foot down.
    pub catch_up_s: Option<f64>,
}

impl StepFollowing {
    /// The share of the human's steps the robot matched (0–1).
    pub fn matched_share(&self) -> f64 {
        self.matched_steps as f64 / self.human_steps as f64
    }
}

/// Where someone stands: ground point (m) and heading (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Stance {
    pub(crate) point: Vector2<f64>,
    pub(crate) heading: f64,
}

/// The robot's stance from its sole placements: the soles' midpoint and mean heading.
pub(crate) fn robot_stance(right: &IsometryMatrix3<f64>, left: &IsometryMatrix3<f64>) -> Stance {
    let x = |s: &IsometryMatrix3<f64>| s.rotation * Vector3::x();
    let forward = x(right) + x(left);
    Stance {
        point: (right.translation.vector + left.translation.vector).xy() * 0.5,
        heading: forward.y.atan2(forward.x),
    }
}

/// Follows the human's and the robot's stances over a run.
#[derive(Debug, Clone, Default)]
pub(crate) struct TravelRecorder {
    start: Option<(Stance, Stance)>,
    last: Option<(Stance, Stance, f64)>,
    clip_end: Option<f64>,
    caught_up_since: Option<f64>,
}

impl TravelRecorder {
    /// One frame: the human's stance (unscaled) and leg ratio, the robot's stance, whether the
    /// robot stands in double support, the frame time.
    pub(crate) fn record(
        &mut self,
        human: Option<Stance>,
        ratio: f64,
        robot: Stance,
        double: bool,
        time: f64,
    ) {
        let Some(human) = human else { return };
        let (h0, r0) = *self.start.get_or_insert((human, robot));
        self.last = Some((human, robot, ratio));
        let Some(end) = self.clip_end else { return };
        let (offset, heading) = self.errors(h0, r0, human, robot, ratio);
        let there = double && offset <= CATCH_UP_DISTANCE && heading.abs() <= CATCH_UP_HEADING;
        self.caught_up_since = match (there, self.caught_up_since) {
            (true, Some(t)) => Some(t),
            (true, None) => Some(time.max(end)),
            (false, _) => None,
        };
    }

    /// The robot's distance (m) from where the scaled human stands and the heading error (rad).
    fn errors(&self, h0: Stance, r0: Stance, h: Stance, r: Stance, ratio: f64) -> (f64, f64) {
        let turn = nalgebra::Rotation2::new(r0.heading - h0.heading);
        let human_move = turn * ((h.point - h0.point) * ratio);
        let offset = (r.point - r0.point - human_move).norm();
        let heading = wrap((r.heading - r0.heading) - (h.heading - h0.heading));
        (offset, heading)
    }

    /// The clip's last frame was at `time`; what follows is the hold.
    pub(crate) fn mark_clip_end(&mut self, time: f64) {
        self.clip_end.get_or_insert(time);
    }

    /// Whether the clip's end has been marked.
    pub(crate) fn clip_ended(&self) -> bool {
        self.clip_end.is_some()
    }

    pub(crate) fn travel(&self) -> Travel {
        let (Some((h0, r0)), Some((h, r, ratio))) = (self.start, self.last) else {
            return Travel::default();
        };
        let (error_m, heading_error_rad) = self.errors(h0, r0, h, r, ratio);
        Travel {
            scaled_human_m: ((h.point - h0.point) * ratio).norm(),
            robot_m: (r.point - r0.point).norm(),
            heading_error_rad,
            error_m,
        }
    }

    /// Seconds after the clip's end until the robot stood where the scaled human stands (and
    /// stayed), or `None`.
    pub(crate) fn catch_up(&self) -> Option<f64> {
        Some(self.caught_up_since? - self.clip_end?)
    }
}

/// Counts episodes of at least [`MIN_STEP_TIME`] with a foot off the floor.
#[derive(Debug, Clone, Default)]
pub(crate) struct StepCounter {
    off_since: Option<f64>,
    steps: usize,
}

impl StepCounter {
    /// `off`: some foot is off the floor at `time`.
    pub(crate) fn record(&mut self, off: bool, time: f64) {
        match (off, self.off_since) {
            (true, None) => self.off_since = Some(time),
            (false, Some(start)) => {
                if time - start >= MIN_STEP_TIME {
                    self.steps += 1;
                }
                self.off_since = None;
            }
            _ => {}
        }
    }

    pub(crate) fn steps(&self) -> usize {
        self.steps
    }
}

/// Lift-offs and landings of each foot (times, s), in time order.
#[derive(Debug, Clone, Default)]
struct FootEvents {
    /// Per foot ([`Side::index`]): whether it is off the ground, and since when.
    up_since: [Option<f64>; 2],
    lifts: [Vec<f64>; 2],
    landings: [Vec<f64>; 2],
}

impl FootEvents {
    /// `up`: which feet are off the ground at `time`. Episodes shorter than `min` are dropped.
    fn record(&mut self, up: [bool; 2], time: f64, min: f64) {
        for foot in Side::BOTH {
            let i = foot.index();
            match (up[i], self.up_since[i]) {
                (true, None) => self.up_since[i] = Some(time),
                (false, Some(start)) => {
                    if time - start >= min {
                        self.lifts[i].push(start);
                        self.landings[i].push(time);
                    }
                    self.up_since[i] = None;
                }
                _ => {}
            }
        }
    }
}

/// The robot's lag behind the human's lift-offs and landings (see the module docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct FootTiming {
    human: FootEvents,
    robot: FootEvents,
}

/// Lags (s) of the paired events, and how many human events there were.
pub(crate) type Lags = (Vec<f64>, usize);

impl FootTiming {
    /// Which feet are off the ground at `time`, the human's and the robot's.
    pub(crate) fn record(&mut self, human_up: [bool; 2], robot_up: [bool; 2], time: f64) {
        self.human.record(human_up, time, MIN_STEP_TIME);
        self.robot.record(robot_up, time, 0.0);
    }

    /// The human's steps, those the robot matched, and the step catch-up; `None` when the
    /// human never stepped.
    pub(crate) fn following(&self) -> Option<StepFollowing> {
        let last = |events: &FootEvents| {
            let landings = events.landings.iter().filter_map(|l| l.last().copied());
            landings.reduce(f64::max)
        };
        let human_last = last(&self.human)?;
        let (matched, human_steps) = pair(&self.human.lifts, &self.robot.lifts);
        Some(StepFollowing {
            human_steps,
            matched_steps: matched.len(),
            catch_up_s: last(&self.robot).map(|robot| robot - human_last),
        })
    }

    /// Lags of the lift-offs and of the landings.
    pub(crate) fn lags(&self) -> (Lags, Lags) {
        (
            pair(&self.human.lifts, &self.robot.lifts),
            pair(&self.human.landings, &self.robot.landings),
        )
    }
}

/// Pairs each human event with a robot event of the same foot (see the module docs).
fn pair(human: &[Vec<f64>; 2], robot: &[Vec<f64>; 2]) -> Lags {
    let mut lags = Vec::new();
    for (human, robot) in human.iter().zip(robot) {
        let mut next = 0;
        for (i, &h) in human.iter().enumerate() {
            let until = human.get(i + 1).copied().unwrap_or(f64::INFINITY);
            let first = next + robot[next..].partition_point(|&r| r < h - MAX_LAG);
            if let Some(&r) = robot.get(first).filter(|&&r| r < until) {
                lags.push(r - h);
                next = first + 1;
            }
        }
    }
    (lags, human.iter().map(Vec::len).sum())
}

/// The shortest shift (s) [`HandTiming`] calls late.
pub const LATE_LAG: f64 = 0.1;
/// The least share of the hands' error a shift must remove for [`HandTiming`] to call the
/// robot late: below it the error barely depends on timing, and the best shift is whichever
/// small wobble the search found.
pub const LATE_SHARE: f64 = 0.25;

/// What the hand lag means: whether the robot's hands follow the human's path late, or are
/// off for another reason (out of reach, at a joint limit, a robot standing where the human
/// no longer is), for which no time shift helps and the best shift says nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandTiming {
    /// The best time shift (s, 0 … [`MAX_LAG`]).
    pub lag_s: f64,
    /// The hands' mean error over the clip without a shift (m).
    pub error_m: f64,
    /// ... and with the best shift removed (m).
    pub lag_removed_error_m: f64,
}

impl HandTiming {
    /// The share of the error the shift removes (0–1; 0 when there is no error).
    pub fn removed_share(&self) -> f64 {
        match self.error_m > 0.0 {
            true => (1.0 - self.lag_removed_error_m / self.error_m).clamp(0.0, 1.0),
            false => 0.0,
        }
    }

    /// Whether the robot is late: the shift is at least [`LATE_LAG`] and removes at least
    /// [`LATE_SHARE`] of the error.
    pub fn late(&self) -> bool {
        self.lag_s >= LATE_LAG && self.removed_share() >= LATE_SHARE
    }
}

/// Most lags (frames) the hand-lag search tries: [`MAX_LAG`] at up to 500 frames per second.
const LAG_CAPACITY: usize = 1024;

/// Per lag, per hand, per support kind ([`SupportKind::index`]): error sum, maximum, count.
type LagCells = [[(f64, f64, usize); SupportKind::COUNT]; 2];

/// The hand-lag search, run as the frames come in memory bounded by [`LAG_CAPACITY`]: for every
/// lag `k` it accumulates the errors between the robot's hands at frame `i + k` and the
/// references of frame `i` (world frame, m), so no trace of the clip is kept.
#[derive(Debug, Clone, Default)]
pub(crate) struct HandTrace {
    /// Times of the first frames: a lag `k` is searched if `first_times[k]` is within
    /// [`MAX_LAG`] of the first.
    first_times: Vec<f64>,
    /// The references and support kinds of the last [`LAG_CAPACITY`] frames, frame `i` at
    /// `i % LAG_CAPACITY`.
    recent: Vec<([Option<Vector3<f64>>; 2], SupportKind)>,
    frames: usize,
    /// Per lag: error sum and count over both hands.
    totals: Vec<(f64, usize)>,
    /// Per lag: the errors by hand and support kind.
    cells: Vec<LagCells>,
}

/// Mean hand errors (m) once the best lag is removed: `[hand][kind]` as (mean, max, count), and
/// the lag (s).
pub(crate) type LagRemoved = (LagCells, f64);

impl HandTrace {
    /// Adds a frame at `time` (s): the robot's hands (left, right), their references, and the
    /// support kind of the reference's frame.
    pub(crate) fn record(
        &mut self,
        time: f64,
        robot: [Vector3<f64>; 2],
        reference: [Option<Vector3<f64>>; 2],
        kind: SupportKind,
    ) {
        let j = self.frames;
        if j < LAG_CAPACITY {
            self.first_times.push(time);
            self.recent.push((reference, kind));
            self.totals.push((0.0, 0));
            self.cells.push(Default::default());
        } else {
            self.recent[j % LAG_CAPACITY] = (reference, kind);
        }
        // Frame j pairs its hands with the references of frames j − k, lag k ascending.
        for k in 0..=j.min(LAG_CAPACITY - 1) {
            if self.first_times[k] - self.first_times[0] > MAX_LAG {
                break;
            }
            let (references, kind) = self.recent[(j - k) % LAG_CAPACITY];
            for h in 0..2 {
                let Some(reference) = references[h] else {
                    continue;
                };
                let e = (robot[h] - reference).norm();
                self.totals[k].0 += e;
                self.totals[k].1 += 1;
                let cell = &mut self.cells[k][h][kind.index()];
                cell.0 += e;
                cell.1 = cell.1.max(e);
                cell.2 += 1;
            }
        }
        self.frames += 1;
    }

    /// The lag (s) that minimises the mean hand error, and the errors with it removed.
    pub(crate) fn lag_removed(&self) -> LagRemoved {
        let mut best = (f64::INFINITY, 0);
        for (k, &(sum, count)) in self.totals.iter().enumerate() {
            if self.first_times[k] - self.first_times[0] > MAX_LAG {
                break;
            }
            if count > 0 && sum / (count as f64) < best.0 {
                best = (sum / count as f64, k);
            }
        }
        let k = best.1;
        let mut out = self.cells.get(k).copied().unwrap_or_default();
        for cell in out.iter_mut().flatten() {
            if cell.2 > 0 {
                cell.0 /= cell.2 as f64;
            }
        }
        let lag = match self.first_times.get(k) {
            Some(t) => t - self.first_times[0],
            None => 0.0,
        };
        (out, lag)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn stance(x: f64, y: f64, heading: f64) -> Stance {
        Stance {
            point: Vector2::new(x, y),
            heading,
        }
    }

    #[test]
    fn travel_scales_the_human_and_compares_headings() {
        let mut t = TravelRecorder::default();
        t.record(
            Some(stance(1.0, 2.0, 0.0)),
            0.5,
            stance(0.0, 0.0, 0.0),
            true,
            0.0,
        );
        // The human walks 2 m forward and turns 90°; at leg ratio 0.5 that is 1 m.
        t.record(
            Some(stance(3.0, 2.0, FRAC_PI_2)),
            0.5,
            stance(0.2, 0.0, 0.0),
            true,
            1.0,
        );
        let travel = t.travel();
        assert!((travel.scaled_human_m - 1.0).abs() < 1e-12);
        assert!((travel.robot_m - 0.2).abs() < 1e-12);
        assert!((travel.heading_error_rad + FRAC_PI_2).abs() < 1e-12);
        // Both started facing +x: the scaled human ends 1 m ahead, the robot 0.2 m.
        assert!((travel.error_m - 0.8).abs() < 1e-12);
        assert_eq!(t.catch_up(), None);
    }

    /// The travel error turns the human's displacement into the robot's world: the human
    /// faces +y at the start and walks 2 m along it (1 m scaled), the robot faces +x, so it
    /// should end 1 m along +x; it ends at (0.6, 0.3): √(0.4² + 0.3²) = 0.5 m off.
    #[test]
    fn travel_error_is_measured_in_the_robots_world() {
        let mut t = TravelRecorder::default();
        let human = [stance(5.0, 1.0, FRAC_PI_2), stance(5.0, 3.0, FRAC_PI_2)];
        let robot = [stance(0.0, 0.0, 0.0), stance(0.6, 0.3, 0.0)];
        for (i, time) in [0.0, 1.0].into_iter().enumerate() {
            t.record(Some(human[i]), 0.5, robot[i], true, time);
        }
        let travel = t.travel();
        assert!((travel.error_m - 0.5).abs() < 1e-12, "{travel:?}");
        assert!(travel.heading_error_rad.abs() < 1e-12);
    }

    /// The human steps with the left foot (lift 1.0, land 1.5) and the right (2.0–2.5); the
    /// robot follows the left (1.3–2.1) and never the right, then steps with the left again
    /// (3.0–3.6): one of two steps matched, its last landing 3.6 − 2.5 = 1.1 s after the
    /// human's.
    #[test]
    fn step_following_counts_matched_steps_and_the_last_landings_apart() {
        let mut timing = FootTiming::default();
        assert_eq!(timing.following(), None, "no human step yet");
        let (l, r, none) = ([true, false], [false, true], [false, false]);
        for (human, robot, time) in [
            (none, none, 0.0),
            (l, none, 1.0),
            (l, l, 1.3),
            (none, l, 1.5),
            (r, l, 2.0),
            (r, none, 2.1),
            (none, none, 2.5),
            (none, l, 3.0),
            (none, none, 3.6),
        ] {
            timing.record(human, robot, time);
        }
        let following = timing.following().unwrap();
        assert_eq!((following.human_steps, following.matched_steps), (2, 1));
        assert!((following.catch_up_s.unwrap() - 1.1).abs() < 1e-12);
        assert_eq!(following.matched_share(), 0.5);
    }

    #[test]
    fn catch_up_counts_from_the_clip_end_when_the_robot_arrives() {
        let mut t = TravelRecorder::default();
        t.record(
            Some(stance(0.0, 0.0, 0.0)),
            0.5,
            stance(0.0, 0.0, 0.0),
            true,
            0.0,
        );
        t.mark_clip_end(1.0);
        // The scaled human stands 0.5 m ahead; the robot is short of it at 1.5 s, there but on
        // one foot at 2.0 s, there in double support at 2.5 s: 1.5 s after the clip's end.
        for (robot_x, double, time) in [(0.3, true, 1.5), (0.49, false, 2.0), (0.49, true, 2.5)] {
            t.record(
                Some(stance(1.0, 0.0, 0.0)),
                0.5,
                stance(robot_x, 0.0, 0.0),
                double,
                time,
            );
        }
        assert_eq!(t.catch_up(), Some(1.5));
    }

    #[test]
    fn steps_need_the_foot_off_long_enough() {
        let mut s = StepCounter::default();
        for (off, t) in [
            (true, 0.0),
            (false, 0.1),
            (true, 1.0),
            (true, 1.1),
            (false, 1.25),
        ] {
            s.record(off, t);
        }
        assert_eq!(s.steps(), 1);
    }

    /// A shift that removes 3 of 4 cm is lateness; one that removes 0.5 of 4 cm (12.5 %) is
    /// not, however long; a short one never is.
    #[test]
    fn hand_timing_calls_late_only_a_shift_that_removes_the_error() {
        let timing = |lag_s, lag_removed_error_m| HandTiming {
            lag_s,
            error_m: 0.04,
            lag_removed_error_m,
        };
        assert!((timing(0.5, 0.01).removed_share() - 0.75).abs() < 1e-12);
        assert!(timing(0.5, 0.01).late());
        assert!(!timing(1.5, 0.035).late());
        assert!(!timing(0.05, 0.01).late());
        let none = HandTiming {
            error_m: 0.0,
            ..timing(0.3, 0.0)
        };
        assert_eq!(none.removed_share(), 0.0);
    }

    #[test]
    fn lag_is_found_and_removed() {
        // The robot's hand repeats the reference 0.5 s (5 frames) later.
        let mut trace = HandTrace::default();
        let path = |t: f64| Vector3::new(t.sin(), 0.0, 0.0);
        for i in 0..100 {
            let t = i as f64 * 0.1;
            trace.record(
                t,
                [path(t - 0.5); 2],
                [Some(path(t)); 2],
                SupportKind::Double,
            );
        }
        let (errors, lag) = trace.lag_removed();
        assert!((lag - 0.5).abs() < 1e-9, "{lag}");
        assert!(errors[0][1].0 < 1e-12 && errors[0][1].2 == 95);
    }
}
