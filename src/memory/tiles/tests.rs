//! The tiled layout's sectors, the tile table's fast clear and compression, hierarchical Z's
//! conservativeness, and a depth cache under overdraw.

use super::*;
use crate::memory::compress::{depth24, rgba8, TILE_PIXELS};
use crate::testkit::SplitMix64;

fn layout(w: u32, h: u32, order: PixelOrder) -> SurfaceLayout {
    SurfaceLayout::new(w, h, 4, 32, order).unwrap()
}

fn one(it: impl Iterator<Item = TileTouch>) -> TileTouch {
    let v: Vec<_> = it.collect();
    assert_eq!(v.len(), 1, "{v:?}");
    v[0]
}

#[test]
fn a_span_and_a_quad_touch_the_sectors_computed_by_hand() {
    let m = layout(16, 16, PixelOrder::Morton);
    // Row 0 of tile 0 in Z order: slots 0 1 4 5 16 17 20 21, so half of sectors 0 and 2.
    let t = one(m.span(0, 0, 8));
    assert_eq!((t.tile, t.sectors, t.full), (0, 0b101, 0));
    // Two rows (a triangle piece): sectors 0 and 2 whole.
    let t = one(m.rect(0, 0, 8, 2));
    assert_eq!((t.sectors, t.full), (0b101, 0b101));
    // The quad at (2, 2): slots 12 to 15, half of sector 1.
    let t = one(m.quad(2, 2));
    assert_eq!((t.sectors, t.full), (0b10, 0));
    let r = layout(16, 16, PixelOrder::RowMajor);
    let t = one(r.span(0, 0, 8));
    assert_eq!((t.sectors, t.full), (0b1, 0b1));
    let t = one(r.quad(2, 2));
    assert_eq!((t.sectors, t.full), (0b1100, 0));
    // A span over two tiles of row 9, clipped at the surface's edge.
    let v: Vec<_> = r
        .span(9, 5, 40)
        .map(|t| (t.tile, t.sectors, t.full))
        .collect();
    assert_eq!(v, [(2, 0b10, 0), (3, 0b10, 0b10)]);
    // Addresses: pixel (9, 1) is in tile 1 at Z slot 3, sector 0; tile 1 starts at 256.
    let s = m.sector_of(9, 1);
    assert_eq!((s, m.address(s)), (SectorId { tile: 1, sector: 0 }, 256));
    assert_eq!(m.address(m.sector_of(15, 7)), 256 + 7 * 32);
}

#[test]
fn morton_slots_are_a_permutation_of_the_tile() {
    let m = layout(8, 8, PixelOrder::Morton);
    let mut seen = [false; 64];
    for y in 0..8 {
        for x in 0..8 {
            seen[m.slot(x, y) as usize] = true;
        }
    }
    assert!(seen.iter().all(|&s| s));
}

fn table(w: u32, h: u32, surface: Surface, features: TileFeatures) -> (TileTable, SectorCache) {
    let cfg = CacheConfig::default();
    let l = layout(w, h, PixelOrder::Morton);
    let t = TileTable::new(l, surface, features, &cfg, "rop.depth_cache").unwrap();
    (t, SectorCache::new(cfg, "test", "rop.depth_cache").unwrap())
}

#[test]
fn a_cleared_tile_is_filled_without_a_read_and_only_with_fast_clear() {
    let mut none = |_| [0u32; TILE_PIXELS];
    let (mut t, mut c) = table(64, 64, Surface::Depth, TileFeatures::default());
    let touch = one(t.layout().span(3, 0, 8));
    let out = t.access(&mut c, &touch, true, true, &mut none);
    assert_eq!((out.misses, out.fill, out.write_back), (2, None, None));
    assert_eq!(t.stats().sectors_cleared_not_read, 8);
    let off = TileFeatures {
        fast_clear: false,
        ..TileFeatures::default()
    };
    let (mut t, mut c) = table(64, 64, Surface::Depth, off);
    assert_eq!(t.clear(Some(&mut c), 1.0), 64 * 8);
    let out = t.access(&mut c, &touch, true, true, &mut none);
    // Row 3 in Z order: slots 10 11 14 15 26 27 30 31, sectors 1 and 3.
    let fill = Transfer {
        addr: 0,
        sectors: 0b1010,
    };
    assert_eq!(out.fill, Some(fill));
}

