//! The candidates: for each effect, the family of forms the search tries
//! (the ones the literature uses, each parameterised so that it carries over
//! to loads the fit did not see), where each search starts (from what the
//! measured data suggest), and the effect's signature — the observables its
//! presence moves whatever its exact form.
//!
//! | effect | forms searched | started from | signature |
//! | --- | --- | --- | --- |
//! | normal-force harmonics | Fourier, amplitudes a share of N0 or in N, phases fitted (turned by a common shift for records with a free time origin); a load that follows the block's position, N0 (1 + α x/U0 + β (x/U0)²) | the measured N's harmonics; the regression of N on x (where no record measures N: of the derived friction on x, and the first harmonic at 2% of N0, its phase searched) | N's harmonics and residual variance |
//! | non-Gaussian friction | skew; skew and tails set apart (Fleishman's power polynomial); each with a load exponent | the signs of the residual's skew and of its tails' excess | residual quantile skewness and tail weight |
//! | hysteresis | build-up over a displacement, friction turning over one through a reversal (Dahl), lag in time (Hess & Soom), relaxation over a slip distance (rate-and-state slip law, Ruina), contact ageing (rate-and-state ageing law, Dieterich) | the sign of the branch asymmetry; the slipping speeds | branch asymmetry, low-speed μ, residual memory |
//! | coloured noise | AR(1) with a coloured share (Lorentzian plus white), two corners | the residual autocorrelation | residual autocorrelation, peak variance |
//! | stiction | constant (released over a slip length), ageing with dwell time | the breakaway excess (the measured one, released, where the baseline's law absorbed it) | breakaway excess, stick fraction |
//! | load-dependent friction | linear (bent where three or more loads are fitted), power law of the level, the whole law scaled by a power of N0, two-term adhesion F = μN + A | the slope of μ (or of the peaks, or of the phases) against N0 | mean μ, mean peak and phase across loads |
//! | normal-force drift | linear, quadratic, a random walk | the measured N's drift and curvature (or the peaks' trend), the spread of the records' slopes | N's drift, curvature and wander, the peaks' trend |
//!
//! The library's other forms (bumps and square harmonics, Tukey h, lognormal and
//! mixture noise, tanh and rational build-ups, held and multi-scale colour,
//! noisy and decaying stiction, saturating and exponential load
//! dependence, saturating and wandering drift) are never searched: the
//! engine benchmark hides effects in those, and the independent benchmark in
//! forms of its own, so no candidate matches a hidden effect exactly.

mod harmonics;
mod load;
mod memory;
mod noise;

pub(crate) use load::bent;

use std::collections::BTreeMap;

use crate::diagnose::data::{Data, levels, same_level};
use crate::diagnose::features::least_squares;
use crate::diagnose::law::FrictionLaw;
use crate::diagnose::mean;
use crate::diagnose::observable::Observable;
use crate::diagnose::score::Score;
use crate::engine::effects::{
    ColourForm, ColouredFrictionNoise, DriftForm, FrictionHysteresis, HarmonicForm, HysteresisForm,
    LoadDependentFriction, LoadForm, NonGaussianForm, NonGaussianFriction, NormalForceDrift, NormalForceHarmonics,
    Stiction, StictionForm,
};
use crate::engine::reduce::{circular_mean_var, wrap_angle};
use crate::engine::{Effect, Model};

/// Sets a variant's effect on a model from its parameter values.
pub(crate) type Apply = Box<dyn Fn(&Model, &[f64]) -> Model + Sync>;

/// One searched parameter: a start, a scale on which it is stepped, and the
/// range it must stay in.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Param {
    /// Its name in the report (with its unit).
    pub(crate) name: &'static str,
    /// Where the search starts.
    pub(crate) start: f64,
    /// Stepped multiplicatively (true: the value's sign is kept) or additively.
    pub(crate) log: bool,
    /// The first step: a factor (log) or an increment.
    pub(crate) step: f64,
    /// Bounds.
    pub(crate) lo: f64,
    pub(crate) hi: f64,
}

