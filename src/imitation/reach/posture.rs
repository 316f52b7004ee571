//! The least hand error any posture of an arm gets, the rest of the body held: a bounded,
//! multi-start inverse kinematics of the arm's own variables.
//!
//! The distance test of [`super`] sees only how far a reference lies from the shoulder. A
//! reference inside that span can still be out of the arm's joint ranges (a NAO hand behind its
//! back), and a hand far from a reference it could reach is late or caught in an arm posture
//! from which the reference cannot be followed; the distance test tells neither apart. Here
//! the arm's variables — those that move the hand relative to the upper body's frame, found in
//! the model — are solved for the reference by damped Gauss–Newton steps kept inside the joint
//! ranges, every other variable at the frame's posture:
//!
//! ```text
//! δq = Jᵀ (J Jᵀ + μ² I)⁻¹ (p_ref − p_hand(q)),    q ← clamp(q + δq)
//! ```
//!
//! (`J` the hand's 3 × k position Jacobian in the arm's free variables, positions in the model's
//! base frame, m; a variable at a limit that the step would push past is held there and its
//! column left out). The steps start from the frame's own posture, then from the last frame's
//! best arm posture, then from [`spread`] postures over the joint ranges, and stop at the
//! first that brings the hand within [`REACHED`]. A posture counts only when the caller
//! accepts it (the meter requires the profile's self-collision margin).
//!
//! The least error found, or the frame's own error when nothing found was nearer, is an upper
//! bound on the error no posture of the arm removes: a multi-start search can miss a better
//! posture, never invent one. What remains of the hand's error is error that some posture
//! within the joint ranges removes.

use faer::Mat;
use nalgebra::{Matrix3, Vector3};

use crate::model::{FrameId, Model, ModelData};

/// A hand this near its reference (m) has reached it: the search stops.
pub(super) const REACHED: f64 = 1e-3;

/// Gauss–Newton steps of one start.
const ITERATIONS: usize = 40;

/// Damping μ of the steps (m): small against an arm, large enough that a near-singular
/// posture takes bounded steps.
const DAMPING: f64 = 5e-3;

/// The largest change of one variable in one step (rad, or m for a prismatic joint): keeps the
/// first-order model of the step near the arm's motion.
const MAX_STEP: f64 = 0.3;

/// A step whose largest change is below this (rad) has stalled, and a step that brings the
/// hand less than [`PROGRESS`] nearer has converged: the start is done.
const STALLED: f64 = 1e-7;

/// See [`STALLED`] (m).
const PROGRESS: f64 = 1e-5;

/// See [`ArmPostures::spread_now`] (m).
const SPREAD_LOSS: f64 = 2e-3;

/// See [`ArmPostures::spread_now`] (frames).
const SPREAD_EVERY: usize = 10;

/// A variable whose change moves the hand less than this relative to the upper body (m) is
/// not one of the arm's.
const OFF_ARM: f64 = 1e-6;

/// The variables of one arm and the scratch of its search; searching does not allocate.
#[derive(Debug, Clone)]
pub(super) struct ArmPostures {
    hand: FrameId,
    /// The arm's variables (model indices) and their ranges.
    variables: Vec<usize>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// Start values of the arm's variables, one row per start.
    starts: Vec<Vec<f64>>,
    /// The last frame's best arm posture and its error (m), when it had one.
    last_best: Option<Vec<f64>>,
    last_least: f64,
    /// Searched frames since the spread starts were last tried.
    since_spread: usize,
    /// The posture being solved (every variable).
    q: Vec<f64>,
    /// The best arm posture of this frame.
    best: Vec<f64>,
    jacobian: Mat<f64>,
    free: Vec<bool>,
    step: Vec<f64>,
}

