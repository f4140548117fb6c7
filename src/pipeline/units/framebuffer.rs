//! The frame-buffer memory port (DESIGN.md §3): the ROPs' depth reads and colour and depth
//! writes share one port of `framebuffer.bytes_per_cycle`. The frame ends when the last
//! write has gone through it.
//!
//! Input: [`MemAccess`]es from every ROP, merged by (arrival, port). Output: none. Cost:
//! ceil(bytes / bytes_per_cycle) per access (at least one cycle); with more than one sample
//! per pixel, the resolve after the last access: every sample's colour read and every
//! pixel's written, at the same rate. Not modelled: DRAM pages,
//! refresh, compression, caches, and the geometry fetch's share of the port
//! (`fetch.rs`).

use crate::config::FrameBufferConfig;
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::pipeline::items::MemAccess;
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::{ceil_div, Ctx};
use crate::pipeline::unit::{Finished, Run, Unit};
use crate::raster::Counts;

/// The frame-buffer memory port.
pub struct FrameBuffer;

impl<R: Real> Unit<R> for FrameBuffer {
    const KIND: UnitKind = UnitKind::FrameBuffer;
    type In = MemAccess;
    type Out = ();
    // A sink: no output links.
    const OUT_WORDS: u32 = 0;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a Run<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        let vp = run.view.viewport;
        let samples = run.view.samples;
        let resolve =
            crate::rop::FrameBuffer::resolve_bytes(vp.width, vp.height / samples.get(), samples);
        Box::pin(self::run(ctx, &run.arch.framebuffer, resolve))
    }
}

/// The memory port's body: every access through the port at its byte rate, then the
/// multisample resolve's `resolve_bytes` (0 with one sample per pixel: no resolve).
pub async fn run(
    mut ctx: Ctx<MemAccess, ()>,
    cfg: &FrameBufferConfig,
    resolve_bytes: u64,
) -> Finished {
    while let Some(MemAccess { bytes, .. }) = ctx.next_input().await {
        ctx.work(ceil_div(bytes, cfg.bytes_per_cycle).max(1));
    }
    if resolve_bytes > 0 {
        // The resolve reads every sample's colour and writes each pixel once the last
        // write is in.
        ctx.work(ceil_div(resolve_bytes, cfg.bytes_per_cycle));
    }
    Finished::new(ctx, Counts::default())
}
