//! Hostile and absurd input, faults and concurrent runs (issue 11): every
//! class is refused cleanly, by name, without hanging, writing or leaking,
//! and valid input still works. Each case is small: the whole file runs in
//! seconds.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use stickslip::Error;
use stickslip::engine::{Condition, InitialState, Job, Model, PeakRange, Point, Record, RunPlan};
use stickslip::measure::read_measurement_set;
use stickslip::sweep::{
    AccumulatorFile, Grid, RunIdentity, Shard, SweepSettings, merge_shards, read_accumulators, run_sweep,
    write_accumulators,
};

use crate::common;

/// A scratch directory removed when dropped.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("stickslip-hostile-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir.canonicalize().unwrap())
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    pub fn write(&self, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
        let p = self.0.join(name);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).unwrap();
        }
        std::fs::write(&p, text).unwrap();
        p
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

pub(crate) fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_stickslip"))
}

pub(crate) fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("stickslip runs")
}

pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs the command line and asserts a refusal with exit code 1 whose
/// message contains every string of `names`; returns the message.
#[track_caller]
pub(crate) fn refused(args: &[&str], names: &[&str]) -> String {
    let o = run(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?} should be refused with exit code 1: {err}");
    for n in names {
        assert!(err.contains(n), "the error for {args:?} should name `{n}`: {err}");
    }
    assert!(err.matches("os error").count() <= 1, "the OS error is repeated: {err}");
    err
}

/// Calls `f` on another thread and fails if it does not return within `limit`.
#[track_caller]
fn within<T: Send + 'static>(limit: Duration, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(limit).expect("the call hung")
}

pub(crate) const RIG: &str = r#"{ "mass_kg": 1.028, "natural_frequency_hz": 10.05, "damping_ratio": 0.00225 }"#;

pub(crate) fn manifest(file: &str) -> String {
    let file = serde_json::to_string(file).unwrap();
    format!(
        r#"{{ "format": "stickslip-measurements/1", "rig": {RIG},
             "runs": [ {{ "file": {file}, "excitation_frequency_hz": 7.0,
                          "excitation_amplitude_m": 0.0025, "normal_force_n": 16.0 }} ] }}"#
    )
}

/// A valid run file: 2 s at 600 Hz of a 7 Hz oscillation.
pub(crate) fn run_csv() -> String {
    let mut text = String::from("t,x,v,normal_force,friction_force\n");
    for i in 0..1200 {
        let t = i as f64 / 600.0;
        let phase = std::f64::consts::TAU * 7.0 * t;
        let v = -0.004 * 7.0 * phase.sin();
        // A friction force of 1 N opposing the motion.
        text += &format!("{t},{},{v},16,{}\n", 0.004 * phase.cos(), -v.signum());
    }
    text
}

#[track_caller]
pub(crate) fn measurement_refused(dir: &Path, names: &[&str]) -> String {
    let err = read_measurement_set(dir).expect_err("the set should be refused");
    assert!(matches!(err, Error::Measurement { .. }), "{err:?}");
    let text = err.to_string();
    for n in names {
        assert!(text.contains(n), "the error should name `{n}`: {text}");
    }
    text
}

