//! Synthetic measurement sets with a withheld effect, and the blind
//! benchmark of the diagnosis on them (`stickslip benchmark-diagnosis`).
//!
//! Each set: a random rig and friction law, 2 frequencies × 2 normal-force
//! levels (by default 45% and 90% of Den Hartog's no-stop threshold: from
//! continuous slip to the edge of stick-slip, where the noise stops the mass
//! now and then, as on the paper's rig at its higher loads; `--load-shares`
//! sets others), several runs per condition at 600 Hz with sensor noise on every
//! channel, and either no effect (a null set) or one effect in one of its
//! non-candidate forms (forms 1 and 2: the diagnosis only ever fits form 0,
//! so the real effect never matches a candidate's form exactly) at one of two
//! strengths. The diagnosis sees only the directory.

use std::f64::consts::TAU;
use std::path::Path;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::diagnose::measure::{RunEntry, write_manifest, write_run_file};
use crate::engine::analytic::DenHartog;
use crate::engine::effects::{
    ColourForm, ColouredFrictionNoise, DriftForm, FrictionHysteresis, HarmonicForm, HysteresisForm,
    LoadDependentFriction, LoadForm, NonGaussianForm, NonGaussianFriction, NormalForceDrift, NormalForceHarmonics,
    Stiction, StictionForm,
};
use crate::engine::{Condition, Effect, Engine, Job, Model, Point, Record, RunPlan};
use crate::error::Result;
use crate::io;

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
pub const LOAD_SHARES: [f64; 2] = [0.45, 0.9];

/// A random rig and friction law with `effect` (`None` for a null set) in
/// `form` (1 or 2, a non-candidate form) at `level`, at two frequencies ×
/// the normal forces that are `load_shares` of the no-stop threshold.
pub fn random_truth(
    seed: u64,
    effect: Option<Effect>,
    form: u32,
    level: u32,
    load_shares: &[f64],
) -> Result<(Model, Vec<Condition>)> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut m = Model::default();
    m.rig.mass_kg = uniform(&mut rng, 0.6, 1.6);
    m.rig.natural_frequency_hz = uniform(&mut rng, 8.0, 13.0);
    m.rig.damping_ratio = uniform(&mut rng, 0.002, 0.01);
    m.excitation.amplitude_m = uniform(&mut rng, 1.5e-3, 3e-3);
    m.friction.a = uniform(&mut rng, 0.15, 0.35);
    m.friction.b = uniform(&mut rng, 0.0, 0.12);
    m.friction.c = uniform(&mut rng, 5.0, 40.0);
    m.friction.d = 0.0;
    m.friction.sigma = uniform(&mut rng, 0.03, 0.07);
    m.normal_force.sigma = uniform(&mut rng, 0.15, 0.4);
    m.noise.interval_s = 1.0 / 600.0;
    let k = m.stiffness_n_per_m();
    let mu = m.friction.a + 0.5 * m.friction.b;
    let mut conditions = Vec::new();
    for eta in [0.65, 0.8] {
        let threshold = DenHartog::stop_threshold(eta);
        for &share in load_shares {
            let n0 = share * threshold * k * m.excitation.amplitude_m / mu;
            conditions
                .push(Condition { excitation_frequency_hz: eta * m.rig.natural_frequency_hz, normal_force_n: n0 });
        }
    }
    let strong = level == 1;
    let pick = |moderate: f64, strong_value: f64| if strong { strong_value } else { moderate };
    let mean_n0 = conditions.iter().map(|c| c.normal_force_n).sum::<f64>() / conditions.len() as f64;
    match effect {
        None => {}
        Some(Effect::NormalForceHarmonics) => {
            let a = pick(0.04, 0.09) * mean_n0;
            m.effects.normal_force_harmonics = Some(NormalForceHarmonics {
                form: if form == 1 { HarmonicForm::Bumps } else { HarmonicForm::Square },
                amplitudes_n: [a, 0.6 * a, 0.0, 0.0],
                phases_rad: [uniform(&mut rng, 0.0, TAU), uniform(&mut rng, 0.0, TAU), 0.0, 0.0],
                amplitudes_per_n0: [0.0; 4],
                shape: if form == 1 { 4.0 } else { 2.5 },
            });
        }
        Some(Effect::NonGaussianFriction) => {
            m.effects.non_gaussian_friction = Some(if form == 1 {
                NonGaussianFriction {
                    form: NonGaussianForm::Lognormal,
                    strength: pick(0.6, 1.0),
                    load_exponent: 0.5,
                    reference_force_n: mean_n0,
                }
            } else {
                NonGaussianFriction {
                    form: NonGaussianForm::TukeyH,
                    strength: pick(0.12, 0.2),
                    load_exponent: 0.0,
                    reference_force_n: mean_n0,
                }
            });
        }
        Some(Effect::FrictionHysteresis) => {
            m.effects.friction_hysteresis = Some(FrictionHysteresis {
                form: if form == 1 { HysteresisForm::Tanh } else { HysteresisForm::Rational },
                length_m: pick(1e-4, 3e-4),
                time_constant_s: 0.0,
            });
        }
        Some(Effect::ColouredFrictionNoise) => {
            m.effects.coloured_friction_noise = Some(ColouredFrictionNoise {
                form: if form == 1 { ColourForm::Hold } else { ColourForm::TwoScale },
                correlation_time_s: pick(8.0, 20.0) * m.noise.interval_s,
                coloured_share: 1.0,
            });
        }
        Some(Effect::Stiction) => {
            m.effects.stiction = Some(Stiction {
                form: if form == 1 { StictionForm::Noisy } else { StictionForm::Decaying },
                excess: pick(0.12, 0.25),
                release_length_m: 0.0,
                dwell_time_s: 0.0,
            });
        }
        Some(Effect::LoadDependentFriction) => {
            m.effects.load_dependent_friction = Some(if form == 1 {
                LoadDependentFriction { form: LoadForm::Power, strength: pick(0.3, 0.6), reference_force_n: mean_n0 }
            } else {
                LoadDependentFriction {
                    form: LoadForm::Saturating,
                    strength: pick(0.25, 0.5) * m.friction.a / mean_n0,
                    reference_force_n: mean_n0,
                }
            });
        }
        Some(Effect::NormalForceDrift) => {
            m.effects.normal_force_drift = Some(NormalForceDrift {
                form: if form == 1 { DriftForm::Saturating } else { DriftForm::Wander },
                rate_per_s: pick(0.006, 0.012),
            });
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

/// The benchmark's list of sets: every effect × `forms` × `levels`, then
/// `nulls` null sets. Returns (effect or None, form, level).
pub fn benchmark_plan(nulls: u32, forms: &[u32], levels: &[u32]) -> Vec<(Option<Effect>, u32, u32)> {
    let mut plan = Vec::new();
    for effect in Effect::ALL {
        for &form in forms {
            for &level in levels {
                plan.push((Some(effect), form, level));
            }
        }
    }
    plan.extend((0..nulls).map(|_| (None, 0, 0)));
    plan
}
