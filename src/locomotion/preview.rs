//! ZMP preview control of the cart-table model (Kajita et al. 2003).
//!
//! Per horizontal axis the state is `x = [c, ċ, c̈]` (CoM position m, velocity m/s, acceleration
//! m/s²) and the input the CoM jerk `u` (m/s³), held over one tick `T` (s):
//!
//! ```text
//! x_{k+1} = A x_k + B u_k,   A = [1 T T²/2; 0 1 T; 0 0 1],   B = [T³/6; T²/2; T]
//! p_k     = C x_k,           C = [1 0 −z_c/g]        (the cart-table ZMP, m)
//! ```
//!
//! The controller minimises `Σ_i Q (p_i − p*_i)² + R u_i²` over an infinite horizon. With `P` the
//! stabilising solution of the discrete algebraic Riccati equation
//! `P = AᵀPA + CᵀQC − AᵀPB (R + BᵀPB)⁻¹ BᵀPA`, the optimal jerk is
//!
//! ```text
//! u_k = −K x_k + Σ_{j=1..N} f_j p*_{k+j},
//! K   = (R + BᵀPB)⁻¹ BᵀPA,
//! f_j = (R + BᵀPB)⁻¹ Bᵀ ((A − BK)ᵀ)^{j−1} CᵀQ,
//! ```
//!
//! exact for a reference that is zero after the `N`-tick preview window; the gains decay
//! geometrically, so a window of a few pendulum time constants `1/ω = √(z_c/g)` loses nothing.
//! The gains depend only on `(z_c, T, Q, R, N)`: computed once per robot and tick.

use nalgebra::{Matrix3, Vector3};

use super::LocomotionError;

/// Gravity (m/s²).
pub const GRAVITY: f64 = 9.81;

/// The discrete cart-table model of one axis: `A`, `B`, `C` of the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CartTable {
    /// State transition over one tick.
    pub a: Matrix3<f64>,
    /// Input (jerk) column.
    pub b: Vector3<f64>,
    /// ZMP output row, as a column.
    pub c: Vector3<f64>,
    /// Tick (s).
    pub dt: f64,
    /// CoM height above the floor (m).
    pub com_height: f64,
}

impl CartTable {
    /// The model for a CoM at `com_height` (m, > 0) above the floor, ticking every `dt` (s, > 0).
    ///
    /// # Errors
    /// [`LocomotionError::InvalidParameter`] for a non-finite or non-positive value.
    pub fn new(com_height: f64, dt: f64) -> Result<Self, LocomotionError> {
        positive("com_height", com_height)?;
        positive("dt", dt)?;
        let t = dt;
        #[rustfmt::skip]
        let a = Matrix3::new(
            1.0, t, t * t / 2.0,
            0.0, 1.0, t,
            0.0, 0.0, 1.0,
        );
        Ok(Self {
            a,
            b: Vector3::new(t * t * t / 6.0, t * t / 2.0, t),
            c: Vector3::new(1.0, 0.0, -com_height / GRAVITY),
            dt,
            com_height,
        })
    }

    /// The ZMP (m) of state `x`: `C x = c − z_c/g · c̈`.
    pub fn zmp(&self, x: &Vector3<f64>) -> f64 {
        self.c.dot(x)
    }

    /// The pendulum's natural frequency `ω = √(g / z_c)` (1/s).
    pub fn omega(&self) -> f64 {
        (GRAVITY / self.com_height).sqrt()
    }
}

/// The weights of the preview cost and its window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreviewSettings {
    /// Weight of the ZMP error (1/m²). Default 1.
    pub q: f64,
    /// Weight of the jerk (s⁶/m²). Default 1e-6 (Kajita et al.): the ZMP follows its reference
    /// within millimetres.
    pub r: f64,
    /// Length of the preview window (s). Default 1.6 s.
    pub horizon: f64,
}

impl Default for PreviewSettings {
    fn default() -> Self {
        Self {
            q: 1.0,
            r: 1e-6,
            horizon: 1.6,
        }
    }
}

