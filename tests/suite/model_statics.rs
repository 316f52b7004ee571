//! `Model::static_torques` against the gradient of the potential energy taken by central finite
//! differences of forward kinematics alone (no Jacobian code).

use faer::Mat;
use nalgebra::Vector3;
use taskstack::model::{Model, ModelData, ModelError, PointLoad};
use taskstack::robots::{g1, nao};

const G: f64 = 9.81;

/// `M g z_c − f z_load` at `q`, by forward kinematics.
fn potential(model: &Model, data: &mut ModelData, q: &[f64], load: &PointLoad) -> f64 {
    model.forward_kinematics(data, q).unwrap();
    let point = data.frame_placement(load.frame) * nalgebra::Point3::from(load.offset);
    model.total_mass() * G * model.com(data).unwrap().z - load.force * point.z
}

/// Deterministic postures inside the limits (and within ±1 rad of zero).
fn postures(model: &Model) -> Vec<Vec<f64>> {
    (1..4)
        .map(|seed| {
            let mix = |k: usize| ((seed * 7919 + k * 104_729) % 1000) as f64 / 1000.0;
            let within = |k: usize, lower: f64, upper: f64| {
                let (lo, hi) = (lower.max(-1.0), upper.min(1.0));
                lo + mix(k) * (hi - lo)
            };
            let vars = model.variables().iter().enumerate();
            vars.map(|(k, v)| within(k, v.lower, v.upper)).collect()
        })
        .collect()
}

#[test]
fn the_torques_are_the_gradient_of_the_potential_energy() {
    let cases = [
        (g1::right_sole(), "left_sole", 120.0),
        (g1::left_sole(), "right_sole", 0.0),
        (nao::rfoot(), "l_sole", 20.0),
    ];
    for (model, load, force) in cases {
        let load = PointLoad {
            frame: model.frame_id(load).unwrap(),
            offset: Vector3::new(0.03, -0.01, 0.002),
            force,
        };
        let mut data = model.new_data();
        for q in postures(&model) {
            model.forward_kinematics(&mut data, &q).unwrap();
            let mut tau = Mat::<f64>::zeros(1, model.nv());
            model
                .static_torques(&data, G, &[load], tau.as_mut())
                .unwrap();
            let h = 1e-6;
            for k in 0..model.nv() {
                let mut qk = q.clone();
                qk[k] += h;
                let plus = potential(&model, &mut data, &qk, &load);
                qk[k] -= 2.0 * h;
                let minus = potential(&model, &mut data, &qk, &load);
                let fd = (plus - minus) / (2.0 * h);
                assert!(
                    (tau[(0, k)] - fd).abs() < 1e-5 * (1.0 + fd.abs()),
                    "{}: variable {k}: {} vs {fd}",
                    model.name(),
                    tau[(0, k)]
                );
            }
        }
    }
}

#[test]
fn bad_loads_are_refused() {
    let model = g1::right_sole();
    let mut data = model.new_data();
    let mut tau = Mat::<f64>::zeros(1, model.nv());
    assert_eq!(
        model.static_torques(&data, G, &[], tau.as_mut()),
        Err(ModelError::KinematicsNotComputed)
    );
    model
        .forward_kinematics(&mut data, &vec![0.0; model.nv()])
        .unwrap();
    let load = PointLoad {
        frame: model.frame_id("left_sole").unwrap(),
        offset: Vector3::zeros(),
        force: f64::NAN,
    };
    let nan = model.static_torques(&data, G, &[load], tau.as_mut());
    assert!(matches!(nan, Err(ModelError::NonFiniteLoad(v)) if v.is_nan()));
    let infinite = model.static_torques(&data, f64::INFINITY, &[], tau.as_mut());
    assert!(matches!(infinite, Err(ModelError::NonFiniteLoad(_))));
    let mut wide = Mat::<f64>::zeros(1, model.nv() + 1);
    let shape = model.static_torques(&data, G, &[], wide.as_mut());
    assert!(matches!(shape, Err(ModelError::OutputShape { .. })));
}
