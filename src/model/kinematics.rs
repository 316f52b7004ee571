//! Forward kinematics, Jacobians and centre of mass (formulas in the [module docs](super)).

use faer::MatMut;
use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Translation3, Unit, Vector3};

use super::{Axis, FrameId, JointKind, Model, ModelData, ModelError};

/// Rotation by `angle` (radians) about the unit `axis` (Rodrigues' formula, no normalisation).
pub(super) fn rotation_about(axis: &Unit<Vector3<f64>>, angle: f64) -> Rotation3<f64> {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    let (x, y, z) = (axis.x, axis.y, axis.z);
    Rotation3::from_matrix_unchecked(Matrix3::new(
        t * x * x + c,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        t * y * y + c,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        t * z * z + c,
    ))
}

impl Model {
    /// Forward kinematics: placements of every link and named frame in the base frame, joint axes,
    /// and the mass moments used by [`Model::com`] and [`Model::com_jacobian`].
    ///
    /// `q` holds one value per variable (radians / metres) in [`Model::variables`] order.
    /// Errors: wrong length, non-finite entry, workspace of another model.
    pub fn forward_kinematics(&self, data: &mut ModelData, q: &[f64]) -> Result<(), ModelError> {
        self.check_data(data)?;
        if q.len() != self.variables.len() {
            return Err(ModelError::WrongQLength {
                expected: self.variables.len(),
                got: q.len(),
            });
        }
        if let Some(index) = q.iter().position(|v| !v.is_finite()) {
            return Err(ModelError::NonFiniteQ {
                index,
                variable: self.variables[index].name.clone(),
                value: q[index],
            });
        }
        let base = &self.links[0];
        data.mass_moments[0] = base.com * base.mass;
        for (j, joint) in self.joints.iter().enumerate() {
            let i = j + 1;
            let frame = data.link_placements[joint.antecedent] * joint.placement;
            data.axes[i] = frame.rotation * joint.axis.into_inner();
            let value = joint
                .variable
                .map_or(0.0, |v| joint.multiplier * q[v] + joint.offset);
            let placement = match joint.kind {
                JointKind::Fixed => frame,
                JointKind::Revolute => {
                    let mut p = frame;
                    if joint.axis.x == 0.0 && joint.axis.y == 0.0 {
                        // About ±z (every DH joint): R·Rz(θ) only mixes the first two columns,
                        // a third of the general product.
                        let (s, c) = (value * joint.axis.z).sin_cos();
                        let m = p.rotation.matrix_mut_unchecked();
                        let (x, y) = (m.column(0).into_owned(), m.column(1).into_owned());
                        m.set_column(0, &(x * c + y * s));
                        m.set_column(1, &(y * c - x * s));
                    } else {
                        p.rotation *= rotation_about(&joint.axis, value);
                    }
                    p
                }
                JointKind::Prismatic => {
                    let mut p = frame;
                    p.translation = Translation3::from(p.translation.vector + data.axes[i] * value);
                    p
                }
            };
            let link = &self.links[i];
            data.mass_moments[i] = placement.transform_point(&link.com.into()).coords * link.mass;
            data.link_placements[i] = placement;
        }
        for i in (1..self.links.len()).rev() {
            let a = self.joints[i - 1].antecedent;
            let moment = data.mass_moments[i];
            data.mass_moments[a] += moment;
        }
        for (placement, frame) in data.frame_placements.iter_mut().zip(&self.frames) {
            *placement = data.link_placements[frame.link] * frame.placement;
        }
        data.computed = true;
        Ok(())
    }

    /// Whole-body centre of mass in the base frame (metres), from the last forward kinematics.
    pub fn com(&self, data: &ModelData) -> Result<Vector3<f64>, ModelError> {
        self.check_computed(data)?;
        if self.total_mass <= 0.0 {
            return Err(ModelError::NoMass);
        }
        Ok(data.mass_moments[0] / self.total_mass)
    }

