//! The contact changes of a recorded clip: which body part starts or stops resting on which
//! surface of a [`Scene`], and when (Di Fava et al. §III.C, eq. 14–15).
//!
//! An event is the 4-tuple η = (link, surface, t, σ) of eq. 14, σ saying whether the contact
//! starts or ends; [`contact_events`] returns the chronological list L = (η₁ … η_μ) of eq. 15
//! from one offline pass over the clip. The paper finds the events by colliding the actor's
//! body model with the environment in a game engine; here each link is a few skeleton joints
//! and the test is geometric, with hysteresis:
//!
//! * a link **enters** contact with a surface when its lowest joint centre is between
//!   `−max_penetration` and `enter_height` above the surface's plane, at most `edge_margin`
//!   outside its rectangle (horizontally), and moving slower than `max_speed`;
//! * it **leaves** when that joint is more than `leave_height` above the plane (or more than
//!   `max_penetration` below it), or more than `edge_margin` outside the rectangle.
//!
//! The feet on the floor (the scene's unbounded surface) are the exception: a foot rests on the
//! floor while the [`SupportDetector`] says it supports the body, as the imitator does. Recorded
//! floors are rarely level (the CMU walks rise 7–10 cm) and a walking foot clears the floor by
//! only a few centimetres, so a height test against a fixed plane misses steps; the detector
//! learns the ground from the clip and uses the foot's speed as well.
//!
//! `leave_height > enter_height` is the hysteresis: a hand resting on a table whose joint
//! centre jitters by a few centimetres stays in contact. Heights are of joint *centres*, which
//! sit above the skin that touches (a wrist 2–4 cm above a palm flat on a table, an ankle
//! 7–9 cm above the floor), so the thresholds differ per kind of link ([`ContactConfig`]).
//! Contacts shorter than `min_duration` are dropped with both their events (a hand brushing past
//! an edge). A link in contact in the first frame gets an entering event at that frame's time.
//!
//! Times are the clip's (s); a link whose joints the frame lacks keeps its state.

use nalgebra::Vector3;
use thiserror::Error;

use crate::human::{CaptureSystem, HumanFrame, HumanJoint, Side};
use crate::imitation::reference::support::{SupportConfig, SupportDetector, SupportError};
use crate::scene::Scene;

/// A body part that can rest on a surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ContactLink {
    /// The left hand (wrist and knuckles).
    LeftHand,
    /// The right hand (wrist and knuckles).
    RightHand,
    /// The left foot (ankle and toe joints).
    LeftFoot,
    /// The right foot (ankle and toe joints).
    RightFoot,
    /// The left knee.
    LeftKnee,
    /// The right knee.
    RightKnee,
}

impl ContactLink {
    /// Every link, in the order events of one frame are listed.
    pub const ALL: [ContactLink; 6] = [
        ContactLink::LeftHand,
        ContactLink::RightHand,
        ContactLink::LeftFoot,
        ContactLink::RightFoot,
        ContactLink::LeftKnee,
        ContactLink::RightKnee,
    ];

    /// The skeleton joints standing for the link; the lowest one is tested.
    pub fn joints(self) -> &'static [HumanJoint] {
        match self {
            ContactLink::LeftHand => &[HumanJoint::LWrist, HumanJoint::LHand],
            ContactLink::RightHand => &[HumanJoint::RWrist, HumanJoint::RHand],
            ContactLink::LeftFoot => &[HumanJoint::LAnkle, HumanJoint::LToe],
            ContactLink::RightFoot => &[HumanJoint::RAnkle, HumanJoint::RToe],
            ContactLink::LeftKnee => &[HumanJoint::LKnee],
            ContactLink::RightKnee => &[HumanJoint::RKnee],
        }
    }

    /// The side of a foot, `None` for the other links.
    pub fn foot_side(self) -> Option<Side> {
        match self {
            ContactLink::LeftFoot => Some(Side::Left),
            ContactLink::RightFoot => Some(Side::Right),
            _ => None,
        }
    }

    /// The link's name (`"left_hand"`, …).
    pub fn name(self) -> &'static str {
        match self {
            ContactLink::LeftHand => "left_hand",
            ContactLink::RightHand => "right_hand",
            ContactLink::LeftFoot => "left_foot",
            ContactLink::RightFoot => "right_foot",
            ContactLink::LeftKnee => "left_knee",
            ContactLink::RightKnee => "right_knee",
        }
    }
}

/// When a link's joint centre counts as resting on a surface (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactThresholds {
    /// The contact starts at or below this height of the lowest joint centre above the plane (m).
    pub enter_height: f64,
    /// The contact ends above this height (m); at least `enter_height`.
    pub leave_height: f64,
    /// The contact starts only below this speed of the link's joints (mean of them, m/s).
    pub max_speed: f64,
}

