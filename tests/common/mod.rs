//! Shared helpers for the integration tests.
#![allow(dead_code)]

use std::sync::OnceLock;

use stickslip::cpu::{InitialState, PathResult, RunPlan};
use stickslip::gpu::{self, GpuContext, PointSpec};
use stickslip::model::Oscillator;

/// One GPU context per test binary. On CI this is lavapipe: GPU tests never skip.
pub fn gpu() -> &'static GpuContext {
    static CONTEXT: OnceLock<GpuContext> = OnceLock::new();
    CONTEXT.get_or_init(|| GpuContext::new(true).expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)"))
}

/// Runs `realisations` paths of one point on the GPU.
pub fn gpu_paths(osc: &Oscillator, initial: InitialState, seed: u64, realisations: u32, plan: RunPlan) -> Vec<PathResult> {
    let ctx = gpu();
    let range = stickslip::reduce::PeakRange { lo_m: -0.01, hi_m: 0.01 };
    let points = [PointSpec { oscillator: osc.clone(), initial, range }];
    let request = gpu::EnsembleRequest {
        points: &points,
        realisations_per_point: realisations,
        realisation_offset: 0,
        seed,
        plan,
        steps_per_dispatch: gpu::DEFAULT_STEPS_PER_DISPATCH,
        record_peaks: true,
    };
    gpu::run_ensemble(&ctx.device, &ctx.queue, &ctx.kernels, &request, &mut |_, _| {})
        .expect("GPU ensemble runs")
        .paths
        .expect("recorded paths")
}
