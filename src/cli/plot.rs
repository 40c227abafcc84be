//! `stickslip plot`: redraws a sweep's or a diagnosis's figures from its
//! output directory, without simulating.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::emit;
use crate::diagnose::report::{ChartData, write_charts};
use crate::engine::model::fmt_value;
use crate::figure::SizePreset;
use crate::io::{OutputSet, owned, write_atomically};
use crate::measure::read_measurement_set;
use crate::sweep::plot::{AmplitudeAxis, PlotOptions, loads, measured_points, pair, write_sweep_plots_with};
use crate::sweep::read_accumulators;
use crate::text::{excerpt, shown};

#[derive(Args, Debug)]
pub(crate) struct PlotArgs {
    /// A sweep or merge output directory (read from its verified accumulators.json) or a diagnosis
    /// output directory (read from its scores.csv and report.json).
    pub(crate) dir: PathBuf,
    /// Where the figures go (created if needed); by default they replace the ones in DIR.
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// A measurement set (a directory with manifest.json) whose statistics are drawn over Figures 8 and 9:
    /// summary rows as mean ± standard error, records as their per-period peaks.
    #[arg(long, value_name = "DIR")]
    pub(crate) measured: Option<PathBuf>,
    /// What the measured data are called in the legends.
    #[arg(long, default_value = "measured", value_name = "TEXT")]
    pub(crate) measured_label: String,
    /// Figure size: screen (1000 px), single or double journal column at 300 dpi, or a 16:9 slide.
    #[arg(long, value_enum, default_value = "screen")]
    pub(crate) size: SizeArg,
    /// Frequency (Hz) whose points Figure 8 shows (the nearest grid frequency).
    #[arg(long, default_value_t = 7.0, allow_negative_numbers = true)]
    pub(crate) fig8_frequency: f64,
    /// Figure 9(a)'s amplitude axis: log when the values span more than 30×, else linear (auto); always log;
    /// or linear from zero, the paper's view.
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) amplitude_axis: AxisArg,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum AxisArg {
    /// Log when the values span more than a factor of 30, else linear from zero.
    Auto,
    /// Logarithmic.
    Log,
    /// Linear from zero, as the paper draws Figure 9(a).
    Linear,
}

