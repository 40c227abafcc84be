//! The independent generator's sets (`diagnose::benchmark::independent`):
//! written in the measurement format, read back by the reader, the same
//! bytes for the same seed, and the free time origin.

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use stickslip::diagnose::benchmark::independent::{
    IndependentTruth, RecordShape, random_truth, simulate_run, truth_path, write_set,
};
use stickslip::engine::{Condition, Effect};
use stickslip::measure::{TimeOrigin as ReadOrigin, read_measurement_set};

/// A scratch directory removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("stickslip-independent-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A small truth (2 loads × 2 frequencies) that integrates quickly.
fn small_truth(hidden: &[(Effect, u32, bool)]) -> (IndependentTruth, Vec<Condition>) {
    let (mut truth, conditions) = random_truth(21, hidden, &[4.0, 16.0], &[0.7, 1.1]).expect("a truth");
    truth.integration.warmup_s = 1.0;
    truth.integration.step_rate_hz = 100e3;
    (truth, conditions)
}

fn shape(duration_s: f64) -> RecordShape {
    RecordShape { duration_s, ..RecordShape::default() }
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    out.sort();
    out
}

/// The base's phase at `t = 0` from a `base_x` column: `U0 cos(Ω t + φ0)`.
fn base_phase(t: &[f64], base: &[f64], omega: f64) -> f64 {
    let (a, b) =
        t.iter().zip(base).fold((0.0, 0.0), |(a, b), (t, u)| (a + u * (omega * t).cos(), b + u * (omega * t).sin()));
    (-b).atan2(a)
}

/// The lag of `x`'s fundamental behind the base `U0 cos(Ω t + φ0)`, rad.
fn lag(x: &[f64], t: &[f64], omega: f64, phase0: f64) -> f64 {
    let (mut a, mut b) = (0.0, 0.0);
    for i in 0..t.len() {
        let theta = omega * t[i] + phase0;
        a += x[i] * theta.cos();
        b += x[i] * theta.sin();
    }
    b.atan2(a)
}

#[test]
fn a_default_origin_set_reads_back() {
    let scratch = Scratch::new("default");
    let (truth, conditions) = small_truth(&[(Effect::NormalForceHarmonics, 0, true), (Effect::Stiction, 1, false)]);
    let data = scratch.0.join("set").join("data");
    write_set(&data, &truth, &conditions, &shape(6.0), 4).expect("the set is written");
    let set = read_measurement_set(&data).expect("the reader takes the set");
    assert_eq!(set.runs.len(), 4);
    assert_eq!(set.rig.mass_kg, truth.rig.mass_kg);
    assert_eq!(set.rig.natural_frequency_hz, truth.rig.natural_frequency_hz);
    for (run, c) in set.runs.iter().zip(&conditions) {
        assert_eq!(run.excitation_frequency_hz, c.excitation_frequency_hz);
        assert_eq!(run.normal_force_n, c.normal_force_n);
        assert_eq!(run.excitation_amplitude_m, truth.rig.excitation_amplitude_m);
        assert_eq!(run.len(), 3600);
        assert_eq!(run.t_s[0], 0.0);
        assert!((run.sample_interval_s() - 1.0 / 600.0).abs() < 1e-12);
        assert!(run.v_m_per_s.is_some() && run.normal_force.is_some() && run.friction_force.is_some());
        assert_eq!(run.time_origin, ReadOrigin::Model);
    }
    // The files hold what the generator simulates, to the digits written.
    let again = simulate_run(&truth, conditions[1], 1, 0, &shape(6.0), 4).expect("a run");
    assert_eq!(set.runs[1].x_m, again.x);
    // The manifest is blind; the truth lies next to the data.
    let manifest = std::fs::read_to_string(data.join("manifest.json")).unwrap();
    assert!(!manifest.contains("stiction") && !manifest.contains("harmonic") && !manifest.contains("time_origin"));
    assert_eq!(truth_path(&data), scratch.0.join("set").join("truth.json"));
    let truth_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(truth_path(&data)).unwrap()).expect("truth.json is JSON");
    assert_eq!(truth_json["truth"]["effects"][0]["effect"], "normal_force_harmonics");
    assert_eq!(truth_json["truth"]["effects"][1]["effect"], "stiction");
    assert_eq!(truth_json["set_seed"], 4);
    assert!(!data.join("truth.json").exists());
}

#[test]
fn the_same_seed_writes_the_same_bytes() {
    let scratch = Scratch::new("determinism");
    let (truth, conditions) = small_truth(&[(Effect::ColouredFrictionNoise, 1, true)]);
    let (a, b, c) = (scratch.0.join("a/data"), scratch.0.join("b/data"), scratch.0.join("c/data"));
    write_set(&a, &truth, &conditions, &shape(4.0), 8).expect("written");
    write_set(&b, &truth, &conditions, &shape(4.0), 8).expect("written");
    write_set(&c, &truth, &conditions, &shape(4.0), 9).expect("written");
    assert_eq!(files(&a), files(&b));
    assert_eq!(std::fs::read(truth_path(&a)).unwrap(), std::fs::read(truth_path(&b)).unwrap());
    let (fa, fc) = (files(&a), files(&c));
    assert_eq!(fa[0].1, fc[0].1, "the manifest does not depend on the noise seed");
    assert_ne!(fa[1].1, fc[1].1, "another seed, other records");
}

