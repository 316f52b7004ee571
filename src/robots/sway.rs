//! Sway shaping: servo commands that do not rock the robot on its stance foot.
//!
//! A robot of stiff position servos standing on one foot sways on its stance ankle like an
//! inverted pendulum on a torsional spring: `I θ̈ = −(k − m g h) θ`, period
//!
//! ```text
//! T = 2π √(I / (k − m g h))
//! ```
//!
//! (`k` the ankle roll servo's stiffness, `m g h` gravity's toppling stiffness at CoM height `h`,
//! `I ≈ m h²` the inertia about the ankle), with almost no damping. A command that shifts the
//! weight or lifts a foot within a fraction of that period leaves the robot rocking after it,
//! and a rocking robot lands its swing foot early and tips over its stance sole's edge.
//!
//! A zero-vibration-derivative (ZVD) shaper (Singer and Seering 1990) removes the command's
//! content at that period: it plays the command as the sum of three copies,
//!
//! ```text
//! y(t) = A₀ x(t) + A₁ x(t − T/2) + A₂ x(t − T),
//! A = (1, 2K, K²) / (1 + K)²,   K = exp(−ζπ / √(1 − ζ²))
//! ```
//!
//! whose responses of the sway mode cancel, with a zero derivative of the residual with respect
//! to the period: a mode whose frequency is 10 % off the assumed one still rocks at under 5 % of
//! what the unshaped command excites, 25 % off at under 20 % (undamped, `cos²(πr/2)` for the
//! frequency ratio `r`). The shaped command is a convex combination of past commands, so it
//! stays inside the joint limits and below the fastest joint speed of the commands; it lags them
//! by `T / 2` on average (the price: the robot moves half a sway period after the plan).
//!
//! The history is kept as the commands of the past `T` seconds at their times, and the delayed
//! copies are interpolated linearly between them; before the first command the robot holds it.

use std::collections::VecDeque;

/// The damping ratio of the sway mode the shaper is designed for: 0.03, measured on the G1's
/// physics model (the logged roll of its pelvis on one foot after a weight shift).
pub const SWAY_DAMPING: f64 = 0.03;

/// A ZVD shaper of servo commands (module docs): feed each command with its time
/// ([`SwayShaper::shape`]); no allocation once the history has held `T` seconds of commands at
/// the steady rate.
#[derive(Debug, Clone)]
pub struct SwayShaper {
    /// The copies' delays (s): 0, T/2, T.
    delays: [f64; 3],
    /// The copies' weights, summing to 1.
    weights: [f64; 3],
    /// Variables per command.
    n: usize,
    /// The times (s) of the commands held, oldest first.
    times: VecDeque<f64>,
    /// The commands held, `n` values each, in the order of `times`.
    commands: VecDeque<f64>,
}

/// What a shaper cannot take.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SwayError {
    /// The period is not a finite time > 0.
    #[error("sway period {0} s is not a finite time > 0")]
    Period(f64),
    /// A command's time is not finite or is before the last command's.
    #[error("command time {time} s is not finite or comes before the last one ({last} s)")]
    Time {
        /// The command's time (s).
        time: f64,
        /// The last command's time (s).
        last: f64,
    },
    /// A command has the wrong number of values.
    #[error("a command has {got} values, the shaper {expected}")]
    Length {
        /// The shaper's variables.
        expected: usize,
        /// The command's.
        got: usize,
    },
    /// A command value is not finite.
    #[error("command value {0} is not finite")]
    NonFinite(f64),
}

impl SwayShaper {
    /// A shaper of commands of `n` variables for a sway of `period` (s), with room for twice
    /// the commands of `T` seconds at one every `dt` seconds (a hint: the history grows when
    /// they come faster).
    ///
    /// # Errors
    /// [`SwayError::Period`] for a period that is not a finite time > 0.
    pub fn new(period: f64, n: usize, dt: f64) -> Result<Self, SwayError> {
        if !(period.is_finite() && period > 0.0) {
            return Err(SwayError::Period(period));
        }
        let k = (-SWAY_DAMPING * std::f64::consts::PI / (1.0 - SWAY_DAMPING.powi(2)).sqrt()).exp();
        let sum = (1.0 + k).powi(2);
        let frames = if dt.is_finite() && dt > 0.0 {
            2 * (period / dt).ceil().min(1e5) as usize + 2
        } else {
            2
        };
        Ok(Self {
            delays: [0.0, period / 2.0, period],
            weights: [1.0 / sum, 2.0 * k / sum, k * k / sum],
            n,
            times: VecDeque::with_capacity(frames),
            commands: VecDeque::with_capacity(frames * n),
        })
    }

    /// The mean delay of the shaped command behind the command (s).
    pub fn mean_delay(&self) -> f64 {
        self.delays
            .iter()
            .zip(&self.weights)
            .map(|(d, w)| d * w)
            .sum()
    }

    /// Takes the command at `time` (s) and overwrites it with the shaped command.
    ///
    /// # Errors
    /// A time before the last one or not finite, a command of the wrong length or with a
    /// non-finite value; the shaper is unchanged then.
    pub fn shape(&mut self, time: f64, command: &mut [f64]) -> Result<(), SwayError> {
        let last = self.times.back().copied().unwrap_or(f64::NEG_INFINITY);
        if !time.is_finite() || time < last {
            return Err(SwayError::Time { time, last });
        }
        if command.len() != self.n {
            return Err(SwayError::Length {
                expected: self.n,
                got: command.len(),
            });
        }
        if let Some(&bad) = command.iter().find(|v| !v.is_finite()) {
            return Err(SwayError::NonFinite(bad));
        }
        self.push(time, command);
        let copies = self.delays.map(|delay| self.bracket(time - delay));
        for (j, value) in command.iter_mut().enumerate() {
            *value = (copies.iter().zip(&self.weights))
                .map(|(&(k0, k1, s), &weight)| {
                    let value = |k: usize| self.commands[k * self.n + j];
                    weight * (value(k0) + s * (value(k1) - value(k0)))
                })
                .sum();
        }
        Ok(())
    }

    /// Appends a command and forgets those no delayed copy will read again (the newest at or
    /// before `time − T` stays, for interpolation).
    fn push(&mut self, time: f64, command: &[f64]) {
        self.times.push_back(time);
        self.commands.extend(command.iter().copied());
        let horizon = time - self.delays[2];
        while self.times.len() > 1 && self.times[1] <= horizon {
            self.times.pop_front();
            self.commands.drain(..self.n);
        }
    }

    /// Where `time` (s) falls among the commands held: the command is `c[k0] + s (c[k1] −
    /// c[k0])`, linear between its neighbours; the oldest one before them, the newest after.
    fn bracket(&self, time: f64) -> (usize, usize, f64) {
        let after = self.times.partition_point(|&t| t <= time);
        if after == 0 {
            return (0, 0, 0.0);
        }
        if after == self.times.len() {
            return (after - 1, after - 1, 0.0);
        }
        let (t0, t1) = (self.times[after - 1], self.times[after]);
        (after - 1, after, (time - t0) / (t1 - t0))
    }
}
