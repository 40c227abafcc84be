//! The slip step of up to [`LANES`] realisations at once as vector
//! code: the RK4 step laid out as structure of arrays, one array element per
//! lane, so that each operation is one vector instruction over the lanes
//! instead of a scalar one per lane. The baseline's law (an adhesion force
//! included) has its own straight-line code; a friction history (hysteresis,
//! a friction memory, a stiction excess carried into the slip) branches on
//! its forms, which are the same for every lane, and calls the effects'
//! own functions lane by lane where they have no vector form (`exp`,
//! `tanh`, `ln`).
//!
//! Each lane's arithmetic is [`Path::rk4_slip_with`](super::Path) and
//! [`Path::add_slip_phase`](super::Path)'s, operation for operation and in
//! the same order (no fused multiply-add: IEEE arithmetic on a vector's
//! element rounds as on a scalar), so the answers are the scalar path's,
//! bit for bit. Stuck lanes are stepped too (with sign 0; their results
//! are discarded), so the code has no branch per lane: a condition is a
//! select.
//!
//! The kernel is compiled three times — for the baseline target (SSE2's
//! two f64 a register), for AVX2 (four) and for AVX-512 (eight) — and the
//! widest the processor has is chosen at run time.

mod lanes;
mod law;

use super::Trig;
pub(crate) use lanes::LANES;
use lanes::V;
pub(super) use lanes::{HistoryLanes, SlipLanes};
pub(super) use law::{HistoryLaw, SlipLaw};
use law::{acceleration, history_rates};

/// A friction history of `N` lanes: what each lane carries, and the law.
#[derive(Clone, Copy, Debug)]
pub(super) struct History<'a, const N: usize> {
    pub(super) lanes: HistoryLanes<N>,
    pub(super) law: HistoryLaw<'a>,
}

/// A slip step's results, one element per lane.
#[derive(Clone, Copy, Debug)]
pub(super) struct SlippedLanes<const N: usize> {
    /// Displacement at the step's end, m.
    pub(super) x_m: [f64; N],
    /// Velocity at the step's end, m/s.
    pub(super) v_m_per_s: [f64; N],
    /// `cos Ωt` and `sin Ωt` of the base at the step's end, –.
    pub(super) end_cos: [f64; N],
    pub(super) end_sin: [f64; N],
    /// The step's RK4 quadrature of `x cos(Ωt)` and `x sin(Ωt)`, m·s.
    pub(super) cos_integral: [f64; N],
    pub(super) sin_integral: [f64; N],
    /// The friction memory at the step's end (the start's plus 0 without
    /// one, as the scalar step's).
    pub(super) memory: [f64; N],
}

/// One RK4 slip step of every lane over `h_s` seconds, `half` the rotation
/// by `Ωh/2`, with the widest vector unit there is.
pub(super) fn slip_step<const N: usize>(
    lanes: &SlipLanes<N>,
    law: &SlipLaw,
    history: Option<&History<'_, N>>,
    h_s: f64,
    half: Trig,
) -> SlippedLanes<N> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the processor has AVX-512F, checked just above.
            return unsafe { slip_step_avx512(lanes, law, history, h_s, half) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { slip_step_avx2(lanes, law, history, h_s, half) };
        }
    }
    slip_step_lanes(lanes, law, history, h_s, half)
}

/// [`slip_step_lanes`] compiled for AVX-512.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn slip_step_avx512<const N: usize>(
    lanes: &SlipLanes<N>,
    law: &SlipLaw,
    history: Option<&History<'_, N>>,
    h_s: f64,
    half: Trig,
) -> SlippedLanes<N> {
    slip_step_lanes(lanes, law, history, h_s, half)
}

/// [`slip_step_lanes`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn slip_step_avx2<const N: usize>(
    lanes: &SlipLanes<N>,
    law: &SlipLaw,
    history: Option<&History<'_, N>>,
    h_s: f64,
    half: Trig,
) -> SlippedLanes<N> {
    slip_step_lanes(lanes, law, history, h_s, half)
}

