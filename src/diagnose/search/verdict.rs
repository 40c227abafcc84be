//! The verdict: which of the effects a forward selection added are named,
//! and how sure that is.
//!
//! The selection walks rounds: in each, the family that closes the largest
//! share of what the model so far leaves out of sample leads, and is added.
//! The verdict names the leading families of the first rounds while each
//! closes a share of what the model before it left beyond the noise,
//! refitted from scratch without each fold; of those it names the longest
//! run whose model, with all of them,
//!
//! - predicts the response over every withheld fold together no worse
//!   than the baseline, up to the noise of that pooled mean (the response:
//!   the peaks' and the phase's mean and variance, what a fitted model is
//!   used to predict),
//! - predicts every withheld fold no worse than the baseline does (the
//!   verdict holds in every fold, not on average), over every observable
//!   and over the response's alone (a handful of scores beside the
//!   friction and normal-force features that dominate the first), and
//! - whose last effect predicts every fold no worse than the model before
//!   it.
//!
//! "No worse" at a fold is up to that fold's noise, and up to what the
//! model's form leaves of that fold when it is fitted to every unit, the
//! fold's own included (its form misfit there, [`Round::fitted`]): a form
//! that cannot fit a withheld level as closely as the baseline predicts
//! it even when it sees that level (a power law through 4 and 16 N misses
//! a load dependence's curvature at 8 N, where a baseline averaged over the
//! loads is closest) predicts it as well as its form allows, and that rise
//! is form misfit, reported as such, not a failed prediction. What is held
//! against a family is a withheld fold it predicts worse than both the
//! baseline and its own fit of that fold, and a response worse over every
//! fold together.
//!
//! The first of two effects is fitted while the second is still missing,
//! and that fit can trade one fold for the others (a load dependence
//! bent by a coloured noise it cannot yet tell apart); the pair is judged
//! by what the two predict together.
//!
//! A family is named for what it explains, not for matching a shape: no
//! effect need close most of the gap alone, because on a real rig no
//! candidate's form is the effect's exact shape, and what the form leaves
//! is reported as its form misfit. (Two effects seen together are judged
//! alike: the second closes part of what the first left, as the first did
//! of the baseline's gap.) Form misfit is what makes a verdict less sure,
//! since a rival family with another shape might explain the
//! rest: the confidence is the share of bootstrap resamples of the
//! conditions that give the same verdict, scaled by [`form_factor`]: the
//! share of the gap the named effects close, and each one's margin over
//! its nearest rival family, over one half, capped at 1. A verdict that
//! explains most of the gap, where no rival explains much of it, keeps its
//! bootstrap confidence; one that explains a third is at most two-thirds
//! sure, and one whose rival explains nearly as much is not sure at all.

use crate::diagnose::search::cv::{Entrant, MOST, NullLoss, UnitLosses, Weights, resamples};
use crate::engine::Effect;

/// One round of the selection as the verdict reads it.
pub(crate) struct Round {
    /// The current model's own losses at the held-out units (the model of
    /// the rounds before, fitted to every unit).
    pub(crate) current: UnitLosses,
    /// Every family's out-of-sample losses and the current model's in the
    /// same yardsticks.
    pub(crate) entrants: Vec<(UnitLosses, UnitLosses)>,
    /// Each entrant's effect.
    pub(crate) effects: Vec<Effect>,
    /// Which entrant led.
    pub(crate) leader: usize,
    /// The models before and after the leader, refitted without each fold
    /// the families were judged on (crossed over loads and frequencies
    /// where there are such folds), at each fold's units, in the latter's
    /// yardstick: what the leader explains out of sample.
    pub(crate) refitted: (UnitLosses, UnitLosses),
    /// The same, refitted without each withheld level (or whatever
    /// [`crate::diagnose::data::Folds`] the set holds out).
    pub(crate) refitted_levels: (UnitLosses, UnitLosses),
    /// The baseline and the models after the leader, refitted without each
    /// fold, at each fold's units, in the latter's yardstick.
    pub(crate) joint: (UnitLosses, UnitLosses),
    /// `joint` over the response's observables alone (the peaks' and the
    /// phase's mean and variance): what a fitted model is used to predict.
    pub(crate) joint_response: (UnitLosses, UnitLosses),
    /// The model after the leader, fitted to every unit (the fold's own
    /// included), its own losses at every unit: over every observable, and
    /// over the response's alone. What its form leaves of a fold it has
    /// seen: no refit without the fold can be asked to predict it closer.
    pub(crate) fitted: (UnitLosses, UnitLosses),
    /// Whether the leader was judged as an effect seen at a few conditions
    /// (on crossed folds, each fall against the noise of the scores it
    /// moved): a rise at a withheld level is then judged so too.
    pub(crate) local: bool,
}