#[test]
fn a_free_origin_set_says_so_and_carries_the_base() {
    let scratch = Scratch::new("free");
    let (truth, conditions) = small_truth(&[]);
    let u0 = truth.rig.excitation_amplitude_m;
    // Option C: free origin with the base's displacement.
    let free = RecordShape { duration_s: 6.0, runs_per_condition: 2, ..RecordShape::free_origin_with_base() };
    let data = scratch.0.join("c/data");
    write_set(&data, &truth, &conditions, &free, 4).expect("written");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(data.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["time_origin"], "free");
    let text = std::fs::read_to_string(data.join("run-00-0.csv")).unwrap();
    assert_eq!(text.lines().next().unwrap(), "t,x,v,normal_force,friction_force,base_x");
    // Runs start at different base phases; x keeps its lag behind the base.
    let model = simulate_run(&truth, conditions[0], 0, 0, &shape(6.0), 4).expect("a run");
    let omega = TAU * conditions[0].excitation_frequency_hz;
    let reference = lag(&model.x, &model.t, omega, 0.0);
    assert!(base_phase(&model.t, &model.base_x, omega).abs() < 0.01);
    let mut phases = Vec::new();
    for run in 0..2 {
        let r = simulate_run(&truth, conditions[0], 0, run, &free, 4).expect("a run");
        let amplitude = (2.0 * r.base_x.iter().map(|u| u * u).sum::<f64>() / r.t.len() as f64).sqrt();
        assert!((amplitude / u0 - 1.0).abs() < 0.01, "base amplitude {amplitude} vs {u0}");
        let phase0 = base_phase(&r.t, &r.base_x, omega);
        let lag_free = lag(&r.x, &r.t, omega, phase0);
        let d = (lag_free - reference + 3.0 * std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
        assert!(d.abs() < 0.05, "lag {lag_free} vs {reference} in the model frame");
        phases.push(phase0);
    }
    assert!((phases[0] - phases[1]).abs() > 1e-3, "two runs at the same base phase: {phases:?}");
    assert!(phases[0].abs() > 1e-3);
    // Option B: free origin, no base column.
    let data_b = scratch.0.join("b/data");
    let b = RecordShape { duration_s: 6.0, ..RecordShape::free_origin() };
    write_set(&data_b, &truth, &conditions, &b, 4).expect("written");
    let text = std::fs::read_to_string(data_b.join("run-00-0.csv")).unwrap();
    assert_eq!(text.lines().next().unwrap(), "t,x,v,normal_force,friction_force");
    let set_b = read_measurement_set(&data_b).expect("the reader takes option B");
    assert!(set_b.runs.iter().all(|r| r.time_origin == ReadOrigin::Free));
}

/// The reader takes option C's base column and moves each run's `t` into
/// the frame of `u = U0 cos(Ω t)`: the shifted times reproduce the written
/// base, whatever phase each record started at.
#[test]
fn a_free_origin_set_reads_back_with_its_origin_and_base() {
    let scratch = Scratch::new("free-read");
    let (truth, conditions) = small_truth(&[(Effect::NormalForceHarmonics, 1, true)]);
    let u0 = truth.rig.excitation_amplitude_m;
    let data = scratch.0.join("set/data");
    let shape = RecordShape { duration_s: 6.0, runs_per_condition: 2, ..RecordShape::free_origin_with_base() };
    write_set(&data, &truth, &conditions, &shape, 4).expect("written");
    let set = read_measurement_set(&data).expect("the reader takes the set");
    assert_eq!(set.runs.len(), 2 * conditions.len());
    let mut shifts = Vec::new();
    for (i, run) in set.runs.iter().enumerate() {
        let (condition, index) = (conditions[i / 2], i / 2);
        let ReadOrigin::BaseChannel { shift_s, amplitude_m } = run.time_origin else {
            panic!("run {i}: {:?}, not read through its base column", run.time_origin);
        };
        assert!((amplitude_m / u0 - 1.0).abs() < 0.01, "run {i}: base amplitude {amplitude_m} vs {u0}");
        let written = simulate_run(&truth, condition, index, (i % 2) as u32, &shape, 4).expect("a run");
        let omega = TAU * condition.excitation_frequency_hz;
        let worst =
            run.t_s.iter().zip(&written.base_x).map(|(t, b)| (u0 * (omega * t).cos() - b).abs()).fold(0.0, f64::max);
        assert!(worst < 12e-6, "run {i}: the shifted time misses the written base by {worst} m");
        shifts.push(shift_s);
    }
    assert!(shifts.windows(2).any(|w| (w[0] - w[1]).abs() > 1e-4), "every run at the same phase: {shifts:?}");
}

/// A displacement-only set writes `t`, `x` and its `base_x` alone; read
/// back, its runs carry no velocity, force or normal force, and the
/// diagnosis derives the velocity and the friction force for it (and its
/// replicates alike).
#[test]
fn a_displacement_only_set_carries_x_and_its_base_alone() {
    let scratch = Scratch::new("x-only");
    let (truth, conditions) = small_truth(&[(Effect::LoadDependentFriction, 1, true)]);
    let data = scratch.0.join("set/data");
    let shape = RecordShape {
        duration_s: 6.0,
        runs_per_condition: 1,
        displacement_only: true,
        ..RecordShape::free_origin_with_base()
    };
    write_set(&data, &truth, &conditions, &shape, 5).expect("written");
    let first = std::fs::read_dir(&data)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "csv"))
        .expect("a run file");
    let header = std::fs::read_to_string(&first).unwrap().lines().next().unwrap().to_string();
    assert_eq!(header, "t,x,base_x");
    let set = read_measurement_set(&data).expect("the reader takes the set");
    assert!(set.runs.iter().all(|r| r.v_m_per_s.is_none() && r.friction_force.is_none() && r.normal_force.is_none()));
    let derived = stickslip::diagnose::derived::DerivedChannels::for_runs(&set.runs);
    assert!(derived.v && derived.friction && derived.nominal_load && !derived.base_from_record, "{derived:?}");
}
