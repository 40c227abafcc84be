//! Records on the GPU: sampled at the noise boundaries by the kernel, they
//! agree with the CPU reference's sample by sample on the same noise keys;
//! sampled otherwise, the GPU engine hands them to the CPU reference.

use stickslip::engine::{Condition, Job, Model, Point, Record, RunPlan, Sample};

use crate::common;

/// (frequency Hz, normal force N): no sticking, and sticking much of the time.
const CONDITIONS: [(f64, f64); 2] = [(7.0, 7.519), (12.0, 16.39)];
const WARMUP_CYCLES: u32 = 7;

/// The signals of a sample: x (m), v (m/s), N (N), friction force (N).
fn signals(s: &Sample) -> [f64; 4] {
    [s.x_m, s.v_m_per_s, s.normal_force_n, s.friction_force_n]
}

/// Each signal's largest magnitude in a record: the scale its differences
/// are measured against.
fn scales(record: &[Sample]) -> [f64; 4] {
    let mut scale = [0.0f64; 4];
    for s in record {
        for (k, v) in signals(s).into_iter().enumerate() {
            scale[k] = scale[k].max(v.abs());
        }
    }
    scale
}

/// Sample `k`'s difference per signal, relative to the CPU record's scales.
fn differences(cpu: &Sample, gpu: &Sample, scale: [f64; 4]) -> [f64; 4] {
    let (c, g) = (signals(cpu), signals(gpu));
    std::array::from_fn(|k| (g[k] - c[k]).abs() / scale[k])
}

/// Runs the noise-aligned records of `seconds` at both conditions on both
/// engines and returns, per record, (point index, CPU, GPU).
fn records(model: &Model, realisations: u32, seconds: f64) -> Vec<(usize, Vec<Sample>, Vec<Sample>)> {
    let points: Vec<Point> = CONDITIONS
        .iter()
        .map(|&(f, n)| Point::steady(model, Condition { excitation_frequency_hz: f, normal_force_n: n }))
        .collect();
    let job = Job {
        model,
        points: &points,
        realisations,
        first_realisation: 5,
        seed: 77,
        plan: RunPlan { warmup_cycles: WARMUP_CYCLES, measured_cycles: 0 },
        record: Record::Samples { interval_s: model.noise.interval_s, duration_s: seconds, at_noise_boundaries: true },
    };
    let cpu = common::cpu().run(&job, &mut |_, _| {}).expect("the CPU records run").records;
    let gpu = common::gpu().run(&job, &mut |_, _| {}).expect("the GPU records run").records;
    assert_eq!(cpu.len(), points.len() * realisations as usize);
    assert_eq!(gpu.len(), cpu.len());
    cpu.into_iter().zip(gpu).enumerate().map(|(i, (c, g))| (i / realisations as usize, c, g)).collect()
}

/// Largest differences of x, v, N and F between agreeing samples, each
/// relative to the signal's largest magnitude in its CPU record: what was
/// measured on lavapipe (over 48 records of 4 s per condition) is
/// [1.9e-6, 1.6e-6, 2.7e-6, 4.8e-6]; the tolerances are about 5× that, f32
/// rounding carried through a few periods.
const TOLERANCE: [f64; 4] = [1e-5, 1e-5, 1e-5, 2e-5];

