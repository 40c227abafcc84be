//! Adaptive frequency refinement: frequencies added to a sweep's grid where
//! the response changes fast between neighbouring grid frequencies (the
//! resonance peak, where amplitude and phase swing within a few hundredths
//! of a hertz; the onset of sticking).
//!
//! **How.** A *pilot* of the model without its noise (`friction.sigma` and
//! `normal_force.sigma` set to zero, so one path per point is the
//! deterministic response) runs on the f64 CPU reference over the base grid,
//! with the sweep's warm-up and at most [`PILOT_CYCLES`] measured periods,
//! at every normal force of the grid. Between each pair of neighbouring
//! frequencies the change is scored, per normal force, as the largest of
//!
//! - the relative change of the mean peak, in units of [`AMPLITUDE_STEP`];
//! - the change of the stick fraction, in units of [`STICK_STEP`];
//! - the change of the mean phase lag, in units of [`PHASE_STEP_DEG`];
//!
//! and the interval is bisected when its score exceeds 1. The interval with
//! the highest score is bisected first (the lower frequency first on a tie);
//! the pilot then runs at the midpoint and both halves are scored again.
//! It stops when no score exceeds 1, when [`RefineSettings::max_added`]
//! frequencies were added (never more than the base grid has), or where an
//! interval is already `2^-max_depth` of the base grid's interval it lies in.
//!
//! **Determinism.** The pilot has no noise and runs on the f64 reference,
//! whose results do not depend on the thread count or the sweep's backend;
//! the grid therefore depends only on the model, the base grid, the normal
//! forces, the warm-up and the settings, never on the seed. Every shard of a
//! sharded run computes the same refined grid before taking its part, so
//! `merge` gives the unsharded run's files byte for byte (and refuses shards
//! whose grids differ, as for any other grid).

use crate::engine::{Condition, Engine, Model, PointAccumulator, RunPlan};
use crate::error::Result;
use crate::sweep::{SweepSettings, run_sweep};

/// Measured periods of a pilot path at most (a noise-free response is periodic).
pub const PILOT_CYCLES: u32 = 10;
/// A relative change of the mean peak that counts as one step (10%).
pub const AMPLITUDE_STEP: f64 = 0.10;
/// A change of the stick fraction that counts as one step.
pub const STICK_STEP: f64 = 0.10;
/// A change of the mean phase lag that counts as one step, degrees.
pub const PHASE_STEP_DEG: f64 = 20.0;
/// The pilot's noise seed (it draws no noise from it; fixed so that the grid
/// never depends on the sweep's seed).
const PILOT_SEED: u64 = 1;

/// How far a grid is refined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RefineSettings {
    /// At most this many frequencies are added (and never more than the base
    /// grid has).
    pub max_added: usize,
    /// An interval is bisected at most this many times below the base grid's.
    pub max_depth: u32,
}

impl Default for RefineSettings {
    fn default() -> Self {
        RefineSettings { max_added: 16, max_depth: 4 }
    }
}

/// The outcome: the refined, increasing frequencies, and which were added.
#[derive(Clone, Debug, PartialEq)]
pub struct Refinement {
    /// Base and added frequencies together, increasing, Hz.
    pub frequencies_hz: Vec<f64>,
    /// The added frequencies, increasing, Hz.
    pub added_hz: Vec<f64>,
}

/// Why a grid is not refined, in words (`None`: it can be).
pub fn not_refinable(frequencies_hz: &[f64]) -> Option<&'static str> {
    if frequencies_hz.len() < 2 {
        Some("a single frequency has no neighbour to refine towards")
    } else if frequencies_hz.windows(2).any(|w| w[1] <= w[0]) {
        Some("the frequencies are not increasing")
    } else {
        None
    }
}

/// The pilot's response at one frequency: per normal force, the mean peak
/// (m), the stick fraction and the mean phase lag (degrees).
type Response = Vec<(f64, f64, f64)>;

/// One interval between neighbouring frequencies of the growing grid.
struct Interval {
    lo: usize,
    hi: usize,
    depth: u32,
    score: f64,
}

/// How fast the response changes between two frequencies (> 1: bisect).
fn score(a: &Response, b: &Response, amplitude_floor_m: f64) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&(ma, sa, pa), &(mb, sb, pb))| {
            let amplitude = (mb - ma).abs() / ma.abs().max(mb.abs()).max(amplitude_floor_m) / AMPLITUDE_STEP;
            let stick = (sb - sa).abs() / STICK_STEP;
            let phase = ((pb - pa + 180.0).rem_euclid(360.0) - 180.0).abs() / PHASE_STEP_DEG;
            amplitude.max(stick).max(phase)
        })
        .filter(|s| s.is_finite())
        .fold(0.0, f64::max)
}

