//! The frame of the records: which runs give absolute phases, a check that
//! the ones that claim to really do, and whether their displacement swings
//! about zero, and whether any of their channels never moves.
//!
//! A response phase (the lag of the response's fundamental behind the base)
//! and the normal force's harmonic phases are read against the base's
//! motion `u = U0 cos(Ω t)`. A run fixes that frame with a `base_x` column
//! (its time is moved into the frame when it is read), or by its `t` being
//! in the frame (the format's default), or it declares a free time origin
//! and gives no absolute phase. Records that start at an arbitrary phase of
//! the base without saying so give phases that disagree with every model by
//! anything up to 180°, condition by condition at random: scored, they
//! would swamp every other observable (z-scores in the tens of thousands)
//! and make a null set look like an effect. A `base_x` or `x` channel with
//! its sign reversed moves every phase by half a turn instead.
//! [`check_phases`] finds either pattern and sets such phases aside, saying
//! so in the report.

use crate::diagnose::data::Data;
use crate::diagnose::observable::Observable;
use crate::diagnose::score::Score;
use crate::engine::reduce::wrap_angle;
use crate::measure::TimeOrigin;

/// Notes on the records' time frames for the report: how many runs gave
/// their phase through `base_x`, how many declared a free origin.
pub(crate) fn frame_notes(data: &Data<'_>) -> Vec<String> {
    let runs = &data.set.runs;
    let mut notes = Vec::new();
    let free = runs.iter().filter(|r| r.time_origin == TimeOrigin::Free).count();
    if free > 0 {
        notes.push(format!(
            "{free} of {} runs declare a free time origin: their response phase means are not scored (phase spreads and everything else are), and the normal force's harmonics are placed against each record's own response",
            runs.len()
        ));
    }
    let based: Vec<(f64, f64)> = runs
        .iter()
        .filter_map(|r| match r.time_origin {
            TimeOrigin::BaseChannel { amplitude_m, .. } => Some((amplitude_m, r.excitation_amplitude_m)),
            _ => None,
        })
        .collect();
    if !based.is_empty() {
        let off = based.iter().filter(|(fitted, stated)| (fitted / stated - 1.0).abs() > 0.1).count();
        notes.push(format!(
            "{} of {} runs give the base's motion in a base_x column: their phases are read against it{}",
            based.len(),
            runs.len(),
            if off > 0 {
                format!(
                    " ({off} of them with a base amplitude more than 10% off their stated excitation_amplitude_m; the stated one is simulated)"
                )
            } else {
                String::new()
            }
        ));
    }
    notes
}

/// Notes for the report on recorded channels that hold one value at every
/// sample: a sensor that recorded nothing (unplugged, saturated, or a
/// column of zeros written by the export), or a block held so still that
/// its sensor shows no noise. No real record of a moving rig is constant,
/// and its features read a block at rest throughout, which the model with
/// any friction misfits: the note puts that misfit on the record. Derived
/// channels are not checked (a constant `x` is, and is what they follow).
pub(crate) fn still_channel_notes(data: &Data<'_>) -> Vec<String> {
    let derived = data.derived;
    let mut notes = Vec::new();
    for (i, run) in data.set.runs.iter().enumerate() {
        let recorded: [(&str, &str, Option<&[f64]>); 4] = [
            ("x", "m", Some(&run.x_m)),
            ("v", "m/s", run.v_m_per_s.as_deref().filter(|_| !derived.v)),
            ("friction_force", "N", run.friction_force.as_deref().filter(|_| !derived.friction)),
            ("normal_force", "N", run.normal_force.as_deref()),
        ];
        let still: Vec<String> = recorded
            .iter()
            .filter_map(|&(name, unit, values)| {
                let values = values?;
                let first = *values.first()?;
                (values.len() > 1 && values.iter().all(|v| v.to_bits() == first.to_bits()))
                    .then(|| format!("`{name}` is {first} {unit}"))
            })
            .collect();
        if !still.is_empty() {
            notes.push(format!(
                "{}: {} at every one of its {} samples: a sensor that recorded nothing, or a block held so still \
                 that its sensor shows no noise; the run is read as it is (a block at rest throughout), so the \
                 misfit there is most likely the record's, not the model's",
                run.file.file_name().map_or_else(|| format!("run {i}"), |f| f.to_string_lossy().into_owned()),
                still.join(" and "),
                run.len()
            ));
        }
    }
    notes
}

