//! Files: bounded reading, atomic files, and atomic output sets.
//!
//! - **Reading.** Everything stickslip reads goes through [`read_bounded`]:
//!   the path must be a regular file (a FIFO, device, socket or directory is
//!   refused at once, without blocking) no larger than a stated limit
//!   ([`MAX_MODEL_FILE_BYTES`], [`MAX_MANIFEST_BYTES`], [`MAX_TABLE_FILE_BYTES`],
//!   [`MAX_ACCUMULATOR_BYTES`]). Messages quote file content only through
//!   [`crate::text::excerpt`]: short, with control and bidirectional
//!   characters escaped. JSON is parsed with [`parse_json`], which refuses
//!   a key given twice.
//! - **Files.** [`write_atomically`] writes a file under a temporary name
//!   beside its destination and renames it into place.
//! - **Output sets.** [`OutputSet`] builds a command's whole output set in a
//!   temporary sibling directory and swaps it in at the end, so the
//!   destination holds exactly one run's complete set, or the previous one,
//!   never a mix. An advisory lock refuses a second run into the same
//!   directory, and [`install_interrupt_cleanup`] removes temporaries on
//!   SIGINT, SIGTERM and SIGHUP.

use std::fs::File;
use std::io::{Read, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

mod json;

use crate::error::{Error, Result};
use crate::text::{excerpt, shown};
pub use json::parse_json;

/// Largest model file (`--config`), bytes: 1 MiB.
pub const MAX_MODEL_FILE_BYTES: u64 = 1 << 20;
/// Largest `manifest.json` of a measurement set, bytes: 16 MiB.
pub const MAX_MANIFEST_BYTES: u64 = 16 << 20;
/// Largest run file or summary table, bytes: 256 MiB (about 2.5 million
/// samples of five channels; the paper's records are 3 MB).
pub const MAX_TABLE_FILE_BYTES: u64 = 256 << 20;
/// Largest `accumulators.json`, bytes: 1 GiB.
pub const MAX_ACCUMULATOR_BYTES: u64 = 1 << 30;
/// Most bytes a measurement set's files may hold together: 2 GiB.
pub const MAX_SET_BYTES: u64 = 2 << 30;

/// Why a file could not be read; its `Display` is one clean sentence that
/// carries the operating system's text at most once.
#[derive(Debug)]
pub enum ReadRefusal {
    /// Opening or reading failed.
    Io(std::io::Error),
    /// Not a regular file: says what it is.
    NotRegular(&'static str),
    /// Over the limit (`size` is a lower bound when the file grew).
    TooLarge { size: u64, limit: u64 },
}

impl std::fmt::Display for ReadRefusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReadRefusal::Io(e) => write!(f, "{e}"),
            ReadRefusal::NotRegular(kind) => write!(f, "it is {kind}, not a regular file"),
            ReadRefusal::TooLarge { size, limit } => {
                write!(f, "it holds {size} bytes, over the limit of {limit} bytes ({})", human_bytes(*limit))
            }
        }
    }
}

impl std::error::Error for ReadRefusal {}

fn human_bytes(n: u64) -> String {
    match n {
        n if n >= 1 << 30 && n % (1 << 30) == 0 => format!("{} GiB", n >> 30),
        n if n >= 1 << 20 && n % (1 << 20) == 0 => format!("{} MiB", n >> 20),
        n if n >= 1 << 10 && n % (1 << 10) == 0 => format!("{} KiB", n >> 10),
        n => format!("{n} B"),
    }
}

/// What a non-regular file is, for messages.
fn kind_of(file_type: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if file_type.is_char_device() {
            return "a character device";
        }
        if file_type.is_block_device() {
            return "a block device";
        }
        if file_type.is_socket() {
            return "a socket";
        }
    }
    if file_type.is_dir() { "a directory" } else { "not a regular file" }
}

