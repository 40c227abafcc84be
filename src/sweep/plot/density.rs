//! Figure 8: the peak densities of every normal force at one frequency, with
//! the Gaussian of the same mean and variance and the measured densities.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::PlotOptions;
use crate::engine::reduce::HISTOGRAM_BINS;
use crate::engine::{Condition, PointAccumulator};
use crate::error::Result;
use crate::figure::{FONT, LEGEND_ICON, Look, caption_below, caption_px, colour, legend_box, plot_error, tick};
use crate::sweep::SweepResult;

/// Density bars (mm, 1/mm) over about `mean ± 4σ`. Each bar is a whole
/// number of the histogram's bins, aligned to its edges (no aliasing).
fn density_bars(a: &PointAccumulator, target_bars: usize) -> (Vec<(f64, f64, f64)>, f64, f64) {
    let (mean, var) = a.moments();
    let fine = (a.range.hi_m - a.range.lo_m) / f64::from(HISTOGRAM_BINS - 2);
    let inner = HISTOGRAM_BINS - 2;
    if !(mean.is_finite() && var.is_finite() && fine.is_finite() && fine > 0.0) {
        // Nothing to draw (a result with such statistics is refused before plotting).
        return (Vec::new(), a.range.lo_m * 1e3, a.range.hi_m * 1e3);
    }
    let sd = var.max(0.0).sqrt().max(fine);
    let per_bar = ((8.0 * sd / target_bars as f64) / fine).round().clamp(1.0, f64::from(inner)) as u32;
    let first =
        (((mean - 4.0 * sd - a.range.lo_m) / fine).floor().clamp(0.0, f64::from(inner)) as u32 / per_bar) * per_bar;
    let last = ((mean + 4.0 * sd - a.range.lo_m) / fine).ceil().clamp(0.0, f64::from(inner)) as u32;
    let total = a.peaks.max(1) as f64;
    let mut bars = Vec::new();
    let mut start = first;
    // Each step advances by at least one bin and stops at `inner`: the loop ends.
    while start < last {
        let end = start.saturating_add(per_bar).min(inner);
        let count: u64 = (start..end).map(|i| a.histogram[(i + 1) as usize]).sum();
        let x0 = a.range.lo_m + f64::from(start) * fine;
        let x1 = a.range.lo_m + f64::from(end) * fine;
        bars.push((x0 * 1e3, x1 * 1e3, count as f64 / (total * (x1 - x0) * 1e3)));
        start = end;
    }
    let lo = a.range.lo_m + f64::from(first) * fine;
    let hi = a.range.lo_m + f64::from(start.max(first + 1)) * fine;
    (bars, lo * 1e3, hi * 1e3)
}

/// The normal density of `mean` and `sd` at `x` (0 for no spread).
fn gaussian(x: f64, mean: f64, sd: f64) -> f64 {
    if sd > 0.0 && sd.is_finite() && mean.is_finite() {
        (-(x - mean).powi(2) / (2.0 * sd * sd)).exp() / (sd * (std::f64::consts::TAU).sqrt())
    } else {
        0.0
    }
}

/// Density outline (mm, 1/mm) of measured peaks: `bins` equal bins over [lo, hi].
fn measured_density(peaks_m: &[f64], lo: f64, hi: f64, bins: usize) -> Vec<(f64, f64)> {
    if peaks_m.len() < 2 || hi <= lo {
        return Vec::new();
    }
    let width = (hi - lo) / bins as f64;
    let mut counts = vec![0u64; bins];
    for &p in peaks_m {
        let x = p * 1e3;
        if x >= lo && x < hi {
            counts[(((x - lo) / width) as usize).min(bins - 1)] += 1;
        }
    }
    let n = peaks_m.len() as f64;
    let mut outline = vec![(lo, 0.0)];
    for (i, c) in counts.iter().enumerate() {
        let d = *c as f64 / (n * width);
        let x0 = lo + i as f64 * width;
        outline.push((x0, d));
        outline.push((x0 + width, d));
    }
    outline.push((hi, 0.0));
    outline
}

