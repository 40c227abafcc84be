//! The f64 reference integrator of one realisation.
//!
//! Each realisation is integrated in steps of at most `T / steps_per_period`.
//! Noise-interval boundaries, output samples and period ends are step
//! boundaries (each span between them is divided into equal steps), so
//! every random value holds exactly over its interval. Slip phases
//! use classical RK4 with the slip direction frozen (the ODE is smooth there);
//! a velocity zero inside a step is located by root finding on the RK4 map
//! itself (Newton's method in a bracket), and the stick→slip breakaway is solved in closed
//! form because the block is at rest and only the base moves. No `sgn` is
//! smoothed. The base's `cos Ωt` and `sin Ωt` are exact at the start of each
//! span and carried through its steps by rotation (by `Ωh/2` for each half
//! step), so a step evaluates no trigonometric function.
//!
//! This file holds one type, the realisation being integrated ([`Path`]).
//! `shaders/oscillator.wgsl` is the same algorithm in f32; the functions
//! below carry the kernel's names and come in its order. The two differ on
//! purpose in these places, and nowhere else:
//!
//! | what | CPU (f64) | GPU (f32) | why |
//! | --- | --- | --- | --- |
//! | arithmetic | f64 | f32 | WGSL has no portable f64; the CPU is the judge |
//! | events per segment before forcing progress | 64 | 16 | a chattering guard only; the GPU's loops must stay short (lavapipe's loop limiter, SIMD divergence) |
//! | velocity zero: method, iterations / tolerance on the step | Newton in the bracket, 100 / 1e-15 · max(h, 10⁻⁶ T) | Illinois, 40 / 2e-7 · h | each converges to its own precision: 1e-15 is f64's, 2e-7 is f32's (2⁻²³ ≈ 1.2e-7); Newton needs the acceleration at each probe's end, a fifth evaluation per probe, and under half the probes |
//! | halvings probing for motion after a start from rest | 60, from a guess of the first under way, walked to it | 30, one by one from h/2 | 2⁻⁶⁰ and 2⁻³⁰ of the step are below each type's resolution; both find the same probe (the first under way) where the motion's sign changes once, the CPU in about two steps |
//! | time inside a period | span start + `k · h` in f64 | the same in f32, boundary position `frac · S / 2³²` by `mulhilo` | f32 cannot hold 32.32 fixed point; both switch noise at the same instants |
//! | `cos Ωt`, `sin Ωt` | exact at the period start and after events, rotated otherwise | also exact at every noise boundary and every 16 steps | f32 rotations drift by about 1e-7 each, f64 ones by 1e-16 |
//! | noise interval index | u64 | u32 (runs are refused past 2³² intervals) | WGSL has no u64 |
//! | normal-force harmonics' `cos((k+1)θ + φ)` per interval | one `sin_cos` of θ, rotated to (k+1)θ, turned by φ's stored (cos, sin) | a `cos` per harmonic | libm's `cos` was 13% of a diagnosis of harmonics in the CPU reference; the CPU's sum is within 1e-14 N of the direct one (`harmonics_by_angle_addition_match_a_cos_per_harmonic`) |
//! | realisations per thread | up to `LANES` of one point, stepped together: each grid step's slip step for all, then events one lane at a time (`run_period`) | one per invocation | the GPU's SIMD already runs invocations side by side; on the CPU one realisation alone waits out each stage's latency. The answers are those of one at a time, bit for bit |
//!
//! Output samples (records) between noise boundaries split steps on the CPU
//! only; records sampled at the noise boundaries split none, and the GPU
//! kernel writes those itself.

use crate::engine::cpu::effects;
use crate::engine::effects::{
    AGEING_CUTOFF_SPEED_M_PER_S, ColourForm, EffectParams, HarmonicForm, HysteresisForm, STICTION_DECAY_M,
    StictionForm, drift_factor,
};
use crate::engine::oscillator::{InitialState, Oscillator, Sample};
use crate::engine::rng;

/// Whether the block sticks or slips, and in which direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Stick,
    /// Slipping with velocity sign +1 or −1.
    Slip(i8),
}

/// The friction memory the slip ODE carries as its third state (hysteresis
/// `lag`, `slip` or `ageing` switched on), or none. The kernel sees the
/// codes as the generated `MEMORY_*` constants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Memory {
    None = 0,
    /// μ_f lags the steady law in time (memory time τ_m).
    Lag = 1,
    /// μ_f relaxes to the steady law over a slip distance L (the slip law).
    Slip = 2,
    /// The contact age θ of the ageing law.
    Ageing = 3,
}

impl Memory {
    /// Every memory, in code order, with its name in the kernel's constants.
    pub(crate) const ALL: [(Memory, &'static str); 4] =
        [(Memory::None, "NONE"), (Memory::Lag, "LAG"), (Memory::Slip, "SLIP"), (Memory::Ageing, "AGEING")];

    /// The memory of flattened effects: on where its form's strength is not
    /// zero (`lag`: τ_m > 0; `slip`: L > 0; `ageing`: L > 0 and B ≠ 0).
    pub(crate) fn of(e: &EffectParams) -> Memory {
        match e.hysteresis_form {
            HysteresisForm::Lag if e.hysteresis_lag_s > 0.0 => Memory::Lag,
            HysteresisForm::Slip if e.hysteresis_length_m > 0.0 => Memory::Slip,
            HysteresisForm::Ageing if e.hysteresis_length_m > 0.0 && e.hysteresis_strength != 0.0 => Memory::Ageing,
            _ => Memory::None,
        }
    }
}

/// Halvings of a step probing for motion after a start from rest: 2⁻⁶⁰ of
/// a step is below f64's resolution of it.
const MAX_PROBE_HALVINGS: i32 = 60;

/// Fixed-point `2^32`.
const FIXED_ONE: f64 = 4_294_967_296.0;
/// Events handled within one segment before the integrator forces progress
/// (guards against chattering at exactly balanced forces).
const MAX_EVENTS_PER_SEGMENT: u32 = 64;

/// `cos Ωt` and `sin Ωt` of the base at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Trig {
    pub(crate) cos: f64,
    pub(crate) sin: f64,
}

impl Trig {
    /// At phase `theta` (rad).
    fn at(theta: f64) -> Trig {
        let (sin, cos) = theta.sin_cos();
        Trig { cos, sin }
    }

    /// A rotation by a half step's angle `theta` (rad): Taylor series up to
    /// 0.1 rad (terms through θ¹⁰: the first omitted, θ¹¹/11!, is under
    /// 3e-19, below f64's resolution), `sin_cos` above. A noise interval of
    /// 1/600 s at 10–20 Hz is a half turn of 0.05–0.1 rad.
    fn turn(theta: f64) -> Trig {
        if theta.abs() > 0.1 {
            return Trig::at(theta);
        }
        let t2 = theta * theta;
        let sin = theta * (1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0))));
        let cos = 1.0 - t2 / 2.0 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0 * (1.0 - t2 / 90.0))));
        Trig { cos, sin }
    }

    /// Advanced by the rotation `by` (the cos and sin of an angle).
    fn rotated(self, by: Trig) -> Trig {
        Trig { cos: self.cos * by.cos - self.sin * by.sin, sin: self.sin * by.cos + self.cos * by.sin }
    }
}

/// The normal force's harmonics (N) at `interval_phase` (of the excitation
/// period, –): Σ A_k w(cos((k+1)θ + φ_k)), θ = 2π · `interval_phase`, each
/// cosine by angle addition from one `sin_cos` of θ ((k+1)θ by repeated
/// rotation, then φ_k's stored cos and sin) instead of a `cos` per harmonic.
/// The `position` form instead follows `x_per_u0`, the displacement at the
/// interval's start over the base amplitude (–): αN0 r + βN0 r².
fn harmonics_n(e: &EffectParams, interval_phase: f64, x_per_u0: f64) -> f64 {
    if e.harmonic_amplitudes_n.iter().all(|&a| a == 0.0) {
        return 0.0;
    }
    if e.harmonic_form == HarmonicForm::Position {
        return effects::position_load(e.harmonic_amplitudes_n[0], e.harmonic_amplitudes_n[1], x_per_u0);
    }
    let base = Trig::at(std::f64::consts::TAU * interval_phase);
    let mut multiple = base;
    let mut sum_n = 0.0;
    for k in 0..4 {
        if k > 0 {
            multiple = multiple.rotated(base);
        }
        if e.harmonic_amplitudes_n[k] != 0.0 {
            let (cos_phase, sin_phase) = e.harmonic_phase_cos_sin[k];
            let c = multiple.cos * cos_phase - multiple.sin * sin_phase;
            sum_n += e.harmonic_amplitudes_n[k]
                * effects::harmonic_wave(e.harmonic_form, c, e.harmonic_shape, e.harmonic_shape_mean);
        }
    }
    sum_n
}

