//! Rop (DESIGN.md §2 and §3; Piranda et al. 2006 section 4 for the ROP's place): the depth test and
//! the frame-buffer write, Np units screen-interleaved by tiles.
//!
//! Input: [`RopItem`]s from every rasterizer, merged by (arrival, port): lembo
//! [`FragmentSpan`]s, or [`TrianglePiece`]s in the triangle path. For each fragment: its
//! depth (from the lembo's depth quadratic, or the triangle's plane), the depth test on
//! (z, id) (the winner does not depend on arrival order), and for a fragment that passes,
//! Phong shading (Piranda et al. 2006 equation 6) and the write. Output: one [`MemAccess`] per
//! item to the frame-buffer memory port: depth reads for every fragment tested, colour and depth
//! writes for every fragment that passed.
//!
//! Storage: each ROP owns the pixels of its tiles ([`RopTiles`](crate::pipeline::tiles::RopTiles)) and writes them in place
//! in the one frame buffer ([`SharedFrame`](crate::pipeline::tiles::SharedFrame)); the ROPs never share a pixel.
//!
//! Cost: ceil(n / `rop.fragments_per_cycle`) per span of n fragments, ready
//! `latency_cycles` later. With the DRAM memory model (`memory.model = "dram"`) the ROP
//! also has its colour and depth caches ([`RopMemory`]): a span costs at least the sectors
//! it touches in either over `memory.cache_sectors_per_cycle`, one cycle when hierarchical
//! Z rejects it, and its output carries the caches' fills and write-backs; once the end of
//! its inputs reaches it, it writes its caches back (and resolves its tiles when
//! multisampled).

use crate::camera::{Samples, View};
use crate::config::{FrameBufferConfig, MemoryModel, RopConfig};
use crate::datapath::Real;
use crate::discoid::report::BlendReport;
use crate::frame::discoid::{
    accumulation_keeps, depth_pass_wins, evaluate, DiscoidFragment, KeptFragment, Pass,
};
use crate::graph::UnitKind;
use crate::pipeline::items::{FragmentSpan, LineTransfer, MemAccess, RopItem, TrianglePiece};
use crate::pipeline::rop_memory::RopMemory;
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::Ctx;
use crate::pipeline::tiles::RopPixels;
use crate::pipeline::unit::{DiscoidPass, Finished, RunInputs, Unit, UnitReport};
use crate::raster::Counts;
use crate::rop::fragment_shader::FragmentShader;
use crate::rop::sink::Batch;

/// A ROP.
pub struct Rop;

impl<R: Real> Unit<R> for Rop {
    const KIND: UnitKind = UnitKind::Rop;
    type In = RopItem<R>;
    type Out = MemAccess;
    // A write request: address and colour with depth.
    const OUT_WORDS: u32 = 3;

    fn spawn<'a>(
        ctx: Ctx<RopItem<R>, MemAccess>,
        run: &'a RunInputs<'a, R>,
        index: usize,
    ) -> UnitFuture<'a, Finished> {
        let vp = run.view.viewport;
        // The builder checked the memory fields (`memory::check` and the ROP tiles).
        let caches = (run.arch.memory.model == MemoryModel::Dram).then(|| {
            RopMemory::new(
                &run.arch.memory,
                vp.width,
                vp.height,
                run.view.samples.get(),
            )
            .expect("the memory fields were checked when the run was built")
        });
        Box::pin(self::run(
            ctx,
            RopContext {
                cfg: &run.arch.rop,
                memory: run.port,
                // SAFETY: the builder makes one ROP unit per index, each with the run's
                // tiles, over a frame of the viewport's width.
                pixels: unsafe {
                    RopPixels::new(&run.frame, &run.tiles, index, run.view.viewport.width)
                },
                shader: FragmentShader::<R>::new(&run.scene.light, run.view),
                view: run.view,
                discoid: run.discoid.as_ref(),
                caches,
            },
        ))
    }
}

