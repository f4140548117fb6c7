//! Rop (DESIGN.md §2 and §3; Piranda et al. 2006 section 4 for the ROP's place): the depth test and
//! the frame-buffer write, Np units screen-interleaved by tiles.
//!
//! Input: [`RopItem`]s from every rasterizer, merged by (arrival, port): lembo
//! [`FragmentSpan`]s, or [`TrianglePiece`]s in the triangle path. For each fragment: its
//! depth (from the lembo's depth quadratic, or the triangle's plane), the depth test on
//! (z, id) (the winner does not depend on arrival order), and for a fragment that passes,
//! Phong shading (Piranda et al. 2006 equation 6) and the write. Output: one [`WriteBurst`] per
//! item to the frame-buffer memory port: depth reads for every fragment tested, colour and depth
//! writes for every fragment that passed.
//!
//! Storage: each ROP owns the pixels of its tiles ([`RopTiles`]) and writes them in place
//! in the one frame buffer ([`SharedFrame`]); the ROPs never share a pixel.
//!
//! Cost: ceil(n / `rop.fragments_per_cycle`) per span of n fragments, ready
//! `latency_cycles` later. Not modelled: caches; the frame-buffer port's bandwidth is the
//! memory model.

use super::rasterizer::FragmentSpan;
use super::triangle_rasterizer::TrianglePiece;
use crate::config::BlendConfig;
use crate::datapath::Real;
use crate::discoid::blend::BlendMode;
use crate::discoid::render::{
    accumulation_keeps, depth_pass_wins, evaluate, BlendReport, DiscoidFragment, KeptFragment, Pass,
};
use crate::pipeline::runtime::{ceil_div, Ctx};
use crate::pipeline::{DiscoidPass, Finished, Shared};
use crate::raster::Counts;
use crate::rop::fragment_shader::FragmentShader;
use crate::rop::framebuffer::depth_test;
use crate::rop::rop::Batch;
use crate::rop::FrameBuffer;

/// Screen interleaving: tile (tx, ty) of `tile_px` x `tile_px` pixels belongs to ROP
/// (tx + ty) mod Np, so neighbouring tiles, along rows and columns, go to different ROPs.
#[derive(Clone, Debug)]
pub struct RopTiles {
    /// Tile side \[pixels\].
    pub tile_px: u32,
    /// Tiles per row.
    pub tiles_x: u32,
    /// Tiles per column.
    pub tiles_y: u32,
    /// ROPs sharing the screen.
    pub rops: u32,
    /// log2 of `tile_px` and `rops - 1` when they are powers of two (the usual sizes): the
    /// owner of a pixel is then found without a division.
    shift: Option<u32>,
    mask: Option<u32>,
}

impl RopTiles {
    /// The tiles of a `width` x `height` screen over `rops` ROPs.
    pub fn new(width: u32, height: u32, tile_px: u32, rops: u32) -> Self {
        RopTiles {
            tile_px,
            tiles_x: width.div_ceil(tile_px),
            tiles_y: height.div_ceil(tile_px),
            rops,
            shift: tile_px.is_power_of_two().then(|| tile_px.trailing_zeros()),
            mask: rops.is_power_of_two().then(|| rops - 1),
        }
    }

    /// The ROP owning pixel (i, j) and the first pixel column past its tile.
    #[inline]
    pub fn owner(&self, i: u32, j: u32) -> (usize, u32) {
        let (tx, ty) = match self.shift {
            Some(s) => (i >> s, j >> s),
            None => (i / self.tile_px, j / self.tile_px),
        };
        let rop = match self.mask {
            Some(m) => (tx + ty) & m,
            None => (tx + ty) % self.rops,
        };
        (rop as usize, (tx + 1) * self.tile_px)
    }
}

/// The frame buffer the ROPs write in place, each only the pixels of its own tiles.
///
/// The ROPs run as units of one host thread or of several; a pixel belongs to exactly one
/// ROP ([`RopTiles`]), so no two ROPs ever touch the same pixel and the frame needs no
/// lock and no per-ROP copy. Each ROP reaches it through [`RopPixels`], which checks that
/// every row of pixels it is given lies inside one of its own tiles.
pub struct SharedFrame<'f> {
    depth: *mut f32,
    primitive: *mut u32,
    color: *mut [u8; 3],
    len: usize,
    _frame: std::marker::PhantomData<&'f mut FrameBuffer>,
}

// SAFETY: the pointers come from a `&'f mut FrameBuffer` held for 'f, and every access goes
// through a `RopPixels`, which confines ROP r to the pixels of its own tiles (checked per
// row); distinct ROPs therefore never access the same element, from any thread.
unsafe impl Send for SharedFrame<'_> {}
unsafe impl Sync for SharedFrame<'_> {}

