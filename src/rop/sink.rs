//! The ROP as a fragment sink: depth test, then shading of the fragments that pass (early
//! depth test: shading a fragment that loses cannot change the image), then the write.
//!
//! On plain `f32`/`f64` the fragments of one primitive that pass are held back, up to
//! [`BATCH`] of them, and shaded together in lanes ([`super::lanes`]): their depth and winner
//! are written at the test, their colour when the batch is shaded, in arrival order, so a
//! pixel two fragments of one primitive reach ends with the later one's colour as before.
//! A batch is shaded when it is full, when a fragment of another primitive (or another piece
//! of a split lembo) arrives, before a fragment is shaded alone, and at [`RopSink::finish`].

use super::fragment_shader::FragmentShader;
use super::framebuffer::{FrameBuffer, FrameRows};
use super::lanes::{self, three, Lanes, LANES};
use crate::camera::{Samples, View};
use crate::datapath::{Op, Real};
use crate::lembo::{eval3, Quadratic3};
use crate::raster::fragment::{self, FragmentSink, Span};
use crate::raster::setup::ScreenLembo;
use crate::raster::subsegmenter::Subsegment;
use crate::raster::triangle::{
    inv_w_at, perspective_lerp, row_by_pixels, ScreenTriangle, TriangleFragment, TriangleSink,
    WEIGHT_LANES,
};
use crate::scene::Light;

/// Fragments a ROP holds back to shade together, at most.
pub const BATCH: usize = 64;

/// What the fragments of a batch are shaded with.
#[derive(Clone, Copy)]
enum Surface<R> {
    /// A lembo, or a piece of one Setup split (its domain corners tell pieces apart): the
    /// fragments hold (u, v), and their normal and position come from its quadratics.
    Lembo {
        id: u32,
        domain: Option<[[f64; 2]; 3]>,
        normal: Quadratic3<R>,
        position: Quadratic3<R>,
        color: [R; 3],
    },
    /// A triangle, or a piece of one clipped (its parent's id; its own vertices tell pieces
    /// apart): the fragments hold their barycentric weights, and their normal and position
    /// are interpolated from its vertices'.
    Triangle {
        id: u32,
        x: [i64; 3],
        y: [i64; 3],
        inv_w: [R; 3],
        normal_w: [[R; 3]; 3],
        position_w: [[R; 3]; 3],
        color: [R; 3],
    },
}

/// Fragments of one primitive that passed the depth test and wait to be shaded: the
/// functional [`RopSink`]'s and each timed ROP unit's.
pub struct Batch<R> {
    of: Option<Surface<R>>,
    len: usize,
    /// Frame-buffer index of each fragment.
    idx: [usize; BATCH],
    /// Per fragment: (u, v) in rows 0 and 1 for a lembo, the three weights for a triangle.
    values: [[R; BATCH]; 3],
}

impl<R: Real> Batch<R> {
    /// An empty batch.
    pub fn new() -> Box<Self> {
        Box::new(Batch {
            of: None,
            len: 0,
            idx: [0; BATCH],
            values: [[R::zero(); BATCH]; 3],
        })
    }

    /// Makes the batch hold fragments of lembo `l` (or its piece), shading what it held of
    /// another primitive first.
    #[inline(always)]
    pub fn begin_lembo(
        &mut self,
        l: &ScreenLembo<R>,
        shader: &FragmentShader<R>,
        write: impl FnMut(usize, [u8; 3], [R; 3]),
    ) {
        let holds = self.holds_lembo(l);
        self.begin(holds, shader, write, || Surface::Lembo {
            id: l.id,
            domain: l.domain,
            normal: l.normal,
            position: l.position,
            color: l.color,
        });
    }

    /// Makes the batch hold fragments of triangle `t` (or its piece), shading what it held
    /// of another primitive first.
    #[inline(always)]
    pub fn begin_triangle(
        &mut self,
        t: &ScreenTriangle<R>,
        shader: &FragmentShader<R>,
        write: impl FnMut(usize, [u8; 3], [R; 3]),
    ) {
        let holds = self.holds_triangle(t);
        self.begin(holds, shader, write, || Surface::Triangle {
            id: t.id,
            x: t.x,
            y: t.y,
            inv_w: t.inv_w,
            normal_w: t.normal_w,
            position_w: t.position_w,
            color: t.color,
        });
    }

