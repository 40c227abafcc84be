//! Cross-validation over the folds of a set, and the contest that names an
//! effect.
//!
//! Every model is judged by how well it predicts units it was not fitted
//! to: each fold's units in turn ([`crate::diagnose::data::Folds`]). A
//! family of an effect (every form the search tried, at every parameter
//! value it tried: its *pool*) predicts fold k with the member that fits
//! the other folds best, so a family is compared by what it explains out of
//! sample, not by how well one shape matches the data: with long records
//! every shape mismatch is tens of standard errors, and an exact-shape test
//! refuses every real rig's effect.
//!
//! The contest ([`contest`]) resamples the units (a bootstrap: whole
//! conditions drawn with replacement) and in each resample asks which family
//! closes the largest share of the current model's explainable
//! out-of-sample gap; it leads when that share is the largest and beyond
//! the noise and the gap stands above its noise. A fall is a paired
//! difference (both models scored against the same measured values), so
//! its noise is carried by the scores the change moved ([`moved`]): an
//! effect that shows at a few conditions is judged against their noise,
//! not diluted by every score it left alone. Which leaders are named,
//! and how sure that is, is [`super::verdict`]'s: the share of resamples
//! that give the same verdict, a probability over the conditions the data
//! happened to hold, discounted by what the named forms leave unexplained.

use std::collections::BTreeMap;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::diagnose::data::{Data, Folds};
use crate::diagnose::observable::Observable;
use crate::diagnose::score::Score;

/// Most of a gap: at least half of it. A named model that closes less of
/// the baseline's gap has its confidence scaled down in proportion.
pub(crate) const MOST: f64 = 0.5;

/// Bootstrap resamples of the contest.
pub(crate) const RESAMPLES: usize = 2000;

/// The loss of one z-score: ln(1 + (z/3)²), twice the negative
/// log-density (up to a constant) of a Cauchy model discrepancy of scale
/// three standard errors. Every model of a real rig misses some observables
/// by tens or thousands of standard errors (long records make every shape
/// mismatch that large), and under a heavy-tailed discrepancy a miss beyond
/// three standard errors counts by its order of magnitude: a z of 8 000
/// counts about three times a z of 30, not 270 times, so an observable that
/// no candidate form can reach does not hide what another effect explains.
/// Within three standard errors it is about z²/9, as a Gaussian's.
pub(crate) fn loss(z: f64) -> f64 {
    (z * z / (DISCREPANCY_SCALE * DISCREPANCY_SCALE)).ln_1p()
}

/// The scale of the model discrepancy in [`loss`], in standard errors: the
/// three beyond which a difference is unlikely to be noise.
pub(crate) const DISCREPANCY_SCALE: f64 = 3.0;

/// The loss a unit's observable counts when a model gives it no value (its
/// simulated records never show it, e.g. friction features of a block that
/// never slips): that of a z of 10.
fn missing_loss() -> f64 {
    loss(10.0)
}

/// The mean and standard deviation of [`loss`] for a model that is right:
/// z is then Student's t with R − 1 degrees of freedom for R simulated
/// replicates (the spread is estimated from them), –.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NullLoss {
    pub(crate) mean: f64,
    pub(crate) sd: f64,
}

impl NullLoss {
    /// For z-scores from `replicates` simulated replicates, by quadrature of
    /// [`loss`] against Student's t density with `replicates − 1` degrees of
    /// freedom (x = tan θ over (−π/2, π/2)).
    pub(crate) fn for_replicates(replicates: u32) -> NullLoss {
        use statrs::distribution::{Continuous, StudentsT};
        let nu = f64::from(replicates.max(2) - 1);
        let t = StudentsT::new(0.0, 1.0, nu).expect("a valid Student's t");
        let n = 4000;
        let (mut m1, mut m2) = (0.0, 0.0);
        let h = std::f64::consts::PI / n as f64;
        for i in 0..n {
            let theta = -std::f64::consts::FRAC_PI_2 + (i as f64 + 0.5) * h;
            let x = theta.tan();
            let w = t.pdf(x) * (1.0 + x * x) * h;
            let l = loss(x);
            m1 += w * l;
            m2 += w * l * l;
        }
        NullLoss { mean: m1, sd: (m2 - m1 * m1).max(0.0).sqrt() }
    }

