//! Reliability (issue 43): no number that is not what it claims to be, a
//! bounded cost for every input, output sets that never mix, ambiguity
//! refused, and messages that name the place and quote nothing raw.

use std::path::Path;

use stickslip::Error;
use stickslip::diagnose::report::Report;
use stickslip::engine::{Condition, Job, Model, PeakRange, Point, Record, RunPlan};
use stickslip::measure::read_measurement_set;
use stickslip::sweep::{SweepSettings, merge_shards, read_accumulators, run_sweep};

use crate::common;
use crate::hostile::{
    RIG, Scratch, forged, listing, manifest, measurement_refused, refused, run, run_csv, snapshot, stderr, sweep_args,
    write_summary_set,
};

/// A friction law strong enough to hold the block where its frictionless
/// start puts it, at 20 Hz: every peak lies below `−0.5 A`, outside the
/// range the point's histogram covers by default.
fn holding_law() -> Model {
    Model::paper_rig(&["friction.a=5".into()]).unwrap()
}

const HELD: Condition = Condition { excitation_frequency_hz: 20.0, normal_force_n: 16.39 };

/// Peaks far outside the default range: the point is run again over a range
/// that holds them, on either backend, and its mean, variance and quantiles
/// are those of the peaks themselves (not the range's edge).
#[test]
fn peaks_outside_the_range_give_exact_statistics() {
    let model = holding_law();
    let plan = RunPlan { warmup_cycles: 10, measured_cycles: 20 };
    let settings = SweepSettings { realisations: 4, plan, seed: 3 };
    let own = PeakRange::for_point(&model, HELD);
    for engine in [common::cpu(), common::gpu()] {
        let result = run_sweep(&model, &[HELD], &settings, engine, &mut |_, _| {}).unwrap();
        let a = &result.accumulators[0];
        assert_ne!(a.range, own, "the range was widened");
        assert_eq!((a.outside_range(), a.clamped), (0, 0));
        let points = [Point::steady(&model, HELD)];
        let job = Job {
            model: &model,
            points: &points,
            realisations: 4,
            first_realisation: 0,
            seed: 3,
            plan,
            record: Record::Peaks,
        };
        let mut peaks: Vec<f64> =
            engine.paths(&job).unwrap().iter().flat_map(|p| p.peaks_m.iter().map(|&x| f64::from(x as f32))).collect();
        assert!(peaks.iter().all(|&x| x < own.lo_m), "every peak lies below the default range");
        peaks.sort_by(f64::total_cmp);
        let n = peaks.len();
        let row = &result.rows()[0];
        let mean = peaks.iter().sum::<f64>() / n as f64;
        assert!((row.peak_mean_m - mean).abs() < 1e-12, "mean {} vs {mean}", row.peak_mean_m);
        let var = peaks.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        assert!((row.peak_var_m2 - var).abs() <= 1e-3 * var + 1e-24, "variance {} vs {var}", row.peak_var_m2);
        let bin = (a.range.hi_m - a.range.lo_m) / 2046.0;
        for (q, p) in [(row.peak_p05_m, 0.05), (row.peak_p50_m, 0.5), (row.peak_p95_m, 0.95)] {
            let exact = peaks[((p * n as f64) as usize).min(n - 1)];
            assert!((q - exact).abs() <= 2.0 * bin, "p{p}: {q} vs {exact} (bins of {bin} m)");
        }
    }
}

