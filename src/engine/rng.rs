//! Counter-based noise: Philox4x32-10 (Salmon et al., SC'11) and Box–Muller.
//!
//! A random value is a pure function of its key `(seed, realisation, stream,
//! interval index)`: the 64-bit seed is the Philox key, and the counter is
//! `[interval_lo, interval_hi, realisation, stream]`. Nothing depends on the
//! thread, the step size or the dispatch layout. `shaders/rng.wgsl` is the
//! same generator in WGSL, word for word.

/// The main noise stream. Its block for an interval gives two Box–Muller
/// pairs: pair A is the friction coefficient's random part `ξ_μ` (cosine
/// branch) and the normal force's `ξ_N` (sine branch), so the baseline draws
/// one Philox block and one pair per interval; pair B, drawn only by effects
/// that need it, is a second friction value (non-Gaussian forms) and the
/// stiction noise.
pub const STREAM_MAIN: u32 = 0;
/// Noise stream of coloured friction noise's slow parts.
pub const STREAM_COLOUR: u32 = 1;
/// Noise stream of the measurement noise a diagnosis adds to simulated
/// records (keyed by sample index, not interval).
pub const STREAM_SENSOR: u32 = 2;
/// Noise stream of the normal force's `random_walk` drift: one increment
/// per noise interval.
pub const STREAM_DRIFT: u32 = 3;

/// Philox4x32's round multipliers.
pub const PHILOX_M0: u32 = 0xD251_1F53;
pub const PHILOX_M1: u32 = 0xCD9E_8D57;
/// Philox4x32's key increments (Weyl sequence).
pub const PHILOX_W0: u32 = 0x9E37_79B9;
pub const PHILOX_W1: u32 = 0xBB67_AE85;

#[inline]
fn mulhilo(a: u32, b: u32) -> (u32, u32) {
    let product = u64::from(a) * u64::from(b);
    ((product >> 32) as u32, product as u32)
}

/// One Philox4x32 round of counter `c` under round key `k`.
#[inline]
fn philox_round(c: [u32; 4], k: [u32; 2]) -> [u32; 4] {
    let (hi0, lo0) = mulhilo(PHILOX_M0, c[0]);
    let (hi1, lo1) = mulhilo(PHILOX_M1, c[2]);
    [hi1 ^ c[1] ^ k[0], lo1, hi0 ^ c[3] ^ k[1], lo0]
}

/// Philox4x32 with 10 rounds.
#[inline]
pub fn philox4x32_10(counter: [u32; 4], key: [u32; 2]) -> [u32; 4] {
    let mut c = counter;
    let mut k = key;
    for round in 0..10 {
        if round > 0 {
            k[0] = k[0].wrapping_add(PHILOX_W0);
            k[1] = k[1].wrapping_add(PHILOX_W1);
        }
        c = philox_round(c, k);
    }
    c
}

/// The Philox key for a run seed.
#[inline]
pub fn seed_key(seed: u64) -> [u32; 2] {
    [seed as u32, (seed >> 32) as u32]
}

/// The Philox counter for one noise value.
#[inline]
pub fn noise_counter(realisation: u32, stream: u32, interval: u64) -> [u32; 4] {
    [interval as u32, (interval >> 32) as u32, realisation, stream]
}

/// Uniform on the open interval (0, 1) from the top 23 bits of a word:
/// `(w >> 9) + 0.5` over 2^23. The value needs 24 significant bits, so it is
/// exact in f32 as in f64: CPU and GPU agree bit for bit, and 1.0 never occurs.
#[inline]
pub fn uniform_open(word: u32) -> f64 {
    ((word >> 9) as f64 + 0.5) * (1.0 / 8_388_608.0)
}

/// `ln 2`'s leading bits (its low 32 mantissa bits zero): `e · LN2_HI` is
/// exact for every exponent `e` of an f64.
const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_0000_0000);
/// `ln 2 − LN2_HI`, rounded to f64 (from a 60-digit `ln 2`).
const LN2_LO: f64 = 4.749_325_039_031_672_6e-7;

/// `2/3, 2/5, …, 2/23`: [`ln_noise`]'s series in `s²`.
const ATANH_TERMS: [f64; 11] = {
    let mut terms = [0.0; 11];
    let mut k = 0;
    while k < 11 {
        terms[k] = 2.0 / (2 * k + 3) as f64;
        k += 1;
    }
    terms
};

