//! Writing measurement sets: run files and `manifest.json`, in the format
//! the reader takes (stickslip's simulated records are measurement sets).

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::engine::{Model, Sample};
use crate::error::Result;
use crate::io::write_atomically;

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
        "format": super::FORMAT,
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
