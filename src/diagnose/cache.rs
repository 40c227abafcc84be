//! The simulation caches of a diagnosis, shared by every view of its data:
//! the sensor-noise draws of simulated records, each unit's sample grid,
//! and what the last models' replicate records gave. A replicate record is
//! determined by (model, seed, warm-up, unit, replicate number), so each is
//! simulated once per diagnosis.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::sync::{Arc, Mutex};

use crate::diagnose::DiagnoseSettings;
use crate::diagnose::features::{RunFeatures, SampleGrid};
use crate::diagnose::law::{LawMoments, Spread};
use crate::engine::Model;
use crate::engine::effects::ColouredFrictionNoise;
use crate::measure::Run;

/// Simulation caches of a diagnosis, shared by every view of its data.
#[derive(Default)]
pub(crate) struct Caches {
    /// The sensor-noise draws of simulated replicate records, by (seed,
    /// realisation): the same for every model, so drawn once per diagnosis
    /// (they were a tenth of its time).
    pub(crate) sensor_draws: SensorDraws,
    /// What the last models' replicate records gave, unit by unit
    /// (features, the law's moments): each record simulated once.
    pub(crate) records: RecordCache,
    /// Each unit's simulated records' sample grid, made once.
    pub(crate) grids: UnitGrids,
    /// How far the replicates' friction residual variance moves per unit
    /// of σ_μ² through a derived force's filter (–), by the friction
    /// noise's colour ([`crate::diagnose::calibrate`]).
    pub(crate) sigma_response: SigmaResponses,
}

/// The filter's response to σ_μ² (–) of a noise that is wholly one part
/// (`None`: white; [`crate::diagnose::calibrate`]), each measured once, on
/// one model: the first asked for a response (the initial baseline), with
/// the part put on it. A coloured noise passes a derived force's smoothing
/// filter more than a white one of the same variance, so one response for
/// every model steps σ_μ too far wherever part of the noise is coloured.
#[derive(Default)]
pub(crate) struct SigmaResponses(Mutex<ResponsesKept>);

/// The model a σ_μ response is measured on, the settings it is simulated
/// under, and per unit its data's friction spread about their law.
pub(crate) type MeasuredOn = (Model, DiagnoseSettings, Vec<Option<Spread>>);

/// What every response is measured on ([`MeasuredOn`]), and the responses
/// measured so far, by noise part.
#[derive(Default)]
struct ResponsesKept {
    on: Option<MeasuredOn>,
    by_colour: Vec<(Option<ColouredFrictionNoise>, f64)>,
}

impl SigmaResponses {
    /// The response kept for the noise part `colour`, if any.
    pub(crate) fn get(&self, colour: &Option<ColouredFrictionNoise>) -> Option<f64> {
        let kept = self.0.lock().expect("sigma responses lock");
        kept.by_colour.iter().find(|(c, _)| c == colour).map(|&(_, r)| r)
    }

    /// What the responses are measured on ([`MeasuredOn`]): what `first`
    /// gives, if nothing was yet.
    pub(crate) fn measured_on(&self, first: impl FnOnce() -> MeasuredOn) -> MeasuredOn {
        let mut kept = self.0.lock().expect("sigma responses lock");
        kept.on.get_or_insert_with(first).clone()
    }

    /// Keeps `response` for `colour` unless one was kept already (measured
    /// on the same model, so the same number); the one kept.
    pub(crate) fn insert(&self, colour: &Option<ColouredFrictionNoise>, response: f64) -> f64 {
        let mut kept = self.0.lock().expect("sigma responses lock");
        if let Some(&(_, r)) = kept.by_colour.iter().find(|(c, _)| c == colour) {
            return r;
        }
        kept.by_colour.push((colour.clone(), response));
        response
    }
}

/// Standard Gaussian pairs (for `x`, `v`) per sample of a simulated record,
/// by (seed, realisation), computed once and shared.
#[derive(Debug, Default)]
pub(crate) struct SensorDraws(Mutex<HashMap<(u64, u32), Draws>>);

/// One record's sensor-noise draws: a standard Gaussian pair per sample.
type Draws = Arc<Vec<(f64, f64)>>;

