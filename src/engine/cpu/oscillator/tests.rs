//! Unit tests of the f64 integrator's parts.

use super::*;

#[test]
fn harmonics_by_angle_addition_match_a_cos_per_harmonic() {
    let effects = crate::engine::effects::Effects {
        normal_force_harmonics: Some(crate::engine::effects::NormalForceHarmonics {
            form: crate::engine::effects::HarmonicForm::Fourier,
            amplitudes_n: [1.5, 0.0, 0.7, 0.3],
            amplitudes_per_n0: [0.0, 0.01, 0.0, 0.0],
            phases_rad: [0.4, -2.0, 3.1, -0.9],
            shape: 2.0,
        }),
        ..Default::default()
    };
    let e = EffectParams::new(&effects, 20.0, 0.3, 1.0 / 600.0);
    for i in 0..1000 {
        let phase = i as f64 * 0.001_234_567;
        let theta = std::f64::consts::TAU * phase;
        let direct: f64 = (0..4)
            .map(|k| e.harmonic_amplitudes_n[k] * ((k + 1) as f64 * theta + e.harmonic_phases_rad[k]).cos())
            .sum();
        assert!((harmonics_n(&e, phase, 0.37) - direct).abs() < 1e-14, "phase {phase}");
    }
    assert_eq!(harmonics_n(&EffectParams::default(), 0.3, 0.37), 0.0);
}

#[test]
fn the_position_form_follows_the_displacement_not_the_phase() {
    let effects = crate::engine::effects::Effects {
        normal_force_harmonics: Some(crate::engine::effects::NormalForceHarmonics {
            form: HarmonicForm::Position,
            amplitudes_n: [1.5, 0.0, 0.7, 0.3],
            amplitudes_per_n0: [0.04, 0.02, 0.5, 0.5],
            phases_rad: [0.4, -2.0, 3.1, -0.9],
            shape: 2.0,
        }),
        ..Default::default()
    };
    let e = EffectParams::new(&effects, 20.0, 0.3, 1.0 / 600.0);
    assert_eq!(e.harmonic_amplitudes_n, [0.04 * 20.0, 0.02 * 20.0, 0.0, 0.0]);
    for r in [-3.0, -1.0, -0.25, 0.0, 0.5, 1.0, 2.7] {
        let expected = 20.0 * (0.04 * r + 0.02 * r * r);
        for phase in [0.0, 0.3, 0.77] {
            assert!((harmonics_n(&e, phase, r) - expected).abs() < 1e-14, "r {r}, phase {phase}");
        }
    }
}

#[test]
fn small_turns_match_sin_cos() {
    for theta in [0.0, 1e-9, 1e-4, 0.0123, -0.03, 0.0499, 0.0731, -0.0999, 0.1] {
        let (turn, exact) = (Trig::turn(theta), Trig::at(theta));
        assert!(
            (turn.cos - exact.cos).abs() <= 2.3e-16 && (turn.sin - exact.sin).abs() <= 1e-17,
            "{theta}: {turn:?} {exact:?}"
        );
    }
}

/// The paper rig at 7 Hz and 16.39 N without noise, under hysteresis
/// `lag` with a 10 ms memory, plus `overrides`.
fn noiseless_lag_oscillator(overrides: &[&str]) -> Oscillator {
    let base = [
        "friction.sigma=0",
        "normal_force.sigma=0",
        "friction_hysteresis.form=\"lag\"",
        "friction_hysteresis.time_constant_s=0.01",
    ];
    let overrides: Vec<String> = base.iter().chain(overrides).map(|s| s.to_string()).collect();
    let model = crate::engine::Model::paper_rig(&overrides).unwrap();
    let condition = crate::engine::Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
    Oscillator::new(&model, condition).unwrap()
}