    /// The noise a mean of `k` losses must rise above (or fall by) to be
    /// more than noise: three standard deviations of that mean, counted as
    /// if only half of the scores were independent (a unit's observables
    /// move together), –.
    pub(crate) fn noise(&self, k: usize) -> f64 {
        3.0 * self.sd * (2.0 / k.max(1) as f64).sqrt()
    }

    /// The noise a fall in the mean of `scores` losses must exceed when a
    /// change moved `moved` of them ([`moved`]): three standard deviations
    /// of a sum of that many paired differences (each as wide as
    /// [`NullLoss::noise`] counts a score), over `scores`. With every score
    /// moved it is [`NullLoss::noise`] itself; never below that of one
    /// whole score, –.
    pub(crate) fn fall_noise(&self, scores: f64, moved: f64) -> f64 {
        let scores = scores.max(1.0);
        if moved >= scores {
            return self.noise(scores.round() as usize);
        }
        3.0 * self.sd * (2.0 * moved.max(1.0)).sqrt() / scores
    }
}

/// A model's loss at one unit: the sum of its scores' losses over the
/// unit's measured observables ([`loss`]), how many there are, and, where
/// it is one of a pair of models measured in one yardstick
/// ([`pair_losses`]), how many of them the change between the two moved
/// ([`moved`]; all of them otherwise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct UnitLoss {
    pub(crate) sum: f64,
    pub(crate) scores: usize,
    pub(crate) moved: f64,
}

impl UnitLoss {
    /// `scores` scores whose losses add to `sum`, every one counted as moved.
    pub(crate) fn whole(sum: f64, scores: usize) -> UnitLoss {
        UnitLoss { sum, scores, moved: scores as f64 }
    }
}

/// A model's loss at each unit.
pub(crate) type UnitLosses = BTreeMap<usize, UnitLoss>;

/// `losses` with every score counted as moved: a fall between them and
/// another model's is then judged against the noise of every score
/// ([`NullLoss::noise`]), as an effect that matters across the set must
/// stand out at the set's scale.
pub(crate) fn unpaired(losses: &UnitLosses) -> UnitLosses {
    losses.iter().map(|(&u, l)| (u, UnitLoss::whole(l.sum, l.scores))).collect()
}

/// How much one score counts towards the noise of a fall in loss when a
/// change moves its prediction by `shift` standard errors: the square of
/// the shift, up to 1. The two models' losses at a score see the same
/// measured value, so the difference between them carries that value's
/// noise only in proportion to how far the prediction moved (the loss's
/// slope is at most 1/3 per standard error): a score the change left where
/// it was adds no noise to the fall, and one moved by a standard error or
/// more adds about what an unpaired difference of losses would. An effect
/// that shows at a few conditions is then judged against the noise of the
/// scores it moved, not diluted by every score it left alone.
pub(crate) fn moved(shift: f64) -> f64 {
    if shift.is_finite() { (shift * shift).min(1.0) } else { 1.0 }
}

/// The losses at every unit of `data` of a model before a change
/// (`before`) and after it (`after`), measured in one yardstick: each
/// (unit, observable) in the spread of measured − simulated under the model
/// after the change (at least a tenth of the spread before it, so that a
/// model whose own spread is degenerate cannot make every departure
/// infinitely large). In a shared yardstick a model cannot close the gap by
/// widening its own simulated spread (a strongly coloured noise widens
/// every simulated distribution and would look closer to the data
/// everywhere by its own z): both models are measured in its wider units,
/// so it must move what it predicts towards the data. And a model whose
/// prediction of an observable is rightly uncertain (the kurtosis of a
/// heavy-tailed friction noise varies a lot from record to record) is
/// asked whether the data are closer to what it predicts than to what the
/// model before it predicts, in its own units, not in the narrow units of
/// a model that cannot produce that value at all. A measured observable
/// without a score counts [`missing_loss`].
pub(crate) fn pair_losses(before: &[Score], after: &[Score], data: &Data<'_>) -> (UnitLosses, UnitLosses) {
    pair_losses_of(before, after, data, |_| true)
}

