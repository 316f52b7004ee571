//! A BVH skeleton whose joints do not carry the CMU names, mapped to the human skeleton by a small
//! TOML file ([`SkeletonMap`]), so that any BVH clip can be imitated without code.
//!
//! ```toml
//! scale = 0.01        # metres per file unit (optional; default 0.01, centimetres)
//! up = "y"            # the file's up axis, "y" or "z" (optional; default "y")
//! skip_frames = 1     # leading frames that are not motion, e.g. a T-pose (optional; default 0)
//!
//! [joints]            # human joint (HumanJoint::name) = the BVH joint that stands for it
//! Pelvis = "hip"
//! LHip = "lThigh"
//! RHip = "rThigh"
//! # … every human joint the robot's profile maps should be here; a BVH joint named here
//! # must exist in the file, and each BVH joint may stand for one human joint only.
//! ```
//!
//! Names are case-sensitive. The human joints are those of [`HumanJoint::name`] (`Pelvis`,
//! `MidHip`, `LHip`, …; `MidHip` is derived from the hips when not mapped).

use std::path::Path;

use serde::Deserialize;
use std::collections::BTreeMap;
use thiserror::Error;

use super::bvh::{BvhConfig, BvhNames, UpAxis};
use crate::human::HumanJoint;

/// Errors of reading a skeleton map; each names the file (or `<string>`).
#[derive(Debug, Error)]
pub enum SkeletonMapError {
    /// The file could not be read.
    #[error("{origin}: {source}")]
    Io {
        /// The file.
        origin: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not valid TOML, or an unknown or mistyped field.
    #[error("{origin}: {message}")]
    Syntax {
        /// The file.
        origin: String,
        /// The parser's message, with line and column.
        message: String,
    },
    /// A field's value is out of range or unknown.
    #[error("{origin}: `{field}`: {reason}")]
    Invalid {
        /// The file.
        origin: String,
        /// The field, e.g. `joints.LHip` or `scale`.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    scale: Option<f64>,
    up: Option<String>,
    skip_frames: Option<usize>,
    joints: BTreeMap<String, String>,
}

/// How to read a BVH file with a skeleton of its own: the reader's settings (unit, up axis,
/// name map) and how many leading frames to skip.
#[derive(Debug, Clone, PartialEq)]
pub struct SkeletonMap {
    /// Settings for [`super::bvh::BvhReader`], with [`BvhNames::Custom`].
    pub config: BvhConfig,
    /// Leading frames that are not motion (a calibration pose), dropped by
    /// [`super::clip::Clip::open_mapped`].
    pub skip_frames: usize,
}

impl SkeletonMap {
    /// Reads a skeleton map file (format in the module docs).
    ///
    /// # Errors
    /// [`SkeletonMapError`] naming the file and the field at fault.
    pub fn from_toml_file(path: impl AsRef<Path>) -> Result<Self, SkeletonMapError> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| SkeletonMapError::Io {
            origin: origin.clone(),
            source,
        })?;
        Self::from_toml_str(&text, &origin)
    }

    /// Reads a skeleton map from `text`; `origin` names it in errors.
    ///
    /// # Errors
    /// As [`SkeletonMap::from_toml_file`].
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self, SkeletonMapError> {
        let file: File = toml::from_str(text).map_err(|e| SkeletonMapError::Syntax {
            origin: origin.to_owned(),
            message: e.to_string(),
        })?;
        let invalid = |field: &str, reason: String| SkeletonMapError::Invalid {
            origin: origin.to_owned(),
            field: field.to_owned(),
            reason,
        };
        let scale = file.scale.unwrap_or(0.01);
        if !(scale.is_finite() && scale > 0.0) {
            return Err(invalid(
                "scale",
                format!("{scale} is not a positive length"),
            ));
        }
        let up = match file.up.as_deref().unwrap_or("y") {
            "y" | "Y" => UpAxis::Y,
            "z" | "Z" => UpAxis::Z,
            other => {
                return Err(invalid(
                    "up",
                    format!("{other:?} is neither \"y\" nor \"z\""),
                ));
            }
        };
        let mut names = Vec::with_capacity(file.joints.len());
        for (human, bvh) in file.joints {
            let field = format!("joints.{human}");
            let joint = HumanJoint::from_name(&human)
                .ok_or_else(|| invalid(&field, format!("{human:?} is not a human joint")))?;
            if names.iter().any(|(name, _)| *name == bvh) {
                return Err(invalid(
                    &field,
                    format!("{bvh:?} stands for two human joints"),
                ));
            }
            names.push((bvh, joint));
        }
        if names.is_empty() {
            return Err(invalid("joints", "maps no joint".to_owned()));
        }
        Ok(SkeletonMap {
            config: BvhConfig {
                scale,
                up,
                names: BvhNames::Custom(names),
                ..BvhConfig::cmu()
            },
            skip_frames: file.skip_frames.unwrap_or(0),
        })
    }
}
