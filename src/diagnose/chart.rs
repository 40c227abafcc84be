//! The report's charts, drawn from the per-unit scores (which `diagnose`
//! also writes as `scores.csv`, so `stickslip plot` can redraw them):
//! - `gap`: the worst observables' |z| under the calibrated baseline and
//!   under the fitted model, one labelled row each;
//! - `comparison`: the mean peak amplitude per condition, measured against
//!   the baseline and the fitted model, in mm, with the simulator's spread.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use crate::diagnose::Diagnosis;
use crate::diagnose::observable::{Observable, Unit};
use crate::error::{Error, Result};
use crate::figure::{FONT, colour, decade_tick, legend_box, plot_error, render, tick};

/// One scored (condition, observable) unit: the measured value and what the
/// baseline and the fitted model simulate, in the observable's unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScoreRow {
    pub excitation_frequency_hz: f64,
    pub normal_force_n: f64,
    pub observable: String,
    pub heldout: bool,
    pub measured: f64,
    pub baseline_simulated: f64,
    pub baseline_z: f64,
    pub fitted_simulated: Option<f64>,
    pub fitted_z: Option<f64>,
}

impl ScoreRow {
    /// The spread of measured − simulated (|difference| / |z|), in the
    /// observable's unit; `None` where z is 0.
    pub fn spread(&self) -> Option<f64> {
        let s = (self.measured - self.baseline_simulated).abs() / self.baseline_z.abs();
        (self.baseline_z != 0.0 && s.is_finite()).then_some(s)
    }

    fn fitted_spread(&self) -> Option<f64> {
        let (sim, z) = (self.fitted_simulated?, self.fitted_z?);
        let s = (self.measured - sim).abs() / z.abs();
        (z != 0.0 && s.is_finite()).then_some(s).or_else(|| self.spread())
    }

    /// What makes this row one no diagnosis writes, naming the column: a
    /// condition outside the ranges a measurement set is read with, an
    /// unknown observable, a number that is not finite, or a measured value
    /// outside the range its unit allows in a measurement set (lengths within
    /// ±10 m, squared lengths 0 to 100 m², angles within ±360°, squared
    /// angles 0 to 360² °², counts not negative). `None` for a plausible row.
    pub fn implausible(&self) -> Option<String> {
        use crate::engine::model::limits;
        let (f_lo, f_hi) = limits::FREQUENCY_HZ;
        let f = self.excitation_frequency_hz;
        if !(f_lo..=f_hi).contains(&f) {
            return Some(format!("column `excitation_frequency_hz`: {f} Hz is outside {f_lo} to {f_hi} Hz"));
        }
        let n = self.normal_force_n;
        if !(0.0..=limits::FORCE_MAX_N).contains(&n) {
            return Some(format!("column `normal_force_n`: {n} N is outside 0 to {} N", limits::FORCE_MAX_N));
        }
        let Some(observable) = Observable::named(&self.observable) else {
            return Some(format!(
                "column `observable`: `{}` is not an observable a diagnosis scores",
                crate::text::excerpt(&self.observable, crate::text::EXCERPT_CHARS)
            ));
        };
        let numbers = [
            ("measured", Some(self.measured)),
            ("baseline_simulated", Some(self.baseline_simulated)),
            ("baseline_z", Some(self.baseline_z)),
            ("fitted_simulated", self.fitted_simulated),
            ("fitted_z", self.fitted_z),
        ];
        if let Some((column, value)) = numbers.iter().find_map(|&(c, v)| v.filter(|v| !v.is_finite()).map(|v| (c, v))) {
            return Some(format!("column `{column}`: {value} is not a finite number"));
        }
        let (x, p) = (limits::DISPLACEMENT_MAX_M, limits::PHASE_MAX_DEG);
        let (lo, hi, range) = match observable.unit() {
            Unit::Metre => (-x, x, format!("within ±{x} m")),
            Unit::SquareMetre => (0.0, x * x, format!("from 0 to {} m²", x * x)),
            Unit::Degree => (-p, p, format!("within ±{p} degrees")),
            Unit::SquareDegree => (0.0, p * p, format!("from 0 to {p}² degrees²")),
            Unit::Count => (0.0, f64::INFINITY, "not negative".to_string()),
            _ => return None,
        };
        let m = self.measured;
        (!(lo..=hi).contains(&m)).then(|| {
            format!("column `measured`: {m} is not a plausible {} (a measured one lies {range})", observable.name())
        })
    }

