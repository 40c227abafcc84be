//! The seven effects: at zero strength each reduces to the baseline path by
//! path (CPU and GPU), with strength the CPU and GPU still agree path by path,
//! and each does what its name says (every form of load dependence:
//! adhesion and the load-scaled law have a test of their own; the friction
//! memories are in `memory.rs`).

use stickslip::engine::gpu::AdapterClass;
use stickslip::engine::{Condition, InitialState, Job, Model, Oscillator, PathResult, Point, Record, RunPlan, Sample};

use crate::common;

const PLAN: RunPlan = RunPlan { warmup_cycles: 5, measured_cycles: 15 };
pub(super) const COND: Condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };

/// Every effect in every form, at zero strength.
const ZERO: [&[&str]; 42] = [
    &[
        "normal_force_harmonics.amplitudes_n=[0.0, 0.0, 0.0, 0.0]",
        "normal_force_harmonics.phases_rad=[0.3, 0.1, 0.0, 2.0]",
    ],
    &["normal_force_harmonics.amplitudes_n=[0.0, 0.0, 0.0, 0.0]", "normal_force_harmonics.form=\"bumps\""],
    &["normal_force_harmonics.amplitudes_n=[0.0, 0.0, 0.0, 0.0]", "normal_force_harmonics.form=\"square\""],
    &[
        "normal_force_harmonics.amplitudes_per_n0=[0.0, 0.0, 0.0, 0.0]",
        "normal_force_harmonics.phases_rad=[1.0, 2.0, 0.0, 0.0]",
    ],
    &["normal_force_harmonics.amplitudes_per_n0=[0.0, 0.0, 0.3, 0.3]", "normal_force_harmonics.form=\"position\""],
    &["non_gaussian_friction.strength=0.0"],
    &["non_gaussian_friction.strength=0.0", "non_gaussian_friction.form=\"lognormal\""],
    &["non_gaussian_friction.strength=0.0", "non_gaussian_friction.form=\"tukey_h\""],
    &["non_gaussian_friction.strength=0.0", "non_gaussian_friction.form=\"mixture\""],
    &["non_gaussian_friction.strength=0.0", "non_gaussian_friction.form=\"polynomial\""],
    &["friction_hysteresis.length_m=0.0"],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.form=\"tanh\""],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.form=\"rational\""],
    &["friction_hysteresis.time_constant_s=0.0", "friction_hysteresis.form=\"lag\""],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.form=\"slip\""],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.form=\"dahl\""],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.form=\"bristle\""],
    // Ageing is off at B = 0 whatever its slip distance, and at L = 0
    // whatever its B (no state, no raised steps).
    &["friction_hysteresis.length_m=2e-5", "friction_hysteresis.strength=0.0", "friction_hysteresis.form=\"ageing\""],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.strength=0.05", "friction_hysteresis.form=\"ageing\""],
    &["coloured_friction_noise.correlation_time_s=0.0"],
    &["coloured_friction_noise.correlation_time_s=0.0", "coloured_friction_noise.coloured_share=0.4"],
    &["coloured_friction_noise.correlation_time_s=0.0", "coloured_friction_noise.form=\"hold\""],
    &["coloured_friction_noise.correlation_time_s=0.0", "coloured_friction_noise.form=\"two_scale\""],
    &["coloured_friction_noise.correlation_time_s=0.0", "coloured_friction_noise.form=\"multi_scale\""],
    &[
        "coloured_friction_noise.correlation_time_s=0.0",
        "coloured_friction_noise.form=\"fast_slow\"",
        "coloured_friction_noise.coloured_share=0.6",
    ],
    &["stiction.excess=0.0"],
    &["stiction.excess=0.0", "stiction.form=\"noisy\""],
    &["stiction.excess=0.0", "stiction.form=\"decaying\""],
    &["stiction.excess=0.0", "stiction.release_length_m=3e-4"],
    &["stiction.excess=0.0", "stiction.form=\"dwell\"", "stiction.dwell_time_s=0.05"],
    &["load_dependent_friction.strength=0.0"],
    &["load_dependent_friction.strength=0.0", "load_dependent_friction.form=\"power\""],
    &["load_dependent_friction.strength=0.0", "load_dependent_friction.form=\"saturating\""],
    &["load_dependent_friction.strength=0.0", "load_dependent_friction.form=\"exponential\""],
    &["load_dependent_friction.strength=0.0", "load_dependent_friction.form=\"quadratic\""],
    &["load_dependent_friction.strength=0.0", "load_dependent_friction.form=\"adhesion\""],
    &["load_dependent_friction.strength=0.0", "load_dependent_friction.form=\"scaled\""],
    &["normal_force_drift.rate_per_s=0.0"],
    &["normal_force_drift.rate_per_s=0.0", "normal_force_drift.form=\"saturating\""],
    &["normal_force_drift.rate_per_s=0.0", "normal_force_drift.form=\"wander\""],
    &["normal_force_drift.rate_per_s=0.0", "normal_force_drift.form=\"quadratic\""],
    &["normal_force_drift.rate_per_s=0.0", "normal_force_drift.form=\"random_walk\""],
];

