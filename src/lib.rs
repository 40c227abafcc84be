//! stickslip: ensembles of a stochastic stick-slip friction oscillator on the
//! GPU (WGSL through wgpu) with an exact f64 CPU reference, reduced into
//! frequency-response statistics, and a diagnosis of where and why a
//! simulation departs from measurements.
//!
//! - [`engine`]: the model, the two integrators and the exact reductions,
//!   behind one entry point ([`engine::Engine::run`]);
//! - [`sweep`]: frequency × normal-force grids, shards, merge and figures;
//! - [`measure`]: measurement sets, read and checked (or written), which the
//!   sweep figures and the diagnosis both use;
//! - [`diagnose`]: features, calibration, candidates, verdict, report and the
//!   blind benchmark;
//! - [`io`], [`text`] and [`figure`]: atomic files, quoted text for
//!   messages and shared drawing helpers;
//! - [`budget`]: the work a run may take before it needs `--force`;
//! - [`app`]: what a front end does with a request, which the command line
//!   and the Python package share;
//! - [`cli`]: the command line, the only module that uses `anyhow`.

pub mod app;
pub mod budget;
pub mod cli;
pub mod diagnose;
pub mod engine;
pub mod error;
pub mod figure;
pub mod io;
pub mod measure;
pub mod sweep;
pub mod text;
mod vector;

pub use error::{Error, Result};
