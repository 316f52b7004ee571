//! The environment a human moves in: horizontal planar surfaces (the floor, a table top, a stool
//! seat) that hands, feet or knees can rest on.
//!
//! # Frame and units
//!
//! Metres and degrees, in the world frame of [`crate::human`] (z up; x and y as the clip reader
//! defines them). A surface is a horizontal rectangle at height `height`: its centre `(x, y)`, its
//! size along its own axes, and its yaw (the angle of its first axis from x, counter-clockwise
//! seen from above). A surface without a size is unbounded: the floor, at most one per scene.
//!
//! # File
//!
//! A scene file is TOML: one `[[surface]]` table per surface. `name` and `height` are required;
//! `centre` (default `[0, 0]`), `size` (default: unbounded) and `yaw` (default 0) are optional.
//! An unknown field is an error.
//!
//! ```toml
//! [[surface]]
//! name = "floor"
//! height = 0.0
//!
//! [[surface]]
//! name = "table"
//! centre = [0.6, 0.0]   # m
//! size = [0.8, 1.2]     # m, along the table's own axes
//! yaw = 90.0            # degrees
//! height = 0.72         # m
//! ```

use std::path::Path;

use nalgebra::{Rotation2, Vector2, Vector3};
use serde::Deserialize;
use thiserror::Error;

/// Error reading or building a [`Scene`].
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file cannot be read.
    #[error("cannot read scene {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Malformed TOML, a missing or unknown field (the message names the line).
    #[error("scene {path}: {message}")]
    Syntax {
        /// The file, or `<text>`.
        path: String,
        /// The parser's message.
        message: String,
    },
    /// A surface's value is out of range (names the surface and the field).
    #[error("surface {surface:?}: {reason}")]
    Invalid {
        /// The surface's name.
        surface: String,
        /// What is wrong.
        reason: String,
    },
}

/// A named surface of a scene: a horizontal rectangle (or the unbounded plane) something can
/// rest on.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    name: String,
    shape: SurfaceShape,
}

/// The geometry of a surface, without its name (so that it can be copied freely): a horizontal
/// rectangle, or the unbounded plane, at a height. Metres and radians, in whichever frame it was
/// built in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceShape {
    centre: Vector2<f64>,
    half_size: Option<Vector2<f64>>,
    yaw: f64,
    height: f64,
}

impl Surface {
    /// The unbounded horizontal plane at `height` (m), named `name`.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] if `height` is not finite.
    pub fn plane(name: impl Into<String>, height: f64) -> Result<Self, SceneError> {
        Self::build(name.into(), [0.0; 2], None, 0.0, height)
    }

    /// A horizontal rectangle centred at `centre` (m), `size` (m) long along its own axes,
    /// turned by `yaw_deg` (degrees) about z, at `height` (m).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] for a non-finite value or a size that is not positive.
    pub fn rectangle(
        name: impl Into<String>,
        centre: [f64; 2],
        size: [f64; 2],
        yaw_deg: f64,
        height: f64,
    ) -> Result<Self, SceneError> {
        Self::build(name.into(), centre, Some(size), yaw_deg, height)
    }

    fn build(
        name: String,
        centre: [f64; 2],
        size: Option<[f64; 2]>,
        yaw_deg: f64,
        height: f64,
    ) -> Result<Self, SceneError> {
        let invalid = |reason: &str| SceneError::Invalid {
            surface: name.clone(),
            reason: reason.to_owned(),
        };
        if !(centre.iter().all(|v| v.is_finite()) && yaw_deg.is_finite() && height.is_finite()) {
            return Err(invalid("centre, yaw and height must be finite"));
        }
        if let Some(size) = size
            && !size.iter().all(|&s| s.is_finite() && s > 0.0)
        {
            return Err(invalid("size must be positive and finite (m)"));
        }
        let shape = SurfaceShape {
            centre: Vector2::from(centre),
            half_size: size.map(|s| Vector2::new(s[0], s[1]) / 2.0),
            yaw: yaw_deg.to_radians(),
            height,
        };
        Ok(Self { name, shape })
    }

    /// The surface's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its geometry.
    pub fn shape(&self) -> &SurfaceShape {
        &self.shape
    }
}

impl SurfaceShape {
    /// The rectangle's centre (m, xy); the origin for an unbounded surface.
    pub fn centre(&self) -> Vector2<f64> {
        self.centre
    }

    /// Half the rectangle's length and width along its own axes (m); `None` when unbounded.
    pub fn half_size(&self) -> Option<Vector2<f64>> {
        self.half_size
    }

    /// The rectangle's turn about z (rad).
    pub fn yaw(&self) -> f64 {
        self.yaw
    }

    /// The surface's height (m).
    pub fn height(&self) -> f64 {
        self.height
    }

    /// Whether the surface is unbounded (the floor).
    pub fn is_unbounded(&self) -> bool {
        self.half_size.is_none()
    }

