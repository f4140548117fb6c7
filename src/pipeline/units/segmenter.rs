//! Segmenter (Martinelli 2006 section 5.2): walks one interval of the curve Y(u, v) = y_j in
//! chords whose midpoint error is exactly k, solving the paper's 2x2 system per step.
//!
//! Input: [`ScanInterval`] from the IntervalManager. Output: one [`ScanSegment`] per chord,
//! dispatched round-robin over the subsegmenters (the n-th segment this unit emits goes to
//! subsegmenter n mod Nb).
//!
//! Cost: `segmenter.cycles_per_segment` per segment (one step of the system), ready
//! `latency_cycles` later. A walk that needs more segments than the cap is recorded as an
//! error and the interval dropped, so the run still ends and reports the first such
//! interval in scene order, whatever the schedule.

use crate::config::SegmenterConfig;
use crate::datapath::Real;
use crate::error::Error;
use crate::graph::UnitKind;
use crate::pipeline::items::{ScanInterval, ScanSegment};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::segmenter::{least_reach, walk_dispatched};
use crate::raster::{Counts, DEFAULT_SEGMENT_CAP};
use std::sync::Arc;

/// A segmenter, Figure 5's fourth box.
pub struct Segmenter;

impl<R: Real> Unit<R> for Segmenter {
    const KIND: UnitKind = UnitKind::Segmenter;
    type In = ScanInterval<R>;
    type Out = ScanSegment<R>;
    // A chord's two domain points (4), its scanline and lembo id.
    const OUT_WORDS: u32 = 6;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(ctx, &run.arch.segmenter, run.k))
    }
}

/// A Segmenter's body: per interval, its segments, dispatched round-robin to the subsegmenters.
pub async fn run<R: Real>(
    mut ctx: Ctx<ScanInterval<R>, ScanSegment<R>>,
    cfg: &SegmenterConfig,
    k: R,
) -> Finished {
    let cost = cfg.cycles_per_segment;
    let mut counts = Counts::default();
    let mut segs = Vec::new();
    // The first (lembo, piece, scanline) over the cap, as the functional model meets them.
    let mut cap_error: Option<(u32, u32, u32)> = None;
    // The last piece's bound on a step's reach (`least_reach`), worked out once for its
    // intervals, which mostly come one after another; the piece is held so that its
    // address cannot be another's.
    let mut reach: Option<(Arc<_>, Option<f64>)> = None;
    while let Some(ScanInterval { piece, j, interval }) = ctx.next_input().await {
        let (l, id) = (&*piece.screen, piece.id);
        let bound = match &reach {
            Some((last, bound)) if Arc::ptr_eq(last, &piece.screen) => *bound,
            _ => {
                let bound = least_reach(l, k);
                reach = Some((piece.screen.clone(), bound));
                bound
            }
        };
        segs.clear();
        let cap = DEFAULT_SEGMENT_CAP;
        if walk_dispatched(l, j, k, &interval, cap, bound, &mut segs, &mut counts).is_err() {
            let at = (id.lembo, id.piece, j);
            cap_error = Some(cap_error.map_or(at, |e| e.min(at)));
            continue;
        }
        for &segment in &segs {
            let piece = piece.clone();
            ctx.emit(cost, ScanSegment { piece, j, segment }).await;
        }
    }
    let mut done = Finished::new(ctx, counts);
    done.error = cap_error.map(|(lembo, _, scanline)| Error::SegmentCap {
        lembo: lembo as usize,
        scanline,
        cap: DEFAULT_SEGMENT_CAP,
    });
    done
}