/// [`pair_losses`] over the observables `keep` selects alone.
pub(crate) fn pair_losses_of(
    before: &[Score],
    after: &[Score],
    data: &Data<'_>,
    keep: fn(Observable) -> bool,
) -> (UnitLosses, UnitLosses) {
    let key = |s: &Score| (s.unit, s.observable);
    let scale_before: BTreeMap<(usize, Observable), f64> = before.iter().map(|s| (key(s), s.scale)).collect();
    let scale_after: BTreeMap<(usize, Observable), f64> = after.iter().map(|s| (key(s), s.scale)).collect();
    let ruler = |k: &(usize, Observable)| {
        let before = scale_before.get(k).copied().unwrap_or(0.0);
        scale_after.get(k).copied().unwrap_or(before).max(0.1 * before)
    };
    let zs = |scores: &[Score]| -> BTreeMap<(usize, Observable), f64> {
        scores
            .iter()
            .map(|s| {
                let r = ruler(&key(s));
                (key(s), if r > 0.0 && s.scale > 0.0 { s.z * s.scale / r } else { s.z })
            })
            .collect()
    };
    let (z_before, z_after) = (zs(before), zs(after));
    // Per score: how much the change moved it (a score one model gives no
    // value counts as moved).
    let shift = |k: &(usize, Observable)| match (z_before.get(k), z_after.get(k)) {
        (Some(b), Some(a)) => moved(b - a),
        _ => 1.0,
    };
    let losses = |z: &BTreeMap<(usize, Observable), f64>| -> BTreeMap<(usize, Observable), (f64, f64)> {
        z.iter().map(|(k, &z)| (*k, (loss(z), shift(k)))).collect()
    };
    (per_unit(&losses(&z_before), data, keep), per_unit(&losses(&z_after), data, keep))
}

/// The losses of a model's `scores` in its own scales (its z-scores).
pub(crate) fn own_losses(scores: &[Score], data: &Data<'_>) -> UnitLosses {
    own_losses_of(scores, data, |_| true)
}

/// [`own_losses`] over the observables `keep` selects alone.
pub(crate) fn own_losses_of(scores: &[Score], data: &Data<'_>, keep: fn(Observable) -> bool) -> UnitLosses {
    per_unit(&scores.iter().map(|s| ((s.unit, s.observable), (loss(s.z), 1.0))).collect(), data, keep)
}

/// Per-score losses (with how much each was moved) summed by unit over the
/// unit's measured observables that `keep` selects.
fn per_unit(
    by: &BTreeMap<(usize, Observable), (f64, f64)>,
    data: &Data<'_>,
    keep: fn(Observable) -> bool,
) -> UnitLosses {
    (0..data.units.len())
        .map(|u| {
            let mut at = UnitLoss::whole(0.0, 0);
            for &o in data.measured[u].keys().filter(|&&o| keep(o)) {
                let (l, m) = by.get(&(u, o)).copied().unwrap_or_else(|| (missing_loss(), 1.0));
                at.sum += l;
                at.scores += 1;
                at.moved += m;
            }
            (u, at)
        })
        .filter(|(_, at)| at.scores > 0)
        .collect()
}

