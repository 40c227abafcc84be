//! The candidates: for each effect, how its candidate form is set from a
//! strength (and a second parameter where it has one), which strengths are
//! searched, and how its parameters are reported. Search grids are centred
//! on what the measured data suggest where they can.

use std::collections::BTreeMap;

use crate::diagnose::data::Data;
use crate::diagnose::mean;
use crate::diagnose::observable::Observable;
use crate::diagnose::score::Score;
use crate::engine::effects::{
    ColourForm, ColouredFrictionNoise, DriftForm, FrictionHysteresis, HarmonicForm, HysteresisForm,
    LoadDependentFriction, LoadForm, NonGaussianForm, NonGaussianFriction, NormalForceDrift, NormalForceHarmonics,
    Stiction, StictionForm,
};
use crate::engine::{Effect, Model};

/// Sets the candidate's effect on a model from (strength, second parameter).
pub(crate) type Apply = Box<dyn Fn(&Model, f64, f64) -> Model + Sync>;
/// The candidate's parameters by name, for the report.
pub(crate) type Describe = Box<dyn Fn(&Model) -> BTreeMap<String, f64> + Sync>;

/// A candidate: how to set its effect from one strength value.
pub(crate) struct CandidateSpec {
    pub(crate) effect: Effect,
    /// Strength values to try.
    pub(crate) grid: Vec<f64>,
    /// Values of a second parameter, each tried with every strength
    /// (`[0.0]` where the candidate has one parameter).
    pub(crate) second: Vec<f64>,
    pub(crate) apply: Apply,
    pub(crate) describe: Describe,
}

/// Mean of an observable over the fitting units that have it.
fn measured_mean(data: &Data<'_>, observable: Observable) -> Option<f64> {
    let v: Vec<f64> = data
        .units
        .iter()
        .zip(&data.measured)
        .filter(|(u, _)| !u.heldout)
        .filter_map(|(_, m)| m.get(&observable).copied())
        .collect();
    (!v.is_empty()).then(|| mean(&v))
}

fn log_grid(centre: f64, factors: &[f64]) -> Vec<f64> {
    factors.iter().map(|f| centre * f).collect()
}

