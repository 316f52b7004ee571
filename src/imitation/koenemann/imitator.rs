//! The per-frame pipeline of Koenemann et al.'s method (see the module docs of
//! [`super`]): state, targets, the three IK problems, and the robot frame it writes.

use std::time::Instant;

use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use super::body::{Body, beyond_fold, outside_torso};
use super::goals::{Goal, GoalIk, in_torso};
use super::mapping::{Posture, PostureMapping};
use super::offset::{OffsetSpeed, offset};
use super::retarget::{FootRetargeting, retarget_double, support_normal};
use super::solves::{Frames, Solves, frames};
use super::support_mode::{SupportMode, target_offset};
use super::{ARM_STOP_TIME_CONSTANTS, KoenemannConfig, LEG_STOP_TIME_CONSTANTS};
use crate::human::{HumanFrame, HumanJoint, Side, centre_of_mass};
use crate::imitation::config::ImitatorConfig;
use crate::imitation::error::ImitationError;
use crate::imitation::output::CONTACT_HEIGHT;
use crate::imitation::output::RobotFrame;
use crate::imitation::phase::{HoldTimer, Landing, SupportPhase, TakeOff};
use crate::imitation::reference::support::{HumanSupport, SupportDetector};
use crate::imitation::shaping::{HandRates, HandSpeed, MotionLimits, SwingHeight};
use crate::imitation::state::{Shared, human_stance};
use crate::locomotion::preview::GRAVITY;
use crate::model::ModelData;
use crate::robots::{BipedProfile, FootArea, SolePlacement};
use crate::solver::JointBounds;

/// Smallest height of a swing sole above the floor while the human's foot is up (m).
const SWING_CLEARANCE: f64 = 0.01;
/// Koenemann et al.'s imitator.
#[derive(Debug)]
pub(crate) struct KoenemannImitator {
    pub(crate) shared: Shared,
    config: KoenemannConfig,
    /// The offset's speed limit: the config's, or the profile's.
    offset_speed: OffsetSpeed,
    frames: [Frames; 2],
    body: Body,
    mapping: Option<PostureMapping>,
    detector: SupportDetector,
    arms: GoalIk,
    /// The upper body's self-collision pairs alone: moves the arms the least that keeps them
    /// apart after `arms`; `None` when the profile pairs no upper-body bodies.
    arms_apart: Option<GoalIk>,
    /// The CoM strictly, then 3 + 2 rows (the swing foot), then 3 + 2 rows (the support sole
    /// in the torso frame): single support, landing, the paper's double support.
    feet: GoalIk,
    /// The held sole (3 + 3 rows), then the CoM, then 3 + 2 rows: double support keeping the
    /// stance.
    stance: GoalIk,
    /// The held sole alone (3 + 3 rows): puts it back after the legs are slowed down.
    settle: GoalIk,
    position_bounds: JointBounds,
    /// The position limits narrowed to what the velocity limits reach in the frame.
    frame_bounds: JointBounds,
    hand_speed: HandSpeed,
    /// The hand targets' speeds, shaped frame by frame.
    hand_rates: HandRates,
    /// How long the human has stood on both feet (s; 0 while a foot is up).
    human_double_time: f64,
    foot_speed: f64,
    motion: MotionLimits,
    step_envelope: FootArea,
    q_start: Vec<f64>,
    /// Each joint's velocity over the last frame (rad/s, model variable order).
    velocity: Vec<f64>,
    /// [`KoenemannConfig::leg_ramp_time`] resolved (s; 0: the legs start at once).
    leg_ramp_time: f64,
    /// [`KoenemannConfig::leg_stop_time`] resolved (s; 0: the legs stop at once).
    leg_stop_time: f64,
    /// [`KoenemannConfig::arm_stop_time`] resolved (s; 0: the other joints stop at once).
    arm_stop_time: f64,
    mode: SupportMode,
    /// How long the robot has been in double support with the human on one foot and its
    /// offset at that foot, against the settle time.
    lift_wait: HoldTimer,
    /// The foot coming down after single support, until it is on the floor.
    landing: Option<Side>,
    /// Commanded offset `o'`, its rate (1/s) and the offset achieved at the last frame.
    command: f64,
    command_rate: f64,
    measured: f64,
    /// Post-processed hand targets (torso frame).
    hands: Option<[Vector3<f64>; 2]>,
    /// Post-processed swing ankle target (root frame).
    swing_target: Option<Vector3<f64>>,
    swing: SwingHeight,
    /// Placement of the non-root sole held in double support (root frame).
    hold: IsometryMatrix3<f64>,
}

