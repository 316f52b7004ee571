//! Built-in robots: models built from data files shipped with the crate.

pub mod g1;
pub mod nao;