/// Every effect in every form, switched on (the coloured `two_scale` form
/// mixes in a slow part, so its strength is a correlation time), and the
/// one pair whose parts meet in one state (lag and a released stiction).
const ON: [&[&str]; 43] = [
    &[
        "normal_force_harmonics.amplitudes_n=[0.4, 0.3, 0.0, 0.1]",
        "normal_force_harmonics.phases_rad=[0.3, 0.1, 0.0, 2.0]",
    ],
    &[
        "normal_force_harmonics.amplitudes_n=[0.6, 0.0, 0.0, 0.0]",
        "normal_force_harmonics.form=\"bumps\"",
        "normal_force_harmonics.shape=4.0",
    ],
    &[
        "normal_force_harmonics.amplitudes_n=[0.0, 0.5, 0.0, 0.0]",
        "normal_force_harmonics.form=\"square\"",
        "normal_force_harmonics.shape=3.0",
    ],
    &[
        "normal_force_harmonics.amplitudes_per_n0=[0.02, 0.01, 0.0, 0.0]",
        "normal_force_harmonics.phases_rad=[1.0, 2.0, 0.0, 0.0]",
    ],
    &["normal_force_harmonics.amplitudes_per_n0=[0.05, -0.03, 0.0, 0.0]", "normal_force_harmonics.form=\"position\""],
    &["non_gaussian_friction.strength=0.8"],
    &["non_gaussian_friction.strength=0.7", "non_gaussian_friction.form=\"lognormal\""],
    &["non_gaussian_friction.strength=0.2", "non_gaussian_friction.form=\"tukey_h\""],
    &["non_gaussian_friction.strength=0.8", "non_gaussian_friction.form=\"mixture\""],
    // Skewed with tails lighter than a Gaussian's.
    &[
        "non_gaussian_friction.strength=0.25",
        "non_gaussian_friction.cubic=-0.1",
        "non_gaussian_friction.form=\"polynomial\"",
    ],
    &["friction_hysteresis.length_m=2e-4"],
    &["friction_hysteresis.length_m=2e-4", "friction_hysteresis.form=\"tanh\""],
    &["friction_hysteresis.length_m=2e-4", "friction_hysteresis.form=\"rational\""],
    &["friction_hysteresis.time_constant_s=0.01", "friction_hysteresis.form=\"lag\""],
    &["friction_hysteresis.length_m=2e-4", "friction_hysteresis.form=\"slip\""],
    &["friction_hysteresis.length_m=2e-5", "friction_hysteresis.strength=0.05", "friction_hysteresis.form=\"ageing\""],
    &["friction_hysteresis.length_m=2e-4", "friction_hysteresis.form=\"dahl\""],
    &["friction_hysteresis.length_m=2e-4", "friction_hysteresis.form=\"bristle\""],
    &["coloured_friction_noise.correlation_time_s=0.05"],
    &["coloured_friction_noise.correlation_time_s=0.05", "coloured_friction_noise.coloured_share=0.4"],
    &["coloured_friction_noise.correlation_time_s=0.05", "coloured_friction_noise.form=\"hold\""],
    &["coloured_friction_noise.correlation_time_s=0.05", "coloured_friction_noise.form=\"two_scale\""],
    &["coloured_friction_noise.correlation_time_s=0.05", "coloured_friction_noise.form=\"multi_scale\""],
    &[
        "coloured_friction_noise.correlation_time_s=0.01",
        "coloured_friction_noise.form=\"fast_slow\"",
        "coloured_friction_noise.coloured_share=0.6",
    ],
    &["stiction.excess=0.15"],
    &["stiction.excess=0.15", "stiction.form=\"noisy\""],
    &["stiction.excess=0.15", "stiction.form=\"decaying\""],
    &["stiction.excess=0.15", "stiction.release_length_m=3e-4"],
    &["stiction.excess=0.15", "stiction.form=\"dwell\"", "stiction.dwell_time_s=0.02"],
    // A lag on top of a released stiction: the lagged coefficient starts
    // below the static one by the excess the release adds.
    &[
        "stiction.excess=0.15",
        "stiction.release_length_m=3e-4",
        "friction_hysteresis.time_constant_s=0.01",
        "friction_hysteresis.form=\"lag\"",
    ],
    &["load_dependent_friction.strength=0.01"],
    &["load_dependent_friction.strength=0.3", "load_dependent_friction.form=\"power\""],
    &["load_dependent_friction.strength=0.01", "load_dependent_friction.form=\"saturating\""],
    &["load_dependent_friction.strength=0.01", "load_dependent_friction.form=\"exponential\""],
    &[
        "load_dependent_friction.strength=0.01",
        "load_dependent_friction.curvature_per_n2=0.002",
        "load_dependent_friction.form=\"quadratic\"",
    ],
    &["load_dependent_friction.strength=1.0", "load_dependent_friction.form=\"adhesion\""],
    &["load_dependent_friction.strength=-1.0", "load_dependent_friction.form=\"adhesion\""],
    &["load_dependent_friction.strength=0.3", "load_dependent_friction.form=\"scaled\""],
    &["normal_force_drift.rate_per_s=0.01"],
    &["normal_force_drift.rate_per_s=0.01", "normal_force_drift.form=\"saturating\""],
    &["normal_force_drift.rate_per_s=0.01", "normal_force_drift.form=\"wander\""],
    &[
        "normal_force_drift.rate_per_s=0.01",
        "normal_force_drift.curvature_per_s2=-4e-4",
        "normal_force_drift.form=\"quadratic\"",
    ],
    &["normal_force_drift.rate_per_s=1e-3", "normal_force_drift.form=\"random_walk\""],
];

