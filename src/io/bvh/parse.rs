//! The BVH header: a tokenizer with line numbers, the `HIERARCHY` (joints, offsets, channels),
//! the `MOTION` header (frame count and time) and the joint names resolved against the
//! configured naming.

use std::io::BufRead;

use nalgebra::Vector3;

use super::skeleton::{
    BvhChannel, BvhError, BvhJoint, BvhNames, BvhSkeleton, CMU_MAX_NAMES, CMU_MB_NAMES,
};
use crate::human::HumanJoint;
use crate::io::read_line_capped;

/// Tokenizer over the header: whitespace-separated tokens with line numbers.
pub(super) struct Lexer<R> {
    pub(super) reader: R,
    pub(super) origin: String,
    pub(super) line: String,
    pub(super) pos: usize,
    pub(super) line_no: usize,
    pub(super) max_line_bytes: usize,
}

impl<R: BufRead> Lexer<R> {
    /// Reads the next line; `false` at end of input.
    fn next_line(&mut self) -> Result<bool, BvhError> {
        self.line_no += 1;
        self.pos = 0;
        match read_line_capped(&mut self.reader, &mut self.line, self.max_line_bytes) {
            Ok(None) => {
                self.line_no -= 1;
                Ok(false)
            }
            Ok(Some(false)) => Ok(true),
            Ok(Some(true)) => Err(BvhError::Limit {
                origin: self.origin.clone(),
                line: self.line_no,
                what: "line length in bytes",
                limit: self.max_line_bytes,
            }),
            Err(source) => Err(BvhError::Io {
                origin: self.origin.clone(),
                line: self.line_no,
                source,
            }),
        }
    }

    /// The next token, reading lines as needed; `None` at end of input.
    fn token(&mut self) -> Result<Option<String>, BvhError> {
        loop {
            let rest = &self.line[self.pos..];
            if let Some(start) = rest.find(|c: char| !c.is_ascii_whitespace()) {
                let len = rest[start..]
                    .find(|c: char| c.is_ascii_whitespace())
                    .unwrap_or(rest.len() - start);
                let token = rest[start..start + len].to_owned();
                self.pos += start + len;
                return Ok(Some(token));
            }
            self.pos = self.line.len();
            if !self.next_line()? {
                return Ok(None);
            }
        }
    }

    /// The next token; at end of input a [`BvhError::TruncatedHeader`] saying what was expected.
    fn expect_token(&mut self, expected: &'static str) -> Result<String, BvhError> {
        self.token()?.ok_or_else(|| BvhError::TruncatedHeader {
            origin: self.origin.clone(),
            line: self.line_no,
            expected,
        })
    }

    fn expect_keyword(&mut self, keyword: &'static str) -> Result<(), BvhError> {
        let token = self.expect_token(keyword)?;
        if token == keyword {
            Ok(())
        } else {
            Err(self.syntax(keyword, token))
        }
    }

    /// The tokens left on the current line.
    fn rest_of_line(&mut self) -> Vec<String> {
        let tokens = self.line[self.pos..]
            .split_ascii_whitespace()
            .map(str::to_owned)
            .collect();
        self.pos = self.line.len();
        tokens
    }

    fn number(&mut self, field: impl Fn() -> String) -> Result<f64, BvhError> {
        let text = self.expect_token("a number")?;
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.number_error(field(), text)),
        }
    }

    fn vector(&mut self, field: impl Fn() -> String) -> Result<Vector3<f64>, BvhError> {
        Ok(Vector3::new(
            self.number(&field)?,
            self.number(&field)?,
            self.number(&field)?,
        ))
    }

    fn syntax(&self, expected: &'static str, found: String) -> BvhError {
        BvhError::Syntax {
            origin: self.origin.clone(),
            line: self.line_no,
            expected,
            found,
        }
    }

    fn number_error(&self, field: String, text: String) -> BvhError {
        BvhError::Number {
            origin: self.origin.clone(),
            line: self.line_no,
            field,
            text,
        }
    }

    /// The next line with something on it, trimmed; what it should hold is `expected`.
    fn next_content_line(&mut self, expected: &'static str) -> Result<String, BvhError> {
        loop {
            if !self.next_line()? {
                return Err(BvhError::TruncatedHeader {
                    origin: self.origin.clone(),
                    line: self.line_no,
                    expected,
                });
            }
            let trimmed = self.line.trim();
            if !trimmed.is_empty() {
                return Ok(trimmed.to_owned());
            }
        }
    }
}

