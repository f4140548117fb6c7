//! A surface in memory: its tiled layout ([`SurfaceLayout`]) and its tile table
//! ([`TileTable`]: per tile a state and a farthest depth, for fast clear, compression and
//! hierarchical Z), which turns a ROP cache's misses and evictions into memory traffic.
//!
//! **Layout.** A surface of W x H pixels (with n samples a pixel, W x nH sample rows, as the
//! frame buffer stores them, each sample `bytes_per_pixel`) is stored in 8x8-pixel tiles,
//! row-major by tile (tile t = tx + ty * tiles_x, at byte t x 64 x B), each tile split into
//! sectors of `sector_bytes`. Within a tile pixels are in Morton (Z) order by default: a
//! 32-byte sector of 4-byte pixels is then a 4x2 block, two 2x2 quads, so a quad lies in
//! one sector and two rows of a tile in two; ATTILA stores a ROP cache line as 16 stamps of
//! 2x2 pixels (`bGPU.ini`, `ZCacheStampsPerLine = 16`), and PICA200 frame buffers are 8x8
//! Morton tiles (Citra, `src/video_core/utils.h`, `MortonInterleave`). Row-major order
//! ([`PixelOrder::RowMajor`]) is the alternative a scan-line unit would choose: a sector is
//! then one row of the tile, and a lembo span (one row within a tile) touches one sector
//! where Morton order makes it touch two. Which is fairer to each path is the lead's
//! decision; both are here.
//!
//! **Tile table.** Per tile a [`TileState`] and a conservative farthest depth. A cleared
//! tile is filled from the clear value (no read); a compressed tile is read whole (its code,
//! [`crate::memory::compress`]) and a line of it decoded whole; an uncompressed tile is read
//! sector by sector. At a line's write-back its tile is encoded from its actual values, and
//! kept compressed when its code fits the budget (at most half the tile's sectors: a 2:1
//! ratio, the bottom of the 2:1 to 8:1 range issue 51 cites for colour; a code of 5 to 7 of
//! 8 sectors saves too little to pay for reading the tile whole). Each mechanism is switched
//! by a [`TileFeatures`] field.
//!
//! **Hierarchical Z.** The project's depth convention (`rop::framebuffer::depth_test`): depth
//! in [0, 1], cleared to 1, nearer (smaller) wins, equal depths go to the smaller primitive
//! id. A tile's farthest depth bounds every stored depth of the tile from above; a span or
//! quad whose nearest depth is greater than it fails the depth test at every pixel and is
//! rejected before any depth read. Equal is not rejected (the smaller id may win).

use super::cache::{CacheConfig, Eviction, LineFill, Request, SectorCache};
use super::compress::{encode_colour, encode_depth, TileValues};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Tile side \[pixels\].
pub const TILE_PX: u32 = 8;

/// The order of pixels within a tile.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PixelOrder {
    /// Z order: bits y2 x2 y1 x1 y0 x0 (module doc).
    #[default]
    Morton,
    /// Row by row: x + 8 y.
    RowMajor,
}

/// A sector of a surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SectorId {
    /// Its tile (tx + ty * tiles_x).
    pub tile: u32,
    /// Its sector within the tile.
    pub sector: u32,
}

/// What an access does to one tile: pixels (bit x + 8 y of the tile) and sectors (bit s).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileTouch {
    /// The tile.
    pub tile: u32,
    /// The pixels touched, bit x + 8 y (screen order within the tile).
    pub pixels: u64,
    /// The sectors holding them.
    pub sectors: u64,
    /// Of those, the sectors all of whose pixels are touched.
    pub full: u64,
}

/// A surface's tiled layout (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SurfaceLayout {
    width: u32,
    height: u32,
    bytes_per_pixel: u32,
    sector_bytes: u32,
    order: PixelOrder,
    tiles_x: u32,
    tiles_y: u32,
}