impl Param {
    pub(crate) fn log(name: &'static str, start: f64, step: f64, lo: f64, hi: f64) -> Param {
        Param { name, start, log: true, step, lo, hi }
    }

    fn linear(name: &'static str, start: f64, step: f64, lo: f64, hi: f64) -> Param {
        Param { name, start, log: false, step, lo, hi }
    }

    /// `value` moved `k` steps (k may be fractional), within bounds.
    pub(crate) fn moved(&self, value: f64, k: f64) -> f64 {
        let v = if self.log { value * self.step.powf(k) } else { value + self.step * k };
        v.clamp(self.lo, self.hi)
    }
}

/// A fitted parameter's unit and meaning, by its name.
pub fn parameter_meaning(name: &str) -> &'static str {
    match name {
        "scale" => "–, a factor on the harmonics' amplitudes (1 = as estimated from the data)",
        "strength" => "–, the strength of the effect's shape (skew, tail weight, or the ageing law's B; 0 = off)",
        "cubic" => {
            "–, the polynomial noise's cubic coefficient d (tails heavier than a Gaussian's above 0, lighter below)"
        }
        "load_exponent" => "–, how the strength grows with load: × (N0 / reference)^exponent",
        "length_m" => "m, the slip distance over which friction builds up or relaxes",
        "time_constant_s" => "s, the memory time of friction",
        "correlation_time_s" => "s, how long the friction noise stays correlated",
        "coloured_share" => "–, the share (0–1) of the noise variance that is correlated",
        "excess" => "–, how much the static friction coefficient exceeds the sliding one",
        "release_length_m" => "m, the slip over which the static excess fades",
        "dwell_time_s" => "s, how long the block must stick for the static excess to grow",
        "strength_per_n" => "1/N, the change of the friction coefficient per newton of normal force",
        "exponent" => "–, the power of the load dependence",
        "rate_per_s" => "1/s, the relative change of the normal force per second",
        "curvature_per_s2" => "1/s², the relative bend of the normal force's drift",
        "adhesion_n" => "N, the adhesion force added to μN (F = μN + A)",
        "bend" => "–, how the slope of friction against load bends (× (1 + bend (N0 − Nref)/Nref))",
        "phase_shift_rad" => "rad, a common phase turn of the harmonics (records without an absolute phase)",
        "arc_added_per_n0" => "–, added to the arc term β of a load that follows the block (share of N0 per U0²)",
        "share_of_n0" => "–, the first harmonic's amplitude as a share of N0",
        "phase_rad" => "rad, the first harmonic's phase against the base's motion",
        "slow_share" => "–, the share (0–1) of the noise variance in its slow part",
        _ => "",
    }
}

/// A form the search fits, by name: the model file's form of the effect,
/// with the parameterisation where one form is searched in two.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SearchedForm {
    /// Normal-force harmonics, `fourier`, amplitudes a share of N0.
    FourierShareOfN0,
    /// Normal-force harmonics, `fourier`, amplitudes in N.
    FourierNewtons,
    /// A normal force that follows the block's position.
    Position,
    /// Skewed friction noise.
    Skew,
    /// Friction noise with its skew and tails set apart (Fleishman's polynomial).
    Polynomial,
    /// Friction that builds up over a displacement after each slip start.
    BuildUp,
    /// Friction continuous through a reversal, turning over a displacement (Dahl).
    Dahl,
    /// Dahl's friction with a stick held by the contact's elasticity (bristles).
    Bristle,
    /// Friction that lags the law in time.
    Lag,
    /// Rate-and-state slip law: relaxation over a slip distance.
    Slip,
    /// Rate-and-state ageing law: contact ageing.
    Ageing,
    /// AR(1) coloured noise with a white part.
    Ar1,
    /// Coloured noise with two corners.
    FastSlow,
    /// Stiction of a constant excess.
    Constant,
    /// Stiction that ages with the dwell time.
    Dwell,
    /// Friction linear in the load.
    Linear,
    /// Friction linear in the load, bent.
    Quadratic,
    /// The friction level a power of the load.
    Power,
    /// Adhesion, F = μN + A.
    Adhesion,
    /// The whole law scaled by a power of the load.
    Scaled,
    /// A linear drift of the normal force.
    DriftLinear,
    /// A quadratic drift of the normal force.
    DriftQuadratic,
    /// A normal force that wanders as a random walk, its own in every run.
    DriftRandomWalk,
}

