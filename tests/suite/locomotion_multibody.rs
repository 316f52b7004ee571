//! The whole body's ZMP of a motion ([`MultibodyZmp`]) against the multi-point-mass formula,
//! computed independently from each link's centre of mass by finite differences:
//!
//! ```text
//! p_x = Σ m_i ((z̈_i + g) x_i − z_i ẍ_i) / Σ m_i (z̈_i + g)     (p_y likewise)
//! ```
//!
//! exact for point-mass links, which the NAO's DH model has (no rotational inertia).

use nalgebra::{IsometryMatrix3, Point3, Rotation3, Translation3, Vector2, Vector3};
use taskstack::Side;
use taskstack::locomotion::MultibodyZmp;
use taskstack::model::{Model, ModelData};
use taskstack::robots::nao;

const G: f64 = 9.81;

/// The posture at time `t` (s): every joint swinging about the standing posture, each at its
/// own frequency, within ±0.15 rad.
fn posture(stand: &[f64], t: f64) -> Vec<f64> {
    (stand.iter().enumerate())
        .map(|(i, q)| q + 0.15 * (t * (3.0 + 0.7 * i as f64)).sin())
        .collect()
}

/// Every link's mass and world CoM at `q`.
fn link_points(
    model: &Model,
    data: &mut ModelData,
    base: &IsometryMatrix3<f64>,
    q: &[f64],
) -> Vec<(f64, Vector3<f64>)> {
    model.forward_kinematics(data, q).unwrap();
    (model.links().iter().enumerate())
        .map(|(i, link)| {
            let at = base * (data.link_placement(i) * Point3::from(link.com));
            (link.mass, at.coords)
        })
        .collect()
}

/// The largest distance (m) between the estimator's ZMP and the point-mass formula's over
/// 0.4 s of motion sampled every `dt` s.
fn worst_error(dt: f64) -> f64 {
    let profile = nao::profile();
    let model = profile.model(Side::Left);
    assert!(model.links().iter().all(|l| l.inertia.is_none()));
    let base = IsometryMatrix3::from_parts(
        Translation3::new(0.2, -0.1, 0.0),
        Rotation3::from_axis_angle(&Vector3::z_axis(), 0.6),
    );
    let mut data = model.new_data();
    let mut zmp = MultibodyZmp::new(model, dt).unwrap();
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    let ticks = (0.4 / dt).round() as usize;
    for k in 0..ticks {
        let t = k as f64 * dt;
        let q = posture(&profile.stand, t);
        model.forward_kinematics(&mut data, &q).unwrap();
        let Some(p) = zmp.push(model, &data, &base, &q).unwrap() else {
            continue;
        };
        // Tick k − 1's ZMP from the links at k − 2, k − 1, k.
        let points: Vec<_> = [t - 2.0 * dt, t - dt, t]
            .map(|s| link_points(model, &mut data, &base, &posture(&profile.stand, s)))
            .into();
        let (mut num, mut den) = (Vector2::zeros(), 0.0);
        for i in 0..points[1].len() {
            let (m, x) = points[1][i];
            let a = (points[2][i].1 - 2.0 * x + points[0][i].1) / (dt * dt);
            num += m * Vector2::new((a.z + G) * x.x - x.z * a.x, (a.z + G) * x.y - x.z * a.y);
            den += m * (a.z + G);
        }
        let expected = num / den;
        worst = worst.max((p - expected).norm());
        checked += 1;
    }
    assert_eq!(checked, ticks - 2);
    worst
}

/// The estimator differences the momentum at half ticks (its Jacobian taken at the tick's
/// end), the formula the positions at whole ones: they differ by O(Δt) and converge (1 ms:
/// 0.97 mm, 0.5 ms: 0.48 mm on this motion of every joint).
#[test]
fn whole_body_zmp_matches_point_masses() {
    let coarse = worst_error(0.001);
    let fine = worst_error(0.0005);
    assert!(
        coarse < 2e-3,
        "whole-body ZMP {coarse} m from the point-mass formula"
    );
    assert!(
        fine < 0.6 * coarse,
        "no convergence: {coarse} m at 1 ms, {fine} m at 0.5 ms"
    );
}
