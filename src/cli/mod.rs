//! The command line: a thin layer that parses flags, opens the engine,
//! reports progress and turns library errors into messages (`anyhow` is used
//! here and nowhere else). One submodule per command family.
//!
//! **Output policy, the same for every command.** stdout carries the result:
//! the one-line summary of what was written (or the benchmark's table, the
//! adapter `check-gpu` found, a completion script, the man page), so that it
//! can be piped or captured. stderr carries everything about the run: the
//! `backend:`/`adapter:` lines, progress, warnings and errors. `--quiet`
//! silences stderr's progress and informational lines; errors are always
//! printed, and stdout is unchanged (redirect it to drop it). When stderr is
//! a terminal progress is a bar or spinner; otherwise (a log file, Slurm,
//! a pipe) it is plain lines, each step as it starts and a heartbeat at
//! least every `HEARTBEAT`.

mod diagnose;
mod plot;
mod simulate;
mod sweep;

pub use simulate::exact_sample_times;

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

use anyhow::Result;
use clap::{Args, CommandFactory, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use crate::engine::gpu::AdapterClass;
use crate::engine::{BackendChoice, BackendKind, Engine, GpuOptions, Model};

#[derive(Parser, Debug)]
#[command(
    name = "stickslip",
    version,
    about = "Ensembles of a stochastic stick-slip friction oscillator on the GPU, checked against an exact CPU reference",
    after_help = "Results go to stdout, progress and the backend/adapter lines to stderr (plain lines when stderr \
                  is not a terminal). Exit status: 0 success, 1 refused input or failed run, 2 usage error."
)]
struct Cli {
    #[command(flatten)]
    global: Global,
    #[command(subcommand)]
    command: Command,
}

/// Flags every command takes.
#[derive(Args, Debug, Clone, Copy, Default)]
struct Global {
    /// Print no progress or informational lines on stderr (errors still are; stdout is unchanged).
    #[arg(long, short = 'q', global = true)]
    quiet: bool,
    /// Let `--backend gpu` run on a software Vulkan adapter (Mesa's lavapipe/llvmpipe), which runs the
    /// kernel on the CPU cores; without it such an adapter is refused.
    #[arg(long, global = true)]
    allow_software_gpu: bool,
    /// Run a sweep, simulation, diagnosis or benchmark whose estimated work is beyond the cost budget
    /// (docs/formats.md); without it such a run is refused before it starts.
    #[arg(long, global = true)]
    force: bool,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Simulate one condition and write time-series records (run files + manifest.json).
    Simulate(simulate::SimulateArgs),
    /// Run a frequency × normal-force grid and write per-point peak statistics (sweep.csv) and plots.
    Sweep(sweep::SweepArgs),
    /// Combine the outputs of `sweep --shard K/N` runs into what the unsharded run writes.
    Merge(sweep::MergeArgs),
    /// Redraw the figures of a sweep or diagnosis output directory without re-simulating.
    Plot(plot::PlotArgs),
    /// Diagnose the gap between a measurement set and the model: where, which effect, how far it shrinks.
    Diagnose(diagnose::DiagnoseArgs),
    /// Run the diagnosis blind on synthetic measurement sets, each with a withheld effect (or none),
    /// and score how often it names the right one.
    BenchmarkDiagnosis(diagnose::BenchmarkArgs),
    /// Driver preflight: print the GPU adapter `--backend gpu` would take; exit 1 when there is none,
    /// or only a software one (unless --allow-software-gpu).
    CheckGpu,
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell) to stdout.
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Print the man page (roff) to stdout: `stickslip man > stickslip.1`.
    Man,
}

static GLOBAL: OnceLock<Global> = OnceLock::new();

fn global() -> Global {
    GLOBAL.get().copied().unwrap_or_default()
}

/// Whether `--quiet` was given.
pub(crate) fn quiet() -> bool {
    global().quiet
}

/// An informational line on stderr (dropped under `--quiet`).
pub(crate) fn info(line: &str) {
    if !quiet() {
        note(line);
    }
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
    /// A hardware GPU if there is one, else the f64 CPU reference.
    Auto,
    /// A GPU adapter, or fail (a software one only with --allow-software-gpu).
    Gpu,
    /// The f64 CPU reference integrator on all cores.
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
    let _ = GLOBAL.set(cli.global);
    let result = match cli.command {
        Command::Simulate(args) => simulate::simulate(args),
        Command::Sweep(args) => sweep::run_sweep(args),
        Command::Merge(args) => sweep::merge(args),
        Command::Plot(args) => plot::run_plot(args),
        Command::Diagnose(args) => diagnose::run_diagnose(args),
        Command::BenchmarkDiagnosis(args) => diagnose::run_benchmark(args),
        Command::CheckGpu => check_gpu(),
        Command::Completions { shell } => {
            // Into a buffer first: clap_complete panics when its writer fails.
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "stickslip", &mut script);
            emit_bytes(&script)
        }
        Command::Man => man_page(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of stdout went away (`stickslip man | head`): the
        // result is written or was only for it; end quietly, as on success.
        Err(e) if e.downcast_ref::<StdoutClosed>().is_some() => ExitCode::SUCCESS,
        Err(e) => {
            note(&format!("error: {}", message(&e)));
            ExitCode::FAILURE
        }
    }
}