    fn label(&self) -> String {
        let observable: &str = match Observable::named(&self.observable) {
            Some(o) => o.label(),
            None => &self.observable,
        };
        format!(
            "{} at {} Hz, {} N{}",
            observable,
            tick((self.excitation_frequency_hz * 100.0).round() / 100.0),
            tick((self.normal_force_n * 100.0).round() / 100.0),
            if self.heldout { " (held out)" } else { "" }
        )
    }
}

/// What the charts draw: the verdict's name and every scored unit.
#[derive(Clone, Debug, PartialEq)]
pub struct ChartData {
    pub verdict: String,
    pub rows: Vec<ScoreRow>,
}

impl ChartData {
    pub fn from_diagnosis(d: &Diagnosis) -> ChartData {
        let rows = d
            .baseline_scores
            .iter()
            .map(|s| {
                let fitted = d.fitted_scores.iter().find(|f| {
                    f.observable == s.observable
                        && f.excitation_frequency_hz == s.excitation_frequency_hz
                        && f.normal_force_n == s.normal_force_n
                        && f.heldout == s.heldout
                });
                ScoreRow {
                    excitation_frequency_hz: s.excitation_frequency_hz,
                    normal_force_n: s.normal_force_n,
                    observable: s.observable.name().to_string(),
                    heldout: s.heldout,
                    measured: s.measured,
                    baseline_simulated: s.simulated,
                    baseline_z: s.z,
                    fitted_simulated: fitted.map(|f| f.simulated),
                    fitted_z: fitted.map(|f| f.z),
                }
            })
            .collect();
        ChartData { verdict: d.verdict_names(), rows }
    }

    /// Writes the rows as `scores.csv`.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        crate::io::write_atomically(path, |w| {
            let mut csv = csv::Writer::from_writer(w);
            for row in &self.rows {
                csv.serialize(row).map_err(std::io::Error::other)?;
            }
            csv.flush()
        })
    }

    /// Reads `DIR/scores.csv` and the verdict of `DIR/report.json`.
    pub fn read(dir: &Path) -> Result<ChartData> {
        let path = dir.join("scores.csv");
        let refuse = |line: Option<u64>, message: String| Error::Measurement { file: path.clone(), line, message };
        let bytes = crate::io::read_bounded(&path, 256 << 20).map_err(|e| {
            refuse(
                None,
                format!("cannot read it ({e}); a diagnosis written before scores.csv existed cannot be redrawn"),
            )
        })?;
        let mut rows = Vec::new();
        for (i, row) in csv::Reader::from_reader(bytes.as_slice()).deserialize::<ScoreRow>().enumerate() {
            let line = Some(i as u64 + 2);
            let row = row.map_err(|e| refuse(line, e.to_string()))?;
            row.implausible().map_or(Ok(()), |problem| Err(refuse(line, problem)))?;
            rows.push(row);
        }
        let report_path = dir.join("report.json");
        let bad_report = |message: String| Error::Measurement { file: report_path.clone(), line: None, message };
        let bytes = crate::io::read_bounded(&report_path, 256 << 20)
            .map_err(|e| bad_report(format!("cannot read the diagnosis's report ({e})")))?;
        let report: serde_json::Value =
            crate::io::parse_json(&bytes).map_err(|e| bad_report(format!("not a diagnosis report: {e}")))?;
        let named = report
            .pointer("/verdict/effects")
            .and_then(|e| e.as_array())
            .filter(|e| !e.is_empty())
            .map(|e| e.iter().filter_map(|x| x.get("effect")?.as_str()).collect::<Vec<_>>().join(" + "));
        let verdict = named
            .or_else(|| report.pointer("/verdict/effect").and_then(|e| e.as_str()).map(str::to_string))
            .ok_or_else(|| bad_report("not a diagnosis report: it has no verdict.effect".into()))?;
        Ok(ChartData { verdict, rows })
    }

    /// The worst units under the baseline, largest |z| first (at most `n`).
    fn worst(&self, n: usize) -> Vec<&ScoreRow> {
        let mut worst: Vec<&ScoreRow> = self.rows.iter().filter(|r| r.baseline_z.is_finite()).collect();
        worst.sort_by(|a, b| b.baseline_z.abs().total_cmp(&a.baseline_z.abs()));
        worst.truncate(n);
        worst
    }

    /// The peak-mean units, one per condition (the first scored), by frequency then force.
    fn peak_means(&self) -> Vec<&ScoreRow> {
        let mut rows: Vec<&ScoreRow> = Vec::new();
        for r in self.rows.iter().filter(|r| r.observable == "peak_mean_m" && r.measured.is_finite()) {
            if !rows
                .iter()
                .any(|q| q.excitation_frequency_hz == r.excitation_frequency_hz && q.normal_force_n == r.normal_force_n)
            {
                rows.push(r);
            }
        }
        rows.sort_by(|a, b| {
            a.excitation_frequency_hz
                .total_cmp(&b.excitation_frequency_hz)
                .then(a.normal_force_n.total_cmp(&b.normal_force_n))
        });
        rows.truncate(MAX_COMPARISON_CONDITIONS);
        rows
    }
}

