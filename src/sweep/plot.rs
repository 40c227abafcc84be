//! Pictures of a sweep: Figure 9(a) mean peak with its 5–95% band, Figure
//! 9(b) peak variance, a phase panel (fig9c), and Figure 8-style peak
//! densities with the Gaussian of the same mean and variance. Each is written
//! as PNG and SVG, atomically. Measured statistics (a measurement set's
//! summary rows, or the peaks of its records) can be drawn over them
//! ([`MeasuredPoint`]), at a size meant for a page ([`SizePreset`]).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::diagnose::measure::MeasurementSet;
use crate::engine::reduce::HISTOGRAM_BINS;
use crate::engine::{Condition, PointAccumulator};
use crate::error::Result;
use crate::figure::{FONT, colour, legend_box, plot_error, render};
use crate::sweep::SweepResult;

/// How large a figure is drawn, and how large its text is relative to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SizePreset {
    /// 1000 px wide, for a screen (the default).
    #[default]
    Screen,
    /// One journal column (3.5 in) at 300 dpi, text about 8 pt when printed at that width.
    Single,
    /// Two columns (7.2 in) at 300 dpi, text about 8 pt.
    Double,
    /// A 16:9 slide, 1920 × 1080, text large enough for the back of the room.
    Slide,
}

impl SizePreset {
    /// Width of a figure (px) and the factor applied to the screen layout's
    /// text, lines and margins.
    fn width_and_scale(self) -> (f64, f64) {
        match self {
            SizePreset::Screen => (1000.0, 1.0),
            SizePreset::Single => (1050.0, 2.1),
            SizePreset::Double => (2160.0, 2.2),
            SizePreset::Slide => (1920.0, 1.9),
        }
    }

    /// The look of a figure designed at `design` px on the screen.
    pub fn look(self, design: (u32, u32)) -> Look {
        let (w, scale) = self.width_and_scale();
        let aspect = match self {
            SizePreset::Slide => 1080.0 / 1920.0,
            _ => f64::from(design.1) / f64::from(design.0),
        };
        Look { size: (w.round() as u32, (w * aspect).round() as u32), scale }
    }
}

/// A figure's pixel size and the scale of its text, lines and margins.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    pub size: (u32, u32),
    pub scale: f64,
}

impl Look {
    /// `base` (px on the screen layout) scaled.
    pub fn px(&self, base: u32) -> u32 {
        (f64::from(base) * self.scale).round().max(1.0) as u32
    }
    fn signed(&self, base: i32) -> i32 {
        (f64::from(base) * self.scale).round() as i32
    }
}

/// Width of a legend's icons, px: plotters sets the labels a fixed distance
/// from the icon's start, so the icon does not scale with the text.
const LEGEND_ICON: i32 = 20;

/// A title's font size: `base` scaled, but no wider than `width` px.
fn caption_px(look: Look, text: &str, base: u32, width: u32) -> u32 {
    let fit = (f64::from(width) * 0.95 / (text.chars().count().max(1) as f64 * 0.56)).floor() as u32;
    look.px(base).min(fit.max(8))
}

/// A tick label without trailing zeros: 200, 2.5, 0.01 (not "200.0").
pub fn tick(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let mut s = format!("{v:.6}");
    if s.contains('.') {
        s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    if s == "-0" { "0".into() } else { s }
}

/// A log axis's tick label: 10ⁿ at the decades, nothing between them.
pub fn decade_tick(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return String::new();
    }
    let e = v.log10();
    if (e - e.round()).abs() > 1e-6 {
        return String::new();
    }
    let digits: String = (e.round() as i64)
        .to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            _ => '⁹',
        })
        .collect();
    format!("10{digits}")
}

/// The decades around `[lo, hi]` (both > 0): the lowest and highest decade
/// of the axis both carry a label.
fn decade_range(lo: f64, hi: f64) -> (f64, f64) {
    let lo = 10f64.powf(lo.log10().floor());
    let mut hi = 10f64.powf(hi.log10().ceil());
    if hi <= lo {
        hi = lo * 10.0;
    }
    (lo, hi)
}

