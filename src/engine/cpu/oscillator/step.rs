//! The slip ODE's RK4 step and the events inside a step: a velocity zero
//! (stick or reversal), breakaway from stick, and a segment between two grid
//! times that handles them in order. The kernel's functions of the same
//! names are in `shaders/oscillator.wgsl`.

use super::*;

impl Path<'_> {
    /// Acceleration (m/s²) while slipping in direction `sign`, with the base
    /// at `cos_omega_t` of its amplitude, and the rate of the friction
    /// memory ([`Path::memory_rate`]; 0 unless a memory is on: `MEMORY` is
    /// whether [`Path::memory_form`] is one, a constant so that without it
    /// no stage computes it).
    #[inline(always)]
    pub(super) fn slip_rates<const MEMORY: bool>(
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
    pub(super) fn rk4_slip(&self, start: Trig, x_m: f64, v_m_per_s: f64, h_s: f64, half: Trig, sign: f64) -> SlipStep {
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
    pub(super) fn rk4_slip_with<const MEMORY: bool>(
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

    /// Adds a stuck interval of `duration_s` between base trigs `a` and `b`
    /// to the period's phase integrals, exactly: x is constant on a rigid
    /// stick, and `κ u + (1 − κ) w` on an elastic one.
    fn add_stick_phase(&mut self, a: Trig, b: Trig, duration_s: f64) {
        let w = self.osc.omega_rad_per_s;
        let kappa = self.stick_compliance;
        if kappa == 0.0 {
            self.period_cos_integral += self.x_m * (b.sin - a.sin) / w;
            self.period_sin_integral += self.x_m * (a.cos - b.cos) / w;
            return;
        }
        let (held, moving) = ((1.0 - kappa) * self.stick_anchor_m, kappa * self.osc.base_amplitude_m);
        // ∫cos² = Δt/2 + (sin 2Ωt_b − sin 2Ωt_a)/(4Ω); ∫cos·sin = (sin²Ωt_b − sin²Ωt_a)/(2Ω).
        let cos2 = 0.5 * duration_s + (b.sin * b.cos - a.sin * a.cos) / (2.0 * w);
        let cos_sin = (b.sin * b.sin - a.sin * a.sin) / (2.0 * w);
        self.period_cos_integral += held * (b.sin - a.sin) / w + moving * cos2;
        self.period_sin_integral += held * (a.cos - b.cos) / w + moving * cos_sin;
    }

    /// Moves a block stuck on an elastic contact to where the base at
    /// `end` puts it, and its period's largest x over the stuck interval
    /// that started with the base at `start` (the base's largest
    /// displacement lies inside where its sin turns from − to +). A rigid
    /// stick does not move.
    fn creep(&mut self, start: Trig, end: Trig) {
        if self.stick_compliance == 0.0 {
            return;
        }
        (self.x_m, self.v_m_per_s) = self.stuck_state(end);
        let top =
            if start.sin < 0.0 && end.sin >= 0.0 { self.stuck_state(Trig { cos: 1.0, sin: 0.0 }).0 } else { self.x_m };
        self.period_max_x_m = self.period_max_x_m.max(top);
    }

    /// The step length `h* ∈ (0, h]` at which the RK4 map's velocity reaches
    /// zero, given that `sign · v` is ≤ 0 after the full step `h`, and the
    /// RK4 step to it when it was taken on the way (not for `h* = h`).
    /// `full_step_v` is the full step's end velocity (m/s) where the caller
    /// has taken that very step.
    pub(super) fn locate_velocity_zero(
        &self,
        start: Trig,
        h_s: f64,
        sign: f64,
        full_step_v: Option<f64>,
    ) -> (f64, Option<SlipStep>) {
        let w = self.osc.omega_rad_per_s;
        let step_to = |h: f64| self.rk4_slip(start, self.x_m, self.v_m_per_s, h, Trig::turn(0.5 * w * h), sign);
        let g = |step: &SlipStep| sign * step.v_m_per_s;
        let (mut lo, mut g_lo) = (0.0, sign * self.v_m_per_s);
        let g_full = full_step_v.map_or_else(|| g(&step_to(h_s)), |v| sign * v);
        let (mut hi, mut g_hi) = (h_s, g_full);
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
        // bracket bisects it instead. On a hysteresis that sticks twice a
        // period: at most 5.2 RK4 steps per zero (passes of the loop
        // below), where Illinois from the chord took 12.7
        // (`benches/RESULTS.md`).
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
    pub(super) fn stick_or_slip(&self, trig: Trig) -> Mode {
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
    /// the direction. `k (U0 cos(Ω t) − x) = ±μ_s N` is solved in closed form
    /// (on an elastic stick `k (1 − κ)(U0 cos(Ω t) − w) = ±μ_s N`).
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
        let reach = threshold / (o.stiffness_n_per_m * (1.0 - self.stick_compliance));
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
        let anchor = if self.stick_compliance == 0.0 { self.x_m } else { self.stick_anchor_m };
        let level = (anchor + f64::from(sign) * reach) / o.base_amplitude_m;
        if !(-1.0..=1.0).contains(&level) {
            return best;
        }
        let base = -f64::from(sign) * self.entry_acos(sign, level);
        let n = ((phase_a - base) / std::f64::consts::TAU).ceil();
        let t = (base + n * std::f64::consts::TAU) / o.omega_rad_per_s;
        if t <= t_b && best.is_none_or(|(tb, _)| t < tb) { Some((t, sign)) } else { best }
    }

    /// `level.acos()` (rad) for the breakaway direction `sign`, remembered:
    /// a stuck block's levels are the same at every grid step of an
    /// interval (its x, load and noise are held), and two `acos` a stuck
    /// step were 3% of the main job.
    fn entry_acos(&self, sign: i8, level: f64) -> f64 {
        let k = usize::from(sign < 0);
        let mut memo = self.entry_acos.get();
        if memo[k].0 != level.to_bits() {
            memo[k] = (level.to_bits(), level.acos());
            self.entry_acos.set(memo);
        }
        memo[k].1
    }

    /// Advances from `t_a` to `t_b` (local times in the period, where the
    /// base's trig is `start`) with the noise held, through any stick/slip
    /// events on the way. `regular` is the rotation by half the segment
    /// (computed once for equal steps). Returns the base's trig at `t_b`.
    pub(super) fn advance_segment(
        &mut self,
        t_a: f64,
        t_b: f64,
        start: Trig,
        regular: Option<Trig>,
        measuring: bool,
    ) -> Trig {
        self.advance_segment_past(t_a, t_b, start, regular, measuring, None)
    }

    /// [`Path::advance_segment`] of a slipping path whose slip step over
    /// the whole segment (with `regular`) is known to end past a velocity
    /// zero (a vector step's, [`simd`]; [`PastZero`]), or of any path with
    /// `None`. The step is the one this would take first, so it is not
    /// taken again, and where its half-turn is the one
    /// [`Path::locate_velocity_zero`] takes, the search starts from its
    /// velocity instead of a step of its own; where the zero was located
    /// already (side by side with other lanes', [`zeros`]), it is not
    /// searched for again: the same steps, bit for bit, taken once.
    pub(super) fn advance_segment_past(
        &mut self,
        mut t_a: f64,
        t_b: f64,
        mut start: Trig,
        regular: Option<Trig>,
        measuring: bool,
        past_zero: Option<PastZero>,
    ) -> Trig {
        let w = self.osc.omega_rad_per_s;
        let period_start_s = self.period as f64 * self.osc.period_s;
        let mut events = 0;
        let mut whole = regular;
        let mut past_zero = past_zero;
        while t_a < t_b {
            // Only the first pass takes the segment's first step whole.
            let known = past_zero.take();
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
                        self.add_stick_phase(start, end, t_end - t_a);
                    }
                    self.creep(start, end);
                    if let Mode::Slip(s) = next
                        && self.stick_compliance != 0.0
                    {
                        // Off an elastic stick the block slips on from the
                        // speed it crept at, where that is the slip's way.
                        self.v_m_per_s = f64::from(s) * (f64::from(s) * self.v_m_per_s).max(0.0);
                    }
                    self.mode = next;
                    self.slip_start_x_m = self.x_m;
                    if next != Mode::Stick {
                        self.memory = if self.memory_form == Memory::Ageing {
                            // The slip starts from the contact age the
                            // breakaway was judged by.
                            self.contact_age_at(self.interval as f64 * self.osc.noise_interval_s)
                        } else {
                            self.breakaway_memory()
                        };
                    }
                    (t_a, start, whole) = (t_end, end, None);
                    events += 1;
                }
                Mode::Slip(s) => {
                    let sign = f64::from(s);
                    let h = t_b - t_a;
                    let half = whole.unwrap_or_else(|| Trig::turn(0.5 * w * h));
                    let full_v = match known {
                        Some(known) => known.full_step_v,
                        None => {
                            let step = self.rk4_slip(start, self.x_m, self.v_m_per_s, h, half, sign);
                            if sign * step.v_m_per_s > 0.0 {
                                return self.commit_slip(h, &step, measuring);
                            }
                            step.v_m_per_s
                        }
                    };
                    let (h_zero, to_zero) = match known.and_then(|k| k.located) {
                        Some(located) => located,
                        None => {
                            let searched_half = Trig::turn(0.5 * w * h);
                            let same_step = searched_half.cos.to_bits() == half.cos.to_bits()
                                && searched_half.sin.to_bits() == half.sin.to_bits();
                            self.locate_velocity_zero(start, h, sign, same_step.then_some(full_v))
                        }
                    };
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
                        self.start_stick(period_start_s + t_a, start);
                    } else if self.memory_form != Memory::Ageing {
                        // A slip from rest is a breakaway like one from a
                        // stick: the lagged coefficient starts at the static
                        // one the breakaway was judged by (carried over, it
                        // held a block the test let go, which then could
                        // not move and re-slipped up to the event limit).
                        // The contact age goes on from where the slip left
                        // it, which the static coefficient just read.
                        // Dahl's friction turns over from where it was.
                        self.memory = self.reversal_memory(self.mode != Mode::Slip(s));
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
    pub(super) fn friction_force(&self, trig: Trig) -> f64 {
        match self.mode {
            Mode::Stick => -self.spring_force(trig.cos, self.x_m),
            Mode::Slip(s) => {
                let sign = f64::from(s);
                -sign * self.friction_force_n(sign * self.v_m_per_s, self.v_m_per_s, self.x_m, self.memory)
            }
        }
    }

    /// [`Path::commit_slip`] of lane `l` of a vector step ([`simd`]).
    #[inline(always)]
    pub(super) fn commit_slip_lane<const N: usize>(
        &mut self,
        step: &simd::SlippedLanes<N>,
        l: usize,
        measuring: bool,
    ) -> Trig {
        if measuring {
            self.period_cos_integral += step.cos_integral[l];
            self.period_sin_integral += step.sin_integral[l];
        }
        self.x_m = step.x_m[l];
        self.v_m_per_s = step.v_m_per_s[l];
        self.memory = step.memory[l];
        self.period_max_x_m = self.period_max_x_m.max(step.x_m[l]);
        Trig { cos: step.end_cos[l], sin: step.end_sin[l] }
    }

    /// The state of `lanes`, with base trigs `trigs` and slip directions
    /// `signs` (0 for a stuck lane), as the vector step takes it.
    pub(super) fn slip_state<const N: usize>(
        lanes: &[Path<'_>; N],
        trigs: &[Trig; N],
        signs: [f64; N],
    ) -> simd::SlipLanes<N> {
        simd::SlipLanes {
            x_m: std::array::from_fn(|l| lanes[l].x_m),
            v_m_per_s: std::array::from_fn(|l| lanes[l].v_m_per_s),
            sign: signs,
            friction_noise: std::array::from_fn(|l| lanes[l].friction_noise),
            normal_force_n: std::array::from_fn(|l| lanes[l].normal_force_n),
            cos: trigs.map(|t| t.cos),
            sin: trigs.map(|t| t.sin),
            memory: std::array::from_fn(|l| lanes[l].memory),
        }
    }

    /// The friction history of `lanes` as the vector step takes it, `None`
    /// where none is on (the same for all: it is the model's).
    pub(super) fn history<'p, const N: usize>(lanes: &'p [Path<'_>; N]) -> Option<simd::History<'p, N>> {
        let first = &lanes[0];
        first.history.then(|| simd::History {
            lanes: simd::HistoryLanes {
                slip_start_x_m: std::array::from_fn(|l| lanes[l].slip_start_x_m),
                stiction_excess: std::array::from_fn(|l| lanes[l].stiction_excess),
            },
            law: simd::HistoryLaw { effects: &first.osc.effects, memory: first.memory_form, dahl: first.dahl() },
        })
    }

    /// The baseline law and the rig as the vector step takes them for the
    /// group `lanes` (at most [`LANES`]): the law's terms at each lane's
    /// load, the rest the first lane's (the same for all: [`steps_beside`]).
    pub(super) fn slip_law(lanes: &[Path<'_>]) -> simd::SlipLaw {
        let o = lanes[0].osc;
        let per_lane = |term: &dyn Fn(&Path<'_>) -> f64| std::array::from_fn(|l| lanes.get(l).map_or(0.0, term));
        simd::SlipLaw {
            a_offset: per_lane(&|p| p.law_a + p.osc.effects.friction_offset),
            b: per_lane(&|p| p.law_b),
            d_s2_per_m2: per_lane(&|p| p.law_d),
            c_s_per_m: o.friction_c_s_per_m,
            stiffness_n_per_m: o.stiffness_n_per_m,
            base_amplitude_m: o.base_amplitude_m,
            damping_n_s_per_m: o.damping_n_s_per_m,
            inv_mass: lanes[0].inv_mass,
            adhesion_n: o.effects.adhesion_force_n,
        }
    }

    /// Commits a slip step over `h_s` seconds that ends still under way:
    /// the state, the period's largest x, and the phase integrals when
    /// `measuring`. Returns the base's trig at its end.
    #[inline(always)]
    pub(super) fn commit_slip(&mut self, h_s: f64, step: &SlipStep, measuring: bool) -> Trig {
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