/// How many of `rounds`' leaders one weighting of the units names (0:
/// none; see the module); `folds` lists each fold's held-out units.
pub(crate) fn named(rounds: &[Round], folds: &[Vec<usize>], weights: &Weights<'_>) -> usize {
    let mut n = 0;
    for (j, r) in rounds.iter().enumerate() {
        let entrants: Vec<Entrant<'_>> =
            r.entrants.iter().map(|(losses, reference)| Entrant { losses, reference }).collect();
        let Some((leader, _)) = weights.leader(&r.current, &entrants) else { break };
        if leader != r.leader {
            break;
        }
        let (refitted, beyond) = weights.share(&r.refitted.1, &r.refitted.0);
        if !(refitted > 0.0 && beyond) {
            break;
        }
        let (fitted, fitted_response) = (&r.fitted.0, &r.fitted.1);
        if no_worse(&r.joint_response, weights, r.local)
            && every_fold_no_worse(&r.joint, fitted, folds, weights, r.local)
            && every_fold_no_worse(&r.joint_response, fitted_response, folds, weights, r.local)
            && every_fold_no_worse(&r.refitted_levels, fitted, folds, weights, r.local)
        {
            n = j + 1;
        }
    }
    n
}

/// Why a leader of the selection was not named, as the unweighted data
/// judge it (the first of the reasons [`named`] checks that holds).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Refused {
    /// Refitted without each fold, it closed `share` of what the model
    /// before it left out of sample, not beyond the noise.
    NotBeyondNoise { share: f64 },
    /// The model with it, refitted without each fold, predicts these folds
    /// (indices into the folds) worse than the baseline does, these
    /// worse than the model before it, and the response at these worse
    /// than the baseline does, beyond each fold's noise; and whether it
    /// predicts the response over every fold together worse than the
    /// baseline, beyond the noise of that pooled mean.
    WorseFolds {
        than_baseline: Vec<usize>,
        than_before: Vec<usize>,
        response_than_baseline: Vec<usize>,
        response_over_every_fold: bool,
    },
}

/// Why `round`'s leader is not named where the unweighted data leave it
/// out (`folds`: each fold's held-out units).
pub(crate) fn refusal(round: &Round, folds: &[Vec<usize>], units: &[usize], null: NullLoss) -> Refused {
    let ones = vec![1.0; units.len()];
    let point = Weights { units, w: &ones, null };
    let (share, beyond) = point.share(&round.refitted.1, &round.refitted.0);
    if !(share > 0.0 && beyond) {
        return Refused::NotBeyondNoise { share };
    }
    let worse = |pair: &(UnitLosses, UnitLosses), fitted: &UnitLosses| -> Vec<usize> {
        (0..folds.len()).filter(|&k| !every_fold_no_worse(pair, fitted, &folds[k..=k], &point, round.local)).collect()
    };
    Refused::WorseFolds {
        than_baseline: worse(&round.joint, &round.fitted.0),
        than_before: worse(&round.refitted_levels, &round.fitted.0),
        response_than_baseline: worse(&round.joint_response, &round.fitted.1),
        response_over_every_fold: !no_worse(&round.joint_response, &point, round.local),
    }
}