impl KoenemannImitator {
    pub(crate) fn new(
        profile: BipedProfile,
        config: &ImitatorConfig,
        method: KoenemannConfig,
    ) -> Result<Self, ImitationError> {
        let (shared, position_bounds) = Shared::new(profile, config)?;
        let profile = &shared.profile;
        let body = Body::measure(profile, &shared.q)?;
        let frames = [frames(profile, Side::Left)?, frames(profile, Side::Right)?];
        let Solves {
            arms,
            arms_apart,
            feet,
            stance,
            settle,
        } = Solves::new(&shared, &frames[Side::Right.index()], &method)?;
        let tuning = profile.tuning;
        let time_constant = (profile.size()?.com_height / GRAVITY).sqrt();
        let leg_ramp_time = (method.leg_ramp_time)
            .or(profile.sway_period)
            .unwrap_or(0.0);
        // The left sole in the right-rooted model (the root at the start).
        let hold = shared.output.left_sole;
        Ok(KoenemannImitator {
            detector: SupportDetector::new(config.support)?,
            // The profile's balanced speeds where it has them (the NAO's 1 m/s, 5 m/s²), though
            // this method has no ZMP level: its CoM offset control keeps the robot up under them.
            // Judged on the bundled clips at the automatic hold, the NAO passes every check on
            // both models at them (16 of 16, as at the old 0.8 / 0.3 m/s and 2 m/s²), the hands
            // 0.5–4.5 cm nearer the human on the clips whose arms move fast (CMU 05_02 9.1 / 7.0
            // → 4.6 / 4.7 cm) and no later than 0.11 s (0.21 s before).
            hand_speed: config.hand_speed_for(&tuning, true),
            hand_rates: HandRates::default(),
            human_double_time: 0.0,
            foot_speed: method.swing_speed.unwrap_or(tuning.task_speed),
            motion: config.motion_for(&tuning),
            step_envelope: config.step_envelope.unwrap_or(profile.step_envelope),
            q_start: shared.q.clone(),
            velocity: vec![0.0; shared.q.len()],
            leg_ramp_time,
            leg_stop_time: (method.leg_stop_time)
                .unwrap_or(leg_ramp_time.max(LEG_STOP_TIME_CONSTANTS * time_constant)),
            arm_stop_time: (method.arm_stop_time).unwrap_or(match profile.sway_period {
                Some(_) => 0.0,
                None => ARM_STOP_TIME_CONSTANTS * time_constant,
            }),
            offset_speed: (method.offset_speed).unwrap_or_else(|| OffsetSpeed::of_robot(&tuning)),
            config: method,
            frames,
            body,
            mapping: None,
            arms,
            arms_apart,
            feet,
            stance,
            settle,
            frame_bounds: position_bounds.clone(),
            position_bounds,
            mode: SupportMode::Double,
            lift_wait: HoldTimer::new((method.settle_time).or(profile.sway_period).unwrap_or(0.0)),
            landing: None,
            command: 0.5,
            command_rate: 0.0,
            measured: 0.5,
            hands: None,
            swing_target: None,
            swing: SwingHeight::at(0.0),
            hold,
            shared,
        })
    }

