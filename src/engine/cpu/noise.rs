//! The main noise stream's pair A, drawn once per realisation and shared.
//!
//! A realisation's noise is a pure function of the seed, the realisation
//! number and the interval index ([`crate::engine::rng`]): it does not
//! depend on the grid point or the model. A sweep integrates realisations
//! `0..n` at every one of its points, and a diagnosis integrates the same
//! replicates under every model it tries, so each would draw the same
//! Gaussians over and over (Philox, `ln`, `sqrt`: a third of the CPU
//! reference's time on the main job). Here each realisation's pair A of
//! every interval (the friction's white value and the normal force's, the
//! baseline's only draws) is drawn once, into a table that the paths of
//! that realisation read instead. The values are the same function's, so
//! nothing changes but the time.
//!
//! The tables are process-wide, keyed by (seed key, realisation), and held
//! within [`BUDGET_BYTES`] ([`pair_a_table`] says which make room); a path
//! without one draws as before.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use crate::engine::rng;

/// Memory the tables may hold in all, bytes: 16 per interval of a
/// realisation (the main job's 64 realisations of up to 24 000 intervals
/// take 25 MB).
pub(crate) const BUDGET_BYTES: usize = 256 << 20;

/// Pair A of the main stream, `(ξ_μ, ξ_N)` (–), of intervals `0..len`.
pub(crate) type PairTable = Arc<[(f64, f64)]>;

/// A path's table (or none: it draws every value), as it reads it.
#[derive(Clone, Default)]
pub(crate) struct PathPairs(pub(crate) Option<PairTable>);

impl PathPairs {
    /// Pair A of interval `interval`, if the table reaches it.
    #[inline]
    pub(crate) fn get(&self, interval: u64) -> Option<(f64, f64)> {
        self.0.as_ref()?.get(usize::try_from(interval).ok()?).copied()
    }
}

/// How far ahead of the interval being read [`PathPairs::prefetch`] asks
/// for, intervals: two cache lines of pairs, a few grid steps' time.
const PREFETCH_INTERVALS: usize = 8;

impl PathPairs {
    /// Asks the processor to fetch the pairs a few intervals after
    /// `interval` into its cache. The tables are read once per point, in
    /// interval order, sixteen at a time, each out of cache (a sweep's
    /// tables, 12 MB a point at 10 Hz, are larger than the second level):
    /// waiting for each pair was most of [`super::oscillator`]'s time at a
    /// noise boundary. Nothing is read, so nothing changes but the time.
    #[inline]
    pub(crate) fn prefetch(&self, interval: u64) {
        #[cfg(target_arch = "x86_64")]
        if let (Some(table), Ok(i)) = (self.0.as_ref(), usize::try_from(interval)) {
            let ahead = table.as_ptr().wrapping_add(i.saturating_add(PREFETCH_INTERVALS));
            // SAFETY: a prefetch reads nothing and faults on no address;
            // SSE (which has it) is in the baseline of x86-64.
            unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(ahead.cast()) };
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = interval;
    }
}

impl std::fmt::Debug for PathPairs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PathPairs({} intervals)", self.0.as_ref().map_or(0, |t| t.len()))
    }
}

#[derive(Default)]
struct Tables {
    /// (seed key, realisation) → (table, the tick it was last asked for).
    by_path: HashMap<([u32; 2], u32), (PairTable, u64)>,
    /// Intervals held in all.
    held: usize,
    /// Requests so far (the clock of least recent use).
    tick: u64,
}

static TABLES: Mutex<Option<Tables>> = Mutex::new(None);

/// Most intervals held at once.
const BUDGET_INTERVALS: usize = BUDGET_BYTES / std::mem::size_of::<(f64, f64)>();