/// One withheld fold as [`named`]'s checks against the baseline read it,
/// unweighted.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FoldCheck {
    /// The fold's index.
    pub(crate) fold: usize,
    /// Over the response's observables alone (else over every observable).
    pub(crate) response: bool,
    /// The baseline refitted without the fold (`other`), the model with the
    /// named effects refitted without it (`model`), and that model's own
    /// fit of it.
    pub(crate) rise: Rise,
}

/// A model's mean loss over some units against another model's, and
/// against its own fit's there where that counts, –: what every check of
/// [`named`] weighs.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Rise {
    /// The other model's mean loss.
    pub(crate) other: f64,
    /// The model's mean loss.
    pub(crate) model: f64,
    /// The model fitted to every unit, these included: its own mean loss
    /// there (`None`: no allowance for form misfit).
    pub(crate) own_fit: Option<f64>,
    /// The noise a rise must exceed to count ([`rise_noise`]).
    pub(crate) noise: f64,
    /// The weighted number of scores behind the means.
    scores: f64,
}

impl Rise {
    /// `pair` (the other model's and the model's losses) and the model's
    /// own fit (`fitted`, where form misfit is allowed for) over the units
    /// `weights` weigh; with `local`, the noise of the scores the change
    /// moved.
    fn of(pair: &(UnitLosses, UnitLosses), fitted: Option<&UnitLosses>, weights: &Weights<'_>, local: bool) -> Rise {
        let ((other, scores), (model, _)) = (weights.gap(&pair.0), weights.gap(&pair.1));
        let own_fit = fitted.map(|f| weights.gap(f).0);
        Rise { other, model, own_fit, noise: rise_noise(&pair.1, weights, scores, local), scores }
    }

    /// Whether the model's mean loss rises above the other's, or above its
    /// own fit's where that is higher, by no more than the noise.
    fn within_noise(&self) -> bool {
        self.scores == 0.0 || self.model - self.own_fit.map_or(self.other, |f| self.other.max(f)) <= self.noise
    }

    /// Whether it passes only for the form's misfit: worse than the other
    /// model beyond the noise, but no worse than the form fits these units
    /// when it sees them.
    pub(crate) fn within_form_misfit(&self) -> bool {
        self.within_noise() && self.model - self.other > self.noise
    }
}

/// Every withheld fold of `round` as its checks against the baseline, over
/// every observable and over the response's alone, read it unweighted.
pub(crate) fn fold_checks(round: &Round, folds: &[Vec<usize>], units: &[usize], null: NullLoss) -> Vec<FoldCheck> {
    let ones = vec![1.0; units.len()];
    let all = Weights { units, w: &ones, null };
    let checks = [(false, &round.joint, &round.fitted.0), (true, &round.joint_response, &round.fitted.1)];
    let mut out = Vec::new();
    for (response, pair, fitted) in checks {
        for (fold, held) in folds.iter().enumerate() {
            out.push(FoldCheck { fold, response, rise: fold_rise(pair, fitted, held, &all, round.local) });
        }
    }
    out
}

/// Whether a model refitted without each fold predicts every fold that
/// carries weight no worse than another (`pair`: the other and the model,
/// at each fold's units; the model before a leader and after it, or the
/// baseline and the model after it), up to the model's form misfit there
/// (`fitted`: its own losses fitted to every unit, the fold's included):
/// its mean loss there rises above the other's, and above its own fit's,
/// by no more than the noise of a mean over that many scores (with
/// `local`, of the scores the change moved there,
/// [`crate::diagnose::search::cv::NullLoss::fall_noise`]: an effect judged
/// at the few conditions it shows at is held to their noise where it makes
/// a prediction worse as well). A fold the effect leaves untouched is then
/// not held against it for the replicates' noise, nor one it predicts as
/// closely as its form can fit it.
fn every_fold_no_worse(
    pair: &(UnitLosses, UnitLosses),
    fitted: &UnitLosses,
    folds: &[Vec<usize>],
    weights: &Weights<'_>,
    local: bool,
) -> bool {
    folds.iter().all(|fold| fold_rise(pair, fitted, fold, weights, local).within_noise())
}

