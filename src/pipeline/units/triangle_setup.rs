//! TriangleSetup (the triangle path, DESIGN.md §5): projects a triangle's three vertices,
//! clips it in clip space to the near and far planes when it crosses one, and to the guard
//! band when a vertex (of what is left) is beyond the 16.8 range, snaps the vertices to 16.8
//! fixed point, sets up the integer edge functions and the perspective-correct attribute
//! planes, and culls (one test per triangle, or per piece of a clipped one).
//!
//! Input: the triangles (the tessellated scene), in their source's order (the unit is the
//! source: the Tessellator's output is read from memory, so the unit is never starved until
//! it runs out); with `triangle_setup.count` instances, each reads the batches of
//! `triangle_setup.batch` triangles dealt to it ([`Deal`]). Output: each set-up triangle,
//! or each piece of a clipped one (with its parent's id), round-robin to the triangle
//! rasterizers.
//!
//! Cost: `triangle_setup.cycles_per_triangle` busy cycles per triangle, culled or not, plus
//! `triangle_setup.cycles_per_clipped_piece` per triangle of a clipped triangle's fan
//! (clipped at the near or far plane, the guard band, or both: one fan), culled or not (the fan's culled triangles are spent before its first piece is emitted);
//! a result is ready `triangle_setup.latency_cycles` after the operation that produces it.
//! Not modelled: vertex fetch and the post-transform vertex cache (each triangle's three
//! vertices are transformed here).

use crate::camera::View;
use crate::config::TriangleSetupConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::deal::Deal;
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, Run, Unit};
use crate::raster::triangle::{setup, ScreenTriangle, TriangleSource};
use crate::raster::Counts;
use std::sync::Arc;

/// The triangle path's setup unit.
pub struct TriangleSetup;

impl<R: Real> Unit<R> for TriangleSetup {
    const KIND: UnitKind = UnitKind::TriangleSetup;
    type In = ();
    type Out = Arc<ScreenTriangle<R>>;
    // The set-up triangle: edge functions (12), depths and 1/w (6), normals and positions
    // over w (18), bounding box (4), area and id.
    const OUT_WORDS: u32 = 42;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a Run<'a, R>,
        index: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(
            ctx,
            &run.arch.triangle_setup,
            index,
            run.triangles,
            run.view,
        ))
    }
}

/// TriangleSetup's body: instance `index`'s triangles of the source (its batches,
/// [`Deal`]) in order, set up (clipped and fanned where needed).
pub async fn run<R: Real>(
    mut ctx: Ctx<(), Arc<ScreenTriangle<R>>>,
    cfg: &TriangleSetupConfig,
    index: usize,
    source: &dyn TriangleSource,
    view: &View,
) -> Finished {
    let per_triangle = cfg.cycles_per_triangle;
    let per_piece = cfg.cycles_per_clipped_piece;
    let mut counts = Counts::default();
    let (mut triangles, mut pieces) = (Vec::new(), Vec::new());
    let mut next = 0;
    let mine = Deal::new(index, cfg.count, cfg.batch);
    let per_chunk = source.per_chunk();
    for c in 0..source.chunks() {
        let first = c as u64 * per_chunk;
        if !mine.takes_any(first, per_chunk) {
            continue;
        }
        source.chunk(c, &mut triangles);
        for (k, t) in triangles.iter().enumerate() {
            if !mine.takes(first + k as u64) {
                continue;
            }
            let id = source.id(c, k);
            let outcome = setup::<R>(id, &t.positions, &t.normals, t.color, view, &mut pieces);
            outcome.count(&mut counts);
            let culled_in_fan = outcome.fan.saturating_sub(pieces.len()) as u64;
            let mut cost = per_triangle + per_piece * culled_in_fan;
            if pieces.is_empty() {
                ctx.work(cost);
            }
            for st in pieces.drain(..) {
                if outcome.fan > 0 {
                    cost += per_piece;
                }
                ctx.emit(cost, next, Arc::new(st)).await;
                next = ctx.next_port(next);
                cost = 0;
            }
        }
    }
    Finished::new(ctx, counts)
}
