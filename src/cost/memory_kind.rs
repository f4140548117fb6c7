//! A memory kind of the technology file (`memory_kinds.<name>`): DRAM priced as DRAM works,
//! per bit read or written at the pins (interface and core) and per row activation (ACT
//! with its PRE), each figure cited in its `note` (`sim/tech/README.md`).
//!
//! [`MemoryKind::energy_pj`] prices what a memory controller counts: atoms read and
//! written, each a whole atom whatever its useful bytes, and row activations. There is no
//! background (standby) term: the per-bit figures are published averages per bit moved,
//! which already hold the device's standby at its source's traffic.
//! [`MemoryKind::dram_energy`] hands the same figures to the controller
//! ([`crate::memory::dram::DramEnergy`]).

use crate::memory::dram::DramEnergy;
use serde::{Deserialize, Serialize};

/// One kind of DRAM: its energies, as the technology file gives them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MemoryKind {
    /// Energy per bit read, interface and core \[pJ/bit\].
    pub pj_per_bit_read: f64,
    /// Energy per bit written, interface and core \[pJ/bit\].
    pub pj_per_bit_written: f64,
    /// Energy per row activation, its precharge included \[pJ\].
    pub pj_per_activation: f64,
    /// Where the figures come from, and how any was derived.
    pub note: String,
}

/// A frame's DRAM energy by what spent it \[pJ\].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct DramEnergySplit {
    /// The memory kind priced (`gddr6`).
    pub kind: &'static str,
    /// Atoms read \[pJ\].
    pub read_pj: f64,
    /// Atoms written \[pJ\].
    pub write_pj: f64,
    /// Row activations \[pJ\].
    pub activation_pj: f64,
    /// The sum of the three \[pJ\].
    pub total_pj: f64,
}

impl MemoryKind {
    /// The energy of `atoms_read` and `atoms_written` atoms of `atom_bytes` bytes each (a
    /// partial write pays its whole atom: the caller counts atoms, not useful bytes) and of
    /// `activations` row activations.
    pub fn energy_pj(
        &self,
        atoms_read: u64,
        atoms_written: u64,
        atom_bytes: u32,
        activations: u64,
    ) -> DramEnergySplit {
        let atom_bits = 8.0 * f64::from(atom_bytes);
        let read_pj = atoms_read as f64 * atom_bits * self.pj_per_bit_read;
        let write_pj = atoms_written as f64 * atom_bits * self.pj_per_bit_written;
        let activation_pj = activations as f64 * self.pj_per_activation;
        DramEnergySplit {
            kind: "",
            read_pj,
            write_pj,
            activation_pj,
            total_pj: read_pj + write_pj + activation_pj,
        }
    }

    /// The controller's per-event energies for atoms of `atom_bytes` bytes: these figures,
    /// with no standby term (as [`MemoryKind::energy_pj`]).
    pub fn dram_energy(&self, atom_bytes: u32) -> DramEnergy {
        let atom_bits = 8.0 * f64::from(atom_bytes);
        DramEnergy {
            read_atom_pj: atom_bits * self.pj_per_bit_read,
            write_atom_pj: atom_bits * self.pj_per_bit_written,
            activation_pj: self.pj_per_activation,
            active_standby_pj: 0.0,
            precharge_standby_pj: 0.0,
        }
    }

    /// The three figures by their field names, for validation.
    pub(super) fn figures(&self) -> [(&'static str, f64); 3] {
        [
            ("pj_per_bit_read", self.pj_per_bit_read),
            ("pj_per_bit_written", self.pj_per_bit_written),
            ("pj_per_activation", self.pj_per_activation),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kind(read: f64, written: f64, activation: f64) -> MemoryKind {
        MemoryKind {
            pj_per_bit_read: read,
            pj_per_bit_written: written,
            pj_per_activation: activation,
            note: String::new(),
        }
    }

    /// GDDR6 at 7.5 pJ/bit both ways and 723.6 pJ an activation, 32-byte atoms (256 bits):
    /// 10 atoms read = 10 x 256 x 7.5 = 19 200 pJ; 4 written = 4 x 256 x 7.5 = 7 680 pJ;
    /// 3 activations = 2 170.8 pJ; total 29 050.8 pJ.
    #[test]
    fn atoms_and_activations_are_priced_by_hand() {
        let e = kind(7.5, 7.5, 723.6).energy_pj(10, 4, 32, 3);
        assert_eq!(e.read_pj, 19_200.0);
        assert_eq!(e.write_pj, 7_680.0);
        assert!((e.activation_pj - 2_170.8).abs() < 1e-9, "{e:?}");
        assert!((e.total_pj - 29_050.8).abs() < 1e-9, "{e:?}");
    }

    /// Reads and writes take their own figures, and the atom's size scales both: LPDDR5's
    /// 2.9 and 2.75 pJ/bit on 64-byte atoms (512 bits): 1 read = 1 484.8 pJ, 2 written =
    /// 2 816 pJ, no activation.
    #[test]
    fn reads_and_writes_take_their_own_figures_per_atom_bit() {
        let e = kind(2.9, 2.75, 2378.25).energy_pj(1, 2, 64, 0);
        assert!((e.read_pj - 1_484.8).abs() < 1e-9, "{e:?}");
        assert_eq!(e.write_pj, 2_816.0);
        assert_eq!(e.activation_pj, 0.0);
        assert!((e.total_pj - 4_300.8).abs() < 1e-9, "{e:?}");
        // Nothing moved, nothing spent.
        assert_eq!(
            kind(2.9, 2.75, 2378.25).energy_pj(0, 0, 32, 0),
            DramEnergySplit::default()
        );
    }

    /// The controller's per-event figures are the same prices: one atom of each, one
    /// activation, and no standby.
    #[test]
    fn the_controller_energy_is_the_same_prices() {
        let k = kind(6.0, 5.0, 828.0);
        let d = k.dram_energy(32);
        let e = k.energy_pj(1, 1, 32, 1);
        assert_eq!(
            (d.read_atom_pj, d.write_atom_pj, d.activation_pj),
            (e.read_pj, e.write_pj, e.activation_pj)
        );
        assert_eq!((d.read_atom_pj, d.write_atom_pj), (1_536.0, 1_280.0));
        assert_eq!((d.active_standby_pj, d.precharge_standby_pj), (0.0, 0.0));
        assert!(d.validate().is_ok());
    }
}
