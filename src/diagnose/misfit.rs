//! What the fitted model still misses, in words: the observables furthest
//! above their noise and where each points, the families whose signature
//! stands out, and the families that fit in sample but predict no withheld
//! fold (`verdict.misfit` in the report).

use std::collections::BTreeMap;

use serde::Serialize;

use super::observable::Observable;
use super::score::Score;
use super::{Candidate, candidates, mean, search};
use crate::engine::Effect;

/// Where the calibrated baseline misfits in a way no effect explains.
#[derive(Clone, Debug, Serialize)]
pub struct Misfit {
    /// The observables whose mean Huber loss over the fitting units is
    /// furthest above noise, worst first.
    pub observables: Vec<MisfitObservable>,
    /// What that pattern points at, in words.
    pub hints: Vec<String>,
}

/// One observable the baseline misfits.
#[derive(Clone, Debug, Serialize)]
pub struct MisfitObservable {
    pub observable: Observable,
    /// Mean z over the fitting units (sign: measured above simulated), –.
    pub mean_z: f64,
    /// Mean loss ln(1 + z²) over the units, –.
    pub mean_loss: f64,
    /// How many units it is scored at.
    #[serde(skip)]
    pub count: usize,
}

/// What a misfit of an observable points at: the parameters of the
/// baseline it moves with, or the effect whose form-agnostic signature it
/// is (so a misfit that no candidate's form closed still names where to
/// look). Every observable has one.
fn misfit_hint(o: Observable) -> &'static str {
    use Observable as O;
    match o {
        O::FrictionMuMean | O::FrictionLowSpeedMuMean => "the friction law's level (a, b, c, d) or its load dependence",
        O::FrictionResidualStd => "the friction noise level sigma_mu",
        O::PeakMeanM | O::PhaseMeanDeg => "the friction level a or the rig (mass, stiffness, damping, base amplitude)",
        O::PeakVarM2 | O::PhaseVarDeg2 | O::PeakSkewness => "the friction noise (its level or its spectrum)",
        O::NormalForceMeanN | O::NormalForceVarN2 | O::NormalForceResidualVarN2 => {
            "the normal-force noise sigma_N or N0"
        }
        O::StickFraction | O::FrictionBreakawayMean | O::FrictionStictionExcess | O::FrictionSlipSamples => {
            "the friction near zero speed (the Stribeck drop b, c, or stiction)"
        }
        O::FrictionHysteresis => {
            "a friction memory: the accelerating and decelerating branches of mu(v) differ (friction_hysteresis, perhaps in a form no candidate has)"
        }
        O::FrictionResidualAutocorrLag1 | O::FrictionResidualAutocorrLag10 => {
            "friction that remembers beyond one noise interval: coloured friction noise or a friction memory"
        }
        O::FrictionResidualSkewness | O::FrictionResidualTailWeight => {
            "the friction noise's distribution (skew or heavy tails: non_gaussian_friction)"
        }
        O::NormalForceHarmonic1N | O::NormalForceHarmonic2N | O::NormalForceHarmonic3N | O::NormalForceHarmonic4N => {
            "a normal force that varies with the excitation (normal_force_harmonics)"
        }
        O::NormalForceDriftNPerS
        | O::NormalForceDriftPerS
        | O::NormalForceCurvaturePerS2
        | O::PeakTrendPerS
        | O::FrictionTrendPerS => "a slow change over the record (normal_force_drift, or wear)",
        O::NormalForceWander => {
            "a normal force that wanders slowly over the record (normal_force_drift random_walk, or wear)"
        }
        O::PeakCount => "the record's length or the excitation frequency (a peak per period)",
    }
}

/// The fitted model's misfit by observable, when it is beyond `noise`,
/// with a hint for each of the worst observables and one for every effect
/// family whose form-agnostic signature still stands out of the noise
/// ([`candidates::signature_excess`]): where to look when no candidate's
/// form explained the gap.
pub(super) fn misfit_of(scores: &[Score], null: search::cv::NullLoss, named: &[Effect]) -> Option<Misfit> {
    let mut by: BTreeMap<Observable, Vec<f64>> = BTreeMap::new();
    for s in scores.iter().filter(|s| !s.heldout) {
        by.entry(s.observable).or_default().push(s.z);
    }
    let mut worst: Vec<MisfitObservable> = by
        .into_iter()
        .map(|(observable, z)| MisfitObservable {
            observable,
            mean_z: mean(&z),
            mean_loss: mean(&z.iter().map(|&z| search::cv::loss(z)).collect::<Vec<_>>()),
            count: z.len(),
        })
        .filter(|m| m.mean_loss - null.mean > null.noise(m.count))
        .collect();
    let mut families: Vec<(Effect, f64)> = Effect::ALL
        .into_iter()
        .filter(|e| !named.contains(e))
        .map(|e| (e, candidates::signature_excess(e, scores)))
        .filter(|(_, x)| *x > candidates::SIGNATURE_STANDS_OUT)
        .collect();
    families.sort_by(|a, b| b.1.total_cmp(&a.1));
    if worst.is_empty() && families.is_empty() {
        return None;
    }
    worst.sort_by(|a, b| b.mean_loss.total_cmp(&a.mean_loss));
    worst.truncate(6);
    let mut hints: Vec<String> = worst
        .iter()
        .map(|m| {
            format!(
                "{} ({} {})",
                misfit_hint(m.observable),
                m.observable.name(),
                if m.mean_z > 0.0 { "measured above simulated" } else { "measured below simulated" }
            )
        })
        .collect();
    hints.extend(
        families
            .iter()
            .map(|(e, x)| format!("the signature of {e} stands {x:.0} noise units out of the noise: {}", e.meaning())),
    );
    Some(Misfit { observables: worst, hints })
}

