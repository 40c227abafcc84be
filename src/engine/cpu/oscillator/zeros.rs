//! Velocity zeros of several lanes located side by side.
//!
//! The realisations of a group share their base motion, so they reach
//! their velocity zeros in the same grid steps: on the main job, a step in
//! which one of sixteen lanes met a zero held 5.4 on average, and one in
//! twelve held all sixteen. One lane's search ([`Path::locate_velocity_zero`])
//! is a chain of RK4 probes, each waiting on the last; here the lanes' searches
//! run in lockstep, each round one vector probe of every lane searched
//! ([`simd::probe_step`]; a lane whose search has ended is probed and not
//! read), so their chains overlap. Each lane's decisions are its own
//! search's, made on the same values, so each finds the same zero, bit for
//! bit.

use super::simd;
use super::*;

/// A lane's velocity zero inside a slip step, as
/// [`Path::locate_velocity_zero`] returns it: the step length to the zero
/// (s) and the RK4 step to it where a probe took it.
pub(super) type Located = (f64, Option<SlipStep>);

/// A slipping lane's step over a whole segment that ended past a velocity
/// zero ([`Path::advance_segment_past`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct PastZero {
    /// The step's end velocity, m/s (`sign · v ≤ 0`).
    pub(super) full_step_v: f64,
    /// The zero, where it was located already.
    pub(super) located: Option<Located>,
}

/// The lanes' searches in progress, one element per lane.
struct Searches<const N: usize> {
    /// The bracket: under way after `lo`, not after `hi`, s.
    lo: [f64; N],
    hi: [f64; N],
    /// The next probe's step length, s.
    x: [f64; N],
    /// Where the bracket is narrow enough, s.
    tolerance: [f64; N],
    searching: [bool; N],
    /// Whether a probe reached `hi` (then `hi_step` holds it).
    probed_hi: [bool; N],
    hi_step: [SlipStep; N],
}