/// Measured statistics of one condition, drawn over the simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredPoint {
    /// Hz
    pub excitation_frequency_hz: f64,
    /// Nominal (or mean) normal force, N.
    pub normal_force_n: f64,
    /// Mean peak amplitude, m.
    pub peak_mean_m: f64,
    /// Variance of the peak amplitude, m², when known.
    pub peak_var_m2: Option<f64>,
    /// Peaks behind the statistics, when known.
    pub n_peaks: Option<u64>,
    /// Mean phase lag behind the base, degrees, and its variance, degrees², when known.
    pub phase_deg: Option<(f64, Option<f64>)>,
    /// The per-period peaks themselves (m), when the set has records.
    pub peaks_m: Vec<f64>,
}

impl MeasuredPoint {
    /// The standard error of the mean peak, m (0 when unknown).
    pub fn mean_standard_error_m(&self) -> f64 {
        match (self.peak_var_m2, self.n_peaks) {
            (Some(v), Some(n)) if n > 0 => (v.max(0.0) / n as f64).sqrt(),
            _ => 0.0,
        }
    }

    /// The standard error of the peak variance, m² (normal approximation; 0 when unknown).
    pub fn var_standard_error_m2(&self) -> f64 {
        match (self.peak_var_m2, self.n_peaks) {
            (Some(v), Some(n)) if n > 1 => v.max(0.0) * (2.0 / (n - 1) as f64).sqrt(),
            _ => 0.0,
        }
    }

    fn matches(&self, c: &Condition) -> bool {
        (self.excitation_frequency_hz - c.excitation_frequency_hz).abs() <= 1e-6 * c.excitation_frequency_hz.abs()
            && (self.normal_force_n - c.normal_force_n).abs() <= 0.01 * c.normal_force_n.abs().max(1e-9)
    }
}

/// The largest displacement in each whole excitation period of a record.
fn period_peaks(t_s: &[f64], x_m: &[f64], frequency_hz: f64) -> Vec<f64> {
    let (Some(&t0), true) = (t_s.first(), frequency_hz > 0.0) else { return Vec::new() };
    let mut peaks = Vec::new();
    let mut current: Option<(i64, f64)> = None;
    for (&t, &x) in t_s.iter().zip(x_m) {
        let k = ((t - t0) * frequency_hz).floor() as i64;
        match current {
            Some((ck, m)) if ck == k => current = Some((k, m.max(x))),
            Some((_, m)) => {
                peaks.push(m);
                current = Some((k, x));
            }
            None => current = Some((k, x)),
        }
    }
    // The last period may be cut short: left out.
    peaks
}

/// A measurement set's statistics per condition: its summary rows, and the
/// per-period peaks of its records (which give the statistics of a
/// condition without a summary row).
pub fn measured_points(set: &MeasurementSet) -> Vec<MeasuredPoint> {
    let mut points: Vec<MeasuredPoint> = set
        .summary
        .iter()
        .filter_map(|r| {
            Some(MeasuredPoint {
                excitation_frequency_hz: r.excitation_frequency_hz,
                normal_force_n: r.normal_force_mean_n,
                peak_mean_m: r.peak_mean_m?,
                peak_var_m2: r.peak_var_m2,
                n_peaks: r.n_peaks,
                phase_deg: r.phase_mean_deg.map(|m| (m, r.phase_var_deg2)),
                peaks_m: Vec::new(),
            })
        })
        .collect();
    for run in &set.runs {
        let peaks = period_peaks(&run.t_s, &run.x_m, run.excitation_frequency_hz);
        let cond =
            Condition { excitation_frequency_hz: run.excitation_frequency_hz, normal_force_n: run.normal_force_n };
        match points.iter_mut().find(|p| p.matches(&cond)) {
            Some(p) => p.peaks_m.extend(peaks),
            None => points.push(MeasuredPoint {
                excitation_frequency_hz: run.excitation_frequency_hz,
                normal_force_n: run.normal_force_n,
                peak_mean_m: f64::NAN,
                peak_var_m2: None,
                n_peaks: None,
                phase_deg: None,
                peaks_m: peaks,
            }),
        }
    }
    for p in &mut points {
        if !p.peak_mean_m.is_finite() && p.peaks_m.len() > 1 {
            let n = p.peaks_m.len() as f64;
            let mean = p.peaks_m.iter().sum::<f64>() / n;
            p.peak_mean_m = mean;
            p.peak_var_m2 = Some(p.peaks_m.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0));
            p.n_peaks = Some(p.peaks_m.len() as u64);
        }
    }
    points.retain(|p| p.peak_mean_m.is_finite());
    points
}