#[test]
fn a_constant_tile_is_written_back_in_one_sector_and_read_back_whole() {
    let mut vals = |_| [depth24(0.5); TILE_PIXELS];
    let (mut t, mut c) = table(8, 8, Surface::Depth, TileFeatures::default());
    let touch = one(t.layout().rect(0, 0, 8, 8));
    t.access(&mut c, &touch, true, true, &mut vals);
    let wb = t.flush(&mut c, &mut vals);
    assert_eq!(
        wb,
        [Transfer {
            addr: 0,
            sectors: 1
        }]
    );
    assert_eq!(t.state(0), TileState::Compressed { sectors: 1 });
    assert_eq!(t.stored_sectors(), 1);
    // Read again: the code, one sector, fills the whole line.
    let quad = one(t.layout().quad(4, 4));
    let out = t.access(&mut c, &quad, true, false, &mut vals);
    assert_eq!(
        out.fill,
        Some(Transfer {
            addr: 0,
            sectors: 1
        })
    );
    assert_eq!(t.access(&mut c, &touch, true, false, &mut vals).hits, 8);
    assert_eq!(t.stats().compression_ratio(), 8.0);
}

#[test]
fn noise_is_written_back_raw_and_compression_off_writes_raw() {
    let mut rng = SplitMix64::new(5);
    let noise: TileValues = std::array::from_fn(|_| rng.next_u64() as u32);
    let mut vals = |_| noise;
    let (mut t, mut c) = table(8, 8, Surface::Colour, TileFeatures::default());
    let touch = one(t.layout().rect(0, 0, 8, 8));
    t.access(&mut c, &touch, false, true, &mut vals);
    assert_eq!(t.flush(&mut c, &mut vals)[0].sectors, 0xff);
    assert_eq!(t.state(0), TileState::Uncompressed);
    let off = TileFeatures {
        colour_compression: false,
        ..TileFeatures::default()
    };
    let mut flat = |_| [rgba8([1, 2, 3]); TILE_PIXELS];
    let (mut t, mut c) = table(8, 8, Surface::Colour, off);
    t.access(&mut c, &touch, false, true, &mut flat);
    assert_eq!(t.flush(&mut c, &mut flat)[0].sectors, 0xff);
    assert_eq!(t.stats().compression_ratio(), 1.0);
}

#[test]
fn a_cache_line_that_is_not_a_tile_is_refused_naming_the_field() {
    let l = layout(64, 64, PixelOrder::Morton);
    let f = TileFeatures::default();
    let cfg = CacheConfig {
        line_bytes: 128,
        ..CacheConfig::default()
    };
    match TileTable::new(l, Surface::Depth, f, &cfg, "rop.depth_cache") {
        Err(Error::Invalid { field, .. }) => assert_eq!(field, "rop.depth_cache.line_bytes"),
        other => panic!("{other:?}"),
    }
    match SurfaceLayout::new(64, 64, 3, 32, PixelOrder::Morton) {
        Err(Error::Invalid { field, .. }) => assert_eq!(field, "sector_bytes"),
        other => panic!("{other:?}"),
    }
}

/// The ROP's depth test (rop::framebuffer::depth_test), restated: the memory layer is a
/// leaf and may not import the ROP.
fn depth_test(z: f32, id: u32, depth: f32, primitive: u32) -> bool {
    (0.0..=1.0).contains(&z) && (z < depth || (z == depth && id < primitive))
}

