//! The request traces the controller is checked against DRAMsim3 with (issue 51, item 5):
//! a streaming geometry fetch, a ROP-cache write-back pattern and a mixed frame of the two
//! interleaved in time. Each is a pure function of its parameters (the write-back pattern
//! draws from a seeded [`SplitMix64`]), so `examples/dram_check` (which feeds them to
//! DRAMsim3) and `tests/integration/dram_check.rs` (which feeds them to [`super::replay`]
//! and compares with DRAMsim3's recorded figures, `traces/dram/dramsim3.json`) run the
//! same requests, byte for byte. With the `testkit` feature only, as its generator.

use crate::memory::trace::Request;
use crate::testkit::SplitMix64;

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
/// The fetch lines of the `stream` and `mixed` traces (2 MiB).
pub const STREAM_READS: u64 = 32_768;
/// The fetch lines of `stream_200k`: the figure, 200 000 64-byte reads.
pub const STREAM_200K_READS: u64 = 200_000;

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
            arrival: offset + i * period,
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
        let arrival = offset + out.len() as u64 * period;
        out.push(Request {
            addr,
            write,
            arrival,
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
    out.sort_by_key(|r| r.arrival);
    out
}

/// The check's traces by name, as `examples/dram_check` writes them: `stream` (32 768
/// sequential 64-byte reads, one a cycle), `rop_writeback` (one a cycle), `mixed` (the two
/// interleaved) and `stream_200k` (200 000 reads, one a cycle).
pub fn all() -> Vec<(&'static str, Vec<Request>)> {
    vec![
        ("stream", stream(STREAM_READS, 1, 0)),
        ("rop_writeback", rop_writeback(1, 0)),
        ("mixed", mixed(STREAM_READS)),
        ("stream_200k", stream(STREAM_200K_READS, 1, 0)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::memory::trace;

    #[test]
    fn stream_is_sequential_lines() {
        let s = stream(3, 2, 5);
        let addrs: Vec<u64> = s.iter().map(|r| r.addr - GEOMETRY_BASE).collect();
        let cycles: Vec<u64> = s.iter().map(|r| r.arrival).collect();
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
        // The counts DRAMsim3's recorded run took (traces/dram/dramsim3.json): 7 760 depth
        // fills and 57 462 write-backs, about 1/4 of 4 096 tiles and 7/8 of 2 x 32 768
        // sectors.
        let writes = w.iter().filter(|r| r.write).count();
        let reads = w.iter().filter(|r| !r.write).count();
        assert_eq!((reads, writes), (7_760, 57_462));
        assert_eq!(w, rop_writeback(1, 0));
    }

    #[test]
    fn mixed_interleaves_both_in_arrival_order() {
        let m = mixed(16);
        assert!(m.windows(2).all(|p| p[0].arrival < p[1].arrival));
        let first: Vec<bool> = m[..4].iter().map(|r| r.addr >= GEOMETRY_BASE).collect();
        assert_eq!(first, [true, false, true, false]);
        assert_eq!(m.len(), 16 + rop_writeback(2, 1).len());
    }

    #[test]
    fn every_trace_round_trips_through_dramsim3s_format() {
        for (name, reqs) in all() {
            let text = trace::write(&reqs);
            assert_eq!(trace::parse(name, &text).unwrap(), reqs, "{name}");
        }
    }
}