pub(super) fn model(sets: &[&str]) -> Model {
    Model::paper_rig(&sets.iter().map(|s| s.to_string()).collect::<Vec<_>>())
        .unwrap_or_else(|e| panic!("{sets:?}: {e}"))
}

fn paths(m: &Model, realisations: u32) -> (Vec<PathResult>, Vec<PathResult>) {
    let init = InitialState::steady(m, COND);
    (
        common::paths(common::cpu(), m, COND, init, 77, realisations, PLAN),
        common::paths(common::gpu(), m, COND, init, 77, realisations, PLAN),
    )
}

/// Whether two GPU ensembles agree as this adapter can promise: the kernel
/// bakes the effect parameters in, so a zero-strength effect runs another
/// compiled kernel. Lavapipe gives the same bits; a hardware compiler may
/// round f32 differently (8.4e-7 relative at most on an H100), so 1e-5.
fn gpu_paths_agree(a: &[PathResult], b: &[PathResult]) -> bool {
    let software = common::gpu().adapter().is_none_or(|(class, _)| class == AdapterClass::Software);
    if software {
        return a == b;
    }
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-5 * x.abs().max(y.abs()).max(1e-12);
    a.len() == b.len()
        && a.iter().zip(b).all(|(p, q)| {
            p.peaks_m.len() == q.peaks_m.len()
                && p.peaks_m.iter().zip(&q.peaks_m).all(|(x, y)| close(*x, *y))
                && p.phases_rad.iter().zip(&q.phases_rad).all(|(x, y)| close(*x, *y))
                && close(p.stick_time_s, q.stick_time_s)
        })
}

#[test]
fn zero_strength_is_the_baseline_path_by_path() {
    let (cpu_base, gpu_base) = paths(&Model::default(), 64);
    for sets in ZERO {
        let (cpu, gpu) = paths(&model(sets), 64);
        assert_eq!(cpu, cpu_base, "CPU paths differ from the baseline with {sets:?}");
        assert!(gpu_paths_agree(&gpu, &gpu_base), "GPU paths differ from the baseline with {sets:?}");
    }
}

#[test]
fn cpu_and_gpu_agree_with_each_effect_on() {
    let (cpu_base, _) = paths(&Model::default(), 128);
    for sets in ON {
        let (cpu, gpu) = paths(&model(sets), 128);
        let (mut within, mut total) = (0, 0);
        for (c, g) in cpu.iter().zip(&gpu) {
            for (pc, pg) in c.peaks_m.iter().zip(&g.peaks_m) {
                total += 1;
                within += usize::from((pg / pc - 1.0).abs() <= 1e-3);
            }
        }
        let fraction = within as f64 / total as f64;
        println!("{sets:?}: {:.2}% of peaks within 1e-3", 100.0 * fraction);
        assert!(fraction >= 0.99, "{sets:?}: only {fraction} of peaks agree");
        assert_ne!(cpu, cpu_base, "{sets:?} changed nothing");
    }
}

pub(super) fn record(m: &Model, seconds: f64) -> Vec<Sample> {
    common::record(m, COND, 5, 0, seconds, 600.0)
}

pub(super) fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n as f64
}

/// α and β of N = N0 (1 + α r + β r²), r = x/U0, by least squares on a
/// record (Cramer's rule on the 3×3 normal equations).
fn position_fit(r: &[Sample], u0: f64, n0: f64) -> (f64, f64) {
    let mut a = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for s in r {
        let x = s.x_m / u0;
        let row = [1.0, x, x * x];
        for i in 0..3 {
            b[i] += row[i] * s.normal_force_n;
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
        }
    }
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let column = |k: usize| {
        let mut m = a;
        for i in 0..3 {
            m[i][k] = b[i];
        }
        det(m) / det(a)
    };
    (column(1) / n0, column(2) / n0)
}

