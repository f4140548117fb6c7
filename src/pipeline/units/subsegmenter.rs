//! Subsegmenter (Martinelli 2006 section 5.3): splits a segment where x(t) folds and into equal
//! steps no longer than dt, so that x is linear within k along each subsegment.
//!
//! Input: [`ScanSegment`] from the segmenters, merged by (arrival, port). Output: one
//! [`ScanSubsegment`] per subsegment, round-robin over the fragment rasterizers (the n-th
//! subsegment this unit emits goes to rasterizer n mod Nr).
//!
//! Cost: `subsegmenter.cycles_per_subsegment` per subsegment, ready `latency_cycles` later.

use crate::config::SubsegmenterConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::{ScanSegment, ScanSubsegment};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::subsegmenter::subsegments_dispatched;
use crate::raster::Counts;

/// A subsegmenter, Figure 5's fifth box.
pub struct Subsegmenter;

impl<R: Real> Unit<R> for Subsegmenter {
    const KIND: UnitKind = UnitKind::Subsegmenter;
    type In = ScanSegment<R>;
    type Out = ScanSubsegment<R>;
    // Two domain points (4), their screen x (2), scanline and lembo id.
    const OUT_WORDS: u32 = 8;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(ctx, &run.arch.subsegmenter, run.k))
    }
}

/// A Subsegmenter's body: per segment, its subsegments, dispatched round-robin to the rasterizers.
pub async fn run<R: Real>(
    mut ctx: Ctx<ScanSegment<R>, ScanSubsegment<R>>,
    cfg: &SubsegmenterConfig,
    k: R,
) -> Finished {
    let cost = cfg.cycles_per_subsegment;
    let mut counts = Counts::default();
    let mut subs = Vec::new();
    while let Some(ScanSegment { piece, j, segment }) = ctx.next_input().await {
        let l = &*piece.screen;
        subs.clear();
        subsegments_dispatched(l, &segment, k, &mut subs, &mut counts);
        for &subsegment in &subs {
            let piece = piece.clone();
            ctx.emit(
                cost,
                ScanSubsegment {
                    piece,
                    j,
                    subsegment,
                },
            )
            .await;
        }
    }
    Finished::new(ctx, counts)
}
