// Exact reduction of peaks in the kernel: src/engine/reduce.rs's quantisation
// and binning in f32 (the same arithmetic as the CPU's), with integer tallies
// that each invocation adds to its point's sums once per dispatch, by
// multi-word atomic additions that carry.

// Accumulator words (ACCUMULATOR_WORDS per point): 0-1 peaks (u64),
// 2-3 Σ(q + 2^31) (u64), 4-6 Σq² (u96), 7-8 stuck time in T/2^20 (u64),
// 9 clamped peaks, 10-11 Σ(s + 2^31) of the phases' quantised sines (u64),
// 12-13 Σ of their quantised versines (u64), 14 periods whose peak or phase
// was not finite (never quantised or binned; the host refuses the result),
// 15 the largest peak and 16 the negated smallest, each as an order-keeping
// key of its f32 (`order_key`; 0 before any peak), 17 unused.

// This invocation's sums over the dispatch, flushed once at its end.
struct Tally {
    peaks: u32,
    sum_biased: vec2<u32>,
    sum_squares: vec3<u32>,
    stick_units: vec2<u32>,
    clamped: u32,
    phase_sin_biased: vec2<u32>,
    phase_versine: vec2<u32>,
    highest_key: u32,
    negated_lowest_key: u32,
}

var<private> tally: Tally;
var<private> point_index: u32;
// Periods of this invocation whose peak or phase was not finite (private
// variables start at zero in every invocation).
var<private> non_finite_periods: u32;

// Whether an f32 is ±inf or NaN, from its bits (the exponent all ones):
// implementations may assume floats finite, so `x != x` is not reliable.
fn is_non_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u;
}

// An f32's bits as a u32 whose order is the floats' (negative floats have
// their bits inverted, others their sign bit set): every finite float's key
// is above 0, so a maximum of keys starting at 0 is the largest float's.
fn order_key(x: f32) -> u32 {
    let bits = bitcast<u32>(x);
    return select(bits | 0x80000000u, ~bits, (bits & 0x80000000u) != 0u);
}

fn add_u64(a: vec2<u32>, b: u32) -> vec2<u32> {
    let lo = a.x + b;
    return vec2<u32>(lo, a.y + select(0u, 1u, lo < b));
}

// a (96 bits) + b (64 bits: lo, hi)
fn add_u96(a: vec3<u32>, b: vec2<u32>) -> vec3<u32> {
    let lo = a.x + b.x;
    let carry0 = select(0u, 1u, lo < b.x);
    let mid0 = a.y + b.y;
    let carry1 = select(0u, 1u, mid0 < b.y);
    let mid = mid0 + carry0;
    let carry2 = select(0u, 1u, mid < carry0);
    return vec3<u32>(lo, mid, a.z + carry1 + carry2);
}

// The histogram bin of a peak; mirrors PeakRange::bin.
fn histogram_bin(peak_m: f32) -> u32 {
    let inner = HISTOGRAM_BINS - 2u;
    let position = (peak_m - point.histogram_lo_m) * point.histogram_bins_per_m;
    if (position < 0.0) {
        return 0u;
    }
    if (position >= f32(inner)) {
        return inner + 1u;
    }
    return u32(position) + 1u;
}

// Quantises and tallies one measured period; mirrors PointAccumulator::tally_period.
fn tally_period(peak_m: f32, phase_rad: f32, stuck_share: f32) {
    if (is_non_finite(peak_m) || is_non_finite(phase_rad)) {
        non_finite_periods += 1u;
        return;
    }
    let q_real = round((peak_m - point.peak_centre_m) * point.inv_quantum_per_m);
    let q = i32(clamp(q_real, -QUANTISE_LIMIT, QUANTISE_LIMIT));
    tally.peaks += 1u;
    tally.sum_biased = add_u64(tally.sum_biased, bitcast<u32>(q) ^ 0x80000000u);
    let magnitude = u32(abs(q));
    let square = mulhilo(magnitude, magnitude);
    tally.sum_squares = add_u96(tally.sum_squares, vec2<u32>(square.y, square.x));
    tally.stick_units = add_u64(tally.stick_units, u32(round(stuck_share * STICK_UNITS_PER_PERIOD)));
    tally.clamped += select(0u, 1u, abs(q_real) > QUANTISE_LIMIT);
    // The phase's deviation from the reference: sine and versine (2 sin²(d/2)).
    let d = phase_rad - point.phase_ref_rad;
    let sine = i32(round(sin(d) * PHASE_QUANTA));
    let half_sine = sin(0.5 * d);
    let versine = u32(round(2.0 * half_sine * half_sine * PHASE_QUANTA));
    tally.phase_sin_biased = add_u64(tally.phase_sin_biased, bitcast<u32>(sine) ^ 0x80000000u);
    tally.phase_versine = add_u64(tally.phase_versine, versine);
    tally.highest_key = max(tally.highest_key, order_key(peak_m));
    tally.negated_lowest_key = max(tally.negated_lowest_key, order_key(-peak_m));
    atomicAdd(&histograms[point_index * HISTOGRAM_BINS + histogram_bin(peak_m)], 1u);
}

// Exact multi-word atomic addition: each word's carry is added to the next.
fn atomic_add_u64(word: u32, value: vec2<u32>) {
    let old = atomicAdd(&accumulators[word], value.x);
    let carry = select(0u, 1u, old + value.x < old);
    atomicAdd(&accumulators[word + 1u], value.y + carry);
}

fn atomic_add_u96(word: u32, value: vec3<u32>) {
    let old0 = atomicAdd(&accumulators[word], value.x);
    let carry0 = select(0u, 1u, old0 + value.x < old0);
    let mid = value.y + carry0;
    let carry_mid = select(0u, 1u, mid < carry0);
    let old1 = atomicAdd(&accumulators[word + 1u], mid);
    let carry1 = select(0u, 1u, old1 + mid < old1) + carry_mid;
    atomicAdd(&accumulators[word + 2u], value.z + carry1);
}

fn flush_tally() {
    let base = point_index * ACCUMULATOR_WORDS;
    if (non_finite_periods != 0u) {
        atomicAdd(&accumulators[base + 14u], non_finite_periods);
    }
    if (tally.peaks == 0u) {
        return;
    }
    atomic_add_u64(base, vec2<u32>(tally.peaks, 0u));
    atomic_add_u64(base + 2u, tally.sum_biased);
    atomic_add_u96(base + 4u, tally.sum_squares);
    atomic_add_u64(base + 7u, tally.stick_units);
    atomicAdd(&accumulators[base + 9u], tally.clamped);
    atomic_add_u64(base + 10u, tally.phase_sin_biased);
    atomic_add_u64(base + 12u, tally.phase_versine);
    atomicMax(&accumulators[base + 15u], tally.highest_key);
    atomicMax(&accumulators[base + 16u], tally.negated_lowest_key);
}