/// Files a measurement set names must lie inside it, after following links;
/// anything else is refused by name without being read, and nothing of it
/// is quoted.
#[test]
fn confinement_to_the_measurement_set() {
    let s = Scratch::new("confine");
    s.write("outside/secret.csv", format!("t,x\nSECRET-TOKEN,1\n{}", run_csv()));
    s.write("outside/r.csv", run_csv());
    let set = |name: &str, entry: &str| {
        let dir = s.path(name);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("manifest.json"), manifest(entry)).unwrap();
        dir
    };
    let outside = s.path("outside/r.csv");
    for (name, entry) in [
        ("dotdot", "../outside/r.csv"),
        ("absolute", outside.to_str().unwrap()),
        ("passwd", "/etc/passwd"),
        ("environ", "/proc/self/environ"),
        ("deep", "a/../../outside/secret.csv"),
    ] {
        let err = measurement_refused(&set(name, entry), &["manifest.json", "runs[0].file", "outside"]);
        assert!(!err.contains("SECRET") && !err.contains("root:") && !err.contains("PATH="), "{err}");
    }
    // Links that lead out: a file link, a directory link, a link to a device.
    let dir = set("link", "r.csv");
    std::os::unix::fs::symlink(&outside, dir.join("r.csv")).unwrap();
    measurement_refused(&dir, &["runs[0].file", "`r.csv`", "outside"]);
    let dir = set("dirlink", "sub/secret.csv");
    std::os::unix::fs::symlink(s.path("outside"), dir.join("sub")).unwrap();
    let err = measurement_refused(&dir, &["outside"]);
    assert!(!err.contains("SECRET"), "{err}");
    let dir = set("devlink", "z.csv");
    std::os::unix::fs::symlink("/dev/zero", dir.join("z.csv")).unwrap();
    within(Duration::from_secs(20), move || measurement_refused(&dir, &["outside"]));
    // The manifest itself may not lead out, nor the summary.
    let dir = s.path("manifest-link");
    std::fs::create_dir_all(&dir).unwrap();
    std::os::unix::fs::symlink(s.path("dotdot/manifest.json"), dir.join("manifest.json")).unwrap();
    measurement_refused(&dir, &["manifest.json", "outside"]);
    let dir = s.path("summary-out");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("manifest.json"),
        format!(r#"{{ "format": "stickslip-measurements/1", "rig": {RIG}, "summary": "../outside/secret.csv" }}"#),
    )
    .unwrap();
    let err = measurement_refused(&dir, &["summary", "outside"]);
    assert!(!err.contains("SECRET"), "{err}");
    // Links and `..` that stay inside are fine.
    let dir = set("inside", "sub/../data/r.csv");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::create_dir_all(dir.join("data")).unwrap();
    std::fs::write(dir.join("data/r.csv"), run_csv()).unwrap();
    read_measurement_set(&dir).expect("a name that stays inside reads");
    let dir = set("inside-link", "alias.csv");
    std::fs::write(dir.join("r.csv"), run_csv()).unwrap();
    std::os::unix::fs::symlink(dir.join("r.csv"), dir.join("alias.csv")).unwrap();
    read_measurement_set(&dir).expect("a link inside the set reads");
    // The command line refuses the same, writes nothing, and exits 1.
    let out = s.path("out");
    refused(
        &["diagnose", "--backend", "cpu", s.path("dotdot").to_str().unwrap(), "--out", out.to_str().unwrap()],
        &["outside"],
    );
    assert!(!out.exists());
}

/// Everything read must be a regular file within its size limit: FIFOs,
/// devices and directories are refused at once (never blocking), big files
/// before they are read; a byte-order mark is fine; quoted content is short
/// and escaped.
#[test]
fn bounded_reading() {
    let s = Scratch::new("bounded");
    let fifo = |p: &Path| {
        let c = std::ffi::CString::new(p.to_str().unwrap()).unwrap();
        // SAFETY: a valid path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    };
    // A FIFO as run file, as manifest, as --config and as accumulators.json.
    let dir = s.path("fifo-run");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("manifest.json"), manifest("r.csv")).unwrap();
    fifo(&dir.join("r.csv"));
    within(Duration::from_secs(20), move || measurement_refused(&dir, &["r.csv", "FIFO"]));
    let dir = s.path("fifo-manifest");
    std::fs::create_dir_all(&dir).unwrap();
    fifo(&dir.join("manifest.json"));
    within(Duration::from_secs(20), move || measurement_refused(&dir, &["manifest.json", "FIFO"]));
    let toml = s.path("fifo.toml");
    fifo(&toml);
    let t = toml.clone();
    let err = within(Duration::from_secs(20), move || Model::from_file(&t, &[]).unwrap_err().to_string());
    assert!(err.contains("fifo.toml") && err.contains("FIFO"), "{err}");
    let shard = s.path("fifo-shard");
    std::fs::create_dir_all(&shard).unwrap();
    fifo(&shard.join("accumulators.json"));
    let sh = shard.clone();
    let err = within(Duration::from_secs(20), move || read_accumulators(&sh).unwrap_err().to_string());
    assert!(err.contains("accumulators.json") && err.contains("FIFO"), "{err}");
    // Devices and directories.
    for (path, kind) in [("/dev/zero", "character device"), ("/dev/urandom", "character device"), ("/tmp", "directory")]
    {
        let err = within(Duration::from_secs(20), move || Model::from_file(Path::new(path), &[]).unwrap_err());
        assert!(err.to_string().contains(kind), "{err}");
    }
    // Big (sparse) files are refused by their size, before reading.
    let big = s.path("big.toml");
    std::fs::File::create(&big).unwrap().set_len(3 << 30).unwrap();
    let err = Model::from_file(&big, &[]).unwrap_err().to_string();
    assert!(err.contains("over the limit") && err.contains("1 MiB"), "{err}");
    let dir = s.path("big-run");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("manifest.json"), manifest("r.csv")).unwrap();
    std::fs::File::create(dir.join("r.csv")).unwrap().set_len(5 << 30).unwrap();
    measurement_refused(&dir, &["r.csv", "over the limit", "256 MiB"]);
    // A pseudo-file as --config: parsed within the limit, and not quoted.
    let err = Model::from_file(Path::new("/proc/self/environ"), &[]).unwrap_err().to_string();
    assert!(!err.contains("PATH=") && !err.contains("HOME="), "{err}");
    // A byte-order mark in a manifest and in a model file reads.
    let dir = s.path("bom");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("manifest.json"), format!("\u{feff}{}", manifest("r.csv"))).unwrap();
    std::fs::write(dir.join("r.csv"), run_csv()).unwrap();
    read_measurement_set(&dir).expect("a manifest with a BOM reads");
    let model = s.write("bom.toml", format!("\u{feff}{}", stickslip::engine::model::PAPER_RIG_TOML));
    Model::from_file(&model, &[]).expect("a model file with a BOM reads");
    // Quoted content is short and escaped (no terminal escapes reach the terminal).
    let dir = s.path("escapes");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("manifest.json"), manifest("r.csv")).unwrap();
    std::fs::write(dir.join("r.csv"), format!("t,x\n0,\u{1b}[2J\u{1b}]0;owned\u{7}{}\n", "A".repeat(5000))).unwrap();
    let err = measurement_refused(&dir, &["r.csv:2", "not a number"]);
    assert!(!err.contains('\u{1b}') && !err.contains('\u{7}') && err.len() < 400, "{err}");
    let err = measurement_refused(
        &{
            let d = s.path("long-header");
            std::fs::create_dir_all(&d).unwrap();
            std::fs::write(d.join("manifest.json"), manifest("r.csv")).unwrap();
            std::fs::write(
                d.join("r.csv"),
                format!("{}\n1\n", (0..5000).map(|i| format!("c{i}")).collect::<Vec<_>>().join(",")),
            )
            .unwrap();
            d
        },
        &["missing required column `t`"],
    );
    assert!(err.len() < 600, "{err}");
}

