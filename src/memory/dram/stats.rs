//! What a controller run measured: atoms and bytes, row-buffer outcomes, commands, latency,
//! bandwidth and energy.

use super::channel::{RowOutcome, Scheduled};
use super::config::DramConfig;

/// Energy of a run, split by what spent it \[pJ\].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DramEnergyStats {
    /// Atoms read \[pJ\].
    pub read_pj: f64,
    /// Atoms written \[pJ\].
    pub write_pj: f64,
    /// Row activations \[pJ\].
    pub activation_pj: f64,
    /// Background (standby) of every rank up to the last completion \[pJ\].
    pub background_pj: f64,
}

impl DramEnergyStats {
    /// The sum \[pJ\].
    pub fn total_pj(&self) -> f64 {
        self.read_pj + self.write_pj + self.activation_pj + self.background_pj
    }
}

/// A run's totals.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DramStats {
    /// Requests completed.
    pub requests: u64,
    /// Atoms read.
    pub atoms_read: u64,
    /// Atoms written.
    pub atoms_written: u64,
    /// Bytes read: atoms read times the atom \[B\].
    pub bytes_read: u64,
    /// Bytes written: atoms written times the atom \[B\].
    pub bytes_written: u64,
    /// Requests whose row was open.
    pub row_hits: u64,
    /// Requests that found their bank precharged.
    pub row_misses: u64,
    /// Requests that found another row open.
    pub row_conflicts: u64,
    /// ACT commands.
    pub activations: u64,
    /// PRE commands.
    pub precharges: u64,
    /// The cycle the last request completed \[cycles\].
    pub last_done: u64,
    /// Mean read latency, arrival to last data \[cycles\].
    pub read_latency_mean: f64,
    /// Largest read latency \[cycles\].
    pub read_latency_max: u64,
    /// Bytes moved over `last_done` \[bytes per cycle\].
    pub bytes_per_cycle: f64,
    /// Bytes moved over `last_done` cycles of tCK \[GB/s\].
    pub gbytes_per_s: f64,
    /// Energy, split.
    pub energy: DramEnergyStats,
}

impl DramStats {
    /// Row hits over requests (0 with none).
    pub fn row_hit_rate(&self) -> f64 {
        self.row_hits as f64 / self.requests.max(1) as f64
    }

    /// Total energy over bytes moved \[pJ/B\] (0 with none).
    pub fn pj_per_byte(&self) -> f64 {
        self.energy.total_pj() / (self.bytes_read + self.bytes_written).max(1) as f64
    }
}

/// The running counts a [`DramStats`] is made from.
#[derive(Clone, Debug, Default)]
pub(crate) struct Counters {
    reads: u64,
    writes: u64,
    hits: u64,
    misses: u64,
    conflicts: u64,
    last_done: u64,
    read_latency_sum: u128,
    read_latency_max: u64,
}

impl Counters {
    pub(crate) fn record(&mut self, s: &Scheduled) {
        match s.outcome {
            RowOutcome::Hit => self.hits += 1,
            RowOutcome::Miss => self.misses += 1,
            RowOutcome::Conflict => self.conflicts += 1,
        }
        if s.req.write {
            self.writes += 1;
        } else {
            self.reads += 1;
            let lat = s.done - s.req.arrival;
            self.read_latency_sum += u128::from(lat);
            self.read_latency_max = self.read_latency_max.max(lat);
        }
        self.last_done = self.last_done.max(s.done);
    }

    /// The totals; `first_acts` holds every rank's first activation (background energy:
    /// precharge standby before it, active standby after, as open pages stay open).
    pub(crate) fn stats(
        &self,
        cfg: &DramConfig,
        first_acts: impl Iterator<Item = Option<u64>>,
    ) -> DramStats {
        let atom = u64::from(cfg.atom_bytes());
        let e = &cfg.energy;
        let activations = self.misses + self.conflicts;
        let end = self.last_done;
        let background_pj: f64 = first_acts
            .map(|first| {
                let idle = first.unwrap_or(end).min(end);
                idle as f64 * e.precharge_standby_pj + (end - idle) as f64 * e.active_standby_pj
            })
            .sum();
        let bytes = (self.reads + self.writes) * atom;
        let cycles = end.max(1) as f64;
        DramStats {
            requests: self.reads + self.writes,
            atoms_read: self.reads,
            atoms_written: self.writes,
            bytes_read: self.reads * atom,
            bytes_written: self.writes * atom,
            row_hits: self.hits,
            row_misses: self.misses,
            row_conflicts: self.conflicts,
            activations,
            precharges: self.conflicts,
            last_done: end,
            read_latency_mean: self.read_latency_sum as f64 / self.reads.max(1) as f64,
            read_latency_max: self.read_latency_max,
            bytes_per_cycle: bytes as f64 / cycles,
            gbytes_per_s: bytes as f64 / (cycles * cfg.timings.tck_ns()),
            energy: DramEnergyStats {
                read_pj: self.reads as f64 * e.read_atom_pj,
                write_pj: self.writes as f64 * e.write_atom_pj,
                activation_pj: activations as f64 * e.activation_pj,
                background_pj,
            },
        }
    }
}