impl ContactThresholds {
    /// Hands: wrist and knuckle centres sit 1.5–4 cm above a palm resting flat.
    pub const HANDS: Self = Self {
        enter_height: 0.06,
        leave_height: 0.09,
        max_speed: 0.5,
    };
    /// Feet: the toe joint centre sits 3–7 cm above the floor, the ankle 7–9 cm.
    pub const FEET: Self = Self {
        enter_height: 0.10,
        leave_height: 0.13,
        max_speed: 0.5,
    };
    /// Knees: the knee joint centre sits 5–8 cm above the floor when kneeling.
    pub const KNEES: Self = Self {
        enter_height: 0.09,
        leave_height: 0.12,
        max_speed: 0.5,
    };
}

/// Thresholds of the contact pass, per kind of link. Lengths in metres, times in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactConfig {
    /// Hands (default [`ContactThresholds::HANDS`]).
    pub hands: ContactThresholds,
    /// Feet on bounded surfaces (a step, a stool; default [`ContactThresholds::FEET`]). On the
    /// floor (the scene's unbounded surface) the feet are the support detector's instead.
    pub feet: ContactThresholds,
    /// The support detector that says when a foot rests on the floor ([`SupportDetector`]: it
    /// learns the ground from the clip, which is rarely level, and tells a planted foot from a
    /// swinging one by its speed).
    pub support: SupportConfig,
    /// Knees ([`ContactThresholds::KNEES`] to include them), or `None` to leave them out (the
    /// default).
    pub knees: Option<ContactThresholds>,
    /// How far outside a surface's rectangle (horizontally) a joint centre may be and still
    /// touch it: the hand or foot reaches beyond its joint (m).
    pub edge_margin: f64,
    /// How far below a surface's plane a joint centre may be and still be on it (m): deeper,
    /// the joint is under the surface (a foot under a table), not on it.
    pub max_penetration: f64,
    /// Contacts shorter than this are dropped (s).
    pub min_duration: f64,
}

impl Default for ContactConfig {
    /// The thresholds for optical motion capture.
    fn default() -> Self {
        Self::for_capture(CaptureSystem::Optical)
    }
}

impl ContactConfig {
    /// The default thresholds, with the support detector's for `capture`
    /// ([`SupportConfig::for_capture`]).
    pub fn for_capture(capture: CaptureSystem) -> Self {
        Self {
            hands: ContactThresholds::HANDS,
            feet: ContactThresholds::FEET,
            support: SupportConfig::for_capture(capture),
            knees: None,
            edge_margin: 0.05,
            max_penetration: 0.10,
            min_duration: 0.2,
        }
    }

    /// The thresholds of `link`, or `None` if that kind of link is left out.
    pub fn thresholds(&self, link: ContactLink) -> Option<&ContactThresholds> {
        match link {
            ContactLink::LeftHand | ContactLink::RightHand => Some(&self.hands),
            ContactLink::LeftFoot | ContactLink::RightFoot => Some(&self.feet),
            ContactLink::LeftKnee | ContactLink::RightKnee => self.knees.as_ref(),
        }
    }

    fn validate(&self) -> Result<(), ContactError> {
        let links = [Some(&self.hands), Some(&self.feet), self.knees.as_ref()];
        for t in links.into_iter().flatten() {
            let finite = t.enter_height.is_finite() && t.leave_height.is_finite();
            let speed_positive = t.max_speed.is_finite() && t.max_speed > 0.0;
            if !finite || t.leave_height < t.enter_height || !speed_positive {
                return Err(ContactError::Config(
                    "heights finite with leave_height ≥ enter_height, max_speed > 0",
                ));
            }
        }
        let lengths = [self.edge_margin, self.max_penetration, self.min_duration];
        if !lengths.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err(ContactError::Config(
                "edge_margin, max_penetration and min_duration finite and ≥ 0",
            ));
        }
        Ok(())
    }
}

/// Whether a contact starts or ends (σ of eq. 14).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactChange {
    /// The link comes to rest on the surface (σ = 1).
    Enter,
    /// The link leaves the surface (σ = 0).
    Leave,
}

/// One contact change η = (link, surface, t, σ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactEvent {
    /// The body part.
    pub link: ContactLink,
    /// The surface's index in the scene.
    pub surface: usize,
    /// The clip time of the first frame in the new state (s).
    pub time: f64,
    /// That frame's index in the clip (0 = the first frame read).
    pub frame: usize,
    /// Whether the contact starts or ends.
    pub change: ContactChange,
}