/// What [`write_sweep_plots_with`] draws.
#[derive(Clone, Copy, Debug)]
pub struct PlotOptions<'a> {
    /// Figure 8 shows the grid frequency nearest to this, Hz.
    pub fig8_frequency_hz: f64,
    pub size: SizePreset,
    /// Measured statistics drawn over the simulation (empty: none).
    pub measured: &'a [MeasuredPoint],
    /// Where the measured statistics come from, for the legends.
    pub measured_label: &'a str,
}

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

/// The frequency axis: the grid's span, widened to take in the measured points.
fn frequency_span(result: &SweepResult, measured: &[MeasuredPoint]) -> (f64, f64) {
    let (lo, hi) = result
        .conditions
        .iter()
        .map(|c| c.excitation_frequency_hz)
        .chain(measured.iter().map(|m| m.excitation_frequency_hz))
        .filter(|f| f.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), f| (lo.min(f), hi.max(f)));
    if hi > lo {
        let pad = 0.01 * (hi - lo);
        (lo - pad, hi + pad)
    } else if lo.is_finite() {
        (lo - 0.5, hi + 0.5)
    } else {
        (0.0, 1.0)
    }
}

/// The colour of a measured point: its normal force's curve when the grid
/// has that force (within 1%), else black.
fn measured_colour(result: &SweepResult, m: &MeasuredPoint) -> RGBColor {
    curves(result)
        .iter()
        .position(|(n, _)| (n - m.normal_force_n).abs() <= 0.01 * n.abs().max(1e-9))
        .map_or(BLACK, colour)
}

/// Measured points (x, y, y_lo, y_hi, colour, label) with error bars, one
/// legend entry for all.
fn draw_measured<'a, DB: DrawingBackend + 'a>(
    chart: &mut Panel<'a, DB>,
    points: &[(f64, f64, f64, f64, RGBColor, String)],
    legend: &str,
    look: Look,
    what: &'static str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    if points.is_empty() {
        return Ok(());
    }
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error(what, e);
    let r = look.px(5);
    let w = look.px(2);
    chart
        .draw_series(points.iter().map(|(x, _, lo, hi, c, _)| {
            ErrorBar::new_vertical(*x, *lo, (lo + hi) / 2.0, *hi, c.stroke_width(w), look.px(10))
        }))
        .map_err(e)?;
    chart
        .draw_series(points.iter().map(|(x, y, _, _, c, _)| Circle::new((*x, *y), r, c.stroke_width(w))))
        .map_err(e)?
        .label(legend.to_string())
        .legend(move |(x, y)| Circle::new((x + LEGEND_ICON / 2, y), r.min(8), BLACK.stroke_width(w)));
    let font = (FONT, look.px(12)).into_font();
    // Labels alternate above and below their points, so close ones stay apart.
    let mut order: Vec<usize> = (0..points.len()).filter(|&i| !points[i].5.is_empty()).collect();
    order.sort_by(|&a, &b| points[a].1.total_cmp(&points[b].1));
    chart
        .draw_series(order.iter().enumerate().map(|(k, &i)| {
            let (x, y, _, _, c, label) = &points[i];
            let dy = if k % 2 == 0 { look.signed(-16) } else { look.signed(4) };
            EmptyElement::at((*x, *y)) + Text::new(label.clone(), (look.signed(8), dy), font.clone().color(c))
        }))
        .map_err(e)?;
    Ok(())
}

