//! A run as a motion track: time, joint angles, the floating base's world pose and the soles'
//! floor contacts per frame.
//!
//! The base pose is forward kinematics from the sole the imitator rooted its model at:
//! `ʷT_base = ʷT_sole · ˢᵒˡᵉT_base(q)`, with `ʷT_sole` the frame's placement of that sole
//! ([`RobotFrame::left_sole`], [`RobotFrame::right_sole`]). A sole is on the floor when every
//! point of its outline is within
//! [`CONTACT_HEIGHT`](crate::imitation::output::CONTACT_HEIGHT) of it, as the imitation
//! metrics count it ([`sole_on_floor`]).
//!
//! Resampling to `fps` frames a second ([`MotionTrack::resampled`]) interpolates positions and
//! joint angles linearly and the base orientation along the great arc (slerp); a contact is
//! that of the earlier of the two frames around the sample.

use nalgebra::{IsometryMatrix3, Quaternion, UnitQuaternion, Vector3};
use thiserror::Error;

use crate::human::Side;
use crate::imitation::output::sole_on_floor;
use crate::imitation::{Imitator, RobotFrame};
use crate::model::{FrameId, ModelData, ModelError};
use crate::robots::BipedProfile;

/// Why an export could not be made.
#[derive(Debug, Error)]
pub enum ExportError {
    /// The model has no frame of this name (the profile's torso, the floating base).
    #[error("export: {0}")]
    Model(#[from] ModelError),
    /// A frame's joint vector has the wrong length.
    #[error("export: a frame has {got} joint angles, the robot {expected}")]
    JointCount {
        /// The robot's joint count.
        expected: usize,
        /// The frame's.
        got: usize,
    },
    /// A number is NaN or infinite (a frame's time or pose, or a rate).
    #[error("export: {0} is not finite")]
    NonFinite(&'static str),
    /// Frame times do not increase.
    #[error("export: frame {index} at {time} s is not after the frame before it")]
    TimeOrder {
        /// The frame's index.
        index: usize,
        /// Its time (s).
        time: f64,
    },
    /// The rate asked for is not positive.
    #[error("export: the frame rate must be > 0 (got {0})")]
    Rate(f64),
    /// A track with no frame cannot be exported.
    #[error("export: the motion has no frame")]
    Empty,
    /// Writing failed.
    #[error("export: {0}")]
    Io(#[from] std::io::Error),
}

/// A robot's motion, one entry per frame (world frame: z up, floor at z = 0).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MotionTrack {
    /// The joint names, in the order of each row of [`Self::dof_pos`].
    pub joint_names: Vec<String>,
    /// Frame times (s), increasing.
    pub time: Vec<f64>,
    /// Joint angles (rad), row-major: frame `i`'s angles are
    /// `dof_pos[i * J .. (i + 1) * J]`, `J` the joint count.
    pub dof_pos: Vec<f64>,
    /// The floating base's origin (m, world).
    pub root_pos: Vec<[f64; 3]>,
    /// The floating base's orientation (world), unit quaternion `[x, y, z, w]`, each in the
    /// hemisphere of the one before it (no sign flips between frames).
    pub root_quat: Vec<[f64; 4]>,
    /// Whether each sole is on the floor, `[left, right]`.
    pub contacts: Vec<[bool; 2]>,
}

impl MotionTrack {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether the track has no frame.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joint_names.len()
    }

    /// Joint angles of frame `i` (rad).
    pub fn joints(&self, i: usize) -> &[f64] {
        let j = self.joint_count();
        &self.dof_pos[i * j..(i + 1) * j]
    }

    /// The mean frame rate of the first `frames` frames (Hz), rounded to a whole number
    /// (at least 1): the rate a clip's own frames come at. `None` with fewer than two frames.
    pub fn nominal_rate(&self, frames: usize) -> Option<f64> {
        let n = frames.min(self.len());
        if n < 2 {
            return None;
        }
        let span = self.time[n - 1] - self.time[0];
        Some(((n - 1) as f64 / span).round().max(1.0))
    }

    /// The track sampled at `fps` frames a second from its first frame to its last (see the
    /// module docs); sample `k` is at `time[0] + k / fps`, and a sample that falls on a
    /// frame (within 1 ns) is that frame's values exactly.
    ///
    /// # Errors
    /// [`ExportError::Rate`] for a rate that is not a positive number, [`ExportError::Empty`]
    /// for an empty track.
    pub fn resampled(&self, fps: f64) -> Result<MotionTrack, ExportError> {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(ExportError::Rate(fps));
        }
        let (Some(&first), Some(&last)) = (self.time.first(), self.time.last()) else {
            return Err(ExportError::Empty);
        };
        let samples = ((last - first) * fps + 1e-9).floor() as usize + 1;
        let mut out = MotionTrack {
            joint_names: self.joint_names.clone(),
            ..MotionTrack::default()
        };
        let mut seg = 0;
        for k in 0..samples {
            let t = first + k as f64 / fps;
            while seg + 1 < self.len() && self.time[seg + 1] <= t + 1e-9 {
                seg += 1;
            }
            let next = (seg + 1).min(self.len() - 1);
            if (t - self.time[seg]).abs() <= 1e-9 || next == seg {
                out.push_blend(self, seg, seg, 0.0, t);
            } else {
                let w = (t - self.time[seg]) / (self.time[next] - self.time[seg]);
                out.push_blend(self, seg, next, w, t);
            }
        }
        Ok(out)
    }