/// A hint for each family of the first round, not named, that closes
/// more of the baseline's gap in sample than `noise` (the out-of-sample
/// noise threshold of the gap) but none of it at the withheld folds: what
/// it fits at some folds does not carry over to the others, which the
/// user should hear about rather than see only `none`.
pub(super) fn fitting_only_hints(first_round: &[Candidate], named: &[Effect], noise: f64) -> Vec<String> {
    first_round
        .iter()
        .filter(|c| !named.contains(&c.effect) && c.cv_share <= 0.0 && c.shrink < 1.0)
        .filter(|c| c.gap_fit / (1.0 - c.shrink) - c.gap_fit > noise)
        .map(|c| {
            let example = match c.effect {
                Effect::LoadDependentFriction => {
                    " (as when the friction changes between two of the loads measured and holds beyond them: \
                     more load levels between those two would tell)"
                }
                _ => "",
            };
            format!(
                "{} ({}) closes {:.0}% of the baseline's gap in sample but none of it at the withheld folds \
                 ({:+.0}%): what it fits at some folds does not carry over to the others{example}",
                c.effect,
                c.form,
                100.0 * c.in_sample_share,
                100.0 * c.cv_share
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{Candidate, Effect, Observable, Score, fitting_only_hints, misfit_of};

    /// A fitting score of `observable` at unit `unit` with z = `z`.
    fn fitting_score(unit: usize, observable: Observable, z: f64) -> Score {
        crate::diagnose::score::test_score(unit, observable, z, false)
    }

    /// A friction memory in a form no candidate has leaves the branch
    /// asymmetry and the residual's autocorrelation far off: each misfit
    /// observable says where to look, worst first, and so does the family
    /// whose signature stands out.
    #[test]
    fn every_misfit_observable_and_family_says_where_to_look() {
        let scores = [
            fitting_score(0, Observable::FrictionHysteresis, -135.0),
            fitting_score(0, Observable::FrictionResidualAutocorrLag1, 113.0),
            fitting_score(0, Observable::PeakMeanM, 0.5),
        ];
        let null = crate::diagnose::search::cv::NullLoss { mean: 0.6, sd: 0.6 };
        let misfit = misfit_of(&scores, null, &[]).expect("a misfit beyond the noise");
        assert_eq!(misfit.observables.len(), 2, "the peak mean is within the noise");
        assert!(misfit.hints[0].contains("friction memory") && misfit.hints[0].contains("measured below simulated"));
        assert!(misfit.hints[1].contains("coloured friction noise"));
        assert!(misfit.hints.iter().any(|h| h.contains("signature of friction_hysteresis")), "{:?}", misfit.hints);
        // A named family is not pointed at again.
        let misfit = misfit_of(&scores, null, &[Effect::FrictionHysteresis]).expect("a misfit");
        assert!(!misfit.hints.iter().any(|h| h.contains("signature of friction_hysteresis")));
    }

    /// A load dependence's signature is a misfit that differs between the
    /// loads: the friction level missed alike at 4, 8 and 16 N (the law's
    /// level, or another effect's misfit) does not point at it, and one
    /// that grows with the load does.
    #[test]
    fn a_load_dependence_is_pointed_at_only_where_the_misfit_differs_between_loads() {
        let at_loads = |z: [f64; 3]| -> Vec<Score> {
            (0..6)
                .map(|u| Score {
                    normal_force_n: [4.0, 8.0, 16.0][u % 3],
                    ..fitting_score(u, Observable::FrictionMuMean, z[u % 3])
                })
                .collect()
        };
        let null = crate::diagnose::search::cv::NullLoss { mean: 0.6, sd: 0.6 };
        let points_at_load = |scores: &[Score]| {
            misfit_of(scores, null, &[])
                .is_some_and(|m| m.hints.iter().any(|h| h.contains("signature of load_dependent_friction")))
        };
        assert!(!points_at_load(&at_loads([-20.0, -20.0, -20.0])));
        assert!(points_at_load(&at_loads([-20.0, 0.0, 20.0])));
    }

    /// A first-round family with `shrink` of the gap `gap_before` in sample
    /// and `cv_share` out of sample.
    fn candidate(effect: Effect, gap_before: f64, shrink: f64, cv_share: f64) -> Candidate {
        Candidate {
            effect,
            form: crate::diagnose::candidates::SearchedForm::Linear,
            gap_fit: gap_before * (1.0 - shrink),
            shrink,
            in_sample_share: shrink,
            cv_share,
            heldout_shrink: cv_share,
            wins: 0.0,
            refined: true,
            parameters: Default::default(),
            unexplained: Vec::new(),
            model: Default::default(),
            scores: Vec::new(),
        }
    }

    /// A family that fits the data in sample but predicts no withheld fold
    /// is pointed at, unless it is named, its fall is within the noise, or
    /// it predicts the withheld folds too.
    #[test]
    fn a_family_that_fits_only_in_sample_is_pointed_at() {
        let noise = 0.06;
        let round = [
            candidate(Effect::LoadDependentFriction, 1.4, 0.3, -0.05),
            candidate(Effect::Stiction, 1.4, 0.02, -0.01),
            candidate(Effect::NormalForceDrift, 1.4, 0.3, 0.2),
        ];
        let hints = fitting_only_hints(&round, &[], noise);
        assert_eq!(hints.len(), 1, "{hints:?}");
        assert!(hints[0].starts_with("load_dependent_friction (linear) closes 30%") && hints[0].contains("(-5%)"));
        assert!(fitting_only_hints(&round, &[Effect::LoadDependentFriction], noise).is_empty());
    }
}