#[test]
fn each_effect_does_what_it_says() {
    // Drift: the normal force's mean in the last fifth exceeds the first fifth's.
    let n = record(&model(&["normal_force_drift.rate_per_s=0.01"]), 20.0);
    let fifth = n.len() / 5;
    let (early, late) =
        (mean(n[..fifth].iter().map(|s| s.normal_force_n)), mean(n[4 * fifth..].iter().map(|s| s.normal_force_n)));
    assert!((late / early - 1.0) > 0.1, "drift: {early} -> {late}");
    // Harmonics: the 2× component of N has the amplitude put in.
    let n = record(&model(&["normal_force_harmonics.amplitudes_n=[0.0, 0.5, 0.0, 0.0]", "normal_force.sigma=0"]), 10.0);
    let w = std::f64::consts::TAU * 2.0 * COND.excitation_frequency_hz;
    let (c, s) = n.iter().fold((0.0, 0.0), |(c, s), x| {
        (c + x.normal_force_n * (w * x.t_s).cos(), s + x.normal_force_n * (w * x.t_s).sin())
    });
    let amplitude = 2.0 * (c * c + s * s).sqrt() / n.len() as f64;
    assert!((amplitude - 0.5).abs() < 0.02, "2x harmonic amplitude {amplitude}");
    // Position: without noise, N is N0 (1 + α r + β r²) with r = x/U0 at
    // the start of the noise interval; a least-squares fit of N on the
    // recorded x and x² gives α and β back to the drift of x within one
    // interval.
    let m = model(&[
        "normal_force_harmonics.amplitudes_per_n0=[0.05, -0.03, 0.0, 0.0]",
        "normal_force_harmonics.form=\"position\"",
        "normal_force.sigma=0",
    ]);
    let u0 = m.excitation.amplitude_m;
    let n = record(&m, 10.0);
    let (alpha, beta) = position_fit(&n, u0, COND.normal_force_n);
    assert!((alpha - 0.05).abs() < 0.005 && (beta + 0.03).abs() < 0.005, "position: alpha {alpha}, beta {beta}");
    let run = |m: &Model| common::paths(common::cpu(), m, COND, InitialState::steady(m, COND), 3, 32, PLAN);
    let mean_peak = |m: &Model| mean(run(m).iter().flat_map(|p| p.peaks_m.clone()));
    let stick_time = |m: &Model| run(m).iter().map(|p| p.stick_time_s).sum::<f64>();
    // Stiction holds the block longer at each reversal.
    let (stuck, stuck_base) = (stick_time(&model(&["stiction.excess=0.2"])), stick_time(&Model::default()));
    assert!(stuck > 1.5 * stuck_base, "stiction: stick time {stuck} vs baseline {stuck_base}");
    // Stiction released over 0.3 mm keeps friction above the kinetic law
    // just after breakaway; released at once it does not.
    let early_slip_mu = |m: &Model| {
        let r = record(m, 5.0);
        let early: Vec<f64> = r
            .windows(2)
            .filter(|w| {
                (0.002..0.03).contains(&w[1].v_m_per_s.abs())
                    && w[1].v_m_per_s.abs() > w[0].v_m_per_s.abs()
                    && w[1].normal_force_n > 0.0
            })
            .map(|w| w[1].friction_force_n.abs() / w[1].normal_force_n)
            .collect();
        mean(early.into_iter())
    };
    let (released, abrupt) = (
        early_slip_mu(&model(&["stiction.excess=0.2", "stiction.release_length_m=3e-4"])),
        early_slip_mu(&model(&["stiction.excess=0.2"])),
    );
    println!("friction coefficient early in a slip: released over 0.3 mm {released:.4}, at once {abrupt:.4}");
    assert!(released - abrupt > 0.05, "stiction release: {released} vs {abrupt}");
    // More friction at 16.39 N than at the 10 N reference lowers the peaks.
    let base = mean_peak(&Model::default());
    assert!(
        mean_peak(&model(&["load_dependent_friction.strength=0.01"])) < base,
        "more friction at 16.39 N than at 10 N"
    );
    // Hysteresis: at the same speed, friction on the accelerating branch
    // (just after a slip starts) is below that on the decelerating branch.
    let branch_gap = |m: &Model| {
        let r = record(m, 5.0);
        let (mut acc, mut dec) = (Vec::new(), Vec::new());
        for w in r.windows(2) {
            let speed = w[1].v_m_per_s.abs();
            if (0.05..0.15).contains(&speed) && w[1].normal_force_n > 0.0 {
                let mu = w[1].friction_force_n.abs() / w[1].normal_force_n;
                if speed > w[0].v_m_per_s.abs() { acc.push(mu) } else { dec.push(mu) }
            }
        }
        mean(dec.into_iter()) - mean(acc.into_iter())
    };
    let (gap, gap_base) = (branch_gap(&model(&["friction_hysteresis.length_m=3e-4"])), branch_gap(&Model::default()));
    println!("decelerating minus accelerating friction coefficient: hysteresis {gap:.4}, baseline {gap_base:.4}");
    assert!(gap > 0.03 && gap_base.abs() < 0.01, "hysteresis branch gap {gap} (baseline {gap_base})");
    // A friction coefficient that lags the falling Stribeck law in time
    // (Hess & Soom) separates the branches the other way: it stays high
    // while the block speeds up and low while it slows down.
    let lag_gap = branch_gap(&model(&["friction_hysteresis.form=\"lag\"", "friction_hysteresis.time_constant_s=0.01"]));
    println!("decelerating minus accelerating friction coefficient: lag 10 ms {lag_gap:.4}");
    assert!(lag_gap < -0.015, "lag branch gap {lag_gap}");
    // Static friction that ages while stuck holds the block longer, but less
    // than the full excess at once.
    let dwell = stick_time(&model(&["stiction.form=\"dwell\"", "stiction.excess=0.2", "stiction.dwell_time_s=0.02"]));
    println!("stick time: baseline {stuck_base:.4}, dwell {dwell:.4}, constant {stuck:.4}");
    assert!(
        dwell > 1.05 * stuck_base && dwell < stuck,
        "dwell stiction: stick time {dwell} vs {stuck_base} and {stuck}"
    );
}