/// How a panel's value axis maps values: as they are, or as log10.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Axis {
    Linear,
    /// log10 of the value on a linear coordinate, from decade `lo` to decade
    /// `hi` (exponents), every decade labelled.
    Log {
        lo: f64,
        hi: f64,
        powers: bool,
    },
}

impl Axis {
    fn map(self, v: f64) -> f64 {
        match self {
            Axis::Linear => v,
            Axis::Log { lo, .. } => {
                if v > 0.0 {
                    v.log10().max(lo)
                } else {
                    lo
                }
            }
        }
    }

    fn label(self, y: f64) -> String {
        match self {
            Axis::Linear => tick(y),
            Axis::Log { powers, .. } => {
                if (y - y.round()).abs() > 1e-9 {
                    String::new()
                } else if powers {
                    decade_tick(10f64.powf(y.round()))
                } else {
                    tick(10f64.powf(y.round()))
                }
            }
        }
    }

    /// Faint lines at 2..9 × 10ⁿ of a log axis, drawn before the data.
    fn minor_lines(self) -> Vec<f64> {
        match self {
            Axis::Linear => Vec::new(),
            Axis::Log { lo, hi, .. } => (lo as i32..hi as i32)
                .flat_map(|d| (2..10).map(move |k| (f64::from(k) * 10f64.powi(d)).log10()))
                .collect(),
        }
    }
}

type Panel<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>;

/// Draws the faint minor lines of a log axis across `x`.
fn draw_minor<'a, DB: DrawingBackend + 'a>(
    chart: &mut Panel<'a, DB>,
    axis: Axis,
    x: (f64, f64),
    look: Look,
    what: &'static str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error(what, e);
    for y in axis.minor_lines() {
        chart
            .draw_series(LineSeries::new(vec![(x.0, y), (x.1, y)], BLACK.mix(0.08).stroke_width(look.px(1))))
            .map_err(e)?;
    }
    Ok(())
}

/// The mean peak curves with their 5–95% bands and the measured points.
fn figure9a_series<'a, DB: DrawingBackend + 'a>(
    chart: &mut Panel<'a, DB>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    axis: Axis,
    labels: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9a", e);
    let y = |v_m: f64| axis.map(v_m * 1e3);
    for (i, (n, pts)) in curves(result).iter().enumerate() {
        let c = colour(i);
        let band: Vec<(f64, f64)> = pts
            .iter()
            .map(|(cond, a)| (cond.excitation_frequency_hz, y(a.quantile(0.95))))
            .chain(pts.iter().rev().map(|(cond, a)| (cond.excitation_frequency_hz, y(a.quantile(0.05)))))
            .filter(|p| finite(*p))
            .collect();
        chart.draw_series(std::iter::once(Polygon::new(band, c.mix(0.28).filled()))).map_err(e)?;
        for p in [0.05, 0.95] {
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|(cond, a)| (cond.excitation_frequency_hz, y(a.quantile(p)))).filter(|p| finite(*p)),
                    c.mix(0.7).stroke_width(look.px(1)),
                ))
                .map_err(e)?;
        }
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|(cond, a)| (cond.excitation_frequency_hz, y(a.moments().0))).filter(|p| finite(*p)),
                c.stroke_width(look.px(2)),
            ))
            .map_err(e)?
            .label(format!("N0 = {} N", tick(*n)))
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + Rectangle::new([(0, -look.signed(6)), (LEGEND_ICON, look.signed(6))], c.mix(0.28).filled())
                    + PathElement::new(vec![(0, 0), (LEGEND_ICON, 0)], c.stroke_width(look.px(3)))
            });
    }
    let measured: Vec<_> = opts
        .measured
        .iter()
        .map(|m| {
            let se = m.mean_standard_error_m();
            (
                m.excitation_frequency_hz,
                y(m.peak_mean_m),
                y(m.peak_mean_m - se),
                y(m.peak_mean_m + se),
                measured_colour(result, m),
                if labels { format!("{} N", tick(m.normal_force_n)) } else { String::new() },
            )
        })
        .collect();
    draw_measured(chart, &measured, &format!("{}: mean ± s.e.", opts.measured_label), look, "fig9a")
}

