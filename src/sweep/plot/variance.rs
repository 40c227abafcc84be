//! Figure 9(b): the peak variance on a log axis, with 95% intervals on the
//! simulated and the measured variances.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::measured::{MeasuredPoint, pair};
use super::panel::{
    Axis, Layout, MeasuredMark, SimPoint, SimSeries, Spread, draw_measured, draw_minor, draw_simulated, frequency_axis,
    frequency_span, labels_fit, pairing_note,
};
use super::{PlotOptions, curves, loads};
use crate::engine::PointAccumulator;
use crate::error::Result;
use crate::figure::{FONT, Look, caption_below, colour, decade_range, legend_box, plot_error, tick};
use crate::sweep::SweepResult;

/// The 95% interval of a variance `s2` estimated from `n` values with excess
/// kurtosis `kurtosis`: a chi-square interval with the effective degrees of
/// freedom ν = 2 / (2/(n−1) + κ/n) (exactly n − 1 for normal values; fewer
/// for heavy tails), never more than n − 1. It assumes independent values.
pub fn variance_interval(s2: f64, n: u64, kurtosis: f64) -> Option<(f64, f64)> {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    if n < 2 || !(s2.is_finite() && s2 >= 0.0) {
        return None;
    }
    let n = n as f64;
    let spread = 2.0 / (n - 1.0) + if kurtosis.is_finite() { kurtosis / n } else { 0.0 };
    let nu = (2.0 / spread.max(2.0 / (n - 1.0) * 1e-3)).min(n - 1.0).max(1.0);
    let chi = ChiSquared::new(nu).ok()?;
    let (lo_q, hi_q) = (chi.inverse_cdf(0.025), chi.inverse_cdf(0.975));
    Some((s2 * nu / hi_q, s2 * nu / lo_q))
}

/// The excess kurtosis of a point's peaks, from its histogram's inner bins
/// (the under- and overflow bins are left out).
fn histogram_kurtosis(a: &PointAccumulator) -> f64 {
    let last = a.histogram.len().saturating_sub(1);
    let centres: Vec<(f64, f64)> = (1..last)
        .filter(|&b| a.histogram[b] > 0)
        .map(|b| {
            let (lo, hi) = a.range.bin_edges(b as u32);
            (0.5 * (lo + hi), a.histogram[b] as f64)
        })
        .collect();
    let n: f64 = centres.iter().map(|c| c.1).sum();
    if n < 4.0 {
        return 0.0;
    }
    let mean = centres.iter().map(|(x, c)| x * c).sum::<f64>() / n;
    let m2 = centres.iter().map(|(x, c)| (x - mean).powi(2) * c).sum::<f64>() / n;
    let m4 = centres.iter().map(|(x, c)| (x - mean).powi(4) * c).sum::<f64>() / n;
    if m2 > 0.0 { m4 / (m2 * m2) - 3.0 } else { 0.0 }
}

/// Figure 9(b)'s caption.
pub(super) fn figure9b_caption(result: &SweepResult, opts: &PlotOptions) -> String {
    let layout = Layout::new(result);
    let what = match layout.single {
        Some(f) => format!("at {} Hz, one colour per normal force N0, the normal forces side by side", tick(f)),
        None => "against excitation frequency, one colour per normal force N0".to_string(),
    };
    format!(
        "Figure 9(b). Variance of the peak amplitude {what}, on a logarithmic axis. Error bars on the simulated \
         points: 95% chi-square intervals from the point's peaks, with degrees of freedom reduced for heavy tails \
         (from the kurtosis of its histogram); they assume \
         independent peaks, and successive peaks of one realisation are correlated, most near resonance, so they \
         understate the uncertainty there.{}",
        pairing_note(
            result,
            opts.measured,
            &format!("{}: variance with its 95% chi-square interval", opts.measured_label)
        )
    )
}

