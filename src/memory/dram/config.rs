//! The controller's configuration: the organisation of the memory (channels, ranks, bank
//! groups, banks, rows, atoms per row), its bus (width and burst length, which make the
//! atom), the address mapping, the timings, the queues and the energies. Validated once by
//! [`DramConfig::validate`]; the presets ([`super::presets`]) cite where each figure comes
//! from.
//!
//! **The atom** is what one column command moves: bus bytes times the burst length, 64 B on
//! a DDR4 x64 channel at BL8, 32 B on a GDDR6 or LPDDR5 x16 channel at BL16. A request
//! smaller than an atom (a 32-byte sector on DDR4) still moves, and pays for, the whole
//! atom: DRAM has no narrower transfer (DDR4's burst chop BC4 moves half the data in the
//! same command slot, so it saves no time).

use super::energy::DramEnergy;
use super::mapping::AddressMapping;
use super::timings::{DramTimings, FILE};
use crate::error::{Error, Result};

/// A memory system behind one controller per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct DramConfig {
    /// The preset's name, for reports (`DDR4-2400 x8`).
    pub name: String,
    /// Independent channels, each with its own controller, queues and bus (a power of two).
    pub channels: u32,
    /// Ranks per channel (a power of two).
    pub ranks: u32,
    /// Bank groups per rank (a power of two; 1 where the part has none in use).
    pub bank_groups: u32,
    /// Banks per bank group (a power of two).
    pub banks_per_group: u32,
    /// Rows per bank (a power of two).
    pub rows: u32,
    /// A row's size in atoms: the row buffer of the rank (all its devices) over the atom
    /// (a power of two).
    pub atoms_per_row: u32,
    /// Data bus width of one channel \[bits\].
    pub bus_bits: u32,
    /// Burst length \[transfers per column command\].
    pub burst_length: u32,
    /// Which address bits pick which field.
    pub mapping: AddressMapping,
    /// The timings.
    pub timings: DramTimings,
    /// Read queue entries per channel, and write queue entries per channel.
    pub queue_depth: u32,
    /// The write queue's occupancy at which the controller starts draining writes.
    pub write_high: u32,
    /// The write queue's occupancy at which a drain stops (below `write_high`).
    pub write_low: u32,
    /// The requests of one bank the scheduler chooses among: that bank's oldest this many in
    /// the queue served (DRAMsim3's per-bank command queue, `cmd_queue_size`).
    pub bank_window: u32,
    /// Column commands to an open row after which an older request to another row of the
    /// same bank goes before further row hits (DRAMsim3's cap of 4 in
    /// `CommandQueue::ArbitratePrecharge`, `src/command_queue.cc`; FR-FCFS with a cap keeps
    /// a stream of hits from starving a conflict).
    pub row_hit_cap: u32,
    /// Permutation-based page interleaving: the bank group and bank are XORed with the low
    /// bits of the row, so rows that share a bank under the plain mapping (two surfaces a
    /// power of two apart, the same column band of consecutive tile rows) spread over the
    /// banks (Zhang, Zhu and Zhang, "A Permutation-based Page Interleaving Scheme to Reduce
    /// Row-buffer Conflicts and Exploit Data Locality", MICRO 2000; GPUs hash their memory
    /// addresses alike, Liu et al., "Get Out of the Valley: Power-Efficient Address
    /// Mapping for GPUs", ISCA 2018). Off in the presets, as in DRAMsim3's files.
    pub bank_xor: bool,
    /// Energy per event.
    pub energy: DramEnergy,
}

impl DramConfig {
    /// Bytes one column command moves: bus bytes times the burst length.
    pub fn atom_bytes(&self) -> u32 {
        self.bus_bits / 8 * self.burst_length
    }

    /// The peak data rate of all channels \[bytes per command-clock cycle\].
    pub fn peak_bytes_per_cycle(&self) -> f64 {
        f64::from(self.channels) * f64::from(self.atom_bytes()) / f64::from(self.timings.tburst)
    }

    /// Refuses a configuration the controller cannot run, naming the field: a zero count or
    /// timing, a size not a power of two (the address mapping takes bits), a bus not whole
    /// bytes, watermarks out of order, an energy negative or not finite.
    pub fn validate(&self) -> Result<()> {
        let counts = [
            ("channels", self.channels),
            ("ranks", self.ranks),
            ("bank_groups", self.bank_groups),
            ("banks_per_group", self.banks_per_group),
            ("rows", self.rows),
            ("atoms_per_row", self.atoms_per_row),
            ("bus_bits", self.bus_bits),
            ("burst_length", self.burst_length),
            ("queue_depth", self.queue_depth),
            ("write_high", self.write_high),
            ("bank_window", self.bank_window),
            ("row_hit_cap", self.row_hit_cap),
        ];
        for (field, v) in counts.into_iter().chain(self.timings.named()) {
            if v == 0 {
                return Err(Error::invalid(FILE, field, v, "must be at least 1"));
            }
        }
        for (field, v) in &counts[..6] {
            if !v.is_power_of_two() {
                return Err(Error::invalid(FILE, *field, v, "must be a power of two"));
            }
        }
        if !self.bus_bits.is_multiple_of(8) || !self.atom_bytes().is_power_of_two() {
            return Err(Error::invalid(
                FILE,
                "bus_bits",
                self.bus_bits,
                "bus bytes times the burst length must be a power of two",
            ));
        }
        if self.write_high > self.queue_depth {
            return Err(Error::invalid(
                FILE,
                "write_high",
                self.write_high,
                format!("must not exceed queue_depth ({})", self.queue_depth),
            ));
        }
        if self.write_low >= self.write_high {
            return Err(Error::invalid(
                FILE,
                "write_low",
                self.write_low,
                format!("must be below write_high ({})", self.write_high),
            ));
        }
        self.energy.validate()
    }

    /// The six sizes the address mapping decodes, channels first.
    pub(crate) fn sizes(&self) -> [u32; 6] {
        [
            self.channels,
            self.ranks,
            self.bank_groups,
            self.banks_per_group,
            self.rows,
            self.atoms_per_row,
        ]
    }
}
