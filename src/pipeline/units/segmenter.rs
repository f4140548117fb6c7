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

use super::interval_manager::ScanInterval;
use crate::datapath::Real;
use crate::error::Error;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::{Finished, PieceId, Shared};
use crate::raster::segmenter::{segments, Segment};
use crate::raster::{Counts, DEFAULT_SEGMENT_CAP};

/// One chord of scanline `j` of lembo `id`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanSegment<R> {
    /// The lembo piece.
    pub id: PieceId,
    /// The scanline.
    pub j: u32,
    /// The chord of midpoint error k.
    pub segment: Segment<R>,
}

/// A Segmenter's body: per interval, its segments, dispatched round-robin to the subsegmenters.
pub async fn run<R: Real>(
    mut ctx: Ctx<ScanInterval<R>, ScanSegment<R>>,
    sh: &Shared<'_, R>,
) -> Finished {
    let cost = sh.arch.segmenter.cycles_per_segment;
    let mut counts = Counts::default();
    let mut segs = Vec::new();
    let mut next_port = 0;
    // The first (lembo, piece, scanline) over the cap, as the functional model meets them.
    let mut cap_error: Option<(u32, u32, u32)> = None;
    while let Some(ScanInterval { id, j, interval }) = ctx.next_input().await {
        let l = sh.lembo(id);
        segs.clear();
        if segments(
            l,
            j,
            sh.k,
            &interval,
            DEFAULT_SEGMENT_CAP,
            &mut segs,
            &mut counts,
        )
        .is_err()
        {
            let at = (id.lembo, id.piece, j);
            cap_error = Some(cap_error.map_or(at, |e| e.min(at)));
            continue;
        }
        for &segment in &segs {
            ctx.emit(cost, next_port, ScanSegment { id, j, segment })
                .await;
            next_port = ctx.next_port(next_port);
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
