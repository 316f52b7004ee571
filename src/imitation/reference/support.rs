//! Which of the human's feet support the body (Poubel §III.A), detected online frame by frame.
//!
//! # Foot height and speed
//!
//! For each foot the *sole point* is the lower of the ankle and toe joints (whichever the source
//! reports). Its height is measured above the **local ground** `g(x, y)` under it:
//! `h = z_sole − g(x_sole, y_sole)`. Its speed is the smaller of the ankle's and the toe's
//! horizontal speeds, each measured over a sliding window ([`SupportConfig::speed_window`]):
//! `v = |xy(t) − xy(t − w)| / w`, using the newest stored sample at least `w` old. A window rather
//! than a frame-to-frame difference, because marker and Kinect jitter make frame differences of a
//! planted foot reach 1–2 m/s; the minimum over the two points, because a foot rolling over its
//! heel (ankle still) or its toes (toe still) is still standing.
//!
//! # Hysteresis
//!
//! A foot goes into support when `h < height_on` and `v < speed_on`, and leaves it when
//! `h > height_off` or `v > speed_off` (`on < off`), each condition having to hold for
//! [`SupportConfig::min_dwell`] seconds of frame time before the state flips. The first frame
//! decides from the height alone.
//!
//! # Ground
//!
//! Floors are not level (the CMU walks rise 7–10 cm over 4 m) and Kinect heights are relative to
//! a possibly tilted sensor, so the ground is learnt from the data. While a foot is in support
//! and also meets the going-into-support condition (a confident contact), its sole point is
//! recorded (at most every [`SupportConfig::ground_sample_interval`] s, in a ring
//! of [`GROUND_SAMPLES`]). The ground under a point `q` is the height at `q` of the plane
//! `z = a + b·(x − q_x) + c·(y − q_y)` fitted by weighted least squares to the samples, with
//! Gaussian weights `w_i = exp(−d_i² / 2σ²) + ε` on the horizontal distance `d_i` to `q`
//! (`σ` = [`SupportConfig::ground_radius`]; `ε` = 1e−9 keeps far samples as a last resort) and a
//! ridge `λ·Σw·(b² + c²)` ([`SupportConfig::ground_slope_ridge`]) so collinear samples (a
//! straight walk) leave the crosswise slope at zero instead of undetermined. Before any sample,
//! the ground is the lowest sole point of the first frame. Heights are thus measured from where
//! the sole point rests when standing, which also absorbs the height of the toe joint above the
//! real floor.
//!
//! # Cost
//!
//! All state is in fixed-size arrays: [`SupportDetector::update`] never allocates.

use nalgebra::{Matrix3, Vector2, Vector3};

use crate::human::{CaptureSystem, HumanFrame, Side};

/// Which feet support the human in one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HumanSupport {
    /// Both feet on the ground (DS).
    Double,
    /// Only the right foot (RS).
    Right,
    /// Only the left foot (LS).
    Left,
    /// Neither foot (a jump, or both feet unknown); a robot keeps its last support.
    Airborne,
}

impl HumanSupport {
    /// The phase given which feet are in support.
    pub const fn from_feet(left: bool, right: bool) -> Self {
        match (left, right) {
            (true, true) => HumanSupport::Double,
            (false, true) => HumanSupport::Right,
            (true, false) => HumanSupport::Left,
            (false, false) => HumanSupport::Airborne,
        }
    }

    /// Which feet are in support, `[left, right]` ([`Side::index`] order): the inverse of
    /// [`HumanSupport::from_feet`].
    pub const fn feet(self) -> [bool; 2] {
        match self {
            HumanSupport::Double => [true, true],
            HumanSupport::Right => [false, true],
            HumanSupport::Left => [true, false],
            HumanSupport::Airborne => [false, false],
        }
    }
}

/// Thresholds of the support detector. Distances in metres, speeds in m/s, times in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupportConfig {
    /// A foot may go into support when its sole point is less than this above the ground.
    pub height_on: f64,
    /// A foot leaves support when its sole point is more than this above the ground.
    pub height_off: f64,
    /// A foot may go into support when its horizontal speed is under this.
    pub speed_on: f64,
    /// A foot leaves support when its horizontal speed is over this.
    pub speed_off: f64,
    /// Window over which speeds are measured.
    pub speed_window: f64,
    /// How long a switching condition must hold before the foot's state flips.
    pub min_dwell: f64,
    /// Width σ of the Gaussian weighting of ground samples by horizontal distance.
    pub ground_radius: f64,
    /// Ridge λ on the fitted ground slope, in m² (see the module docs).
    pub ground_slope_ridge: f64,
    /// Least time between two ground samples of the same foot.
    pub ground_sample_interval: f64,
}