/// Checks one model's records: the same sample count and times (the host
/// derives the GPU's times from the noise boundaries exactly as the CPU
/// does), and x, v, N and F within [`TOLERANCE`] sample by sample.
///
/// A record may split from its reference only at a stick/slip event: a
/// breakaway or a velocity zero that falls within about 1e-9 s of a noise
/// boundary lands on either side of it in f32 (then one engine samples the
/// block stuck and the other slipping, and F differs by up to 0.2 of its
/// scale at that sample), or a breakaway near the base's turning point,
/// where its time is ill-conditioned in f32 (then x differs by up to 5e-3
/// of its scale for the next slip). So each record must agree until its
/// first split, which must be at a sample where either engine has the block
/// stuck (v = 0) at it or the one before; at the second condition at most
/// `most_split` records may split (measured: 6 of 48 records of 4 s), at
/// the first (no sticking) none. The second condition's CPU records must
/// be stuck at `least_stuck` of their samples or more.
fn assert_records_agree(
    label: &str,
    model: &Model,
    realisations: u32,
    seconds: f64,
    most_split: usize,
    least_stuck: f64,
) {
    let expected = (seconds / model.noise.interval_s).round() as usize;
    let mut worst = [0.0f64; 4];
    let mut split = [0usize; 2];
    let (mut stuck, mut sampled) = ([0usize; 2], [0usize; 2]);
    for (i, (point, cpu, gpu)) in records(model, realisations, seconds).iter().enumerate() {
        assert_eq!(cpu.len(), expected, "{label}: record {i} on the CPU");
        assert_eq!(gpu.len(), cpu.len(), "{label}: record {i}: sample counts");
        for (c, g) in cpu.iter().zip(gpu) {
            assert_eq!(c.t_s, g.t_s, "{label}: record {i}: sample times");
        }
        assert!(cpu[0].t_s >= 0.0 && cpu[0].t_s < model.noise.interval_s, "{label}: first sample at {}", cpu[0].t_s);
        stuck[*point] += cpu.iter().filter(|s| s.v_m_per_s == 0.0).count();
        sampled[*point] += cpu.len();
        let scale = scales(cpu);
        let beyond = |k: usize| differences(&cpu[k], &gpu[k], scale).iter().zip(TOLERANCE).any(|(d, t)| *d > t);
        let agreeing = (0..cpu.len()).position(beyond).unwrap_or(cpu.len());
        for k in 0..agreeing {
            let d = differences(&cpu[k], &gpu[k], scale);
            for (w, d) in worst.iter_mut().zip(d) {
                *w = w.max(d);
            }
        }
        if agreeing < cpu.len() {
            split[*point] += 1;
            let at_event =
                (agreeing.saturating_sub(1)..=agreeing).any(|k| cpu[k].v_m_per_s == 0.0 || gpu[k].v_m_per_s == 0.0);
            let (c, g) = (&cpu[agreeing], &gpu[agreeing]);
            println!("{label}: record {i} splits at t = {:.5} s: cpu {c:?}, gpu {g:?}", c.t_s);
            assert!(at_event, "{label}: record {i} splits from the reference away from any stick at t = {} s", c.t_s);
        }
    }
    let stuck_fraction = |p: usize| stuck[p] as f64 / sampled[p] as f64;
    println!(
        "{label}: largest differences x {:.1e} v {:.1e} N {:.1e} F {:.1e} of scale; stuck samples {:.3} and {:.3}; \
         records split {split:?}",
        worst[0],
        worst[1],
        worst[2],
        worst[3],
        stuck_fraction(0),
        stuck_fraction(1)
    );
    assert!(
        stuck_fraction(1) >= least_stuck,
        "{label}: the second condition must stick (stuck {:.3} < {least_stuck})",
        stuck_fraction(1)
    );
    assert!(worst.iter().any(|&w| w > 0.0), "{label}: the GPU's records are the f64 reference's, not the kernel's");
    assert_eq!(split[0], 0, "{label}: records without sticking split from the reference");
    assert!(split[1] <= most_split, "{label}: {} records split from the reference at stick/slip events", split[1]);
}

/// The paper rig, 4 s of record at the noise rate (600 Hz) after 7 warm-up
/// periods, at a condition without sticking and one that sticks much of the
/// time (12 Hz, 16.39 N), 16 realisations each.
#[test]
fn gpu_records_at_the_noise_boundaries_agree_with_the_cpu() {
    let model = Model::paper_rig(&[]).expect("the paper rig");
    assert_records_agree("baseline", &model, 16, 4.0, 4, 0.1);
}

