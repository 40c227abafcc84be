//! The friction law and the rig as the vector step takes them: the
//! baseline's, an adhesion force included, and a friction history's, each
//! the scalar path's operations in the same order. (The module is private
//! to `simd`, which hands the law's types on to the oscillator.)

use super::lanes::{HistoryLanes, LANES, SlipLanes, V};
use crate::engine::cpu::effects;
use crate::engine::effects::{
    AGEING_CUTOFF_SPEED_M_PER_S, AGEING_FLOOR_SPEED_M_PER_S, EffectParams, Memory, STICTION_DECAY_M, StictionForm,
};

/// A friction history's law, the same for every lane (the model's).
#[derive(Clone, Copy, Debug)]
pub(crate) struct HistoryLaw<'a> {
    /// The effects (hysteresis and stiction forms and parameters).
    pub(crate) effects: &'a EffectParams,
    /// Which friction memory is on.
    pub(crate) memory: Memory,
    /// Whether hysteresis `dahl` or `bristle` is on (friction may point
    /// along the motion for a while: no clip at 0).
    pub(crate) dahl: bool,
}

/// The baseline law and the rig as a group's lanes step them: the law's
/// terms at each lane's load (lanes of one group may be at different
/// loads; the elements past the group's lanes are unused), the rest the
/// same for every lane (the model's).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SlipLaw {
    /// The law's `a` plus the effects' friction offset, per lane, –.
    pub(crate) a_offset: [f64; LANES],
    /// The law's `b`, per lane, –.
    pub(crate) b: [f64; LANES],
    /// The law's `d`, per lane, s²/m².
    pub(crate) d_s2_per_m2: [f64; LANES],
    /// The Stribeck rate `c`, s/m.
    pub(crate) c_s_per_m: f64,
    /// Spring stiffness, N/m.
    pub(crate) stiffness_n_per_m: f64,
    /// Base amplitude, m.
    pub(crate) base_amplitude_m: f64,
    /// Damping, N·s/m.
    pub(crate) damping_n_s_per_m: f64,
    /// 1 / m, 1/kg.
    pub(crate) inv_mass: f64,
    /// Adhesion force A of load dependence `adhesion`, N (0 without).
    pub(crate) adhesion_n: f64,
}

/// `Path::mean_law` per lane: `a + Δa + b S(c, s) + d v²` at speed
/// `speed` and velocity `v_m_per_s` (m/s), –, with each lane's `a + Δa`,
/// `b` and `d`. `stribeck_factor`: both branches, then the one the speed's
/// sign picks.
#[inline(always)]
pub(super) fn mean_law<const N: usize>(law: &SlipLaw, speed: V<N>, v_m_per_s: V<N>) -> V<N> {
    let c = V::splat(law.c_s_per_m);
    let one = V::splat(1.0);
    let under_way = one / (one + c * speed);
    let past_zero = one - c * speed;
    let stribeck = V(std::array::from_fn(|l| if speed.0[l] >= 0.0 { under_way.0[l] } else { past_zero.0[l] }));
    let per_lane = |terms: &[f64; LANES]| V::lanewise(|l| terms[l]);
    per_lane(&law.a_offset) + per_lane(&law.b) * stribeck + per_lane(&law.d_s2_per_m2) * v_m_per_s * v_m_per_s
}

/// `Path::slip_rates`' acceleration from the friction coefficient `mu`
/// (–), per lane: μN plus an adhesion force (`Path::friction_force_n`),
/// against the spring and the damper, m/s².
#[inline(always)]
pub(super) fn acceleration_with<const N: usize>(
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
pub(super) fn acceleration<const N: usize>(
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
pub(super) fn history_rates<const N: usize>(
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
        let decay = V::lanewise(|l| effects::exp_neg(slipped_m.0[l] / STICTION_DECAY_M));
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
