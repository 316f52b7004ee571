//! `joints.csv`, what a robot with position servos plays and the physics judge reads: a header
//! `time,<the robot's joint names>`, then per frame the time (s) and the joint angles (rad), six
//! decimals, one line per frame.

use std::fmt::Write as _;

use crate::imitation::{Imitator, RobotFrame};

/// Writes `joints.csv` as the frames come: a header `time,<the imitator's variable names>`,
/// then per frame the time (s) and the joint angles (rad), six decimals.
#[derive(Debug)]
pub struct JointsWriter<W: std::io::Write> {
    out: W,
    line: String,
}

impl<W: std::io::Write> JointsWriter<W> {
    /// A writer into `out` (buffer it: one write per frame follows).
    pub fn new(out: W) -> Self {
        Self {
            out,
            line: String::new(),
        }
    }

    /// Writes the header line.
    pub fn header(&mut self, imitator: &Imitator) -> std::io::Result<()> {
        self.header_names(imitator.variable_names())
    }

    /// Writes the header line for joints named `names` (any source of joint angles: a walk, a
    /// user's own loop).
    pub fn header_names<'n>(
        &mut self,
        names: impl IntoIterator<Item = &'n str>,
    ) -> std::io::Result<()> {
        self.line.clear();
        self.line.push_str("time");
        for name in names {
            self.line.push(',');
            self.line.push_str(name);
        }
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())
    }

    /// Writes `frame`'s line: its servo targets ([`RobotFrame::servo_targets`]), what a robot
    /// with position servos plays.
    pub fn frame(&mut self, frame: &RobotFrame) -> std::io::Result<()> {
        self.row(frame.time, &frame.servo_targets)
    }

    /// Writes one line: `time` (s) and the joint angles `q` (rad).
    pub fn row(&mut self, time: f64, q: &[f64]) -> std::io::Result<()> {
        self.line.clear();
        let _ = write!(self.line, "{time:.6}");
        for q in q {
            let _ = write!(self.line, ",{q:.6}");
        }
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())
    }

    /// Flushes the output.
    pub fn finish(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }

    /// The output, given back.
    pub fn into_inner(self) -> W {
        self.out
    }
}
