//! Streaming reader of Microsoft Kinect v2 skeleton CSV (KinectReader tool, Kinect for Windows
//! SDK 2.0 body tracking) into [`HumanFrame`]s.
//!
//! # Format
//!
//! No header. One line per frame: the sensor timestamp in 100 ns units, then 25 × (X, Y, Z,
//! state) in the SDK's joint order ([`KINECT_JOINTS`]) = 101 comma-separated values; a trailing
//! comma (an empty 102nd field) is accepted and so is its absence. Blank lines are skipped.
//! `state` is 0 = not tracked, 1 = inferred, 2 = tracked.
//!
//! # Frame
//!
//! Kinect camera space: metres, origin at the IR sensor, +X to the sensor's left, +Y up (relative
//! to the sensor, which may be tilted), +Z away from the sensor. The subject faces the sensor, so
//! it faces −Z with its left side towards −X. The human frame ([`crate::human`]) is
//! `(x, y, z) = (−Z, −X, Y)`: the subject faces +x, +y is its left, z is up. This is a proper
//! rotation (det = +1). Heights are relative to the sensor and a sensor tilt is not corrected;
//! support detection fits the ground from the data, which absorbs both.
//!
//! # Time
//!
//! [`HumanFrame::time`] is `(timestamp − first timestamp) · 1e−7` s. Timestamps must not decrease
//! (equal ones are accepted); dropped frames show as larger gaps, so consumers must use the time,
//! not the line index.
//!
//! # Tracking state
//!
//! Not tracked (0) gives a missing joint. Inferred (1) joints are estimated by the SDK from their
//! neighbours; they are kept by default ([`KinectConfig::keep_inferred`]) because in standing
//! capture they are mostly plausible and dropping them would leave gaps the scaler has to bridge
//! anyway; set it to `false` to treat them as missing.

use std::fs::File;
use std::io::{self, BufRead, BufReader};
use std::path::Path;

use nalgebra::Vector3;

use super::read_line_capped;
use crate::human::{HumanFrame, HumanJoint};

/// Values per line: timestamp + 25 × 4.
pub const KINECT_FIELDS: usize = 1 + 4 * KINECT_JOINTS.len();

/// The 25 Kinect v2 joints in file order, with the human joint each gives (`None`: unused).
pub const KINECT_JOINTS: [(&str, Option<HumanJoint>); 25] = [
    ("SpineBase", Some(HumanJoint::Pelvis)),
    ("SpineMid", None),
    ("Neck", Some(HumanJoint::Neck)),
    ("Head", Some(HumanJoint::Head)),
    ("ShoulderLeft", Some(HumanJoint::LShoulder)),
    ("ElbowLeft", Some(HumanJoint::LElbow)),
    ("WristLeft", Some(HumanJoint::LWrist)),
    ("HandLeft", Some(HumanJoint::LHand)),
    ("ShoulderRight", Some(HumanJoint::RShoulder)),
    ("ElbowRight", Some(HumanJoint::RElbow)),
    ("WristRight", Some(HumanJoint::RWrist)),
    ("HandRight", Some(HumanJoint::RHand)),
    ("HipLeft", Some(HumanJoint::LHip)),
    ("KneeLeft", Some(HumanJoint::LKnee)),
    ("AnkleLeft", Some(HumanJoint::LAnkle)),
    ("FootLeft", Some(HumanJoint::LToe)),
    ("HipRight", Some(HumanJoint::RHip)),
    ("KneeRight", Some(HumanJoint::RKnee)),
    ("AnkleRight", Some(HumanJoint::RAnkle)),
    ("FootRight", Some(HumanJoint::RToe)),
    ("SpineShoulder", Some(HumanJoint::MidShoulder)),
    ("HandTipLeft", None),
    ("ThumbLeft", None),
    ("HandTipRight", None),
    ("ThumbRight", None),
];