/// The command line: such a point is written with exact statistics and no
/// bin without edges, said on stderr and in sweep.json; shards with such a
/// point merge into the unsharded run byte for byte, and a forged widened
/// range is refused. A law the integrator cannot follow (peaks of metres
/// to kilometres) is refused, and nothing is written.
#[test]
fn widened_ranges_on_the_command_line() {
    let s = Scratch::new("widened");
    let whole = s.path("whole");
    let args =
        ["--set", "friction.a=5", "--frequencies", "7,20", "--normal-forces", "16.39", "--no-plots", "--no-refine"];
    let o = run(&sweep_args(whole.to_str().unwrap(), &args));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("widened_ranges"), "{}", stderr(&o));
    let histograms = std::fs::read_to_string(whole.join("histograms.csv")).unwrap();
    assert!(!histograms.contains("inf"), "{histograms}");
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("sweep.json")).unwrap()).unwrap();
    let widened = sidecar["widened_ranges"].as_array().unwrap();
    assert_eq!(widened.len(), 1, "{widened:?}");
    assert_eq!(widened[0]["excitation_frequency_hz"], 20.0);
    let mut shards = Vec::new();
    for k in 0..2 {
        let dir = s.path(&format!("shard-{k}"));
        let shard = format!("{k}/2");
        let mut shard_args = args.to_vec();
        shard_args.extend(["--shard", &shard]);
        let o = run(&sweep_args(dir.to_str().unwrap(), &shard_args));
        assert!(o.status.success(), "{}", stderr(&o));
        shards.push(dir);
    }
    let merged = s.path("merged");
    let o =
        run(&["merge", "--out", merged.to_str().unwrap(), shards[0].to_str().unwrap(), shards[1].to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["sweep.csv", "histograms.csv", "accumulators.json"] {
        assert_eq!(std::fs::read(whole.join(f)).unwrap(), std::fs::read(merged.join(f)).unwrap(), "{f}");
    }
    // A forged range (digest recomputed) is refused; so is a forged extreme.
    let forged_range = forged(&s, &shards[1], "forged-range", |f| f.points[0].range.lo_m *= 1.5);
    let err = merge_shards(&[shards[0].clone(), forged_range]).unwrap_err().to_string();
    assert!(err.contains("forged-range/accumulators.json") && err.contains("peak range"), "{err}");
    let forged_extreme = forged(&s, &shards[1], "forged-extreme", |f| {
        f.points[0].peak_extremes_m = f.points[0].peak_extremes_m.map(|(lo, hi)| (lo * 0.5, hi));
    });
    let err = merge_shards(&[shards[0].clone(), forged_extreme]).unwrap_err().to_string();
    assert!(err.contains("forged-extreme/accumulators.json"), "{err}");
    read_accumulators(&whole).expect("a widened range reads back");
    // A law too steep for the step: refused by name on either backend, nothing written.
    let out = s.path("unstable");
    let err = refused(
        &sweep_args(out.to_str().unwrap(), &["--set", "friction.d=1e6", "--frequencies", "7", "--no-plots"]),
        &["7 Hz, 10 N", "unstable", "solver.steps_per_period"],
    );
    assert!(!err.contains("inf"), "{err}");
    assert!(!out.exists());
    let model = Model::paper_rig(&["friction.d=1e6".into()]).unwrap();
    let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 10.0 };
    let settings = SweepSettings { realisations: 2, plan: RunPlan { warmup_cycles: 1, measured_cycles: 2 }, seed: 1 };
    let err = run_sweep(&model, &[condition], &settings, common::cpu(), &mut |_, _| {}).unwrap_err();
    assert!(matches!(err, Error::Diverged { .. }), "{err:?}");
}

/// A set with a summary table `rows` (after the header below).
fn summary_set(s: &Scratch, name: &str, rows: &str) -> std::path::PathBuf {
    let dir = s.path(name);
    write_summary_set(
        &dir,
        &format!(
            "excitation_frequency_hz,excitation_amplitude_m,normal_force_mean_n,peak_mean_m,peak_var_m2,\
             phase_mean_deg,n_peaks\n{rows}"
        ),
    );
    dir
}

/// A run file `r.csv` whose lines (after the header) are edited by `edit`.
fn run_set(s: &Scratch, name: &str, edit: impl Fn(usize, &str) -> String) -> std::path::PathBuf {
    let dir = s.path(name);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("manifest.json"), manifest("r.csv")).unwrap();
    let text: String = run_csv().lines().enumerate().map(|(i, l)| edit(i, l) + "\n").collect();
    std::fs::write(dir.join("r.csv"), text).unwrap();
    dir
}