/// A slip from rest right after a velocity zero is a breakaway like one
/// from a stick, so under hysteresis `lag` the lagged coefficient starts
/// at the static one the breakaway was judged by. Here the law rises with
/// speed (b < 0: static 0.027), the block slips forward with a lagged
/// coefficient of 0.3 carried from faster sliding, and the spring pushes
/// forward with 0.15 N0: friction stops it within the step, and the spring
/// is beyond the static friction, so it slips on. Carried over, the 0.3
/// held it: it re-slipped without moving up to the event limit and was
/// forced to stick.
#[test]
fn a_slip_from_rest_under_lag_starts_at_the_static_coefficient() {
    let osc = noiseless_lag_oscillator(&["friction.b=-0.4"]);
    let mut path = Path::new(&osc, 1, 0, InitialState { x_m: 0.0, v_m_per_s: 1e-4 });
    let n = path.normal_force_n;
    assert!((path.static_coefficient() - 0.027).abs() < 1e-12 && n > 0.0);
    // The spring at t = 0 (base at its amplitude) pushes with 0.15 N.
    path.x_m = osc.base_amplitude_m - 0.15 * n / osc.stiffness_n_per_m;
    path.slip_start_x_m = path.x_m;
    path.memory = 0.3;
    assert_eq!(path.mode, Mode::Slip(1));
    path.advance_segment(0.0, 1e-3, Trig { cos: 1.0, sin: 0.0 }, None, false);
    assert_eq!(path.mode, Mode::Slip(1), "held at rest: v = {}", path.v_m_per_s);
    assert!(path.v_m_per_s > 0.0 && path.memory < 0.3, "v = {}, μ_f = {}", path.v_m_per_s, path.memory);
}

/// Under hysteresis `lag` with a stiction released over a slip length,
/// a block that breaks away slips on: sliding starts at the static
/// coefficient, the lagged part of it without the excess the release
/// adds on top. With the excess counted twice (the lagged coefficient
/// started at the static one, excess included), friction at the start
/// exceeded the force that broke the block away, and it re-slipped
/// without moving up to the event limit and was forced to stick.
#[test]
fn a_breakaway_under_lag_and_a_released_stiction_slips_on() {
    let osc = noiseless_lag_oscillator(&["stiction.excess=0.2", "stiction.release_length_m=1e-4"]);
    let mut path = Path::new(&osc, 1, 0, InitialState { x_m: 0.0, v_m_per_s: 0.0 });
    let (n, mu_s) = (path.normal_force_n, path.static_coefficient());
    // At rest, the spring at t = 0 pushing with 1.05 of the breakaway force.
    path.mode = Mode::Stick;
    path.x_m = osc.base_amplitude_m - 1.05 * mu_s * n / osc.stiffness_n_per_m;
    let x0 = path.x_m;
    path.advance_segment(0.0, 1e-3, Trig { cos: 1.0, sin: 0.0 }, None, false);
    assert_eq!(path.mode, Mode::Slip(1), "stuck: v = {}", path.v_m_per_s);
    assert!(path.v_m_per_s > 0.0 && path.x_m > x0, "v = {}, moved {} m", path.v_m_per_s, path.x_m - x0);
    assert!((path.lag_start_coefficient() + 0.2 - mu_s).abs() < 1e-12);
}

