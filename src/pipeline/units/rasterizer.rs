//! FragmentRasterizer (Martinelli 2006 section 5.3: "the generation of fragments along the
//! subsegment may be done with a simple linear equation for the u and v components, which
//! may be evaluated step by step with simple increments").
//!
//! Input: [`ScanSubsegment`] from the subsegmenters, merged by (arrival, port). Output: the
//! subsegment's pixel run cut at ROP tile borders into [`FragmentSpan`]s, each routed to
//! the ROP that owns its tile (screen interleaving, [`RopTiles`]).
//! A span carries (u, v) at its first pixel and the increments; the ROP walks it with the
//! same additions, so its fragments are bit-identical to the functional model's.
//!
//! On the host, a span's first pixel is asked of the cache as the span is sent
//! ([`SharedFrame::prefetch`], a hint that reads nothing), so the ROP's depth test finds it
//! nearer when the span comes out of its FIFO.
//!
//! Cost: `rasterizer.cycles_per_subsegment` per subsegment (increment setup), then
//! ceil(n / fragments_per_cycle) per span of n fragments, ready `latency_cycles` later.
//! Depth is evaluated from the depth quadratic in the ROP, with the depth test.

use crate::config::RasterizerConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::{FragmentSpan, RopItem, ScanSubsegment};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::{ceil_div, Ctx};
use crate::pipeline::tiles::{RopTiles, SharedFrame};
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::fragment::{span, Columns, Span};
use crate::raster::Counts;

/// A fragment rasterizer, Figure 5's sixth box.
pub struct FragmentRasterizer;

impl<R: Real> Unit<R> for FragmentRasterizer {
    const KIND: UnitKind = UnitKind::FragmentRasterizer;
    type In = ScanSubsegment<R>;
    type Out = RopItem<R>;
    // A fragment's pixel (2), domain point (2), depth and lembo id.
    const OUT_WORDS: u32 = 6;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(
            ctx,
            &run.arch.rasterizer,
            &run.tiles,
            Columns::of(run.view),
            &run.frame,
        ))
    }
}

/// A FragmentRasterizer's body: per subsegment, its fragments on the screen columns `cols`
/// in spans, one per ROP tile of `tiles` crossed.
pub async fn run<R: Real>(
    mut ctx: Ctx<ScanSubsegment<R>, RopItem<R>>,
    cfg: &RasterizerConfig,
    tiles: &RopTiles,
    cols: Columns,
    frame: &SharedFrame<'_>,
) -> Finished {
    let mut counts = Counts::default();
    while let Some(ScanSubsegment {
        piece,
        j,
        subsegment,
    }) = ctx.next_input().await
    {
        ctx.work(cfg.cycles_per_subsegment);
        let Some(mut run) = span(&subsegment, cols.width, cols.centre(j)) else {
            continue;
        };
        counts.fragments += run.len() as u64;
        while !run.is_empty() {
            let tile_end = tiles.tile_end(run.i0);
            let n = run.i1.min(tile_end) - run.i0;
            let span = Span {
                i1: run.i0 + n,
                ..run
            };
            let cycles = ceil_div(n as u64, cfg.fragments_per_cycle);
            frame.prefetch(j as usize * cols.width as usize + run.i0 as usize);
            let piece = piece.clone();
            ctx.emit(cycles, RopItem::Lembo(FragmentSpan { piece, j, span }))
                .await;
            if run.i1 <= tile_end {
                // The last span: no (u, v) to step on to.
                break;
            }
            run.advance(n);
        }
    }
    Finished::new(ctx, counts)
}
