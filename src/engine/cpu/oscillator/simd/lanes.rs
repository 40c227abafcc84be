//! The lanes of a vector step: each lane's state as structure of arrays,
//! `V`, lanes of f64 on which one operation acts on all, and how many lanes
//! a group steps at most. (The module is private to `simd`, which hands
//! the state's types on to the oscillator.)

/// Realisations of one model at one frequency (at one load or several)
/// stepped together, grid step by grid step.
/// Their step grids are the same (the noise boundaries and samples fall at
/// the same times), so each grid step's RK4 for all of them is one run of
/// straight-line code: independent dependency chains the core overlaps
/// instead of waiting out one chain's latency (one realisation at a time,
/// the reference was latency-bound: each stage's division and sums wait on
/// the last). Sixteen are two AVX-512 registers' worth, two chains: eight,
/// one register, still waited out each stage's latency (the main job took
/// 12% more CPU time); 32 took 15% more than 16 (the step's values no longer
/// fit the registers).
pub(crate) const LANES: usize = 16;

/// The per-lane state a slip step starts from, one element per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SlipLanes<const N: usize> {
    /// Displacement x, m.
    pub(crate) x_m: [f64; N],
    /// Velocity v, m/s.
    pub(crate) v_m_per_s: [f64; N],
    /// Slip direction ±1, or 0 for a stuck lane (stepped and discarded), –.
    pub(crate) sign: [f64; N],
    /// Friction coefficient's random part in the current interval, –.
    pub(crate) friction_noise: [f64; N],
    /// Normal force in the current interval, N.
    pub(crate) normal_force_n: [f64; N],
    /// `cos Ωt` and `sin Ωt` of the base at the step's start, –.
    pub(crate) cos: [f64; N],
    pub(crate) sin: [f64; N],
    /// The friction memory at the step's start (μ_f, –, or θ, s; see
    /// [`Memory`](crate::engine::effects::Memory); carried unchanged without one).
    pub(crate) memory: [f64; N],
}

/// What a friction history reads of each lane besides [`SlipLanes`], one
/// element per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HistoryLanes<const N: usize> {
    /// Where the current slip started, m.
    pub(crate) slip_start_x_m: [f64; N],
    /// The stiction excess carried into the slip, –.
    pub(crate) stiction_excess: [f64; N],
}

/// Lanes of f64, one operation for all: a vector where the target has one.
#[derive(Clone, Copy)]
pub(super) struct V<const N: usize>(pub(super) [f64; N]);

impl<const N: usize> V<N> {
    #[inline(always)]
    pub(super) fn splat(value: f64) -> Self {
        V([value; N])
    }

    #[inline(always)]
    pub(super) fn map(self, f: impl Fn(f64) -> f64) -> Self {
        V(self.0.map(f))
    }

    /// `f` of each lane's index: for a function of several lanes' values
    /// that has no vector form (a library call).
    #[inline(always)]
    pub(super) fn lanewise(f: impl Fn(usize) -> f64) -> Self {
        V(std::array::from_fn(f))
    }

    #[inline(always)]
    pub(super) fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
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