impl SearchedForm {
    /// The form as the model file and the report name it.
    pub fn name(self) -> &'static str {
        match self {
            SearchedForm::FourierShareOfN0 => "fourier (amplitudes a share of N0)",
            SearchedForm::FourierNewtons => "fourier (amplitudes in N)",
            SearchedForm::Position => "position",
            SearchedForm::Skew => "skew",
            SearchedForm::Polynomial => "polynomial",
            SearchedForm::BuildUp => "exponential",
            SearchedForm::Dahl => "dahl",
            SearchedForm::Bristle => "bristle",
            SearchedForm::Lag => "lag",
            SearchedForm::Slip => "slip",
            SearchedForm::Ageing => "ageing",
            SearchedForm::Ar1 => "ar1",
            SearchedForm::FastSlow => "fast_slow",
            SearchedForm::Constant => "constant",
            SearchedForm::Dwell => "dwell",
            SearchedForm::Linear | SearchedForm::DriftLinear => "linear",
            SearchedForm::Quadratic | SearchedForm::DriftQuadratic => "quadratic",
            SearchedForm::Power => "power",
            SearchedForm::Adhesion => "adhesion",
            SearchedForm::Scaled => "scaled",
            SearchedForm::DriftRandomWalk => "random_walk",
        }
    }
}

impl std::fmt::Display for SearchedForm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One form of an effect as the search fits it.
pub(crate) struct Variant {
    pub(crate) effect: Effect,
    /// The form.
    pub(crate) form: SearchedForm,
    pub(crate) params: Vec<Param>,
    pub(crate) apply: Apply,
}

impl Variant {
    /// The parameters by name, for the report.
    pub(crate) fn describe(&self, values: &[f64]) -> BTreeMap<String, f64> {
        self.params.iter().zip(values).map(|(p, v)| (p.name.to_string(), *v)).collect()
    }

    /// The start of every parameter.
    pub(crate) fn start(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.start).collect()
    }
}

/// The observables an effect moves whatever its exact form (its signature).
pub(crate) fn signature(effect: Effect) -> &'static [Observable] {
    match effect {
        Effect::NormalForceHarmonics => &[
            Observable::NormalForceHarmonic1N,
            Observable::NormalForceHarmonic2N,
            Observable::NormalForceHarmonic3N,
            Observable::NormalForceHarmonic4N,
            Observable::NormalForceResidualVarN2,
        ],
        Effect::NonGaussianFriction => &[Observable::FrictionResidualSkewness, Observable::FrictionResidualTailWeight],
        Effect::FrictionHysteresis => &[
            Observable::FrictionHysteresis,
            Observable::FrictionLowSpeedMuMean,
            Observable::FrictionResidualAutocorrLag1,
        ],
        Effect::ColouredFrictionNoise => &[
            Observable::FrictionResidualAutocorrLag1,
            Observable::FrictionResidualAutocorrLag10,
            Observable::PeakVarM2,
        ],
        Effect::Stiction => {
            &[Observable::FrictionStictionExcess, Observable::FrictionBreakawayMean, Observable::StickFraction]
        }
        Effect::LoadDependentFriction => &[Observable::FrictionMuMean, Observable::PeakMeanM, Observable::PhaseMeanDeg],
        Effect::NormalForceDrift => &[
            Observable::NormalForceDriftPerS,
            Observable::FrictionTrendPerS,
            Observable::NormalForceCurvaturePerS2,
            Observable::NormalForceWander,
            Observable::PeakTrendPerS,
        ],
    }
}

