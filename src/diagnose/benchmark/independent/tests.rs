use super::*;

/// A truth with the given rig and law, no effects.
fn plain(rig: TruthRig, friction: TruthFriction) -> IndependentTruth {
    IndependentTruth {
        generator: GENERATOR.into(),
        seed: 0,
        description: String::new(),
        rig,
        friction,
        effects: Vec::new(),
        integration: Integration::default(),
        conditions: Vec::new(),
    }
}

fn rig(zeta: f64) -> TruthRig {
    TruthRig { mass_kg: 1.0, natural_frequency_hz: 10.0, damping_ratio: zeta, excitation_amplitude_m: 2.5e-3 }
}

fn coulomb(mu: f64) -> TruthFriction {
    TruthFriction {
        a: mu,
        b: 0.0,
        c_s_per_m: 0.0,
        d_s2_per_m2: 0.0,
        sigma_mu: 0.0,
        sigma_n_n: 0.0,
        noise_interval_s: 1.0 / 600.0,
    }
}

/// Without friction and noise the steady amplitude is the linear one.
#[test]
fn linear_amplitude_matches_the_closed_form() {
    for (zeta, eta) in [(0.005, 0.7), (0.01, 0.9), (0.003, 1.2), (0.008, 0.6)] {
        let truth = plain(rig(zeta), coulomb(0.0));
        let c = Condition { excitation_frequency_hz: 10.0 * eta, normal_force_n: 4.0 };
        let stats = truth_path_stats(&truth, &[c], 5.0, 1, 1);
        let want = 2.5e-3 / ((1.0 - eta * eta).powi(2) + (2.0 * zeta * eta).powi(2)).sqrt();
        let got = stats[0][0].peak_mean_m;
        eprintln!("linear ζ={zeta} η={eta}: {got} vs {want} ({:+.4}%)", 100.0 * (got / want - 1.0));
        assert!((got / want - 1.0).abs() < 0.005, "ζ={zeta} η={eta}: {got} vs {want}");
        let phase = (2.0 * zeta * eta).atan2(1.0 - eta * eta).to_degrees();
        assert!((stats[0][0].phase_mean_deg - phase).abs() < 0.5, "{} vs {phase}", stats[0][0].phase_mean_deg);
    }
}

/// Den Hartog's Coulomb solution without stops (ζ = 0).
#[test]
fn coulomb_amplitude_matches_den_hartog() {
    use crate::engine::analytic::DenHartog;
    let r = rig(0.0);
    let k_u0 = r.stiffness_n_per_m() * r.excitation_amplitude_m;
    for (eta, share) in [(0.6, 0.5), (0.8, 0.7), (1.2, 0.5), (0.7, 0.3)] {
        let beta = share * DenHartog::stop_threshold(eta);
        let n0 = 10.0;
        let truth = plain(r, coulomb(beta * k_u0 / n0));
        let c = Condition { excitation_frequency_hz: 10.0 * eta, normal_force_n: n0 };
        let stats = truth_path_stats(&truth, &[c], 5.0, 1, 1);
        let want = DenHartog { eta, beta }.amplitude_ratio().expect("no stops") * r.excitation_amplitude_m;
        let got = stats[0][0].peak_mean_m;
        eprintln!("den hartog η={eta} share={share}: {got} vs {want} ({:+.4}%)", 100.0 * (got / want - 1.0));
        assert!((got / want - 1.0).abs() < 0.01, "η={eta}: {got} vs {want}");
        assert_eq!(stats[0][0].stick_fraction, 0.0);
    }
}

/// Statistics of one record that the effects' signatures move.
#[derive(Clone, Copy, Debug, Default)]
struct Signature {
    /// Mean and variance of the per-period peaks, m, m².
    peak_mean: f64,
    peak_var: f64,
    /// Mean friction coefficient `|F|/N` while sliding (|v| > 2 cm/s).
    mu_mean: f64,
    /// Lag-10 autocorrelation of the friction residual `|F|/N − μ(|v|)`.
    lag10: f64,
    /// Kurtosis and skewness of that residual.
    kurtosis: f64,
    skewness: f64,
    /// Mean residual on the accelerating branch minus the decelerating one.
    branch_gap: f64,
    /// Amplitude of N at 1× and 2× the excitation, per mean N.
    n_h1: f64,
    n_h2: f64,
    /// Mean N of the last fifth minus the first, per mean N.
    n_drift: f64,
    /// Mean over stick episodes of the largest `|F|/N` (0 without stops).
    stick_mu: f64,
}

