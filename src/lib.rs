#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod batch;
pub mod human;
pub mod imitation;
pub mod io;
pub mod model;
pub mod problem;
pub mod robots;
pub mod solver;
pub mod tasks;