/// What a ROP works with: its configuration and the memory port's, its own pixels, the
/// shader, and the discoid pass when there is one.
pub struct RopContext<'a, R> {
    /// Its rate.
    pub cfg: &'a RopConfig,
    /// The bytes a fragment moves through the frame-buffer port.
    pub memory: &'a FrameBufferConfig,
    /// The pixels of its tiles.
    pub pixels: RopPixels<'a, 'a>,
    /// The fragment shader (the scene's light seen from the camera).
    pub shader: FragmentShader<R>,
    /// The camera, for the accumulation pass's threshold.
    pub view: &'a View,
    /// The discoid pass it runs; None for ordinary rendering.
    pub discoid: Option<&'a DiscoidPass<'a, R>>,
    /// Its colour and depth caches, with the DRAM memory model.
    pub caches: Option<RopMemory>,
}

/// Where a batch's colours go: this ROP's pixels.
fn into<'b, 'a: 'b, 'f: 'a, R>(
    pixels: &'b mut RopPixels<'a, 'f>,
) -> impl FnMut(usize, [u8; 3], [R; 3]) + use<'a, 'b, 'f, R> {
    // SAFETY: a batch holds only pixels whose depth test passed, each in a run `row` admitted
    // (`lembo_fragments`, `triangle_fragments`).
    move |idx, rgb, _| unsafe { pixels.set_color(idx, rgb) }
}

/// A discoid pass's work on one fragment at pixel index `idx`: returns whether it passed
/// (the depth pass) or was kept (the accumulation pass).
///
/// # Safety
/// `idx` is a pixel of a run `pixels.row` admitted ([`RopPixels::depth`]).
#[allow(clippy::too_many_arguments)]
#[inline]
unsafe fn discoid_fragment<R: Real>(
    dp: &DiscoidPass<R>,
    view: &View,
    shader: &FragmentShader<R>,
    pixels: &mut RopPixels,
    kept: &mut (Vec<KeptFragment>, BlendReport),
    idx: usize,
    f: &DiscoidFragment<R>,
) -> bool {
    let e = evaluate(dp.table, shader, f);
    match dp.pass {
        Pass::Depth => {
            // SAFETY: the caller's promise, passed on.
            let (depth, winner) = unsafe { (pixels.depth(idx), pixels.primitive(idx)) };
            let wins = depth_pass_wins(&e, f.id, depth, winner);
            if wins {
                // SAFETY: as above.
                unsafe { pixels.set_depth(idx, e.z, f.id) };
            }
            wins
        }
        Pass::Accumulate => {
            let (depth, winner) = (dp.depth[idx], dp.winner[idx]);
            match accumulation_keeps(&mut kept.1, view, shader, dp.threshold, &e, depth, winner) {
                Some(input) => {
                    kept.0.push(KeptFragment {
                        idx: idx as u32,
                        id: f.id,
                        st: f.st.map(f64::to_bits),
                        input,
                    });
                    true
                }
                None => false,
            }
        }
    }
}