/// The mean loss over `units` of `losses` (0 for none).
pub(crate) fn mean_loss(losses: &UnitLosses, units: impl Iterator<Item = usize>) -> f64 {
    let (sum, n) = units.filter_map(|u| losses.get(&u)).fold((0.0, 0usize), |(s, n), l| (s + l.sum, n + l.scores));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// Every unit some fold holds out.
pub(crate) fn held_units(folds: &Folds) -> Vec<usize> {
    let mut units: Vec<usize> = folds.folds.iter().flat_map(|f| f.units.iter().copied()).collect();
    units.sort_unstable();
    units
}

/// Out of sample, a family predicts each fold's units with the member of
/// its `pool` that closes the largest share of the current model's gap at
/// the units the fold does not hold out (each member's losses, and the
/// current model's in the same yardstick, at every unit; see
/// [`pair_losses`]): the held-out units' losses so predicted, the current
/// model's there in the same yardsticks, and the member chosen for each fold
/// (its index in the pool). Empty without members.
pub(crate) fn pool_predictions(
    pool: &[(UnitLosses, UnitLosses)],
    folds: &Folds,
) -> (UnitLosses, UnitLosses, Vec<usize>) {
    let (mut out, mut reference) = (UnitLosses::new(), UnitLosses::new());
    let picks = fold_picks(pool, folds, |_| true);
    for (fold, &best) in folds.folds.iter().zip(&picks) {
        for &u in &fold.units {
            if let (Some(&l), Some(&c)) = (pool[best].0.get(&u), pool[best].1.get(&u)) {
                out.insert(u, l);
                reference.insert(u, c);
            }
        }
    }
    (out, reference, picks)
}

/// Per fold, the member of `pool` (of those `eligible` takes) that closes
/// the largest share of the current model's gap at the units the fold does
/// not hold out (see [`pool_predictions`]); none where no member is
/// eligible.
pub(crate) fn fold_picks(
    pool: &[(UnitLosses, UnitLosses)],
    folds: &Folds,
    eligible: impl Fn(usize) -> bool,
) -> Vec<usize> {
    let members: Vec<usize> = (0..pool.len()).filter(|&i| eligible(i)).collect();
    folds
        .folds
        .iter()
        .map(|fold| {
            let training = |(member, current): &(UnitLosses, UnitLosses)| {
                let units = || member.keys().copied().filter(|u| !fold.units.contains(u));
                mean_loss(member, units()) / mean_loss(current, units()).max(1e-12)
            };
            members.iter().copied().min_by(|&a, &b| training(&pool[a]).total_cmp(&training(&pool[b])))
        })
        .collect::<Option<Vec<usize>>>()
        .unwrap_or_default()
}

/// The losses at the held-out units of fold models: `per_fold[k]` is the
/// model fitted without fold k, whose losses at that fold's units are kept.
pub(crate) fn fold_predictions(per_fold: &[UnitLosses], folds: &Folds) -> UnitLosses {
    let mut out = UnitLosses::new();
    for (fold, losses) in folds.folds.iter().zip(per_fold) {
        for &u in &fold.units {
            if let Some(&l) = losses.get(&u) {
                out.insert(u, l);
            }
        }
    }
    out
}

/// Gaps out of sample with the units weighted by `w` (a resample's
/// counts): the mean loss, the weighted number of scores behind it, and how
/// many of them were moved.
fn weighted_gap(losses: &UnitLosses, units: &[usize], w: &[f64]) -> (f64, f64, f64) {
    let (mut sum, mut n, mut moved) = (0.0, 0.0, 0.0);
    for (&u, &wu) in units.iter().zip(w) {
        if let Some(l) = losses.get(&u) {
            sum += wu * l.sum;
            n += wu * l.scores as f64;
            moved += wu * l.moved;
        }
    }
    (if n > 0.0 { sum / n } else { 0.0 }, n, moved)
}

/// One family in a round: its out-of-sample losses, and the current
/// model's in the same yardsticks.
#[derive(Clone, Copy)]
pub(crate) struct Entrant<'a> {
    pub(crate) losses: &'a UnitLosses,
    pub(crate) reference: &'a UnitLosses,
}

/// One weighting of the units (a bootstrap resample's counts) and what it
/// is judged against.
pub(crate) struct Weights<'a> {
    pub(crate) units: &'a [usize],
    pub(crate) w: &'a [f64],
    pub(crate) null: NullLoss,
}