#[test]
fn a_quadratic_load_dependence_bends_the_linear_one_by_its_curvature() {
    // Offsets of `a` about the 10 N reference: with no curvature the
    // quadratic form is the linear one; with q it adds q (N0 − Nref)².
    let offset = |sets: &[&str], n0: f64| {
        stickslip::engine::effects::EffectParams::new(&model(sets).effects, n0, 0.3, 1.0 / 600.0).friction_offset
    };
    let linear = ["load_dependent_friction.strength=0.01"];
    let straight = ["load_dependent_friction.strength=0.01", "load_dependent_friction.form=\"quadratic\""];
    let bent = [
        "load_dependent_friction.strength=0.01",
        "load_dependent_friction.curvature_per_n2=0.002",
        "load_dependent_friction.form=\"quadratic\"",
    ];
    for n0 in [4.0, 10.0, 16.39, 30.0] {
        let x = n0 - 10.0;
        assert_eq!(offset(&straight, n0), offset(&linear, n0), "at {n0} N");
        let expected = 0.01 * x + 0.002 * x * x;
        assert!((offset(&bent, n0) - expected).abs() < 1e-12, "at {n0} N: {} vs {expected}", offset(&bent, n0));
    }
}

/// A record of `seconds` at `rate_hz` after 10 warm-up periods, noise off
/// (friction and normal force), with `sets` on top, at `condition`.
pub(super) fn noiseless_record(
    sets: &[&str],
    condition: Condition,
    seconds: f64,
    rate_hz: f64,
) -> (Model, Vec<Sample>) {
    let sets: Vec<&str> = ["friction.sigma=0", "normal_force.sigma=0"].iter().chain(sets).copied().collect();
    let m = model(&sets);
    let r = common::record(&m, condition, 5, 10, seconds, rate_hz);
    (m, r)
}

/// The noise-free steady law μ(v) = a + b/(1 + c|v|) + d v² of `m`, –.
pub(super) fn law(m: &Model, v: f64) -> f64 {
    let f = &m.friction;
    f.a + f.b / (1.0 + f.c * v.abs()) + f.d * v * v
}

/// Each stick in `r` as (its duration, s, and |F|/N at its last sample,
/// just before the breakaway), the first (cut by the record's start) and a
/// last one that does not end left out.
pub(super) fn sticks(r: &[Sample]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut since: Option<f64> = None;
    let mut seen_slip = false;
    for w in r.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if a.v_m_per_s != 0.0 && b.v_m_per_s == 0.0 {
            seen_slip = true;
            since = Some(b.t_s);
        }
        if a.v_m_per_s == 0.0 && b.v_m_per_s != 0.0 && seen_slip {
            if let Some(t0) = since.take() {
                out.push((a.t_s - t0, a.friction_force_n.abs() / a.normal_force_n));
            }
        }
    }
    out
}

/// Load dependence `adhesion`, the two-term law F = μN + A: while slipping
/// the friction force's magnitude is μ(v) N + A (noise off, so μ(v) is known
/// at every sample), and the force that breaks a stuck block away, read at
/// each stick's last sample, is μ_s N + A (below it by at most the spring's
/// rise over one 20 µs sample, under 0.03 N). A negative A lowers both.
#[test]
fn adhesion_adds_its_force_to_sliding_friction_and_to_the_breakaway() {
    // Where each sticks: at 12 Hz, 16.39 N with A = 1 N, 20 N with A = −1 N.
    for (adhesion_n, normal_force_n) in [(1.0, 16.39), (-1.0, 20.0)] {
        let condition = Condition { excitation_frequency_hz: 12.0, normal_force_n };
        let strength = format!("load_dependent_friction.strength={adhesion_n}");
        let (m, r) =
            noiseless_record(&["load_dependent_friction.form=\"adhesion\"", &strength], condition, 3.0, 50_000.0);
        let slipping: Vec<&Sample> = r.iter().filter(|s| s.v_m_per_s != 0.0).collect();
        let worst = slipping
            .iter()
            .map(|s| (s.friction_force_n.abs() - law(&m, s.v_m_per_s) * s.normal_force_n - adhesion_n).abs())
            .fold(0.0f64, f64::max);
        let sticks = sticks(&r);
        let breakaway_n: Vec<f64> = sticks.iter().map(|s| s.1 * condition.normal_force_n).collect();
        let static_n = law(&m, 0.0) * condition.normal_force_n;
        let (lo, hi) = breakaway_n.iter().fold((f64::MAX, f64::MIN), |(l, h), &f| (l.min(f), h.max(f)));
        println!(
            "adhesion {adhesion_n} N: |F| − μN − A within {worst:.1e} N over {} slipping samples; breakaway \
             {lo:.4}..{hi:.4} N against μ_s N + A = {:.4} N ({} sticks)",
            slipping.len(),
            static_n + adhesion_n,
            sticks.len()
        );
        assert!(slipping.len() > 1000 && worst < 1e-9, "adhesion {adhesion_n} N: |F| − μN − A up to {worst} N");
        assert!(sticks.len() >= 20, "adhesion {adhesion_n} N: {} sticks", sticks.len());
        assert!(
            breakaway_n.iter().all(|f| (static_n + adhesion_n - f) > -1e-9 && (static_n + adhesion_n - f) < 0.03),
            "adhesion {adhesion_n} N: breakaway forces {lo}..{hi} N against {} N",
            static_n + adhesion_n
        );
    }
}