impl Path<'_> {
    /// [`Path::locate_velocity_zero`] of the lanes in `zero` side by side:
    /// each lane `l` slipping from the vector step's start `state` (its
    /// trig there `start`) over `h_s` seconds, whose full step ends at
    /// velocity `full_step_v[l]` with `sign · v ≤ 0`, and which was under way
    /// at the start (`sign · v > 0`; a lane from rest probes halvings first
    /// and is left to its own search: `None`). `half` is the step's half turn as the
    /// vector step took it; where it is not `Trig::turn` of this step's
    /// length, the search takes its own full step, as the scalar one does.
    /// `history` is the lanes' friction history where one is on.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn locate_zeros<const N: usize>(
        lanes: &[Path<'_>; N],
        state: &simd::SlipLanes<N>,
        law: &simd::SlipLaw,
        history: Option<&simd::History<'_, N>>,
        zero: [bool; N],
        h_s: f64,
        half: Trig,
        full_step_v: [f64; N],
    ) -> [Option<Located>; N] {
        let o = lanes[0].osc;
        let w = o.omega_rad_per_s;
        let searched_half = Trig::turn(0.5 * w * h_s);
        let same_step =
            searched_half.cos.to_bits() == half.cos.to_bits() && searched_half.sin.to_bits() == half.sin.to_bits();
        let unprobed = SlipStep { x_m: 0.0, v_m_per_s: 0.0, memory: 0.0, stage_x_m: [0.0; 4], trig: [half; 3] };
        let mut s = Searches {
            lo: [0.0; N],
            hi: [h_s; N],
            x: [h_s; N],
            tolerance: [0.0; N],
            searching: [false; N],
            probed_hi: [false; N],
            hi_step: [unprobed; N],
        };
        for l in 0..N {
            let p = &lanes[l];
            let sign = state.sign[l];
            let g_lo = sign * p.v_m_per_s;
            if !zero[l] || g_lo <= 0.0 {
                continue;
            }
            let start = Trig { cos: state.cos[l], sin: state.sin[l] };
            let g_hi = if same_step {
                sign * full_step_v[l]
            } else {
                sign * p.rk4_slip(start, p.x_m, p.v_m_per_s, h_s, searched_half, sign).v_m_per_s
            };
            (s.x[l], s.tolerance[l]) = p.first_newton_guess(start, h_s, sign, g_lo, g_hi);
            s.searching[l] = true;
        }
        let searched = s.searching;
        // The searching lanes, packed once: each round probes them all
        // (a lane whose search has ended probes again and is not read), so
        // only the probes' lengths change from round to round.
        let mut order = [0; N];
        let mut count = 0;
        for l in (0..N).filter(|&l| s.searching[l]) {
            order[count] = l;
            count += 1;
        }
        let order = &order[..count];
        match count {
            0 => {}
            1..=4 => search_packed::<N, 4>(state, history, law, w, order, &mut s),
            5..=8 => search_packed::<N, 8>(state, history, law, w, order, &mut s),
            _ => search_packed::<N, N>(state, history, law, w, order, &mut s),
        }
        std::array::from_fn(|l| searched[l].then(|| (s.hi[l], s.probed_hi[l].then_some(s.hi_step[l]))))
    }

    /// The bracket `(0, h_s)` of a search under way at the start (`g_lo` =
    /// `sign · v` > 0 there, `g_hi` ≤ 0 after the full step): its first
    /// guess and its tolerance (s), as [`Path::locate_velocity_zero`]
    /// starts it.
    fn first_newton_guess(&self, start: Trig, h_s: f64, sign: f64, g_lo: f64, g_hi: f64) -> (f64, f64) {
        let (lo, hi) = (0.0, h_s);
        let tolerance = 1e-15 * h_s.max(self.osc.period_s * 1e-6);
        let mut x = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
        let b = sign * self.slip_rates::<false>(start.cos, self.x_m, self.v_m_per_s, self.memory, sign).0;
        let c = (g_hi - g_lo - b * h_s) / (h_s * h_s);
        let disc = b * b - 4.0 * c * g_lo;
        if disc >= 0.0 {
            x = 2.0 * g_lo / (disc.sqrt() - b);
        }
        (x, tolerance)
    }
}

/// The searches of the lanes `order` (at most `M`), round by round until
/// each has ended: their states packed into `M` lanes once (the rest copies
/// of the first, discarded), then each round one vector probe of every
/// packed lane and each searching lane's Newton step on its own probe, as
/// [`Path::locate_velocity_zero`]'s loop takes it.
#[inline(always)]
fn search_packed<const N: usize, const M: usize>(
    state: &simd::SlipLanes<N>,
    history: Option<&simd::History<'_, N>>,
    law: &simd::SlipLaw,
    omega: f64,
    order: &[usize],
    s: &mut Searches<N>,
) {
    let lane = |j: usize| order.get(j).copied().unwrap_or(order[0]);
    let packed = simd::SlipLanes::<M> {
        x_m: std::array::from_fn(|j| state.x_m[lane(j)]),
        v_m_per_s: std::array::from_fn(|j| state.v_m_per_s[lane(j)]),
        sign: std::array::from_fn(|j| state.sign[lane(j)]),
        friction_noise: std::array::from_fn(|j| state.friction_noise[lane(j)]),
        normal_force_n: std::array::from_fn(|j| state.normal_force_n[lane(j)]),
        cos: std::array::from_fn(|j| state.cos[lane(j)]),
        sin: std::array::from_fn(|j| state.sin[lane(j)]),
        memory: std::array::from_fn(|j| state.memory[lane(j)]),
    };
    let packed_history = history.map(|h| simd::History::<M> {
        lanes: simd::HistoryLanes {
            slip_start_x_m: std::array::from_fn(|j| h.lanes.slip_start_x_m[lane(j)]),
            stiction_excess: std::array::from_fn(|j| h.lanes.stiction_excess[lane(j)]),
        },
        law: h.law,
    });
    // The law's per-lane terms packed like the lanes.
    let pack = |terms: &[f64; LANES]| std::array::from_fn(|j| if j < M { terms[lane(j)] } else { 0.0 });
    let law =
        simd::SlipLaw { a_offset: pack(&law.a_offset), b: pack(&law.b), d_s2_per_m2: pack(&law.d_s2_per_m2), ..*law };
    for _ in 0..100 {
        let mut searching = false;
        for &l in order {
            if !s.searching[l] {
                continue;
            }
            if s.hi[l] - s.lo[l] <= s.tolerance[l] {
                s.searching[l] = false;
                continue;
            }
            if !(s.x[l] > s.lo[l] && s.x[l] < s.hi[l]) {
                s.x[l] = 0.5 * (s.lo[l] + s.hi[l]);
            }
            searching = true;
        }
        if !searching {
            break;
        }
        let probes = std::array::from_fn(|j| s.x[lane(j)]);
        let probed = simd::probe_step(&packed, &law, packed_history.as_ref(), probes, omega);
        for (j, &l) in order.iter().enumerate() {
            if !s.searching[l] {
                continue;
            }
            newton_round(&packed, &probed, j, l, s);
        }
    }
}

