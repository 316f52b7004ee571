//! The live session's frame source: a stream's lines decoded into human frames in time order,
//! its faults counted and bridged (see the [module docs](super)).

use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use super::decoder::{Decoded, LineDecoder};
use super::transport::{Arrival, Received};
use super::{LiveConfig, LiveCounts, LiveError};
use crate::batch::HOLD_STEP;
use crate::human::{HumanFrame, HumanJoint};
use crate::imitation::reference::support::{HumanSupport, SupportConfig, SupportDetector};
use crate::io::FrameSource;
use crate::io::clip::ClipError;

/// Human frames from a stream of lines, for the imitation's clip loop
/// ([`crate::batch::imitate_clip`]): the frames as they arrive, the last one held through a
/// gap, the human's last pose on both feet after a long one.
#[derive(Debug)]
pub struct LiveSource {
    arrivals: Receiver<Arrival>,
    decoder: LineDecoder,
    config: LiveConfig,
    counts: LiveCounts,
    /// The first line, when it was a frame (read to tell the format).
    pending: Option<Arrival>,
    /// The last frame given out, and the human's last pose on both feet.
    last: Option<HumanFrame>,
    standing: Option<HumanFrame>,
    support: SupportDetector,
    /// When the last frame arrived; when the current gap's held frames began.
    last_arrival: Instant,
    gap_since: Option<Instant>,
    /// Added to the stream's times so that they go on after a gap or a new stream.
    offset: f64,
    /// The gap's held frames are the standing pose.
    holding_stand: bool,
    /// When a frame of the stream arrived and its time: the stream's real-time schedule.
    schedule: Option<(Instant, f64)>,
    ended: bool,
}

impl LiveSource {
    /// A source of `arrivals` (see [`super::transport::Input::open`]). The format is BVH lines
    /// of the skeleton in `header` when given; else the stream tells it: a BVH header first
    /// (`HIERARCHY` … `Frame Time:`), or Kinect v2 CSV lines. Waits for the first line.
    ///
    /// # Errors
    /// [`LiveError::NoFrames`] when the stream ends before its first line,
    /// [`LiveError::Stream`] for a malformed header or a failed input, [`LiveError::Config`]
    /// for settings out of range.
    pub fn start(
        arrivals: Receiver<Arrival>,
        header: Option<&str>,
        origin: &str,
        config: LiveConfig,
    ) -> Result<Self, LiveError> {
        config.validate()?;
        let mut counts = LiveCounts::default();
        let (decoder, pending) = match header {
            Some(header) => (LineDecoder::bvh(header, origin)?, None),
            None => tell_format(&arrivals, origin, &mut counts)?,
        };
        let support = SupportDetector::new(SupportConfig::for_capture(decoder.capture()))
            .map_err(|_| LiveError::Config("the capture's support thresholds"))?;
        Ok(Self {
            arrivals,
            decoder,
            config,
            counts,
            pending,
            last: None,
            standing: None,
            support,
            last_arrival: Instant::now(),
            gap_since: None,
            offset: 0.0,
            holding_stand: false,
            schedule: None,
            ended: false,
        })
    }

    /// The format's kind of capture system, for the imitator's support thresholds.
    pub fn capture(&self) -> crate::human::CaptureSystem {
        self.decoder.capture()
    }

    /// What the session has counted so far.
    pub fn counts(&self) -> &LiveCounts {
        &self.counts
    }

    /// The next arrival: the pending first line, or one from the channel within `wait`.
    fn next_arrival(&mut self, wait: Duration) -> Result<Arrival, RecvTimeoutError> {
        match self.pending.take() {
            Some(arrival) => Ok(arrival),
            None => self.arrivals.recv_timeout(wait),
        }
    }

