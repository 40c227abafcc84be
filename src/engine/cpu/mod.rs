//! The CPU backend: the f64 reference integrator ([`oscillator`]) run over
//! an ensemble with rayon, reduced with the same exact integer sums as the
//! GPU ([`crate::engine::reduce`]).
//!
//! Work is done in chunks of at most [`PATHS_PER_CHUNK`] realisations, so
//! memory stays bounded (for [`Record::Sums`]) whatever the ensemble size;
//! within a chunk, realisations run in parallel. The sums are integers, so
//! the result does not depend on the chunking or the number of threads.

pub mod effects;
pub mod oscillator;

use rayon::prelude::*;

use crate::engine::oscillator::{PathResult, Sample};
use crate::engine::reduce::PointAccumulator;
use crate::engine::{Backend, BackendKind, Job, Output, Record};
use crate::error::Result;

/// Most realisations integrated between two progress reports (and held in
/// memory at once when only sums are kept).
pub const PATHS_PER_CHUNK: usize = 1 << 14;

/// The f64 reference integrator on all of rayon's threads.
pub struct CpuBackend;

impl Backend for CpuBackend {
    fn kind(&self) -> BackendKind {
        BackendKind::Cpu
    }

    fn run(&self, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Output> {
        let oscillators = job.oscillators()?;
        let n = job.realisations as usize;
        let tasks: Vec<(usize, u32)> = (0..job.points.len())
            .flat_map(|p| (0..job.realisations).map(move |r| (p, job.first_realisation + r)))
            .collect();
        let total = job.work();
        let per_path = job.plan.total_cycles();
        let mut output = Output::default();
        if let Record::Samples { interval_s, duration_s } = job.record {
            for (done, chunk) in tasks.chunks(PATHS_PER_CHUNK).enumerate() {
                let records: Vec<Vec<Sample>> = chunk
                    .par_iter()
                    .map(|&(p, r)| {
                        let point = &job.points[p];
                        oscillator::sample_record(
                            &oscillators[p],
                            job.seed,
                            r,
                            job.plan.warmup_cycles,
                            duration_s,
                            interval_s,
                            point.initial,
                        )
                    })
                    .collect();
                output.records.extend(records);
                progress(((done * PATHS_PER_CHUNK + chunk.len()) as u64 * per_path).min(total), total);
            }
            return Ok(output);
        }
        output.sums = job.points.iter().map(|p| PointAccumulator::new(p.range)).collect();
        let mut done = 0u64;
        for chunk in tasks.chunks(PATHS_PER_CHUNK) {
            let paths: Vec<PathResult> = chunk
                .par_iter()
                .map(|&(p, r)| {
                    oscillator::simulate_path(&oscillators[p], job.seed, r, job.plan, job.points[p].initial, None)
                })
                .collect();
            for (&(p, _), path) in chunk.iter().zip(&paths) {
                output.sums[p].add_path(path, oscillators[p].period_s);
            }
            if job.record == Record::Peaks {
                output.paths.extend(paths);
            }
            done += chunk.len() as u64 * per_path;
            progress(done, total);
        }
        debug_assert!(job.record != Record::Peaks || output.paths.len() == n * job.points.len());
        Ok(output)
    }
}