/// Every number read is finite and physically plausible; the refusal names
/// the file, the line and the column, and a plausible set still reads.
#[test]
fn implausible_numbers_are_refused_by_file_line_and_column() {
    let s = Scratch::new("plausible");
    let good = "7,0.0025,16.39,0.0038,2.8e-8,45,350\n";
    read_measurement_set(&summary_set(&s, "good", good)).expect("a plausible summary reads");
    for (name, row, column) in [
        ("phase-720", "7,0.0025,16.39,0.0038,2.8e-8,720,350\n", "phase_mean_deg"),
        ("phase-900", "7,0.0025,16.39,0.0038,2.8e-8,-900,350\n", "phase_mean_deg"),
        ("phase-360", "7,0.0025,16.39,0.0038,2.8e-8,-360,350\n", "phase_mean_deg"),
        ("negative-mean", "7,0.0025,16.39,-0.0038,2.8e-8,45,350\n", "peak_mean_m"),
        ("huge-mean", "7,0.0025,16.39,1e10,2.8e-8,45,350\n", "peak_mean_m"),
        ("huge-variance", "7,0.0025,16.39,0.0038,1e300,45,350\n", "peak_var_m2"),
    ] {
        let err = measurement_refused(&summary_set(&s, name, &format!("{good}{row}")), &["s.csv:3", column]);
        assert!(err.len() < 300, "{err}");
    }
    // The phase range is (−360°, 360°]: 360 and 0 read.
    read_measurement_set(&summary_set(
        &s,
        "phase-edges",
        "7,0.0025,16.39,0.0038,2.8e-8,360,350\n7,0.0025,10,0.004,2.8e-8,0,350\n",
    ))
    .expect("360 and 0 degrees read");
    // Run files: a displacement scaled by 1e300, a negative measured normal
    // force, an absurd speed or friction force; the header is line 1.
    let scaled = run_set(&s, "scaled", |i, l| {
        if i == 0 {
            return l.to_string();
        }
        let mut f: Vec<String> = l.split(',').map(str::to_string).collect();
        f[1] = format!("{:e}", f[1].parse::<f64>().unwrap() * 1e300);
        f.join(",")
    });
    measurement_refused(&scaled, &["r.csv:2", "column `x`", "10 m"]);
    let negative = run_set(&s, "negative-force", |i, l| if i >= 40 { l.replace(",16,", ",-16,") } else { l.into() });
    let err = measurement_refused(&negative, &["r.csv:41", "column `normal_force`", "negative"]);
    assert!(err.contains("mean"), "{err}");
    // A sample below zero with the sensor's noise, beside a positive mean, reads.
    let noisy = run_set(&s, "noisy-force", |i, l| if i == 40 { l.replace(",16,", ",-0.03,") } else { l.into() });
    read_measurement_set(&noisy).expect("a noisy sample below zero reads");
    let fast = run_set(&s, "fast", |i, l| {
        if i == 7 { format!("{},-1e9", l.rsplit_once(',').map_or(l, |(head, _)| head)) } else { l.into() }
    });
    measurement_refused(&fast, &["r.csv:8", "column `friction_force`"]);
    // The command line refuses the same before any work, writing nothing.
    let out = s.path("out");
    refused(
        &["diagnose", "--backend", "cpu", negative.to_str().unwrap(), "--out", out.to_str().unwrap()],
        &["r.csv:41", "normal_force"],
    );
    assert!(!out.exists());
    // A rig inside the manifest's ranges that no step count can integrate
    // at the run's frequency is refused by the manifest and its key.
    let stiff = run_set(&s, "stiff-rig", |_, l| l.into());
    let text = std::fs::read_to_string(stiff.join("manifest.json")).unwrap();
    std::fs::write(
        stiff.join("manifest.json"),
        text.replace("\"natural_frequency_hz\": 10.05", "\"natural_frequency_hz\": 1e6"),
    )
    .unwrap();
    refused(
        &["diagnose", "--backend", "cpu", stiff.to_str().unwrap(), "--out", out.to_str().unwrap()],
        &["manifest.json", "`rig.natural_frequency_hz`", "steps per period"],
    );
    assert!(!out.exists());
}

