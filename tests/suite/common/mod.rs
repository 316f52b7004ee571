//! Helpers shared by the model tests: finite-difference checks of the Jacobians and random
//! configurations within the limits.

use faer::Mat;
use nalgebra::{IsometryMatrix3, Vector3};
use taskstack::model::{Axis, FrameId, Model, ModelData};

/// Step of the central differences (error O(h²) ≈ 1e-12 on these arm lengths).
pub const H: f64 = 1e-6;

/// `q` from unit-interval samples `u`, mapped into each variable's limits (infinite limits: ±π).
pub fn q_from_unit(model: &Model, u: &[f64]) -> Vec<f64> {
    model
        .variables()
        .iter()
        .zip(u)
        .map(|(v, &t)| {
            let lo = if v.lower.is_finite() {
                v.lower
            } else {
                -std::f64::consts::PI
            };
            let hi = if v.upper.is_finite() {
                v.upper
            } else {
                std::f64::consts::PI
            };
            lo + t * (hi - lo)
        })
        .collect()
}

fn fk(model: &Model, data: &mut ModelData, q: &[f64]) {
    model.forward_kinematics(data, q).expect("fk");
}

fn placement(model: &Model, q: &[f64], frame: FrameId) -> IsometryMatrix3<f64> {
    let mut data = model.new_data();
    fk(model, &mut data, q);
    *data.frame_placement(frame)
}

fn com(model: &Model, q: &[f64]) -> Vector3<f64> {
    let mut data = model.new_data();
    fk(model, &mut data, q);
    model.com(&data).expect("com")
}

/// Central difference of `f` along variable `k`.
fn diff<T>(
    q: &[f64],
    k: usize,
    f: impl Fn(&[f64]) -> T,
    d: impl Fn(&T, &T) -> Vector3<f64>,
) -> Vector3<f64> {
    let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
    qp[k] += H;
    qm[k] -= H;
    d(&f(&qp), &f(&qm)) / (2.0 * H)
}

/// Largest difference between every analytic Jacobian of `frame` (position of the point at
/// `offset`, its z row, orientation) and central differences of forward kinematics at `q`.
pub fn frame_jacobian_error(
    model: &Model,
    q: &[f64],
    frame: FrameId,
    offset: &Vector3<f64>,
) -> f64 {
    let n = model.nv();
    let mut data = model.new_data();
    fk(model, &mut data, q);
    let mut jp = Mat::<f64>::zeros(3, n);
    let mut jr = Mat::<f64>::zeros(3, n);
    // A row-major 1×n view through a strided buffer: the model must write through indexing.
    let mut zrow = Mat::<f64>::zeros(4, n);
    model
        .point_jacobian(&data, frame, offset, jp.as_mut())
        .unwrap();
    model
        .orientation_jacobian(&data, frame, jr.as_mut())
        .unwrap();
    model
        .point_jacobian_row(
            &data,
            frame,
            offset,
            Axis::Z,
            zrow.as_mut().submatrix_mut(2, 0, 1, n),
        )
        .unwrap();
    // Along an oblique direction, added onto a row of ones (it must add, not overwrite).
    let direction = Vector3::new(0.48, -0.6, 0.64);
    let mut along = Mat::<f64>::from_fn(1, n, |_, _| 1.0);
    model
        .add_point_jacobian_along(&data, frame, offset, &direction, along.as_mut())
        .unwrap();
    let mut worst: f64 = 0.0;
    for k in 0..n {
        let dp = diff(
            q,
            k,
            |q| {
                placement(model, q, frame)
                    .transform_point(&(*offset).into())
                    .coords
            },
            |a, b| a - b,
        );
        let dr = diff(
            q,
            k,
            |q| placement(model, q, frame).rotation,
            |a, b| small_rotation_vector(&(a * b.inverse())),
        );
        for r in 0..3 {
            worst = worst.max((jp[(r, k)] - dp[r]).abs());
            worst = worst.max((jr[(r, k)] - dr[r]).abs());
        }
        worst = worst.max((zrow[(2, k)] - dp[2]).abs());
        worst = worst.max((along[(0, k)] - 1.0 - direction.dot(&dp)).abs());
        // Rows of the buffer outside the view must stay untouched.
        worst = worst
            .max(zrow[(0, k)].abs())
            .max(zrow[(1, k)].abs())
            .max(zrow[(3, k)].abs());
    }
    worst
}

/// Largest difference between the CoM Jacobian (3 rows, and the xy rows into a row-major view)
/// and central differences of the CoM at `q`.
pub fn com_jacobian_error(model: &Model, q: &[f64]) -> f64 {
    let n = model.nv();
    let mut data = model.new_data();
    fk(model, &mut data, q);
    let mut j = Mat::<f64>::zeros(3, n);
    model.com_jacobian(&data, j.as_mut()).unwrap();
    let mut buf = vec![0.0; 2 * n];
    let jxy = faer::MatMut::from_row_major_slice_mut(&mut buf, 2, n);
    model.com_jacobian_rows(&data, 2, jxy).unwrap();
    let mut worst: f64 = 0.0;
    for k in 0..n {
        let d = diff(q, k, |q| com(model, q), |a, b| a - b);
        for r in 0..3 {
            worst = worst.max((j[(r, k)] - d[r]).abs());
        }
        worst = worst
            .max((buf[k] - d[0]).abs())
            .max((buf[n + k] - d[1]).abs());
    }
    worst
}

/// Rotation vector of a small rotation from its skew part, `vee((R − Rᵀ)/2)` (= sin θ · axis; acos of
/// the trace would lose half the digits near the identity).
pub fn small_rotation_vector(r: &nalgebra::Rotation3<f64>) -> Vector3<f64> {
    let m = r.matrix();
    Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5
}

/// Orientation difference (rad, small angles) between two rotations.
pub fn rotation_error(a: &nalgebra::Rotation3<f64>, b: &nalgebra::Rotation3<f64>) -> f64 {
    (a.matrix() - b.matrix()).amax()
}

/// The whole body's angular momentum about the base origin (kg·m²/s) when `q` moves at `v`,
/// from the links' motion alone: `Σ m x × ẋ + R I Rᵀ ω`, with `ẋ` and `ω` central differences
/// of the links' placements (no Jacobian of the crate).
pub fn momentum_by_differences(model: &Model, q: &[f64], v: &[f64]) -> Vector3<f64> {
    let at = |t: f64| {
        let mut data = model.new_data();
        let q: Vec<f64> = q.iter().zip(v).map(|(q, v)| q + t * v).collect();
        model.forward_kinematics(&mut data, &q).unwrap();
        data
    };
    let (now, ahead, behind) = (at(0.0), at(H), at(-H));
    let mut momentum = Vector3::zeros();
    for (i, link) in model.links().iter().enumerate() {
        let com = |d: &ModelData| d.link_placement(i) * nalgebra::Point3::from(link.com);
        let x = com(&now).coords;
        let velocity = (com(&ahead) - com(&behind)) / (2.0 * H);
        let turn = ahead.link_placement(i).rotation * behind.link_placement(i).rotation.inverse();
        let omega = small_rotation_vector(&turn) / (2.0 * H);
        let r = now.link_placement(i).rotation.matrix();
        let spin = (link.inertia).map_or(Vector3::zeros(), |inertia| {
            r * inertia * r.transpose() * omega
        });
        momentum += x.cross(&velocity) * link.mass + spin;
    }
    momentum
}