    /// The rectangle's corners (m, xy; counter-clockwise from `+x +y` in its own axes); `None`
    /// when unbounded.
    pub fn corners(&self) -> Option<[Vector2<f64>; 4]> {
        let half = self.half_size?;
        let turn = Rotation2::new(self.yaw);
        Some(
            [[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]
                .map(|[sx, sy]| self.centre + turn * Vector2::new(sx * half.x, sy * half.y)),
        )
    }

    /// `xy` in the rectangle's own axes, relative to its centre (m).
    fn local(&self, xy: Vector2<f64>) -> Vector2<f64> {
        Rotation2::new(-self.yaw) * (xy - self.centre)
    }

    /// How far the vertical projection of `point` lies outside the rectangle (m): 0 over the
    /// surface, the horizontal distance to its nearest edge or corner otherwise; 0 everywhere
    /// for an unbounded surface.
    pub fn outside_distance(&self, point: &Vector3<f64>) -> f64 {
        let Some(half) = self.half_size else {
            return 0.0;
        };
        let excess = self.local(point.xy()).abs() - half;
        excess.sup(&Vector2::zeros()).norm()
    }

    /// Height of `point` above the surface's plane (m; negative below it).
    pub fn height_above(&self, point: &Vector3<f64>) -> f64 {
        point.z - self.height
    }

    /// The point of the rectangle shrunk by `margin` (m) on every side nearest to `xy` (m); the
    /// centre line or the centre when the margin eats a whole side; `xy` itself when unbounded.
    pub fn nearest_inside(&self, xy: Vector2<f64>, margin: f64) -> Vector2<f64> {
        let Some(half) = self.half_size else {
            return xy;
        };
        let room = (half - Vector2::repeat(margin)).sup(&Vector2::zeros());
        let local = self.local(xy).zip_map(&room, |v, r| v.clamp(-r, r));
        self.centre + Rotation2::new(self.yaw) * local
    }

    /// The image of the surface under the similarity `x ↦ to + scale·R(turn)·(x − from)` of the
    /// horizontal plane (`turn` in rad about z), at `height` (m): how a surface of one frame
    /// looks in another that is turned, shifted and scaled about a point the two frames share.
    pub fn mapped(
        &self,
        from: Vector2<f64>,
        to: Vector2<f64>,
        scale: f64,
        turn: f64,
        height: f64,
    ) -> SurfaceShape {
        SurfaceShape {
            centre: to + Rotation2::new(turn) * (self.centre - from) * scale,
            half_size: self.half_size.map(|h| h * scale),
            yaw: self.yaw + turn,
            height,
        }
    }
}

/// The surfaces of an environment, in the order given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    surfaces: Vec<Surface>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    surface: Vec<SurfaceFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SurfaceFile {
    name: String,
    height: f64,
    #[serde(default)]
    centre: [f64; 2],
    size: Option<[f64; 2]>,
    #[serde(default)]
    yaw: f64,
}

impl Scene {
    /// A scene of `surfaces`.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] if two surfaces share a name, or more than one is unbounded (the
    /// floor is the one unbounded surface; contact detection learns its real height).
    pub fn new(surfaces: Vec<Surface>) -> Result<Self, SceneError> {
        for (i, s) in surfaces.iter().enumerate() {
            let earlier = &surfaces[..i];
            let reason = if earlier.iter().any(|t| t.name == s.name) {
                "two surfaces have this name"
            } else if s.shape.is_unbounded() && earlier.iter().any(|t| t.shape.is_unbounded()) {
                "a second unbounded surface: give it a size"
            } else {
                continue;
            };
            return Err(SceneError::Invalid {
                surface: s.name.clone(),
                reason: reason.to_owned(),
            });
        }
        Ok(Self { surfaces })
    }

    /// Reads a scene file (see the module docs for its format).
    ///
    /// # Errors
    /// [`SceneError::Io`], [`SceneError::Syntax`] (naming the line), [`SceneError::Invalid`].
    pub fn from_toml_file(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Reads a scene from TOML text (see the module docs for its format).
    ///
    /// # Errors
    /// As [`Scene::from_toml_file`], without the I/O.
    pub fn from_toml_str(text: &str) -> Result<Self, SceneError> {
        Self::parse(text, "<text>")
    }

    fn parse(text: &str, path: &str) -> Result<Self, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| SceneError::Syntax {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        let surfaces = file
            .surface
            .into_iter()
            .map(|s| Surface::build(s.name, s.centre, s.size, s.yaw, s.height))
            .collect::<Result<Vec<_>, _>>()?;
        Self::new(surfaces)
    }

    /// The surfaces, in the order given.
    pub fn surfaces(&self) -> &[Surface] {
        &self.surfaces
    }

    /// The index of the surface named `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.surfaces.iter().position(|s| s.name == name)
    }
}
