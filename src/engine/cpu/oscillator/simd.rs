//! The slip step of up to [`LANES`](super::LANES) realisations at once as vector
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

use super::Trig;
use crate::engine::cpu::effects;
use crate::engine::effects::{
    AGEING_CUTOFF_SPEED_M_PER_S, AGEING_FLOOR_SPEED_M_PER_S, EffectParams, Memory, STICTION_DECAY_M, StictionForm,
};

/// The per-lane state a slip step starts from, one element per lane.
#[derive(Clone, Copy, Debug)]
pub(super) struct SlipLanes<const N: usize> {
    /// Displacement x, m.
    pub(super) x_m: [f64; N],
    /// Velocity v, m/s.
    pub(super) v_m_per_s: [f64; N],
    /// Slip direction ±1, or 0 for a stuck lane (stepped and discarded), –.
    pub(super) sign: [f64; N],
    /// Friction coefficient's random part in the current interval, –.
    pub(super) friction_noise: [f64; N],
    /// Normal force in the current interval, N.
    pub(super) normal_force_n: [f64; N],
    /// `cos Ωt` and `sin Ωt` of the base at the step's start, –.
    pub(super) cos: [f64; N],
    pub(super) sin: [f64; N],
    /// The friction memory at the step's start (μ_f, –, or θ, s; see
    /// [`Memory`]; carried unchanged without one).
    pub(super) memory: [f64; N],
}

/// What a friction history reads of each lane besides [`SlipLanes`], one
/// element per lane.
#[derive(Clone, Copy, Debug)]
pub(super) struct HistoryLanes<const N: usize> {
    /// Where the current slip started, m.
    pub(super) slip_start_x_m: [f64; N],
    /// The stiction excess carried into the slip, –.
    pub(super) stiction_excess: [f64; N],
}

/// A friction history's law, the same for every lane (the oscillator's).
#[derive(Clone, Copy, Debug)]
pub(super) struct HistoryLaw<'a> {
    /// The effects (hysteresis and stiction forms and parameters).
    pub(super) effects: &'a EffectParams,
    /// Which friction memory is on.
    pub(super) memory: Memory,
    /// Whether hysteresis `dahl` or `bristle` is on (friction may point
    /// along the motion for a while: no clip at 0).
    pub(super) dahl: bool,
}

/// A friction history of `N` lanes: what each lane carries, and the law.
#[derive(Clone, Copy, Debug)]
pub(super) struct History<'a, const N: usize> {
    pub(super) lanes: HistoryLanes<N>,
    pub(super) law: HistoryLaw<'a>,
}

/// The baseline law and the rig, the same for every lane (they are the
/// oscillator's).
#[derive(Clone, Copy, Debug)]
pub(super) struct SlipLaw {
    /// The law's `a` plus the effects' friction offset, –.
    pub(super) a_offset: f64,
    /// The law's `b`, –.
    pub(super) b: f64,
    /// The Stribeck rate `c`, s/m.
    pub(super) c_s_per_m: f64,
    /// The law's `d`, s²/m².
    pub(super) d_s2_per_m2: f64,
    /// Spring stiffness, N/m.
    pub(super) stiffness_n_per_m: f64,
    /// Base amplitude, m.
    pub(super) base_amplitude_m: f64,
    /// Damping, N·s/m.
    pub(super) damping_n_s_per_m: f64,
    /// 1 / m, 1/kg.
    pub(super) inv_mass: f64,
    /// Adhesion force A of load dependence `adhesion`, N (0 without).
    pub(super) adhesion_n: f64,
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

/// Lanes of f64, one operation for all: a vector where the target has one.
#[derive(Clone, Copy)]
struct V<const N: usize>([f64; N]);

impl<const N: usize> V<N> {
    #[inline(always)]
    fn splat(value: f64) -> Self {
        V([value; N])
    }

    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        V(self.0.map(f))
    }

    /// `f` of each lane's index: for a function of several lanes' values
    /// that has no vector form (a library call).
    #[inline(always)]
    fn lanewise(f: impl Fn(usize) -> f64) -> Self {
        V(std::array::from_fn(f))
    }