/// The ranges one panel of Figure 9(a) shows.
#[derive(Clone, Copy, Debug)]
struct PanelRange {
    /// Excitation frequencies, Hz.
    x: (f64, f64),
    /// Peak amplitudes, mm.
    y: (f64, f64),
}

/// One panel of Figure 9(a) over `range`: a log amplitude axis when it spans
/// more than a factor of 30.
fn figure9a_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    caption: &str,
    range: PanelRange,
    zoom: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let PanelRange { x, y } = range;
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9a", e);
    let (y_lo, y_hi, axis) = if y.0 > 0.0 && y.1 / y.0 > 30.0 {
        let (lo, hi) = decade_range(y.0, y.1);
        let (lo, hi) = (lo.log10().round(), hi.log10().round());
        (lo, hi, Axis::Log { lo, hi, powers: false })
    } else if zoom {
        let pad = 0.08 * (y.1 - y.0).max(1e-6);
        (y.0 - pad, y.1 + pad, Axis::Linear)
    } else {
        (0.0, if y.1 > 0.0 { y.1 * 1.1 } else { 1.0 }, Axis::Linear)
    };
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, caption_px(look, caption, if zoom { 16 } else { 18 }, area.dim_in_pixel().0)))
        .margin(look.px(12))
        .x_label_area_size(look.px(52))
        .y_label_area_size(look.px(64))
        .build_cartesian_2d(x.0..x.1, y_lo..y_hi)
        .map_err(e)?;
    let x_fmt = |v: &f64| tick(*v);
    let y_fmt = |v: &f64| axis.label(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc("excitation frequency (Hz)")
        .y_desc("peak amplitude (mm)")
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FONT, look.px(15)))
        .axis_desc_style((FONT, look.px(16)))
        .x_labels(if zoom { 5 } else { 11 });
    if let Axis::Log { lo, hi, .. } = axis {
        mesh.y_labels((hi - lo) as usize + 1).light_line_style(TRANSPARENT);
    }
    mesh.draw().map_err(e)?;
    draw_minor(&mut chart, axis, x, look, "fig9a")?;
    figure9a_series(&mut chart, result, opts, look, axis, zoom || opts.measured.len() <= 1)?;
    if zoom {
        return Ok(()); // the full panel's legend serves both
    }
    legend_box(&mut chart, look.px(14), SeriesLabelPosition::UpperRight, "fig9a")
}

