//! Rop (DESIGN §2 and §3; paper 000 section 4 for the ROP's place): the depth test and the
//! frame-buffer write, Np units screen-interleaved by tiles.
//!
//! Input: [`RopItem`]s from every rasterizer, merged by (arrival, port): lembo
//! [`FragmentSpan`]s, or [`TrianglePiece`]s in the triangle path. For each fragment: its
//! depth (from the lembo's depth quadratic, or the triangle's plane), the depth test on
//! (z, id) (the winner does not depend on arrival order), and for a fragment that passes,
//! Phong shading (paper 000 equation 6) and the write. Output: one [`WriteBurst`] per item
//! to the frame-buffer memory port: depth reads for every fragment tested, colour and depth
//! writes for every fragment that passed.
//!
//! Storage: each ROP owns the pixels of its tiles ([`RopTiles`]), held tile by tile, so the
//! ROPs never share a pixel and together hold one frame buffer.
//!
//! Cost: ceil(n / `rop.fragments_per_cycle`) per span of n fragments, ready
//! `latency_cycles` later. Not modelled: caches; the frame-buffer port's bandwidth is the
//! memory model.

use super::actor::{ActorError, Ctx};
use super::rasterizer::FragmentSpan;
use super::triangle_rasterizer::TrianglePiece;
use super::{DiscoidPass, Finished, Shared};
use crate::config::BlendConfig;
use crate::datapath::Real;
use crate::discoid::blend::BlendMode;
use crate::discoid::render::{
    accumulation_keeps, depth_pass_wins, evaluate, BlendReport, DiscoidFragment, Pass, Pending,
};
use crate::raster::Counts;
use crate::rop::framebuffer::{depth_test, NO_PRIMITIVE};
use crate::rop::rop::FragmentShader;
use crate::rop::FrameBuffer;

/// Screen interleaving: tile (tx, ty) of `tile_px` x `tile_px` pixels belongs to ROP
/// (tx + ty) mod Np, so neighbouring tiles, along rows and columns, go to different ROPs.
#[derive(Clone, Debug)]
pub struct RopTiles {
    pub tile_px: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub rops: u32,
    /// Per tile (row-major): its slot among the tiles of its ROP.
    slot: Vec<u32>,
    /// Tiles per ROP.
    owned: Vec<u32>,
}

impl RopTiles {
    pub fn new(width: u32, height: u32, tile_px: u32, rops: u32) -> Self {
        let tiles_x = width.div_ceil(tile_px);
        let tiles_y = height.div_ceil(tile_px);
        let mut owned = vec![0u32; rops as usize];
        let mut slot = Vec::with_capacity((tiles_x * tiles_y) as usize);
        for ty in 0..tiles_y {
            for tx in 0..tiles_x {
                let r = ((tx + ty) % rops) as usize;
                slot.push(owned[r]);
                owned[r] += 1;
            }
        }
        RopTiles {
            tile_px,
            tiles_x,
            tiles_y,
            rops,
            slot,
            owned,
        }
    }

    /// The ROP owning pixel (i, j) and the first pixel column past its tile.
    #[inline]
    pub fn owner(&self, i: u32, j: u32) -> (usize, u32) {
        let (tx, ty) = (i / self.tile_px, j / self.tile_px);
        (((tx + ty) % self.rops) as usize, (tx + 1) * self.tile_px)
    }

    /// Index of pixel (i, j) in its owner's storage.
    #[inline]
    fn local(&self, i: u32, j: u32) -> usize {
        let (tx, ty) = (i / self.tile_px, j / self.tile_px);
        let slot = self.slot[(ty * self.tiles_x + tx) as usize] as usize;
        let t = self.tile_px as usize;
        slot * t * t + (j % self.tile_px) as usize * t + (i % self.tile_px) as usize
    }
}

/// The pixels one ROP owns: depth, winner id and colour, tile by tile.
pub struct TileStore {
    rop: usize,
    depth: Vec<f32>,
    primitive: Vec<u32>,
    color: Vec<[u8; 3]>,
}

impl TileStore {
    fn new(tiles: &RopTiles, rop: usize, background: [u8; 3]) -> Self {
        let n = tiles.owned[rop] as usize * (tiles.tile_px as usize).pow(2);
        TileStore {
            rop,
            depth: vec![1.0; n],
            primitive: vec![NO_PRIMITIVE; n],
            color: vec![background; n],
        }
    }

    /// Copies this ROP's pixels into the frame buffer.
    pub fn write_into(&self, tiles: &RopTiles, fb: &mut FrameBuffer) {
        for j in 0..fb.height {
            let ty = j / tiles.tile_px;
            for tx in 0..tiles.tiles_x {
                if ((tx + ty) % tiles.rops) as usize != self.rop {
                    continue;
                }
                let i0 = tx * tiles.tile_px;
                for i in i0..(i0 + tiles.tile_px).min(fb.width) {
                    let (src, dst) = (tiles.local(i, j), fb.index(i, j));
                    fb.depth[dst] = self.depth[src];
                    fb.primitive[dst] = self.primitive[src];
                    fb.color[dst] = self.color[src];
                }
            }
        }
    }
}