/// One RK4 step of the slip ODE, with what the phase quadrature needs: the
/// four stage displacements (m) and the base's trig at the step's start,
/// middle and end.
#[derive(Clone, Copy, Debug)]
struct SlipStep {
    x_m: f64,
    v_m_per_s: f64,
    /// The friction memory at the end (μ_f, –, or θ, s; see [`Memory`]).
    memory: f64,
    stage_x_m: [f64; 4],
    trig: [Trig; 3],
}

/// The phase lag (rad) of a period's fundamental behind the base, from
/// `∫ x cos(Ωt) dt` and `∫ x sin(Ωt) dt` over the period: the fundamental is
/// `sqrt(a² + b²) cos(Ωt − φ)` with `φ = atan2(b, a)` (`interfaces.md`).
pub fn phase_of(cos_integral: f64, sin_integral: f64) -> f64 {
    sin_integral.atan2(cos_integral)
}

/// The state of one realisation.
#[derive(Clone, Debug)]
pub(crate) struct Path<'a> {
    osc: &'a Oscillator,
    key: [u32; 2],
    realisation: u32,
    /// Displacement x, m.
    pub(crate) x_m: f64,
    /// Velocity v, m/s.
    pub(crate) v_m_per_s: f64,
    mode: Mode,
    /// Index of the current excitation period.
    period: u64,
    /// Index of the current noise interval.
    interval: u64,
    /// Start of the next noise interval, in periods, 32.32 fixed point.
    next_boundary: u64,
    /// Friction coefficient's random part `σ_μ ξ_μ` in the current interval, –.
    friction_noise: f64,
    /// Normal force in the current interval, N.
    normal_force_n: f64,
    /// x where the current slip began, m (displacement hysteresis, stiction release).
    slip_start_x_m: f64,
    /// Coloured noise states: the AR(1) parts of `ar1`, `two_scale`,
    /// `multi_scale` and `fast_slow`, –.
    colour_state: [f64; 3],
    /// Start of the current noise interval within its period, in periods.
    interval_phase: f64,
    /// Static-friction excess in the current interval, –.
    stiction_excess: f64,
    /// The friction memory: μ_f of hysteresis `lag` and `slip` (–), the
    /// contact age θ of `ageing` (s; while stuck, θ when the stick began).
    memory: f64,
    /// The static coefficient's contact-age term B ln((θ + θ_c)/(2 θ_c)) of
    /// hysteresis `ageing`, with θ at the current interval's start while
    /// stuck (or at the stick's start), and at the last velocity zero, –.
    ageing_excess: f64,
    /// When the current stick began, s from the run's start (stiction
    /// `dwell`, hysteresis `ageing`).
    stick_since_s: f64,
    /// Whether sliding friction depends on more than the current velocity
    /// and interval (hysteresis, or a stiction excess carried into the
    /// slip), or has an adhesion force: whether it takes more than the
    /// baseline's arithmetic.
    history: bool,
    /// Which friction memory is on ([`Memory::of`] the effects).
    memory_form: Memory,
    /// The law's a, b (–) and d (s²/m²) at this point's load: times
    /// (N0/Nref)^k under load dependence `scaled`, themselves otherwise.
    law_a: f64,
    law_b: f64,
    law_d: f64,
    /// 1 / m, 1/kg.
    inv_mass: f64,
    /// Largest x so far in the current period, m.
    pub(crate) period_max_x_m: f64,
    /// Time stuck so far in the current period, s.
    pub(crate) period_stick_s: f64,
    /// `∫ x cos(Ωt) dt` and `∫ x sin(Ωt) dt` over the current period so far,
    /// m·s (the response's fundamental; see [`phase_of`]).
    pub(crate) period_cos_integral: f64,
    pub(crate) period_sin_integral: f64,
}

impl<'a> Path<'a> {
    pub(crate) fn new(osc: &'a Oscillator, seed: u64, realisation: u32, initial: InitialState) -> Self {
        let e = &osc.effects;
        let memory_form = Memory::of(e);
        let build_up =
            matches!(e.hysteresis_form, HysteresisForm::Exponential | HysteresisForm::Tanh | HysteresisForm::Rational);
        let history = memory_form != Memory::None
            || (e.hysteresis_length_m != 0.0 && build_up)
            || e.adhesion_force_n != 0.0
            || e.stiction_form == StictionForm::Decaying
            || (e.stiction_form == StictionForm::Constant && e.stiction_release_m > 0.0);
        let mut path = Path {
            osc,
            key: rng::seed_key(seed),
            realisation,
            x_m: initial.x_m,
            v_m_per_s: initial.v_m_per_s,
            mode: Mode::Stick,
            period: 0,
            interval: 0,
            next_boundary: osc.noise_interval_fixed,
            friction_noise: 0.0,
            normal_force_n: 0.0,
            slip_start_x_m: initial.x_m,
            colour_state: [0.0; 3],
            interval_phase: 0.0,
            stiction_excess: 0.0,
            memory: 0.0,
            ageing_excess: 0.0,
            stick_since_s: 0.0,
            history,
            memory_form,
            law_a: osc.friction_a * e.friction_scale,
            law_b: osc.friction_b * e.friction_scale,
            law_d: osc.friction_d_s2_per_m2 * e.friction_scale,
            inv_mass: 1.0 / osc.mass_kg,
            period_max_x_m: initial.x_m,
            period_stick_s: 0.0,
            period_cos_integral: 0.0,
            period_sin_integral: 0.0,
        };
        path.draw_noise();
        path.mode = if initial.v_m_per_s > 0.0 {
            Mode::Slip(1)
        } else if initial.v_m_per_s < 0.0 {
            Mode::Slip(-1)
        } else {
            path.stick_or_slip(Trig { cos: 1.0, sin: 0.0 })
        };
        if path.mode == Mode::Stick {
            path.start_stick(0.0);
        } else if path.memory_form != Memory::Ageing {
            // The contact age starts at 0 whether the block sticks or slips.
            path.memory = path.lag_start_coefficient();
        }
        path
    }

