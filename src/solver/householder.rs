//! Householder reflectors and small QR factorizations on contiguous column slices.
//!
//! A reflector is `H = I − τ v vᵀ` with `v[0] = 1` implied; `make_reflector` overwrites `x` with
//! `β` in `x[0]` and `v[1..]` in `x[1..]`, such that `H x_original = β e₁`. The matrices here are
//! small (a task level has at most tens of rows), column-major, with columns contiguous, so every
//! kernel is a dot product or an axpy over a slice. Sizes are checked by the callers.

/// Euclidean norm, scaled only when the plain sum of squares over- or underflows.
pub(crate) fn norm(x: &[f64]) -> f64 {
    let sum_sq: f64 = x.iter().map(|v| v * v).sum();
    if sum_sq.is_finite() && sum_sq > f64::MIN_POSITIVE {
        return sum_sq.sqrt();
    }
    let scale = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return scale;
    }
    // Divide rather than multiply by 1/scale: for a subnormal scale, 1/scale overflows to
    // infinity and the norm came out NaN.
    scale
        * x.iter()
            .map(|v| (v / scale) * (v / scale))
            .sum::<f64>()
            .sqrt()
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Turns `x` into a reflector in place (see the module docs) and returns `τ`.
pub(crate) fn make_reflector(x: &mut [f64]) -> f64 {
    let Some((&mut alpha, tail)) = x.split_first_mut() else {
        return 0.0;
    };
    let tail_norm = norm(tail);
    if tail_norm == 0.0 {
        return 0.0;
    }
    let full = norm(&[alpha, tail_norm]);
    let beta = if alpha >= 0.0 { -full } else { full };
    let tau = (beta - alpha) / beta;
    let denom = alpha - beta;
    if denom.abs() >= f64::MIN_POSITIVE {
        let scale = 1.0 / denom;
        tail.iter_mut().for_each(|v| *v *= scale);
    } else {
        // 1/denom would overflow to infinity for a subnormal denom.
        tail.iter_mut().for_each(|v| *v /= denom);
    }
    x[0] = beta;
    tau
}

/// Applies the reflector stored in `v` (with `v[0] = 1` implied) to `y`: `y ← (I − τ v vᵀ) y`.
pub(crate) fn apply_reflector(v: &[f64], tau: f64, y: &mut [f64]) {
    if tau == 0.0 {
        return;
    }
    let s = tau * (y[0] + dot(&v[1..], &y[1..]));
    y[0] -= s;
    for (yi, vi) in y[1..].iter_mut().zip(&v[1..]) {
        *yi -= s * vi;
    }
}

/// Householder QR with column pivoting of the `rows × cols` column-major matrix `a`, truncated at
/// the first pivot whose remaining column norm is `≤ tol`.
///
/// On return the leading `rank` columns hold `R` on and above the diagonal and the reflectors below
/// it, `tau[..rank]` their factors, and `perm[k]` the original index of column `k`. Columns
/// `rank..` are left partially reduced; they belong to the discarded (numerically null) part.
pub(crate) fn qr_col_pivoting(
    a: &mut [f64],
    rows: usize,
    cols: usize,
    tol: f64,
    tau: &mut [f64],
    perm: &mut [usize],
) -> usize {
    for (k, p) in perm[..cols].iter_mut().enumerate() {
        *p = k;
    }
    let steps = rows.min(cols);
    for k in 0..steps {
        let (mut best, mut best_norm) = (k, -1.0);
        for c in k..cols {
            let nrm = norm(&a[c * rows + k..(c + 1) * rows]);
            if nrm > best_norm {
                (best, best_norm) = (c, nrm);
            }
        }
        if best_norm <= tol {
            return k;
        }
        if best != k {
            for i in 0..rows {
                a.swap(k * rows + i, best * rows + i);
            }
            perm.swap(k, best);
        }
        let (head, rest) = a.split_at_mut((k + 1) * rows);
        let v = &mut head[k * rows + k..];
        tau[k] = make_reflector(v);
        for c in 0..cols - k - 1 {
            apply_reflector(v, tau[k], &mut rest[c * rows + k..(c + 1) * rows]);
        }
    }
    steps
}

/// Householder QR without pivoting of the `rows × cols` column-major matrix `a` (`rows ≥ cols`).
/// On return `a` holds `R` on and above the diagonal and the reflectors below it, `tau[..cols]`
/// their factors: [`apply_qt`] applies `Qᵀ` to any number of right-hand sides.
pub(crate) fn qr_factor(a: &mut [f64], rows: usize, cols: usize, tau: &mut [f64]) {
    for k in 0..cols {
        let (head, rest) = a.split_at_mut((k + 1) * rows);
        let v = &mut head[k * rows + k..];
        tau[k] = make_reflector(v);
        for c in 0..cols - k - 1 {
            apply_reflector(v, tau[k], &mut rest[c * rows + k..(c + 1) * rows]);
        }
    }
}