/// Figure 9(a): the mean peak against frequency with the 5–95% band of the
/// peaks. A log amplitude axis when the values span more than a factor of
/// 30 (a resonance beside a stuck block), else linear from zero; the band is
/// outlined, so a narrow one still shows. With measured data, a second
/// panel zooms on the measured conditions (linear, mm).
fn figure9a<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9a", e);
    let means: Vec<f64> =
        result.accumulators.iter().map(|a| a.moments().0 * 1e3).filter(|v| v.is_finite() && *v > 0.0).collect();
    let values: Vec<f64> = result
        .accumulators
        .iter()
        .flat_map(|a| [a.quantile(0.05), a.quantile(0.95)])
        .chain(opts.measured.iter().map(|m| m.peak_mean_m))
        .map(|v| v * 1e3)
        .filter(|v| v.is_finite() && *v > 0.0)
        .chain(means.iter().copied())
        .collect();
    let mean_lo = means.iter().copied().fold(f64::INFINITY, f64::min);
    // The band may reach far below the lowest mean (a block that sticks);
    // the axis stops a decade below it.
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min).max(mean_lo / 10.0);
    let hi = values.iter().copied().fold(0.0, f64::max);
    let x = frequency_span(result, opts.measured);
    let title = "Figure 9(a): mean peak amplitude; band: 5–95% of the peaks";
    let root = root.titled(title, (FONT, caption_px(look, title, 21, look.size.0))).map_err(e)?;
    if opts.measured.is_empty() {
        return figure9a_panel(&root, result, opts, look, "", PanelRange { x, y: (lo, hi) }, false);
    }
    let (left, right) = root.split_horizontally(look.size.0 * 57 / 100);
    figure9a_panel(&left, result, opts, look, "all conditions", PanelRange { x, y: (lo, hi) }, false)?;
    // The zoom: the measured frequencies ± 0.6 Hz, every value there.
    let (m_lo, m_hi) = opts.measured.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), m| {
        (l.min(m.excitation_frequency_hz), h.max(m.excitation_frequency_hz))
    });
    let zx = ((m_lo - 0.6).max(x.0), (m_hi + 0.6).min(x.1));
    let zx = if zx.1 > zx.0 { zx } else { (m_lo - 0.6, m_hi + 0.6) };
    let mut zy = (f64::INFINITY, f64::NEG_INFINITY);
    for (c, a) in result.conditions.iter().zip(&result.accumulators) {
        if (zx.0..=zx.1).contains(&c.excitation_frequency_hz) {
            for v in [a.moments().0, a.quantile(0.05), a.quantile(0.95)] {
                if v.is_finite() {
                    zy = (zy.0.min(v * 1e3), zy.1.max(v * 1e3));
                }
            }
        }
    }
    for m in opts.measured {
        let se = m.mean_standard_error_m();
        zy = (zy.0.min((m.peak_mean_m - se) * 1e3), zy.1.max((m.peak_mean_m + se) * 1e3));
    }
    figure9a_panel(&right, result, opts, look, "zoom on the measured conditions", PanelRange { x: zx, y: zy }, true)
}

/// Figure 9(b): the peak variance on a log axis from decade to decade, each
/// decade labelled 10ⁿ.
fn figure9b<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9b", e);
    let vars: Vec<f64> = result
        .accumulators
        .iter()
        .map(|a| a.moments().1 * 1e6)
        .chain(opts.measured.iter().filter_map(|m| m.peak_var_m2).map(|v| v * 1e6))
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let v_max = vars.iter().copied().fold(1e-12, f64::max);
    let v_min = vars.iter().copied().fold(f64::INFINITY, f64::min).min(v_max);
    let (v_lo, v_hi) = decade_range(v_min, v_max);
    let axis = Axis::Log { lo: v_lo.log10().round(), hi: v_hi.log10().round(), powers: true };
    let Axis::Log { lo: y_lo, hi: y_hi, .. } = axis else { unreachable!() };
    let x = frequency_span(result, opts.measured);
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Figure 9(b): peak-amplitude variance",
            (FONT, caption_px(look, "Figure 9(b): peak-amplitude variance", 21, look.size.0)),
        )
        .margin(look.px(14))
        .x_label_area_size(look.px(52))
        .y_label_area_size(look.px(72))
        .build_cartesian_2d(x.0..x.1, y_lo..y_hi)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("excitation frequency (Hz)")
        .y_desc("peak variance (mm²)")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| axis.label(*v))
        .y_labels((y_hi - y_lo) as usize + 1)
        .x_labels(11)
        .light_line_style(TRANSPARENT)
        .label_style((FONT, look.px(15)))
        .axis_desc_style((FONT, look.px(17)))
        .draw()
        .map_err(e)?;
    draw_minor(&mut chart, axis, x, look, "fig9b")?;
    for (i, (n, pts)) in curves(result).iter().enumerate() {
        let c = colour(i);
        let line: Vec<(f64, f64)> = pts
            .iter()
            .map(|(cond, a)| (cond.excitation_frequency_hz, a.moments().1 * 1e6))
            .filter(|p| finite(*p) && p.1 > 0.0)
            .map(|(f, v)| (f, axis.map(v)))
            .collect();
        chart
            .draw_series(LineSeries::new(line.clone(), c.stroke_width(look.px(2))))
            .map_err(e)?
            .label(format!("N0 = {} N", tick(*n)))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + LEGEND_ICON, y)], c.stroke_width(look.px(3))));
        chart.draw_series(line.into_iter().map(|p| Circle::new(p, look.px(3), c.filled()))).map_err(e)?;
    }
    let measured: Vec<_> = opts
        .measured
        .iter()
        .filter_map(|m| {
            let v = m.peak_var_m2? * 1e6;
            let se = m.var_standard_error_m2() * 1e6;
            Some((
                m.excitation_frequency_hz,
                axis.map(v),
                axis.map(v - se),
                axis.map(v + se),
                measured_colour(result, m),
                format!("{} N", tick(m.normal_force_n)),
            ))
        })
        .collect();
    draw_measured(&mut chart, &measured, &format!("{}: variance ± s.e.", opts.measured_label), look, "fig9b")?;
    legend_box(&mut chart, look.px(15), SeriesLabelPosition::UpperRight, "fig9b")
}

