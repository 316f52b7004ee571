//! Hands as supports (Di Fava et al. §III.C, Algorithm 1): a hand that the contact list of a
//! recording ([`crate::imitation::reference::contact_events`]) puts on a surface becomes a support of the robot.
//!
//! # The plan
//!
//! [`HandContactPlan`] is the offline part: per hand, the intervals `[t_enter, t_leave)` of the
//! human's clock (s) during which the human's hand rests on a surface of the scene, with the
//! surface and the human hand's position at `t_enter` (human world frame, m).
//!
//! # Placing, pausing, holding (Algorithm 1)
//!
//! From `t_enter − lead` the hand is *placed*: its target becomes the point where the human will
//! touch, mapped to the robot (below), and it goes there at the tracking speed, as a task of a
//! level of its own below the feet's contact level and above balance. It comes from above, so that it never passes through the
//! surface: a hand lower than `approach_height` above the surface and not over it first rises
//! where it is, then moves over its contact point at that height, then goes down. If the
//! human's clock reaches `t_enter` before the hand is within `tolerance` of the point, the clock
//! pauses there ([`RobotFrame::awaiting_contact`]: the imitator is fed the same human frame
//! again while the robot's clock runs on) until it is, or until `max_pause` has passed. Then the
//! contact is on: the hand is held at the point, and the point joins the feet's sole outlines in the support polygon whose area centroid becomes the
//! CoM goal (the centre of the contact hull). At `t_leave` the hand is free and follows the
//! human again.
//!
//! # From the human's surface to the robot's
//!
//! The scene is in the human's world; the robot is smaller and stands elsewhere. When the placing
//! starts, with the human hand at `H` and the scaled hand (its robot target) at `S` (robot world),
//! the similarity that takes `H` to `S` with the scaler's leg ratio `k` and the turn from the
//! human's base-foot heading to the robot's base sole maps the rest: the contact point is
//! `S.xy + k·R·(H_enter − H).xy` (kept `edge_margin` inside the mapped surface), at height
//! `S.z − k·(H.z − H_enter.z)`; the mapped surface lies `k·(H_enter.z − h_surface)` under it (the
//! human hand point's height above the surface at contact, scaled).
//!
//! Units: metres, seconds. The imitator allocates what the hand supports need in its constructor;
//! stepping with them allocates nothing.

use nalgebra::{Rotation2, Vector2, Vector3};
use thiserror::Error;

use crate::human::{HumanFrame, HumanJoint, Side};
use crate::imitation::error::ImitationError;
#[cfg(doc)]
use crate::imitation::output::RobotFrame;
use crate::imitation::reference::contact_events::{
    ContactChange, ContactConfig, ContactError, ContactEvent, ContactLink, contact_events,
};
use crate::scene::{Scene, Surface};
use crate::tasks::convex_hull;

/// One planned hand contact: the human's hand rests on `surface` from `enter` to `leave`.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedContact {
    /// The surface (human world frame).
    pub surface: Surface,
    /// Human clock time the contact starts (s).
    pub enter: f64,
    /// Human clock time it ends (s); infinite if it lasts to the end of the clip.
    pub leave: f64,
    /// The human's hand point ([`HumanJoint::LHand`] / [`HumanJoint::RHand`], else the wrist)
    /// at `enter` (human world frame, m).
    pub hand: Vector3<f64>,
}

/// Error building a [`HandContactPlan`].
#[derive(Debug, Error, PartialEq)]
pub enum HandSupportError {
    /// The contact pass failed.
    #[error(transparent)]
    Contacts(#[from] ContactError),
    /// An event names a surface the scene does not have.
    #[error("contact event {event}: no surface {surface} in the scene")]
    UnknownSurface {
        /// The event's index in the list.
        event: usize,
        /// Its surface index.
        surface: usize,
    },
    /// An event names a frame the clip does not have, or one without the hand.
    #[error("contact event {event}: frame {frame} has no hand or wrist position")]
    NoHand {
        /// The event's index in the list.
        event: usize,
        /// Its frame index.
        frame: usize,
    },
    /// An event of a hand earlier than the hand's previous event (or at a NaN time).
    #[error("contact event {event}: earlier than its hand's previous event")]
    OutOfOrder {
        /// The event's index in the list.
        event: usize,
    },
}

/// The hand contacts of a recording, per hand, in time order (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HandContactPlan {
    /// `[left, right]`.
    hands: [Vec<PlannedContact>; 2],
}