/// Pair A of realisation `realisation` under Philox key `key` for at least
/// the intervals `0..intervals`: a table as long if one is held, else (with
/// `make`, and room for it) one drawn now; `None` otherwise (the path draws
/// as it goes).
///
/// Room is made by dropping tables of other seeds, least recently used
/// first; this seed's tables stay. A run reads its tables in turn, over and
/// over (a sweep's points, a diagnosis's trials): where they do not all
/// fit, dropping the least recently used would drop each one just before
/// it is read again, and none would ever be read twice.
pub(crate) fn pair_a_table(key: [u32; 2], realisation: u32, intervals: u64, make: bool) -> Option<PairTable> {
    let wanted = usize::try_from(intervals).ok().filter(|&n| n <= BUDGET_INTERVALS)?;
    {
        let mut guard = TABLES.lock().unwrap_or_else(|e| e.into_inner());
        let tables = guard.get_or_insert_with(Tables::default);
        tables.tick += 1;
        let tick = tables.tick;
        if let Some((table, used)) = tables.by_path.get_mut(&(key, realisation))
            && table.len() >= wanted
        {
            *used = tick;
            return Some(table.clone());
        }
        if !make || tables.seed_held(key, realisation) + wanted > BUDGET_INTERVALS {
            return None;
        }
    }
    // Drawn outside the lock, so that other threads' paths go on; two
    // threads asking for the same realisation at once both draw it (the
    // same values).
    let table: PairTable = (0..wanted as u64)
        .step_by(rng::SIDE_BY_SIDE)
        .flat_map(|first| {
            let count = (wanted as u64 - first).min(rng::SIDE_BY_SIDE as u64) as usize;
            rng::pair_a_run(key, realisation, first, count).into_iter().take(count)
        })
        .collect();
    let mut guard = TABLES.lock().unwrap_or_else(|e| e.into_inner());
    let tables = guard.get_or_insert_with(Tables::default);
    if let Some((old, _)) = tables.by_path.remove(&(key, realisation)) {
        tables.held -= old.len();
    }
    while tables.held + wanted > BUDGET_INTERVALS {
        let oldest = tables.by_path.iter().filter(|((k, _), _)| *k != key).min_by_key(|(_, (_, used))| *used);
        let Some((&oldest, _)) = oldest else {
            // Filled by this seed's tables meanwhile: this one is used, not kept.
            return Some(table);
        };
        let (old, _) = tables.by_path.remove(&oldest).expect("a held table");
        tables.held -= old.len();
    }
    tables.held += wanted;
    tables.tick += 1;
    let tick = tables.tick;
    tables.by_path.insert((key, realisation), (table.clone(), tick));
    Some(table)
}

impl Tables {
    /// Intervals held in tables of seed key `key`, but for realisation
    /// `realisation`'s (which a longer one would replace).
    fn seed_held(&self, key: [u32; 2], realisation: u32) -> usize {
        self.by_path.iter().filter(|((k, r), _)| *k == key && *r != realisation).map(|(_, (t, _))| t.len()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table holds the draws themselves, and a longer request replaces a
    /// shorter table.
    #[test]
    fn tables_hold_the_draws() {
        let key = rng::seed_key(0x007A_B1E5);
        let short = pair_a_table(key, 3, 5, true).expect("a table");
        let long = pair_a_table(key, 3, 40, true).expect("a table");
        assert_eq!(long.len(), 40);
        for (i, &(white, xi_n)) in long.iter().enumerate() {
            let drawn = rng::pair_a(rng::noise_block(key, 3, rng::STREAM_MAIN, i as u64));
            assert_eq!((white.to_bits(), xi_n.to_bits()), (drawn.0.to_bits(), drawn.1.to_bits()));
        }
        assert_eq!(&long[..5], &short[..]);
        assert!(pair_a_table(key, 3, BUDGET_INTERVALS as u64 + 1, true).is_none());
        // A held table serves a request that would not make one.
        assert_eq!(pair_a_table(key, 3, 30, false).expect("the held table").len(), 40);
        assert!(pair_a_table(key, 4, 30, false).is_none());
    }
}
