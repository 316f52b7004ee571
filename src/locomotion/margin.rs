//! How far a point is inside the support polygon of a walk state.

use nalgebra::Vector2;

use super::footstep::GroundPose;
use super::generator::WalkState;
use super::schedule::Support;
use crate::human::Side;
use crate::tasks::{convex_hull, hull_margin};

/// The support polygon of a [`WalkState`]: the convex hull of the outlines of the soles on the
/// floor. Buffers are allocated once; [`SupportPolygon::margin`] allocates nothing.
#[derive(Debug, Clone)]
pub struct SupportPolygon {
    outlines: [Vec<[f64; 2]>; 2],
    points: Vec<[f64; 2]>,
    hull: Vec<[f64; 2]>,
}

impl SupportPolygon {
    /// For soles with contact areas `outlines` (`[left, right]`, sole frame, m).
    pub fn new(outlines: [&[[f64; 2]]; 2]) -> Self {
        let corners = outlines[0].len() + outlines[1].len();
        Self {
            outlines: outlines.map(<[[f64; 2]]>::to_vec),
            points: Vec::with_capacity(corners),
            hull: Vec::with_capacity(corners + 1),
        }
    }

    /// Signed distance (m) of `point` (world) inside the support polygon of `state`: > 0
    /// inside, < 0 outside.
    pub fn margin(&mut self, state: &WalkState, point: Vector2<f64>) -> f64 {
        self.points.clear();
        for side in Side::BOTH {
            if matches!(state.support, Support::Single { swing, .. } if swing == side) {
                continue;
            }
            let sole = state.feet[side.index()];
            let pose = GroundPose::new(sole.position[0], sole.position[1], sole.yaw);
            let corners = self.outlines[side.index()].iter().map(|&c| {
                let w = pose.to_world(c);
                [w.x, w.y]
            });
            self.points.extend(corners);
        }
        convex_hull(&mut self.points, &mut self.hull);
        hull_margin(&self.hull, point)
    }
}
