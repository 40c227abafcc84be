//! Pictures of a sweep: Figure 9(a) mean peak with its 5–95% band, Figure
//! 9(b) peak variance, a phase panel (fig9c), and Figure 8-style peak
//! densities with the Gaussian of the same mean and variance. Each is written
//! as PNG and SVG, atomically. Measured statistics (a measurement set's
//! summary rows, or the peaks of its records) can be drawn over them
//! ([`MeasuredPoint`]), at a size meant for a page ([`SizePreset`]).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::diagnose::measure::MeasurementSet;
use crate::engine::reduce::HISTOGRAM_BINS;
use crate::engine::{Condition, PointAccumulator};
use crate::error::Result;
use crate::figure::{FONT, colour, decade_range, decade_tick, legend_box, plot_error, render, tick};
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

    /// Whether this is the grid point `c`: its frequency (within 1e-6) and
    /// its normal force (within 1%).
    pub fn matches(&self, c: &Condition) -> bool {
        (self.excitation_frequency_hz - c.excitation_frequency_hz).abs() <= 1e-6 * c.excitation_frequency_hz.abs()
            && same_load(self.normal_force_n, c.normal_force_n)
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

/// How Figure 9(a)'s amplitude axis is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AmplitudeAxis {
    /// Logarithmic when the values span more than a factor of 30 (a
    /// resonance beside a stuck block), else linear from zero.
    #[default]
    Auto,
    /// Logarithmic, every decade labelled.
    Log,
    /// Linear from zero, as the paper draws its Figure 9(a).
    Linear,
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
    /// Figure 9(a)'s amplitude axis.
    pub amplitude_axis: AmplitudeAxis,
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

/// The normal forces of the grid, increasing: one curve each.
pub fn loads(result: &SweepResult) -> Vec<f64> {
    curves(result).iter().map(|(n, _)| *n).collect()
}

/// Whether two normal forces are the same load (within 1%).
fn same_load(a: f64, b: f64) -> bool {
    (a - b).abs() <= 0.01 * a.abs().max(b.abs()).max(1e-9)
}

/// A measured point's simulated counterpart: the curve of its normal force
/// (within 1%), else the curve of the nearest simulated normal force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pairing {
    /// Index of the curve (normal forces in increasing order).
    pub curve: usize,
    /// The curve's normal force, N.
    pub force_n: f64,
    /// Whether the curve is at the measured load (else the nearest one).
    pub same_load: bool,
}

/// Pairs a measured point with a curve of `forces` (increasing).
pub fn pair(forces: &[f64], m: &MeasuredPoint) -> Option<Pairing> {
    let (curve, &force_n) = forces
        .iter()
        .enumerate()
        .min_by(|(_, a), (_, b)| (*a - m.normal_force_n).abs().total_cmp(&(*b - m.normal_force_n).abs()))?;
    Some(Pairing { curve, force_n, same_load: same_load(force_n, m.normal_force_n) })
}

/// The simulated mean peak (m) of a curve at `frequency_hz`: the grid point's
/// when the grid has that frequency, else interpolated linearly between the
/// neighbouring grid frequencies; `None` outside the grid.
fn mean_at(points: &[(Condition, &PointAccumulator)], frequency_hz: f64) -> Option<f64> {
    let at = |k: usize| (points[k].0.excitation_frequency_hz, points[k].1.moments().0);
    let tol = 1e-6 * frequency_hz.abs();
    if let Some(k) = points.iter().position(|(c, _)| (c.excitation_frequency_hz - frequency_hz).abs() <= tol) {
        return Some(at(k).1);
    }
    let k = points.iter().position(|(c, _)| c.excitation_frequency_hz > frequency_hz)?;
    if k == 0 {
        return None;
    }
    let ((f0, m0), (f1, m1)) = (at(k - 1), at(k));
    Some(m0 + (m1 - m0) * (frequency_hz - f0) / (f1 - f0))
}

/// Where things sit along a panel's frequency axis. A grid of one frequency
/// sets its normal forces side by side ("dodged") about that frequency, the
/// simulation left of each slot's centre and the measurement right of it,
/// so that neither hides the other; otherwise everything sits at its
/// frequency.
#[derive(Clone, Copy, Debug)]
struct Layout {
    /// The grid's one frequency, Hz, when it has only one.
    single: Option<f64>,
    curves: usize,
}

impl Layout {
    fn new(result: &SweepResult) -> Layout {
        let mut freqs: Vec<f64> = result.conditions.iter().map(|c| c.excitation_frequency_hz).collect();
        freqs.sort_by(f64::total_cmp);
        freqs.dedup();
        let single = if freqs.len() == 1 { Some(freqs[0]) } else { None };
        Layout { single, curves: curves(result).len().max(1) }
    }

    /// Half the width of the frequency axis of a one-frequency grid, Hz.
    const HALF_SPAN: f64 = 0.5;