    /// Imitates one human frame.
    pub(crate) fn step(&mut self, frame: &HumanFrame) -> Result<&RobotFrame, ImitationError> {
        let start = Instant::now();
        let dt = self.shared.begin_frame(frame.time)?;
        let human = self.detector.update(frame);
        self.human_double_time = match human {
            HumanSupport::Double => self.human_double_time + dt,
            _ => 0.0,
        };
        self.q_start.copy_from_slice(&self.shared.q);
        let posture = Posture::of_human(frame);
        if self.mapping.is_none() && posture.is_some() {
            self.mapping = PostureMapping::calibrate(
                frame,
                &self.body.limbs,
                self.body.stance,
                self.config.calibration,
            );
        }
        let mapped = match (&self.mapping, &posture) {
            (Some(mapping), Some(p)) => Some(mapping.map(p)),
            _ => None,
        };
        // The root's forward kinematics are current: from the last step's end, the root
        // switch, or the start; every IK run below leaves them current at its final q.
        self.update_mode(frame, human, dt)?;
        self.track_hands(mapped.as_ref(), dt)?;
        self.stabilize(mapped.as_ref(), dt)?;
        self.limit_velocities(dt);
        self.keep_arms_apart(dt)?;
        self.settle_hold(dt)?;
        for (v, (q, q0)) in (self.velocity.iter_mut()).zip(self.shared.q.iter().zip(&self.q_start))
        {
            *v = (q - q0) / dt;
        }
        self.shared.refresh()?;
        self.measure();
        self.write_output(frame, human, mapped.as_ref())?;
        self.shared.previous_time = Some(frame.time);
        self.shared.output.micros = start.elapsed().as_secs_f64() * 1e6;
        Ok(&self.shared.output)
    }

    /// Fig. 4 and the offset command; the root follows the support foot.
    fn update_mode(
        &mut self,
        frame: &HumanFrame,
        human: HumanSupport,
        dt: f64,
    ) -> Result<(), ImitationError> {
        let tolerance = self.config.offset_tolerance;
        let next = self.settled(self.mode.next(human, self.measured, tolerance), dt);
        if let (SupportMode::Left | SupportMode::Right, SupportMode::Double) = (self.mode, next) {
            let support = if self.mode == SupportMode::Left {
                Side::Left
            } else {
                Side::Right
            };
            self.landing = Some(support.other());
            self.swing = SwingHeight::at(self.swing_sole_height(support.other()));
        }
        if let SupportMode::Left | SupportMode::Right = next {
            self.landing = None;
        }
        self.mode = next;
        if self.landing.is_none() {
            let target = match next {
                SupportMode::Left => 0.0,
                SupportMode::Right => 1.0,
                SupportMode::Double => {
                    target_offset(human, human_offset(frame).unwrap_or(0.5), self.command)
                }
            };
            (self.command, self.command_rate) =
                self.offset_speed
                    .step(self.command, self.command_rate, target, dt);
        }
        let root = match (next, self.landing) {
            (SupportMode::Left, _) => Side::Left,
            (SupportMode::Right, _) => Side::Right,
            (SupportMode::Double, Some(swing)) => swing.other(),
            (SupportMode::Double, None) => self.shared.root,
        };
        if root != self.shared.root {
            self.shared.switch_root(root)?;
            self.swing_target = None;
        }
        Ok(())
    }

    /// `next`, except that double support holds until the offset has stayed at the support
    /// foot for the settle time (the shaped command catching up with the plan).
    fn settled(&mut self, next: SupportMode, dt: f64) -> SupportMode {
        if self.mode != SupportMode::Double || next == SupportMode::Double {
            self.lift_wait.restart();
            return next;
        }
        match self.lift_wait.hold(true, dt) {
            true => next,
            false => SupportMode::Double,
        }
    }

    /// Height of `side`'s sole origin above the root sole (m).
    fn swing_sole_height(&self, side: Side) -> f64 {
        let (data, f) = self.current();
        data.frame_placement(f.soles[side.index()]).translation.z
    }

    fn current(&self) -> (&ModelData, &Frames) {
        let root = self.shared.root.index();
        (&self.shared.data[root], &self.frames[root])
    }

