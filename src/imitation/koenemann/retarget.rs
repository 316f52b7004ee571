//! End-effector retargeting for a statically stable posture (Koenemann et al. §V.C, eq. 7).
//!
//! All points are foot centres and the CoM in one frame (the robot's torso frame).
//!
//! * Double support, the paper's rule (Fig. 5): one foot moves toward the CoM (horizontally:
//!   across the frame's z axis) until the CoM's offset between the feet is the desired `o'`:
//!   the left foot if `o' < o`, else the right.
//! * Double support, keeping the stance: both feet move by the same vector along the line
//!   between them, `δ = (o − o') (p_R − p_L)`, so that the CoM's offset is `o'` and the feet
//!   keep their distance (on the floor, neither slides).
//! * Both feet then take the common sole normal of eq. 7,
//!   `n = p_CoM − (p'_L + o' (p'_R − p'_L))`: from the point at offset `o'` to the CoM, so that
//!   on a floor with this normal the CoM is right above that point. In single support the same
//!   formula with `o'` 0 or 1 tilts the support foot so the CoM is above its centre.

use nalgebra::Vector3;

use super::offset::offset;

/// How double support meets the desired offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FootRetargeting {
    /// Both feet shift together along the line between them: the stance is kept, so on the
    /// floor the robot's hips move over its feet and no foot slides. Default.
    #[default]
    ShiftBothFeet,
    /// The paper's Fig. 5: one foot moves toward the CoM. The distance between the feet
    /// changes, which on a real floor means the moved foot slides.
    MoveOneFoot,
}

/// Eq. 7: the unit sole normal that puts `com` above the point at offset `o` between `left`
/// and `right`; `None` when the CoM is on that point.
pub fn support_normal(
    com: &Vector3<f64>,
    left: &Vector3<f64>,
    right: &Vector3<f64>,
    o: f64,
) -> Option<Vector3<f64>> {
    (com - (left + (right - left) * o)).try_normalize(1e-9)
}

/// The foot centres `[left, right]` moved by `rule` so that the offset of `com` is `desired`.
/// Feet that coincide are returned unchanged.
pub fn retarget_double(
    rule: FootRetargeting,
    com: &Vector3<f64>,
    feet: [Vector3<f64>; 2],
    desired: f64,
) -> [Vector3<f64>; 2] {
    let [left, right] = feet;
    let Some(current) = offset(com, &left, &right) else {
        return feet;
    };
    match rule {
        FootRetargeting::ShiftBothFeet => {
            let shift = (right - left) * (current - desired);
            [left + shift, right + shift]
        }
        // Offsets measured from the moved foot: o for the left, 1 − o for the right.
        FootRetargeting::MoveOneFoot if desired < current => {
            [move_toward(com, left, &right, desired), right]
        }
        FootRetargeting::MoveOneFoot => [left, move_toward(com, right, &left, 1.0 - desired)],
    }
}

/// `foot` moved toward the CoM across z by the fraction `s ∈ [0, 1]` of its horizontal distance
/// that makes `offset(com, foot', other)` equal `goal` (bisection: the offset falls as the foot
/// comes under the CoM); `s = 1` if even that is not enough.
fn move_toward(
    com: &Vector3<f64>,
    foot: Vector3<f64>,
    other: &Vector3<f64>,
    goal: f64,
) -> Vector3<f64> {
    let mut toward = com - foot;
    toward.z = 0.0;
    let at = |s: f64| offset(com, &(foot + toward * s), other).unwrap_or(0.0);
    if at(1.0) > goal {
        return foot + toward;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if at(mid) > goal { lo = mid } else { hi = mid }
    }
    foot + toward * hi
}