/// `HIERARCHY ROOT name { … }`, iteratively (an explicit stack, so deep nesting cannot overflow
/// the call stack), up to and including the `MOTION` keyword.
pub(super) fn parse_hierarchy<R: BufRead>(
    lexer: &mut Lexer<R>,
    max_joints: usize,
) -> Result<BvhSkeleton, BvhError> {
    lexer.expect_keyword("HIERARCHY")?;
    lexer.expect_keyword("ROOT")?;
    let mut joints: Vec<BvhJoint> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    let mut parent = None;
    loop {
        // Here a joint keyword (ROOT or JOINT) has just been read.
        if joints.len() >= max_joints {
            return Err(BvhError::Limit {
                origin: lexer.origin.clone(),
                line: lexer.line_no,
                what: "number of joints",
                limit: max_joints,
            });
        }
        let name = lexer.expect_token("a joint name")?;
        lexer.expect_keyword("{")?;
        joints.push(BvhJoint {
            name,
            parent,
            offset: Vector3::zeros(),
            channels: Vec::new(),
            end_site: None,
            first_value: 0,
        });
        open.push(joints.len() - 1);
        // Statements of the open joints until the next JOINT (or the end of the hierarchy).
        let next_joint_parent = loop {
            let Some(&current) = open.last() else {
                break None;
            };
            let token = lexer.expect_token("OFFSET, CHANNELS, JOINT, End Site or }")?;
            match token.as_str() {
                "OFFSET" => {
                    let offset =
                        lexer.vector(|| format!("OFFSET of joint `{}`", joints[current].name))?;
                    joints[current].offset = offset;
                }
                "CHANNELS" => {
                    joints[current].channels = parse_channels(lexer, &joints[current].name)?;
                }
                "JOINT" => break Some(current),
                "End" => {
                    lexer.expect_keyword("Site")?;
                    lexer.expect_keyword("{")?;
                    lexer.expect_keyword("OFFSET")?;
                    let offset = lexer.vector(|| {
                        format!("End Site OFFSET of joint `{}`", joints[current].name)
                    })?;
                    lexer.expect_keyword("}")?;
                    joints[current].end_site = Some(offset);
                }
                "}" => {
                    open.pop();
                }
                _ => return Err(lexer.syntax("OFFSET, CHANNELS, JOINT, End Site or }", token)),
            }
        };
        match next_joint_parent {
            Some(p) => parent = Some(p),
            None => break,
        }
    }
    let token = lexer.expect_token("MOTION")?;
    if token != "MOTION" {
        return Err(lexer.syntax("MOTION (one ROOT per file)", token));
    }
    let mut first_value = 0;
    for joint in &mut joints {
        joint.first_value = first_value;
        first_value += joint.channels.len();
    }
    Ok(BvhSkeleton { joints })
}

/// `CHANNELS n c1 … cn` after the keyword: the count and the names on the rest of the line.
fn parse_channels<R: BufRead>(
    lexer: &mut Lexer<R>,
    joint: &str,
) -> Result<Vec<BvhChannel>, BvhError> {
    let count_text = lexer.expect_token("a channel count")?;
    let declared: usize = count_text.parse().map_err(|_| {
        lexer.number_error(
            format!("channel count of joint `{joint}`"),
            count_text.clone(),
        )
    })?;
    let names = lexer.rest_of_line();
    if declared > 6 || names.len() != declared {
        return Err(BvhError::ChannelCount {
            origin: lexer.origin.clone(),
            line: lexer.line_no,
            joint: joint.to_owned(),
            declared,
            listed: names.len(),
        });
    }
    let mut seen = 0u8;
    let mut channels = Vec::with_capacity(declared);
    for name in &names {
        let channel = BvhChannel::from_name(name).ok_or_else(|| BvhError::UnknownChannel {
            origin: lexer.origin.clone(),
            line: lexer.line_no,
            joint: joint.to_owned(),
            channel: name.clone(),
        })?;
        if seen & channel.bit() != 0 {
            return Err(BvhError::RotationOrder {
                origin: lexer.origin.clone(),
                line: lexer.line_no,
                joint: joint.to_owned(),
                order: names.join(" "),
            });
        }
        seen |= channel.bit();
        channels.push(channel);
    }
    Ok(channels)
}