/// Load dependence `scaled`: the whole law scales with the load,
/// μ(v, N0) = (N0/Nref)^k μ(v). Noise off, the sliding friction coefficient
/// measured at 4 N and at 12 N (Nref = 10 N, k = 0.3) is the law times its
/// factor at every slipping sample, so the two differ by (12/4)^k at every
/// speed, and the breakaway force carries the factor on a + b; the factor
/// is exactly 1 at k = 0.
#[test]
fn the_scaled_law_scales_friction_with_the_load_at_every_speed() {
    let k = 0.3;
    let strength = format!("load_dependent_friction.strength={k}");
    let sets = ["load_dependent_friction.form=\"scaled\"", strength.as_str()];
    for n0 in [4.0, 12.0] {
        let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: n0 };
        let (m, r) = noiseless_record(&sets, condition, 3.0, 2_000.0);
        let factor = (n0 / 10.0f64).powf(k);
        let ratios: Vec<f64> = r
            .iter()
            .filter(|s| s.v_m_per_s != 0.0)
            .map(|s| s.friction_force_n.abs() / s.normal_force_n / law(&m, s.v_m_per_s))
            .collect();
        let speeds = r.iter().map(|s| s.v_m_per_s.abs()).fold(0.0f64, f64::max);
        let worst = ratios.iter().map(|q| (q / factor - 1.0).abs()).fold(0.0f64, f64::max);
        println!(
            "scaled at {n0} N: μ/μ(v) = {factor:.6} within {worst:.1e} over {} samples up to {speeds:.3} m/s",
            ratios.len()
        );
        assert!(ratios.len() > 1000 && speeds > 0.1 && worst < 1e-12, "scaled at {n0} N: off by {worst}");
        let e = stickslip::engine::effects::EffectParams::new(&m.effects, n0, 0.5, 1.0 / 600.0);
        assert!((e.friction_scale / factor - 1.0).abs() < 1e-15 && e.friction_offset == 0.0, "{e:?}");
    }
    // The static coefficient's a + b scale too: at 12 Hz and 20 N (k = −0.3,
    // a factor 0.81, so that the block sticks) the force that breaks it away,
    // read at each stick's last 20 µs sample, is the factor times (a + b) N.
    let condition = Condition { excitation_frequency_hz: 12.0, normal_force_n: 20.0 };
    let (m, r) = noiseless_record(&[sets[0], "load_dependent_friction.strength=-0.3"], condition, 3.0, 50_000.0);
    let static_n = (20.0 / 10.0f64).powf(-0.3) * law(&m, 0.0) * 20.0;
    let sticks = sticks(&r);
    let (lo, hi) = sticks.iter().map(|s| s.1 * 20.0).fold((f64::MAX, f64::MIN), |(l, h), f| (l.min(f), h.max(f)));
    println!(
        "scaled at 20 N, k = −0.3: breakaway {lo:.4}..{hi:.4} N against {static_n:.4} N ({} sticks)",
        sticks.len()
    );
    assert!(sticks.len() >= 20 && lo > static_n - 0.03 && hi <= static_n + 1e-9, "{lo}..{hi} against {static_n}");
    let off = model(&["load_dependent_friction.form=\"scaled\"", "load_dependent_friction.strength=0.0"]);
    let e = stickslip::engine::effects::EffectParams::new(&off.effects, 30.0, 0.5, 1.0 / 600.0);
    assert_eq!(e.friction_scale, 1.0);
}

/// A stiff rig driven far below resonance (f0 = 1 kHz at 7 Hz) takes the
/// steps that resolve its natural period (16 each: 2286 per period), and
/// its record stays finite and within the base's amplitude plus the
/// friction's static deflection (it diverged at the default steps: RK4 is
/// unstable past ω0·dt ≈ 2.8); one that would need more than the solver
/// allows is refused, naming the natural frequency.
#[test]
fn a_stiff_rig_takes_the_steps_its_natural_period_needs() {
    let m = model(&["rig.natural_frequency_hz=1000.0"]);
    let steps = Oscillator::new(&m, COND).expect("an oscillator").steps_per_period;
    assert_eq!(steps, (16.0 * 1000.0 / COND.excitation_frequency_hz).ceil() as u32);
    let r = record(&m, 2.0);
    let bound = 2.0 * m.excitation.amplitude_m + 0.2;
    assert!(
        r.iter().all(|s| s.x_m.is_finite() && s.x_m.abs() < bound),
        "{:?}",
        r.iter().map(|s| s.x_m).fold(0.0, f64::max)
    );
    let err = Oscillator::new(&model(&["rig.natural_frequency_hz=1e6"]), COND).expect_err("refused").to_string();
    assert!(err.contains("rig.natural_frequency_hz") && err.contains("steps per period"), "{err}");
    // The paper rig keeps its steps.
    assert_eq!(
        Oscillator::new(&Model::default(), COND).unwrap().steps_per_period,
        Model::default().solver.steps_per_period
    );
}

