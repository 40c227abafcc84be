//! Shared helpers for the integration tests.

use std::sync::OnceLock;

use stickslip::engine::gpu::GpuContext;
use stickslip::engine::{
    Condition, Engine, GpuOptions, InitialState, Job, Model, PathResult, PeakRange, Point, Record, RunPlan, Sample,
};

/// One GPU engine per test binary. On CI this is lavapipe: GPU tests never skip.
pub fn gpu() -> &'static Engine {
    static ENGINE: OnceLock<Engine> = OnceLock::new();
    ENGINE.get_or_init(|| {
        let ctx = GpuContext::new(true).expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)");
        Engine::gpu(ctx, GpuOptions::default())
    })
}

/// The f64 reference.
pub fn cpu() -> &'static Engine {
    static ENGINE: OnceLock<Engine> = OnceLock::new();
    ENGINE.get_or_init(|| Engine::cpu("tests"))
}

/// Runs `realisations` paths of one point on `engine`, each from `initial`.
pub fn paths(
    engine: &Engine,
    model: &Model,
    condition: Condition,
    initial: InitialState,
    seed: u64,
    realisations: u32,
    plan: RunPlan,
) -> Vec<PathResult> {
    let range = PeakRange { lo_m: -0.01, hi_m: 0.01, phase_ref_rad: 0.0 };
    let points = [Point { condition, initial, range, realisation_offset: 0 }];
    let job = Job { model, points: &points, realisations, first_realisation: 0, seed, plan, record: Record::Peaks };
    engine.paths(&job).expect("the ensemble runs")
}

/// One realisation's record on the reference: `seconds` of samples at
/// 600 Hz (or `rate_hz`) after `warmup` periods, from the frictionless
/// steady state.
pub fn record(model: &Model, condition: Condition, seed: u64, warmup: u32, seconds: f64, rate_hz: f64) -> Vec<Sample> {
    let points = [Point::steady(model, condition)];
    let plan = RunPlan { warmup_cycles: warmup, measured_cycles: 0 };
    let job = Job { model, points: &points, realisations: 1, first_realisation: 0, seed, plan, record: Record::Sums };
    cpu().records(&job, 1.0 / rate_hz, seconds).expect("the record runs").remove(0)
}
