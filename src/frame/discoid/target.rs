//! The ROP's side of the discoid passes over one frame ([`DiscoidTarget`]: nearest depth,
//! winner, the blend units' sums, the kept fragments): what a ROP does with one discoid
//! fragment in each pass ([`process`], from the tests [`depth_pass_wins`] and
//! [`accumulation_keeps`]), the blend in primitive order, and the resolve into an image with
//! its error and holes ([`resolve`], [`count_holes`]). The functional passes
//! ([`super::passes`]) and the timed ROP units share them.

use super::table::{evaluate, DiscoidFragment, DiscoidTable, Evaluated};
use crate::camera::View;
use crate::datapath::{Op, Real};
use crate::discoid::blend::{Accum, BlendInput, BlendMode, ExactAccum};
use crate::discoid::report::BlendReport;
use crate::graph::UnitKind;
use crate::rop::fragment_shader::FragmentShader;
use crate::rop::framebuffer::{depth_test, NO_PRIMITIVE};
use crate::rop::shade::to_u8;
use crate::rop::FrameBuffer;

/// Which pass the ROPs run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// The depth pass: nearest depth per pixel, no blending.
    Depth,
    /// The accumulation pass: the kept fragments' sums of equation (5).
    Accumulate,
}

/// The per-pixel state of the discoid passes and their counters; the ROP side of one
/// frame, whichever unit feeds it.
pub struct DiscoidTarget {
    /// Frame width \[pixels\].
    pub width: u32,
    /// Precision of the blend units.
    pub mode: BlendMode,
    /// World units, along the view direction.
    pub threshold: f64,
    /// Nearest depth per pixel (depth pass), 1 where none.
    pub depth: Vec<f32>,
    /// The primitive that won the depth pass, for the resolve's colour.
    pub winner: Vec<u32>,
    /// The blend units' sums per pixel, in the mode's precision.
    pub accum: Vec<Accum>,
    /// The same sums in f64, to measure the mode's error.
    pub exact: Vec<ExactAccum>,
    /// Fragments kept by the accumulation pass, blended in order at its end.
    pub kept: Vec<KeptFragment>,
    /// The depth pass winner's unit normal per pixel, kept only when accuracy is measured
    /// against the surface (the metrics', not the unit's).
    pub normal: Option<Vec<[f32; 3]>>,
    /// The passes' counters and the blend error.
    pub report: BlendReport,
}

/// A fragment the accumulation pass keeps: pixel, primitive id, texture coordinates (the
/// order within a primitive) and what it blends.
#[derive(Clone, Copy, Debug)]
pub struct KeptFragment {
    /// Pixel index, row-major.
    pub idx: u32,
    /// Primitive id.
    pub id: u32,
    /// Texture coordinates as f64 bits (an exact sort key within a primitive).
    pub st: [u64; 2],
    /// What the fragment adds to the pixel's sums.
    pub input: BlendInput,
}

impl DiscoidTarget {
    /// An empty target of `width` x `height` pixels: depth 1, no winner, zero sums.
    pub fn new(width: u32, height: u32, mode: BlendMode, threshold: f64) -> Self {
        let n = width as usize * height as usize;
        DiscoidTarget {
            width,
            mode,
            threshold,
            depth: vec![1.0; n],
            winner: vec![NO_PRIMITIVE; n],
            accum: vec![Accum::default(); n],
            exact: vec![ExactAccum::default(); n],
            kept: Vec::new(),
            normal: None,
            report: BlendReport {
                mode: mode.name().to_string(),
                bytes_per_fragment: mode.bytes_per_fragment(),
                accumulation_buffer_bytes: n as u64 * mode.bytes_per_pixel(),
                threshold,
                ..BlendReport::default()
            },
        }
    }
}