    /// The centre and width of curve `curve`'s slot: the slots fill the axis
    /// from 0.9 of its half-span left of the frequency to 0.6 right of it,
    /// leaving room for the last slot's label.
    fn slot(&self, curve: usize) -> Option<(f64, f64)> {
        self.single.map(|f| {
            let width = 1.5 * Self::HALF_SPAN / self.curves as f64;
            (f - 0.9 * Self::HALF_SPAN + (curve as f64 + 0.5) * width, width)
        })
    }

    /// The x of curve `curve`'s point at `f`.
    fn simulated(&self, curve: usize, f: f64) -> f64 {
        self.slot(curve).map_or(f, |(centre, width)| centre - 0.18 * width)
    }

    /// The x of a measured point at `f` paired with `curve`.
    fn measured(&self, curve: Option<usize>, f: f64) -> f64 {
        match (self.slot(curve.unwrap_or(0)), curve) {
            (Some((centre, width)), Some(_)) => centre + 0.18 * width,
            _ => f,
        }
    }

    /// Half the width of a one-frequency point's spread box, Hz.
    fn box_half_width(&self) -> f64 {
        self.slot(0).map_or(0.0, |(_, width)| 0.1 * width)
    }
}

/// The frequency axis: the grid's span, widened to take in the measured
/// points; a one-frequency grid's slots about its frequency.
fn frequency_span(result: &SweepResult, measured: &[MeasuredPoint]) -> (f64, f64) {
    if let Some(f) = Layout::new(result).single {
        return (f - Layout::HALF_SPAN, f + Layout::HALF_SPAN);
    }
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

/// The frequency axis's description and tick labels: a one-frequency grid
/// names its frequency in the description and labels no ticks (its slots
/// are normal forces, not frequencies).
fn frequency_axis(layout: Layout) -> (String, fn(&f64) -> String) {
    match layout.single {
        Some(f) => (format!("normal forces side by side at {} Hz", tick(f)), |_| String::new()),
        None => ("excitation frequency (Hz)".to_string(), |v| tick(*v)),
    }
}

/// A measured point as drawn: (x, y, y_lo, y_hi, colour, label), in the
/// panel's coordinates.
type MeasuredMark = (f64, f64, f64, f64, RGBColor, String);

/// Measured points with error bars (open circles), one legend entry for all.
fn draw_measured<'a, DB: DrawingBackend + 'a>(
    chart: &mut Panel<'a, DB>,
    points: &[MeasuredMark],
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
    let r = look.px(6);
    let w = look.px(2);
    chart
        .draw_series(points.iter().map(|(x, _, lo, hi, c, _)| {
            ErrorBar::new_vertical(*x, *lo, (lo + hi) / 2.0, *hi, c.stroke_width(w), look.px(10))
        }))
        .map_err(e)?;
    chart.draw_series(points.iter().map(|(x, y, ..)| Circle::new((*x, *y), r, WHITE.filled()))).map_err(e)?;
    chart
        .draw_series(points.iter().map(|(x, y, _, _, c, _)| Circle::new((*x, *y), r, c.stroke_width(w))))
        .map_err(e)?
        .label(legend.to_string())
        .legend(move |(x, y)| Circle::new((x + LEGEND_ICON / 2, y), r.min(8), BLACK.stroke_width(w)));
    let font = (FONT, look.px(12)).into_font();
    // Labels sit beside their points, right where they fit in the panel, else
    // left, and are stacked so that close ones stay apart.
    let mut order: Vec<usize> = (0..points.len()).filter(|&i| !points[i].5.is_empty()).collect();
    order.sort_by(|&a, &b| points[a].1.total_cmp(&points[b].1));
    let (left, right) = {
        let range = chart.plotting_area().get_pixel_range().0;
        (range.start, range.end)
    };
    let gap = look.signed(10);
    let line_height = look.signed(14);
    let style = TextStyle::from(font.clone());
    // Each label: its point, side, lines, and pixel position (x, y of the point).
    let mut marks: Vec<(usize, i32, HPos, Vec<String>, i32)> = order
        .iter()
        .map(|&i| {
            let (x, y, _, _, _, label) = &points[i];
            // A long label breaks before its parenthesis: "7.519 N" over "(nearest ...)".
            let lines: Vec<String> = match label.find(" (") {
                Some(at) => vec![label[..at].to_string(), label[at + 1..].to_string()],
                None => vec![label.clone()],
            };
            let (px, py) = chart.backend_coord(&(*x, *y));
            let width = lines
                .iter()
                .map(|l| chart.plotting_area().estimate_text_size(l, &style).map_or(0, |(w, _)| w as i32))
                .max()
                .unwrap_or(0);
            let (room_right, room_left) = (right - px - gap, px - gap - left);
            // Right of the point where the label fits, else left where it fits there,
            // else on the side with more room.
            let (dx, h) =
                if width <= room_right || room_right >= room_left { (gap, HPos::Left) } else { (-gap, HPos::Right) };
            (i, dx, h, lines, py)
        })
        .collect();
    // Labels centred on their points, pushed down where they would overlap the
    // label above them on the same side.
    marks.sort_by_key(|m| m.4);
    let mut bottom: [Option<i32>; 2] = [None, None];
    let tops: Vec<i32> = marks
        .iter()
        .map(|(_, _, h, lines, py)| {
            let side = usize::from(matches!(h, HPos::Right));
            let height = lines.len() as i32 * line_height;
            let mut top = py - height / 2;
            if let Some(b) = bottom[side] {
                top = top.max(b + look.signed(2));
            }
            bottom[side] = Some(top + height);
            top - py
        })
        .collect();
    chart
        .draw_series(marks.iter().zip(tops).flat_map(|((i, dx, h, lines, _), top)| {
            let (x, y, _, _, c, _) = &points[*i];
            let style = font.clone().color(c).pos(Pos::new(*h, VPos::Top));
            lines
                .iter()
                .enumerate()
                .map(move |(j, line)| {
                    EmptyElement::at((*x, *y))
                        + Text::new(line.clone(), (*dx, top + j as i32 * line_height), style.clone())
                })
                .collect::<Vec<_>>()
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

/// One simulated point as drawn: at `x` (dodged on a one-frequency grid),
/// the value `y` and its spread `lo..hi`, in the panel's coordinates.
#[derive(Clone, Copy, Debug)]
struct SimPoint {
    x: f64,
    y: f64,
    lo: f64,
    hi: f64,
}

/// One curve of simulated points.
struct SimSeries {
    force_n: f64,
    colour: RGBColor,
    points: Vec<SimPoint>,
}

/// How a curve's spread is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Spread {
    /// A shaded band between `lo` and `hi` with its edges drawn (a box on a
    /// one-frequency grid): a range of the data, such as 5–95%.
    Band,
    /// Error bars: an uncertainty of the value itself.
    Bars,
}

/// Draws simulated curves: every spread first, so that no line hides a band,
/// then the lines and a marker at every grid point (a one-frequency grid
/// gets markers and boxes only).
fn draw_simulated<'a, DB: DrawingBackend + 'a>(
    chart: &mut Panel<'a, DB>,
    series: &[SimSeries],
    spread: Spread,
    layout: Layout,
    look: Look,
    what: &'static str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error(what, e);
    let ok = |p: &&SimPoint| p.x.is_finite() && p.y.is_finite() && p.lo.is_finite() && p.hi.is_finite();
    // Lines and bands run to the panel's edges (plotters clips them); marks
    // are drawn only for points inside it.
    let x_range = chart.x_range();
    let (x_lo, x_hi) = (x_range.start, x_range.end);
    let inside = move |p: &&SimPoint| ok(p) && (x_lo..=x_hi).contains(&p.x);
    for s in series {
        let c = s.colour;
        match (spread, layout.single) {
            (Spread::Band, None) => {
                let band: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .filter(ok)
                    .map(|p| (p.x, p.hi))
                    .chain(s.points.iter().rev().filter(ok).map(|p| (p.x, p.lo)))
                    .collect();
                chart.draw_series(std::iter::once(Polygon::new(band, c.mix(0.22).filled()))).map_err(e)?;
                for edge in [|p: &SimPoint| p.lo, |p: &SimPoint| p.hi] {
                    chart
                        .draw_series(LineSeries::new(
                            s.points.iter().filter(ok).map(|p| (p.x, edge(p))),
                            c.mix(0.85).stroke_width(look.px(1)),
                        ))
                        .map_err(e)?;
                }
            }
            (Spread::Band, Some(_)) => {
                let w = layout.box_half_width();
                chart
                    .draw_series(s.points.iter().filter(inside).flat_map(|p| {
                        [
                            Rectangle::new([(p.x - w, p.lo), (p.x + w, p.hi)], c.mix(0.3).filled()),
                            Rectangle::new([(p.x - w, p.lo), (p.x + w, p.hi)], c.stroke_width(look.px(1))),
                        ]
                    }))
                    .map_err(e)?;
            }
            (Spread::Bars, single) => {
                let (stroke, cap) = if single.is_some() { (look.px(2), look.px(10)) } else { (look.px(1), look.px(5)) };
                chart
                    .draw_series(
                        s.points
                            .iter()
                            .filter(inside)
                            .map(|p| ErrorBar::new_vertical(p.x, p.lo, p.y, p.hi, c.stroke_width(stroke), cap)),
                    )
                    .map_err(e)?;
            }
        }
    }
    for s in series {
        let c = s.colour;
        let fill = if spread == Spread::Band { c.mix(0.22) } else { c.mix(0.0) };
        let line = LineSeries::new(s.points.iter().filter(ok).map(|p| (p.x, p.y)), c.stroke_width(look.px(2)));
        let anno = if layout.single.is_some() {
            chart.draw_series(std::iter::empty::<Circle<(f64, f64), u32>>()).map_err(e)?
        } else {
            chart.draw_series(line).map_err(e)?
        };
        let (icon_half, band_icon) = (look.signed(6), spread == Spread::Band);
        anno.label(format!("N0 = {} N", tick(s.force_n))).legend(move |(x, y)| {
            let band = if band_icon {
                Rectangle::new([(0, -icon_half), (LEGEND_ICON, icon_half)], fill.filled())
            } else {
                Rectangle::new([(0, 0), (0, 0)], fill.filled())
            };
            EmptyElement::at((x, y))
                + band
                + PathElement::new(vec![(0, 0), (LEGEND_ICON, 0)], c.stroke_width(look.px(2)))
                + Circle::new((LEGEND_ICON / 2, 0), look.px(3), c.filled())
        });
        // Error bars are the point's own uncertainty, often smaller than a dot: a
        // smaller dot leaves their caps in view.
        let r = match (spread, layout.single.is_some()) {
            (Spread::Band, true) => look.px(5),
            (Spread::Band, false) => look.px(3),
            (Spread::Bars, true) => look.px(3),
            (Spread::Bars, false) => look.px(2),
        };
        chart.draw_series(s.points.iter().filter(inside).map(|p| Circle::new((p.x, p.y), r, c.filled()))).map_err(e)?;
    }
    Ok(())
}

/// Wraps `text` into lines no wider than `width` px in `style`.
fn wrap<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, text: &str, style: &TextStyle, width: u32) -> Vec<String> {
    let fits = |s: &str| area.estimate_text_size(s, style).map_or(s.chars().count() < 60, |(w, _)| w <= width);
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let candidate = if line.is_empty() { word.to_string() } else { format!("{line} {word}") };
        if fits(&candidate) || line.is_empty() {
            line = candidate;
        } else {
            lines.push(std::mem::replace(&mut line, word.to_string()));
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// A caption's font size, line height and margin, px on the screen layout.
const CAPTION_FONT: u32 = 14;
const CAPTION_LINE: u32 = 19;
const CAPTION_PAD: u32 = 12;

/// The look of a figure designed at `design` px on the screen with `caption`
/// set below it: the canvas grows by the caption's height, so a long caption
/// never squeezes the plot (a slide keeps its 16:9 and gives the plot less).
/// The height is estimated generously (0.62 em a character); what the
/// wrapped caption does not use goes to the plot.
fn with_caption(size: SizePreset, design: (u32, u32), caption: &str) -> Look {
    let look = size.look(design);
    if size == SizePreset::Slide {
        return look;
    }
    let width = f64::from(look.size.0.saturating_sub(2 * look.px(CAPTION_PAD)));
    let per_line = (width / (0.62 * f64::from(look.px(CAPTION_FONT)))).floor().max(10.0) as usize;
    let mut lines = 1;
    let mut used = 0;
    for word in caption.split_whitespace() {
        let n = word.chars().count();
        if used > 0 && used + 1 + n > per_line {
            lines += 1;
            used = n;
        } else {
            used += n + usize::from(used > 0);
        }
    }
    let strip = 2 * look.px(CAPTION_PAD) + look.px(CAPTION_LINE) * lines;
    Look { size: (look.size.0, look.size.1 + strip), scale: look.scale }
}

/// Writes `caption` below the figure, as a journal sets it, and returns the
/// area above it for the plot: the figure's number in bold-face words, then
/// what is drawn. The caption is outside every plot area.
fn caption_below<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    caption: &str,
    look: Look,
    what: &'static str,
) -> Result<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error(what, e);
    let (w, h) = root.dim_in_pixel();
    let ink = RGBColor(40, 40, 40);
    let style = TextStyle::from((FONT, look.px(CAPTION_FONT)).into_font()).color(&ink);
    let pad = look.px(CAPTION_PAD);
    let lines = wrap(root, caption, &style, w.saturating_sub(2 * pad));
    let line_h = look.px(CAPTION_LINE);
    let strip = (2 * pad + line_h * lines.len() as u32).min(h / 2);
    let (plot, below) = root.split_vertically(h - strip);
    for (i, line) in lines.iter().enumerate() {
        below
            .draw(&Text::new(line.clone(), (pad as i32, (pad / 2 + line_h * i as u32) as i32), style.clone()))
            .map_err(e)?;
    }
    Ok(plot)
}

/// The sentences that say how measured points meet the curves, for a
/// caption: each measured load without a simulated curve of its own is
/// named with the nearest simulated load it is set against.
fn pairing_note(result: &SweepResult, measured: &[MeasuredPoint], label: &str) -> String {
    if measured.is_empty() {
        return String::new();
    }
    let forces = loads(result);
    let mut nearest: Vec<String> = measured
        .iter()
        .filter_map(|m| pair(&forces, m).filter(|p| !p.same_load).map(|p| (m.normal_force_n, p.force_n)))
        .map(|(m, p)| format!("{} N against {} N", tick(m), tick(p)))
        .collect();
    nearest.dedup();
    let mut note =
        format!(" Open circles: {label}, each in the colour of the simulated normal force it is set against.");
    if !nearest.is_empty() {
        note.push_str(&format!(
            " Measured at a normal force the sweep did not simulate, so set against the nearest simulated load: {}; \
             run the sweep at the measured loads to compare like with like.",
            nearest.join(", ")
        ));
    }
    note
}

/// Whether measured points may carry labels in a panel: a one-frequency
/// grid (each has its own slot), or no two of them at the same frequency.
fn labels_fit(layout: Layout, measured: &[MeasuredPoint]) -> bool {
    layout.single.is_some()
        || measured.iter().enumerate().all(|(i, a)| {
            measured[..i].iter().all(|b| (a.excitation_frequency_hz - b.excitation_frequency_hz).abs() > 1e-9)
        })
}

/// The measured points of Figure 9(a) in the panel's coordinates, labelled
/// with their load and how far the simulation misses them (same load), or
/// with the nearest simulated load they are set against.
fn figure9a_measured(
    result: &SweepResult,
    opts: &PlotOptions,
    layout: Layout,
    y: &dyn Fn(f64) -> f64,
    labels: bool,
) -> Vec<MeasuredMark> {
    let curves = curves(result);
    let forces: Vec<f64> = curves.iter().map(|(n, _)| *n).collect();
    opts.measured
        .iter()
        .map(|m| {
            let se = m.mean_standard_error_m();
            let paired = pair(&forces, m);
            let colour = paired.map_or(BLACK, |p| colour(p.curve));
            let label = match paired {
                _ if !labels => String::new(),
                Some(p) if p.same_load => match mean_at(&curves[p.curve].1, m.excitation_frequency_hz) {
                    Some(sim) => format!(
                        "{} N: simulated {}",
                        tick(m.normal_force_n),
                        percent(100.0 * (sim / m.peak_mean_m - 1.0))
                    ),
                    None => format!("{} N", tick(m.normal_force_n)),
                },
                Some(p) => format!("{} N (nearest simulated load {} N)", tick(m.normal_force_n), tick(p.force_n)),
                None => format!("{} N", tick(m.normal_force_n)),
            };
            (
                layout.measured(paired.map(|p| p.curve), m.excitation_frequency_hz),
                y(m.peak_mean_m),
                y(m.peak_mean_m - se),
                y(m.peak_mean_m + se),
                colour,
                label,
            )
        })
        .collect()
}

/// A signed percentage with one decimal, two below 0.1% (`−2.9%`, `+0.04%`).
fn percent(p: f64) -> String {
    let text = if p.abs() < 0.1 { format!("{:.2}", p.abs()) } else { format!("{:.1}", p.abs()) };
    format!("{}{text}%", if p < 0.0 { "−" } else { "+" })
}

/// The curves of Figure 9(a): mean peak (mm) with its 5–95% range, only those
/// `keep` lets through.
fn figure9a_series(
    result: &SweepResult,
    layout: Layout,
    y: &dyn Fn(f64) -> f64,
    keep: &dyn Fn(usize) -> bool,
) -> Vec<SimSeries> {
    curves(result)
        .iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(i, (n, pts))| SimSeries {
            force_n: *n,
            colour: colour(i),
            points: pts
                .iter()
                .map(|(c, a)| SimPoint {
                    x: layout.simulated(i, c.excitation_frequency_hz),
                    y: y(a.moments().0),
                    lo: y(a.quantile(0.05)),
                    hi: y(a.quantile(0.95)),
                })
                .collect(),
        })
        .collect()
}

/// The ranges one panel of Figure 9(a) shows.
#[derive(Clone, Copy, Debug)]
struct PanelRange {
    /// Excitation frequencies, Hz.
    x: (f64, f64),
    /// Peak amplitudes, mm.
    y: (f64, f64),
}

/// One panel of Figure 9(a) over `range`. `zoom` draws only the curves the
/// measured points are set against, on a linear axis fitted to them.
#[allow(clippy::too_many_arguments)]
fn figure9a_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    heading: &str,
    range: PanelRange,
    zoom: bool,
    legend: bool,
) -> Result<Axis>
where
    DB::ErrorType: 'static,
{
    let PanelRange { x, y } = range;
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9a", e);
    let log = match opts.amplitude_axis {
        _ if zoom => false,
        AmplitudeAxis::Auto => y.0 > 0.0 && y.1 / y.0 > 30.0,
        AmplitudeAxis::Log => y.0 > 0.0,
        AmplitudeAxis::Linear => false,
    };
    let (y_lo, y_hi, axis) = if log {
        let (lo, hi) = decade_range(y.0, y.1);
        let (lo, hi) = (lo.log10().round(), hi.log10().round());
        (lo, hi, Axis::Log { lo, hi, powers: false })
    } else if zoom {
        let pad = 0.08 * (y.1 - y.0).max(1e-6);
        (y.0 - pad, y.1 + pad, Axis::Linear)
    } else {
        (0.0, if y.1 > 0.0 { y.1 * 1.1 } else { 1.0 }, Axis::Linear)
    };
    let layout = Layout::new(result);
    let mut builder = ChartBuilder::on(area);
    if !heading.is_empty() {
        builder.caption(heading, (FONT, caption_px(look, heading, 16, area.dim_in_pixel().0)));
    }
    let mut chart = builder
        .margin(look.px(12))
        .x_label_area_size(look.px(52))
        .y_label_area_size(look.px(64))
        .build_cartesian_2d(x.0..x.1, y_lo..y_hi)
        .map_err(e)?;
    let (x_desc, x_fmt) = frequency_axis(layout);
    let y_fmt = |v: &f64| axis.label(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc("peak amplitude (mm)")
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FONT, look.px(15)))
        .axis_desc_style((FONT, look.px(16)))
        .x_labels(if zoom { 5 } else { 11 });
    if layout.single.is_some() {
        mesh.disable_x_mesh().x_labels(0);
    }
    if let Axis::Log { lo, hi, .. } = axis {
        mesh.y_labels((hi - lo) as usize + 1).light_line_style(TRANSPARENT);
    }
    mesh.draw().map_err(e)?;
    draw_minor(&mut chart, axis, x, look, "fig9a")?;
    let ymap = |v_m: f64| axis.map(v_m * 1e3);
    let forces = loads(result);
    let paired: Vec<usize> = opts.measured.iter().filter_map(|m| pair(&forces, m)).map(|p| p.curve).collect();
    let keep = |i: usize| !zoom || paired.contains(&i);
    let series = figure9a_series(result, layout, &ymap, &keep);
    draw_simulated(&mut chart, &series, Spread::Band, layout, look, "fig9a")?;
    let labels = zoom || labels_fit(layout, opts.measured);
    let measured = figure9a_measured(result, opts, layout, &ymap, labels);
    draw_measured(&mut chart, &measured, &format!("{}: mean ± s.e.", opts.measured_label), look, "fig9a")?;
    if legend {
        legend_box(&mut chart, look.px(14), SeriesLabelPosition::UpperRight, "fig9a")?;
    }
    Ok(axis)
}

