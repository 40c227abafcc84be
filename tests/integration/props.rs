//! Property tests (proptest): arbitrary bytes and arbitrary numbers fed to
//! the model-file reader, the measurement reader and merge. Each call must
//! return within a time limit (never a hang), never panic, and give either a
//! result that is valid or an error that names what it refuses; the readers
//! write nothing.

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::TestRunner;
use stickslip::Error;
use stickslip::engine::Model;
use stickslip::engine::model::{PAPER_RIG_TOML, limits};
use stickslip::measure::read_measurement_set;
use stickslip::sweep::{AccumulatorFile, merge_shards, read_accumulators, write_accumulators};

use crate::hostile::{Scratch, honest_shards};

/// Runs `f` on another thread; `None` if it panicked, a failure if it hung.
fn guarded<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> Option<T> {
    let (tx, rx) = mpsc::channel();
    let handle = std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    match rx.recv_timeout(Duration::from_secs(20)) {
        Ok(v) => Some(v),
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("the call hung"),
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            let _ = handle.join();
            None
        }
    }
}

/// Every entry under `dir`, recursively, with its size.
fn tree(dir: &Path) -> Vec<(PathBuf, u64)> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let p = e.path();
            let len = e.metadata().map(|m| m.len()).unwrap_or(0);
            if p.is_dir() {
                out.extend(tree(&p));
            }
            out.push((p, len));
        }
    }
    out.sort();
    out
}

/// A valid model satisfies every range and has finite derived quantities.
fn assert_valid(m: &Model) {
    assert!(m.validate().is_ok());
    let (k, c) = (m.stiffness_n_per_m(), m.damping_n_s_per_m());
    assert!(k.is_finite() && k > 0.0 && c.is_finite() && c >= 0.0, "k {k}, c {c}");
    assert!(m.excitation.amplitude_m <= limits::AMPLITUDE_MAX_M);
}

const KEYS: &[&str] = &[
    "rig.mass_kg",
    "rig.natural_frequency_hz",
    "rig.damping_ratio",
    "excitation.amplitude_m",
    "friction.a",
    "friction.b",
    "friction.c",
    "friction.d",
    "friction.sigma",
    "normal_force.sigma",
    "noise.interval_s",
    "solver.steps_per_period",
    "stiction.excess",
    "stiction.release_length_m",
    "friction_hysteresis.length_m",
    "coloured_friction_noise.correlation_time_s",
    "normal_force_drift.rate_per_s",
    "normal_force_drift.curvature_per_s2",
    "load_dependent_friction.strength",
    "load_dependent_friction.curvature_per_n2",
    "non_gaussian_friction.strength",
];

/// Numbers that matter: tiny, huge, zero, negative, non-finite and ordinary.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>(),
        Just(0.0),
        Just(-0.0),
        Just(f64::MIN_POSITIVE),
        Just(5e-324),
        Just(1e308),
        Just(-1e308),
        Just(f64::INFINITY),
        Just(f64::NAN),
        -1e7..1e7f64,
        -2.0..2.0f64,
    ]
}

/// 256 cases per property (PROPTEST_CASES overrides it for a deeper run).
fn config() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(256);
    ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() }
}

