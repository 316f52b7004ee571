//! Distances between bodies, kept above a margin: capsule to capsule (self-collision) and capsule
//! to plane (the floor, a table top).
//!
//! A [`Capsule`] is a segment `[a, b]` fixed in a frame, swept by a sphere of radius `r`. The
//! distance of two capsules is `d = ‖p₁ − p₂‖ − r₁ − r₂`, with `p₁`, `p₂` the closest points of
//! the two segments (Ericson, *Real-Time Collision Detection*, §5.1.9); its Jacobian is
//! `nᵀ (J_{p₁} − J_{p₂})`, `n = (p₁ − p₂)/‖p₁ − p₂‖`, the closest points held fixed in their
//! frames (the derivative of a minimum distance, where the closest points are unique). The
//! distance of a capsule to the plane through `o` with unit normal `ν` is
//! `d = ν ᵀ (p − o) − r`, `p` the segment end nearer the plane (its midpoint when both are as
//! near), Jacobian `νᵀ J_p`. Each task is one row `margin − d ≤ C δq ≤ +∞`.

use std::any::Any;

use faer::MatMut;
use nalgebra::Vector3;

use super::inequality::InequalityTask;
use super::{TaskError, check_error_len, finite_target};
use crate::model::{FrameId, Model, ModelData, ModelError};

/// A segment `[a, b]` fixed in a frame (m, in the frame's axes), swept by a sphere of `radius`
/// (m). A sphere is a capsule with `a = b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// The frame the capsule moves with.
    pub frame: FrameId,
    /// Segment ends, in the frame's axes (m).
    pub a: Vector3<f64>,
    /// See `a`.
    pub b: Vector3<f64>,
    /// Radius (m, ≥ 0).
    pub radius: f64,
}

impl Capsule {
    /// A capsule on the named frame.
    ///
    /// # Errors
    /// [`TaskError::Model`] for an unknown frame, [`TaskError::NonFiniteTarget`] for a NaN or
    /// infinite end or radius, [`TaskError::InvalidGeometry`] for a negative radius.
    pub fn new(
        model: &Model,
        frame: &str,
        a: Vector3<f64>,
        b: Vector3<f64>,
        radius: f64,
    ) -> Result<Self, TaskError> {
        let frame = model.frame_id(frame)?;
        finite_target("capsule", a.as_slice())?;
        finite_target("capsule", b.as_slice())?;
        finite_target("capsule", &[radius])?;
        if radius < 0.0 {
            return Err(TaskError::InvalidGeometry {
                task: "capsule".to_owned(),
                reason: "negative radius",
            });
        }
        Ok(Self {
            frame,
            a,
            b,
            radius,
        })
    }

    /// The segment's ends in the base frame (m).
    fn ends(&self, model: &Model, data: &ModelData) -> Result<[Vector3<f64>; 2], ModelError> {
        Ok([
            model.point_position(data, self.frame, &self.a)?,
            model.point_position(data, self.frame, &self.b)?,
        ])
    }

    /// The signed distance (m; < 0 when they overlap) between `self` and `other` at the
    /// forward kinematics in `data`.
    ///
    /// # Errors
    /// [`ModelError`] when `data` has no kinematics or a frame is not in `model`.
    pub fn distance_to(
        &self,
        other: &Capsule,
        model: &Model,
        data: &ModelData,
    ) -> Result<f64, ModelError> {
        Ok(self.closest(other, model, data)?.distance)
    }

    fn closest(
        &self,
        other: &Capsule,
        model: &Model,
        data: &ModelData,
    ) -> Result<Closest, ModelError> {
        let [p1, q1] = self.ends(model, data)?;
        let [p2, q2] = other.ends(model, data)?;
        let (s, t) = closest_segment_parameters(&p1, &q1, &p2, &q2);
        let gap = (p1 + (q1 - p1) * s) - (p2 + (q2 - p2) * t);
        let length = gap.norm();
        // Touching axes: any direction is a subgradient; the one between the segments' middles
        // pushes them apart.
        let normal = if length > 1e-12 {
            gap / length
        } else {
            let between = (p1 + q1 - p2 - q2) * 0.5;
            if between.norm() > 1e-12 {
                between.normalize()
            } else {
                Vector3::z()
            }
        };
        Ok(Closest {
            distance: length - self.radius - other.radius,
            normal,
            s,
            t,
        })
    }