/// Figure 9(b): the peak variance on a log axis from decade to decade, each
/// decade labelled 10ⁿ, with 95% intervals on the simulated and the measured
/// variances. The caption is set below the plot.
pub(super) fn figure9b<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    caption: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9b", e);
    let layout = Layout::new(result);
    let interval = |a: &PointAccumulator| {
        let (_, v) = a.moments();
        variance_interval(v, a.peaks, histogram_kurtosis(a)).unwrap_or((v, v))
    };
    let measured_interval =
        |m: &MeasuredPoint| m.peak_var_m2.and_then(|v| m.n_peaks.and_then(|n| variance_interval(v, n, 0.0)));
    let vars: Vec<f64> = result
        .accumulators
        .iter()
        .flat_map(|a| {
            let (lo, hi) = interval(a);
            [a.moments().1, lo, hi]
        })
        .chain(opts.measured.iter().filter_map(|m| m.peak_var_m2))
        .chain(opts.measured.iter().filter_map(measured_interval).flat_map(|(lo, hi)| [lo, hi]))
        .map(|v| v * 1e6)
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let v_max = vars.iter().copied().fold(1e-12, f64::max);
    let v_min = vars.iter().copied().fold(f64::INFINITY, f64::min).min(v_max);
    let (v_lo, v_hi) = decade_range(v_min, v_max);
    let axis = Axis::Log { lo: v_lo.log10().round(), hi: v_hi.log10().round(), powers: true };
    let Axis::Log { lo: y_lo, hi: y_hi, .. } = axis else { unreachable!() };
    let x = frequency_span(result, opts.measured);
    let plot = caption_below(&root, caption, look, "fig9b")?;
    let mut chart = ChartBuilder::on(&plot)
        .margin(look.px(14))
        .x_label_area_size(look.px(52))
        .y_label_area_size(look.px(72))
        .build_cartesian_2d(x.0..x.1, y_lo..y_hi)
        .map_err(e)?;
    let (x_desc, x_fmt) = frequency_axis(layout);
    let y_fmt = |v: &f64| axis.label(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc("peak variance (mm²)")
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .y_labels((y_hi - y_lo) as usize + 1)
        .x_labels(11)
        .light_line_style(TRANSPARENT)
        .label_style((FONT, look.px(15)))
        .axis_desc_style((FONT, look.px(17)));
    if layout.single.is_some() {
        mesh.disable_x_mesh().x_labels(0);
    }
    mesh.draw().map_err(e)?;
    draw_minor(&mut chart, axis, x, look, "fig9b")?;
    let ymap = |v: f64| axis.map(v * 1e6);
    let series: Vec<SimSeries> = curves(result)
        .iter()
        .enumerate()
        .map(|(i, (n, pts))| SimSeries {
            force_n: *n,
            colour: colour(i),
            points: pts
                .iter()
                .filter(|(_, a)| a.moments().1 > 0.0)
                .map(|(c, a)| {
                    let (lo, hi) = interval(a);
                    SimPoint {
                        x: layout.simulated(i, c.excitation_frequency_hz),
                        y: ymap(a.moments().1),
                        lo: ymap(lo),
                        hi: ymap(hi),
                    }
                })
                .collect(),
        })
        .collect();
    draw_simulated(&mut chart, &series, Spread::Bars, layout, look, "fig9b")?;
    let forces = loads(result);
    let labels = labels_fit(layout, opts.measured);
    let measured: Vec<MeasuredMark> = opts
        .measured
        .iter()
        .filter_map(|m| {
            let v = m.peak_var_m2?;
            let (lo, hi) = measured_interval(m).unwrap_or((v, v));
            let paired = pair(&forces, m);
            let label = match paired {
                _ if !labels => String::new(),
                Some(p) if !p.same_load => {
                    format!("{} N (nearest simulated load {} N)", tick(m.normal_force_n), tick(p.force_n))
                }
                _ => format!("{} N", tick(m.normal_force_n)),
            };
            Some((
                layout.measured(paired.map(|p| p.curve), m.excitation_frequency_hz),
                ymap(v),
                ymap(lo),
                ymap(hi),
                paired.map_or(BLACK, |p| colour(p.curve)),
                label,
            ))
        })
        .collect();
    draw_measured(&mut chart, &measured, &format!("{}: variance, 95% interval", opts.measured_label), look, "fig9b")?;
    legend_box(&mut chart, look.px(15), SeriesLabelPosition::UpperRight, "fig9b")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_variance_intervals_are_chi_square_and_widen_with_tails() {
        // Normal values: n − 1 degrees of freedom; about ±3.5% at n = 6400.
        let (lo, hi) = variance_interval(1.0, 6400, 0.0).unwrap();
        assert!((0.96..0.97).contains(&lo) && (1.03..1.04).contains(&hi), "{lo} {hi}");
        // n = 350 (the paper's records): about −14% / +16%.
        let (lo, hi) = variance_interval(1.0, 350, 0.0).unwrap();
        assert!((0.85..0.88).contains(&lo) && (1.15..1.18).contains(&hi), "{lo} {hi}");
        // Heavy tails widen it; it never claims more than n − 1 degrees of freedom.
        let (lo_t, hi_t) = variance_interval(1.0, 350, 3.0).unwrap();
        assert!(lo_t < lo && hi_t > hi);
        assert_eq!(variance_interval(1.0, 350, -1.9), variance_interval(1.0, 350, 0.0).map(|_| (lo, hi)));
        assert!(variance_interval(1.0, 1, 0.0).is_none());
    }
}
