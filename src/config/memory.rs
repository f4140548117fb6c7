//! The memory system's architecture fields (`memory`, DESIGN.md §3, "The memory system"):
//! which model prices the frame buffer, the ROP caches' geometry, the tile table's switches
//! and the DRAM behind them. The checks one field alone cannot make (a cache smaller than a
//! line, a line not a multiple of the sector) are [`MemoryConfig::check`]'s.

use super::declare::section;
use super::rules::{OneOf, Whole, COUNT};
use crate::error::{Error, Result};
use crate::memory::cache::CacheConfig;
use crate::memory::dram::{ddr4_2400_x8, gddr6_16g_x16, lpddr5_6400_x16, DramConfig};
use crate::memory::tiles::{PixelOrder, TileFeatures, TILE_PX};
use serde::{Deserialize, Serialize};

/// The names of [`MemoryModel`] (a unit test holds them equal to serde's).
pub(super) const MEMORY_MODELS: OneOf = OneOf(&["port", "dram"]);
/// The names of [`DramPreset`] (a unit test holds them equal to serde's).
pub(super) const DRAM_KINDS: OneOf = OneOf(&["ddr4", "gddr6", "lpddr5"]);
/// Bytes of a colour (RGBA8) and of a depth (D24S8) pixel as the frame buffer stores them.
pub const BYTES_PER_PIXEL: u32 = 4;
/// The names of [`PixelOrder`].
pub(super) const PIXEL_ORDERS: OneOf = OneOf(&["morton", "row_major"]);
/// A switch's names.
pub(super) const SWITCH: OneOf = OneOf(&["true", "false"]);

/// How the frame buffer's traffic is priced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MemoryModel {
    /// The ROPs' bytes through one port of `framebuffer.bytes_per_cycle`, an access at
    /// least one slot (DESIGN.md §3, "One memory port").
    #[default]
    Port,
    /// Per-ROP colour and depth caches over tile tables (fast clear, compression,
    /// hierarchical Z), their fills and write-backs through a DRAM controller.
    Dram,
}

/// The DRAM behind the controller: one of the presets of [`crate::memory::dram`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DramPreset {
    /// DDR4-2400, x8 devices, a 64-bit channel ([`ddr4_2400_x8`]).
    Ddr4,
    /// GDDR6 at 16 Gb/s, x16 channels ([`gddr6_16g_x16`]).
    #[default]
    Gddr6,
    /// LPDDR5-6400, x16 channels ([`lpddr5_6400_x16`]).
    Lpddr5,
}

impl DramPreset {
    /// Its name in architecture files, reports and the technology file's memory kinds.
    pub fn name(self) -> &'static str {
        match self {
            DramPreset::Ddr4 => "ddr4",
            DramPreset::Gddr6 => "gddr6",
            DramPreset::Lpddr5 => "lpddr5",
        }
    }
}

/// A cache size's rule: one line (at least a sector) up to 16 MiB; the check that it holds
/// whole sets of whole lines is [`MemoryConfig::check`]'s.
const CACHE_BYTES: Whole = Whole {
    min: 1,
    max: crate::memory::cache::MAX_CACHE_BYTES as u64,
    unit: "bytes (a cache of at most 16 MiB)",
};
/// A line's or a sector's size.
const BLOCK_BYTES: Whole = Whole {
    min: 1,
    max: 4096,
    unit: "bytes",
};

