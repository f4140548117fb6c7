//! GeometryFetch (DESIGN.md §3, "Geometry fetch"): reads the scene's primitives from memory,
//! in submission order, and deals them in batches (batch b to engine b mod count:
//! DESIGN.md §13, "Front ends") to the engines it feeds: the lembo Setups; the triangle
//! setup engines, from a mesh tessellated in memory; or the Tessellators, whose lembos are
//! tessellated on chip (`tessellation.source`).
//!
//! A batch of a mesh's triangles reads each triangle's three indices and, through its setup
//! engine's post-transform vertex cache (FIFO replacement, `tessellation.vertex_cache_entries`
//! entries, one cache per engine, so a batch starts where that engine's last batch left the
//! cache), each vertex the cache misses. Other primitives (lembos, a source that is not an
//! indexed mesh) read their share of the bytes stored.
//!
//! Input: none (the unit is the source). Output: per batch one [`MemAccess`] (the first
//! primitive, the count, the bytes) to the batch's engine, the link's `latency_cycles`
//! later (`fetch_to_setup`, `fetch_to_triangle_setup` or `fetch_to_tessellator`: the DRAM
//! latency).
//!
//! The bytes are the architecture's (`fetch.bytes_per_lembo`; `fetch.bytes_per_vertex` and
//! `fetch.index_bytes_per_triangle` for a mesh in memory).
//!
//! Cost: each batch is one access of the memory port, priced as the frame-buffer port
//! prices its accesses ([`PortClock`]: whole slots of `framebuffer.access_cycles`, so
//! ceil(bytes / `framebuffer.bytes_per_cycle`) busy cycles with the default slot), at least
//! one cycle a batch. With the message port (`memory.model = "port"`) the bytes are priced
//! as DRAM on this unit, and the port is shared with the ROPs' frame-buffer traffic as a
//! bound: the frame takes at least the port's cycles for both (DESIGN.md §3, "One memory
//! port"). With the DRAM controller (`dram`) each batch is first sent to it as a read
//! ([`Ctx::emit_shared`], a cycle of the batch's, at least two a batch): its atoms queue
//! there among the ROPs' fills and write-backs, in time, and are priced there; the batch
//! still reaches its engine the fetch link's latency after it is issued.

use crate::config::{FetchConfig, FrameBufferConfig};
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::MemAccess;
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::{Ctx, Cycle};
use crate::pipeline::unit::{
    FetchPlan, FetchReport, Finished, RunInputs, Unit, UnitReport, VertexCacheCounts,
};
use crate::pipeline::units::framebuffer::PortClock;
use crate::raster::triangle::TriangleSource;
use crate::raster::Counts;
use std::collections::{HashSet, VecDeque};

/// The geometry fetch.
pub struct GeometryFetch;

impl<R: Real> Unit<R> for GeometryFetch {
    const KIND: UnitKind = UnitKind::GeometryFetch;
    type In = ();
    type Out = MemAccess;
    // A batch's first primitive and count, and its bytes.
    const OUT_WORDS: u32 = 3;

    fn spawn<'a>(
        ctx: Ctx<(), MemAccess>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(
            ctx,
            run.fetch,
            run.triangles,
            &run.arch.fetch,
            run.port,
        ))
    }
}

/// The fetch's body: the primitives of `plan`, a batch (its consumers', which its boundary
/// hands it) at a time, to the engines in turn, read through the memory port `port`; with a vertex cache, the triangles' vertex indices
/// come from `source`, and each triangle's and vertex's bytes are `sizes`'.
pub async fn run(
    mut ctx: Ctx<(), MemAccess>,
    plan: FetchPlan,
    source: &dyn TriangleSource,
    sizes: &FetchConfig,
    port: &FrameBufferConfig,
) -> Finished {
    let batch = u64::from(ctx.batch().expect("the fetch's boundary deals batches"));
    let mut port = PortClock::new(port);
    // One vertex cache per engine the batches are dealt to.
    let mut caches = plan.vertex_cache.map(|entries| {
        (0..ctx.consumers())
            .map(|_| VertexCache::new(entries as usize))
            .collect::<Vec<_>>()
    });
    let mut indices = MeshIndices::new(source);
    let mut report = FetchReport {
        source: plan.source,
        primitives: plan.primitives,
        ..FetchReport::default()
    };
    // The fetch's clock when its last access ended.
    let mut issued = Cycle::ZERO;
    let mut first = 0;
    while first < plan.primitives {
        let end = (first + batch).min(plan.primitives);
        let bytes = match caches.as_mut() {
            Some(caches) => {
                // The cache of the engine the runtime deals this batch to.
                let engine = ctx.next_consumer().expect("batches are dealt in turn");
                let cache = &mut caches[engine];
                let misses = indices.misses(first..end, cache);
                sizes.mesh_bytes(end - first, misses)
            }
            None => plan.bytes_of(first, end),
        };
        let access = MemAccess::batch(first as u32, (end - first) as u32, bytes, report.bytes);
        report.bytes += bytes;
        // The fetch always has its next batch ready: it starts where the port's last slot
        // ended, unless a full FIFO froze the fetch since (then at its clock). An emit
        // takes at least a cycle (two with the read sent to the DRAM controller first), and
        // the port's time moves to its end.
        let (now, _) = ctx.clock();
        let ready = if now == issued { Cycle::ZERO } else { now };
        let least = if ctx.has_shared() { 2 } else { 1 };
        let mut cycles = port.access(now, ready, bytes);
        if cycles < least {
            cycles = least;
            port.hold_until(Cycle(now.0 + least));
        }
        issued = Cycle(now.0 + cycles);
        if ctx.has_shared() {
            ctx.emit_shared(1, access).await;
            cycles -= 1;
        }
        ctx.emit(cycles, access).await;
        first = end;
    }
    report.vertex_cache = caches.map(|caches| VertexCacheCounts {
        entries: plan.vertex_cache.unwrap_or(0),
        hits: caches.iter().map(|c| c.hits).sum(),
        misses: caches.iter().map(|c| c.misses).sum(),
    });
    Finished::new(ctx, Counts::default()).with(UnitReport::Fetch(report))
}