    /// The hand targets: mapped, at most the hands' speed ([`HandSpeed`]) × `dt` from the last
    /// ones, outside the torso; then the arms' IK.
    fn track_hands(&mut self, mapped: Option<&Posture>, dt: f64) -> Result<(), ImitationError> {
        let (data, f) = self.current();
        let current = f
            .hands
            .map(|h| in_torso(data, f.torso, h).translation.vector);
        let wanted = match mapped {
            Some(m) => [0, 1].map(|k| self.body.shoulders[k] + m.hands[k]),
            None => self.hands.unwrap_or(current),
        };
        let previous = self.hands.unwrap_or(current);
        // Both feet down and no foot landing: the robot stands on both.
        let robot_double = self.mode == SupportMode::Double && self.landing.is_none();
        let cap = (self.hand_speed).at(self.human_double_time, robot_double);
        let distances = [0, 1].map(|k| (wanted[k] - previous[k]).norm());
        let acceleration = self.hand_speed.acceleration;
        let speeds = (self.hand_rates).advance(cap, acceleration, distances, dt);
        let radius = 0.5 * (self.body.hips[0] - self.body.hips[1]).norm();
        let targets = [0, 1].map(|k| {
            let moved = step_toward(previous[k], wanted[k], speeds[k] * dt);
            let unfolded = beyond_fold(moved, k, &self.body);
            outside_torso(unfolded, radius, &self.body)
        });
        self.hands = Some(targets);
        let root = self.shared.root.index();
        let f = &self.frames[root];
        for (goal, (&frame, target)) in self.arms.goals.iter_mut().zip(f.hands.iter().zip(targets))
        {
            *goal = Goal::TorsoPoint {
                frame,
                offset: Vector3::zeros(),
                target,
            };
        }
        self.arms
            .run(&mut self.shared, f.torso, &self.position_bounds)?;
        Ok(())
    }

    /// §V.C: the feet's goals for the mode, and the legs' IK.
    fn stabilize(&mut self, mapped: Option<&Posture>, dt: f64) -> Result<(), ImitationError> {
        let (data, f) = self.current();
        let ankles_now = f
            .ankles
            .map(|a| in_torso(data, f.torso, a).translation.vector);
        let ankles = match mapped {
            Some(m) => [0, 1].map(|k| self.body.hips[k] + m.feet[k]),
            None => ankles_now,
        };
        // Mapped ankle targets carried to the sole centres by the feet's current offsets.
        let centres_now = Side::BOTH.map(|s| self.centre_in_torso(s));
        let centres = [0, 1].map(|k| ankles[k] + (centres_now[k] - ankles_now[k]));
        let com = self.com_in_torso()?;
        match (self.mode, self.landing) {
            (SupportMode::Left, _) => self.single(Side::Left, &com, &centres, &ankles, false, dt),
            (SupportMode::Right, _) => self.single(Side::Right, &com, &centres, &ankles, false, dt),
            (SupportMode::Double, Some(swing)) => {
                self.single(swing.other(), &com, &centres, &ankles, true, dt)
            }
            (SupportMode::Double, None) => self.double(&com, centres, &centres_now),
        }
    }

    /// Single support on `support` (or the landing of the other foot), in priority order: the
    /// CoM above the support sole's centre; the swing ankle at its post-processed target, flat
    /// (so a landing foot comes down); the support sole at its mapped place in the torso frame
    /// with the normal of eq. 7 (offset 0 or 1).
    fn single(
        &mut self,
        support: Side,
        com: &Vector3<f64>,
        centres: &[Vector3<f64>; 2],
        ankles: &[Vector3<f64>; 2],
        landing: bool,
        dt: f64,
    ) -> Result<(), ImitationError> {
        let (s, w) = (support.index(), support.other().index());
        let normal = support_normal(com, &centres[s], &centres[s], 0.0).unwrap_or(Vector3::z());
        let swing = self.swing_ankle_target(support, ankles[w], landing, dt);
        let above = self.floor_centres()[s];
        let root = self.shared.root.index();
        let f = &self.frames[root];
        self.feet.goals.copy_from_slice(&[
            Goal::RootCom { target: above },
            Goal::RootPoint {
                frame: f.ankles[w],
                offset: Vector3::zeros(),
                target: swing,
            },
            Goal::RootNormal {
                frame: f.soles[w],
                normal: Vector3::z(),
            },
            Goal::TorsoPoint {
                frame: f.soles[s],
                offset: self.body.centres[s],
                target: centres[s],
            },
            Goal::TorsoNormal {
                frame: f.soles[s],
                normal,
            },
        ]);
        self.feet
            .run(&mut self.shared, f.torso, &self.position_bounds)?;
        Ok(())
    }