impl SurfaceLayout {
    /// The layout of a `width` x `height` surface (sample rows included) of
    /// `bytes_per_pixel` bytes a sample, in sectors of `sector_bytes`. Refused: a zero size;
    /// a sector that does not hold whole pixels or does not divide the tile; more than 64
    /// sectors a tile.
    pub fn new(
        width: u32,
        height: u32,
        bytes_per_pixel: u32,
        sector_bytes: u32,
        order: PixelOrder,
    ) -> Result<Self> {
        let bad = |field: &str, v: u32, why: &str| Err(Error::invalid("surface", field, v, why));
        if width == 0 || height == 0 {
            return bad(
                "width",
                width.min(height),
                "a surface of at least one pixel",
            );
        }
        if bytes_per_pixel == 0 || bytes_per_pixel > 16 {
            return bad("bytes_per_pixel", bytes_per_pixel, "1 to 16 bytes");
        }
        let tile = 64 * bytes_per_pixel;
        if sector_bytes == 0
            || !sector_bytes.is_multiple_of(bytes_per_pixel)
            || !tile.is_multiple_of(sector_bytes)
        {
            return bad(
                "sector_bytes",
                sector_bytes,
                "whole pixels a sector and whole sectors a tile",
            );
        }
        if tile / sector_bytes > 64 {
            return bad("sector_bytes", sector_bytes, "at most 64 sectors a tile");
        }
        Ok(SurfaceLayout {
            width,
            height,
            bytes_per_pixel,
            sector_bytes,
            order,
            tiles_x: width.div_ceil(TILE_PX),
            tiles_y: height.div_ceil(TILE_PX),
        })
    }

    /// Tiles of the surface.
    pub fn tiles(&self) -> u32 {
        self.tiles_x * self.tiles_y
    }

    /// Bytes of a tile (64 x bytes per pixel).
    pub fn tile_bytes(&self) -> u32 {
        64 * self.bytes_per_pixel
    }

    /// Bytes of a sector.
    pub fn sector_bytes(&self) -> u32 {
        self.sector_bytes
    }

    /// Sectors of a tile.
    pub fn sectors_per_tile(&self) -> u32 {
        self.tile_bytes() / self.sector_bytes
    }

    /// Its width \[pixels\].
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Its height \[pixels, sample rows\].
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The tile holding pixel (x, y).
    pub fn tile_of(&self, x: u32, y: u32) -> u32 {
        x / TILE_PX + y / TILE_PX * self.tiles_x
    }

    /// The position in memory order (0..64) of pixel (x, y) of a tile (x, y < 8).
    pub fn slot(&self, x: u32, y: u32) -> u32 {
        match self.order {
            PixelOrder::RowMajor => x + 8 * y,
            PixelOrder::Morton => (0..3).fold(0, |m, b| {
                m | ((x >> b & 1) << (2 * b)) | ((y >> b & 1) << (2 * b + 1))
            }),
        }
    }

    /// The sector holding pixel (x, y) of the surface.
    pub fn sector_of(&self, x: u32, y: u32) -> SectorId {
        let per_sector = self.sector_bytes / self.bytes_per_pixel;
        SectorId {
            tile: self.tile_of(x, y),
            sector: self.slot(x % TILE_PX, y % TILE_PX) / per_sector,
        }
    }

    /// The byte address of a tile's first sector (the surface at address 0).
    pub fn tile_address(&self, tile: u32) -> u64 {
        tile as u64 * self.tile_bytes() as u64
    }

    /// The byte address of a sector.
    pub fn address(&self, s: SectorId) -> u64 {
        self.tile_address(s.tile) + s.sector as u64 * self.sector_bytes as u64
    }

    /// The sectors holding `pixels` (bit x + 8 y) of tile `tile`, and those fully covered.
    pub fn touch(&self, tile: u32, pixels: u64) -> TileTouch {
        let per_sector = self.sector_bytes / self.bytes_per_pixel;
        let mut slots = 0u64;
        for i in (0..64).filter(|i| pixels >> i & 1 == 1) {
            slots |= 1 << self.slot(i % 8, i / 8);
        }
        let group = if per_sector == 64 {
            u64::MAX
        } else {
            (1u64 << per_sector) - 1
        };
        let (mut sectors, mut full) = (0, 0);
        for s in 0..self.sectors_per_tile() {
            let bits = slots >> (s * per_sector) & group;
            sectors |= ((bits != 0) as u64) << s;
            full |= ((bits == group) as u64) << s;
        }
        TileTouch {
            tile,
            pixels,
            sectors,
            full,
        }
    }