    /// Noise values (and everything else held per interval) of the current
    /// interval. The main stream's pair A gives the friction's white value
    /// and the normal force's; pair B and the colour stream are drawn only
    /// by the effects that use them.
    fn draw_noise(&mut self) {
        let o = self.osc;
        let e = &o.effects;
        let main = rng::block(self.key, self.realisation, rng::STREAM_MAIN, self.interval);
        let (white, xi_n) = rng::pair_a(main);
        let friction_block = if e.colour_form == ColourForm::Hold && e.colour_hold_intervals > 1 {
            rng::block(self.key, self.realisation, rng::STREAM_MAIN, self.interval / u64::from(e.colour_hold_intervals))
        } else {
            main
        };
        let z = if friction_block == main { white } else { rng::pair_a(friction_block).0 };
        let colour = || rng::block(self.key, self.realisation, rng::STREAM_COLOUR, self.interval);
        let first = self.interval == 0;
        let ar1 = |state: f64, rho: f64, innovation: f64| {
            if first { innovation } else { rho * state + (1.0 - rho * rho).sqrt() * innovation }
        };
        let g = match e.colour_form {
            _ if e.colour_rho == 0.0 => z,
            ColourForm::Ar1 if e.colour_share >= 1.0 => {
                self.colour_state[0] = ar1(self.colour_state[0], e.colour_rho, z);
                self.colour_state[0]
            }
            ColourForm::Ar1 => {
                self.colour_state[0] = ar1(self.colour_state[0], e.colour_rho, rng::pair_a(colour()).0);
                (1.0 - e.colour_share).sqrt() * z + e.colour_share.sqrt() * self.colour_state[0]
            }
            ColourForm::Hold => z,
            ColourForm::TwoScale => {
                self.colour_state[0] = ar1(self.colour_state[0], e.colour_rho, rng::pair_a(colour()).0);
                std::f64::consts::FRAC_1_SQRT_2 * (z + self.colour_state[0])
            }
            ColourForm::MultiScale => {
                let words = colour();
                let ((c0, c1), (c2, _)) = (rng::pair_a(words), rng::pair_b(words));
                for (k, innovation) in [c0, c1, c2].into_iter().enumerate() {
                    self.colour_state[k] = ar1(self.colour_state[k], e.colour_rhos[k], innovation);
                }
                self.colour_state.iter().sum::<f64>() * (1.0 / 3f64.sqrt())
            }
            ColourForm::FastSlow => {
                let (fast, slow) = rng::pair_a(colour());
                self.colour_state[0] = ar1(self.colour_state[0], e.colour_rhos[0], fast);
                self.colour_state[1] = ar1(self.colour_state[1], e.colour_rhos[1], slow);
                (1.0 - e.colour_share).sqrt() * self.colour_state[0] + e.colour_share.sqrt() * self.colour_state[1]
            }
        };
        let xi_mu = if e.non_gaussian_strength == 0.0 {
            g
        } else {
            effects::non_gaussian(e.non_gaussian_form, e.non_gaussian_strength, g, rng::pair_b(friction_block).0)
        };
        self.friction_noise = o.friction_sigma * xi_mu;
        let t_s = self.interval as f64 * o.noise_interval_s;
        let mean_n =
            o.normal_force_mean_n * drift_factor(e.drift_form, e.drift_rate_per_s, e.drift_curvature_per_s2, t_s);
        let harmonics_n = harmonics_n(e, self.interval_phase, self.x_m / o.base_amplitude_m);
        self.normal_force_n = (mean_n + o.normal_force_sigma_n * xi_n + harmonics_n).max(0.0);
        self.stiction_excess = match e.stiction_form {
            StictionForm::Noisy if e.stiction_excess != 0.0 => {
                e.stiction_excess * (1.0 + 0.5 * rng::pair_b(main).1).max(0.0)
            }
            StictionForm::Dwell if self.mode == Mode::Stick => {
                effects::dwell_excess(e.stiction_excess, t_s - self.stick_since_s, e.stiction_dwell_s)
            }
            StictionForm::Dwell => 0.0,
            _ => e.stiction_excess,
        };
        if self.memory_form == Memory::Ageing && self.mode == Mode::Stick {
            self.ageing_excess = self.contact_age_excess(self.contact_age_at(t_s));
        }
    }

    /// The contact age θ (s) of hysteresis `ageing` while stuck, held over
    /// the noise interval that starts at `interval_start_s` (s from the
    /// run's start): θ at the stick's start plus the time stuck up to the
    /// interval's start (none in the interval the stick began).
    fn contact_age_at(&self, interval_start_s: f64) -> f64 {
        self.memory + (interval_start_s - self.stick_since_s).max(0.0)
    }

    /// The static coefficient's contact-age term at age `age_s` (s):
    /// `B ln((θ + θ_c)/(2 θ_c))`, the sliding friction's term at v = 0, –.
    fn contact_age_excess(&self, age_s: f64) -> f64 {
        let e = &self.osc.effects;
        let cutoff_age_s = e.hysteresis_length_m / AGEING_CUTOFF_SPEED_M_PER_S;
        effects::contact_age_term(e.hysteresis_strength, age_s, cutoff_age_s, cutoff_age_s)
    }

    /// Marks the start of a stick at `t_s` (from the run's start): the
    /// `dwell` stiction's ageing starts again.
    fn start_stick(&mut self, t_s: f64) {
        self.stick_since_s = t_s;
        if self.osc.effects.stiction_form == StictionForm::Dwell {
            let e = &self.osc.effects;
            self.stiction_excess = effects::dwell_excess(e.stiction_excess, 0.0, e.stiction_dwell_s);
        }
    }

    /// Force of springs and damper on the block at rest, `k (u − x)` with
    /// the base at `cos_omega_t` of its amplitude, N.
    #[inline(always)]
    fn spring_force(&self, cos_omega_t: f64, x_m: f64) -> f64 {
        let o = self.osc;
        o.stiffness_n_per_m * (o.base_amplitude_m * cos_omega_t - x_m)
    }

    /// The steady friction law while slipping with speed `speed` (m/s) at
    /// velocity `v` (m/s), before effects of history:
    /// `a + Δa + b S(c, s) + d v² + σ ξ` with `S` = [`stribeck_factor`]
    /// (a, b and d at this point's load), –.
    #[inline(always)]
    fn steady_law(&self, speed_m_per_s: f64, v_m_per_s: f64) -> f64 {
        self.mean_law(speed_m_per_s, v_m_per_s) + self.friction_noise
    }

    /// The steady law without its random part, `a + Δa + b S(c, s) + d v²`:
    /// what a friction memory that relaxes (`lag`, `slip`) follows, the
    /// random part added on top. The random part of friction comes from
    /// asperity contacts faster than any memory of the contact's state (the
    /// rate-and-state and bristle laws carry no noise): a memory that
    /// filtered it would lower and colour the record's friction noise, –.
    #[inline(always)]
    fn mean_law(&self, speed_m_per_s: f64, v_m_per_s: f64) -> f64 {
        let o = self.osc;
        self.law_a
            + o.effects.friction_offset
            + self.law_b * stribeck_factor(o.friction_c_s_per_m, speed_m_per_s)
            + self.law_d * v_m_per_s * v_m_per_s
    }

    /// Friction coefficient while slipping with speed `speed` (m/s) at
    /// displacement `x_m`, with the friction memory `memory` (μ_f of
    /// hysteresis `lag` and `slip`, θ of `ageing`; unused otherwise),
    /// clipped at 0.
    #[inline(always)]
    fn friction_coefficient(&self, speed_m_per_s: f64, v_m_per_s: f64, x_m: f64, memory: f64) -> f64 {
        if !self.history {
            return self.steady_law(speed_m_per_s, v_m_per_s).max(0.0);
        }
        let e = &self.osc.effects;
        let slipped_m = (x_m - self.slip_start_x_m).abs();
        let mut mu = match self.memory_form {
            Memory::Lag | Memory::Slip => memory + self.friction_noise,
            Memory::Ageing => self.ageing_coefficient(speed_m_per_s, v_m_per_s, memory),
            Memory::None => {
                self.steady_law(speed_m_per_s, v_m_per_s)
                    * effects::hysteresis_factor(e.hysteresis_form, slipped_m, e.hysteresis_length_m)
            }
        };
        if e.stiction_form == StictionForm::Decaying {
            mu += self.stiction_excess * (-slipped_m / STICTION_DECAY_M).exp();
        } else if e.stiction_form == StictionForm::Constant && e.stiction_release_m > 0.0 {
            mu += self.stiction_excess * (1.0 - slipped_m / e.stiction_release_m).max(0.0);
        }
        mu.max(0.0)
    }

    /// The magnitude of the friction force while slipping, the arguments
    /// those of [`Path::friction_coefficient`]: μN, plus the adhesion force
    /// under load dependence `adhesion` (the sum clipped at 0), N. The
    /// adhesion is added on the history path only ([`Path::history`] is set
    /// with it), so the baseline's stages test nothing more.
    #[inline(always)]
    fn friction_force_n(&self, speed_m_per_s: f64, v_m_per_s: f64, x_m: f64, memory: f64) -> f64 {
        let friction_n = self.friction_coefficient(speed_m_per_s, v_m_per_s, x_m, memory) * self.normal_force_n;
        if !self.history {
            return friction_n;
        }
        friction_n + effects::adhesion(friction_n, self.osc.effects.adhesion_force_n)
    }