/// Rows of the gap chart.
const GAP_ROWS: usize = 12;
/// The gap chart's |z| axis ends at 10^this at most, –.
const GAP_AXIS_DECADES: f64 = 12.0;
/// Conditions of the comparison chart.
const MAX_COMPARISON_CONDITIONS: usize = 24;
/// The chart's width, px.
const WIDTH: u32 = 1000;

/// Approximate width of `text` at `size` px of DejaVu Sans.
fn text_width(text: &str, size: u32) -> u32 {
    (text.chars().count() as f64 * f64::from(size) * 0.56).ceil() as u32
}

/// Empty rows above the bars, where the legend goes.
const LEGEND_ROWS: f64 = 2.0;

fn gap_height(d: &ChartData) -> u32 {
    110 + (40.0 * (d.worst(GAP_ROWS).len().max(1) as f64 + LEGEND_ROWS)) as u32
}

/// Horizontal bars, one row per unit, its label in full on the left; |z| on
/// a log axis; the dashed line at |z| = 3 is where a departure starts.
fn gap_chart<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, d: &ChartData) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("gap", e);
    let worst = d.worst(GAP_ROWS);
    let labels: Vec<String> = worst.iter().map(|r| r.label()).collect();
    let label_area = labels.iter().map(|l| text_width(l, 13)).max().unwrap_or(100).clamp(100, WIDTH / 2) + 16;
    let n = worst.len().max(1);
    let z_max = worst
        .iter()
        .flat_map(|r| [r.baseline_z.abs(), r.fitted_z.map_or(0.0, f64::abs)])
        .filter(|z| z.is_finite())
        .fold(3.0, f64::max);
    // The axis ends at a whole decade above the worst |z|, and no further
    // than 10^GAP_AXIS_DECADES: a larger |z| (a score file may hold up to
    // 1e308) is drawn to the axis' end rather than overflowing it.
    let hi = 10f64.powf((z_max * 1.5).log10().ceil().min(GAP_AXIS_DECADES));
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("|z| of the worst observables: calibrated baseline vs fitted ({})", d.verdict), (FONT, 18))
        .margin(12)
        .margin_right(24)
        .x_label_area_size(44)
        .y_label_area_size(label_area)
        .build_cartesian_2d((0.1..hi).log_scale(), 0.0..n as f64 + LEGEND_ROWS)
        .map_err(e)?;
    let to_row = |y: f64| n as f64 - 0.5 - y;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(2 * (n + LEGEND_ROWS as usize) + 1)
        .y_label_formatter(&|y| {
            let i = to_row(*y).round();
            if (to_row(*y) - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .x_label_formatter(&|x| {
            let t = decade_tick(*x);
            if t.is_empty() { t } else { tick(*x) }
        })
        .x_desc("|z| = |measured − simulated| / simulator's spread (log scale)")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(e)?;
    let bar = |i: usize, z: f64, upper: bool| {
        let top = n as f64 - i as f64 - if upper { 0.1 } else { 0.5 };
        [(0.1, top - 0.4), (z.abs().clamp(0.1, hi), top)]
    };
    chart
        .draw_series(
            worst.iter().enumerate().map(|(i, r)| Rectangle::new(bar(i, r.baseline_z, true), colour(1).filled())),
        )
        .map_err(e)?
        .label("calibrated baseline")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour(1).filled()));
    chart
        .draw_series(
            worst
                .iter()
                .enumerate()
                .filter_map(|(i, r)| Some(Rectangle::new(bar(i, r.fitted_z?, false), colour(0).filled()))),
        )
        .map_err(e)?
        .label(format!("fitted ({})", d.verdict))
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour(0).filled()));
    chart
        .draw_series(DashedLineSeries::new(
            vec![(3.0, 0.0), (3.0, n as f64 + LEGEND_ROWS)],
            6,
            4,
            BLACK.stroke_width(1),
        ))
        .map_err(e)?
        .label("|z| = 3: beyond it, a departure from the data")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], BLACK.stroke_width(1)));
    legend_box(&mut chart, 13, SeriesLabelPosition::UpperRight, "gap")
}

