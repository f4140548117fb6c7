//! TriangleSetup (the triangle path, DESIGN.md §5): projects a triangle's three vertices,
//! clips it in clip space to the near and far planes when it crosses one, and to the guard
//! band when a vertex (of what is left) is beyond the 16.8 range, snaps the vertices to 16.8
//! fixed point, sets up the integer edge functions and the perspective-correct attribute
//! planes, and culls (one test per triangle, or per piece of a clipped one).
//!
//! Input: the batches of triangles the geometry fetch ([`super::fetch`]) read from a mesh in
//! memory, or a domain evaluator ([`super::domain_eval`]) made on chip, dealt to this engine
//! ([`MemAccess`]: the first triangle and the count), in the order they arrive. Output: each set-up triangle, or each
//! piece of a clipped one (with its parent's id), round-robin to the triangle rasterizers.
//!
//! Cost: `triangle_setup.cycles_per_triangle` busy cycles per triangle drawn or clipped, and
//! per `triangle_setup.culled_per_cycle` triangles culled whole (a leftover group costs the
//! full slot at the end), plus
//! `triangle_setup.cycles_per_clipped_piece` per triangle of a clipped triangle's fan
//! (clipped at the near or far plane, the guard band, or both: one fan), culled or not (the fan's culled triangles are spent before its first piece is emitted);
//! a result is ready `triangle_setup.latency_cycles` after the operation that produces it.
//! The post-transform vertex cache is the fetch's account (it reads the vertices the cache
//! misses); the functional setup here projects each triangle's three vertices, so its
//! operation counts are those of a cache that never hits.

use crate::camera::View;
use crate::config::TriangleSetupConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::MemAccess;
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::triangle::{setup, ScreenTriangle, TriangleSource};
use crate::raster::Counts;
use std::sync::Arc;

/// The triangle path's setup unit.
pub struct TriangleSetup;

impl<R: Real> Unit<R> for TriangleSetup {
    const KIND: UnitKind = UnitKind::TriangleSetup;
    type In = MemAccess;
    type Out = Arc<ScreenTriangle<R>>;
    // The set-up triangle: edge functions (12), depths and 1/w (6), normals and positions
    // over w (18), bounding box (4), area and id.
    const OUT_WORDS: u32 = 42;

    fn batch(arch: &crate::config::ArchConfig) -> Option<u32> {
        Some(arch.triangle_setup.batch)
    }

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(
            ctx,
            &run.arch.triangle_setup,
            run.triangles,
            run.view,
        ))
    }
}

/// TriangleSetup's body: the batches of the source's triangles the geometry fetch dealt it,
/// in order, set up (clipped and fanned where needed).
pub async fn run<R: Real>(
    mut ctx: Ctx<MemAccess, Arc<ScreenTriangle<R>>>,
    cfg: &TriangleSetupConfig,
    source: &dyn TriangleSource,
    view: &View,
) -> Finished {
    let per_triangle = cfg.cycles_per_triangle;
    let per_piece = cfg.cycles_per_clipped_piece;
    // Whole culled triangles since the engine last spent `per_triangle` on them.
    let mut culled = 0;
    let mut counts = Counts::default();
    let (mut triangles, mut pieces) = (Vec::new(), Vec::new());
    let per_chunk = source.per_chunk().max(1);
    // The chunk in `triangles`, if any.
    let mut held = None;
    while let Some(MemAccess { first, count, .. }) = ctx.next_input().await {
        for t in first as u64..first as u64 + count as u64 {
            let (c, k) = ((t / per_chunk) as usize, (t % per_chunk) as usize);
            if held != Some(c) {
                source.chunk(c, &mut triangles);
                held = Some(c);
            }
            let t = &triangles[k];
            let id = source.id(c, k);
            let outcome = setup::<R>(id, &t.positions, &t.normals, t.color, view, &mut pieces);
            outcome.count(&mut counts);
            let culled_in_fan = outcome.fan.saturating_sub(pieces.len()) as u64;
            let mut cost = per_triangle + per_piece * culled_in_fan;
            if pieces.is_empty() && outcome.fan == 0 {
                // Culled whole: `culled_per_cycle` of them share the engine's slot.
                culled += 1;
                if culled == cfg.culled_per_cycle {
                    ctx.work(per_triangle);
                    culled = 0;
                }
            } else if pieces.is_empty() {
                ctx.work(cost);
            }
            for st in pieces.drain(..) {
                if outcome.fan > 0 {
                    cost += per_piece;
                }
                ctx.emit(cost, Arc::new(st)).await;
                cost = 0;
            }
        }
    }
    if culled > 0 {
        ctx.work(per_triangle);
    }
    Finished::new(ctx, counts)
}