/// `ln x` (–) of a positive normal `x`, as straight-line arithmetic that the
/// compiler runs lane by lane in vector registers (libm's `ln` is a call per
/// value). With `x = 2^e (1 + g)`, `1 + g` in `[√½, √2)`, and `s = g / (2 + g)`:
/// `ln(1 + g) = 2 atanh s = g − g²/2 + s (g²/2 + R)`, `R = 2 (s²/3 + s⁴/5 + …)`
/// summed to `s²²` (`s² ≤ 0.0295`: the rest is below 1e-18 of `g`). Where
/// `x` has at most 26 significant bits (every [`uniform_open`] value has 24)
/// `g` and `g²/2` are exact and the rest is small beside them; the large
/// terms are summed with their rounding errors kept. The result is within
/// one unit in the last place of `ln x`: a test checks all 2²³ uniform
/// values against libm's (and finds 0.5% of them one unit apart). The
/// Box–Muller radius is the only use.
#[inline(always)]
pub fn ln_noise(x: f64) -> f64 {
    let bits = x.to_bits();
    // The exponent as an f64, exactly: 2^52 + its biased bits, less the bias.
    let biased = f64::from_bits((bits >> 52) | 0x4330_0000_0000_0000) - (4_503_599_627_370_496.0 + 1023.0);
    let mantissa = f64::from_bits((bits & 0x000F_FFFF_FFFF_FFFF) | 0x3FF0_0000_0000_0000);
    let above = mantissa > std::f64::consts::SQRT_2;
    let f = if above { 0.5 * mantissa } else { mantissa };
    let e = if above { biased + 1.0 } else { biased };
    let g = f - 1.0;
    let s = g / (2.0 + g);
    let z = s * s;
    // Horner from the highest power.
    let mut r = ATANH_TERMS[10];
    for &term in ATANH_TERMS[..10].iter().rev() {
        r = r * z + term;
    }
    r *= z;
    // `e ln 2 + g − g²/2 + s (g²/2 + R)` (the identity's other form): its
    // two large terms summed with their rounding errors kept, so that only
    // the last addition rounds at the result's scale.
    let half_square = 0.5 * g * g;
    let (lead, lead_error) = two_sum(e * LN2_HI, g);
    let (sum, sum_error) = two_sum(lead, -half_square);
    sum + ((lead_error + sum_error) + (s * (half_square + r) + e * LN2_LO))
}

/// `a + b` rounded and its rounding error, exactly (Knuth's two-sum).
#[inline(always)]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let sum = a + b;
    let b_part = sum - a;
    (sum, (a - (sum - b_part)) + (b - b_part))
}

/// Box–Muller's radius `√(−2 ln u1)` of a uniform `u1` in (0, 1]: the one
/// home of the formula, so that every draw (alone, side by side, into a
/// table) gives the same bits.
#[inline(always)]
fn radius(u1: f64) -> f64 {
    (-2.0 * ln_noise(u1)).sqrt()
}

/// Standard Gaussian from two uniforms (Box–Muller, cosine branch).
#[inline]
pub fn box_muller(u1: f64, u2: f64) -> f64 {
    radius(u1) * (std::f64::consts::TAU * u2).cos()
}

/// Two independent standard Gaussians from two uniforms: Box–Muller's
/// cosine and sine branches, `r cos θ` and `r sin θ`.
#[inline]
pub fn box_muller_pair(u1: f64, u2: f64) -> (f64, f64) {
    let r = radius(u1);
    let (sin, cos) = (std::f64::consts::TAU * u2).sin_cos();
    (r * cos, r * sin)
}

/// Bits of [`uniform_open`]'s 23-bit grid that index [`ANGLE_FINE`]'s table.
const FINE_BITS: u32 = 12;

/// `(sin θ, cos θ)` of the coarse angles `θ = 2π j / 2¹¹` and of the fine
/// ones `θ = 2π (i + ½) / 2²³`, `j < 2¹¹`, `i < 2¹²`, from `sin_cos`.
static ANGLE_COARSE: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();
static ANGLE_FINE: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();

