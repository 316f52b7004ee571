//! Live imitation: human frames streamed in as text lines, one frame a line, imitated as they
//! arrive (the edge layer, beside [`crate::batch`]: it reads the `io` formats and feeds the
//! imitation's clip loop, [`crate::batch::imitate_clip`]).
//!
//! # Protocol
//!
//! UTF-8 lines ending in `\n` or `\r\n` ([`transport::Input`]: standard input, TCP as server or
//! client, UDP datagrams of one or more lines), in a format the clip readers read:
//!
//! * **BVH**: the file's header (`HIERARCHY` … `Frame Time:`) first on the stream, or given by
//!   the caller (a skeleton file), then one motion line a frame: the channel values in the
//!   header's order (CMU conventions, see [`crate::io::clip`]). A frame's time is its index
//!   among the stream's frames × the header's `Frame Time` (a malformed line takes no index).
//!   A CMU MotionBuilder skeleton's first motion line, the synthetic T-pose, is skipped as the
//!   clip reader skips it. A source that connects again may send the header again.
//! * **Kinect v2 CSV** lines ([`crate::io::kinect`]): a frame's time is its sensor time stamp,
//!   from the stream's first.
//!
//! The first line that is not blank tells the format: `HIERARCHY` begins a BVH header, anything
//! else is a Kinect line. The support detection's thresholds are the format's capture system's
//! ([`SupportConfig::for_capture`](crate::imitation::reference::support::SupportConfig::for_capture)),
//! as for a clip file: they need no calibration, and the scaler measures the human's segments
//! from the first frames as it does for a file. A stream of a clip's lines, none lost, is
//! therefore imitated exactly as the file is.
//!
//! # Faults
//!
//! | fault | what the session does | counted in [`LiveCounts`] |
//! |---|---|---|
//! | a line that is no frame of the format (a wrong value count, a value that is not a finite number, a Kinect time going back, a line over 64 KiB) | skipped | `malformed` |
//! | a frame out of range: a joint farther than [`LiveConfig::max_reach`] from the pelvis, or the pelvis faster than [`LiveConfig::max_speed`] | skipped | `out_of_range` |
//! | a gap: no frame for [`LiveConfig::hold_after`] | the last frame held, one every [`HOLD_STEP`](crate::batch::HOLD_STEP) in real time: the robot holds its last pose | `gaps`, `held_frames` |
//! | a gap longer than [`LiveConfig::stand_after`] | the human's last pose on both feet held: the robot goes back to standing on both feet | `stands` |
//! | the source leaves | held as a gap while it is away; a TCP server accepts the next source, a client reconnects every 0.5 s; a new stream's time goes on from the last frame's | `disconnects`, `connections`, `time_shifts` |
//! | the imitation falls behind: a line waited longer than [`LiveConfig::max_lag`] to be read | dropped | `stale` |
//!
//! Frames arriving in a burst are imitated in order (an imitation step takes tens of
//! microseconds); a stream faster than real time is imitated at its own time stamps. A stream's
//! time that leaps more than [`LiveConfig::max_time_step`] ahead is shifted to one hold step
//! after the last frame (`time_shifts`), so that the imitator never takes a long step at once.

mod decoder;
mod source;
pub mod transport;

pub use decoder::{Decoded, LineDecoder, bvh_header};
pub use source::LiveSource;

use serde_json::{Value, json};
use thiserror::Error;

use crate::io::clip::ClipError;

/// Errors of a live session before its first frame.
#[derive(Debug, Error)]
pub enum LiveError {
    /// The stream ended before its first line.
    #[error("{0}: the stream ended before its first frame")]
    NoFrames(String),
    /// A malformed BVH header, or an input that failed.
    #[error(transparent)]
    Stream(#[from] ClipError),
    /// A setting out of range (named).
    #[error("live setting {0}: must be finite and > 0")]
    Config(&'static str),
}

/// How a live session bridges a stream's faults (times in s, distances in m, speeds in m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveConfig {
    /// No frame for this long is a gap: the last frame is held. Default 0.1 s (three frames
    /// of a 30 Hz Kinect, twelve of 120 Hz capture).
    pub hold_after: f64,
    /// A gap this long brings the robot back onto both feet (the human's last pose on both
    /// feet). Default 2 s.
    pub stand_after: f64,
    /// A line that waited longer than this to be read is dropped as stale. Default 0.25 s.
    pub max_lag: f64,
    /// A stream's time leaping further than this ahead of the last frame is shifted back.
    /// Default 0.5 s (the bundled Kinect clips' longest dropped stretch is below it).
    pub max_time_step: f64,
    /// A joint farther than this from the pelvis makes a frame out of range. Default 3 m.
    pub max_reach: f64,
    /// A pelvis faster than this makes a frame out of range. Default 10 m/s (a sprinter's).
    pub max_speed: f64,
    /// The session ends after this long without a frame (`None`, default: it ends only when
    /// the input does).
    pub end_after: Option<f64>,
}

impl Default for LiveConfig {
    fn default() -> Self {
        Self {
            hold_after: 0.1,
            stand_after: 2.0,
            max_lag: 0.25,
            max_time_step: 0.5,
            max_reach: 3.0,
            max_speed: 10.0,
            end_after: None,
        }
    }
}

impl LiveConfig {
    /// Checks that every setting is finite and > 0.
    ///
    /// # Errors
    /// [`LiveError::Config`] naming the first that is not.
    pub fn validate(&self) -> Result<(), LiveError> {
        let end_after = self.end_after.unwrap_or(1.0);
        [
            (self.hold_after, "hold_after"),
            (self.stand_after, "stand_after"),
            (self.max_lag, "max_lag"),
            (self.max_time_step, "max_time_step"),
            (self.max_reach, "max_reach"),
            (self.max_speed, "max_speed"),
            (end_after, "end_after"),
        ]
        .into_iter()
        .find(|(value, _)| !(value.is_finite() && *value > 0.0))
        .map_or(Ok(()), |(_, name)| Err(LiveError::Config(name)))
    }
}

/// What a live session met (see the fault table in the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LiveCounts {
    /// Frames imitated as they came.
    pub frames: u64,
    /// Lines skipped as no frame of the format.
    pub malformed: u64,
    /// Frames skipped as out of range.
    pub out_of_range: u64,
    /// Lines dropped as stale.
    pub stale: u64,
    /// Gaps, and the held frames that bridged them.
    pub gaps: u64,
    /// Held frames given in gaps.
    pub held_frames: u64,
    /// Gaps long enough to bring the robot back onto both feet.
    pub stands: u64,
    /// Sources that connected, and that left.
    pub connections: u64,
    /// Sources that left.
    pub disconnects: u64,
    /// Times the stream's time was shifted (a new stream, a leap ahead).
    pub time_shifts: u64,
}

impl LiveCounts {
    /// Each count with its name (as in `metrics.json`'s `live`), in the order of the fields.
    pub fn named(&self) -> [(&'static str, u64); 10] {
        [
            ("frames", self.frames),
            ("malformed", self.malformed),
            ("out_of_range", self.out_of_range),
            ("stale", self.stale),
            ("gaps", self.gaps),
            ("held_frames", self.held_frames),
            ("stands", self.stands),
            ("connections", self.connections),
            ("disconnects", self.disconnects),
            ("time_shifts", self.time_shifts),
        ]
    }

    /// The counts as JSON (`metrics.json`'s `live`).
    pub fn to_json(&self) -> Value {
        let counts = self
            .named()
            .map(|(name, count)| (name.to_owned(), json!(count)));
        Value::Object(counts.into_iter().collect())
    }
}