impl SupportConfig {
    /// Defaults for optical motion capture (CMU, 120 Hz, millimetre noise). Tuned on the CMU
    /// clips: a planted foot's sole point stays within ~2 cm of the learnt ground and moves under
    /// 0.2 m/s over 50 ms, a swinging foot moves at 1.5–3.5 m/s and a lifted foot is 0.1–0.4 m
    /// up, while a landing foot still slides at 0.3–0.5 m/s as it rolls flat (hence an on speed
    /// above that, or the walks show airborne gaps at each landing): on below 5 cm and 0.6 m/s,
    /// off above 8 cm or 1.0 m/s, 50 ms window, 30 ms dwell.
    pub const fn optical() -> Self {
        SupportConfig {
            height_on: 0.05,
            height_off: 0.08,
            speed_on: 0.6,
            speed_off: 1.0,
            speed_window: 0.05,
            min_dwell: 0.03,
            ground_radius: 0.75,
            ground_slope_ridge: 0.05,
            ground_sample_interval: 0.05,
        }
    }

    /// Defaults for Kinect v2 (30 Hz, centimetre noise, foot joints jumping by 5 cm): the
    /// paper's 200 mm height threshold as the off level (on below 150 mm), speeds on below
    /// 0.5 m/s and off above 1.0 m/s over 0.2 s, 70 ms dwell (two frames).
    pub const fn kinect() -> Self {
        SupportConfig {
            height_on: 0.15,
            height_off: 0.20,
            speed_on: 0.5,
            speed_off: 1.0,
            speed_window: 0.2,
            min_dwell: 0.07,
            ground_radius: 0.75,
            ground_slope_ridge: 0.05,
            ground_sample_interval: 0.1,
        }
    }

    /// The defaults for motion captured with `system`: [`SupportConfig::optical`] or
    /// [`SupportConfig::kinect`].
    pub const fn for_capture(system: CaptureSystem) -> Self {
        match system {
            CaptureSystem::Optical => Self::optical(),
            CaptureSystem::DepthCamera => Self::kinect(),
        }
    }

    fn validate(&self) -> Result<(), SupportError> {
        let positive = [
            (self.height_off, "height_off"),
            (self.speed_on, "speed_on"),
            (self.speed_window, "speed_window"),
            (self.ground_radius, "ground_radius"),
        ];
        for (value, name) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(SupportError::Config(name, "must be finite and positive"));
            }
        }
        let non_negative = [
            (self.min_dwell, "min_dwell"),
            (self.ground_slope_ridge, "ground_slope_ridge"),
            (self.ground_sample_interval, "ground_sample_interval"),
        ];
        for (value, name) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(SupportError::Config(
                    name,
                    "must be finite and non-negative",
                ));
            }
        }
        if !(self.height_on.is_finite() && self.height_on <= self.height_off) {
            return Err(SupportError::Config(
                "height_on",
                "must be finite and ≤ height_off",
            ));
        }
        if !(self.speed_off.is_finite() && self.speed_on <= self.speed_off) {
            return Err(SupportError::Config(
                "speed_off",
                "must be finite and ≥ speed_on",
            ));
        }
        Ok(())
    }
}

/// Errors of the support detector.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SupportError {
    /// A [`SupportConfig`] field is out of range.
    #[error("support config: {0} {1}")]
    Config(&'static str, &'static str),
}

/// What the detector measured for one foot in the last frame. Values are always finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootStatus {
    /// Whether the foot is in support.
    pub in_support: bool,
    /// Height of the sole point above the local ground, metres (`None`: foot joints missing, or
    /// no finite ground estimate).
    pub height: Option<f64>,
    /// Horizontal speed, m/s (`None`: foot joints missing or no earlier sample yet); saturates
    /// at `f64::MAX` for absurd input.
    pub speed: Option<f64>,
}

/// Number of past positions kept per foot point for speed windows: a 0.2 s window fits up to
/// 320 Hz; at higher rates the window shrinks to this many frames.
pub const SPEED_HISTORY: usize = 64;

/// Number of ground samples kept (the oldest is overwritten).
pub const GROUND_SAMPLES: usize = 64;

/// A fixed-capacity ring buffer, newest last.
#[derive(Clone, Copy, Debug)]
struct Ring<T: Copy, const N: usize> {
    items: [T; N],
    len: usize,
    next: usize,
}

impl<T: Copy, const N: usize> Ring<T, N> {
    fn new(fill: T) -> Self {
        Ring {
            items: [fill; N],
            len: 0,
            next: 0,
        }
    }