    #[inline(always)]
    fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        V(std::array::from_fn(|l| f(self.0[l], other.0[l])))
    }
}

impl<const N: usize> std::ops::Add for V<N> {
    type Output = Self;
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        self.zip(other, |a, b| a + b)
    }
}

impl<const N: usize> std::ops::Sub for V<N> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, other: Self) -> Self {
        self.zip(other, |a, b| a - b)
    }
}

impl<const N: usize> std::ops::Mul for V<N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, other: Self) -> Self {
        self.zip(other, |a, b| a * b)
    }
}

impl<const N: usize> std::ops::Div for V<N> {
    type Output = Self;
    #[inline(always)]
    fn div(self, other: Self) -> Self {
        self.zip(other, |a, b| a / b)
    }
}

/// `Path::mean_law` per lane: `a + Δa + b S(c, s) + d v²` at speed
/// `speed` and velocity `v_m_per_s` (m/s), –. `stribeck_factor`: both
/// branches, then the one the speed's sign picks.
#[inline(always)]
fn mean_law<const N: usize>(law: &SlipLaw, speed: V<N>, v_m_per_s: V<N>) -> V<N> {
    let c = V::splat(law.c_s_per_m);
    let one = V::splat(1.0);
    let under_way = one / (one + c * speed);
    let past_zero = one - c * speed;
    let stribeck = V(std::array::from_fn(|l| if speed.0[l] >= 0.0 { under_way.0[l] } else { past_zero.0[l] }));
    V::splat(law.a_offset) + V::splat(law.b) * stribeck + V::splat(law.d_s2_per_m2) * v_m_per_s * v_m_per_s
}

/// `Path::slip_rates`' acceleration from the friction coefficient `mu`
/// (–), per lane: μN plus an adhesion force (`Path::friction_force_n`),
/// against the spring and the damper, m/s².
#[inline(always)]
fn acceleration_with<const N: usize>(
    law: &SlipLaw,
    lanes: &SlipLanes<N>,
    cos_omega_t: V<N>,
    x_m: V<N>,
    v_m_per_s: V<N>,
    mu: V<N>,
) -> V<N> {
    let sign = V(lanes.sign);
    let friction_n = mu * V(lanes.normal_force_n);
    // `Path::friction_force_n`: μN plus `effects::adhesion`, A but no less than −μN.
    let friction_n = if law.adhesion_n == 0.0 {
        friction_n
    } else {
        friction_n + V::splat(law.adhesion_n).zip(friction_n.map(|f| -f), f64::max)
    };
    // `spring_force`.
    let spring = V::splat(law.stiffness_n_per_m) * (V::splat(law.base_amplitude_m) * cos_omega_t - x_m);
    (spring - V::splat(law.damping_n_s_per_m) * v_m_per_s - sign * friction_n) * V::splat(law.inv_mass)
}

/// The acceleration (m/s²) of `Path::slip_rates` without a memory or a
/// history (an adhesion force included), per lane: slipping in direction
/// `sign` with the base at `cos_omega_t`, at `x_m` (m) and `v_m_per_s` (m/s).
#[inline(always)]
fn acceleration<const N: usize>(
    law: &SlipLaw,
    lanes: &SlipLanes<N>,
    cos_omega_t: V<N>,
    x_m: V<N>,
    v_m_per_s: V<N>,
) -> V<N> {
    let speed = V(lanes.sign) * v_m_per_s;
    // `steady_law`, clipped at 0 (`friction_coefficient`).
    let mu = (mean_law(law, speed, v_m_per_s) + V(lanes.friction_noise)).zip(V::splat(0.0), f64::max);
    acceleration_with(law, lanes, cos_omega_t, x_m, v_m_per_s, mu)
}