impl DiscoidTarget {
    /// Blends the pending fragments, pixel by pixel in primitive order, with the blend
    /// ALU's word `B` (`f32`, or a counting `f32` charged to the blend units).
    pub fn blend_in_order<B: Real>(&mut self) {
        B::charge(UnitKind::BlendUnit);
        let mut pending = std::mem::take(&mut self.kept);
        pending.sort_unstable_by_key(|p| (p.idx, p.id, p.st));
        for p in &pending {
            let idx = p.idx as usize;
            if self
                .mode
                .blend_in::<B>(&mut self.accum[idx], p.input)
                .saturated
            {
                self.report.saturations += 1;
            }
            self.exact[idx].add(p.input);
        }
        self.report.fragments_accumulated += pending.len() as u64;
    }
}

/// The depth pass: whether fragment `e` of primitive `id` replaces a pixel holding
/// (`depth`, `winner`). Only fragments facing the eye, inside their discoid and inside the
/// depth range count; ties go to the smaller id, so the result does not depend on order.
#[inline]
pub fn depth_pass_wins<R: Real>(e: &Evaluated<R>, id: u32, depth: f32, winner: u32) -> bool {
    if !(e.facing && e.beta > 0.0) {
        return false;
    }
    // The depth test's compare (on the stored f32 depth, beside the datapath), as the
    // surface ROP counts it.
    R::count_beside(Op::Cmp, 1);
    depth_test(e.z, id, depth, winner)
}

/// Counts the accumulation pass's depth tests as the datapath would do them: they run in
/// `f64` beside it ([`View::linear_depth`]). The depth range is two compares; the threshold
/// test linear_depth(z) > linear_depth(depth) + t is two linear depths (in perspective
/// 2 z - 1, (f + n) - ndc (f - n) and 2 f n over it: 2 multiplies, 2 adds and a divide
/// each; orthographic n + z (f - n): a multiply and an add), the threshold's add and a
/// compare.
#[inline(always)]
fn count_threshold_test<R: Real>(view: &View) {
    let (mul, add, div) = if view.orthographic {
        (1, 1, 0)
    } else {
        (2, 2, 1)
    };
    R::count_beside(Op::Mul, 2 * mul);
    R::count_beside(Op::Add, 2 * add + 1);
    R::count_beside(Op::Div, 2 * div);
    R::count_beside(Op::Cmp, 2 + 1);
}

/// The accumulation pass's tests on fragment `e` at a pixel whose depth pass left
/// (`depth`, `winner`): back-face cull, beta = 0 discard, threshold; counted in `report`.
/// Returns what to blend for a fragment kept.
#[inline]
pub fn accumulation_keeps<R: Real>(
    report: &mut BlendReport,
    view: &View,
    shader: &FragmentShader<R>,
    threshold: f64,
    e: &Evaluated<R>,
    depth: f32,
    winner: u32,
) -> Option<BlendInput> {
    if !e.facing {
        report.culled_backface += 1;
        return None;
    }
    if e.beta <= 0.0 {
        report.discarded_beta_zero += 1;
        return None;
    }
    count_threshold_test::<R>(view);
    if !(0.0..=1.0).contains(&e.z)
        || winner == NO_PRIMITIVE
        || view.linear_depth(e.z as f64) > view.linear_depth(depth as f64) + threshold
    {
        report.discarded_threshold += 1;
        return None;
    }
    let (cos_a, cos_g_n) = shader.shader().terms(e.normal, e.to_eye);
    Some(BlendInput {
        beta: e.beta,
        diffuse: cos_a.f64(),
        specular: cos_g_n.f64(),
    })
}

/// The ROP's work on one discoid fragment at pixel `idx` in `pass`, on a whole-frame
/// target (the functional model).
#[inline]
pub fn process<R: Real>(
    pass: Pass,
    target: &mut DiscoidTarget,
    table: &DiscoidTable<R>,
    shader: &FragmentShader<R>,
    view: &View,
    idx: usize,
    f: &DiscoidFragment<R>,
) {
    let e = evaluate(table, shader, f);
    let (depth, winner) = (target.depth[idx], target.winner[idx]);
    match pass {
        Pass::Depth => {
            if depth_pass_wins(&e, f.id, depth, winner) {
                target.depth[idx] = e.z;
                target.winner[idx] = f.id;
                if let Some(normals) = target.normal.as_mut() {
                    normals[idx] = e.normal.map(|c| c.f64() as f32);
                }
            }
        }
        Pass::Accumulate => {
            let threshold = target.threshold;
            if let Some(input) = accumulation_keeps(
                &mut target.report,
                view,
                shader,
                threshold,
                &e,
                depth,
                winner,
            ) {
                target.kept.push(KeptFragment {
                    idx: idx as u32,
                    id: f.id,
                    st: f.st.map(f64::to_bits),
                    input,
                });
            }
        }
    }
}