/// Measured, baseline and fitted mean peak per condition (mm); the bars on
/// the simulated values are ± the simulator's spread of the difference.
fn comparison_chart<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, d: &ChartData) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("comparison", e);
    let rows = d.peak_means();
    let n = rows.len().max(1);
    let mm = |v: f64| v * 1e3;
    let mut values = Vec::new();
    for r in &rows {
        let s = r.spread().unwrap_or(0.0);
        values.extend([mm(r.measured), mm(r.baseline_simulated - s), mm(r.baseline_simulated + s)]);
        if let Some(f) = r.fitted_simulated {
            let s = r.fitted_spread().unwrap_or(0.0);
            values.extend([mm(f - s), mm(f + s)]);
        }
    }
    let values: Vec<f64> = values.into_iter().filter(|v| v.is_finite()).collect();
    let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
    let (lo, hi) = if lo < hi {
        let pad = 0.08 * (hi - lo);
        (lo - pad, hi + pad)
    } else if lo.is_finite() {
        (lo - 0.5, lo + 0.5)
    } else {
        (0.0, 1.0)
    };
    let labels: Vec<String> = rows
        .iter()
        .map(|r| {
            format!(
                "{} Hz, {} N",
                tick((r.excitation_frequency_hz * 100.0).round() / 100.0),
                tick((r.normal_force_n * 100.0).round() / 100.0)
            )
        })
        .collect();
    let rotate = n > 6;
    let x_area = if rotate { labels.iter().map(|l| text_width(l, 12)).max().unwrap_or(60) + 40 } else { 50 };
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("Mean peak amplitude per condition: measured, baseline and fitted ({})", d.verdict),
            (FONT, 18),
        )
        .margin(12)
        .margin_right(24)
        .x_label_area_size(x_area)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5..n as f64 - 0.5, lo..hi)
        .map_err(e)?;
    let label_style = if rotate {
        (FONT, 12).into_font().transform(FontTransform::Rotate90).into_text_style(&root)
    } else {
        (FONT, 13).into_font().into_text_style(&root)
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n + 1)
        .x_label_formatter(&|x| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_label_formatter(&|y| tick(*y))
        .y_labels(8)
        .light_line_style(BLACK.mix(0.04))
        .x_label_style(label_style)
        .y_label_style((FONT, 13))
        .y_desc("mean peak amplitude (mm)")
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(e)?;
    let black = BLACK;
    chart
        .draw_series(
            rows.iter().enumerate().map(|(i, r)| Circle::new((i as f64 - 0.22, mm(r.measured)), 6, black.filled())),
        )
        .map_err(e)?
        .label("measured")
        .legend(move |(x, y)| Circle::new((x + 7, y), 6, black.filled()));
    let red = colour(1);
    let blue = colour(0);
    let square =
        |x: f64, v: f64, c: RGBColor| EmptyElement::at((x, mm(v))) + Rectangle::new([(-5, -5), (5, 5)], c.filled());
    chart.draw_series(rows.iter().enumerate().map(|(i, r)| square(i as f64, r.baseline_simulated, red))).map_err(e)?;
    chart
        .draw_series(
            rows.iter().enumerate().filter_map(|(i, r)| Some(square(i as f64 + 0.22, r.fitted_simulated?, blue))),
        )
        .map_err(e)?;
    chart
        .draw_series(rows.iter().enumerate().map(|(i, r)| {
            let s = r.spread().unwrap_or(0.0);
            let v = r.baseline_simulated;
            ErrorBar::new_vertical(i as f64, mm(v - s), mm(v), mm(v + s), red.stroke_width(2), 10)
        }))
        .map_err(e)?
        .label("calibrated baseline ± spread")
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], red.filled()));
    chart
        .draw_series(rows.iter().enumerate().filter_map(|(i, r)| {
            let v = r.fitted_simulated?;
            let s = r.fitted_spread().unwrap_or(0.0);
            Some(ErrorBar::new_vertical(i as f64 + 0.22, mm(v - s), mm(v), mm(v + s), blue.stroke_width(2), 10))
        }))
        .map_err(e)?
        .label(format!("fitted ({}) ± spread", d.verdict))
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], blue.filled()));
    legend_box(&mut chart, 13, SeriesLabelPosition::UpperRight, "comparison")
}

