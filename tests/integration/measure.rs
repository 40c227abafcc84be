//! Reading measurement sets: the Figure 8 set, every bad-input rule of
//! `docs/formats.md`, and a round trip through stickslip's
//! own writers.

use std::path::{Path, PathBuf};

use stickslip::Error;
use stickslip::engine::{Condition, Model, Sample};
use stickslip::measure::{self, read_measurement_set};

use crate::common;

/// A scratch directory removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("stickslip-measure-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    fn write(&self, name: &str, text: &str) {
        std::fs::write(self.0.join(name), text).unwrap();
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

const RIG: &str = r#"{ "mass_kg": 1.028, "natural_frequency_hz": 10.05, "damping_ratio": 0.00225 }"#;

/// A manifest with one run entry `run.csv` at `frequency` Hz.
fn manifest_with_run(frequency: &str) -> String {
    format!(
        r#"{{ "format": "stickslip-measurements/1", "rig": {RIG},
             "runs": [ {{ "file": "run.csv", "excitation_frequency_hz": {frequency},
                          "excitation_amplitude_m": 0.0025, "normal_force_n": 16.0 }} ] }}"#
    )
}

/// A run file `t,x,v,normal_force,friction_force` of `n` samples at 600 Hz.
fn run_csv(n: usize) -> String {
    let mut text = String::from("t,x,v,normal_force,friction_force\n");
    for i in 0..n {
        let t = i as f64 / 600.0;
        let phase = std::f64::consts::TAU * 7.0 * t;
        let v = -0.004 * 7.0 * phase.sin();
        // A friction force of 1 N opposing the motion.
        text += &format!("{t},{},{v},16,{}\n", 0.004 * phase.cos(), -v.signum());
    }
    text
}

/// A valid set: one 2 s run at 7 Hz (14 periods).
fn valid_set(name: &str) -> Scratch {
    let s = Scratch::new(name);
    s.write("manifest.json", &manifest_with_run("7.0"));
    s.write("run.csv", &run_csv(1200));
    s
}

/// Replaces line `line` (1-based) of `text`.
fn replace_line(text: &str, line: usize, with: &str) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    lines[line - 1] = with;
    lines.join("\n") + "\n"
}

/// Asserts that reading `dir` fails with a measurement error naming the
/// file `file`, the line `line`, and containing every string of `problem`.
#[track_caller]
fn refused(dir: &Path, file: &str, line: Option<u64>, problem: &[&str]) {
    let err = read_measurement_set(dir).expect_err("the set should be refused");
    let text = err.to_string();
    match &err {
        Error::Measurement { file: f, line: l, message } => {
            assert_eq!(f.file_name().and_then(|n| n.to_str()), Some(file), "{text}");
            assert_eq!(*l, line, "{text}");
            for p in problem {
                assert!(message.contains(p), "message should contain `{p}`: {text}");
            }
        }
        other => panic!("expected Error::Measurement, got {other:?}"),
    }
    // The printed form names the file and line too.
    let shown = match line {
        Some(l) => format!("{file}:{l}: "),
        None => format!("{file}: "),
    };
    assert!(text.contains(&shown), "`{text}` should contain `{shown}`");
}

#[test]
fn figure8_summary_set() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/data/figure8"));
    let set = read_measurement_set(dir).expect("figure8 reads");
    assert!(set.runs.is_empty());
    assert_eq!(set.summary.len(), 4);
    assert!(set.description.contains("Figure 8"));
    assert_eq!(set.rig.mass_kg, 1.028);
    assert_eq!(set.rig.natural_frequency_hz, 10.05);
    assert_eq!(set.rig.damping_ratio, 0.00225);
    assert_eq!(set.summary_file.as_deref(), Some(dir.join("summary.csv").as_path()));
    let forces: Vec<f64> = set.summary.iter().map(|r| r.normal_force_mean_n).collect();
    assert_eq!(forces, [7.519, 11.5, 15.3, 16.39]);
    let last = set.summary[3];
    assert_eq!(last.line, 5);
    assert_eq!(last.excitation_frequency_hz, 7.0);
    assert_eq!(last.excitation_amplitude_m, 0.0025);
    assert_eq!(last.peak_mean_m, Some(3.854e-3));
    assert_eq!(last.peak_var_m2, Some(2.796425e-8));
    assert_eq!(last.normal_force_var_n2, Some(0.1102));
    assert_eq!(last.n_peaks, Some(350));
    assert_eq!(set.summary.iter().map(|r| r.line).collect::<Vec<_>>(), [2, 3, 4, 5]);
}