proptest! {
    #![proptest_config(config())]

    /// Arbitrary bytes as a model file, and the paper rig with arbitrary
    /// bytes spliced in: a valid model or a named error.
    #[test]
    fn model_reader_takes_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..1024), at in 0usize..2000) {
        let s = Scratch::new("prop-model");
        let mut spliced = PAPER_RIG_TOML.as_bytes().to_vec();
        let at = at.min(spliced.len());
        spliced.splice(at..at, bytes.iter().copied().take(64));
        for (name, content) in [("arbitrary.toml", bytes.clone()), ("spliced.toml", spliced)] {
            let path = s.write(name, &content);
            let before = tree(&s.0);
            let result = guarded(move || Model::from_file(&path, &[]).map_err(|e| e.to_string()));
            let result = result.expect("the model reader panicked");
            match result {
                Ok(model) => assert_valid(&model),
                Err(message) => prop_assert!(
                    message.contains(name) || message.contains("model parameter"),
                    "{message}"
                ),
            }
            prop_assert_eq!(tree(&s.0), before, "the reader wrote something");
        }
    }

    /// Arbitrary numbers for any key (`--set`): a valid model or an error
    /// naming the key.
    #[test]
    fn model_takes_arbitrary_numbers(key in prop::sample::select(KEYS), value in number()) {
        let assignment = format!("{key}={value:e}");
        let result = guarded(move || Model::paper_rig(&[assignment]).map_err(|e| e.to_string()))
            .expect("the model reader panicked");
        match result {
            Ok(model) => assert_valid(&model),
            Err(message) => {
                let table = key.split('.').next().unwrap();
                prop_assert!(message.contains(key) || message.contains(table), "{key}={value:e}: {message}");
                prop_assert!(message.len() < 400, "{message}");
            }
        }
    }

    /// Arbitrary bytes as the manifest and as the run file; arbitrary numbers
    /// in the manifest and the record: a set or an error naming a file of it.
    #[test]
    fn measurement_reader_takes_arbitrary_input(
        manifest_bytes in prop::collection::vec(any::<u8>(), 0..512),
        run_bytes in prop::collection::vec(any::<u8>(), 0..2048),
        numbers in prop::collection::vec(number(), 6),
        samples in 0usize..400,
        which in 0usize..3,
    ) {
        let s = Scratch::new("prop-measure");
        let manifest = match which {
            0 => manifest_bytes.clone(),
            _ => {
                let n: Vec<String> =
                    numbers.iter().map(|v| if v.is_finite() { format!("{v:e}") } else { "1e999".into() }).collect();
                format!(
                    r#"{{ "format": "stickslip-measurements/1",
                         "rig": {{ "mass_kg": {}, "natural_frequency_hz": {}, "damping_ratio": {} }},
                         "runs": [ {{ "file": "r.csv", "excitation_frequency_hz": {},
                                      "excitation_amplitude_m": {}, "normal_force_n": {} }} ] }}"#,
                    n[0], n[1], n[2], n[3], n[4], n[5]
                ).into_bytes()
            }
        };
        let run = match which {
            2 => {
                let mut text = String::from("t,x,v\n");
                let dt = numbers[3].abs().max(1e-300);
                for i in 0..samples {
                    text += &format!("{:e},{:e},{:e}\n", i as f64 * dt, numbers[i % 6], numbers[(i + 1) % 6]);
                }
                text.into_bytes()
            }
            _ => run_bytes.clone(),
        };
        s.write("set/manifest.json", &manifest);
        s.write("set/r.csv", &run);
        let before = tree(&s.0);
        let dir = s.path("set");
        let result = guarded(move || {
            read_measurement_set(&dir).map_err(|e| (matches!(e, Error::Measurement { .. }), e.to_string()))
        })
        .expect("the measurement reader panicked");
        match result {
            Ok(set) => {
                prop_assert!(set.rig.mass_kg > 0.0 && set.rig.natural_frequency_hz > 0.0);
                for r in &set.runs {
                    prop_assert!(r.t_s.iter().chain(&r.x_m).all(|v| v.is_finite()));
                    prop_assert!(r.excitation_frequency_hz <= limits::FREQUENCY_HZ.1);
                }
            }
            Err((is_measurement, message)) => {
                prop_assert!(is_measurement, "{message}");
                prop_assert!(message.contains("manifest.json") || message.contains("r.csv"), "{message}");
                prop_assert!(!message.contains('\u{1b}') && message.len() < 700, "{message}");
            }
        }
        prop_assert_eq!(tree(&s.0), before, "the reader wrote something");
    }
}