    /// The sliding coefficient of hysteresis `ageing` with contact age
    /// `age_s` (s), before stiction: `μ_ss(v) + B ln((θ + θ_c)/(θ_ss(v) + θ_c))`,
    /// θ_ss(v) = L/(|v| + v_c), –. Not inlined: it calls `ln` anyway.
    #[inline(never)]
    fn ageing_coefficient(&self, speed_m_per_s: f64, v_m_per_s: f64, age_s: f64) -> f64 {
        let e = &self.osc.effects;
        let length_m = e.hysteresis_length_m;
        let steady_age_s = length_m / (v_m_per_s.abs() + AGEING_CUTOFF_SPEED_M_PER_S);
        let cutoff_age_s = length_m / AGEING_CUTOFF_SPEED_M_PER_S;
        self.steady_law(speed_m_per_s, v_m_per_s)
            + effects::contact_age_term(e.hysteresis_strength, age_s, steady_age_s, cutoff_age_s)
    }

    /// The static coefficient `μ(0) + stiction excess + contact-age term`,
    /// clipped at 0, –.
    fn static_coefficient(&self) -> f64 {
        let o = self.osc;
        (self.law_a
            + o.effects.friction_offset
            + self.law_b
            + self.friction_noise
            + self.stiction_excess
            + self.ageing_excess)
            .max(0.0)
    }

    /// Where the friction memory μ_f of hysteresis `lag` and `slip` starts
    /// when the block breaks away: the static coefficient the breakaway was judged by, less
    /// the stiction excess that [`Path::friction_coefficient`] adds on top
    /// while it is released (`decaying`, or `constant` with a release
    /// length), so that sliding starts at exactly the static coefficient.
    /// Counted twice, friction at the start of a slip exceeded the force
    /// that broke the block away: it stopped at once and re-slipped, up to
    /// the event limit of every segment (a diagnosis's trials of `lag` on
    /// top of a released stiction took 20–45 s instead of under 1 s), –.
    fn lag_start_coefficient(&self) -> f64 {
        let e = &self.osc.effects;
        let released = e.stiction_form == StictionForm::Decaying
            || (e.stiction_form == StictionForm::Constant && e.stiction_release_m > 0.0);
        // The memory holds the mean part: the noise is added on top.
        self.static_coefficient() - if released { self.stiction_excess } else { 0.0 } - self.friction_noise
    }

    /// Breakaway force `μ_s N` (plus the adhesion force under load
    /// dependence `adhesion`, the sum clipped at 0), N.
    fn breakaway_force(&self) -> f64 {
        let friction_n = self.static_coefficient() * self.normal_force_n;
        let adhesion_n = self.osc.effects.adhesion_force_n;
        if adhesion_n != 0.0 { friction_n + effects::adhesion(friction_n, adhesion_n) } else { friction_n }
    }

    /// Rate of the friction memory while slipping at velocity `v` (m/s)
    /// with speed `speed` (m/s, the slip direction's): `lag`
    /// (μ_ss − μ_f)/τ_m and `slip` (|v|/L)(μ_ss − μ_f), 1/s; `ageing`
    /// 1 − |v| θ/L, –.
    #[inline(always)]
    fn memory_rate(&self, speed_m_per_s: f64, v_m_per_s: f64, memory: f64) -> f64 {
        let e = &self.osc.effects;
        match self.memory_form {
            Memory::Lag => (self.mean_law(speed_m_per_s, v_m_per_s) - memory) / e.hysteresis_lag_s,
            Memory::Slip => effects::slip_law_rate(
                self.mean_law(speed_m_per_s, v_m_per_s),
                memory,
                v_m_per_s.abs(),
                e.hysteresis_length_m,
            ),
            Memory::Ageing => effects::ageing_rate(memory, v_m_per_s.abs(), e.hysteresis_length_m),
            Memory::None => 0.0,
        }
    }

    /// Acceleration (m/s²) while slipping in direction `sign`, with the base
    /// at `cos_omega_t` of its amplitude, and the rate of the friction
    /// memory ([`Path::memory_rate`]; 0 unless a memory is on: `MEMORY` is
    /// whether [`Path::memory_form`] is one, a constant so that without it
    /// no stage computes it).
    #[inline(always)]
    fn slip_rates<const MEMORY: bool>(
        &self,
        cos_omega_t: f64,
        x_m: f64,
        v_m_per_s: f64,
        memory: f64,
        sign: f64,
    ) -> (f64, f64) {
        let o = self.osc;
        let friction_n = self.friction_force_n(sign * v_m_per_s, v_m_per_s, x_m, memory);
        let spring = self.spring_force(cos_omega_t, x_m);
        let acceleration = (spring - o.damping_n_s_per_m * v_m_per_s - sign * friction_n) * self.inv_mass;
        let memory_rate = if MEMORY { self.memory_rate(sign * v_m_per_s, v_m_per_s, memory) } else { 0.0 };
        (acceleration, memory_rate)
    }

    /// One classical RK4 step of the slip ODE from `t` (where the base's trig
    /// is `start`) over `h` seconds; `half` rotates by `Ωh/2`.
    #[inline]
    fn rk4_slip(&self, start: Trig, x_m: f64, v_m_per_s: f64, h_s: f64, half: Trig, sign: f64) -> SlipStep {
        // Compiled twice, with and without the friction memory's state:
        // the same arithmetic (its rate is exactly 0 without it), but the
        // step most runs take has no memory rate in its dependency chain
        // (the compiler evaluated it and threw it away).
        if self.memory_form != Memory::None {
            self.rk4_slip_with::<true>(start, x_m, v_m_per_s, h_s, half, sign)
        } else {
            self.rk4_slip_with::<false>(start, x_m, v_m_per_s, h_s, half, sign)
        }
    }

    /// [`Path::rk4_slip`] with `MEMORY` = whether [`Path::memory_form`] is
    /// a memory.
    #[inline(always)]
    fn rk4_slip_with<const MEMORY: bool>(
        &self,
        start: Trig,
        x_m: f64,
        v_m_per_s: f64,
        h_s: f64,
        half: Trig,
        sign: f64,
    ) -> SlipStep {
        let mid = start.rotated(half);
        let end = mid.rotated(half);
        let m0 = self.memory;
        let hh = 0.5 * h_s;
        let k1x = v_m_per_s;
        let (k1v, k1m) = self.slip_rates::<MEMORY>(start.cos, x_m, v_m_per_s, m0, sign);
        let k2x = v_m_per_s + hh * k1v;
        let x2 = x_m + hh * k1x;
        let (k2v, k2m) = self.slip_rates::<MEMORY>(mid.cos, x2, k2x, m0 + hh * k1m, sign);
        let k3x = v_m_per_s + hh * k2v;
        let x3 = x_m + hh * k2x;
        let (k3v, k3m) = self.slip_rates::<MEMORY>(mid.cos, x3, k3x, m0 + hh * k2m, sign);
        let k4x = v_m_per_s + h_s * k3v;
        let x4 = x_m + h_s * k3x;
        let (k4v, k4m) = self.slip_rates::<MEMORY>(end.cos, x4, k4x, m0 + h_s * k3m, sign);
        SlipStep {
            x_m: x_m + h_s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v_m_per_s: v_m_per_s + h_s / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
            memory: m0 + h_s / 6.0 * (k1m + 2.0 * k2m + 2.0 * k3m + k4m),
            stage_x_m: [x_m, x2, x3, x4],
            trig: [start, mid, end],
        }
    }

    /// Adds an accepted slip step to the period's phase integrals: the RK4
    /// quadrature of `x cos(Ωt)` and `x sin(Ωt)` over the step, with the
    /// step's own stage displacements (the integrals are two more RK4 states).
    fn add_slip_phase(&mut self, h_s: f64, step: &SlipStep) {
        let [x1, x2, x3, x4] = step.stage_x_m;
        let [a, m, b] = step.trig;
        self.period_cos_integral += h_s / 6.0 * (x1 * a.cos + 2.0 * (x2 + x3) * m.cos + x4 * b.cos);
        self.period_sin_integral += h_s / 6.0 * (x1 * a.sin + 2.0 * (x2 + x3) * m.sin + x4 * b.sin);
    }

    /// Adds a stuck interval between base trigs `a` and `b` to the period's
    /// phase integrals, exactly: x is constant.
    fn add_stick_phase(&mut self, a: Trig, b: Trig) {
        let w = self.osc.omega_rad_per_s;
        self.period_cos_integral += self.x_m * (b.sin - a.sin) / w;
        self.period_sin_integral += self.x_m * (a.cos - b.cos) / w;
    }