/// Figure 9(a): the mean peak against frequency, one curve per normal force,
/// a marker at every grid point, with the 5–95% range of the peaks (a band;
/// a box on a one-frequency grid). With measured data over a grid of several
/// frequencies, a second panel zooms on the measured conditions and the
/// curves they are set against. The caption is set below the plot.
/// The amplitudes (mm) Figure 9(a)'s full panel spans: every simulated 5–95%
/// range and mean, and the measured means with their error bars, down to a
/// decade below the lowest mean (a block that sticks can have a 5% quantile
/// far below it).
fn figure9a_extent(result: &SweepResult, opts: &PlotOptions) -> (f64, f64) {
    let means: Vec<f64> =
        result.accumulators.iter().map(|a| a.moments().0 * 1e3).filter(|v| v.is_finite() && *v > 0.0).collect();
    let values: Vec<f64> = result
        .accumulators
        .iter()
        .flat_map(|a| [a.quantile(0.05), a.quantile(0.95)])
        .chain(opts.measured.iter().flat_map(|m| {
            let se = m.mean_standard_error_m();
            [m.peak_mean_m - se, m.peak_mean_m + se]
        }))
        .map(|v| v * 1e3)
        .filter(|v| v.is_finite() && *v > 0.0)
        .chain(means.iter().copied())
        .collect();
    let mean_lo = means.iter().copied().fold(f64::INFINITY, f64::min);
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min).max(mean_lo / 10.0);
    let hi = values.iter().copied().fold(0.0, f64::max);
    (lo, hi)
}

