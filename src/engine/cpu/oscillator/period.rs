//! A period of up to [`LANES`] realisations of one model at one frequency stepped
//! together, grid step by grid step, and the samples a record takes on the
//! way.

use super::*;
use super::{interval, simd};

/// Half of [`LANES`]: a group of fewer steps this many together.
const HALF_LANES: usize = LANES / 2;

/// The smallest set of lanes stepped together: a diagnosis's search runs 4
/// replicates per condition.
pub(crate) const QUARTER_LANES: usize = LANES / 4;

/// The group sizes that step together ([`advance_lanes`] takes each),
/// widest first; other sizes step one realisation at a time.
pub(crate) const LANE_WIDTHS: [usize; 3] = [LANES, HALF_LANES, QUARTER_LANES];

/// Advances every path in `lanes` over the grid step `[t_a, t_b]` (local
/// times in the period; `turn` rotates by half of it), each from its base
/// trig in `trigs`. With a set of lanes of one of the [`LANE_WIDTHS`], the
/// slip step is taken for every slipping lane first, as if none met an
/// event, and kept where the lane still slips at the step's end; every other
/// lane takes [`Path::advance_segment_past`] from the step's start (a
/// slipping one told where that same step ended, so it takes it no second
/// time), so the answers are those of one path at a time, bit for bit.
fn advance_lanes(
    lanes: &mut [Path<'_>],
    trigs: &mut [Trig],
    law: &simd::SlipLaw,
    (t_a, t_b): (f64, f64),
    turn: Trig,
    measuring: bool,
) {
    match lanes.len() {
        LANES => slip_lanes::<LANES>(lanes, trigs, law, t_a, t_b, turn, measuring),
        QUARTER_LANES => slip_lanes::<QUARTER_LANES>(lanes, trigs, law, t_a, t_b, turn, measuring),
        HALF_LANES => slip_lanes::<HALF_LANES>(lanes, trigs, law, t_a, t_b, turn, measuring),
        _ => {
            for (path, trig) in lanes.iter_mut().zip(trigs.iter_mut()) {
                *trig = path.advance_segment(t_a, t_b, *trig, Some(turn), measuring);
            }
        }
    }
}

/// [`advance_lanes`] for `N` lanes. The slip step is the baseline's vector
/// step, or the vector step of a friction history where one is on (the
/// same for all lanes: it is the model's). A stuck lane's step is
/// taken and thrown away: the vector code has no branch per lane.
#[inline(always)]
fn slip_lanes<const N: usize>(
    lanes: &mut [Path<'_>],
    trigs: &mut [Trig],
    law: &simd::SlipLaw,
    t_a: f64,
    t_b: f64,
    turn: Trig,
    measuring: bool,
) {
    let lanes: &mut [Path<'_>; N] = lanes.try_into().expect("N lanes");
    let trigs: &mut [Trig; N] = trigs.try_into().expect("a trig per lane");
    let h = t_b - t_a;
    let signs: [f64; N] = std::array::from_fn(|l| match lanes[l].mode {
        Mode::Slip(s) => f64::from(s),
        Mode::Stick => 0.0,
    });
    let state = Path::slip_state(lanes, trigs, signs);
    let history = Path::history(lanes);
    let step = simd::slip_step(&state, law, history.as_ref(), h, turn);
    let zero: [bool; N] = std::array::from_fn(|l| signs[l] != 0.0 && signs[l] * step.v_m_per_s[l] <= 0.0);
    // Two or more zeros in the step are located side by side.
    let mut located = [None; N];
    if zero.iter().filter(|&&z| z).count() > 1 {
        located = Path::locate_zeros(lanes, &state, law, history.as_ref(), zero, h, turn, step.v_m_per_s);
    }
    for l in 0..N {
        trigs[l] = if signs[l] * step.v_m_per_s[l] > 0.0 {
            lanes[l].commit_slip_lane(&step, l, measuring)
        } else {
            let past_zero = zero[l].then_some(PastZero { full_step_v: step.v_m_per_s[l], located: located[l] });
            lanes[l].advance_segment_past(t_a, t_b, trigs[l], Some(turn), measuring, past_zero)
        };
    }
}

/// Integrates one excitation period of every path in `lanes` (at most
/// [`LANES`] realisations of oscillators that step together,
/// [`steps_beside`], in the same period; with
/// `samplers`, one per path). Noise-interval boundaries, output samples and
/// the period's end are step boundaries: each span between them is divided
/// into the fewest equal steps no longer than `T / S` (`S` =
/// `steps_per_period`). The base's trig starts exact at the period's start
/// and is carried by rotation (recomputed exactly after each event); in f64
/// the rotations drift by about 1e-16 each.
pub(crate) fn run_period(lanes: &mut [Path<'_>], measuring: bool, mut samplers: Option<&mut [Sampler]>) {
    assert!(!lanes.is_empty() && lanes.len() <= LANES, "1 to {LANES} paths step together, not {}", lanes.len());
    let o = lanes[0].osc;
    debug_assert!(lanes.iter().all(|p| steps_beside(p.osc, o) && p.next_boundary == lanes[0].next_boundary));
    let w = o.omega_rad_per_s;
    let max_step_s = o.period_s / f64::from(o.steps_per_period);
    let period_start_s = lanes[0].period as f64 * o.period_s;
    for path in lanes.iter_mut() {
        path.period_max_x_m = path.x_m;
        path.period_stick_s = 0.0;
        path.period_cos_integral = 0.0;
        path.period_sin_integral = 0.0;
    }
    // The lanes' law, the same all period.
    let law = Path::slip_law(lanes);
    let mut t = 0.0;
    let mut trigs = [Trig { cos: 1.0, sin: 0.0 }; LANES];
    let trigs = &mut trigs[..lanes.len()];
    // The last span's bits, its steps, their length (s) and half turn:
    // most noise intervals' spans repeat the one before bit for bit.
    let mut last_span: Option<(u64, u32, f64, Trig)> = None;
    while t < o.period_s {
        let next_boundary = lanes[0].next_boundary;
        let noise_t = if next_boundary >> 32 == lanes[0].period {
            (next_boundary & 0xFFFF_FFFF) as f64 / FIXED_ONE * o.period_s
        } else {
            f64::INFINITY
        };
        // Every path's sampler has taken as many samples: the first's
        // times are all of theirs.
        let sampler = samplers.as_deref().map(|s| &s[0]);
        let sample_t =
            sampler.filter(|s| s.from_interval.is_none()).map_or(f64::INFINITY, |s| s.next_time_s() - period_start_s);
        let target = o.period_s.min(noise_t).min(sample_t).max(t);
        let span = target - t;
        if span > 0.0 {
            let (steps, h, turn) = match last_span {
                Some((bits, steps, h, turn)) if bits == span.to_bits() => (steps, h, turn),
                _ => {
                    let steps = span_steps(span, max_step_s);
                    let h = span / f64::from(steps);
                    let turn = Trig::turn(0.5 * w * h);
                    last_span = Some((span.to_bits(), steps, h, turn));
                    (steps, h, turn)
                }
            };
            let mut step_start = t;
            for k in 1..=steps {
                let step_end = if k == steps { target } else { t + f64::from(k) * h };
                advance_lanes(lanes, trigs, &law, (step_start, step_end), turn, measuring);
                step_start = step_end;
            }
        }
        t = target;
        let mut sample_now = sample_t <= target;
        if noise_t <= target {
            for path in lanes.iter_mut() {
                path.interval_phase = (next_boundary & 0xFFFF_FFFF) as f64 / FIXED_ONE;
                path.interval += 1;
                path.next_boundary += o.noise_interval_fixed;
            }
            interval::draw_lanes_noise(lanes);
            // A sampler aligned with the noise samples at each boundary.
            sample_now |= sampler.and_then(|s| s.from_interval).is_some_and(|j| lanes[0].interval >= j);
        }
        if sample_now {
            let samplers = samplers.as_deref_mut().expect("sample time implies samplers");
            for ((path, trig), sampler) in lanes.iter().zip(trigs.iter()).zip(samplers.iter_mut()) {
                sampler.push(Sample {
                    t_s: period_start_s + t,
                    x_m: path.x_m,
                    v_m_per_s: path.v_m_per_s,
                    normal_force_n: path.normal_force_n,
                    friction_force_n: path.friction_force(*trig),
                });
            }
        }
    }
    for path in lanes.iter_mut() {
        path.period += 1;
    }
}

/// The fewest equal steps no longer than `max_step_s` that cover `span_s`
/// (a span of exactly k steps takes k, up to rounding).
pub(crate) fn span_steps(span_s: f64, max_step_s: f64) -> u32 {
    // The usual case, without the division and `ceil` (a library call on
    // the baseline target): the quotient is at most 1, so its ceiling is 1.
    if span_s <= max_step_s {
        return 1;
    }
    ((span_s / max_step_s) * (1.0 - 1e-12)).ceil().max(1.0) as u32
}

/// Collects output samples at a fixed rate.
#[derive(Clone, Debug)]
pub(crate) struct Sampler {
    /// Sampling interval, s.
    pub(crate) interval_s: f64,
    /// Samples so far.
    pub(crate) samples: Vec<Sample>,
    /// Time of the first sample, s.
    pub(crate) start_s: f64,
    /// Aligned with the noise: one sample at the start of every noise
    /// interval from this index on (then `interval_s` and `start_s` are
    /// unused), so samples add no step boundaries of their own.
    pub(crate) from_interval: Option<u64>,
}

impl Sampler {
    /// A sampler recording at `start_s + i * interval_s`.
    pub(crate) fn new(interval_s: f64, start_s: f64) -> Self {
        Sampler { interval_s, samples: Vec::new(), start_s, from_interval: None }
    }

    /// A sampler recording at each noise-interval boundary from interval
    /// `first` on.
    pub(crate) fn at_noise_boundaries(first: u64) -> Self {
        Sampler { interval_s: 0.0, samples: Vec::new(), start_s: 0.0, from_interval: Some(first) }
    }

    fn next_time_s(&self) -> f64 {
        self.start_s + self.samples.len() as f64 * self.interval_s
    }

    fn push(&mut self, sample: Sample) {
        self.samples.push(sample);
    }
}