    /// The step length `h* ∈ (0, h]` at which the RK4 map's velocity reaches
    /// zero, given that `sign · v` is ≤ 0 after the full step `h`, and the
    /// RK4 step to it when it was taken on the way (not for `h* = h`).
    fn locate_velocity_zero(&self, start: Trig, h_s: f64, sign: f64) -> (f64, Option<SlipStep>) {
        let w = self.osc.omega_rad_per_s;
        let step_to = |h: f64| self.rk4_slip(start, self.x_m, self.v_m_per_s, h, Trig::turn(0.5 * w * h), sign);
        let g = |step: &SlipStep| sign * step.v_m_per_s;
        let (mut lo, mut g_lo) = (0.0, sign * self.v_m_per_s);
        let (mut hi, mut g_hi) = (h_s, g(&step_to(h_s)));
        let mut hi_step = None;
        if g_lo <= 0.0 {
            // Slip starting from rest: the first of h/2, h/4, …, 2⁻⁶⁰ h at
            // which it is under way (the largest bracket of the zero).
            let probe = |k: i32| h_s * 0.5f64.powi(k);
            let mut k = self.first_probe_guess(start, h_s, g_hi, sign);
            let mut at_k = step_to(probe(k));
            if g(&at_k) > 0.0 {
                // Under way at the guess: the probes above it, while under way.
                loop {
                    if k == 1 {
                        break;
                    }
                    let above = step_to(probe(k - 1));
                    if g(&above) <= 0.0 {
                        (hi, g_hi, hi_step) = (probe(k - 1), g(&above), Some(above));
                        break;
                    }
                    (k, at_k) = (k - 1, above);
                }
            } else {
                // Not yet: the probes below it, until one is.
                loop {
                    (hi, g_hi, hi_step) = (probe(k), g(&at_k), Some(at_k));
                    if k == MAX_PROBE_HALVINGS {
                        return (hi, hi_step);
                    }
                    k += 1;
                    at_k = step_to(probe(k));
                    if g(&at_k) > 0.0 {
                        break;
                    }
                }
            }
            (lo, g_lo) = (probe(k), g(&at_k));
        }
        // Newton on the RK4 map's velocity inside the bracket g_lo > 0 >=
        // g_hi: the slope of g is the acceleration at the step's end (the
        // flow's dv/dh; the map's differs by O(h⁴), which only slows the
        // last digits). A probe past the zero whose Newton step back is
        // under half the tolerance ends the search there; one before it
        // within that distance is followed by a probe half a tolerance
        // past it, which closes the bracket. A Newton step out of the
        // bracket bisects it instead. On seed 22's 18-run set 9 (a
        // hysteresis that sticks twice a period): at most 5.2 RK4 steps per
        // zero (passes of the loop below); Illinois from the chord took
        // 12.7 on the 18-run hysteresis set.
        let tolerance = 1e-15 * h_s.max(self.osc.period_s * 1e-6);
        let mut x = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
        if lo == 0.0 && hi == h_s {
            // The first guess: the first root of the quadratic through
            // g(0), its slope there and g(h), O(h³) from the zero where
            // the chord's is O(h²).
            let b = sign * self.slip_rates::<false>(start.cos, self.x_m, self.v_m_per_s, self.memory, sign).0;
            let c = (g_hi - g_lo - b * h_s) / (h_s * h_s);
            let disc = b * b - 4.0 * c * g_lo;
            if disc >= 0.0 {
                x = 2.0 * g_lo / (disc.sqrt() - b);
            }
        }
        for _ in 0..100 {
            if hi - lo <= tolerance {
                break;
            }
            if !(x > lo && x < hi) {
                x = 0.5 * (lo + hi);
            }
            let at_x = step_to(x);
            let g_x = g(&at_x);
            let end = at_x.trig[2];
            let slope = sign * self.slip_rates::<false>(end.cos, at_x.x_m, at_x.v_m_per_s, at_x.memory, sign).0;
            let newton = x - g_x / slope;
            if g_x > 0.0 {
                lo = x;
            } else {
                (hi, hi_step) = (x, Some(at_x));
                if (newton - x).abs() < 0.5 * tolerance {
                    break;
                }
            }
            x = if (newton - x).abs() < 0.5 * tolerance {
                x + if g_x > 0.0 { 0.5 } else { -0.5 } * tolerance
            } else {
                newton
            };
        }
        (hi, hi_step)
    }

    /// How many halvings of a step `h_s` (s) from rest first give a step
    /// that is still under way, guessed from the RK4 map's velocity being
    /// `A h − B h²` for small `h`: `A` the acceleration at the start, `B`
    /// from the full step's `g_full` (`sign · v`, ≤ 0). Only a guess that
    /// [`Path::locate_velocity_zero`] confirms or walks from: the answer is
    /// the same probe as halving one by one from `h/2` (about two steps
    /// instead of ten on the benchmark's 18-run set).
    fn first_probe_guess(&self, start: Trig, h_s: f64, g_full: f64, sign: f64) -> i32 {
        let a = sign * self.slip_rates::<false>(start.cos, self.x_m, self.v_m_per_s, self.memory, sign).0;
        let b = (a * h_s - g_full) / (h_s * h_s);
        let k = (h_s * b / a).log2().ceil();
        if a > 0.0 && b > 0.0 && k.is_finite() { (k as i32).clamp(1, MAX_PROBE_HALVINGS) } else { 1 }
    }

    /// At rest with the base at `trig`: stick if the spring force does not
    /// exceed the breakaway force, otherwise slip in the direction of that
    /// force.
    fn stick_or_slip(&self, trig: Trig) -> Mode {
        let force = self.spring_force(trig.cos, self.x_m);
        if force.abs() <= self.breakaway_force() {
            Mode::Stick
        } else if force > 0.0 {
            Mode::Slip(1)
        } else {
            Mode::Slip(-1)
        }
    }

    /// Earliest time in `[t_a, t_b]` at which a stuck block breaks away, and
    /// the direction. `k (U0 cos(Ω t) − x) = ±μ_s N` is solved in closed form.
    fn breakaway_time(&self, t_a: f64, start: Trig, t_b: f64) -> Option<(f64, i8)> {
        let o = self.osc;
        let force = self.spring_force(start.cos, self.x_m);
        let threshold = self.breakaway_force();
        if force > threshold {
            return Some((t_a, 1));
        }
        if force < -threshold {
            return Some((t_a, -1));
        }
        if o.base_amplitude_m == 0.0 {
            return None;
        }
        let phase_a = o.omega_rad_per_s * t_a;
        let reach = threshold / o.stiffness_n_per_m;
        let best = self.earliest_entry(None, 1, phase_a, reach, t_b);
        self.earliest_entry(best, -1, phase_a, reach, t_b).map(|(t, sign)| (t.max(t_a), sign))
    }

    /// Entering `cos(θ) >= C+` happens at `θ = 2πn − acos(C+)`; entering
    /// `cos(θ) <= C−` at `θ = 2πn + acos(C−)`. Keeps `best` unless this
    /// direction's entry is earlier.
    fn earliest_entry(
        &self,
        best: Option<(f64, i8)>,
        sign: i8,
        phase_a: f64,
        reach: f64,
        t_b: f64,
    ) -> Option<(f64, i8)> {
        let o = self.osc;
        let level = (self.x_m + f64::from(sign) * reach) / o.base_amplitude_m;
        if !(-1.0..=1.0).contains(&level) {
            return best;
        }
        let base = -f64::from(sign) * level.acos();
        let n = ((phase_a - base) / std::f64::consts::TAU).ceil();
        let t = (base + n * std::f64::consts::TAU) / o.omega_rad_per_s;
        if t <= t_b && best.is_none_or(|(tb, _)| t < tb) { Some((t, sign)) } else { best }
    }