/// `Frames: N` and `Frame Time: dt` after `MOTION`.
pub(super) fn parse_motion_header<R: BufRead>(
    lexer: &mut Lexer<R>,
) -> Result<(u64, f64), BvhError> {
    let rest = lexer.rest_of_line();
    if let Some(extra) = rest.into_iter().next() {
        return Err(lexer.syntax("end of line after MOTION", extra));
    }
    let frames_line = lexer.next_content_line("Frames: N")?;
    let frames_text = labelled_value(&frames_line, &["Frames"])
        .ok_or_else(|| lexer.syntax("Frames: N", frames_line.clone()))?;
    let frames: u64 = frames_text
        .parse()
        .map_err(|_| lexer.number_error("Frames".to_owned(), frames_text.to_owned()))?;
    let time_line = lexer.next_content_line("Frame Time: dt")?;
    let time_text = labelled_value(&time_line, &["Frame", "Time"])
        .ok_or_else(|| lexer.syntax("Frame Time: dt", time_line.clone()))?;
    let frame_time = match time_text.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => t,
        _ => return Err(lexer.number_error("Frame Time".to_owned(), time_text.to_owned())),
    };
    Ok((frames, frame_time))
}

/// For `line` = `"Frame Time: 0.0083"` and `words` = `["Frame", "Time"]`: `Some("0.0083")`.
/// The words may be separated by any whitespace; the colon is optional.
fn labelled_value<'a>(line: &'a str, words: &[&str]) -> Option<&'a str> {
    let mut rest = line;
    for word in words {
        rest = rest.trim_start().strip_prefix(word)?;
    }
    let rest = rest.trim_start();
    let rest = rest.strip_prefix(':').unwrap_or(rest).trim();
    (!rest.is_empty() && !rest.contains(char::is_whitespace)).then_some(rest)
}

/// Skeleton index of every human joint under `names`.
pub(super) fn resolve_names(
    skeleton: &BvhSkeleton,
    names: &BvhNames,
    origin: &str,
) -> Result<[Option<usize>; HumanJoint::COUNT], BvhError> {
    let has_all = |table: &[(&str, HumanJoint)]| {
        table
            .iter()
            .all(|(name, _)| skeleton.index_of(name).is_some())
    };
    let table: Vec<(&str, HumanJoint)> = match names {
        BvhNames::Auto if has_all(&CMU_MB_NAMES) => CMU_MB_NAMES.to_vec(),
        BvhNames::Auto if has_all(&CMU_MAX_NAMES) => CMU_MAX_NAMES.to_vec(),
        BvhNames::Auto => {
            return Err(BvhError::UnknownSkeleton {
                origin: origin.to_owned(),
                root: skeleton
                    .joints
                    .first()
                    .map(|j| j.name.clone())
                    .unwrap_or_default(),
            });
        }
        BvhNames::CmuMb => CMU_MB_NAMES.to_vec(),
        BvhNames::CmuMax => CMU_MAX_NAMES.to_vec(),
        BvhNames::Custom(pairs) => pairs.iter().map(|(n, h)| (n.as_str(), *h)).collect(),
    };
    let mut map = [None; HumanJoint::COUNT];
    for (name, human) in table {
        let mut matches = skeleton
            .joints
            .iter()
            .enumerate()
            .filter(|(_, j)| j.name == name)
            .map(|(i, _)| i);
        let problem = match (matches.next(), matches.next()) {
            (Some(index), None) => {
                map[human.index()] = Some(index);
                continue;
            }
            (None, _) => "is not in the skeleton",
            (Some(_), Some(_)) => "names several joints",
        };
        return Err(BvhError::NameMap {
            origin: origin.to_owned(),
            name: name.to_owned(),
            human,
            problem,
        });
    }
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labelled_values() {
        assert_eq!(labelled_value("Frames: 12", &["Frames"]), Some("12"));
        assert_eq!(labelled_value("Frames 12", &["Frames"]), Some("12"));
        assert_eq!(
            labelled_value("Frame  Time:\t.0083", &["Frame", "Time"]),
            Some(".0083")
        );
        assert_eq!(labelled_value("Frames: 1 2", &["Frames"]), None);
        assert_eq!(labelled_value("Frame Time:", &["Frame", "Time"]), None);
    }
}
