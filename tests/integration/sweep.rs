//! Sweeps at scale: the GPU reduction against the CPU, chunked and unchunked
//! runs, a grid larger than one binding, and determinism.

use stickslip::engine::gpu::{DEFAULT_STEPS_PER_DISPATCH, GpuContext};
use stickslip::engine::{Condition, Engine, GpuOptions, Model, RunPlan};
use stickslip::sweep::{Grid, SweepResult, SweepSettings, run_sweep};

use crate::common;

fn settings() -> SweepSettings {
    SweepSettings { realisations: 64, plan: RunPlan { warmup_cycles: 10, measured_cycles: 20 }, seed: 5 }
}

fn gpu(steps_per_dispatch: u64, ctx: GpuContext) -> Engine {
    Engine::gpu(ctx, GpuOptions { steps_per_dispatch, ..GpuOptions::default() })
}

fn grid() -> Vec<Condition> {
    Grid { frequencies_hz: vec![5.0, 6.5, 7.0, 9.0, 12.0], normal_forces_n: vec![4.0, 8.0, 12.0, 16.39] }.conditions()
}

fn run(engine: &Engine, s: &SweepSettings) -> SweepResult {
    run_sweep(&Model::default(), &grid(), s, engine, &mut |_, _| {}).unwrap()
}

/// Small binding limits split the 20-point grid into chunks of 8 points
/// (8 KiB of histogram each in 64 KiB); the sums must be bit-identical to a
/// run in one chunk, and to runs split into different dispatches.
#[test]
fn chunked_and_small_binding_runs_equal_the_whole_run() {
    let reference = run(common::gpu(), &settings());
    let tiny_dispatches = run(&gpu(20_000, GpuContext::new(true).unwrap()), &settings());
    assert_eq!(reference, tiny_dispatches, "dispatch split changed the sums");

    let limits = wgpu::Limits {
        max_storage_buffer_binding_size: 64 << 10,
        max_buffer_size: 64 << 10,
        ..wgpu::Limits::default()
    };
    let small = gpu(DEFAULT_STEPS_PER_DISPATCH, GpuContext::with_limits(true, limits).unwrap());
    let chunked = run(&small, &settings());
    assert_eq!(reference, chunked, "chunking the grid changed the sums");
}

/// The GPU's exact reduction agrees with the CPU reference's statistically:
/// with common noise the means agree closely.
#[test]
fn gpu_reduction_matches_cpu_reduction() {
    let s = settings();
    let gpu = run(common::gpu(), &s);
    let cpu = run(common::cpu(), &s);
    for ((g, c), cond) in gpu.rows().iter().zip(cpu.rows()).zip(grid()) {
        assert_eq!(g.peaks, c.peaks);
        let rel = (g.peak_mean_m / c.peak_mean_m - 1.0).abs();
        assert!(rel < 1e-4, "{cond:?}: GPU mean {} vs CPU {}", g.peak_mean_m, c.peak_mean_m);
        assert!(
            (g.stick_fraction - c.stick_fraction).abs() < 2e-3,
            "{cond:?}: stick {} vs {}",
            g.stick_fraction,
            c.stick_fraction
        );
        assert!(
            (g.phase_mean_deg - c.phase_mean_deg).abs() < 1e-2,
            "{cond:?}: phase {} vs {} degrees",
            g.phase_mean_deg,
            c.phase_mean_deg
        );
    }
}