/// A ROP's body: depth-tests, shades and writes the fragments it is given into its pixels.
pub async fn run<R: Real>(mut ctx: Ctx<RopItem<R>, MemAccess>, rop: RopContext<'_, R>) -> Finished {
    let RopContext {
        cfg,
        memory: fbc,
        mut pixels,
        shader,
        view,
        discoid,
        mut caches,
    } = rop;
    if caches.is_some() {
        // Its caches are written back once its inputs end.
        ctx.pushes_at_end();
    }
    let mut counts = Counts::default();
    let mut kept = (Vec::new(), BlendReport::default());
    // The fragments that passed, shaded in lanes as the functional ROP shades them
    // (`rop::Batch`): colours are written in arrival order, and a pixel is only ever this
    // ROP's, so the frame is the functional one.
    let mut batch = Batch::<R>::new();
    // The cache transfers of the item being charged.
    let mut transfers = Vec::new();
    while let Some(item) = ctx.next_input().await {
        let mut passed = 0u64;
        let mut nearest = f32::INFINITY;
        let rows = item.rows();
        let n = match item {
            RopItem::Triangle(piece) => triangle_fragments(
                &piece,
                discoid,
                view,
                &shader,
                &mut pixels,
                &mut batch,
                &mut kept,
                &mut passed,
                &mut nearest,
            ),
            RopItem::Lembo(span) => lembo_fragments(
                span,
                discoid,
                view,
                &shader,
                &mut pixels,
                &mut batch,
                &mut kept,
                &mut passed,
                &mut nearest,
            ),
        };
        counts.fragments_passed_depth += passed;
        if discoid.is_some() {
            // The discoid passes keep their own depths: nothing for hierarchical Z.
            nearest = f32::NEG_INFINITY;
        }
        let (bytes, extra) = traffic(fbc, discoid, n, passed);
        let mut cycles = cfg.fragments_per_cycle.ceil_div(n) + extra;
        let Some(c) = caches.as_mut() else {
            ctx.emit(cycles, MemAccess::frame(bytes)).await;
            continue;
        };
        transfers.clear();
        let (ports, rejected) = c.access(&rows, nearest, passed > 0, &pixels, &mut transfers);
        // Hierarchical Z discards a rejected span in its one test.
        cycles = if rejected { 1 } else { cycles.max(ports) };
        send(&mut ctx, cycles, bytes, &transfers).await;
    }
    batch.flush(&shader, into(&mut pixels));
    let mut memory = None;
    if let Some(c) = caches.as_mut() {
        write_back(&mut ctx, c, &pixels).await;
        memory = Some(c.stats(&pixels));
    }
    let finished = Finished::new(ctx, counts);
    let finished = match memory {
        Some(m) => finished.with(UnitReport::RopMemory(m)),
        None => finished,
    };
    match discoid {
        Some(DiscoidPass {
            pass: Pass::Accumulate,
            ..
        }) => finished.with(UnitReport::Kept(kept.0, kept.1)),
        _ => finished,
    }
}

/// Sends one item's traffic: `bytes` for the port and the caches' `transfers`, in
/// `cycles`. A span over several memory tiles may make more transfers than an item carries:
/// the rest follow in items of their own, a cycle each.
async fn send<R: Real>(
    ctx: &mut Ctx<RopItem<R>, MemAccess>,
    cycles: u64,
    bytes: u64,
    transfers: &[LineTransfer],
) {
    let mut chunks = transfers.chunks(MemAccess::CAP);
    let mut out = MemAccess::frame(bytes);
    chunks
        .next()
        .into_iter()
        .flatten()
        .for_each(|&t| out.push(t));
    ctx.emit(cycles, out).await;
    for chunk in chunks {
        let mut out = MemAccess::default();
        chunk.iter().for_each(|&t| out.push(t));
        ctx.emit(1, out).await;
    }
}

/// The end of the frame, once it reaches the ROP with the end of its inputs: the caches'
/// write-backs and this ROP's share of the resolve, a burst of transfers an item, at the
/// caches' port rate.
async fn write_back<R: Real>(
    ctx: &mut Ctx<RopItem<R>, MemAccess>,
    c: &mut RopMemory,
    pixels: &RopPixels<'_, '_>,
) {
    ctx.wait_for_end_of_inputs();
    for chunk in c.finish(pixels).chunks(MemAccess::CAP) {
        let mut out = MemAccess::default();
        chunk.iter().for_each(|&t| out.push(t));
        let sectors: u64 = chunk
            .iter()
            .map(|t| u64::from(t.sectors.count_ones()))
            .sum();
        ctx.emit(sectors.div_ceil(c.per_cycle()).max(1), out).await;
    }
}

