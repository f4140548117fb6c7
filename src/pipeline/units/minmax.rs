//! MinMax finder (Martinelli 2006 section 5, "the first step ... is to find the minimum and the
//! maximum of y"): the y range of a lembo over its domain (corners, edge extrema, interior
//! critical point) and the scanlines it covers, clipped to the viewport.
//!
//! Input: [`LemboReady`] from Setup. Output: [`ScanlineRange`] to the IntervalManager, or
//! nothing when the range holds no scanline centre (counted as culled outside).
//!
//! When the run culls back faces (`minmax.cull_backfaces`, resolved per scene into the
//! view's [`crate::camera::Culling`]), MinMax first tests whether the piece faces
//! away from the eye over its whole surface ([`facing`]) and drops it if so (counted as
//! culled back-facing): Figure 5's MinMax is the unit that culls, and it holds the piece's
//! world-space position function that the test needs, after Setup's split, so a piece of a
//! split lembo is tested on its own.
//!
//! Cost: `minmax.cycles_per_lembo` per lembo, and `minmax.cull_cycles_per_lembo` more when
//! the run culls back faces (the test, culled or not); ready `minmax.latency_cycles` later.

use crate::camera::{Culling, View};
use crate::config::MinMaxConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::{LemboReady, ScanlineRange};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::{facing, minmax, Counts};

/// The MinMax finder, Figure 5's second box.
pub struct MinMax;

impl<R: Real> Unit<R> for MinMax {
    const KIND: UnitKind = UnitKind::MinMax;
    type In = LemboReady<R>;
    type Out = ScanlineRange<R>;
    // The screen lembo (40) with its first and last scanline (2).
    const OUT_WORDS: u32 = 42;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(ctx, &run.arch.minmax, run.view))
    }
}

/// The MinMax finder's body: per lembo piece, its back-face cull when `view` culls, then
/// its scanline range (or a cull) on `view`'s viewport.
pub async fn run<R: Real>(
    mut ctx: Ctx<LemboReady<R>, ScanlineRange<R>>,
    cfg: &MinMaxConfig,
    view: &View,
) -> Finished {
    let culls = view.culling != Culling::Off;
    let cost = cfg.cycles_per_lembo + if culls { cfg.cull_cycles_per_lembo } else { 0 };
    let height = view.viewport.height;
    let mut counts = Counts::default();
    while let Some(LemboReady { piece }) = ctx.next_input().await {
        if facing::faces_away(&piece.screen, view) {
            counts.lembos_culled_backface += 1;
            ctx.work(cost);
            continue;
        }
        match minmax::scanlines(&piece.screen, height) {
            Some((j0, j1)) => {
                ctx.emit(cost, ScanlineRange { piece, j0, j1 }).await;
            }
            None => {
                counts.lembos_culled_outside += 1;
                ctx.work(cost);
            }
        }
    }
    Finished::new(ctx, counts)
}