section! {
    /// The memory system (DESIGN.md §3, "The memory system"): `model` picks the message
    /// port of `framebuffer` or the ROP caches, tile tables and DRAM described by the
    /// other fields. Cache defaults are ATTILA's (Moya et al., ISPASS 2006, `bGPU.ini`):
    /// 16 KB Z and colour caches per ROP, 4 ways, lines of an 8x8 tile at 32 bits, a
    /// 32-byte cache port.
    pub struct MemoryConfig {
        /// `port`: the ROPs' bytes through the port of `framebuffer`; `dram`: per-ROP
        /// caches over tile tables, their fills and write-backs through a DRAM controller.
        /// Default `port`.
        pub model: MemoryModel = MemoryModel::Port => MEMORY_MODELS,
        /// The DRAM, one of the cited presets: `ddr4` (DDR4-2400 x8, 64-bit channels),
        /// `gddr6` (16 Gb/s, x16 channels), `lpddr5` (6400 MT/s, x16 channels). Its energy
        /// comes from the technology file's memory kind of the same name. Default `gddr6`.
        pub dram: DramPreset = DramPreset::Gddr6 => DRAM_KINDS,
        /// DRAM channels, each with its own controller, queues and bus \[channels\]; a power
        /// of two. Default 1: one x16 GDDR6 channel moves 32 GB/s, 64 bytes a cycle at
        /// 500 MHz, the `framebuffer` port's default rate.
        pub channels: u32 = 1 => COUNT,
        /// Permutation-based page interleaving: the DRAM's bank group and bank XORed with
        /// the row's low bits, as GPU memory controllers hash addresses (Zhang et al.,
        /// MICRO 2000; Liu et al., ISCA 2018), so a surface's tile rows and the colour and
        /// depth surfaces spread over the banks. Default true.
        pub bank_xor: bool = true => SWITCH,
        /// Each ROP's colour cache \[bytes\]. Default 16384 (ATTILA).
        pub colour_cache_bytes: u32 = 16384 => CACHE_BYTES,
        /// Each ROP's depth cache \[bytes\]. Default 16384 (ATTILA).
        pub depth_cache_bytes: u32 = 16384 => CACHE_BYTES,
        /// Ways of both caches. Default 4 (ATTILA).
        pub cache_ways: u32 = 4 => Whole {
                min: 1,
                max: 64,
                unit: "ways",
            },
        /// A cache line \[bytes\]: one 8x8 tile of the surface. Default 256 (64 pixels of 4
        /// bytes, ATTILA's 16 stamps of 2x2).
        pub cache_line_bytes: u32 = 256 => BLOCK_BYTES,
        /// A sector, the unit a cache fills, writes back and charges \[bytes\]. Default 32
        /// (ATTILA's cache port width).
        pub sector_bytes: u32 = 32 => BLOCK_BYTES,
        /// The order of pixels within a tile: `morton` (Z order: a 32-byte sector is a 4x2
        /// block, two quads) or `row_major` (a sector is one row of the tile). Default `morton`, as GPUs store tiles.
        pub pixel_order: PixelOrder = PixelOrder::Morton => PIXEL_ORDERS,
        /// Sectors each cache reads or writes a cycle: a span costs its ROP at least the
        /// sectors it touches in either cache over this \[sectors/cycle\]. Default 1
        /// (ATTILA's 32-byte cache port).
        pub cache_sectors_per_cycle: u32 = 1 => Whole {
                min: 1,
                max: 64,
                unit: "sectors a cycle",
            },
        /// Fast clear: a clear marks tiles cleared, and a cleared tile is filled without a
        /// read. Default true.
        pub fast_clear: bool = true => SWITCH,
        /// Depth tiles plane-encoded at write-back when the code fits half the tile.
        /// Default true.
        pub depth_compression: bool = true => SWITCH,
        /// Colour tiles delta-encoded at write-back when the code fits half the tile.
        /// Default true.
        pub colour_compression: bool = true => SWITCH,
        /// Hierarchical Z: a span or quad wholly behind its tile's farthest depth is
        /// rejected before the depth read. Default true.
        pub hierarchical_z: bool = true => SWITCH,
    }
}

impl MemoryConfig {
    /// The colour cache's geometry.
    pub fn colour_cache(&self) -> CacheConfig {
        self.cache(self.colour_cache_bytes)
    }

    /// The depth cache's geometry.
    pub fn depth_cache(&self) -> CacheConfig {
        self.cache(self.depth_cache_bytes)
    }

    fn cache(&self, size_bytes: u32) -> CacheConfig {
        CacheConfig {
            size_bytes,
            ways: self.cache_ways,
            line_bytes: self.cache_line_bytes,
            sector_bytes: self.sector_bytes,
        }
    }

    /// The tile table's switches.
    pub fn features(&self) -> TileFeatures {
        TileFeatures {
            fast_clear: self.fast_clear,
            depth_compression: self.depth_compression,
            colour_compression: self.colour_compression,
            hierarchical_z: self.hierarchical_z,
        }
    }

    /// The DRAM: the preset of `dram` with `channels` channels.
    pub fn dram_config(&self) -> DramConfig {
        let mut cfg = match self.dram {
            DramPreset::Ddr4 => ddr4_2400_x8(),
            DramPreset::Gddr6 => gddr6_16g_x16(),
            DramPreset::Lpddr5 => lpddr5_6400_x16(),
        };
        cfg.channels = self.channels;
        cfg.bank_xor = self.bank_xor;
        cfg
    }

    /// What one field cannot refuse alone, naming the field of `file`: a cache smaller
    /// than one line or not whole sets of lines, a line not a whole number of sectors or
    /// not one 8x8 tile of 32-bit pixels, a channel count not a power of two.
    pub fn check(&self, file: &str) -> Result<()> {
        for (size_field, cache) in [
            ("memory.colour_cache_bytes", self.colour_cache()),
            ("memory.depth_cache_bytes", self.depth_cache()),
        ] {
            cache.validate(file, "").map_err(|e| match e {
                Error::Invalid {
                    field,
                    value,
                    reason,
                    ..
                } => Error::Invalid {
                    file: file.to_string(),
                    field: match field.as_str() {
                        "size_bytes" => size_field.to_string(),
                        "ways" => "memory.cache_ways".to_string(),
                        "line_bytes" => "memory.cache_line_bytes".to_string(),
                        other => format!("memory.{other}"),
                    },
                    value,
                    reason,
                },
                other => other,
            })?;
        }
        let tile = TILE_PX * TILE_PX * BYTES_PER_PIXEL;
        if self.cache_line_bytes != tile {
            return Err(Error::invalid(
                file,
                "memory.cache_line_bytes",
                self.cache_line_bytes,
                format!("must be one 8x8 tile of 4-byte pixels, {tile} bytes"),
            ));
        }
        if !self.channels.is_power_of_two() {
            return Err(Error::invalid(
                file,
                "memory.channels",
                self.channels,
                "must be a power of two (the address mapping takes bits)",
            ));
        }
        Ok(())
    }
}
