//! Synthetic measurement sets with withheld effects, for the blind benchmark
//! of the diagnosis (`stickslip benchmark-diagnosis`).
//!
//! Each set: a random rig and a friction law drawn from the whole of the
//! paper's eq. 7 (a, b of either sign, c, d ≠ 0, σ_μ, σ_N), 2 frequencies × 3
//! normal-force levels (by default 40%, 65% and 90% of Den Hartog's no-stop
//! threshold: from continuous slip to the edge of stick-slip; the middle
//! level is the one the diagnosis holds out), runs at 600 Hz with sensor
//! noise on every channel, and no effect (a null set), one effect or two,
//! each in a **withheld form**: a form the candidate search never fits
//! (`WITHHELD_FORMS`; the candidates in [`crate::diagnose::candidates`] are
//! built from other forms, so no hidden effect matches a candidate exactly).
//! The diagnosis sees only the directory.

use std::f64::consts::TAU;
use std::path::Path;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::engine::analytic::DenHartog;
use crate::engine::effects::{
    ColourForm, ColouredFrictionNoise, DriftForm, FrictionHysteresis, HarmonicForm, HysteresisForm,
    LoadDependentFriction, LoadForm, NonGaussianForm, NonGaussianFriction, NormalForceDrift, NormalForceHarmonics,
    Stiction, StictionForm,
};
use crate::engine::{Condition, Effect, Engine, Job, Model, Point, Record, RunPlan};
use crate::error::{Error, Result};
use crate::io;
use crate::measure::{RunEntry, write_manifest, write_run_file};

/// How big the synthetic sets are.
#[derive(Clone, Copy, Debug)]
pub struct SetShape {
    pub runs_per_condition: u32,
    /// Record length, s.
    pub duration_s: f64,
    /// Sampling rate, Hz.
    pub sample_rate_hz: f64,
}

impl Default for SetShape {
    fn default() -> Self {
        SetShape { runs_per_condition: 2, duration_s: 20.0, sample_rate_hz: 600.0 }
    }
}

fn uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// Normal-force levels of the benchmark's sets, as shares of Den Hartog's
/// no-stop threshold (see the module's documentation).
pub const LOAD_SHARES: [f64; 3] = [0.4, 0.65, 0.9];

/// Excitation frequencies of the benchmark's sets, as ratios η of the
/// rig's natural frequency (–).
pub const FREQUENCY_RATIOS: [f64; 2] = [0.65, 0.8];

/// One effect hidden in a set: which, in which withheld form (1 or 2, see
/// [`WITHHELD_FORMS`]) and at which strength (0 moderate, 1 strong).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hidden {
    pub effect: Effect,
    pub form: u32,
    pub level: u32,
}

/// The forms the benchmark hides effects in (form 1, form 2) — never among
/// the forms the candidate search fits (Fourier harmonics; skew and Tukey-h
/// noise; exponential build-up and time lag; AR(1) colour; constant and
/// dwell stiction; linear and power load laws; linear drift).
pub const WITHHELD_FORMS: [(Effect, &str, &str); 7] = [
    (Effect::NormalForceHarmonics, "bumps", "square"),
    (Effect::NonGaussianFriction, "lognormal (growing with load)", "mixture"),
    (Effect::FrictionHysteresis, "tanh", "rational"),
    (Effect::ColouredFrictionNoise, "hold", "multi_scale"),
    (Effect::Stiction, "noisy", "decaying"),
    (Effect::LoadDependentFriction, "saturating", "exponential"),
    (Effect::NormalForceDrift, "saturating", "wander"),
];