    /// World placement of the named frame `frame`, given the world placement of the model's base:
    /// `ʷT_f = ʷT_base · ᵇᵃˢᵉT_f(q)` (metres, radians; from the last forward kinematics).
    pub fn placement_in_world(
        &self,
        data: &ModelData,
        world_t_base: &IsometryMatrix3<f64>,
        frame: FrameId,
    ) -> Result<IsometryMatrix3<f64>, ModelError> {
        self.check_computed(data)?;
        self.check_frame(frame)?;
        Ok(world_t_base * data.frame_placements[frame.0])
    }

    /// Position in the base frame (metres) of the point at `offset` (metres, in the frame's axes)
    /// from the named frame `frame`.
    pub fn point_position(
        &self,
        data: &ModelData,
        frame: FrameId,
        offset: &Vector3<f64>,
    ) -> Result<Vector3<f64>, ModelError> {
        self.check_computed(data)?;
        self.check_frame(frame)?;
        check_offset(offset)?;
        Ok(data.frame_placements[frame.0]
            .transform_point(&(*offset).into())
            .coords)
    }

    /// 3×n Jacobian of the position (base frame, metres) of the point at `offset` from `frame`
    /// (see [`Model::point_position`]) with respect to `q`, written into `out` (3 rows: x, y, z;
    /// one column per variable; any strides).
    pub fn point_jacobian(
        &self,
        data: &ModelData,
        frame: FrameId,
        offset: &Vector3<f64>,
        mut out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        let x = self.point_position(data, frame, offset)?;
        self.check_shape(&out, 3)?;
        out.fill(0.0);
        let link = self.frames[frame.0].link;
        for &i in &self.chain[self.chain_start[link]..self.chain_start[link + 1]] {
            let (k, column) = self.point_column(data, i, &x);
            for r in 0..3 {
                out[(r, k)] += column[r];
            }
        }
        Ok(())
    }

    /// One row (`axis` of the base frame) of [`Model::point_jacobian`],
    /// written into the 1×n view `out` (e.g. the height rate of a toe or heel).
    pub fn point_jacobian_row(
        &self,
        data: &ModelData,
        frame: FrameId,
        offset: &Vector3<f64>,
        axis: Axis,
        mut out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        let x = self.point_position(data, frame, offset)?;
        self.check_shape(&out, 1)?;
        out.fill(0.0);
        let link = self.frames[frame.0].link;
        for &i in &self.chain[self.chain_start[link]..self.chain_start[link + 1]] {
            let (k, column) = self.point_column(data, i, &x);
            out[(0, k)] += column[axis as usize];
        }
        Ok(())
    }

    /// Adds `directionᵀ J` to the 1×n view `out`, with `J` the [`Model::point_jacobian`] of the
    /// point at `offset` from `frame` (`direction` in the base frame's axes; the rate of the
    /// point's displacement along it, m per unit q̇ for a unit direction). It adds, so that
    /// `nᵀ (J₁ − J₂)`, the rate of a distance between two points, takes two calls (the second
    /// with `−n`) and no 3×n scratch.
    pub fn add_point_jacobian_along(
        &self,
        data: &ModelData,
        frame: FrameId,
        offset: &Vector3<f64>,
        direction: &Vector3<f64>,
        mut out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        let x = self.point_position(data, frame, offset)?;
        self.check_shape(&out, 1)?;
        let link = self.frames[frame.0].link;
        for &i in &self.chain[self.chain_start[link]..self.chain_start[link + 1]] {
            let (k, column) = self.point_column(data, i, &x);
            out[(0, k)] += direction.dot(&column);
        }
        Ok(())
    }

    /// 3×n orientation Jacobian of `frame`: maps `q̇` to the frame's angular velocity in the base
    /// frame (rad/s per unit q̇), written into `out`.
    pub fn orientation_jacobian(
        &self,
        data: &ModelData,
        frame: FrameId,
        out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        self.orientation_jacobian_rows(data, frame, 3, out)
    }