fn comparison_height(d: &ChartData) -> u32 {
    let rotate = d.peak_means().len() > 6;
    if rotate { 620 } else { 500 }
}

/// Writes `gap.png`/`gap.svg` and, when the set has mean peaks,
/// `comparison.png`/`comparison.svg`; returns the files.
pub fn write_charts(dir: &Path, d: &ChartData) -> Result<Vec<PathBuf>> {
    let mut files = render(dir, "gap", (WIDTH, gap_height(d)), &|r| gap_chart(r, d), &|r| gap_chart(r, d))?;
    if !d.peak_means().is_empty() {
        files.extend(render(dir, "comparison", (WIDTH, comparison_height(d)), &|r| comparison_chart(r, d), &|r| {
            comparison_chart(r, d)
        })?);
    }
    Ok(files)
}

/// Writes the charts of a diagnosis and its `scores.csv`.
pub(crate) fn write_gap_chart(dir: &Path, d: &Diagnosis) -> Result<Vec<PathBuf>> {
    let data = ChartData::from_diagnosis(d);
    data.write_csv(&dir.join("scores.csv"))?;
    let mut files = write_charts(dir, &data)?;
    files.push(dir.join("scores.csv"));
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A score file may hold any finite z; one near f64's largest drew an
    /// axis that overflowed to infinity (and never finished). The chart
    /// ends its axis at 10^GAP_AXIS_DECADES and draws such a bar to it.
    #[test]
    fn a_vast_z_is_drawn_to_the_axis_end() {
        let row = |observable: &str, z: f64| ScoreRow {
            excitation_frequency_hz: 7.0,
            normal_force_n: 10.0,
            observable: observable.to_string(),
            heldout: false,
            measured: 0.5,
            baseline_simulated: 0.4,
            baseline_z: z,
            fitted_simulated: Some(0.45),
            fitted_z: Some(-z),
        };
        let d = ChartData {
            verdict: "none".into(),
            rows: vec![row("peak_mean_m", 1e308), row("peak_var_m2", -1e308), row("phase_mean_deg", 2.0)],
        };
        let dir = std::env::temp_dir().join(format!("stickslip-vast-z-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary directory");
        let files = write_charts(&dir, &d).expect("the charts are drawn");
        assert!(files.iter().all(|f| f.exists()), "{files:?}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
