//! One prioritized pass over the joints not clamped (the recursion of the module docs), its
//! repeats for new right-hand sides, and the report of a solve.

use super::rows::{LevelFactor, UsedRow, apply_chain, apply_level, used_row};
use super::settings::{Method, RELATIVE_RANK_TOLERANCE};
use super::solver::Solver;
use crate::solver::householder::{
    apply_qt, apply_reflector, dot, norm, qr_col_pivoting, qr_factor, solve_upper,
    solve_upper_transposed,
};
use crate::solver::report::ActiveInequality;

impl Solver {
    /// One solve by the configured method over the joints not clamped; writes `self.velocity`.
    pub(super) fn pass(&mut self) {
        match self.settings.method {
            Method::Prioritized => self.prioritized_pass(),
            Method::WeightedDls { damping } => self.weighted_dls_pass(damping),
        }
    }

    /// One prioritized solve over the joints not clamped; writes `self.velocity`.
    pub(super) fn prioritized_pass(&mut self) {
        let n = self.stack.dof();
        self.free.clear();
        self.free.extend((0..n).filter(|&i| !self.clamped[i]));
        let mut dim = self.free.len();
        let reference = self.stack.damping_reference();
        self.damp_toward_reference = reference.iter().any(|&v| v != 0.0);
        for (c, &i) in self.reference_coords.iter_mut().zip(&self.free) {
            *c = reference[i];
        }
        let mut offset = 0;
        for j in 0..self.stack.level_count() {
            let rows = self.project_level_rows(j, dim);
            let (rank, damping) = self.factor_level(j, dim, rows);
            self.factors[j] = LevelFactor {
                dim,
                rank,
                rows,
                damping,
            };
            if self.damp_toward_reference {
                self.project_reference(j, offset);
            }
            self.solve_level(j, true);
            dim -= rank;
            offset += rank;
        }
        self.assemble_velocity();
    }

    /// Level j's range coordinates of the damping reference, `U_jᵀ q̇_ref`, into
    /// `reference_coeff`: `reference_coords[offset..]` holds `Z_{j−1}ᵀ q̇_ref` on entry and
    /// level j's reflectors are applied to it ([`apply_level`]).
    fn project_reference(&mut self, j: usize, offset: usize) {
        let (n, start, f) = (self.stack.dof(), self.seg_start[j], self.factors[j]);
        let cur = &mut self.reference_coords[offset..offset + f.dim];
        let dim = cur.len();
        apply_level(&self.qr[n * start..], &self.tau[start..], &f, cur, dim, 0);
        self.reference_coeff[start..start + f.rank].copy_from_slice(&cur[..f.rank]);
    }

    /// The last prioritized pass again for the current scales and fixed velocities, on its
    /// factorization (same free joints, same used rows): the velocity a new pass would give,
    /// bit for bit, without projecting and factoring the levels again.
    pub(super) fn repeat_pass(&mut self) {
        self.repeat_pass_from(0);
    }

    /// [`Solver::repeat_pass`] for a right-hand side that is zero on the levels above `first`
    /// (their scales 0, no fixed velocities): their coefficients are zero and not solved for.
    pub(super) fn repeat_pass_from(&mut self, first: usize) {
        if !matches!(self.settings.method, Method::Prioritized) {
            return self.pass();
        }
        for j in 0..self.stack.level_count() {
            if j < first {
                let start = self.seg_start[j];
                self.coeff[start..start + self.factors[j].rows].fill(0.0);
            } else {
                self.solve_level(j, false);
            }
        }
        self.assemble_velocity();
    }

    /// Lists the rows level `j` uses in this pass (its equality rows, then its active inequality
    /// rows), writes `A_jᵀ = Z_{j−1}ᵀ J_jᵀ` into level j's QR buffer and each row's
    /// coordinates along the levels above into `projections`. Returns the number of rows.
    fn project_level_rows(&mut self, j: usize, dim: usize) -> usize {
        let n = self.stack.dof();
        let seg = self.seg_start[j];
        let rows = self.list_used_rows(j);
        // Each row's free-joint coordinates, rotated in place in its `projections` slot (n
        // entries): the first `offset` are the row's coordinates along the levels above, the
        // next `dim` its column of `A_jᵀ`.
        let block = &mut self.projections[n * seg..n * (seg + rows)];
        self.row_scale = 0.0;
        for (t, coords) in block.chunks_mut(n).enumerate() {
            let (row, _) = used_row(&self.stack, self.used[seg + t], self.scales[j]);
            self.row_scale = self.row_scale.max(norm(row));
            for (c, &i) in coords.iter_mut().zip(&self.free) {
                *c = row[i];
            }
        }
        let (head, tail) = self.qr.split_at_mut(n * seg);
        let (factors, seg_start) = (&self.factors[..j], &self.seg_start);
        let offset = apply_chain(head, n, &self.tau, factors, seg_start, block, n);
        for (t, coords) in block.chunks(n).enumerate() {
            tail[t * dim..(t + 1) * dim].copy_from_slice(&coords[offset..offset + dim]);
        }
        rows
    }