/// Values outside the physical ranges are refused wherever they come from,
/// naming the key or flag.
#[test]
fn physics_that_stays_finite() {
    for (key, value) in [
        ("excitation.amplitude_m", "1e308"),
        ("rig.mass_kg", "1e308"),
        ("rig.mass_kg", "5e-324"),
        ("rig.natural_frequency_hz", "1e308"),
        ("friction.a", "1e308"),
        ("friction.b", "1e308"),
        ("friction.c", "1e308"),
        ("friction.d", "-1e308"),
        ("friction.sigma", "1e308"),
        ("normal_force.sigma", "1e308"),
        ("noise.interval_s", "1e-300"),
        ("rig.damping_ratio", "nan"),
        ("rig.mass_kg", "inf"),
        ("normal_force_harmonics.amplitudes_n", "[1e308, 0, 0, 0]"),
        ("stiction.excess", "1e308"),
        ("normal_force_drift.rate_per_s", "1e308"),
    ] {
        let err = Model::paper_rig(&[format!("{key}={value}")]).expect_err(key).to_string();
        assert!(err.contains(key), "{key}={value}: {err}");
        assert!(err.len() < 300, "no 309-digit numbers: {err}");
    }
    // The quadratic forms' curvatures, beside the strengths their tables need.
    for (table, key) in [
        ("normal_force_drift.rate_per_s=0.01", "normal_force_drift.curvature_per_s2"),
        ("load_dependent_friction.strength=0.01", "load_dependent_friction.curvature_per_n2"),
    ] {
        let err = Model::paper_rig(&[table.into(), format!("{key}=-1e308")]).expect_err(key).to_string();
        assert!(err.contains(key) && err.len() < 300, "{err}");
    }
    // A table no model has, made by a `--set`, blames that flag.
    let err = Model::paper_rig(&["foo.bar=1".into()]).expect_err("unknown table").to_string();
    assert!(err.contains("--set foo.bar=1") && err.contains("unknown table `foo`"), "{err}");
    // A rule over two keys names both: a friction level below −b.
    let err = Model::paper_rig(&["friction.a=-0.5".into()]).expect_err("a + b < 0").to_string();
    assert!(err.contains("friction.a") && err.contains("friction.b") && err.contains("-0.4"), "{err}");
    // The frequency Figure 8 is drawn at, for a sweep or a redraw.
    refused(&["sweep", "--fig8-frequency", "-5", "--out", "/nonexistent/x"], &["--fig8-frequency", "> 0 Hz"]);
    refused(&["plot", "/nonexistent/y", "--fig8-frequency", "0"], &["--fig8-frequency", "> 0 Hz"]);
    // Grid flags name the flag and the physical rule, negative numbers included.
    refused(&["sweep", "--normal-forces", "-1", "--out", "/nonexistent/x"], &["--normal-forces", ">= 0 N"]);
    refused(&["sweep", "--normal-forces", "1e308", "--out", "/nonexistent/x"], &["--normal-forces"]);
    refused(&["sweep", "--frequencies", "0", "--out", "/nonexistent/x"], &["--frequencies", "> 0 Hz"]);
    refused(&["sweep", "--frequencies", "1e9", "--out", "/nonexistent/x"], &["--frequencies"]);
    refused(&["simulate", "--frequency", "-7", "--out", "/nonexistent/x"], &["--frequency", "> 0 Hz"]);
    // Manifests likewise.
    let s = Scratch::new("physics");
    for (from, to, key) in [
        ("\"mass_kg\": 1.028", "\"mass_kg\": 1e308", "rig.mass_kg"),
        ("\"excitation_frequency_hz\": 7.0", "\"excitation_frequency_hz\": 1e308", "excitation_frequency_hz"),
        ("\"excitation_amplitude_m\": 0.0025", "\"excitation_amplitude_m\": 1e300", "excitation_amplitude_m"),
        ("\"normal_force_n\": 16.0", "\"normal_force_n\": 1e300", "normal_force_n"),
    ] {
        let dir = s.path(key);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("manifest.json"), manifest("r.csv").replace(from, to)).unwrap();
        std::fs::write(dir.join("r.csv"), run_csv()).unwrap();
        measurement_refused(&dir, &[key, "physically sensible"]);
    }
}

