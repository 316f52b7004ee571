//! Self-collision clearance of the robot's postures: the smallest surface-to-surface distance
//! of the pairs of the profile's self-collision model
//! ([`BipedProfile::self_collision`](crate::robots::BipedProfile::self_collision)), measured
//! frame by frame for the metrics.

use crate::model::{Model, ModelData, ModelError};
use crate::robots::{BipedProfile, ProfileError};
use crate::tasks::Capsule;

/// The clearance of a run: the closest the paired bodies came.
#[derive(Debug, Clone, PartialEq)]
pub struct SelfClearance {
    /// Smallest distance of any pair over the run (m; < 0: the bodies overlapped).
    pub min_distance: f64,
    /// The pair that came closest.
    pub closest: [String; 2],
    /// The profile's margin (m).
    pub margin: f64,
    /// Frames where some pair was closer than the margin by more than 0.1 mm (the first-order
    /// steps of the IK can end a hair inside).
    pub frames_below_margin: usize,
}

/// Measures the clearance of postures of one profile; holds its model data, so measuring does
/// not allocate.
#[derive(Debug, Clone)]
pub struct ClearanceMeter {
    model: Model,
    data: ModelData,
    pairs: Vec<[Capsule; 2]>,
    names: Vec<[String; 2]>,
    margin: f64,
    min: Option<(f64, usize)>,
    below: usize,
}

/// How far inside the margin a frame may end before it counts as below it (m).
const MARGIN_SLACK: f64 = 1e-4;

impl ClearanceMeter {
    /// A meter for `profile`'s pairs; `None` when the profile has none.
    ///
    /// # Errors
    /// [`ProfileError`] when the self-collision model does not resolve on the profile's models.
    pub fn new(profile: &BipedProfile) -> Result<Option<Self>, ProfileError> {
        let collision = &profile.self_collision;
        if collision.is_empty() {
            return Ok(None);
        }
        // The distances do not depend on the root: the left-rooted model measures them.
        let model = profile.models[0].clone();
        let pairs = collision.resolve(&model, &profile.stand)?;
        Ok(Some(Self {
            data: model.new_data(),
            model,
            pairs,
            names: collision.pairs.clone(),
            margin: collision.margin,
            min: None,
            below: 0,
        }))
    }

    /// Records the posture `q` (model variable order, rad).
    ///
    /// # Errors
    /// [`ModelError`] for a `q` of the wrong length.
    pub fn record(&mut self, q: &[f64]) -> Result<(), ModelError> {
        self.model.forward_kinematics(&mut self.data, q)?;
        let mut frame_min = f64::INFINITY;
        for (k, [a, b]) in self.pairs.iter().enumerate() {
            let d = a.distance_to(b, &self.model, &self.data)?;
            frame_min = frame_min.min(d);
            if self.min.is_none_or(|(m, _)| d < m) {
                self.min = Some((d, k));
            }
        }
        if frame_min < self.margin - MARGIN_SLACK {
            self.below += 1;
        }
        Ok(())
    }

    /// The clearance of the postures recorded so far; `None` before the first.
    pub fn clearance(&self) -> Option<SelfClearance> {
        let (min_distance, k) = self.min?;
        Some(SelfClearance {
            min_distance,
            closest: self.names[k].clone(),
            margin: self.margin,
            frames_below_margin: self.below,
        })
    }
}