/// Arbitrary bytes as a shard's accumulators.json: refused by name.
#[test]
fn merge_takes_arbitrary_bytes() {
    let s = Scratch::new("prop-merge-bytes");
    let (a, _) = honest_shards(&s);
    let mut runner = TestRunner::new(config());
    runner
        .run(&prop::collection::vec(any::<u8>(), 0..2048), |bytes| {
            s.write("shard/accumulators.json", &bytes);
            let before = tree(&s.0);
            let (a, shard) = (a.clone(), s.path("shard"));
            let result = guarded(move || merge_shards(&[a, shard]).map(|_| ()).map_err(|e| e.to_string()))
                .expect("merge panicked");
            let message = result.expect_err("arbitrary bytes are not an honest shard");
            prop_assert!(message.contains("shard/accumulators.json"), "{message}");
            prop_assert_eq!(tree(&s.0), before);
            Ok(())
        })
        .unwrap();
}

/// An honest shard with one field set to an arbitrary value and its
/// digest recomputed (a forgery): refused by name, or, when the value
/// happens to keep every invariant, merged into finite, ordered statistics
/// with a variance that is not negative.
#[test]
fn merge_takes_forged_numbers() {
    let s = Scratch::new("prop-merge-forged");
    let (a, b) = honest_shards(&s);
    let (honest, _) = read_accumulators(&b).unwrap();
    let strategy = (0usize..12, 0usize..2, any::<u128>(), any::<u64>(), number());
    let mut runner = TestRunner::new(config());
    runner
        .run(&strategy, |(field, point, big, small, real)| {
            let mut file: AccumulatorFile = honest.clone();
            let p = &mut file.points[point];
            let signed = (big as i128) >> (big % 100) as u32;
            match field {
                0 => p.peaks = small,
                1 => p.realisations = small,
                2 => p.sum_q = signed.to_string(),
                3 => p.sum_q2 = (big >> (big % 128) as u32).to_string(),
                4 => p.stick_units = small >> (small % 64) as u32,
                5 => p.clamped = small % 4,
                6 => p.sum_phase_sin = signed.to_string(),
                7 => p.sum_phase_versine = (big >> (big % 128) as u32).to_string(),
                8 => p.excitation_frequency_hz = real,
                9 => p.range.hi_m = real,
                10 => p.histogram = vec![((small % 2048) as u32, small % 64 + 1)],
                _ => {
                    let i = (small as usize) % p.histogram.len();
                    p.histogram[i].1 = small % 40 + 1;
                }
            }
            file.integrity.digest = file.content_digest();
            let dir = s.path("forged");
            std::fs::create_dir_all(&dir).unwrap();
            write_accumulators(&dir.join("accumulators.json"), &file).unwrap();
            let before = tree(&s.0);
            let a = a.clone();
            let result = guarded(move || merge_shards(&[a, dir]).map_err(|e| e.to_string())).expect("merge panicked");
            match result {
                Ok((_, merged)) => {
                    for row in merged.rows() {
                        prop_assert!(row.peak_mean_m.is_finite() && row.peak_var_m2 >= 0.0, "{row:?}");
                        prop_assert!(row.peak_p05_m <= row.peak_p50_m && row.peak_p50_m <= row.peak_p95_m, "{row:?}");
                        prop_assert!((0.0..=1.0 + 1e-6).contains(&row.stick_fraction), "{row:?}");
                        prop_assert!(row.phase_mean_deg.is_finite() && row.phase_var_deg2 >= 0.0, "{row:?}");
                    }
                }
                Err(message) => prop_assert!(message.contains("forged/accumulators.json"), "{message}"),
            }
            prop_assert_eq!(tree(&s.0), before);
            Ok(())
        })
        .unwrap();
    // The honest shards themselves merge, and their digests check.
    let (_, merged) = merge_shards(&[a.clone(), b.clone()]).unwrap();
    assert_eq!(merged.conditions.len(), 4);
    assert_eq!(honest.integrity.digest, honest.content_digest());
}