/// Both integrators check every finished path: a path that leaves the
/// finite numbers fails the run, naming the grid point, and nothing of it
/// is quantised or binned.
#[test]
fn non_finite_paths_fail_naming_the_grid_point() {
    // A start far outside f32 (and, with a quadratic friction term, outside
    // f64 after a step): valid input cannot get here, a broken start can.
    let model = Model::paper_rig(&["friction.d=1".into(), "friction.sigma=0".into()]).unwrap();
    let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 10.0 };
    let points = [Point {
        condition,
        initial: InitialState { x_m: 1e300, v_m_per_s: 1e300 },
        range: PeakRange::for_point(&model, condition),
        realisation_offset: 0,
    }];
    let job = Job {
        model: &model,
        points: &points,
        realisations: 2,
        first_realisation: 0,
        seed: 1,
        plan: RunPlan { warmup_cycles: 0, measured_cycles: 2 },
        record: Record::Sums,
    };
    for engine in [common::cpu(), common::gpu()] {
        let err = engine.sums(&job, &mut |_, _| {}).expect_err("a diverged path is refused");
        assert!(matches!(err, Error::Diverged { .. }), "{err:?}");
        assert!(err.to_string().contains("7 Hz, 10 N"), "{err}");
    }
    // The reduction never quantises a non-finite value.
    let mut acc = stickslip::engine::PointAccumulator::new(points[0].range);
    acc.tally_period(f64::NAN, 0.0, 0.0);
    acc.tally_period(1e300, 0.0, 0.0);
    acc.tally_period(1e-3, f64::INFINITY, 0.0);
    assert_eq!((acc.non_finite, acc.peaks, acc.histogram.iter().sum::<u64>()), (3, 0, 0));
}

/// Both backends refuse the same oversized requests with the same message,
/// before allocating; the command line refuses them naming the flag.
#[test]
fn bounded_memory_and_work() {
    let model = Model::default();
    let points = [Point::steady(&model, Condition { excitation_frequency_hz: 7.0, normal_force_n: 10.0 })];
    let base = Job {
        model: &model,
        points: &points,
        realisations: 4,
        first_realisation: 0,
        seed: 1,
        plan: RunPlan { warmup_cycles: 1, measured_cycles: 1 },
        record: Record::Sums,
    };
    let too_big = [
        Job { realisations: 4_000_000_000, ..base },
        Job { plan: RunPlan { warmup_cycles: 0, measured_cycles: 4_000_000_000 }, ..base },
        Job {
            record: Record::Samples { interval_s: 1.0 / 600.0, duration_s: 1e12, at_noise_boundaries: false },
            ..base
        },
        Job {
            record: Record::Peaks,
            realisations: 1 << 20,
            plan: RunPlan { warmup_cycles: 0, measured_cycles: 1 << 10 },
            ..base
        },
    ];
    for job in &too_big {
        let cpu = common::cpu().run(job, &mut |_, _| {}).expect_err("the CPU refuses").to_string();
        let gpu = common::gpu().run(job, &mut |_, _| {}).expect_err("the GPU refuses").to_string();
        assert_eq!(cpu, gpu, "both backends refuse with the same message");
        assert!(cpu.contains("limit"), "{cpu}");
    }
    // A point's realisation offset counts as well: numbers past 2^32 are
    // refused by both, with one message.
    let shifted = [Point { realisation_offset: u32::MAX - 2, ..points[0] }];
    let job = Job { points: &shifted, ..base };
    let cpu = common::cpu().run(&job, &mut |_, _| {}).expect_err("the CPU refuses").to_string();
    let gpu = common::gpu().run(&job, &mut |_, _| {}).expect_err("the GPU refuses").to_string();
    assert_eq!(cpu, gpu, "both backends refuse with the same message");
    assert!(cpu.contains("realisation") && cpu.contains("2^32"), "{cpu}");
    let many: Vec<Point> = (0..Job::MAX_POINTS + 1).map(|_| points[0]).collect();
    let err = Job { points: &many, ..base }.validate().unwrap_err().to_string();
    assert!(err.contains("grid") && err.contains("limit"), "{err}");
    // The command line, in well under a second each.
    let started = Instant::now();
    refused(&["sweep", "--frequencies", "5:15:1000000000", "--out", "/nonexistent/x"], &["--frequencies", "at most"]);
    refused(
        &["sweep", "--backend", "cpu", "--realisations", "4000000000", "--out", "/nonexistent/x"],
        &["--realisations"],
    );
    refused(&["sweep", "--backend", "cpu", "--cycles", "4000000000", "--out", "/nonexistent/x"], &["--cycles"]);
    refused(&["simulate", "--duration", "1e12", "--out", "/nonexistent/x"], &["--duration"]);
    assert!(started.elapsed() < Duration::from_secs(20), "refusals must come before any work");
}