/// `b ← Qᵀ b` (length `rows`) for the factorization [`qr_factor`] left in `a` and `tau`: then
/// `b[..cols]` holds `(Qᵀ b)[..cols]`.
pub(crate) fn apply_qt(a: &[f64], rows: usize, cols: usize, tau: &[f64], b: &mut [f64]) {
    for k in 0..cols {
        apply_reflector(&a[k * rows + k..(k + 1) * rows], tau[k], &mut b[k..rows]);
    }
}

/// Solves `R x = b` in place for the upper-triangular `n × n` block of the column-major `a` with
/// leading dimension `lda`. Diagonal entries are non-zero by construction of the callers.
pub(crate) fn solve_upper(a: &[f64], lda: usize, n: usize, b: &mut [f64]) {
    for i in (0..n).rev() {
        let mut s = b[i];
        for j in i + 1..n {
            s -= a[j * lda + i] * b[j];
        }
        b[i] = s / a[i * lda + i];
    }
}

/// Solves `Rᵀ x = b` in place for the upper-triangular `n × n` block of the column-major `a` with
/// leading dimension `lda`.
pub(crate) fn solve_upper_transposed(a: &[f64], lda: usize, n: usize, b: &mut [f64]) {
    for i in 0..n {
        let s = b[i] - dot(&a[i * lda..i * lda + i], &b[..i]);
        b[i] = s / a[i * lda + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflector_maps_vector_to_multiple_of_e1() {
        let original = [3.0, 4.0, 0.0, 12.0];
        let mut x = original;
        let tau = make_reflector(&mut x);
        // ‖(3, 4, 0, 12)‖ = 13, and β takes the sign opposite to x[0].
        assert!((x[0] + 13.0).abs() < 1e-12);
        let mut y = original;
        apply_reflector(&x, tau, &mut y);
        assert!((y[0] + 13.0).abs() < 1e-12);
        assert!(y[1..].iter().all(|v| v.abs() < 1e-12));
    }

    #[test]
    fn pivoted_qr_reveals_rank_of_dependent_columns() {
        // Columns: c0, c1 = 2·c0, c2 independent. Rank 2.
        let mut a = [1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, -1.0];
        let (mut tau, mut perm) = ([0.0; 3], [0; 3]);
        let rank = qr_col_pivoting(&mut a, 3, 3, 1e-12, &mut tau, &mut perm);
        assert_eq!(rank, 2);
        // The largest column (2·c0, norm 2√14) is chosen first.
        assert_eq!(perm[0], 1);
        assert!((a[0].abs() - 2.0 * 14f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn one_factorization_solves_several_least_squares_right_hand_sides() {
        // A = [[1, 0], [0, 1], [1, 1]] (column-major). By hand, x = (AᵀA)⁻¹ Aᵀ b with
        // (AᵀA)⁻¹ = ⅓ [[2, −1], [−1, 2]]: b = (1, 2, 3) gives Aᵀb = (4, 5), x = (1, 2);
        // b = (1, 0, 0) gives Aᵀb = (1, 0), x = (⅔, −⅓).
        let mut a = [1.0, 0.0, 1.0, 0.0, 1.0, 1.0];
        let mut tau = [0.0; 2];
        qr_factor(&mut a, 3, 2, &mut tau);
        for (b, x) in [
            ([1.0, 2.0, 3.0], [1.0, 2.0]),
            ([1.0, 0.0, 0.0], [2.0 / 3.0, -1.0 / 3.0]),
        ] {
            let mut b = b;
            apply_qt(&a, 3, 2, &tau, &mut b);
            solve_upper(&a, 3, 2, &mut b);
            assert!(
                (b[0] - x[0]).abs() < 1e-14 && (b[1] - x[1]).abs() < 1e-14,
                "{b:?}"
            );
        }
    }

    #[test]
    fn norm_survives_huge_and_tiny_entries() {
        assert!((norm(&[3e200, 4e200]) / 5e200 - 1.0).abs() < 1e-15);
        assert!((norm(&[3e-200, 4e-200]) - 5e-200).abs() < 1e-212);
        // Subnormal largest entry (found by tests/suite/hardening_solver.rs: the residual was NaN).
        assert_eq!(norm(&[0.0, -5e-311]), 5e-311);
        assert_eq!(norm(&[5e-324, 5e-324]), 5e-324 * 2f64.sqrt());
    }

    #[test]
    fn reflector_of_subnormal_entries_is_finite() {
        // ‖x‖ subnormal: the reflector must still be finite (1/(α − β) overflowed).
        let mut x = [0.0, 3e-311, 4e-311];
        let tau = make_reflector(&mut x);
        assert!(
            tau.is_finite() && x.iter().all(|v| v.is_finite()),
            "{tau} {x:?}"
        );
        // Applied to the original vector it gives (β, 0, 0) with |β| = ‖x‖ = 5e-311.
        let mut y = [0.0, 3e-311, 4e-311];
        apply_reflector(&x, tau, &mut y);
        assert!(
            (y[0].abs() - 5e-311).abs() < 1e-323 && y[1].abs() < 1e-323,
            "{y:?}"
        );
    }
}
