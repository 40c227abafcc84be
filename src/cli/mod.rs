//! The command line: a thin layer that parses flags, opens the engine,
//! reports progress and turns library errors into messages (`anyhow` is used
//! here and nowhere else). One submodule per command family.

mod diagnose;
mod simulate;
mod sweep;

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use crate::engine::{BackendChoice, Model};

#[derive(Parser, Debug)]
#[command(
    name = "stickslip",
    version,
    about = "Ensembles of a stochastic stick-slip friction oscillator on the GPU, checked against an exact CPU reference"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Simulate one condition and write time-series records (run files + manifest.json).
    Simulate(simulate::SimulateArgs),
    /// Run a frequency × normal-force grid and write per-point peak statistics (sweep.csv) and plots.
    Sweep(sweep::SweepArgs),
    /// Combine the outputs of `sweep --shard K/N` runs into what the unsharded run writes.
    Merge(sweep::MergeArgs),
    /// Diagnose the gap between a measurement set and the model: where, which effect, how far it shrinks.
    Diagnose(diagnose::DiagnoseArgs),
    /// Benchmark the diagnosis blind on synthetic sets with a withheld effect.
    BenchmarkDiagnosis(diagnose::BenchmarkArgs),
}

#[derive(Args, Debug)]
pub(crate) struct ModelArgs {
    /// Model file (TOML); without it, the embedded paper rig.
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
    /// Override one model parameter by its dotted key, e.g. friction.a=0.3 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(crate) set: Vec<String>,
}

impl ModelArgs {
    pub(crate) fn load(&self) -> Result<Model> {
        Ok(match &self.config {
            Some(path) => Model::from_file(path, &self.set)?,
            None => Model::paper_rig(&self.set)?,
        })
    }
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum BackendArg {
    Auto,
    Gpu,
    Cpu,
}

impl From<BackendArg> for BackendChoice {
    fn from(b: BackendArg) -> Self {
        match b {
            BackendArg::Auto => BackendChoice::Auto,
            BackendArg::Gpu => BackendChoice::Gpu,
            BackendArg::Cpu => BackendChoice::Cpu,
        }
    }
}

/// Runs the command line; returns the process exit code: 0 on success, 1
/// when the input is refused or the run fails, 2 for a usage error (clap's:
/// an unknown flag, a missing or malformed value), and 128 + n when signal
/// n (SIGINT, SIGTERM, SIGHUP) stops it after removing its unfinished output.
pub fn main() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa's Vulkan loader probes Wayland and prints a misleading
        // "error: XDG_RUNTIME_DIR is invalid" on headless machines.
        // SAFETY: no other thread exists yet.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    // While this is the only thread: every later thread inherits the signal
    // mask, and one thread takes the signals and cleans up.
    crate::io::install_interrupt_cleanup();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Simulate(args) => simulate::simulate(args),
        Command::Sweep(args) => sweep::run_sweep(args),
        Command::Merge(args) => sweep::merge(args),
        Command::Diagnose(args) => diagnose::run_diagnose(args),
        Command::BenchmarkDiagnosis(args) => diagnose::run_benchmark(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", message(&e));
            ExitCode::FAILURE
        }
    }
}

/// An error and its causes on one line, each cause only when its text is
/// not already there (an I/O error's text is part of its message).
fn message(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}

pub(crate) fn progress_bar(total: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed_precise} (eta {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}