/// The diagnosis refuses absurd settings and records before any work.
#[test]
fn absurd_diagnosis_settings() {
    let s = Scratch::new("diagnose");
    let set = s.path("set");
    std::fs::create_dir_all(&set).unwrap();
    std::fs::write(set.join("manifest.json"), manifest("r.csv")).unwrap();
    std::fs::write(set.join("r.csv"), run_csv()).unwrap();
    let set_s = set.to_str().unwrap();
    let out = s.path("out");
    let out_s = out.to_str().unwrap();
    for (flag, value) in [
        ("--replicates", "0"),
        ("--replicates", "1"),
        ("--realisations", "0"),
        ("--sample-rate", "0"),
        ("--sample-rate", "-600"),
        ("--sample-rate", "nan"),
    ] {
        refused(&["diagnose", "--backend", "cpu", flag, value, set_s, "--out", out_s], &[flag]);
    }
    // --out equal to, inside or containing the input set; the set is untouched.
    let before: Vec<_> = std::fs::read_dir(&set).unwrap().map(|e| e.unwrap().file_name()).collect();
    refused(&["diagnose", "--backend", "cpu", set_s, "--out", set_s], &["--out", "input"]);
    refused(&["diagnose", "--backend", "cpu", set_s, "--out", &format!("{set_s}/out")], &["--out", "inside"]);
    refused(&["diagnose", "--backend", "cpu", set_s, "--out", s.0.to_str().unwrap()], &["--out", "contains"]);
    let after: Vec<_> = std::fs::read_dir(&set).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(before, after);
    assert!(!out.exists());
    // A record sampled below twice its excitation frequency, and n_peaks 0.
    let slow: String = run_csv()
        .lines()
        .enumerate()
        .filter(|(i, _)| *i == 0 || (i - 1) % 100 == 0)
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    std::fs::write(set.join("r.csv"), slow).unwrap();
    std::fs::write(set.join("manifest.json"), manifest("r.csv")).unwrap();
    measurement_refused(&set, &["r.csv", "Nyquist"]);
    write_summary_set(
        &set,
        "excitation_frequency_hz,excitation_amplitude_m,normal_force_mean_n,peak_mean_m,peak_var_m2,n_peaks\n\
         7,0.0025,16.39,0.0038,2.8e-8,0\n",
    );
    measurement_refused(&set, &["s.csv:2", "n_peaks"]);
}

/// Makes `dir` a measurement set whose manifest names the summary table
/// `s.csv`, holding `table` (its header and rows).
pub(crate) fn write_summary_set(dir: &Path, table: &str) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(
        dir.join("manifest.json"),
        format!(r#"{{ "format": "stickslip-measurements/1", "rig": {RIG}, "summary": "s.csv" }}"#),
    )
    .unwrap();
    std::fs::write(dir.join("s.csv"), table).unwrap();
}

/// A small CPU sweep into `out`; a flag in `extra` replaces the default.
pub(crate) fn sweep_args<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let defaults = [
        ("--frequencies", "7"),
        ("--normal-forces", "10"),
        ("--realisations", "2"),
        ("--cycles", "2"),
        ("--warmup-cycles", "1"),
    ];
    let mut v = vec!["sweep", "--backend", "cpu", "--out", out];
    for (flag, value) in defaults {
        if !extra.contains(&flag) {
            v.extend([flag, value]);
        }
    }
    v.extend_from_slice(extra);
    v
}

/// The names in a directory, sorted.
pub(crate) fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = match std::fs::read_dir(dir) {
        Ok(entries) => entries.map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect(),
        Err(_) => Vec::new(),
    };
    names.sort();
    names
}