impl SensorDraws {
    /// The first `n` pairs of (seed, realisation), made by `draw` (given
    /// the sample index) the first time they are asked for.
    pub(crate) fn get(&self, seed: u64, realisation: u32, n: usize, draw: impl Fn(usize) -> (f64, f64)) -> Draws {
        let cached = self.0.lock().expect("sensor draws lock").get(&(seed, realisation)).cloned();
        if let Some(d) = cached.filter(|d| d.len() >= n) {
            return d;
        }
        let drawn = Arc::new((0..n).map(draw).collect::<Vec<_>>());
        self.0.lock().expect("sensor draws lock").insert((seed, realisation), Arc::clone(&drawn));
        drawn
    }
}

/// The [`SampleGrid`] of each unit's simulated records, made from the first
/// record that needs it (and again should a record be sampled otherwise).
#[derive(Default)]
pub(crate) struct UnitGrids(Mutex<HashMap<usize, Arc<SampleGrid>>>);

impl UnitGrids {
    /// Unit `unit`'s grid, one that serves `run`.
    pub(crate) fn of(&self, unit: usize, run: &Run) -> Arc<SampleGrid> {
        let kept = self.0.lock().expect("grids lock").get(&unit).cloned();
        if let Some(grid) = kept.filter(|g| g.serves(run)) {
            return grid;
        }
        let grid = Arc::new(SampleGrid::of(run));
        self.0.lock().expect("grids lock").insert(unit, Arc::clone(&grid));
        grid
    }
}

/// What the diagnosis reads from one replicate record: its features, and
/// the moments of its slipping samples for the friction law's fit at the
/// measured law's Stribeck rate (where there is a measured law).
#[derive(Clone, Debug)]
pub(crate) struct RecordReading {
    pub(crate) features: RunFeatures,
    pub(crate) moments: Option<LawMoments>,
}

/// How many models' readings a diagnosis keeps.
const KEPT_MODELS: usize = 96;

/// The readings of record units' replicate records ([`RecordReading`], per
/// unit, replicates `0..n` in order) of the last [`KEPT_MODELS`] models, by
/// (model, noise seed, warm-up). A replicate record is determined by
/// (model, seed, warm-up, unit, replicate number), so each is simulated
/// once per diagnosis, whichever view of the data (fold) asks for it: a
/// law step reads the records of the model it steps from, which were
/// simulated to score that model a moment before; a form's best model,
/// searched on half the replicates, is then calibrated on all of them; a
/// fold's held-out units are another fold's fitting units.
#[derive(Default)]
pub(crate) struct RecordCache(Mutex<VecDeque<KeptReadings>>);

/// A model's readings by unit, with the noise seed and warm-up periods
/// they were simulated with.
type KeptReadings = (Model, u64, u32, BTreeMap<usize, Vec<RecordReading>>);

impl RecordCache {
    /// The readings kept for `model` under `settings` (by unit, the
    /// replicates simulated so far), if any.
    pub(crate) fn get(&self, model: &Model, settings: &DiagnoseSettings) -> BTreeMap<usize, Vec<RecordReading>> {
        let kept = self.0.lock().expect("record cache lock");
        kept.iter()
            .find(|(m, seed, warmup, _)| m == model && *seed == settings.seed && *warmup == settings.warmup_cycles)
            .map(|(_, _, _, readings)| readings.clone())
            .unwrap_or_default()
    }

    /// Keeps `readings` for `model` under `settings` (replacing what was
    /// kept for those units of it).
    pub(crate) fn insert(
        &self,
        model: &Model,
        settings: &DiagnoseSettings,
        readings: BTreeMap<usize, Vec<RecordReading>>,
    ) {
        let mut kept = self.0.lock().expect("record cache lock");
        let at = kept
            .iter()
            .position(|(m, seed, warmup, _)| m == model && *seed == settings.seed && *warmup == settings.warmup_cycles);
        let mut entry = match at {
            Some(i) => kept.remove(i).expect("a kept entry"),
            None => (model.clone(), settings.seed, settings.warmup_cycles, BTreeMap::new()),
        };
        entry.3.extend(readings);
        if kept.len() == KEPT_MODELS {
            kept.pop_front();
        }
        kept.push_back(entry);
    }
}