/// stdout's reader went away (a broken pipe): not a failure of the command.
#[derive(Debug)]
pub(crate) struct StdoutClosed;

impl std::fmt::Display for StdoutClosed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("stdout was closed by its reader")
    }
}

impl std::error::Error for StdoutClosed {}

/// Writes the command's result to stdout. Every result goes through here
/// (never `println!`, which panics on a broken pipe): a closed pipe becomes
/// [`StdoutClosed`], which `main` ends on quietly.
pub(crate) fn emit_bytes(bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(bytes).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(StdoutClosed.into()),
        Err(e) => Err(anyhow::Error::new(e).context("cannot write to stdout")),
    }
}

/// One line of the command's result on stdout (see [`emit_bytes`]), its
/// control characters escaped (a path given on the command line may hold
/// any).
pub(crate) fn emit(line: &str) -> Result<()> {
    emit_bytes(format!("{}\n", crate::text::excerpt(line, usize::MAX)).as_bytes())
}

/// A line on stderr, whatever became of it: a closed stderr loses the line
/// and nothing else (`eprintln!` would panic). Control characters (a
/// terminal escape from a flag's value, say) are written escaped, whatever
/// the line quotes.
pub(crate) fn note(line: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{}", crate::text::excerpt(line, usize::MAX));
}

/// The man page: the top-level page with every visible subcommand's flags
/// appended as sections.
fn man_page() -> Result<()> {
    let cmd = Cli::command();
    let mut out = Vec::new();
    let man = clap_mangen::Man::new(cmd.clone());
    man.render_title(&mut out)?;
    man.render_name_section(&mut out)?;
    man.render_synopsis_section(&mut out)?;
    man.render_description_section(&mut out)?;
    man.render_options_section(&mut out)?;
    man.render_subcommands_section(&mut out)?;
    for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
        let name = format!("stickslip-{}", sub.get_name());
        // A one-shot command: leaking the two names is harmless.
        let title: &'static str = Box::leak(name.clone().into_boxed_str());
        let bin: &'static str = Box::leak(format!("stickslip {}", sub.get_name()).into_boxed_str());
        let sub = sub.clone().name(title).bin_name(bin);
        let page = clap_mangen::Man::new(sub);
        let mut section = Vec::new();
        page.render_synopsis_section(&mut section)?;
        page.render_options_section(&mut section)?;
        let text = String::from_utf8_lossy(&section)
            .replace(".SH SYNOPSIS", &format!(".SH \"{}\"", name.to_uppercase()))
            .replace(".SH OPTIONS", ".SS Options");
        out.extend_from_slice(text.as_bytes());
    }
    man.render_version_section(&mut out)?;
    emit_bytes(&out)
}

/// Refuses `cost` beyond the budget of `backend` unless `--force`
/// (see [`crate::budget`]).
pub(crate) fn check_budget(cost: crate::budget::Cost, backend: BackendKind, what: &str, lower: &str) -> Result<()> {
    cost.check(backend, crate::budget::cpu_threads(), force(), what, lower)?;
    Ok(())
}

/// Whether `--force` was given: a run beyond the cost budget goes ahead.
pub(crate) fn force() -> crate::budget::Force {
    crate::budget::Force::flag(global().force)
}

/// Whether a software adapter may run `--backend gpu`.
pub(crate) fn allow_software_gpu() -> bool {
    global().allow_software_gpu
}

/// The adapter an engine runs on, in words for the `adapter:` line.
fn adapter_words(engine: &Engine) -> &'static str {
    match engine.adapter() {
        Some((AdapterClass::Hardware, _)) => "hardware GPU",
        Some((AdapterClass::Software, _)) => "software GPU (allowed by --allow-software-gpu)",
        None => "none (CPU reference)",
    }
}