/// Reads the whole of `path` if it is a regular file of at most `limit`
/// bytes. The file is opened without blocking (a FIFO with no writer does
/// not hang), checked on the open descriptor, and read no further than
/// `limit + 1` bytes (so a file that grows, or a `/proc` file that claims
/// size 0, cannot exhaust memory).
pub fn read_bounded(path: &Path, limit: u64) -> std::result::Result<Vec<u8>, ReadRefusal> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY);
    }
    let file = options.open(path).map_err(ReadRefusal::Io)?;
    let meta = file.metadata().map_err(ReadRefusal::Io)?;
    if !meta.file_type().is_file() {
        return Err(ReadRefusal::NotRegular(kind_of(&meta.file_type())));
    }
    if meta.len() > limit {
        return Err(ReadRefusal::TooLarge { size: meta.len(), limit });
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(ReadRefusal::Io)?;
    if bytes.len() as u64 > limit {
        return Err(ReadRefusal::TooLarge { size: bytes.len() as u64, limit });
    }
    Ok(bytes)
}

/// `bytes` without a leading UTF-8 byte-order mark.
pub fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes)
}

/// `path` made absolute against the working directory and normalised
/// lexically (`.` dropped, `..` taken back), without touching the file
/// system.
pub fn absolute(path: &Path) -> std::io::Result<PathBuf> {
    let joined = if path.is_absolute() { path.to_path_buf() } else { std::env::current_dir()?.join(path) };
    let mut out = PathBuf::new();
    for c in joined.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other.as_os_str()),
        }
    }
    Ok(out)
}

/// Where a name written in a directory's own files leads.
#[derive(Debug)]
pub enum Confined {
    /// Inside the directory: the resolved (canonical) path.
    Inside(PathBuf),
    /// It leads (textually, or after following links) outside.
    Outside,
    /// It does not resolve (missing, or a link to nothing).
    Unresolved(std::io::Error),
}

/// Resolves `name`, written in a file of directory `root` (canonical), to a
/// path that must lie inside `root` after following every link. Absolute
/// names and `..` that climb out are refused before the file system is
/// touched; links are then followed and the result checked again.
pub fn confine(root: &Path, name: &str) -> Confined {
    let mut depth = 0usize;
    for c in Path::new(name).components() {
        match c {
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            Component::ParentDir if depth > 0 => depth -= 1,
            _ => return Confined::Outside,
        }
    }
    match std::fs::canonicalize(root.join(name)) {
        // The set's directory itself is inside it (and is refused as a
        // directory when read).
        Ok(resolved) if resolved.starts_with(root) => Confined::Inside(resolved),
        Ok(_) => Confined::Outside,
        Err(e) => Confined::Unresolved(e),
    }
}

/// Writes `path` atomically: `fill` writes into a temporary file in the same
/// directory, which is renamed over `path` only when `fill` succeeds.
pub fn write_atomically(path: &Path, fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name =
        path.file_name().ok_or_else(|| Error::setting("output path", format!("{} has no file name", shown(path))))?;
    let tmp = dir.join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut writer = std::io::BufWriter::new(file);
        fill(&mut writer)?;
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

/// Creates an output directory (and parents).
pub fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
}

/// The files each command's output set may hold (`*` matches any text). A
/// directory holding anything else is not replaced.
/// The file every output set carries, written before anything else: a
/// destination that holds files is replaced only when it has it (a set
/// stickslip wrote), never because its files merely look like one (a
/// measurement set named like `simulate`'s own).
pub const OUTPUT_STAMP: &str = ".stickslip-output";

pub mod owned {
    /// `sweep` and `merge`.
    pub const SWEEP: &[&str] = &[
        "sweep.csv",
        "histograms.csv",
        "accumulators.json",
        "sweep.json",
        "fig9a.png",
        "fig9a.svg",
        "fig9b.png",
        "fig9b.svg",
        "fig9c.png",
        "fig9c.svg",
        "fig8.png",
        "fig8.svg",
    ];
    /// `diagnose`.
    pub const DIAGNOSIS: &[&str] = &[
        "report.json",
        "report.html",
        "baseline-model.toml",
        "fitted-model.toml",
        "scores.csv",
        "gap.png",
        "gap.svg",
        "comparison.png",
        "comparison.svg",
    ];
    /// `simulate`.
    pub const SIMULATION: &[&str] = &["manifest.json", "model.toml", "run-*.csv"];
    /// `benchmark-diagnosis`: its summary and a directory per set (a
    /// pattern ending in `/` names directories).
    pub const BENCHMARK: &[&str] = &["summary.txt", "set-*/"];
    /// `plot`: the figures it draws, of a sweep and of a diagnosis, and,
    /// in a directory of their own (`--out`), the `plot.json` that names
    /// their kind and source.
    pub const PLOT: &[&str] =
        &["plot.json", "fig*.png", "fig*.svg", "gap.png", "gap.svg", "comparison.png", "comparison.svg"];
}