/// The human hand point of `side` in `frame`: the hand, else the wrist.
pub(crate) fn hand_point(frame: &HumanFrame, side: Side) -> Option<Vector3<f64>> {
    let [hand, wrist] = match side {
        Side::Left => [HumanJoint::LHand, HumanJoint::LWrist],
        Side::Right => [HumanJoint::RHand, HumanJoint::RWrist],
    };
    frame.get(hand).or_else(|| frame.get(wrist))
}

impl HandContactPlan {
    /// The hand contacts of `events` (a chronological contact list of `frames` with the surfaces
    /// of `scene`, as [`contact_events`] gives); feet and knee events are ignored.
    ///
    /// # Errors
    /// [`HandSupportError`] naming the first event that does not fit the clip or the scene.
    pub fn new(
        events: &[ContactEvent],
        frames: &[HumanFrame],
        scene: &Scene,
    ) -> Result<Self, HandSupportError> {
        let mut hands: [Vec<PlannedContact>; 2] = Default::default();
        let mut last_time = [f64::NEG_INFINITY; 2];
        for (index, event) in events.iter().enumerate() {
            let side = match event.link {
                ContactLink::LeftHand => Side::Left,
                ContactLink::RightHand => Side::Right,
                _ => continue,
            };
            let list = &mut hands[side.index()];
            let open = list.last_mut().filter(|c| c.leave.is_infinite());
            if event.time.is_nan() || event.time < last_time[side.index()] {
                return Err(HandSupportError::OutOfOrder { event: index });
            }
            last_time[side.index()] = event.time;
            let surface =
                scene
                    .surfaces()
                    .get(event.surface)
                    .ok_or(HandSupportError::UnknownSurface {
                        event: index,
                        surface: event.surface,
                    })?;
            // A hand on two surfaces at once (an edge between them) stays on the first.
            match (event.change, open) {
                (ContactChange::Leave, Some(contact)) if contact.surface == *surface => {
                    contact.leave = event.time;
                }
                (ContactChange::Enter, None) => {
                    let hand = frames.get(event.frame).and_then(|f| hand_point(f, side));
                    list.push(PlannedContact {
                        surface: surface.clone(),
                        enter: event.time,
                        leave: f64::INFINITY,
                        hand: hand.ok_or(HandSupportError::NoHand {
                            event: index,
                            frame: event.frame,
                        })?,
                    });
                }
                _ => {}
            }
        }
        Ok(Self { hands })
    }

    /// The hand contacts of `frames` with the surfaces of `scene`: [`contact_events`] with
    /// `config`, then [`HandContactPlan::new`].
    ///
    /// # Errors
    /// As [`contact_events`].
    pub fn of_clip(
        frames: &[HumanFrame],
        scene: &Scene,
        config: &ContactConfig,
    ) -> Result<Self, HandSupportError> {
        let events = contact_events(frames, scene, config)?;
        Self::new(&events, frames, scene)
    }

    /// The contacts of `hand`, in time order.
    pub fn contacts(&self, hand: Side) -> &[PlannedContact] {
        &self.hands[hand.index()]
    }
}

/// Settings of hand supports: the plan and Algorithm 1's timing.
#[derive(Clone, Debug, PartialEq)]
pub struct HandSupportConfig {
    /// The recording's hand contacts.
    pub plan: HandContactPlan,
    /// How long before a contact the hand starts to be placed, `t^ε` (s). Default 0.5 (the
    /// paper suggests about 1 s; half a second keeps the hand with the human longer on a
    /// 0.5–1 s reach).
    pub lead: f64,
    /// How close to its contact point the robot's hand must be for the contact to start (m).
    /// Default 0.005.
    pub tolerance: f64,
    /// Longest pause of the human's clock for one contact (s); the contact then starts where the
    /// hand is. Default 2.
    pub max_pause: f64,
    /// How far inside the mapped surface's edges the contact point is kept (m, robot scale).
    /// Default 0.01.
    pub edge_margin: f64,
    /// How high above the surface a hand comes over its contact point before it goes down to
    /// it (m, robot scale). Default 0.02.
    pub approach_height: f64,
}

impl HandSupportConfig {
    /// `plan` with the default timing.
    pub fn new(plan: HandContactPlan) -> Self {
        Self {
            plan,
            lead: 0.5,
            tolerance: 0.005,
            max_pause: 2.0,
            edge_margin: 0.01,
            approach_height: 0.02,
        }
    }

