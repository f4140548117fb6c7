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
    #[allow(clippy::too_many_arguments)]
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
// `!(a < b)` is deliberate: it also rejects NaN.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::interval::{CurvePoint, INTERIOR};
    use crate::raster::setup::tests::{
        quad, scanline_fragments, screen_lembo, x_linear, y_bowl, y_error, y_plane, y_saddle,
        Collect, SIDE,
    };
    use std::collections::BTreeMap;

    fn sub(x0: f64, x1: f64) -> Subsegment<f64> {
        let p = |x: f64| CurvePoint {
            uv: [0.2, 0.2],
            x,
            edge: INTERIOR,
        };
        Subsegment { a: p(x0), b: p(x1) }
    }

    /// Pixels covered by the subsegments, with how often each is covered.
    fn pixels(subs: &[Subsegment<f64>]) -> BTreeMap<u32, u32> {
        let l = screen_lembo::<f64>(x_linear(), y_plane());
        let (mut sink, mut counts) = (Collect::default(), Counts::default());
        for s in subs {
            rasterize(&l, 7, s, SIDE, &mut sink, &mut counts);
        }
        assert_eq!(counts.fragments, sink.0.len() as u64);
        let mut hits = BTreeMap::new();
        for (i, _, _) in sink.0 {
            *hits.entry(i).or_insert(0) += 1;
        }
        hits
    }

    #[test]
    fn fragment_pixel_rule_is_half_open() {
        let want = BTreeMap::from([(10, 1), (11, 1)]);
        assert_eq!(pixels(&[sub(10.5, 12.5)]), want);
        assert_eq!(pixels(&[sub(12.5, 10.5)]), want);
        // Consecutive subsegments sharing x = 11.5 neither drop nor double pixel 11.
        let want = BTreeMap::from([(10, 1), (11, 1), (12, 1)]);
        assert_eq!(pixels(&[sub(10.2, 11.5), sub(11.5, 12.9)]), want);
        assert_eq!(pixels(&[sub(12.9, 11.5), sub(11.5, 10.2)]), want);
        // No pixel centre inside, or no length: nothing.
        assert!(pixels(&[sub(10.6, 11.4), sub(11.5, 11.5)]).is_empty());
    }

    #[test]
    fn fragment_pixels_outside_the_viewport_are_clipped() {
        assert_eq!(
            pixels(&[sub(-3.2, 2.7)]),
            BTreeMap::from([(0, 1), (1, 1), (2, 1)])
        );
        let right = pixels(&[sub(SIDE as f64 - 1.7, SIDE as f64 + 5.0)]);
        assert_eq!(right, BTreeMap::from([(SIDE - 2, 1), (SIDE - 1, 1)]));
        assert!(pixels(&[sub(-9.0, -1.0), sub(SIDE as f64 + 0.5, 1e9)]).is_empty());
    }

    #[test]
    fn fragment_domain_point_is_interpolated_at_the_pixel_centre() {
        let l = screen_lembo::<f64>(x_linear(), y_plane());
        let a = CurvePoint {
            uv: [0.1, 0.3],
            x: 10.25,
            edge: INTERIOR,
        };
        let b = CurvePoint {
            uv: [0.5, 0.1],
            x: 30.25,
            edge: INTERIOR,
        };
        let (mut sink, mut counts) = (Collect::default(), Counts::default());
        rasterize(
            &l,
            7,
            &Subsegment { a: b, b: a },
            SIDE,
            &mut sink,
            &mut counts,
        );
        assert_eq!(sink.0.len(), 20);
        for (i, u, v) in sink.0 {
            let t = (i as f64 + 0.5 - 10.25) / 20.0;
            assert!((u - (0.1 + 0.4 * t)).abs() < 1e-12 && (v - (0.3 - 0.2 * t)).abs() < 1e-12);
        }
    }

    fn hits<R: Real>(frags: &[(u32, R, R)]) -> BTreeMap<u32, u32> {
        let mut hits = BTreeMap::new();
        for (i, _, _) in frags {
            *hits.entry(*i).or_insert(0) += 1;
        }
        hits
    }

    fn closed_loop<R: Real>(slack: f64) {
        let l = screen_lembo::<R>(x_linear(), y_bowl());
        let (frags, c) = scanline_fragments(&l, 40, 0.5);
        assert!(c.virtual_roots == 2 && !frags.is_empty(), "{c:?}");
        for (_, u, v) in &frags {
            assert!(y_error(&l, 40, [*u, *v]) <= 0.5 + slack);
        }
        // The loop maps onto a piece of the scanline, run forward then back (the bowl is
        // seen edge-on along a contour): every pixel of that piece is covered exactly twice,
        // and the covered pixels are contiguous.
        let hits = hits(&frags);
        assert!(hits.values().all(|&n| n == 2), "{hits:?}");
        let (first, last) = (*hits.keys().next().unwrap(), *hits.keys().last().unwrap());
        assert_eq!(hits.len() as u32, last - first + 1);
    }

    #[test]
    fn fragment_closed_loop_covers_its_scanline_piece() {
        closed_loop::<f32>(1e-3);
        closed_loop::<f64>(1e-9);
    }

    fn saddle<R: Real>(slack: f64) {
        let l = screen_lembo::<R>(x_linear(), y_saddle());
        let (frags, c) = scanline_fragments(&l, 50, 0.5);
        assert!(c.saddle_splits > 0 && !frags.is_empty());
        for (_, u, v) in &frags {
            assert!(y_error(&l, 50, [*u, *v]) <= 0.5 + slack);
        }
    }

    #[test]
    fn fragment_saddle_crossing_stays_within_k() {
        saddle::<f32>(1e-3);
        saddle::<f64>(1e-9);
    }

    fn through_vertex<R: Real>() {
        // y = 10 + 40u + 20.5v: C = (0, 1) exactly on scanline 30; x = 20 + 80u + 30v puts C
        // at x = 50 and the crossing on AB at u = 20.5/40, x = 61.
        let l = screen_lembo::<R>(x_linear(), quad(0.0, 0.0, 0.0, 40.0, 20.5, 10.0));
        let (frags, c) = scanline_fragments(&l, 30, 0.5);
        assert_eq!((c.intervals, c.unpaired_roots), (1, 0));
        assert_eq!(hits(&frags), (50..61).map(|i| (i, 1)).collect());
    }

    #[test]
    fn fragment_scanline_through_a_vertex_covers_each_pixel_once() {
        through_vertex::<f32>();
        through_vertex::<f64>();
    }
}