/// One candidate per effect, in [`Effect::ALL`]'s order.
pub(crate) fn candidate_specs(data: &Data<'_>, baseline: &Model, baseline_scores: &[Score]) -> Vec<CandidateSpec> {
    let dt = data.sample_interval_s;
    let mean_n0 =
        mean(&data.units.iter().map(|u| data.simulated_condition(u, baseline, 0).normal_force_n).collect::<Vec<_>>());
    let sim_of = |observable: Observable| {
        let v: Vec<f64> =
            baseline_scores.iter().filter(|s| !s.heldout && s.observable == observable).map(|s| s.simulated).collect();
        (!v.is_empty()).then(|| mean(&v))
    };
    // Harmonic amplitudes in excess of the baseline's noise floor.
    let harmonic_excess: Vec<f64> = (1..=4)
        .map(|k| {
            let observable = Observable::normal_force_harmonic(k);
            match (measured_mean(data, observable), sim_of(observable)) {
                (Some(m), Some(s)) => (m * m - s * s).max(0.0).sqrt(),
                _ => 0.0,
            }
        })
        .collect();
    let has_n = harmonic_excess.iter().any(|a| *a > 0.0);
    let skew = measured_mean(data, Observable::FrictionResidualSkewness).unwrap_or(0.5);
    let drift = measured_mean(data, Observable::NormalForceDriftPerS)
        .or_else(|| measured_mean(data, Observable::PeakTrendPerS).map(|t| -t))
        .unwrap_or(0.002);
    // Where friction is measured, the slope of mean μ against N0 across the
    // fitting conditions centres the load-dependence search.
    let points: Vec<(f64, f64)> = data
        .units
        .iter()
        .zip(&data.measured)
        .filter(|(u, _)| !u.heldout)
        .filter_map(|(u, m)| {
            m.get(&Observable::FrictionMuMean).map(|mu| (data.simulated_condition(u, baseline, 0).normal_force_n, *mu))
        })
        .collect();
    let slope_estimate = if points.len() >= 2 {
        let (mx, my) = (
            mean(&points.iter().map(|p| p.0).collect::<Vec<_>>()),
            mean(&points.iter().map(|p| p.1).collect::<Vec<_>>()),
        );
        let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        (sxx > 0.0).then(|| sxy / sxx).filter(|s| s.abs() > 1e-5)
    } else {
        None
    };
    Effect::ALL
        .into_iter()
        .map(|effect| match effect {
            Effect::NormalForceHarmonics => {
                let excess = harmonic_excess.clone();
                CandidateSpec {
                    effect,
                    grid: if has_n { vec![0.5, 0.75, 1.0, 1.25] } else { vec![0.1, 0.3, 1.0, 2.0] },
                    second: vec![0.0],
                    apply: Box::new(move |m, s, _| {
                        let mut m = m.clone();
                        let amps = if has_n {
                            [excess[0] * s, excess[1] * s, excess[2] * s, excess[3] * s]
                        } else {
                            [s, 0.0, 0.0, 0.0]
                        };
                        m.effects.normal_force_harmonics = Some(NormalForceHarmonics {
                            form: HarmonicForm::Fourier,
                            amplitudes_n: amps,
                            phases_rad: [0.0; 4],
                            amplitudes_per_n0: [0.0; 4],
                            shape: 2.0,
                        });
                        m
                    }),
                    describe: Box::new(|m| {
                        let h = m.effects.normal_force_harmonics.as_ref().expect("set by apply");
                        (0..4).map(|k| (format!("amplitude_{}x_n", k + 1), h.amplitudes_n[k])).collect()
                    }),
                }
            }
            Effect::NonGaussianFriction => {
                let sign = if skew < 0.0 { -1.0 } else { 1.0 };
                CandidateSpec {
                    effect,
                    grid: [0.15, 0.3, 0.5, 0.8, 1.2].iter().map(|s| s * sign).collect(),
                    second: vec![0.0],
                    apply: Box::new(|m, s, _| {
                        let mut m = m.clone();
                        m.effects.non_gaussian_friction = Some(NonGaussianFriction {
                            form: NonGaussianForm::Skew,
                            strength: s,
                            load_exponent: 0.0,
                            reference_force_n: 10.0,
                        });
                        m
                    }),
                    describe: Box::new(|m| {
                        let g = m.effects.non_gaussian_friction.as_ref().expect("set by apply");
                        BTreeMap::from([("skew_strength".to_string(), g.strength)])
                    }),
                }
            }
            Effect::FrictionHysteresis => CandidateSpec {
                effect,
                grid: vec![2e-5, 5e-5, 1e-4, 2e-4, 4e-4, 8e-4],
                second: vec![0.0],
                apply: Box::new(|m, s, _| {
                    let mut m = m.clone();
                    m.effects.friction_hysteresis = Some(FrictionHysteresis {
                        form: HysteresisForm::Exponential,
                        length_m: s,
                        time_constant_s: 0.0,
                    });
                    m
                }),
                describe: Box::new(|m| {
                    let h = m.effects.friction_hysteresis.as_ref().expect("set by apply");
                    BTreeMap::from([("length_m".to_string(), h.length_m)])
                }),
            },
            Effect::ColouredFrictionNoise => CandidateSpec {
                effect,
                grid: log_grid(dt, &[2.0, 4.0, 8.0, 16.0, 32.0]),
                second: vec![0.0],
                apply: Box::new(|m, s, _| {
                    let mut m = m.clone();
                    m.effects.coloured_friction_noise = Some(ColouredFrictionNoise {
                        form: ColourForm::Ar1,
                        correlation_time_s: s,
                        coloured_share: 1.0,
                    });
                    m
                }),
                describe: Box::new(|m| {
                    let c = m.effects.coloured_friction_noise.as_ref().expect("set by apply");
                    BTreeMap::from([("correlation_time_s".to_string(), c.correlation_time_s)])
                }),
            },
            Effect::Stiction => CandidateSpec {
                effect,
                grid: vec![0.02, 0.05, 0.1, 0.2, 0.35],
                // Static friction that is released at once, or over the first
                // 0.1 or 0.3 mm of slip.
                second: vec![0.0, 1e-4, 3e-4],
                apply: Box::new(|m, s, release| {
                    let mut m = m.clone();
                    m.effects.stiction = Some(Stiction {
                        form: StictionForm::Constant,
                        excess: s,
                        release_length_m: release,
                        dwell_time_s: 0.0,
                    });
                    m
                }),
                describe: Box::new(|m| {
                    let s = m.effects.stiction.as_ref().expect("set by apply");
                    BTreeMap::from([
                        ("excess".to_string(), s.excess),
                        ("release_length_m".to_string(), s.release_length_m),
                    ])
                }),
            },
            Effect::LoadDependentFriction => CandidateSpec {
                effect,
                grid: match slope_estimate {
                    Some(s) => log_grid(s, &[0.5, 0.75, 1.0, 1.25, 1.5]),
                    None => vec![-0.04, -0.02, -0.01, -0.004, 0.004, 0.01, 0.02, 0.04],
                },
                second: vec![0.0],
                apply: Box::new(move |m, s, _| {
                    let mut m = m.clone();
                    m.effects.load_dependent_friction = Some(LoadDependentFriction {
                        form: LoadForm::Linear,
                        strength: s,
                        reference_force_n: mean_n0.max(1e-3),
                    });
                    m
                }),
                describe: Box::new(|m| {
                    let l = m.effects.load_dependent_friction.as_ref().expect("set by apply");
                    BTreeMap::from([
                        ("slope_per_n".to_string(), l.strength),
                        ("reference_force_n".to_string(), l.reference_force_n),
                    ])
                }),
            },
            Effect::NormalForceDrift => CandidateSpec {
                effect,
                grid: log_grid(if drift == 0.0 { 0.002 } else { drift }, &[0.5, 0.75, 1.0, 1.5]),
                second: vec![0.0],
                apply: Box::new(|m, s, _| {
                    let mut m = m.clone();
                    m.effects.normal_force_drift = Some(NormalForceDrift { form: DriftForm::Linear, rate_per_s: s });
                    m
                }),
                describe: Box::new(|m| {
                    let d = m.effects.normal_force_drift.as_ref().expect("set by apply");
                    BTreeMap::from([("rate_per_s".to_string(), d.rate_per_s)])
                }),
            },
        })
        .collect()
}