    /// Checks the settings.
    ///
    /// # Errors
    /// [`ImitationError::InvalidParameter`] naming the first field that is not finite and ≥ 0
    /// (the tolerance > 0).
    pub fn validate(&self) -> Result<(), ImitationError> {
        let fields = [
            ("hand_supports.lead", self.lead, 0.0),
            ("hand_supports.tolerance", self.tolerance, f64::MIN_POSITIVE),
            ("hand_supports.max_pause", self.max_pause, 0.0),
            ("hand_supports.edge_margin", self.edge_margin, 0.0),
            ("hand_supports.approach_height", self.approach_height, 0.0),
        ];
        for (name, value, least) in fields {
            if !(value.is_finite() && value >= least) {
                return Err(ImitationError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and not negative (the tolerance positive)",
                });
            }
        }
        Ok(())
    }
}

// The old path of `output::HandPlacement`; kept for one release.
#[doc(hidden)]
pub use crate::imitation::output::HandPlacement;

/// What the imitator knows of a hand in the current frame, to map a surface to the robot.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HandView {
    /// The human's hand point (human world frame, m).
    pub(crate) human: Vector3<f64>,
    /// The scaled hand (the robot hand's target, robot world frame, m).
    pub(crate) scaled: Vector3<f64>,
    /// The robot hand's current position (robot world frame, m).
    pub(crate) robot: Vector3<f64>,
    /// The turn from the human world to the robot world (rad about z).
    pub(crate) turn: f64,
    /// The scaler's leg ratio (robot / human).
    pub(crate) ratio: f64,
}

#[derive(Clone, Copy, Debug)]
enum HandState {
    /// Not in contact; `next` is the first planned contact still to come.
    Free { next: usize },
    /// Going to the contact point by way of `aim` (see [`approach`]); `waited`: robot time
    /// spent with the human's clock paused (s).
    Placing {
        contact: usize,
        at: HandPlacement,
        aim: Vector3<f64>,
        waited: f64,
    },
    /// In contact.
    Holding { contact: usize, at: HandPlacement },
}

/// The state of both hands' supports over a run (Algorithm 1; see the module docs).
#[derive(Debug)]
pub(crate) struct HandSupports {
    config: HandSupportConfig,
    states: [HandState; 2],
    points: Vec<[f64; 2]>,
    hull: Vec<[f64; 2]>,
}

impl HandSupports {
    /// Supports following `config` (validated by the caller); `outline_points`: the most sole
    /// outline points a support polygon has (both feet's).
    pub(crate) fn new(config: HandSupportConfig, outline_points: usize) -> Self {
        Self {
            config,
            states: [HandState::Free { next: 0 }; 2],
            points: Vec::with_capacity(outline_points + 2),
            hull: Vec::with_capacity(outline_points + 2),
        }
    }

    /// Advances both hands to the human clock `time` (s) after `dt` seconds of robot time;
    /// `views[hand]`: the hand's view this frame (`None` when the human hand is missing, which
    /// only delays a placing).
    pub(crate) fn update(&mut self, time: f64, dt: f64, views: [Option<HandView>; 2]) {
        for side in Side::BOTH {
            let contacts = self.config.plan.contacts(side);
            let state = &mut self.states[side.index()];
            let config = &self.config;
            *state = match *state {
                HandState::Free { mut next } => {
                    while contacts.get(next).is_some_and(|c| c.leave <= time) {
                        next += 1;
                    }
                    let starting = contacts
                        .get(next)
                        .filter(|c| time >= c.enter - config.lead)
                        .zip(views[side.index()]);
                    match starting {
                        Some((contact, view)) => {
                            let at = placement(contact, &view, config.edge_margin);
                            HandState::Placing {
                                contact: next,
                                at,
                                aim: approach(&at, view.robot, config),
                                waited: 0.0,
                            }
                        }
                        None => HandState::Free { next },
                    }
                }
                HandState::Placing {
                    contact,
                    mut at,
                    aim,
                    mut waited,
                } => {
                    let planned = &contacts[contact];
                    let robot = views[side.index()].map(|v| v.robot);
                    let placed = robot.is_some_and(|r| (r - at.point).norm() <= config.tolerance);
                    if time >= planned.enter && !placed {
                        waited += dt;
                    }
                    let timed_out = waited > config.max_pause;
                    if time >= planned.leave {
                        HandState::Free { next: contact + 1 }
                    } else if time >= planned.enter && (placed || timed_out) {
                        if let (true, Some(robot)) = (timed_out && !placed, robot) {
                            at.point = robot;
                        }
                        at.holding = true;
                        HandState::Holding { contact, at }
                    } else {
                        HandState::Placing {
                            contact,
                            at,
                            aim: robot.map_or(aim, |r| approach(&at, r, config)),
                            waited,
                        }
                    }
                }
                HandState::Holding { contact, at } if time < contacts[contact].leave => {
                    HandState::Holding { contact, at }
                }
                HandState::Holding { contact, .. } => HandState::Free { next: contact + 1 },
            };
        }
    }