impl From<AxisArg> for AmplitudeAxis {
    fn from(a: AxisArg) -> Self {
        match a {
            AxisArg::Auto => AmplitudeAxis::Auto,
            AxisArg::Log => AmplitudeAxis::Log,
            AxisArg::Linear => AmplitudeAxis::Linear,
        }
    }
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum SizeArg {
    /// 1000 px wide, for a screen.
    Screen,
    /// One journal column (3.5 in at 300 dpi).
    Single,
    /// Two journal columns (7.2 in at 300 dpi).
    Double,
    /// A 16:9 slide (1920 × 1080).
    Slide,
}

impl From<SizeArg> for SizePreset {
    fn from(s: SizeArg) -> Self {
        match s {
            SizeArg::Screen => SizePreset::Screen,
            SizeArg::Single => SizePreset::Single,
            SizeArg::Double => SizePreset::Double,
            SizeArg::Slide => SizePreset::Slide,
        }
    }
}

pub(crate) fn run_plot(args: PlotArgs) -> Result<()> {
    super::check_fig8_frequency(args.fig8_frequency)?;
    let kind = if args.dir.join("accumulators.json").is_file() {
        "sweep"
    } else if args.dir.join("report.json").is_file() {
        if args.measured.is_some() {
            anyhow::bail!("invalid --measured: a diagnosis already compares with its measurement set");
        }
        "diagnosis"
    } else if !args.dir.is_dir() {
        anyhow::bail!("{}: no such directory (give a sweep's or a diagnosis's output directory)", shown(&args.dir));
    } else {
        anyhow::bail!(
            "{}: neither a sweep output directory (accumulators.json) nor a diagnosis output directory (report.json)",
            shown(&args.dir)
        );
    };
    // The figures replace those of the set in place (the whole set swapped
    // in, as a sweep's is), or go into a directory of their own: a new or
    // empty one, or one that holds figures of the same kind and source.
    let source = std::fs::canonicalize(&args.dir).map_err(|e| anyhow::anyhow!("{}: {e}", shown(&args.dir)))?;
    let out = args.out.clone().unwrap_or_else(|| args.dir.clone());
    let in_place = std::fs::canonicalize(&out).is_ok_and(|o| o == source);
    let set = if in_place {
        let set =
            OutputSet::prepare(&out, "--out", if kind == "sweep" { owned::SWEEP } else { owned::DIAGNOSIS }, &[])?;
        set.carry_over(owned::PLOT)?;
        set
    } else {
        let set = OutputSet::prepare(&out, "--out", owned::PLOT, &[args.dir.as_path()])?;
        check_plot_source(&out, kind, &source)?;
        set
    };
    let mut files = if kind == "sweep" {
        let (_, result) = read_accumulators(&args.dir)?;
        let measured = match &args.measured {
            Some(dir) => {
                let points = measured_points(&read_measurement_set(dir)?);
                if points.is_empty() {
                    anyhow::bail!("invalid --measured {}: the set has no peak statistics to draw", shown(dir));
                }
                let forces = loads(&result);
                for p in &points {
                    let on_grid = result.conditions.iter().any(|c| p.matches(c));
                    if !on_grid {
                        let against = match pair(&forces, p) {
                            Some(q) if !q.same_load => {
                                format!("against the nearest simulated load {} N", fmt_value(q.force_n))
                            }
                            _ => "against its load's curve".to_string(),
                        };
                        super::info(&format!(
                            "note: the measured condition {} Hz, {} N is not a grid point: drawn in Figure 9 {against}, \
                             not in Figure 8",
                            fmt_value(p.excitation_frequency_hz),
                            fmt_value(p.normal_force_n)
                        ));
                    }
                }
                points
            }
            None => Vec::new(),
        };
        super::note_fig8_frequency(args.fig8_frequency, result.conditions.iter().map(|c| c.excitation_frequency_hz));
        let opts = PlotOptions {
            fig8_frequency_hz: args.fig8_frequency,
            size: args.size.into(),
            measured: &measured,
            measured_label: &args.measured_label,
            amplitude_axis: args.amplitude_axis.into(),
        };
        write_sweep_plots_with(set.dir(), &result, &opts)?
    } else {
        write_charts(set.dir(), &ChartData::read(&args.dir)?)?
    };
    let names: Vec<String> =
        files.iter().filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned())).collect();
    if !in_place {
        let record = serde_json::json!({
            "format": PLOT_FORMAT,
            "kind": kind,
            "source": source.to_string_lossy(),
            "files": names,
        });
        files.push(set.dir().join("plot.json"));
        write_atomically(&set.dir().join("plot.json"), |w| {
            serde_json::to_writer_pretty(&mut *w, &record)?;
            writeln!(w)
        })?;
    }
    set.commit()?;
    emit(&format!("wrote {} to {}", names.join(", "), out.display()))?;
    Ok(())
}

/// The format tag of `plot.json`.
const PLOT_FORMAT: &str = "stickslip-plot/1";

/// Refuses `out` (being replaced by `plot --out`) unless it is missing or
/// empty, or its `plot.json` says it holds figures of a `kind` set at
/// `source` (the canonical path): figures of two runs never mix.
fn check_plot_source(out: &Path, kind: &str, source: &Path) -> Result<()> {
    let has_entries = std::fs::read_dir(out)
        .map(|entries| entries.flatten().any(|e| !e.file_name().to_string_lossy().starts_with('.')))
        .unwrap_or(false);
    if !has_entries {
        return Ok(());
    }
    let record = out.join("plot.json");
    let bytes = crate::io::read_bounded(&record, crate::io::MAX_MANIFEST_BYTES).map_err(|e| {
        anyhow::anyhow!(
            "invalid --out: `{}` holds figures but no readable plot.json naming their source ({e}); plot replaces \
             only figures it drew from the same source (choose a new or empty directory)",
            shown(out)
        )
    })?;
    let value: serde_json::Value = crate::io::parse_json(&bytes)
        .map_err(|e| anyhow::anyhow!("{}: not a plot record: {}", shown(&record), excerpt(&e.to_string(), 160)))?;
    let (their_kind, their_source) =
        (value.get("kind").and_then(|k| k.as_str()), value.get("source").and_then(|s| s.as_str()));
    if value.get("format").and_then(|f| f.as_str()) != Some(PLOT_FORMAT)
        || their_kind != Some(kind)
        || their_source != Some(&*source.to_string_lossy())
    {
        anyhow::bail!(
            "invalid --out: `{}` holds the figures of {} `{}`, not of this {kind} (`{}`); plot replaces only \
             figures of the same kind and source (choose a new or empty directory)",
            shown(out),
            their_kind.map_or("an unknown set".to_string(), |k| format!("the {}", excerpt(k, 20))),
            excerpt(their_source.unwrap_or("?"), 200),
            shown(source)
        );
    }
    Ok(())
}
