//! A ROP's side of the DRAM memory model (`memory.model = "dram"`, DESIGN.md §3, "The
//! memory system"): its colour and depth caches over the surfaces' tile tables. Each span
//! or piece the ROP tests is charged by the sectors it touches; hits cost the caches' port
//! rate, misses become fills and evictions become write-backs, which the ROP sends to the
//! memory controller ([`MemAccess`](crate::pipeline::items::MemAccess)). The caches hold tags and sector states only: the
//! pixels stay in the frame buffer, so nothing here changes a pixel.
//!
//! Surfaces: colour (RGBA8) at address 0, depth (D24S8) after it, and with multisampling
//! the resolved colour after that, each `width` x `sample rows` pixels in 8x8 tiles. A ROP
//! owns whole memory tiles (`rop.tile_px` is a multiple of 8, checked when the run is
//! built), so no two ROPs' caches hold the same sector.

use crate::config::{MemoryConfig, BYTES_PER_PIXEL};
use crate::error::Result;
use crate::memory::cache::{CacheStats, SectorCache};
use crate::memory::compress::{depth24, TileValues};
use crate::memory::tiles::{
    Surface, SurfaceLayout, TableStats, TileTable, TileTouch, Transfer, TILE_PX,
};
use crate::pipeline::items::LineTransfer;
use crate::pipeline::tiles::RopPixels;
use serde::Serialize;

/// One surface: its tile table, this ROP's cache of it, and where it starts in memory.
struct Cached {
    table: TileTable,
    cache: SectorCache,
    base: u64,
}

/// What one ROP's caches and tables counted in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RopMemoryStats {
    /// The colour cache.
    pub colour_cache: CacheStats,
    /// The depth cache.
    pub depth_cache: CacheStats,
    /// The colour surface's tile table (this ROP's tiles).
    pub colour: TableStats,
    /// The depth surface's tile table (this ROP's tiles, and hierarchical Z).
    pub depth: TableStats,
    /// Tiles this ROP found cleared when the frame ended (fast clear's saving in the
    /// resolve and in the next frame's reads).
    pub cleared_tiles: u64,
}

impl RopMemoryStats {
    /// The sum of two ROPs' counts.
    pub fn add(&mut self, o: &RopMemoryStats) {
        for (a, b) in [
            (&mut self.colour_cache, &o.colour_cache),
            (&mut self.depth_cache, &o.depth_cache),
        ] {
            a.hits += b.hits;
            a.misses += b.misses;
            a.fills += b.fills;
            a.write_backs += b.write_backs;
        }
        for (a, b) in [(&mut self.colour, &o.colour), (&mut self.depth, &o.depth)] {
            a.sectors_read += b.sectors_read;
            a.sectors_written += b.sectors_written;
            a.write_back_sectors += b.write_back_sectors;
            a.write_back_sectors_raw += b.write_back_sectors_raw;
            a.sectors_cleared_not_read += b.sectors_cleared_not_read;
            a.compressed_write_backs += b.compressed_write_backs;
            a.raw_write_backs += b.raw_write_backs;
            a.hz_tests += b.hz_tests;
            a.hz_rejects += b.hz_rejects;
        }
        self.cleared_tiles += o.cleared_tiles;
    }
}

/// A ROP's caches and tile tables.
pub struct RopMemory {
    colour: Cached,
    depth: Cached,
    per_cycle: u64,
    /// Where the resolved colour starts, with multisampling.
    resolve_base: Option<u64>,
    samples: u32,
    /// The tiles of the span being charged (kept to reuse its allocation).
    touched: Vec<TileTouch>,
}

/// The layout of `cfg`'s surfaces of `width` x `rows` sample rows.
fn layout(cfg: &MemoryConfig, width: u32, rows: u32) -> Result<SurfaceLayout> {
    SurfaceLayout::new(
        width,
        rows,
        BYTES_PER_PIXEL,
        cfg.sector_bytes,
        cfg.pixel_order,
    )
}

/// The bytes one surface of `layout` takes in memory.
fn surface_bytes(layout: &SurfaceLayout) -> u64 {
    layout.tiles() as u64 * layout.tile_bytes() as u64
}