/// [`Rise::of`] over the units of `fold` that `weights` weigh.
fn fold_rise(
    pair: &(UnitLosses, UnitLosses),
    fitted: &UnitLosses,
    fold: &[usize],
    weights: &Weights<'_>,
    local: bool,
) -> Rise {
    let (units, w): (Vec<usize>, Vec<f64>) =
        weights.units.iter().zip(weights.w).filter(|(u, _)| fold.contains(u)).map(|(&u, &w)| (u, w)).unzip();
    Rise::of(pair, Some(fitted), &Weights { units: &units, w: &w, null: weights.null }, local)
}

/// Whether the model (`pair.1`) predicts the units `weights` weigh, pooled,
/// no worse than the other (`pair.0`), up to the noise of that mean (as
/// [`every_fold_no_worse`] asks of each fold, with no allowance for form
/// misfit).
fn no_worse(pair: &(UnitLosses, UnitLosses), weights: &Weights<'_>, local: bool) -> bool {
    Rise::of(pair, None, weights, local).within_noise()
}

/// The noise a model's (`after`) mean loss over `n` weighted scores may
/// rise by before it counts: that of the mean, or with `local` that of the
/// scores the change moved ([`NullLoss::fall_noise`]).
fn rise_noise(after: &UnitLosses, weights: &Weights<'_>, n: f64, local: bool) -> f64 {
    if local { weights.null.fall_noise(n, weights.moved(after).0) } else { weights.noise(n) }
}

/// How far form misfit discounts a verdict that names the first `n`
/// leaders: the smallest, over what those leaders close together of the
/// baseline's out-of-sample gap (refitted without each fold) and over each
/// leader's margin over its nearest rival in its round (the share of the
/// gap it closes beyond the best other family's, none below 0), of that
/// share over one half, within 0 and 1; 1 when nothing is named. The
/// margin is the part of the gap that speaks for this family rather than
/// another: two families with other shapes that each explain some of a
/// gap are told apart only by what one explains and the other does not.
/// A family the verdict names too is no rival: where two effects each
/// explain part of the gap, the first round's runner-up is the second
/// round's leader, and a verdict that names both is not made less sure
/// by either one's share of the other's.
pub(crate) fn form_factor(rounds: &[Round], n: usize, weights: &Weights<'_>) -> f64 {
    if n == 0 {
        return 1.0;
    }
    let joint = &rounds[n - 1].joint;
    let mut factor = weights.share(&joint.1, &joint.0).0;
    let named: Vec<Effect> = rounds[..n].iter().map(|r| r.effects[r.leader]).collect();
    for r in &rounds[..n] {
        let shares: Vec<f64> =
            r.entrants.iter().map(|(losses, reference)| weights.share(losses, reference).0).collect();
        let rival = (0..shares.len())
            .filter(|&i| i != r.leader && !named.contains(&r.effects[i]))
            .map(|i| shares[i])
            .fold(0.0, f64::max);
        factor = factor.min(shares[r.leader] - rival);
    }
    (factor / MOST).clamp(0.0, 1.0)
}

