//! stickslip: ensembles of a stochastic stick-slip friction oscillator.

pub mod analytic;
pub mod cpu;
pub mod error;
pub mod gpu;
pub mod model;
pub mod rng;

pub use error::{Error, Result};