    /// Writes level j's right-hand side `b_j = ẋ_j − J_j q̇_{j−1}` into `rhs`: the scaled
    /// targets less the clamped joints' and the levels above's velocities along each row.
    fn level_rhs(&mut self, j: usize) {
        let (n, seg) = (self.stack.dof(), self.seg_start[j]);
        for t in 0..self.factors[j].rows {
            let (row, target) = used_row(&self.stack, self.used[seg + t], self.scales[j]);
            let mut b = target - dot(row, &self.fixed_velocity);
            let projection = &self.projections[n * (seg + t)..];
            let mut level_offset = 0;
            for (i, f) in self.factors[..j].iter().enumerate() {
                let level_seg = self.seg_start[i];
                b -= dot(
                    &projection[level_offset..level_offset + f.rank],
                    &self.coeff[level_seg..level_seg + f.rank],
                );
                level_offset += f.rank;
            }
            self.rhs[seg + t] = b;
        }
    }

    /// Fills `used[seg_start[j]..]` with level j's equality rows, then its active inequality rows.
    fn list_used_rows(&mut self, j: usize) -> usize {
        let seg = self.seg_start[j];
        let (eq_start, eq_end) = (self.stack.level_start(j), self.stack.level_start(j + 1));
        let (in_start, in_end) = (
            self.stack.inequality_start(j),
            self.stack.inequality_start(j + 1),
        );
        let mut t = seg;
        for r in eq_start..eq_end {
            self.used[t] = UsedRow::Equality(r);
            t += 1;
        }
        for r in in_start..in_end {
            if let Some(side) = self.inequality_state[r] {
                self.used[t] = UsedRow::Inequality(r, side);
                t += 1;
            }
        }
        t - seg
    }

    /// Factorizes level j's `rows` projected rows. Returns the rank used and the damping its
    /// smallest kept singular value calls for.
    fn factor_level(&mut self, j: usize, dim: usize, rows: usize) -> (usize, f64) {
        let n = self.stack.dof();
        let start = self.seg_start[j];
        let a = &mut self.qr[n * start..n * start + dim * rows];
        let tau = &mut self.tau[start..start + rows];
        let perm = &mut self.perm[start..start + rows];
        // Rounding leaves ~1e-16 of a row's norm behind in the directions removed by the levels
        // above; on rows of any scale that noise must not count as rank.
        let tolerance = self
            .settings
            .rank_tolerance
            .max(RELATIVE_RANK_TOLERANCE * self.row_scale);
        let rank = qr_col_pivoting(a, dim, rows, tolerance, tau, perm);
        let mut damping = 0.0;
        if rank > 0 {
            let sigma = a[(rank - 1) * dim + rank - 1].abs();
            let eps = self.settings.damping_threshold;
            if sigma < eps {
                let ratio = sigma / eps;
                damping = self.settings.max_damping * (1.0 - ratio * ratio).sqrt();
            }
        }
        self.report.levels[j].rank = rank;
        self.report.levels[j].rows = rows;
        self.report.levels[j].damping = damping;
        (rank, damping)
    }

    /// Level j's right-hand side ([`Solver::level_rhs`]) and its least-squares coefficients
    /// `w_j` from the level's factorization; with `factor`, a damped or rank-deficient level's
    /// stacked matrix is factored first (once per pass: the repeats reuse it).
    fn solve_level(&mut self, j: usize, factor: bool) {
        self.level_rhs(j);
        let n = self.stack.dof();
        let start = self.seg_start[j];
        let LevelFactor {
            dim,
            rank,
            rows,
            damping,
        } = self.factors[j];
        let a = &self.qr[n * start..n * start + dim * rows];
        let perm = &self.perm[start..start + rows];
        let w = &mut self.coeff[start..start + rows];
        w.fill(0.0);
        if rank > 0 {
            let c = &mut self.ls_rhs[..rows + rank];
            for (ck, &p) in c.iter_mut().zip(perm.iter()) {
                *ck = self.rhs[start + p];
            }
            if rank == rows && damping == 0.0 {
                solve_upper_transposed(a, dim, rank, c);
            } else {
                // min ‖[Rᵀ; μ I] w − [c; μ w_ref]‖ by a QR of the stacked matrix, w_ref the
                // damping reference's coordinates (0 without one), scaled with the level.
                let aug_rows = rows + if damping > 0.0 { rank } else { 0 };
                let m = &mut self.damped_qr[self.damped_start[j]..][..aug_rows * rank];
                let tau = &mut self.damped_tau[start..start + rank];
                if factor {
                    m.fill(0.0);
                    for l in 0..rank {
                        // Rᵀ is lower-trapezoidal; below R's diagonal `a` holds reflectors.
                        for t in l..rows {
                            m[l * aug_rows + t] = a[t * dim + l];
                        }
                        if damping > 0.0 {
                            m[l * aug_rows + rows + l] = damping;
                        }
                    }
                    qr_factor(m, aug_rows, rank, tau);
                }
                c[rows..aug_rows].fill(0.0);
                // A level holding inequality rows at their bounds is damped toward rest: a
                // bound must not give way to the last step's momentum.
                let equalities = self.stack.level_start(j + 1) - self.stack.level_start(j);
                if damping > 0.0 && self.damp_toward_reference && rows == equalities {
                    let reference = &self.reference_coeff[start..start + rank];
                    for (ck, &r) in c[rows..aug_rows].iter_mut().zip(reference) {
                        *ck = damping * self.scales[j] * r;
                    }
                }
                apply_qt(m, aug_rows, rank, tau, &mut c[..aug_rows]);
                solve_upper(m, aug_rows, rank, c);
            }
            w[..rank].copy_from_slice(&c[..rank]);
        }
    }