    /// Advances from `t_a` to `t_b` (local times in the period, where the
    /// base's trig is `start`) with the noise held, through any stick/slip
    /// events on the way. `regular` is the rotation by half the segment
    /// (computed once for equal steps). Returns the base's trig at `t_b`.
    fn advance_segment(
        &mut self,
        mut t_a: f64,
        t_b: f64,
        mut start: Trig,
        regular: Option<Trig>,
        measuring: bool,
    ) -> Trig {
        let w = self.osc.omega_rad_per_s;
        let period_start_s = self.period as f64 * self.osc.period_s;
        let mut events = 0;
        let mut whole = regular;
        while t_a < t_b {
            match self.mode {
                Mode::Stick => {
                    let until =
                        if events < MAX_EVENTS_PER_SEGMENT { self.breakaway_time(t_a, start, t_b) } else { None };
                    let (t_end, next) = match until {
                        None => (t_b, Mode::Stick),
                        Some((t, sign)) => (t, Mode::Slip(sign)),
                    };
                    // A whole grid step held to its end is carried by
                    // rotation like a slip step; an event's time exactly.
                    let end = match (whole, next) {
                        (Some(half), Mode::Stick) => start.rotated(half).rotated(half),
                        _ => Trig::at(w * t_end),
                    };
                    if measuring {
                        self.period_stick_s += t_end - t_a;
                        self.add_stick_phase(start, end);
                    }
                    self.mode = next;
                    self.slip_start_x_m = self.x_m;
                    if next != Mode::Stick {
                        self.memory = if self.memory_form == Memory::Ageing {
                            // The slip starts from the contact age the
                            // breakaway was judged by.
                            self.contact_age_at(self.interval as f64 * self.osc.noise_interval_s)
                        } else {
                            self.lag_start_coefficient()
                        };
                    }
                    (t_a, start, whole) = (t_end, end, None);
                    events += 1;
                }
                Mode::Slip(s) => {
                    let sign = f64::from(s);
                    let h = t_b - t_a;
                    let half = whole.unwrap_or_else(|| Trig::turn(0.5 * w * h));
                    let step = self.rk4_slip(start, self.x_m, self.v_m_per_s, h, half, sign);
                    if sign * step.v_m_per_s > 0.0 {
                        return self.commit_slip(h, &step, measuring);
                    }
                    let (h_zero, to_zero) = self.locate_velocity_zero(start, h, sign);
                    let to_zero = to_zero.unwrap_or_else(|| {
                        self.rk4_slip(start, self.x_m, self.v_m_per_s, h_zero, Trig::turn(0.5 * w * h_zero), sign)
                    });
                    if measuring {
                        self.add_slip_phase(h_zero, &to_zero);
                    }
                    self.x_m = to_zero.x_m;
                    self.v_m_per_s = 0.0;
                    self.memory = to_zero.memory;
                    self.period_max_x_m = self.period_max_x_m.max(to_zero.x_m);
                    t_a += h_zero;
                    start = Trig::at(w * t_a);
                    whole = None;
                    if self.memory_form == Memory::Ageing {
                        // At rest the static coefficient reads the contact
                        // age the slip reached.
                        self.ageing_excess = self.contact_age_excess(self.memory);
                    }
                    self.mode = if events < MAX_EVENTS_PER_SEGMENT { self.stick_or_slip(start) } else { Mode::Stick };
                    if self.mode == Mode::Stick {
                        self.start_stick(period_start_s + t_a);
                    } else if self.memory_form != Memory::Ageing {
                        // A slip from rest is a breakaway like one from a
                        // stick: the lagged coefficient starts at the static
                        // one the breakaway was judged by (carried over, it
                        // held a block the test let go, which then could
                        // not move and re-slipped up to the event limit).
                        // The contact age goes on from where the slip left
                        // it, which the static coefficient just read.
                        self.memory = self.lag_start_coefficient();
                    }
                    self.slip_start_x_m = self.x_m;
                    events += 1;
                }
            }
        }
        start
    }

    /// Friction force on the block with the base at `trig` (for output
    /// samples), N.
    fn friction_force(&self, trig: Trig) -> f64 {
        match self.mode {
            Mode::Stick => -self.spring_force(trig.cos, self.x_m),
            Mode::Slip(s) => {
                let sign = f64::from(s);
                -sign * self.friction_force_n(sign * self.v_m_per_s, self.v_m_per_s, self.x_m, self.memory)
            }
        }
    }

    /// Commits a slip step over `h_s` seconds that ends still under way:
    /// the state, the period's largest x, and the phase integrals when
    /// `measuring`. Returns the base's trig at its end.
    #[inline(always)]
    fn commit_slip(&mut self, h_s: f64, step: &SlipStep, measuring: bool) -> Trig {
        if measuring {
            self.add_slip_phase(h_s, step);
        }
        self.x_m = step.x_m;
        self.v_m_per_s = step.v_m_per_s;
        self.memory = step.memory;
        self.period_max_x_m = self.period_max_x_m.max(step.x_m);
        step.trig[2]
    }
}

/// Realisations of one oscillator stepped together, grid step by grid step.
/// Their step grids are the same (the noise boundaries and samples fall at
/// the same times), so each grid step's RK4 for all of them is one run of
/// straight-line code: eight independent dependency chains the core overlaps
/// instead of waiting out one chain's latency (one realisation at a time,
/// the reference was latency-bound: each stage's division and sums wait on
/// the last).
pub(crate) const LANES: usize = 8;

/// The smaller set of lanes stepped together: a diagnosis's search runs 4
/// replicates per condition.
pub(crate) const HALF_LANES: usize = LANES / 2;

/// The group sizes that step together ([`advance_lanes`] takes each),
/// widest first; other sizes step one realisation at a time.
pub(crate) const LANE_WIDTHS: [usize; 2] = [LANES, HALF_LANES];

