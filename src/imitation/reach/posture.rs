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
//! column left out; a step that does not bring the hand nearer is halved). The steps start
//! from the frame's own posture, then from the last frame's best arm posture, then from the
//! samples of a grid over the arm's joint ranges whose hands lie nearest the reference
//! ([`Grid`], computed once), and stop at the first start that brings the hand within
//! [`REACHED`]. A posture counts only when the caller accepts it (the meter requires the
//! profile's self-collision margin).
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
const ITERATIONS: usize = 100;

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
const PROGRESS: f64 = 1e-6;

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
    /// The arm's joint space sampled on a grid ([`Grid`]): seeds for the search.
    grid: Grid,
    /// The last frame's best arm posture and its error (m), when it had one.
    last_best: Option<Vec<f64>>,
    last_least: f64,
    /// Searched frames since the spread starts were last tried.
    since_spread: usize,
    /// The posture being solved (every variable), and the one before the last step.
    q: Vec<f64>,
    previous: Vec<f64>,
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
            variables
                .iter()
                .map(|&k| f(&model.variables()[k]))
                .collect()
        };
        let (lower, upper) = (range(|v| v.lower), range(|v| v.upper));
        let k = variables.len();
        Some(Self {
            hand,
            grid: Grid::of(model, stand, upper_body, hand, &variables)?,
            lower,
            upper,
            variables,
            last_best: None,
            last_least: f64::INFINITY,
            since_spread: 0,
            q: stand.to_vec(),
            previous: stand.to_vec(),
            best: vec![0.0; k],
            jacobian: Mat::zeros(3, model.nv()),
            free: vec![true; k],
            step: vec![0.0; k],
        })
    }

    /// The least distance (m) from `target` (model base frame, m) to which some posture of
    /// the arm brings the hand, the other variables at `frame_q`, among the postures that
    /// `accept` (called with the forward kinematics of the posture in `data`) accepts; `None`
    /// when the search found none or the kinematics failed. Overwrites `data`.
    pub(super) fn least_error(
        &mut self,
        model: &Model,
        data: &mut ModelData,
        frame_q: &[f64],
        target: &Vector3<f64>,
        mut accept: impl FnMut(&Model, &ModelData) -> bool,
    ) -> Option<f64> {
        let mut least: Option<f64> = None;
        let reached = |least: Option<f64>| least.is_some_and(|l| l <= REACHED);
        for start in [Start::Own, Start::LastBest] {
            if !reached(least) {
                self.try_start(model, data, frame_q, target, start, &mut least, &mut accept);
            }
        }
        if !reached(least) && self.spread_now(least) {
            model.forward_kinematics(data, frame_q).ok()?;
            let body = data.frame_placement(self.grid.upper_body);
            let in_body = body.inverse_transform_point(&(*target).into()).coords;
            for seed in self.grid.nearest(&in_body) {
                if !reached(least) {
                    let start = Start::Seed(seed);
                    self.try_start(model, data, frame_q, target, start, &mut least, &mut accept);
                }
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

    /// One descent from `start` (the arm's variables; every other at `frame_q`); a result
    /// nearer than `least` that `accept` accepts becomes `least` and the frame's best posture.
    /// Nothing when `start` is the last best and there is none, or when the kinematics fails.
    #[allow(clippy::too_many_arguments)]
    fn try_start(
        &mut self,
        model: &Model,
        data: &mut ModelData,
        frame_q: &[f64],
        target: &Vector3<f64>,
        start: Start,
        least: &mut Option<f64>,
        accept: &mut impl FnMut(&Model, &ModelData) -> bool,
    ) {
        self.q.copy_from_slice(frame_q);
        let values = match start {
            Start::Own => &[][..],
            Start::LastBest => match &self.last_best {
                Some(values) => values.as_slice(),
                None => return,
            },
            Start::Seed(i) => self.grid.values(i),
        };
        for (&k, &v) in self.variables.iter().zip(values) {
            self.q[k] = v;
        }
        let Some(error) = self.descend(model, data, target) else {
            return;
        };
        if least.is_none_or(|l| error < l) && accept(model, data) {
            *least = Some(error);
            for (b, &k) in self.best.iter_mut().zip(&self.variables) {
                *b = self.q[k];
            }
        }
    }

    /// Forgets the last frame's best posture (a frame without a reference broke the series).
    pub(super) fn forget(&mut self) {
        self.last_best = None;
    }

    /// Whether to try the grid's seeds after the frame's own posture and the last frame's
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

    /// Damped Gauss–Newton steps from `self.q` toward `target`, each halved until it brings
    /// the hand nearer (a full step overshoots where the arm's motion bends away from its
    /// first-order model); the hand's final distance (m), with `data` at the final posture;
    /// `None` when the kinematics fails.
    fn descend(
        &mut self,
        model: &Model,
        data: &mut ModelData,
        target: &Vector3<f64>,
    ) -> Option<f64> {
        let mut error = self.hand_error(model, data, target)?;
        let mut scale = 1.0;
        for _ in 0..ITERATIONS {
            if error.norm() <= REACHED {
                break;
            }
            model
                .point_jacobian(data, self.hand, &Vector3::zeros(), self.jacobian.as_mut())
                .ok()?;
            if self.bounded_step(&error) * scale < STALLED {
                break;
            }
            self.previous.copy_from_slice(&self.q);
            for (i, &k) in self.variables.iter().enumerate() {
                let moved = self.q[k] + scale * self.step[i];
                self.q[k] = moved.clamp(self.lower[i], self.upper[i]);
            }
            let trial = self.hand_error(model, data, target)?;
            if trial.norm() < error.norm() {
                let gain = error.norm() - trial.norm();
                error = trial;
                scale = (2.0 * scale).min(1.0);
                if gain < PROGRESS {
                    break;
                }
            } else {
                self.q.copy_from_slice(&self.previous);
                error = self.hand_error(model, data, target)?;
                scale *= 0.5;
            }
        }
        Some(error.norm())
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
            let y = normal
                .cholesky()
                .map_or(Vector3::zeros(), |c| c.solve(error));
            let mut blocked = false;
            for (i, &k) in self.variables.iter().enumerate() {
                self.step[i] = if self.free[i] {
                    self.column(k).dot(&y)
                } else {
                    0.0
                };
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
        Vector3::new(
            self.jacobian[(0, k)],
            self.jacobian[(1, k)],
            self.jacobian[(2, k)],
        )
    }
}

/// Where a descent of [`ArmPostures::least_error`] starts.
#[derive(Debug, Clone, Copy)]
enum Start {
    /// The frame's own posture.
    Own,
    /// The last frame's best arm posture.
    LastBest,
    /// Sample `i` of the [`Grid`].
    Seed(usize),
}

/// The joint space of an arm sampled on a grid: `n` values over each variable's range, ends
/// included, with `n^k ≤` [`GRID_POINTS`] (at least 2; beyond 12 variables, the ends of the
/// first 12 and the middle of the others), and the hand's position in the upper body's frame
/// at each. The arm's variables are all that move the hand relative to that
/// frame, so the positions hold in every posture of the rest of the body.
#[derive(Debug, Clone)]
struct Grid {
    upper_body: FrameId,
    /// The hand's position (upper body frame, m) per sample.
    points: Vec<Vector3<f64>>,
    /// The arm's variables per sample, `k` a row.
    values: Vec<f64>,
    k: usize,
}

/// Largest number of samples of an arm's joint space ([`Grid`]): 5 values a variable for the
/// NAO's 5 arm variables, 3 for the G1's 7.
const GRID_POINTS: usize = 4096;

/// Samples nearest the reference that seed the search ([`Grid::nearest`]).
const GRID_SEEDS: usize = 4;

impl Grid {
    fn of(
        model: &Model,
        stand: &[f64],
        upper_body: FrameId,
        hand: FrameId,
        variables: &[usize],
    ) -> Option<Self> {
        let k = variables.len();
        let fits = |n: usize, m: usize| n.checked_pow(m as u32).is_some_and(|c| c <= GRID_POINTS);
        // `n` values over each of the first `varied` variables, the rest at mid-range: an arm
        // of more than log2(GRID_POINTS) variables is sampled at the ends of its first ones.
        let varied = (0..=k).take_while(|&m| fits(2, m)).last().unwrap_or(0);
        let n = (2..).take_while(|&n| fits(n, varied)).last().unwrap_or(2);
        let count = n.pow(varied as u32);
        let mut data = model.new_data();
        let mut q = stand.to_vec();
        let mut grid = Grid {
            upper_body,
            points: Vec::with_capacity(count),
            values: Vec::with_capacity(count * k),
            k,
        };
        for cell in 0..count {
            for (j, &v) in variables.iter().enumerate() {
                let var = &model.variables()[v];
                let t = match j < varied {
                    true => (cell / n.pow(j as u32) % n) as f64 / (n - 1) as f64,
                    false => 0.5,
                };
                q[v] = var.lower + t * (var.upper - var.lower);
                grid.values.push(q[v]);
            }
            model.forward_kinematics(&mut data, &q).ok()?;
            let p = data.frame_placement(hand).translation.vector;
            let body = data.frame_placement(upper_body);
            grid.points
                .push(body.inverse_transform_point(&p.into()).coords);
        }
        Some(grid)
    }

    /// The [`GRID_SEEDS`] samples whose hand lies nearest `target` (upper body frame, m),
    /// nearest first.
    fn nearest(&self, target: &Vector3<f64>) -> [usize; GRID_SEEDS] {
        let mut best = [(f64::INFINITY, 0); GRID_SEEDS];
        for (i, p) in self.points.iter().enumerate() {
            let d = (p - target).norm_squared();
            if d < best[GRID_SEEDS - 1].0 {
                best[GRID_SEEDS - 1] = (d, i);
                best.sort_by(|a, b| a.0.total_cmp(&b.0));
            }
        }
        best.map(|(_, i)| i)
    }

    /// The arm's variables of sample `i`.
    fn values(&self, i: usize) -> &[f64] {
        &self.values[i * self.k..(i + 1) * self.k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robots::nao;

    /// The planar 3R arm of `tests/data/planar3r.toml` (links 0.3, 0.2, 0.1 m in the x–y
    /// plane, all axes z) with the given ranges of its three variables, and a frame on its base.
    fn planar(ranges: [[f64; 2]; 3]) -> (Model, FrameId, FrameId) {
        let mut text = include_str!("../../../tests/data/planar3r.toml").to_owned();
        for (i, [lo, hi]) in ranges.iter().enumerate() {
            let name = format!("name = \"q{}\"\nlower = -3.0\nupper = 3.0", i + 1);
            let with = format!("name = \"q{}\"\nlower = {lo:?}\nupper = {hi:?}", i + 1);
            assert!(text.contains(&name));
            text = text.replace(&name, &with);
        }
        text.push_str(
            "\n[[frames]]\nname = \"base\"\nlink = \"ground\"\nposition = [0.0, 0.0, 0.0]\n",
        );
        let model = Model::from_dh_str(&text, "planar test arm").unwrap();
        let (base, tip) = (
            model.frame_id("base").unwrap(),
            model.frame_id("tip").unwrap(),
        );
        (model, base, tip)
    }

    fn least(
        model: &Model,
        base: FrameId,
        tip: FrameId,
        q: &[f64],
        target: [f64; 3],
    ) -> Option<f64> {
        let mut arm = ArmPostures::of(model, q, base, tip).unwrap();
        let mut data = model.new_data();
        arm.least_error(model, &mut data, q, &target.into(), |_, _| true)
    }

    /// Beyond the stretched arm (0.6 m) a target 0.8 m out is 0.2 m short, whatever the start.
    #[test]
    fn a_target_beyond_the_stretched_arm_is_its_distance_short() {
        let (model, base, tip) = planar([[-3.0, 3.0]; 3]);
        let found = least(&model, base, tip, &[2.0, 1.0, -1.5], [0.0, -0.8, 0.0]).unwrap();
        // No posture gets nearer; the straight arm is singular, so the damped steps stop a
        // hair short of it (the bound is from above).
        assert!((0.2 - 1e-12..0.2 + 1e-3).contains(&found), "{found}");
    }

    /// A target the arm reaches only by folding is reached from a start folded the other way.
    #[test]
    fn a_reachable_target_is_reached() {
        let (model, base, tip) = planar([[-3.0, 3.0]; 3]);
        let found = least(&model, base, tip, &[0.0, 0.0, 0.0], [-0.1, 0.25, 0.0]).unwrap();
        assert!(found <= REACHED, "{found}");
    }

    /// With the elbow and the wrist locked straight (ranges of 1e-12 rad move the tip less than
    /// the arm test sees) and the shoulder kept in [0, 0.5] rad, the tip runs on an arc of
    /// 0.6 m from 0 to 0.5 rad: a target on that circle at −0.5 rad is nearest the arc's end
    /// at 0, a chord of `2 · 0.6 · sin(0.25)` away.
    #[test]
    fn a_joint_limit_keeps_the_hand_on_its_arc() {
        let (model, base, tip) = planar([[0.0, 0.5], [0.0, 1e-12], [0.0, 1e-12]]);
        let arm = ArmPostures::of(&model, &[0.3, 0.0, 0.0], base, tip).unwrap();
        assert_eq!(arm.variables, [0]);
        let target = [0.6 * (-0.5f64).cos(), 0.6 * (-0.5f64).sin(), 0.0];
        let found = least(&model, base, tip, &[0.3, 0.0, 0.0], target).unwrap();
        let chord = 2.0 * 0.6 * 0.25f64.sin();
        assert!((found - chord).abs() < 1e-6, "{found} vs {chord}");
    }

    /// An arm of 20 revolute joints (a planar chain of 0.05 m links): the grid keeps to its
    /// size, the ends of the first 12 variables (4 096 samples), and the search still reaches
    /// a target in the chain's plane.
    #[test]
    fn a_long_arm_is_sampled_within_the_grid_size() {
        let mut text = String::from(
            "format = \"taskstack-dh/1\"\nname = \"chain\"\n[units]\nlength = \"m\"\nangle = \"rad\"\nmass = \"kg\"\n[base]\nlink = \"L0\"\nmass = 0.0\ncom = [0.0, 0.0, 0.0]\n",
        );
        for i in 1..=20 {
            text.push_str(&format!(
                "[[variables]]\nname = \"q{i}\"\nlower = -1.0\nupper = 1.0\nvelocity = 1.0\n\
                 [[joints]]\nname = \"J{i}\"\nantecedent = \"L{}\"\nlink = \"L{i}\"\n\
                 type = \"revolute\"\ngamma = 0.0\nb = 0.0\nalpha = 0.0\nd = {}\ntheta = 0.0\n\
                 r = 0.0\nvariable = \"q{i}\"\nmass = 0.1\ncom = [0.0, 0.0, 0.0]\n",
                i - 1,
                if i == 1 { 0.0 } else { 0.05 }
            ));
        }
        text.push_str("[[frames]]\nname = \"tip\"\nlink = \"L20\"\nposition = [0.05, 0.0, 0.0]\n");
        text.push_str("[[frames]]\nname = \"base\"\nlink = \"L0\"\nposition = [0.0, 0.0, 0.0]\n");
        let model = Model::from_dh_str(&text, "chain test arm").unwrap();
        let (base, tip) = (
            model.frame_id("base").unwrap(),
            model.frame_id("tip").unwrap(),
        );
        let q = vec![0.0; 20];
        let mut arm = ArmPostures::of(&model, &q, base, tip).unwrap();
        assert_eq!(arm.variables.len(), 20);
        assert_eq!(arm.grid.points.len(), GRID_POINTS);
        let mut data = model.new_data();
        let target = [0.6, 0.4, 0.0].into();
        let found = arm
            .least_error(&model, &mut data, &q, &target, |_, _| true)
            .unwrap();
        assert!(found <= REACHED, "{found}");
    }

    /// A posture the caller refuses does not count.
    #[test]
    fn a_refused_posture_is_not_counted() {
        let (model, base, tip) = planar([[-3.0, 3.0]; 3]);
        let q = [0.1, 0.2, 0.3];
        let mut arm = ArmPostures::of(&model, &q, base, tip).unwrap();
        let mut data = model.new_data();
        let target = [0.2, 0.2, 0.0].into();
        assert_eq!(
            arm.least_error(&model, &mut data, &q, &target, |_, _| false),
            None
        );
    }

    /// The NAO's left arm: the search ends at most 2 mm farther from each of a set of targets
    /// around the shoulder than the best posture of an exhaustive grid over the arm's variables
    /// (8 values each over their ranges), an independent search of the same joint space.
    #[test]
    fn the_search_finds_what_a_grid_over_the_nao_arm_finds() {
        let profile = nao::profile();
        let model = &profile.models[0];
        let frame = |name: &str| model.frame_id(name).unwrap();
        let hand = frame(&profile.hands[0]);
        let mut arm = ArmPostures::of(model, &profile.stand, frame(&profile.torso), hand).unwrap();
        assert!(
            (4..=5).contains(&arm.variables.len()),
            "{:?}",
            arm.variables
        );
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, &profile.stand).unwrap();
        let hand_at_rest = data.frame_placement(hand).translation.vector;
        let samples = 8usize;
        for i in 0..10 {
            let t = i as f64;
            let offset = Vector3::new((1.3 * t).sin(), (2.1 * t).cos(), (0.7 * t).sin()) * 0.12;
            let target = hand_at_rest + offset;
            let mut q = profile.stand.clone();
            let mut grid = f64::INFINITY;
            let k = arm.variables.len();
            for cell in 0..samples.pow(k as u32) {
                for (j, &v) in arm.variables.iter().enumerate() {
                    let step = cell / samples.pow(j as u32) % samples;
                    let frac = step as f64 / (samples - 1) as f64;
                    q[v] = arm.lower[j] + frac * (arm.upper[j] - arm.lower[j]);
                }
                model.forward_kinematics(&mut data, &q).unwrap();
                grid = grid.min((target - data.frame_placement(hand).translation.vector).norm());
            }
            arm.forget();
            let found = arm
                .least_error(model, &mut data, &profile.stand, &target, |_, _| true)
                .unwrap();
            assert!(
                found <= grid + 2e-3,
                "target {i}: search {found} m, grid {grid} m"
            );
        }
    }
}