/// Errors of the Kinect reader, naming origin, 1-based line and what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum KinectError {
    /// Reading failed (including invalid UTF-8).
    #[error("{origin}:{line}: read error: {source}")]
    Io {
        /// File or stream name.
        origin: String,
        /// Line being read.
        line: usize,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// A line without exactly 101 values.
    #[error("{origin}:{line}: {found} fields, expected {expected} (timestamp + 25 × X,Y,Z,state)")]
    FieldCount {
        /// File or stream name.
        origin: String,
        /// Line number.
        line: usize,
        /// Always [`KINECT_FIELDS`].
        expected: usize,
        /// Fields on the line (a trailing empty field not counted).
        found: usize,
    },
    /// A field that is not a finite number, or a state other than 0, 1, 2.
    #[error("{origin}:{line}: field {field} ({what}): `{text}` is not valid")]
    Value {
        /// File or stream name.
        origin: String,
        /// Line number.
        line: usize,
        /// 1-based field index.
        field: usize,
        /// What the field is, e.g. "KneeLeft Y".
        what: String,
        /// The text found.
        text: String,
    },
    /// A timestamp smaller than the previous one.
    #[error("{origin}:{line}: timestamp {timestamp} is before the previous one ({previous})")]
    TimeGoesBack {
        /// File or stream name.
        origin: String,
        /// Line number.
        line: usize,
        /// This line's timestamp (100 ns).
        timestamp: f64,
        /// The previous line's (100 ns).
        previous: f64,
    },
    /// A line longer than [`KinectConfig::max_line_bytes`].
    #[error("{origin}:{line}: line longer than {limit} bytes")]
    LineTooLong {
        /// File or stream name.
        origin: String,
        /// Line number.
        line: usize,
        /// The limit.
        limit: usize,
    },
}

/// Settings of a [`KinectReader`].
#[derive(Clone, Debug, PartialEq)]
pub struct KinectConfig {
    /// Keep joints whose state is "inferred" (1); if `false` they are missing.
    pub keep_inferred: bool,
    /// Longest line accepted, in bytes.
    pub max_line_bytes: usize,
}

impl Default for KinectConfig {
    /// Keep inferred joints; lines up to 64 KiB (a frame line is about 2.5 KB).
    fn default() -> Self {
        KinectConfig {
            keep_inferred: true,
            max_line_bytes: 64 * 1024,
        }
    }
}

/// Streaming Kinect v2 CSV reader: one [`HumanFrame`] per non-blank line, via
/// [`KinectReader::read_frame`] or as an iterator. Allocation-free per frame once the longest
/// line has been seen.
#[derive(Debug)]
pub struct KinectReader<R> {
    reader: R,
    origin: String,
    config: KinectConfig,
    line: String,
    line_no: usize,
    first_timestamp: Option<f64>,
    previous_timestamp: f64,
    done: bool,
}

impl KinectReader<BufReader<File>> {
    /// Opens the file at `path`; the path is the origin in errors.
    pub fn open(path: impl AsRef<Path>, config: KinectConfig) -> Result<Self, KinectError> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let file = File::open(path).map_err(|source| KinectError::Io {
            origin: origin.clone(),
            line: 0,
            source,
        })?;
        Ok(KinectReader::new(BufReader::new(file), origin, config))
    }
}

impl<R: BufRead> KinectReader<R> {
    /// A reader of `reader`; `origin` names the source in errors.
    pub fn new(reader: R, origin: impl Into<String>, config: KinectConfig) -> Self {
        KinectReader {
            reader,
            origin: origin.into(),
            config,
            line: String::new(),
            line_no: 0,
            first_timestamp: None,
            previous_timestamp: f64::NEG_INFINITY,
            done: false,
        }
    }

    /// Reads the next frame into `out`. Returns `Ok(false)` at the end of input; after an error
    /// the reader is finished.
    pub fn read_frame(&mut self, out: &mut HumanFrame) -> Result<bool, KinectError> {
        if self.done {
            return Ok(false);
        }
        let result = self.read_frame_inner(out);
        if !matches!(result, Ok(true)) {
            self.done = true;
        }
        result
    }

    fn read_frame_inner(&mut self, out: &mut HumanFrame) -> Result<bool, KinectError> {
        loop {
            self.line_no += 1;
            let read =
                read_line_capped(&mut self.reader, &mut self.line, self.config.max_line_bytes)
                    .map_err(|source| KinectError::Io {
                        origin: self.origin.clone(),
                        line: self.line_no,
                        source,
                    })?;
            match read {
                None => return Ok(false),
                Some(true) => {
                    return Err(KinectError::LineTooLong {
                        origin: self.origin.clone(),
                        line: self.line_no,
                        limit: self.config.max_line_bytes,
                    });
                }
                Some(false) if self.line.trim().is_empty() => continue,
                Some(false) => break,
            }
        }
        self.decode_current(out).map(|()| true)
    }

