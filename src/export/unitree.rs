//! The CSV layout of Unitree's retargeted LAFAN1 dataset (`LAFAN1_Retargeting_Dataset` on
//! Hugging Face, 30 frames a second): one row per frame, no header, comma-separated: the
//! floating base's position `x y z` (m, world), its orientation as a quaternion `x y z w`,
//! then the joint angles (rad) in the robot's URDF order.
//!
//! The joints are written in the model's variable order: for the G1 that is its URDF's joint
//! order (`robots::g1::VARIABLES`); the NAO's coupled `HipYawPitch` is one column
//! (`LHipYawPitch`), as in `joints.csv`.

use std::io::Write;

use super::motion::{ExportError, MotionTrack};

/// Writes `track` sampled at `fps` frames a second ([`MotionTrack::resampled`]) in the layout of
/// Unitree's retargeted LAFAN1 dataset (see the module docs); numbers in Rust's shortest
/// round-trip form.
///
/// # Errors
/// [`ExportError`] for a bad rate, an empty track, or a failed write.
pub fn write_unitree_csv(
    mut out: impl Write,
    track: &MotionTrack,
    fps: f64,
) -> Result<(), ExportError> {
    let t = track.resampled(fps)?;
    let mut line = String::new();
    for i in 0..t.len() {
        line.clear();
        let values = t.root_pos[i]
            .iter()
            .chain(&t.root_quat[i])
            .chain(t.joints(i));
        for (k, v) in values.enumerate() {
            if k > 0 {
                line.push(',');
            }
            line.push_str(&v.to_string());
        }
        line.push('\n');
        out.write_all(line.as_bytes())?;
    }
    Ok(out.flush()?)
}
