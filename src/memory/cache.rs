//! A ROP's colour or depth cache: set-associative, sectored lines, write-back,
//! write-allocate, LRU replacement. It models tags and sector states only (the data stay in
//! the frame buffer); what it returns is the traffic a memory controller would see.
//!
//! **Policy.** A line holds `line_bytes` in sectors of `sector_bytes`, each with a valid and
//! a dirty bit. An access names, as masks over the line's sectors, the sectors it reads,
//! the sectors it writes and, of those, the ones it writes fully. A sector that is read or
//! partially written and not valid is a miss and is filled (one sector read); a sector
//! written fully needs no fill (its old bytes are all overwritten), becomes valid and dirty,
//! and counts as a miss when it was not valid. A line is allocated on any miss
//! (write-allocate); its victim is the least recently used way, and only a victim's dirty
//! sectors are written back. [`LineFill::Whole`] fills every sector of a newly allocated
//! line at once: the tile table asks for it when a tile is stored cleared or compressed and
//! is therefore decoded whole.
//!
//! **Defaults** (ATTILA, Moya et al., "ATTILA: a cycle-level execution-driven simulator for
//! modern GPU architectures", ISPASS 2006; its configuration file `bGPU.ini`, sections
//! `[ZSTENCILTEST]` and `[COLORWRITE]`): `ZCacheWays = 4`, `ZCacheLines = 16` lines per way,
//! `ZCacheStampsPerLine = 16` stamps of 2x2 pixels at `BytesPerPixel = 4`, so a line is an
//! 8x8 tile of 256 bytes and the cache 4 x 16 x 256 = 16 KB, the colour cache the same; the
//! caches' port is `ZCachePortWidth = 32` bytes, which is the sector here.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// The largest accepted cache \[bytes\] (16 MiB: far above any ROP cache; it keeps the
/// host's tag arrays small).
pub const MAX_CACHE_BYTES: u32 = 1 << 24;
/// The most sectors a line may hold: a line's sector states are 64-bit masks.
pub const MAX_SECTORS_PER_LINE: u32 = 64;

/// A cache's geometry. Defaults: ATTILA's Z and colour caches (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CacheConfig {
    /// Capacity \[bytes\]; a whole number of sets of `ways` lines, the sets a power of two.
    /// Default 16 384 (ATTILA: 4 ways x 16 lines x 256 bytes).
    pub size_bytes: u32,
    /// Lines per set (associativity), at least 1. Default 4 (ATTILA `ZCacheWays`).
    pub ways: u32,
    /// Bytes per line, a power of two and a multiple of `sector_bytes`. Default 256: an 8x8
    /// tile at 4 bytes per pixel (ATTILA: 16 stamps of 4 pixels at 4 bytes).
    pub line_bytes: u32,
    /// Bytes per sector, the unit of fills and write-backs, a power of two. Default 32
    /// (ATTILA `ZCachePortWidth`; also the sector of NVIDIA's L2, Jia et al., "Dissecting
    /// the NVIDIA Volta GPU Architecture via Microbenchmarking", 2018).
    pub sector_bytes: u32,
}

impl Default for CacheConfig {
    fn default() -> Self {
        CacheConfig {
            size_bytes: 16 * 1024,
            ways: 4,
            line_bytes: 256,
            sector_bytes: 32,
        }
    }
}

impl CacheConfig {
    /// Checks the geometry; a refused field is an [`Error::Invalid`] naming `file` and
    /// `section.field` (just `field` when `section` is empty).
    pub fn validate(&self, file: &str, section: &str) -> Result<()> {
        let bad = |field: &str, value: u32, reason: &str| {
            let field = match section {
                "" => field.to_string(),
                s => format!("{s}.{field}"),
            };
            Err(Error::invalid(file, field, value, reason))
        };
        if self.ways == 0 {
            return bad("ways", self.ways, "at least 1 way");
        }
        if !self.sector_bytes.is_power_of_two() {
            return bad("sector_bytes", self.sector_bytes, "a power of two");
        }
        if self.line_bytes < self.sector_bytes || !self.line_bytes.is_multiple_of(self.sector_bytes)
        {
            return bad("line_bytes", self.line_bytes, "a multiple of sector_bytes");
        }
        if !self.line_bytes.is_power_of_two() {
            return bad("line_bytes", self.line_bytes, "a power of two");
        }
        if self.line_bytes / self.sector_bytes > MAX_SECTORS_PER_LINE {
            return bad("line_bytes", self.line_bytes, "at most 64 sectors a line");
        }
        if self.size_bytes < self.line_bytes || self.size_bytes > MAX_CACHE_BYTES {
            return bad(
                "size_bytes",
                self.size_bytes,
                "at least one line and at most 16 MiB",
            );
        }
        let set_bytes = self.line_bytes as u64 * self.ways as u64;
        let sets = self.size_bytes as u64 / set_bytes;
        if !(self.size_bytes as u64).is_multiple_of(set_bytes) || !sets.is_power_of_two() {
            return bad(
                "size_bytes",
                self.size_bytes,
                "ways x line_bytes times a power of two (sets are indexed by address bits)",
            );
        }
        Ok(())
    }