/// `(sin θ, cos θ)` of `θ = 2π u` for `u = uniform_open(word)`. The uniform
/// takes one of 2²³ values `(k + ½) / 2²³`, so the angle is a coarse part
/// (`k`'s top 11 bits) plus a fine one (its low 12 bits and the half), each
/// looked up (96 KiB of tables, made once) and put together by the addition
/// formulas: within 1e-15 of `sin_cos` of `2π u` (a test checks every
/// coarse and fine index; `2π u` itself rounds the angle by up to 4.4e-16,
/// and so do the tables' angles), at a fraction of its cost — Box–Muller's
/// `sin_cos` was an eighth of a diagnosis's time.
#[inline]
pub fn turn_of_uniform(word: u32) -> (f64, f64) {
    let k = word >> 9;
    let coarse = ANGLE_COARSE.get_or_init(|| {
        (0..1u32 << (23 - FINE_BITS))
            .map(|j| (std::f64::consts::TAU * f64::from(j << FINE_BITS) / 8_388_608.0).sin_cos())
            .collect()
    });
    let fine = ANGLE_FINE.get_or_init(|| {
        (0..1u32 << FINE_BITS).map(|i| (std::f64::consts::TAU * (f64::from(i) + 0.5) / 8_388_608.0).sin_cos()).collect()
    });
    let (sa, ca) = coarse[(k >> FINE_BITS) as usize];
    let (sb, cb) = fine[(k & ((1 << FINE_BITS) - 1)) as usize];
    (sa * cb + ca * sb, ca * cb - sa * sb)
}

/// [`box_muller_pair`] of `uniform_open(radius_word)` and
/// `uniform_open(angle_word)`, its angle by [`turn_of_uniform`].
#[inline]
fn gaussian_pair(radius_word: u32, angle_word: u32) -> (f64, f64) {
    let r = radius(uniform_open(radius_word));
    let (sin, cos) = turn_of_uniform(angle_word);
    (r * cos, r * sin)
}

/// The Philox block of key `(seed, realisation, stream, interval)`.
#[inline]
pub fn noise_block(key: [u32; 2], realisation: u32, stream: u32, interval: u64) -> [u32; 4] {
    philox4x32_10(noise_counter(realisation, stream, interval), key)
}

/// Blocks drawn at once, of realisations ([`pair_a_side_by_side`]) or of
/// intervals ([`pair_a_run`]): a group's sixteen lanes, two AVX-512
/// registers, so each Philox round is two
/// independent chains (eight, one chain, waited out each round's multiply:
/// the noisy default's draws took 4% more of its time).
pub const SIDE_BY_SIDE: usize = 16;

crate::vector::widest_vectors! {
/// [`pair_a`] of the main-stream blocks of interval `interval` of the first
/// `count` of `realisations` (the rest are not drawn: their pairs are 0),
/// side by side ([`pairs_of_counters`]).
pub fn pair_a_side_by_side(
    key: [u32; 2],
    realisations: [u32; SIDE_BY_SIDE],
    count: usize,
    interval: u64,
) -> [(f64, f64); SIDE_BY_SIDE] {
    let counter = noise_counter(0, STREAM_MAIN, interval);
    pairs_of_counters(key, [counter[0]; SIDE_BY_SIDE], [counter[1]; SIDE_BY_SIDE], realisations, count)
}
}

crate::vector::widest_vectors! {
/// [`pair_a`] of the main-stream blocks of realisation `realisation`'s
/// intervals `first..first + count` (`count` at most [`SIDE_BY_SIDE`]; the
/// rest of the array is 0), side by side ([`pairs_of_counters`]).
pub fn pair_a_run(key: [u32; 2], realisation: u32, first: u64, count: usize) -> [(f64, f64); SIDE_BY_SIDE] {
    let intervals: [u64; SIDE_BY_SIDE] = std::array::from_fn(|l| first.wrapping_add(l as u64));
    let (lo, hi) = (intervals.map(|i| i as u32), intervals.map(|i| (i >> 32) as u32));
    pairs_of_counters(key, lo, hi, [realisation; SIDE_BY_SIDE], count)
}
}

