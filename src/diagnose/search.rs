//! Attribution and verdict: each candidate's strength is searched with the
//! baseline recalibrated at every trial, and the best candidate is the
//! verdict only if it lowers both the held-out and the fitting gaps by more
//! than their noise.

use crate::diagnose::calibrate::calibrate_and_score;
use crate::diagnose::candidates::CandidateSpec;
use crate::diagnose::data::Data;
use crate::diagnose::score::{Score, count_of, gap_of};
use crate::diagnose::{Candidate, DiagnoseSettings, Unexplained};
use crate::engine::{Effect, Engine, Model};
use crate::error::Result;

/// The best trial so far: (gap on the fitting units, calibrated model,
/// scores, strength, second parameter).
type Trial = (f64, Model, Vec<Score>, f64, f64);

/// Prints one trial's gap and worst observables (`STICKSLIP_DEBUG=1`).
fn debug_trial(effect: Effect, s: f64, t: f64, trial: &Model, scores: &[Score], g: f64) {
    let mut w: Vec<&Score> = scores.iter().filter(|s| !s.heldout).collect();
    w.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
    let top: Vec<String> = w
        .iter()
        .take(6)
        .map(|s| {
            format!(
                "{}@{:.1}N {:+.1} (m {:.3e} s {:.3e})",
                s.observable, s.normal_force_n, s.z, s.measured, s.simulated
            )
        })
        .collect();
    eprintln!(
        "{effect} {s:e} {t:e}: a {:.4} b {:.4} sigma {:.4} gap {g:.2} | {}",
        trial.friction.a,
        trial.friction.b,
        trial.friction.sigma,
        top.join("; ")
    );
}

/// Searches one candidate's strength (and second parameter) on a grid, then
/// halfway to each neighbour of the best strength. `None` when no trial
/// gives a valid model.
pub(crate) fn fit_candidate(
    spec: &CandidateSpec,
    baseline: &Model,
    baseline_gaps: (f64, f64),
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Option<Candidate>> {
    let (g0_fit, g0_ho) = baseline_gaps;
    let mut best: Option<Trial> = None;
    let trial_at = |s: f64, t: f64, best: &mut Option<Trial>| -> Result<()> {
        let trial = (spec.apply)(baseline, s, t);
        if trial.validate().is_err() {
            return Ok(());
        }
        let (trial, scores, _) = calibrate_and_score(&trial, data, settings, engine, Some(slope))?;
        let g = gap_of(&scores, false);
        if std::env::var_os("STICKSLIP_DEBUG").is_some() {
            debug_trial(spec.effect, s, t, &trial, &scores, g);
        }
        if best.as_ref().is_none_or(|b| g < b.0) {
            *best = Some((g, trial, scores, s, t));
        }
        Ok(())
    };
    for &t in &spec.second {
        for &s in &spec.grid {
            trial_at(s, t, &mut best)?;
        }
    }
    // Refine: halfway to each neighbour of the best strength.
    if let Some((at, t)) = best.as_ref().map(|b| (b.3, b.4)) {
        if let Some(i) = spec.grid.iter().position(|&g| g == at) {
            let neighbours = [i.checked_sub(1).map(|j| spec.grid[j]), spec.grid.get(i + 1).copied()];
            for n in neighbours.into_iter().flatten() {
                trial_at(0.5 * (at + n), t, &mut best)?;
            }
        }
    }
    let Some((g1_fit, model, scores, _, _)) = best else { return Ok(None) };
    let g1_ho = gap_of(&scores, true);
    let mut worst: Vec<&Score> = scores.iter().collect();
    worst.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
    let unexplained = worst
        .iter()
        .take(5)
        .map(|s| Unexplained {
            observable: s.observable,
            excitation_frequency_hz: s.excitation_frequency_hz,
            normal_force_n: s.normal_force_n,
            z: s.z,
        })
        .collect();
    Ok(Some(Candidate {
        unexplained,
        effect: spec.effect,
        gap_fit: g1_fit,
        gap_heldout: g1_ho,
        shrink: if g0_fit > 0.0 { (g0_fit - g1_fit) / g0_fit } else { 0.0 },
        heldout_shrink: (data.has_heldout() && g0_ho > 0.0).then(|| (g0_ho - g1_ho) / g0_ho),
        parameters: (spec.describe)(&model),
        model,
    }))
}

/// The verdict on ranked candidates.
pub(crate) struct Verdict {
    /// The effect named, `None` when the baseline explains the data.
    pub(crate) effect: Option<Effect>,
    pub(crate) confidence: f64,
    /// What the held-out (or, without held-out units, the fitting) gap had
    /// to fall by.
    pub(crate) noise_threshold: f64,
}

/// Ranks `candidates` (best first) and decides: the best is the verdict
/// only if it lowers both the held-out and the fitting gaps by more than
/// their noise, 3·sqrt(2/k) + 0.5 for k scored entries.
pub(crate) fn decide(candidates: &mut [Candidate], baseline_scores: &[Score], has_heldout: bool) -> Verdict {
    let (g0_fit, g0_ho) = (gap_of(baseline_scores, false), gap_of(baseline_scores, true));
    // Rank by held-out gap where there is one, else by the fitting gap.
    let key = |c: &Candidate| if has_heldout { c.gap_heldout } else { c.gap_fit };
    candidates.sort_by(|a, b| key(a).total_cmp(&key(b)));
    let k_ho = count_of(baseline_scores, has_heldout).max(1) as f64;
    // The noise of a mean of k values of z² is about sqrt(2/k): the held-out
    // improvement must beat three of those plus a margin of 0.5 for the
    // replicate estimate of each z's spread.
    let noise_threshold = 3.0 * (2.0 / k_ho).sqrt() + 0.5;
    let g0_key = if has_heldout { g0_ho } else { g0_fit };
    // A real effect must help where it was fitted as well as where it was
    // not: the fitting gap must also fall by more than its own noise.
    let k_fit = count_of(baseline_scores, false).max(1) as f64;
    let fit_threshold = 3.0 * (2.0 / k_fit).sqrt() + 0.5;
    match candidates.first() {
        Some(best) if g0_key - key(best) > noise_threshold && g0_fit - best.gap_fit > fit_threshold => {
            let margin = (g0_key - key(best)) / noise_threshold;
            let runner_up = candidates.get(1).map(key).unwrap_or(g0_key);
            let separation = ((runner_up - key(best)) / (g0_key - key(best)).max(1e-9)).clamp(0.0, 1.0);
            let confidence = ((1.0 - (-margin).exp()) * (0.5 + 0.5 * separation)).clamp(0.0, 1.0);
            Verdict { effect: Some(best.effect), confidence, noise_threshold }
        }
        _ => {
            let best_gain = candidates.first().map(|b| (g0_key - key(b)) / noise_threshold).unwrap_or(0.0);
            Verdict { effect: None, confidence: (1.0 - best_gain.max(0.0)).clamp(0.05, 0.95), noise_threshold }
        }
    }
}
