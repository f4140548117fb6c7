//! DomainEval (the `onchip` triangle source, DESIGN.md §5): evaluates each domain point of
//! a lembo's tessellation, its position and unit normal, from the lembo's quadratic
//! functions (a DX11 domain shader's work), and passes the lembo's triangles on in batches
//! of the setup engines' `batch` (which its boundary hands it), batch after batch to the triangle setup engines in turn. The
//! vertices are the functional model's ([`crate::lembo::tessellate`]), evaluated where
//! TriangleSetup reads them; this unit adds only time.
//!
//! Input: [`Patch`]es from the tessellators. Output: per batch one [`MemAccess`] naming
//! the batch's triangles (the first and the count; no bytes: they come from this unit's
//! output buffer, not memory).
//!
//! Cost: `domain_eval.cycles_per_vertex` busy cycles per domain point (a multiple of 1/64:
//! 0.5 is two points a cycle), (n + 1)(n + 2)/2 a lembo (patches are independent: a point
//! on an edge two lembos share is evaluated by both), spent batch by batch in proportion to
//! the triangles each batch holds (the batch holding the first p points of its lembo ends
//! at ceil(p * cycles_per_vertex) cycles into the lembo), at least one cycle a batch; a batch is ready `domain_eval.latency_cycles` after its last point.
//! Not modelled: the output buffer holding a lembo's evaluated vertices until setup reads
//! them (its area and energy).

use crate::config::DomainEvalConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::{MemAccess, Patch};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::unit::{Finished, RunInputs, Unit};
use crate::raster::triangle::TriangleSource;
use crate::raster::Counts;

/// The on-chip domain evaluator.
pub struct DomainEval;

impl<R: Real> Unit<R> for DomainEval {
    const KIND: UnitKind = UnitKind::DomainEval;
    type In = Patch;
    type Out = MemAccess;
    // A batch: its first triangle and count, and where its vertices sit in the output
    // buffer.
    const OUT_WORDS: u32 = 3;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        Box::pin(self::run(ctx, &run.arch.domain_eval, run.triangles))
    }
}

/// DomainEval's body: each patch's points evaluated and its triangles passed on in batches
/// of the setup engines' batch (its boundary's), to the engines in turn.
pub async fn run(
    mut ctx: Ctx<Patch, MemAccess>,
    cfg: &DomainEvalConfig,
    source: &dyn TriangleSource,
) -> Finished {
    let batch = ctx.batch().expect("DomainEval's boundary deals batches");
    let triangles = source.per_chunk();
    let vertices = source.vertices_per_chunk();
    // The points evaluated once the first `t` triangles of a patch are out: their share.
    let points = |t: u64| (vertices as u128 * t as u128 / triangles.max(1) as u128) as u64;
    while let Some(Patch { lembo }) = ctx.next_input().await {
        let base = u64::from(lembo) * triangles;
        let mut done = 0;
        while done < triangles {
            let end = (done + u64::from(batch)).min(triangles);
            let rate = cfg.cycles_per_vertex;
            let cycles = rate.ceil_mul(points(end)) - rate.ceil_mul(points(done));
            let access = MemAccess::batch((base + done) as u32, (end - done) as u32, 0, 0);
            ctx.emit(cycles.max(1), access).await;
            done = end;
        }
    }
    Finished::new(ctx, Counts::default())
}
