//! `Model`: a kinematic tree (the NAO, the G1 or any URDF) with forward kinematics, Jacobians
//! and the centre of mass, in the model's base frame (m, rad).

use std::path::PathBuf;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use taskstack::IsometryMatrix3;
use taskstack::faer::Mat;
use taskstack::model::{Model, ModelData, UrdfOptions};
use taskstack::robots::{g1, nao};

use crate::errors::{to_py, value_error};

/// A kinematic model and its forward-kinematics workspace.
#[pyclass(name = "Model", module = "taskstack._taskstack")]
pub(crate) struct PyModel {
    pub(crate) model: Model,
    data: ModelData,
}

impl PyModel {
    pub(crate) fn new(model: Model) -> Self {
        let data = model.new_data();
        Self { model, data }
    }

    /// Forward kinematics at `q`, checked: one finite angle per variable.
    pub(crate) fn compute(&mut self, q: &[f64]) -> PyResult<()> {
        if q.len() != self.model.nv() {
            return Err(value_error(format!(
                "q has {} values, the model {} variables",
                q.len(),
                self.model.nv()
            )));
        }
        self.model
            .forward_kinematics(&mut self.data, q)
            .map_err(to_py)
    }
}

#[pymethods]
impl PyModel {
    /// The NAO H25 V5 from its DH tables, rooted at `root`: "r_sole", "l_sole" or "torso".
    #[staticmethod]
    #[pyo3(signature = (root = "r_sole"))]
    fn nao(root: &str) -> PyResult<Self> {
        let model = match root {
            "r_sole" => nao::rfoot(),
            "l_sole" => nao::lfoot(),
            "torso" => nao::torso(),
            other => {
                return Err(value_error(format!(
                    "NAO root {other:?}: expected \"r_sole\", \"l_sole\" or \"torso\""
                )));
            }
        };
        Ok(Self::new(model))
    }

    /// The Unitree G1 (29 DoF) from its bundled URDF, rooted at the link `root` ("left_sole",
    /// "right_sole", or None for the pelvis).
    #[staticmethod]
    #[pyo3(signature = (root = None))]
    fn g1(root: Option<&str>) -> PyResult<Self> {
        g1::from_urdf_str(g1::URDF, root)
            .map(Self::new)
            .map_err(to_py)
    }

    /// Any URDF file, rooted at the link `root` (None: the URDF's root); every link is a frame.
    #[staticmethod]
    #[pyo3(signature = (path, root = None))]
    fn from_urdf(path: PathBuf, root: Option<&str>) -> PyResult<Self> {
        let options = UrdfOptions {
            root_link: root.map(str::to_owned),
            link_frames: true,
            ..UrdfOptions::default()
        };
        Model::from_urdf_file(path, &options)
            .map(Self::new)
            .map_err(to_py)
    }

    /// Number of variables (joint angles, rad).
    #[getter]
    fn nv(&self) -> usize {
        self.model.nv()
    }

    /// The variable names, in the order of `q`.
    #[getter]
    fn variable_names(&self) -> Vec<String> {
        self.model
            .variables()
            .iter()
            .map(|v| v.name.clone())
            .collect()
    }

    /// The named frames.
    #[getter]
    fn frame_names(&self) -> Vec<String> {
        self.model.frames().iter().map(|f| f.name.clone()).collect()
    }

    /// Lower and upper joint limits (rad), two arrays of `nv`.
    #[getter]
    fn limits<'py>(
        &self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>) {
        let vars = self.model.variables();
        (
            PyArray1::from_iter(py, vars.iter().map(|v| v.lower)),
            PyArray1::from_iter(py, vars.iter().map(|v| v.upper)),
        )
    }

    /// Total mass (kg).
    #[getter]
    fn total_mass(&self) -> f64 {
        self.model.total_mass()
    }

    /// Every frame's placement at `q`: a dict name -> 4 x 4 homogeneous matrix (base frame, m).
    fn fk_all<'py>(&mut self, py: Python<'py>, q: Vec<f64>) -> PyResult<Bound<'py, PyDict>> {
        self.compute(&q)?;
        let out = PyDict::new(py);
        for (frame, placement) in self.model.frames().iter().zip(self.data.frame_placements()) {
            out.set_item(&frame.name, matrix(py, placement))?;
        }
        Ok(out)
    }

    /// The placement of `frame` at `q`: a 4 x 4 homogeneous matrix (base frame, m).
    fn fk<'py>(
        &mut self,
        py: Python<'py>,
        q: Vec<f64>,
        frame: &str,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let id = self.model.frame_id(frame).map_err(to_py)?;
        self.compute(&q)?;
        Ok(matrix(py, self.data.frame_placement(id)))
    }

    /// The centre of mass at `q` (base frame, m), shape (3,).
    fn com<'py>(&mut self, py: Python<'py>, q: Vec<f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.compute(&q)?;
        let c = self.model.com(&self.data).map_err(to_py)?;
        Ok(PyArray1::from_slice(py, c.as_slice()))
    }

    /// The Jacobian of `frame` at `q`, shape (6, nv): rows 0–2 the origin's linear velocity
    /// (m/s per rad/s), rows 3–5 the angular velocity (base frame).
    fn jacobian<'py>(
        &mut self,
        py: Python<'py>,
        q: Vec<f64>,
        frame: &str,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let id = self.model.frame_id(frame).map_err(to_py)?;
        self.compute(&q)?;
        let nv = self.model.nv();
        let mut linear = Mat::<f64>::zeros(3, nv);
        let mut angular = Mat::<f64>::zeros(3, nv);
        let origin = taskstack::Vector3::zeros();
        self.model
            .point_jacobian(&self.data, id, &origin, linear.as_mut())
            .map_err(to_py)?;
        self.model
            .orientation_jacobian(&self.data, id, angular.as_mut())
            .map_err(to_py)?;
        let j = Array2::from_shape_fn((6, nv), |(r, c)| {
            if r < 3 {
                linear[(r, c)]
            } else {
                angular[(r - 3, c)]
            }
        });
        Ok(j.into_pyarray(py))
    }

    /// The CoM Jacobian at `q`, shape (3, nv) (m/s per rad/s, base frame).
    fn com_jacobian<'py>(
        &mut self,
        py: Python<'py>,
        q: Vec<f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.compute(&q)?;
        let nv = self.model.nv();
        let mut j = Mat::<f64>::zeros(3, nv);
        self.model
            .com_jacobian(&self.data, j.as_mut())
            .map_err(to_py)?;
        Ok(Array2::from_shape_fn((3, nv), |(r, c)| j[(r, c)]).into_pyarray(py))
    }
}

/// A placement as a 4 × 4 homogeneous matrix.
pub(crate) fn matrix<'py>(
    py: Python<'py>,
    placement: &IsometryMatrix3<f64>,
) -> Bound<'py, PyArray2<f64>> {
    let m = placement.to_homogeneous();
    Array2::from_shape_fn((4, 4), |(r, c)| m[(r, c)]).into_pyarray(py)
}