fn matches_pattern(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((head, tail)) => name.len() >= head.len() + tail.len() && name.starts_with(head) && name.ends_with(tail),
    }
}

/// One output set being built, for the interrupt handler.
#[derive(Clone, Debug)]
struct Pending {
    staging: PathBuf,
    lock_path: PathBuf,
    /// Directories created for the set, deepest last.
    created: Vec<PathBuf>,
}

/// Output sets of this process not yet committed. The interrupt handler
/// takes this lock, so a set is never removed while it is being swapped in.
static PENDING: Mutex<Vec<Pending>> = Mutex::new(Vec::new());
static SERIAL: AtomicU64 = AtomicU64::new(0);

fn pending() -> std::sync::MutexGuard<'static, Vec<Pending>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

fn remove_pending(p: &Pending) {
    remove_tree(&p.staging);
    let _ = std::fs::remove_file(&p.lock_path);
    for dir in p.created.iter().rev() {
        // Only empty directories go: never anything another process put there.
        let _ = std::fs::remove_dir(dir);
    }
}

/// Removes the directory `dir` whole, even while other threads still write
/// into it (an interrupt arrives mid-write): it is first renamed aside
/// (`….old`, which a later run into the same place also clears), so that
/// no new file lands under its name, then removed; both are repeated
/// while a removal finds the directory refilled or recreated.
fn remove_tree(dir: &Path) {
    let aside = dir.with_extension("old");
    let exists = |p: &Path| std::fs::symlink_metadata(p).is_ok();
    for _ in 0..8 {
        if exists(dir) && std::fs::rename(dir, &aside).is_err() {
            let _ = std::fs::remove_dir_all(dir);
        }
        let _ = std::fs::remove_dir_all(&aside);
        if !exists(dir) && !exists(&aside) {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// A command's output set, built in a temporary sibling directory of its
/// destination and swapped in by [`OutputSet::commit`].
///
/// [`OutputSet::prepare`] runs before any computation and refuses, naming
/// the flag: a destination that is not a directory, cannot be created or
/// written, holds files the command does not write, overlaps an input, or is
/// locked by another stickslip run. Dropping an uncommitted set removes
/// everything it created.
#[derive(Debug)]
pub struct OutputSet {
    /// The destination as given (for messages).
    dest: PathBuf,
    /// The destination's resolved location.
    target: PathBuf,
    /// Where the set is built; `target` itself for a nested set.
    staging: PathBuf,
    owned: &'static [&'static str],
    flag: String,
    /// The lock's open file, held until the set is committed or dropped.
    lock: Option<File>,
    record: Option<Pending>,
}

impl OutputSet {
    /// Prepares `dest` for an output set whose files match `owned`; `flag`
    /// names the option in messages and `inputs` are paths the set must not
    /// overlap (neither inside them nor containing them).
    ///
    /// When `dest` is itself a set being built by this process (the command
    /// line prepared it before computing), the set is nested: files go
    /// straight into it and [`OutputSet::commit`] leaves the swap to the
    /// outer set.
    pub fn prepare(dest: &Path, flag: &str, owned: &'static [&'static str], inputs: &[&Path]) -> Result<OutputSet> {
        let bad = |message: String| Error::setting(flag, format!("`{}`: {message}", shown(dest)));
        if dest.as_os_str().is_empty() {
            return Err(bad("an empty path".into()));
        }
        let abs = absolute(dest).map_err(|e| bad(format!("cannot resolve it: {e}")))?;
        let nested = std::fs::canonicalize(&abs).ok().filter(|c| pending().iter().any(|p| &p.staging == c));
        if let Some(canonical) = nested {
            return Ok(OutputSet {
                dest: dest.to_path_buf(),
                target: canonical.clone(),
                staging: canonical,
                owned,
                flag: flag.to_string(),
                lock: None,
                record: None,
            });
        }
        // Where the set goes: an existing destination is followed through links.
        let target = match std::fs::symlink_metadata(&abs) {
            Ok(_) => std::fs::canonicalize(&abs).map_err(|e| bad(format!("cannot resolve it: {e}")))?,
            Err(_) => abs.clone(),
        };
        match std::fs::metadata(&target) {
            Ok(m) if !m.is_dir() => return Err(bad("it exists and is not a directory".into())),
            _ => {}
        }
        if target.parent().is_none() || target.file_name().is_none() {
            return Err(bad("the file system root cannot be an output directory".into()));
        }
        for input in inputs {
            let input = std::fs::canonicalize(input).unwrap_or_else(|_| absolute(input).unwrap_or_default());
            let relation = if input == target {
                Some("is the input")
            } else if target.starts_with(&input) {
                Some("lies inside the input")
            } else if input.starts_with(&target) {
                Some("contains the input")
            } else {
                None
            };
            if let Some(relation) = relation {
                return Err(bad(format!(
                    "it {relation} `{}`; the output must go elsewhere, or it would replace what it reads",
                    shown(&input)
                )));
            }
        }
        let mut set = OutputSet {
            dest: dest.to_path_buf(),
            target: target.clone(),
            staging: PathBuf::new(),
            owned,
            flag: flag.to_string(),
            lock: None,
            record: None,
        };
        set.check_replaceable()?;
        // The parent: created if missing (and removed again if the run fails).
        let parent = target.parent().expect("checked above").to_path_buf();
        let mut created = Vec::new();
        let mut missing = Vec::new();
        let mut ancestor = parent.as_path();
        while std::fs::symlink_metadata(ancestor).is_err() {
            missing.push(ancestor.to_path_buf());
            match ancestor.parent() {
                Some(p) => ancestor = p,
                None => break,
            }
        }
        let mut pending_record = Pending { staging: PathBuf::new(), lock_path: PathBuf::new(), created: Vec::new() };
        for dir in missing.iter().rev() {
            match std::fs::create_dir(dir) {
                Ok(()) => created.push(dir.clone()),
                // Another run made it meanwhile: it is not ours to remove.
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && dir.is_dir() => {}
                Err(e) => {
                    pending_record.created = created;
                    remove_pending(&pending_record);
                    return Err(bad(format!("cannot create `{}`: {e}", shown(dir))));
                }
            }
        }
        pending_record.created = created;
        set.record = Some(pending_record);
        if !std::fs::metadata(&parent).map(|m| m.is_dir()).unwrap_or(false) {
            return Err(bad(format!("`{}` is not a directory", shown(&parent))));
        }
        let name = target.file_name().expect("checked above").to_string_lossy().into_owned();
        // The lock: a file beside the destination, locked (advisory) while the set is built.
        let lock_path = parent.join(format!(".{name}.stickslip-lock"));
        set.lock = Some(lock_file(&lock_path).map_err(&bad)?);
        if let Some(record) = set.record.as_mut() {
            record.lock_path = lock_path;
        }
        if target.exists() && !writable(&target) {
            return Err(bad("it is not writable: the previous set in it could not be replaced".into()));
        }
        // Temporaries of earlier runs into the same place that were killed
        // outright: no live run holds them (we hold the lock).
        let stale = format!(".{name}.stickslip-");
        if let Ok(entries) = std::fs::read_dir(&parent) {
            for entry in entries.flatten() {
                let n = entry.file_name().to_string_lossy().into_owned();
                // Exactly `.{name}.stickslip-PID-N.tmp` (or `.old`): nothing else is touched.
                let ours = n
                    .strip_prefix(&stale)
                    .and_then(|rest| rest.strip_suffix(".tmp").or_else(|| rest.strip_suffix(".old")))
                    .and_then(|ids| ids.split_once('-'))
                    .is_some_and(|(pid, serial)| {
                        [pid, serial].iter().all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
                    });
                if ours {
                    let _ = std::fs::remove_dir_all(entry.path());
                }
            }
        }
        let staging = parent.join(format!(
            ".{name}.stickslip-{}-{}.tmp",
            std::process::id(),
            SERIAL.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir(&staging).map_err(|e| bad(format!("cannot write in `{}`: {e}", shown(&parent))))?;
        set.staging = staging.clone();
        let record = set.record.as_mut().expect("set above");
        record.staging = staging.clone();
        pending().push(record.clone());
        std::fs::write(
            staging.join(OUTPUT_STAMP),
            format!("an output set of stickslip {}\n", env!("CARGO_PKG_VERSION")),
        )
        .map_err(|e| bad(format!("cannot write in `{}`: {e}", shown(&staging))))?;
        Ok(set)
    }

    /// Where the files of the set are written until it is committed.
    pub fn dir(&self) -> &Path {
        &self.staging
    }

    /// The destination as given.
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// Puts into the set being built every regular file of the destination
    /// that matches none of `except` (hard-linked where the file system
    /// allows, else copied): for a command that redraws part of a set in
    /// place (`plot`), which still swaps in a whole set. Nothing for a
    /// nested set, which is the destination itself.
    pub fn carry_over(&self, except: &[&str]) -> Result<()> {
        if self.staging == self.target {
            return Ok(());
        }
        let entries = match std::fs::read_dir(&self.target) {
            Ok(entries) => entries,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(Error::io(&self.target, e)),
        };
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(&self.target, e))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let regular = entry.file_type().map(|t| t.is_file()).unwrap_or(false);
            if !regular || name.starts_with('.') || except.iter().any(|p| matches_pattern(p, &name)) {
                continue;
            }
            let to = self.staging.join(entry.file_name());
            if std::fs::hard_link(entry.path(), &to).is_err() {
                std::fs::copy(entry.path(), &to).map_err(|e| Error::io(entry.path(), e))?;
            }
        }
        Ok(())
    }

    /// Refuses a destination whose entries are not all files this command
    /// writes (or temporaries of an interrupted write).
    fn check_replaceable(&self) -> Result<()> {
        let entries = match std::fs::read_dir(&self.target) {
            Ok(entries) => entries,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::NotADirectory => {
                return Err(Error::setting(
                    &self.flag,
                    format!("`{}`: a part of the path is a file, not a directory", shown(&self.dest)),
                ));
            }
            Err(e) => {
                return Err(Error::setting(&self.flag, format!("`{}`: cannot list it: {e}", shown(&self.dest))));
            }
        };
        let mut outputs = None;
        for entry in entries {
            let entry = entry
                .map_err(|e| Error::setting(&self.flag, format!("`{}`: cannot list it: {e}", shown(&self.dest))))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let regular = entry.file_type().map(|t| t.is_file()).unwrap_or(false);
            let directory = entry.file_type().map(|t| t.is_dir()).unwrap_or(false);
            let temporary = name.starts_with('.') && name.contains(".tmp");
            if regular && name == OUTPUT_STAMP {
                continue;
            }
            if (regular || directory) && !temporary {
                outputs.get_or_insert(name.clone());
            }
            let owned_directory =
                directory && self.owned.iter().any(|p| p.strip_suffix('/').is_some_and(|p| matches_pattern(p, &name)));
            let owned_name = self.owned.iter().any(|p| matches_pattern(p, &name));
            if !(owned_directory || regular && (temporary || owned_name)) {
                let what = if owned_name {
                    "which is not a file (this command writes a file of that name)"
                } else {
                    "which this command does not write"
                };
                return Err(Error::setting(
                    &self.flag,
                    format!(
                        "`{}` holds `{}`, {what}; it replaces only its own output sets (choose a new or empty \
                         directory)",
                        shown(&self.dest),
                        excerpt(&name, 80)
                    ),
                ));
            }
        }
        if let Some(name) = outputs.filter(|_| !self.target.join(OUTPUT_STAMP).is_file()) {
            return Err(Error::setting(
                &self.flag,
                format!(
                    "`{}` holds `{}` but no `{OUTPUT_STAMP}`: stickslip did not write it as an output set, and \
                     replaces only its own (choose a new or empty directory, or remove it yourself)",
                    shown(&self.dest),
                    excerpt(&name, 80)
                ),
            ));
        }
        Ok(())
    }

    /// Swaps the finished set into place: atomically (`RENAME_EXCHANGE`)
    /// where the file system allows, else by two renames; the previous set
    /// is then removed whole, so none of its files remain beside the new.
    pub fn commit(mut self) -> Result<()> {
        let Some(record) = self.record.take() else {
            return Ok(());
        };
        let mut guard = pending();
        let result = self.swap_in();
        guard.retain(|p| p.staging != record.staging);
        drop(guard);
        if result.is_err() {
            remove_pending(&record);
        } else {
            let _ = std::fs::remove_file(&record.lock_path);
        }
        self.lock = None;
        result
    }

    fn swap_in(&self) -> Result<()> {
        let fail = |e: std::io::Error| {
            Error::setting(&self.flag, format!("`{}`: cannot move the finished set into place: {e}", shown(&self.dest)))
        };
        if let Ok(dir) = std::fs::File::open(&self.staging) {
            let _ = dir.sync_all();
        }
        if std::fs::symlink_metadata(&self.target).is_err() {
            return std::fs::rename(&self.staging, &self.target).map_err(fail);
        }
        self.check_replaceable()?;
        if exchange(&self.staging, &self.target).is_ok() {
            // The staging path now holds the previous set.
            let _ = std::fs::remove_dir_all(&self.staging);
            return Ok(());
        }
        let old = self.staging.with_extension("old");
        std::fs::rename(&self.target, &old).map_err(fail)?;
        if let Err(e) = std::fs::rename(&self.staging, &self.target) {
            let _ = std::fs::rename(&old, &self.target);
            return Err(fail(e));
        }
        let _ = std::fs::remove_dir_all(&old);
        Ok(())
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if let Some(record) = self.record.take() {
            let mut guard = pending();
            guard.retain(|p| p.staging != record.staging);
            remove_pending(&record);
        }
    }
}

/// Opens and locks (exclusively, without waiting) the lock file at `path`.
/// The lock file is removed when a set is committed; a run that opened it
/// just before then finds the path gone or changed and tries again.
fn lock_file(path: &Path) -> std::result::Result<File, String> {
    for _ in 0..16 {
        let file = std::fs::OpenOptions::new().read(true).write(true).create(true).truncate(false).open(path).map_err(
            |e| {
                let why = if e.kind() == std::io::ErrorKind::PermissionDenied {
                    " (an output is built beside its destination and swapped in whole, so the directory that \
                     holds it must be writable)"
                } else {
                    ""
                };
                format!("cannot create its lock file `{}`: {e}{why}", shown(path))
            },
        )?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            use std::os::unix::io::AsRawFd;
            // SAFETY: flock on a descriptor this function owns.
            if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
                let e = std::io::Error::last_os_error();
                // A file system without locks (some network and FUSE ones):
                // go on unlocked; the swap still never mixes two sets.
                if matches!(e.raw_os_error(), Some(libc::ENOLCK | libc::EOPNOTSUPP | libc::ENOSYS)) {
                    return Ok(file);
                }
                if e.raw_os_error() == Some(libc::EWOULDBLOCK) {
                    return Err(format!(
                        "another stickslip run is writing there (it holds `{}`); wait for it to finish or \
                         choose another directory",
                        shown(path)
                    ));
                }
                return Err(format!("cannot lock `{}`: {e}", shown(path)));
            }
            let held = file.metadata().map_err(|e| format!("cannot lock `{}`: {e}", shown(path)))?;
            match std::fs::metadata(path) {
                Ok(now) if now.dev() == held.dev() && now.ino() == held.ino() => return Ok(file),
                _ => continue,
            }
        }
        #[cfg(not(unix))]
        return Ok(file);
    }
    Err(format!("cannot lock `{}`: it keeps changing", shown(path)))
}