    /// `q̇ = q̇_clamped + Z_0 (Σ_j Z-chain [w_j] + Z_N Z_Nᵀ g)`, folding the levels back from the
    /// deepest.
    fn assemble_velocity(&mut self) {
        let n = self.stack.dof();
        let levels = self.stack.level_count();
        // Z_Nᵀ g: the gradient through every level's reflectors.
        let gradient = self.stack.gradient();
        for (c, &i) in self.coords.iter_mut().zip(&self.free) {
            *c = self.scales[levels] * gradient[i];
        }
        let mut offset = apply_chain(
            &self.qr,
            n,
            &self.tau,
            &self.factors,
            &self.seg_start,
            &mut self.coords,
            n,
        );
        // Fold back: at level j the vector is [w_j; (deeper part)] in r_{j−1} coordinates.
        for j in (0..levels).rev() {
            let f = self.factors[j];
            let start = self.seg_start[j];
            offset -= f.rank;
            let factor = &self.qr[n * start..];
            let cur = &mut self.coords[offset..offset + f.dim];
            cur[..f.rank].copy_from_slice(&self.coeff[start..start + f.rank]);
            for l in (0..f.rank).rev() {
                apply_reflector(
                    &factor[l * f.dim + l..(l + 1) * f.dim],
                    self.tau[start + l],
                    &mut cur[l..],
                );
            }
        }
        self.velocity.copy_from_slice(&self.fixed_velocity);
        for (&c, &i) in self.coords.iter().zip(&self.free) {
            self.velocity[i] = c;
        }
    }

    /// Whether joint intervals and inequality rows are handled by the active-set method.
    pub(super) fn uses_active_set(&self) -> bool {
        self.settings.limits_by_active_set || self.stack.total_inequality_rows() > 0
    }

    /// Residuals, violations and feasibility of every level for the final velocity, and the
    /// active inequality rows.
    pub(super) fn finish_report(&mut self) {
        self.report.gradient_scale = self.scales[self.scales.len() - 1];
        self.report.active.clear();
        for j in 0..self.stack.level_count() {
            let (violation, bound_scale) = self.level_violation(j);
            let start = self.stack.level_start(j);
            let end = self.stack.level_start(j + 1);
            let targets = &self.stack.stacked_target()[start..end];
            // Reuse the least-squares scratch for the residual vector.
            let r = &mut self.ls_rhs[..end - start];
            for (t, (ri, &x)) in r.iter_mut().zip(targets).enumerate() {
                *ri = dot(self.stack.row(start + t), &self.velocity) - x;
            }
            let residual = norm(r);
            let level = &mut self.report.levels[j];
            level.residual = norm(&[residual, violation]);
            level.violation = violation;
            level.feasible = level.residual
                <= self.settings.feasibility_tolerance * (1.0 + norm(targets) + bound_scale);
            level.scale = self.scales[j];
        }
    }

    /// `‖v_j‖` of level j's inequality rows for the final velocity, and the norm of the bounds
    /// they violate (for the relative tolerance); lists the level's active rows in the report.
    fn level_violation(&mut self, j: usize) -> (f64, f64) {
        let (first, last) = (
            self.stack.inequality_start(j),
            self.stack.inequality_start(j + 1),
        );
        let (mut violation, mut bounds) = (0.0_f64, 0.0_f64);
        for r in first..last {
            let value = dot(self.stack.inequality_row(r), &self.velocity);
            let (lower, upper) = self.stack.inequality_bounds(r);
            let (v, b) = if value > upper {
                (value - upper, upper)
            } else if value < lower {
                (lower - value, lower)
            } else {
                (0.0, 0.0)
            };
            violation = norm(&[violation, v]);
            bounds = norm(&[bounds, b]);
            if let Some(bound) = self.inequality_state[r] {
                self.report.active.push(ActiveInequality {
                    level: j,
                    row: r - first,
                    bound,
                });
            }
        }
        (violation, bounds)
    }
}
