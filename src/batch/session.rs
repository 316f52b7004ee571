//! A clip prepared for one run: opened once; read whole first when the run needs what comes
//! later in it (the feet's look-ahead of an offline run, a scene's hand contacts); and the
//! imitator settings that belong to this clip: the support thresholds of its capture system
//! ([`SupportConfig::for_capture`]), the human's foot lifts ([`FootLookAhead`]) and the hand
//! contacts with the scene ([`HandSupportConfig`]). `taskstack imitate`, `taskstack batch`,
//! [`retarget_clip`](super::retarget_clip) and the Python package prepare their clips here.

use std::path::{Path, PathBuf};

use super::BatchError;
use crate::imitation::ImitatorConfig;
use crate::imitation::poubel::hand_support::{HandContactPlan, HandSupportConfig};
use crate::imitation::reference::contact_events::ContactConfig;
use crate::imitation::reference::support::SupportConfig;
use crate::imitation::walking::look_ahead::{FootLookAhead, FootSchedule};
use crate::io::clip::Clip;
use crate::io::skeleton_map::SkeletonMap;
use crate::scene::Scene;

/// What a run takes from its clip beyond the frames; the same for every clip of a batch.
#[derive(Debug, Clone, Default)]
pub struct ClipSetup {
    /// The skeleton of a BVH file that does not follow the CMU conventions; `None`: the reader
    /// is chosen by extension ([`Clip::open`]).
    pub skeleton_map: Option<SkeletonMap>,
    /// Offline: the robot knows the human's foot lifts ahead ([`FootLookAhead`]), starting
    /// from these first guesses of its own timing; `None`: online.
    pub look_ahead: Option<LookAheadLeads>,
    /// Hands as supports on this scene's surfaces (the clip's world frame; Poubel et al.'s
    /// method only).
    pub scene: Option<Scene>,
}

/// The first guesses of an offline run's timing (s, ≥ 0): [`FootLookAhead::lift_lead`] and
/// [`FootLookAhead::landing_lead`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LookAheadLeads {
    /// How long before the human lifts a foot the robot starts shifting its weight (s).
    pub lift_lead: f64,
    /// How long before the human puts a foot down the robot starts lowering it (s).
    pub landing_lead: f64,
}

impl Default for LookAheadLeads {
    fn default() -> Self {
        Self {
            lift_lead: FootLookAhead::DEFAULT_LIFT_LEAD,
            landing_lead: FootLookAhead::DEFAULT_LANDING_LEAD,
        }
    }
}

/// A clip opened for one run, with the settings it gives the imitator.
#[derive(Debug)]
pub struct ClipSession {
    path: PathBuf,
    clip: Clip,
    look_ahead: Option<FootLookAhead>,
    hand_supports: Option<HandSupportConfig>,
}

impl ClipSession {
    /// Opens the clip at `path` as `setup` says, reading it whole when the look-ahead or the
    /// scene needs it.
    ///
    /// # Errors
    /// [`BatchError::Clip`] when the clip cannot be opened or read, [`BatchError::LookAhead`]
    /// and [`BatchError::HandSupports`] when its foot lifts or hand contacts cannot be found;
    /// each names the clip.
    pub fn open(path: &Path, setup: &ClipSetup) -> Result<Self, BatchError> {
        let clip_error = |source| BatchError::Clip {
            path: path.to_path_buf(),
            source,
        };
        let mut clip = match &setup.skeleton_map {
            None => Clip::open(path),
            Some(map) => Clip::open_mapped(path, map),
        }
        .map_err(clip_error)?;
        if setup.look_ahead.is_none() && setup.scene.is_none() {
            return Ok(Self {
                path: path.to_path_buf(),
                clip,
                look_ahead: None,
                hand_supports: None,
            });
        }
        clip = clip.read_whole().map_err(clip_error)?;
        let capture = clip.capture();
        let frames = clip.frames_ahead().unwrap_or_default();
        let hand_supports = (setup.scene.as_ref())
            .map(|scene| {
                HandContactPlan::of_clip(frames, scene, &ContactConfig::for_capture(capture))
                    .map(HandSupportConfig::new)
            })
            .transpose()
            .map_err(|source| BatchError::HandSupports {
                path: path.to_path_buf(),
                source,
            })?;
        let look_ahead = (setup.look_ahead)
            .map(|leads| {
                FootSchedule::of_clip(frames, SupportConfig::for_capture(capture)).map(|schedule| {
                    FootLookAhead {
                        schedule,
                        lift_lead: leads.lift_lead,
                        landing_lead: leads.landing_lead,
                    }
                })
            })
            .transpose()
            .map_err(|source| BatchError::LookAhead {
                path: path.to_path_buf(),
                source,
            })?;
        Ok(Self {
            path: path.to_path_buf(),
            clip,
            look_ahead,
            hand_supports,
        })
    }

    /// The clip, to read the frames from (replayed from memory when it was read whole).
    pub fn clip(&self) -> &Clip {
        &self.clip
    }

    /// `base` with this clip's settings: the support thresholds of its capture system, its
    /// foot lifts ahead (offline) and its hand contacts (a scene).
    ///
    /// # Errors
    /// [`BatchError::NeedsPoubel`] when the clip was opened offline or with a scene and
    /// `base` imitates by Koenemann et al.'s method.
    pub fn config(&self, base: &ImitatorConfig) -> Result<ImitatorConfig, BatchError> {
        let mut config = ImitatorConfig {
            support: SupportConfig::for_capture(self.clip.capture()),
            ..base.clone()
        };
        let needs_poubel = |what| BatchError::NeedsPoubel {
            path: self.path.clone(),
            what,
        };
        if let Some(look_ahead) = &self.look_ahead {
            let poubel = config.poubel_mut();
            poubel
                .ok_or_else(|| needs_poubel("the offline look-ahead"))?
                .look_ahead = Some(look_ahead.clone());
        }
        if let Some(hand_supports) = &self.hand_supports {
            let poubel = config.poubel_mut();
            poubel.ok_or_else(|| needs_poubel("a scene"))?.hand_supports =
                Some(hand_supports.clone());
        }
        Ok(config)
    }

    /// The clip, to imitate ([`imitate_clip`](super::imitate_clip)).
    pub fn into_clip(self) -> Clip {
        self.clip
    }
}