/// Draws random spans into random tiles through the depth test, keeping hierarchical Z by
/// `note_depth_write` and `set_farthest`, and returns the fragments `reject` rejected that
/// the exact test passes.
fn wrongly_rejected(reject: fn(f32, f32) -> bool, seed: u64) -> u64 {
    let mut rng = SplitMix64::new(seed);
    let (mut t, _) = table(8, 8, Surface::Depth, TileFeatures::default());
    let mut wrong = 0;
    for _ in 0..200 {
        let mut depth = [1.0f32; 8];
        let mut prim = [u32::MAX; 8];
        t.set_farthest(0, 1.0);
        for _ in 0..40 {
            // Depths on a coarse grid, so that ties happen.
            let zs: [f32; 8] = std::array::from_fn(|_| rng.below(9) as f32 / 8.0);
            let id = rng.below(20) as u32;
            let nearest = zs.iter().copied().fold(f32::INFINITY, f32::min);
            let farthest = t.farthest(0);
            let rejected = reject(nearest, farthest);
            for x in 0..8 {
                if depth_test(zs[x], id, depth[x], prim[x]) {
                    wrong += rejected as u64;
                    depth[x] = zs[x];
                    prim[x] = id;
                    t.note_depth_write(0, zs[x]);
                }
            }
            if rng.below(8) == 0 {
                t.set_farthest(0, depth.iter().copied().fold(0.0, f32::max));
            }
        }
    }
    wrong
}

#[test]
fn hierarchical_z_never_rejects_a_fragment_the_depth_test_passes() {
    let mut t = table(8, 8, Surface::Depth, TileFeatures::default()).0;
    let rule = |nearest: f32, farthest: f32| nearest > farthest;
    assert_eq!(wrongly_rejected(rule, 1), 0);
    assert!(t.hz_rejects(0, 1.5) && !t.hz_rejects(0, 1.0) && !t.hz_rejects(0, f32::NAN));
    // Planted: rejecting at equality throws away fragments a smaller id wins.
    let planted = |nearest: f32, farthest: f32| nearest >= farthest;
    assert!(wrongly_rejected(planted, 1) > 0);
}

/// A full-screen overdraw pattern: 256x256 pixels drawn as 32x32-pixel squares in screen
/// order, each drawn `layers` times (as a mesh's overlapping triangles reach one region),
/// every span of 8 pixels read and written. Returns the depth cache's hit rate.
fn overdraw_hit_rate(layers: u32, order: PixelOrder, fast_clear: bool) -> (f64, TableStats) {
    let cfg = CacheConfig::default();
    let l = SurfaceLayout::new(256, 256, 4, 32, order).unwrap();
    let f = TileFeatures {
        fast_clear,
        ..TileFeatures::default()
    };
    let mut t = TileTable::new(l, Surface::Depth, f, &cfg, "rop.depth_cache").unwrap();
    let mut c = SectorCache::new(cfg, "test", "rop.depth_cache").unwrap();
    let mut vals = |tile: u32| [depth24(tile as f32 / 1024.0); TILE_PIXELS];
    for (sy, sx) in (0..8).flat_map(|sy| (0..8).map(move |sx| (sy, sx))) {
        for _ in 0..layers {
            for y in sy * 32..sy * 32 + 32 {
                for x0 in (sx * 32..sx * 32 + 32).step_by(8) {
                    for touch in l.span(y, x0, x0 + 8) {
                        t.access(&mut c, &touch, true, true, &mut vals);
                    }
                }
            }
        }
    }
    t.flush(&mut c, &mut vals);
    (c.stats().hit_rate(), *t.stats())
}

#[test]
fn the_depth_cache_absorbs_repeated_tests_under_overdraw() {
    // Each 32x32 square is 16 tiles (4 KB), well inside 16 KB. Without fast clear, one
    // layer: in Z order a sector is two rows of 4 pixels, so of a row pair's spans the first
    // misses and the second hits (1/2); in row order each span is its own sector (0). Each
    // further layer hits every sector.
    let (one, _) = overdraw_hit_rate(1, PixelOrder::Morton, false);
    assert_eq!(one, 0.5);
    let (four, _) = overdraw_hit_rate(4, PixelOrder::Morton, false);
    assert_eq!(four, 1.0 - 0.5 / 4.0);
    let (rows, _) = overdraw_hit_rate(4, PixelOrder::RowMajor, false);
    assert_eq!(rows, 0.75);
    // Fast clear fills a cleared tile's line whole at its first touch: only that span's two
    // sectors miss, of 16 touches a layer, and no sector is read.
    let (four, stats) = overdraw_hit_rate(4, PixelOrder::Morton, true);
    assert_eq!(four, 1.0 - 2.0 / 64.0);
    assert_eq!(stats.sectors_read, 0);
    // Each constant tile goes back in one sector of eight.
    assert_eq!(stats.compression_ratio(), 8.0);
}
