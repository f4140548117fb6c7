//! Subsegmenter (Martinelli 2006 section 5.3): splits a segment where x(t) folds and into equal
//! steps no longer than dt, so that x is linear within k along each subsegment.
//!
//! Input: [`ScanSegment`] from the segmenters, merged by (arrival, port). Output: one
//! [`ScanSubsegment`] per subsegment, round-robin over the fragment rasterizers (the n-th
//! subsegment this unit emits goes to rasterizer n mod Nr).
//!
//! Cost: `subsegmenter.cycles_per_subsegment` per subsegment, ready `latency_cycles` later.

use super::segmenter::ScanSegment;
use crate::datapath::Real;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::{Finished, PieceId, Shared};
use crate::raster::subsegmenter::{subsegments, Subsegment};
use crate::raster::Counts;

/// One subsegment of scanline `j` of lembo `id`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanSubsegment<R> {
    /// The lembo piece.
    pub id: PieceId,
    /// The scanline.
    pub j: u32,
    /// The piece of the chord along which x is linear.
    pub subsegment: Subsegment<R>,
}

/// A Subsegmenter's body: per segment, its subsegments, dispatched round-robin to the rasterizers.
pub async fn run<R: Real>(
    mut ctx: Ctx<ScanSegment<R>, ScanSubsegment<R>>,
    sh: &Shared<'_, R>,
) -> Finished {
    let cost = sh.arch.subsegmenter.cycles_per_subsegment;
    let mut counts = Counts::default();
    let mut subs = Vec::new();
    let mut next_port = 0;
    while let Some(ScanSegment { id, j, segment }) = ctx.next_input().await {
        let l = sh.lembo(id);
        subs.clear();
        subsegments(l, &segment, sh.k, &mut subs, &mut counts);
        for &subsegment in &subs {
            ctx.emit(cost, next_port, ScanSubsegment { id, j, subsegment })
                .await;
            next_port = ctx.next_port(next_port);
        }
    }
    Finished::new(ctx, counts)
}
