//! The shader every ROP shades a fragment with ([`FragmentShader`]: Piranda et al. 2006
//! equation 6, [`super::shade`], for one view) and [`normalize`]. A file of its own so that
//! the functional ROP ([`super::sink`]), its shading in lanes ([`super::lanes`]), the timed ROP
//! units and the discoid passes import it without importing each other.

use super::shade::{to_u8, Shader};
use crate::camera::View;
use crate::datapath::Real;
use crate::lembo::eval3;
use crate::raster::setup::ScreenLembo;
use crate::scene::Light;

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

    /// The direction to the eye when it is the same everywhere (orthographic views).
    #[inline(always)]
    pub(super) fn to_eye_constant(&self) -> Option<[R; 3]> {
        self.to_eye
    }

    /// The eye position \[world units\].
    #[inline(always)]
    pub(super) fn eye(&self) -> [R; 3] {
        self.eye
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
