//! Live imitation from Python: `LiveSession`, the CLI's `taskstack live` as an iterator of
//! robot frames (the library's `taskstack::live`).

use std::path::Path;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use taskstack::Imitator;
use taskstack::export::MotionRecorder;
use taskstack::human::HumanFrame;
use taskstack::io::FrameSource;
use taskstack::live::transport::Input;
use taskstack::live::{LiveConfig, LiveSource};

use crate::errors::{to_py, value_error};
use crate::imitate::{Settings, robot_frame_dict};

/// Human frames streamed in (TCP or UDP, one frame a line), imitated as each arrives; iterating
/// the session gives the robot frames (the dicts of `Imitator.step`) until the stream ends.
// Unsendable: the imitator keeps scratch space in `RefCell`s (see `Imitator`).
#[pyclass(name = "LiveSession", module = "taskstack._taskstack", unsendable)]
pub(crate) struct PyLiveSession {
    source: LiveSource,
    imitator: Imitator,
    recorder: MotionRecorder,
    frame: HumanFrame,
    /// The robot asked for the last human frame again (a hand being placed).
    again: bool,
}

#[pymethods]
impl PyLiveSession {
    #[new]
    #[pyo3(signature = (listen = None, connect = None, udp = None, robot = "nao", bvh_header = None,
                        once = false, end_after = None, **options))]
    #[allow(clippy::too_many_arguments)] // the CLI's options, as keywords
    fn new(
        py: Python<'_>,
        listen: Option<String>,
        connect: Option<String>,
        udp: Option<String>,
        robot: &str,
        bvh_header: Option<String>,
        once: bool,
        end_after: Option<f64>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let input = match (listen, connect, udp) {
            (Some(a), None, None) => Input::TcpListen(a),
            (None, Some(a), None) => Input::TcpConnect(a),
            (None, None, Some(a)) => Input::Udp(a),
            _ => return Err(value_error("give exactly one of listen, connect, udp")),
        };
        let header = bvh_header
            .map(|path| {
                let text = std::fs::read_to_string(Path::new(&path))?;
                taskstack::live::bvh_header(&text).ok_or_else(|| {
                    value_error(format!("{path}: no `Frame Time:` line: not a BVH file"))
                })
            })
            .transpose()?;
        let settings = Settings::from_kwargs(options)?;
        let profile = settings.profile(robot)?;
        let config = LiveConfig {
            end_after,
            ..LiveConfig::default()
        };
        config.validate().map_err(to_py)?;
        let origin = input.origin();
        let (arrivals, _) = input.open(once)?;
        // The first line may be long in coming: Python threads run meanwhile.
        let source = py
            .detach(|| LiveSource::start(arrivals, header.as_deref(), &origin, config))
            .map_err(to_py)?;
        let imitator = Imitator::new(profile, settings.config(source.capture())?).map_err(to_py)?;
        let recorder = MotionRecorder::new(&imitator).map_err(to_py)?;
        Ok(Self {
            source,
            imitator,
            recorder,
            frame: HumanFrame::new(0.0),
            again: false,
        })
    }

    /// The robot's joint names, in the order of `q`.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.imitator.variable_names().map(str::to_owned).collect()
    }

    /// What the session met so far (the CLI's `live` counts).
    #[getter]
    fn counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for (name, count) in self.source.counts().named() {
            out.set_item(name, count)?;
        }
        Ok(out)
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        if !self.again {
            let (source, frame) = (&mut self.source, &mut self.frame);
            let more = py.detach(|| source.read_frame(frame)).map_err(to_py)?;
            if !more {
                return Ok(None);
            }
        }
        let frame = self.imitator.step(&self.frame).map_err(to_py)?;
        self.again = frame.awaiting_contact;
        let (root_pos, root_quat) = self.recorder.base_pose(frame).map_err(to_py)?;
        let contacts = self.recorder.contacts(frame);
        robot_frame_dict(py, frame, root_pos, root_quat, contacts).map(Some)
    }
}
