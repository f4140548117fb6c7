//! The ROP as a fragment sink: depth test, then shading of the fragments that pass (early
//! depth test: shading a fragment that loses cannot change the image), then the write.

use super::framebuffer::{FrameBuffer, FrameRows};
use super::shade::{to_u8, Light, Shader};
use crate::camera::View;
use crate::cost::counted::Op;
use crate::datapath::Real;
use crate::lembo::eval3;
use crate::raster::fragment::FragmentSink;
use crate::raster::setup::ScreenLembo;
use crate::raster::subsegmenter::Subsegment;
use crate::raster::triangle::{ScreenTriangle, TriangleFragment, TriangleSink};

/// Per-fragment shading (Piranda et al. 2006 equation 6) from the lembo's normal and position
/// functions; shared by the functional ROP and the timed ROP units so both give the same
/// colour bit for bit.
pub struct FragmentShader<R> {
    shader: Shader<R>,
    /// Eye position (perspective) [world units].
    eye: [R; 3],
    /// Constant direction to the eye (orthographic).
    to_eye: Option<[R; 3]>,
}

impl<R: Real> FragmentShader<R> {
    /// The shader of `light` for `view` (a constant direction to the eye when orthographic).
    pub fn new(light: &Light, view: &View) -> Self {
        let to_eye = view
            .orthographic
            .then(|| view.to_eye(glam::DVec3::ZERO).to_array().map(R::of));
        FragmentShader {
            shader: Shader::new(light),
            eye: view.eye.to_array().map(R::of),
            to_eye,
        }
    }

    /// The colour of lembo `l` at (u, v) and the unit normal it was shaded with.
    #[inline]
    pub fn shade(&self, l: &ScreenLembo<R>, u: R, v: R) -> ([u8; 3], [R; 3]) {
        let position = match self.to_eye {
            Some(_) => [R::zero(); 3],
            None => eval3(&l.position, u, v),
        };
        self.shade_at(eval3(&l.normal, u, v), position, l.color)
    }

    /// The colour of a surface point with (not necessarily unit) normal `normal` at world
    /// `position` (unused for orthographic views), and the unit normal it was shaded with.
    #[inline]
    pub fn shade_at(&self, normal: [R; 3], position: [R; 3], color: [R; 3]) -> ([u8; 3], [R; 3]) {
        let n = normalize(normal);
        let c = self.shader.shade(n, self.to_eye(position), color);
        ([to_u8(c[0]), to_u8(c[1]), to_u8(c[2])], n)
    }

    /// The unit direction from world `position` to the eye (constant for orthographic
    /// views, where `position` is unused).
    #[inline]
    pub fn to_eye(&self, position: [R; 3]) -> [R; 3] {
        match self.to_eye {
            Some(d) => d,
            None => {
                let p = position;
                normalize([self.eye[0] - p[0], self.eye[1] - p[1], self.eye[2] - p[2]])
            }
        }
    }

    /// The light and material terms.
    pub fn shader(&self) -> &Shader<R> {
        &self.shader
    }
}

/// The ROP of the functional model: depth test, Phong shading and the frame-buffer write,
/// as a fragment sink for both paths.
pub struct Rop<'a, R> {
    fb: FrameRows<'a>,
    shader: FragmentShader<R>,
    /// Fragments that passed the depth test.
    pub passed: u64,
    /// The frame row that `fb`'s row 0 holds (a band of a frame drawn on several threads).
    row0: u32,
}

impl<'a, R: Real> Rop<'a, R> {
    /// A ROP writing into `fb`, shading with `light` for `view`.
    pub fn new(fb: &'a mut FrameBuffer, light: &Light, view: &View) -> Self {
        Rop::band(fb.rows_mut(), light, view, 0)
    }

    /// A ROP writing `rows`, whose first row is frame row `row0` (`raster::parallel`'s
    /// bands).
    pub fn band(rows: FrameRows<'a>, light: &Light, view: &View, row0: u32) -> Self {
        Rop {
            fb: rows,
            shader: FragmentShader::new(light, view),
            passed: 0,
            row0,
        }
    }
}

/// `v` scaled to unit length, or zero for a zero vector.
#[inline(always)]
pub fn normalize<R: Real>(v: [R; 3]) -> [R; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if n > R::zero() {
        [v[0] / n, v[1] / n, v[2] / n]
    } else {
        [R::zero(); 3]
    }
}

impl<R: Real> Rop<'_, R> {
    /// Depth test, shading and write of one fragment of primitive `id`.
    #[inline(always)]
    fn write(
        &mut self,
        id: u32,
        i: u32,
        j: u32,
        z: R,
        shade: impl FnOnce(&FragmentShader<R>) -> ([u8; 3], [R; 3]),
    ) {
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

impl<R: Real> TriangleSink<R> for Rop<'_, R> {
    #[inline]
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>) {
        self.write(t.id, i, j, f.z, |s| {
            s.shade_at(f.normal, f.position, t.color)
        });
    }
}

impl<R: Real> FragmentSink<R> for Rop<'_, R> {
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
}
