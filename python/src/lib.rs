//! Python bindings of taskstack: the extension module `taskstack._taskstack`, wrapped by the
//! pure-Python package `taskstack` (`python/taskstack/`), which documents the API and adds the
//! result types.
//!
//! * `imitate`: `imitate_clip` (a clip file in, arrays out: the numbers of `taskstack
//!   imitate`) and `Imitator` (live, one human frame at a time).
//! * `live`: `LiveSession` (frames streamed in over TCP or UDP, robot frames out).
//! * `kinematics`: `Model` (the NAO, the G1, any URDF): forward kinematics, Jacobians, CoM.
//! * `solve`: `Task` and `TaskSet`, the prioritized solver on its own.
//! * `description`: `robot_description`, what `taskstack.sim` builds a physics model from.
//!
//! Errors become Python exceptions carrying the Rust message (`errors`): `ValueError` for bad
//! input, `OSError` for files; no panic crosses the boundary (a panic would become
//! `pyo3_runtime.PanicException`; the library returns typed errors instead).

use pyo3::prelude::*;

mod description;
mod errors;
mod imitate;
mod kinematics;
mod live;
mod solve;

#[pymodule]
fn _taskstack(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(imitate::imitate_clip, m)?)?;
    m.add_function(wrap_pyfunction!(imitate::read_clip, m)?)?;
    m.add_function(wrap_pyfunction!(description::robot_description, m)?)?;
    m.add_class::<imitate::PyImitator>()?;
    m.add_class::<live::PyLiveSession>()?;
    m.add_class::<kinematics::PyModel>()?;
    m.add_class::<solve::PyTask>()?;
    m.add_class::<solve::PyTaskSet>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