    fn push(&mut self, item: T) {
        self.items[self.next] = item;
        self.next = (self.next + 1) % N;
        self.len = (self.len + 1).min(N);
    }

    fn clear(&mut self) {
        self.len = 0;
        self.next = 0;
    }

    /// Items from newest to oldest.
    fn newest_first(&self) -> impl Iterator<Item = &T> {
        (1..=self.len).map(move |k| &self.items[(self.next + N - k) % N])
    }
}

/// Past (time, horizontal position) of one foot point.
type PointHistory = Ring<(f64, Vector2<f64>), SPEED_HISTORY>;

#[derive(Clone, Copy, Debug)]
struct Foot {
    in_support: bool,
    /// Frame time at which the condition to switch state started holding.
    switch_since: Option<f64>,
    ankle: PointHistory,
    toe: PointHistory,
    last_sample: f64,
    status: FootStatus,
}

/// Online support detector: feed it every frame in time order with [`SupportDetector::update`].
#[derive(Clone, Debug)]
pub struct SupportDetector {
    config: SupportConfig,
    feet: [Foot; 2],
    ground: Ring<Vector3<f64>, GROUND_SAMPLES>,
    last_time: Option<f64>,
    support: HumanSupport,
}

impl SupportDetector {
    /// A detector with `config`; errors if a threshold is out of range.
    pub fn new(config: SupportConfig) -> Result<Self, SupportError> {
        config.validate()?;
        let foot = Foot {
            in_support: false,
            switch_since: None,
            ankle: Ring::new((0.0, Vector2::zeros())),
            toe: Ring::new((0.0, Vector2::zeros())),
            last_sample: f64::NEG_INFINITY,
            status: FootStatus {
                in_support: false,
                height: None,
                speed: None,
            },
        };
        Ok(SupportDetector {
            config,
            feet: [foot; 2],
            ground: Ring::new(Vector3::zeros()),
            last_time: None,
            support: HumanSupport::Airborne,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SupportConfig {
        &self.config
    }

    /// The support phase of the last frame (`Airborne` before the first).
    pub fn support(&self) -> HumanSupport {
        self.support
    }

    /// What was measured for `side`'s foot in the last frame.
    pub fn foot(&self, side: Side) -> FootStatus {
        self.feet[side.index()].status
    }

    /// Estimated ground height (metres, frame z) under the horizontal point `(x, y)`, or `None`
    /// before the first frame with a foot.
    pub fn ground_height(&self, x: f64, y: f64) -> Option<f64> {
        self.fit_ground(Vector2::new(x, y))
    }

    /// Takes the next frame and returns the support phase in it. A frame whose time is not
    /// finite changes nothing; a frame earlier than the previous one restarts the detector's
    /// memory of motion (speed histories), keeping the ground it learnt. A foot whose ankle and
    /// toe are both missing keeps its previous state.
    pub fn update(&mut self, frame: &HumanFrame) -> HumanSupport {
        let now = frame.time;
        if !now.is_finite() {
            return self.support;
        }
        let first = self.last_time.is_none();
        if self.last_time.is_some_and(|t| now < t) {
            for foot in &mut self.feet {
                foot.ankle.clear();
                foot.toe.clear();
                foot.switch_since = None;
            }
        }
        self.last_time = Some(now);
        if self.ground.len == 0 {
            self.seed_ground(frame);
        }
        for side in [Side::Left, Side::Right] {
            self.update_foot(side, frame, now, first);
        }
        self.support = HumanSupport::from_feet(self.feet[0].in_support, self.feet[1].in_support);
        self.support
    }

    /// Before any stance sample: the lowest sole point of this frame is the ground.
    fn seed_ground(&mut self, frame: &HumanFrame) {
        let lowest = [Side::Left, Side::Right]
            .into_iter()
            .filter_map(|side| sole_point(frame, side))
            .min_by(|a, b| a.z.total_cmp(&b.z));
        if let Some(p) = lowest {
            self.ground.push(p);
        }
    }

    fn update_foot(&mut self, side: Side, frame: &HumanFrame, now: f64, first: bool) {
        let config = self.config;
        let sole = sole_point(frame, side);
        let height = sole
            .and_then(|p| Some(p.z - self.fit_ground(p.xy())?))
            .filter(|h| h.is_finite());
        let foot = &mut self.feet[side.index()];
        let ankle = frame.get(side.ankle()).map(|p| p.xy());
        let toe = frame.get(side.toe()).map(|p| p.xy());
        let speed = [(&mut foot.ankle, ankle), (&mut foot.toe, toe)]
            .into_iter()
            .filter_map(|(history, point)| {
                let point = point?;
                let speed = windowed_speed(history, now, point, config.speed_window);
                history.push((now, point));
                // Absurd coordinates can overflow the difference; that foot is moving.
                speed.map(|v| if v.is_finite() { v } else { f64::MAX })
            })
            .min_by(f64::total_cmp);
        foot.status.height = height;
        foot.status.speed = speed;
        let Some(h) = height else {
            return;
        };
        let v = speed.unwrap_or(0.0);
        if first {
            foot.in_support = h < config.height_on;
        } else {
            let wants_switch = if foot.in_support {
                h > config.height_off || v > config.speed_off
            } else {
                h < config.height_on && v < config.speed_on
            };
            if wants_switch {
                let since = *foot.switch_since.get_or_insert(now);
                if now - since >= config.min_dwell {
                    foot.in_support = !foot.in_support;
                    foot.switch_since = None;
                }
            } else {
                foot.switch_since = None;
            }
        }
        foot.status.in_support = foot.in_support;
        // Only confident contacts teach the ground: a foot kept in support by hysteresis while
        // hovering between the on and off heights would otherwise raise the ground under itself.
        if foot.in_support
            && h < config.height_on
            && v < config.speed_on
            && now - foot.last_sample >= config.ground_sample_interval
            && let Some(p) = sole
        {
            foot.last_sample = now;
            self.ground.push(p);
        }
    }

    /// Weighted ridge-regularised plane fit of the ground samples around `q` (module docs).
    fn fit_ground(&self, q: Vector2<f64>) -> Option<f64> {
        if self.ground.len == 0 {
            return None;
        }
        let two_sigma_sq = 2.0 * self.config.ground_radius * self.config.ground_radius;
        let mut normal = Matrix3::zeros();
        let mut rhs = Vector3::zeros();
        let mut total = 0.0;
        for s in self.ground.newest_first() {
            let d = s.xy() - q;
            let w = (-d.norm_squared() / two_sigma_sq).exp() + 1e-9;
            let row = Vector3::new(1.0, d.x, d.y);
            normal += row * row.transpose() * w;
            rhs += row * (w * s.z);
            total += w;
        }
        let ridge = self.config.ground_slope_ridge * total;
        normal[(1, 1)] += ridge;
        normal[(2, 2)] += ridge;
        let weighted_mean = rhs[0] / total;
        // With a zero ridge and collinear samples the system is singular; the weighted mean
        // height is then the honest answer.
        let height = normal
            .cholesky()
            .map(|c| c.solve(&rhs)[0])
            .filter(|h| h.is_finite())
            .unwrap_or(weighted_mean);
        height.is_finite().then_some(height)
    }
}

/// The lower of the foot's ankle and toe joints.
fn sole_point(frame: &HumanFrame, side: Side) -> Option<Vector3<f64>> {
    match (frame.get(side.ankle()), frame.get(side.toe())) {
        (Some(a), Some(t)) => Some(if a.z <= t.z { a } else { t }),
        (a, t) => a.or(t),
    }
}

/// Horizontal speed of `point` at `now` against the newest sample at least `window` older
/// (the oldest one if none is that old); `None` without an earlier sample.
fn windowed_speed(
    history: &PointHistory,
    now: f64,
    point: Vector2<f64>,
    window: f64,
) -> Option<f64> {
    let mut reference = None;
    for &(t, p) in history.newest_first() {
        if t < now {
            reference = Some((t, p));
            if now - t >= window {
                break;
            }
        }
    }
    let (t, p) = reference?;
    Some((point - p).norm() / (now - t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ring_keeps_the_newest_items() {
        let mut ring: Ring<i32, 3> = Ring::new(0);
        for k in 1..=5 {
            ring.push(k);
        }
        let items: Vec<i32> = ring.newest_first().copied().collect();
        assert_eq!(items, vec![5, 4, 3]);
    }

    #[test]
    fn ground_fit_recovers_a_sloped_plane() {
        // Samples on z = 0.1 + 0.02·x + 0.01·y spread over 2 m in x and y: the fitted height at
        // (1, 1) is 0.1 + 0.02 + 0.01 = 0.13 (up to the small ridge bias).
        let mut detector = SupportDetector::new(SupportConfig {
            ground_slope_ridge: 0.0,
            ..SupportConfig::optical()
        })
        .unwrap();
        for i in 0..5 {
            for j in 0..5 {
                let (x, y) = (0.5 * i as f64, 0.5 * j as f64);
                detector
                    .ground
                    .push(Vector3::new(x, y, 0.1 + 0.02 * x + 0.01 * y));
            }
        }
        let h = detector.ground_height(1.0, 1.0).unwrap();
        assert!((h - 0.13).abs() < 1e-12, "{h}");
    }
}
