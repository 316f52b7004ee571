//! The pattern generator: footsteps in, a CoM whose cart-table ZMP follows the support, and
//! the swing soles, out, one control tick at a time.

use nalgebra::{Rotation2, Rotation3, Vector2, Vector3};

use super::LocomotionError;
use super::footstep::{Footstep, GroundPose, mean_heading};
use super::preview::{CartTable, PreviewGains, PreviewSettings, positive};
use super::schedule::{Schedule, SoleCentres, Support};
use super::swing::{SolePose, SwingProfile};
use crate::human::Side;

/// What a walk is made of: the pendulum, the controller and the swing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkSettings {
    /// Height of the CoM above the floor while walking (m): the cart-table's `z_c`.
    pub com_height: f64,
    /// Control tick (s).
    pub dt: f64,
    /// Weights and window of the preview controller.
    pub preview: PreviewSettings,
    /// Shape of every swing.
    pub swing: SwingProfile,
    /// Time the ZMP reference takes to return between the feet after the last queued step (s).
    pub stop_duration: f64,
    /// Shortest double support of a step that starts a walk, from rest or while stopping (s):
    /// the preview controller sees such a step only once it is queued.
    pub start_duration: f64,
    /// Most steps queued at once: the queue is allocated once with this capacity.
    pub capacity: usize,
}

impl WalkSettings {
    fn validate(&self) -> Result<(), LocomotionError> {
        positive("com_height", self.com_height)?;
        positive("dt", self.dt)?;
        positive("stop_duration", self.stop_duration)?;
        positive("start_duration", self.start_duration)?;
        let swing = self.swing;
        if !(swing.height.is_finite() && swing.height >= 0.0) {
            return Err(LocomotionError::InvalidParameter {
                name: "swing.height",
                value: swing.height,
                reason: "must be finite and >= 0",
            });
        }
        if !(0.0..0.5).contains(&swing.lift_share) {
            return Err(LocomotionError::InvalidParameter {
                name: "swing.lift_share",
                value: swing.lift_share,
                reason: "must be in [0, 0.5)",
            });
        }
        if self.capacity == 0 {
            return Err(LocomotionError::InvalidParameter {
                name: "capacity",
                value: 0.0,
                reason: "must be at least one step",
            });
        }
        Ok(())
    }
}

/// The walk at one instant (world frame, m, s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkState {
    /// Generator clock (s).
    pub time: f64,
    /// CoM position (m; z is the walking height).
    pub com: Vector3<f64>,
    /// CoM horizontal velocity (m/s).
    pub com_velocity: Vector2<f64>,
    /// CoM horizontal acceleration (m/s²).
    pub com_acceleration: Vector2<f64>,
    /// The cart-table ZMP of the CoM motion, `c − z_c/g · c̈` (m).
    pub zmp: Vector2<f64>,
    /// The ZMP reference at this instant (m).
    pub zmp_reference: Vector2<f64>,
    /// Both soles `[left, right]`: on the floor or swinging.
    pub feet: [SolePose; 2],
    /// Which feet are on the floor.
    pub support: Support,
}

impl WalkState {
    /// The torso's up direction (unit) in a frame turned `frame_yaw` rad about the vertical:
    /// leaning sideways toward the side the CoM is on, by `lean_max` rad times the CoM's
    /// offset from the middle of the soles (across their mean heading) as a share of
    /// `half_span` m, at most `lean_max`.
    pub fn torso_up(&self, lean_max: f64, half_span: f64, frame_yaw: f64) -> Vector3<f64> {
        let heading = mean_heading(self.feet[0].yaw, self.feet[1].yaw);
        let [l, r] = self
            .feet
            .map(|f| Vector2::new(f.position[0], f.position[1]));
        let offset = Rotation2::new(-heading) * (self.com.xy() - (l + r) / 2.0);
        let share = offset.y / half_span.max(f64::EPSILON);
        let (sin, cos) = (lean_max * share.clamp(-1.0, 1.0)).sin_cos();
        Rotation3::from_axis_angle(&Vector3::z_axis(), heading - frame_yaw)
            * Vector3::new(0.0, sin, cos)
    }

    /// Standing at `feet` with the CoM at rest above `com_xy` at height `com_height` (m).
    fn at_rest(feet: [GroundPose; 2], com_xy: Vector2<f64>, com_height: f64) -> Self {
        WalkState {
            time: 0.0,
            com: Vector3::new(com_xy.x, com_xy.y, com_height),
            com_velocity: Vector2::zeros(),
            com_acceleration: Vector2::zeros(),
            zmp: com_xy,
            zmp_reference: com_xy,
            feet: feet.map(|f| SolePose::on_floor(&f)),
            support: Support::Double,
        }
    }
}

/// ZMP preview control over a queue of footsteps (see the module docs of
/// [`crate::locomotion`]). Allocates its buffers in [`PatternGenerator::new`]; `push` and `tick`
/// allocate nothing.
#[derive(Debug, Clone)]
pub struct PatternGenerator {
    settings: WalkSettings,
    gains: PreviewGains,
    schedule: Schedule,
    /// Per axis (x, y): CoM position, velocity, acceleration.
    axes: [Vector3<f64>; 2],
    reference: [Vec<f64>; 2],
    state: WalkState,
}