/// Every file's bytes, by name.
pub(crate) fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    listing(dir).into_iter().map(|n| (n.clone(), std::fs::read(dir.join(&n)).unwrap())).collect()
}

/// Waits until a run into `parent/name` holds its lock and has its staging
/// directory (then it is computing).
fn wait_for_staging(parent: &Path, name: &str) {
    let started = Instant::now();
    loop {
        let names = listing(parent);
        let locked = names.iter().any(|n| *n == format!(".{name}.stickslip-lock"));
        let staging = names.iter().any(|n| n.starts_with(&format!(".{name}.stickslip-")) && n.ends_with(".tmp"));
        if locked && staging {
            return;
        }
        assert!(started.elapsed() < Duration::from_secs(60), "the run never started: {names:?}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn signal(child: &std::process::Child, sig: libc::c_int) {
    // SAFETY: signals a child of this process.
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, sig) }, 0);
}

/// An output directory holds one run's complete set or the previous one:
/// re-runs replace the whole set, a second run into the same place is
/// refused, an interrupted or killed run leaves the previous set and no
/// temporaries, and a bad --out is refused before any computation.
#[test]
fn atomic_output_sets_and_concurrent_runs() {
    let s = Scratch::new("output");
    let out = s.path("out");
    let out_s = out.to_str().unwrap();
    // A set with plots, then a re-run without: no figure of the first remains.
    let o = run(&sweep_args(out_s, &[]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(listing(&out).iter().any(|n| n == "fig8.png"));
    let o = run(&sweep_args(out_s, &["--no-plots", "--seed", "2"]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(listing(&out), [".stickslip-output", "accumulators.json", "histograms.csv", "sweep.csv", "sweep.json"]);
    assert_eq!(listing(&s.0), ["out"], "no temporaries or locks are left beside the set");
    let previous = snapshot(&out);

    // A long run holds the lock; a second run into the same --out is refused at once.
    let long = sweep_args(out_s, &["--no-plots", "--realisations", "64", "--cycles", "1000000", "--seed", "3"]);
    let mut a = bin().args(&long).stderr(std::process::Stdio::null()).spawn().unwrap();
    wait_for_staging(&s.0, "out");
    let started = Instant::now();
    refused(&sweep_args(out_s, &["--no-plots"]), &["--out", "another stickslip run"]);
    assert!(started.elapsed() < Duration::from_secs(10));
    // SIGTERM: the unfinished set, its lock and staging go; the previous set stays whole.
    signal(&a, libc::SIGTERM);
    assert_eq!(a.wait().unwrap().code(), Some(143));
    assert_eq!(snapshot(&out), previous);
    assert_eq!(listing(&s.0), ["out"]);
    // SIGINT likewise (exit 130).
    let mut b = bin().args(&long).stderr(std::process::Stdio::null()).spawn().unwrap();
    wait_for_staging(&s.0, "out");
    signal(&b, libc::SIGINT);
    assert_eq!(b.wait().unwrap().code(), Some(130));
    assert_eq!(snapshot(&out), previous);
    assert_eq!(listing(&s.0), ["out"]);
    // SIGKILL cannot be caught: the previous set still stays whole, and the
    // next run into the same place removes the dead run's temporaries.
    let mut c = bin().args(&long).stderr(std::process::Stdio::null()).spawn().unwrap();
    wait_for_staging(&s.0, "out");
    c.kill().unwrap();
    c.wait().unwrap();
    assert_eq!(snapshot(&out), previous);
    let o = run(&sweep_args(out_s, &["--no-plots", "--seed", "4"]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(listing(&s.0), ["out"]);

    // A bad --out is refused before any computation (this run would take minutes).
    let file = s.write("a-file", "x");
    let slow = ["--cycles", "1000000", "--realisations", "64"];
    let started = Instant::now();
    refused(&sweep_args(file.to_str().unwrap(), &slow), &["--out", "not a directory"]);
    refused(&sweep_args(s.path("a-file/sub").to_str().unwrap(), &slow), &["--out", "not a directory"]);
    refused(&sweep_args("/proc/stickslip-cannot-create", &slow), &["--out"]);
    assert!(started.elapsed() < Duration::from_secs(10), "--out must be checked before computing");
    // A directory of other files is not replaced.
    let foreign = s.path("home");
    s.write("home/notes.txt", "mine");
    refused(&sweep_args(foreign.to_str().unwrap(), &[]), &["--out", "notes.txt"]);
    assert_eq!(std::fs::read_to_string(foreign.join("notes.txt")).unwrap(), "mine");
    assert_eq!(listing(&s.0), ["a-file", "home", "out"], "a refused run leaves nothing behind");
}

/// An honest two-shard run, made through the library.
pub(crate) fn honest_shards(s: &Scratch) -> (PathBuf, PathBuf) {
    let model = Model::default();
    let grid = Grid { frequencies_hz: vec![6.0, 7.0], normal_forces_n: vec![8.0, 16.39] };
    let settings = SweepSettings { realisations: 4, plan: RunPlan { warmup_cycles: 2, measured_cycles: 4 }, seed: 3 };
    let identity = RunIdentity {
        model_toml: model.to_toml_string(),
        frequencies_hz: grid.frequencies_hz.clone(),
        normal_forces_n: grid.normal_forces_n.clone(),
        realisations: 4,
        warmup_cycles: 2,
        measured_cycles: 4,
        seed: 3,
        backend: stickslip::engine::BackendKind::Cpu,
    };
    let all = grid.conditions();
    let mut dirs = Vec::new();
    for k in 0..2 {
        let shard = Shard { index: k, count: 2 };
        let result =
            run_sweep(&model, &all[shard.points(all.len())], &settings, common::cpu(), &mut |_, _| {}).unwrap();
        let dir = s.path(&format!("shard-{k}"));
        std::fs::create_dir_all(&dir).unwrap();
        write_accumulators(&dir.join("accumulators.json"), &result.to_file(&identity, shard)).unwrap();
        dirs.push(dir);
    }
    (dirs[0].clone(), dirs[1].clone())
}

/// A forged copy of `shard` at `name`: `edit` changes the file, and the
/// digest is recomputed so that only the invariants can catch it.
pub(crate) fn forged(s: &Scratch, shard: &Path, name: &str, edit: impl FnOnce(&mut AccumulatorFile)) -> PathBuf {
    let (mut file, _) = read_accumulators(shard).unwrap();
    edit(&mut file);
    file.integrity.digest = file.content_digest();
    let dir = s.path(name);
    std::fs::create_dir_all(&dir).unwrap();
    write_accumulators(&dir.join("accumulators.json"), &file).unwrap();
    dir
}

/// Merge verifies: a tampered, truncated or forged shard is refused by name
/// (and point), the same shard twice names both, and merge --out may not be
/// one of its inputs.
#[test]
fn merge_that_verifies() {
    let s = Scratch::new("merge");
    let (a, b) = honest_shards(&s);
    merge_shards(&[a.clone(), b.clone()]).expect("honest shards merge");
    // Edited without updating the digest, or truncated.
    let edited = s.path("edited");
    std::fs::create_dir_all(&edited).unwrap();
    let text = std::fs::read_to_string(b.join("accumulators.json")).unwrap();
    std::fs::write(edited.join("accumulators.json"), text.replacen("\"peaks\":16", "\"peaks\":15", 1)).unwrap();
    let err = merge_shards(&[a.clone(), edited.clone()]).unwrap_err().to_string();
    assert!(err.contains("edited/accumulators.json") && err.contains("digest"), "{err}");
    std::fs::write(edited.join("accumulators.json"), &text[..text.len() / 2]).unwrap();
    let err = merge_shards(&[a.clone(), edited]).unwrap_err().to_string();
    assert!(err.contains("edited/accumulators.json") && err.contains("truncated"), "{err}");
    // Forged with a valid digest: each breaks an invariant of honest shards.
    type Edit = Box<dyn FnOnce(&mut AccumulatorFile)>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        ("peaks0", Box::new(|f| f.points[0].peaks = 0), "peaks"),
        ("variance", Box::new(|f| f.points[0].sum_q2 = "0".into()), "Σq²"),
        ("mean", Box::new(|f| f.points[0].sum_q = "99999999999999".into()), "Σq"),
        ("frequency", Box::new(|f| f.points[0].excitation_frequency_hz = 99.0), "grid point"),
        ("stuck", Box::new(|f| f.points[0].stick_units = 1 << 60), "stuck time"),
        ("histogram", Box::new(|f| f.points[0].histogram.push((2047, 5))), "histogram"),
        ("bins", Box::new(|f| f.points[0].histogram = vec![(5, 8), (5, 8)]), "histogram"),
        ("range", Box::new(|f| f.points[0].range.hi_m = 1.0), "peak range"),
        ("realisations", Box::new(|f| f.points[0].realisations = 1_000_000_000), "realisations"),
        ("phase", Box::new(|f| f.points[0].sum_phase_versine = "999999999999999999".into()), "phase"),
        ("shard", Box::new(|f| f.shard = Shard { index: 5, count: 2 }), "shard"),
        ("grid", Box::new(|f| f.identity.normal_forces_n = vec![8.0, 1e308]), "normal force"),
        ("points", Box::new(|f| f.points.truncate(1)), "points"),
        ("model", Box::new(|f| f.identity.model_toml = "[rig]\nmass_kg = -1\n".into()), "model"),
    ];
    for (name, edit, names) in cases {
        let dir = forged(&s, &b, name, edit);
        let err = merge_shards(&[a.clone(), dir]).expect_err(name).to_string();
        assert!(err.contains(&format!("{name}/accumulators.json")) && err.contains(names), "{name}: {err}");
    }
    // The same shard twice names both directories; a missing one is named.
    let copy = s.path("copy");
    std::fs::create_dir_all(&copy).unwrap();
    std::fs::copy(b.join("accumulators.json"), copy.join("accumulators.json")).unwrap();
    let err = merge_shards(&[a.clone(), b.clone(), copy.clone()]).unwrap_err().to_string();
    assert!(err.contains("1/2 is given twice") && err.contains("shard-1") && err.contains("copy"), "{err}");
    let err = merge_shards(&[b.clone(), b.clone()]).unwrap_err().to_string();
    assert!(err.contains("given twice"), "{err}");
    let err = merge_shards(std::slice::from_ref(&b)).unwrap_err().to_string();
    assert!(err.contains("0/2 is missing"), "{err}");
    // merge --out may be neither a shard nor contain one; nothing is written.
    let before = snapshot(&a);
    refused(&["merge", "--out", a.to_str().unwrap(), a.to_str().unwrap(), b.to_str().unwrap()], &["--out", "input"]);
    refused(&["merge", "--out", s.0.to_str().unwrap(), a.to_str().unwrap(), b.to_str().unwrap()], &["--out"]);
    assert_eq!(snapshot(&a), before);
    let out = s.path("merged");
    refused(
        &["merge", "--out", out.to_str().unwrap(), a.to_str().unwrap(), s.path("peaks0").to_str().unwrap()],
        &["peaks0"],
    );
    assert!(!out.exists());
}

/// One exit-code convention: 0 success, 1 refused input or failed run, 2
/// usage errors (clap's); messages name the flag, the key or the file.
#[test]
fn messages_and_exit_codes() {
    for args in [&["sweep", "--bogus"][..], &[][..], &["sweep", "--realisations", "x"][..], &["merge"][..]] {
        let o = run(args);
        assert_eq!(o.status.code(), Some(2), "{args:?} is a usage error: {}", stderr(&o));
    }
    let s = Scratch::new("messages");
    let table = s.write(
        "effects.toml",
        format!("{}\n[normal_force_harmonics]\namplitudes_n = [1, 2, 3]\n", stickslip::engine::model::PAPER_RIG_TOML),
    );
    refused(
        &["sweep", "--config", table.to_str().unwrap(), "--out", "/nonexistent/x"],
        &["normal_force_harmonics.amplitudes_n", "length 3"],
    );
    refused(&["sweep", "--set", "stiction.excess=abc", "--out", "/nonexistent/x"], &["stiction.excess"]);
    refused(&["sweep", "--set", "rig.mass=3", "--out", "/nonexistent/x"], &["rig.mass"]);
    let missing = s.path("absent.toml");
    refused(
        &["sweep", "--config", missing.to_str().unwrap(), "--out", "/nonexistent/x"],
        &["absent.toml", "os error 2"],
    );
    let err = refused(&["sweep", "--config", "/etc/passwd", "--out", "/nonexistent/x"], &["/etc/passwd", "line 1"]);
    assert!(!err.contains("root:"), "the file's content is not quoted: {err}");
}

/// A measurement set whose files are named as `simulate` names its own (a
/// manifest and `run-*.csv`) is a user's data, not an output set stickslip
/// wrote: `simulate --out` into it is refused and nothing changes; its own
/// previous set (stamped) is replaced whole.
#[test]
fn a_users_set_named_like_an_output_is_never_replaced() {
    let s = Scratch::new("users-set");
    s.write("lab/manifest.json", "{\"description\": \"precious lab data\"}");
    s.write("lab/run-07.0hz-16n.csv", "t,x\n0,0\n");
    let lab = s.path("lab");
    let before = snapshot(&lab);
    let args = |out: &str| -> Vec<String> {
        ["simulate", "--realisations", "1", "--duration", "2", "--warmup-cycles", "1", "--out", out]
            .iter()
            .map(|a| a.to_string())
            .collect()
    };
    let lab_args = args(lab.to_str().unwrap());
    refused(&lab_args.iter().map(String::as_str).collect::<Vec<_>>(), &["--out", ".stickslip-output", "manifest.json"]);
    assert_eq!(snapshot(&lab), before, "the user's set is untouched");
    let own = s.path("own");
    let own_args = args(own.to_str().unwrap());
    for _ in 0..2 {
        let o = run(&own_args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert!(
        listing(&own).contains(&".stickslip-output".to_string())
            && listing(&own).contains(&"manifest.json".to_string())
    );
}