fn moments(values: &[f64]) -> (f64, f64, f64, f64) {
    let n = values.len().max(1) as f64;
    let mean = values.iter().sum::<f64>() / n;
    let m2 = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    let m3 = values.iter().map(|v| (v - mean).powi(3)).sum::<f64>() / n;
    let m4 = values.iter().map(|v| (v - mean).powi(4)).sum::<f64>() / n;
    (mean, m2, m3 / m2.powf(1.5), m4 / (m2 * m2))
}

fn signature(truth: &IndependentTruth, c: Condition, r: &RecordColumns) -> Signature {
    let f = &truth.friction;
    let law = |s: f64| f.a + f.b / (1.0 + f.c_s_per_m * s) + f.d_s2_per_m2 * s * s;
    let len = r.t.len();
    let dt = r.t[1] - r.t[0];
    let period = 1.0 / c.excitation_frequency_hz;
    // Peaks per period (model origin).
    let mut peaks = Vec::new();
    let mut current = f64::NEG_INFINITY;
    let mut k = 0;
    for i in 0..len {
        if r.t[i] >= f64::from(k + 1) * period - 0.5 * dt {
            peaks.push(current);
            current = f64::NEG_INFINITY;
            k += 1;
        }
        current = current.max(r.x[i]);
    }
    let (peak_mean, peak_var, _, _) = moments(&peaks);
    // Friction while sliding.
    let sliding: Vec<bool> = r.v.iter().map(|v| v.abs() > 0.02).collect();
    let mu_hat: Vec<f64> = (0..len).map(|i| (r.friction_force[i] / r.normal_force[i].max(1e-9)).abs()).collect();
    let resid: Vec<f64> = (0..len).map(|i| mu_hat[i] - law(r.v[i].abs())).collect();
    let slid: Vec<f64> = (0..len).filter(|&i| sliding[i]).map(|i| resid[i]).collect();
    let mu_slid: Vec<f64> = (0..len).filter(|&i| sliding[i]).map(|i| mu_hat[i]).collect();
    let (mu_mean, _, _, _) = moments(&mu_slid);
    let (r_mean, r_var, skewness, kurtosis) = moments(&slid);
    let pairs: Vec<(f64, f64)> =
        (0..len - 10).filter(|&i| sliding[i] && sliding[i + 10]).map(|i| (resid[i], resid[i + 10])).collect();
    let lag10 = pairs.iter().map(|(a, b)| (a - r_mean) * (b - r_mean)).sum::<f64>() / pairs.len().max(1) as f64 / r_var;
    let (mut up, mut down) = (Vec::new(), Vec::new());
    for i in 1..len - 1 {
        if sliding[i] && sliding[i - 1] && sliding[i + 1] {
            let accel = r.v[i].signum() * (r.v[i + 1] - r.v[i - 1]);
            if accel > 0.0 { up.push(resid[i]) } else { down.push(resid[i]) }
        }
    }
    let branch_gap = moments(&up).0 - moments(&down).0;
    let n_mean = r.normal_force.iter().sum::<f64>() / len as f64;
    let harmonic = |h: f64| {
        let w = TAU * h * c.excitation_frequency_hz;
        let (mut a, mut b) = (0.0, 0.0);
        for i in 0..len {
            a += (r.normal_force[i] - n_mean) * (w * r.t[i]).cos();
            b += (r.normal_force[i] - n_mean) * (w * r.t[i]).sin();
        }
        2.0 * (a * a + b * b).sqrt() / len as f64 / n_mean
    };
    let fifth = len / 5;
    let first = r.normal_force[..fifth].iter().sum::<f64>() / fifth as f64;
    let last = r.normal_force[len - fifth..].iter().sum::<f64>() / fifth as f64;
    // Stick episodes: at least 3 samples in a row below 6 mm/s.
    let mut episodes = Vec::new();
    let mut i = 0;
    while i < len {
        if r.v[i].abs() < 6e-3 {
            let start = i;
            while i < len && r.v[i].abs() < 6e-3 {
                i += 1;
            }
            if i - start >= 3 {
                episodes.push(mu_hat[start..i].iter().cloned().fold(0.0, f64::max));
            }
        }
        i += 1;
    }
    Signature {
        peak_mean,
        peak_var,
        mu_mean,
        lag10,
        kurtosis,
        skewness,
        branch_gap,
        n_h1: harmonic(1.0),
        n_h2: harmonic(2.0),
        n_drift: (last - first) / n_mean,
        stick_mu: if episodes.is_empty() { 0.0 } else { moments(&episodes).0 },
    }
}