/// Whether the current user may create and remove entries in `dir`.
fn writable(dir: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let Ok(c) = std::ffi::CString::new(dir.as_os_str().as_bytes()) else {
            return false;
        };
        // SAFETY: a valid NUL-terminated path.
        unsafe { libc::access(c.as_ptr(), libc::W_OK | libc::X_OK) == 0 }
    }
    #[cfg(not(unix))]
    {
        std::fs::metadata(dir).map(|m| !m.permissions().readonly()).unwrap_or(false)
    }
}

/// Exchanges two directories atomically (Linux `renameat2(RENAME_EXCHANGE)`).
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::ffi::OsStrExt;
        let to_c = |p: &Path| {
            std::ffi::CString::new(p.as_os_str().as_bytes())
                .map_err(|_| std::io::Error::from(std::io::ErrorKind::InvalidInput))
        };
        let (ca, cb) = (to_c(a)?, to_c(b)?);
        // SAFETY: two valid NUL-terminated paths; the flag is RENAME_EXCHANGE.
        let rc = unsafe {
            libc::syscall(libc::SYS_renameat2, libc::AT_FDCWD, ca.as_ptr(), libc::AT_FDCWD, cb.as_ptr(), 2u32)
        };
        if rc == 0 { Ok(()) } else { Err(std::io::Error::last_os_error()) }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (a, b);
        Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
    }
}

