//! Energy per DRAM event: per atom read or written, per row activation, and background per
//! rank and cycle. Either computed from a part's IDD currents as DRAMsim3 computes them
//! ([`DramEnergy::from_idd`]) or taken from a per-bit figure ([`DramEnergy::per_bit`]).
//!
//! DRAMsim3 (`Config::InitOtherParams`, `src/configuration.cc`) charges, per rank (every
//! device of the rank takes each command):
//! - a read atom: VDD (IDD4R - IDD3N) tBURST devices;
//! - a write atom: VDD (IDD4W - IDD3N) tBURST devices;
//! - an activation: VDD (IDD0 tRC - (IDD3N tRAS + IDD2N tRP)) devices, tRC = tRAS + tRP
//!   (the IDD0 loop less its standby share, Micron TN-41-01's method);
//! - background, each cycle: VDD IDD3N devices with a row open, VDD IDD2N with all banks
//!   precharged.
//!
//! DRAMsim3 keeps the times in cycles and reports V·mA·cycle as pJ, which is pJ only at
//! tCK = 1 ns; here the times are in ns (cycles times tCK), so the figures are pJ
//! (DRAMsim3's "pJ" = these / tCK\[ns\]). Neither counts the I/O (termination, PHY), so
//! these are the DRAM core's energy; a system figure such as GDDR6's 7.5 pJ/bit includes
//! the interface and goes in through [`DramEnergy::per_bit`].

use super::timings::{DramTimings, FILE};
use crate::error::{Error, Result};

/// Energy per event \[pJ\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DramEnergy {
    /// One atom read \[pJ\].
    pub read_atom_pj: f64,
    /// One atom written \[pJ\].
    pub write_atom_pj: f64,
    /// One row activation (with its precharge) \[pJ\].
    pub activation_pj: f64,
    /// One rank for one cycle with a row open \[pJ\].
    pub active_standby_pj: f64,
    /// One rank for one cycle with every bank precharged \[pJ\].
    pub precharge_standby_pj: f64,
}

/// A part's supply and IDD currents, from its datasheet or DRAMsim3's `[power]` section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IddCurrents {
    /// Supply \[V\].
    pub vdd: f64,
    /// One bank ACT-PRE loop at tRC \[mA\].
    pub idd0: f64,
    /// Precharge standby \[mA\].
    pub idd2n: f64,
    /// Active standby \[mA\].
    pub idd3n: f64,
    /// Burst read \[mA\].
    pub idd4r: f64,
    /// Burst write \[mA\].
    pub idd4w: f64,
    /// Devices in a rank (bus width over device width).
    pub devices: u32,
}

impl DramEnergy {
    /// DRAMsim3's per-command energies (module doc), with times in ns so the result is pJ.
    pub fn from_idd(idd: &IddCurrents, t: &DramTimings) -> DramEnergy {
        let ns = |cycles: u32| f64::from(cycles) * t.tck_ns();
        let k = idd.vdd * f64::from(idd.devices);
        let (tras, trp) = (ns(t.tras), ns(t.trp));
        DramEnergy {
            read_atom_pj: k * (idd.idd4r - idd.idd3n) * ns(t.tburst),
            write_atom_pj: k * (idd.idd4w - idd.idd3n) * ns(t.tburst),
            activation_pj: k * (idd.idd0 * (tras + trp) - (idd.idd3n * tras + idd.idd2n * trp)),
            active_standby_pj: k * idd.idd3n * t.tck_ns(),
            precharge_standby_pj: k * idd.idd2n * t.tck_ns(),
        }
    }

    /// A flat `pj_per_bit` for every bit read or written, `activation_pj` per activation,
    /// no background: the form of a technology table's memory kind.
    pub fn per_bit(pj_per_bit: f64, activation_pj: f64, atom_bytes: u32) -> DramEnergy {
        let atom = pj_per_bit * 8.0 * f64::from(atom_bytes);
        DramEnergy {
            read_atom_pj: atom,
            write_atom_pj: atom,
            activation_pj,
            active_standby_pj: 0.0,
            precharge_standby_pj: 0.0,
        }
    }

    /// Refuses a negative or non-finite energy, naming it.
    pub fn validate(&self) -> Result<()> {
        let named = [
            ("energy.read_atom_pj", self.read_atom_pj),
            ("energy.write_atom_pj", self.write_atom_pj),
            ("energy.activation_pj", self.activation_pj),
            ("energy.active_standby_pj", self.active_standby_pj),
            ("energy.precharge_standby_pj", self.precharge_standby_pj),
        ];
        for (field, v) in named {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(FILE, field, v, "must be finite and >= 0"));
            }
        }
        Ok(())
    }
}
