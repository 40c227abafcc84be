//! The power behind a `none`: could these records have shown each effect
//! family at the smallest size a user would care about?
//!
//! A `none` says that no family explained the baseline's gap beyond its
//! noise. That is only worth the records' power to show an effect: a
//! stiction leaves no trace where the block never rests long enough to
//! break away, nor a noise's colour in peaks averaged over hundreds of
//! periods. For each family, the baseline with a reference effect of that
//! family (its smallest size of interest, below) is simulated on the same
//! noise paths as the baseline. The difference of the two models'
//! simulated means, in the baseline's z-score scale, is what records
//! holding that effect would show; the expected rise of the baseline's
//! mean loss over the units the selection holds out (each z-score
//! shifted by that difference, averaged over a unit Gaussian of
//! measurement noise) is set against the noise threshold of the
//! selection's first gate, which asks whether the baseline's gap stands
//! above its noise at all. The family's power is the chance that the gap
//! clears that threshold, Φ((rise − threshold)/σ) with σ a third of the
//! threshold (the threshold is three standard deviations of the gap).
//!
//! The rise is an upper bound: a baseline calibrated to records that held
//! the effect would absorb part of it, and clearing the first gate is
//! needed, not enough, for a family to be named. A `none` is no surer than
//! the least of these powers.
//!
//! | family | reference effect (smallest size of interest) |
//! | --- | --- |
//! | normal-force harmonics | Fourier, at the excitation frequency, 2% of N0 |
//! | non-Gaussian friction | skew form, s = 0.7 (skewness of the friction noise about 0.5) |
//! | friction hysteresis | Dahl, friction turning over in a twentieth of the base amplitude U0 |
//! | coloured friction noise | AR(1), half the variance correlated over ten noise intervals |
//! | stiction | constant, breakaway a fifth above the law at rest, μ(0) = a + b |
//! | load-dependent friction | power law, μ 10% apart between the least and the greatest load |
//! | normal-force drift | linear, N moving 5% over the longest record, the nominal force its mean |
//!
//! A load dependence is not tested on a set of one load (there it is the
//! baseline's law), nor a drift without records; a family the baseline
//! already holds, or whose reference the model cannot run, is skipped.

use std::collections::HashMap;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

use crate::diagnose::data::Data;
use crate::diagnose::observable::Observable;
use crate::diagnose::score::{Scope, Score, score};
use crate::diagnose::search::cv::{NullLoss, loss};
use crate::diagnose::simulate::fits_per_task;
use crate::diagnose::{DiagnoseSettings, mean, records_window_s};
use crate::engine::effects::{
    ColourForm, ColouredFrictionNoise, DriftForm, FrictionHysteresis, HarmonicForm, HysteresisForm,
    LoadDependentFriction, LoadForm, NonGaussianForm, NonGaussianFriction, NormalForceDrift, NormalForceHarmonics,
    Stiction, StictionForm,
};
use crate::engine::reduce::wrap_angle;
use crate::engine::{Effect, Engine, Model};
use crate::error::Result;

/// How surely the records would show one family at its reference size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Power {
    pub effect: Effect,
    /// The reference effect, in words.
    pub reference: String,
    /// The expected rise of the baseline's out-of-sample mean loss on
    /// records holding the reference effect, –.
    pub rise: f64,
    /// The noise threshold that rise must clear, –.
    pub threshold: f64,
    /// The chance it clears it, –, in [0, 1].
    pub power: f64,
}

impl Power {
    /// Whether the records would more likely than not have shown the
    /// family at its reference size: where not, a `none` says nothing of it.
    pub fn could_show(&self) -> bool {
        self.power >= 0.5
    }
}

/// The least power over `powers` (1 where none was measured).
pub(crate) fn least(powers: &[Power]) -> f64 {
    powers.iter().map(|p| p.power).fold(1.0, f64::min)
}