    /// The first `rows` (1, 2 or 3: x; x, y; x, y, z) rows of [`Model::orientation_jacobian`],
    /// written into a `rows`×n view (the xy rows: how fast the frame tilts).
    pub fn orientation_jacobian_rows(
        &self,
        data: &ModelData,
        frame: FrameId,
        rows: usize,
        mut out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        self.check_computed(data)?;
        self.check_frame(frame)?;
        self.check_shape(&out, rows.min(3))?;
        out.fill(0.0);
        let link = self.frames[frame.0].link;
        for &i in &self.chain[self.chain_start[link]..self.chain_start[link + 1]] {
            let joint = &self.joints[i - 1];
            if joint.kind == JointKind::Revolute {
                let (k, column) = self.driven(i, data.axes[i]);
                for r in 0..rows.min(3) {
                    out[(r, k)] += column[r];
                }
            }
        }
        Ok(())
    }

    /// 3×n Jacobian of the whole-body centre of mass (base frame, metres per unit q̇), written into
    /// `out` (3 rows x, y, z; pass a 2-row view via [`Model::com_jacobian_rows`] for the xy rows).
    pub fn com_jacobian(&self, data: &ModelData, out: MatMut<'_, f64>) -> Result<(), ModelError> {
        self.com_jacobian_rows(data, 3, out)
    }

    /// The first `rows` (1, 2 or 3: x; x, y; x, y, z) rows of [`Model::com_jacobian`], written
    /// into a `rows`×n view (the paper's balance task uses the xy rows).
    pub fn com_jacobian_rows(
        &self,
        data: &ModelData,
        rows: usize,
        out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        if rows == 0 || rows > 3 {
            return Err(ModelError::BadRowCount(rows));
        }
        self.com_jacobian_axes(data, &[Axis::X, Axis::Y, Axis::Z][..rows], out)
    }

    /// The rows of [`Model::com_jacobian`] of `axes` (1–3, in that order), written into an
    /// `axes.len()`×n view: `[Axis::Z]` for a CoM height task.
    pub fn com_jacobian_axes(
        &self,
        data: &ModelData,
        axes: &[Axis],
        mut out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        if axes.is_empty() || axes.len() > 3 {
            return Err(ModelError::BadRowCount(axes.len()));
        }
        self.check_computed(data)?;
        if self.total_mass <= 0.0 {
            return Err(ModelError::NoMass);
        }
        self.check_shape(&out, axes.len())?;
        out.fill(0.0);
        let inv_mass = 1.0 / self.total_mass;
        for &i in &self.moving {
            let joint = &self.joints[i - 1];
            let axis = data.axes[i];
            let share = self.subtree_mass[i] * inv_mass;
            let column = match joint.kind {
                JointKind::Revolute => {
                    let origin = data.link_placements[i].translation.vector;
                    axis.cross(&(data.mass_moments[i] * inv_mass - origin * share))
                }
                JointKind::Prismatic | JointKind::Fixed => axis * share,
            };
            let (k, column) = self.driven(i, column);
            for (r, &a) in axes.iter().enumerate() {
                out[(r, k)] += column[a as usize];
            }
        }
        Ok(())
    }