/// The index buffer of an indexed triangle source, read a chunk at a time.
struct MeshIndices<'a> {
    source: &'a dyn TriangleSource,
    per_chunk: u64,
    /// The chunk in `ids`, if any.
    held: Option<usize>,
    ids: Vec<[u64; 3]>,
}

impl<'a> MeshIndices<'a> {
    fn new(source: &'a dyn TriangleSource) -> Self {
        MeshIndices {
            source,
            per_chunk: source.per_chunk().max(1),
            held: None,
            ids: Vec::new(),
        }
    }

    /// Looks up the vertices of triangles `range` in `cache`, in order; the misses.
    fn misses(&mut self, range: std::ops::Range<u64>, cache: &mut VertexCache) -> u64 {
        let before = cache.misses;
        for t in range {
            let (c, k) = ((t / self.per_chunk) as usize, (t % self.per_chunk) as usize);
            if self.held != Some(c) {
                debug_assert!(
                    self.source.indexed(),
                    "a vertex cache needs an indexed mesh"
                );
                self.source.vertex_ids(c, &mut self.ids);
                self.held = Some(c);
            }
            for v in self.ids[k] {
                cache.look_up(v);
            }
        }
        cache.misses - before
    }
}

/// A post-transform vertex cache: the last `entries` distinct vertices missed, replaced
/// first in, first out (a hit does not refresh an entry), as the FIFO caches of GPUs are.
struct VertexCache {
    entries: usize,
    fifo: VecDeque<u64>,
    /// The vertices in `fifo`, for a large cache (a small one is searched directly).
    held: HashSet<u64>,
    hits: u64,
    misses: u64,
}

impl VertexCache {
    /// Up to this many entries the FIFO is searched directly.
    const SCAN: usize = 64;

    fn new(entries: usize) -> Self {
        VertexCache {
            entries,
            fifo: VecDeque::with_capacity(entries),
            held: HashSet::new(),
            hits: 0,
            misses: 0,
        }
    }

    /// Whether vertex `v` is cached; on a miss it enters the cache.
    fn look_up(&mut self, v: u64) -> bool {
        let hit = if self.entries <= Self::SCAN {
            self.fifo.contains(&v)
        } else {
            self.held.contains(&v)
        };
        if hit {
            self.hits += 1;
            return true;
        }
        self.misses += 1;
        if self.fifo.len() == self.entries {
            let old = self.fifo.pop_front();
            if self.entries > Self::SCAN {
                old.map(|o| self.held.remove(&o));
            }
        }
        self.fifo.push_back(v);
        if self.entries > Self::SCAN {
            self.held.insert(v);
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// FIFO replacement: a vertex stays for `entries` misses after its own, hits or not.
    #[test]
    fn vertex_cache_replaces_first_in_first_out() {
        for entries in [2, VertexCache::SCAN + 1] {
            let mut c = VertexCache::new(entries);
            assert!(!c.look_up(7));
            assert!(c.look_up(7));
            for v in 0..entries as u64 - 1 {
                assert!(!c.look_up(100 + v));
            }
            // 7 was the oldest entry when the cache filled; a hit did not refresh it.
            assert!(c.look_up(7));
            assert!(!c.look_up(1000));
            assert!(!c.look_up(7), "{entries}: 7 was evicted");
            assert_eq!((c.hits, c.misses), (2, entries as u64 + 2));
        }
    }
}