    /// Appends, at time `t`, frame `a` of `src` blended toward frame `b` by `w` in [0, 1)
    /// (`w = 0`: frame `a` exactly).
    fn push_blend(&mut self, src: &MotionTrack, a: usize, b: usize, w: f64, t: f64) {
        let lerp = |x: f64, y: f64| if w == 0.0 { x } else { x + (y - x) * w };
        self.time.push(t);
        let (ja, jb) = (src.joints(a), src.joints(b));
        self.dof_pos
            .extend(ja.iter().zip(jb).map(|(&x, &y)| lerp(x, y)));
        let (pa, pb) = (src.root_pos[a], src.root_pos[b]);
        self.root_pos.push([0, 1, 2].map(|i| lerp(pa[i], pb[i])));
        let unit =
            |q: [f64; 4]| UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2]));
        let quat = if w == 0.0 {
            src.root_quat[a]
        } else {
            // nalgebra's slerp of two nearly equal rotations leaves the norm 1e-9 off.
            let q = unit(src.root_quat[a]).slerp(&unit(src.root_quat[b]), w);
            let q = UnitQuaternion::new_normalize(q.into_inner());
            [q.i, q.j, q.k, q.w]
        };
        self.root_quat.push(quat);
        self.contacts.push(src.contacts[a]);
    }
}

/// Records a [`MotionTrack`] from an imitator's frames as they come.
#[derive(Debug)]
pub struct MotionRecorder {
    profile: BipedProfile,
    data: [ModelData; 2],
    /// The floating base's frame in the model rooted at each sole.
    base: [FrameId; 2],
    track: MotionTrack,
}

impl MotionRecorder {
    /// A recorder for the frames of `imitator`.
    ///
    /// # Errors
    /// [`ExportError::Model`] when a rooted model lacks the profile's torso frame.
    pub fn new(imitator: &Imitator) -> Result<Self, ExportError> {
        let profile = imitator.profile().clone();
        let base_in = |side: Side| profile.model(side).frame_id(&profile.torso);
        let base = [base_in(Side::Left)?, base_in(Side::Right)?];
        let data = [Side::Left, Side::Right].map(|side| profile.model(side).new_data());
        let track = MotionTrack {
            joint_names: imitator.variable_names().map(str::to_owned).collect(),
            ..MotionTrack::default()
        };
        Ok(Self {
            profile,
            data,
            base,
            track,
        })
    }

    /// Adds `frame` (frames in time order).
    ///
    /// # Errors
    /// [`ExportError::JointCount`], [`ExportError::NonFinite`] or [`ExportError::TimeOrder`]
    /// for a frame that does not fit; nothing is recorded then.
    pub fn record(&mut self, frame: &RobotFrame) -> Result<(), ExportError> {
        if !frame.time.is_finite() {
            return Err(ExportError::NonFinite("a frame's time"));
        }
        if self.track.time.last().is_some_and(|&t| frame.time <= t) {
            return Err(ExportError::TimeOrder {
                index: self.track.len(),
                time: frame.time,
            });
        }
        let (position, quat) = self.base_pose(frame)?;
        let contacts = self.contacts(frame);
        self.track.time.push(frame.time);
        self.track.dof_pos.extend_from_slice(&frame.q);
        self.track.root_pos.push(position);
        self.track.root_quat.push(quat);
        self.track.contacts.push(contacts);
        Ok(())
    }

    /// The floating base's world pose at `frame` without recording it: position (m) and
    /// quaternion `[x, y, z, w]`, in the hemisphere of the last recorded one (w ≥ 0 before any).
    ///
    /// # Errors
    /// [`ExportError::JointCount`] or [`ExportError::NonFinite`] for a frame that does not fit.
    pub fn base_pose(&mut self, frame: &RobotFrame) -> Result<([f64; 3], [f64; 4]), ExportError> {
        let expected = self.track.joint_count();
        if frame.q.len() != expected {
            return Err(ExportError::JointCount {
                expected,
                got: frame.q.len(),
            });
        }
        let root = frame.root.index();
        let model = self.profile.model(frame.root);
        model.forward_kinematics(&mut self.data[root], &frame.q)?;
        let world_t_sole = match frame.root {
            Side::Left => &frame.left_sole,
            Side::Right => &frame.right_sole,
        };
        let base = world_t_sole * self.data[root].frame_placement(self.base[root]);
        let (position, quat) = pose(&base, self.track.root_quat.last());
        if !(position.iter().chain(&quat)).all(|v| v.is_finite()) {
            return Err(ExportError::NonFinite("the base pose"));
        }
        Ok((position, quat))
    }

    /// Whether each sole is on the floor at `frame`, `[left, right]`.
    pub fn contacts(&self, frame: &RobotFrame) -> [bool; 2] {
        let soles = [&frame.left_sole, &frame.right_sole];
        [Side::Left, Side::Right]
            .map(|side| sole_on_floor(&self.profile.foot(side).outline, soles[side.index()]))
    }

    /// The track recorded so far.
    pub fn track(&self) -> &MotionTrack {
        &self.track
    }

    /// The recorded track.
    pub fn finish(self) -> MotionTrack {
        self.track
    }
}

/// Position and `[x, y, z, w]` quaternion of `placement`, the quaternion in the hemisphere of
/// `previous` (w ≥ 0 without one).
fn pose(placement: &IsometryMatrix3<f64>, previous: Option<&[f64; 4]>) -> ([f64; 3], [f64; 4]) {
    let q = UnitQuaternion::from_rotation_matrix(&placement.rotation);
    let mut quat = [q.i, q.j, q.k, q.w];
    let dot = previous.map_or(quat[3], |p| (0..4).map(|i| p[i] * quat[i]).sum());
    if dot < 0.0 {
        quat = quat.map(|v| -v);
    }
    let t: Vector3<f64> = placement.translation.vector;
    ([t.x, t.y, t.z], quat)
}