/// Error of the contact pass.
#[derive(Debug, Error, PartialEq)]
pub enum ContactError {
    /// A threshold is out of range.
    #[error("contact thresholds: {0}")]
    Config(&'static str),
    /// The support detector's configuration is out of range.
    #[error(transparent)]
    Support(SupportError),
    /// Frame times do not increase.
    #[error("frame {frame}: time {time} s does not follow the previous frame's")]
    Time {
        /// The frame's index.
        frame: usize,
        /// Its time (s).
        time: f64,
    },
}

/// The chronological contact change list (eq. 15) of `frames` with the surfaces of `scene`.
///
/// # Errors
/// [`ContactError::Config`] for bad thresholds, [`ContactError::Time`] if frame times do not
/// strictly increase.
pub fn contact_events<'a>(
    frames: impl IntoIterator<Item = &'a HumanFrame>,
    scene: &Scene,
    config: &ContactConfig,
) -> Result<Vec<ContactEvent>, ContactError> {
    config.validate()?;
    let mut feet = SupportDetector::new(config.support).map_err(ContactError::Support)?;
    let links: Vec<(ContactLink, ContactThresholds)> = ContactLink::ALL
        .iter()
        .filter_map(|&l| config.thresholds(l).map(|t| (l, *t)))
        .collect();
    let surfaces = scene.surfaces().len();
    let mut list = EventList::new(links.len() * surfaces, config.min_duration);
    let mut previous: Vec<Option<(f64, Vector3<f64>)>> = vec![None; links.len()];
    let mut last_time = f64::NEG_INFINITY;
    for (index, frame) in frames.into_iter().enumerate() {
        if frame.time.is_nan() || frame.time <= last_time {
            return Err(ContactError::Time {
                frame: index,
                time: frame.time,
            });
        }
        last_time = frame.time;
        feet.update(frame);
        for (k, &(link, thresholds)) in links.iter().enumerate() {
            let Some((lowest, mean)) = link_points(frame, link) else {
                continue;
            };
            let speed = previous[k].map_or(0.0, |(t, p)| (mean - p).norm() / (frame.time - t));
            previous[k] = Some((frame.time, mean));
            for (s, surface) in scene.surfaces().iter().enumerate() {
                let slot = k * surfaces + s;
                let touching = match link.foot_side() {
                    Some(side) if surface.shape().is_unbounded() => feet.foot(side).in_support,
                    _ => {
                        let height = surface.shape().height_above(&lowest);
                        let over = surface.shape().outside_distance(&lowest) <= config.edge_margin
                            && height >= -config.max_penetration;
                        if list.is_open(slot) {
                            over && height <= thresholds.leave_height
                        } else {
                            over && height <= thresholds.enter_height
                                && speed <= thresholds.max_speed
                        }
                    }
                };
                list.update(slot, touching, link, s, frame.time, index);
            }
        }
    }
    Ok(list.events)
}

/// The events found so far, and the contacts under way (one slot per link and surface).
struct EventList {
    events: Vec<ContactEvent>,
    /// Per slot: when the contact under way started and where its entering event is.
    open: Vec<Option<(f64, usize)>>,
    min_duration: f64,
}

impl EventList {
    fn new(slots: usize, min_duration: f64) -> Self {
        Self {
            events: Vec::new(),
            open: vec![None; slots],
            min_duration,
        }
    }

    fn is_open(&self, slot: usize) -> bool {
        self.open[slot].is_some()
    }

    /// Records the start or end of `slot`'s contact when `touching` differs from its state. A
    /// contact ending before `min_duration` is dropped with its entering event.
    fn update(
        &mut self,
        slot: usize,
        touching: bool,
        link: ContactLink,
        surface: usize,
        time: f64,
        frame: usize,
    ) {
        let change = match (self.open[slot], touching) {
            (None, true) => {
                self.open[slot] = Some((time, self.events.len()));
                ContactChange::Enter
            }
            (Some((start, entered)), false) => {
                self.open[slot] = None;
                if time - start < self.min_duration {
                    self.events.remove(entered);
                    for (_, later) in self.open.iter_mut().flatten() {
                        if *later > entered {
                            *later -= 1;
                        }
                    }
                    return;
                }
                ContactChange::Leave
            }
            _ => return,
        };
        self.events.push(ContactEvent {
            link,
            surface,
            time,
            frame,
            change,
        });
    }
}

/// The lowest of `link`'s joints and the mean of them, or `None` if the frame has none.
fn link_points(frame: &HumanFrame, link: ContactLink) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let mut points = link.joints().iter().filter_map(|&j| frame.get(j));
    let first = points.next()?;
    let (lowest, sum, count) = points.fold((first, first, 1.0), |(low, sum, n), p| {
        (if p.z < low.z { p } else { low }, sum + p, n + 1.0)
    });
    Some((lowest, sum / count))
}