impl<'f> SharedFrame<'f> {
    /// Shares `fb`'s depth, winner and colour planes among the ROPs for `'f`.
    pub fn new(fb: &'f mut FrameBuffer) -> Self {
        SharedFrame {
            depth: fb.depth.as_mut_ptr(),
            primitive: fb.primitive.as_mut_ptr(),
            color: fb.color.as_mut_ptr(),
            len: fb.depth.len(),
            _frame: std::marker::PhantomData,
        }
    }
}

/// ROP `rop`'s access to the pixels of its tiles.
pub struct RopPixels<'a, 'f> {
    frame: &'a SharedFrame<'f>,
    tiles: &'a RopTiles,
    rop: usize,
    width: usize,
}

impl<'a, 'f> RopPixels<'a, 'f> {
    /// ROP `rop`'s pixels of `frame`, `width` pixels a row.
    pub fn new(frame: &'a SharedFrame<'f>, tiles: &'a RopTiles, rop: usize, width: u32) -> Self {
        RopPixels {
            frame,
            tiles,
            rop,
            width: width as usize,
        }
    }

    /// The index of pixel (0, j): pixels i0..i1 of row j are `row + i`. Panics unless the
    /// run lies inside one tile of this ROP (the rasterizers cut their output at tile
    /// borders), which is what makes the unsynchronised writes sound.
    #[inline]
    fn row(&self, i0: u32, i1: u32, j: u32) -> usize {
        let (owner, tile_end) = self.tiles.owner(i0, j);
        assert!(
            owner == self.rop && i1 <= tile_end && i0 < i1,
            "ROP {} given pixels {i0}..{i1} of row {j}",
            self.rop
        );
        let row = j as usize * self.width;
        assert!(row + (i1 as usize) <= self.frame.len);
        row
    }

    #[inline(always)]
    fn depth(&self, idx: usize) -> f32 {
        // SAFETY: idx is in a row `row` checked to be this ROP's (type doc).
        unsafe { *self.frame.depth.add(idx) }
    }

    #[inline(always)]
    fn primitive(&self, idx: usize) -> u32 {
        // SAFETY: as for `depth`.
        unsafe { *self.frame.primitive.add(idx) }
    }

    #[inline(always)]
    fn set_depth(&mut self, idx: usize, z: f32, id: u32) {
        // SAFETY: as for `depth`; `&mut self` keeps one writer per ROP.
        unsafe {
            *self.frame.depth.add(idx) = z;
            *self.frame.primitive.add(idx) = id;
        }
    }

    /// The depth test of fragment (z, id) at pixel index `idx`, and its depth and winner
    /// written when it passes; whether it passed.
    #[inline(always)]
    fn test_depth(&mut self, idx: usize, z: f32, id: u32) -> bool {
        let pass = depth_test(z, id, self.depth(idx), self.primitive(idx));
        if pass {
            self.set_depth(idx, z, id);
        }
        pass
    }

    #[inline(always)]
    fn set_color(&mut self, idx: usize, rgb: [u8; 3]) {
        // SAFETY: as for `depth`; `&mut self` keeps one writer per ROP.
        unsafe { *self.frame.color.add(idx) = rgb };
    }
}

/// Where a batch's colours go: this ROP's pixels.
fn into<'b, 'a: 'b, 'f: 'a, R>(
    pixels: &'b mut RopPixels<'a, 'f>,
) -> impl FnMut(usize, [u8; 3], [R; 3]) + use<'a, 'b, 'f, R> {
    move |idx, rgb, _| pixels.set_color(idx, rgb)
}

/// What a ROP takes: fragments of a lembo or of a triangle inside one of its tiles.
#[derive(Clone, Debug, PartialEq)]
pub enum RopItem<R> {
    /// A lembo's span of fragments.
    Lembo(FragmentSpan<R>),
    /// A triangle's piece of two rows.
    Triangle(TrianglePiece<R>),
}

/// Frame-buffer traffic of one span \[bytes\].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriteBurst {
    /// Bytes moved: depth reads, colour and depth writes \[bytes\].
    pub bytes: u64,
}

