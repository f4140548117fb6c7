//! FragmentRasterizer (Martinelli 2006 section 5.3: "the generation of fragments along the
//! subsegment may be done with a simple linear equation for the u and v components, which
//! may be evaluated step by step with simple increments").
//!
//! Input: [`ScanSubsegment`] from the subsegmenters, merged by (arrival, port). Output: the
//! subsegment's pixel run cut at ROP tile borders into [`FragmentSpan`]s, each routed to
//! the ROP that owns its tile (screen interleaving, [`RopTiles`](super::rop::RopTiles)).
//! A span carries (u, v) at its first pixel and the increments; the ROP walks it with the
//! same additions, so its fragments are bit-identical to the functional model's.
//!
//! Cost: `rasterizer.cycles_per_subsegment` per subsegment (increment setup), then
//! ceil(n / fragments_per_cycle) per span of n fragments, ready `latency_cycles` later.
//! Depth is evaluated from the depth quadratic in the ROP, with the depth test.

use super::rop::RopItem;
use super::subsegmenter::ScanSubsegment;
use crate::datapath::Real;
use crate::pipeline::runtime::{ceil_div, Ctx};
use crate::pipeline::{Finished, PieceId, Shared};
use crate::raster::fragment::{span, Span};
use crate::raster::Counts;

/// Fragments of lembo `id` on scanline `j` inside one ROP tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FragmentSpan<R> {
    /// The lembo piece.
    pub id: PieceId,
    /// The scanline.
    pub j: u32,
    /// The pixels of one subsegment inside one ROP tile.
    pub span: Span<R>,
}

/// A FragmentRasterizer's body: per subsegment, its fragments in spans, one per ROP tile crossed.
pub async fn run<R: Real>(
    mut ctx: Ctx<ScanSubsegment<R>, RopItem<R>>,
    sh: &Shared<'_, R>,
) -> Finished {
    let cfg = &sh.arch.rasterizer;
    let mut counts = Counts::default();
    let width = sh.view.viewport.width;
    while let Some(ScanSubsegment { id, j, subsegment }) = ctx.next_input().await {
        ctx.work(cfg.cycles_per_subsegment);
        let Some(mut run) = span(&subsegment, width) else {
            continue;
        };
        counts.fragments += run.len() as u64;
        while !run.is_empty() {
            let (rop, tile_end) = sh.tiles.owner(run.i0, j);
            let n = run.i1.min(tile_end) - run.i0;
            let piece = Span {
                i1: run.i0 + n,
                ..run
            };
            let cycles = ceil_div(n as u64, cfg.fragments_per_cycle);
            ctx.emit(
                cycles,
                rop,
                RopItem::Lembo(FragmentSpan { id, j, span: piece }),
            )
            .await;
            run.advance(n);
        }
    }
    Finished::new(ctx, counts)
}
