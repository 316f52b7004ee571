//! The robot's bodies for self-collision avoidance, as data: capsules fixed to named frames
//! ([`BodyCapsule`]), the pairs that must stay apart and the distance they keep
//! ([`SelfCollision`]).
//!
//! A capsule is the segment between two points swept by a sphere. Each end is a named frame's
//! origin moved by an offset in that frame's axes ([`FramePoint`]), so a profile names points
//! the model already has (the elbow, the hand) instead of coordinates in a frame whose axes
//! depend on how the model was built (DH or URDF). Both ends must be fixed to the capsule's own
//! frame: [`SelfCollision::resolve`] checks it at three postures and refuses a capsule whose
//! ends move on that frame (a joint between them).
//!
//! Pairs are chosen by hand: bodies next to each other on the chain (an upper arm and the
//! torso) always touch and are not paired.

use nalgebra::Vector3;

use super::error::ProfileError;
use crate::model::{Model, ModelData};
use crate::tasks::Capsule;

/// A point fixed to a named frame: its origin moved by `offset` (m, in the frame's axes).
#[derive(Clone, Debug, PartialEq)]
pub struct FramePoint {
    /// The frame's name.
    pub frame: String,
    /// Offset from the frame's origin (m, frame axes).
    pub offset: [f64; 3],
}

impl FramePoint {
    /// The origin of `frame`.
    pub fn origin(frame: &str) -> Self {
        Self {
            frame: frame.to_owned(),
            offset: [0.0; 3],
        }
    }
}

/// A body: the segment between two points swept by a sphere of `radius`, moving with `frame`.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyCapsule {
    /// Name, used by [`SelfCollision::pairs`] (e.g. `"l_forearm"`).
    pub name: String,
    /// The frame the body moves with.
    pub frame: String,
    /// The segment's ends; each must be fixed to `frame`.
    pub ends: [FramePoint; 2],
    /// Radius (m, ≥ 0).
    pub radius: f64,
}

/// The self-collision model of a robot: bodies, the pairs kept apart, and how far apart.
/// Empty by default (no self-collision avoidance).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SelfCollision {
    /// The bodies.
    pub bodies: Vec<BodyCapsule>,
    /// Pairs of body names kept at least [`SelfCollision::margin`] apart.
    pub pairs: Vec<[String; 2]>,
    /// Smallest surface-to-surface distance of a pair (m, ≥ 0).
    pub margin: f64,
}

/// Largest motion (m) of a capsule end on its frame across the test postures that still counts
/// as fixed (rounding of the forward kinematics).
const RIGID_TOLERANCE: f64 = 1e-7;

impl SelfCollision {
    /// Whether there is anything to keep apart.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// The pairs as capsules on `model`, in [`SelfCollision::pairs`] order, each end expressed
    /// in its body's frame. The ends are measured at `stand` and must be fixed to the body's
    /// frame: they are measured again at the zero posture and at the middle of the joint ranges.
    ///
    /// # Errors
    /// [`ProfileError::Model`] for an unknown frame or a `stand` of the wrong length;
    /// [`ProfileError::Invalid`] for a pair naming an unknown body, a negative or non-finite
    /// radius, margin or offset, or an end not fixed to its body's frame.
    pub fn resolve(&self, model: &Model, stand: &[f64]) -> Result<Vec<[Capsule; 2]>, ProfileError> {
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return Err(invalid(
                "self_collision.margin",
                format!("{} is not finite and ≥ 0", self.margin),
            ));
        }
        let data = test_postures(model, stand)?;
        let capsule = |name: &str| self.body(name)?.resolve(model, &data);
        self.pairs
            .iter()
            .map(|[a, b]| Ok([capsule(a)?, capsule(b)?]))
            .collect()
    }

    /// The body named `name`.
    ///
    /// # Errors
    /// [`ProfileError::Invalid`] when there is none.
    pub fn body(&self, name: &str) -> Result<&BodyCapsule, ProfileError> {
        self.bodies
            .iter()
            .find(|b| b.name == name)
            .ok_or_else(|| invalid("self_collision.pairs", format!("no body named {name:?}")))
    }
}

/// The forward kinematics at `stand`, at the zero posture and at the middle of the joint
/// ranges: where a capsule's ends are measured and checked fixed.
fn test_postures(model: &Model, stand: &[f64]) -> Result<Vec<ModelData>, ProfileError> {
    let middle: Vec<f64> = model
        .variables()
        .iter()
        .map(|v| 0.5 * (v.lower + v.upper))
        .collect();
    [stand.to_vec(), vec![0.0; model.nv()], middle]
        .iter()
        .map(|q| {
            let mut d = model.new_data();
            model.forward_kinematics(&mut d, q)?;
            Ok(d)
        })
        .collect()
}

impl BodyCapsule {
    /// The capsule on `model`, its ends measured at `stand` and checked fixed to the body's
    /// frame at the zero posture and at the middle of the joint ranges.
    ///
    /// # Errors
    /// As [`SelfCollision::resolve`].
    pub fn capsule(&self, model: &Model, stand: &[f64]) -> Result<Capsule, ProfileError> {
        self.resolve(model, &test_postures(model, stand)?)
    }

    /// The capsule on `model`, its ends measured in the forward kinematics `data[0]` and checked
    /// fixed to the body's frame in the others.
    fn resolve(&self, model: &Model, data: &[ModelData]) -> Result<Capsule, ProfileError> {
        let field = format!("self_collision.bodies.{}", self.name);
        let frame = model.frame_id(&self.frame)?;
        let mut ends = [Vector3::zeros(); 2];
        for (end, point) in ends.iter_mut().zip(&self.ends) {
            if point.offset.iter().any(|v| !v.is_finite()) {
                return Err(invalid(&field, "an end's offset is not finite".into()));
            }
            let id = model.frame_id(&point.frame)?;
            let offset = Vector3::from(point.offset);
            let local = |d: &ModelData| {
                let world = d.frame_placement(id).transform_point(&offset.into());
                d.frame_placement(frame)
                    .inverse_transform_point(&world)
                    .coords
            };
            *end = local(&data[0]);
            if data[1..]
                .iter()
                .any(|d| (local(d) - *end).norm() > RIGID_TOLERANCE)
            {
                return Err(invalid(
                    &field,
                    format!("{} is not fixed to {}", point.frame, self.frame),
                ));
            }
        }
        if !(self.radius.is_finite() && self.radius >= 0.0) {
            return Err(invalid(
                &field,
                format!("radius {} is not ≥ 0", self.radius),
            ));
        }
        Ok(Capsule {
            frame,
            a: ends[0],
            b: ends[1],
            radius: self.radius,
        })
    }
}

fn invalid(field: &str, reason: String) -> ProfileError {
    ProfileError::Invalid {
        field: field.to_owned(),
        reason,
    }
}
