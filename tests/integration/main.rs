//! The integration tests, compiled as one binary so that wgpu is linked once.

mod common;

mod agreement;
mod analytic;
mod cli;
mod diagnose;
mod effects;
mod features;
mod hostile;
mod independent;
mod layout;
mod measure;
mod memory;
mod props;
mod records;
mod reliability;
mod rng;
mod sweep;
mod twins;