/// A law that strengthens with speed (μ from a + b = 0.06 at rest to
/// a = 0.33 within a few mm/s: b = −0.27, c = 950 s/m, as fitted to
/// records of a friction memory) settles a slip within
/// `m / (c_r + N |b| c)`, 0.2 ms at 16 N: the steps per period rise so
/// that no step is longer (against the model's 64 at 7 Hz, one step was
/// 12 settling times, and RK4 turned each slip into a chatter of false
/// stops up to the event limit). Noise off, so the law is known at every
/// sample: the slipping friction stays within the law's range, and four
/// times as many steps move the record by under 1e-4 of the base's
/// amplitude (at the model's 64 steps they moved it by 2.4e-3). The
/// paper's law, which weakens with speed, keeps its steps.
#[test]
fn a_law_that_strengthens_with_speed_takes_the_steps_its_slip_needs() {
    let sets = ["friction.a=0.33", "friction.b=-0.27", "friction.c=950.0"];
    let (m, r) = noiseless_record(&sets, COND, 2.0, 600.0);
    let steps = Oscillator::new(&m, COND).expect("an oscillator").steps_per_period;
    let rate_per_s = (m.damping_n_s_per_m() + COND.normal_force_n * 0.27 * 950.0) / m.rig.mass_kg;
    assert_eq!(steps, (rate_per_s / COND.excitation_frequency_hz).ceil() as u32);
    let finer = format!("solver.steps_per_period={}", 4 * steps);
    let (_, fine) = noiseless_record(&[sets[0], sets[1], sets[2], &finer], COND, 2.0, 600.0);
    let mu = |s: &Sample| s.friction_force_n.abs() / s.normal_force_n;
    let slipping: Vec<&Sample> = r.iter().filter(|s| s.v_m_per_s.abs() > 1e-4).collect();
    let (lowest, highest) = (law(&m, 0.0), m.friction.a);
    let outside = slipping.iter().filter(|s| !(lowest - 1e-9..=highest + 1e-9).contains(&mu(s))).count();
    let worst = r.iter().zip(&fine).map(|(a, b)| (a.x_m - b.x_m).abs()).fold(0.0f64, f64::max);
    println!(
        "strengthening law at {steps} steps per period: {} slipping samples, {outside} outside [{lowest}, {highest}]; \
         against {} steps x moves by up to {worst:.2e} m",
        slipping.len(),
        4 * steps
    );
    assert!(slipping.len() > 300 && outside == 0, "{outside} of {} slipping samples outside the law", slipping.len());
    assert!(worst < 1e-4 * m.excitation.amplitude_m, "{worst} m from four times the steps");
    let err = Oscillator::new(&model(&["friction.a=50", "friction.b=-50", "friction.c=1e6"]), COND)
        .expect_err("refused")
        .to_string();
    assert!(err.contains("friction.b") && err.contains("steps per period"), "{err}");
    assert_eq!(
        Oscillator::new(&Model::default(), COND).unwrap().steps_per_period,
        Model::default().solver.steps_per_period
    );
}

/// A GPU grid over two frequencies under the slip law: the slip distance
/// raises the steps differently at each (88 per period at 7 Hz, 177 at
/// 9 Hz), and each point takes its own, path by path as on the CPU (one
/// step count for the whole grid was refused as a model mismatch).
#[test]
fn a_gpu_grid_takes_each_points_own_steps() {
    use stickslip::engine::{Job, PeakRange, Point, Record};
    let m = model(&["friction_hysteresis.form=\"slip\"", "friction_hysteresis.length_m=5e-4"]);
    let range = PeakRange { lo_m: -0.05, hi_m: 0.05, phase_ref_rad: 0.0 };
    let points: Vec<Point> = [7.0, 9.0]
        .map(|hz| {
            let condition = Condition { excitation_frequency_hz: hz, normal_force_n: 16.39 };
            Point { condition, initial: InitialState::steady(&m, condition), range, realisation_offset: 0 }
        })
        .to_vec();
    let steps: Vec<u32> = points.iter().map(|p| Oscillator::new(&m, p.condition).unwrap().steps_per_period).collect();
    println!("steps per period at 7 and 9 Hz: {steps:?}");
    assert!(steps[0] != steps[1] && steps.iter().all(|&s| s > 64), "{steps:?}");
    let job = Job {
        model: &m,
        points: &points,
        realisations: 64,
        first_realisation: 0,
        seed: 77,
        plan: PLAN,
        record: Record::Peaks,
    };
    let (cpu, gpu) =
        (common::cpu().paths(&job).expect("the CPU runs"), common::gpu().paths(&job).expect("the GPU runs"));
    assert_eq!((cpu.len(), gpu.len()), (128, 128));
    for (k, (cpu, gpu)) in cpu.chunks(64).zip(gpu.chunks(64)).enumerate() {
        let (mut within, mut total) = (0, 0);
        for (c, g) in cpu.iter().zip(gpu) {
            for (pc, pg) in c.peaks_m.iter().zip(&g.peaks_m) {
                total += 1;
                within += usize::from((pg / pc - 1.0).abs() <= 1e-3);
            }
        }
        println!("point {k}: {within}/{total} peaks within 1e-3");
        assert!(within as f64 >= 0.99 * total as f64, "point {k}: {within}/{total} peaks agree");
    }
}

