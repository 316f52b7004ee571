//! What a run's walks did: steps, their duration, the walking speed and the planned ZMP's
//! margin ([`WalkingSummary`], recorded frame by frame by [`WalkMeter`]).

use nalgebra::Vector2;

use crate::imitation::output::RobotFrame;
use crate::locomotion::{Support, SupportPolygon};
use crate::robots::BipedProfile;

/// The walks of a run ([`super`]): `None` in the metrics of a run that never walked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkingSummary {
    /// Steps taken: single supports begun while walking.
    pub steps: usize,
    /// Path length of the middle of the soles over the walking frames, divided by their
    /// duration (m/s).
    pub mean_speed_m_s: f64,
    /// Median time from one lift-off to the next within a walk (s); `None` before two steps
    /// of one walk.
    pub step_duration_s: Option<f64>,
    /// Smallest signed distance of the plan's ZMP (the cart-table ZMP of the generator's CoM)
    /// inside the support polygon of the soles on the floor, over the walking frames (m; > 0
    /// inside).
    pub zmp_margin_min_m: f64,
    /// Time spent walking (s).
    pub walking_s: f64,
}

/// Accumulates a [`WalkingSummary`] frame by frame.
#[derive(Debug, Clone)]
pub struct WalkMeter {
    polygon: SupportPolygon,
    steps: usize,
    /// Lift-off times of the current walk's steps, and the intervals between them.
    last_lift: Option<f64>,
    intervals: Vec<f64>,
    path: f64,
    walking_s: f64,
    zmp_margin: f64,
    /// The last frame: its time, whether it walked in single support, its soles' middle.
    previous: Option<(f64, bool, Vector2<f64>)>,
}

impl WalkMeter {
    /// A meter for the soles of `profile`.
    pub fn new(profile: &BipedProfile) -> Self {
        let outlines = profile.feet.each_ref().map(|f| f.outline.as_slice());
        Self {
            polygon: SupportPolygon::new(outlines),
            steps: 0,
            last_lift: None,
            intervals: Vec::new(),
            path: 0.0,
            walking_s: 0.0,
            zmp_margin: f64::INFINITY,
            previous: None,
        }
    }

    /// Records one frame.
    pub fn record(&mut self, frame: &RobotFrame) {
        let middle = (frame.left_sole.translation.vector.xy()
            + frame.right_sole.translation.vector.xy())
            / 2.0;
        let Some(walk) = &frame.walk else {
            self.last_lift = None;
            self.previous = Some((frame.time, false, middle));
            return;
        };
        let single = matches!(walk.support, Support::Single { .. });
        if let Some((time, was_single, was_middle)) = self.previous {
            self.walking_s += frame.time - time;
            self.path += (middle - was_middle).norm();
            if single && !was_single {
                self.steps += 1;
                if let Some(lift) = self.last_lift {
                    self.intervals.push(frame.time - lift);
                }
                self.last_lift = Some(frame.time);
            }
        }
        self.zmp_margin = self.zmp_margin.min(self.polygon.margin(walk, walk.zmp));
        self.previous = Some((frame.time, single, middle));
    }

    /// The summary; `None` if no frame walked.
    pub fn finish(&self) -> Option<WalkingSummary> {
        if !self.zmp_margin.is_finite() {
            return None;
        }
        let mut intervals = self.intervals.clone();
        intervals.sort_by(f64::total_cmp);
        Some(WalkingSummary {
            steps: self.steps,
            mean_speed_m_s: match self.walking_s > 0.0 {
                true => self.path / self.walking_s,
                false => 0.0,
            },
            step_duration_s: intervals.get(intervals.len() / 2).copied(),
            zmp_margin_min_m: self.zmp_margin,
            walking_s: self.walking_s,
        })
    }
}