/// `Path::slip_rates` with a friction history, per lane: the acceleration
/// (m/s²) and the friction memory's rate (`Path::memory_rate`; 0 without a
/// memory), at `x_m` (m), `v_m_per_s` (m/s) and memory `memory`. The
/// branches are on the law, the same for every lane; what has no vector
/// form (`tanh`, `exp`, `ln`) is the effects' own function, lane by lane.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn history_rates<const N: usize>(
    law: &SlipLaw,
    history: &HistoryLaw<'_>,
    lanes: &SlipLanes<N>,
    past: &HistoryLanes<N>,
    cos_omega_t: V<N>,
    x_m: V<N>,
    v_m_per_s: V<N>,
    memory: V<N>,
) -> (V<N>, V<N>) {
    let e = history.effects;
    let speed = V(lanes.sign) * v_m_per_s;
    let mean = mean_law(law, speed, v_m_per_s);
    let steady = mean + V(lanes.friction_noise);
    let slipped_m = (x_m - V(past.slip_start_x_m)).map(f64::abs);
    let length_m = e.hysteresis_length_m;
    // `Path::friction_coefficient`'s history branch.
    let mut mu = match history.memory {
        Memory::Lag | Memory::Slip => memory + V(lanes.friction_noise),
        Memory::Ageing => {
            // `Path::ageing_coefficient`.
            let steady_age_s = V::splat(length_m) / (v_m_per_s.map(f64::abs) + V::splat(AGEING_CUTOFF_SPEED_M_PER_S));
            let floor_age_s = length_m / AGEING_FLOOR_SPEED_M_PER_S;
            steady
                + V::lanewise(|l| {
                    effects::contact_age_term(e.hysteresis_strength, memory.0[l], steady_age_s.0[l], floor_age_s)
                })
        }
        Memory::None => {
            let steady = if history.dahl { steady.zip(V::splat(0.0), f64::max) } else { steady };
            steady
                * V::lanewise(|l| effects::hysteresis_factor(e.hysteresis_form, slipped_m.0[l], length_m, memory.0[l]))
        }
    };
    if e.stiction_form == StictionForm::Decaying {
        let decay = V::lanewise(|l| (-slipped_m.0[l] / STICTION_DECAY_M).exp());
        mu = mu + V(past.stiction_excess) * decay;
    } else if e.stiction_form == StictionForm::Constant && e.stiction_release_m > 0.0 {
        let left = (V::splat(1.0) - slipped_m / V::splat(e.stiction_release_m)).zip(V::splat(0.0), f64::max);
        mu = mu + V(past.stiction_excess) * left;
    }
    // Dahl's friction may point along the motion just after a reversal.
    let mu = if history.dahl { mu } else { mu.zip(V::splat(0.0), f64::max) };
    let acceleration = acceleration_with(law, lanes, cos_omega_t, x_m, v_m_per_s, mu);
    // `Path::memory_rate`.
    let rate = match history.memory {
        Memory::Lag => (mean - memory) / V::splat(e.hysteresis_lag_s),
        Memory::Slip => V::lanewise(|l| effects::slip_law_rate(mean.0[l], memory.0[l], v_m_per_s.0[l].abs(), length_m)),
        Memory::Ageing => V::lanewise(|l| effects::ageing_rate(memory.0[l], v_m_per_s.0[l].abs(), length_m)),
        Memory::None => V::splat(0.0),
    };
    (acceleration, rate)
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
    (half_cos, half_sin): (V<N>, V<N>),
    rates: impl Fn(V<N>, V<N>, V<N>, V<N>) -> (V<N>, V<N>),
) -> Stages<N> {
    // `Trig::rotated`, twice.
    let rotate = |cos: V<N>, sin: V<N>| (cos * half_cos - sin * half_sin, sin * half_cos + cos * half_sin);
    let (start_cos, start_sin) = (V(lanes.cos), V(lanes.sin));
    let (mid_cos, mid_sin) = rotate(start_cos, start_sin);
    let (end_cos, end_sin) = rotate(mid_cos, mid_sin);
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
    use crate::engine::effects::HysteresisForm;

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
        let law = SlipLaw {
            a_offset: 0.35,
            b: 0.1,
            c_s_per_m: 40.0,
            d_s2_per_m2: 0.02,
            stiffness_n_per_m: 2.0e4,
            base_amplitude_m: 1e-3,
            damping_n_s_per_m: 3.0,
            inv_mass: 1.0 / 1.6,
            adhesion_n: 0.0,
        };
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
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
            let law = SlipLaw { adhesion_n: [0.0, 0.3, -2.0][iteration % 3], ..law };
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
