//! `robot_description`: what a physics model of a built-in robot is generated from (the
//! URDF text the crate's models come from, how its joints map to the `joints.csv` columns,
//! the profile's soles, floating base and standing posture), so that `taskstack.sim` builds it
//! from the same facts as the Rust models.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use taskstack::human::Side;
use taskstack::model::{JointKind, Model};
use taskstack::robots::{BipedProfile, g1, nao};

use crate::errors::{profile_error, to_py};
use crate::imitate::profile;

/// The NAO H25 V5 URDF (qibullet's, no meshes): the second derivation of the NAO in this
/// repository (its README is beside it), and the source of its physics model.
const NAO_URDF: &str = include_str!("../../tests/data/nao.urdf");

/// The description of `robot` (`"nao"`, `"g1"` or a profile file); see the Python docstring.
#[pyfunction]
pub(crate) fn robot_description<'py>(py: Python<'py>, robot: &str) -> PyResult<Bound<'py, PyDict>> {
    let (urdf, model, profile): (String, Model, BipedProfile) = match robot {
        "nao" => (
            NAO_URDF.to_owned(),
            nao::from_urdf_str(NAO_URDF, None).map_err(to_py)?,
            nao::profile(),
        ),
        "g1" => (
            g1::urdf_with_soles(g1::URDF).map_err(to_py)?,
            g1::pelvis(),
            g1::profile(),
        ),
        path => {
            let (urdf, options) =
                BipedProfile::physics_source(path).map_err(|e| profile_error(path, e))?;
            let model = Model::from_urdf_str(&urdf, &options).map_err(to_py)?;
            (urdf, model, profile(path)?)
        }
    };
    let variables = model.variables();
    let joints = PyList::empty(py);
    for joint in model.joints() {
        let entry = PyDict::new(py);
        entry.set_item("name", &joint.name)?;
        let variable = match joint.kind {
            JointKind::Fixed => None,
            _ => joint.variable.map(|v| variables[v].name.clone()),
        };
        entry.set_item("variable", variable)?;
        entry.set_item("multiplier", joint.multiplier)?;
        entry.set_item("offset", joint.offset)?;
        joints.append(entry)?;
    }
    let out = PyDict::new(py);
    out.set_item("name", &profile.name)?;
    out.set_item("urdf", urdf)?;
    out.set_item("base", &profile.torso)?;
    out.set_item("joints", joints)?;
    out.set_item(
        "variables",
        variables.iter().map(|v| v.name.clone()).collect::<Vec<_>>(),
    )?;
    out.set_item(
        "lower",
        PyArray1::from_iter(py, variables.iter().map(|v| v.lower)),
    )?;
    out.set_item(
        "upper",
        PyArray1::from_iter(py, variables.iter().map(|v| v.upper)),
    )?;
    out.set_item(
        "velocity",
        PyArray1::from_iter(py, variables.iter().map(|v| v.velocity)),
    )?;
    let soles = PyList::empty(py);
    for side in [Side::Left, Side::Right] {
        let foot = profile.foot(side);
        let sole = PyDict::new(py);
        sole.set_item("link", &foot.sole)?;
        sole.set_item("outline", foot.outline.clone())?;
        soles.append(sole)?;
    }
    out.set_item("soles", soles)?;
    // The standing posture by name: the profile's models and the URDF model order their
    // variables alike for the built-in robots, but a name is what the caller matches.
    let stand = PyDict::new(py);
    let names = profile
        .model(Side::Right)
        .variables()
        .iter()
        .map(|v| v.name.as_str());
    for (name, q) in names.zip(&profile.stand) {
        stand.set_item(name, *q)?;
    }
    out.set_item("stand", stand)?;
    out.set_item("total_mass", model.total_mass())?;
    Ok(out)
}