/// Under hysteresis `ageing` a breakaway is judged by the static
/// coefficient with the contact age held at the interval's start, and
/// the slip starts from that same age, so sliding friction at v = 0
/// starts at exactly that static coefficient (no stop and re-slip at
/// once). The age held is the stick's start plus the time stuck up to
/// the interval's start, and the term is B ln((θ + θ_0)/(θ_c + θ_0)).
#[test]
fn an_ageing_slip_starts_at_the_static_coefficient() {
    let model = crate::engine::Model::paper_rig(&[
        "friction.sigma=0".into(),
        "normal_force.sigma=0".into(),
        "friction_hysteresis.form=\"ageing\"".into(),
        "friction_hysteresis.length_m=1e-5".into(),
        "friction_hysteresis.strength=0.03".into(),
    ])
    .unwrap();
    let condition = crate::engine::Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
    let osc = Oscillator::new(&model, condition).unwrap();
    let mut path = Path::new(&osc, 1, 0, InitialState { x_m: 0.0, v_m_per_s: 0.0 });
    assert_eq!(path.memory_form, Memory::Ageing);
    // Stuck since 0.1 s with an age of 2 ms then; interval 100 starts later.
    path.mode = Mode::Stick;
    (path.memory, path.stick_since_s, path.interval) = (2e-3, 0.1, 100);
    path.draw_noise();
    let t_s = 100.0 * osc.noise_interval_s;
    let age_s = path.contact_age_at(t_s);
    let cutoff_age_s = 1e-5 / AGEING_CUTOFF_SPEED_M_PER_S;
    let floor_age_s = 1e-5 / AGEING_FLOOR_SPEED_M_PER_S;
    assert!((age_s - (2e-3 + t_s - 0.1)).abs() < 1e-15, "{age_s}");
    let expected = 0.03 * ((age_s + floor_age_s) / (cutoff_age_s + floor_age_s)).ln();
    assert!((path.ageing_excess - expected).abs() < 1e-15, "{} vs {expected}", path.ageing_excess);
    assert!((path.static_coefficient() - (0.527 + expected)).abs() < 1e-12);
    let sliding = path.friction_coefficient(0.0, 0.0, path.x_m, age_s);
    assert!((sliding - path.static_coefficient()).abs() < 1e-15, "{sliding} vs {}", path.static_coefficient());
}

/// The friction noise's standardised values g over `n` intervals with
/// the coloured noise set by `overrides`.
fn friction_noise(overrides: &[&str], n: u64) -> Vec<f64> {
    let mut overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    overrides.push("friction.sigma=0.02".into());
    let model = crate::engine::Model::paper_rig(&overrides).unwrap();
    let condition = crate::engine::Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
    let osc = Oscillator::new(&model, condition).unwrap();
    let mut path = Path::new(&osc, 5, 0, InitialState { x_m: 0.0, v_m_per_s: 0.0 });
    (0..n)
        .map(|k| {
            path.interval = k;
            path.draw_noise();
            path.friction_noise / 0.02
        })
        .collect()
}

/// Sample autocorrelation of `g` at `lag`.
fn autocorrelation(g: &[f64], lag: usize) -> f64 {
    let m = g.iter().sum::<f64>() / g.len() as f64;
    let var = g.iter().map(|x| (x - m).powi(2)).sum::<f64>();
    g.windows(lag + 1).map(|w| (w[0] - m) * (w[lag] - m)).sum::<f64>() / var
}

/// `fast_slow` is two AR(1) parts with τc and 10 τc, the slow one
/// carrying `coloured_share` of the variance: at 30 intervals with τc =
/// 5 intervals the correlation is 0.4 e^−6 + 0.6 e^−0.6 = 0.33, where a
/// single AR(1) with τc has lost it (e^−6 = 0.002). The variance stays
/// σ_μ². With 200 000 intervals the sample autocorrelation's standard
/// error is about 0.015 and the variance's about 0.03 (about 3 000
/// independent values), so the bounds are 4 standard errors or more.
#[test]
fn fast_slow_noise_has_two_time_scales() {
    let interval = "noise.interval_s=0.001";
    let tau = "coloured_friction_noise.correlation_time_s=0.005";
    let two = friction_noise(
        &[interval, tau, "coloured_friction_noise.form=\"fast_slow\"", "coloured_friction_noise.coloured_share=0.6"],
        200_000,
    );
    let one = friction_noise(&[interval, tau], 200_000);
    let variance = two.iter().map(|x| x * x).sum::<f64>() / two.len() as f64;
    let (two_30, one_30) = (autocorrelation(&two, 30), autocorrelation(&one, 30));
    let two_1 = autocorrelation(&two, 1);
    let expected_1 = 0.4 * (-0.2f64).exp() + 0.6 * (-0.02f64).exp();
    println!(
        "fast_slow: variance {variance:.3}, lag 1 {two_1:.3} ({expected_1:.3}), lag 30 {two_30:.3}; ar1 lag 30 {one_30:.3}"
    );
    assert!((variance - 1.0).abs() < 0.12, "variance {variance}");
    assert!((two_30 - 0.331).abs() < 0.06, "fast_slow at lag 30: {two_30}");
    assert!((two_1 - expected_1).abs() < 0.03, "fast_slow at lag 1: {two_1} vs {expected_1}");
    assert!(one_30.abs() < 0.03, "ar1 at lag 30: {one_30}");
}