/// The characterisation rig: stops at η = 0.6 and 20 N, none at 4 N.
fn test_truth(effects: Vec<IndependentEffect>) -> IndependentTruth {
    let mut t = plain(
        TruthRig { mass_kg: 1.0, natural_frequency_hz: 10.0, damping_ratio: 0.004, excitation_amplitude_m: 2e-3 },
        TruthFriction {
            a: 0.22,
            b: 0.05,
            c_s_per_m: 10.0,
            d_s2_per_m2: 0.1,
            sigma_mu: 0.03,
            sigma_n_n: 0.2,
            noise_interval_s: 1.0 / 600.0,
        },
    );
    t.effects = effects;
    t
}

fn at(eta: f64, n: f64) -> Condition {
    Condition { excitation_frequency_hz: 10.0 * eta, normal_force_n: n }
}

/// Prints, for every form at both presets, how far its records'
/// signatures lie from the baseline's, in units of the baseline's
/// record-to-record spread (50 s records). Run with
/// `cargo test --release --lib independent::tests::presets -- --ignored --nocapture`.
#[test]
#[ignore = "minutes on 2 cores: the check that the presets are above a 50 s record's noise"]
fn presets_move_their_signatures_beyond_the_record_spread() {
    let records = 5u32;
    let conditions = [at(0.6, 20.0), at(0.7, 4.0), at(0.9, 8.0)];
    let shape = RecordShape { duration_s: 50.0, ..RecordShape::default() };
    let run = |truth: &IndependentTruth| -> Vec<Vec<Signature>> {
        conditions
            .iter()
            .enumerate()
            .map(|(ci, &c)| {
                (0..records)
                    .into_par_iter()
                    .map(|r| signature(truth, c, &simulate_run(truth, c, ci, r, &shape, 11).expect("a run")))
                    .collect()
            })
            .collect()
    };
    let names = [
        "peak_mean",
        "peak_var",
        "mu_mean",
        "lag10",
        "kurtosis",
        "skewness",
        "branch_gap",
        "n_h1",
        "n_h2",
        "n_drift",
        "stick_mu",
    ];
    let get = |s: &Signature| {
        [
            s.peak_mean,
            s.peak_var,
            s.mu_mean,
            s.lag10,
            s.kurtosis,
            s.skewness,
            s.branch_gap,
            s.n_h1,
            s.n_h2,
            s.n_drift,
            s.stick_mu,
        ]
    };
    let base = run(&test_truth(Vec::new()));
    let spread = |sigs: &[Signature], j: usize| {
        let v: Vec<f64> = sigs.iter().map(|s| get(s)[j]).collect();
        let (m, var, _, _) = moments(&v);
        (m, (var * v.len() as f64 / (v.len() as f64 - 1.0)).sqrt())
    };
    for (ci, c) in conditions.iter().enumerate() {
        let row: Vec<String> = (0..names.len())
            .map(|j| {
                let (m, sd) = spread(&base[ci], j);
                format!("{}={m:.4e}±{sd:.1e}", names[j])
            })
            .collect();
        eprintln!("baseline {:.1} Hz {} N: {}", c.excitation_frequency_hz, c.normal_force_n, row.join(" "));
    }
    let mut rng = stream_rng(1, 2, 3);
    for (family, forms) in FORMS {
        for form in 0..forms.len() as u32 {
            for strong in [false, true] {
                let e = IndependentEffect::preset(family, form, strong, 8.0, &mut rng).expect("a preset");
                let sigs = run(&test_truth(vec![e]));
                let mut best = Vec::new();
                for (j, name) in names.iter().enumerate() {
                    let (zmax, at) = (0..conditions.len())
                        .map(|ci| {
                            let (m0, sd0) = spread(&base[ci], j);
                            let (m1, _) = spread(&sigs[ci], j);
                            ((m1 - m0) / sd0.max(1e-300), ci)
                        })
                        .fold((0.0, 0), |acc, x| if x.0.abs() > f64::abs(acc.0) { x } else { acc });
                    best.push(format!("{name}:{zmax:+.1}@{at}"));
                }
                eprintln!("{family} form {form} {}: {}", if strong { "strong" } else { "moderate" }, best.join(" "));
            }
        }
    }
}

