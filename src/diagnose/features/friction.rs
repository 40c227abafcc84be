//! Features of the friction coefficient while slipping: its random part's
//! spread, shape, memory and trend over the record, the accelerating
//! against decelerating branch, and breakaway against low-speed friction.

use super::stats::{moments, negligible, solve_normal};
use super::{
    BREAKAWAY_SAMPLES, FrictionFeatures, HYSTERESIS_BINS, HYSTERESIS_MIN_PER_SIDE, LOW_SPEED_FRACTION, MIN_PAIRS,
    MIN_SLIP_SAMPLES, MIN_STICK_SAMPLES, MotionReading, SLIP_SPEED_FRACTION, STICK_SPEED_FRACTION,
};

/// How many Stribeck rates the friction baseline tries.
const STRIBECK_RATES: usize = 11;

/// Grid of Stribeck rates `c` (in units of 1 / max|v|) tried by the friction baseline.
fn stribeck_grid() -> [f64; STRIBECK_RATES] {
    std::array::from_fn(|i| 0.3 * 10f64.powf(i as f64 * 0.4))
}

crate::vector::widest_vectors! {
/// Friction-coefficient features (see [`FrictionFeatures`]), with the
/// widest vectors there are (the Stribeck rates' sums side by side).
pub(super) fn friction_features(
    t: &[f64],
    v: &[f64],
    force: &[f64],
    normal: &[f64],
    motion: MotionReading,
) -> Option<FrictionFeatures> {
    let n = t.len().min(v.len()).min(force.len()).min(normal.len());
    let (t, v, force, normal) = (&t[..n], &v[..n], &force[..n], &normal[..n]);
    let v_max = v.iter().filter(|x| x.is_finite()).fold(0.0f64, |m, x| m.max(x.abs()));
    if v_max <= 0.0 {
        return None;
    }
    let floor = super::normal_force_floor(normal);
    let usable = |i: usize| v[i].is_finite() && force[i].is_finite() && normal[i].is_finite() && normal[i] >= floor;
    let moving = motion.slipping(v);
    let slipping: Vec<bool> = (0..n).map(|i| moving[i] && usable(i) && force[i] * v[i] < 0.0).collect();
    let idx: Vec<usize> = (0..n).filter(|&i| slipping[i]).collect();
    if idx.len() < MIN_SLIP_SAMPLES {
        return None;
    }
    let mu: Vec<f64> = idx.iter().map(|&i| force[i].abs() / normal[i]).collect();
    let speed: Vec<f64> = idx.iter().map(|&i| v[i].abs() / v_max).collect();
    let (mu_mean, _, _, _) = moments(&mu);

    // Baseline law μ(s): quadratic, plus a Stribeck term when it fits better.
    // The normal equations of every fit in one pass: the quadratic block is
    // shared, and each Stribeck rate adds one row (the same sums, in the same
    // order, as a pass per fit).
    let m = mu.len();
    let y = |i: usize| mu[i] - mu_mean;
    let rates: [f64; STRIBECK_RATES] = stribeck_grid();
    let mut quadratic = ([[0.0f64; 3]; 3], [0.0f64; 3], 0.0f64);
    // Per rate: the sums of g·1, g·s, g·s², g² and g·y, g = 1/(1 + c s),
    // each an array over the rates (the rates' divisions side by side).
    let mut stribeck = [[0.0f64; STRIBECK_RATES]; 5];
    for (i, &s) in speed.iter().enumerate() {
        let yi = y(i);
        let row = [1.0, s, s * s];
        let (ata, aty, yty) = &mut quadratic;
        *yty += yi * yi;
        for a in 0..3 {
            aty[a] += row[a] * yi;
            for b in 0..=a {
                ata[a][b] += row[a] * row[b];
            }
        }
        let g: [f64; STRIBECK_RATES] = std::array::from_fn(|k| 1.0 / (1.0 + rates[k] * s));
        let [g_one, g_s, g_s2, g_g, g_y] = &mut stribeck;
        for k in 0..STRIBECK_RATES {
            g_y[k] += g[k] * yi;
            g_one[k] += g[k] * row[0];
            g_s[k] += g[k] * row[1];
            g_s2[k] += g[k] * row[2];
            g_g[k] += g[k] * g[k];
        }
    }
    let mut best: Option<(Vec<f64>, f64, Option<f64>)> = if m >= 3 {
        solve_normal(&quadratic.0, &quadratic.1, quadratic.2).map(|(coef, ssr)| (coef, ssr, None))
    } else {
        None
    };
    for (k, &c) in rates.iter().enumerate() {
        if m < 4 {
            break;
        }
        let [g_one, g_s, g_s2, g_g, g_y] = &stribeck;
        let (extra, extra_y) = ([g_one[k], g_s[k], g_s2[k], g_g[k]], g_y[k]);
        let mut ata = [[0.0f64; 4]; 4];
        for (row, shared) in ata.iter_mut().zip(&quadratic.0) {
            row[..3].copy_from_slice(shared);
        }
        ata[3] = extra;
        let aty = [quadratic.1[0], quadratic.1[1], quadratic.1[2], extra_y];
        if let Some((coef, ssr)) = solve_normal(&ata, &aty, quadratic.2) {
            if best.as_ref().is_none_or(|b| ssr < b.1) {
                best = Some((coef, ssr, Some(c)));
            }
        }
    }
    let residual: Vec<f64> = match &best {
        Some((coef, _, c)) => (0..m)
            .map(|i| {
                let s = speed[i];
                let mut fit = coef[0] + coef[1] * s + coef[2] * s * s;
                if let Some(c) = c {
                    fit += coef[3] / (1.0 + c * s);
                }
                y(i) - fit
            })
            .collect(),
        None => (0..m).map(y).collect(),
    };
    let (r_mean, r2, _, _) = moments(&residual);
    let (residual_skewness, residual_tail_weight) = quantile_shape(&residual);
    let residual_std = (r2 * m as f64 / (m - 1) as f64).sqrt();

    // Slip phases: runs of consecutive slipping samples moving the same way.
    let mut phase = vec![0usize; m];
    for j in 1..m {
        let same = idx[j] == idx[j - 1] + 1 && v[idx[j]].signum() == v[idx[j - 1]].signum();
        phase[j] = if same { phase[j - 1] } else { phase[j - 1] + 1 };
    }
    let autocorr = |lag: usize| -> Option<f64> {
        if negligible(r2, mu_mean) {
            return None;
        }
        let (mut sum, mut pairs) = (0.0, 0usize);
        for j in 0..m.saturating_sub(lag) {
            if phase[j + lag] == phase[j] {
                sum += (residual[j] - r_mean) * (residual[j + lag] - r_mean);
                pairs += 1;
            }
        }
        (pairs >= MIN_PAIRS).then(|| sum / pairs as f64 / r2)
    };

    // Trend: the residual's least-squares slope against time, over the
    // mean μ (the law's fit has a constant, so the residual's own mean is
    // about zero and leaves the slope alone).
    let trend_per_s = {
        let t_mean = idx.iter().map(|&i| t[i]).sum::<f64>() / m as f64;
        let (mut sty, mut stt) = (0.0, 0.0);
        for (j, &i) in idx.iter().enumerate() {
            let dt = t[i] - t_mean;
            sty += dt * (residual[j] - r_mean);
            stt += dt * dt;
        }
        (stt > 0.0 && mu_mean > 0.0 && !negligible(r2, mu_mean)).then(|| sty / stt / mu_mean)
    };

    // Hysteresis: accelerating minus decelerating residual within |v| bins.
    let mut bins = [(0.0, 0usize, 0.0, 0usize); HYSTERESIS_BINS];
    for (j, &i) in idx.iter().enumerate() {
        if i == 0 || i + 1 >= n || !v[i - 1].is_finite() || !v[i + 1].is_finite() {
            continue;
        }
        let dv = v[i + 1] - v[i - 1];
        let b = ((speed[j] - SLIP_SPEED_FRACTION) / (1.0 - SLIP_SPEED_FRACTION) * HYSTERESIS_BINS as f64) as usize;
        let bin = &mut bins[b.min(HYSTERESIS_BINS - 1)];
        if v[i] * dv > 0.0 {
            bin.0 += residual[j];
            bin.1 += 1;
        } else if v[i] * dv < 0.0 {
            bin.2 += residual[j];
            bin.3 += 1;
        }
    }
    let (mut weighted, mut weights) = (0.0, 0.0);
    for &(acc_sum, n_acc, dec_sum, n_dec) in &bins {
        if n_acc >= HYSTERESIS_MIN_PER_SIDE && n_dec >= HYSTERESIS_MIN_PER_SIDE {
            let (a, d) = (n_acc as f64, n_dec as f64);
            let w = a * d / (a + d);
            weighted += w * (acc_sum / a - dec_sum / d);
            weights += w;
        }
    }
    let hysteresis = (weights > 0.0).then(|| weighted / weights);

    // Breakaway: the largest |F|/N over the end of each stick phase followed by motion.
    let stuck = |i: usize| v[i].is_finite() && v[i].abs() <= STICK_SPEED_FRACTION * v_max;
    let mut ratios = Vec::new();
    let mut start = 0;
    while start < n {
        if !stuck(start) {
            start += 1;
            continue;
        }
        let mut end = start;
        while end < n && stuck(end) {
            end += 1;
        }
        if end - start >= MIN_STICK_SAMPLES && end < n {
            let ratio = (end.saturating_sub(BREAKAWAY_SAMPLES).max(start)..end)
                .filter(|&i| usable(i))
                .map(|i| force[i].abs() / normal[i])
                .fold(f64::NEG_INFINITY, f64::max);
            if ratio.is_finite() {
                ratios.push(ratio);
            }
        }
        start = end;
    }
    let breakaway_mean = (!ratios.is_empty()).then(|| ratios.iter().sum::<f64>() / ratios.len() as f64);
    let low: Vec<f64> = speed.iter().zip(&mu).filter(|(s, _)| **s < LOW_SPEED_FRACTION).map(|(_, m)| *m).collect();
    let low_speed_mu_mean = (!low.is_empty()).then(|| low.iter().sum::<f64>() / low.len() as f64);
    let stiction_excess = breakaway_mean.zip(low_speed_mu_mean).map(|(b, l)| b - l);

    Some(FrictionFeatures {
        slip_samples: m,
        mu_mean,
        residual_std,
        residual_skewness,
        residual_tail_weight,
        residual_autocorr_lag1: autocorr(1),
        residual_autocorr_lag10: autocorr(10),
        trend_per_s,
        hysteresis,
        breakaway_mean,
        low_speed_mu_mean,
        stiction_excess,
    })
}
}

