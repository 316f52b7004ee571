//! The support polygon of a phase for its ZMP rows
//! ([`Constraint::Zmp`](crate::imitation::phase::tables::Constraint::Zmp)): the root sole's contact area, with
//! the other sole's where the phase stands on both feet, as their convex hull in the root frame
//! at the start of each frame.

use crate::imitation::phase::tables::TaskTable;
use crate::model::{FrameId, Model, ModelData};
use crate::robots::BipedProfile;
use crate::tasks::{TaskError, ZmpTask, convex_hull};

/// A phase's ZMP rows with the polygon they keep the ZMP in. Buffers are allocated once;
/// [`SupportZmp::begin_frame`] allocates nothing.
#[derive(Debug, Clone)]
pub(crate) struct SupportZmp {
    pub(crate) task: ZmpTask,
    margin: f64,
    /// The contact areas (sole frame, m): the root's, and the other sole's when it stands.
    root: Vec<[f64; 2]>,
    other: Option<(FrameId, Vec<[f64; 2]>)>,
    points: Vec<[f64; 2]>,
    hull: Vec<[f64; 2]>,
}

impl SupportZmp {
    /// The rows of a ZMP constraint of `margin` (m) and `max_yaw_moment` (N·m) with room for
    /// `vertices` polygon corners, for `table`'s phase on `model`, seeing the momentum of the
    /// joints `arms` (one per variable).
    pub(crate) fn new(
        table: &TaskTable,
        profile: &BipedProfile,
        model: &Model,
        arms: Vec<bool>,
        [margin, max_yaw_moment]: [f64; 2],
        vertices: usize,
    ) -> Result<Self, TaskError> {
        let root = table.model_root;
        let standing = table.phase.standing_feet();
        let other = (standing[root.other().index()])
            .then(|| {
                let foot = profile.foot(root.other());
                Ok::<_, TaskError>((model.frame_id(&foot.sole)?, foot.outline.clone()))
            })
            .transpose()?;
        let outline = profile.foot(root).outline.clone();
        let mut points = outline.clone();
        let mut hull = Vec::with_capacity(vertices + 1);
        convex_hull(&mut points, &mut hull);
        points.reserve(vertices);
        let task = ZmpTask::new(model, vertices, &hull, margin, max_yaw_moment)?.seeing(arms)?;
        Ok(Self {
            task,
            margin,
            root: outline,
            other,
            points,
            hull,
        })
    }

    /// Sets the polygon from the other sole's placement in `data` (the frame's start) and
    /// starts the task's frame (see [`ZmpTask::begin_frame`]).
    pub(crate) fn begin_frame(
        &mut self,
        data: &ModelData,
        start: &[f64],
        velocity: &[f64],
        dt: f64,
    ) -> Result<(), TaskError> {
        self.points.clear();
        self.points.extend_from_slice(&self.root);
        if let Some((sole, outline)) = &self.other {
            let placement = data.frame_placement(*sole);
            self.points.extend(outline.iter().map(|&[x, y]| {
                let p = placement.transform_point(&nalgebra::Point3::new(x, y, 0.0));
                [p.x, p.y]
            }));
        }
        convex_hull(&mut self.points, &mut self.hull);
        self.task.set_polygon(&self.hull, self.margin)?;
        self.task.begin_frame(start, velocity, dt)
    }
}

/// The joints' velocity over the last frame (per second, one per model variable), from the
/// postures at the start of consecutive frames: what the ZMP rows need to turn a
/// frame's step into an acceleration. Zero before the second frame. Allocates nothing after
/// [`JointVelocity::new`].
#[derive(Debug, Clone)]
pub(crate) struct JointVelocity {
    start: Vec<f64>,
    velocity: Vec<f64>,
    /// The length of the frame that began at `start` (s); `None` before the first.
    dt: Option<f64>,
}

impl JointVelocity {
    /// For `nv` variables, at rest.
    pub(crate) fn new(nv: usize) -> Self {
        Self {
            start: vec![0.0; nv],
            velocity: vec![0.0; nv],
            dt: None,
        }
    }

    /// At the start of a frame of `dt` seconds at posture `q`: the velocity of the frame that
    /// ends here becomes [`JointVelocity::get`].
    pub(crate) fn begin(&mut self, q: &[f64], dt: f64) {
        if let Some(previous) = self.dt {
            for ((v, &q), &q0) in self.velocity.iter_mut().zip(q).zip(&self.start) {
                *v = (q - q0) / previous;
            }
        }
        self.start.copy_from_slice(q);
        self.dt = Some(dt);
    }

    /// The joints' velocity over the last frame.
    pub(crate) fn get(&self) -> &[f64] {
        &self.velocity
    }
}