/// A quick version of the characterisation truth: 1 s warm-up, 100 kHz.
fn quick(effects: Vec<IndependentEffect>) -> IndependentTruth {
    let mut t = test_truth(effects);
    t.integration.warmup_s = 1.0;
    t.integration.step_rate_hz = MIN_STEP_RATE_HZ;
    t
}

fn short(duration_s: f64) -> RecordShape {
    RecordShape { duration_s, ..RecordShape::default() }
}

/// Signatures of `records` runs of `truth` at `c`.
fn signatures(truth: &IndependentTruth, c: Condition, records: u32, duration_s: f64) -> Vec<Signature> {
    (0..records)
        .into_par_iter()
        .map(|r| signature(truth, c, &simulate_run(truth, c, 0, r, &short(duration_s), 5).expect("a run")))
        .collect()
}

fn mean_of(sigs: &[Signature], f: impl Fn(&Signature) -> f64) -> f64 {
    sigs.iter().map(f).sum::<f64>() / sigs.len() as f64
}

fn strong(family: Effect, form: u32) -> IndependentEffect {
    IndependentEffect::preset(family, form, true, 8.0, &mut stream_rng(4, 5, 6)).expect("a preset")
}

/// Every form at strength 0 gives the baseline's record bit for bit.
#[test]
fn zero_strength_effects_equal_the_baseline_path() {
    let c = at(0.6, 20.0);
    let shape = short(3.0);
    let base = simulate_run(&quick(Vec::new()), c, 0, 0, &shape, 9).expect("a run");
    for (family, forms) in FORMS {
        for form in 0..forms.len() as u32 {
            let e = strong(family, form);
            let zero = simulate_run(&quick(vec![e.with_strength(0.0)]), c, 0, 0, &shape, 9).expect("a run");
            assert!(zero == base, "{family} form {form} at strength 0 differs from the baseline");
            let on = simulate_run(&quick(vec![e]), c, 0, 0, &shape, 9).expect("a run");
            assert!(on != base, "{family} form {form} at its strong preset changes nothing");
        }
    }
    // Two at once, both at zero.
    let pair = vec![
        strong(Effect::Stiction, 1).with_strength(0.0),
        strong(Effect::ColouredFrictionNoise, 0).with_strength(0.0),
    ];
    assert!(simulate_run(&quick(pair), c, 0, 0, &shape, 9).expect("a run") == base);
}

#[test]
fn load_forms_change_the_friction_level_with_load() {
    for form in 0..3 {
        let e = strong(Effect::LoadDependentFriction, form);
        let mut moved = 0.0f64;
        for n in [4.0, 16.0] {
            let c = at(0.7, n);
            let base = mean_of(&signatures(&quick(Vec::new()), c, 1, 10.0), |s| s.mu_mean);
            let on = mean_of(&signatures(&quick(vec![e]), c, 1, 10.0), |s| s.mu_mean);
            moved = moved.max((on - base).abs());
        }
        eprintln!("load form {form}: sliding μ moves by {moved}");
        assert!(moved > 0.01, "load form {form}: sliding μ moves by {moved} only");
    }
}

#[test]
fn memory_forms_separate_the_accelerating_and_decelerating_branches() {
    let c = at(0.9, 8.0);
    let base = mean_of(&signatures(&quick(Vec::new()), c, 2, 10.0), |s| s.branch_gap);
    let lugre = mean_of(&signatures(&quick(vec![strong(Effect::FrictionHysteresis, 0)]), c, 2, 10.0), |s| s.branch_gap);
    let rate_state =
        mean_of(&signatures(&quick(vec![strong(Effect::FrictionHysteresis, 1)]), c, 2, 10.0), |s| s.branch_gap);
    eprintln!("branch gap: baseline {base}, LuGre {lugre}, rate-and-state {rate_state}");
    assert!(base.abs() < 0.002, "baseline gap {base}");
    // LuGre: friction builds up over the bristle length after each reversal,
    // so it is lower while accelerating.
    assert!(lugre - base < -0.005, "LuGre gap {lugre}");
    // Rate-and-state: the state lags, so friction is higher while accelerating.
    assert!(rate_state - base > 0.004, "rate-and-state gap {rate_state}");
}

