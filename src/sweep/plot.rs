//! Pictures of a sweep: Figure 9(a) mean peak with its 5–95% band, Figure
//! 9(b) peak variance, a phase panel (fig9c), and Figure 8-style peak densities with the Gaussian of
//! the same mean and variance. Each is written as PNG and SVG, atomically.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::engine::reduce::HISTOGRAM_BINS;
use crate::engine::{Condition, PointAccumulator};
use crate::error::Result;
use crate::figure::{FONT, colour, legend_box, plot_error, render};
use crate::sweep::SweepResult;

/// Normal forces of the grid in order, and per force its points sorted by frequency.
fn curves(result: &SweepResult) -> Vec<(f64, Vec<(Condition, &PointAccumulator)>)> {
    let mut forces: Vec<f64> = result.conditions.iter().map(|c| c.normal_force_n).collect();
    forces.sort_by(f64::total_cmp);
    forces.dedup();
    forces
        .into_iter()
        .map(|n| {
            let mut pts: Vec<(Condition, &PointAccumulator)> = result
                .conditions
                .iter()
                .zip(&result.accumulators)
                .filter(|(c, _)| c.normal_force_n == n)
                .map(|(c, a)| (*c, a))
                .collect();
            pts.sort_by(|a, b| a.0.excitation_frequency_hz.total_cmp(&b.0.excitation_frequency_hz));
            (n, pts)
        })
        .collect()
}

fn finite(p: (f64, f64)) -> bool {
    p.0.is_finite() && p.1.is_finite()
}

fn frequency_span(result: &SweepResult) -> (f64, f64) {
    let (lo, hi) = result.conditions.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
        (lo.min(c.excitation_frequency_hz), hi.max(c.excitation_frequency_hz))
    });
    if hi > lo { (lo, hi) } else { (lo - 0.5, hi + 0.5) }
}

fn figure9a<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, result: &SweepResult, title: &str) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9a", e);
    let series = curves(result);
    let rows = result.rows();
    // Only finite statistics set the axes (plotters spins on non-finite ranges).
    let y_max =
        rows.iter().map(|r| r.peak_p95_m.max(r.peak_mean_m)).filter(|v| v.is_finite()).fold(0.0, f64::max) * 1e3 * 1.08;
    let y_min = rows
        .iter()
        .map(|r| r.peak_p05_m.min(r.peak_mean_m))
        .filter(|v| v.is_finite())
        .fold(f64::INFINITY, f64::min)
        .min(0.0)
        * 1e3;
    let (f_lo, f_hi) = frequency_span(result);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 22))
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(68)
        .build_cartesian_2d(f_lo..f_hi, y_min..y_max.max(1e-6))
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("excitation frequency (Hz)")
        .y_desc("peak amplitude (mm)")
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(e)?;
    for (i, (n, pts)) in series.iter().enumerate() {
        let c = colour(i);
        let band: Vec<(f64, f64)> = pts
            .iter()
            .map(|(cond, a)| (cond.excitation_frequency_hz, a.quantile(0.95) * 1e3))
            .chain(pts.iter().rev().map(|(cond, a)| (cond.excitation_frequency_hz, a.quantile(0.05) * 1e3)))
            .filter(|p| finite(*p))
            .collect();
        chart.draw_series(std::iter::once(Polygon::new(band, c.mix(0.18).filled()))).map_err(e)?;
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|(cond, a)| (cond.excitation_frequency_hz, a.moments().0 * 1e3)).filter(|p| finite(*p)),
                c.stroke_width(2),
            ))
            .map_err(e)?
            .label(format!("N0 = {n} N"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
    }
    legend_box(&mut chart, 15, SeriesLabelPosition::UpperRight, "fig9")
}

fn figure9b<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, result: &SweepResult, title: &str) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9b", e);
    let series = curves(result);
    let vars: Vec<f64> =
        result.accumulators.iter().map(|a| a.moments().1 * 1e6).filter(|v| v.is_finite() && *v > 0.0).collect();
    let v_max = vars.iter().copied().fold(1e-12, f64::max) * 2.0;
    let v_min = vars.iter().copied().fold(f64::INFINITY, f64::min).min(v_max / 10.0) / 2.0;
    let (f_lo, f_hi) = frequency_span(result);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 22))
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d(f_lo..f_hi, (v_min..v_max).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("excitation frequency (Hz)")
        .y_desc("peak variance (mm²)")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(e)?;
    for (i, (n, pts)) in series.iter().enumerate() {
        let c = colour(i);
        let line: Vec<(f64, f64)> = pts
            .iter()
            .map(|(cond, a)| (cond.excitation_frequency_hz, a.moments().1 * 1e6))
            .filter(|p| finite(*p) && p.1 > 0.0)
            .collect();
        chart
            .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
            .map_err(e)?
            .label(format!("N0 = {n} N"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
        chart.draw_series(line.into_iter().map(|p| Circle::new(p, 3, c.filled()))).map_err(e)?;
    }
    legend_box(&mut chart, 15, SeriesLabelPosition::UpperRight, "fig9")
}

/// Figure 9's phase panel: the circular mean phase lag of the response's
/// fundamental (degrees) against frequency, one curve per normal force, with
/// a band of ± one circular standard deviation.
fn figure9c<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, result: &SweepResult, title: &str) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9c", e);
    let series = curves(result);
    let (f_lo, f_hi) = frequency_span(result);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 22))
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(68)
        .build_cartesian_2d(f_lo..f_hi, -10.0..190.0)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("excitation frequency (Hz)")
        .y_desc("phase lag behind the base (degrees)")
        .y_labels(11)
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(e)?;
    // Lags are drawn in [0°, 360°) so curves above resonance do not jump.
    let lag = |a: &PointAccumulator| {
        let (mean, var) = a.phase_moments();
        (mean.to_degrees().rem_euclid(360.0), var.max(0.0).sqrt().to_degrees())
    };
    for (i, (n, pts)) in series.iter().enumerate() {
        let c = colour(i);
        let band: Vec<(f64, f64)> = pts
            .iter()
            .map(|(cond, a)| (cond.excitation_frequency_hz, lag(a).0 + lag(a).1))
            .chain(pts.iter().rev().map(|(cond, a)| (cond.excitation_frequency_hz, lag(a).0 - lag(a).1)))
            .filter(|p| finite(*p))
            .collect();
        chart.draw_series(std::iter::once(Polygon::new(band, c.mix(0.18).filled()))).map_err(e)?;
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|(cond, a)| (cond.excitation_frequency_hz, lag(a).0)).filter(|p| finite(*p)),
                c.stroke_width(2),
            ))
            .map_err(e)?
            .label(format!("N0 = {n} N"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
    }
    legend_box(&mut chart, 15, SeriesLabelPosition::LowerRight, "fig9c")
}

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