/// A random rig and friction law from the whole eq. 7 family with the
/// `hidden` effects, at the frequencies `frequency_ratios` × the rig's
/// natural frequency, each × the normal forces that are `load_shares` of
/// the no-stop threshold there.
pub fn random_truth(
    seed: u64,
    hidden: &[Hidden],
    frequency_ratios: &[f64],
    load_shares: &[f64],
) -> Result<(Model, Vec<Condition>)> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut m = Model::default();
    m.rig.mass_kg = uniform(&mut rng, 0.6, 1.6);
    m.rig.natural_frequency_hz = uniform(&mut rng, 8.0, 13.0);
    m.rig.damping_ratio = uniform(&mut rng, 0.002, 0.01);
    m.excitation.amplitude_m = uniform(&mut rng, 1.5e-3, 3e-3);
    m.friction.a = uniform(&mut rng, 0.15, 0.35);
    m.friction.b = uniform(&mut rng, -0.04, 0.12);
    m.friction.c = 10f64.powf(uniform(&mut rng, 0.3, 1.6));
    m.friction.d = uniform(&mut rng, 0.0, 0.3);
    m.friction.sigma = uniform(&mut rng, 0.015, 0.07);
    m.normal_force.sigma = uniform(&mut rng, 0.1, 0.4);
    m.noise.interval_s = 1.0 / 600.0;
    let k = m.stiffness_n_per_m();
    let mu = m.friction.a + 0.5 * m.friction.b.max(0.0);
    let mut conditions = Vec::new();
    for &eta in frequency_ratios {
        let threshold = DenHartog::stop_threshold(eta);
        // Near η = 1/3, 1/5, … the block stops at every load, and shares
        // of the threshold name none.
        if threshold.is_nan() || threshold <= 1e-3 {
            return Err(Error::setting(
                "frequency ratio",
                format!(
                    "{eta}: Den Hartog's no-stop threshold there is {threshold:.1e} (the block stops at every \
                     load), so shares of it name no normal force; move the ratio away from 1/3 and 1/5"
                ),
            ));
        }
        for &share in load_shares {
            let n0 = share * threshold * k * m.excitation.amplitude_m / mu;
            conditions
                .push(Condition { excitation_frequency_hz: eta * m.rig.natural_frequency_hz, normal_force_n: n0 });
        }
    }
    let mean_n0 = conditions.iter().map(|c| c.normal_force_n).sum::<f64>() / conditions.len() as f64;
    for h in hidden {
        let pick = |moderate: f64, strong: f64| if h.level == 1 { strong } else { moderate };
        let first = h.form == 1;
        match h.effect {
            Effect::NormalForceHarmonics => {
                let a = pick(0.04, 0.08);
                m.effects.normal_force_harmonics = Some(NormalForceHarmonics {
                    form: if first { HarmonicForm::Bumps } else { HarmonicForm::Square },
                    amplitudes_n: [0.0; 4],
                    amplitudes_per_n0: [a, 0.6 * a, 0.0, 0.0],
                    phases_rad: [uniform(&mut rng, 0.0, TAU), uniform(&mut rng, 0.0, TAU), 0.0, 0.0],
                    shape: if first { 4.0 } else { 2.5 },
                });
            }
            Effect::NonGaussianFriction => {
                m.effects.non_gaussian_friction = Some(NonGaussianFriction {
                    form: if first { NonGaussianForm::Lognormal } else { NonGaussianForm::Mixture },
                    strength: if first { pick(0.6, 1.0) } else { pick(1.0, 2.0) },
                    cubic: 0.0,
                    load_exponent: if first { 0.5 } else { 0.0 },
                    reference_force_n: mean_n0,
                });
            }
            Effect::FrictionHysteresis => {
                m.effects.friction_hysteresis = Some(FrictionHysteresis {
                    form: if first { HysteresisForm::Tanh } else { HysteresisForm::Rational },
                    length_m: pick(1e-4, 3e-4),
                    time_constant_s: 0.0,
                    strength: 0.0,
                });
            }
            Effect::ColouredFrictionNoise => {
                m.effects.coloured_friction_noise = Some(ColouredFrictionNoise {
                    form: if first { ColourForm::Hold } else { ColourForm::MultiScale },
                    correlation_time_s: pick(8.0, 20.0) * m.noise.interval_s,
                    coloured_share: if first { 1.0 } else { 0.8 },
                });
            }
            Effect::Stiction => {
                m.effects.stiction = Some(Stiction {
                    form: if first { StictionForm::Noisy } else { StictionForm::Decaying },
                    excess: pick(0.12, 0.25),
                    release_length_m: 0.0,
                    dwell_time_s: 0.0,
                });
            }
            Effect::LoadDependentFriction => {
                m.effects.load_dependent_friction = Some(LoadDependentFriction {
                    form: if first { LoadForm::Saturating } else { LoadForm::Exponential },
                    strength: pick(0.25, 0.5) * m.friction.a / mean_n0,
                    curvature_per_n2: 0.0,
                    reference_force_n: mean_n0,
                });
            }
            Effect::NormalForceDrift => {
                m.effects.normal_force_drift = Some(NormalForceDrift {
                    form: if first { DriftForm::Saturating } else { DriftForm::Wander },
                    curvature_per_s2: 0.0,
                    rate_per_s: pick(0.006, 0.012),
                    mean_over_s: None,
                });
            }
        }
    }
    m.validate()?;
    Ok((m, conditions))
}

/// Writes a measurement set simulated from `truth` at `conditions` into
/// `dir`, with Gaussian sensor noise (x: 2 µm, v: 2 mm/s, N and F: 0.02 N).
pub fn write_set(dir: &Path, truth: &Model, conditions: &[Condition], shape: SetShape, seed: u64) -> Result<()> {
    io::create_dir(dir)?;
    // The truth is simulated by the f64 reference, whatever engine diagnoses it.
    let reference = Engine::cpu("the synthetic truth");
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5E75_0123);
    let mut entries = Vec::new();
    let dt = 1.0 / shape.sample_rate_hz;
    for (ci, &c) in conditions.iter().enumerate() {
        let points = [Point::steady(truth, c)];
        let job = Job {
            model: truth,
            points: &points,
            realisations: shape.runs_per_condition,
            first_realisation: ci as u32 * 100,
            seed,
            plan: RunPlan { warmup_cycles: 60, measured_cycles: 0 },
            record: Record::Sums,
        };
        for (r, mut samples) in reference.records(&job, dt, shape.duration_s)?.into_iter().enumerate() {
            let gauss = |rng: &mut StdRng| {
                let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random::<f64>());
                (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
            };
            for s in &mut samples {
                s.x_m += 2e-6 * gauss(&mut rng);
                s.v_m_per_s += 2e-3 * gauss(&mut rng);
                s.normal_force_n += 0.02 * gauss(&mut rng);
                s.friction_force_n += 0.02 * gauss(&mut rng);
            }
            let file = format!("run-{ci}-{r}.csv");
            write_run_file(&dir.join(&file), &samples)?;
            entries.push(RunEntry {
                file,
                excitation_frequency_hz: c.excitation_frequency_hz,
                excitation_amplitude_m: truth.excitation.amplitude_m,
                normal_force_n: c.normal_force_n,
            });
        }
    }
    write_manifest(dir, "synthetic measurement set (stickslip benchmark-diagnosis)", truth, &entries)?;
    Ok(())
}