#[test]
fn rotation_by_half_steps_matches_the_functions() {
    let w = 44.0;
    let (t, h) = (0.0123, 0.004);
    let half = Trig::at(0.5 * w * h);
    let end = Trig::at(w * t).rotated(half).rotated(half);
    let exact = Trig::at(w * (t + h));
    assert!((end.cos - exact.cos).abs() < 1e-15 && (end.sin - exact.sin).abs() < 1e-15, "{end:?} {exact:?}");
}

/// A path that reads the main stream's pair A from a shared table is the
/// path that draws it, bit for bit: without effects, and with every effect
/// that draws more of the main stream (a friction value held over several
/// intervals, a second value for non-Gaussian friction, noisy stiction) or
/// the colour stream.
#[test]
fn paths_reading_the_noise_table_are_those_drawing_it() {
    let cases: [&[&str]; 4] = [
        &[],
        &["coloured_friction_noise.form=\"hold\"", "coloured_friction_noise.correlation_time_s=0.01"],
        &["non_gaussian_friction.strength=0.5", "non_gaussian_friction.form=\"mixture\""],
        &[
            "stiction.form=\"noisy\"",
            "stiction.excess=0.2",
            "coloured_friction_noise.form=\"two_scale\"",
            "coloured_friction_noise.correlation_time_s=0.01",
        ],
    ];
    for overrides in cases {
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        let model = crate::engine::Model::paper_rig(&overrides).unwrap();
        let condition = crate::engine::Condition { excitation_frequency_hz: 12.0, normal_force_n: 16.39 };
        let osc = Oscillator::new(&model, condition).unwrap();
        let initial = InitialState { x_m: 0.0, v_m_per_s: 0.0 };
        let table = noise::pair_a_table(rng::seed_key(4), 2, osc.noise_intervals_in(20) as u64 + 1, true);
        let mut read = Path::new(&osc, 4, 2, initial);
        read.pair_a_table = noise::PathPairs(table);
        let mut drawn = Path::new(&osc, 4, 2, initial);
        for _ in 0..20 {
            run_period(std::slice::from_mut(&mut read), true, None);
            run_period(std::slice::from_mut(&mut drawn), true, None);
            let state = |p: &Path<'_>| {
                [p.x_m, p.v_m_per_s, p.friction_noise, p.normal_force_n, p.period_cos_integral].map(f64::to_bits)
            };
            assert_eq!(state(&read), state(&drawn), "{overrides:?}");
        }
    }
}

/// A span no longer than one step takes one without the division and
/// `ceil`: the same count as the rule's formula, at the bound, a last bit
/// either side of it, far below it and past it.
#[test]
fn a_span_within_one_step_takes_one_as_the_formula_does() {
    let formula = |span: f64, max: f64| ((span / max) * (1.0 - 1e-12)).ceil().max(1.0) as u32;
    for max in [1e-3f64, 1.0 / 600.0, 1.0 / 7.0 / 16.0] {
        let below = f64::from_bits(max.to_bits() - 1);
        let above = f64::from_bits(max.to_bits() + 1);
        for span in [max, below, above, 0.5 * max, 1e-300, max * (1.0 + 1e-12), 2.0 * max, 2.0 * above, 7.3 * max] {
            assert_eq!(period::span_steps(span, max), formula(span, max), "span {span:e} of steps {max:e}");
        }
        assert_eq!(period::span_steps(below, max), 1);
    }
}