#[test]
fn valid_set_reads_with_any_column_order_and_unknown_keys() {
    let s = valid_set("valid");
    let set = read_measurement_set(&s.0).expect("valid set reads");
    assert_eq!(set.runs.len(), 1);
    let run = &set.runs[0];
    assert_eq!(run.len(), 1200);
    assert!((measure::sample_rate_hz(run) - 600.0).abs() < 1e-9);
    assert!(run.v_m_per_s.is_some() && run.normal_force.is_some() && run.friction_force.is_some());
    assert_eq!(run.excitation_frequency_hz, 7.0);
    assert_eq!(run.normal_force_n, 16.0);
    assert!(set.summary.is_empty() && set.summary_file.is_none());

    // Reordered and extra columns, optional ones absent, unknown keys, blank-padded fields.
    s.write(
        "manifest.json",
        &manifest_with_run("7.0").replacen("\"rig\"", "\"operator\": \"A. N. Other\", \"rig\"", 1),
    );
    let mut text = String::from("temperature, x ,t\n");
    for i in 0..1200 {
        text += &format!("21.5,{},{}\n", i as f64 * 1e-6, i as f64 / 600.0);
    }
    s.write("run.csv", &text);
    let set = read_measurement_set(&s.0).expect("reordered columns read");
    let run = &set.runs[0];
    assert_eq!(run.t_s[3], 3.0 / 600.0);
    assert_eq!(run.x_m[3], 3e-6);
    assert!(run.v_m_per_s.is_none() && run.normal_force.is_none() && run.friction_force.is_none());

    // A spreadsheet's export: byte-order mark and CRLF line ends.
    s.write("run.csv", &format!("\u{feff}{}", run_csv(1200).replace('\n', "\r\n")));
    let set = read_measurement_set(&s.0).expect("BOM and CRLF read");
    assert_eq!(set.runs[0].len(), 1200);
    // Lines still count from the header as line 1.
    let bad = run_csv(1200).replace("\n0.01,", "\n0.01x,");
    assert_ne!(bad, run_csv(1200));
    let line = bad.lines().position(|l| l.starts_with("0.01x,")).unwrap() as u64 + 1;
    s.write("run.csv", &format!("\u{feff}{}", bad.replace('\n', "\r\n")));
    refused(&s.0, "run.csv", Some(line), &["column `t`", "`0.01x` is not a number"]);
    // Blank lines count too, with any line end.
    for end in ["\n", "\r\n", "\r"] {
        let text = bad.replacen('\n', "\n\n\n", 2).replace('\n', end);
        s.write("run.csv", &text);
        refused(&s.0, "run.csv", Some(line + 4), &["`0.01x` is not a number"]);
    }
}

