//! The address mapping: which bits of a byte address pick the channel, rank, bank group,
//! bank, row and column. Written as DRAMsim3 writes it (`address_mapping` in its
//! configuration files, `Config::SetAddressMapping` in `src/configuration.cc`): six
//! two-letter fields from the most significant to the least, `ch ra bg ba ro co`, above
//! the atom's offset bits. DRAMsim3's default, `rochrababgco`, puts the column lowest (a
//! sequential stream stays in one row of one bank until the row ends), then the bank
//! group, bank, rank and channel, and the row highest.

use super::timings::FILE;
use crate::error::{Error, Result};
use std::fmt;

/// One field of a mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapField {
    /// `ch`: the channel.
    Channel,
    /// `ra`: the rank.
    Rank,
    /// `bg`: the bank group.
    BankGroup,
    /// `ba`: the bank within its group.
    Bank,
    /// `ro`: the row.
    Row,
    /// `co`: the column, in atoms.
    Column,
}

impl MapField {
    fn code(self) -> &'static str {
        match self {
            MapField::Channel => "ch",
            MapField::Rank => "ra",
            MapField::BankGroup => "bg",
            MapField::Bank => "ba",
            MapField::Row => "ro",
            MapField::Column => "co",
        }
    }
}

/// The six fields, most significant first; each appears once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AddressMapping(pub [MapField; 6]);

impl AddressMapping {
    /// DRAMsim3's default, `rochrababgco` (row, channel, rank, bank, bank group, column).
    pub const ROCHRABABGCO: AddressMapping = AddressMapping([
        MapField::Row,
        MapField::Channel,
        MapField::Rank,
        MapField::Bank,
        MapField::BankGroup,
        MapField::Column,
    ]);

    /// Parses DRAMsim3's twelve-letter form (`rochrababgco`); an unknown, missing or
    /// repeated field is [`Error::Invalid`] naming `address_mapping`.
    pub fn parse(text: &str) -> Result<AddressMapping> {
        let bad = |reason: &str| Error::invalid(FILE, "address_mapping", text, reason);
        if text.len() != 12 || !text.is_ascii() {
            return Err(bad("six two-letter fields (ch ra bg ba ro co), each once"));
        }
        let all = [
            MapField::Channel,
            MapField::Rank,
            MapField::BankGroup,
            MapField::Bank,
            MapField::Row,
            MapField::Column,
        ];
        let mut fields = [MapField::Row; 6];
        for (i, slot) in fields.iter_mut().enumerate() {
            let code = &text[2 * i..2 * i + 2];
            *slot = *all
                .iter()
                .find(|f| f.code() == code)
                .ok_or_else(|| bad("fields are ch, ra, bg, ba, ro, co"))?;
        }
        for f in all {
            if !fields.contains(&f) {
                return Err(bad("each of ch, ra, bg, ba, ro, co exactly once"));
            }
        }
        Ok(AddressMapping(fields))
    }
}

impl fmt::Display for AddressMapping {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for field in self.0 {
            f.write_str(field.code())?;
        }
        Ok(())
    }
}

/// Where an atom lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Location {
    /// Channel index.
    pub channel: u32,
    /// Rank within the channel.
    pub rank: u32,
    /// Bank group within the rank.
    pub bank_group: u32,
    /// Bank within the group.
    pub bank: u32,
    /// Row within the bank.
    pub row: u32,
    /// Column within the row, in atoms.
    pub column: u32,
}

/// The bit widths of each field, and the atom's offset bits, for a decode.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Decoder {
    mapping: AddressMapping,
    offset_bits: u32,
    /// log2 of channels, ranks, bank groups, banks, rows, columns.
    bits: [u32; 6],
    /// Bank group and bank XORed with the row's low bits ([`super::DramConfig::bank_xor`]).
    bank_xor: bool,
}

impl Decoder {
    /// `sizes`: channels, ranks, bank groups, banks per group, rows, atoms per row, each a
    /// power of two (the configuration checked it).
    pub(crate) fn new(mapping: AddressMapping, atom_bytes: u32, sizes: [u32; 6]) -> Decoder {
        Decoder {
            mapping,
            offset_bits: atom_bytes.trailing_zeros(),
            bits: sizes.map(|s| s.trailing_zeros()),
            bank_xor: false,
        }
    }

