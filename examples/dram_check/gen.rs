//! The request traces the DRAM check runs (issue 51, item 5): a streaming geometry fetch, a
//! ROP-cache write-back pattern and a mixed frame of the two interleaved in time. Each is a
//! pure function of its parameters (the write-back pattern draws from a seeded
//! [`SplitMix64`]), so the same command writes the same bytes on every machine.

use crate::trace::Request;
use lembo_sim::testkit::SplitMix64;

/// Bytes of one geometry-fetch read: a 64-byte line.
pub const FETCH_BYTES: u64 = 64;
/// Bytes of one ROP-cache sector: one 8-pixel row of an 8x8 tile at 32 bits a pixel.
pub const SECTOR_BYTES: u64 = 32;
/// The surfaces' side in pixels (the bunny's frame, 512x512).
pub const SURFACE_SIDE: u64 = 512;
/// A tile's side in pixels (ATTILA's 256-byte line of 8x8 pixels at 32 bits, issue 51).
pub const TILE_SIDE: u64 = 8;
/// Where the geometry buffer starts: 256 MiB, clear of the surfaces.
pub const GEOMETRY_BASE: u64 = 0x1000_0000;
/// Where the colour surface starts (16 MiB); the depth surface follows it.
pub const COLOUR_BASE: u64 = 0x0100_0000;
/// The seed of the write-back pattern's draws (the number).
pub const SEED: u64 = 51;

/// The bytes a generated request asks for: a fetch line above [`GEOMETRY_BASE`], a ROP
/// sector below it.
pub fn payload_bytes(r: &Request) -> u64 {
    if r.addr >= GEOMETRY_BASE {
        FETCH_BYTES
    } else {
        SECTOR_BYTES
    }
}

/// `n` sequential 64-byte reads from [`GEOMETRY_BASE`], one offered every `period` cycles
/// from cycle `offset`.
pub fn stream(n: u64, period: u64, offset: u64) -> Vec<Request> {
    (0..n)
        .map(|i| Request {
            addr: GEOMETRY_BASE + i * FETCH_BYTES,
            write: false,
            arrival_cycle: offset + i * period,
        })
        .collect()
}

/// A ROP cache's traffic over a 512x512 colour surface and its depth surface (32 bits a
/// pixel each, tiled: 8x8-pixel tiles of 256 contiguous bytes, tiles in row-major order,
/// sector `k` of a tile its pixel row `k`), written back in tile order.
///
/// Per tile, in order: with probability 1/4 its depth line is filled first (8 sector reads:
/// a tile the cache had evicted before its last test); then each of its 8 colour sectors is
/// dirty with probability 7/8 (a partly covered tile), and a dirty colour sector writes back
/// with the depth sector of the same row. One request offered every `period` cycles from
/// cycle `offset`.
pub fn rop_writeback(period: u64, offset: u64) -> Vec<Request> {
    let surface_bytes = SURFACE_SIDE * SURFACE_SIDE * 4;
    let depth_base = COLOUR_BASE + surface_bytes;
    let tile_bytes = TILE_SIDE * TILE_SIDE * 4;
    let tiles = (SURFACE_SIDE / TILE_SIDE) * (SURFACE_SIDE / TILE_SIDE);
    let mut rng = SplitMix64::new(SEED);
    let mut out = Vec::new();
    let mut push = |addr: u64, write: bool| {
        let arrival_cycle = offset + out.len() as u64 * period;
        out.push(Request {
            addr,
            write,
            arrival_cycle,
        });
    };
    for t in 0..tiles {
        let tile = t * tile_bytes;
        if rng.below(4) == 0 {
            for k in 0..TILE_SIDE {
                push(depth_base + tile + k * SECTOR_BYTES, false);
            }
        }
        for k in 0..TILE_SIDE {
            if rng.below(8) != 0 {
                push(COLOUR_BASE + tile + k * SECTOR_BYTES, true);
                push(depth_base + tile + k * SECTOR_BYTES, true);
            }
        }
    }
    out
}

/// A frame's traffic: the geometry fetch of `fetch_reads` lines offered on even cycles and
/// the ROP write-back pattern on odd cycles, merged in arrival order (one request a cycle
/// while both run).
pub fn mixed(fetch_reads: u64) -> Vec<Request> {
    let mut out = stream(fetch_reads, 2, 0);
    out.extend(rop_writeback(2, 1));
    out.sort_by_key(|r| r.arrival_cycle);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stream_is_sequential_lines() {
        let s = stream(3, 2, 5);
        let addrs: Vec<u64> = s.iter().map(|r| r.addr - GEOMETRY_BASE).collect();
        let cycles: Vec<u64> = s.iter().map(|r| r.arrival_cycle).collect();
        assert_eq!(addrs, [0, 64, 128]);
        assert_eq!(cycles, [5, 7, 9]);
        assert!(s.iter().all(|r| !r.write));
    }

    #[test]
    fn rop_writeback_stays_on_its_surfaces_in_tile_order() {
        let w = rop_writeback(1, 0);
        let end = COLOUR_BASE + 2 * SURFACE_SIDE * SURFACE_SIDE * 4;
        assert!(w.iter().all(|r| (COLOUR_BASE..end).contains(&r.addr)));
        assert!(w.iter().all(|r| r.addr % SECTOR_BYTES == 0));
        // Tile order: colour writes never go back to an earlier address.
        let colour: Vec<u64> = w
            .iter()
            .filter(|r| r.write && r.addr < COLOUR_BASE + SURFACE_SIDE * SURFACE_SIDE * 4)
            .map(|r| r.addr)
            .collect();
        assert!(colour.windows(2).all(|p| p[0] < p[1]));
        // About 7/8 of the 32 768 colour sectors are written, about 1/4 of tiles filled.
        let writes = w.iter().filter(|r| r.write).count() as f64;
        let reads = w.iter().filter(|r| !r.write).count() as f64;
        assert!((writes / (2.0 * 32768.0) - 0.875).abs() < 0.01, "{writes}");
        assert!((reads / (8.0 * 4096.0) - 0.25).abs() < 0.02, "{reads}");
        // Deterministic: the same call gives the same trace.
        assert_eq!(w, rop_writeback(1, 0));
    }

    #[test]
    fn mixed_interleaves_both_in_arrival_order() {
        let m = mixed(16);
        assert!(m
            .windows(2)
            .all(|p| p[0].arrival_cycle < p[1].arrival_cycle));
        let first: Vec<bool> = m[..4].iter().map(|r| r.addr >= GEOMETRY_BASE).collect();
        assert_eq!(first, [true, false, true, false]);
        assert_eq!(m.len(), 16 + rop_writeback(2, 1).len());
    }
}