#[test]
fn harmonic_forms_put_harmonics_into_the_normal_force() {
    let c = at(0.7, 8.0);
    let base = signatures(&quick(Vec::new()), c, 1, 10.0)[0];
    assert!(base.n_h1 < 0.003 && base.n_h2 < 0.003, "baseline harmonics {} {}", base.n_h1, base.n_h2);
    let pos = signatures(&quick(vec![strong(Effect::NormalForceHarmonics, 0)]), c, 1, 10.0)[0];
    eprintln!("harmonics: baseline {} {}, position-following {} {}", base.n_h1, base.n_h2, pos.n_h1, pos.n_h2);
    assert!(pos.n_h1 > 0.03 && pos.n_h2 > 0.005, "position-following: 1× {} 2× {}", pos.n_h1, pos.n_h2);
    let wander = IndependentEffect::NormalForceHarmonics(HarmonicForm::WanderingHarmonic {
        strength: 0.08,
        order: 2,
        phase_diffusion_rad2_per_s: 0.05,
        initial_phase_rad: 1.0,
    });
    let w = signatures(&quick(vec![wander]), c, 1, 10.0)[0];
    eprintln!("wandering 2×: {} {}", w.n_h1, w.n_h2);
    assert!(w.n_h2 > 0.04 && w.n_h1 < 0.01, "wandering 2×: 1× {} 2× {}", w.n_h1, w.n_h2);
}

#[test]
fn colour_forms_raise_the_residuals_lag_10_autocorrelation() {
    let c = at(0.7, 8.0);
    let base = mean_of(&signatures(&quick(Vec::new()), c, 2, 10.0), |s| s.lag10);
    assert!(base.abs() < 0.05, "baseline lag-10 autocorrelation {base}");
    for form in 0..2 {
        let on =
            mean_of(&signatures(&quick(vec![strong(Effect::ColouredFrictionNoise, form)]), c, 2, 10.0), |s| s.lag10);
        eprintln!("colour form {form}: lag-10 {on} (baseline {base})");
        assert!(on > 0.25, "colour form {form}: lag-10 autocorrelation {on}");
    }
}

#[test]
fn non_gaussian_forms_change_the_residuals_shape() {
    let c = at(0.7, 8.0);
    let base = signatures(&quick(Vec::new()), c, 2, 10.0);
    let (k0, s0) = (mean_of(&base, |s| s.kurtosis), mean_of(&base, |s| s.skewness));
    assert!((k0 - 3.0).abs() < 0.3 && s0.abs() < 0.1, "baseline kurtosis {k0}, skewness {s0}");
    let t = IndependentEffect::NonGaussianFriction(ShapeForm::StudentT { strength: 1.0, degrees_of_freedom: 4 });
    let k = mean_of(&signatures(&quick(vec![t]), c, 2, 10.0), |s| s.kurtosis);
    eprintln!("shape: baseline kurtosis {k0} skewness {s0}; Student-t kurtosis {k}");
    assert!(k > 4.5, "Student-t kurtosis {k}");
    let skew = mean_of(&signatures(&quick(vec![strong(Effect::NonGaussianFriction, 1)]), c, 2, 10.0), |s| s.skewness);
    eprintln!("bimodal skewness {skew}");
    assert!(skew > 0.4, "bimodal skewness {skew}");
}

#[test]
fn stiction_forms_raise_the_breakaway_friction() {
    let c = at(0.6, 20.0);
    let base = mean_of(&signatures(&quick(Vec::new()), c, 2, 10.0), |s| s.stick_mu);
    assert!(base > 0.25, "the baseline sticks here ({base})");
    for form in 0..2 {
        let on = mean_of(&signatures(&quick(vec![strong(Effect::Stiction, form)]), c, 2, 10.0), |s| s.stick_mu);
        eprintln!("stiction form {form}: breakaway |F|/N {on} against {base}");
        assert!(on - base > 0.02, "stiction form {form}: breakaway |F|/N {on} against {base}");
    }
}