/// Each family's power on the units `units` (every unit where empty), the
/// `baseline` scored as `baseline_scores` with `settings`.
pub(crate) fn powers(
    baseline: &Model,
    baseline_scores: &[Score],
    units: &[usize],
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    null: NullLoss,
) -> Result<Vec<Power>> {
    let references: Vec<(Effect, Model, String)> = Effect::ALL
        .iter()
        .filter(|&&e| !baseline.effects.has(e))
        .filter_map(|&e| reference(e, baseline, data).map(|(m, words)| (e, m, words)))
        .collect();
    let by_key: HashMap<(usize, Observable), &Score> =
        baseline_scores.iter().map(|s| ((s.unit, s.observable), s)).collect();
    let held = |u: usize| units.is_empty() || units.binary_search(&u).is_ok();
    let quantiles = gaussian_quantiles();
    let null_of_noise = mean(&quantiles.iter().map(|&q| loss(q)).collect::<Vec<_>>());
    references
        .into_par_iter()
        .with_min_len(fits_per_task(engine))
        .map(|(effect, model, reference)| {
            let scores = match score(engine, &model, data, settings, Scope::All) {
                Ok(s) => s,
                // A reference the engine cannot run is skipped.
                Err(e) if e.cannot_run() => return Ok(None),
                Err(e) => return Err(e),
            };
            let rises: Vec<f64> = scores
                .iter()
                .filter(|s| held(s.unit))
                .filter_map(|s| {
                    let b = by_key.get(&(s.unit, s.observable))?;
                    let shift = if s.observable.is_angle_deg() {
                        wrap_angle((s.simulated - b.simulated).to_radians()).to_degrees()
                    } else {
                        s.simulated - b.simulated
                    };
                    let z = shift / b.scale;
                    let expected = mean(&quantiles.iter().map(|&q| loss(z + q)).collect::<Vec<_>>());
                    Some(expected - null_of_noise)
                })
                .collect();
            if rises.is_empty() {
                return Ok(None);
            }
            let rise = mean(&rises);
            let threshold = null.noise(rises.len());
            let power = Normal::standard().cdf(3.0 * (rise - threshold) / threshold);
            Ok(Some(Power { effect, reference, rise, threshold, power }))
        })
        .collect::<Result<Vec<_>>>()
        .map(|p| p.into_iter().flatten().collect())
}

/// The midpoints of 64 bins of equal probability of a unit Gaussian.
fn gaussian_quantiles() -> Vec<f64> {
    let n = 64;
    (0..n).map(|i| Normal::standard().inverse_cdf((f64::from(i) + 0.5) / f64::from(n))).collect()
}

/// The baseline with `effect`'s reference (see the module), and its words;
/// `None` where the data cannot tell that family from the baseline.
fn reference(effect: Effect, baseline: &Model, data: &Data<'_>) -> Option<(Model, String)> {
    let mut m = baseline.clone();
    let loads = data.loads();
    let words = match effect {
        Effect::NormalForceHarmonics => {
            m.effects.normal_force_harmonics = Some(NormalForceHarmonics {
                form: HarmonicForm::Fourier,
                amplitudes_n: [0.0; 4],
                amplitudes_per_n0: [0.02, 0.0, 0.0, 0.0],
                phases_rad: [0.0; 4],
                shape: 2.0,
            });
            "a normal-force harmonic at the excitation frequency, 2% of N0".to_string()
        }
        Effect::NonGaussianFriction => {
            m.effects.non_gaussian_friction = Some(NonGaussianFriction {
                form: NonGaussianForm::Skew,
                strength: 0.7,
                cubic: 0.0,
                load_exponent: 0.0,
                reference_force_n: 10.0,
            });
            "a friction noise of skewness about 0.5 (skew form, s = 0.7)".to_string()
        }
        Effect::FrictionHysteresis => {
            let length_m = baseline.excitation.amplitude_m / 20.0;
            if length_m <= 0.0 {
                return None;
            }
            m.effects.friction_hysteresis =
                Some(FrictionHysteresis { form: HysteresisForm::Dahl, length_m, time_constant_s: 0.0, strength: 0.0 });
            format!("a Dahl memory turning the friction over {:.3} mm (a twentieth of U0)", length_m * 1e3)
        }
        Effect::ColouredFrictionNoise => {
            m.effects.coloured_friction_noise = Some(ColouredFrictionNoise {
                form: ColourForm::Ar1,
                correlation_time_s: 10.0 * baseline.noise.interval_s,
                coloured_share: 0.5,
            });
            "half the friction noise's variance correlated over ten noise intervals".to_string()
        }
        Effect::Stiction => {
            let excess = 0.2 * (baseline.friction.a + baseline.friction.b).max(baseline.friction.a);
            m.effects.stiction =
                Some(Stiction { form: StictionForm::Constant, excess, release_length_m: 0.0, dwell_time_s: 0.0 });
            format!("a breakaway friction 20% above the law at rest (Δμ = {excess:.4})")
        }
        Effect::LoadDependentFriction => {
            let (&lightest, &heaviest) = (loads.first()?, loads.last()?);
            if loads.len() < 2 || lightest <= 0.0 {
                return None;
            }
            m.effects.load_dependent_friction = Some(LoadDependentFriction {
                form: LoadForm::Power,
                strength: 1.1f64.ln() / (heaviest / lightest).ln(),
                curvature_per_n2: 0.0,
                reference_force_n: (lightest * heaviest).sqrt(),
            });
            format!("a friction 10% higher at {heaviest:.3} N than at {lightest:.3} N (power law)")
        }
        Effect::NormalForceDrift => {
            if data.longest_record_s <= 0.0 {
                return None;
            }
            m.effects.normal_force_drift = Some(NormalForceDrift {
                form: DriftForm::Linear,
                rate_per_s: 0.05 / data.longest_record_s,
                curvature_per_s2: 0.0,
                mean_over_s: Some(records_window_s(data)),
            });
            "a normal force moving 5% over the longest record".to_string()
        }
    };
    m.validate().ok()?;
    Some((m, words))
}