/// Advances every path in `lanes` over the grid step `[t_a, t_b]` (local
/// times in the period; `turn` rotates by half of it), each from its base
/// trig in `trigs`. With a set of lanes of one of the [`LANE_WIDTHS`], the
/// slip step is taken for every slipping lane first, as if none met an
/// event, and kept where the lane still slips at the step's end; every other
/// lane takes [`Path::advance_segment`] from the step's start (a slipping
/// one repeats that same step first), so the answers are those of one path
/// at a time, bit for bit.
fn advance_lanes(lanes: &mut [Path<'_>], trigs: &mut [Trig], t_a: f64, t_b: f64, turn: Trig, measuring: bool) {
    let memory = lanes[0].memory_form != Memory::None;
    match lanes.len() {
        LANES if memory => slip_lanes::<LANES, true>(lanes, trigs, t_a, t_b, turn, measuring),
        LANES => slip_lanes::<LANES, false>(lanes, trigs, t_a, t_b, turn, measuring),
        HALF_LANES if memory => slip_lanes::<HALF_LANES, true>(lanes, trigs, t_a, t_b, turn, measuring),
        HALF_LANES => slip_lanes::<HALF_LANES, false>(lanes, trigs, t_a, t_b, turn, measuring),
        _ => {
            for (path, trig) in lanes.iter_mut().zip(trigs.iter_mut()) {
                *trig = path.advance_segment(t_a, t_b, *trig, Some(turn), measuring);
            }
        }
    }
}

/// [`advance_lanes`] for `N` lanes, `MEMORY` = whether a friction memory is
/// on (the same for all: it is the oscillator's). A stuck lane takes no slip step (at 12 Hz
/// and 16.39 N, where the block sticks much of each period, that was a
/// tenth of the time).
#[inline(always)]
fn slip_lanes<const N: usize, const MEMORY: bool>(
    lanes: &mut [Path<'_>],
    trigs: &mut [Trig],
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
    let steps: [Option<SlipStep>; N] = std::array::from_fn(|l| {
        let p = &lanes[l];
        (signs[l] != 0.0).then(|| p.rk4_slip_with::<MEMORY>(trigs[l], p.x_m, p.v_m_per_s, h, turn, signs[l]))
    });
    for l in 0..N {
        trigs[l] = match &steps[l] {
            Some(step) if signs[l] * step.v_m_per_s > 0.0 => lanes[l].commit_slip(h, step, measuring),
            _ => lanes[l].advance_segment(t_a, t_b, trigs[l], Some(turn), measuring),
        };
    }
}

/// The law's Stribeck factor `1/(1 + c s)` at speed `s` (m/s) with rate `c`
/// (s/m, ≥ 0), –; for `s < 0` its first-order continuation `1 − c s`, equal
/// to it in value and slope at 0. Only an RK4 stage past a velocity zero
/// sees `s < 0` (a slip's sign is held over its steps, so its speed is
/// `sign · v`), and `1/(1 + c s)` has a pole at `s = −1/c`: with a steep law
/// (c ≈ 950 s/m, a diagnosis's calibrated baseline on blind seed 29 set 12)
/// a stage 1 mm/s past the zero reached it, the friction turned into a huge
/// driving force and the path ran away to x ≈ 1e12 m. The kernel's
/// `stribeck_factor` is the same.
#[inline(always)]
pub(crate) fn stribeck_factor(c_s_per_m: f64, speed_m_per_s: f64) -> f64 {
    if speed_m_per_s >= 0.0 { 1.0 / (1.0 + c_s_per_m * speed_m_per_s) } else { 1.0 - c_s_per_m * speed_m_per_s }
}

/// Integrates one excitation period of every path in `lanes` (at most
/// [`LANES`] realisations of one oscillator, in the same period; with
/// `samplers`, one per path). Noise-interval boundaries, output samples and
/// the period's end are step boundaries: each span between them is divided
/// into the fewest equal steps no longer than `T / S` (`S` =
/// `steps_per_period`). The base's trig starts exact at the period's start
/// and is carried by rotation (recomputed exactly after each event); in f64
/// the rotations drift by about 1e-16 each.
pub(crate) fn run_period(lanes: &mut [Path<'_>], measuring: bool, mut samplers: Option<&mut [Sampler]>) {
    assert!(!lanes.is_empty() && lanes.len() <= LANES, "1 to {LANES} paths step together, not {}", lanes.len());
    let o = lanes[0].osc;
    debug_assert!(lanes.iter().all(|p| std::ptr::eq(p.osc, o) && p.next_boundary == lanes[0].next_boundary));
    let w = o.omega_rad_per_s;
    let max_step_s = o.period_s / f64::from(o.steps_per_period);
    let period_start_s = lanes[0].period as f64 * o.period_s;
    for path in lanes.iter_mut() {
        path.period_max_x_m = path.x_m;
        path.period_stick_s = 0.0;
        path.period_cos_integral = 0.0;
        path.period_sin_integral = 0.0;
    }
    let mut t = 0.0;
    let mut trigs = [Trig { cos: 1.0, sin: 0.0 }; LANES];
    let trigs = &mut trigs[..lanes.len()];
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
            let steps = span_steps(span, max_step_s);
            let h = span / f64::from(steps);
            let turn = Trig::turn(0.5 * w * h);
            let mut step_start = t;
            for k in 1..=steps {
                let step_end = if k == steps { target } else { t + f64::from(k) * h };
                advance_lanes(lanes, trigs, step_start, step_end, turn, measuring);
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
                path.draw_noise();
            }
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

/// Time (s from the run's start) at which noise interval `interval` (≥ 1)
/// begins, in the arithmetic [`Path::run_period`] gives an aligned sample
/// there: the boundary's period start plus its position in the period, both
/// from the 32.32 fixed-point boundary `interval · noise_interval_fixed`.
pub(crate) fn noise_boundary_time_s(osc: &Oscillator, interval: u64) -> f64 {
    let boundary = u128::from(interval) * u128::from(osc.noise_interval_fixed);
    let period_start_s = (boundary >> 32) as u64 as f64 * osc.period_s;
    let noise_t = (boundary as u64 & 0xFFFF_FFFF) as f64 / FIXED_ONE * osc.period_s;
    period_start_s + noise_t
}

/// The fewest equal steps no longer than `max_step_s` that cover `span_s`
/// (a span of exactly k steps takes k, up to rounding).
pub(crate) fn span_steps(span_s: f64, max_step_s: f64) -> u32 {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonics_by_angle_addition_match_a_cos_per_harmonic() {
        let effects = crate::engine::effects::Effects {
            normal_force_harmonics: Some(crate::engine::effects::NormalForceHarmonics {
                form: crate::engine::effects::HarmonicForm::Fourier,
                amplitudes_n: [1.5, 0.0, 0.7, 0.3],
                amplitudes_per_n0: [0.0, 0.01, 0.0, 0.0],
                phases_rad: [0.4, -2.0, 3.1, -0.9],
                shape: 2.0,
            }),
            ..Default::default()
        };
        let e = EffectParams::new(&effects, 20.0, 0.3, 1.0 / 600.0);
        for i in 0..1000 {
            let phase = i as f64 * 0.001_234_567;
            let theta = std::f64::consts::TAU * phase;
            let direct: f64 = (0..4)
                .map(|k| e.harmonic_amplitudes_n[k] * ((k + 1) as f64 * theta + e.harmonic_phases_rad[k]).cos())
                .sum();
            assert!((harmonics_n(&e, phase, 0.37) - direct).abs() < 1e-14, "phase {phase}");
        }
        assert_eq!(harmonics_n(&EffectParams::default(), 0.3, 0.37), 0.0);
    }

    #[test]
    fn the_position_form_follows_the_displacement_not_the_phase() {
        let effects = crate::engine::effects::Effects {
            normal_force_harmonics: Some(crate::engine::effects::NormalForceHarmonics {
                form: HarmonicForm::Position,
                amplitudes_n: [1.5, 0.0, 0.7, 0.3],
                amplitudes_per_n0: [0.04, 0.02, 0.5, 0.5],
                phases_rad: [0.4, -2.0, 3.1, -0.9],
                shape: 2.0,
            }),
            ..Default::default()
        };
        let e = EffectParams::new(&effects, 20.0, 0.3, 1.0 / 600.0);
        assert_eq!(e.harmonic_amplitudes_n, [0.04 * 20.0, 0.02 * 20.0, 0.0, 0.0]);
        for r in [-3.0, -1.0, -0.25, 0.0, 0.5, 1.0, 2.7] {
            let expected = 20.0 * (0.04 * r + 0.02 * r * r);
            for phase in [0.0, 0.3, 0.77] {
                assert!((harmonics_n(&e, phase, r) - expected).abs() < 1e-14, "r {r}, phase {phase}");
            }
        }
    }

    #[test]
    fn small_turns_match_sin_cos() {
        for theta in [0.0, 1e-9, 1e-4, 0.0123, -0.03, 0.0499, 0.0731, -0.0999, 0.1] {
            let (turn, exact) = (Trig::turn(theta), Trig::at(theta));
            assert!(
                (turn.cos - exact.cos).abs() <= 2.3e-16 && (turn.sin - exact.sin).abs() <= 1e-17,
                "{theta}: {turn:?} {exact:?}"
            );
        }
    }

    /// The paper rig at 7 Hz and 16.39 N without noise, under hysteresis
    /// `lag` with a 10 ms memory, plus `overrides`.
    fn noiseless_lag_oscillator(overrides: &[&str]) -> Oscillator {
        let base = [
            "friction.sigma=0",
            "normal_force.sigma=0",
            "friction_hysteresis.form=\"lag\"",
            "friction_hysteresis.time_constant_s=0.01",
        ];
        let overrides: Vec<String> = base.iter().chain(overrides).map(|s| s.to_string()).collect();
        let model = crate::engine::Model::paper_rig(&overrides).unwrap();
        let condition = crate::engine::Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
        Oscillator::new(&model, condition).unwrap()
    }

    /// A slip from rest right after a velocity zero is a breakaway like one
    /// from a stick, so under hysteresis `lag` the lagged coefficient starts
    /// at the static one the breakaway was judged by. Here the law rises with
    /// speed (b < 0: static 0.027), the block slips forward with a lagged
    /// coefficient of 0.3 carried from faster sliding, and the spring pushes
    /// forward with 0.15 N0: friction stops it within the step, and the spring
    /// is beyond the static friction, so it slips on. Carried over, the 0.3
    /// held it: it re-slipped without moving up to the event limit and was
    /// forced to stick.
    #[test]
    fn a_slip_from_rest_under_lag_starts_at_the_static_coefficient() {
        let osc = noiseless_lag_oscillator(&["friction.b=-0.4"]);
        let mut path = Path::new(&osc, 1, 0, InitialState { x_m: 0.0, v_m_per_s: 1e-4 });
        let n = path.normal_force_n;
        assert!((path.static_coefficient() - 0.027).abs() < 1e-12 && n > 0.0);
        // The spring at t = 0 (base at its amplitude) pushes with 0.15 N.
        path.x_m = osc.base_amplitude_m - 0.15 * n / osc.stiffness_n_per_m;
        path.slip_start_x_m = path.x_m;
        path.memory = 0.3;
        assert_eq!(path.mode, Mode::Slip(1));
        path.advance_segment(0.0, 1e-3, Trig { cos: 1.0, sin: 0.0 }, None, false);
        assert_eq!(path.mode, Mode::Slip(1), "held at rest: v = {}", path.v_m_per_s);
        assert!(path.v_m_per_s > 0.0 && path.memory < 0.3, "v = {}, μ_f = {}", path.v_m_per_s, path.memory);
    }

    /// Under hysteresis `lag` with a stiction released over a slip length,
    /// a block that breaks away slips on: sliding starts at the static
    /// coefficient, the lagged part of it without the excess the release
    /// adds on top. With the excess counted twice (the lagged coefficient
    /// started at the static one, excess included), friction at the start
    /// exceeded the force that broke the block away, and it re-slipped
    /// without moving up to the event limit and was forced to stick.
    #[test]
    fn a_breakaway_under_lag_and_a_released_stiction_slips_on() {
        let osc = noiseless_lag_oscillator(&["stiction.excess=0.2", "stiction.release_length_m=1e-4"]);
        let mut path = Path::new(&osc, 1, 0, InitialState { x_m: 0.0, v_m_per_s: 0.0 });
        let (n, mu_s) = (path.normal_force_n, path.static_coefficient());
        // At rest, the spring at t = 0 pushing with 1.05 of the breakaway force.
        path.mode = Mode::Stick;
        path.x_m = osc.base_amplitude_m - 1.05 * mu_s * n / osc.stiffness_n_per_m;
        let x0 = path.x_m;
        path.advance_segment(0.0, 1e-3, Trig { cos: 1.0, sin: 0.0 }, None, false);
        assert_eq!(path.mode, Mode::Slip(1), "stuck: v = {}", path.v_m_per_s);
        assert!(path.v_m_per_s > 0.0 && path.x_m > x0, "v = {}, moved {} m", path.v_m_per_s, path.x_m - x0);
        assert!((path.lag_start_coefficient() + 0.2 - mu_s).abs() < 1e-12);
    }

    /// Under hysteresis `ageing` a breakaway is judged by the static
    /// coefficient with the contact age held at the interval's start, and
    /// the slip starts from that same age, so sliding friction at v = 0
    /// starts at exactly that static coefficient (no stop and re-slip at
    /// once). The age held is the stick's start plus the time stuck up to
    /// the interval's start, and the term is B ln((θ + θ_c)/(2 θ_c)).
    #[test]
    fn an_ageing_slip_starts_at_the_static_coefficient() {
        let model = crate::engine::Model::paper_rig(&[
            "friction.sigma=0".into(),
            "normal_force.sigma=0".into(),
            "friction_hysteresis.form=\"ageing\"".into(),
            "friction_hysteresis.length_m=1e-5".into(),
            "friction_hysteresis.strength=0.03".into(),
        ])
        .unwrap();
        let condition = crate::engine::Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
        let osc = Oscillator::new(&model, condition).unwrap();
        let mut path = Path::new(&osc, 1, 0, InitialState { x_m: 0.0, v_m_per_s: 0.0 });
        assert_eq!(path.memory_form, Memory::Ageing);
        // Stuck since 0.1 s with an age of 2 ms then; interval 100 starts later.
        path.mode = Mode::Stick;
        (path.memory, path.stick_since_s, path.interval) = (2e-3, 0.1, 100);
        path.draw_noise();
        let t_s = 100.0 * osc.noise_interval_s;
        let age_s = path.contact_age_at(t_s);
        let cutoff_age_s = 1e-5 / AGEING_CUTOFF_SPEED_M_PER_S;
        assert!((age_s - (2e-3 + t_s - 0.1)).abs() < 1e-15, "{age_s}");
        let expected = 0.03 * ((age_s + cutoff_age_s) / (2.0 * cutoff_age_s)).ln();
        assert!((path.ageing_excess - expected).abs() < 1e-15, "{} vs {expected}", path.ageing_excess);
        assert!((path.static_coefficient() - (0.527 + expected)).abs() < 1e-12);
        let sliding = path.friction_coefficient(0.0, 0.0, path.x_m, age_s);
        assert!((sliding - path.static_coefficient()).abs() < 1e-15, "{sliding} vs {}", path.static_coefficient());
    }

    /// The friction noise's standardised values g over `n` intervals with
    /// the coloured noise set by `overrides`.
    fn friction_noise(overrides: &[&str], n: u64) -> Vec<f64> {
        let mut overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        overrides.push("friction.sigma=0.02".into());
        let model = crate::engine::Model::paper_rig(&overrides).unwrap();
        let condition = crate::engine::Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
        let osc = Oscillator::new(&model, condition).unwrap();
        let mut path = Path::new(&osc, 5, 0, InitialState { x_m: 0.0, v_m_per_s: 0.0 });
        (0..n)
            .map(|k| {
                path.interval = k;
                path.draw_noise();
                path.friction_noise / 0.02
            })
            .collect()
    }

    /// Sample autocorrelation of `g` at `lag`.
    fn autocorrelation(g: &[f64], lag: usize) -> f64 {
        let m = g.iter().sum::<f64>() / g.len() as f64;
        let var = g.iter().map(|x| (x - m).powi(2)).sum::<f64>();
        g.windows(lag + 1).map(|w| (w[0] - m) * (w[lag] - m)).sum::<f64>() / var
    }

    /// `fast_slow` is two AR(1) parts with τc and 10 τc, the slow one
    /// carrying `coloured_share` of the variance: at 30 intervals with τc =
    /// 5 intervals the correlation is 0.4 e^−6 + 0.6 e^−0.6 = 0.33, where a
    /// single AR(1) with τc has lost it (e^−6 = 0.002). The variance stays
    /// σ_μ². With 200 000 intervals the sample autocorrelation's standard
    /// error is about 0.015 and the variance's about 0.03 (about 3 000
    /// independent values), so the bounds are 4 standard errors or more.
    #[test]
    fn fast_slow_noise_has_two_time_scales() {
        let interval = "noise.interval_s=0.001";
        let tau = "coloured_friction_noise.correlation_time_s=0.005";
        let two = friction_noise(
            &[
                interval,
                tau,
                "coloured_friction_noise.form=\"fast_slow\"",
                "coloured_friction_noise.coloured_share=0.6",
            ],
            200_000,
        );
        let one = friction_noise(&[interval, tau], 200_000);
        let variance = two.iter().map(|x| x * x).sum::<f64>() / two.len() as f64;
        let (two_30, one_30) = (autocorrelation(&two, 30), autocorrelation(&one, 30));
        let two_1 = autocorrelation(&two, 1);
        let expected_1 = 0.4 * (-0.2f64).exp() + 0.6 * (-0.02f64).exp();
        println!(
            "fast_slow: variance {variance:.3}, lag 1 {two_1:.3} ({expected_1:.3}), lag 30 {two_30:.3}; ar1 lag 30 {one_30:.3}"
        );
        assert!((variance - 1.0).abs() < 0.12, "variance {variance}");
        assert!((two_30 - 0.331).abs() < 0.06, "fast_slow at lag 30: {two_30}");
        assert!((two_1 - expected_1).abs() < 0.03, "fast_slow at lag 1: {two_1} vs {expected_1}");
        assert!(one_30.abs() < 0.03, "ar1 at lag 30: {one_30}");
    }

    #[test]
    fn rotation_by_half_steps_matches_the_functions() {
        let w = 44.0;
        let (t, h) = (0.0123, 0.004);
        let half = Trig::at(0.5 * w * h);
        let end = Trig::at(w * t).rotated(half).rotated(half);
        let exact = Trig::at(w * (t + h));
        assert!((end.cos - exact.cos).abs() < 1e-15 && (end.sin - exact.sin).abs() < 1e-15, "{end:?} {exact:?}");
    }
}