    /// The point at parameter `s ∈ [0, 1]` of the segment, in the frame's axes.
    fn local(&self, s: f64) -> Vector3<f64> {
        self.a + (self.b - self.a) * s
    }

    /// [`Model::levers`] of the segment's points (within `max(|a|, |b|)` of the frame's origin).
    fn levers(&self, model: &Model) -> Result<Vec<Option<f64>>, ModelError> {
        model.levers(self.frame, self.a.norm().max(self.b.norm()))
    }
}

/// Parameters `(s, t) ∈ [0, 1]²` of the closest points `p₁ + s d₁`, `p₂ + t d₂` of two segments
/// (Ericson §5.1.9, with its degenerate cases: points, parallel segments).
pub fn closest_segment_parameters(
    p1: &Vector3<f64>,
    q1: &Vector3<f64>,
    p2: &Vector3<f64>,
    q2: &Vector3<f64>,
) -> (f64, f64) {
    const EPS: f64 = 1e-12;
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    if a <= EPS && e <= EPS {
        return (0.0, 0.0);
    }
    if a <= EPS {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(&r);
    if e <= EPS {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(&d2);
    let denom = a * e - b * b;
    let mut s = if denom > EPS * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// The closest approach of two capsules.
struct Closest {
    /// Signed distance (m; < 0 when they overlap).
    distance: f64,
    /// Unit direction from the second capsule's closest point to the first's.
    normal: Vector3<f64>,
    /// Parameters of the closest points on the first and second segments.
    s: f64,
    t: f64,
}

/// The distance row of a task: `margin − d ≤ C δq ≤ +∞`.
fn write_room(margin: f64, distance: f64, lower: &mut [f64], upper: &mut [f64]) {
    lower[0] = margin - distance;
    upper[0] = f64::INFINITY;
}

fn check_margin(task: &str, margin: f64) -> Result<(), TaskError> {
    finite_target(task, &[margin])?;
    if margin < 0.0 {
        return Err(TaskError::InvalidGeometry {
            task: task.to_owned(),
            reason: "negative margin",
        });
    }
    Ok(())
}

/// Two capsules kept at least `margin` apart (m): one row, `margin − d ≤ C δq`.
///
/// # How fast the distance changes
///
/// Entry `v` of `C = nᵀ (J_{p₁} − J_{p₂})` sums the joints driven by variable `v`. A joint that
/// moves both capsules turns (or shifts) them together: its part `μ nᵀ (w × (p₁ − p₂))` is 0, as
/// `p₁ − p₂` is along `n`. A joint that moves one of them contributes at most `|μ| ℓ`, its
/// [lever](Model::levers) to that capsule's segment. So `|C_v| ≤ k_v`, the sum of those
/// bounds ([`CapsuleDistanceTask::rate_bounds`], fixed for the task), in every posture, and a
/// step moving each variable by at most `δ_v` changes `d` by at most `Σ_v k_v δ_v` to first
/// order: farther apart than that beyond the margin, the row cannot bind
/// ([`CapsuleDistanceTask::write_for_step`]).
#[derive(Debug, Clone)]
pub struct CapsuleDistanceTask {
    name: String,
    first: Capsule,
    second: Capsule,
    margin: f64,
    rates: Vec<f64>,
}

impl CapsuleDistanceTask {
    /// Keeps `first` and `second` (capsules on frames of `model`) at least `margin` (m, ≥ 0)
    /// apart; named `name`.
    ///
    /// # Errors
    /// [`TaskError::NonFiniteTarget`], [`TaskError::InvalidGeometry`] for a bad margin;
    /// [`TaskError::Model`] for a capsule on a frame `model` does not have.
    pub fn new(
        model: &Model,
        name: &str,
        first: Capsule,
        second: Capsule,
        margin: f64,
    ) -> Result<Self, TaskError> {
        check_margin(name, margin)?;
        let (levers, others) = (first.levers(model)?, second.levers(model)?);
        let mut rates = vec![0.0; model.nv()];
        for ((joint, lever), other) in model.joints().iter().zip(levers).zip(others) {
            let one_side = match (lever, other) {
                (Some(l), None) | (None, Some(l)) => l,
                _ => continue,
            };
            if let Some(v) = joint.variable {
                rates[v] += joint.multiplier.abs() * one_side;
            }
        }
        Ok(Self {
            name: name.to_owned(),
            first,
            second,
            margin,
            rates,
        })
    }

    /// Per variable `v` of the model, `k_v` with `|∂d/∂q_v| ≤ k_v` in every posture (m/rad, or
    /// m/m for a prismatic variable; see the type's docs).
    pub fn rate_bounds(&self) -> &[f64] {
        &self.rates
    }

    /// [`InequalityTask::write`] for a step that moves each variable `v` by at most `step[v]`
    /// (rad or m; its size counts, and a NaN entry writes the row in full): when the capsules
    /// are farther apart than the margin plus `Σ_v k_v |step[v]|`
    /// ([`CapsuleDistanceTask::rate_bounds`]), no such step brings them to the
    /// margin, and the row is written as `0 · δq ≥ −∞` without computing its Jacobian, the
    /// costly part of the row; otherwise in full. Returns whether the row was written in full.
    /// A solver keeping the step within those bounds finds the same solution with either row.
    ///
    /// # Errors
    /// [`ModelError::OutputShape`] for a `step` of another length than the model's variables;
    /// [`ModelError`] when `data` has no kinematics or a frame is not in `model`.
    pub fn write_for_step(
        &self,
        model: &Model,
        data: &ModelData,
        step: &[f64],
        mut jacobian: MatMut<'_, f64>,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<bool, ModelError> {
        let nv = self.rates.len();
        check_error_len(lower, 1)?;
        check_error_len(upper, 1)?;
        if step.len() != nv {
            return Err(ModelError::OutputShape {
                expected_rows: nv,
                expected_cols: 1,
                rows: step.len(),
                cols: 1,
            });
        }
        model.check_shape(&jacobian, 1)?;
        let closest = self.closest(model, data)?;
        // A joint that does not move adds nothing, whatever its bound (an unbounded prismatic
        // joint's is infinite); a NaN step makes the reach NaN, and the row is written in full.
        let reach: f64 = (self.rates.iter().zip(step))
            .map(|(k, s)| if *s == 0.0 { 0.0 } else { k * s.abs() })
            .sum();
        if closest.distance - self.margin > reach {
            jacobian.fill(0.0);
            lower[0] = f64::NEG_INFINITY;
            upper[0] = f64::INFINITY;
            return Ok(false);
        }
        self.write_closest(model, &closest, data, jacobian, lower, upper)?;
        Ok(true)
    }

    /// The signed distance `d` (m; < 0 when the capsules overlap) at the forward kinematics in
    /// `data`.
    pub fn distance(&self, model: &Model, data: &ModelData) -> Result<f64, ModelError> {
        Ok(self.closest(model, data)?.distance)
    }

    /// The row's room alone, `margin − d` into `lower[0]` and `+∞` into `upper[0]`, as
    /// [`InequalityTask::write`] writes them: for a task model that measures its rows after its
    /// last step, where no Jacobian is needed.
    ///
    /// # Errors
    /// [`ModelError`] when `data` has no kinematics or a frame is not in `model`.
    pub fn write_room(
        &self,
        model: &Model,
        data: &ModelData,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<(), ModelError> {
        write_room(self.margin, self.distance(model, data)?, lower, upper);
        Ok(())
    }

    fn closest(&self, model: &Model, data: &ModelData) -> Result<Closest, ModelError> {
        self.first.closest(&self.second, model, data)
    }

    /// The row at the capsules' closest approach `closest`.
    fn write_closest(
        &self,
        model: &Model,
        closest: &Closest,
        data: &ModelData,
        mut jacobian: MatMut<'_, f64>,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<(), ModelError> {
        let (first, second) = (self.first.local(closest.s), self.second.local(closest.t));
        jacobian.fill(0.0);
        let n = closest.normal;
        model.add_point_jacobian_along(data, self.first.frame, &first, &n, jacobian.as_mut())?;
        model.add_point_jacobian_along(data, self.second.frame, &second, &-n, jacobian.as_mut())?;
        write_room(self.margin, closest.distance, lower, upper);
        Ok(())
    }
}

impl InequalityTask for CapsuleDistanceTask {
    fn name(&self) -> &str {
        &self.name
    }

    fn rows(&self) -> usize {
        1
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        jacobian: MatMut<'_, f64>,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<(), ModelError> {
        let closest = self.closest(model, data)?;
        self.write_closest(model, &closest, data, jacobian, lower, upper)
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// A capsule kept at least `margin` above a plane (m): the plane through `point` with unit
/// `normal` (base frame), unbounded. One row, `margin − d ≤ C δq`.
#[derive(Debug, Clone)]
pub struct PlaneDistanceTask {
    name: String,
    capsule: Capsule,
    point: Vector3<f64>,
    normal: Vector3<f64>,
    margin: f64,
}

impl PlaneDistanceTask {
    /// Keeps `capsule` (on a frame of `model`) at least `margin` (m) on the `normal` side of the
    /// plane through `point`; named `name`. `normal` is normalized.
    ///
    /// # Errors
    /// [`TaskError::NonFiniteTarget`]; [`TaskError::InvalidGeometry`] for a zero normal or a
    /// negative margin; [`TaskError::Model`] for a capsule on a frame `model` does not have.
    pub fn new(
        model: &Model,
        name: &str,
        capsule: Capsule,
        point: Vector3<f64>,
        normal: Vector3<f64>,
        margin: f64,
    ) -> Result<Self, TaskError> {
        check_margin(name, margin)?;
        model.check_frame(capsule.frame)?;
        finite_target(name, point.as_slice())?;
        finite_target(name, normal.as_slice())?;
        if normal.norm() < 1e-12 {
            return Err(TaskError::InvalidGeometry {
                task: name.to_owned(),
                reason: "zero plane normal",
            });
        }
        Ok(Self {
            name: name.to_owned(),
            capsule,
            point,
            normal: normal.normalize(),
            margin,
        })
    }

    /// The signed distance `d` (m; < 0 when the capsule cuts the plane) at the forward
    /// kinematics in `data`.
    pub fn distance(&self, model: &Model, data: &ModelData) -> Result<f64, ModelError> {
        Ok(self.nearest(model, data)?.0)
    }

    /// The signed distance and the segment parameter of the point nearest the plane.
    fn nearest(&self, model: &Model, data: &ModelData) -> Result<(f64, f64), ModelError> {
        let [a, b] = self.capsule.ends(model, data)?;
        let (ha, hb) = (
            self.normal.dot(&(a - self.point)),
            self.normal.dot(&(b - self.point)),
        );
        let s = if (ha - hb).abs() <= 1e-12 {
            0.5
        } else if ha < hb {
            0.0
        } else {
            1.0
        };
        Ok((ha.min(hb) - self.capsule.radius, s))
    }
}

impl InequalityTask for PlaneDistanceTask {
    fn name(&self) -> &str {
        &self.name
    }

    fn rows(&self) -> usize {
        1
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        mut jacobian: MatMut<'_, f64>,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<(), ModelError> {
        let (d, s) = self.nearest(model, data)?;
        let offset = self.capsule.local(s);
        jacobian.fill(0.0);
        let (frame, normal) = (self.capsule.frame, &self.normal);
        model.add_point_jacobian_along(data, frame, &offset, normal, jacobian.as_mut())?;
        write_room(self.margin, d, lower, upper);
        Ok(())
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