/// The share of the runs' median amplitude by which their median
/// displacement may lie off zero before the report notes it. The model's
/// block swings about x = 0 (the spring at rest); a block that sticks for
/// most of a cycle may rest off zero by up to μN/k, but to either side at
/// random, run by run, and the one effect that pushes it aside steadily (a
/// normal force whose first harmonic makes one direction's friction
/// larger) moves it by about 0.1 mm, a few percent of the paper's
/// amplitudes, at a harmonic of a tenth of the load. A sensor's zero
/// shifts every run alike.
const DISPLACEMENT_OFFSET_SHARE: f64 = 0.05;

/// A note for the report where the records' displacement `x` swings about
/// a common mean off zero: the median over the runs of each run's mean
/// beyond [`DISPLACEMENT_OFFSET_SHARE`] of the median of their amplitudes
/// (half a record's range). Every peak read from such records is off by
/// that offset, which no effect explains, so the hints that blame the
/// friction level or the rig would point the wrong way.
pub(crate) fn displacement_offset_note(data: &Data<'_>) -> Option<String> {
    let (mut means, mut amplitudes): (Vec<f64>, Vec<f64>) = data
        .set
        .runs
        .iter()
        .filter_map(|r| {
            let finite = r.x_m.iter().copied().filter(|x| x.is_finite());
            let (count, sum, lo, hi) = finite
                .fold((0usize, 0.0, f64::INFINITY, f64::NEG_INFINITY), |(n, s, lo, hi), x| {
                    (n + 1, s + x, lo.min(x), hi.max(x))
                });
            (count > 0).then(|| (sum / count as f64, 0.5 * (hi - lo)))
        })
        .unzip();
    if means.is_empty() {
        return None;
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (offset, amplitude) = (median(&mut means), median(&mut amplitudes));
    (amplitude > 0.0 && offset.abs() > DISPLACEMENT_OFFSET_SHARE * amplitude).then(|| {
        format!(
            "the displacement x swings about {:.3} mm, not zero (the median over the runs of each run's mean; \
             {:.0}% of their median amplitude): the model's block swings about x = 0, the spring at rest, so every \
             peak read from these records is off by that offset, which no effect explains; if it is the sensor's \
             zero, subtract it from x",
            offset * 1e3,
            100.0 * offset.abs() / amplitude
        )
    })
}

/// The share of the mean friction coefficient by which the coefficient
/// while slipping may differ between the two directions of motion (half
/// the difference, the median over the runs) before the report notes it.
/// The model's friction is the same both ways, and so is every effect's: a
/// normal-force harmonic that loads one direction more is divided out by
/// the measured normal force. On 71 stored benchmark sets of seeds 5, 6,
/// 7, 8 and 36 the median is at most 0.6%; a friction channel's zero offset
/// of 0.3 N on the paper's rig at 4–16 N makes 8%.
const FRICTION_ASYMMETRY_SHARE: f64 = 0.03;

/// Fewest fast slipping samples each way a run needs for its friction
/// asymmetry to be read.
const ASYMMETRY_MIN_SAMPLES: usize = 20;

/// A run's friction asymmetry: half the difference of the mean |F|/N over
/// the samples where the block slips at more than half its peak speed
/// backwards and forwards, as a share of their mean, and that half
/// difference times the mean normal force there (the zero offset of the
/// friction channel that would make it, N). `None` without a friction
/// channel or with too few such samples either way.
fn friction_asymmetry(run: &crate::measure::Run) -> Option<(f64, f64)> {
    let friction = run.friction_force.as_ref()?;
    // (count, Σμ, ΣN) forwards and backwards.
    let mut sums = [(0usize, 0.0, 0.0); 2];
    for (i, v) in crate::measure::fast_motion(&run.t_s, &run.x_m) {
        let normal = run.normal_force.as_ref().map_or(run.normal_force_n, |n| n[i]);
        let f = friction[i];
        if f * v < 0.0 && normal > 0.0 {
            let side = &mut sums[usize::from(v < 0.0)];
            *side = (side.0 + 1, side.1 + f.abs() / normal, side.2 + normal);
        }
    }
    let [(n_fwd, mu_fwd, load_fwd), (n_back, mu_back, load_back)] = sums;
    if n_fwd < ASYMMETRY_MIN_SAMPLES || n_back < ASYMMETRY_MIN_SAMPLES {
        return None;
    }
    let (fwd, back) = (mu_fwd / n_fwd as f64, mu_back / n_back as f64);
    let (half, mean) = (0.5 * (back - fwd), 0.5 * (back + fwd));
    let load = (load_fwd + load_back) / (n_fwd + n_back) as f64;
    (mean > 0.0).then(|| (half / mean, half * load))
}

/// A note for the report where the friction coefficient while slipping is
/// larger one way than the other beyond [`FRICTION_ASYMMETRY_SHARE`] (the
/// median over the runs): a zero offset of the friction channel adds to
/// the friction one way and takes from it the other, which no effect
/// explains, so hints that point at the friction noise or a memory would
/// point the wrong way.
pub(crate) fn friction_offset_note(data: &Data<'_>) -> Option<String> {
    let mut found: Vec<(f64, f64)> = data.set.runs.iter().filter_map(friction_asymmetry).collect();
    if found.is_empty() {
        return None;
    }
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (share, offset_n) = found[found.len() / 2];
    (share.abs() > FRICTION_ASYMMETRY_SHARE).then(|| {
        format!(
            "the friction coefficient while slipping is {:.0}% larger one way than the other (the median over {} \
             runs): a zero offset of about {offset_n:+.3} N in the friction channel would do that; the model's \
             friction is the same both ways, so no effect explains it; if it is the transducer's zero, subtract it \
             from friction_force",
            200.0 * share.abs(),
            found.len()
        )
    })
}

/// Fewest record units whose phases a frame check reads.
const MIN_UNITS: usize = 4;

/// Whether the phase means of `scores` (measured against simulated, one per
/// record unit whose runs claim the model's frame) look like records with a
/// free time origin: their misfits are large (median beyond 30°, median
/// |z| beyond 10) and spread over the whole circle, as uniform angles are
/// (Rayleigh's test: the mean resultant length R̄ of n uniform angles
/// exceeds sqrt(3/n) with probability about e⁻³ = 5%). A model that
/// misfits the phase misfits it smoothly across conditions, and its misfits
/// cluster. Returns R̄ and n where the pattern holds.
pub(crate) fn looks_free(scores: &[Score], claims_frame: impl Fn(usize) -> bool) -> Option<(f64, usize)> {
    let misfits = PhaseMisfits::of(scores, claims_frame)?;
    let n = misfits.residuals.len();
    let (c, s) = misfits.sums();
    let resultant = (c * c + s * s).sqrt() / n as f64;
    let mut degrees: Vec<f64> = misfits.residuals.iter().map(|r| r.abs().to_degrees()).collect();
    degrees.sort_by(f64::total_cmp);
    let large = degrees[n / 2] > 30.0 && misfits.median_abs_z > 10.0;
    (large && resultant < (3.0 / n as f64).sqrt()).then_some((resultant, n))
}

/// The phase means' misfits of the record units `claims` picks: each
/// residual (measured − simulated, rad, wrapped into (−π, π]) and the
/// median |z|; `None` below [`MIN_UNITS`] units.
struct PhaseMisfits {
    residuals: Vec<f64>,
    median_abs_z: f64,
}

impl PhaseMisfits {
    fn of(scores: &[Score], claims: impl Fn(usize) -> bool) -> Option<PhaseMisfits> {
        let phases: Vec<&Score> =
            scores.iter().filter(|s| s.observable == Observable::PhaseMeanDeg && claims(s.unit)).collect();
        if phases.len() < MIN_UNITS {
            return None;
        }
        let residuals = phases.iter().map(|s| wrap_angle((s.measured - s.simulated).to_radians())).collect();
        let mut z: Vec<f64> = phases.iter().map(|s| s.z.abs()).collect();
        z.sort_by(f64::total_cmp);
        Some(PhaseMisfits { residuals, median_abs_z: z[z.len() / 2] })
    }

    /// The residuals' summed cosines and sines.
    fn sums(&self) -> (f64, f64) {
        self.residuals.iter().fold((0.0, 0.0), |(c, s), r| (c + r.cos(), s + r.sin()))
    }
}

/// Whether the phase means of `scores` (measured against simulated, one per
/// record unit that gives an absolute phase, `claims_phase`) sit half a turn
/// from the simulated ones: each residual within [`HALF_TURN_TOLERANCE_DEG`]
/// of ±180° and the median |z| beyond 10. A `base_x` or `x` channel with
/// its sign reversed (or the opposite convention for the lag) moves every
/// phase by 180° and nothing else; a model that misfits the phase (a wrong
/// natural frequency, say) misfits it by half a turn only between the
/// stated and the true resonance, not at every condition. Returns the
/// residuals' circular mean (degrees) and their number where the pattern
/// holds.
pub(crate) fn looks_reversed(scores: &[Score], claims_phase: impl Fn(usize) -> bool) -> Option<(f64, usize)> {
    let misfits = PhaseMisfits::of(scores, claims_phase)?;
    let half_turn = misfits.residuals.iter().all(|r| r.abs().to_degrees() >= 180.0 - HALF_TURN_TOLERANCE_DEG);
    let (c, s) = misfits.sums();
    (half_turn && misfits.median_abs_z > 10.0).then_some((s.atan2(c).to_degrees(), misfits.residuals.len()))
}

/// How far from ±180° every phase residual must lie for
/// [`looks_reversed`], degrees.
const HALF_TURN_TOLERANCE_DEG: f64 = 45.0;

/// Sets aside the phase means of record units `units`: they leave the
/// measured observables and the records' phases count as relative ones.
fn set_phases_aside(data: &mut Data<'_>, units: &[usize]) {
    for &u in units {
        data.measured[u].remove(&Observable::PhaseMeanDeg);
        for f in &mut data.features[u] {
            f.absolute_phase = false;
        }
    }
}

/// Whether record unit `u` is records only (no summary row), each with a
/// time origin that `keep` accepts.
fn runs_all(data: &Data<'_>, u: usize, keep: impl Fn(TimeOrigin) -> bool) -> bool {
    let unit = &data.units[u];
    unit.summary.is_none() && unit.runs.iter().all(|&r| keep(data.set.runs[r].time_origin))
}

/// Checks the absolute phases against the calibrated baseline's `scores`,
/// and sets aside those that cannot mean what they claim, saying why in a
/// note for the report (a line for progress beside each): the record units
/// that claim the model's frame where they look as if their time origin
/// were free ([`looks_free`]), and those that give an absolute phase where
/// every one of them sits half a turn from the baseline's
/// ([`looks_reversed`]).
pub(crate) fn check_phases(data: &mut Data<'_>, scores: &[Score]) -> Vec<(String, &'static str)> {
    let mut notes = Vec::new();
    let in_frame = |data: &Data<'_>, u: usize| runs_all(data, u, |o| o == TimeOrigin::Model);
    if let Some((resultant, n)) = looks_free(scores, |u| in_frame(data, u)) {
        let units: Vec<usize> = (0..data.units.len()).filter(|&u| in_frame(data, u)).collect();
        set_phases_aside(data, &units);
        notes.push((format!(
            "the response phases of {n} record units disagree with the calibrated baseline by a median of more than 30° and in every direction (mean resultant length {resultant:.2}, below the {:.2} that uniform angles exceed 5% of the time): their time origin looks free, not the frame of u = U0 cos(2π f t) the format assumes without a base_x column. Their phase means are set aside (not scored); declare \"time_origin\": \"free\" or give a base_x column to say so",
            (3.0 / n as f64).sqrt()
        ), "the records' phases look as if their time origin were free; their phase means are set aside"));
    }
    let absolute = |data: &Data<'_>, u: usize| {
        runs_all(data, u, TimeOrigin::phase_known) && data.measured[u].contains_key(&Observable::PhaseMeanDeg)
    };
    if let Some((mean, n)) = looks_reversed(scores, |u| absolute(data, u)) {
        let units: Vec<usize> = (0..data.units.len()).filter(|&u| absolute(data, u)).collect();
        set_phases_aside(data, &units);
        notes.push((format!(
            "the response phases of {n} record units sit half a turn from the calibrated baseline's at every condition (mean difference {mean:.0}°, each within {HALF_TURN_TOLERANCE_DEG:.0}° of 180°): a base_x or x column with its sign reversed, or a lag measured the other way round, does that and nothing else. Their phase means are set aside (not scored); check the sign of those channels"
        ), "the records' phases sit half a turn from the baseline's (a channel's sign reversed?); their phase means are set aside"));
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::score::test_score;

    fn phase(unit: usize, measured: f64, simulated: f64) -> Score {
        Score { measured, simulated, ..test_score(unit, Observable::PhaseMeanDeg, 200.0, false) }
    }

    /// A run whose `x` holds one value throughout is noted by its name; a
    /// record of a moving block, with its sensor's noise, is not.
    #[test]
    fn a_channel_that_never_moves_is_noted_and_a_live_one_is_not() {
        let truth = crate::engine::Model::paper_rig(&[]).expect("the paper rig");
        let mut set = crate::diagnose::synthetic::displacement_only_set(&truth, 5);
        let live = Data::new(&set, Default::default()).expect("data");
        assert!(still_channel_notes(&live).is_empty());
        set.runs[1].x_m.iter_mut().for_each(|x| *x = 0.0);
        let dead = Data::new(&set, Default::default()).expect("data");
        let notes = still_channel_notes(&dead);
        assert_eq!(notes.len(), 1, "{notes:?}");
        let name = set.runs[1].file.file_name().expect("a run file").to_string_lossy();
        assert!(notes[0].starts_with(&format!("{name}: `x` is 0 m at every one of its")), "{}", notes[0]);
    }

    #[test]
    fn phases_spread_over_the_circle_look_free_and_a_smooth_misfit_does_not() {
        // Eighteen records started at random phases of the base.
        let random = [
            151.0, -97.0, 12.0, -163.0, 78.0, -41.0, 119.0, -130.0, 58.0, 170.0, -12.0, 95.0, -75.0, 33.0, -150.0,
            140.0, -60.0, 105.0,
        ];
        let scores: Vec<Score> = random.iter().enumerate().map(|(u, &m)| phase(u, m, 10.0)).collect();
        let (r, n) = looks_free(&scores, |_| true).expect("random phases");
        assert_eq!(n, 18);
        assert!(r < (3.0f64 / 18.0).sqrt(), "{r}");
        // A model that lags every condition by 40-60°: large, but clustered.
        let smooth: Vec<Score> = (0..18).map(|u| phase(u, 10.0 + 40.0 + u as f64, 10.0)).collect();
        assert_eq!(looks_free(&smooth, |_| true), None);
        // Small misfits never look free.
        let small: Vec<Score> = random.iter().enumerate().map(|(u, &m)| phase(u, 10.0 + m / 10.0, 10.0)).collect();
        assert_eq!(looks_free(&small, |_| true), None);
        // Too few units to tell.
        assert_eq!(looks_free(&scores[..3], |_| true), None);
    }

    #[test]
    fn phases_half_a_turn_off_everywhere_look_reversed_and_a_resonance_misplaced_does_not() {
        // A reversed base_x: every lag 180° from the model's, give or take.
        let lags = [3.0, 5.0, 8.0, 12.0, 20.0, 35.0, 60.0, 120.0, 150.0, 165.0, 172.0, 176.0];
        let reversed: Vec<Score> =
            lags.iter().enumerate().map(|(u, &l)| phase(u, l + 180.0 + (u as f64 - 6.0), l)).collect();
        let (mean, n) = looks_reversed(&reversed, |_| true).expect("a reversed channel");
        assert_eq!(n, 12);
        assert!((mean.abs() - 180.0).abs() < 5.0, "{mean}");
        // A natural frequency stated wrong puts the conditions between the
        // two resonances half a turn off, and no others.
        let misplaced: Vec<Score> = lags
            .iter()
            .enumerate()
            .map(|(u, &l)| phase(u, if (5..8).contains(&u) { l + 170.0 } else { l + 2.0 }, l))
            .collect();
        assert_eq!(looks_reversed(&misplaced, |_| true), None);
        // Units that give no absolute phase are not read.
        assert_eq!(looks_reversed(&reversed, |u| u < 3), None);
    }
}
