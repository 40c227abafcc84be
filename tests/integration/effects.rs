//! The seven effects: at zero strength each reduces to the baseline path by
//! path (CPU and GPU), with strength the CPU and GPU still agree path by path,
//! and each does what its name says.

use stickslip::engine::{Condition, InitialState, Model, Oscillator, PathResult, RunPlan, Sample};

use crate::common;

const PLAN: RunPlan = RunPlan { warmup_cycles: 5, measured_cycles: 15 };
const COND: Condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };

/// Every effect in every form, at zero strength.
const ZERO: [&[&str]; 37] = [
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
    &["non_gaussian_friction.strength=0.0"],
    &["non_gaussian_friction.strength=0.0", "non_gaussian_friction.form=\"lognormal\""],
    &["non_gaussian_friction.strength=0.0", "non_gaussian_friction.form=\"tukey_h\""],
    &["non_gaussian_friction.strength=0.0", "non_gaussian_friction.form=\"mixture\""],
    &["friction_hysteresis.length_m=0.0"],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.form=\"tanh\""],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.form=\"rational\""],
    &["friction_hysteresis.time_constant_s=0.0", "friction_hysteresis.form=\"lag\""],
    &["friction_hysteresis.length_m=0.0", "friction_hysteresis.form=\"slip\""],
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
];

/// Every effect in every form, switched on (the coloured `two_scale` form
/// mixes in a slow part, so its strength is a correlation time), and the
/// one pair whose parts meet in one state (lag and a released stiction).
const ON: [&[&str]; 38] = [
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
    &["non_gaussian_friction.strength=0.8"],
    &["non_gaussian_friction.strength=0.7", "non_gaussian_friction.form=\"lognormal\""],
    &["non_gaussian_friction.strength=0.2", "non_gaussian_friction.form=\"tukey_h\""],
    &["non_gaussian_friction.strength=0.8", "non_gaussian_friction.form=\"mixture\""],
    &["friction_hysteresis.length_m=2e-4"],
    &["friction_hysteresis.length_m=2e-4", "friction_hysteresis.form=\"tanh\""],
    &["friction_hysteresis.length_m=2e-4", "friction_hysteresis.form=\"rational\""],
    &["friction_hysteresis.time_constant_s=0.01", "friction_hysteresis.form=\"lag\""],
    &["friction_hysteresis.length_m=2e-4", "friction_hysteresis.form=\"slip\""],
    &["friction_hysteresis.length_m=2e-5", "friction_hysteresis.strength=0.05", "friction_hysteresis.form=\"ageing\""],
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
];

fn model(sets: &[&str]) -> Model {
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

#[test]
fn zero_strength_is_the_baseline_path_by_path() {
    let (cpu_base, gpu_base) = paths(&Model::default(), 64);
    for sets in ZERO {
        let (cpu, gpu) = paths(&model(sets), 64);
        assert_eq!(cpu, cpu_base, "CPU paths differ from the baseline with {sets:?}");
        assert_eq!(gpu, gpu_base, "GPU paths differ from the baseline with {sets:?}");
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

fn record(m: &Model, seconds: f64) -> Vec<Sample> {
    common::record(m, COND, 5, 0, seconds, 600.0)
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n as f64
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

/// Hysteresis `lag` with a memory time far shorter than a step (0.1 ms
/// against 2.2 ms at 7 Hz): the steps are raised to resolve it, so the
/// lagged coefficient follows the law within its lag instead of growing
/// without bound (classical RK4 on the lag is unstable beyond 2.8 τ per
/// step). Noise off, so the law is known exactly at every sample.
#[test]
fn a_lag_shorter_than_a_step_follows_the_law() {
    let m = model(&[
        "friction_hysteresis.form=\"lag\"",
        "friction_hysteresis.time_constant_s=1e-4",
        "friction.sigma=0",
        "normal_force.sigma=0",
    ]);
    let f = &m.friction;
    let law = |v: f64| f.a + f.b / (1.0 + f.c * v.abs()) + f.d * v * v;
    let slipping: Vec<Sample> = record(&m, 5.0).into_iter().filter(|s| s.v_m_per_s.abs() > 1e-3).collect();
    assert!(slipping.len() > 500, "only {} slipping samples", slipping.len());
    let worst = slipping
        .iter()
        .map(|s| (s.friction_force_n.abs() / s.normal_force_n - law(s.v_m_per_s)).abs())
        .fold(0.0f64, f64::max);
    println!("lag 0.1 ms: largest |μ − μ(v)| while slipping {worst:.2e}");
    assert!(worst < 0.01, "the lagged coefficient left the law by {worst}");
}

/// A memory time that no allowed step count resolves is refused by name
/// (it would need 1.4e11 steps per period at 7 Hz), not run for days.
#[test]
fn a_lag_too_short_to_integrate_is_refused_by_name() {
    let m = model(&["friction_hysteresis.form=\"lag\"", "friction_hysteresis.time_constant_s=1e-12"]);
    let err = Oscillator::new(&m, COND).expect_err("refused").to_string();
    assert!(err.contains("friction_hysteresis.time_constant_s") && err.contains("steps per period"), "{err}");
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
