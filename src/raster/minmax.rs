//! MinMax finder: the y range of a lembo and the scanlines it covers (Martinelli 2006 section 5,
//! "Finding maximum and minimum values for y").
//!
//! Input: a [`ScreenLembo`]. Output: the inclusive range of scanlines `j` whose sample line
//! y = j + 0.5 meets [y_min, y_max], clipped to the viewport, or `None`.
//!
//! Candidates, as the paper lists them: the vertices A', B', C'; the extrema of the three
//! edge parabolas, (a) u = -d/(2a), v = 0, (b) u = 0, v = -e/(2b), (c) on u + v = 1 at
//! u = -(-2b + c + d - e) / (2(a + b - c)); and the interior critical point where both
//! partial derivatives vanish. The range is widened by a small pad so that a scanline
//! grazing an extremum is still handed to the interval manager, whose edge tests decide it
//! exactly (and identically for neighbouring lembos).

use super::screen::{Partition, ScreenLembo};
use crate::datapath::Real;

/// Widening of the y range \[pixels\] before rounding to scanlines.
const PAD_PX: f64 = 1e-3;

/// The y range [y_min, y_max] of the lembo over its domain \[pixels\].
pub fn y_range<R: Real>(l: &ScreenLembo<R>) -> (R, R) {
    let y = &l.y;
    let (zero, one, two) = (R::zero(), R::one(), R::of(2.0));
    let mut lo = l.vertex_y[0].min(l.vertex_y[1]).min(l.vertex_y[2]);
    let mut hi = l.vertex_y[0].max(l.vertex_y[1]).max(l.vertex_y[2]);
    let mut take = |u: R, v: R| {
        if u.is_finite() && v.is_finite() && u >= zero && v >= zero && u + v <= one {
            let val = y.eval(u, v);
            lo = lo.min(val);
            hi = hi.max(val);
        }
    };
    take(-y.d / (two * y.a), zero);
    take(zero, -y.e / (two * y.b));
    let uc = -(-two * y.b + y.c + y.d - y.e) / (two * (y.a + y.b - y.c));
    take(uc, one - uc);
    if let Partition::Central { centre, .. } = l.partition {
        take(centre[0], centre[1]);
    }
    (lo, hi)
}

/// The scanlines `j0..=j1` with j + 0.5 in the y range, clipped to `0..height`.
pub fn scanlines<R: Real>(l: &ScreenLembo<R>, height: u32) -> Option<(u32, u32)> {
    let (lo, hi) = y_range(l);
    let (lo, hi) = (lo.f64() - PAD_PX, hi.f64() + PAD_PX);
    let j0 = (lo - 0.5).ceil().max(0.0);
    let j1 = (hi - 0.5).floor().min(height as f64 - 1.0);
    (j0 <= j1).then_some((j0 as u32, j1 as u32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::setup::tests::{
        quad, screen_lembo, x_linear, y_bowl, y_plane, y_saddle, SIDE,
    };

    #[test]
    fn minmax_vertices_bound_a_plane() {
        // A = 10, B = 70, C = 40.
        let l = screen_lembo::<f32>(x_linear(), y_plane());
        assert_eq!(y_range(&l), (10.0, 70.0));
        assert_eq!(scanlines(&l, SIDE), Some((10, 69)));
    }

    #[test]
    fn minmax_interior_extremum_is_a_candidate() {
        let l = screen_lembo::<f64>(x_linear(), y_bowl());
        let (lo, _) = y_range(&l);
        assert!((lo - 40.3).abs() < 1e-12, "{lo}");
        assert_eq!(scanlines(&l, SIDE).map(|(j0, _)| j0), Some(40));
        // A saddle's critical value is no extremum: the range is set by the boundary.
        let l = screen_lembo::<f64>(x_linear(), y_saddle());
        let (lo, hi) = y_range(&l);
        assert!(lo < 50.3 - 1.0 && hi > 50.3 + 1.0);
    }

    #[test]
    fn minmax_edge_extrema_are_candidates() {
        // Each y has its minimum 20.5 on one edge, (a) v = 0, (b) u = 0, (c) u + v = 1, and
        // 30.5 at all three vertices, so only the edge candidate finds scanline 20 (which
        // grazes the minimum: kept by the pad for the interval manager to decide).
        for y in [
            quad(40.0, 0.0, 40.0, -40.0, 0.0, 30.5),
            quad(0.0, 40.0, 40.0, 0.0, -40.0, 30.5),
            quad(10.0, 10.0, -20.0, -10.0, -10.0, 30.5),
        ] {
            let l = screen_lembo::<f32>(x_linear(), y);
            assert_eq!(l.vertex_y, [30.5; 3]);
            assert_eq!(y_range(&l).0, 20.5, "{y:?}");
            assert_eq!(scanlines(&l, SIDE).map(|(j0, _)| j0), Some(20));
        }
    }

    #[test]
    fn minmax_clips_to_the_viewport() {
        // y from -30 to 170.
        let l = screen_lembo::<f32>(x_linear(), quad(0.0, 0.0, 0.0, 200.0, 100.0, -30.0));
        assert_eq!(scanlines(&l, SIDE), Some((0, SIDE - 1)));
        // y within [0.1, 0.4]: no sample line y = j + 0.5 in range.
        let l = screen_lembo::<f32>(x_linear(), quad(0.0, 0.0, 0.0, 0.3, 0.0, 0.1));
        assert_eq!(scanlines(&l, SIDE), None);
    }
}