#[test]
fn drift_forms_move_the_mean_normal_force() {
    let c = at(0.7, 8.0);
    let base = mean_of(&signatures(&quick(Vec::new()), c, 4, 10.0), |s| s.n_drift.abs());
    assert!(base < 0.005, "baseline drift {base}");
    let thermal =
        IndependentEffect::NormalForceDrift(DriftForm::ThermalRelaxation { strength: -0.15, time_constant_s: 5.0 });
    let d = mean_of(&signatures(&quick(vec![thermal]), c, 1, 10.0), |s| s.n_drift);
    eprintln!("drift: baseline {base}, thermal {d}");
    assert!(d < -0.06, "thermal relaxation drift {d}");
    let wear = mean_of(&signatures(&quick(vec![strong(Effect::NormalForceDrift, 1)]), c, 4, 10.0), |s| s.n_drift.abs());
    eprintln!("Brownian wear |drift| {wear}");
    assert!(wear > 0.015, "Brownian wear drift {wear}");
}

/// The truth statistics and the records see the same dynamics.
#[test]
fn truth_statistics_agree_with_the_records() {
    let truth = quick(Vec::new());
    for c in [at(0.7, 4.0), at(0.6, 20.0)] {
        let records = signatures(&truth, c, 2, 10.0);
        let stats = truth_path_stats(&truth, &[c], 10.0, 4, 3);
        assert_eq!(stats.len(), 1);
        assert_eq!(stats[0].len(), 4);
        let from_stats = stats[0].iter().map(|s| s.peak_mean_m).sum::<f64>() / 4.0;
        let from_records = mean_of(&records, |s| s.peak_mean);
        assert!((from_stats / from_records - 1.0).abs() < 0.005, "{from_stats} vs {from_records}");
        assert!(stats[0].iter().all(|s| s.periods == (10.0 * c.excitation_frequency_hz) as u32));
    }
    let stats = truth_path_stats(&truth, &[at(0.6, 20.0)], 10.0, 2, 3);
    assert!(stats[0][0].stick_fraction > 0.0, "stops at η = 0.6, 20 N");
    // Same seed, same numbers; another seed, other numbers.
    assert_eq!(stats, truth_path_stats(&truth, &[at(0.6, 20.0)], 10.0, 2, 3));
    assert_ne!(stats, truth_path_stats(&truth, &[at(0.6, 20.0)], 10.0, 2, 4));
    assert!(truth_path_stats(&truth, &[at(0.6, 20.0)], 10.0, 0, 3)[0].is_empty());
}