/// What a ROP takes: fragments of a lembo or of a triangle inside one of its tiles.
#[derive(Clone, Debug, PartialEq)]
pub enum RopItem<R> {
    Lembo(FragmentSpan<R>),
    Triangle(TrianglePiece<R>),
}

impl TileStore {
    /// The depth test and write of fragment (z, id) at storage index `idx`; `shade` gives
    /// the colour of a fragment that passes.
    #[inline(always)]
    fn test_and_write(
        &mut self,
        idx: usize,
        z: f32,
        id: u32,
        shade: impl FnOnce() -> [u8; 3],
    ) -> bool {
        if !depth_test(z, id, self.depth[idx], self.primitive[idx]) {
            return false;
        }
        self.depth[idx] = z;
        self.primitive[idx] = id;
        self.color[idx] = shade();
        true
    }
}

/// Frame-buffer traffic of one span [bytes].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriteBurst {
    pub bytes: u64,
}

/// A discoid pass's work on one fragment at storage index `local` (global `idx`):
/// returns whether it passed (the depth pass) or was kept (the accumulation pass).
#[allow(clippy::too_many_arguments)]
#[inline]
fn discoid_fragment<R: Real>(
    dp: &DiscoidPass<R>,
    sh: &Shared<R>,
    shader: &FragmentShader<R>,
    store: &mut TileStore,
    kept: &mut (Vec<Pending>, BlendReport),
    local: usize,
    idx: usize,
    f: &DiscoidFragment<R>,
) -> bool {
    let e = evaluate(dp.table, shader, f);
    match dp.pass {
        Pass::Depth => {
            let wins = depth_pass_wins(&e, f.id, store.depth[local], store.primitive[local]);
            if wins {
                store.depth[local] = e.z;
                store.primitive[local] = f.id;
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
                    kept.0.push(Pending {
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

pub fn run<R: Real>(
    mut ctx: Ctx<RopItem<R>, WriteBurst>,
    sh: &Shared<R>,
    rop: usize,
) -> Result<(Finished, TileStore), ActorError> {
    let cfg = &sh.arch.rop;
    let fbc = &sh.arch.framebuffer;
    let mut counts = Counts::default();
    let mut store = TileStore::new(&sh.tiles, rop, sh.background);
    let shader = FragmentShader::<R>::new(&sh.scene.light, sh.view);
    let width = sh.view.viewport.width as usize;
    let mut kept = (Vec::new(), BlendReport::default());
    while let Some(item) = ctx.next_input()? {
        let mut passed = 0u64;
        // The rasterizers cut their output at tile borders: a row's pixels are consecutive
        // in the tile's storage row, so the index is found once per row, not per fragment.
        let row_start = |i: u32, j: u32| {
            debug_assert!(sh.tiles.owner(i, j).0 == rop, "item for another ROP");
            sh.tiles.local(i, j) as isize - i as isize
        };
        let n = match item {
            RopItem::Lembo(FragmentSpan { id, j, span }) => {
                let l = sh.lembo(id);
                let first = row_start(span.i0, j);
                span.walk(|i, u, v| {
                    let local = (first + i as isize) as usize;
                    let z = l.z.eval(u, v);
                    let wins = match &sh.discoid {
                        None => store.test_and_write(local, z.f64() as f32, l.id, || {
                            shader.shade(l, u, v).0
                        }),
                        Some(dp) => dp.table.lembo_fragment(l, u, v, z).is_some_and(|f| {
                            let idx = j as usize * width + i as usize;
                            discoid_fragment(dp, sh, &shader, &mut store, &mut kept, local, idx, &f)
                        }),
                    };
                    passed += wins as u64;
                });
                span.len() as u64
            }
            RopItem::Triangle(piece) => {
                let t = &*piece.tri;
                for (r, &(a, b)) in piece.rows.iter().enumerate() {
                    let j = piece.j + r as u32;
                    if a >= b {
                        continue;
                    }
                    let first = row_start(a, j);
                    for i in a..b {
                        let f = t.fragment(i, j);
                        let local = (first + i as isize) as usize;
                        let wins = match &sh.discoid {
                            None => store.test_and_write(local, f.z.f64() as f32, t.id, || {
                                shader.shade_at(f.normal, f.position, t.color).0
                            }),
                            Some(dp) => {
                                let df = dp.table.planar_fragment(t, &f);
                                let idx = j as usize * width + i as usize;
                                discoid_fragment(
                                    dp, sh, &shader, &mut store, &mut kept, local, idx, &df,
                                )
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
            n.div_ceil(cfg.fragments_per_cycle) + extra,
            0,
            WriteBurst { bytes },
        )?;
    }
    let mut finished = Finished::new(ctx, counts)?;
    if matches!(
        &sh.discoid,
        Some(DiscoidPass {
            pass: Pass::Accumulate,
            ..
        })
    ) {
        finished.discoid = Some(kept);
    }
    Ok((finished, store))
}

/// Blend-unit cycles per kept fragment in `mode`.
pub fn blend_cycles(cfg: &BlendConfig, mode: BlendMode) -> u64 {
    match mode {
        BlendMode::Rgba8 => cfg.cycles_per_fragment_rgba8,
        BlendMode::F16 => cfg.cycles_per_fragment_f16,
        BlendMode::F32 => cfg.cycles_per_fragment_f32,
    }
}