/// Refines `frequencies_hz` (increasing, two or more; see [`not_refinable`])
/// for a grid at `normal_forces_n`, as the module documentation describes.
pub fn refine_frequencies(
    model: &Model,
    frequencies_hz: &[f64],
    normal_forces_n: &[f64],
    warmup_cycles: u32,
    settings: RefineSettings,
) -> Result<Refinement> {
    let unchanged = Refinement { frequencies_hz: frequencies_hz.to_vec(), added_hz: Vec::new() };
    if not_refinable(frequencies_hz).is_some() || settings.max_added == 0 || normal_forces_n.is_empty() {
        return Ok(unchanged);
    }
    let mut pilot_model = model.clone();
    pilot_model.friction.sigma = 0.0;
    pilot_model.normal_force.sigma = 0.0;
    let engine = Engine::cpu("the refinement's pilot");
    let pilot = SweepSettings {
        realisations: 1,
        plan: RunPlan { warmup_cycles, measured_cycles: PILOT_CYCLES },
        seed: PILOT_SEED,
    };
    let respond = |freqs: &[f64]| -> Result<Vec<Response>> {
        let conditions: Vec<Condition> = freqs
            .iter()
            .flat_map(|&f| {
                normal_forces_n.iter().map(move |&n| Condition { excitation_frequency_hz: f, normal_force_n: n })
            })
            .collect();
        let result = run_sweep(&pilot_model, &conditions, &pilot, &engine, &mut |_, _| {})?;
        let per_point: Vec<(f64, f64, f64)> = result
            .conditions
            .iter()
            .zip(&result.accumulators)
            .map(|(&c, a): (&Condition, &PointAccumulator)| {
                let s = a.stats(c);
                (s.peak_mean_m, s.stick_fraction, s.phase_mean_deg)
            })
            .collect();
        Ok(per_point.chunks(normal_forces_n.len()).map(<[_]>::to_vec).collect())
    };
    let floor = 1e-3 * model.excitation.amplitude_m.abs().max(f64::MIN_POSITIVE);
    // Frequencies and responses grow by appending; intervals index into them.
    let mut freqs = frequencies_hz.to_vec();
    let mut responses = respond(&freqs)?;
    let mut intervals: Vec<Interval> = (0..freqs.len() - 1)
        .map(|i| Interval { lo: i, hi: i + 1, depth: 0, score: score(&responses[i], &responses[i + 1], floor) })
        .collect();
    let budget = settings.max_added.min(frequencies_hz.len());
    let mut added = Vec::new();
    while added.len() < budget {
        // The fastest change first; on a tie, the lower frequency.
        let candidate = intervals
            .iter()
            .enumerate()
            .filter(|(_, iv)| iv.score > 1.0 && iv.depth < settings.max_depth)
            .max_by(|(_, a), (_, b)| a.score.total_cmp(&b.score).then(freqs[b.lo].total_cmp(&freqs[a.lo])))
            .map(|(k, _)| k);
        let Some(k) = candidate else { break };
        let Interval { lo, hi, depth, .. } = intervals.swap_remove(k);
        let mid = 0.5 * (freqs[lo] + freqs[hi]);
        if !(mid > freqs[lo] && mid < freqs[hi]) {
            continue; // no f64 between them
        }
        let response = respond(&[mid])?.remove(0);
        let m = freqs.len();
        freqs.push(mid);
        responses.push(response);
        added.push(mid);
        for (a, b) in [(lo, m), (m, hi)] {
            let s = score(&responses[a], &responses[b], floor);
            intervals.push(Interval { lo: a, hi: b, depth: depth + 1, score: s });
        }
    }
    freqs.sort_by(f64::total_cmp);
    added.sort_by(f64::total_cmp);
    Ok(Refinement { frequencies_hz: freqs, added_hz: added })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refine_only_increasing_grids_of_two_or_more() {
        assert!(not_refinable(&[7.0]).is_some());
        assert!(not_refinable(&[8.0, 7.0]).is_some());
        assert!(not_refinable(&[7.0, 7.0]).is_some());
        assert!(not_refinable(&[6.0, 7.0]).is_none());
        let one = refine_frequencies(&Model::default(), &[7.0], &[16.39], 10, RefineSettings::default()).unwrap();
        assert_eq!(one.frequencies_hz, [7.0]);
        assert!(one.added_hz.is_empty());
    }

    #[test]
    fn refine_scores_amplitude_stick_and_phase_steps() {
        let a = vec![(1.0e-3, 0.0, 10.0)];
        assert!(score(&a, &vec![(1.05e-3, 0.0, 10.0)], 1e-6) < 1.0);
        assert!(score(&a, &vec![(1.2e-3, 0.0, 10.0)], 1e-6) > 1.0);
        assert!(score(&a, &vec![(1.0e-3, 0.15, 10.0)], 1e-6) > 1.0);
        assert!(score(&a, &vec![(1.0e-3, 0.0, 35.0)], 1e-6) > 1.0);
        // Phases wrap: 179° to −179° is a step of 2°.
        assert!(score(&vec![(1.0e-3, 0.0, 179.0)], &vec![(1.0e-3, 0.0, -179.0)], 1e-6) < 1.0);
    }

    /// Across the paper rig's resonance (10.05 Hz without friction), a grid
    /// of 0.5 Hz steps gets frequencies added next to the peak, within the
    /// budget, the same ones on every call.
    #[test]
    fn refine_adds_frequencies_at_the_resonance_deterministically() {
        let model = Model::default();
        let base = [9.0, 9.5, 10.0, 10.5, 11.0];
        let settings = RefineSettings { max_added: 4, max_depth: 4 };
        let r = refine_frequencies(&model, &base, &[4.0], 30, settings).unwrap();
        assert!(!r.added_hz.is_empty() && r.added_hz.len() <= 4, "{r:?}");
        assert!(r.added_hz.iter().all(|f| (9.5..=10.5).contains(f)), "{r:?}");
        assert!(r.frequencies_hz.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(r.frequencies_hz.len(), base.len() + r.added_hz.len());
        let again = refine_frequencies(&model, &base, &[4.0], 30, settings).unwrap();
        assert_eq!(r, again);
    }
}
