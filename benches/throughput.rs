//! Throughput of the GPU kernel and the CPU reference, in realisation-steps
//! per second (one step = one of `steps_per_period` RK4 steps of one
//! realisation; noise boundaries and events add work inside a step), at
//! several ensemble sizes so the scaling with work shows.
//!
//! Workload: the default paper rig at 7 Hz and 16.39 N (noise on, ~3%
//! sticking), 256 steps per period (the default before it became 64, kept
//! so the rates stay comparable with `benches/RESULTS.md`), 20 cycles per
//! realisation.
//!
//!     cargo bench --bench throughput
//!
//! The GPU sizes suit lavapipe on a few cores; a real GPU needs far more
//! realisations to fill it. `STICKSLIP_BENCH_GPU_SIZES` (three comma-separated
//! counts, e.g. `65536,262144,1048576`) replaces them.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use stickslip::engine::gpu::GpuContext;
use stickslip::engine::{Condition, Engine, GpuOptions, Job, Model, Point, Record, RunPlan};

const PLAN: RunPlan = RunPlan { warmup_cycles: 0, measured_cycles: 20 };
const CONDITION: Condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };

fn steps(realisations: u32, model: &Model) -> u64 {
    u64::from(realisations) * u64::from(PLAN.measured_cycles) * u64::from(model.solver.steps_per_period)
}

fn throughput(c: &mut Criterion, group: &str, engine: &Engine, sizes: [u32; 3]) {
    eprintln!("{group}: {}", engine.description());
    let model = Model::paper_rig(&["solver.steps_per_period=256".into()]).expect("the paper rig");
    let points = [Point::steady(&model, CONDITION)];
    let mut group = c.benchmark_group(group);
    group.sample_size(10);
    for realisations in sizes {
        group.throughput(Throughput::Elements(steps(realisations, &model)));
        group.bench_with_input(BenchmarkId::from_parameter(realisations), &realisations, |b, &r| {
            let job = Job {
                model: &model,
                points: &points,
                realisations: r,
                first_realisation: 0,
                seed: 1,
                plan: PLAN,
                record: Record::Sums,
            };
            b.iter(|| engine.run(&job, &mut |_, _| {}).unwrap())
        });
    }
    group.finish();
}

/// The GPU ensemble sizes: `STICKSLIP_BENCH_GPU_SIZES` when set, else sizes
/// that suit lavapipe.
fn gpu_sizes() -> [u32; 3] {
    let Ok(list) = std::env::var("STICKSLIP_BENCH_GPU_SIZES") else {
        return [1024, 4096, 16384];
    };
    let sizes: Vec<u32> = list
        .split(',')
        .map(|s| s.trim().parse().expect("STICKSLIP_BENCH_GPU_SIZES: counts like 65536,262144,1048576"))
        .collect();
    sizes.try_into().expect("STICKSLIP_BENCH_GPU_SIZES: exactly three counts")
}

fn gpu_throughput(c: &mut Criterion) {
    let ctx = GpuContext::new(true).expect("a GPU adapter (lavapipe will do)");
    throughput(c, "gpu", &Engine::gpu(ctx, GpuOptions::default()), gpu_sizes());
}

fn cpu_throughput(c: &mut Criterion) {
    throughput(c, "cpu", &Engine::cpu("bench"), [256, 1024, 4096]);
}

criterion_group!(benches, gpu_throughput, cpu_throughput);
criterion_main!(benches);
