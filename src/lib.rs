//! stickslip: ensembles of a stochastic stick-slip friction oscillator.

pub mod analytic;
pub mod cli;
pub mod cpu;
pub mod effects;
pub mod error;
pub mod gpu;
pub mod io;
pub mod model;
pub mod plot;
pub mod reduce;
pub mod rng;
pub mod sweep;

pub use error::{Error, Result};
