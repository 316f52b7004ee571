//! The argument checks every public entry of the solver makes: lengths against the stack's
//! shape, values finite. A failed check is a [`SolverError`] naming the argument.

use super::SolverError;

/// `got` values of `what` where `expected` are needed: an error unless equal.
pub(crate) fn check_len(what: &str, expected: usize, got: usize) -> Result<(), SolverError> {
    if expected == got {
        Ok(())
    } else {
        Err(SolverError::DimensionMismatch {
            what: what.to_owned(),
            expected,
            got,
        })
    }
}

/// Whether every value is finite: `0 · v` is ±0 for a finite `v` and NaN otherwise, summed in
/// four independent lanes so that the loop vectorizes.
pub(crate) fn all_finite(values: &[f64]) -> bool {
    let mut lanes = [0.0; 4];
    let chunks = values.chunks_exact(4);
    let rest: f64 = chunks.remainder().iter().map(|v| 0.0 * v).sum();
    for chunk in chunks {
        for (lane, v) in lanes.iter_mut().zip(chunk) {
            *lane += 0.0 * v;
        }
    }
    lanes.iter().sum::<f64>() + rest == 0.0
}

/// An error naming the first non-finite value of `what` and its index, if any.
pub(crate) fn check_finite_slice(what: &str, values: &[f64]) -> Result<(), SolverError> {
    match values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        None => Ok(()),
        Some((i, &value)) => Err(SolverError::NonFinite {
            what: format!("{what} at index {i}"),
            value,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::all_finite;

    /// Every length up to three chunks and a remainder, a bad value at every place: found.
    #[test]
    fn all_finite_finds_a_bad_value_in_every_lane_and_the_remainder() {
        for len in 0..11 {
            let values: Vec<f64> = (0..len).map(|i| f64::MAX / (i + 1) as f64).collect();
            assert!(all_finite(&values), "{len}");
            for at in 0..len {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let mut v = values.clone();
                    v[at] = bad;
                    assert!(!all_finite(&v), "{len} {at} {bad}");
                }
            }
        }
    }
}