    /// Whether the human's clock is paused: a hand's contact time has come and it is not yet
    /// placed.
    pub(crate) fn awaiting(&self, time: f64) -> bool {
        (self.states.iter().zip(Side::BOTH)).any(|(state, side)| match *state {
            HandState::Placing { contact, .. } => {
                time >= self.config.plan.contacts(side)[contact].enter
            }
            _ => false,
        })
    }

    /// Each hand's placement (robot world frame), while it is being placed or held.
    pub(crate) fn placements(&self) -> [Option<HandPlacement>; 2] {
        self.states.map(|state| match state {
            HandState::Free { .. } => None,
            HandState::Placing { at, .. } | HandState::Holding { at, .. } => Some(at),
        })
    }

    /// Where each hand goes this frame (robot world frame): its way to the contact point while
    /// it is placed, the point while it is held.
    pub(crate) fn aims(&self) -> [Option<Vector3<f64>>; 2] {
        self.states.map(|state| match state {
            HandState::Free { .. } => None,
            HandState::Placing { aim, .. } => Some(aim),
            HandState::Holding { at, .. } => Some(at.point),
        })
    }

    /// The area centroid of the convex hull of `sole_points` (the outlines of the feet on the
    /// ground, robot world frame, m) and the held hands' contact points; `None` when no hand is
    /// held (the phase's own CoM goal stands).
    pub(crate) fn com_goal(
        &mut self,
        sole_points: impl Iterator<Item = [f64; 2]>,
    ) -> Option<Vector2<f64>> {
        let held = self.placements().map(|p| p.filter(|p| p.holding));
        if held.iter().all(Option::is_none) {
            return None;
        }
        self.points.clear();
        self.points.extend(sole_points);
        self.points
            .extend(held.iter().flatten().map(|p| [p.point.x, p.point.y]));
        convex_hull(&mut self.points, &mut self.hull);
        Some(area_centroid(&self.hull))
    }
}

/// The placement of a hand for `contact` seen through `view` (see the module docs).
fn placement(contact: &PlannedContact, view: &HandView, edge_margin: f64) -> HandPlacement {
    let (k, h) = (view.ratio, view.human);
    let surface = contact.surface.shape();
    let resting = k * (contact.hand.z - surface.height());
    let height = view.scaled.z - k * (h.z - contact.hand.z);
    let mapped = surface.mapped(h.xy(), view.scaled.xy(), k, view.turn, height - resting);
    let touch = view.scaled.xy() + Rotation2::new(view.turn) * (contact.hand - h).xy() * k;
    let xy = mapped.nearest_inside(touch, edge_margin);
    HandPlacement {
        point: Vector3::new(xy.x, xy.y, height),
        surface: mapped,
        holding: false,
    }
}

/// Where a hand at `hand` goes next on its way to `at.point` from above: up where it is while
/// it is below the approach height and not over the surface, then over the point at that
/// height, then down to it.
fn approach(at: &HandPlacement, hand: Vector3<f64>, config: &HandSupportConfig) -> Vector3<f64> {
    let clear = at.surface.height() + config.approach_height;
    let over_point = (hand.xy() - at.point.xy()).norm() <= config.tolerance;
    if over_point {
        at.point
    } else if hand.z < clear - config.tolerance && at.surface.outside_distance(&hand) > 0.0 {
        Vector3::new(hand.x, hand.y, clear)
    } else {
        Vector3::new(at.point.x, at.point.y, clear.max(at.point.z))
    }
}

/// The area centroid of the convex polygon `hull` (counter-clockwise); the mean of its vertices
/// when it has no area.
fn area_centroid(hull: &[[f64; 2]]) -> Vector2<f64> {
    let n = hull.len();
    let (mut area, mut centroid) = (0.0, Vector2::zeros());
    for i in 0..n {
        let (a, b) = (Vector2::from(hull[i]), Vector2::from(hull[(i + 1) % n]));
        let cross = a.x * b.y - a.y * b.x;
        area += cross;
        centroid += (a + b) * cross;
    }
    if area.abs() > 1e-12 {
        centroid / (3.0 * area)
    } else {
        hull.iter().map(|&p| Vector2::from(p)).sum::<Vector2<f64>>() / n.max(1) as f64
    }
}