    /// Unless the batch `holds` the primitive's fragments already, shades what it holds and
    /// starts holding `surface`'s.
    #[inline(always)]
    fn begin(
        &mut self,
        holds: bool,
        shader: &FragmentShader<R>,
        write: impl FnMut(usize, [u8; 3], [R; 3]),
        surface: impl FnOnce() -> Surface<R>,
    ) {
        if !holds {
            self.flush(shader, write);
            self.of = Some(surface());
        }
    }

    /// Shades the fragments held and hands each to `write` (frame-buffer index, colour and
    /// the unit normal it was shaded with), in arrival order.
    pub fn flush(&mut self, shader: &FragmentShader<R>, write: impl FnMut(usize, [u8; 3], [R; 3])) {
        if self.len == 0 {
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if crate::isa::kernels() == crate::isa::Isa::Avx2 {
            // SAFETY: `kernels` says AVX2 only where the CPU has it. (No fused multiply-add is
            // enabled, and Rust does not contract without it: the same IEEE operations.)
            unsafe { self.flush_avx2(shader, write) };
            return;
        }
        self.flush_lanes(shader, write);
    }

    /// [`Self::flush_lanes`] compiled for AVX2: eight `f32` lanes in one register.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn flush_avx2(
        &mut self,
        shader: &FragmentShader<R>,
        write: impl FnMut(usize, [u8; 3], [R; 3]),
    ) {
        self.flush_lanes(shader, write);
    }

    /// Shades the batch `LANES` fragments at a time (a last, partial group repeats its last
    /// fragment in the spare lanes, whose results are not written) and hands the colours to
    /// `write` in arrival order.
    #[inline(always)]
    fn flush_lanes(
        &mut self,
        shader: &FragmentShader<R>,
        mut write: impl FnMut(usize, [u8; 3], [R; 3]),
    ) {
        let Some(surface) = self.of else {
            return;
        };
        let ortho = shader.to_eye_constant().is_some();
        for first in (0..self.len).step_by(LANES) {
            let (rgb, unit) = match &surface {
                Surface::Lembo {
                    normal,
                    position,
                    color,
                    ..
                } => {
                    let (u, v) = (self.lanes(0, first), self.lanes(1, first));
                    let at = |k: usize| {
                        let p = match ortho {
                            true => [R::zero(); 3],
                            false => eval3(position, u[k], v[k]),
                        };
                        (eval3(normal, u[k], v[k]), p)
                    };
                    shader.shade_lanes(at, *color)
                }
                Surface::Triangle {
                    inv_w,
                    normal_w,
                    position_w,
                    color,
                    ..
                } => {
                    let l = three(|row| self.lanes(row, first));
                    let at = |k: usize| {
                        let l = [l[0][k], l[1][k], l[2][k]];
                        let sum = inv_w_at(l, *inv_w);
                        let p = match ortho {
                            true => [R::zero(); 3],
                            false => perspective_lerp(l, sum, position_w),
                        };
                        (perspective_lerp(l, sum, normal_w), p)
                    };
                    shader.shade_lanes(at, *color)
                }
            };
            for k in 0..LANES.min(self.len - first) {
                write(self.idx[first + k], rgb[k], three(|c| unit[c][k]));
            }
        }
        self.len = 0;
    }

    fn holds_lembo(&self, l: &ScreenLembo<R>) -> bool {
        matches!(self.of, Some(Surface::Lembo { id, domain, .. }) if id == l.id && domain == l.domain)
    }

    fn holds_triangle(&self, t: &ScreenTriangle<R>) -> bool {
        matches!(self.of, Some(Surface::Triangle { id, x, y, .. }) if id == t.id && x == t.x && y == t.y)
    }

    /// Takes a fragment at `idx` with its values (for a lembo (u, v), for a triangle its
    /// three weights); whether the batch is now full.
    #[inline(always)]
    pub fn push<const N: usize>(&mut self, idx: usize, values: [R; N]) -> bool {
        self.idx[self.len] = idx;
        for (row, x) in values.into_iter().enumerate() {
            self.values[row][self.len] = x;
        }
        self.len += 1;
        self.len == BATCH
    }

    /// Lane k of row `row` for the fragments from `first` on (lanes past the last fragment
    /// repeat it; their results are not written).
    #[inline(always)]
    fn lanes(&self, row: usize, first: usize) -> Lanes<R> {
        let last = self.len - 1;
        lanes::lanes(|k| self.values[row][(first + k).min(last)])
    }
}