impl RopMemory {
    /// The caches of `cfg` over surfaces of `width` x `rows` sample rows (`samples` a
    /// pixel), every tile cleared.
    pub fn new(cfg: &MemoryConfig, width: u32, rows: u32, samples: u32) -> Result<Self> {
        let layout = layout(cfg, width, rows)?;
        let size = surface_bytes(&layout);
        let surface = |kind, cache: crate::memory::cache::CacheConfig, base| -> Result<Cached> {
            Ok(Cached {
                table: TileTable::new(layout, kind, cfg.features(), &cache, "memory")?,
                cache: SectorCache::new(cache, "architecture", "memory")?,
                base,
            })
        };
        Ok(RopMemory {
            colour: surface(Surface::Colour, cfg.colour_cache(), 0)?,
            depth: surface(Surface::Depth, cfg.depth_cache(), size)?,
            per_cycle: u64::from(cfg.cache_sectors_per_cycle),
            resolve_base: (samples > 1).then_some(2 * size),
            samples,
            touched: Vec::new(),
        })
    }

    /// Where the primitives the geometry fetch reads start in memory, after the surfaces of
    /// `new(cfg, width, rows, _)` (colour, depth, and the resolved colour's room).
    pub fn geometry_base(cfg: &MemoryConfig, width: u32, rows: u32) -> Result<u64> {
        Ok(3 * surface_bytes(&layout(cfg, width, rows)?))
    }

    /// Sectors each cache moves a cycle.
    pub fn per_cycle(&self) -> u64 {
        self.per_cycle
    }

    /// The memory tiles the pixels `rows` (row, x0, x1) of one span or piece touch, in
    /// column order (a ROP tile of 8m pixels holds m memory tiles a row), into `tiles`.
    fn touches(&self, rows: &[(u32, u32, u32)], tiles: &mut Vec<TileTouch>) {
        tiles.clear();
        let layout = self.depth.table.layout();
        for &(y, x0, x1) in rows.iter().filter(|r| r.1 < r.2) {
            let mut x = x0;
            while x < x1 {
                let bx = x / TILE_PX * TILE_PX;
                let end = x1.min(bx + TILE_PX);
                let bits = ((1u64 << (end - x)) - 1) << (x - bx) << (8 * (y % TILE_PX));
                let tile = layout.tile_of(x, y);
                match tiles.iter_mut().find(|t| t.tile == tile) {
                    Some(t) => t.pixels |= bits,
                    None => tiles.push(TileTouch {
                        tile,
                        pixels: bits,
                        sectors: 0,
                        full: 0,
                    }),
                }
                x = end;
            }
        }
        for t in tiles.iter_mut() {
            *t = layout.touch(t.tile, t.pixels);
        }
    }

    /// One span or piece: rows `rows` tested, `nearest` its nearest fragment depth,
    /// `passed` whether any fragment passed (then depth and colour are written in every
    /// tile it touches that hierarchical Z keeps). Its transfers are added to `out`;
    /// returns the cache ports' cycles and whether hierarchical Z rejected it whole (no
    /// depth read, no write).
    pub fn access(
        &mut self,
        rows: &[(u32, u32, u32)],
        nearest: f32,
        passed: bool,
        pixels: &RopPixels,
        out: &mut Vec<LineTransfer>,
    ) -> (u64, bool) {
        let mut tiles = std::mem::take(&mut self.touched);
        self.touches(rows, &mut tiles);
        let (mut depth, mut colour, mut kept) = (0, 0, 0);
        for touch in &tiles {
            if self.depth.table.hz_rejects(touch.tile, nearest) {
                continue;
            }
            kept += 1;
            depth += access(&mut self.depth, touch, true, passed, pixels, out);
            if passed {
                colour += access(&mut self.colour, touch, false, true, pixels, out);
            }
        }
        let rejected = kept == 0 && !tiles.is_empty();
        debug_assert!(
            !(rejected && passed),
            "hierarchical Z rejected a span that passed"
        );
        self.touched = tiles;
        (depth.max(colour).div_ceil(self.per_cycle), rejected)
    }

