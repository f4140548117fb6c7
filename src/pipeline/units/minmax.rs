//! MinMax finder (Martinelli 2006 section 5, "the first step ... is to find the minimum and the
//! maximum of y"): the y range of a lembo over its domain (corners, edge extrema, interior
//! critical point) and the scanlines it covers, clipped to the viewport.
//!
//! Input: [`LemboReady`] from Setup. Output: [`ScanlineRange`] to the IntervalManager, or
//! nothing when the range holds no scanline centre (counted as culled outside).
//!
//! Cost: `minmax.cycles_per_lembo` per lembo, ready `minmax.latency_cycles` later.

use super::setup::LemboReady;
use crate::datapath::Real;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::{Finished, PieceId, Shared};
use crate::raster::{minmax, Counts};

/// The scanlines j0..=j1 of lembo `id`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScanlineRange {
    /// The lembo piece.
    pub id: PieceId,
    /// The first scanline it covers.
    pub j0: u32,
    /// The last scanline it covers.
    pub j1: u32,
}

/// The MinMax finder's body: per lembo piece, its scanline range (or a cull).
pub async fn run<R: Real>(mut ctx: Ctx<LemboReady, ScanlineRange>, sh: &Shared<'_, R>) -> Finished {
    let cost = sh.arch.minmax.cycles_per_lembo;
    let mut counts = Counts::default();
    // Whole lembos (pieces) to the interval managers, round-robin.
    let mut next_port = 0;
    while let Some(LemboReady { id }) = ctx.next_input().await {
        let l = sh.lembo(id);
        match minmax::scanlines(l, sh.view.viewport.height) {
            Some((j0, j1)) => {
                ctx.emit(cost, next_port, ScanlineRange { id, j0, j1 })
                    .await;
                next_port = ctx.next_port(next_port);
            }
            None => {
                counts.lembos_culled_outside += 1;
                ctx.work(cost);
            }
        }
    }
    Finished::new(ctx, counts)
}