/// A report never holds a number that is not finite: one with an infinite
/// or NaN gap is refused before anything is written.
#[test]
fn a_report_with_a_number_that_is_not_finite_is_refused() {
    let text = r#"{ "format": "stickslip-diagnosis/1",
        "verdict": { "effect": "none", "confidence": 0.5 },
        "gap": { "metric": "m", "baseline": 1.5, "after": 1.2, "shrink": 0.2, "heldout_shrink": null,
                 "heldout_baseline": null, "heldout_after": null, "noise_threshold": 0.4 },
        "locations": [], "candidates": [],
        "models": { "baseline": "baseline-model.toml", "fitted": "fitted-model.toml" },
        "source": "set", "elapsed_s": 1.0 }"#;
    let report: Report = serde_json::from_str(text).unwrap();
    report.check_numbers().expect("a finite report passes");
    // Numbers that do not exist (nothing held out) are left out, not null.
    let written = serde_json::to_string(&report).unwrap();
    assert!(!written.contains("\"heldout_shrink\"") && !written.contains("\"heldout_after\""), "{written}");
    assert!(!written.contains(": null") && !written.contains(":null,\"heldout"), "{written}");
    let mut bad = report.clone();
    bad.gap.baseline = f64::INFINITY;
    let err = bad.check_numbers().unwrap_err().to_string();
    assert!(err.contains("not finite") && err.contains("nothing was written"), "{err}");
    let mut bad = report.clone();
    bad.gap.heldout_shrink = Some(f64::NAN);
    assert!(bad.check_numbers().is_err());
    let mut bad = report;
    bad.verdict.confidence = f64::NAN;
    assert!(bad.check_numbers().is_err());
}

