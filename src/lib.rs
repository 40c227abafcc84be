//! stickslip: ensembles of a stochastic stick-slip friction oscillator.

pub mod analytic;
pub mod cli;
pub mod cpu;
pub mod diagnose;
pub mod effects;
pub mod features;
pub mod error;
pub mod gpu;
pub mod io;
pub mod measure;
pub mod model;
pub mod plot;
pub mod reduce;
pub mod report;
pub mod rng;
pub mod sweep;
pub mod synthetic;

pub use error::{Error, Result};