#[test]
fn missing_or_unreadable_files() {
    let s = Scratch::new("missing");
    refused(&s.0, "manifest.json", None, &["cannot read"]);

    let s = valid_set("missing-run");
    std::fs::remove_file(s.0.join("run.csv")).unwrap();
    refused(&s.0, "run.csv", None, &["cannot read", "runs[0].file"]);

    // A directory where the run file should be: opens, but cannot be read.
    std::fs::create_dir(s.0.join("run.csv")).unwrap();
    refused(&s.0, "run.csv", None, &["cannot read", "runs[0].file"]);

    let s = Scratch::new("missing-summary");
    s.write(
        "manifest.json",
        &format!(r#"{{ "format": "stickslip-measurements/1", "rig": {RIG}, "summary": "stats.csv" }}"#),
    );
    refused(&s.0, "stats.csv", None, &["cannot read", "summary"]);

    let s = valid_set("bad-json");
    s.write("manifest.json", "{\n  \"format\": \"stickslip-measurements/1\",\n  \"rig\": {\n}");
    refused(&s.0, "manifest.json", Some(4), &["not valid JSON"]);
}

#[test]
fn wrong_or_missing_format() {
    let s = valid_set("format");
    let good = manifest_with_run("7.0");
    s.write("manifest.json", &good.replace("stickslip-measurements/1", "stickslip-measurements/2"));
    refused(&s.0, "manifest.json", None, &["format", "stickslip-measurements/2"]);
    s.write("manifest.json", &good.replace("stickslip-measurements/1", "stickslip-measurements/1 "));
    refused(&s.0, "manifest.json", None, &["format"]);
    s.write("manifest.json", &good.replace("\"format\"", "\"fmt\""));
    refused(&s.0, "manifest.json", None, &["missing required key `format`"]);
}

#[test]
fn missing_required_keys() {
    let s = valid_set("keys");
    let good = manifest_with_run("7.0");
    for (from, to, key) in [
        ("\"rig\"", "\"rigging\"", "`rig`"),
        ("\"mass_kg\"", "\"mass\"", "`rig.mass_kg`"),
        ("\"natural_frequency_hz\"", "\"f0\"", "`rig.natural_frequency_hz`"),
        ("\"damping_ratio\"", "\"zeta\"", "`rig.damping_ratio`"),
        ("\"file\"", "\"path\"", "`runs[0].file`"),
        ("\"excitation_frequency_hz\"", "\"f\"", "`runs[0].excitation_frequency_hz`"),
        ("\"excitation_amplitude_m\"", "\"u0\"", "`runs[0].excitation_amplitude_m`"),
        ("\"normal_force_n\"", "\"n\"", "`runs[0].normal_force_n`"),
    ] {
        s.write("manifest.json", &good.replacen(from, to, 1));
        refused(&s.0, "manifest.json", None, &["missing required key", key]);
    }
}

#[test]
fn missing_required_columns() {
    let s = valid_set("columns");
    let good = run_csv(1200);
    s.write("run.csv", &replace_line(&good, 1, "time,x,v,normal_force,friction_force"));
    refused(&s.0, "run.csv", Some(1), &["missing required column `t`"]);
    s.write("run.csv", &replace_line(&good, 1, "t,displacement,v,normal_force,friction_force"));
    refused(&s.0, "run.csv", Some(1), &["missing required column `x`"]);
    s.write("run.csv", "");
    refused(&s.0, "run.csv", Some(1), &["empty"]);

    let s = Scratch::new("summary-columns");
    s.write(
        "manifest.json",
        &format!(r#"{{ "format": "stickslip-measurements/1", "rig": {RIG}, "summary": "summary.csv" }}"#),
    );
    s.write("summary.csv", "excitation_frequency_hz,excitation_amplitude_m,peak_mean_m\n7,0.0025,0.004\n");
    refused(&s.0, "summary.csv", Some(1), &["missing required column `normal_force_mean_n`"]);
    s.write("summary.csv", "excitation_frequency_hz,excitation_amplitude_m,normal_force_mean_n\n7,0.0025,16\n");
    refused(&s.0, "summary.csv", Some(1), &["missing required column `peak_mean_m`"]);
}

#[test]
fn values_that_are_not_finite_numbers() {
    let s = valid_set("finite");
    let good = run_csv(1200);
    let line5 = good.lines().nth(4).unwrap().to_string();
    let fields: Vec<&str> = line5.split(',').collect();
    for (column, bad, problem) in [
        (1, "NaN", "not a finite number"),
        (1, "inf", "not a finite number"),
        (2, "fast", "not a number"),
        (3, "", "empty field"),
        (0, "-infinity", "not a finite number"),
    ] {
        let mut f = fields.clone();
        f[column] = bad;
        s.write("run.csv", &replace_line(&good, 5, &f.join(",")));
        let name = ["t", "x", "v", "normal_force", "friction_force"][column];
        refused(&s.0, "run.csv", Some(5), &[problem, &format!("column `{name}`")]);
    }
    s.write("run.csv", &replace_line(&good, 9, "0.0133,0.001"));
    refused(&s.0, "run.csv", Some(9), &["2 fields", "header has 5"]);

    // In the manifest: a string where a number belongs, and a number JSON cannot hold.
    s.write("run.csv", &good);
    let manifest = manifest_with_run("7.0");
    s.write("manifest.json", &manifest.replace("1.028", "\"NaN\""));
    refused(&s.0, "manifest.json", None, &["`rig.mass_kg` must be a number"]);
    s.write("manifest.json", &manifest.replace("1.028", "1e999"));
    refused(&s.0, "manifest.json", Some(1), &["not valid JSON"]);

    let s = Scratch::new("summary-finite");
    s.write(
        "manifest.json",
        &format!(r#"{{ "format": "stickslip-measurements/1", "rig": {RIG}, "summary": "summary.csv" }}"#),
    );
    let header = "excitation_frequency_hz,excitation_amplitude_m,normal_force_mean_n,peak_mean_m,n_peaks\n";
    s.write("summary.csv", &format!("{header}7,0.0025,16,0.004,350\n7,0.0025,nan,0.004,350\n"));
    refused(&s.0, "summary.csv", Some(3), &["column `normal_force_mean_n`", "not a finite number"]);
    s.write("summary.csv", &format!("{header}7,0.0025,16,0.004,350.5\n"));
    refused(&s.0, "summary.csv", Some(2), &["column `n_peaks`", "whole number"]);
}

#[test]
fn negative_or_zero_mass_and_frequencies() {
    let s = valid_set("negative");
    let good = manifest_with_run("7.0");
    for (from, to, key, problem) in [
        ("1.028", "-1.028", "rig.mass_kg", "negative"),
        ("1.028", "0", "rig.mass_kg", "positive"),
        ("10.05", "-10.05", "rig.natural_frequency_hz", "negative"),
        ("10.05", "0.0", "rig.natural_frequency_hz", "positive"),
        ("0.00225", "-0.00225", "rig.damping_ratio", "negative"),
        ("\"normal_force_n\": 16.0", "\"normal_force_n\": -16.0", "runs[0].normal_force_n", "negative"),
        // An undriven block stays at rest, and without a normal force there
        // is no friction: a run has both.
        ("\"normal_force_n\": 16.0", "\"normal_force_n\": 0", "runs[0].normal_force_n", "positive (> 0 N)"),
        (
            "\"excitation_amplitude_m\": 0.0025",
            "\"excitation_amplitude_m\": 0",
            "runs[0].excitation_amplitude_m",
            "positive",
        ),
    ] {
        s.write("manifest.json", &good.replacen(from, to, 1));
        refused(&s.0, "manifest.json", None, &[key, problem]);
    }
    s.write("manifest.json", &manifest_with_run("-7.0"));
    refused(&s.0, "manifest.json", None, &["runs[0].excitation_frequency_hz", "negative"]);
    s.write("manifest.json", &manifest_with_run("0"));
    refused(&s.0, "manifest.json", None, &["runs[0].excitation_frequency_hz", "positive"]);

    let s = Scratch::new("summary-negative");
    s.write(
        "manifest.json",
        &format!(r#"{{ "format": "stickslip-measurements/1", "rig": {RIG}, "summary": "summary.csv" }}"#),
    );
    let header = "peak_mean_m,normal_force_mean_n,excitation_amplitude_m,excitation_frequency_hz,peak_var_m2\n";
    s.write("summary.csv", &format!("{header}0.004,16,0.0025,7,1e-8\n0.004,16,0.0025,-7,1e-8\n"));
    refused(&s.0, "summary.csv", Some(3), &["column `excitation_frequency_hz`", "negative"]);
    s.write("summary.csv", &format!("{header}0.004,16,0.0025,7,-1e-8\n"));
    refused(&s.0, "summary.csv", Some(2), &["column `peak_var_m2`", "negative"]);
    s.write("summary.csv", &format!("{header}0.004,16,0,7,1e-8\n"));
    refused(&s.0, "summary.csv", Some(2), &["column `excitation_amplitude_m`", "positive"]);
    s.write("summary.csv", &format!("{header}0.004,0,0.0025,7,1e-8\n"));
    refused(&s.0, "summary.csv", Some(2), &["column `normal_force_mean_n`", "positive"]);
    // The same table with a valid row reads, columns in this order.
    s.write("summary.csv", &format!("{header}0.004,16,0.0025,7,1e-8\n"));
    let set = read_measurement_set(&s.0).expect("valid summary reads");
    assert_eq!(set.summary[0].excitation_frequency_hz, 7.0);
    assert_eq!(set.summary[0].peak_var_m2, Some(1e-8));
    assert_eq!(set.summary[0].n_peaks, None);
}

#[test]
fn time_must_increase_and_be_uniform() {
    let s = valid_set("time");
    let good = run_csv(1200);
    // Row 7 (line 7) repeats the time of line 6.
    let line6 = good.lines().nth(5).unwrap();
    let t6 = line6.split(',').next().unwrap();
    let line7 = good.lines().nth(6).unwrap();
    let repeated = format!("{t6},{}", line7.split_once(',').unwrap().1);
    s.write("run.csv", &replace_line(&good, 7, &repeated));
    refused(&s.0, "run.csv", Some(7), &["time does not increase"]);
    // Time going backwards.
    let back = format!("0.001,{}", line7.split_once(',').unwrap().1);
    s.write("run.csv", &replace_line(&good, 7, &back));
    refused(&s.0, "run.csv", Some(7), &["time does not increase"]);
    // A dropped sample: the interval after line 100 doubles.
    let mut lines: Vec<&str> = good.lines().collect();
    lines.remove(100);
    s.write("run.csv", &(lines.join("\n") + "\n"));
    refused(&s.0, "run.csv", Some(101), &["uniformly sampled"]);
}

/// A slipping block's record at 600 Hz for 2 s, its velocity column scaled
/// by `v_factor` and its friction force (2 N, opposing the motion) by
/// `friction_sign` (either may be 0).
fn run_csv_slipping(v_factor: f64, friction_sign: f64) -> String {
    let mut text = String::from("t,x,v,normal_force,friction_force\n");
    let w = std::f64::consts::TAU * 7.0;
    for i in 0..1200 {
        let t = i as f64 / 600.0;
        let v = -0.004 * w * (w * t).sin();
        text += &format!("{t},{},{},16,{}\n", 0.004 * (w * t).cos(), v_factor * v, -2.0 * friction_sign * v.signum());
    }
    text
}

/// A channel that breaks a convention no single value breaks (a velocity
/// with its sign reversed or in mm/s, a friction force with its sign
/// reversed, a normal force in kN) is refused by file and column. Read as it was, a reversed
/// friction force (or velocity) left no sample slipping, every friction
/// feature vanished, and a diagnosis of a null set was sure of `none`
/// without having looked at the friction.
#[test]
fn a_channel_with_its_sign_reversed_or_in_another_unit_is_refused() {
    let s = valid_set("conventions");
    s.write("run.csv", &run_csv_slipping(1.0, 1.0));
    read_measurement_set(&s.0).expect("a record that keeps the conventions reads");
    s.write("run.csv", &run_csv_slipping(-1.0, 1.0));
    refused(&s.0, "run.csv", None, &["column `v`", "falls where `x` rises"]);
    s.write("run.csv", &run_csv_slipping(1000.0, 1.0));
    refused(&s.0, "run.csv", None, &["column `v`", "1000 times its size", "m/s"]);
    s.write("run.csv", &run_csv_slipping(1.0, -1.0));
    refused(&s.0, "run.csv", None, &["column `friction_force`", "along its motion", "sign reversed"]);
    // The normal force in kN beside a nominal setting in N.
    s.write("run.csv", &run_csv_slipping(1.0, 1.0).replace(",16,", ",0.016,"));
    refused(&s.0, "run.csv", None, &["column `normal_force`", "0.001 times", "nominal normal_force_n, 16 N"]);
    // A channel that holds one value while the block moves is dead: a zero
    // normal force, velocity or friction force is refused, by column.
    s.write("run.csv", &run_csv_slipping(1.0, 1.0).replace(",16,", ",0,"));
    refused(&s.0, "run.csv", None, &["column `normal_force`", "0 times", "nominal normal_force_n, 16 N"]);
    s.write("run.csv", &run_csv_slipping(0.0, 1.0));
    refused(&s.0, "run.csv", None, &["column `v`", "dead channel"]);
    s.write("run.csv", &run_csv_slipping(1.0, 0.0));
    refused(&s.0, "run.csv", None, &["column `friction_force`", "dead channel"]);
    // A displacement in millimetres swings far beyond what the rig could
    // without friction (4 m against about 5 mm), even with no other channel.
    let in_mm: String = run_csv_slipping(1.0, 1.0)
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            match f[1].parse::<f64>() {
                Ok(x) => format!("{},{}\n", f[0], x * 1000.0),
                Err(_) => "t,x\n".to_string(),
            }
        })
        .collect();
    s.write("run.csv", &in_mm);
    refused(&s.0, "run.csv", None, &["column `x`", "in metres", "without friction"]);
}

#[test]
fn records_shorter_than_ten_periods() {
    let s = Scratch::new("short");
    // 6 Hz at 600 Hz: ten periods are exactly 1000 samples.
    s.write("manifest.json", &manifest_with_run("6.0"));
    s.write("run.csv", &run_csv(1000));
    read_measurement_set(&s.0).expect("exactly ten periods are enough");
    s.write("run.csv", &run_csv(999));
    refused(&s.0, "run.csv", None, &["too short", "9.990 excitation periods"]);
    s.write("run.csv", &run_csv(1));
    refused(&s.0, "run.csv", None, &["1 sample"]);
    s.write("run.csv", &run_csv(0));
    refused(&s.0, "run.csv", None, &["0 sample"]);
}

#[test]
fn a_set_needs_runs_or_a_summary() {
    let s = Scratch::new("empty-set");
    let bare = format!(r#"{{ "format": "stickslip-measurements/1", "rig": {RIG} }}"#);
    s.write("manifest.json", &bare);
    refused(&s.0, "manifest.json", None, &["no runs and no summary"]);
    s.write("manifest.json", &bare.replacen('{', "{ \"runs\": [], ", 1));
    refused(&s.0, "manifest.json", None, &["no runs and no summary"]);
    // A summary table without rows holds nothing either.
    s.write("manifest.json", &bare.replacen('{', "{ \"summary\": \"s.csv\", ", 1));
    s.write("s.csv", "excitation_frequency_hz,excitation_amplitude_m,normal_force_mean_n,peak_mean_m\n");
    refused(&s.0, "s.csv", None, &["no rows"]);
}

/// Writes `samples`, a record of `model` at 7 Hz and 16.39 N, as `sim.csv`
/// in `s`, with a manifest that names it.
fn write_simulated_set(s: &Scratch, description: &str, model: &Model, samples: &[Sample]) {
    measure::write_run_file(&s.0.join("sim.csv"), samples).unwrap();
    let entry = measure::RunEntry {
        file: "sim.csv".into(),
        excitation_frequency_hz: 7.0,
        excitation_amplitude_m: model.excitation.amplitude_m,
        normal_force_n: 16.39,
    };
    measure::write_manifest(&s.0, description, model, &[entry]).unwrap();
}

#[test]
fn simulated_set_round_trips() {
    let s = Scratch::new("round-trip");
    let model = Model::default();
    let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
    let rate_hz = 600.0;
    let samples = common::record(&model, condition, 5, 10, 2.0, rate_hz);
    write_simulated_set(&s, "round trip", &model, &samples);

    let set = read_measurement_set(&s.0).expect("stickslip's own output reads");
    assert_eq!(set.description, "round trip");
    assert_eq!(set.rig.mass_kg, model.rig.mass_kg);
    assert_eq!(set.rig.natural_frequency_hz, model.rig.natural_frequency_hz);
    assert_eq!(set.rig.damping_ratio, model.rig.damping_ratio);
    assert_eq!(set.runs.len(), 1);
    let mut expected = measure::Run::from_samples(&samples, 7.0, model.excitation.amplitude_m, 16.39);
    expected.file = s.0.join("sim.csv");
    assert_eq!(set.runs[0], expected, "every value comes back bit for bit");
    assert!((measure::sample_rate_hz(&set.runs[0]) - rate_hz).abs() < 1e-6);
}

/// A friction force in another unit is refused by what the equation of
/// motion says the force on the block is: a simulated record reads, the
/// same record with its friction force in kN does not.
#[test]
fn a_friction_force_the_equation_of_motion_disowns_is_refused() {
    let s = Scratch::new("force-balance");
    let model = Model::default();
    let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
    let mut samples = common::record(&model, condition, 5, 10, 4.0, 600.0);
    write_simulated_set(&s, "force balance", &model, &samples);
    read_measurement_set(&s.0).expect("a simulated record keeps the equation of motion");
    let original = samples.clone();
    // In kN, with a gain ten times too large, or dead: each is refused.
    for (scale, said) in [(1e-3, "times the force"), (10.0, "times the force"), (0.0, "dead channel")] {
        for (sample, first) in samples.iter_mut().zip(&original) {
            sample.friction_force_n = first.friction_force_n * scale;
        }
        measure::write_run_file(&s.0.join("sim.csv"), &samples).unwrap();
        let needs: &[&str] = if scale == 0.0 { &[said] } else { &["equation of motion", "newtons", said] };
        refused(&s.0, "sim.csv", None, &[&["column `friction_force`"], needs].concat());
    }
}

/// Some rigs publish only phases: a summary row needs a mean peak or a mean
/// phase, its other statistics may be blank, and a row with neither is
/// refused by line.
#[test]
fn phase_only_summary_rows() {
    let s = Scratch::new("phase-only");
    s.write(
        "manifest.json",
        &format!(r#"{{ "format": "stickslip-measurements/1", "rig": {RIG}, "summary": "s.csv" }}"#),
    );
    s.write(
        "s.csv",
        "excitation_frequency_hz,excitation_amplitude_m,normal_force_mean_n,phase_mean_deg,phase_var_deg2\n\
         7,0.0025,8,24.5,0.4\n9,0.0025,8,27.0,\n",
    );
    let set = read_measurement_set(&s.0).expect("a phase-only table reads");
    assert_eq!(set.summary.len(), 2);
    assert_eq!((set.summary[0].peak_mean_m, set.summary[0].phase_mean_deg), (None, Some(24.5)));
    assert_eq!((set.summary[1].phase_var_deg2, set.summary[1].line), (None, 3));

    s.write(
        "s.csv",
        "excitation_frequency_hz,excitation_amplitude_m,normal_force_mean_n,peak_mean_m,phase_mean_deg\n\
         7,0.0025,8,0.004,\n9,0.0025,8,,\n",
    );
    refused(&s.0, "s.csv", Some(3), &["neither `peak_mean_m` nor `phase_mean_deg`"]);
    s.write(
        "s.csv",
        "excitation_frequency_hz,excitation_amplitude_m,normal_force_mean_n,phase_mean_deg\n7,0.0025,8,west\n",
    );
    refused(&s.0, "s.csv", Some(2), &["`west` is not a number"]);
}

/// A run file with a `base_x` column: the base `U0 cos(2π 7 (t + offset))`
/// recorded from a clock that started `offset` seconds into the base's
/// cycle, and a response 30° behind it.
fn run_csv_with_base(n: usize, offset_s: f64) -> String {
    let mut text = String::from("t,x,base_x\n");
    for i in 0..n {
        let t = i as f64 / 600.0;
        let theta = std::f64::consts::TAU * 7.0 * (t + offset_s);
        text += &format!("{t},{},{}\n", 0.004 * (theta - 30f64.to_radians()).cos(), 0.0025 * theta.cos());
    }
    text
}

#[test]
fn a_base_x_column_puts_the_record_in_the_model_frame() {
    use stickslip::diagnose::features::run_features;
    use stickslip::measure::TimeOrigin;
    let s = Scratch::new("base-x");
    s.write("manifest.json", &manifest_with_run("7.0"));
    s.write("run.csv", &run_csv_with_base(1200, 0.031));
    let set = read_measurement_set(&s.0).unwrap();
    let run = &set.runs[0];
    let TimeOrigin::BaseChannel { shift_s, amplitude_m } = run.time_origin else { panic!("{:?}", run.time_origin) };
    // The record's clock started 0.031 s into the base's cycle: its t is
    // moved back by the rest of that cycle (mod one period), and the base's
    // amplitude is read too.
    let period = 1.0 / 7.0;
    assert!(((shift_s + 0.031) / period - ((shift_s + 0.031) / period).round()).abs() < 1e-6, "{shift_s}");
    assert!((amplitude_m - 0.0025).abs() < 1e-9, "{amplitude_m}");
    // The response's phase lag is then read as the 30° it is.
    let phase = run_features(run).peaks.unwrap().phase_mean_deg;
    assert!((phase - 30.0).abs() < 0.5, "phase {phase}");
}

/// A `base_x` column that is not the base the run declares is refused by
/// file and column, with what is wrong: one that moves mostly at twice the
/// excitation frequency (no phase read against it would mean anything),
/// and one a
/// hundred times the declared amplitude (a column in other units). Sensor
/// noise of a few micrometres on the right base reads.
#[test]
fn a_base_x_column_that_is_not_the_declared_base_is_refused() {
    let s = Scratch::new("base-x-wrong");
    s.write("manifest.json", &manifest_with_run("7.0"));
    let with_base = |base: &dyn Fn(f64) -> f64| {
        let mut text = String::from("t,x,base_x\n");
        for i in 0..1200 {
            let t = i as f64 / 600.0;
            text += &format!("{t},{},{}\n", 0.004 * (std::f64::consts::TAU * 7.0 * t).cos(), base(t));
        }
        text
    };
    let omega = std::f64::consts::TAU * 7.0;
    s.write("run.csv", &with_base(&|t| 0.0025 * (2.0 * omega * t).cos() + 0.00025 * (omega * t).cos()));
    refused(&s.0, "run.csv", None, &["column `base_x`", "sinusoid at the excitation frequency (7 Hz)", "1.0%"]);
    s.write("run.csv", &with_base(&|t| 0.25 * (omega * t).cos()));
    refused(&s.0, "run.csv", None, &["column `base_x`", "100.000 times", "`excitation_amplitude_m` (0.0025 m)"]);
    // The right base with a few micrometres of noise, and 1.5 times the
    // declared amplitude (a shaker off its nominal setting), read.
    s.write("run.csv", &with_base(&|t| 0.0025 * (omega * t).cos() + 3e-6 * (977.0 * t).sin()));
    read_measurement_set(&s.0).expect("a noisy base reads");
    s.write("run.csv", &with_base(&|t| 0.00375 * (omega * t + 1.0).cos()));
    read_measurement_set(&s.0).expect("a base off its nominal amplitude reads");
}

#[test]
fn a_free_time_origin_is_declared_by_name_and_anything_else_refused() {
    use stickslip::diagnose::features::run_features;
    use stickslip::measure::TimeOrigin;
    let s = Scratch::new("free-origin");
    let manifest = manifest_with_run("7.0").replacen("{ \"format\"", "{ \"time_origin\": \"free\", \"format\"", 1);
    s.write("manifest.json", &manifest);
    s.write("run.csv", &run_csv(1200));
    let set = read_measurement_set(&s.0).unwrap();
    assert_eq!(set.runs[0].time_origin, TimeOrigin::Free);
    // No absolute phase is read from it; its spread still is.
    let names: Vec<_> = run_features(&set.runs[0]).named_values().into_iter().map(|(o, _)| o.name()).collect();
    assert!(!names.contains(&"phase_mean_deg") && names.contains(&"phase_var_deg2"), "{names:?}");
    // Per run, too; a value that is not "free" is refused by key.
    let per_run = manifest_with_run("7.0")
        .replace("\"normal_force_n\": 16.0", "\"normal_force_n\": 16.0, \"time_origin\": \"model\"");
    s.write("manifest.json", &per_run);
    let e = read_measurement_set(&s.0).unwrap_err().to_string();
    assert!(e.contains("runs[0].time_origin") && e.contains("free"), "{e}");
}
