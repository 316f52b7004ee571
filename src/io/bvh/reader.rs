//! The streaming reader: the header parsed once, then one frame of joint positions per line.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

use nalgebra::{Matrix3, Vector3};

use super::parse::{Lexer, parse_hierarchy, parse_motion_header, resolve_names};
use super::skeleton::{BvhChannel, BvhConfig, BvhError, BvhSkeleton};
use crate::human::{HumanFrame, HumanJoint};
use crate::io::read_line_capped;

/// Streaming BVH reader: parses the header on construction, then yields one [`HumanFrame`] per
/// motion line ([`BvhReader::read_frame`], or as an iterator). Frame `k` has time `k·dt`.
///
/// Per frame it reuses its buffers: reading a frame allocates nothing once the longest line has
/// been seen.
#[derive(Debug)]
pub struct BvhReader<R> {
    reader: R,
    origin: String,
    skeleton: BvhSkeleton,
    frame_time: f64,
    declared_frames: u64,
    frames_read: u64,
    line_no: usize,
    line: String,
    max_line_bytes: usize,
    to_human: Matrix3<f64>,
    values: Vec<f64>,
    rotations: Vec<Matrix3<f64>>,
    positions: Vec<Vector3<f64>>,
    map: [Option<usize>; HumanJoint::COUNT],
    done: bool,
}

impl BvhReader<BufReader<File>> {
    /// Opens the file at `path` and parses its header; the path is the origin in errors.
    pub fn open(path: impl AsRef<Path>, config: BvhConfig) -> Result<Self, BvhError> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let file = File::open(path).map_err(|source| BvhError::Io {
            origin: origin.clone(),
            line: 0,
            source,
        })?;
        BvhReader::new(BufReader::new(file), origin, config)
    }
}

impl<R: BufRead> BvhReader<R> {
    /// Parses the header (hierarchy, frame count, frame time) from `reader`; `origin` names the
    /// source in errors.
    pub fn new(reader: R, origin: impl Into<String>, config: BvhConfig) -> Result<Self, BvhError> {
        if !(config.scale.is_finite() && config.scale > 0.0) {
            return Err(BvhError::Config("scale must be finite and positive"));
        }
        if config.max_line_bytes == 0 || config.max_joints == 0 {
            return Err(BvhError::Config("limits must be positive"));
        }
        let mut lexer = Lexer {
            reader,
            origin: origin.into(),
            line: String::new(),
            pos: 0,
            line_no: 0,
            max_line_bytes: config.max_line_bytes,
        };
        let skeleton = parse_hierarchy(&mut lexer, config.max_joints)?;
        let (declared_frames, frame_time) = parse_motion_header(&mut lexer)?;
        let map = resolve_names(&skeleton, &config.names, &lexer.origin)?;
        let n = skeleton.joints.len();
        let channels = skeleton.channel_count();
        let Lexer {
            reader,
            origin,
            line,
            line_no,
            ..
        } = lexer;
        Ok(BvhReader {
            reader,
            origin,
            skeleton,
            frame_time,
            declared_frames,
            frames_read: 0,
            line_no,
            line,
            max_line_bytes: config.max_line_bytes,
            to_human: config.up.matrix() * config.scale,
            values: vec![0.0; channels],
            rotations: vec![Matrix3::identity(); n],
            positions: vec![Vector3::zeros(); n],
            map,
            done: false,
        })
    }

    /// The hierarchy.
    pub fn skeleton(&self) -> &BvhSkeleton {
        &self.skeleton
    }

    /// Seconds between frames (`Frame Time`).
    pub fn frame_time(&self) -> f64 {
        self.frame_time
    }

    /// Number of frames the header declares (`Frames`). Not trusted for allocation.
    pub fn declared_frames(&self) -> u64 {
        self.declared_frames
    }

    /// Frames read so far.
    pub fn frames_read(&self) -> u64 {
        self.frames_read
    }

    /// Positions of every skeleton joint in the last frame read, in metres in the human frame
    /// (z up), indexed like [`BvhSkeleton::joints`]. All zeros before the first frame.
    pub fn joint_positions(&self) -> &[Vector3<f64>] {
        &self.positions
    }

    /// Reads the next frame into `out` (its time and every joint; unmapped joints are missing).
    /// Returns `Ok(false)` once all declared frames were read. After an error, the reader is
    /// finished and returns `Ok(false)`.
    pub fn read_frame(&mut self, out: &mut HumanFrame) -> Result<bool, BvhError> {
        if self.done || self.frames_read >= self.declared_frames {
            self.done = true;
            return Ok(false);
        }
        let result = self.read_values().and_then(|()| self.frame_of_values(out));
        if result.is_err() {
            self.done = true;
        }
        result.map(|()| true)
    }

    /// Decodes `line`, one motion line received from elsewhere (a stream of the same
    /// skeleton's frames), into `out` as the next frame: the reader's own source is not read.
    /// Unlike [`BvhReader::read_frame`], an error leaves the reader usable (the line is
    /// skipped: the next line gets its frame index) and the header's frame count is not a
    /// limit.
    ///
    /// # Errors
    /// [`BvhError::FrameValueCount`], [`BvhError::Number`], [`BvhError::NonFinitePosition`]
    /// or [`BvhError::Limit`] for the line, numbered as the reader's lines.
    pub fn decode_line(&mut self, line: &str, out: &mut HumanFrame) -> Result<(), BvhError> {
        self.line_no += 1;
        if line.len() > self.max_line_bytes {
            return Err(self.limit("line length in bytes", self.max_line_bytes));
        }
        self.line.clear();
        self.line.push_str(line);
        self.parse_values()?;
        self.frame_of_values(out)
    }