/// Lane `l`'s Newton step on its probe, packed lane `j` of `probed`.
#[inline(always)]
fn newton_round<const N: usize, const M: usize>(
    packed: &simd::SlipLanes<M>,
    probed: &simd::ProbedLanes<M>,
    j: usize,
    l: usize,
    s: &mut Searches<N>,
) {
    let sign = packed.sign[j];
    let x = s.x[l];
    let g_x = sign * probed.v_m_per_s[j];
    let slope = sign * probed.end_acceleration[j];
    let newton = x - g_x / slope;
    let tolerance = s.tolerance[l];
    if g_x > 0.0 {
        s.lo[l] = x;
    } else {
        s.hi[l] = x;
        s.probed_hi[l] = true;
        // As the scalar RK4 step returns it.
        s.hi_step[l] = SlipStep {
            x_m: probed.x_m[j],
            v_m_per_s: probed.v_m_per_s[j],
            memory: probed.memory[j],
            stage_x_m: probed.stage_x_m.map(|x| x[j]),
            trig: [
                Trig { cos: packed.cos[j], sin: packed.sin[j] },
                Trig { cos: probed.mid_cos[j], sin: probed.mid_sin[j] },
                Trig { cos: probed.end_cos[j], sin: probed.end_sin[j] },
            ],
        };
        if (newton - x).abs() < 0.5 * tolerance {
            s.searching[l] = false;
            return;
        }
    }
    s.x[l] =
        if (newton - x).abs() < 0.5 * tolerance { x + if g_x > 0.0 { 0.5 } else { -0.5 } * tolerance } else { newton };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{Condition, Model};
    use rand::{RngExt, SeedableRng};

    /// The lanes' zeros located side by side are each lane's own search's,
    /// bit for bit, with lanes slipping either way (some stuck, some with no
    /// zero in the step), over a grid step whose half turn is the search's
    /// and one whose is not, at each group width, on the baseline and with
    /// a friction history (a time-lag memory over a decaying stiction, and
    /// Dahl's build-up).
    #[test]
    fn zeros_side_by_side_are_those_located_alone() {
        let histories: [&[&str]; 3] = [
            &[],
            &[
                "friction_hysteresis.form=\"lag\"",
                "friction_hysteresis.time_constant_s=0.01",
                "stiction.excess=0.15",
                "stiction.form=\"decaying\"",
            ],
            &["friction_hysteresis.form=\"dahl\"", "friction_hysteresis.length_m=2e-4"],
        ];
        for overrides in histories {
            let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
            let model = Model::paper_rig(&overrides).expect("the paper rig");
            let osc = Oscillator::new(&model, Condition { excitation_frequency_hz: 12.0, normal_force_n: 16.39 })
                .expect("an oscillator");
            let compared = compare::<16>(&osc) + compare::<8>(&osc) + compare::<4>(&osc);
            assert!(compared > 500, "only {compared} zeros compared with {overrides:?}");
        }
    }

    /// Zeros compared.
    fn compare<const N: usize>(osc: &Oscillator) -> usize {
        let initial = InitialState { x_m: 0.0, v_m_per_s: 0.0 };
        let mut rng = rand::rngs::StdRng::seed_from_u64(0x2545_F491_4F6C_DD1D);
        let mut uniform = || rng.random::<f64>();
        let w = osc.omega_rad_per_s;
        let mut compared = 0;
        for trial in 0..100 {
            let h_s = osc.period_s / 64.0 * (0.5 + uniform());
            // The vector step's half turn is the search's, or (every third
            // trial) a last bit off it, as a span's equal steps can be.
            let mut half = Trig::turn(0.5 * w * h_s);
            if trial % 3 == 0 {
                half.cos = f64::from_bits(half.cos.to_bits() - 1);
            }
            let mut lanes: [Path<'_>; N] = std::array::from_fn(|r| Path::new(osc, 7, r as u32, initial));
            let mut trigs = [Trig { cos: 1.0, sin: 0.0 }; N];
            for (l, (p, trig)) in lanes.iter_mut().zip(&mut trigs).enumerate() {
                let sign = [1.0, -1.0, 1.0, 0.0, -1.0][l % 5];
                p.mode = if sign == 0.0 { Mode::Stick } else { Mode::Slip(sign as i8) };
                p.x_m = 3e-3 * (uniform() - 0.5);
                // Slow enough for the step to reverse many of them.
                p.v_m_per_s = sign * 0.02 * uniform();
                p.friction_noise = 0.1 * (uniform() - 0.5);
                // What a history reads: a memory near the law, a slip
                // started up to a few tenths of a mm back, an excess.
                p.memory = 0.3 + 0.2 * uniform();
                p.slip_start_x_m = p.x_m - sign * 4e-4 * uniform();
                p.stiction_excess = 0.15 * uniform();
                *trig = Trig::at(std::f64::consts::TAU * uniform());
            }
            let sign: [f64; N] = std::array::from_fn(|l| match lanes[l].mode {
                Mode::Slip(s) => f64::from(s),
                Mode::Stick => 0.0,
            });
            let state = Path::slip_state(&lanes, &trigs, sign);
            let history = Path::history(&lanes);
            let law = Path::slip_law(&lanes);
            let step = simd::slip_step(&state, &law, history.as_ref(), h_s, half);
            let zero: [bool; N] = std::array::from_fn(|l| sign[l] != 0.0 && sign[l] * step.v_m_per_s[l] <= 0.0);
            let located = Path::locate_zeros(&lanes, &state, &law, history.as_ref(), zero, h_s, half, step.v_m_per_s);
            let searched_half = Trig::turn(0.5 * w * h_s);
            let same_step = searched_half.cos.to_bits() == half.cos.to_bits();
            for l in 0..N {
                let Some((h_zero, to_zero)) = located[l] else {
                    assert!(!zero[l] || sign[l] * lanes[l].v_m_per_s <= 0.0, "lane {l} not searched");
                    continue;
                };
                let full_v = same_step.then_some(step.v_m_per_s[l]);
                let (alone_h, alone_step) = lanes[l].locate_velocity_zero(trigs[l], h_s, sign[l], full_v);
                assert_eq!(h_zero.to_bits(), alone_h.to_bits(), "lane {l} of {N}, trial {trial}");
                let bits = |s: Option<SlipStep>| {
                    s.map(|s| {
                        let trig = s.trig.map(|t| [t.cos, t.sin]).concat();
                        [&[s.x_m, s.v_m_per_s, s.memory][..], &s.stage_x_m, &trig]
                            .concat()
                            .iter()
                            .map(|v| v.to_bits())
                            .collect::<Vec<_>>()
                    })
                };
                assert_eq!(bits(to_zero), bits(alone_step), "lane {l} of {N}, trial {trial}");
                compared += 1;
            }
        }
        compared
    }
}