/// Makes SIGINT, SIGTERM and SIGHUP remove every output set still being
/// built (and its lock and the directories made for it) before the process
/// exits with 128 + the signal's number. Call it first thing in `main`,
/// before any other thread exists: the signals are blocked in every thread
/// and taken by one thread that waits for them.
pub fn install_interrupt_cleanup() {
    #[cfg(unix)]
    {
        // SAFETY: plain signal-set manipulation on stack values; the mask is
        // set before other threads exist, so they all inherit it.
        unsafe {
            let mut set: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut set);
            for sig in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
                libc::sigaddset(&mut set, sig);
            }
            if libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) != 0 {
                return;
            }
            let spawned = std::thread::Builder::new().name("stickslip-signals".into()).spawn(move || {
                loop {
                    let mut sig: libc::c_int = 0;
                    if libc::sigwait(&set, &mut sig) != 0 {
                        continue;
                    }
                    let sets = pending();
                    for p in sets.iter() {
                        remove_pending(p);
                    }
                    let name = match sig {
                        libc::SIGINT => "interrupted",
                        libc::SIGTERM => "terminated",
                        _ => "hung up",
                    };
                    let note = if sets.is_empty() { "" } else { "; removed the unfinished output" };
                    let _ = writeln!(std::io::stderr(), "\nstickslip: {name}{note}");
                    libc::_exit(128 + sig);
                }
            });
            if spawned.is_err() {
                libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A staging directory that another thread keeps writing into is
    /// removed whole, and nothing of it (nor its renamed copy) is left.
    #[test]
    fn a_tree_written_into_while_removed_is_removed_whole() {
        let parent = std::env::temp_dir().join(format!("stickslip-remove-tree-{}", std::process::id()));
        let dir = parent.join(".out.stickslip-1-0.tmp");
        std::fs::create_dir_all(&dir).unwrap();
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let writer = {
            let (dir, stop) = (dir.clone(), stop.clone());
            std::thread::spawn(move || {
                let mut i = 0u64;
                while !stop.load(Ordering::Relaxed) {
                    let _ = std::fs::write(dir.join(format!("run-{i}.csv")), b"t,x\n0,0\n");
                    i += 1;
                }
            })
        };
        std::thread::sleep(std::time::Duration::from_millis(20));
        remove_tree(&dir);
        stop.store(true, Ordering::Relaxed);
        writer.join().unwrap();
        let left: Vec<_> = std::fs::read_dir(&parent).unwrap().flatten().map(|e| e.file_name()).collect();
        assert!(left.is_empty(), "{left:?}");
        std::fs::remove_dir_all(&parent).unwrap();
    }

    #[test]
    fn confinement_refuses_names_that_climb_out() {
        let root = std::env::temp_dir().canonicalize().unwrap();
        assert!(matches!(confine(&root, "/etc/passwd"), Confined::Outside));
        assert!(matches!(confine(&root, "../x"), Confined::Outside));
        assert!(matches!(confine(&root, "a/../../x"), Confined::Outside));
        assert!(matches!(confine(&root, "definitely-missing-file"), Confined::Unresolved(_)));
    }

    #[test]
    fn patterns_match_names() {
        assert!(matches_pattern("run-*.csv", "run-7hz.csv"));
        assert!(!matches_pattern("run-*.csv", "run.csv"));
        assert!(matches_pattern("sweep.csv", "sweep.csv"));
    }

    #[test]
    fn bounded_reading_refuses_what_is_not_a_regular_file() {
        let dir = std::env::temp_dir();
        let e = read_bounded(&dir, 10).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        let path = dir.join(format!("stickslip-io-{}.txt", std::process::id()));
        std::fs::write(&path, "0123456789abc").unwrap();
        assert!(matches!(read_bounded(&path, 10), Err(ReadRefusal::TooLarge { .. })));
        assert_eq!(read_bounded(&path, 13).unwrap().len(), 13);
        std::fs::remove_file(&path).unwrap();
        #[cfg(unix)]
        {
            let e = read_bounded(Path::new("/dev/zero"), 10).unwrap_err();
            assert!(e.to_string().contains("character device"), "{e}");
        }
    }
}
