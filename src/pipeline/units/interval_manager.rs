//! IntervalManager (Martinelli 2006 section 5.1): for each scanline y_j of a lembo, the roots of
//! Y(u, v) = y_j on the three domain edges (and the virtual roots at the tips of a closed
//! loop), paired into intervals: the pieces of the curve the segmenters walk.
//!
//! Input: [`ScanlineRange`] from MinMax. Output: one [`ScanInterval`] per interval,
//! dispatched round-robin over the segmenters (deterministic: the n-th interval this unit
//! emits goes to segmenter n mod Ns).
//!
//! Cost: a pipelined quadratic solver, `interval_manager.cycles_per_scanline` per scanline
//! (three edges, one root pair per cycle by default) plus `cycles_per_interval` per
//! interval emitted; ready `latency_cycles` after issue. Not modelled: the small sort of
//! the roots by walk key, taken as part of the per-interval cycle.

use super::minmax::ScanlineRange;
use crate::datapath::Real;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::{Finished, PieceId, Shared};
use crate::raster::interval::{intervals, Interval, IntervalScratch};
use crate::raster::Counts;

/// One interval of scanline `j` of lembo `id`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanInterval<R> {
    /// The lembo piece.
    pub id: PieceId,
    /// The scanline.
    pub j: u32,
    /// The piece of the curve Y = y_j to walk.
    pub interval: Interval<R>,
}

/// The IntervalManager's body: per lembo piece, per scanline of its range, the intervals,
/// dispatched round-robin to the segmenters.
pub async fn run<R: Real>(
    mut ctx: Ctx<ScanlineRange, ScanInterval<R>>,
    sh: &Shared<'_, R>,
) -> Finished {
    let cfg = &sh.arch.interval_manager;
    let mut counts = Counts::default();
    let mut scratch = IntervalScratch::default();
    let mut ivs = Vec::new();
    let mut next_port = 0;
    while let Some(ScanlineRange { id, j0, j1 }) = ctx.next_input().await {
        let l = sh.lembo(id);
        for j in j0..=j1 {
            counts.scanlines += 1;
            ctx.work(cfg.cycles_per_scanline);
            ivs.clear();
            intervals(l, j, sh.k, &mut scratch, &mut ivs, &mut counts);
            for &interval in &ivs {
                ctx.emit(
                    cfg.cycles_per_interval,
                    next_port,
                    ScanInterval { id, j, interval },
                )
                .await;
                next_port = ctx.next_port(next_port);
            }
        }
    }
    Finished::new(ctx, counts)
}
