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
    // One peak per point has no variance: refused, not written as 0.
    run(&["--realisations", "1", "--cycles", "1"], "--realisations");
    run(&["--config", dir.join("absent.toml").to_str().unwrap()], "absent.toml");

    refused(&["simulate", "--out", out_s, "--set", "rig.mass_kg=-1"], &out, "rig.mass_kg");
    refused(&["simulate", "--out", out_s, "--frequency", "0"], &out, "--frequency");
    refused(&["simulate", "--out", out_s, "--sample-rate", "0"], &out, "--sample-rate");
    // A set `diagnose` could not read is not written.
    refused(&["simulate", "--out", out_s, "--normal-force", "0"], &out, "--normal-force");
    // Where the block stops at every load (η = 1/3), shares of the no-stop
    // threshold name no load.
    refused(&["benchmark-diagnosis", "--out", out_s, "--frequency-ratios", "0.7,0.3333333333333333"], &out, "0.333");
    refused(&["benchmark-diagnosis", "--out", out_s, "--load-shares", "0.5,-1"], &out, "--load-shares");
    refused(&["benchmark-diagnosis", "--out", out_s, "--effects", "stickiness"], &out, "stickiness");
    refused(&["benchmark-diagnosis", "--out", out_s, "--frequency-ratios", "0.7,NaN"], &out, "--frequency-ratios");
    refused(&["benchmark-diagnosis", "--out", out_s, "--frequency-ratios", "0.7,0.9,0.7"], &out, "--frequency-ratios");
    // A generator's load flag is refused with the other generator, not ignored.
    refused(&["benchmark-diagnosis", "--out", out_s, "--loads", "4,8"], &out, "--loads");
    refused(
        &["benchmark-diagnosis", "--out", out_s, "--generator", "independent", "--load-shares", "0.5"],
        &out,
        "--load-shares",
    );
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
        // The grid as given: 2 × 2 rows (the refinement has its own test).
        "--no-refine",
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
/// The GPU shards run on whatever adapter there is, lavapipe included (CI
/// has no GPU): `--allow-software-gpu` lets `--backend gpu` take it.
#[test]
fn shards_merge_into_the_unsharded_run() {
    let dir = scratch("shards");
    let whole = dir.join("whole");
    let (ok, err) = stickslip(&sweep_args(whole.to_str().unwrap(), &["--backend", "gpu", "--allow-software-gpu"]));
    assert!(ok, "{err}");
    let mut shard_dirs = Vec::new();
    for k in [2, 0, 1] {
        let d = dir.join(format!("shard-{k}"));
        let shard = format!("{k}/3");
        let (ok, err) = stickslip(&sweep_args(
            d.to_str().unwrap(),
            &["--backend", "gpu", "--allow-software-gpu", "--shard", &shard, "--no-plots"],
        ));
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
        &["--backend", "gpu", "--allow-software-gpu", "--shard", "1/3", "--no-plots", "--seed", "10"],
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
        &["--backend", "gpu", "--allow-software-gpu", "--shard", "1/3", "--no-plots", "--set", "friction.a=0.4"],
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

/// The adaptive refinement adds frequencies across the resonance, the same
/// ones in every shard, so shards merged still equal the unsharded run byte
/// for byte; `--no-refine` keeps the grid as given.
#[test]
fn refined_shards_merge_into_the_unsharded_run() {
    let dir = scratch("refine");
    let args = |out: &Path, extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = [
            "sweep",
            "--backend",
            "cpu",
            "--no-plots",
            "--frequencies",
            "9.5:10.5:3",
            "--normal-forces",
            "4,16.39",
            "--realisations",
            "4",
            "--cycles",
            "5",
            "--warmup-cycles",
            "30",
            "--out",
            out.to_str().unwrap(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |v: Vec<String>| {
        let refs: Vec<&str> = v.iter().map(String::as_str).collect();
        let (ok, stdout, err) = stickslip_out(&refs);
        assert!(ok, "{err}");
        (stdout, err)
    };
    let whole = dir.join("whole");
    let (stdout, err) = run(args(&whole, &[]));
    assert!(err.contains("refine: added"), "{err}");
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("sweep.json")).unwrap()).unwrap();
    let added: Vec<f64> =
        sidecar["refinement"]["added_frequencies_hz"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert!(!added.is_empty() && added.len() <= 3, "{added:?}");
    assert!(added.iter().all(|f| *f > 9.5 && *f < 10.5), "{added:?}");
    let frequencies = sidecar["frequencies_hz"].as_array().unwrap().len();
    assert_eq!(frequencies, 3 + added.len());
    assert!(stdout.contains(&format!("{} added by refinement", added.len())), "{stdout}");
    let mut shards = Vec::new();
    for k in 0..3 {
        let d = dir.join(format!("shard-{k}"));
        let shard = format!("{k}/3");
        run(args(&d, &["--shard", &shard]));
        shards.push(d);
    }
    let merged = dir.join("merged");
    let mut merge = vec!["merge".to_string(), "--out".into(), merged.to_str().unwrap().into()];
    merge.extend(shards.iter().map(|d| d.to_str().unwrap().to_string()));
    run(merge);
    for f in ["sweep.csv", "histograms.csv", "accumulators.json"] {
        same_bytes(&whole, &merged, f);
    }
    let plain = dir.join("plain");
    run(args(&plain, &["--no-refine"]));
    let rows = std::fs::read_to_string(plain.join("sweep.csv")).unwrap().lines().count() - 1;
    assert_eq!(rows, 3 * 2, "--no-refine kept the grid");
    // More shards than points: some shard would be empty and `merge` could
    // never be given them all, so it is refused up front, naming --shard.
    let v = args(&dir.join("too-many"), &["--no-refine", "--shard", "0/7"]);
    let (ok, _, err) = stickslip_out(&v.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(!ok && err.contains("--shard") && err.contains("6 point"), "{err}");
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

/// Runs stickslip and returns (success, stdout, stderr).
fn stickslip_out(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_stickslip")).args(args).output().expect("runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `--backend gpu` refuses a software adapter unless `--allow-software-gpu`
/// is given, and every run states the adapter kind. Which case this
/// machine shows depends on its adapter; both are checked against the
/// library's own classification, so neither is skipped.
#[test]
fn gpu_backend_refuses_a_software_adapter_unless_allowed() {
    use stickslip::engine::gpu::{AdapterClass, GpuContext};
    let dir = scratch("software-gpu");
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    let tiny = ["--frequencies", "7", "--normal-forces", "16.39", "--realisations", "2", "--cycles", "3"];
    let mut plain = vec!["sweep", "--backend", "gpu", "--no-plots", "--warmup-cycles", "2", "--out", out_s];
    plain.extend_from_slice(&tiny);
    let class = GpuContext::new(true).map(|c| c.adapter_class());
    let (ok, _, err) = stickslip_out(&plain);
    match class {
        Ok(AdapterClass::Software) => {
            assert!(!ok && err.contains("--allow-software-gpu"), "software adapter accepted silently: {err}");
            assert!(!out.exists(), "the refused run wrote {out_s}");
            let (ok, _, err) = stickslip_out(&[plain.as_slice(), &["--allow-software-gpu"]].concat());
            assert!(ok && err.contains("adapter: software GPU"), "{err}");
            let (ok, _, err) = stickslip_out(&["check-gpu"]);
            assert!(!ok && err.contains("--allow-software-gpu"), "{err}");
        }
        Ok(AdapterClass::Hardware) => {
            assert!(ok && err.contains("adapter: hardware GPU"), "{err}");
        }
        Err(e) => assert!(!ok, "no adapter ({e}), yet --backend gpu ran: {err}"),
    }
    let (ok, _, err) = stickslip_out(
        &["sweep", "--backend", "cpu", "--no-plots", "--out", dir.join("cpu").to_str().unwrap()]
            .into_iter()
            .chain(tiny)
            .collect::<Vec<_>>(),
    );
    assert!(ok && err.contains("adapter: none (CPU reference)"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// One output policy: results on stdout, progress and the backend on
/// stderr (plain lines when it is not a terminal), nothing there with -q.
#[test]
fn cli_results_go_to_stdout_and_quiet_silences_stderr() {
    let dir = scratch("streams");
    let args = |out: &std::path::Path| {
        vec![
            "sweep".to_string(),
            "--backend".into(),
            "cpu".into(),
            "--no-plots".into(),
            "--frequencies".into(),
            "7".into(),
            "--normal-forces".into(),
            "16.39".into(),
            "--realisations".into(),
            "2".into(),
            "--cycles".into(),
            "3".into(),
            "--warmup-cycles".into(),
            "2".into(),
            "--out".into(),
            out.to_str().unwrap().to_string(),
        ]
    };
    let loud = args(&dir.join("loud"));
    let (ok, stdout, stderr) = stickslip_out(&loud.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok, "{stderr}");
    assert!(stdout.contains("wrote") && !stderr.contains("wrote"), "stdout: {stdout}\nstderr: {stderr}");
    assert!(stderr.contains("backend: CPU") && stderr.contains("adapter: "), "{stderr}");
    assert!(stderr.contains("sweep: [") && stderr.contains("done"), "no plain progress lines: {stderr}");
    let mut quiet = args(&dir.join("quiet"));
    quiet.insert(0, "--quiet".into());
    let (ok, stdout, stderr) = stickslip_out(&quiet.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok && stderr.is_empty(), "--quiet printed: {stderr}");
    assert!(stdout.contains("wrote"), "{stdout}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Completions and the man page come from the clap definitions.
#[test]
fn cli_completions_and_man_page() {
    let (ok, stdout, err) = stickslip_out(&["completions", "bash"]);
    assert!(ok && stdout.contains("_stickslip") && stdout.contains("--allow-software-gpu"), "{err}");
    let (ok, stdout, err) = stickslip_out(&["completions", "zsh"]);
    assert!(ok && stdout.contains("#compdef stickslip"), "{err}");
    let (ok, stdout, err) = stickslip_out(&["man"]);
    assert!(ok && stdout.contains(".TH stickslip") && stdout.contains(".SH \"STICKSLIP-SWEEP\""), "{err}\n{stdout}");
    assert!(stdout.contains("Random seed"), "the man page lacks --seed's help");
}

/// A reader that goes away (`stickslip completions bash | head`) ends the
/// command quietly: exit 0, nothing on stderr, no panic; and `--help` lists
/// `completions` and `man`.
#[test]
fn cli_a_closed_stdout_ends_quietly() {
    for args in [&["completions", "bash"][..], &["completions", "zsh"], &["completions", "fish"], &["man"]] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_stickslip"))
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("runs");
        // Close the only read end before the child writes: every write fails with EPIPE.
        drop(child.stdout.take());
        let out = child.wait_with_output().expect("ends");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success() && stderr.is_empty(), "{args:?}: {:?}, stderr: {stderr}", out.status);
    }
    let (ok, stdout, err) = stickslip_out(&["--help"]);
    assert!(ok, "{err}");
    for command in ["completions", "man"] {
        assert!(stdout.lines().any(|l| l.trim_start().starts_with(command)), "--help lacks `{command}`:\n{stdout}");
    }
}

/// `simulate` writes its sample times as `i / rate`, the shortest decimal
/// that reads back as that `f64`: no float noise such as 0.0016666666666669272.
#[test]
fn simulate_writes_exact_sample_times() {
    let dir = scratch("times");
    let out = dir.join("out");
    let (ok, _, err) = stickslip_out(&[
        "simulate",
        "--out",
        out.to_str().unwrap(),
        "--realisations",
        "1",
        "--duration",
        "2",
        "--warmup-cycles",
        "3",
    ]);
    assert!(ok, "{err}");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    let text = std::fs::read_to_string(out.join(manifest["runs"][0]["file"].as_str().unwrap())).unwrap();
    for (i, line) in text.lines().skip(1).enumerate() {
        let t = line.split(',').next().unwrap();
        assert_eq!(t, format!("{}", i as f64 / 600.0), "sample {i}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The paper's Figure 8 workflow: a one-frequency grid at the measured loads
/// shows the simulated means beside the measured ones, with the miss in per
/// cent; a grid at other loads sets each measured point against the nearest
/// simulated load and says so; titles are captions.
#[test]
fn plot_sets_measured_points_against_their_loads() {
    let dir = scratch("figure8-plot");
    let figure8 = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/figure8");
    let sweep = |forces: &str, out: &Path| {
        let (ok, _, err) = stickslip_out(&[
            "sweep",
            "--backend",
            "cpu",
            "--frequencies",
            "7",
            "--normal-forces",
            forces,
            "--realisations",
            "4",
            "--cycles",
            "20",
            "--warmup-cycles",
            "20",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        let (ok, _, err) = stickslip_out(&["plot", out.to_str().unwrap(), "--measured", figure8.to_str().unwrap()]);
        assert!(ok, "{err}");
        (std::fs::read_to_string(out.join("fig9a.svg")).unwrap(), err)
    };
    let (same, _) = sweep("7.519,11.5,15.3,16.39", &dir.join("same"));
    for load in ["7.519 N: simulated", "11.5 N: simulated", "15.3 N: simulated", "16.39 N: simulated"] {
        assert!(same.contains(load), "fig9a lacks `{load}`");
    }
    assert!(same.contains("Figure 9(a) at one frequency") && !same.contains("nearest simulated load"));
    let (nearest, err) = sweep("4,8,12,16.39", &dir.join("nearest"));
    assert!(nearest.contains("nearest simulated load 8 N"), "7.519 N is not set against 8 N");
    assert!(nearest.contains("nearest simulated load 16.39 N"), "15.3 N is not set against 16.39 N");
    assert!(err.contains("against the nearest simulated load 8 N"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `plot` redraws a sweep without simulating, with the measured Figure 8
/// statistics drawn over it, at a journal size; and a diagnosis's charts.
#[test]
fn plot_redraws_a_sweep_with_the_measured_overlay() {
    let dir = scratch("plot");
    let sweep = dir.join("sweep");
    let figure8 = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/figure8");
    let (ok, _, err) = stickslip_out(&[
        "sweep",
        "--backend",
        "cpu",
        "--no-plots",
        "--frequencies",
        "6,7,8",
        "--normal-forces",
        "7.519,16.39",
        "--realisations",
        "4",
        "--cycles",
        "20",
        "--warmup-cycles",
        "5",
        "--out",
        sweep.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(!sweep.join("fig9a.png").exists());
    let figs = dir.join("figs");
    let (ok, stdout, err) = stickslip_out(&[
        "plot",
        sweep.to_str().unwrap(),
        "--measured",
        figure8.to_str().unwrap(),
        "--size",
        "single",
        "--out",
        figs.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("wrote") && err.contains("11.5 N is not a grid point"), "{stdout}\n{err}");
    for f in ["fig9a", "fig9b", "fig9c", "fig8"] {
        let png = std::fs::read(figs.join(format!("{f}.png"))).unwrap_or_else(|_| panic!("{f}.png written"));
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        // single column at 300 dpi: 1050 px wide (the PNG header's width field)
        assert_eq!(u32::from_be_bytes(png[16..20].try_into().unwrap()), 1050, "{f}.png width");
        let svg = std::fs::read_to_string(figs.join(format!("{f}.svg"))).unwrap();
        // fig9c: the Figure 8 set has no phase to draw
        assert!(svg.contains("<text") && (f == "fig9c" || svg.contains("measured")), "{f}.svg has no measured overlay");
    }
    let svg = std::fs::read_to_string(figs.join("fig9b.svg")).unwrap();
    assert!(svg.contains("10⁻"), "fig9b's decades are not labelled 10ⁿ");
    assert!(!svg.contains(".0\n</text>"), "a tick reads like 200.0");
    // Neither a sweep nor a diagnosis: refused by name, nothing written.
    let (ok, _, err) = stickslip_out(&["plot", figure8.to_str().unwrap(), "--out", dir.join("x").to_str().unwrap()]);
    assert!(!ok && err.contains("neither a sweep"), "{err}");
    assert!(!dir.join("x").exists());
    // A directory that does not exist is said to be missing.
    let missing = dir.join("no-such-sweep");
    let (ok, _, err) = stickslip_out(&["plot", missing.to_str().unwrap()]);
    assert!(!ok && err.contains("no-such-sweep") && err.contains("no such directory"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
