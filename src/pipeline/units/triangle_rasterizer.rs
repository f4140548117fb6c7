//! TriangleRasterizer (the triangle path, DESIGN.md §5): tests 2x2 quads against the integer
//! edge functions with the top-left fill rule.
//!
//! Input: set-up triangles from TriangleSetup (round-robin). Output: [`TrianglePiece`]s,
//! the covered pixels of one quad row (two pixel rows) inside one ROP tile, each routed to
//! the ROP that owns the tile. A piece carries the triangle; the ROP evaluates each
//! fragment from the triangle and the pixel alone
//! ([`ScreenTriangle::fragment`]), so its fragments are bit-identical to the functional
//! model's.
//!
//! Cost: ceil(4 q / `triangle_rasterizer.pixels_per_cycle`) cycles per piece of q quads, at
//! least one; a triangle with no covered pixel costs one cycle (its bounding-box test).
//! Quads with no covered pixel are skipped for free, as a hierarchical rasterizer rejects
//! them by tile. Ready `latency_cycles` later.

use crate::config::TriangleRasterizerConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::{RopItem, TrianglePiece};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::{ceil_div, Ctx};
use crate::pipeline::tiles::RopTiles;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::triangle::{quads_in, ScreenTriangle};
use crate::raster::Counts;
use std::sync::Arc;

/// A triangle path's quad rasterizer.
pub struct TriangleRasterizer;

impl<R: Real> Unit<R> for TriangleRasterizer {
    const KIND: UnitKind = UnitKind::TriangleRasterizer;
    type In = Arc<ScreenTriangle<R>>;
    type Out = RopItem<R>;
    // A fragment's pixel (2), depth, normal (3), position (3) and triangle id.
    const OUT_WORDS: u32 = 10;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(ctx, &run.arch.triangle_rasterizer, &run.tiles))
    }
}

/// `span` clipped to columns [lo, hi).
fn clip((a, b): (u32, u32), lo: u32, hi: u32) -> (u32, u32) {
    let (a, b) = (a.max(lo), b.min(hi));
    if a < b {
        (a, b)
    } else {
        (0, 0)
    }
}

/// A TriangleRasterizer's body: per triangle, its quads in two-row pieces, one per ROP tile
/// crossed.
pub async fn run<R: Real>(
    mut ctx: Ctx<Arc<ScreenTriangle<R>>, RopItem<R>>,
    cfg: &TriangleRasterizerConfig,
    tiles: &RopTiles,
) -> Finished {
    let ppc = cfg.pixels_per_cycle;
    let tile = tiles.tile_px;
    let mut counts = Counts::default();
    while let Some(tri) = ctx.next_input().await {
        let [_, _, j0, j1] = tri.bbox;
        let mut emitted = false;
        let mut qj = j0 & !1;
        while qj < j1 {
            let rows = [tri.row_span(qj), tri.row_span(qj + 1)];
            counts.quads += quads_in(&rows);
            let live = || rows.iter().filter(|r| r.0 < r.1);
            let (Some(lo), Some(hi)) = (live().map(|r| r.0).min(), live().map(|r| r.1).max())
            else {
                qj += 2;
                continue;
            };
            counts.fragments += live().map(|r| (r.1 - r.0) as u64).sum::<u64>();
            // Rows j and j + 1 share a tile row unless a tile border runs between them.
            let split = qj / tile != (qj + 1) / tile;
            let mut i = lo;
            while i < hi {
                let end = ((i / tile + 1) * tile).min(hi);
                let both = [clip(rows[0], i, end), clip(rows[1], i, end)];
                let pieces = if split {
                    [[both[0], (0, 0)], [(0, 0), both[1]]]
                } else {
                    [both, [(0, 0); 2]]
                };
                for piece in pieces {
                    let piece = TrianglePiece {
                        tri: tri.clone(),
                        j: qj,
                        rows: piece,
                    };
                    if piece.is_empty() {
                        continue;
                    }
                    let cycles = ceil_div(4 * quads_in(&piece.rows), ppc).max(1);
                    ctx.emit(cycles, RopItem::Triangle(piece)).await;
                    emitted = true;
                }
                i = end;
            }
            qj += 2;
        }
        if !emitted {
            ctx.work(1);
        }
    }
    Finished::new(ctx, counts)
}