/// Figure 9(a)'s caption: what is drawn, on which axis, and how the measured
/// points meet the curves.
fn figure9a_caption(result: &SweepResult, opts: &PlotOptions) -> String {
    let (lo, hi) = figure9a_extent(result, opts);
    let layout = Layout::new(result);
    let zoom = !opts.measured.is_empty() && layout.single.is_none();
    let single_zoomed = !opts.measured.is_empty() && layout.single.is_some();
    // The axis by the full panel's own rule, on the same range.
    let log = match opts.amplitude_axis {
        _ if single_zoomed => false,
        AmplitudeAxis::Auto => lo > 0.0 && hi / lo > 30.0,
        AmplitudeAxis::Log => lo > 0.0,
        AmplitudeAxis::Linear => false,
    };
    let mut caption = match layout.single {
        Some(f) => format!(
            "Figure 9(a) at one frequency. Mean peak amplitude at {} Hz, one colour per normal force N0, the normal \
             forces side by side: a dot marks the simulated mean, the box the 5–95% range of the simulated peaks.",
            tick(f)
        ),
        None => "Figure 9(a). Mean peak amplitude against excitation frequency, one colour per normal force N0: a \
                 dot marks every simulated grid point, the shaded band (edges drawn) the 5–95% range of the \
                 simulated peaks."
            .to_string(),
    };
    caption.push_str(if log {
        " Logarithmic amplitude axis (`stickslip plot --amplitude-axis linear` draws the paper's linear view)."
    } else {
        " Linear amplitude axis."
    });
    caption.push_str(&pairing_note(result, opts.measured, &format!("{}: mean ± standard error", opts.measured_label)));
    if zoom {
        caption.push_str(" Right: zoom on the measured conditions, with only the curves they are set against.");
    }
    caption
}