/// A span of lembo fragments: depth-tested, shaded into `batch` and written (or a discoid
/// pass's work on each); its fragments, the ones that passed added to `passed`.
#[allow(clippy::too_many_arguments)]
fn lembo_fragments<R: Real>(
    item: FragmentSpan<R>,
    discoid: Option<&DiscoidPass<R>>,
    view: &View,
    shader: &FragmentShader<R>,
    pixels: &mut RopPixels,
    batch: &mut Batch<R>,
    kept: &mut (Vec<KeptFragment>, BlendReport),
    passed: &mut u64,
    nearest: &mut f32,
) -> u64 {
    match (item, discoid) {
        (FragmentSpan { piece, j, span }, None) => {
            let l = &*piece.screen;
            let row = pixels.row(span.i0, span.i1, j);
            pixels.prefetch(row + pixels.width() + span.i0 as usize);
            batch.begin_lembo(l, shader, into(pixels));
            span.walk(|i, u, v| {
                let idx = row + i as usize;
                let z = l.z.eval(u, v).f64() as f32;
                *nearest = nearest.min(z);
                // SAFETY: i is in span.i0..span.i1, the run `row` admitted.
                if unsafe { pixels.test_depth(idx, z, l.id) } {
                    *passed += 1;
                    if batch.push(idx, [u, v]) {
                        batch.flush(shader, into(pixels));
                    }
                }
            });
            span.len() as u64
        }
        (FragmentSpan { piece, j, span }, Some(dp)) => {
            let l = &*piece.screen;
            let row = pixels.row(span.i0, span.i1, j);
            span.walk(|i, u, v| {
                let idx = row + i as usize;
                let z = l.z.eval(u, v);
                // SAFETY: i is in span.i0..span.i1, the run `row` admitted.
                let wins = dp.table.lembo_fragment(l, u, v, z).is_some_and(|f| unsafe {
                    discoid_fragment(dp, view, shader, pixels, kept, idx, &f)
                });
                *passed += wins as u64;
            });
            span.len() as u64
        }
    }
}

/// A piece of a triangle: as [`lembo_fragments`], row by row.
#[allow(clippy::too_many_arguments)]
fn triangle_fragments<R: Real>(
    piece: &TrianglePiece<R>,
    discoid: Option<&DiscoidPass<R>>,
    view: &View,
    shader: &FragmentShader<R>,
    pixels: &mut RopPixels,
    batch: &mut Batch<R>,
    kept: &mut (Vec<KeptFragment>, BlendReport),
    passed: &mut u64,
    nearest: &mut f32,
) -> u64 {
    let t = &*piece.tri;
    if discoid.is_none() {
        batch.begin_triangle(t, shader, into(pixels));
    }
    for (r, &(a, b)) in piece.rows.iter().enumerate() {
        let j = piece.j + r as u32;
        if a >= b {
            continue;
        }
        let row = pixels.row(a, b, j);
        for i in a..b {
            let idx = row + i as usize;
            let wins = match discoid {
                None => {
                    let (l, z) = t.weights(i, j);
                    // Multisampled, each sample is shaded at its pixel's centre.
                    let l = match t.samples == Samples::ONE {
                        true => l,
                        false => t.shading_weights(i, j),
                    };
                    let z = z.f64() as f32;
                    *nearest = nearest.min(z);
                    // SAFETY: i is in a..b, the run `row` admitted.
                    let pass = unsafe { pixels.test_depth(idx, z, t.id) };
                    if pass && batch.push(idx, l) {
                        batch.flush(shader, into(pixels));
                    }
                    pass
                }
                Some(dp) => {
                    let df = dp.table.planar_fragment(t, &t.fragment(i, j));
                    // SAFETY: i is in a..b, the run `row` admitted.
                    unsafe { discoid_fragment(dp, view, shader, pixels, kept, idx, &df) }
                }
            };
            *passed += wins as u64;
        }
    }
    piece.len()
}

/// The bytes `n` fragments tested, `passed` of them passing, move through the memory port
/// `fbc`, and the blend cycles a discoid pass adds.
fn traffic<R>(
    fbc: &FrameBufferConfig,
    discoid: Option<&DiscoidPass<R>>,
    n: u64,
    passed: u64,
) -> (u64, u64) {
    let tested = n * fbc.bytes_per_fragment_tested;
    match discoid {
        None => (tested + passed * fbc.bytes_per_fragment_written, 0),
        // The depth pass writes depth only.
        Some(DiscoidPass {
            pass: Pass::Depth, ..
        }) => (tested + passed * fbc.bytes_per_fragment_tested, 0),
        Some(dp) => (
            tested + passed * dp.mode.bytes_per_fragment(),
            passed * dp.blend_cycles,
        ),
    }
}