    /// The swing ankle's target in the root frame: the mapped one, at most `foot_speed` from
    /// the last, above the floor, beside the support foot; while landing, at its last place on
    /// the floor's step envelope, lowered at the touchdown speed.
    fn swing_ankle_target(
        &mut self,
        support: Side,
        mapped: Vector3<f64>,
        landing: bool,
        dt: f64,
    ) -> Vector3<f64> {
        let (data, f) = self.current();
        let w = support.other().index();
        let torso = data.frame_placement(f.torso);
        let wanted = torso.transform_point(&mapped.into()).coords;
        let current = data.frame_placement(f.ankles[w]).translation.vector;
        let previous = self.swing_target.unwrap_or(current);
        let reach = self.foot_speed * dt;
        let mut target = step_toward(previous, wanted, reach);
        let ankle_height = self.body.ankles[w].z;
        // The sole's place relative to the support sole (the root), clipped.
        let sole_offset = target.xy() - self.body.ankles[w].xy();
        let placement = SolePlacement {
            xy: sole_offset,
            yaw: 0.0,
        };
        let clipped = if landing {
            self.step_envelope.clip(support.other(), placement)
        } else {
            let lateral = FootArea {
                x_min: f64::NEG_INFINITY,
                x_max: f64::INFINITY,
                lateral_max: f64::INFINITY,
                yaw_max: 0.0,
                ..self.step_envelope
            };
            lateral.clip(support.other(), placement)
        };
        target.x = clipped.xy.x + self.body.ankles[w].x;
        target.y = clipped.xy.y + self.body.ankles[w].y;
        if landing {
            self.swing.advance(0.0, dt, &self.motion);
            target.z = ankle_height + self.swing.height();
        } else {
            target.z = target.z.max(ankle_height + SWING_CLEARANCE);
        }
        self.swing_target = Some(target);
        target
    }

    /// Double support: the CoM strictly above the point at the commanded offset between the
    /// soles on the floor; below it the feet's goals from the retargeting rule (in the torso
    /// frame, with the common normal of eq. 7).
    fn double(
        &mut self,
        com: &Vector3<f64>,
        mapped: [Vector3<f64>; 2],
        now: &[Vector3<f64>; 2],
    ) -> Result<(), ImitationError> {
        let rule = self.config.retargeting;
        let root = self.shared.root;
        let (r, o) = (root.index(), root.other().index());
        let targets = match rule {
            FootRetargeting::ShiftBothFeet => {
                // The stance as it is, placed where the mapping puts its middle.
                let (middle, half) = ((mapped[0] + mapped[1]) * 0.5, (now[1] - now[0]) * 0.5);
                retarget_double(rule, com, [middle - half, middle + half], self.command)
            }
            FootRetargeting::MoveOneFoot => retarget_double(rule, com, mapped, self.command),
        };
        let normal =
            support_normal(com, &targets[0], &targets[1], self.command).unwrap_or(Vector3::z());
        let above = self.floor_point(&targets, self.command);
        let f = &self.frames[r];
        let centre = |k: usize| Goal::TorsoPoint {
            frame: f.soles[k],
            offset: self.body.centres[k],
            target: targets[k],
        };
        let sole_normal = |k: usize| Goal::TorsoNormal {
            frame: f.soles[k],
            normal,
        };
        let com_goal = Goal::RootCom { target: above };
        let ik = match rule {
            FootRetargeting::ShiftBothFeet => {
                let [point, orientation] = self.hold_goals();
                self.stance.goals.copy_from_slice(&[
                    point,
                    orientation,
                    com_goal,
                    centre(r),
                    sole_normal(r),
                ]);
                &mut self.stance
            }
            FootRetargeting::MoveOneFoot => {
                // The other sole's goals above the root's: they are the ones that move it.
                self.feet.goals.copy_from_slice(&[
                    com_goal,
                    centre(o),
                    sole_normal(o),
                    centre(r),
                    sole_normal(r),
                ]);
                &mut self.feet
            }
        };
        ik.run(&mut self.shared, f.torso, &self.position_bounds)?;
        Ok(())
    }