/// The ratio (q97.5 − q2.5) / (q75 − q25) of a Gaussian: 3.919 93 / 1.348 98.
pub(crate) const GAUSSIAN_TAIL_RATIO: f64 = 2.905_847_5;

/// Kelly's quantile skewness (q90 + q10 − 2 q50) / (q90 − q10), in [−1, 1],
/// and the excess tail weight (q97.5 − q2.5) / (q75 − q25) / that of a
/// Gaussian − 1 (0 for a Gaussian, above for heavier tails, below for
/// lighter ones) of `values` (0, 0 where they do not spread). Quantiles, not
/// moments: the sampling spread of a third or fourth moment grows with the
/// sixth or eighth, which heavy-tailed friction noise may not have, so a
/// model with heavy tails would predict its own moments with a spread so
/// wide that no record could tell it from a Gaussian one; quantile shapes
/// have a bounded spread whatever the tails.
pub(super) fn quantile_shape(values: &[f64]) -> (f64, f64) {
    if values.len() < 8 {
        return (0.0, 0.0);
    }
    let mut v = values.to_vec();
    let n = v.len();
    let rank = |p: f64| ((p * (n - 1) as f64).round() as usize).min(n - 1);
    // The median first, then each quantile within the part the last one
    // left on its side (the ranks are monotone in p): the same order
    // statistics as a selection over all values each, in a fraction of
    // the passes.
    let mid = rank(0.5);
    let q50 = *v.select_nth_unstable_by(mid, f64::total_cmp).1;
    let mut below = |bound: &mut usize, p: f64| {
        let k = rank(p);
        if k < *bound {
            v[..*bound].select_nth_unstable_by(k, f64::total_cmp);
            *bound = k;
        }
        v[*bound]
    };
    let mut bound = mid;
    let [q25, q10, q025] = [0.25, 0.1, 0.025].map(|p| below(&mut bound, p));
    let mut above = |bound: &mut usize, p: f64| {
        let k = rank(p);
        if k > *bound {
            v[*bound + 1..].select_nth_unstable_by(k - *bound - 1, f64::total_cmp);
            *bound = k;
        }
        v[*bound]
    };
    let mut bound = mid;
    let [q75, q90, q975] = [0.75, 0.9, 0.975].map(|p| above(&mut bound, p));
    let (wide, mid) = (q90 - q10, q75 - q25);
    let skewness = if wide > 0.0 { (q90 + q10 - 2.0 * q50) / wide } else { 0.0 };
    let tail = if mid > 0.0 { (q975 - q025) / mid / GAUSSIAN_TAIL_RATIO - 1.0 } else { 0.0 };
    (skewness, tail)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The quantiles selected side by side are those of a full sort, bit
    /// for bit, with ties and at the smallest sizes.
    #[test]
    fn quantile_shape_is_that_of_sorted_values() {
        let by_sort = |values: &[f64]| {
            let mut sorted = values.to_vec();
            sorted.sort_unstable_by(f64::total_cmp);
            let n = sorted.len();
            let q = |p: f64| sorted[((p * (n - 1) as f64).round() as usize).min(n - 1)];
            let (wide, mid) = (q(0.9) - q(0.1), q(0.75) - q(0.25));
            let skewness = if wide > 0.0 { (q(0.9) + q(0.1) - 2.0 * q(0.5)) / wide } else { 0.0 };
            let tail = if mid > 0.0 { (q(0.975) - q(0.025)) / mid / GAUSSIAN_TAIL_RATIO - 1.0 } else { 0.0 };
            (skewness, tail)
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(0x2545_F491_4F6C_DD1D);
        for n in [8, 9, 10, 17, 40, 101, 1000, 4097] {
            for ties in [false, true] {
                let values: Vec<f64> = (0..n)
                    .map(|_| {
                        let u = rng.random::<f64>();
                        let x = (u - 0.3).powi(3);
                        if ties { (x * 20.0).round() } else { x }
                    })
                    .collect();
                let (a, b) = (quantile_shape(&values), by_sort(&values));
                assert_eq!((a.0.to_bits(), a.1.to_bits()), (b.0.to_bits(), b.1.to_bits()), "n {n}, ties {ties}");
            }
        }
    }
}