/// The ROP of the functional model: depth test, Phong shading and the frame-buffer write,
/// as a fragment sink for both paths.
pub struct RopSink<'a, R: Real> {
    fb: FrameRows<'a>,
    shader: FragmentShader<R>,
    /// Fragments that passed the depth test.
    pub passed: u64,
    /// The frame row that `fb`'s row 0 holds (a band of a frame drawn on several threads).
    row0: u32,
    batch: Box<Batch<R>>,
    /// Per column, the colour and normal a multisampled triangle (or piece) was last shaded
    /// with in that column, and at which pixel row: what a counting datapath's ROP shades
    /// once per pixel and primitive ([`RopSink::write_multisampled`]).
    shaded: Vec<Option<Shaded>>,
}

/// A pixel's colour and normal as a multisampled triangle was shaded there.
#[derive(Clone, Copy)]
struct Shaded {
    /// The triangle (id) or piece (its first vertex) and the pixel row.
    tag: (u32, i64, i64, u32),
    rgb: [u8; 3],
    normal: [f32; 3],
}

impl<'a, R: Real> RopSink<'a, R> {
    /// A ROP writing into `fb`, shading with `light` for `view`.
    pub fn new(fb: &'a mut FrameBuffer, light: &Light, view: &View) -> Self {
        RopSink::band(fb.rows_mut(), light, view, 0)
    }

    /// A ROP writing `rows`, whose first row is frame row `row0` (`frame::bands`'s
    /// bands).
    pub fn band(rows: FrameRows<'a>, light: &Light, view: &View, row0: u32) -> Self {
        RopSink {
            fb: rows,
            shader: FragmentShader::new(light, view),
            passed: 0,
            row0,
            batch: Batch::new(),
            shaded: Vec::new(),
        }
    }

    /// Shades what is held back; returns the fragments that passed the depth test and the
    /// pixels of its rows that some primitive covers.
    pub fn finish(mut self) -> (u64, u64) {
        self.flush();
        (self.passed, self.fb.covered() as u64)
    }

    /// Shades and writes the batch.
    fn flush(&mut self) {
        self.batch.flush(&self.shader, into_rows(&mut self.fb));
    }

    /// The depth test of a fragment of primitive `id` at pixel (i, j); a fragment that
    /// passes has its depth and winner written and joins the batch with `values`.
    #[inline(always)]
    fn test<const N: usize>(&mut self, id: u32, i: u32, j: u32, z: R, values: [R; N]) {
        let idx = self.fb.index(i, j - self.row0);
        let zf = z.f64() as f32;
        if self.fb.passes(idx, zf, id) {
            self.passed += 1;
            self.fb.write_depth(idx, zf, id);
            if self.batch.push(idx, values) {
                self.flush();
            }
        }
    }
}

/// Where a batch's colours go in the functional model: the frame rows `fb` (with the unit
/// normals, where normals are kept).
fn into_rows<'b, 'a: 'b, R: Real>(
    fb: &'b mut FrameRows<'a>,
) -> impl FnMut(usize, [u8; 3], [R; 3]) + use<'a, 'b, R> {
    move |idx, rgb, unit| fb.write_color(idx, rgb, || unit.map(|c| c.f64() as f32))
}

impl<R: Real> Drop for RopSink<'_, R> {
    /// What is held back is shaded even if [`RopSink::finish`] is not called.
    fn drop(&mut self) {
        self.flush();
    }
}

impl<R: Real> RopSink<'_, R> {
    /// Depth test, shading and write of one fragment of primitive `id`, shaded alone (for
    /// a counting datapath, and fragments handed over one by one).
    #[inline(always)]
    fn write(
        &mut self,
        id: u32,
        i: u32,
        j: u32,
        z: R,
        shade: impl FnOnce(&FragmentShader<R>) -> ([u8; 3], [R; 3]),
    ) {
        self.flush();
        let idx = self.fb.index(i, j - self.row0);
        let zf = z.f64() as f32;
        // The depth test's compare (on the stored f32 depth, beside the datapath).
        R::count_beside(Op::Cmp, 1);
        if !self.fb.passes(idx, zf, id) {
            return;
        }
        self.passed += 1;
        let (rgb, n) = shade(&self.shader);
        self.fb
            .write(idx, zf, id, rgb, || n.map(|c| c.f64() as f32));
    }
}

