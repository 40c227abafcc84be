//! What the sweep's panels share: where things sit along the frequency axis
//! ([`Layout`]), the value axis ([`Axis`]), the simulated curves with their
//! spread, the measured points with their error bars, and the sentences a
//! caption uses to say how the two meet.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::measured::{MeasuredPoint, pair};
use super::{curves, loads};
use crate::error::Result;
use crate::figure::{FONT, LEGEND_ICON, Look, decade_tick, plot_error, tick};
use crate::sweep::SweepResult;

/// Where things sit along a panel's frequency axis. A grid of one frequency
/// sets its normal forces side by side ("dodged") about that frequency, the
/// simulation left of each slot's centre and the measurement right of it,
/// so that neither hides the other; otherwise everything sits at its
/// frequency.
#[derive(Clone, Copy, Debug)]
pub(super) struct Layout {
    /// The grid's one frequency, Hz, when it has only one.
    pub(super) single: Option<f64>,
    pub(super) curves: usize,
}

impl Layout {
    pub(super) fn new(result: &SweepResult) -> Layout {
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
    pub(super) fn slot(&self, curve: usize) -> Option<(f64, f64)> {
        self.single.map(|f| {
            let width = 1.5 * Self::HALF_SPAN / self.curves as f64;
            (f - 0.9 * Self::HALF_SPAN + (curve as f64 + 0.5) * width, width)
        })
    }

    /// The x of curve `curve`'s point at `f`.
    pub(super) fn simulated(&self, curve: usize, f: f64) -> f64 {
        self.slot(curve).map_or(f, |(centre, width)| centre - 0.18 * width)
    }

    /// The x of a measured point at `f` paired with `curve`.
    pub(super) fn measured(&self, curve: Option<usize>, f: f64) -> f64 {
        match (self.slot(curve.unwrap_or(0)), curve) {
            (Some((centre, width)), Some(_)) => centre + 0.18 * width,
            _ => f,
        }
    }

    /// Half the width of a one-frequency point's spread box, Hz.
    pub(super) fn box_half_width(&self) -> f64 {
        self.slot(0).map_or(0.0, |(_, width)| 0.1 * width)
    }
}

/// The frequency axis: the grid's span, widened to take in the measured
/// points; a one-frequency grid's slots about its frequency.
pub(super) fn frequency_span(result: &SweepResult, measured: &[MeasuredPoint]) -> (f64, f64) {
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
pub(super) fn frequency_axis(layout: Layout) -> (String, fn(&f64) -> String) {
    match layout.single {
        Some(f) => (format!("normal forces side by side at {} Hz", tick(f)), |_| String::new()),
        None => ("excitation frequency (Hz)".to_string(), |v| tick(*v)),
    }
}

/// A measured point as drawn: (x, y, y_lo, y_hi, colour, label), in the
/// panel's coordinates.
pub(super) type MeasuredMark = (f64, f64, f64, f64, RGBColor, String);

/// Measured points with error bars (open circles), one legend entry for all.
pub(super) fn draw_measured<'a, DB: DrawingBackend + 'a>(
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
pub(super) enum Axis {
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
    pub(super) fn map(self, v: f64) -> f64 {
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

    pub(super) fn label(self, y: f64) -> String {
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
    pub(super) fn minor_lines(self) -> Vec<f64> {
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
pub(super) fn draw_minor<'a, DB: DrawingBackend + 'a>(
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
pub(super) struct SimPoint {
    pub(super) x: f64,
    pub(super) y: f64,
    pub(super) lo: f64,
    pub(super) hi: f64,
}

/// One curve of simulated points.
pub(super) struct SimSeries {
    pub(super) force_n: f64,
    pub(super) colour: RGBColor,
    pub(super) points: Vec<SimPoint>,
}

/// How a curve's spread is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Spread {
    /// A shaded band between `lo` and `hi` with its edges drawn (a box on a
    /// one-frequency grid): a range of the data, such as 5–95%.
    Band,
    /// Error bars: an uncertainty of the value itself.
    Bars,
}

/// Draws simulated curves: every spread first, so that no line hides a band,
/// then the lines and a marker at every grid point (a one-frequency grid
/// gets markers and boxes only).
pub(super) fn draw_simulated<'a, DB: DrawingBackend + 'a>(
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

/// The sentences that say how measured points meet the curves, for a
/// caption: each measured load without a simulated curve of its own is
/// named with the nearest simulated load it is set against.
pub(super) fn pairing_note(result: &SweepResult, measured: &[MeasuredPoint], label: &str) -> String {
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
pub(super) fn labels_fit(layout: Layout, measured: &[MeasuredPoint]) -> bool {
    layout.single.is_some()
        || measured.iter().enumerate().all(|(i, a)| {
            measured[..i].iter().all(|b| (a.excitation_frequency_hz - b.excitation_frequency_hz).abs() > 1e-9)
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figure::decade_range;

    #[test]
    fn plot_log_ranges_start_and_end_on_labelled_ticks() {
        let (lo, hi) = decade_range(3.2e-6, 4.1e-2);
        assert!((lo - 1e-6).abs() < 1e-18 && (hi - 1e-1).abs() < 1e-15);
        assert_eq!(decade_tick(lo), "10⁻⁶");
        let axis = Axis::Log { lo: -1.0, hi: 3.0, powers: false };
        assert_eq!((axis.label(-1.0), axis.label(2.0), axis.label(0.5)), ("0.1".into(), "100".into(), String::new()));
        assert_eq!(axis.map(0.0), -1.0);
    }
}