impl PatternGenerator {
    /// A generator at time 0 with the soles standing at `feet` (`[left, right]`, world), whose
    /// contact-area centres are `centres`, and the CoM at rest above `com_xy` (m, world).
    ///
    /// # Errors
    /// [`LocomotionError::InvalidParameter`] for bad settings, [`LocomotionError::NonFinite`]
    /// for a non-finite pose or CoM, [`LocomotionError::RiccatiDiverged`].
    pub fn new(
        settings: WalkSettings,
        centres: SoleCentres,
        feet: [GroundPose; 2],
        com_xy: Vector2<f64>,
    ) -> Result<Self, LocomotionError> {
        settings.validate()?;
        let model = CartTable::new(settings.com_height, settings.dt)?;
        let gains = PreviewGains::new(model, settings.preview)?;
        let window = gains.window();
        let schedule = Schedule::new(
            centres,
            feet,
            settings.capacity,
            settings.stop_duration,
            settings.start_duration,
        );
        let mut generator = Self {
            settings,
            gains,
            schedule,
            axes: [Vector3::zeros(); 2],
            reference: [vec![0.0; window], vec![0.0; window]],
            state: WalkState::at_rest(feet, com_xy, settings.com_height),
        };
        generator.restart(feet, com_xy)?;
        Ok(generator)
    }

    /// Starts over at time 0, the queue empty, the soles standing at `feet` (`[left, right]`,
    /// world) and the CoM at rest above `com_xy` (m, world); allocates nothing, so a walk can
    /// start from wherever a robot stands.
    ///
    /// # Errors
    /// [`LocomotionError::NonFinite`] for a non-finite pose or CoM (the generator is unchanged).
    pub fn restart(
        &mut self,
        feet: [GroundPose; 2],
        com_xy: Vector2<f64>,
    ) -> Result<(), LocomotionError> {
        if !feet.iter().all(GroundPose::is_finite) || !com_xy.iter().all(|v| v.is_finite()) {
            return Err(LocomotionError::NonFinite("initial feet or CoM"));
        }
        self.schedule.restart(feet);
        self.axes = [
            Vector3::new(com_xy.x, 0.0, 0.0),
            Vector3::new(com_xy.y, 0.0, 0.0),
        ];
        self.state = WalkState::at_rest(feet, com_xy, self.settings.com_height);
        Ok(())
    }

    /// The settings it was built with.
    pub fn settings(&self) -> &WalkSettings {
        &self.settings
    }

    /// The preview controller's gains.
    pub fn gains(&self) -> &PreviewGains {
        &self.gains
    }

    /// The walk at the last tick.
    pub fn state(&self) -> &WalkState {
        &self.state
    }

    /// Queues `step` after the queued ones: it starts when the last queued step lands, or now
    /// when none is pending (from wherever the ZMP reference is, with a double support of at
    /// least [`WalkSettings::start_duration`]). Returns its landing time (s, generator clock).
    ///
    /// # Errors
    /// [`LocomotionError::QueueFull`], [`LocomotionError::InvalidParameter`] for a timing that
    /// is not positive, [`LocomotionError::NonFinite`] for a non-finite target.
    pub fn push(&mut self, step: Footstep) -> Result<f64, LocomotionError> {
        Ok(self.schedule.push(step, self.state.time)?.land)
    }

    /// Drops the queued steps that have not begun, but the one after a step under way (the
    /// CoM is already on its way to that stance): the walk then stops in double support.
    /// Returns how many were dropped.
    pub fn cancel_pending(&mut self) -> usize {
        self.schedule.cancel_pending(self.state.time)
    }

    /// Steps queued and not yet landed.
    pub fn queued(&self) -> usize {
        self.schedule.steps().len()
    }

    /// Where the soles stand once every queued step has landed (`[left, right]`, world).
    pub fn planned_feet(&self) -> &[GroundPose; 2] {
        self.schedule.planned()
    }

    /// Where the soles stand now, the swing foot at its lift-off place (`[left, right]`).
    pub fn standing_feet(&self) -> &[GroundPose; 2] {
        self.schedule.feet()
    }

    /// The queued steps' lift-off and landing times (s) with the step.
    pub fn queued_steps(&self) -> impl ExactSizeIterator<Item = (f64, f64, &Footstep)> {
        self.schedule.steps().map(|s| (s.lift, s.land, &s.step))
    }

    /// True once every queued step has landed and the ZMP reference is at rest between the feet.
    pub fn is_stopped(&self) -> bool {
        self.queued() == 0 && self.state.time >= self.schedule.rest_time()
    }

    /// Advances the walk by one tick and returns it.
    pub fn tick(&mut self) -> &WalkState {
        let dt = self.settings.dt;
        let now = self.state.time;
        let [rx, ry] = &mut self.reference;
        self.schedule.fill_reference(now, dt, rx, ry);
        let model = *self.gains.model();
        for (x, future) in self.axes.iter_mut().zip(&self.reference) {
            let jerk = self.gains.jerk(x, future);
            *x = model.a * *x + model.b * jerk;
        }
        let time = now + dt;
        self.schedule.retire(time);
        let (support, swinging) = self.schedule.support_at(time);
        let mut feet = self.schedule.feet().map(|f| SolePose::on_floor(&f));
        if let (Support::Single { swing, phase }, Some(step)) = (support, swinging) {
            feet[swing.index()] = self.settings.swing.at(&step.from, &step.step.target, phase);
        }
        let [x, y] = self.axes;
        self.state = WalkState {
            time,
            com: Vector3::new(x[0], y[0], self.settings.com_height),
            com_velocity: Vector2::new(x[1], y[1]),
            com_acceleration: Vector2::new(x[2], y[2]),
            zmp: Vector2::new(model.zmp(&x), model.zmp(&y)),
            zmp_reference: Vector2::new(self.reference[0][0], self.reference[1][0]),
            feet,
            support,
        };
        &self.state
    }

    /// The soles on the floor at the last tick, `[left, right]`.
    pub fn on_floor(&self) -> [bool; 2] {
        match self.state.support {
            Support::Double => [true, true],
            Support::Single { swing, .. } => Side::BOTH.map(|s| s != swing),
        }
    }
}