/// The optimal preview controller of a [`CartTable`]: state gain `K` and preview gains `f_j`.
#[derive(Debug, Clone, PartialEq)]
pub struct PreviewGains {
    model: CartTable,
    /// Riccati solution `P`.
    riccati: Matrix3<f64>,
    /// State feedback `K` (as a column; `u = −K·x`).
    state: Vector3<f64>,
    /// `f_1 … f_N`: the gain on the reference `j` ticks ahead is `preview[j − 1]`.
    preview: Vec<f64>,
}

/// Iteration cap and relative tolerance of the Riccati fixed point.
const RICCATI_ITERATIONS: usize = 200_000;
const RICCATI_TOLERANCE: f64 = 1e-13;

impl PreviewGains {
    /// Solves the Riccati equation of `model` with `settings` and builds the gains; the window
    /// has `N = round(horizon / dt)` ticks (at least one).
    ///
    /// # Errors
    /// [`LocomotionError::InvalidParameter`] for a weight that is not finite and > 0 or a
    /// horizon that is not; [`LocomotionError::RiccatiDiverged`] when the fixed-point iteration
    /// does not converge (it does for every positive weight: the pair (A, B) is controllable
    /// and (A, C) observable).
    pub fn new(model: CartTable, settings: PreviewSettings) -> Result<Self, LocomotionError> {
        positive("q", settings.q)?;
        positive("r", settings.r)?;
        positive("horizon", settings.horizon)?;
        let riccati = solve_riccati(&model, settings.q, settings.r)?;
        let (a, b, c) = (model.a, model.b, model.c);
        let denominator = settings.r + b.dot(&(riccati * b));
        let state = (a.transpose() * riccati * b) / denominator;
        let closed_loop_t = (a - b * state.transpose()).transpose();
        let n = ((settings.horizon / model.dt).round() as usize).max(1);
        let mut preview = Vec::with_capacity(n);
        let mut propagated = c * settings.q; // ((A − BK)ᵀ)^{j−1} CᵀQ
        for _ in 0..n {
            preview.push(b.dot(&propagated) / denominator);
            propagated = closed_loop_t * propagated;
        }
        Ok(Self {
            model,
            riccati,
            state,
            preview,
        })
    }

    /// The model the gains were computed for.
    pub fn model(&self) -> &CartTable {
        &self.model
    }

    /// The Riccati solution `P`.
    pub fn riccati(&self) -> &Matrix3<f64> {
        &self.riccati
    }

    /// The state gain `K`: the jerk's feedback is `−K·x`.
    pub fn state_gain(&self) -> &Vector3<f64> {
        &self.state
    }

    /// The preview gains `f_1 … f_N` (1/s³): `preview()[j − 1]` weighs the reference `j`
    /// ticks ahead.
    pub fn preview(&self) -> &[f64] {
        &self.preview
    }

    /// The window length `N` (ticks).
    pub fn window(&self) -> usize {
        self.preview.len()
    }

    /// The optimal jerk (m/s³) for state `x` and the reference `future[j − 1]` `j` ticks ahead
    /// (`future` holds at least [`PreviewGains::window`] values; extra ones are ignored).
    pub fn jerk(&self, x: &Vector3<f64>, future: &[f64]) -> f64 {
        let feedforward: f64 = self.preview.iter().zip(future).map(|(f, p)| f * p).sum();
        feedforward - self.state.dot(x)
    }
}

/// The stabilising solution of the discrete Riccati equation, by fixed-point iteration from
/// `CᵀQC`.
fn solve_riccati(model: &CartTable, q: f64, r: f64) -> Result<Matrix3<f64>, LocomotionError> {
    let (a, b, c) = (model.a, model.b, model.c);
    let output = c * c.transpose() * q;
    let mut p = output;
    for _ in 0..RICCATI_ITERATIONS {
        let pb = p * b;
        let pa = a.transpose() * p * a;
        let apb = a.transpose() * pb;
        let next = pa + output - apb * apb.transpose() / (r + b.dot(&pb));
        let change = (next - p).abs().max();
        p = next;
        if !p.iter().all(|v| v.is_finite()) {
            break;
        }
        if change <= RICCATI_TOLERANCE * p.abs().max().max(f64::MIN_POSITIVE) {
            return Ok(p);
        }
    }
    Err(LocomotionError::RiccatiDiverged)
}

pub(super) fn positive(name: &'static str, value: f64) -> Result<(), LocomotionError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(LocomotionError::InvalidParameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}