    /// The end of the frame: every dirty line written back, then with multisampling this
    /// ROP's share of the resolve (its colour tiles read as stored, the resolved pixels
    /// written whole). Returns the transfers, in order.
    pub fn finish(&mut self, pixels: &RopPixels) -> Vec<LineTransfer> {
        let mut out = Vec::new();
        for s in [&mut self.colour, &mut self.depth] {
            let (base, surface, layout) = (s.base, s.table.surface(), *s.table.layout());
            let mut values = |tile| tile_values(&layout, surface, tile, pixels);
            for t in s.table.flush(&mut s.cache, &mut values) {
                out.push(LineTransfer::at(base, t, true));
            }
        }
        if let Some(resolve) = self.resolve_base {
            let layout = *self.colour.table.layout();
            let all = low_bits(layout.sectors_per_tile());
            for tile in self.owned_tiles(pixels) {
                let read = match self.colour.table.state(tile) {
                    crate::memory::tiles::TileState::Cleared => 0,
                    crate::memory::tiles::TileState::Compressed { sectors } => low_bits(sectors),
                    crate::memory::tiles::TileState::Uncompressed => all,
                };
                let addr = layout.tile_address(tile);
                if read != 0 {
                    out.push(LineTransfer::at(
                        0,
                        Transfer {
                            addr,
                            sectors: read,
                        },
                        false,
                    ));
                }
                // A tile of n sample rows resolves to 1/n of a tile, written whole.
                let sectors = low_bits(layout.sectors_per_tile() / self.samples);
                let addr = addr / u64::from(self.samples);
                out.push(LineTransfer::at(resolve, Transfer { addr, sectors }, true));
            }
        }
        out
    }

    /// The tiles of the surface this ROP owns.
    fn owned_tiles<'p>(&self, pixels: &'p RopPixels) -> impl Iterator<Item = u32> + 'p {
        let layout = *self.colour.table.layout();
        (0..layout.tiles()).filter(move |&t| {
            let (x, y, _, _) = bounds(&layout, t);
            pixels.owns(x, y)
        })
    }

    /// Its counts.
    pub fn stats(&self, pixels: &RopPixels) -> RopMemoryStats {
        let cleared = self
            .owned_tiles(pixels)
            .filter(|&t| self.colour.table.state(t) == crate::memory::tiles::TileState::Cleared)
            .count() as u64;
        RopMemoryStats {
            colour_cache: *self.colour.cache.stats(),
            depth_cache: *self.depth.cache.stats(),
            colour: *self.colour.table.stats(),
            depth: *self.depth.table.stats(),
            cleared_tiles: cleared,
        }
    }
}

/// One access of `touch` to surface `s`: its fill and write-back into `out`; the sectors
/// the cache's port moves.
fn access(
    s: &mut Cached,
    touch: &TileTouch,
    read: bool,
    write: bool,
    pixels: &RopPixels,
    out: &mut Vec<LineTransfer>,
) -> u64 {
    let surface = s.table.surface();
    let layout = *s.table.layout();
    let mut values = |tile| tile_values(&layout, surface, tile, pixels);
    let t = s
        .table
        .access(&mut s.cache, touch, read, write, &mut values);
    if let Some(f) = t.fill {
        out.push(LineTransfer::at(s.base, f, false));
    }
    if let Some(w) = t.write_back {
        // The victim's farthest depth, exact as it leaves the cache (a passing depth
        // test only ever lowers a depth, so it stays an upper bound until the next clear).
        if surface == Surface::Depth {
            let tile = (w.addr / u64::from(layout.tile_bytes())) as u32;
            s.table.set_farthest(tile, farthest(&layout, tile, pixels));
        }
        out.push(LineTransfer::at(s.base, w, true));
    }
    u64::from(t.hits + t.misses)
}

/// The farthest depth stored in tile `tile` (1, the clear depth, past the surface's edge).
fn farthest(layout: &SurfaceLayout, tile: u32, pixels: &RopPixels) -> f32 {
    let (bx, by, x1, y1) = bounds(layout, tile);
    let mut far: f32 = if x1 - bx < TILE_PX || y1 - by < TILE_PX {
        1.0
    } else {
        0.0
    };
    for y in by..y1 {
        let row = pixels.row(bx, x1, y);
        for x in bx..x1 {
            // SAFETY: x is in bx..x1, the run `row` admitted.
            far = far.max(unsafe { pixels.depth(row + x as usize) });
        }
    }
    far
}

/// Tile `tile`'s first column and row and the column and row past it, within the surface.
fn bounds(layout: &SurfaceLayout, tile: u32) -> (u32, u32, u32, u32) {
    let tiles_x = layout.width().div_ceil(TILE_PX);
    let (bx, by) = (tile % tiles_x * TILE_PX, tile / tiles_x * TILE_PX);
    let x1 = (bx + TILE_PX).min(layout.width());
    (bx, by, x1, (by + TILE_PX).min(layout.height()))
}

