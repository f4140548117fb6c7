//! FragmentRasterizer: the fragments of one subsegment (paper 001 section 5: "the generation
//! of fragments along the subsegment may be done with a simple linear equation for the u
//! and v components, which may be evaluated step by step with simple increments").
//!
//! Input: a [`Subsegment`] of scanline j. Output: one fragment per pixel centre it covers,
//! passed to a [`FragmentSink`] with its (u, v) and depth z(u, v) from the lembo's depth
//! quadratic. Pixel rule (DESIGN §2): with the ends ordered so x0 <= x1, pixel i is covered
//! when x0 <= i + 0.5 < x1, so consecutive subsegments neither drop nor double a pixel.
//! Pixels outside the viewport are clipped here.

use super::setup::ScreenLembo;
use super::subsegmenter::Subsegment;
use super::Counts;
use crate::datapath::Real;

/// Receives fragments: the ROP in a render, a probe in tests and accuracy runs.
pub trait FragmentSink<R: Real> {
    /// A fragment of lembo `l` at pixel (i, j) with domain point (u, v) and depth z, from
    /// subsegment `sub`.
    fn fragment(
        &mut self,
        l: &ScreenLembo<R>,
        sub: &Subsegment<R>,
        i: u32,
        j: u32,
        u: R,
        v: R,
        z: R,
    );
}

/// Rasterizes one subsegment on scanline `j` of a viewport `width` pixels wide.
#[inline]
pub fn rasterize<R: Real, S: FragmentSink<R>>(
    l: &ScreenLembo<R>,
    j: u32,
    sub: &Subsegment<R>,
    width: u32,
    sink: &mut S,
    counts: &mut Counts,
) {
    let (a, b) = if sub.a.x <= sub.b.x {
        (sub.a, sub.b)
    } else {
        (sub.b, sub.a)
    };
    let dx = b.x - a.x;
    if !(dx > R::zero()) {
        return;
    }
    let half = R::of(0.5);
    let i0 = (a.x - half).ceil().max(R::zero());
    let i1 = (b.x - half).ceil().min(R::of(width as f64));
    if !(i0 < i1) {
        return;
    }
    let (i0, i1) = (i0.to_u32().unwrap_or(0), i1.to_u32().unwrap_or(0));
    let dudx = (b.uv[0] - a.uv[0]) / dx;
    let dvdx = (b.uv[1] - a.uv[1]) / dx;
    let x0 = R::of(i0 as f64) + half - a.x;
    let mut u = a.uv[0] + x0 * dudx;
    let mut v = a.uv[1] + x0 * dvdx;
    for i in i0..i1 {
        let z = l.z.eval(u, v);
        sink.fragment(l, sub, i, j, u, v, z);
        u = u + dudx;
        v = v + dvdx;
    }
    counts.fragments += (i1 - i0) as u64;
}