/// What the data and the current model's scores say about where each
/// search should start.
pub(crate) struct Context<'a> {
    data: &'a Data<'a>,
    /// The model the candidates are added to.
    model: &'a Model,
    scores: &'a [Score],
    /// Periods each simulated record is preceded by (the drift's clock
    /// starts there).
    warmup_cycles: u32,
    /// The `position` form's start (α, β, –) read from a friction derived
    /// from the motion and corrected for that reading's bias on the
    /// model's own records ([`Context::with_position_start`]); `None`: the
    /// reading as it is.
    position_start: Option<(f64, f64)>,
}

impl<'a> Context<'a> {
    pub(crate) fn new(data: &'a Data<'a>, model: &'a Model, scores: &'a [Score], warmup_cycles: u32) -> Context<'a> {
        Context { data, model, scores, warmup_cycles, position_start: None }
    }

    /// Mean over the fitting units of the time from a simulated run's start
    /// to the middle of its record, s.
    fn mean_record_middle_s(&self) -> f64 {
        let middles: Vec<f64> = self
            .data
            .units
            .iter()
            .filter(|u| !u.heldout)
            .map(|u| {
                let f = u.condition.excitation_frequency_hz;
                let record: Vec<f64> = u.runs.iter().map(|&r| self.data.set.runs[r].duration_s()).collect();
                f64::from(self.warmup_cycles) / f + 0.5 * if record.is_empty() { 0.0 } else { mean(&record) }
            })
            .collect();
        if middles.is_empty() { 0.0 } else { mean(&middles) }
    }

    /// Mean over the fitting units of `value(mean record length, s; number
    /// of records; the unit's measured observables, means over its
    /// records)`, where it gives one.
    fn mean_over_fitting_runs(
        &self,
        value: impl Fn(f64, usize, &BTreeMap<Observable, f64>) -> Option<f64>,
    ) -> Option<f64> {
        let v: Vec<f64> = self
            .data
            .units
            .iter()
            .zip(&self.data.measured)
            .filter(|(u, _)| !u.heldout && !u.runs.is_empty())
            .filter_map(|(u, m)| {
                let durations: Vec<f64> = u.runs.iter().map(|&r| self.data.set.runs[r].duration_s()).collect();
                value(mean(&durations), durations.len(), m)
            })
            .collect();
        (!v.is_empty()).then(|| mean(&v))
    }

    /// Mean over the fitting units of a measured observable.
    fn measured(&self, o: Observable) -> Option<f64> {
        let v: Vec<f64> = self
            .data
            .units
            .iter()
            .zip(&self.data.measured)
            .filter(|(u, _)| !u.heldout)
            .filter_map(|(_, m)| m.get(&o).copied())
            .collect();
        (!v.is_empty()).then(|| mean(&v))
    }

    /// Mean over the fitting units of the current model's simulated value.
    fn simulated(&self, o: Observable) -> Option<f64> {
        let v: Vec<f64> = self.scores.iter().filter(|s| !s.heldout && s.observable == o).map(|s| s.simulated).collect();
        (!v.is_empty()).then(|| mean(&v))
    }

    /// Measured minus simulated, over the fitting units.
    fn excess(&self, o: Observable) -> Option<f64> {
        Some(self.measured(o)? - self.simulated(o)?)
    }

    /// Whether the records carry friction (v, F and N) or N.
    fn has(&self, o: Observable) -> bool {
        self.data.measured.iter().any(|m| m.contains_key(&o))
    }

    /// The fitting units' (N0 as simulated, measured, simulated) values of an observable.
    fn by_load(&self, o: Observable) -> Vec<(f64, f64, f64)> {
        self.data
            .units
            .iter()
            .zip(&self.data.measured)
            .filter(|(u, _)| !u.heldout)
            .filter_map(|(u, m)| {
                let measured = *m.get(&o)?;
                let simulated = self
                    .scores
                    .iter()
                    .find(|s| {
                        !s.heldout
                            && s.observable == o
                            && s.excitation_frequency_hz == u.condition.excitation_frequency_hz
                            && s.normal_force_n == u.condition.normal_force_n
                    })?
                    .simulated;
                Some((self.data.simulated_condition(u, self.model).normal_force_n, measured, simulated))
            })
            .collect()
    }

    /// Mean N0 of the data, N.
    fn mean_load(&self) -> f64 {
        mean(
            &self
                .data
                .units
                .iter()
                .map(|u| self.data.simulated_condition(u, self.model).normal_force_n)
                .collect::<Vec<_>>(),
        )
        .max(1e-3)
    }
}

