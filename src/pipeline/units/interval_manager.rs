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

use crate::config::IntervalManagerConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::{ScanInterval, ScanlineRange};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::interval::{intervals, IntervalScratch};
use crate::raster::Counts;

/// The interval manager, Figure 5's third box.
pub struct IntervalManager;

impl<R: Real> Unit<R> for IntervalManager {
    const KIND: UnitKind = UnitKind::IntervalManager;
    type In = ScanlineRange<R>;
    type Out = ScanInterval<R>;
    // Two roots (u, v), the walk direction (2), the scanline and lembo id.
    const OUT_WORDS: u32 = 8;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(ctx, &run.arch.interval_manager, run.k))
    }
}

/// The IntervalManager's body: per lembo piece, per scanline of its range, the intervals,
/// dispatched round-robin to the segmenters.
pub async fn run<R: Real>(
    mut ctx: Ctx<ScanlineRange<R>, ScanInterval<R>>,
    cfg: &IntervalManagerConfig,
    k: R,
) -> Finished {
    let mut counts = Counts::default();
    let mut scratch = IntervalScratch::default();
    let mut ivs = Vec::new();
    while let Some(ScanlineRange { piece, j0, j1 }) = ctx.next_input().await {
        let l = &*piece.screen;
        for j in j0..=j1 {
            counts.scanlines += 1;
            ctx.work(cfg.cycles_per_scanline);
            ivs.clear();
            intervals(l, j, k, &mut scratch, &mut ivs, &mut counts);
            for &interval in &ivs {
                ctx.emit(
                    cfg.cycles_per_interval,
                    ScanInterval {
                        piece: piece.clone(),
                        j,
                        interval,
                    },
                )
                .await;
            }
        }
    }
    Finished::new(ctx, counts)
}