/// The RK4 stages of every lane from the step's start over `h` (s), with
/// `hh` = `0.5 · h` and `sixth` = `h / 6` (s), `half` the rotation by
/// `Ωh/2` (cos, sin), and `rates` the acceleration and the memory's rate
/// at (cos Ωt, x, v, memory): [`Path::rk4_slip_with`](super::Path)'s
/// operations.
#[inline(always)]
fn rk4_lanes<const N: usize>(
    lanes: &SlipLanes<N>,
    (h, hh, sixth): (V<N>, V<N>, V<N>),
    half: (V<N>, V<N>),
    rates: impl Fn(V<N>, V<N>, V<N>, V<N>) -> (V<N>, V<N>),
) -> Stages<N> {
    let (start_cos, start_sin) = (V(lanes.cos), V(lanes.sin));
    let (mid_cos, mid_sin) = rotated((start_cos, start_sin), half);
    let (end_cos, end_sin) = rotated((mid_cos, mid_sin), half);
    let (x, v, m) = (V(lanes.x_m), V(lanes.v_m_per_s), V(lanes.memory));
    let two = V::splat(2.0);
    let k1x = v;
    let (k1v, k1m) = rates(start_cos, x, v, m);
    let k2x = v + hh * k1v;
    let x2 = x + hh * k1x;
    let (k2v, k2m) = rates(mid_cos, x2, k2x, m + hh * k1m);
    let k3x = v + hh * k2v;
    let x3 = x + hh * k2x;
    let (k3v, k3m) = rates(mid_cos, x3, k3x, m + hh * k2m);
    let k4x = v + h * k3v;
    let x4 = x + h * k3x;
    let (k4v, k4m) = rates(end_cos, x4, k4x, m + h * k3m);
    Stages {
        x_end: x + sixth * (k1x + two * k2x + two * k3x + k4x),
        v_end: v + sixth * (k1v + two * k2v + two * k3v + k4v),
        memory_end: m + sixth * (k1m + two * k2m + two * k3m + k4m),
        stage_x: [x, x2, x3, x4],
        mid: (mid_cos, mid_sin),
        end: (end_cos, end_sin),
    }
}

/// `Trig::rotated` of every lane: (cos, sin) advanced by the rotation
/// `half` (cos, sin). A function, not a closure, so that it can be marked
/// inline: the compiler made the closure a call of its own, outside the
/// vector copies (5% of the noisy workload's time).
#[inline(always)]
fn rotated<const N: usize>((cos, sin): (V<N>, V<N>), (half_cos, half_sin): (V<N>, V<N>)) -> (V<N>, V<N>) {
    (cos * half_cos - sin * half_sin, sin * half_cos + cos * half_sin)
}

/// [`rk4_lanes`]'s results: the end state (m, m/s, the memory), the four
/// stage displacements (m) and the base's (cos, sin) in the middle and at
/// the end.
struct Stages<const N: usize> {
    x_end: V<N>,
    v_end: V<N>,
    memory_end: V<N>,
    stage_x: [V<N>; 4],
    mid: (V<N>, V<N>),
    end: (V<N>, V<N>),
}

/// The rates for [`rk4_lanes`]: the baseline's acceleration and no memory,
/// or a friction history's acceleration and memory rate.
#[inline(always)]
fn rates<'a, const N: usize>(
    law: &'a SlipLaw,
    lanes: &'a SlipLanes<N>,
    history: Option<&'a History<'_, N>>,
) -> impl Fn(V<N>, V<N>, V<N>, V<N>) -> (V<N>, V<N>) + 'a {
    #[inline(always)]
    move |cos, x, v, m| match history {
        None => (acceleration(law, lanes, cos, x, v), V::splat(0.0)),
        Some(h) => history_rates(law, &h.law, lanes, &h.lanes, cos, x, v, m),
    }
}

/// The step itself, inlined into each target's copy.
#[inline(always)]
fn slip_step_lanes<const N: usize>(
    lanes: &SlipLanes<N>,
    law: &SlipLaw,
    history: Option<&History<'_, N>>,
    h_s: f64,
    half: Trig,
) -> SlippedLanes<N> {
    let lengths = (V::splat(h_s), V::splat(0.5 * h_s), V::splat(h_s / 6.0));
    let half = (V::splat(half.cos), V::splat(half.sin));
    // The branch outside the stages: each arm its own straight-line code.
    let s = match history {
        None => rk4_lanes(lanes, lengths, half, rates(law, lanes, None)),
        Some(_) => rk4_lanes(lanes, lengths, half, rates(law, lanes, history)),
    };
    slipped(lanes, lengths.2, &s)
}