impl ArmPostures {
    /// The arm of `model` between the frame `upper_body` and the frame `hand`: every variable
    /// with a finite range whose change moves the hand relative to `upper_body` in the posture
    /// `stand`. `None` when none does or the forward kinematics fails.
    pub(super) fn of(
        model: &Model,
        stand: &[f64],
        upper_body: FrameId,
        hand: FrameId,
    ) -> Option<Self> {
        let mut data = model.new_data();
        let mut q = stand.to_vec();
        let mut hand_in_body = |q: &[f64]| {
            model.forward_kinematics(&mut data, q).ok()?;
            let body = data.frame_placement(upper_body);
            let p = data.frame_placement(hand).translation.vector;
            Some(body.inverse_transform_point(&p.into()).coords)
        };
        let standing = hand_in_body(&q)?;
        let mut variables = Vec::new();
        for (k, v) in model.variables().iter().enumerate() {
            if !(v.lower.is_finite() && v.upper.is_finite() && v.upper > v.lower) {
                continue;
            }
            let mut moves = false;
            for t in [0.0, 0.5, 1.0] {
                q[k] = v.lower + t * (v.upper - v.lower);
                moves |= (hand_in_body(&q)? - standing).norm() > OFF_ARM;
            }
            q[k] = stand[k];
            if moves {
                variables.push(k);
            }
        }
        if variables.is_empty() {
            return None;
        }
        let range = |f: fn(&crate::model::Variable) -> f64| -> Vec<f64> {
            variables.iter().map(|&k| f(&model.variables()[k])).collect()
        };
        let (lower, upper) = (range(|v| v.lower), range(|v| v.upper));
        let k = variables.len();
        Some(Self {
            hand,
            starts: spread(&lower, &upper),
            lower,
            upper,
            variables,
            last_best: None,
            last_least: f64::INFINITY,
            since_spread: 0,
            q: stand.to_vec(),
            best: vec![0.0; k],
            jacobian: Mat::zeros(3, model.nv()),
            free: vec![true; k],
            step: vec![0.0; k],
        })
    }

    /// The least distance (m) from `target` (model base frame, m) to which some posture of
    /// the arm brings the hand, the other variables at `frame_q`, among the postures that
    /// `accept` (called with the forward kinematics of the posture in `data`) accepts; `None`
    /// when the search found none. Leaves `data` at an arbitrary posture.
    pub(super) fn least_error(
        &mut self,
        model: &Model,
        data: &mut ModelData,
        frame_q: &[f64],
        target: &Vector3<f64>,
        mut accept: impl FnMut(&Model, &ModelData) -> bool,
    ) -> Option<f64> {
        let mut least: Option<f64> = None;
        let had_last = usize::from(self.last_best.is_some());
        for start in 0..1 + had_last + self.starts.len() {
            if start == 1 + had_last && !self.spread_now(least) {
                break;
            }
            self.q.copy_from_slice(frame_q);
            let values = match start {
                0 => None,
                1 if had_last == 1 => self.last_best.as_deref(),
                s => Some(self.starts[s - 1 - had_last].as_slice()),
            };
            for (&k, &v) in self.variables.iter().zip(values.unwrap_or_default()) {
                self.q[k] = v;
            }
            let Some(error) = self.descend(model, data, target) else {
                continue;
            };
            if least.is_none_or(|l| error < l) && accept(model, data) {
                least = Some(error);
                for (b, &k) in self.best.iter_mut().zip(&self.variables) {
                    *b = self.q[k];
                }
            }
            if least.is_some_and(|l| l <= REACHED) {
                break;
            }
        }
        match (least, &mut self.last_best) {
            (Some(_), Some(kept)) => kept.copy_from_slice(&self.best),
            (Some(_), None) => self.last_best = Some(self.best.clone()),
            (None, _) => self.last_best = None,
        }
        self.last_least = least.unwrap_or(f64::INFINITY);
        least
    }

    /// Forgets the last frame's best posture (a frame without a reference broke the series).
    pub(super) fn forget(&mut self) {
        self.last_best = None;
    }

    /// Whether to try the spread starts after the frame's own posture and the last frame's
    /// best ended at `least`: always without a last best, or when they ended more than
    /// [`SPREAD_LOSS`] farther than the last frame's least (the reference left the basin the
    /// arm was following it in), and otherwise every [`SPREAD_EVERY`] searched frames (a
    /// nearer basin may have opened). Following a basin from frame to frame is what keeps
    /// the search's cost near one or two starts a frame.
    fn spread_now(&mut self, least: Option<f64>) -> bool {
        self.since_spread += 1;
        let lost = least.is_none_or(|l| l > self.last_least + SPREAD_LOSS);
        let due = self.last_best.is_none() || lost || self.since_spread >= SPREAD_EVERY;
        if due {
            self.since_spread = 0;
        }
        due
    }