    /// The upper body's self-collision pairs kept apart, within what the velocity limits reach
    /// this frame: after [`Self::limit_velocities`], whose straight line in joint space can cut
    /// through the torso where the hands' IK went around it. The frame's start was apart, so
    /// the reach always holds a posture that is.
    fn keep_arms_apart(&mut self, dt: f64) -> Result<(), ImitationError> {
        let Some(arms_apart) = &mut self.arms_apart else {
            return Ok(());
        };
        let f = &self.frames[self.shared.root.index()];
        self.frame_bounds
            .copy_within_reach(&self.shared.bounds, &self.q_start, dt);
        arms_apart.run(&mut self.shared, f.torso, &self.frame_bounds)?;
        Ok(())
    }

    /// The non-root sole at its held placement (root frame): its origin and its orientation.
    fn hold_goals(&self) -> [Goal; 2] {
        let root = self.shared.root;
        let frame = self.frames[root.index()].soles[root.other().index()];
        [
            Goal::RootPoint {
                frame,
                offset: Vector3::zeros(),
                target: self.hold.translation.vector,
            },
            Goal::RootOrientation {
                frame,
                target: self.hold.rotation,
            },
        ]
    }

    /// The sole centres on the floor (x, y in the root frame, m), `[left, right]`.
    fn floor_centres(&self) -> [Vector2<f64>; 2] {
        let (data, f) = self.current();
        [0, 1].map(|k| {
            let sole = data.frame_placement(f.soles[k]);
            sole.transform_point(&self.body.centres[k].into())
                .coords
                .xy()
        })
    }

    /// The point at offset `o` between the sole centres `targets` (torso frame) once on the
    /// floor: the targets placed by the current torso, then moved so the root sole's centre
    /// stays where it is (the root sole does not move on the floor).
    fn floor_point(&self, targets: &[Vector3<f64>; 2], o: f64) -> Vector2<f64> {
        let (data, f) = self.current();
        let torso = data.frame_placement(f.torso);
        let placed = targets.map(|t| torso.transform_point(&t.into()).coords.xy());
        let r = self.shared.root.index();
        let shift = self.floor_centres()[r] - placed[r];
        let [left, right] = placed.map(|p| p + shift);
        left + (right - left) * o
    }

    /// The CoM in the torso frame (current forward kinematics).
    fn com_in_torso(&self) -> Result<Vector3<f64>, ImitationError> {
        let (data, f) = self.current();
        let com = self.shared.profile.model(self.shared.root).com(data)?;
        Ok(data
            .frame_placement(f.torso)
            .inverse_transform_point(&com.into())
            .coords)
    }

    /// The centre of `side`'s sole in the torso frame.
    fn centre_in_torso(&self, side: Side) -> Vector3<f64> {
        let (data, f) = self.current();
        let k = side.index();
        let sole = in_torso(data, f.torso, f.soles[k]);
        sole.transform_point(&self.body.centres[k].into()).coords
    }