/// The values of tile `tile` of a surface as stored (depth as D24, colour as RGBA8), in
/// the order the codes read them (x + 8 y); pixels past the surface's edge hold the clear
/// value.
fn tile_values(
    layout: &SurfaceLayout,
    surface: Surface,
    tile: u32,
    pixels: &RopPixels,
) -> TileValues {
    let (bx, by, x1, y1) = bounds(layout, tile);
    let mut v = [match surface {
        Surface::Depth => depth24(1.0),
        Surface::Colour => 0,
    }; 64];
    for y in by..y1 {
        let row = pixels.row(bx, x1, y);
        for x in bx..x1 {
            let idx = row + x as usize;
            // SAFETY: x is in bx..x1, the run `row` admitted.
            let (depth, [r, g, b]) = unsafe { (pixels.depth(idx), pixels.color(idx)) };
            v[((x - bx) + 8 * (y - by)) as usize] = match surface {
                Surface::Depth => depth24(depth),
                Surface::Colour => u32::from_le_bytes([r, g, b, 255]),
            };
        }
    }
    v
}

/// The mask of the first `n` sectors.
fn low_bits(n: u32) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1 << n) - 1
    }
}

/// What the DRAM controller measured of its clients, beside the DRAM's own totals.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClientStats {
    /// Atoms the geometry fetch read.
    pub geometry_atoms: u64,
    /// Atoms the ROPs read (cache fills, the resolve's reads).
    pub rop_reads: u64,
    /// Mean latency of the ROPs' reads, from the item's arrival at the controller to the
    /// atom's last data \[DRAM cycles\].
    pub rop_read_latency_mean: f64,
}

/// What the DRAM memory model measured over a frame: `memory_system` in report.json.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MemoryReport {
    /// The DRAM preset (`GDDR6 16 Gb/s x16`).
    pub dram: String,
    /// Its channels.
    pub channels: u32,
    /// Bytes one DRAM atom moves \[bytes\].
    pub atom_bytes: u32,
    /// Atoms read (cache fills, the resolve's reads, the geometry fetch's reads).
    pub atoms_read: u64,
    /// Of them, the geometry fetch's.
    pub geometry_atoms_read: u64,
    /// Atoms written (write-backs, the resolve's writes).
    pub atoms_written: u64,
    /// Row activations.
    pub activations: u64,
    /// Requests that found their row open, over all requests.
    pub row_hit_rate: f64,
    /// Mean read latency from arrival \[DRAM cycles\].
    pub read_latency_mean: f64,
    /// Mean latency of the ROPs' reads alone, from their item's arrival \[DRAM cycles\]:
    /// what the geometry fetch's reads queued among them add to.
    pub rop_read_latency_mean: f64,
    /// The cycle the last request completed \[DRAM cycles\].
    pub dram_cycles: u64,
    /// The DRAM's energy by the preset's current figures \[pJ\]: reads, writes,
    /// activations, background.
    pub energy_pj: [f64; 4],
    /// The colour caches' hit rate (sectors), over every ROP.
    pub colour_cache_hit_rate: f64,
    /// The depth caches' hit rate (sectors), over every ROP.
    pub depth_cache_hit_rate: f64,
    /// The colour write-backs' compression: raw sectors over sectors written.
    pub colour_compression_ratio: f64,
    /// The depth write-backs' compression.
    pub depth_compression_ratio: f64,
    /// Every ROP's counts, summed.
    pub rops: RopMemoryStats,
}

impl MemoryReport {
    /// The report of a frame whose ROPs counted `rops` (summed) over `dram`, its clients'
    /// share `clients`.
    pub fn new(
        cfg: &crate::memory::dram::DramConfig,
        rops: RopMemoryStats,
        dram: &crate::memory::dram::DramStats,
        clients: &ClientStats,
    ) -> Self {
        let e = &dram.energy;
        MemoryReport {
            dram: cfg.name.clone(),
            channels: cfg.channels,
            atom_bytes: cfg.atom_bytes(),
            atoms_read: dram.atoms_read,
            geometry_atoms_read: clients.geometry_atoms,
            atoms_written: dram.atoms_written,
            activations: dram.activations,
            row_hit_rate: dram.row_hit_rate(),
            read_latency_mean: dram.read_latency_mean,
            rop_read_latency_mean: clients.rop_read_latency_mean,
            dram_cycles: dram.last_done,
            energy_pj: [e.read_pj, e.write_pj, e.activation_pj, e.background_pj],
            colour_cache_hit_rate: rops.colour_cache.hit_rate(),
            depth_cache_hit_rate: rops.depth_cache.hit_rate(),
            colour_compression_ratio: rops.colour.compression_ratio(),
            depth_compression_ratio: rops.depth.compression_ratio(),
            rops,
        }
    }
}