impl Weights<'_> {
    /// A model's mean loss and the weighted number of scores behind it.
    pub(crate) fn gap(&self, losses: &UnitLosses) -> (f64, f64) {
        let (gap, n, _) = weighted_gap(losses, self.units, self.w);
        (gap, n)
    }

    /// How many scores a pair's `losses` hold and how many of them the
    /// change moved ([`moved`]), weighted.
    pub(crate) fn moved(&self, losses: &UnitLosses) -> (f64, f64) {
        let (_, n, moved) = weighted_gap(losses, self.units, self.w);
        (moved, n)
    }

    /// The noise threshold of a gap over `n` weighted scores.
    pub(crate) fn noise(&self, n: f64) -> f64 {
        self.null.noise(n.round().max(1.0) as usize)
    }

    /// Whether the `current` model's gap stands above its noise.
    pub(crate) fn above_noise(&self, current: &UnitLosses) -> bool {
        let (gap, n) = self.gap(current);
        gap - self.null.mean > self.noise(n)
    }

    /// The share of `reference`'s explainable gap (above the null loss)
    /// that `losses` close, and whether that fall is beyond the noise of a
    /// paired difference ([`NullLoss::fall_noise`]: the scores the change
    /// moved carry it). An explainable gap is counted as at least its noise
    /// threshold: one within its noise cannot be told from none, and a
    /// share of it would be a ratio of noises, without bound.
    pub(crate) fn share(&self, losses: &UnitLosses, reference: &UnitLosses) -> (f64, bool) {
        let (r, n) = self.gap(reference);
        let (l, _, moved) = weighted_gap(losses, self.units, self.w);
        ((r - l) / (r - self.null.mean).max(self.noise(n)), r - l > self.null.fall_noise(n, moved))
    }

    /// The entrant that closes the largest share of the current model's
    /// gap, when that gap and the fall stand above the noise.
    pub(crate) fn leader(&self, current: &UnitLosses, entrants: &[Entrant<'_>]) -> Option<(usize, f64)> {
        if !self.above_noise(current) {
            return None;
        }
        let shares: Vec<(f64, bool)> = entrants.iter().map(|e| self.share(e.losses, e.reference)).collect();
        let best = (0..entrants.len()).max_by(|&a, &b| shares[a].0.total_cmp(&shares[b].0))?;
        shares[best].1.then_some((best, shares[best].0))
    }
}

/// What one round's contest found.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Contest {
    /// The share of resamples each entrant led, in entrant order.
    pub(crate) leads: Vec<f64>,
    /// The share of resamples in which the current model's gap stood within
    /// its noise of the floor (nothing to explain): how sure "the current
    /// model explains the data" is.
    pub(crate) fits: f64,
    /// Without resampling: each entrant's share of the current model's
    /// explainable gap (its out-of-sample gap less the null loss, in the
    /// entrant's yardstick).
    pub(crate) shares: Vec<f64>,
    /// Without resampling: the leader, if any.
    pub(crate) leader: Option<usize>,
    /// Without resampling: the current model's gap out of sample and its
    /// noise threshold.
    pub(crate) gap: f64,
    pub(crate) noise: f64,
}

/// [`RESAMPLES`] bootstrap weightings of `n` units (counts of each unit in
/// a draw of `n` with replacement), from `seed`.
pub(crate) fn resamples(n: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..RESAMPLES)
        .map(|_| {
            let mut w = vec![0.0; n];
            for _ in 0..n {
                w[rng.random_range(0..n)] += 1.0;
            }
            w
        })
        .collect()
}