    /// §V.D: every joint within its velocity limit for `dt`; the legs scaled together, then
    /// ramped ([`Self::ramp`]); the other joints slowed down before their targets over
    /// [`KoenemannConfig::arm_stop_time`].
    fn limit_velocities(&mut self, dt: f64) {
        let velocity = self.shared.bounds.velocity();
        let mut legs = 1.0_f64;
        for (i, &leg) in self.shared.legs.iter().enumerate() {
            let delta = (self.shared.q[i] - self.q_start[i]).abs();
            if leg && delta > velocity[i] * dt {
                legs = legs.min(velocity[i] * dt / delta);
            }
        }
        for i in 0..self.shared.q.len() {
            let delta = self.shared.q[i] - self.q_start[i];
            let reach = velocity[i] * dt;
            self.shared.q[i] = self.q_start[i]
                + match self.shared.legs[i] {
                    true => self.ramp(i, delta, delta * legs, dt),
                    false => stop_before(
                        delta,
                        delta.clamp(-reach, reach),
                        velocity[i],
                        self.arm_stop_time,
                        dt,
                    ),
                };
        }
        self.shared.bounds.clamp_position(&mut self.shared.q);
    }

    /// Leg joint `i`'s `step` this frame (rad) toward its `target` (the legs' IK solution, rad
    /// ahead), ramped: its speed within `√(2 a |target|)`, what stops it there at the
    /// deceleration `a = v_max / T` ([`KoenemannConfig::leg_stop_time`] `T`, `v_max` its
    /// velocity limit), and within `v_max dt / T'` of its last frame's speed
    /// ([`KoenemannConfig::leg_ramp_time`] `T'`, unbounded at 0). The legs then stop smoothly
    /// (and start so where `T'` > 0), and so does the CoM they carry. Joint by joint, so the
    /// legs leave their common line a little; in double support the held sole is put back
    /// after ([`Self::settle_hold`]).
    fn ramp(&self, i: usize, target: f64, step: f64, dt: f64) -> f64 {
        let limit = self.shared.bounds.velocity()[i];
        let step = stop_before(target, step, limit, self.leg_stop_time, dt);
        if self.leg_ramp_time <= 0.0 {
            return step;
        }
        let last = self.velocity[i] * dt;
        let change = limit / self.leg_ramp_time * dt * dt;
        step.clamp(last - change, last + change)
    }

    /// In double support, the held sole put back where it stands, within the frame's velocity
    /// limits: slowing the legs down moves them along a straight line in joint space, which
    /// leaves the closed chain of the two feet by the square of the step (millimetres after a
    /// large correction).
    fn settle_hold(&mut self, dt: f64) -> Result<(), ImitationError> {
        if self.mode != SupportMode::Double || self.landing.is_some() {
            return Ok(());
        }
        let hold = self.hold_goals();
        self.settle.goals.copy_from_slice(&hold);
        let f = &self.frames[self.shared.root.index()];
        self.frame_bounds
            .copy_within_reach(&self.shared.bounds, &self.q_start, dt);
        self.settle
            .run(&mut self.shared, f.torso, &self.frame_bounds)?;
        Ok(())
    }

    /// The offset achieved (the CoM's ground projection between the sole centres) and the
    /// landing foot's contact: once it is down, it is held where it landed.
    fn measure(&mut self) {
        let [left, right] = self.floor_centres().map(|c| Vector3::new(c.x, c.y, 0.0));
        let (data, f) = self.current();
        let measured = match self.shared.profile.model(self.shared.root).com(data) {
            Ok(com) => offset(&Vector3::new(com.x, com.y, 0.0), &left, &right),
            Err(_) => None,
        };
        let landed = self.landing.and_then(|swing| {
            let sole = *data.frame_placement(f.soles[swing.index()]);
            let outline = &self.shared.profile.foot(swing).outline;
            let down = outline.iter().all(|&[x, y]| {
                sole.transform_point(&Vector3::new(x, y, 0.0).into()).z <= CONTACT_HEIGHT
            });
            down.then_some(sole)
        });
        self.measured = measured.unwrap_or(self.measured);
        if let Some(sole) = landed {
            self.landing = None;
            self.hold = sole;
            self.swing_target = None;
        }
    }