    /// The same decode with the bank group and bank XORed with the row's low bits.
    pub(crate) fn with_bank_xor(mut self, on: bool) -> Decoder {
        self.bank_xor = on;
        self
    }

    /// The atom holding byte `addr`. Bits above the mapped ones wrap (as in DRAMsim3).
    pub(crate) fn decode(&self, addr: u64) -> Location {
        let mut rest = addr >> self.offset_bits;
        let mut v = [0u32; 6];
        for field in self.mapping.0.iter().rev() {
            let i = *field as usize;
            let mask = (1u64 << self.bits[i]) - 1;
            v[i] = (rest & mask) as u32;
            rest >>= self.bits[i];
        }
        if self.bank_xor {
            // The row's lowest bits permute the groups, the next ones the banks.
            let (g, b) = (self.bits[2], self.bits[3]);
            v[2] ^= v[4] & ((1 << g) - 1);
            v[3] ^= (v[4] >> g) & ((1 << b) - 1);
        }
        Location {
            channel: v[0],
            rank: v[1],
            bank_group: v[2],
            bank: v[3],
            row: v[4],
            column: v[5],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With the XOR, rows that shared a bank spread over every group and bank, each row
    /// keeping its own (a permutation: no two rows of one bank collide that did not).
    #[test]
    fn bank_xor_spreads_one_banks_rows_over_every_bank() {
        // 32-byte atoms, one channel and rank, 2 groups of 8 banks, 128 columns:
        // bits 5..12 column, 12 group, 13..16 bank, 16.. row (rorabacobgch-like order).
        let sizes = [1, 1, 2, 8, 1 << 14, 128];
        let plain = Decoder::new(AddressMapping::ROCHRABABGCO, 32, sizes);
        let hashed = plain.with_bank_xor(true);
        let stride = 1u64 << 16; // one row further, same group and bank before hashing
        let mut seen = std::collections::HashSet::new();
        for r in 0..16 {
            let p = plain.decode(r * stride);
            assert_eq!((p.bank_group, p.bank, p.row), (0, 0, r as u32));
            let h = hashed.decode(r * stride);
            assert_eq!(h.row, r as u32);
            assert!(seen.insert((h.bank_group, h.bank)), "row {r} shares a bank");
        }
        // Within one row the mapping still permutes banks one to one.
        let banks: std::collections::HashSet<_> = (0..16u64)
            .map(|b| hashed.decode(5 * stride + (b << 12)))
            .map(|l| (l.bank_group, l.bank))
            .collect();
        assert_eq!(banks.len(), 16);
    }

    #[test]
    fn rochrababgco_decodes_as_dramsim3_lays_it_out() {
        // 64-byte atoms, 2 channels, 2 ranks, 4 groups, 4 banks, 65536 rows, 128 columns:
        // bits 6..13 column, 13..15 group, 15..17 bank, 17 rank, 18 channel, 19.. row.
        let d = Decoder::new(AddressMapping::ROCHRABABGCO, 64, [2, 2, 4, 4, 65536, 128]);
        let addr = (5u64 << 19) | (1 << 18) | (1 << 17) | (2 << 15) | (3 << 13) | (7 << 6) | 9;
        let loc = d.decode(addr);
        assert_eq!(
            loc,
            Location {
                channel: 1,
                rank: 1,
                bank_group: 3,
                bank: 2,
                row: 5,
                column: 7
            }
        );
    }

    #[test]
    fn mappings_parse_and_print_and_bad_ones_are_named() {
        let m = AddressMapping::parse("rochrababgco").unwrap();
        assert_eq!(m, AddressMapping::ROCHRABABGCO);
        assert_eq!(m.to_string(), "rochrababgco");
        for bad in ["rochrababg", "rochrababgxx", "rorochrababg", "rochrababgc0"] {
            match AddressMapping::parse(bad) {
                Err(Error::Invalid { field, .. }) => assert_eq!(field, "address_mapping"),
                other => panic!("{bad}: {other:?}"),
            }
        }
    }
}
