//! The verdict: which of the effects a forward selection added are named,
//! and how sure that is.
//!
//! The selection walks rounds: in each, the family that closes the largest
//! share of what the model so far leaves out of sample leads, and is added.
//! The verdict names the leading families of the first rounds while
//!
//! - the first closes a share of the baseline's gap beyond the noise,
//! - every further one closes at least half of what the ones before it
//!   left (an effect added on top of another must explain most of what is
//!   left, not a sliver of the first one's form misfit), both among the
//!   families' own members fold by fold and refitted from scratch without
//!   each fold,
//! - and together they close at least half of the baseline's
//!   out-of-sample gap (most of it), refitted without each fold.
//!
//! So one effect is named when it explains most of the gap alone, and two
//! when the first explains the largest share and the second most of what
//! the first left: two effects of about equal weight, of which neither
//! explains half alone, are named together. The confidence is the share of
//! bootstrap resamples of the conditions that give the same verdict.

use crate::diagnose::search::cv::{Entrant, MOST, NullLoss, UnitLosses, Weights, resamples};

/// One round of the selection as the verdict reads it.
pub(crate) struct Round {
    /// The current model's own losses at the held-out units (the model of
    /// the rounds before, fitted to every unit).
    pub(crate) current: UnitLosses,
    /// Every family's out-of-sample losses and the current model's in the
    /// same yardsticks.
    pub(crate) entrants: Vec<(UnitLosses, UnitLosses)>,
    /// Which entrant led.
    pub(crate) leader: usize,
    /// The models before and after the leader, refitted without each fold,
    /// at each fold's units, in the latter's yardstick.
    pub(crate) refitted: (UnitLosses, UnitLosses),
    /// The baseline and the models after the leader, refitted without each
    /// fold, at each fold's units, in the latter's yardstick.
    pub(crate) joint: (UnitLosses, UnitLosses),
}

/// How many of `rounds`' leaders one weighting of the units names (0:
/// none; see the module).
pub(crate) fn named(rounds: &[Round], weights: &Weights<'_>) -> usize {
    let mut n = 0;
    for (j, r) in rounds.iter().enumerate() {
        let entrants: Vec<Entrant<'_>> =
            r.entrants.iter().map(|(losses, reference)| Entrant { losses, reference }).collect();
        let Some((leader, share)) = weights.leader(&r.current, &entrants) else { break };
        if leader != r.leader {
            break;
        }
        let (refitted, beyond) = weights.share(&r.refitted.1, &r.refitted.0);
        let holds = if j == 0 { refitted > 0.0 && beyond } else { share >= MOST && refitted >= MOST };
        if !holds {
            break;
        }
        n = j + 1;
    }
    while n > 0 && weights.share(&rounds[n - 1].joint.1, &rounds[n - 1].joint.0).0 < MOST {
        n -= 1;
    }
    n
}

/// The verdict over `rounds`: how many leaders are named without
/// resampling, the share of resamples (from `seed`) that name exactly as
/// many, and for each round the share that name its leader at least.
pub(crate) fn judge(rounds: &[Round], units: &[usize], null: NullLoss, seed: u64) -> (usize, f64, Vec<f64>) {
    let ones = vec![1.0; units.len()];
    let point = named(rounds, &Weights { units, w: &ones, null });
    let mut same = 0usize;
    let mut at_least = vec![0usize; rounds.len()];
    let draws = resamples(units.len(), seed);
    for w in &draws {
        let n = named(rounds, &Weights { units, w, null });
        if n == point {
            same += 1;
        }
        for slot in &mut at_least[..n] {
            *slot += 1;
        }
    }
    let share = |k: usize| k as f64 / draws.len() as f64;
    (point, share(same), at_least.into_iter().map(share).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::search::cv::loss;

    const NULL: NullLoss = NullLoss { mean: 0.18, sd: 0.32 };

    fn at(z: &[f64]) -> UnitLosses {
        z.iter().enumerate().map(|(u, &z)| (u, (10.0 * loss(z), 10))).collect()
    }

    /// A round whose current model misses by `before` everywhere, whose
    /// leader (of two) leaves `after`, its rival `rival`, refitted alike;
    /// the baseline misses by `baseline`.
    fn round(before: f64, after: f64, rival: f64, baseline: f64) -> Round {
        let n = 12;
        Round {
            current: at(&vec![before; n]),
            entrants: vec![(at(&vec![after; n]), at(&vec![before; n])), (at(&vec![rival; n]), at(&vec![before; n]))],
            leader: 0,
            refitted: (at(&vec![before; n]), at(&vec![after; n])),
            joint: (at(&vec![baseline; n]), at(&vec![after; n])),
        }
    }

    #[test]
    fn one_effect_that_explains_most_is_named_alone() {
        let units: Vec<usize> = (0..12).collect();
        // z 10 → 2: most of the gap; the next round finds nothing that
        // closes half of what is left.
        let rounds = [round(10.0, 2.0, 9.0, 10.0), round(2.0, 1.8, 1.9, 10.0)];
        let (n, confidence, each) = judge(&rounds, &units, NULL, 1);
        assert_eq!(n, 1);
        assert!(confidence > 0.95 && each[0] > 0.95, "{confidence} {each:?}");
    }

    #[test]
    fn two_effects_of_which_neither_explains_half_alone_are_named_together() {
        let units: Vec<usize> = (0..12).collect();
        // The first closes about a third (z 10 → 6); the second, on top,
        // most of what is left (6 → 1.5): together most of the gap.
        let rounds = [round(10.0, 6.0, 7.0, 10.0), round(6.0, 1.5, 5.5, 10.0)];
        assert_eq!(judge(&rounds, &units, NULL, 1).0, 2);
        // Without the second, the first alone is not named.
        assert_eq!(judge(&rounds[..1], &units, NULL, 1).0, 0);
        // Nor when the second closes only a sliver of what is left.
        let rounds = [round(10.0, 6.0, 7.0, 10.0), round(6.0, 5.0, 5.5, 10.0)];
        assert_eq!(judge(&rounds, &units, NULL, 1).0, 0);
    }
}