/// A discoid pass's work on one fragment at pixel index `idx`: returns whether it passed
/// (the depth pass) or was kept (the accumulation pass).
#[allow(clippy::too_many_arguments)]
#[inline]
fn discoid_fragment<R: Real>(
    dp: &DiscoidPass<R>,
    sh: &Shared<'_, R>,
    shader: &FragmentShader<R>,
    pixels: &mut RopPixels,
    kept: &mut (Vec<KeptFragment>, BlendReport),
    idx: usize,
    f: &DiscoidFragment<R>,
) -> bool {
    let e = evaluate(dp.table, shader, f);
    match dp.pass {
        Pass::Depth => {
            let wins = depth_pass_wins(&e, f.id, pixels.depth(idx), pixels.primitive(idx));
            if wins {
                pixels.set_depth(idx, e.z, f.id);
            }
            wins
        }
        Pass::Accumulate => {
            let (depth, winner) = (dp.depth[idx], dp.winner[idx]);
            match accumulation_keeps(
                &mut kept.1,
                sh.view,
                shader,
                dp.threshold,
                &e,
                depth,
                winner,
            ) {
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

/// ROP `rop`: depth-tests, shades and writes the fragments it is given into `frame`.
pub async fn run<R: Real>(
    mut ctx: Ctx<RopItem<R>, WriteBurst>,
    sh: &Shared<'_, R>,
    rop: usize,
    frame: &SharedFrame<'_>,
) -> Finished {
    let cfg = &sh.arch.rop;
    let fbc = &sh.arch.framebuffer;
    let mut counts = Counts::default();
    let mut pixels = RopPixels::new(frame, &sh.tiles, rop, sh.view.viewport.width);
    let shader = FragmentShader::<R>::new(&sh.scene.light, sh.view);
    let mut kept = (Vec::new(), BlendReport::default());
    // The fragments that passed, shaded in lanes as the functional ROP shades them
    // (`rop::Batch`): colours are written in arrival order, and a pixel is only ever this
    // ROP's, so the frame is the functional one.
    let mut batch = Batch::<R>::new();
    while let Some(item) = ctx.next_input().await {
        let mut passed = 0u64;
        let n = match (item, &sh.discoid) {
            (RopItem::Lembo(FragmentSpan { id, j, span }), None) => {
                let l = sh.lembo(id);
                let row = pixels.row(span.i0, span.i1, j);
                batch.begin_lembo(l, &shader, into(&mut pixels));
                span.walk(|i, u, v| {
                    let idx = row + i as usize;
                    let z = l.z.eval(u, v);
                    if pixels.test_depth(idx, z.f64() as f32, l.id) {
                        passed += 1;
                        if batch.push(idx, [u, v]) {
                            batch.flush(&shader, into(&mut pixels));
                        }
                    }
                });
                span.len() as u64
            }
            (RopItem::Lembo(FragmentSpan { id, j, span }), Some(dp)) => {
                let l = sh.lembo(id);
                let row = pixels.row(span.i0, span.i1, j);
                span.walk(|i, u, v| {
                    let idx = row + i as usize;
                    let z = l.z.eval(u, v);
                    let wins = dp.table.lembo_fragment(l, u, v, z).is_some_and(|f| {
                        discoid_fragment(dp, sh, &shader, &mut pixels, &mut kept, idx, &f)
                    });
                    passed += wins as u64;
                });
                span.len() as u64
            }
            (RopItem::Triangle(piece), discoid) => {
                let t = &*piece.tri;
                if discoid.is_none() {
                    batch.begin_triangle(t, &shader, into(&mut pixels));
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
                                let pass = pixels.test_depth(idx, z.f64() as f32, t.id);
                                if pass && batch.push(idx, l) {
                                    batch.flush(&shader, into(&mut pixels));
                                }
                                pass
                            }
                            Some(dp) => {
                                let df = dp.table.planar_fragment(t, &t.fragment(i, j));
                                discoid_fragment(dp, sh, &shader, &mut pixels, &mut kept, idx, &df)
                            }
                        };
                        passed += wins as u64;
                    }
                }
                piece.len()
            }
        };
        counts.fragments_passed_depth += passed;
        let tested = n * fbc.bytes_per_fragment_tested;
        let (bytes, extra) = match &sh.discoid {
            None => (tested + passed * fbc.bytes_per_fragment_written, 0),
            // The depth pass writes depth only.
            Some(DiscoidPass {
                pass: Pass::Depth, ..
            }) => (tested + passed * fbc.bytes_per_fragment_tested, 0),
            Some(dp) => (
                tested + passed * dp.mode.bytes_per_fragment(),
                passed * blend_cycles(&sh.arch.blend, dp.mode),
            ),
        };
        ctx.emit(
            ceil_div(n, cfg.fragments_per_cycle) + extra,
            0,
            WriteBurst { bytes },
        )
        .await;
    }
    batch.flush(&shader, into(&mut pixels));
    let mut finished = Finished::new(ctx, counts);
    if matches!(
        &sh.discoid,
        Some(DiscoidPass {
            pass: Pass::Accumulate,
            ..
        })
    ) {
        finished.discoid = Some(kept);
    }
    finished
}

/// Blend-unit cycles per kept fragment in `mode`.
pub fn blend_cycles(cfg: &BlendConfig, mode: BlendMode) -> u64 {
    match mode {
        BlendMode::Rgba8 => cfg.cycles_per_fragment_rgba8,
        BlendMode::F16 => cfg.cycles_per_fragment_f16,
        BlendMode::F32 => cfg.cycles_per_fragment_f32,
    }
}