    /// The robot's phase in [`SupportPhase`] terms.
    fn phase(&self, human: HumanSupport) -> SupportPhase {
        let tolerance = self.config.offset_tolerance;
        match (self.mode, self.landing) {
            (SupportMode::Left, _) => SupportPhase::Left,
            (SupportMode::Right, _) => SupportPhase::Right,
            (SupportMode::Double, Some(Side::Right)) => {
                SupportPhase::LeftToDouble(Landing::LowerFoot)
            }
            (SupportMode::Double, Some(Side::Left)) => {
                SupportPhase::RightToDouble(Landing::LowerFoot)
            }
            (SupportMode::Double, None) => match human {
                HumanSupport::Left if self.command > tolerance => {
                    SupportPhase::DoubleToLeft(TakeOff::ComToFoot)
                }
                HumanSupport::Right if self.command < 1.0 - tolerance => {
                    SupportPhase::DoubleToRight(TakeOff::ComToFoot)
                }
                _ => SupportPhase::Double,
            },
        }
    }

    fn write_output(
        &mut self,
        frame: &HumanFrame,
        human: HumanSupport,
        mapped: Option<&Posture>,
    ) -> Result<(), ImitationError> {
        let phase = self.phase(human);
        let root = self.shared.root.index();
        let f = &self.frames[root];
        let data = &self.shared.data[root];
        let torso = *data.frame_placement(f.torso);
        let out = &mut self.shared.output;
        out.reference = [None; HumanJoint::COUNT];
        let to_root = |p: Vector3<f64>| torso.transform_point(&p.into()).coords;
        if let Some(m) = mapped {
            use HumanJoint as J;
            for (k, (hand, ankle)) in [(J::LHand, J::LAnkle), (J::RHand, J::RAnkle)]
                .into_iter()
                .enumerate()
            {
                out.reference[hand.index()] = Some(to_root(self.body.shoulders[k] + m.hands[k]));
                out.reference[ankle.index()] = Some(to_root(self.body.hips[k] + m.feet[k]));
            }
        }
        out.task_count = 0;
        out.human_stance = human_stance(frame);
        out.leg_ratio = self
            .mapping
            .as_ref()
            .map_or(1.0, |m| 0.5 * (m.ratios().legs[0] + m.ratios().legs[1]));
        out.pending_steps = 0;
        out.human_support = human;
        let effectors = f.effectors;
        self.shared.write_output(frame.time, phase, &effectors)
    }
}

/// Human offset (eq. 6) of the estimated CoM between the foot centres (ankle–toe midpoints, or
/// the ankles), on the ground plane.
fn human_offset(frame: &HumanFrame) -> Option<f64> {
    use HumanJoint as J;
    let foot = |ankle: J, toe: J| -> Option<Vector3<f64>> {
        let a = frame.get(ankle)?;
        let mut c = frame.get(toe).map_or(a, |t| (a + t) * 0.5);
        c.z = 0.0;
        Some(c)
    };
    let mut com = centre_of_mass(frame)?;
    com.z = 0.0;
    offset(&com, &foot(J::LAnkle, J::LToe)?, &foot(J::RAnkle, J::RToe)?)
}

/// `from` moved toward `to` by at most `reach` (m).
fn step_toward(from: Vector3<f64>, to: Vector3<f64>, reach: f64) -> Vector3<f64> {
    let step = to - from;
    let distance = step.norm();
    match distance <= reach {
        true => to,
        false => from + step * (reach / distance),
    }
}

/// A joint's `step` this frame (rad) toward its `target` (rad ahead) within `√(2 a |target|)
/// dt`, the speed that stops it there at the deceleration `a = v_max / T` (`v_max` its velocity
/// limit, rad/s; `stop_time` `T`, s; 0: `step` unchanged).
fn stop_before(target: f64, step: f64, limit: f64, stop_time: f64, dt: f64) -> f64 {
    if stop_time <= 0.0 {
        return step;
    }
    let stop = (2.0 * limit / stop_time * target.abs()).sqrt() * dt;
    step.clamp(-stop, stop)
}
