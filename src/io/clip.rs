//! A motion clip of either supported format, chosen by file extension: `.csv` is a Kinect v2
//! recording, anything else BVH (CMU conventions: ×0.056444 to metres, Y up, CMU-MB or CMU-MAX
//! names). Streams frames and says which kind of capture system the source is.
//!
//! The CMU MotionBuilder-friendly release (CMU-MB names) prepends a synthetic T-pose as frame 0
//! (`tests/data/mocap/README.md` in the repository); [`Clip`] skips it, so the first frame is captured motion.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use thiserror::Error;

use super::FrameSource;
use super::bvh::{BvhConfig, BvhError, BvhReader, BvhSkeleton, CMU_MB_NAMES};
use super::kinect::{KinectConfig, KinectError, KinectReader};
use super::skeleton_map::SkeletonMap;
use crate::human::{CaptureSystem, HumanFrame};

/// Error of either reader.
#[derive(Debug, Error)]
pub enum ClipError {
    /// From the BVH reader.
    #[error(transparent)]
    Bvh(#[from] BvhError),
    /// From the Kinect reader.
    #[error(transparent)]
    Kinect(#[from] KinectError),
    /// A stream of frames could not be read (a socket or standard input failed).
    #[error("{origin}: {source}")]
    Stream {
        /// The stream (`tcp://ADDR`, `udp://ADDR`, `stdin`).
        origin: String,
        /// The failure.
        #[source]
        source: std::io::Error,
    },
}

#[derive(Debug)]
enum Source {
    // Boxed: the BVH reader is several times larger than the Kinect one.
    Bvh(Box<BvhReader<BufReader<File>>>),
    Kinect(KinectReader<BufReader<File>>),
    /// A clip read whole ([`Clip::read_whole`]), replayed from `next` on.
    Frames {
        frames: Vec<HumanFrame>,
        next: usize,
    },
}

/// A clip being read, one frame at a time.
#[derive(Debug)]
pub struct Clip {
    source: Source,
    capture: CaptureSystem,
}

impl Clip {
    /// Opens `path` (the reader is chosen by extension; see the module docs).
    pub fn open(path: impl AsRef<Path>) -> Result<Self, ClipError> {
        let path = path.as_ref();
        let is_csv = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
        if is_csv {
            return Ok(Self {
                source: Source::Kinect(KinectReader::open(path, KinectConfig::default())?),
                capture: CaptureSystem::DepthCamera,
            });
        }
        let mut reader = BvhReader::open(path, BvhConfig::cmu())?;
        if leads_with_t_pose(reader.skeleton()) {
            let mut t_pose = HumanFrame::new(0.0);
            reader.read_frame(&mut t_pose)?;
        }
        Ok(Self {
            source: Source::Bvh(Box::new(reader)),
            capture: CaptureSystem::Optical,
        })
    }

    /// Opens the BVH file `path` (any extension) whose skeleton `map` describes: its unit, up
    /// axis and joint names (see [`super::skeleton_map`]); the map's leading frames are skipped.
    pub fn open_mapped(path: impl AsRef<Path>, map: &SkeletonMap) -> Result<Self, ClipError> {
        let mut reader = BvhReader::open(path, map.config.clone())?;
        let mut skipped = HumanFrame::new(0.0);
        for _ in 0..map.skip_frames {
            if !reader.read_frame(&mut skipped)? {
                break;
            }
        }
        Ok(Self {
            source: Source::Bvh(Box::new(reader)),
            capture: CaptureSystem::Optical,
        })
    }

    /// The system the clip was captured with (optical mocap for BVH, a depth camera for Kinect
    /// CSV), for thresholds that depend on it (`SupportConfig::for_capture`).
    pub fn capture(&self) -> CaptureSystem {
        self.capture
    }

    /// How many frames are left to read according to the file's header (a BVH `Frames` count
    /// less the frames already read or skipped), for progress reports only: the file may hold
    /// fewer. `None` for a Kinect CSV, which has no header count.
    pub fn declared_frames(&self) -> Option<u64> {
        match &self.source {
            Source::Bvh(r) => Some(r.declared_frames().saturating_sub(r.frames_read())),
            Source::Kinect(_) => None,
            Source::Frames { frames, next } => Some((frames.len() - next) as u64),
        }
    }

    /// The clip with the frames not read yet read into memory, replayed by [`Clip::read_frame`]
    /// and seen whole by [`Clip::frames_ahead`]: for a run that needs the whole clip before its
    /// first frame (the look-ahead of the feet, a scene's hand contacts).
    ///
    /// # Errors
    /// The reader's error, naming the line.
    pub fn read_whole(self) -> Result<Clip, ClipError> {
        if matches!(self.source, Source::Frames { .. }) {
            return Ok(self);
        }
        let capture = self.capture;
        let frames = self.collect::<Result<Vec<HumanFrame>, _>>()?;
        Ok(Clip {
            source: Source::Frames { frames, next: 0 },
            capture,
        })
    }

    /// The frames still to read of a clip read whole ([`Clip::read_whole`]); `None` for a clip
    /// read from its file as it goes.
    pub fn frames_ahead(&self) -> Option<&[HumanFrame]> {
        match &self.source {
            Source::Frames { frames, next } => Some(&frames[*next..]),
            _ => None,
        }
    }

    /// Reads the next frame into `out`; `Ok(false)` at the end of the clip.
    pub fn read_frame(&mut self, out: &mut HumanFrame) -> Result<bool, ClipError> {
        Ok(match &mut self.source {
            Source::Bvh(r) => r.read_frame(out)?,
            Source::Kinect(r) => r.read_frame(out)?,
            Source::Frames { frames, next } => match frames.get(*next) {
                Some(frame) => {
                    *out = *frame;
                    *next += 1;
                    true
                }
                None => false,
            },
        })
    }
}

/// Whether a BVH clip of `skeleton` begins with a synthetic T-pose frame: the CMU
/// MotionBuilder-friendly release's skeletons (CMU-MB names) do (see the module docs).
pub(crate) fn leads_with_t_pose(skeleton: &BvhSkeleton) -> bool {
    CMU_MB_NAMES
        .iter()
        .all(|(name, _)| skeleton.index_of(name).is_some())
}

impl FrameSource for Clip {
    fn read_frame(&mut self, out: &mut HumanFrame) -> Result<bool, ClipError> {
        Clip::read_frame(self, out)
    }
}

impl Iterator for Clip {
    type Item = Result<HumanFrame, ClipError>;

    fn next(&mut self) -> Option<Self::Item> {
        super::next_frame(|frame| self.read_frame(frame))
    }
}
