//! Subsegmenter: splits a segment so that x is linear within k on each piece (paper 001
//! section 5, "The sub-segmentation").
//!
//! Input: a [`Segment`]. Output: [`Subsegment`]s. Along the segment, u(t) and v(t) are
//! linear and x(t) = a t² + b t + c with a = x_uu du²/2 + x_uv du dv + x_vv dv²/2 from the
//! lembo and b fixed so that x(0) and x(1) are the segment ends' carried x values (edge
//! values on domain edges, so neighbours agree). The chord of x over a step dt errs by
//! |a| dt²/4 at its middle, so dt = sqrt(4k/|a|) keeps it within k. We cut each monotone piece
//! into ceil(len/dt) equal steps (never longer than dt, without the paper's short last
//! step). A fold (x'(t) = 0 inside the segment, x turning back) is a cut point, so each
//! subsegment's chord spans its exact x extent.

use super::interval::{CurvePoint, INTERIOR};
use super::segmenter::Segment;
use super::setup::ScreenLembo;
use super::Counts;
use crate::datapath::Real;

/// A piece of a segment over which u, v and x are treated as linear; `a` and `b` in walk
/// order (not sorted by x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Subsegment<R> {
    pub a: CurvePoint<R>,
    pub b: CurvePoint<R>,
}

/// Most subsegments one segment may produce (a bound on work, far above any visible need:
/// one per pixel of a 16384-pixel scanline is 16384).
pub const MAX_SUBSEGMENTS_PER_SEGMENT: u32 = 1 << 15;

/// Appends the subsegments of `seg` to `out`.
pub fn subsegments<R: Real>(
    l: &ScreenLembo<R>,
    seg: &Segment<R>,
    k: R,
    out: &mut Vec<Subsegment<R>>,
    counts: &mut Counts,
) {
    let (zero, one) = (R::zero(), R::one());
    let (p0, p1) = (seg.p0, seg.p1);
    let du = p1.uv[0] - p0.uv[0];
    let dv = p1.uv[1] - p0.uv[1];
    let at = l.x.a * du * du + l.x.b * dv * dv + l.x.c * du * dv;
    let bt = p1.x - p0.x - at;
    let point = |t: R| {
        if t == zero {
            p0
        } else if t == one {
            p1
        } else {
            CurvePoint {
                uv: [p0.uv[0] + t * du, p0.uv[1] + t * dv],
                x: p0.x + t * (bt + t * at),
                edge: INTERIOR,
            }
        }
    };
    let fold = if at != zero {
        -bt / (R::of(2.0) * at)
    } else {
        -one
    };
    let mut cuts = [zero, one, one];
    let pieces = if fold > zero && fold < one {
        counts.folds += 1;
        cuts[1] = fold;
        2
    } else {
        1
    };
    let dt = if at != zero {
        (R::of(4.0) * k / at.abs()).sqrt()
    } else {
        R::infinity()
    };
    for w in 0..pieces {
        let (ta, tb) = (cuts[w], cuts[w + 1]);
        let n = ((tb - ta) / dt)
            .ceil()
            .to_u32()
            .unwrap_or(1)
            .clamp(1, MAX_SUBSEGMENTS_PER_SEGMENT);
        let mut a = point(ta);
        for i in 1..=n {
            let t = if i == n {
                tb
            } else {
                ta + (tb - ta) * R::of(i as f64) / R::of(n as f64)
            };
            let b = point(t);
            out.push(Subsegment { a, b });
            a = b;
        }
        counts.subsegments += n as u64;
    }
}