    /// Damped Gauss–Newton steps from `self.q` toward `target`; the hand's final distance
    /// (m), with `data` at the final posture; `None` when the kinematics fails.
    fn descend(&mut self, model: &Model, data: &mut ModelData, target: &Vector3<f64>) -> Option<f64> {
        let mut last = f64::INFINITY;
        for _ in 0..ITERATIONS {
            let error = self.hand_error(model, data, target)?;
            if error.norm() <= REACHED || last - error.norm() < PROGRESS {
                return Some(error.norm());
            }
            last = error.norm();
            model
                .point_jacobian(data, self.hand, &Vector3::zeros(), self.jacobian.as_mut())
                .ok()?;
            if self.bounded_step(&error) < STALLED {
                break;
            }
            for (i, &k) in self.variables.iter().enumerate() {
                self.q[k] = (self.q[k] + self.step[i]).clamp(self.lower[i], self.upper[i]);
            }
        }
        Some(self.hand_error(model, data, target)?.norm())
    }

    /// `target` less the hand's position at `self.q`, with `data` at that posture.
    fn hand_error(
        &self,
        model: &Model,
        data: &mut ModelData,
        target: &Vector3<f64>,
    ) -> Option<Vector3<f64>> {
        model.forward_kinematics(data, &self.q).ok()?;
        Some(target - data.frame_placement(self.hand).translation.vector)
    }

    /// Writes the damped step toward `error` into `self.step`, holding every variable at a
    /// limit that the step pushes past (one more each pass, so at most k passes), scaled so
    /// that no variable moves more than [`MAX_STEP`]; returns the largest change.
    fn bounded_step(&mut self, error: &Vector3<f64>) -> f64 {
        self.free.fill(true);
        for _ in 0..self.variables.len() {
            let mut normal = Matrix3::identity() * (DAMPING * DAMPING);
            for (i, &k) in self.variables.iter().enumerate() {
                if self.free[i] {
                    let c = self.column(k);
                    normal += c * c.transpose();
                }
            }
            // The damping keeps `normal` positive definite.
            let y = normal.cholesky().map_or(Vector3::zeros(), |c| c.solve(error));
            let mut blocked = false;
            for (i, &k) in self.variables.iter().enumerate() {
                self.step[i] = if self.free[i] { self.column(k).dot(&y) } else { 0.0 };
                let at_lower = self.q[k] <= self.lower[i] && self.step[i] < 0.0;
                let at_upper = self.q[k] >= self.upper[i] && self.step[i] > 0.0;
                if at_lower || at_upper {
                    self.free[i] = false;
                    blocked = true;
                }
            }
            if !blocked {
                break;
            }
        }
        let largest = self.step.iter().fold(0.0_f64, |m, s| m.max(s.abs()));
        if largest > MAX_STEP {
            self.step.iter_mut().for_each(|s| *s *= MAX_STEP / largest);
        }
        largest.min(MAX_STEP)
    }

    /// The hand's Jacobian column of variable `k`.
    fn column(&self, k: usize) -> Vector3<f64> {
        Vector3::new(self.jacobian[(0, k)], self.jacobian[(1, k)], self.jacobian[(2, k)])
    }
}

/// The spread starts over the ranges `[lower, upper]` of an arm's variables: each of the first
/// three (the shoulder's, in a chain from the body) at a quarter and at three quarters of its
/// range, the rest at the middle, and the middle of every range: `2^min(k, 3) + 1` starts.
fn spread(lower: &[f64], upper: &[f64]) -> Vec<Vec<f64>> {
    let at = |i: usize, t: f64| lower[i] + t * (upper[i] - lower[i]);
    let varied = lower.len().min(3);
    let mut starts: Vec<Vec<f64>> = (0..1usize << varied)
        .map(|corner| {
            (0..lower.len())
                .map(|i| match i < varied {
                    true => at(i, if corner >> i & 1 == 1 { 0.75 } else { 0.25 }),
                    false => at(i, 0.5),
                })
                .collect()
        })
        .collect();
    starts.push((0..lower.len()).map(|i| at(i, 0.5)).collect());
    starts
}