/// The forms searched for `effect`, started where the data point; empty
/// where the data carry no trace of it (no channel it could show in).
pub(crate) fn variants(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    match effect {
        Effect::NormalForceHarmonics => harmonics::normal_force_harmonics(effect, ctx),
        Effect::NonGaussianFriction => noise::non_gaussian_friction(effect, ctx),
        Effect::FrictionHysteresis => memory::friction_hysteresis(effect, ctx),
        Effect::ColouredFrictionNoise => noise::coloured_friction_noise(effect, ctx),
        Effect::Stiction => memory::stiction(effect, ctx),
        Effect::LoadDependentFriction => load::load_dependent_friction(effect, ctx),
        Effect::NormalForceDrift => load::normal_force_drift(effect, ctx),
    }
}

/// How far the signature of `effect` departs from the noise in `scores`:
/// for each of its observables, the mean over the fitting units of the
/// Huber loss of z above its expectation under pure noise ([`NULL_HUBER`]),
/// in units of that mean's noise (a Huber loss of a null z has a standard
/// deviation of about [`NULL_HUBER_SD`]); the largest over the observables.
/// Large means the data carry a trace the current model lacks. A load
/// dependence's trace is what differs between the loads
/// ([`between_loads`]): a misfit alike at every load is the friction
/// level's, or another effect's, and none can be seen at one load.
pub(crate) fn signature_excess(effect: Effect, scores: &[Score]) -> f64 {
    signature(effect)
        .iter()
        .filter_map(|&o| {
            let fitting: Vec<&Score> = scores.iter().filter(|s| !s.heldout && s.observable == o).collect();
            let z: Vec<f64> = match effect {
                Effect::LoadDependentFriction => between_loads(&fitting),
                _ => fitting.iter().map(|s| s.z).collect(),
            };
            let losses: Vec<f64> = z.iter().map(|&z| crate::diagnose::score::huber(z)).collect();
            (!losses.is_empty()).then(|| (mean(&losses) - NULL_HUBER) / (NULL_HUBER_SD / (losses.len() as f64).sqrt()))
        })
        .fold(0.0, f64::max)
}

/// The part of `scores`' misfit that differs between normal-force levels:
/// per level, its mean z less the mean over every score, times the square
/// root of its count (about a unit-spread z under pure noise, as a score's
/// own z is); none where the scores hold fewer than two levels.
fn between_loads(scores: &[&Score]) -> Vec<f64> {
    let loads = levels(scores.iter().map(|s| s.normal_force_n));
    if loads.len() < 2 {
        return Vec::new();
    }
    let overall = mean(&scores.iter().map(|s| s.z).collect::<Vec<_>>());
    loads
        .iter()
        .map(|&n| {
            let at: Vec<f64> = scores.iter().filter(|s| same_level(s.normal_force_n, n)).map(|s| s.z).collect();
            (mean(&at) - overall) * (at.len() as f64).sqrt()
        })
        .collect()
}

/// A family's signature stands out of the noise when its excess
/// ([`signature_excess`]) is beyond this many noise units: the report then
/// points at the family even where no form of it was named.
pub(crate) const SIGNATURE_STANDS_OUT: f64 = 3.0;

