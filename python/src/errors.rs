//! Rust errors as Python exceptions: the message is the Rust error's, its causes appended once
//! each; the class says what went wrong for a Python caller.

use std::error::Error;

use pyo3::PyErr;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use taskstack::robots::ProfileError;

/// The error and its causes, `: `-separated, each once (our messages quote their sources).
pub(crate) fn message(error: &(dyn Error + 'static)) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        let next = cause.to_string();
        if !text.contains(&next) {
            text.push_str(": ");
            text.push_str(&next);
        }
        source = cause.source();
    }
    text
}

/// The I/O error somewhere in `error`'s chain, if any.
fn io_cause<'e>(error: &'e (dyn Error + 'static)) -> Option<&'e std::io::Error> {
    let mut current = Some(error);
    while let Some(e) = current {
        if let Some(io) = e.downcast_ref::<std::io::Error>() {
            return Some(io);
        }
        current = e.source();
    }
    None
}

/// `error` as a Python exception: `FileNotFoundError` or `OSError` when a file could not be
/// read or written, `ValueError` for everything else (bad input: a malformed clip, a number out
/// of range, an unknown frame or joint).
pub(crate) fn to_py(error: impl Error + 'static) -> PyErr {
    let text = message(&error);
    match io_cause(&error) {
        Some(io) if io.kind() == std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(text),
        Some(_) => PyOSError::new_err(text),
        None => PyValueError::new_err(text),
    }
}

/// A `ValueError` with `text`.
pub(crate) fn value_error(text: impl Into<String>) -> PyErr {
    PyValueError::new_err(text.into())
}

/// A profile file's error: the profile error keeps an I/O error's message only, so the class
/// comes from the path (`FileNotFoundError` when it does not exist, `OSError` otherwise).
pub(crate) fn profile_error(path: &str, error: ProfileError) -> PyErr {
    match error {
        ProfileError::Io { .. } if !std::path::Path::new(path).exists() => {
            PyFileNotFoundError::new_err(error.to_string())
        }
        ProfileError::Io { .. } => PyOSError::new_err(error.to_string()),
        other => to_py(other),
    }
}
