//! GeometryFetch (DESIGN.md §3, "Geometry fetch"): reads the scene's primitives (lembos,
//! or the triangle path's indexed mesh) from memory, in submission order, and deals them
//! to the setup engines in batches of the path's `setup.batch` or `triangle_setup.batch`
//! (batch b to engine b mod count: ARCHITECTURE.md, "Front ends"). A batch of triangles
//! reads its share of the mesh's bytes (each shared vertex once: a perfect post-transform
//! vertex cache).
//!
//! Input: none (the unit is the source). Output: per batch one [`MemAccess`] (the first
//! primitive, the count, the bytes) to the batch's setup engine, `fetch_to_setup` (or
//! `fetch_to_triangle_setup`) `.latency_cycles` later: the DRAM latency.
//!
//! Cost: ceil(bytes / `framebuffer.bytes_per_cycle`) busy cycles per batch: reads at the
//! memory port's peak rate; the bytes are priced as DRAM on this unit. Not
//! modelled: contention with the ROPs' frame-buffer traffic for the port (each has the
//! port's whole rate; DESIGN.md §11 says why), caches (every primitive is read once a
//! pass).

use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::MemAccess;
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::{ceil_div, Ctx};
use crate::pipeline::unit::{FetchPlan, Finished, Run, Unit};
use crate::raster::Counts;

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
        run: &'a Run<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(
            ctx,
            run.fetch,
            run.arch.framebuffer.bytes_per_cycle,
        ))
    }
}

/// The fetch's body: the primitives of `plan`, a batch at a time, to the setup engines in
/// turn, read at `bytes_per_cycle`.
pub async fn run(mut ctx: Ctx<(), MemAccess>, plan: FetchPlan, bytes_per_cycle: u64) -> Finished {
    // Its first boundary leads to the path's setup engines (a graph with both paths' setup
    // engines feeds the second kind nothing).
    let engines = ctx.group(0);
    let mut engine = engines.start;
    let mut first = 0;
    while first < plan.primitives {
        let end = (first + plan.batch as u64).min(plan.primitives);
        let access = MemAccess {
            bytes: plan.bytes_of(first, end),
            first: first as u32,
            count: (end - first) as u32,
        };
        ctx.emit(
            ceil_div(access.bytes, bytes_per_cycle).max(1),
            engine,
            access,
        )
        .await;
        engine = if engine + 1 >= engines.end {
            engines.start
        } else {
            engine + 1
        };
        first = end;
    }
    Finished::new(ctx, Counts::default())
}