    /// The frame of the values parsed last, into `out`, at time `frame index × frame time`.
    fn frame_of_values(&mut self, out: &mut HumanFrame) -> Result<(), BvhError> {
        // Frame counts in real files are far below 2^53, so the conversion is exact.
        let time = self.frames_read as f64 * self.frame_time;
        self.forward_kinematics()?;
        if !time.is_finite() {
            return Err(BvhError::Number {
                origin: self.origin.clone(),
                line: self.line_no,
                field: "frame time × frame index".to_owned(),
                text: time.to_string(),
            });
        }
        out.clear(time);
        for joint in HumanJoint::ALL {
            out.set(joint, self.map[joint.index()].map(|j| self.positions[j]));
        }
        out.derive_mid_hip();
        self.frames_read += 1;
        Ok(())
    }

    /// Reads the next motion line and parses it into `self.values`.
    fn read_values(&mut self) -> Result<(), BvhError> {
        loop {
            self.line_no += 1;
            let read = read_line_capped(&mut self.reader, &mut self.line, self.max_line_bytes)
                .map_err(|source| BvhError::Io {
                    origin: self.origin.clone(),
                    line: self.line_no,
                    source,
                })?;
            match read {
                None => {
                    return Err(BvhError::TruncatedMotion {
                        origin: self.origin.clone(),
                        line: self.line_no - 1,
                        declared: self.declared_frames,
                        found: self.frames_read,
                    });
                }
                Some(true) => return Err(self.limit("line length in bytes", self.max_line_bytes)),
                Some(false) if self.line.trim().is_empty() => continue,
                Some(false) => break,
            }
        }
        self.parse_values()
    }

    /// Parses the motion line in `self.line` into `self.values`.
    fn parse_values(&mut self) -> Result<(), BvhError> {
        let expected = self.values.len();
        let mut found = 0;
        for token in self.line.split_ascii_whitespace() {
            if found < expected {
                match token.parse::<f64>() {
                    Ok(v) if v.is_finite() => self.values[found] = v,
                    _ => {
                        return Err(BvhError::Number {
                            origin: self.origin.clone(),
                            line: self.line_no,
                            field: describe_value(&self.skeleton, found),
                            text: token.to_owned(),
                        });
                    }
                }
            }
            found += 1;
        }
        if found != expected {
            return Err(BvhError::FrameValueCount {
                origin: self.origin.clone(),
                line: self.line_no,
                expected,
                found,
            });
        }
        Ok(())
    }

    fn forward_kinematics(&mut self) -> Result<(), BvhError> {
        for (j, joint) in self.skeleton.joints.iter().enumerate() {
            let mut rotation = Matrix3::identity();
            let mut translation = joint.offset;
            let values = &self.values[joint.first_value..joint.first_value + joint.channels.len()];
            for (&channel, &v) in joint.channels.iter().zip(values) {
                match channel {
                    BvhChannel::Xposition => translation.x += v,
                    BvhChannel::Yposition => translation.y += v,
                    BvhChannel::Zposition => translation.z += v,
                    BvhChannel::Xrotation => rotation *= rot_x(v.to_radians()),
                    BvhChannel::Yrotation => rotation *= rot_y(v.to_radians()),
                    BvhChannel::Zrotation => rotation *= rot_z(v.to_radians()),
                }
            }
            // `positions` holds file-frame positions during the pass and is mapped afterwards.
            match joint.parent {
                None => {
                    self.rotations[j] = rotation;
                    self.positions[j] = translation;
                }
                Some(p) => {
                    self.positions[j] = self.positions[p] + self.rotations[p] * translation;
                    self.rotations[j] = self.rotations[p] * rotation;
                }
            }
        }
        for (j, p) in self.positions.iter_mut().enumerate() {
            *p = self.to_human * *p;
            if !p.iter().all(|c| c.is_finite()) {
                return Err(BvhError::NonFinitePosition {
                    origin: self.origin.clone(),
                    line: self.line_no,
                    joint: self.skeleton.joints[j].name.clone(),
                });
            }
        }
        Ok(())
    }

    fn limit(&self, what: &'static str, limit: usize) -> BvhError {
        BvhError::Limit {
            origin: self.origin.clone(),
            line: self.line_no,
            what,
            limit,
        }
    }
}

impl<R: BufRead> Iterator for BvhReader<R> {
    type Item = Result<HumanFrame, BvhError>;

    fn next(&mut self) -> Option<Self::Item> {
        crate::io::next_frame(|frame| self.read_frame(frame))
    }
}

fn rot_x(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

fn rot_y(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

fn rot_z(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// "value 12 (LeftLeg Zrotation)": names the motion value at `index` for error messages.
fn describe_value(skeleton: &BvhSkeleton, index: usize) -> String {
    skeleton
        .joints
        .iter()
        .find(|j| (j.first_value..j.first_value + j.channels.len()).contains(&index))
        .map(|j| {
            format!(
                "value {} ({} {})",
                index + 1,
                j.name,
                j.channels[index - j.first_value].name()
            )
        })
        .unwrap_or_else(|| format!("value {}", index + 1))
}
