//! No heap allocation in forward kinematics, Jacobians and CoM once the workspace exists: a
//! counting global allocator around the RS-stack kinematics of the NAO.

use faer::Mat;
use nalgebra::Vector3;
use taskstack::model::Axis;
use taskstack::robots::nao;

use crate::alloc_counter;
use alloc_counter::allocations;

#[test]
fn kinematics_do_not_allocate_after_new_data() {
    let model = nao::rfoot();
    let mut data = model.new_data();
    let ids = ["l_hand", "r_hand", "l_ankle", "l_toe"].map(|f| model.frame_id(f).unwrap());
    let mut j = Mat::<f64>::zeros(16, model.nv());
    let mut q = vec![0.1; model.nv()];
    let zero = Vector3::zeros();
    let before = allocations();
    let mut checksum = 0.0;
    for step in 0..100 {
        q[step % 23] += 0.01;
        model.forward_kinematics(&mut data, &q).unwrap();
        model
            .com_jacobian_rows(&data, 2, j.as_mut().submatrix_mut(0, 0, 2, 23))
            .unwrap();
        for (k, id) in ids[..3].iter().enumerate() {
            model
                .point_jacobian(
                    &data,
                    *id,
                    &zero,
                    j.as_mut().submatrix_mut(2 + 3 * k, 0, 3, 23),
                )
                .unwrap();
        }
        model
            .point_jacobian_row(
                &data,
                ids[3],
                &zero,
                Axis::Z,
                j.as_mut().submatrix_mut(11, 0, 1, 23),
            )
            .unwrap();
        model
            .orientation_jacobian(&data, ids[0], j.as_mut().submatrix_mut(12, 0, 3, 23))
            .unwrap();
        checksum += model.com(&data).unwrap().x + j[(5, 3)];
    }
    let after = allocations();
    assert!(checksum.is_finite());
    assert_eq!(after - before, 0, "heap allocations in the kinematics loop");
}
