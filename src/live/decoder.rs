//! One frame a line: the decoder of a stream's lines into [`HumanFrame`]s, in the formats the
//! clip readers read (see the [module docs](super)).

use std::io::{self, Cursor};

use crate::human::{CaptureSystem, HumanFrame};
use crate::io::bvh::{BvhConfig, BvhReader};
use crate::io::clip::{ClipError, leads_with_t_pose};
use crate::io::kinect::{KinectConfig, KinectReader};

/// What a line was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decoded {
    /// A frame, now in the output.
    Frame,
    /// A line that is no frame and no fault: blank, a line of a BVH header sent again, the
    /// synthetic T-pose a CMU MotionBuilder skeleton's motion begins with.
    Skipped,
}

#[derive(Debug)]
enum Format {
    Bvh {
        /// The header text, kept to start the frame count again on a new stream.
        header: String,
        reader: Box<BvhReader<Cursor<Vec<u8>>>>,
        /// The next motion line is the synthetic T-pose.
        t_pose_next: bool,
        /// Inside a header sent again on the stream.
        in_header: bool,
    },
    Kinect(KinectReader<io::Empty>),
}

/// Decodes a stream's lines into human frames, one frame a line; a malformed line is an error
/// and leaves the decoder usable for the next.
#[derive(Debug)]
pub struct LineDecoder {
    format: Format,
    origin: String,
}

impl LineDecoder {
    /// Motion lines of the BVH skeleton in `header` (the file's text from `HIERARCHY` to its
    /// `Frame Time:` line; CMU conventions: ×0.056444 to metres, Y up). `origin` names the
    /// stream in errors.
    ///
    /// # Errors
    /// [`ClipError::Bvh`] for a malformed header.
    pub fn bvh(header: &str, origin: &str) -> Result<Self, ClipError> {
        let reader = bvh_reader(header, origin)?;
        let t_pose_next = leads_with_t_pose(reader.skeleton());
        Ok(Self {
            format: Format::Bvh {
                header: header.to_owned(),
                reader: Box::new(reader),
                t_pose_next,
                in_header: false,
            },
            origin: origin.to_owned(),
        })
    }

    /// Kinect v2 CSV lines (see [`crate::io::kinect`]).
    pub fn kinect(origin: &str) -> Self {
        Self {
            format: Format::Kinect(KinectReader::new(
                io::empty(),
                origin,
                KinectConfig::default(),
            )),
            origin: origin.to_owned(),
        }
    }

    /// The kind of capture system the format comes from (for the support detection's
    /// thresholds).
    pub fn capture(&self) -> CaptureSystem {
        match self.format {
            Format::Bvh { .. } => CaptureSystem::Optical,
            Format::Kinect(_) => CaptureSystem::DepthCamera,
        }
    }

    /// A new stream begins (a source connected again): BVH frames are counted from 0 again,
    /// Kinect times measured from the new stream's first time stamp. (A CMU MotionBuilder
    /// stream's T-pose is skipped at the session's start only: a source that comes back
    /// resumes its motion.)
    pub fn restart(&mut self) {
        match &mut self.format {
            Format::Bvh { header, reader, .. } => {
                // The header parsed before, so it parses again.
                if let Ok(fresh) = bvh_reader(header, &self.origin) {
                    **reader = fresh;
                }
            }
            Format::Kinect(reader) => {
                *reader = KinectReader::new(io::empty(), &self.origin, KinectConfig::default());
            }
        }
    }

    /// Decodes `line` into `out`. A BVH header sent again (a source that connects again sends
    /// it first) is skipped and starts the count again ([`LineDecoder::restart`]).
    ///
    /// # Errors
    /// The reader's error for a malformed line (the decoder stays usable).
    pub fn decode(&mut self, line: &str, out: &mut HumanFrame) -> Result<Decoded, ClipError> {
        if line.trim().is_empty() {
            return Ok(Decoded::Skipped);
        }
        let restart = match &mut self.format {
            Format::Kinect(reader) => {
                reader.decode_line(line, out)?;
                return Ok(Decoded::Frame);
            }
            Format::Bvh {
                reader,
                t_pose_next,
                in_header,
                ..
            } => {
                let word = line.split_whitespace().next().unwrap_or("");
                if word.eq_ignore_ascii_case("HIERARCHY") {
                    *in_header = true;
                }
                if !*in_header {
                    reader.decode_line(line, out)?;
                    let t_pose = std::mem::take(t_pose_next);
                    return Ok(if t_pose {
                        Decoded::Skipped
                    } else {
                        Decoded::Frame
                    });
                }
                *in_header = !word.eq_ignore_ascii_case("Frame");
                !*in_header
            }
        };
        if restart {
            self.restart();
        }
        Ok(Decoded::Skipped)
    }
}

/// The header of the BVH text `text` (a file's, say): its lines up to and including the one
/// that begins with `Frame` (`Frame Time:`); `None` without one.
pub fn bvh_header(text: &str) -> Option<String> {
    let mut header = String::new();
    for line in text.lines() {
        header.push_str(line);
        header.push('\n');
        if line.split_whitespace().next() == Some("Frame") {
            return Some(header);
        }
    }
    None
}

/// A BVH reader of the header text `header`, positioned at its end.
fn bvh_reader(header: &str, origin: &str) -> Result<BvhReader<Cursor<Vec<u8>>>, ClipError> {
    let text = Cursor::new(header.as_bytes().to_vec());
    Ok(BvhReader::new(text, origin, BvhConfig::cmu())?)
}