/// The verdict over `rounds`: how many leaders are named without
/// resampling, the share of resamples (from `seed`) that name exactly as
/// many, and for each round the share that name its leader at least, each
/// share scaled by the [`form_factor`] of the leaders it names: of the
/// verdict's, where it is among them (an effect is as sure as the verdict
/// that names it allows, and the other named effects are no rivals of it),
/// else of the leaders up to it.
pub(crate) fn judge(
    rounds: &[Round],
    folds: &[Vec<usize>],
    units: &[usize],
    null: NullLoss,
    seed: u64,
) -> (usize, f64, Vec<f64>) {
    let ones = vec![1.0; units.len()];
    let unweighted = Weights { units, w: &ones, null };
    let point = named(rounds, folds, &unweighted);
    let mut same = 0usize;
    let mut at_least = vec![0usize; rounds.len()];
    let draws = resamples(units.len(), seed);
    for w in &draws {
        let n = named(rounds, folds, &Weights { units, w, null });
        if n == point {
            same += 1;
        }
        for slot in &mut at_least[..n] {
            *slot += 1;
        }
    }
    let share = |k: usize| k as f64 / draws.len() as f64;
    let each =
        at_least.into_iter().enumerate().map(|(i, k)| share(k) * form_factor(rounds, point.max(i + 1), &unweighted));
    (point, share(same) * form_factor(rounds, point, &unweighted), each.collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::search::cv::{UnitLoss, loss};

    const NULL: NullLoss = NullLoss { mean: 0.18, sd: 0.32 };

    fn at(z: &[f64]) -> UnitLosses {
        z.iter().enumerate().map(|(u, &z)| (u, UnitLoss::whole(10.0 * loss(z), 10))).collect()
    }

    /// A round whose current model misses by `before` everywhere, whose
    /// leader (of two) leaves `after`, its rival `rival`, refitted alike;
    /// the baseline misses by `baseline`.
    fn round(before: f64, after: f64, rival: f64, baseline: f64) -> Round {
        let n = 12;
        Round {
            current: at(&vec![before; n]),
            entrants: vec![(at(&vec![after; n]), at(&vec![before; n])), (at(&vec![rival; n]), at(&vec![before; n]))],
            effects: vec![Effect::LoadDependentFriction, Effect::ColouredFrictionNoise],
            leader: 0,
            refitted: (at(&vec![before; n]), at(&vec![after; n])),
            refitted_levels: (at(&vec![before; n]), at(&vec![after; n])),
            joint: (at(&vec![baseline; n]), at(&vec![after; n])),
            joint_response: (at(&vec![baseline; n]), at(&vec![after; n])),
            fitted: (at(&vec![after; n]), at(&vec![after; n])),
            local: false,
        }
    }

    /// Two folds of six units each.
    fn halves() -> Vec<Vec<usize>> {
        vec![(0..6).collect(), (6..12).collect()]
    }

    #[test]
    fn one_effect_that_explains_most_is_named_alone() {
        let units: Vec<usize> = (0..12).collect();
        // z 10 → 2: most of the gap; the next round closes nothing of what
        // is left beyond the noise.
        let rounds = [round(10.0, 2.0, 9.0, 10.0), round(2.0, 1.8, 1.9, 10.0)];
        let (n, confidence, each) = judge(&rounds, &halves(), &units, NULL, 1);
        assert_eq!(n, 1);
        assert!(confidence > 0.95 && each[0] > 0.95, "{confidence} {each:?}");
    }

    #[test]
    fn an_effect_that_explains_a_third_is_named_with_its_form_misfit_in_the_confidence() {
        let units: Vec<usize> = (0..12).collect();
        // z 10 → 6 closes (ln 12.1 − ln 5)/(ln 12.1 − 0.18) ≈ 0.38 of the
        // gap, its rival (10 → 9) 0.08: named, at most 0.30/0.5 ≈ 0.60 sure.
        let rounds = [round(10.0, 6.0, 9.0, 10.0)];
        let (n, confidence, _) = judge(&rounds, &halves(), &units, NULL, 1);
        assert_eq!(n, 1);
        assert!(confidence > 0.55 && confidence < 0.65, "{confidence}");
        // Without a rival that closes anything, the share alone: ≈ 0.76.
        let rounds = [round(10.0, 6.0, 10.0, 10.0)];
        let (_, confidence, _) = judge(&rounds, &halves(), &units, NULL, 1);
        assert!(confidence > 0.72 && confidence < 0.8, "{confidence}");
        // A rival that closes nearly as much (z 10 → 6.5) leaves a margin
        // of about 0.04: named, but not sure.
        let rounds = [round(10.0, 6.0, 6.5, 10.0)];
        let (n, confidence, _) = judge(&rounds, &halves(), &units, NULL, 1);
        assert_eq!(n, 1);
        assert!(confidence < 0.15, "{confidence}");
        // Nothing closed beyond the noise: nothing named.
        let rounds = [round(10.0, 9.95, 9.97, 10.0)];
        assert_eq!(judge(&rounds, &halves(), &units, NULL, 1).0, 0);
    }

    #[test]
    fn an_effect_that_predicts_one_fold_worse_is_not_named() {
        let units: Vec<usize> = (0..12).collect();
        // Better than the baseline on average (z 10 → 2 in the first fold,
        // 10 → 12 in the second), but the second withheld fold is
        // predicted worse, beyond the noise.
        let mut r = round(10.0, 2.0, 9.0, 10.0);
        let after: Vec<f64> = (0..12).map(|u| if u < 6 { 2.0 } else { 12.0 }).collect();
        r.refitted.1 = at(&after);
        r.refitted_levels.1 = r.refitted.1.clone();
        assert_eq!(judge(&[r], &halves(), &units, NULL, 1).0, 0);
        // A fold the effect leaves as it was, up to the noise (10 → 10.1),
        // is no objection.
        let mut r = round(10.0, 2.0, 9.0, 10.0);
        let after: Vec<f64> = (0..12).map(|u| if u < 6 { 2.0 } else { 10.1 }).collect();
        r.refitted.1 = at(&after);
        r.refitted_levels.1 = r.refitted.1.clone();
        assert_eq!(judge(&[r], &halves(), &units, NULL, 1).0, 1);
    }

    #[test]
    fn a_second_effect_is_judged_as_the_first_and_together_they_explain_most() {
        let units: Vec<usize> = (0..12).collect();
        // The first closes about a third (z 10 → 6); the second, on top,
        // most of what is left (6 → 1.5): both named.
        let rounds = [round(10.0, 6.0, 7.0, 10.0), round(6.0, 1.5, 5.5, 10.0)];
        assert_eq!(judge(&rounds, &halves(), &units, NULL, 1).0, 2);
        // A second that closes 0.41 of what the first left (6 → 4), beyond
        // the noise, is named too: together they close 0.64 of the gap.
        let rounds = [round(10.0, 6.0, 7.0, 10.0), round(6.0, 4.0, 5.5, 10.0)];
        assert_eq!(judge(&rounds, &halves(), &units, NULL, 1).0, 2);
        // Two slivers (10 → 7.5 → 6.5) that together close a third of the
        // gap are named, but neither surely: a rival with another shape
        // might explain the rest.
        let rounds = [round(10.0, 7.5, 9.0, 10.0), round(7.5, 6.5, 7.3, 10.0)];
        let (n, confidence, _) = judge(&rounds, &halves(), &units, NULL, 1);
        assert_eq!(n, 2);
        assert!(confidence < 0.5, "{confidence}");
        // A second that predicts one withheld fold worse is not named.
        let mut second = round(6.0, 1.5, 5.5, 10.0);
        second.refitted.1 = at(&(0..12).map(|u| if u < 6 { 1.5 } else { 7.0 }).collect::<Vec<f64>>());
        second.refitted_levels.1 = second.refitted.1.clone();
        let rounds = [round(10.0, 6.0, 7.0, 10.0), second];
        assert_eq!(judge(&rounds, &halves(), &units, NULL, 1).0, 1);
    }

    /// Two effects that each explain part of the gap: the first round's
    /// runner-up (z 10 → 6.5 beside the leader's 10 → 6) leads the second.
    /// A verdict that names both is not made unsure by either one's share
    /// of the other's; one that names the first alone still is, and so is
    /// one whose runner-up is another family than the second leader.
    #[test]
    fn a_family_the_verdict_names_too_is_no_rival() {
        let units: Vec<usize> = (0..12).collect();
        let mut first = round(10.0, 6.0, 6.5, 10.0);
        first.effects = vec![Effect::ColouredFrictionNoise, Effect::LoadDependentFriction];
        let mut second = round(6.0, 1.5, 5.9, 10.0);
        second.effects = vec![Effect::LoadDependentFriction, Effect::Stiction];
        second.joint.1 = second.refitted.1.clone();
        let both = [first, second];
        let (n, confidence, each) = judge(&both, &halves(), &units, NULL, 1);
        assert_eq!(n, 2);
        assert!(confidence > 0.5, "{confidence} {each:?}");
        // Each named effect is as sure as the verdict allows; the first
        // alone, named only as surely as its margin over the second.
        assert!(each.iter().all(|&c| c > 0.5), "{each:?}");
        assert!(judge(&both[..1], &halves(), &units, NULL, 1).1 < 0.15);
        // The same shares with a runner-up the verdict does not name.
        let [mut first, second] = both;
        first.effects = vec![Effect::ColouredFrictionNoise, Effect::FrictionHysteresis];
        let (n, confidence, _) = judge(&[first, second], &halves(), &units, NULL, 1);
        assert_eq!(n, 2);
        assert!(confidence < 0.15, "{confidence}");
    }

    /// A fold predicted worse than the baseline predicts it, but no worse
    /// than the model's form fits it when it sees that fold (a power law
    /// through the outer loads missing a curved load dependence at the
    /// middle one), is form misfit, not a failed prediction: named. A fold
    /// predicted worse than both, beyond the noise, is not.
    #[test]
    fn a_fold_predicted_as_closely_as_the_form_fits_it_is_not_held_against_it() {
        let units: Vec<usize> = (0..12).collect();
        let after: Vec<f64> = (0..12).map(|u| if u < 6 { 2.0 } else { 3.0 }).collect();
        let mut r = round(10.0, 2.0, 9.0, 10.0);
        let baseline: Vec<f64> = (0..12).map(|u| if u < 6 { 10.0 } else { 1.0 }).collect();
        r.joint = (at(&baseline), at(&after));
        r.joint_response = r.joint.clone();
        r.refitted_levels = r.joint.clone();
        r.refitted.1 = at(&after);
        // Fitted to every unit, the form leaves z 3 at the second fold too.
        r.fitted = (at(&after), at(&after));
        assert_eq!(judge(std::slice::from_ref(&r), &halves(), &units, NULL, 1).0, 1);
        // Where the form fits the second fold closely (z 1), predicting it
        // at z 3 is a prediction that failed.
        r.fitted = (at(&[2.0; 12]), at(&[1.0; 12]));
        assert_eq!(judge(std::slice::from_ref(&r), &halves(), &units, NULL, 1).0, 0);
        match refusal(&r, &halves(), &units, NULL) {
            Refused::WorseFolds { than_baseline, response_than_baseline, .. } => {
                assert_eq!((than_baseline, response_than_baseline), (vec![1], vec![1]));
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_refused_leader_says_which_folds_it_predicts_worse() {
        let units: Vec<usize> = (0..12).collect();
        // The second fold predicted worse than the baseline (and than the
        // model before it, here the baseline).
        let mut r = round(10.0, 2.0, 9.0, 10.0);
        let after: Vec<f64> = (0..12).map(|u| if u < 6 { 2.0 } else { 12.0 }).collect();
        r.refitted.1 = at(&after);
        r.refitted_levels.1 = r.refitted.1.clone();
        r.joint.1 = at(&after);
        assert_eq!(judge(std::slice::from_ref(&r), &halves(), &units, NULL, 1).0, 0);
        let expected = Refused::WorseFolds {
            than_baseline: vec![1],
            than_before: vec![1],
            response_than_baseline: vec![],
            response_over_every_fold: false,
        };
        assert_eq!(refusal(&r, &halves(), &units, NULL), expected);
        // Nothing closed beyond the noise: that is the reason, with the share.
        let r = round(10.0, 9.95, 9.97, 10.0);
        match refusal(&r, &halves(), &units, NULL) {
            Refused::NotBeyondNoise { share } => assert!(share > 0.0 && share < 0.01, "{share}"),
            other => panic!("{other:?}"),
        }
    }

    /// A model that predicts every fold's observables together better than
    /// the baseline but the response (peaks and phase) at one fold worse,
    /// beyond its noise, is not named: the response is what it would be
    /// used to predict. One that leaves that fold's response as it was, up
    /// to the noise, is.
    #[test]
    fn an_effect_that_predicts_one_folds_response_worse_is_not_named() {
        let units: Vec<usize> = (0..12).collect();
        let mut r = round(10.0, 2.0, 9.0, 10.0);
        r.joint_response = (at(&[1.0; 12]), at(&(0..12).map(|u| if u < 6 { 1.0 } else { 3.0 }).collect::<Vec<_>>()));
        assert_eq!(judge(std::slice::from_ref(&r), &halves(), &units, NULL, 1).0, 0);
        let expected = Refused::WorseFolds {
            than_baseline: vec![],
            than_before: vec![],
            response_than_baseline: vec![1],
            response_over_every_fold: true,
        };
        assert_eq!(refusal(&r, &halves(), &units, NULL), expected);
        r.joint_response.1 = at(&(0..12).map(|u| if u < 6 { 1.0 } else { 1.05 }).collect::<Vec<_>>());
        assert_eq!(judge(&[r], &halves(), &units, NULL, 1).0, 1);
    }

    /// A model that predicts the response a little worse at every fold,
    /// each rise within that fold's noise (a mean over 60 scores) but the
    /// rise over both together beyond the noise of a mean over 120, is not
    /// named: small folds must not let a model through by their width
    /// alone. A smaller rise, within the pooled noise too, is named.
    #[test]
    fn an_effect_that_predicts_the_response_worse_over_every_fold_together_is_not_named() {
        let units: Vec<usize> = (0..12).collect();
        let (fold_noise, pooled_noise) = (NULL.noise(60), NULL.noise(120));
        let rise = loss(1.6) - loss(1.0);
        assert!(rise < fold_noise && rise > pooled_noise, "{rise} {fold_noise} {pooled_noise}");
        let mut r = round(10.0, 2.0, 9.0, 10.0);
        r.joint_response = (at(&[1.0; 12]), at(&[1.6; 12]));
        assert_eq!(judge(std::slice::from_ref(&r), &halves(), &units, NULL, 1).0, 0);
        let expected = Refused::WorseFolds {
            than_baseline: vec![],
            than_before: vec![],
            response_than_baseline: vec![],
            response_over_every_fold: true,
        };
        assert_eq!(refusal(&r, &halves(), &units, NULL), expected);
        r.joint_response.1 = at(&[1.3; 12]);
        assert!(loss(1.3) - loss(1.0) < pooled_noise);
        assert_eq!(judge(&[r], &halves(), &units, NULL, 1).0, 1);
    }

    #[test]
    fn a_pair_is_judged_by_what_the_two_predict_together() {
        let units: Vec<usize> = (0..12).collect();
        // The first, fitted while the second is missing, trades the second
        // fold for the first (10 → 4 there, 10 → 12 here); with the
        // second on top both folds fall to 1.5, below the baseline's 10:
        // both named.
        let split: Vec<f64> = (0..12).map(|u| if u < 6 { 4.0 } else { 12.0 }).collect();
        let mut first = round(10.0, 7.0, 9.0, 10.0);
        first.refitted.1 = at(&split);
        first.refitted_levels.1 = first.refitted.1.clone();
        first.joint.1 = at(&split);
        let mut second = round(7.0, 1.5, 6.5, 10.0);
        second.refitted.0 = at(&split);
        second.refitted_levels.0 = second.refitted.0.clone();
        let rounds = [first, second];
        assert_eq!(judge(&rounds, &halves(), &units, NULL, 1).0, 2);
        // Alone, the first is not named.
        assert_eq!(judge(&rounds[..1], &halves(), &units, NULL, 1).0, 0);
        // A second that leaves the second fold worse than the baseline
        // (12 → 11) does not rescue the first.
        let [first, mut second] = rounds;
        let still: Vec<f64> = (0..12).map(|u| if u < 6 { 1.5 } else { 11.0 }).collect();
        second.refitted.1 = at(&still);
        second.refitted_levels.1 = second.refitted.1.clone();
        second.joint.1 = at(&still);
        assert_eq!(judge(&[first, second], &halves(), &units, NULL, 1).0, 0);
    }
}