/// [`pair_a`] of the main-stream blocks of counters `[lo[l], hi[l],
/// realisations[l], STREAM_MAIN]` for the first `count` lanes (the rest
/// are 0): the Philox rounds, logarithms and square roots as vector code,
/// the turns looked up one value at a time. The same operations on each
/// value as [`noise_block`] and [`pair_a`], so the same values, bit for bit.
#[inline(always)]
fn pairs_of_counters(
    key: [u32; 2],
    lo: [u32; SIDE_BY_SIDE],
    hi: [u32; SIDE_BY_SIDE],
    realisations: [u32; SIDE_BY_SIDE],
    count: usize,
) -> [(f64, f64); SIDE_BY_SIDE] {
    // Each word in a 64-bit lane of its own (its top half zero), so that a
    // round's 32×32→64 multiplies, shifts and exclusive-ors are one vector
    // instruction each, with no packing between 32- and 64-bit lanes. The
    // rounds are written out, not looped: the instruction selector sees one
    // block at a time, and across a loop's back edge it could not tell that
    // a word's top half is zero, so it built two of the four multiplies
    // from three 32-bit ones each.
    let c = [lo, hi, realisations, [STREAM_MAIN; SIDE_BY_SIDE]].map(|w| w.map(u64::from));
    let k = |round: u32| {
        [
            u64::from(key[0].wrapping_add(PHILOX_W0.wrapping_mul(round))),
            u64::from(key[1].wrapping_add(PHILOX_W1.wrapping_mul(round))),
        ]
    };
    let c = philox_round_lanes(c, k(0));
    let c = philox_round_lanes(c, k(1));
    let c = philox_round_lanes(c, k(2));
    let c = philox_round_lanes(c, k(3));
    let c = philox_round_lanes(c, k(4));
    let c = philox_round_lanes(c, k(5));
    let c = philox_round_lanes(c, k(6));
    let c = philox_round_lanes(c, k(7));
    let c = philox_round_lanes(c, k(8));
    let [c0, c1, _, _] = philox_round_lanes(c, k(9));
    let (c0, c1): ([u32; SIDE_BY_SIDE], [u32; SIDE_BY_SIDE]) =
        (std::array::from_fn(|l| c0[l] as u32), std::array::from_fn(|l| c1[l] as u32));
    let count = count.min(SIDE_BY_SIDE);
    let radii: [f64; SIDE_BY_SIDE] = std::array::from_fn(|l| radius(uniform_open(c0[l])));
    let mut pairs = [(0.0, 0.0); SIDE_BY_SIDE];
    for l in 0..count {
        let (sin, cos) = turn_of_uniform(c1[l]);
        pairs[l] = (radii[l] * cos, radii[l] * sin);
    }
    pairs
}

/// [`philox_round`] of every lane: words `c` (each in a 64-bit lane, its
/// top half zero) under the round key `k` (the same).
#[inline(always)]
fn philox_round_lanes(c: [[u64; SIDE_BY_SIDE]; 4], k: [u64; 2]) -> [[u64; SIDE_BY_SIDE]; 4] {
    const LOW: u64 = 0xFFFF_FFFF;
    let [c0, c1, c2, c3] = c;
    let p0: [u64; SIDE_BY_SIDE] = std::array::from_fn(|l| u64::from(PHILOX_M0) * (c0[l] & LOW));
    let p1: [u64; SIDE_BY_SIDE] = std::array::from_fn(|l| u64::from(PHILOX_M1) * (c2[l] & LOW));
    [
        std::array::from_fn(|l| (p1[l] >> 32) ^ c1[l] ^ k[0]),
        std::array::from_fn(|l| p1[l] & LOW),
        std::array::from_fn(|l| (p0[l] >> 32) ^ c3[l] ^ k[1]),
        std::array::from_fn(|l| p0[l] & LOW),
    ]
}

/// Pair A of a block: the Gaussians of words 0 and 1.
#[inline]
pub fn pair_a(words: [u32; 4]) -> (f64, f64) {
    gaussian_pair(words[0], words[1])
}

/// Pair B of a block: the Gaussians of words 2 and 3.
#[inline]
pub fn pair_b(words: [u32; 4]) -> (f64, f64) {
    gaussian_pair(words[2], words[3])
}