/// The same (2 s, 8 realisations) with two effects on, normal-force
/// harmonics and hysteresis, so the records carry the model's effects on
/// the GPU too (hysteresis keeps the block slipping at both conditions).
#[test]
fn gpu_records_carry_the_effects() {
    let overrides: Vec<String> = [
        "normal_force_harmonics.amplitudes_n=[0.4, 0.3, 0.0, 0.1]",
        "normal_force_harmonics.phases_rad=[0.3, 0.1, 0.0, 2.0]",
        "friction_hysteresis.length_m=2e-4",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let model = Model::paper_rig(&overrides).expect("the paper rig with effects");
    assert_records_agree("harmonics and hysteresis", &model, 8, 2.0, 2, 0.0);
}

/// A record sampled between the noise boundaries (here 500 Hz against the
/// noise's 600 Hz) still runs on the GPU engine: it falls back to the CPU
/// reference, so it is the reference's record exactly.
#[test]
fn gpu_engine_records_off_the_noise_boundaries_fall_back_to_the_cpu() {
    let model = Model::paper_rig(&[]).expect("the paper rig");
    let points = [Point::steady(&model, Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 })];
    let job = Job {
        model: &model,
        points: &points,
        realisations: 2,
        first_realisation: 0,
        seed: 3,
        plan: RunPlan { warmup_cycles: 2, measured_cycles: 0 },
        record: Record::Samples { interval_s: 1.0 / 500.0, duration_s: 0.2, at_noise_boundaries: true },
    };
    let cpu = common::cpu().run(&job, &mut |_, _| {}).expect("the CPU records run").records;
    let gpu = common::gpu().run(&job, &mut |_, _| {}).expect("the GPU engine's records run").records;
    assert_eq!(cpu.len(), 2);
    assert_eq!(cpu[0].len(), 100);
    assert_eq!(gpu, cpu);
}

/// A point's realisation offset moves its noise paths and nothing else:
/// point `p`'s record `r` of a job whose points have offsets 0 and 1000 is,
/// bit for bit, the record of realisation `first + offset_p + r` run alone
/// at that point, on each engine (so a diagnosis can simulate every
/// measured unit's replicates in one job, each unit on paths of its own);
/// and the offset point's records are not those of offset 0.
#[test]
fn realisation_offsets_key_each_points_own_paths() {
    let model = Model::paper_rig(&[]).expect("the paper rig");
    let points: Vec<Point> = CONDITIONS
        .iter()
        .zip([0, 1000])
        .map(|(&(f, n), offset)| Point {
            realisation_offset: offset,
            ..Point::steady(&model, Condition { excitation_frequency_hz: f, normal_force_n: n })
        })
        .collect();
    fn job<'a>(model: &'a Model, points: &'a [Point], first_realisation: u32) -> Job<'a> {
        Job {
            model,
            points,
            realisations: 2,
            first_realisation,
            seed: 11,
            plan: RunPlan { warmup_cycles: 3, measured_cycles: 0 },
            record: Record::Samples { interval_s: model.noise.interval_s, duration_s: 0.5, at_noise_boundaries: true },
        }
    }
    for (name, engine) in [("cpu", common::cpu()), ("gpu", common::gpu())] {
        let run = |job: &Job<'_>| engine.run(job, &mut |_, _| {}).expect("the records run").records;
        let together = run(&job(&model, &points, 3));
        assert_eq!(together.len(), 4, "{name}");
        for (p, point) in points.iter().enumerate() {
            let at_zero = Point { realisation_offset: 0, ..*point };
            let alone = run(&job(&model, &[at_zero], 3 + point.realisation_offset));
            assert_eq!(together[2 * p..2 * p + 2], alone[..], "{name}: point {p}");
        }
        let unshifted = run(&job(&model, &[Point { realisation_offset: 0, ..points[1] }], 3));
        assert_ne!(together[2..4], unshifted[..], "{name}: the offset moved no path");
    }
}