/// The mean Huber loss of a z-score under pure noise with the replicate
/// spread estimated from 8 replicates (z then about t with 7 degrees of
/// freedom): about 1.3.
pub(crate) const NULL_HUBER: f64 = 1.3;

/// The standard deviation of the Huber loss of such a z-score: about 2.
pub(crate) const NULL_HUBER_SD: f64 = 2.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::DiagnoseSettings;
    use crate::diagnose::derived::with_derived_channels;
    use crate::diagnose::score::{Scope, score};
    use crate::diagnose::synthetic::{SetShape, displacement_only_set_at, set_at};
    use crate::engine::{Condition, Engine};

    /// Every parameter a form is searched by, from records with every
    /// channel and from records of `x` alone, is explained in the report
    /// (its unit and meaning).
    #[test]
    fn every_searched_parameter_has_a_meaning_in_the_report() {
        let model = Model::paper_rig(&[]).expect("the paper rig");
        let conditions: Vec<Condition> = [(7.0, 8.0), (7.0, 11.0), (9.0, 14.0)]
            .map(|(f, n)| Condition { excitation_frequency_hz: f, normal_force_n: n })
            .to_vec();
        let shape = SetShape { runs_per_condition: 1, duration_s: 5.0, sample_rate_hz: 600.0 };
        let engine = Engine::cpu("test");
        let settings = DiagnoseSettings { replicates: 4, warmup_cycles: 5, ..DiagnoseSettings::default() };
        let mut forms = 0;
        for displacement_only in [false, true] {
            let set = if displacement_only {
                displacement_only_set_at(&model, &conditions, shape, 13)
            } else {
                set_at(&model, &conditions, shape, 13)
            };
            let (derived_set, derived) = with_derived_channels(&set);
            let set = derived_set.unwrap_or(set);
            let data = Data::new(&set, derived).expect("data");
            let scores = score(&engine, &model, &data, &settings, Scope::Fitting).expect("scores");
            let ctx = Context::new(&data, &model, &scores, settings.warmup_cycles);
            for effect in Effect::ALL {
                for v in variants(effect, &ctx) {
                    forms += 1;
                    for p in &v.params {
                        assert!(
                            !parameter_meaning(p.name).is_empty(),
                            "{effect} [{}]: `{}` unexplained",
                            v.form,
                            p.name
                        );
                    }
                }
            }
        }
        assert!(forms > 30, "{forms} forms");
    }

    /// At one load every load-dependence form is a shift of the friction
    /// level (the adhesion form's A/N0 most plainly), which the calibration
    /// owns: the family is searched only where the set holds two loads or
    /// more, held-out ones included.
    #[test]
    fn a_load_dependence_is_searched_only_across_loads() {
        let model = Model::paper_rig(&[]).expect("the paper rig");
        let shape = SetShape { runs_per_condition: 2, duration_s: 5.0, sample_rate_hz: 600.0 };
        let engine = Engine::cpu("test");
        let settings = DiagnoseSettings { replicates: 4, warmup_cycles: 5, ..DiagnoseSettings::default() };
        let forms_at = |loads: &[f64]| -> usize {
            let conditions: Vec<Condition> =
                loads.iter().map(|&n| Condition { excitation_frequency_hz: 7.0, normal_force_n: n }).collect();
            let set = set_at(&model, &conditions, shape, 17);
            let data = Data::new(&set, Default::default()).expect("data");
            let scores = score(&engine, &model, &data, &settings, Scope::Fitting).expect("scores");
            let ctx = Context::new(&data, &model, &scores, settings.warmup_cycles);
            variants(Effect::LoadDependentFriction, &ctx).len()
        };
        assert_eq!(forms_at(&[14.0]), 0, "searched at one load");
        assert!(forms_at(&[10.0, 14.0]) >= 3, "not searched across two loads");
    }
}