impl<R: Real> RopSink<'_, R> {
    /// [`Self::write`] of a sample of a multisampled triangle `t` at column i of sample row
    /// j, one by one (a counting datapath, a probe's fragments): the depth test per sample,
    /// and the shading once per pixel and triangle, at the pixel centre (the colour of its
    /// first sample that passes is kept for the pixel's others: the same colour whichever
    /// sample it is).
    fn write_multisampled(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, z: R) {
        self.flush();
        let idx = self.fb.index(i, j - self.row0);
        let zf = z.f64() as f32;
        R::count_beside(Op::Cmp, 1);
        if !self.fb.passes(idx, zf, t.id) {
            return;
        }
        self.passed += 1;
        let tag = (t.id, t.x[0], t.y[0], j / t.samples.get());
        if self.shaded.len() <= i as usize {
            self.shaded.resize(i as usize + 1, None);
        }
        let shaded = match self.shaded[i as usize] {
            Some(s) if s.tag == tag => s,
            _ => {
                let f = t.fragment_at(t.shading_weights(i, j), z);
                let (rgb, n) = self.shader.shade_at(f.normal, f.position, t.color);
                let s = Shaded {
                    tag,
                    rgb,
                    normal: n.map(|c| c.f64() as f32),
                };
                self.shaded[i as usize] = Some(s);
                s
            }
        };
        self.fb.write(idx, zf, t.id, shaded.rgb, || shaded.normal);
    }
}

impl<R: Real> TriangleSink<R> for RopSink<'_, R> {
    #[inline]
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>) {
        if t.samples != Samples::ONE {
            // Shaded at the pixel centre, not at the sample `f` was interpolated at.
            return self.write_multisampled(t, i, j, f.z);
        }
        self.write(t.id, i, j, f.z, |s| {
            s.shade_at(f.normal, f.position, t.color)
        });
    }

    #[inline]
    fn covered(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, l: [R; 3], z: R) {
        let multisampled = t.samples != Samples::ONE;
        if R::COUNTS_OPERATIONS {
            if multisampled {
                return self.write_multisampled(t, i, j, z);
            }
            let f = t.fragment_at(l, z);
            return TriangleSink::fragment(self, t, i, j, &f);
        }
        self.batch
            .begin_triangle(t, &self.shader, into_rows(&mut self.fb));
        // Multisampled, every sample of a pixel is shaded at the pixel centre.
        let l = if multisampled {
            t.shading_weights(i, j)
        } else {
            l
        };
        self.test(t.id, i, j, z, l);
    }

    /// The row's weights and depths [`WEIGHT_LANES`] pixels at a time (the same values as
    /// pixel by pixel), then the depth test of each pixel in turn.
    #[inline(always)]
    fn row(&mut self, t: &ScreenTriangle<R>, j: u32, a: u32, b: u32) {
        if R::COUNTS_OPERATIONS {
            return row_by_pixels(self, t, j, a, b);
        }
        self.batch
            .begin_triangle(t, &self.shader, into_rows(&mut self.fb));
        // The pixels two rows down, which the next row pair's same row will most likely test.
        self.fb.prefetch(a, j + 2 - self.row0);
        self.fb.prefetch(b - 1, j + 2 - self.row0);
        let edges = t.row_edges(j);
        let multisampled = t.samples != Samples::ONE;
        for i in (a..b).step_by(WEIGHT_LANES) {
            let (l, z) = t.weights_lanes(&edges, i);
            for k in 0..WEIGHT_LANES.min((b - i) as usize) {
                let i = i + k as u32;
                // Multisampled, every sample of a pixel is shaded at the pixel centre.
                let l = match multisampled {
                    false => [l[0][k], l[1][k], l[2][k]],
                    true => t.shading_weights(i, j),
                };
                self.test(t.id, i, j, z[k], l);
            }
        }
    }
}

impl<R: Real> FragmentSink<R> for RopSink<'_, R> {
    #[inline]
    fn fragment(
        &mut self,
        l: &ScreenLembo<R>,
        _sub: &Subsegment<R>,
        i: u32,
        j: u32,
        u: R,
        v: R,
        z: R,
    ) {
        self.write(l.id, i, j, z, |s| s.shade(l, u, v));
    }

    #[inline]
    fn span(&mut self, l: &ScreenLembo<R>, sub: &Subsegment<R>, j: u32, span: &Span<R>) {
        if R::COUNTS_OPERATIONS {
            return fragment::fragments(l, sub, j, span, self);
        }
        self.batch
            .begin_lembo(l, &self.shader, into_rows(&mut self.fb));
        self.fb.prefetch(span.i0, j + 1 - self.row0);
        self.fb.prefetch(span.i1 - 1, j + 1 - self.row0);
        span.walk(|i, u, v| self.test(l.id, i, j, l.z.eval(u, v), [u, v]));
    }
}
