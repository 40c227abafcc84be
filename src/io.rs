//! Files: atomic writes, time-series run files and their manifest.
//!
//! Every output is written to a temporary name beside its destination and
//! renamed into place, so an interrupted run leaves no half-written file.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::cpu::Sample;
use crate::error::{Error, Result};
use crate::model::Model;

/// Writes `path` atomically: `fill` writes into a temporary file in the same
/// directory, which is renamed over `path` only when `fill` succeeds.
pub fn write_atomically(path: &Path, fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().ok_or_else(|| Error::setting("output path", format!("{} has no file name", path.display())))?;
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

/// Writes one time-series record in the run-file format of
/// `measurement-format.md`: `t,x,v,normal_force,friction_force` (SI units).
pub fn write_run_file(path: &Path, samples: &[Sample]) -> Result<()> {
    write_atomically(path, |w| {
        writeln!(w, "t,x,v,normal_force,friction_force")?;
        for s in samples {
            writeln!(w, "{},{},{},{},{}", s.t_s, s.x_m, s.v_m_per_s, s.normal_force_n, s.friction_force_n)?;
        }
        Ok(())
    })
}

/// One entry of a manifest's `runs`.
#[derive(Clone, Debug, Serialize)]
pub struct RunEntry {
    pub file: String,
    pub excitation_frequency_hz: f64,
    pub excitation_amplitude_m: f64,
    pub normal_force_n: f64,
}

/// Writes `manifest.json` for a set of run files.
pub fn write_manifest(dir: &Path, description: &str, model: &Model, runs: &[RunEntry]) -> Result<PathBuf> {
    let manifest = serde_json::json!({
        "format": "stickslip-measurements/1",
        "description": description,
        "rig": {
            "mass_kg": model.rig.mass_kg,
            "natural_frequency_hz": model.rig.natural_frequency_hz,
            "damping_ratio": model.rig.damping_ratio,
        },
        "runs": runs,
    });
    let path = dir.join("manifest.json");
    write_atomically(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &manifest)?;
        writeln!(w)
    })?;
    Ok(path)
}