/// Figure 8's caption.
pub(super) fn figure8_caption(points: &[(Condition, &PointAccumulator)], opts: &PlotOptions) -> String {
    let frequency =
        points.first().map_or(String::new(), |(c, _)| format!(" at {} Hz", tick(c.excitation_frequency_hz)));
    let with_measured = points.iter().any(|(c, _)| opts.measured.iter().any(|m| m.matches(c)));
    let mut caption = format!(
        "Figure 8. Probability density of the peak amplitude{frequency}, one panel per normal force N0: bars, the \
         histogram of the simulated peaks; black line, the Gaussian of their mean and variance."
    );
    if with_measured {
        caption.push_str(&format!(
            " Red, {}: dashed, the Gaussian of the measured mean and variance; dot, the measured mean ± standard \
             error (a solid outline: the measured peaks, where the set has records). Measured conditions are drawn \
             only in the panel of their own normal force.",
            opts.measured_label
        ));
    }
    caption
}

pub(super) fn figure8<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    points: &[(Condition, &PointAccumulator)],
    opts: &PlotOptions,
    look: Look,
    caption: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig8", e);
    let root = caption_below(&root, caption, look, "fig8")?;
    let cols = points.len().clamp(1, 2);
    let rows = points.len().div_ceil(cols).max(1);
    let panels = root.split_evenly((rows, cols));
    for ((cond, a), panel) in points.iter().zip(panels) {
        let measured = opts.measured.iter().find(|m| m.matches(cond));
        let (bars, lo, hi) = density_bars(a, 40);
        let (mut lo, mut hi) = if lo.is_finite() && hi.is_finite() && lo < hi { (lo, hi) } else { (0.0, 1.0) };
        let (mean, var) = a.moments();
        let (mean_mm, sd_mm) = (mean * 1e3, var.max(0.0).sqrt() * 1e3);
        let m_stats = measured.map(|m| {
            (m.peak_mean_m * 1e3, m.peak_var_m2.map(|v| v.max(0.0).sqrt() * 1e3), m.mean_standard_error_m() * 1e3)
        });
        if let Some((mm, msd, _)) = m_stats {
            let reach = 4.0 * msd.unwrap_or(0.0);
            lo = lo.min(mm - reach.max(1e-6));
            hi = hi.max(mm + reach.max(1e-6));
        }
        let m_density = measured.map(|m| measured_density(&m.peaks_m, lo, hi, 30)).unwrap_or_default();
        let top = bars
            .iter()
            .map(|b| b.2)
            .chain(m_density.iter().map(|p| p.1))
            .chain(m_stats.and_then(|(mm, msd, _)| msd.map(|s| gaussian(mm, mm, s))))
            .filter(|d| d.is_finite())
            .fold(gaussian(mean_mm, mean_mm, sd_mm), f64::max)
            * 1.75;
        let caption = match m_stats {
            Some((mm, _, se)) => format!(
                "{} Hz, N0 = {} N: simulated {:.3} mm, measured {:.3} ± {:.3} mm",
                tick(cond.excitation_frequency_hz),
                tick(cond.normal_force_n),
                mean_mm,
                mm,
                se
            ),
            None => format!(
                "{} Hz, N0 = {} N: mean {:.3} mm, sd {:.3} mm",
                tick(cond.excitation_frequency_hz),
                tick(cond.normal_force_n),
                mean_mm,
                sd_mm
            ),
        };
        let panel_width = panel.dim_in_pixel().0;
        let mut chart = ChartBuilder::on(&panel)
            .caption(&caption, (FONT, caption_px(look, &caption, 15, panel_width)))
            .margin(look.px(10))
            .x_label_area_size(look.px(44))
            .y_label_area_size(look.px(60))
            .build_cartesian_2d(lo..hi.max(lo + 1e-9), 0.0..top.max(1e-9))
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("peak amplitude (mm)")
            .y_desc("probability density (1/mm)")
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style((FONT, look.px(13)))
            .axis_desc_style((FONT, look.px(14)))
            .x_labels(6)
            .y_labels(6)
            .draw()
            .map_err(e)?;
        chart
            .draw_series(
                bars.iter().map(|&(x0, x1, d)| Rectangle::new([(x0, 0.0), (x1, d)], colour(0).mix(0.55).filled())),
            )
            .map_err(e)?
            .label("simulated peaks")
            .legend(move |(x, y)| {
                Rectangle::new(
                    [(x, y - look.signed(5)), (x + LEGEND_ICON, y + look.signed(5))],
                    colour(0).mix(0.55).filled(),
                )
            });
        let curve: Vec<(f64, f64)> = (0..=200)
            .map(|i| lo + (hi - lo) * f64::from(i) / 200.0)
            .map(|x| (x, gaussian(x, mean_mm, sd_mm)))
            .collect();
        chart
            .draw_series(LineSeries::new(curve, BLACK.stroke_width(look.px(2))))
            .map_err(e)?
            .label("Gaussian, simulated mean and variance")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + LEGEND_ICON, y)], BLACK.stroke_width(look.px(2))));
        if let Some((mm, msd, se)) = m_stats {
            let red = colour(1);
            if !m_density.is_empty() {
                chart
                    .draw_series(LineSeries::new(m_density.clone(), red.stroke_width(look.px(2))))
                    .map_err(e)?
                    .label(format!("{}: peaks", opts.measured_label))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + LEGEND_ICON, y)], red.stroke_width(look.px(2)))
                    });
            }
            if let Some(msd) = msd {
                let curve: Vec<(f64, f64)> = (0..=200)
                    .map(|i| lo + (hi - lo) * f64::from(i) / 200.0)
                    .map(|x| (x, gaussian(x, mm, msd)))
                    .collect();
                chart
                    .draw_series(DashedLineSeries::new(curve, look.px(8), look.px(5), red.stroke_width(look.px(2))))
                    .map_err(e)?
                    .label(format!("{}: Gaussian, measured mean and variance", opts.measured_label))
                    .legend(move |(x, y)| {
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(0, 0), (8, 0)], red.stroke_width(look.px(2)))
                            + PathElement::new(vec![(12, 0), (LEGEND_ICON, 0)], red.stroke_width(look.px(2)))
                    });
            }
            // The measured mean with its standard error, just above the curves.
            let y = top / 1.75 * 1.08;
            chart
                .draw_series(std::iter::once(ErrorBar::new_horizontal(
                    y,
                    mm - se,
                    mm,
                    mm + se,
                    red.stroke_width(look.px(2)),
                    look.px(10),
                )))
                .map_err(e)?;
            chart
                .draw_series(std::iter::once(Circle::new((mm, y), look.px(5), red.filled())))
                .map_err(e)?
                .label(format!("{}: mean ± s.e.", opts.measured_label))
                .legend(move |(x, y)| Circle::new((x + LEGEND_ICON / 2, y), look.px(5).min(8), red.filled()));
        }
        legend_box(&mut chart, look.px(12), SeriesLabelPosition::UpperLeft, "fig8")?;
    }
    Ok(())
}

/// The points drawn in Figure 8: at the grid frequency nearest to
/// `frequency_hz`, every normal force.
pub fn figure8_points(result: &SweepResult, frequency_hz: f64) -> Vec<(Condition, &PointAccumulator)> {
    let nearest = result
        .conditions
        .iter()
        .map(|c| c.excitation_frequency_hz)
        .min_by(|a, b| (a - frequency_hz).abs().total_cmp(&(b - frequency_hz).abs()));
    let mut pts: Vec<(Condition, &PointAccumulator)> = result
        .conditions
        .iter()
        .zip(&result.accumulators)
        .filter(|(c, _)| Some(c.excitation_frequency_hz) == nearest)
        .map(|(c, a)| (*c, a))
        .collect();
    pts.sort_by(|a, b| a.0.normal_force_n.total_cmp(&b.0.normal_force_n));
    pts
}