    /// The tiles a rectangle x0..x1, y0..y1 (clipped to the surface) touches, in tile order.
    pub fn rect(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> impl Iterator<Item = TileTouch> + '_ {
        let (x1, y1) = (x1.min(self.width), y1.min(self.height));
        let (tx0, ty0) = (x0 / TILE_PX, y0 / TILE_PX);
        let (tx1, ty1) = (x1.div_ceil(TILE_PX), y1.div_ceil(TILE_PX));
        let empty = x0 >= x1 || y0 >= y1;
        let tys = if empty { 0..0 } else { ty0..ty1 };
        tys.flat_map(move |ty| (tx0..tx1).map(move |tx| (tx, ty)))
            .map(move |(tx, ty)| {
                let (bx, by) = (tx * TILE_PX, ty * TILE_PX);
                let mut pixels = 0u64;
                for y in y0.max(by)..y1.min(by + TILE_PX) {
                    for x in x0.max(bx)..x1.min(bx + TILE_PX) {
                        pixels |= 1 << ((x - bx) + 8 * (y - by));
                    }
                }
                self.touch(tx + ty * self.tiles_x, pixels)
            })
    }

    /// The tiles a horizontal span of row `y`, columns x0..x1, touches.
    pub fn span(&self, y: u32, x0: u32, x1: u32) -> impl Iterator<Item = TileTouch> + '_ {
        self.rect(x0, y, x1, y + 1)
    }

    /// The tiles the 2x2 quad with top-left pixel (x, y) touches (one when x and y are even).
    pub fn quad(&self, x: u32, y: u32) -> impl Iterator<Item = TileTouch> + '_ {
        self.rect(x, y, x + 2, y + 2)
    }
}

/// Which surface a table describes: its compressor and whether it has hierarchical Z.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// 24-bit depth ([`crate::memory::compress::depth24`]).
    Depth,
    /// RGBA8 colour ([`crate::memory::compress::rgba8`]).
    Colour,
}

/// The tile table's switches, each on by default; the sensitivity tooling turns them off
/// one at a time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TileFeatures {
    /// A clear marks tiles cleared instead of writing them.
    pub fast_clear: bool,
    /// Depth tiles are plane-encoded at write-back.
    pub depth_compression: bool,
    /// Colour tiles are delta-encoded at write-back.
    pub colour_compression: bool,
    /// Spans and quads wholly behind a tile's farthest depth are rejected.
    pub hierarchical_z: bool,
}

impl Default for TileFeatures {
    fn default() -> Self {
        TileFeatures {
            fast_clear: true,
            depth_compression: true,
            colour_compression: true,
            hierarchical_z: true,
        }
    }
}

/// How a tile is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TileState {
    /// Holds the clear value; nothing in memory.
    Cleared,
    /// Its code, in this many sectors at the start of the tile's place.
    Compressed {
        /// Sectors the code occupies.
        sectors: u32,
    },
    /// Raw, sector by sector.
    Uncompressed,
}

/// A transfer between a cache and memory: sectors (bit s) of the line at `addr`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transfer {
    /// The line's (the tile's) first byte.
    pub addr: u64,
    /// The sectors moved.
    pub sectors: u64,
}

/// What one access to a surface costs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Traffic {
    /// Sectors touched that were in the cache.
    pub hits: u32,
    /// Sectors touched that were not.
    pub misses: u32,
    /// The read that fills the line, if any.
    pub fill: Option<Transfer>,
    /// The victim's write-back, if any.
    pub write_back: Option<Transfer>,
}

/// A surface's counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TableStats {
    /// Sectors read from memory by fills.
    pub sectors_read: u64,
    /// Sectors written to memory: write-backs and clears that are not fast.
    pub sectors_written: u64,
    /// Sectors write-backs wrote.
    pub write_back_sectors: u64,
    /// Sectors the same write-backs would have written raw: the dirty sectors of a tile
    /// stored raw, every sector of a tile stored cleared or compressed. A tile stored raw
    /// with few dirty sectors and compressed at write-back may write more than raw.
    pub write_back_sectors_raw: u64,
    /// Sectors a fill found cleared and did not read.
    pub sectors_cleared_not_read: u64,
    /// Write-backs stored compressed.
    pub compressed_write_backs: u64,
    /// Write-backs stored raw.
    pub raw_write_backs: u64,
    /// Spans or quads tested against hierarchical Z.
    pub hz_tests: u64,
    /// Of those, rejected.
    pub hz_rejects: u64,
}

impl TableStats {
    /// The write-backs' compression: raw sectors / sectors written (1 with none).
    pub fn compression_ratio(&self) -> f64 {
        match self.write_back_sectors {
            0 => 1.0,
            n => self.write_back_sectors_raw as f64 / n as f64,
        }
    }
}