/// The new forms' parameters are range-checked, and a refusal names the
/// dotted key: B of `ageing` must be finite, the adhesion force a finite
/// force (within the model's force bound, not the exponents'), the
/// `scaled` exponent finite.
#[test]
fn the_new_forms_parameters_are_refused_by_name() {
    for (sets, key) in [
        (["friction_hysteresis.form=\"ageing\"", "friction_hysteresis.strength=nan"], "friction_hysteresis.strength"),
        (["friction_hysteresis.form=\"ageing\"", "friction_hysteresis.strength=1e308"], "friction_hysteresis.strength"),
        (
            ["load_dependent_friction.form=\"adhesion\"", "load_dependent_friction.strength=inf"],
            "load_dependent_friction.strength",
        ),
        (
            ["load_dependent_friction.form=\"adhesion\"", "load_dependent_friction.strength=1e308"],
            "load_dependent_friction.strength",
        ),
        (
            ["load_dependent_friction.form=\"scaled\"", "load_dependent_friction.strength=nan"],
            "load_dependent_friction.strength",
        ),
        (
            ["normal_force_drift.form=\"random_walk\"", "normal_force_drift.rate_per_s=-1e-3"],
            "normal_force_drift.rate_per_s",
        ),
    ] {
        let overrides: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let err = Model::paper_rig(&overrides).expect_err(key).to_string();
        assert!(err.contains(key) && err.len() < 300, "{sets:?}: {err}");
    }
    // An adhesion force of 500 N is a force, not an exponent beyond 100.
    model(&["load_dependent_friction.form=\"adhesion\"", "load_dependent_friction.strength=500"]);
    model(&["load_dependent_friction.form=\"adhesion\"", "load_dependent_friction.strength=-2.5"]);
}

/// A drift whose model file says over which window the nominal normal force
/// is its mean: swept at 10 N, the force over that window averages 10 N
/// (without it, 10 N is the force where the warm-up ends and the mean
/// drifts away with it). The drift's clock starts at the end of the
/// warm-up: seven warm-up periods or seventy, the record sees the same
/// force (a drift counted from the run's start would reach a record after
/// seventy periods at 10% more).
#[test]
fn a_drift_with_a_mean_window_gives_its_nominal_force_there() {
    let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 10.0 };
    let with = |window: &str| {
        let mut overrides =
            vec!["normal_force.sigma=0.0", "normal_force_drift.form=\"linear\"", "normal_force_drift.rate_per_s=0.02"];
        if !window.is_empty() {
            overrides.push(window);
        }
        let overrides: Vec<String> = overrides.into_iter().map(String::from).collect();
        Model::paper_rig(&overrides).unwrap()
    };
    // The record spans 0 s to 20 s of the drift's clock.
    let mean_force = |model: &Model, warmup: u32| {
        let samples = common::record(model, condition, 3, warmup, 20.0, 600.0);
        samples.iter().map(|s| s.normal_force_n).sum::<f64>() / samples.len() as f64
    };
    let windowed = with("normal_force_drift.mean_over_s=[0.0, 20.0]");
    for warmup in [7, 70] {
        let mean = mean_force(&windowed, warmup);
        assert!((mean / 10.0 - 1.0).abs() < 2e-3, "mean force {mean} N over the window after {warmup} periods");
    }
    let unwindowed = mean_force(&with(""), 7);
    assert!((unwindowed / (10.0 * (1.0 + 0.02 * 10.0)) - 1.0).abs() < 2e-3, "{unwindowed} N");
}

/// A `random_walk` drift: N/N0 − 1 is a walk of its own in each
/// realisation, from 0, with variance r t. Over 48 realisations the sample
/// variance of W at 10 s, and of its increment from 5 s to 10 s, stands
/// within [0.5, 1.7] of r t (a χ²₄₇/47 leaves that range with probability
/// under 0.001 each way; a walk with twice or half the variance, or one
/// shared by the realisations, leaves it with probability above 0.99).
#[test]
fn a_random_walk_drift_wanders_with_its_variance_per_second() {
    let r = 2e-3;
    let m = model(&[
        "normal_force.sigma=0.0",
        "normal_force_drift.rate_per_s=2e-3",
        "normal_force_drift.form=\"random_walk\"",
    ]);
    let points = [Point::steady(&m, COND)];
    let plan = RunPlan { warmup_cycles: 0, measured_cycles: 0 };
    let realisations = 48;
    let job =
        Job { model: &m, points: &points, realisations, first_realisation: 0, seed: 31, plan, record: Record::Sums };
    let records = common::cpu().records(&job, 0.05, 10.0).expect("the records run");
    let walk_at = |r: &[Sample], t: f64| {
        let s = r.iter().min_by(|a, b| (a.t_s - t).abs().total_cmp(&(b.t_s - t).abs())).expect("a sample");
        (s.normal_force_n / COND.normal_force_n - 1.0, s.t_s)
    };
    let variance = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64
    };
    let (mut end, mut increment, mut t_end, mut t_mid) = (Vec::new(), Vec::new(), 0.0, 0.0);
    for record in &records {
        assert!(walk_at(record, 0.0).0.abs() < 0.02, "the walk starts at 0");
        let ((w_end, te), (w_mid, tm)) = (walk_at(record, 10.0), walk_at(record, 5.0));
        (t_end, t_mid) = (te, tm);
        end.push(w_end);
        increment.push(w_end - w_mid);
    }
    let (end_ratio, increment_ratio) = (variance(&end) / (r * t_end), variance(&increment) / (r * (t_end - t_mid)));
    assert!((0.5..1.7).contains(&end_ratio), "Var W({t_end} s) / r t = {end_ratio}");
    assert!((0.5..1.7).contains(&increment_ratio), "Var of the increment / r Δt = {increment_ratio}");
    let mean_end = end.iter().sum::<f64>() / end.len() as f64;
    assert!(mean_end.abs() < 4.0 * (r * t_end / f64::from(realisations)).sqrt(), "mean W = {mean_end}");
}