/// One set of the benchmark: what it hides and how it is measured.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedSet {
    /// The hidden effects, leading (strongest) first; empty for a null set.
    pub hidden: Vec<Hidden>,
    /// Only a summary table with phase columns (no records, no amplitudes).
    pub phase_only: bool,
}

/// The pairs of the two-effect sets: effects the seed paper's rig shows
/// together, the first the stronger.
pub const PAIRS: [(Effect, Effect); 6] = [
    (Effect::NormalForceHarmonics, Effect::NonGaussianFriction),
    (Effect::LoadDependentFriction, Effect::ColouredFrictionNoise),
    (Effect::FrictionHysteresis, Effect::NormalForceHarmonics),
    (Effect::Stiction, Effect::NormalForceDrift),
    (Effect::ColouredFrictionNoise, Effect::FrictionHysteresis),
    (Effect::NonGaussianFriction, Effect::LoadDependentFriction),
];

/// The benchmark's list of sets: every effect × `forms` × `levels`, then
/// `pairs` two-effect sets (the leading effect strong, the second moderate,
/// forms alternating), then `phase_only` phase-only summary sets (null and
/// load-dependent friction alternately), then `nulls` null sets.
pub fn benchmark_plan(nulls: u32, forms: &[u32], levels: &[u32], pairs: u32, phase_only: u32) -> Vec<PlannedSet> {
    let mut plan = Vec::new();
    for effect in Effect::ALL {
        for &form in forms {
            for &level in levels {
                plan.push(PlannedSet { hidden: vec![Hidden { effect, form, level }], phase_only: false });
            }
        }
    }
    for i in 0..pairs as usize {
        let (a, b) = PAIRS[i % PAIRS.len()];
        let form = 1 + (i as u32 / PAIRS.len() as u32) % 2;
        plan.push(PlannedSet {
            hidden: vec![Hidden { effect: a, form, level: 1 }, Hidden { effect: b, form: 3 - form, level: 0 }],
            phase_only: false,
        });
    }
    for i in 0..phase_only {
        let hidden = if i % 2 == 1 {
            vec![Hidden { effect: Effect::LoadDependentFriction, form: 1 + (i / 2) % 2, level: 1 }]
        } else {
            Vec::new()
        };
        plan.push(PlannedSet { hidden, phase_only: true });
    }
    plan.extend((0..nulls).map(|_| PlannedSet { hidden: Vec::new(), phase_only: false }));
    plan
}

/// A set of `truth`'s records at 6 Hz/10 N and 7 Hz/14 N (two runs of
/// 10 s each at 600 Hz, noise from `seed`) with only `t` and `x` kept: the
/// displacement-only records the derived-channel tests read.
#[cfg(test)]
pub(crate) fn displacement_only_set(truth: &Model, seed: u64) -> crate::measure::MeasurementSet {
    let at = |f: f64, n: f64| Condition { excitation_frequency_hz: f, normal_force_n: n };
    let shape = SetShape { runs_per_condition: 2, duration_s: 10.0, sample_rate_hz: 600.0 };
    displacement_only_set_at(truth, &[at(6.0, 10.0), at(7.0, 14.0)], shape, seed)
}

/// A set of `truth`'s records at `conditions` in `shape` (noise from
/// `seed`), every channel kept.
#[cfg(test)]
pub(crate) fn set_at(
    truth: &Model,
    conditions: &[Condition],
    shape: SetShape,
    seed: u64,
) -> crate::measure::MeasurementSet {
    // One directory per call: tests run side by side in one process, and
    // two that asked for the same seed would otherwise share (and remove)
    // each other's.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("stickslip-set-at-{}-{seed}-{call}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    write_set(&dir, truth, conditions, shape, seed).expect("set");
    let set = crate::measure::read_measurement_set(&dir).expect("read");
    let _ = std::fs::remove_dir_all(&dir);
    set
}

/// A set of `truth`'s records at `conditions` in `shape` (noise from
/// `seed`) with only `t` and `x` kept.
#[cfg(test)]
pub(crate) fn displacement_only_set_at(
    truth: &Model,
    conditions: &[Condition],
    shape: SetShape,
    seed: u64,
) -> crate::measure::MeasurementSet {
    let mut set = set_at(truth, conditions, shape, seed);
    for run in &mut set.runs {
        (run.v_m_per_s, run.friction_force, run.normal_force) = (None, None, None);
    }
    set
}