/// The first standard Gaussian of key `(seed, realisation, stream,
/// interval)`: the cosine branch of pair A (the same value as `pair_a(..).0`
/// up to rounding of `sin_cos` against `cos`).
#[inline]
pub fn gaussian(key: [u32; 2], realisation: u32, stream: u32, interval: u64) -> f64 {
    let w = philox4x32_10(noise_counter(realisation, stream, interval), key);
    box_muller(uniform_open(w[0]), uniform_open(w[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Known-answer vectors from Random123's `kat_vectors` for philox4x32_10.
    #[test]
    fn philox_known_answers() {
        assert_eq!(philox4x32_10([0, 0, 0, 0], [0, 0]), [0x6627_e8d5, 0xe169_c58d, 0xbc57_ac4c, 0x9b00_dbd8]);
        assert_eq!(philox4x32_10([u32::MAX; 4], [u32::MAX; 2]), [0x408f_276d, 0x41c8_3b0e, 0xa20b_c7c6, 0x6d54_51fd]);
        assert_eq!(
            philox4x32_10([0x243f_6a88, 0x85a3_08d3, 0x1319_8a2e, 0x0370_7344], [0xa409_3822, 0x299f_31d0]),
            [0xd16c_fe09, 0x94fd_cceb, 0x5001_e420, 0x2412_6ea1]
        );
    }

    /// The looked-up turn against `sin_cos` of the same angle, at every
    /// coarse index (with the fine ends) and every fine index (with the
    /// coarse ends and the middle).
    #[test]
    fn looked_up_turns_match_sin_cos() {
        let mut worst = 0.0f64;
        let mut check = |k: u32| {
            let word = k << 9 | 0x1ab;
            let (sin, cos) = (std::f64::consts::TAU * uniform_open(word)).sin_cos();
            let (s, c) = turn_of_uniform(word);
            worst = worst.max((s - sin).abs()).max((c - cos).abs());
        };
        let fine_last = (1 << FINE_BITS) - 1;
        for j in 0..1u32 << (23 - FINE_BITS) {
            for i in [0, 1, fine_last / 2, fine_last] {
                check(j << FINE_BITS | i);
            }
        }
        for i in 0..=fine_last {
            for j in [0, 1, 1 << (22 - FINE_BITS), (1 << (23 - FINE_BITS)) - 1] {
                check(j << FINE_BITS | i);
            }
        }
        assert!(worst < 1e-15, "worst difference {worst:e}");
    }

    /// Pairs drawn side by side are those drawn one block at a time, bit
    /// for bit; lanes past the count are not drawn.
    #[test]
    fn pairs_side_by_side_are_those_drawn_alone() {
        let key = seed_key(0x0123_4567_89AB_CDEF);
        for interval in [0, 1, 599, 1 << 32, u64::MAX - 3] {
            for count in [SIDE_BY_SIDE, 5, 1] {
                let realisations = std::array::from_fn(|l| 1000 * l as u32 + 7);
                let pairs = pair_a_side_by_side(key, realisations, count, interval);
                for (l, &(a, b)) in pairs.iter().enumerate() {
                    let expected = if l < count {
                        pair_a(noise_block(key, realisations[l], STREAM_MAIN, interval))
                    } else {
                        (0.0, 0.0)
                    };
                    assert_eq!((a.to_bits(), b.to_bits()), (expected.0.to_bits(), expected.1.to_bits()));
                }
            }
        }
    }

    /// The noise's logarithm against libm's at every value the uniform
    /// takes (all 2²³): within one unit in the last place, and mostly the
    /// same value.
    #[test]
    fn noise_logarithm_is_within_an_ulp_of_libm_everywhere() {
        let (mut worst_ulps, mut differ) = (0u64, 0usize);
        for k in 0..1u32 << 23 {
            let u = uniform_open(k << 9);
            let (ours, libm) = (ln_noise(u), u.ln());
            let ulps = ours.to_bits().abs_diff(libm.to_bits());
            worst_ulps = worst_ulps.max(ulps);
            differ += usize::from(ulps != 0);
        }
        assert!(worst_ulps <= 1, "{worst_ulps} units in the last place at worst");
        assert!(differ < (1 << 23) / 100, "{differ} of 2^23 values differ from libm's");
        for x in [1e-300, 0.1, 0.5, 1.0, 1.5, 2.0, 10.0, 1e300] {
            assert!(ln_noise(x).to_bits().abs_diff(x.ln().to_bits()) <= 1, "ln {x}");
        }
    }

    /// A realisation's intervals drawn side by side are those drawn one
    /// block at a time, bit for bit, across the interval index's 32-bit
    /// carry; lanes past the count are not drawn.
    #[test]
    fn a_run_of_intervals_is_drawn_as_one_at_a_time() {
        let key = seed_key(0x0FED_CBA9_8765_4321);
        for first in [0, 17, (1 << 32) - 5, u64::MAX - 20] {
            for count in [SIDE_BY_SIDE, 3] {
                let pairs = pair_a_run(key, 42, first, count);
                for (l, &(a, b)) in pairs.iter().enumerate() {
                    let expected = if l < count {
                        pair_a(noise_block(key, 42, STREAM_MAIN, first + l as u64))
                    } else {
                        (0.0, 0.0)
                    };
                    assert_eq!((a.to_bits(), b.to_bits()), (expected.0.to_bits(), expected.1.to_bits()));
                }
            }
        }
    }

    #[test]
    fn uniform_is_strictly_inside_unit_interval() {
        assert!(uniform_open(0) > 0.0);
        assert!(uniform_open(u32::MAX) < 1.0);
    }
}