const FIG9C_TITLE: &str = "Figure 9(c): phase lag of the response's fundamental; band: ± 1 sd";

/// Figure 9's phase panel: the circular mean phase lag of the response's
/// fundamental (degrees) against frequency, one curve per normal force, with
/// a band of ± one circular standard deviation.
fn figure9c<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9c", e);
    let (f_lo, f_hi) = frequency_span(result, opts.measured);
    let mut chart = ChartBuilder::on(&root)
        .caption(FIG9C_TITLE, (FONT, caption_px(look, FIG9C_TITLE, 21, look.size.0)))
        .margin(look.px(14))
        .x_label_area_size(look.px(52))
        .y_label_area_size(look.px(72))
        .build_cartesian_2d(f_lo..f_hi, -10.0..190.0)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("excitation frequency (Hz)")
        .y_desc("phase lag behind the base (°)")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .y_labels(11)
        .x_labels(11)
        .label_style((FONT, look.px(15)))
        .axis_desc_style((FONT, look.px(17)))
        .draw()
        .map_err(e)?;
    // Lags are drawn in [0°, 360°) so curves above resonance do not jump.
    let lag = |a: &PointAccumulator| {
        let (mean, var) = a.phase_moments();
        (mean.to_degrees().rem_euclid(360.0), var.max(0.0).sqrt().to_degrees())
    };
    for (i, (n, pts)) in curves(result).iter().enumerate() {
        let c = colour(i);
        let band: Vec<(f64, f64)> = pts
            .iter()
            .map(|(cond, a)| (cond.excitation_frequency_hz, lag(a).0 + lag(a).1))
            .chain(pts.iter().rev().map(|(cond, a)| (cond.excitation_frequency_hz, lag(a).0 - lag(a).1)))
            .filter(|p| finite(*p))
            .collect();
        chart.draw_series(std::iter::once(Polygon::new(band, c.mix(0.25).filled()))).map_err(e)?;
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|(cond, a)| (cond.excitation_frequency_hz, lag(a).0)).filter(|p| finite(*p)),
                c.stroke_width(look.px(2)),
            ))
            .map_err(e)?
            .label(format!("N0 = {} N", tick(*n)))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + LEGEND_ICON, y)], c.stroke_width(look.px(3))));
    }
    let measured: Vec<_> = opts
        .measured
        .iter()
        .filter_map(|m| {
            let (mean, var) = m.phase_deg?;
            let mean = mean.rem_euclid(360.0);
            let se = match (var, m.n_peaks) {
                (Some(v), Some(n)) if n > 0 => (v.max(0.0) / n as f64).sqrt(),
                _ => 0.0,
            };
            Some((
                m.excitation_frequency_hz,
                mean,
                mean - se,
                mean + se,
                measured_colour(result, m),
                format!("{} N", tick(m.normal_force_n)),
            ))
        })
        .collect();
    draw_measured(&mut chart, &measured, &format!("{}: mean ± s.e.", opts.measured_label), look, "fig9c")?;
    legend_box(&mut chart, look.px(15), SeriesLabelPosition::LowerRight, "fig9c")
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

