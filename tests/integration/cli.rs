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
        let base = [
            ("--backend", "cpu"),
            ("--out", out_s),
            ("--frequencies", "7"),
            ("--normal-forces", "10"),
            ("--realisations", "2"),
            ("--cycles", "2"),
            ("--warmup-cycles", "1"),
        ];
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
    std::fs::write(&missing, stickslip::engine::model::PAPER_RIG_TOML.replace("mass_kg = 1.028", "")).unwrap();
    run(&["--config", missing.to_str().unwrap()], "mass_kg");

    let unknown = dir.join("unknown-key.toml");
    std::fs::write(&unknown, format!("{}\n[rig2]\nx = 1\n", stickslip::engine::model::PAPER_RIG_TOML)).unwrap();
    run(&["--config", unknown.to_str().unwrap()], "rig2");

    run(&["--set", "rig.mass_kg=-1"], "rig.mass_kg");
    run(&["--set", "rig.damping_ratio=-0.1"], "rig.damping_ratio");
    run(&["--set", "friction.sigma=-0.01"], "friction.sigma");
    run(&["--set", "normal_force.sigma=-1"], "normal_force.sigma");
    run(&["--set", "rig.natural_frequency_hz=0"], "rig.natural_frequency_hz");
    run(&["--frequencies", "0,7"], "--frequencies");
    run(&["--set", "solver.steps_per_period=4"], "solver.steps_per_period");
    run(&["--set", "noise.interval_s=0"], "noise.interval_s");
    run(&["--frequencies", "5:15"], "--frequencies");
    run(&["--realisations", "0"], "--realisations");
    run(&["--config", dir.join("absent.toml").to_str().unwrap()], "absent.toml");

    refused(&["simulate", "--out", out_s, "--set", "rig.mass_kg=-1"], &out, "rig.mass_kg");
    refused(&["simulate", "--out", out_s, "--frequency", "0"], &out, "--frequency");
    refused(&["simulate", "--out", out_s, "--sample-rate", "0"], &out, "--sample-rate");
    refused(&["benchmark-diagnosis", "--out", out_s, "--load-shares", "0.5,-1"], &out, "--load-shares");
    refused(&["benchmark-diagnosis", "--out", out_s, "--effects", "stickiness"], &out, "stickiness");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sweep_writes_the_contract_columns() {
    let dir = scratch("sweep");
    let out = dir.join("out");
    let (ok, stderr) = stickslip(&[
        "sweep",
        "--backend",
        "cpu",
        "--out",
        out.to_str().unwrap(),
        "--frequencies",
        "6,7",
        "--normal-forces",
        "8:16:2",
        "--realisations",
        "4",
        "--cycles",
        "5",
        "--warmup-cycles",
        "5",
        "--set",
        "friction.a=0.3",
    ]);
    assert!(ok, "{stderr}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "excitation_frequency_hz,normal_force_n,realisations,peaks,peak_mean_m,peak_var_m2,peak_p05_m,peak_p50_m,peak_p95_m,stick_fraction,phase_mean_deg,phase_var_deg2"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 4);
    assert!(rows[0].starts_with("6,8,4,20,"), "{}", rows[0]);
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(sidecar["model"]["friction"]["a"], 0.3);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn simulate_writes_a_measurement_set() {
    let dir = scratch("simulate");
    let out = dir.join("out");
    let (ok, stderr) = stickslip(&[
        "simulate",
        "--out",
        out.to_str().unwrap(),
        "--realisations",
        "2",
        "--duration",
        "2",
        "--warmup-cycles",
        "10",
    ]);
    assert!(ok, "{stderr}");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
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

fn sweep_args<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
        "sweep",
        "--out",
        out,
        "--frequencies",
        "6:8:5",
        "--normal-forces",
        "4,12,16.39",
        "--realisations",
        "16",
        "--cycles",
        "10",
        "--warmup-cycles",
        "10",
    ];
    if !extra.contains(&"--seed") {
        v.extend_from_slice(&["--seed", "9"]);
    }
    v.extend_from_slice(extra);
    v
}

fn same_bytes(a: &Path, b: &Path, file: &str) {
    let (x, y) = (std::fs::read(a.join(file)).unwrap(), std::fs::read(b.join(file)).unwrap());
    assert!(x == y, "{file} differs between {} and {}", a.display(), b.display());
}

/// Shards merged equal the unsharded run byte for byte; plots are written.
#[test]
fn shards_merge_into_the_unsharded_run() {
    let dir = scratch("shards");
    let whole = dir.join("whole");
    let (ok, err) = stickslip(&sweep_args(whole.to_str().unwrap(), &["--backend", "gpu"]));
    assert!(ok, "{err}");
    let mut shard_dirs = Vec::new();
    for k in [2, 0, 1] {
        let d = dir.join(format!("shard-{k}"));
        let shard = format!("{k}/3");
        let (ok, err) =
            stickslip(&sweep_args(d.to_str().unwrap(), &["--backend", "gpu", "--shard", &shard, "--no-plots"]));
        assert!(ok, "{err}");
        shard_dirs.push(d);
    }
    let merged = dir.join("merged");
    let mut args = vec!["merge", "--out", merged.to_str().unwrap()];
    args.extend(shard_dirs.iter().map(|d| d.to_str().unwrap()));
    let (ok, err) = stickslip(&args);
    assert!(ok, "{err}");
    for f in ["sweep.csv", "histograms.csv", "accumulators.json"] {
        same_bytes(&whole, &merged, f);
    }
    for f in ["fig9a.png", "fig9b.png", "fig8.png", "fig9a.svg", "fig9b.svg", "fig8.svg"] {
        let bytes = std::fs::read(merged.join(f)).unwrap_or_else(|_| panic!("{f} written"));
        assert!(bytes.len() > 1000, "{f} is only {} bytes", bytes.len());
        if f.ends_with(".png") {
            assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{f} is a PNG");
        } else {
            assert!(String::from_utf8_lossy(&bytes).contains("<svg"), "{f} is an SVG");
        }
    }
    // A missing shard and a shard of another run are refused, naming the problem.
    let (ok, err) = stickslip(&[
        "merge",
        "--out",
        dir.join("m2").to_str().unwrap(),
        shard_dirs[0].to_str().unwrap(),
        shard_dirs[1].to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("missing"), "{err}");
    let other = dir.join("other-seed");
    let (ok, err) = stickslip(&sweep_args(
        other.to_str().unwrap(),
        &["--backend", "gpu", "--shard", "1/3", "--no-plots", "--seed", "10"],
    ));
    assert!(ok, "{err}");
    let (ok, err) = stickslip(&[
        "merge",
        "--out",
        dir.join("m3").to_str().unwrap(),
        shard_dirs[1].to_str().unwrap(),
        other.to_str().unwrap(),
        shard_dirs[2].to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("seed"), "{err}");
    let other_model = dir.join("other-model");
    let (ok, err) = stickslip(&sweep_args(
        other_model.to_str().unwrap(),
        &["--backend", "gpu", "--shard", "1/3", "--no-plots", "--set", "friction.a=0.4"],
    ));
    assert!(ok, "{err}");
    let (ok, err) = stickslip(&[
        "merge",
        "--out",
        dir.join("m4").to_str().unwrap(),
        shard_dirs[1].to_str().unwrap(),
        other_model.to_str().unwrap(),
        shard_dirs[2].to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("model"), "{err}");
    assert!(
        !dir.join("m2").exists() && !dir.join("m3").exists() && !dir.join("m4").exists(),
        "a refused merge wrote nothing"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The CPU backend's output does not depend on the number of threads.
#[test]
fn cpu_sweep_is_identical_whatever_the_thread_count() {
    let dir = scratch("threads");
    let mut outs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.join(format!("t{threads}"));
        let args = sweep_args(out.to_str().unwrap(), &["--backend", "cpu", "--no-plots"]);
        let o = Command::new(env!("CARGO_BIN_EXE_stickslip"))
            .args(&args)
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        outs.push(out);
    }
    same_bytes(&outs[0], &outs[1], "sweep.csv");
    same_bytes(&outs[0], &outs[1], "histograms.csv");
    std::fs::remove_dir_all(&dir).unwrap();
}
