//! The noise of a group's lanes at the start of each interval.

use super::*;

// A group's lanes draw their noise side by side (`rng::pair_a_side_by_side`),
// `rng::SIDE_BY_SIDE` at a time.
const _: () = assert!(LANES.is_multiple_of(rng::SIDE_BY_SIDE));

/// [`Path::draw_noise`] of every path in `lanes` (at the same interval of
/// oscillators that step together, [`steps_beside`]): lanes without a
/// table draw their pairs side by side; where the noise is white and
/// nothing of it depends on the path's own state ([`Path::plain_noise`]),
/// the parts common to an oscillator's lanes are computed once for them
/// and each lane's values come straight from its pair.
pub(super) fn draw_lanes_noise(lanes: &mut [Path<'_>]) {
    // Lanes read their tables (the usual case: one lane's answer is all
    // of theirs) or all draw: then side by side.
    let drawn = (lanes.len() > 1 && lanes[0].draws_pair_a() && lanes.iter().all(Path::draws_pair_a))
        .then(|| pairs_side_by_side(lanes));
    if lanes[0].plain_noise() {
        // The lanes of one load are usually neighbours: the last load's
        // parts serve until the oscillator changes.
        let mut load: Option<(&Oscillator, (f64, f64))> = None;
        for (l, path) in lanes.iter_mut().enumerate() {
            let (mean_n, harmonics_n) = match load {
                Some((osc, parts)) if std::ptr::eq(osc, path.osc) => parts,
                _ => {
                    let parts = path.interval_load();
                    load = Some((path.osc, parts));
                    parts
                }
            };
            let pair = drawn.as_ref().map_or_else(|| path.pair_a(), |pairs| pairs[l]);
            path.draw_plain_noise(pair, mean_n, harmonics_n);
            path.pair_a_table.prefetch(path.interval);
        }
        return;
    }
    for (l, path) in lanes.iter_mut().enumerate() {
        path.draw_noise_with(drawn.as_ref().map(|pairs| pairs[l]));
        path.pair_a_table.prefetch(path.interval);
    }
}

/// Pair A of the current interval of every path in `lanes`, drawn side by
/// side (`rng::SIDE_BY_SIDE` at a time).
fn pairs_side_by_side(lanes: &[Path<'_>]) -> [(f64, f64); LANES] {
    let mut pairs = [(0.0, 0.0); LANES];
    for (pairs, lanes) in pairs.chunks_mut(rng::SIDE_BY_SIDE).zip(lanes.chunks(rng::SIDE_BY_SIDE)) {
        let realisations = std::array::from_fn(|l| lanes.get(l).map_or(0, |p| p.realisation));
        let drawn = rng::pair_a_side_by_side(lanes[0].key, realisations, lanes.len(), lanes[0].interval);
        pairs.copy_from_slice(&drawn[..pairs.len()]);
    }
    pairs
}

impl Path<'_> {
    /// Whether [`Path::draw_noise`] takes the friction's value and the
    /// normal force's straight from pair A (white friction noise of this
    /// interval's block, no non-Gaussian part), and nothing else it sets
    /// depends on the path (no harmonics that follow the displacement, no
    /// stiction excess that is drawn or ages, no contact age, no random
    /// walk of the load): then [`Path::draw_plain_noise`] is the same.
    fn plain_noise(&self) -> bool {
        let e = &self.osc.effects;
        e.drift_form != DriftForm::RandomWalk
            && e.colour_rho == 0.0
            && !(e.colour_form == ColourForm::Hold && e.colour_hold_intervals > 1)
            && e.non_gaussian_strength == 0.0
            && e.non_gaussian_cubic == 0.0
            && (e.harmonic_form != HarmonicForm::Position || e.harmonic_amplitudes_n.iter().all(|&a| a == 0.0))
            && !matches!(e.stiction_form, StictionForm::Noisy | StictionForm::Dwell)
            && self.memory_form != Memory::Ageing
    }

    /// The normal force's mean (with its drift) and its harmonics in the
    /// current interval, N: the same for every path of the oscillator
    /// where [`Path::plain_noise`] holds.
    fn interval_load(&self) -> (f64, f64) {
        let o = self.osc;
        let e = &o.effects;
        let drift_t_s = o.drift_time_s(self.interval as f64 * o.noise_interval_s);
        let mean_n =
            o.normal_force_mean_n * drift_factor(e.drift_form, e.drift_rate_per_s, e.drift_curvature_per_s2, drift_t_s);
        (mean_n, harmonics_n(e, self.interval_phase, self.x_m / o.base_amplitude_m))
    }

    /// [`Path::draw_noise`] where [`Path::plain_noise`] holds, with the
    /// interval's pair A `(ξ_μ, ξ_N)` (–) and [`Path::interval_load`]'s
    /// `mean_n` and `harmonics_n` (N): the same operations on the same
    /// values.
    #[inline(always)]
    fn draw_plain_noise(&mut self, (white, xi_n): (f64, f64), mean_n: f64, harmonics_n: f64) {
        let o = self.osc;
        self.friction_noise = o.friction_sigma * white;
        self.normal_force_n = (mean_n + o.normal_force_sigma_n * xi_n + harmonics_n).max(0.0);
        self.stiction_excess = o.effects.stiction_excess;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{Condition, Model};

    /// Where the noise is plain, its draw with the common parts computed
    /// once is [`Path::draw_noise`]'s, bit for bit: without effects, with
    /// harmonics of the phase, a drifting load and a constant stiction
    /// excess; coloured noise and a random-walk load are not plain.
    #[test]
    fn plain_noise_is_the_full_draw() {
        let cases: [(&[&str], bool); 5] = [
            (&[], true),
            (&["normal_force_harmonics.amplitudes_n=[0.4, 0.3, 0.0, 0.1]", "normal_force_drift.rate_per_s=0.02"], true),
            (&["stiction.excess=0.15"], true),
            (&["coloured_friction_noise.correlation_time_s=0.01"], false),
            (&["normal_force_drift.form=\"random_walk\"", "normal_force_drift.rate_per_s=1e-3"], false),
        ];
        for (overrides, plain) in cases {
            let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
            let model = Model::paper_rig(&overrides).expect("the paper rig");
            let osc = Oscillator::new(&model, Condition { excitation_frequency_hz: 9.0, normal_force_n: 8.0 })
                .expect("an oscillator");
            let initial = InitialState { x_m: 1e-4, v_m_per_s: 0.0 };
            let mut path = Path::new(&osc, 3, 5, initial);
            assert_eq!(path.plain_noise(), plain, "{overrides:?}");
            for interval in 1..300 {
                path.interval = interval;
                path.interval_phase = (interval as f64 * 0.0731).fract();
                path.x_m = 1e-3 * (interval as f64 * 0.37).sin();
                let mut full = path.clone();
                full.draw_noise();
                let (mean_n, harmonics_n) = path.interval_load();
                path.draw_plain_noise(path.pair_a(), mean_n, harmonics_n);
                let bits = |p: &Path<'_>| [p.friction_noise, p.normal_force_n, p.stiction_excess].map(f64::to_bits);
                if plain {
                    assert_eq!(bits(&path), bits(&full), "{overrides:?}, interval {interval}");
                }
            }
        }
    }
}