/// One round's contest of `entrants` against the `current` model's
/// out-of-sample losses over the held-out `units`: who leads without
/// resampling and how often each leads over [`resamples`] from `seed`;
/// `null` is the loss of a model that is right.
pub(crate) fn contest(
    current: &UnitLosses,
    entrants: &[Entrant<'_>],
    units: &[usize],
    null: NullLoss,
    seed: u64,
) -> Contest {
    let ones = vec![1.0; units.len()];
    let point = Weights { units, w: &ones, null };
    let shares: Vec<f64> = entrants.iter().map(|e| point.share(e.losses, e.reference).0).collect();
    let (gap, n) = point.gap(current);
    let mut leads = vec![0usize; entrants.len()];
    let mut fits = 0usize;
    for w in resamples(units.len(), seed) {
        let weights = Weights { units, w: &w, null };
        if let Some((i, _)) = weights.leader(current, entrants) {
            leads[i] += 1;
        }
        if !weights.above_noise(current) {
            fits += 1;
        }
    }
    let share = |k: usize| k as f64 / RESAMPLES as f64;
    Contest {
        leads: leads.into_iter().map(share).collect(),
        fits: share(fits),
        shares,
        leader: point.leader(current, entrants).map(|(i, _)| i),
        gap,
        noise: point.noise(n),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Losses of `k` scores per unit at z-score `z` for units 0..n.
    fn at(z: &[f64]) -> UnitLosses {
        z.iter().enumerate().map(|(u, &z)| (u, UnitLoss::whole(10.0 * loss(z), 10))).collect()
    }

    /// `n` folds, fold k holding out unit k.
    pub(crate) fn one_unit_folds(n: usize) -> Folds {
        use crate::diagnose::data::{Fold, FoldKind};
        let fold = |u: usize| Fold { label: format!("{u}"), units: vec![u], conditions: Vec::new() };
        Folds { kind: FoldKind::LoadLevels, folds: (0..n).map(fold).collect() }
    }

    const NULL: NullLoss = NullLoss { mean: 0.18, sd: 0.32 };
    /// (mean, sd) of ln(1 + (z/3)²) by Monte Carlo (two million draws).
    const GAUSS: (f64, f64) = (0.0969, 0.1228);
    const T3: (f64, f64) = (0.1797, 0.3198);
    const T7: (f64, f64) = (0.1241, 0.1815);

    #[test]
    fn the_null_loss_is_that_of_students_t() {
        // Monte Carlo values of ln(1 + (z/3)²) (two million draws): for a
        // Gaussian z, for t with 3 degrees of freedom, and with 7.
        let close = |n: NullLoss, m: f64, s: f64| (n.mean - m).abs() < 0.003 && (n.sd - s).abs() < 0.006;
        assert!(close(NullLoss::for_replicates(100_000), GAUSS.0, GAUSS.1), "{:?}", NullLoss::for_replicates(100_000));
        assert!(close(NullLoss::for_replicates(4), T3.0, T3.1), "{:?}", NullLoss::for_replicates(4));
        assert!(close(NullLoss::for_replicates(8), T7.0, T7.1), "{:?}", NullLoss::for_replicates(8));
    }

    #[test]
    fn the_family_that_closes_most_leads_and_nothing_leads_within_noise() {
        let units: Vec<usize> = (0..12).collect();
        let current = at(&[8.0; 12]);
        let good = at(&[2.0; 12]);
        let weak = at(&[6.5; 12]);
        let entrants = [Entrant { losses: &weak, reference: &current }, Entrant { losses: &good, reference: &current }];
        let c = contest(&current, &entrants, &units, NULL, 1);
        assert_eq!(c.leader, Some(1));
        assert!(c.leads[1] > 0.99, "{c:?}");
        assert!(c.shares[1] > 0.8 && c.shares[0] < 0.3, "{c:?}");
        assert_eq!(c.fits, 0.0);
        // A current model within noise: nothing to explain.
        let fits = at(&[1.0; 12]);
        let better = at(&[0.5; 12]);
        let c = contest(&fits, &[Entrant { losses: &better, reference: &fits }], &units, NULL, 1);
        assert_eq!(c.leader, None);
        assert!(c.fits > 0.99, "{c:?}");
    }

    /// A reference (the current model in an entrant's yardstick) within
    /// its noise of a right model's loss has no gap to speak of: what an
    /// entrant closes of it is a share of at most the fall over the noise
    /// threshold, never the ratio of two noises.
    #[test]
    fn a_gap_within_its_noise_is_not_a_denominator() {
        let units: Vec<usize> = (0..12).collect();
        let ones = vec![1.0; 12];
        let w = Weights { units: &units, w: &ones, null: NULL };
        // A reference a hair above the floor, and an entrant below it.
        let z_at = |l: f64| 3.0 * (l.exp() - 1.0).sqrt();
        let reference = at(&[z_at(NULL.mean + 1e-9); 12]);
        let entrant = at(&[z_at(NULL.mean - 0.05); 12]);
        let (share, _) = w.share(&entrant, &reference);
        let noise = w.noise(120.0);
        assert!((share - 0.05 / noise).abs() < 1e-6, "{share} against {}", 0.05 / noise);
        // Above the noise the share is of the explainable gap itself.
        let current = at(&[z_at(NULL.mean + 3.0 * noise); 12]);
        let halfway = at(&[z_at(NULL.mean + 1.5 * noise); 12]);
        assert!((w.share(&halfway, &current).0 - 0.5).abs() < 1e-9);
    }

    /// A change that lowers the loss at two units of twelve and leaves the
    /// rest where they were: against the noise of every score the fall is
    /// noise, against that of the scores it moved it is not. The same fall
    /// spread as a small shift of every score is not beyond the noise.
    #[test]
    fn a_fall_at_the_few_scores_a_change_moved_is_judged_against_their_noise() {
        let units: Vec<usize> = (0..12).collect();
        let ones = vec![1.0; 12];
        let w = Weights { units: &units, w: &ones, null: NULL };
        let reference: UnitLosses =
            (0..12).map(|u| (u, UnitLoss { moved: 0.0, ..UnitLoss::whole(10.0 * 0.5, 10) })).collect();
        // Units 0 and 1 fall from 0.5 to 0.1 per score, every score moved;
        // the others are untouched.
        let local: UnitLosses = (0..12)
            .map(|u| {
                (u, if u < 2 { UnitLoss::whole(10.0 * 0.1, 10) } else { UnitLoss { moved: 0.0, ..reference[&u] } })
            })
            .collect();
        let fall = 2.0 * 10.0 * 0.4 / 120.0;
        assert!(fall < NULL.noise(120), "{fall} {}", NULL.noise(120));
        let (share, beyond) = w.share(&local, &reference);
        assert!(beyond && share > 0.0, "{share}");
        // The same fall everywhere as a shift of every score by a standard
        // error or more: judged against every score's noise.
        let everywhere: UnitLosses = (0..12).map(|u| (u, UnitLoss::whole(10.0 * (0.5 - fall), 10))).collect();
        assert!(!w.share(&everywhere, &reference).1);
        // Fully moved, the paired noise is the unpaired one.
        assert_eq!(NULL.fall_noise(120.0, 120.0), NULL.noise(120));
        assert_eq!(moved(0.0), 0.0);
        assert_eq!(moved(0.5), 0.25);
        assert_eq!(moved(-3.0), 1.0);
    }

    #[test]
    fn two_families_that_close_about_as_much_share_the_lead() {
        let units: Vec<usize> = (0..12).collect();
        let current = at(&[6.0; 12]);
        let a: Vec<f64> = (0..12).map(|u| if u % 2 == 0 { 2.0 } else { 5.0 }).collect();
        let b: Vec<f64> = (0..12).map(|u| if u % 2 == 1 { 2.0 } else { 5.0 }).collect();
        let (a, b) = (at(&a), at(&b));
        let c = contest(
            &current,
            &[Entrant { losses: &a, reference: &current }, Entrant { losses: &b, reference: &current }],
            &units,
            NULL,
            3,
        );
        assert!(c.leads[0] > 0.2 && c.leads[1] > 0.2, "{c:?}");
    }

    #[test]
    fn each_fold_is_predicted_by_the_member_that_fits_the_other_folds() {
        let folds = one_unit_folds(2);
        // Member 0 fits unit 0 and misses unit 1; member 1 the reverse.
        let current = at(&[5.0, 5.0]);
        let pool = vec![(at(&[0.0, 5.0]), current.clone()), (at(&[5.0, 0.0]), current.clone())];
        let (predicted, reference, picks) = pool_predictions(&pool, &folds);
        // Fold 0 (unit 0 held out) trains on unit 1: member 1, which misses unit 0.
        assert_eq!(picks, vec![1, 0]);
        assert_eq!(predicted[&0], pool[1].0[&0]);
        assert_eq!(predicted[&1], pool[0].0[&1]);
        assert_eq!(reference[&0], current[&0]);
    }

    /// A fold's pick is made among the eligible members alone (a family's
    /// named form), by the same fit to the other folds; none is made where
    /// no member is eligible.
    #[test]
    fn fold_picks_choose_among_the_eligible_members() {
        let folds = one_unit_folds(2);
        let current = at(&[5.0, 5.0]);
        // Member 0 fits both folds' other units best; members 1 and 2 are
        // the eligible ones, 1 closer at unit 1 and 2 closer at unit 0.
        let pool = vec![
            (at(&[0.0, 0.0]), current.clone()),
            (at(&[4.0, 1.0]), current.clone()),
            (at(&[1.0, 4.0]), current.clone()),
        ];
        assert_eq!(fold_picks(&pool, &folds, |_| true), vec![0, 0]);
        assert_eq!(fold_picks(&pool, &folds, |i| i > 0), vec![1, 2]);
        assert!(fold_picks(&pool, &folds, |_| false).is_empty());
    }
}
