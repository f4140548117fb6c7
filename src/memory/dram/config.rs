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
use crate::error::{Error, Result};

/// Where configuration errors say they come from.
pub(crate) const FILE: &str = "DRAM config";

/// The timings, in cycles of the DRAM command clock (JEDEC's nCK) but for the clock period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DramTimings {
    /// Command clock period \[ps\].
    pub tck_ps: u32,
    /// ACT to a read command \[cycles\].
    pub trcd_rd: u32,
    /// ACT to a write command \[cycles\] (GDDR6's tRCDWR; tRCD on DDR4).
    pub trcd_wr: u32,
    /// PRE to ACT, same bank \[cycles\].
    pub trp: u32,
    /// Read command to first data: CAS latency (CL, with AL = 0) \[cycles\].
    pub tcl: u32,
    /// Write command to first data: CAS write latency (CWL) \[cycles\].
    pub tcwl: u32,
    /// ACT to PRE, same bank \[cycles\].
    pub tras: u32,
    /// One atom's data on the bus \[cycles\].
    pub tburst: u32,
    /// End of write data to a read command, other bank group \[cycles\].
    pub twtr_s: u32,
    /// End of write data to a read command, same bank group \[cycles\].
    pub twtr_l: u32,
    /// Read command to write command (the bus turnaround, tRTW) \[cycles\].
    pub trtw: u32,
    /// Idle data-bus cycles between bursts of different ranks (tRTRS) \[cycles\].
    pub trtrs: u32,
    /// Column command to column command, other bank group \[cycles\].
    pub tccd_s: u32,
    /// Column command to column command, same bank group \[cycles\].
    pub tccd_l: u32,
    /// ACT to ACT, same rank, other bank group \[cycles\].
    pub trrd_s: u32,
    /// ACT to ACT, same rank, same bank group \[cycles\].
    pub trrd_l: u32,
    /// Window that holds at most four ACTs of one rank \[cycles\].
    pub tfaw: u32,
    /// Read command to PRE, same bank \[cycles\].
    pub trtp: u32,
    /// End of write data to PRE, same bank (write recovery) \[cycles\].
    pub twr: u32,
}

impl DramTimings {
    /// Each timing by name, for validation.
    fn named(&self) -> [(&'static str, u32); 19] {
        [
            ("timings.tck_ps", self.tck_ps),
            ("timings.trcd_rd", self.trcd_rd),
            ("timings.trcd_wr", self.trcd_wr),
            ("timings.trp", self.trp),
            ("timings.tcl", self.tcl),
            ("timings.tcwl", self.tcwl),
            ("timings.tras", self.tras),
            ("timings.tburst", self.tburst),
            ("timings.twtr_s", self.twtr_s),
            ("timings.twtr_l", self.twtr_l),
            ("timings.trtw", self.trtw),
            ("timings.trtrs", self.trtrs),
            ("timings.tccd_s", self.tccd_s),
            ("timings.tccd_l", self.tccd_l),
            ("timings.trrd_s", self.trrd_s),
            ("timings.trrd_l", self.trrd_l),
            ("timings.tfaw", self.tfaw),
            ("timings.trtp", self.trtp),
            ("timings.twr", self.twr),
        ]
    }

    /// The clock period \[ns\].
    pub fn tck_ns(&self) -> f64 {
        f64::from(self.tck_ps) / 1000.0
    }
}

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