/// The resolve pass: the image, and the error and hole counters in the target's report.
/// The ROPs resolve (the timed model's resolve pass): each pixel's Σβ test in the blend
/// ALU's word `B`, equation (6) in the datapath's `R`; a counting run charges both to the
/// ROP. The blend error beside them is the simulator's measurement, in `f64`, not counted.
pub fn resolve<R: Real, B: Real>(
    target: &mut DiscoidTarget,
    table: &DiscoidTable<R>,
    shader: &FragmentShader<R>,
    background: [u8; 3],
    height: u32,
) -> FrameBuffer {
    R::charge(UnitKind::Rop);
    B::charge(UnitKind::Rop);
    let width = target.width;
    let mut fb = FrameBuffer::new(width, height, background, target.normal.is_some());
    let s = shader.shader();
    let (ka, kd, ks) = (s.ka.f64(), s.kd.f64(), s.ks.f64().max(0.0));
    let luminance = |d: f64, g: f64| ka + kd * d + if ks > 0.0 { ks * g } else { 0.0 };
    let (mut max, mut sum, mut n) = (0.0f64, 0.0f64, 0u64);
    for idx in 0..fb.color.len() {
        let Some((d, g)) = target.mode.resolve_in::<B>(&target.accum[idx]) else {
            continue;
        };
        let color = table.color(target.winner[idx]).map(R::of);
        let c = s.combine(R::of(d), R::of(g), color);
        fb.write(idx, target.depth[idx], target.winner[idx], c.map(to_u8));
        if let (Some(out), Some(normals)) = (fb.normal.as_mut(), target.normal.as_ref()) {
            out[idx] = normals[idx];
        }
        if let Some((ed, eg)) = target.exact[idx].resolve() {
            let e = (luminance(d, g) - luminance(ed, eg)).abs();
            max = max.max(e);
            sum += e;
            n += 1;
        }
    }
    let r = &mut target.report;
    r.error_max = max;
    r.error_mean = if n > 0 { sum / n as f64 } else { 0.0 };
    r.holes = Some(count_holes(&fb, HOLE_REACH));
    fb
}

/// How far [`count_holes`] looks for covered pixels around an uncovered one \[pixels\].
pub const HOLE_REACH: u32 = 3;

/// Uncovered pixels with a covered pixel within `reach` pixels to their left, right, top
/// and bottom: holes inside the silhouette (the hole detection of Pfister et al. 2000, on the
/// image). A pixel the depth pass covered but whose every fragment the accumulation pass
/// discarded is uncovered too (the resolve leaves it the background). The one definition
/// of holes for every kind of discoid (planar, curved, surfels).
pub fn count_holes(fb: &FrameBuffer, reach: u32) -> u64 {
    let (w, h) = (fb.width as i64, fb.height as i64);
    let covered = |i: i64, j: i64| {
        (0..w).contains(&i)
            && (0..h).contains(&j)
            && fb.primitive[(j * w + i) as usize] != NO_PRIMITIVE
    };
    let r = reach as i64;
    let mut holes = 0;
    for j in 0..h {
        for i in 0..w {
            if covered(i, j) {
                continue;
            }
            let near = |di: i64, dj: i64| (1..=r).any(|k| covered(i + k * di, j + k * dj));
            if near(1, 0) && near(-1, 0) && near(0, 1) && near(0, -1) {
                holes += 1;
            }
        }
    }
    holes
}