/// A surface's tile table (module doc).
#[derive(Clone, Debug)]
pub struct TileTable {
    layout: SurfaceLayout,
    surface: Surface,
    features: TileFeatures,
    state: Vec<TileState>,
    farthest: Vec<f32>,
    stats: TableStats,
}

impl TileTable {
    /// The table of a surface laid out as `layout`, cached by a cache of geometry `cache`,
    /// every tile cleared to depth 1 (a colour surface ignores depth). Refused: a cache
    /// whose line is not one tile or whose sector is not the layout's (field `line_bytes`
    /// or `sector_bytes` of `section`).
    pub fn new(
        layout: SurfaceLayout,
        surface: Surface,
        features: TileFeatures,
        cache: &CacheConfig,
        section: &str,
    ) -> Result<Self> {
        let field = |f: &str| format!("{section}.{f}");
        if cache.line_bytes != layout.tile_bytes() {
            let why = format!("one tile of the surface, {} bytes", layout.tile_bytes());
            return Err(Error::invalid(
                "surface",
                field("line_bytes"),
                cache.line_bytes,
                why,
            ));
        }
        if cache.sector_bytes != layout.sector_bytes() {
            let why = format!("the surface's sector, {} bytes", layout.sector_bytes());
            return Err(Error::invalid(
                "surface",
                field("sector_bytes"),
                cache.sector_bytes,
                why,
            ));
        }
        let n = layout.tiles() as usize;
        let mut table = TileTable {
            layout,
            surface,
            features,
            state: vec![TileState::Uncompressed; n],
            farthest: vec![1.0; n],
            stats: TableStats::default(),
        };
        table.clear(None, 1.0);
        table.stats = TableStats::default();
        Ok(table)
    }

    /// Its layout.
    pub fn layout(&self) -> &SurfaceLayout {
        &self.layout
    }

    /// Which surface it describes.
    pub fn surface(&self) -> Surface {
        self.surface
    }

    /// Its counts so far.
    pub fn stats(&self) -> &TableStats {
        &self.stats
    }

    /// How tile `tile` is stored.
    pub fn state(&self, tile: u32) -> TileState {
        self.state[tile as usize]
    }

    /// Tile `tile`'s farthest depth (an upper bound on its stored depths).
    pub fn farthest(&self, tile: u32) -> f32 {
        self.farthest[tile as usize]
    }

    /// Sectors the surface occupies as stored (cleared tiles none), against
    /// `tiles x sectors_per_tile` raw.
    pub fn stored_sectors(&self) -> u64 {
        let raw = self.layout.sectors_per_tile() as u64;
        self.state
            .iter()
            .map(|s| match s {
                TileState::Cleared => 0,
                TileState::Compressed { sectors } => *sectors as u64,
                TileState::Uncompressed => raw,
            })
            .sum()
    }

    /// Clears the surface to depth `depth` (a colour surface: its clear colour; `depth` is
    /// then unused). The cache's lines are dropped (the clear overwrites them). Returns the
    /// sectors written: none with fast clear, every sector without.
    pub fn clear(&mut self, cache: Option<&mut SectorCache>, depth: f32) -> u64 {
        if let Some(c) = cache {
            c.invalidate();
        }
        self.farthest.iter_mut().for_each(|f| *f = depth);
        let (state, written) = match self.features.fast_clear {
            true => (TileState::Cleared, 0),
            false => (
                TileState::Uncompressed,
                self.layout.tiles() as u64 * self.layout.sectors_per_tile() as u64,
            ),
        };
        self.state.iter_mut().for_each(|s| *s = state);
        self.stats.sectors_written += written;
        written
    }

    /// Whether hierarchical Z rejects a span or quad of tile `tile` whose nearest depth is
    /// `nearest`: on, a depth surface, and `nearest` beyond the tile's farthest depth (NaN
    /// is never rejected).
    pub fn hz_rejects(&mut self, tile: u32, nearest: f32) -> bool {
        if !self.features.hierarchical_z || self.surface != Surface::Depth {
            return false;
        }
        self.stats.hz_tests += 1;
        let reject = nearest > self.farthest[tile as usize];
        self.stats.hz_rejects += reject as u64;
        reject
    }

    /// A depth `z` was written into tile `tile`: the farthest depth stays an upper bound
    /// (it only grows, which a depth test that passed never needs).
    pub fn note_depth_write(&mut self, tile: u32, z: f32) {
        let f = &mut self.farthest[tile as usize];
        *f = f.max(z);
    }