fn figure8<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    points: &[(Condition, &PointAccumulator)],
    title: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig8", e);
    let root = root.titled(title, (FONT, 22)).map_err(e)?;
    let cols = points.len().clamp(1, 2);
    let rows = points.len().div_ceil(cols).max(1);
    let panels = root.split_evenly((rows, cols));
    for ((cond, a), panel) in points.iter().zip(panels) {
        let (bars, lo, hi) = density_bars(a, 40);
        let (lo, hi) = if lo.is_finite() && hi.is_finite() && lo < hi { (lo, hi) } else { (0.0, 1.0) };
        let (mean, var) = a.moments();
        let (mean_mm, sd_mm) = (mean * 1e3, var.max(0.0).sqrt() * 1e3);
        let gauss = |x: f64| {
            if sd_mm > 0.0 && sd_mm.is_finite() && mean_mm.is_finite() {
                (-(x - mean_mm).powi(2) / (2.0 * sd_mm * sd_mm)).exp() / (sd_mm * (std::f64::consts::TAU).sqrt())
            } else {
                0.0
            }
        };
        let top = bars.iter().map(|b| b.2).filter(|d| d.is_finite()).fold(gauss(mean_mm), f64::max) * 1.15;
        let mut chart = ChartBuilder::on(&panel)
            .caption(
                format!(
                    "{} Hz, N0 = {} N: mean {:.4} mm, var {:.3e} mm²",
                    cond.excitation_frequency_hz,
                    cond.normal_force_n,
                    mean_mm,
                    var * 1e6
                ),
                (FONT, 15),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d(lo..hi.max(lo + 1e-9), 0.0..top.max(1e-9))
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("peak amplitude (mm)")
            .y_desc("probability density (1/mm)")
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 14))
            .x_labels(6)
            .draw()
            .map_err(e)?;
        chart
            .draw_series(
                bars.iter().map(|&(x0, x1, d)| Rectangle::new([(x0, 0.0), (x1, d)], colour(0).mix(0.55).filled())),
            )
            .map_err(e)?
            .label("simulated peaks")
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], colour(0).mix(0.55).filled()));
        let curve: Vec<(f64, f64)> =
            (0..=200).map(|i| lo + (hi - lo) * f64::from(i) / 200.0).map(|x| (x, gauss(x))).collect();
        chart
            .draw_series(LineSeries::new(curve, BLACK.stroke_width(2)))
            .map_err(e)?
            .label("Gaussian, same mean and variance")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
        legend_box(&mut chart, 12, SeriesLabelPosition::UpperLeft, "fig8")?;
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

/// Writes fig9a, fig9b and fig8 (PNG + SVG) into `dir`; returns the files.
pub fn write_sweep_plots(dir: &Path, result: &SweepResult, figure8_frequency_hz: f64) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let title_a = "Mean peak amplitude, band: 5–95% of peaks";
    files.extend(render(dir, "fig9a", (1000, 650), &|r| figure9a(r, result, title_a), &|r| {
        figure9a(r, result, title_a)
    })?);
    let title_b = "Peak-amplitude variance";
    files.extend(render(dir, "fig9b", (1000, 650), &|r| figure9b(r, result, title_b), &|r| {
        figure9b(r, result, title_b)
    })?);
    let title_c = "Phase lag of the response's fundamental, band: ± 1 sd";
    files.extend(render(dir, "fig9c", (1000, 650), &|r| figure9c(r, result, title_c), &|r| {
        figure9c(r, result, title_c)
    })?);
    let pts = figure8_points(result, figure8_frequency_hz);
    let rows = pts.len().div_ceil(2).max(1) as u32;
    let title_8 = "Probability density of the peak amplitude";
    files.extend(render(dir, "fig8", (1100, 60 + 380 * rows), &|r| figure8(r, &pts, title_8), &|r| {
        figure8(r, &pts, title_8)
    })?);
    Ok(files)
}