fn figure8<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    points: &[(Condition, &PointAccumulator)],
    opts: &PlotOptions,
    look: Look,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig8", e);
    let title = "Figure 8: probability density of the peak amplitude";
    let root = root.titled(title, (FONT, caption_px(look, title, 21, look.size.0))).map_err(e)?;
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

/// Writes fig9a, fig9b, fig9c and fig8 (PNG + SVG) into `dir` at the
/// screen size without measured data; returns the files.
pub fn write_sweep_plots(dir: &Path, result: &SweepResult, figure8_frequency_hz: f64) -> Result<Vec<PathBuf>> {
    let opts = PlotOptions {
        fig8_frequency_hz: figure8_frequency_hz,
        size: SizePreset::Screen,
        measured: &[],
        measured_label: "measured",
    };
    write_sweep_plots_with(dir, result, &opts)
}

/// Writes fig9a, fig9b, fig9c and fig8 (PNG + SVG) into `dir` as `opts`
/// says; returns the files.
pub fn write_sweep_plots_with(dir: &Path, result: &SweepResult, opts: &PlotOptions) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let look = opts.size.look((1000, 650));
    files.extend(render(dir, "fig9a", look.size, &|r| figure9a(r, result, opts, look), &|r| {
        figure9a(r, result, opts, look)
    })?);
    files.extend(render(dir, "fig9b", look.size, &|r| figure9b(r, result, opts, look), &|r| {
        figure9b(r, result, opts, look)
    })?);
    files.extend(render(dir, "fig9c", look.size, &|r| figure9c(r, result, opts, look), &|r| {
        figure9c(r, result, opts, look)
    })?);
    let pts = figure8_points(result, opts.fig8_frequency_hz);
    let rows = pts.len().div_ceil(2).max(1) as u32;
    let look8 = opts.size.look((1100, 60 + 380 * rows));
    files.extend(render(dir, "fig8", look8.size, &|r| figure8(r, &pts, opts, look8), &|r| {
        figure8(r, &pts, opts, look8)
    })?);
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_ticks_have_no_trailing_zeros() {
        assert_eq!(tick(200.0), "200");
        assert_eq!(tick(2.5), "2.5");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(-0.0), "0");
        assert_eq!(decade_tick(1e-3), "10⁻³");
        assert_eq!(decade_tick(100.0), "10²");
        assert_eq!(decade_tick(2e-3), "");
    }

    #[test]
    fn plot_log_ranges_start_and_end_on_labelled_ticks() {
        let (lo, hi) = decade_range(3.2e-6, 4.1e-2);
        assert!((lo - 1e-6).abs() < 1e-18 && (hi - 1e-1).abs() < 1e-15);
        assert_eq!(decade_tick(lo), "10⁻⁶");
        let axis = Axis::Log { lo: -1.0, hi: 3.0, powers: false };
        assert_eq!((axis.label(-1.0), axis.label(2.0), axis.label(0.5)), ("0.1".into(), "100".into(), String::new()));
        assert_eq!(axis.map(0.0), -1.0);
    }

    #[test]
    fn plot_period_peaks_of_a_sampled_sine() {
        let f = 7.0;
        let t: Vec<f64> = (0..6000).map(|i| f64::from(i) / 600.0).collect();
        let x: Vec<f64> = t.iter().map(|t| 0.004 * (std::f64::consts::TAU * f * t).sin()).collect();
        let peaks = period_peaks(&t, &x, f);
        assert_eq!(peaks.len(), 69);
        assert!(peaks.iter().all(|p| (p - 0.004).abs() < 0.004 * 1e-3), "{peaks:?}");
    }
}