    /// Tightens tile `tile`'s farthest depth to `farthest`, the exact maximum of its stored
    /// depths (the ROP computes it when it has the whole tile, as at a write-back).
    pub fn set_farthest(&mut self, tile: u32, farthest: f32) {
        self.farthest[tile as usize] = farthest;
    }

    /// One access of `touch`'s pixels through `cache`: the sectors read (`read`) and
    /// written (`write`, whose fully covered sectors need no fill). `values` gives a tile's
    /// current values when a victim is encoded.
    pub fn access(
        &mut self,
        cache: &mut SectorCache,
        touch: &TileTouch,
        read: bool,
        write: bool,
        values: &mut dyn FnMut(u32) -> TileValues,
    ) -> Traffic {
        let state = self.state[touch.tile as usize];
        let req = Request {
            addr: self.layout.tile_address(touch.tile),
            read: if read { touch.sectors } else { 0 },
            write: if write { touch.sectors } else { 0 },
            full: if write { touch.full } else { 0 },
            fill: match state {
                TileState::Uncompressed => LineFill::Sectors,
                _ => LineFill::Whole,
            },
        };
        let out = cache.access(&req);
        let fill = (out.filled != 0).then(|| self.fill(out.line, out.filled, state));
        Traffic {
            hits: out.hits,
            misses: out.misses,
            fill: fill.flatten(),
            write_back: out.evicted.and_then(|e| self.write_back(&e, values)),
        }
    }

    /// Writes back every dirty line of `cache` (the end of a frame).
    pub fn flush(
        &mut self,
        cache: &mut SectorCache,
        values: &mut dyn FnMut(u32) -> TileValues,
    ) -> Vec<Transfer> {
        let evicted = cache.flush();
        evicted
            .iter()
            .filter_map(|e| self.write_back(e, values))
            .collect()
    }

    /// The read that fills sectors `filled` of the line at `addr`, of a tile in `state`.
    fn fill(&mut self, addr: u64, filled: u64, state: TileState) -> Option<Transfer> {
        let sectors = match state {
            TileState::Cleared => {
                self.stats.sectors_cleared_not_read += filled.count_ones() as u64;
                return None;
            }
            TileState::Compressed { sectors } => low_bits(sectors),
            TileState::Uncompressed => filled,
        };
        self.stats.sectors_read += sectors.count_ones() as u64;
        Some(Transfer { addr, sectors })
    }

    /// The write-back of a dirty line: its tile encoded when the line holds it whole and
    /// compression is on and fits, else raw (every sector when memory held no raw tile).
    fn write_back(
        &mut self,
        e: &Eviction,
        values: &mut dyn FnMut(u32) -> TileValues,
    ) -> Option<Transfer> {
        let tile = (e.addr / self.layout.tile_bytes() as u64) as u32;
        let n = self.layout.sectors_per_tile();
        let all = low_bits(n);
        let compress = match self.surface {
            Surface::Depth => self.features.depth_compression,
            Surface::Colour => self.features.colour_compression,
        };
        let code = (compress && e.valid == all).then(|| {
            let v = values(tile);
            let code = match self.surface {
                Surface::Depth => encode_depth(&v),
                Surface::Colour => encode_colour(&v),
            };
            code.sectors(self.layout.sector_bytes())
        });
        let old = self.state[tile as usize];
        // What a raw write-back writes: the dirty sectors over a raw tile, else all.
        let raw = if old == TileState::Uncompressed {
            e.dirty
        } else {
            all
        };
        let (state, sectors) = match code {
            Some(c) if c <= n / 2 => (TileState::Compressed { sectors: c }, low_bits(c)),
            _ => (TileState::Uncompressed, raw),
        };
        self.state[tile as usize] = state;
        let written = sectors.count_ones() as u64;
        self.stats.sectors_written += written;
        self.stats.write_back_sectors += written;
        self.stats.write_back_sectors_raw += raw.count_ones() as u64;
        match state {
            TileState::Compressed { .. } => self.stats.compressed_write_backs += 1,
            _ => self.stats.raw_write_backs += 1,
        }
        Some(Transfer {
            addr: e.addr,
            sectors,
        })
    }
}

/// The mask of the first `n` sectors.
fn low_bits(n: u32) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1 << n) - 1
    }
}

#[cfg(test)]
mod tests;
