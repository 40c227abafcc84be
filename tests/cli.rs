//! The command line: bad input is refused with an error naming what is
//! wrong, the exit code is non-zero, and nothing is written.

use std::path::{Path, PathBuf};
use std::process::Command;

fn stickslip(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_stickslip")).args(args).output().expect("runs");
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stickslip-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn refused(args: &[&str], out: &Path, must_name: &str) {
    let (ok, stderr) = stickslip(args);
    assert!(!ok, "{args:?} should fail");
    assert!(stderr.contains(must_name), "error for {args:?} should name `{must_name}`: {stderr}");
    assert!(!out.exists(), "{args:?} wrote {}", out.display());
}

#[test]
fn bad_input_is_named_and_nothing_is_written() {
    let dir = scratch("bad");
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    // A small valid sweep; `extra` replaces a flag of the same name.
    let sweep = |extra: &[&str]| -> Vec<String> {
        let base = [("--backend", "cpu"), ("--out", out_s), ("--frequencies", "7"), ("--normal-forces", "10"), ("--realisations", "2"), ("--cycles", "2"), ("--warmup-cycles", "1")];
        let mut v = vec!["sweep".to_string()];
        for (flag, value) in base {
            if !extra.contains(&flag) {
                v.extend([flag.to_string(), value.to_string()]);
            }
        }
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |extra: &[&str], name: &str| {
        let args = sweep(extra);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        refused(&refs, &out, name);
    };

    let malformed = dir.join("malformed.toml");
    std::fs::write(&malformed, "[rig]\nmass_kg = = 1\n").unwrap();
    run(&["--config", malformed.to_str().unwrap()], "malformed.toml");

    let missing = dir.join("missing-key.toml");
    std::fs::write(&missing, stickslip::model::PAPER_RIG_TOML.replace("mass_kg = 1.028", "")).unwrap();
    run(&["--config", missing.to_str().unwrap()], "mass_kg");

    let unknown = dir.join("unknown-key.toml");
    std::fs::write(&unknown, format!("{}\n[rig2]\nx = 1\n", stickslip::model::PAPER_RIG_TOML)).unwrap();
    run(&["--config", unknown.to_str().unwrap()], "rig2");

    run(&["--set", "rig.mass_kg=-1"], "rig.mass_kg");
    run(&["--set", "rig.damping_ratio=-0.1"], "rig.damping_ratio");
    run(&["--set", "friction.sigma=-0.01"], "friction.sigma");
    run(&["--set", "normal_force.sigma=-1"], "normal_force.sigma");
    run(&["--set", "rig.natural_frequency_hz=0"], "rig.natural_frequency_hz");
    run(&["--frequencies", "0,7"], "excitation_frequency_hz");
    run(&["--set", "solver.steps_per_period=4"], "solver.steps_per_period");
    run(&["--set", "noise.interval_s=0"], "noise.interval_s");
    run(&["--frequencies", "5:15"], "--frequencies");
    run(&["--realisations", "0"], "--realisations");
    run(&["--config", dir.join("absent.toml").to_str().unwrap()], "absent.toml");

    refused(&["simulate", "--out", out_s, "--set", "rig.mass_kg=-1"], &out, "rig.mass_kg");
    refused(&["simulate", "--out", out_s, "--frequency", "0"], &out, "excitation_frequency_hz");
    refused(&["simulate", "--out", out_s, "--sample-rate", "0"], &out, "--sample-rate");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sweep_writes_the_contract_columns() {
    let dir = scratch("sweep");
    let out = dir.join("out");
    let (ok, stderr) = stickslip(&[
        "sweep", "--backend", "cpu", "--out", out.to_str().unwrap(), "--frequencies", "6,7", "--normal-forces", "8:16:2",
        "--realisations", "4", "--cycles", "5", "--warmup-cycles", "5", "--set", "friction.a=0.3",
    ]);
    assert!(ok, "{stderr}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "excitation_frequency_hz,normal_force_n,realisations,peaks,peak_mean_m,peak_var_m2,peak_p05_m,peak_p50_m,peak_p95_m,stick_fraction"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 4);
    assert!(rows[0].starts_with("6,8,4,20,"), "{}", rows[0]);
    let sidecar: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(sidecar["model"]["friction"]["a"], 0.3);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn simulate_writes_a_measurement_set() {
    let dir = scratch("simulate");
    let out = dir.join("out");
    let (ok, stderr) = stickslip(&["simulate", "--out", out.to_str().unwrap(), "--realisations", "2", "--duration", "2", "--warmup-cycles", "10"]);
    assert!(ok, "{stderr}");
    let manifest: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["format"], "stickslip-measurements/1");
    let runs = manifest["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    let file = out.join(runs[0]["file"].as_str().unwrap());
    let text = std::fs::read_to_string(file).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,x,v,normal_force,friction_force");
    let times: Vec<f64> = lines.map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    assert_eq!(times.len(), 1200, "2 s at 600 Hz");
    assert!(times.windows(2).all(|w| ((w[1] - w[0]) * 600.0 - 1.0).abs() < 1e-9), "uniform sampling");
    std::fs::remove_dir_all(&dir).unwrap();
}