    /// Sets (size / (ways x line)).
    pub fn sets(&self) -> u32 {
        self.size_bytes / (self.ways * self.line_bytes)
    }

    /// Sectors per line.
    pub fn sectors_per_line(&self) -> u32 {
        self.line_bytes / self.sector_bytes
    }
}

/// How a newly allocated line is filled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineFill {
    /// Only the sectors the access needs (read or partially written), one read each.
    Sectors,
    /// Every sector at once (a cleared or compressed tile, decoded whole).
    Whole,
}

/// One access to one line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    /// A byte address inside the line.
    pub addr: u64,
    /// Sectors read (bit s: sector s of the line).
    pub read: u64,
    /// Sectors written.
    pub write: u64,
    /// Of `write`, the sectors written fully (every byte): they need no fill.
    pub full: u64,
    /// How the line is filled if it is allocated.
    pub fill: LineFill,
}

/// A dirty line leaving the cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Eviction {
    /// The line's first byte.
    pub addr: u64,
    /// Its valid sectors.
    pub valid: u64,
    /// Its dirty sectors: what a write-back of the raw line moves.
    pub dirty: u64,
}

/// What one access did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outcome {
    /// Sectors touched (read or written) that were valid.
    pub hits: u32,
    /// Sectors touched that were not.
    pub misses: u32,
    /// The line's first byte.
    pub line: u64,
    /// Sectors that became valid by a fill (reads, unless the tile table says otherwise).
    pub filled: u64,
    /// The dirty victim written back to make room, if any.
    pub evicted: Option<Eviction>,
}

/// Counts over a cache's life.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct CacheStats {
    /// Sectors touched that were valid.
    pub hits: u64,
    /// Sectors touched that were not.
    pub misses: u64,
    /// Sectors filled.
    pub fills: u64,
    /// Dirty sectors written back (by evictions and flushes).
    pub write_backs: u64,
}

