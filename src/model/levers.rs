//! How fast a point of a link can move per unit of each joint, in every posture
//! ([`Model::levers`]).

use super::{FrameId, JointKind, Model, ModelError};

impl Model {
    /// Per joint (in [`Model::joints`] order): `Some(ℓ)`, a bound (m per unit of the joint's
    /// value: m/rad for a revolute joint, 1 for a prismatic one) on how fast a point within
    /// `extent` m of `frame`'s origin moves with the joint, valid in every posture, for the
    /// joints that move the frame; `None` for the others and for fixed joints. Multiply by the
    /// joint's `|multiplier|` for a rate per unit of its variable.
    ///
    /// A point `x` fixed to the frame's link moves with a revolute joint `i` on the path from
    /// the base by `μ_i w_i × (x − p_i)` per unit of its variable ([module docs](super)), at
    /// most `|μ_i| ‖x − p_i‖`. Between the joint's axis point `p_i` (its link's origin) and the
    /// frame's origin lie the constant placements `P_j` of the joints below it and the frame's
    /// own placement `F`: rigid offsets that the joints between only turn, so, whatever the
    /// posture,
    ///
    /// ```text
    /// ‖x − p_i‖ ≤ ℓ_i = extent + ‖t(F)‖ + Σ_{j below i on the path} (‖t(P_j)‖ + travel_j)
    /// ```
    ///
    /// with `t(·)` a placement's translation and `travel_j` the largest `|v_j|` of a prismatic
    /// joint `j` (from its variable's limits; infinite when they are), 0 for the others. A
    /// prismatic joint moves the point by `μ_i w_i`: lever 1, its unit axis' length.
    ///
    /// # Errors
    /// [`ModelError::FrameOutOfRange`] for a frame of another model.
    pub fn levers(&self, frame: FrameId, extent: f64) -> Result<Vec<Option<f64>>, ModelError> {
        self.check_frame(frame)?;
        let mut levers = vec![None; self.joints.len()];
        let placed = &self.frames[frame.0];
        let mut length = extent + placed.placement.translation.vector.norm();
        let mut link = placed.link;
        while link > 0 {
            let joint = &self.joints[link - 1];
            match joint.kind {
                JointKind::Revolute => levers[link - 1] = Some(length),
                JointKind::Prismatic => {
                    levers[link - 1] = Some(1.0);
                    length += self.travel(link - 1);
                }
                JointKind::Fixed => {}
            }
            length += joint.placement.translation.vector.norm();
            link = joint.antecedent;
        }
        Ok(levers)
    }

    /// The largest `|v|` of joint `j` (m for a prismatic joint) over its variable's limits.
    fn travel(&self, j: usize) -> f64 {
        let joint = &self.joints[j];
        let reach = joint.variable.map_or(0.0, |k| {
            let v = &self.variables[k];
            v.lower.abs().max(v.upper.abs())
        });
        joint.multiplier.abs() * reach + joint.offset.abs()
    }
}