/// A step's results from its stages, `sixth` = `h / 6` (s), with
/// `Path::add_slip_phase`'s increments.
#[inline(always)]
fn slipped<const N: usize>(lanes: &SlipLanes<N>, sixth: V<N>, s: &Stages<N>) -> SlippedLanes<N> {
    let (start_cos, start_sin) = (V(lanes.cos), V(lanes.sin));
    let ((mid_cos, mid_sin), (end_cos, end_sin)) = (s.mid, s.end);
    let [x, x2, x3, x4] = s.stage_x;
    let middle = V::splat(2.0) * (x2 + x3);
    let cos_integral = sixth * (x * start_cos + middle * mid_cos + x4 * end_cos);
    let sin_integral = sixth * (x * start_sin + middle * mid_sin + x4 * end_sin);
    SlippedLanes {
        x_m: s.x_end.0,
        v_m_per_s: s.v_end.0,
        end_cos: end_cos.0,
        end_sin: end_sin.0,
        cos_integral: cos_integral.0,
        sin_integral: sin_integral.0,
        memory: s.memory_end.0,
    }
}

/// Probes of a velocity zero's search, one per lane, each over its own
/// step length: the RK4 step and the acceleration at its end, one element
/// per lane.
#[derive(Clone, Copy, Debug)]
pub(super) struct ProbedLanes<const N: usize> {
    /// Displacement and velocity at the probe's end, m and m/s.
    pub(super) x_m: [f64; N],
    pub(super) v_m_per_s: [f64; N],
    /// The stage displacements `[x, x2, x3, x4]`, m.
    pub(super) stage_x_m: [[f64; N]; 4],
    /// `cos Ωt` and `sin Ωt` of the base in the probe's middle and at its end, –.
    pub(super) mid_cos: [f64; N],
    pub(super) mid_sin: [f64; N],
    pub(super) end_cos: [f64; N],
    pub(super) end_sin: [f64; N],
    /// The acceleration at the end (the slip ODE's at the end state), m/s².
    pub(super) end_acceleration: [f64; N],
    /// The friction memory at the probe's end (the start's plus 0 without
    /// one).
    pub(super) memory: [f64; N],
}

/// One RK4 slip step of every lane over its own `h_s[l]` seconds (base
/// angular frequency `omega`, rad/s), as [`Path::locate_velocity_zero`]'s
/// `step_to` takes it (the half turn `Trig::turn(0.5 · Ω · h)`), and the
/// acceleration at each step's end, with the widest vector unit there is.
pub(super) fn probe_step<const N: usize>(
    lanes: &SlipLanes<N>,
    law: &SlipLaw,
    history: Option<&History<'_, N>>,
    h_s: [f64; N],
    omega: f64,
) -> ProbedLanes<N> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the processor has AVX-512F, checked just above.
            return unsafe { probe_step_avx512(lanes, law, history, h_s, omega) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { probe_step_avx2(lanes, law, history, h_s, omega) };
        }
    }
    probe_step_lanes(lanes, law, history, h_s, omega)
}

/// [`probe_step_lanes`] compiled for AVX-512.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn probe_step_avx512<const N: usize>(
    lanes: &SlipLanes<N>,
    law: &SlipLaw,
    history: Option<&History<'_, N>>,
    h_s: [f64; N],
    omega: f64,
) -> ProbedLanes<N> {
    probe_step_lanes(lanes, law, history, h_s, omega)
}

/// [`probe_step_lanes`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn probe_step_avx2<const N: usize>(
    lanes: &SlipLanes<N>,
    law: &SlipLaw,
    history: Option<&History<'_, N>>,
    h_s: [f64; N],
    omega: f64,
) -> ProbedLanes<N> {
    probe_step_lanes(lanes, law, history, h_s, omega)
}