impl CacheStats {
    /// hits / (hits + misses), 0 before any access.
    pub fn hit_rate(&self) -> f64 {
        match self.hits + self.misses {
            0 => 0.0,
            n => self.hits as f64 / n as f64,
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Line {
    present: bool,
    tag: u64,
    valid: u64,
    dirty: u64,
    last_use: u64,
}

/// A sectored, set-associative, write-back, LRU cache (module doc).
#[derive(Clone, Debug)]
pub struct SectorCache {
    cfg: CacheConfig,
    line_shift: u32,
    set_bits: u32,
    all: u64,
    lines: Vec<Line>,
    clock: u64,
    stats: CacheStats,
}

impl SectorCache {
    /// An empty cache of geometry `cfg`, validated (`file` and `section` name it in an error).
    pub fn new(cfg: CacheConfig, file: &str, section: &str) -> Result<Self> {
        cfg.validate(file, section)?;
        let n = cfg.sectors_per_line();
        Ok(SectorCache {
            cfg,
            line_shift: cfg.line_bytes.trailing_zeros(),
            set_bits: cfg.sets().trailing_zeros(),
            all: if n == 64 { u64::MAX } else { (1 << n) - 1 },
            lines: vec![Line::default(); (cfg.sets() * cfg.ways) as usize],
            clock: 0,
            stats: CacheStats::default(),
        })
    }

    /// Its geometry.
    pub fn config(&self) -> &CacheConfig {
        &self.cfg
    }

    /// Its counts so far.
    pub fn stats(&self) -> &CacheStats {
        &self.stats
    }

    /// One access (see the module doc's policy).
    pub fn access(&mut self, req: &Request) -> Outcome {
        let (read, write) = (req.read & self.all, req.write & self.all);
        let full = req.full & write;
        let line_no = req.addr >> self.line_shift;
        let set = (line_no & ((1 << self.set_bits) - 1)) as usize;
        let tag = line_no >> self.set_bits;
        let ways = self.cfg.ways as usize;
        let slots = &mut self.lines[set * ways..(set + 1) * ways];
        self.clock += 1;
        let mut out = Outcome {
            line: line_no << self.line_shift,
            ..Outcome::default()
        };
        let way = match slots.iter().position(|l| l.present && l.tag == tag) {
            Some(w) => w,
            None => {
                let w = victim(slots);
                let old = slots[w];
                if old.present && old.dirty != 0 {
                    let addr = ((old.tag << self.set_bits) | set as u64) << self.line_shift;
                    out.evicted = Some(Eviction {
                        addr,
                        valid: old.valid,
                        dirty: old.dirty,
                    });
                    self.stats.write_backs += old.dirty.count_ones() as u64;
                }
                slots[w] = Line {
                    present: true,
                    tag,
                    ..Line::default()
                };
                if req.fill == LineFill::Whole {
                    slots[w].valid = self.all;
                    out.filled = self.all;
                }
                w
            }
        };
        let line = &mut slots[way];
        let touched = read | write;
        let was_valid = line.valid & !out.filled;
        out.hits = (touched & was_valid).count_ones();
        out.misses = (touched & !was_valid).count_ones();
        out.filled |= (read | (write & !full)) & !line.valid;
        line.valid |= out.filled | write;
        line.dirty |= write;
        line.last_use = self.clock;
        self.stats.hits += out.hits as u64;
        self.stats.misses += out.misses as u64;
        self.stats.fills += out.filled.count_ones() as u64;
        out
    }

    /// Writes back every dirty line and empties the cache (the end of a frame).
    pub fn flush(&mut self) -> Vec<Eviction> {
        let ways = self.cfg.ways as usize;
        let mut out = Vec::new();
        for (i, l) in self.lines.iter_mut().enumerate() {
            if l.present && l.dirty != 0 {
                let set = (i / ways) as u64;
                out.push(Eviction {
                    addr: ((l.tag << self.set_bits) | set) << self.line_shift,
                    valid: l.valid,
                    dirty: l.dirty,
                });
                self.stats.write_backs += l.dirty.count_ones() as u64;
            }
            *l = Line::default();
        }
        out
    }

    /// Drops every line without writing anything back (a fast clear overwrites them all).
    pub fn invalidate(&mut self) {
        self.lines.iter_mut().for_each(|l| *l = Line::default());
    }
}

/// The way to replace: an empty one, else the least recently used.
fn victim(slots: &[Line]) -> usize {
    match slots.iter().position(|l| !l.present) {
        Some(w) => w,
        None => (0..slots.len())
            .min_by_key(|&w| slots[w].last_use)
            .unwrap_or(0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cache(size: u32, ways: u32) -> SectorCache {
        let cfg = CacheConfig {
            size_bytes: size,
            ways,
            line_bytes: 256,
            sector_bytes: 32,
        };
        SectorCache::new(cfg, "test", "rop.depth_cache").unwrap()
    }

    fn read(addr: u64, sectors: u64) -> Request {
        Request {
            addr,
            read: sectors,
            write: 0,
            full: 0,
            fill: LineFill::Sectors,
        }
    }

    #[test]
    fn atttila_defaults_are_sixteen_kilobytes_in_sixteen_sets_of_four() {
        let cfg = CacheConfig::default();
        cfg.validate("test", "").unwrap();
        assert_eq!((cfg.sets(), cfg.sectors_per_line()), (16, 8));
    }

    #[test]
    fn two_ways_evict_the_least_recently_used_line() {
        // 512 bytes, 2 ways of 256: one set; lines A, B, A again, then C evicts B.
        let mut c = cache(512, 2);
        let (a, b, x) = (0u64, 256, 512);
        assert_eq!(c.access(&read(a, 1)).misses, 1);
        assert_eq!(c.access(&read(b, 1)).misses, 1);
        assert_eq!(c.access(&read(a, 1)).hits, 1);
        let w = Request {
            addr: b,
            read: 0,
            write: 1,
            full: 0,
            fill: LineFill::Sectors,
        };
        // Writing B makes it the most recent, so C evicts A (clean: no write-back).
        assert_eq!(c.access(&w).hits, 1);
        assert_eq!(c.access(&read(x, 1)).evicted, None);
        assert_eq!(c.access(&read(b, 1)).hits, 1);
        assert_eq!(c.access(&read(a, 1)).misses, 1);
        let s = c.stats();
        assert_eq!((s.hits, s.misses, s.fills, s.write_backs), (3, 4, 4, 0));
    }

    #[test]
    fn a_dirty_eviction_writes_back_only_the_dirty_sectors() {
        let mut c = cache(256, 1);
        let w = Request {
            addr: 0,
            read: 0b1111,
            write: 0b0110,
            full: 0,
            fill: LineFill::Sectors,
        };
        assert_eq!(c.access(&w).filled, 0b1111);
        let out = c.access(&read(256 + 32, 0b1));
        let e = out.evicted.unwrap();
        assert_eq!((e.addr, e.valid, e.dirty), (0, 0b1111, 0b0110));
        assert_eq!(c.stats().write_backs, 2);
    }

    #[test]
    fn a_full_sector_write_needs_no_fill_and_a_partial_one_does() {
        let mut c = cache(256, 1);
        let w = Request {
            addr: 0,
            read: 0,
            write: 0b11,
            full: 0b01,
            fill: LineFill::Sectors,
        };
        let out = c.access(&w);
        assert_eq!((out.misses, out.filled), (2, 0b10));
        // Both are valid now: reading them hits.
        assert_eq!(c.access(&read(0, 0b11)).hits, 2);
    }

    #[test]
    fn a_whole_line_fill_validates_every_sector() {
        let mut c = cache(256, 1);
        let r = Request {
            fill: LineFill::Whole,
            ..read(0, 0b1)
        };
        assert_eq!(c.access(&r).filled, 0xff);
        assert_eq!(c.access(&read(0, 0xff)).hits, 8);
    }

    #[test]
    fn flush_writes_back_dirty_lines_and_empties_the_cache() {
        let mut c = cache(1024, 2);
        let w = |addr| Request {
            addr,
            read: 0,
            write: 1,
            full: 1,
            fill: LineFill::Sectors,
        };
        c.access(&w(0));
        c.access(&w(256 * 7));
        c.access(&read(512, 1));
        let mut e: Vec<u64> = c.flush().iter().map(|e| e.addr).collect();
        e.sort();
        assert_eq!(e, [0, 256 * 7]);
        assert_eq!(c.access(&read(0, 1)).misses, 1);
    }

    #[test]
    fn bad_geometries_are_refused_naming_the_field() {
        let base = CacheConfig::default();
        let cases = [
            (CacheConfig { ways: 0, ..base }, "ways"),
            (
                CacheConfig {
                    sector_bytes: 24,
                    ..base
                },
                "sector_bytes",
            ),
            (
                CacheConfig {
                    sector_bytes: 0,
                    ..base
                },
                "sector_bytes",
            ),
            (
                CacheConfig {
                    line_bytes: 48,
                    sector_bytes: 32,
                    ..base
                },
                "line_bytes",
            ),
            (
                CacheConfig {
                    line_bytes: 16,
                    ..base
                },
                "line_bytes",
            ),
            (
                CacheConfig {
                    line_bytes: 384,
                    ..base
                },
                "line_bytes",
            ),
            (
                CacheConfig {
                    line_bytes: 4096,
                    sector_bytes: 32,
                    ..base
                },
                "line_bytes",
            ),
            (
                CacheConfig {
                    size_bytes: 128,
                    ..base
                },
                "size_bytes",
            ),
            (
                CacheConfig {
                    size_bytes: 3 * 1024,
                    ..base
                },
                "size_bytes",
            ),
            (
                CacheConfig {
                    size_bytes: 12 * 1024,
                    ..base
                },
                "size_bytes",
            ),
        ];
        for (cfg, field) in cases {
            match SectorCache::new(cfg, "arch.json", "rop.depth_cache") {
                Err(Error::Invalid { file, field: f, .. }) => {
                    assert_eq!(
                        (file.as_str(), f),
                        ("arch.json", format!("rop.depth_cache.{field}"))
                    )
                }
                other => panic!("{cfg:?} gave {other:?}"),
            }
        }
    }
}