/// Opens the `--backend` choice ([`Engine::open`], with the global flags'
/// options) and states it on stderr: the backend line and the adapter kind
/// (hardware GPU, software GPU, or none).
pub(crate) fn open_engine(backend: BackendArg, options: GpuOptions) -> Result<Engine> {
    let engine = Engine::open(backend.into(), GpuOptions { allow_software_gpu: allow_software_gpu(), ..options })?;
    info(&format!("backend: {}", engine.description()));
    info(&format!("adapter: {}", adapter_words(&engine)));
    Ok(engine)
}

fn check_gpu() -> Result<()> {
    let options = GpuOptions { allow_software_gpu: allow_software_gpu(), ..GpuOptions::default() };
    let engine = Engine::open(BackendChoice::Gpu, options)?;
    match engine.adapter() {
        Some((AdapterClass::Hardware, name)) => emit(&format!("hardware GPU: {name}")),
        Some((AdapterClass::Software, name)) => emit(&format!("software GPU: {name}")),
        None => anyhow::bail!("--backend gpu opened no GPU"),
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

/// How often plain-text progress prints a line when nothing else was printed.
pub(crate) const HEARTBEAT: Duration = Duration::from_secs(30);

struct PlainState {
    started: Instant,
    last_print: Instant,
    step: String,
    /// When the current step began.
    step_started: Instant,
    fraction: Option<(u64, u64)>,
}

impl PlainState {
    /// The line a new step (or the end) prints: the time since the start,
    /// the share done where there is one, and the step.
    fn line(&self, what: &str) -> String {
        let mut line = self.head(what);
        if !self.step.is_empty() {
            line.push(' ');
            line.push_str(&self.step);
        }
        line
    }

    /// The heartbeat's line: as [`PlainState::line`], but a step still
    /// under way is said to be, with how long it has taken so far, so that
    /// a log does not read as the step starting again.
    fn heartbeat_line(&self, what: &str) -> String {
        let mut line = self.head(what);
        if !self.step.is_empty() {
            line.push_str(&format!(" still {} ({} s so far)", self.step, self.step_started.elapsed().as_secs()));
        }
        line
    }

    /// `what`, the seconds since the start and the share done, if known.
    fn head(&self, what: &str) -> String {
        let elapsed = self.started.elapsed().as_secs();
        let mut line = format!("{what}: [{elapsed:>4} s]");
        if let Some((done, total)) = self.fraction {
            let pct = if total > 0 { 100.0 * done as f64 / total as f64 } else { 0.0 };
            line.push_str(&format!(" {pct:5.1}%"));
        }
        line
    }
}

/// Progress of one command on stderr: an indicatif bar or spinner on a
/// terminal; plain lines otherwise (a log file), each new step at once and a
/// heartbeat every [`HEARTBEAT`] without one; nothing under `--quiet`.
pub(crate) struct Progress {
    what: String,
    bar: Option<ProgressBar>,
    plain: Option<Arc<Mutex<PlainState>>>,
    /// Dropped to stop the heartbeat thread, which wakes at once (a sleep
    /// would add up to its period to every timed command's end).
    stop: Option<mpsc::Sender<()>>,
    heartbeat: Option<std::thread::JoinHandle<()>>,
}

impl Progress {
    /// A bar with a percentage (`position` reports done of total).
    pub(crate) fn bar(what: &str) -> Progress {
        Progress::new(what, true)
    }

    /// A spinner with the current step (`step` reports it).
    pub(crate) fn steps(what: &str) -> Progress {
        Progress::new(what, false)
    }

    fn new(what: &str, with_bar: bool) -> Progress {
        let (stop, stopped) = mpsc::channel::<()>();
        let mut p = Progress { what: what.to_string(), bar: None, plain: None, stop: Some(stop), heartbeat: None };
        if quiet() {
            return p;
        }
        if std::io::stderr().is_terminal() {
            let bar = if with_bar {
                let bar = ProgressBar::new(1);
                bar.set_style(
                    ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed_precise} (eta {eta})")
                        .expect("valid template")
                        .progress_chars("=> "),
                );
                bar
            } else {
                let bar = ProgressBar::new_spinner();
                bar.enable_steady_tick(Duration::from_millis(200));
                bar
            };
            bar.set_message(what.to_string());
            p.bar = Some(bar);
        } else {
            let now = Instant::now();
            let state = Arc::new(Mutex::new(PlainState {
                started: now,
                last_print: now,
                step: String::new(),
                step_started: now,
                fraction: with_bar.then_some((0, 1)),
            }));
            p.plain = Some(state.clone());
            let what = what.to_string();
            p.heartbeat = Some(std::thread::spawn(move || {
                // Wakes every 250 ms, and at once when `stop` is dropped.
                while let Err(RecvTimeoutError::Timeout) = stopped.recv_timeout(Duration::from_millis(250)) {
                    let mut s = state.lock().unwrap_or_else(|e| e.into_inner());
                    if s.last_print.elapsed() >= HEARTBEAT {
                        note(&s.heartbeat_line(&what));
                        s.last_print = Instant::now();
                    }
                }
            }));
        }
        p
    }

    /// `done` of `total` units of work.
    pub(crate) fn position(&self, done: u64, total: u64) {
        if let Some(bar) = &self.bar {
            bar.set_length(total);
            bar.set_position(done);
        }
        if let Some(state) = &self.plain {
            let mut s = state.lock().unwrap_or_else(|e| e.into_inner());
            s.fraction = Some((done, total));
        }
    }

    /// A new step: shown on the spinner, printed as a line in a log.
    pub(crate) fn step(&self, step: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{}: {step}", self.what));
        }
        if let Some(state) = &self.plain {
            let mut s = state.lock().unwrap_or_else(|e| e.into_inner());
            s.step = step.to_string();
            s.step_started = Instant::now();
            note(&s.line(&self.what));
            s.last_print = Instant::now();
        }
    }

    /// A line that stays (a result as it comes), above the bar on a terminal.
    pub(crate) fn println(&self, line: &str) {
        if let Some(bar) = &self.bar {
            bar.println(line);
        } else if self.plain.is_some() {
            note(line);
            if let Some(state) = &self.plain {
                state.lock().unwrap_or_else(|e| e.into_inner()).last_print = Instant::now();
            }
        }
    }

    /// Ends the progress display (a final line in a log).
    pub(crate) fn finish(mut self) {
        self.stop_heartbeat();
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        if let Some(state) = &self.plain {
            let mut s = state.lock().unwrap_or_else(|e| e.into_inner());
            s.step = "done".into();
            note(&s.line(&self.what));
        }
    }

    fn stop_heartbeat(&mut self) {
        drop(self.stop.take());
        if let Some(h) = self.heartbeat.take() {
            let _ = h.join();
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.stop_heartbeat();
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

/// `--fig8-frequency`: the frequency Figure 8 is drawn at, a finite number
/// of hertz above 0.
fn check_fig8_frequency(hz: f64) -> Result<()> {
    if !(hz.is_finite() && hz > 0.0) {
        anyhow::bail!("invalid --fig8-frequency: `{hz}`; it must be a frequency > 0 Hz");
    }
    Ok(())
}

/// Says on stderr which grid frequency Figure 8 shows when it is not the
/// `--fig8-frequency` asked for (`hz`): the figure takes the nearest.
fn note_fig8_frequency(hz: f64, grid_hz: impl IntoIterator<Item = f64>) {
    let nearest = grid_hz.into_iter().min_by(|a, b| (a - hz).abs().total_cmp(&(b - hz).abs()));
    if let Some(f) = nearest
        && f != hz
    {
        info(&format!(
            "note: Figure 8 shows {} Hz, the grid frequency nearest to --fig8-frequency {} Hz",
            crate::engine::model::fmt_value(f),
            crate::engine::model::fmt_value(hz)
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step's line names it; the heartbeat's says it is still under way
    /// and for how long, so a log does not read as the step starting again.
    #[test]
    fn a_heartbeat_says_the_step_goes_on() {
        let now = Instant::now();
        let ago = |s: u64| now.checked_sub(Duration::from_secs(s)).expect("a time in the past");
        let mut state = PlainState {
            started: ago(41),
            last_print: now,
            step: String::new(),
            step_started: ago(41),
            fraction: None,
        };
        assert_eq!(state.heartbeat_line("diagnose"), "diagnose: [  41 s]");
        state.step = "trying every family".into();
        state.step_started = ago(30);
        assert_eq!(state.line("diagnose"), "diagnose: [  41 s] trying every family");
        assert_eq!(state.heartbeat_line("diagnose"), "diagnose: [  41 s] still trying every family (30 s so far)");
        state.fraction = Some((1, 4));
        assert_eq!(state.heartbeat_line("sweep"), "sweep: [  41 s]  25.0% still trying every family (30 s so far)");
    }

    #[test]
    fn cli_definition_is_valid() {
        Cli::command().debug_assert();
    }

    #[test]
    fn cli_every_flag_has_help() {
        fn walk(cmd: &clap::Command, path: &str) {
            for arg in cmd.get_arguments() {
                let id = arg.get_id().as_str();
                if id == "help" || id == "version" {
                    continue;
                }
                assert!(arg.get_help().is_some(), "{path} {id} has no help text");
            }
            for sub in cmd.get_subcommands() {
                walk(sub, &format!("{path} {}", sub.get_name()));
            }
        }
        walk(&Cli::command(), "stickslip");
    }
}