    /// 3×n Jacobian of the whole body's angular momentum about the base frame's origin:
    /// `H_O = A_O q̇` (kg·m²/s per unit q̇, base-frame axes), written into `out`.
    ///
    /// `H_O = Σ_i m_i x_i × ẋ_i + R_i I_i R_iᵀ ω_i` over the links (`x_i` the link's centre of
    /// mass, `R_i` its orientation, `I_i` its [`Link::inertia`](super::Link::inertia), taken as
    /// zero when the model has none: point masses, as a DH table gives). A revolute joint of
    /// axis `a` through `o` moves link `i` of its subtree with `ẋ_i = a × (x_i − o) θ̇` and
    /// `ω_i = a θ̇`, so its column is `Σ_i m_i x_i × (a × (x_i − o)) + R_i I_i R_iᵀ a`; a
    /// prismatic joint's is `Σ_i m_i x_i × a`. About the centre of mass `c` instead (the
    /// centroidal momentum): `A_G = A_O − m [c]× J_c`. With the base fixed in the world (a
    /// standing sole) `Ḣ_O` is the moment of the external forces about `O`: gravity's and the
    /// ground's, which is how a whole-body ZMP is read off it
    /// ([`ZmpTask`](crate::tasks::ZmpTask)).
    pub fn angular_momentum_jacobian(
        &self,
        data: &ModelData,
        mut out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        self.check_computed(data)?;
        self.check_shape(&out, 3)?;
        out.fill(0.0);
        for (i, link) in self.links.iter().enumerate().skip(1) {
            let placement = &data.link_placements[i];
            let x = placement.transform_point(&link.com.into()).coords;
            let rotational = link.inertia.map(|inertia| {
                let r = placement.rotation.matrix();
                r * inertia * r.transpose()
            });
            for &j in &self.chain[self.chain_start[i]..self.chain_start[i + 1]] {
                let axis = data.axes[j];
                let column = match self.joints[j - 1].kind {
                    JointKind::Revolute => {
                        let o = data.link_placements[j].translation.vector;
                        let spin = rotational.map_or(Vector3::zeros(), |r| r * axis);
                        x.cross(&axis.cross(&(x - o))) * link.mass + spin
                    }
                    JointKind::Prismatic | JointKind::Fixed => x.cross(&axis) * link.mass,
                };
                let (k, column) = self.driven(j, column);
                for r in 0..3 {
                    out[(r, k)] += column[r];
                }
            }
        }
        Ok(())
    }

    /// Column contribution of the moving joint of link `i` to the velocity of the point `x`.
    fn point_column(&self, data: &ModelData, i: usize, x: &Vector3<f64>) -> (usize, Vector3<f64>) {
        let axis = data.axes[i];
        let column = match self.joints[i - 1].kind {
            JointKind::Revolute => axis.cross(&(x - data.link_placements[i].translation.vector)),
            JointKind::Prismatic | JointKind::Fixed => axis,
        };
        self.driven(i, column)
    }

    /// Scales a joint column by the joint's multiplier and returns it with its variable index.
    fn driven(&self, i: usize, column: Vector3<f64>) -> (usize, Vector3<f64>) {
        let joint = &self.joints[i - 1];
        // Chains and `moving` only hold driven joints, so the variable is always present.
        (joint.variable.unwrap_or(0), column * joint.multiplier)
    }

    fn check_data(&self, data: &ModelData) -> Result<(), ModelError> {
        if data.link_placements.len() != self.links.len()
            || data.frame_placements.len() != self.frames.len()
        {
            return Err(ModelError::ForeignData);
        }
        Ok(())
    }

    pub(crate) fn check_computed(&self, data: &ModelData) -> Result<(), ModelError> {
        self.check_data(data)?;
        if !data.computed {
            return Err(ModelError::KinematicsNotComputed);
        }
        Ok(())
    }

    pub(crate) fn check_frame(&self, frame: FrameId) -> Result<(), ModelError> {
        if frame.0 >= self.frames.len() {
            return Err(ModelError::FrameOutOfRange(frame.0));
        }
        Ok(())
    }

    pub(crate) fn check_shape(&self, out: &MatMut<'_, f64>, rows: usize) -> Result<(), ModelError> {
        if out.nrows() != rows || out.ncols() != self.variables.len() {
            return Err(ModelError::OutputShape {
                expected_rows: rows,
                expected_cols: self.variables.len(),
                rows: out.nrows(),
                cols: out.ncols(),
            });
        }
        Ok(())
    }
}

fn check_offset(offset: &Vector3<f64>) -> Result<(), ModelError> {
    if offset.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::NonFiniteOffset([offset.x, offset.y, offset.z]))
    }
}