    /// Decodes `line`, one frame line received from elsewhere (a stream of Kinect frames), into
    /// `out` as the next frame: the reader's own source is not read. Unlike
    /// [`KinectReader::read_frame`], an error leaves the reader usable: the line is skipped
    /// and the next one must still not go back in time.
    ///
    /// # Errors
    /// [`KinectError::FieldCount`], [`KinectError::Value`], [`KinectError::TimeGoesBack`] or
    /// [`KinectError::LineTooLong`] for the line, numbered as the reader's lines.
    pub fn decode_line(&mut self, line: &str, out: &mut HumanFrame) -> Result<(), KinectError> {
        self.line_no += 1;
        if line.len() > self.config.max_line_bytes {
            return Err(KinectError::LineTooLong {
                origin: self.origin.clone(),
                line: self.line_no,
                limit: self.config.max_line_bytes,
            });
        }
        self.line.clear();
        self.line.push_str(line);
        self.decode_current(out)
    }

    /// Decodes the line in `self.line` into `out`.
    fn decode_current(&mut self, out: &mut HumanFrame) -> Result<(), KinectError> {
        let line = self.line.trim();
        let line = line.strip_suffix(',').unwrap_or(line);
        let found = line.split(',').count();
        if found != KINECT_FIELDS {
            return Err(KinectError::FieldCount {
                origin: self.origin.clone(),
                line: self.line_no,
                expected: KINECT_FIELDS,
                found,
            });
        }
        let mut fields = line.split(',').map(str::trim).enumerate();
        let timestamp = self.number(fields.next(), || "timestamp".to_owned())?;
        if timestamp < self.previous_timestamp {
            return Err(KinectError::TimeGoesBack {
                origin: self.origin.clone(),
                line: self.line_no,
                timestamp,
                previous: self.previous_timestamp,
            });
        }
        let first = self.first_timestamp.unwrap_or(timestamp);
        let time = (timestamp - first) * 1e-7;
        if !time.is_finite() {
            return Err(self.value_error(
                Some((0, fields_text(line, 0))),
                "timestamp (too far from the first)".to_owned(),
            ));
        }
        out.clear(time);
        for (name, human) in KINECT_JOINTS {
            let x = self.number(fields.next(), || format!("{name} X"))?;
            let y = self.number(fields.next(), || format!("{name} Y"))?;
            let z = self.number(fields.next(), || format!("{name} Z"))?;
            let state_field = fields.next();
            let what = || format!("{name} state (0, 1 or 2)");
            let present = match self.number(state_field, what)? {
                0.0 => false,
                1.0 => self.config.keep_inferred,
                2.0 => true,
                _ => return Err(self.value_error(state_field, what())),
            };
            if let Some(joint) = human {
                out.set(joint, present.then(|| Vector3::new(-z, -x, y)));
            }
        }
        self.first_timestamp = Some(first);
        self.previous_timestamp = timestamp;
        out.derive_mid_hip();
        Ok(())
    }

    /// Parses the field `(index, text)` as a finite number; `what` describes it for errors.
    fn number(
        &self,
        field: Option<(usize, &str)>,
        what: impl Fn() -> String,
    ) -> Result<f64, KinectError> {
        match field.map(|(_, text)| text.parse::<f64>()) {
            Some(Ok(v)) if v.is_finite() => Ok(v),
            _ => Err(self.value_error(field, what())),
        }
    }

    /// A [`KinectError::Value`] for `field` (0-based index and text; always present because the
    /// field count was checked first).
    fn value_error(&self, field: Option<(usize, &str)>, what: String) -> KinectError {
        let (index, text) = field.unwrap_or((KINECT_FIELDS, ""));
        KinectError::Value {
            origin: self.origin.clone(),
            line: self.line_no,
            field: index + 1,
            what,
            text: text.to_owned(),
        }
    }
}

/// The text of field `index` (0-based) of `line`.
fn fields_text(line: &str, index: usize) -> &str {
    line.split(',').nth(index).unwrap_or("").trim()
}

impl<R: BufRead> Iterator for KinectReader<R> {
    type Item = Result<HumanFrame, KinectError>;

    fn next(&mut self) -> Option<Self::Item> {
        super::next_frame(|frame| self.read_frame(frame))
    }
}
