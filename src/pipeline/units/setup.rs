//! Setup (Martinelli 2006 section 4, Figure 5's first unit): projects a lembo's six reference
//! points, rebuilds the screen-space coefficients of x, y and depth with the paper's linear
//! transform, and culls lembos outside the viewport or behind the eye (one cull test each).
//!
//! Input: the batches of lembos the geometry fetch ([`super::fetch`]) read from memory and
//! dealt to this engine ([`MemAccess`]: the first lembo and the count), in scene order.
//! Output: [`LemboReady`] per visible lembo to the MinMax units, round-robin, carrying the
//! [`ScreenLembo`](crate::raster::setup::ScreenLembo) behind a shared pointer, as a hardware
//! setup unit writes a primitive's coefficients into a parameter buffer that later stages
//! index; the screen form is dropped with the last item in flight that points at it.
//!
//! A lembo whose hull reaches far beyond the viewport is split into pieces
//! ([`setup_pieces`]); each piece goes down the pipeline as a lembo does.
//!
//! Cost: `setup.cycles_per_lembo` busy cycles per lembo, culled or not, and as many again
//! per sub-patch a split examines; a further piece of a split lembo is emitted at 1 cycle
//! (it was computed with the split). The result is ready `setup.latency_cycles` later.

use crate::camera::View;
use crate::config::SetupConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::lembo::set::LastParent;
use crate::pipeline::items::{LemboReady, MemAccess, Piece, PieceId};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::setup::setup_pieces;
use crate::raster::Counts;
use crate::scene::Scene;
use std::sync::Arc;

/// Setup, Figure 5's first box.
pub struct Setup;

impl<R: Real> Unit<R> for Setup {
    const KIND: UnitKind = UnitKind::Setup;
    type In = MemAccess;
    type Out = LemboReady<R>;
    // The screen lembo: x, y, z and the normal as six-coefficient quadratics (36 words),
    // its colour (3) and id (1).
    const OUT_WORDS: u32 = 40;

    fn batch(arch: &crate::config::ArchConfig) -> Option<u32> {
        Some(arch.setup.batch)
    }

    fn spawn<'a>(
        ctx: Ctx<MemAccess, LemboReady<R>>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(
            ctx,
            &run.arch.setup,
            run.scene,
            run.view,
            run.perspective_tol,
        ))
    }
}

/// Setup's body: the batches of lembos of `scene` the geometry fetch dealt it, in order,
/// projected (and split or clipped) into pieces.
pub async fn run<R: Real>(
    mut ctx: Ctx<MemAccess, LemboReady<R>>,
    cfg: &SetupConfig,
    scene: &Scene,
    view: &View,
    perspective_tol: Option<f64>,
) -> Finished {
    let cost = cfg.cycles_per_lembo;
    let mut counts = Counts::default();
    let mut pieces = Vec::new();
    // Each lembo of the batches dealt to this engine, made as it is taken (the others'
    // lembos are not made here).
    let (starts, mut last) = (scene.lembo_index(), LastParent::default());
    while let Some(MemAccess { first, count, .. }) = ctx.next_input().await {
        for id in first as usize..first as usize + count as usize {
            let (lembo, color) = scene.lembo_near(&starts, id, &mut last);
            counts.lembos += 1;
            match setup_pieces::<R>(id as u32, &lembo, color, view, perspective_tol, &mut pieces) {
                Ok(split) => {
                    counts.add_split(split, pieces.len());
                    // Each sub-patch examined is set up as a lembo is (six points
                    // evaluated, hull tested); the lembo's own cost comes with its first
                    // emission.
                    let n = pieces.len();
                    let mut owed = cost * (1 + split.examined as u64);
                    for (k, screen) in pieces.drain(..).enumerate() {
                        let id = PieceId {
                            lembo: id as u32,
                            piece: k as u32,
                        };
                        let piece = Piece {
                            id,
                            screen: Arc::new(screen),
                        };
                        ctx.emit(owed.max(1), LemboReady { piece }).await;
                        owed = 0;
                    }
                    if n == 0 {
                        ctx.work(owed);
                    }
                }
                Err(cull) => {
                    counts.add_cull(cull);
                    ctx.work(cost);
                }
            }
        }
    }
    Finished::new(ctx, counts)
}
