//! The centre of mass's ground projection inside a convex support polygon.

use std::any::Any;

use faer::MatMut;
use nalgebra::Vector2;

use super::inequality::InequalityTask;
use super::{TaskError, finite_target};
use crate::model::{Model, ModelData, ModelError};

/// The CoM's ground projection `c_xy` kept inside a convex polygon shrunk by a margin: for each
/// edge `i` with outward unit normal `n_i` through vertex `v_i`,
/// `n_iᵀ c_xy ≤ n_iᵀ v_i − margin` (base frame, metres). One row per edge; named
/// `"com_in_polygon"`.
///
/// The task has a fixed number of rows (the most vertices it will hold); a polygon with fewer
/// vertices leaves the spare rows open (`−∞ ≤ 0 ≤ +∞`), so one stack serves single support (4
/// edges) and double support (a hull of up to 8).
#[derive(Debug, Clone, PartialEq)]
pub struct ComPolygonTask {
    /// Vertices, counter-clockwise seen from above (m, base frame).
    vertices: Vec<[f64; 2]>,
    capacity: usize,
    /// Distance kept from every edge (m, ≥ 0).
    margin: f64,
    /// Each row's edge (outward unit normal, offset `n_iᵀ v_i`), `None` for a spare row:
    /// computed when the polygon is set, not per Jacobian column.
    edges: Vec<Option<([f64; 2], f64)>>,
}

impl ComPolygonTask {
    /// A polygon task with room for `capacity` vertices (≥ 3), holding `vertices` (see
    /// [`ComPolygonTask::set_polygon`]).
    ///
    /// # Errors
    /// As [`ComPolygonTask::set_polygon`]; [`TaskError::Model`] when the model has no mass.
    pub fn new(
        model: &Model,
        capacity: usize,
        vertices: &[[f64; 2]],
        margin: f64,
    ) -> Result<Self, TaskError> {
        if model.total_mass() <= 0.0 {
            return Err(ModelError::NoMass.into());
        }
        let mut task = Self {
            vertices: Vec::with_capacity(capacity),
            capacity,
            margin: 0.0,
            edges: vec![None; capacity],
        };
        task.set_polygon(vertices, margin)?;
        Ok(task)
    }

    /// Replaces the polygon: 3 to `capacity` finite vertices of a convex polygon,
    /// counter-clockwise seen from above (no three consecutive ones on a line), and the margin
    /// (m, finite, ≥ 0). Does not allocate. On error the task is unchanged.
    ///
    /// # Errors
    /// [`TaskError::WrongLength`] for too few or too many vertices, [`TaskError::NonFiniteTarget`]
    /// for a NaN or infinite vertex or margin, [`TaskError::InvalidPolygon`] for a polygon that is
    /// not convex and counter-clockwise, or a negative margin.
    pub fn set_polygon(&mut self, vertices: &[[f64; 2]], margin: f64) -> Result<(), TaskError> {
        let k = vertices.len();
        if k < 3 || k > self.capacity {
            return Err(TaskError::WrongLength {
                task: "com_in_polygon".to_owned(),
                expected: self.capacity,
                got: k,
            });
        }
        finite_target("com_in_polygon", vertices.as_flattened())?;
        finite_target("com_in_polygon", &[margin])?;
        let convex = (0..k).all(|i| {
            let (a, b, c) = (vertices[i], vertices[(i + 1) % k], vertices[(i + 2) % k]);
            (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) > 0.0
        });
        if !convex || margin < 0.0 {
            return Err(TaskError::InvalidPolygon {
                task: "com_in_polygon".to_owned(),
            });
        }
        self.vertices.clear();
        self.vertices.extend_from_slice(vertices);
        self.margin = margin;
        for (i, edge) in self.edges.iter_mut().enumerate() {
            *edge = (i < k).then(|| {
                let (a, b) = (vertices[i], vertices[(i + 1) % k]);
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let length = dx.hypot(dy);
                let n = [dy / length, -dx / length];
                (n, n[0] * a[0] + n[1] * a[1])
            });
        }
        Ok(())
    }

    /// Each row's edge: its outward unit normal `n_i` and offset `n_iᵀ v_i` (m), or `None` for
    /// a spare row.
    pub(crate) fn edges(&self) -> &[Option<([f64; 2], f64)>] {
        &self.edges
    }

    /// The most vertices the task holds (its rows).
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// The distance kept from every edge (m).
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// The vertices (m, base frame, counter-clockwise).
    pub fn vertices(&self) -> &[[f64; 2]] {
        &self.vertices
    }
}

impl InequalityTask for ComPolygonTask {
    fn name(&self) -> &str {
        "com_in_polygon"
    }

    fn rows(&self) -> usize {
        self.capacity
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        mut jacobian: MatMut<'_, f64>,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<(), ModelError> {
        let c = model.com(data)?;
        // The CoM's xy Jacobian rows go into rows 0 and 1 first; each column is then turned
        // into the edges' combinations, reading its two entries before writing any.
        model.com_jacobian_rows(data, 2, jacobian.as_mut().subrows_mut(0, 2))?;
        for col in 0..jacobian.ncols() {
            let (x, y) = (jacobian[(0, col)], jacobian[(1, col)]);
            for (i, edge) in self.edges.iter().enumerate() {
                jacobian[(i, col)] = match edge {
                    Some(([nx, ny], _)) => nx * x + ny * y,
                    None => 0.0,
                };
            }
        }
        for (i, edge) in self.edges.iter().enumerate() {
            lower[i] = f64::NEG_INFINITY;
            upper[i] = match edge {
                Some(([nx, ny], offset)) => offset - self.margin - (nx * c[0] + ny * c[1]),
                None => f64::INFINITY,
            };
        }
        Ok(())
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// Signed distance (m) of `p` to the boundary of the counter-clockwise convex polygon `hull`
/// (as [`convex_hull`] writes it): positive inside; −∞ for fewer than three vertices.
pub fn hull_margin(hull: &[[f64; 2]], p: Vector2<f64>) -> f64 {
    let n = hull.len();
    if n < 3 {
        return f64::NEG_INFINITY;
    }
    (0..n)
        .map(|i| {
            let (a, b) = (Vector2::from(hull[i]), Vector2::from(hull[(i + 1) % n]));
            let edge = b - a;
            edge.perp(&(p - a)) / edge.norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The convex hull of `points` (m), counter-clockwise seen from above without repeated or
/// collinear vertices (Andrew's monotone chain), written into `hull`; `points` is reordered.
/// Fewer than three vertices when the points are all on a line.
pub fn convex_hull(points: &mut [[f64; 2]], hull: &mut Vec<[f64; 2]>) {
    points.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let turns_left = |hull: &[[f64; 2]], p: [f64; 2]| {
        let (o, a) = (hull[hull.len() - 2], hull[hull.len() - 1]);
        (a[0] - o[0]) * (p[1] - o[1]) - (a[1] - o[1]) * (p[0] - o[0]) > 0.0
    };
    hull.clear();
    for &p in points.iter() {
        while hull.len() >= 2 && !turns_left(hull, p) {
            hull.pop();
        }
        hull.push(p);
    }
    let lower = hull.len() + 1;
    for &p in points.iter().rev().skip(1) {
        while hull.len() >= lower && !turns_left(hull, p) {
            hull.pop();
        }
        hull.push(p);
    }
    // The last point pushed is the first vertex again.
    hull.pop();
}
