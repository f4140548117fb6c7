//! Tessellator (the `onchip` triangle source, DESIGN.md §5): makes each lembo's n² domain
//! triangles and their domain points, as the fixed-function tessellator between a DX11
//! GPU's hull and domain shaders does. The triangles and their vertices are the same as a
//! mesh tessellated in memory would hold ([`crate::lembo::tessellate`]); the functional
//! model evaluates them where TriangleSetup reads them, so this unit adds only time.
//!
//! Input: the batches of lembos the geometry fetch read and dealt it ([`MemAccess`]: the
//! first lembo and the count). Output: each lembo as a [`Patch`], round-robin to the
//! domain evaluators.
//!
//! Cost: `tessellator.cycles_per_triangle` busy cycles per domain triangle, a multiple of
//! 1/64 (0.5: two triangles a cycle), n² a lembo: ceil(n² * cycles_per_triangle), at least
//! one;
//! a patch is ready `tessellator.latency_cycles` after its last triangle is issued.

use crate::config::TessellatorConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::{MemAccess, Patch};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::Counts;

/// The on-chip tessellator.
pub struct Tessellator;

impl<R: Real> Unit<R> for Tessellator {
    const KIND: UnitKind = UnitKind::Tessellator;
    type In = MemAccess;
    type Out = Patch;
    // The lembo the domain evaluator reads: six points and six normals (36 words, its
    // patch constants) and its id.
    const OUT_WORDS: u32 = 37;

    fn batch(arch: &crate::config::ArchConfig) -> Option<u32> {
        Some(arch.tessellator.batch)
    }

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(
            ctx,
            &run.arch.tessellator,
            run.triangles.per_chunk(),
        ))
    }
}

/// The Tessellator's body: each lembo of each batch dealt it, `triangles` domain triangles
/// apiece, to the domain evaluators in turn.
pub async fn run(
    mut ctx: Ctx<MemAccess, Patch>,
    cfg: &TessellatorConfig,
    triangles: u64,
) -> Finished {
    while let Some(MemAccess { first, count, .. }) = ctx.next_input().await {
        for lembo in first..first + count {
            let cycles = cfg.cycles_per_triangle.ceil_mul(triangles).max(1);
            ctx.emit(cycles, Patch { lembo }).await;
        }
    }
    Finished::new(ctx, Counts::default())
}