    /// Handles one arrival: `Some(true)` with a frame in `out`, `Some(false)` at the end,
    /// `None` to read on.
    fn take(&mut self, arrival: Arrival, out: &mut HumanFrame) -> Result<Option<bool>, ClipError> {
        match arrival.received {
            Received::Line(text) => Ok(self.frame_of(&text, arrival.at, out).then_some(true)),
            Received::Connected(_) => {
                self.counts.connections += 1;
                self.decoder.restart();
                self.schedule = None;
                Ok(None)
            }
            Received::Disconnected => {
                self.counts.disconnects += 1;
                Ok(None)
            }
            Received::End => {
                self.ended = true;
                Ok(Some(false))
            }
            Received::Failed(source) => Err(ClipError::Stream {
                origin: "live input".to_owned(),
                source,
            }),
        }
    }

    /// Decodes `text` into `out` when it is a frame within range; counts it otherwise.
    fn frame_of(&mut self, text: &str, at: Instant, out: &mut HumanFrame) -> bool {
        let mut frame = HumanFrame::new(0.0);
        match self.decoder.decode(text, &mut frame) {
            Ok(Decoded::Frame) => {}
            Ok(Decoded::Skipped) => return false,
            Err(_) => {
                self.counts.malformed += 1;
                return false;
            }
        }
        let shifted = self.place_in_time(&mut frame);
        if self.is_late(frame.time, at) {
            self.counts.stale += 1;
            return false;
        }
        if !self.in_range(&frame, shifted) {
            self.counts.out_of_range += 1;
            return false;
        }
        self.last_arrival = at;
        self.gap_since = None;
        self.holding_stand = false;
        self.counts.frames += 1;
        self.give(frame, out);
        true
    }

    /// Whether the imitation has fallen more than [`LiveConfig::max_lag`] behind real time at
    /// a frame of (stream) time `time` that arrived at `at`: behind the stream's schedule,
    /// the latest any of its frames arrived for its time (since the last gap or new source),
    /// so that a sender a little slower than real time sets the pace. A stream sent faster
    /// than real time, or in a burst, runs ahead of that schedule and is imitated in order;
    /// a frame that waited to be read is late by its wait.
    fn is_late(&mut self, time: f64, at: Instant) -> bool {
        let (anchor, anchor_time) = *self.schedule.get_or_insert((at, time));
        let due = |anchor: Instant, anchor_time: f64| {
            anchor + Duration::from_secs_f64((time - anchor_time).max(0.0))
        };
        let (anchor, anchor_time) = match at > due(anchor, anchor_time) {
            true => *self.schedule.insert((at, time)),
            false => (anchor, anchor_time),
        };
        let lag = Instant::now().saturating_duration_since(due(anchor, anchor_time));
        lag.as_secs_f64() > self.config.max_lag
    }

    /// Whether every joint of `frame` is within [`LiveConfig::max_reach`] of its pelvis and
    /// the pelvis moved no faster than [`LiveConfig::max_speed`] since the last frame (unless
    /// its time was `shifted`: a new stream may begin anywhere).
    fn in_range(&self, frame: &HumanFrame, shifted: bool) -> bool {
        let Some(pelvis) = frame.get(HumanJoint::Pelvis) else {
            return true;
        };
        let near = frame
            .joints()
            .filter_map(|(_, p)| p)
            .all(|p| (p - pelvis).norm() <= self.config.max_reach);
        let last = (self.last.filter(|_| !shifted))
            .and_then(|l| l.get(HumanJoint::Pelvis).map(|p| (l.time, p)));
        let slow = last.is_none_or(|(time, before)| {
            let dt = (frame.time - time).max(HOLD_STEP);
            (pelvis - before).norm() <= self.config.max_speed * dt
        });
        near && slow
    }

    /// Moves `frame`'s time after the last frame's: a stream's own time goes on unchanged,
    /// but one that restarts or stands still across a gap, or leaps more than
    /// [`LiveConfig::max_time_step`] ahead, is shifted to one hold step after it (`true`).
    fn place_in_time(&mut self, frame: &mut HumanFrame) -> bool {
        let time = frame.time + self.offset;
        let shift = (self.last)
            .is_some_and(|last| time <= last.time || time > last.time + self.config.max_time_step);
        if let (true, Some(last)) = (shift, self.last) {
            self.offset = last.time + HOLD_STEP - frame.time;
            self.counts.time_shifts += 1;
        }
        frame.time += self.offset;
        shift
    }

