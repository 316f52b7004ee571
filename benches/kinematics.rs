//! NAO (right-sole model) kinematics of one RS-stack iteration: forward kinematics, the CoM xy
//! Jacobian (2 rows), the l_hand, r_hand, l_ankle position Jacobians (9 rows) and the CoM.
//! Goal: ≤ 2 µs median. Also FK alone, for the split; and the whole body's angular momentum
//! Jacobian (3 rows) and the ZMP task's rows (a 4-edge sole and the vertical moment), the
//! rows `PoubelConfig::zmp_balance` adds.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use faer::Mat;
use nalgebra::Vector3;
use taskstack::robots::nao;
use taskstack::tasks::ZmpTask;

fn kinematics(c: &mut Criterion) {
    let model = nao::rfoot();
    let mut data = model.new_data();
    let ids = ["l_hand", "r_hand", "l_ankle"].map(|f| model.frame_id(f).unwrap());
    let n = model.nv();
    let mut j = Mat::<f64>::zeros(11, n);
    // StandInit-like posture.
    let mut q = vec![0.0; n];
    for (name, v) in [
        ("LShoulderPitch", 1.4),
        ("LElbowRoll", -1.0),
        ("RShoulderPitch", 1.4),
        ("RElbowRoll", 1.0),
        ("LHipPitch", -0.35),
        ("LKneePitch", 0.7),
        ("LAnklePitch", -0.35),
        ("RHipPitch", -0.35),
        ("RKneePitch", 0.7),
        ("RAnklePitch", -0.35),
    ] {
        q[model.variable_index(name).unwrap()] = v;
    }
    let zero = Vector3::zeros();
    c.bench_function("nao_rfoot_fk", |b| {
        b.iter(|| model.forward_kinematics(&mut data, black_box(&q)).unwrap())
    });
    c.bench_function("nao_rfoot_fk_rs_jacobians_com", |b| {
        b.iter(|| {
            model.forward_kinematics(&mut data, black_box(&q)).unwrap();
            model
                .com_jacobian_rows(&data, 2, j.as_mut().submatrix_mut(0, 0, 2, n))
                .unwrap();
            for (k, id) in ids.iter().enumerate() {
                model
                    .point_jacobian(
                        &data,
                        *id,
                        &zero,
                        j.as_mut().submatrix_mut(2 + 3 * k, 0, 3, n),
                    )
                    .unwrap();
            }
            black_box(model.com(&data).unwrap())
        })
    });
    let mut momentum = Mat::<f64>::zeros(3, n);
    model.forward_kinematics(&mut data, &q).unwrap();
    c.bench_function("nao_rfoot_angular_momentum_jacobian", |b| {
        b.iter(|| (model.angular_momentum_jacobian(black_box(&data), momentum.as_mut())).unwrap())
    });
    let sole = nao::sole_outline(taskstack::human::Side::Right);
    let mut sole = sole.to_vec();
    sole.reverse(); // counter-clockwise
    let mut zmp = ZmpTask::new(&model, 4, &sole, 0.0, 0.3).unwrap();
    zmp.begin_frame(&q, &vec![0.5; n], 1.0 / 120.0).unwrap();
    let mut rows = Mat::<f64>::zeros(zmp.rows(), n);
    let (mut lower, mut upper) = (vec![0.0; zmp.rows()], vec![0.0; zmp.rows()]);
    c.bench_function("nao_rfoot_zmp_rows", |b| {
        b.iter(|| {
            zmp.write(
                &model,
                black_box(&data),
                &q,
                rows.as_mut(),
                &mut lower,
                &mut upper,
            )
            .unwrap()
        })
    });
}

criterion_group!(benches, kinematics);
criterion_main!(benches);
