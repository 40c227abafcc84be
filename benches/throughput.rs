//! Throughput of the GPU kernel and the CPU reference, in realisation-steps
//! per second (one step = one of `steps_per_period` RK4 steps of one
//! realisation; noise boundaries and events add work inside a step), at
//! several ensemble sizes so the scaling with work shows.
//!
//! Workload: the default paper rig at 7 Hz and 16.39 N (noise on, ~3%
//! sticking), 256 steps per period, 20 cycles per realisation.
//!
//!     cargo bench --bench throughput

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use stickslip::cpu::{simulate_ensemble, RunPlan};
use stickslip::gpu::{self, GpuContext, PointSpec};
use stickslip::model::{Condition, Model, Oscillator};
use stickslip::reduce::PeakRange;
use stickslip::sweep::initial_state;

const PLAN: RunPlan = RunPlan { warmup_cycles: 0, measured_cycles: 20 };

fn workload() -> (Model, Condition, Oscillator) {
    let model = Model::default();
    let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
    let osc = Oscillator::new(&model, condition).unwrap();
    (model, condition, osc)
}

fn steps(realisations: u32, osc: &Oscillator) -> u64 {
    u64::from(realisations) * u64::from(PLAN.measured_cycles) * u64::from(osc.steps_per_period)
}

fn gpu_throughput(c: &mut Criterion) {
    let ctx = GpuContext::new(true).expect("a GPU adapter (lavapipe will do)");
    eprintln!("adapter: {}", ctx.describe());
    let (model, condition, osc) = workload();
    let points = [PointSpec { oscillator: osc.clone(), initial: initial_state(&model, condition), range: PeakRange::for_point(&model, condition) }];
    let mut group = c.benchmark_group("gpu");
    group.sample_size(10);
    for realisations in [1024u32, 4096, 16384] {
        group.throughput(Throughput::Elements(steps(realisations, &osc)));
        group.bench_with_input(BenchmarkId::from_parameter(realisations), &realisations, |b, &r| {
            let request = gpu::EnsembleRequest {
                points: &points,
                realisations_per_point: r,
                realisation_offset: 0,
                seed: 1,
                plan: PLAN,
                steps_per_dispatch: gpu::DEFAULT_STEPS_PER_DISPATCH,
                record_peaks: false,
            };
            b.iter(|| gpu::run_ensemble(&ctx.device, &ctx.queue, &ctx.kernels, &request, &mut |_, _| {}).unwrap())
        });
    }
    group.finish();
}

fn cpu_throughput(c: &mut Criterion) {
    let (model, condition, osc) = workload();
    let initial = initial_state(&model, condition);
    let mut group = c.benchmark_group("cpu");
    group.sample_size(10);
    for realisations in [256u32, 1024, 4096] {
        group.throughput(Throughput::Elements(steps(realisations, &osc)));
        group.bench_with_input(BenchmarkId::from_parameter(realisations), &realisations, |b, &r| {
            b.iter(|| simulate_ensemble(&osc, 1, 0..r, PLAN, initial))
        });
    }
    group.finish();
}

criterion_group!(benches, gpu_throughput, cpu_throughput);
criterion_main!(benches);