/// The probes themselves, inlined into each target's copy.
#[inline(always)]
fn probe_step_lanes<const N: usize>(
    lanes: &SlipLanes<N>,
    law: &SlipLaw,
    history: Option<&History<'_, N>>,
    h_s: [f64; N],
    omega: f64,
) -> ProbedLanes<N> {
    let h = V(h_s);
    // `Trig::turn(0.5 * w * h)`: the series where it holds, `sin_cos` (lane
    // by lane) where it does not.
    let theta = V::splat(0.5 * omega) * h;
    let t2 = theta * theta;
    let q = |d: f64| t2 / V::splat(d);
    let one = V::splat(1.0);
    let series_sin = theta * (one - q(6.0) * (one - q(20.0) * (one - q(42.0) * (one - q(72.0)))));
    // t2/2 is t2 · ½ exactly.
    let series_cos = one - t2 * V::splat(0.5) * (one - q(12.0) * (one - q(30.0) * (one - q(56.0) * (one - q(90.0)))));
    let mut half = (series_cos, series_sin);
    if theta.0.iter().any(|t| t.abs() > 0.1) {
        for l in 0..N {
            if theta.0[l].abs() > 0.1 {
                let (sin, cos) = theta.0[l].sin_cos();
                (half.0.0[l], half.1.0[l]) = (cos, sin);
            }
        }
    }
    let lengths = (h, V::splat(0.5) * h, h / V::splat(6.0));
    let (s, end_acceleration) = match history {
        None => {
            let s = rk4_lanes(lanes, lengths, half, rates(law, lanes, None));
            let end = acceleration(law, lanes, s.end.0, s.x_end, s.v_end);
            (s, end)
        }
        Some(h) => {
            let s = rk4_lanes(lanes, lengths, half, rates(law, lanes, history));
            let end = history_rates(law, &h.law, lanes, &h.lanes, s.end.0, s.x_end, s.v_end, s.memory_end).0;
            (s, end)
        }
    };
    ProbedLanes {
        x_m: s.x_end.0,
        v_m_per_s: s.v_end.0,
        stage_x_m: s.stage_x.map(|x| x.0),
        mid_cos: s.mid.0.0,
        mid_sin: s.mid.1.0,
        end_cos: s.end.0.0,
        end_sin: s.end.1.0,
        end_acceleration: end_acceleration.0,
        memory: s.memory_end.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::effects::{EffectParams, HysteresisForm, Memory, StictionForm};
    use rand::{RngExt, SeedableRng};

    /// Every compiled copy of the step gives the same bits (the one the
    /// processor runs is checked against the scalar path elsewhere), with
    /// lanes slipping either way, past a velocity zero and stuck, at each
    /// group width (one vector register of AVX-512 and two), the baseline's
    /// and a friction history's.
    #[test]
    fn every_copy_of_the_step_gives_the_same_bits() {
        copies_give_the_same_bits::<8>();
        copies_give_the_same_bits::<16>();
    }

    fn copies_give_the_same_bits<const N: usize>() {
        let mut law = SlipLaw {
            a_offset: [0.35; LANES],
            b: [0.1; LANES],
            d_s2_per_m2: [0.02; LANES],
            c_s_per_m: 40.0,
            stiffness_n_per_m: 2.0e4,
            base_amplitude_m: 1e-3,
            damping_n_s_per_m: 3.0,
            inv_mass: 1.0 / 1.6,
            adhesion_n: 0.0,
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(0x9E37_79B9_7F4A_7C15);
        let mut uniform = || rng.random::<f64>();
        let history = |form, length_m, lag_s, stiction_form, release_m| EffectParams {
            hysteresis_form: form,
            hysteresis_length_m: length_m,
            hysteresis_lag_s: lag_s,
            hysteresis_strength: 0.05,
            stiction_form,
            stiction_release_m: release_m,
            ..EffectParams::default()
        };
        let histories = [
            history(HysteresisForm::Lag, 0.0, 0.01, StictionForm::Constant, 0.0),
            history(HysteresisForm::Slip, 2e-4, 0.0, StictionForm::Decaying, 0.0),
            history(HysteresisForm::Ageing, 2e-4, 0.0, StictionForm::Constant, 3e-4),
            history(HysteresisForm::Tanh, 2e-4, 0.0, StictionForm::Constant, 0.0),
            history(HysteresisForm::Dahl, 2e-4, 0.0, StictionForm::Decaying, 0.0),
        ];
        for iteration in 0..200 {
            // Without an adhesion force, with one, and with one that μN
            // clips (A < −μN at small loads).
            law.adhesion_n = [0.0, 0.3, -2.0][iteration % 3];
            let mut lanes = SlipLanes::<N> {
                x_m: [0.0; N],
                v_m_per_s: [0.0; N],
                sign: [0.0; N],
                friction_noise: [0.0; N],
                normal_force_n: [0.0; N],
                cos: [0.0; N],
                sin: [0.0; N],
                memory: [0.0; N],
            };
            let mut past = HistoryLanes::<N> { slip_start_x_m: [0.0; N], stiction_excess: [0.0; N] };
            for l in 0..N {
                let angle = std::f64::consts::TAU * uniform();
                lanes.x_m[l] = 2e-3 * (uniform() - 0.5);
                lanes.v_m_per_s[l] = 0.1 * (uniform() - 0.5);
                lanes.sign[l] = [-1.0, 0.0, 1.0][l % 3];
                lanes.friction_noise[l] = 0.1 * (uniform() - 0.5);
                lanes.normal_force_n[l] = 16.0 * uniform();
                (lanes.cos[l], lanes.sin[l]) = (angle.cos(), angle.sin());
                lanes.memory[l] = 0.5 * uniform();
                // Each lane's law at a load of its own.
                law.a_offset[l] = 0.3 + 0.1 * uniform();
                law.b[l] = 0.1 * uniform();
                law.d_s2_per_m2[l] = 0.04 * uniform();
                past.slip_start_x_m[l] = 2e-3 * (uniform() - 0.5);
                past.stiction_excess[l] = 0.1 * uniform();
            }
            let h_s = 2e-3 * uniform();
            let half = Trig { cos: (0.5 * 70.0 * h_s).cos(), sin: (0.5 * 70.0 * h_s).sin() };
            let bits = |s: SlippedLanes<N>| {
                [s.x_m, s.v_m_per_s, s.end_cos, s.end_sin, s.cos_integral, s.sin_integral, s.memory]
                    .map(|a| a.map(f64::to_bits))
            };
            // Every other step the baseline's; between, each memory, a
            // build-up with and without Dahl's reversal, and the stiction
            // excesses carried into a slip.
            let effects = &histories[iteration % histories.len()];
            let history = History {
                lanes: past,
                law: HistoryLaw {
                    effects,
                    memory: Memory::form(effects),
                    dahl: matches!(effects.hysteresis_form, HysteresisForm::Dahl | HysteresisForm::Bristle),
                },
            };
            let history = (iteration % 2 == 1).then_some(&history);
            let portable = bits(slip_step_lanes(&lanes, &law, history, h_s, half));
            assert_eq!(bits(slip_step(&lanes, &law, history, h_s, half)), portable);
            // Probes, each lane over its own length (some past the series'
            // range of the half turn).
            let probes: [f64; N] = std::array::from_fn(|l| if l == 1 { 0.01 } else { h_s * uniform() });
            let probed_bits = |s: ProbedLanes<N>| {
                let [a, b, c, d] = s.stage_x_m;
                [
                    s.x_m,
                    s.v_m_per_s,
                    a,
                    b,
                    c,
                    d,
                    s.mid_cos,
                    s.mid_sin,
                    s.end_cos,
                    s.end_sin,
                    s.end_acceleration,
                    s.memory,
                ]
                .map(|a| a.map(f64::to_bits))
            };
            let probed = probed_bits(probe_step_lanes(&lanes, &law, history, probes, 70.0));
            assert_eq!(probed_bits(probe_step(&lanes, &law, history, probes, 70.0)), probed);
            #[cfg(target_arch = "x86_64")]
            {
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor has AVX2, checked just above.
                    assert_eq!(bits(unsafe { slip_step_avx2(&lanes, &law, history, h_s, half) }), portable);
                    // SAFETY: as above.
                    assert_eq!(probed_bits(unsafe { probe_step_avx2(&lanes, &law, history, probes, 70.0) }), probed);
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the processor has AVX-512F, checked just above.
                    assert_eq!(bits(unsafe { slip_step_avx512(&lanes, &law, history, h_s, half) }), portable);
                    // SAFETY: as above.
                    assert_eq!(probed_bits(unsafe { probe_step_avx512(&lanes, &law, history, probes, 70.0) }), probed);
                }
            }
        }
    }
}