fn figure9a<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    caption: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (lo, hi) = figure9a_extent(result, opts);
    let x = frequency_span(result, opts.measured);
    let layout = Layout::new(result);
    let zoom = !opts.measured.is_empty() && layout.single.is_none();
    let single_zoomed = !opts.measured.is_empty() && layout.single.is_some();
    let plot = caption_below(&root, caption, look, "fig9a")?;
    if single_zoomed {
        // Zoom on the values: the measured points and the boxes they meet.
        return figure9a_panel(
            &plot,
            result,
            opts,
            look,
            "",
            PanelRange { x, y: zoom_range(result, opts, x) },
            true,
            true,
        )
        .map(|_| ());
    }
    if !zoom {
        return figure9a_panel(&plot, result, opts, look, "", PanelRange { x, y: (lo, hi) }, false, true).map(|_| ());
    }
    let (left, right) = plot.split_horizontally(look.size.0 * 57 / 100);
    figure9a_panel(&left, result, opts, look, "all conditions", PanelRange { x, y: (lo, hi) }, false, true)?;
    // The zoom: the measured frequencies ± 0.6 Hz, every value there.
    let (m_lo, m_hi) = opts.measured.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), m| {
        (l.min(m.excitation_frequency_hz), h.max(m.excitation_frequency_hz))
    });
    let zx = ((m_lo - 0.6).max(x.0), (m_hi + 0.6).min(x.1));
    let zx = if zx.1 > zx.0 { zx } else { (m_lo - 0.6, m_hi + 0.6) };
    let range = PanelRange { x: zx, y: zoom_range(result, opts, zx) };
    figure9a_panel(&right, result, opts, look, "zoom on the measured conditions", range, true, false).map(|_| ())
}