    /// Gives `frame` out, remembering it (and whether the human stands on both feet in it).
    fn give(&mut self, frame: HumanFrame, out: &mut HumanFrame) {
        if self.support.update(&frame) == HumanSupport::Double {
            self.standing = Some(frame);
        }
        self.last = Some(frame);
        *out = frame;
    }

    /// A held frame for a gap at this moment, if the gap is long enough: the last frame, or
    /// after [`LiveConfig::stand_after`] the human's last pose on both feet, one hold step
    /// after the last frame given out.
    fn held(&mut self, out: &mut HumanFrame) -> bool {
        let Some(last) = self.last else { return false };
        let quiet = self.last_arrival.elapsed().as_secs_f64();
        if quiet < self.config.hold_after {
            return false;
        }
        let since = *self.gap_since.get_or_insert_with(|| {
            self.counts.gaps += 1;
            Instant::now()
        });
        // The stream may come back on a clock of its own.
        self.schedule = None;
        let standing = since.elapsed().as_secs_f64() >= self.config.stand_after;
        let mut frame = match (standing, self.standing) {
            (true, Some(stand)) => stand,
            _ => last,
        };
        if standing && !self.holding_stand {
            self.counts.stands += 1;
        }
        self.holding_stand = standing;
        frame.time = last.time + HOLD_STEP;
        self.counts.held_frames += 1;
        // The held pose is not a new observation of the human: the detector is not fed.
        self.last = Some(frame);
        *out = frame;
        true
    }
}

impl FrameSource for LiveSource {
    /// The next frame: the next line that is a frame in range, or a held frame every
    /// [`HOLD_STEP`] of a gap; `Ok(false)` when the session ends (the input's end, or
    /// [`LiveConfig::end_after`] without a line).
    fn read_frame(&mut self, out: &mut HumanFrame) -> Result<bool, ClipError> {
        while !self.ended {
            match self.next_arrival(Duration::from_secs_f64(HOLD_STEP)) {
                Ok(arrival) => {
                    if let Some(more) = self.take(arrival, out)? {
                        return Ok(more);
                    }
                }
                Err(RecvTimeoutError::Timeout) => {
                    let quiet = self.last_arrival.elapsed().as_secs_f64();
                    if self.config.end_after.is_some_and(|end| quiet >= end) {
                        self.ended = true;
                    } else if self.held(out) {
                        return Ok(true);
                    }
                }
                Err(RecvTimeoutError::Disconnected) => self.ended = true,
            }
        }
        Ok(false)
    }
}

/// Reads the stream's first lines to tell its format: a BVH header (kept whole) or a first
/// Kinect line (kept to be decoded as the first frame).
fn tell_format(
    arrivals: &Receiver<Arrival>,
    origin: &str,
    counts: &mut LiveCounts,
) -> Result<(LineDecoder, Option<Arrival>), LiveError> {
    let mut header: Option<String> = None;
    for arrival in arrivals.iter() {
        let text = match arrival.received {
            Received::Line(text) => text,
            Received::Connected(_) => {
                counts.connections += 1;
                continue;
            }
            Received::Disconnected => {
                counts.disconnects += 1;
                continue;
            }
            Received::End => break,
            Received::Failed(source) => {
                return Err(LiveError::Stream(ClipError::Stream {
                    origin: origin.to_owned(),
                    source,
                }));
            }
        };
        let word = text.split_whitespace().next().unwrap_or("");
        if let Some(header) = header.as_mut() {
            header.push_str(&text);
            header.push('\n');
            if word.eq_ignore_ascii_case("Frame") {
                return Ok((LineDecoder::bvh(header, origin)?, None));
            }
        } else if word.eq_ignore_ascii_case("HIERARCHY") {
            header = Some(format!("{text}\n"));
        } else if !word.is_empty() {
            let first = Arrival {
                received: Received::Line(text),
                at: arrival.at,
            };
            return Ok((LineDecoder::kinect(origin), Some(first)));
        }
    }
    Err(LiveError::NoFrames(origin.to_owned()))
}