/// Work beyond the budget is refused before it starts, saying the estimate
/// and the limit; `--force` runs it. A noise interval of 1e-9 s is 1.4e8
/// steps per period at 7 Hz, whatever the run's size.
#[test]
fn work_beyond_the_budget_is_refused_unless_forced() {
    let s = Scratch::new("budget");
    let out = s.path("out");
    let out_s = out.to_str().unwrap();
    let started = std::time::Instant::now();
    let tiny_noise = ["--set", "noise.interval_s=1e-9", "--no-plots", "--no-refine"];
    refused(&sweep_args(out_s, &tiny_noise), &["per period", "2097152", "realisation-steps", "--force"]);
    refused(
        &["simulate", "--set", "noise.interval_s=1e-9", "--duration", "2", "--warmup-cycles", "1", "--out", out_s],
        &["simulate", "per period", "--force"],
    );
    refused(
        &sweep_args(out_s, &["--realisations", "100000", "--cycles", "40000", "--no-plots"]),
        &["estimated", "realisation-steps", "over the limit of 1e11", "--force"],
    );
    refused(
        &sweep_args(
            out_s,
            &["--warmup-cycles", "16000000", "--frequencies", "5:15:41", "--normal-forces", "4,8,12,16"],
        ),
        &["refinement", "--no-refine", "--force"],
    );
    let figure8 = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/figure8");
    refused(
        &["diagnose", "--backend", "cpu", figure8.to_str().unwrap(), "--realisations", "1000000", "--out", out_s],
        &["diagnose", "estimated", "--force"],
    );
    assert!(started.elapsed() < std::time::Duration::from_secs(20), "refusals come before any work");
    assert_eq!(listing(&s.0), Vec::<String>::new(), "a refused run writes nothing");
    // --force runs what the budget refuses (here three periods of one
    // realisation at 100 Hz, one of warm-up and the two a variance needs,
    // with 1e7 noise intervals each: a few seconds).
    let forced = [
        "--set",
        "noise.interval_s=1e-9",
        "--frequencies",
        "100",
        "--realisations",
        "1",
        "--cycles",
        "2",
        "--no-plots",
        "--no-refine",
    ];
    refused(&sweep_args(out_s, &forced), &["per period"]);
    let mut args = sweep_args(out_s, &forced);
    args.push("--force");
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `benchmark-diagnosis` goes through the budget too: a benchmark of long,
/// many records is refused before any set is generated, and nothing is
/// written.
#[test]
fn a_benchmark_beyond_the_budget_is_refused() {
    let s = Scratch::new("benchmark-budget");
    let out = s.path("out");
    let started = std::time::Instant::now();
    refused(
        &[
            "benchmark-diagnosis",
            "--backend",
            "cpu",
            "--out",
            out.to_str().unwrap(),
            "--duration",
            "600",
            "--runs-per-condition",
            "20",
        ],
        &["benchmark-diagnosis", "estimated", "realisation-steps", "--runs-per-condition", "--force"],
    );
    assert!(started.elapsed() < std::time::Duration::from_secs(20), "the refusal comes before any work");
    assert_eq!(listing(&s.0), Vec::<String>::new(), "a refused benchmark writes nothing");
}

/// `plot` reads a diagnosis's `scores.csv` as strictly as a measurement set:
/// a number that is not finite, a condition or a measured value outside the
/// ranges a set is read with, or an unknown observable is refused by file,
/// line and column, and no figure is drawn.
#[test]
fn implausible_scores_are_refused_by_plot() {
    let s = Scratch::new("scores");
    let header = "excitation_frequency_hz,normal_force_n,observable,heldout,measured,baseline_simulated,\
                  baseline_z,fitted_simulated,fitted_z\n";
    let good = "7,16.39,peak_mean_m,false,0.002,0.0021,-0.5,0.00201,-0.1\n";
    let diagnosis = |name: &str, rows: &str| {
        s.write(&format!("{name}/report.json"), r#"{"verdict": {"effect": "none"}}"#);
        s.write(&format!("{name}/scores.csv"), format!("{header}{good}{rows}"));
        s.path(name)
    };
    let plain = diagnosis("plain", "7,16.39,phase_mean_deg,true,-20.5,-21,0.4,,\n");
    let figs = s.path("figs");
    let o = run(&["plot", plain.to_str().unwrap(), "--out", figs.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(listing(&figs).contains(&"comparison.png".to_string()), "{:?}", listing(&figs));
    let cases: [(&str, &[&str]); 7] = [
        ("7,16.39,peak_mean_m,false,0.002,0.0021,inf,0.002,0.1", &["column `baseline_z`", "not a finite"]),
        ("7,16.39,peak_mean_m,false,0.002,NaN,0.5,0.002,0.1", &["column `baseline_simulated`", "not a finite"]),
        ("7,16.39,peak_var_m2,false,1e-8,1e-8,0.5,1e-8,-inf", &["column `fitted_z`", "not a finite"]),
        ("7,16.39,peak_mean_m,false,1e10,0.002,1e12,0.002,1e12", &["column `measured`", "peak_mean_m"]),
        ("7,16.39,phase_mean_deg,false,720,-21,0.4,,", &["column `measured`", "360"]),
        ("1e300,16.39,peak_mean_m,false,0.002,0.0021,-0.5,0.002,0.1", &["column `excitation_frequency_hz`"]),
        ("7,16.39,no_such_thing,false,0.002,0.0021,-0.5,0.002,0.1", &["column `observable`", "no_such_thing"]),
    ];
    for (i, (row, names)) in cases.iter().enumerate() {
        let dir = diagnosis(&format!("bad{i}"), &format!("{row}\n"));
        let out = s.path(&format!("figs{i}"));
        let err = refused(&["plot", dir.to_str().unwrap(), "--out", out.to_str().unwrap()], names);
        assert!(err.contains("scores.csv:3: "), "{row}: {err}");
        assert!(!out.exists(), "{row}: a refused plot draws nothing");
    }
}

/// `plot A --out B` writes only into a new or empty directory or one that
/// holds figures of the same kind and source, never beside another run's
/// set; redrawn in place, the whole set is swapped in with its data as it
/// was, under the same lock and atomic rules as `sweep`.
#[test]
fn plot_outputs_stay_one_runs() {
    let s = Scratch::new("plot");
    let (a, b) = (s.path("a"), s.path("b"));
    let (a_s, b_s) = (a.to_str().unwrap(), b.to_str().unwrap());
    for (dir, seed) in [(a_s, "1"), (b_s, "2")] {
        let o = run(&sweep_args(dir, &["--no-plots", "--seed", seed]));
        assert!(o.status.success(), "{}", stderr(&o));
    }
    // Into another sweep's set, or a diagnosis's: refused, nothing changes.
    let before = snapshot(&b);
    refused(&["plot", a_s, "--out", b_s], &["--out", "does not write"]);
    assert_eq!(snapshot(&b), before);
    s.write("diagnosis/report.json", "{}");
    let diagnosis = s.path("diagnosis");
    refused(&["plot", a_s, "--out", diagnosis.to_str().unwrap()], &["--out", "report.json"]);
    assert_eq!(listing(&diagnosis), ["report.json"]);
    // A directory of its own, redrawn from the same source; another source is refused.
    let figs = s.path("figs");
    let figs_s = figs.to_str().unwrap();
    for _ in 0..2 {
        let o = run(&["plot", a_s, "--out", figs_s]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert!(listing(&figs).contains(&"plot.json".to_string()) && listing(&figs).contains(&"fig8.png".to_string()));
    let drawn = snapshot(&figs);
    refused(&["plot", b_s, "--out", figs_s], &["--out", "figures of the sweep", "same kind and source"]);
    assert_eq!(snapshot(&figs), drawn);
    // Loose figures that stickslip did not write as an output set are not replaced.
    s.write("loose/fig8.png", "not ours");
    refused(&["plot", a_s, "--out", s.path("loose").to_str().unwrap()], &["--out", ".stickslip-output"]);
    refused(&["plot", a_s, "--out", &format!("{a_s}/sub")], &["--out", "inside"]);
    // In place: the data stay as they were, the figures join them.
    let data = snapshot(&a);
    let o = run(&["plot", a_s]);
    assert!(o.status.success(), "{}", stderr(&o));
    let after = snapshot(&a);
    for (name, bytes) in &data {
        assert!(after.contains(&(name.clone(), bytes.clone())), "{name} changed");
    }
    assert!(listing(&a).contains(&"fig9a.svg".to_string()));
    assert_eq!(listing(&s.0), ["a", "b", "diagnosis", "figs", "loose"], "no temporaries or locks are left");
}

/// Ambiguous input is refused by name: one file as two runs, one condition
/// twice in a summary, a JSON key twice; a grid value given twice runs once
/// and that is said.
#[test]
fn ambiguity_is_refused_or_said() {
    let s = Scratch::new("ambiguity");
    // One run file listed as two conditions, directly or through a link.
    let two = |name: &str, second: &str| {
        let dir = s.path(name);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("r.csv"), run_csv()).unwrap();
        let entry = |file: &str, f: f64, n: f64| {
            format!(
                r#"{{ "file": "{file}", "excitation_frequency_hz": {f}, "excitation_amplitude_m": 0.0025, "normal_force_n": {n} }}"#
            )
        };
        std::fs::write(
            dir.join("manifest.json"),
            format!(
                r#"{{ "format": "stickslip-measurements/1", "rig": {RIG}, "runs": [ {}, {} ] }}"#,
                entry("r.csv", 7.0, 16.39),
                entry(second, 9.0, 4.0)
            ),
        )
        .unwrap();
        dir
    };
    measurement_refused(
        &two("twice", "r.csv"),
        &["manifest.json", "runs[1].file", "runs[0].file", "9 Hz, 4 N", "7 Hz, 16.39 N"],
    );
    let linked = two("linked", "alias.csv");
    std::os::unix::fs::symlink(linked.join("r.csv"), linked.join("alias.csv")).unwrap();
    measurement_refused(&linked, &["runs[1].file `alias.csv`", "same file"]);
    // One condition twice in a summary, with different values or the same.
    let row = "7,0.0025,16.39,0.0038,2.8e-8,45,350\n";
    measurement_refused(
        &summary_set(&s, "differ", &format!("{row}7,0.0025,16.39,0.0041,2.8e-8,45,350\n")),
        &["s.csv:3", "also on line 2", "different values"],
    );
    measurement_refused(
        &summary_set(&s, "same", &format!("{row}7,0.0025,10,0.004,2.8e-8,45,350\n{row}")),
        &["s.csv:4", "also on line 2", "same values"],
    );
    // A JSON key given twice: the manifest's, and in accumulators.json even
    // with the same value (the digest cannot see it).
    let dir = s.path("keys");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("r.csv"), run_csv()).unwrap();
    std::fs::write(
        dir.join("manifest.json"),
        manifest("r.csv").replace(r#""mass_kg": 1.028"#, r#""mass_kg": -5.0, "mass_kg": 1.028"#),
    )
    .unwrap();
    measurement_refused(&dir, &["manifest.json:1", "`mass_kg` appears twice"]);
    let (a, b) = crate::hostile::honest_shards(&s);
    let text = std::fs::read_to_string(b.join("accumulators.json")).unwrap();
    let twice = s.path("twice-key");
    std::fs::create_dir_all(&twice).unwrap();
    std::fs::write(twice.join("accumulators.json"), text.replacen(r#""seed":3"#, r#""seed":3,"seed":3"#, 1)).unwrap();
    let err = merge_shards(&[a, twice]).unwrap_err().to_string();
    assert!(err.contains("twice-key/accumulators.json") && err.contains("`seed` appears twice"), "{err}");
    // Grid values given twice run once, and that is said.
    let out = s.path("grid");
    let o = run(&sweep_args(out.to_str().unwrap(), &["--frequencies", "7,7", "--no-plots", "--no-refine"]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("--frequencies gives 7 more than once"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(out.join("sweep.csv")).unwrap().lines().count(), 2, "one row for 7 Hz");
    let o =
        run(&sweep_args(out.to_str().unwrap(), &["--frequencies", "5:5:3", "--normal-forces", "4,4", "--no-plots"]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--frequencies gives 5 more than once") && stderr(&o).contains("--normal-forces gives 4")
    );
    assert_eq!(std::fs::read_to_string(out.join("sweep.csv")).unwrap().lines().count(), 2, "one row for 5 Hz, 4 N");
    // A base that does not move leaves the block stuck: no phase is
    // written (blank cells), and Figure 8's grid frequency is named.
    let o = run(&sweep_args(
        out.to_str().unwrap(),
        &["--set", "excitation.amplitude_m=0", "--frequencies", "5", "--normal-forces", "4"],
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("Figure 8 shows 5 Hz, the grid frequency nearest to --fig8-frequency 7 Hz"));
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let row = csv.lines().nth(1).unwrap();
    assert!(row.ends_with(",1,,"), "stuck throughout, no phase: {row}");
}

/// No control character reaches the terminal raw: a flag's value, a path
/// or a key holding a terminal escape is quoted escaped, on stderr and on
/// stdout alike.
#[test]
fn control_characters_are_escaped_in_every_message() {
    let s = Scratch::new("escapes");
    let out = s.path("out");
    let out_s = out.to_str().unwrap();
    for (flag, value, names) in [
        ("--frequencies", "7\u{1b}[2J", "--frequencies"),
        ("--normal-forces", "4,\u{1b}]0;owned\u{7}", "--normal-forces"),
        ("--shard", "1\u{1b}[31m/2", "--shard"),
        ("--set", "friction.\u{1b}[31ma=1", "friction."),
        ("--set", "friction.a=\u{1b}[31m", "friction.a"),
        ("--config", "/nonexistent/\u{1b}[2J.toml", "/nonexistent/"),
    ] {
        let err = refused(&sweep_args(out_s, &[flag, value]), &[names]);
        assert!(!err.contains('\u{1b}') && !err.contains('\u{7}'), "{flag} {value:?}: {err:?}");
        assert!(err.contains("\\u{1b}") || err.contains("\\u001B"), "{flag}: the escape is shown escaped: {err:?}");
    }
    let odd = s.path("o\u{1b}[2J");
    let o = run(&sweep_args(odd.to_str().unwrap(), &["--no-plots"]));
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(!stdout.contains('\u{1b}') && stdout.contains("o\\u{1b}[2J"), "{stdout:?}");
}

/// A machine with a GPU whose Vulkan driver did not load is told what to
/// check (the ICD file, VK_ICD_FILENAMES, the loader, vulkaninfo); a
/// machine without one (or with only a virtual display) is not.
#[test]
fn a_gpu_whose_driver_did_not_load_says_what_to_check() {
    use stickslip::engine::gpu::context::driver_hint_in;
    let s = Scratch::new("gpu-hint");
    assert_eq!(driver_hint_in(&s.0), None);
    s.write("sys/class/drm/card0/device/vendor", "0x1af4\n");
    assert_eq!(driver_hint_in(&s.0), None, "a virtio display is not a GPU");
    s.write("sys/class/drm/card1/device/vendor", "0x1002\n");
    assert!(driver_hint_in(&s.0).unwrap().contains("an AMD GPU"));
    s.write("proc/driver/nvidia/version", "NVRM version: NVIDIA UNIX x86_64 Kernel Module  550.54.14\n");
    let hint = driver_hint_in(&s.0).unwrap();
    for needle in ["NVIDIA", "550.54.14", "icd.d", "VK_ICD_FILENAMES", "libvulkan1", "vulkaninfo", "nvidia-smi"] {
        assert!(hint.contains(needle), "the hint lacks `{needle}`: {hint}");
    }
}