/// The amplitude range (mm) of a zoom over frequencies `x`: the measured
/// points with their error bars and the curves they are set against.
fn zoom_range(result: &SweepResult, opts: &PlotOptions, x: (f64, f64)) -> (f64, f64) {
    let forces = loads(result);
    let paired: Vec<f64> = opts.measured.iter().filter_map(|m| pair(&forces, m)).map(|p| p.force_n).collect();
    let mut zy = (f64::INFINITY, f64::NEG_INFINITY);
    for (c, a) in result.conditions.iter().zip(&result.accumulators) {
        if (x.0..=x.1).contains(&c.excitation_frequency_hz) && paired.contains(&c.normal_force_n) {
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
    if zy.0.is_finite() { zy } else { (0.0, 1.0) }
}

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
fn figure9b_caption(result: &SweepResult, opts: &PlotOptions) -> String {
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
fn figure9b<DB: DrawingBackend>(
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

/// Figure 9(c)'s caption.
fn figure9c_caption(result: &SweepResult, opts: &PlotOptions) -> String {
    let layout = Layout::new(result);
    format!(
        "Figure 9(c). Phase lag of the response's fundamental behind the base motion {}, one colour per normal \
         force N0 (circular mean over every measured period of every realisation); the {} is ± one circular \
         standard deviation of the per-period lag.{}",
        match layout.single {
            Some(f) => format!("at {} Hz, the normal forces side by side", tick(f)),
            None => "against excitation frequency".to_string(),
        },
        if layout.single.is_some() { "box" } else { "band" },
        pairing_note(result, opts.measured, &format!("{}: mean ± standard error", opts.measured_label))
    )
}

/// Figure 9's phase panel: the circular mean phase lag of the response's
/// fundamental (degrees) against frequency, one curve per normal force, with
/// a band of ± one circular standard deviation. The caption is set below.
fn figure9c<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    caption: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9c", e);
    let layout = Layout::new(result);
    let (f_lo, f_hi) = frequency_span(result, opts.measured);
    let plot = caption_below(&root, caption, look, "fig9c")?;
    let mut chart = ChartBuilder::on(&plot)
        .margin(look.px(14))
        .x_label_area_size(look.px(52))
        .y_label_area_size(look.px(72))
        .build_cartesian_2d(f_lo..f_hi, -10.0..190.0)
        .map_err(e)?;
    let (x_desc, x_fmt) = frequency_axis(layout);
    let y_fmt = |v: &f64| tick(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc("phase lag behind the base (°)")
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .y_labels(11)
        .x_labels(11)
        .label_style((FONT, look.px(15)))
        .axis_desc_style((FONT, look.px(17)));
    if layout.single.is_some() {
        mesh.disable_x_mesh().x_labels(0);
    }
    mesh.draw().map_err(e)?;
    // Lags are drawn in [0°, 360°) so curves above resonance do not jump.
    let lag = |a: &PointAccumulator| {
        let (mean, var) = a.phase_moments();
        (mean.to_degrees().rem_euclid(360.0), var.max(0.0).sqrt().to_degrees())
    };
    let series: Vec<SimSeries> = curves(result)
        .iter()
        .enumerate()
        .map(|(i, (n, pts))| SimSeries {
            force_n: *n,
            colour: colour(i),
            points: pts
                .iter()
                .map(|(c, a)| {
                    let (m, sd) = lag(a);
                    SimPoint { x: layout.simulated(i, c.excitation_frequency_hz), y: m, lo: m - sd, hi: m + sd }
                })
                .collect(),
        })
        .collect();
    draw_simulated(&mut chart, &series, Spread::Band, layout, look, "fig9c")?;
    let forces = loads(result);
    let labels = labels_fit(layout, opts.measured);
    let measured: Vec<MeasuredMark> = opts
        .measured
        .iter()
        .filter_map(|m| {
            let (mean, var) = m.phase_deg?;
            let mean = mean.rem_euclid(360.0);
            let se = match (var, m.n_peaks) {
                (Some(v), Some(n)) if n > 0 => (v.max(0.0) / n as f64).sqrt(),
                _ => 0.0,
            };
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
                mean,
                mean - se,
                mean + se,
                paired.map_or(BLACK, |p| colour(p.curve)),
                label,
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

/// Figure 8's caption.
fn figure8_caption(points: &[(Condition, &PointAccumulator)], opts: &PlotOptions) -> String {
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

fn figure8<DB: DrawingBackend>(
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

/// Writes fig9a, fig9b, fig9c and fig8 (PNG + SVG) into `dir` at the
/// screen size without measured data; returns the files.
pub fn write_sweep_plots(dir: &Path, result: &SweepResult, figure8_frequency_hz: f64) -> Result<Vec<PathBuf>> {
    let opts = PlotOptions {
        fig8_frequency_hz: figure8_frequency_hz,
        size: SizePreset::Screen,
        measured: &[],
        measured_label: "measured",
        amplitude_axis: AmplitudeAxis::Auto,
    };
    write_sweep_plots_with(dir, result, &opts)
}

/// Writes fig9a, fig9b, fig9c and fig8 (PNG + SVG) into `dir` as `opts`
/// says; returns the files.
pub fn write_sweep_plots_with(dir: &Path, result: &SweepResult, opts: &PlotOptions) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let caption = figure9a_caption(result, opts);
    let look = with_caption(opts.size, (1000, 650), &caption);
    files.extend(render(dir, "fig9a", look.size, &|r| figure9a(r, result, opts, look, &caption), &|r| {
        figure9a(r, result, opts, look, &caption)
    })?);
    let caption = figure9b_caption(result, opts);
    let look = with_caption(opts.size, (1000, 650), &caption);
    files.extend(render(dir, "fig9b", look.size, &|r| figure9b(r, result, opts, look, &caption), &|r| {
        figure9b(r, result, opts, look, &caption)
    })?);
    let caption = figure9c_caption(result, opts);
    let look = with_caption(opts.size, (1000, 650), &caption);
    files.extend(render(dir, "fig9c", look.size, &|r| figure9c(r, result, opts, look, &caption), &|r| {
        figure9c(r, result, opts, look, &caption)
    })?);
    let pts = figure8_points(result, opts.fig8_frequency_hz);
    let rows = pts.len().div_ceil(2).max(1) as u32;
    let caption = figure8_caption(&pts, opts);
    let look8 = with_caption(opts.size, (1100, 30 + 380 * rows), &caption);
    files.extend(render(dir, "fig8", look8.size, &|r| figure8(r, &pts, opts, look8, &caption), &|r| {
        figure8(r, &pts, opts, look8, &caption)
    })?);
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn plot_pairs_measured_loads_with_their_own_or_the_nearest_curve() {
        let point = |n: f64| MeasuredPoint {
            excitation_frequency_hz: 7.0,
            normal_force_n: n,
            peak_mean_m: 4e-3,
            peak_var_m2: None,
            n_peaks: None,
            phase_deg: None,
            peaks_m: Vec::new(),
        };
        let forces = [4.0, 8.0, 12.0, 16.39];
        assert_eq!(pair(&forces, &point(16.39)), Some(Pairing { curve: 3, force_n: 16.39, same_load: true }));
        assert_eq!(pair(&forces, &point(16.4)).map(|p| p.same_load), Some(true));
        assert_eq!(pair(&forces, &point(7.519)), Some(Pairing { curve: 1, force_n: 8.0, same_load: false }));
        assert_eq!(pair(&forces, &point(15.3)).map(|p| p.force_n), Some(16.39));
        assert_eq!(pair(&[], &point(1.0)), None);
        assert_eq!(percent(-2.94), "−2.9%");
        assert_eq!(percent(0.044), "+0.04%");
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