#[test]
fn random_truths_are_deterministic_and_refuse_bad_requests() {
    let hidden = [(Effect::Stiction, 1, true), (Effect::NormalForceDrift, 0, false)];
    let (a, ca) = random_truth(5, &hidden, &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth");
    let (b, cb) = random_truth(5, &hidden, &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth");
    assert_eq!(a, b);
    assert_eq!(ca, cb);
    assert_eq!(ca.len(), 18);
    assert_eq!(a.families(), vec![Effect::Stiction, Effect::NormalForceDrift]);
    // The rig and law do not depend on what is hidden.
    let (plain, _) = random_truth(5, &[], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth");
    assert_eq!((plain.rig, plain.friction), (a.rig, a.friction));
    assert!(random_truth(6, &hidden, &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth").0 != a);
    assert!(a.description.contains("stiction") && a.description.contains("Dieterich"));
    // Frequency-major grid.
    assert_eq!(ca[1].normal_force_n, 8.0);
    assert_eq!(ca[3].excitation_frequency_hz, 0.7 * a.rig.natural_frequency_hz);
    let dup = [(Effect::Stiction, 0, true), (Effect::Stiction, 1, true)];
    assert!(random_truth(5, &dup, &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).is_err());
    assert!(random_truth(5, &[(Effect::Stiction, 2, true)], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).is_err());
    assert!(random_truth(5, &[], &[], &DEFAULT_FREQUENCY_RATIOS).is_err());
    assert!(random_truth(5, &[], &DEFAULT_LOADS_N, &[0.0]).is_err());
    // Every family and form has a preset and serialises.
    for (family, forms) in FORMS {
        for form in 0..forms.len() as u32 {
            let (t, _) = random_truth(1, &[(family, form, false)], &[4.0], &[0.8]).expect("a truth");
            assert_eq!(t.effects[0].family(), family);
            assert_eq!(t.effects[0].form_index(), form);
            let json = serde_json::to_value(&t).expect("serialises");
            assert_eq!(json["effects"][0]["effect"], family.name());
        }
    }
}

/// Some drawn truths hold the block at the heaviest load; the
/// description says so.
#[test]
fn a_truth_that_sticks_throughout_says_so() {
    let stuck = (0..200)
        .map(|seed| random_truth(seed, &[], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth").0)
        .find(|t| t.conditions.iter().any(|c| c.expected_to_stick_throughout))
        .expect("some seed draws a heavy friction level");
    assert!(stuck.description.contains("stay stuck"), "{}", stuck.description);
    let (n, _) = random_truth(0, &[], &[0.5], &[0.8]).expect("a truth");
    assert!(!n.description.contains("stay stuck"));
}

/// One path's statistics on one thread, and the thread's CPU time, s.
fn truth_path_stats_on_one_thread(truth: &IndependentTruth, c: Condition, duration_s: f64) -> (PathStat, f64) {
    let thread_cpu_s = || {
        let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: clock_gettime writes one timespec into `ts`.
        unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
        ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
    };
    rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool").install(|| {
        let start = thread_cpu_s();
        let stat = truth_path_stats(truth, &[c], duration_s, 1, 1)[0][0];
        (stat, thread_cpu_s() - start)
    })
}

/// Times one 18-run set (3 loads × 6 frequencies × 50 s) and one truth-
/// statistics call (32 paths × 18 conditions × 50 s). Run with
/// `cargo test --release --lib independent::tests::timing -- --ignored --nocapture`.
#[test]
#[ignore = "minutes: the runtime of a full set and of the truth statistics (12.7e9 steps)"]
fn timing_of_a_full_set_and_the_truth_statistics() {
    let (truth, conditions) =
        random_truth(7, &[(Effect::FrictionHysteresis, 1, true)], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS)
            .expect("a truth");
    // CPU time per step of one path on one thread (the machine may be shared).
    for (name, t) in [("baseline", truth.baseline()), ("rate-and-state", truth.clone())] {
        let (stat, cpu_s) = truth_path_stats_on_one_thread(&t, conditions[4], 50.0);
        let grid = Grid::new(&t, conditions[4].excitation_frequency_hz, 50.0);
        let steps = (grid.warmup_steps + grid.record_steps) as f64;
        eprintln!("{name}: {:.1} ns CPU per step ({} periods, {cpu_s:.2} s)", cpu_s / steps * 1e9, stat.periods);
    }
    let dir = std::env::temp_dir().join(format!("stickslip-independent-timing-{}", std::process::id()));
    let data = dir.join("data");
    let start = std::time::Instant::now();
    write_set(&data, &truth, &conditions, &RecordShape::default(), 3).expect("the set is written");
    eprintln!("18-run set (rate-and-state hidden): {:.2} s", start.elapsed().as_secs_f64());
    let (plain, _) = random_truth(7, &[], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth");
    let start = std::time::Instant::now();
    write_set(&data, &plain, &conditions, &RecordShape::default(), 3).expect("the set is written");
    eprintln!("18-run set (baseline): {:.2} s", start.elapsed().as_secs_f64());
    let start = std::time::Instant::now();
    let stats = truth_path_stats(&plain, &conditions, 50.0, 32, 5);
    eprintln!("truth stats 32 × 18 × 50 s (baseline): {:.2} s", start.elapsed().as_secs_f64());
    assert_eq!(stats.len(), 18);
    let start = std::time::Instant::now();
    let stats = truth_path_stats(&truth, &conditions, 50.0, 32, 5);
    eprintln!("truth stats 32 × 18 × 50 s (rate-and-state): {:.2} s", start.elapsed().as_secs_f64());
    assert!(stats.iter().all(|s| s.len() == 32));
    let _ = std::fs::remove_dir_all(&dir);
}
