//! Subsegmenter: splits a segment so that x is linear within k on each piece (Martinelli 2006
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

use super::counts::Counts;
use super::interval::{ConicPoint, INTERIOR};
use super::screen::ScreenLembo;
use super::segmenter::Segment;
use crate::datapath::Real;

/// A piece of a segment over which u, v and x are treated as linear; `a` and `b` in walk
/// order (not sorted by x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Subsegment<R> {
    /// The subsegment's start, in walking order.
    pub a: ConicPoint<R>,
    /// Its end.
    pub b: ConicPoint<R>,
}

/// Most subsegments one segment may produce (a bound on work, far above any visible need:
/// one per pixel of a 16384-pixel scanline is 16384).
pub const MAX_SUBSEGMENTS_PER_SEGMENT: u32 = 1 << 15;

/// [`subsegments`] compiled for AVX2 where the CPU has it (`isa::kernels`): the same IEEE
/// operations in the same order, so the same subsegments (the timed subsegmenters call it).
pub fn subsegments_dispatched<R: Real>(
    l: &ScreenLembo<R>,
    seg: &Segment<R>,
    k: R,
    out: &mut Vec<Subsegment<R>>,
    counts: &mut Counts,
) {
    #[cfg(target_arch = "x86_64")]
    if crate::isa::kernels() == crate::isa::Isa::Avx2 {
        // SAFETY: `kernels` says AVX2 only where the CPU has it.
        return unsafe { subsegments_avx2(l, seg, k, out, counts) };
    }
    subsegments(l, seg, k, out, counts)
}

/// [`subsegments`] compiled for AVX2.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn subsegments_avx2<R: Real>(
    l: &ScreenLembo<R>,
    seg: &Segment<R>,
    k: R,
    out: &mut Vec<Subsegment<R>>,
    counts: &mut Counts,
) {
    subsegments(l, seg, k, out, counts)
}

/// Appends the subsegments of `seg` to `out`.
#[inline(always)]
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
            ConicPoint {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::setup::tests::{quad, screen_lembo, x_linear, y_plane};

    /// A segment of `l` between two domain points, with x from the lembo.
    fn segment<R: Real>(l: &ScreenLembo<R>, p0: [f64; 2], p1: [f64; 2]) -> Segment<R> {
        let point = |p: [f64; 2], edge| {
            let uv = p.map(R::of);
            ConicPoint {
                uv,
                x: l.x.eval(uv[0], uv[1]),
                edge,
            }
        };
        Segment {
            p0: point(p0, 2),
            p1: point(p1, 1),
        }
    }

    /// Checks that every subsegment is monotone in x and its chord within `k` (+ rounding)
    /// of the true x(u, v) along it; returns the subsegments' x ends.
    fn check<R: Real>(
        l: &ScreenLembo<R>,
        seg: &Segment<R>,
        k: f64,
    ) -> (Vec<Subsegment<R>>, Counts) {
        let (mut out, mut counts) = (Vec::new(), Counts::default());
        subsegments(l, seg, R::of(k), &mut out, &mut counts);
        let x = l.x.cast::<f64>();
        let round = if R::epsilon().f64() > 1e-10 {
            1e-3
        } else {
            1e-9
        };
        assert_eq!(out[0].a, seg.p0);
        assert_eq!(out.last().unwrap().b, seg.p1);
        for (n, s) in out.iter().enumerate() {
            assert_ne!(s.a.uv, s.b.uv, "subsegment {n} is a point");
            if n > 0 {
                assert_eq!(
                    out[n - 1].b,
                    s.a,
                    "subsegments {n} and {} do not meet",
                    n - 1
                );
            }
            let (a, b) = (s.a.uv.map(R::f64), s.b.uv.map(R::f64));
            let at = |t: f64| x.eval(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
            let dir = (at(1.0) - at(0.0)).signum();
            for m in 1..=32 {
                let (t0, t1) = ((m - 1) as f64 / 32.0, m as f64 / 32.0);
                assert!(
                    dir * (at(t1) - at(t0)) >= -round,
                    "subsegment {n} turns back"
                );
                let chord = s.a.x.f64() + t1 * (s.b.x.f64() - s.a.x.f64());
                assert!(
                    (chord - at(t1)).abs() <= k + round,
                    "subsegment {n}: chord off by {}",
                    chord - at(t1)
                );
            }
        }
        (out, counts)
    }

    /// x = 100u² - 100u + 45 + 20v, turning back at u = 1/2; y = 10 + 50v (level lines v = c).
    fn folding<R: Real>() -> ScreenLembo<R> {
        screen_lembo(
            quad(100.0, 0.0, 0.0, -100.0, 20.0, 45.0),
            quad(0.0, 0.0, 0.0, 0.0, 50.0, 10.0),
        )
    }

    fn fold<R: Real>() {
        let l = folding::<R>();
        let seg = segment(&l, [0.0, 0.2], [0.8, 0.2]);
        for k in [0.5, 0.05, 0.01] {
            let (subs, c) = check(&l, &seg, k);
            assert_eq!(c.folds, 1);
            assert_eq!(c.subsegments, subs.len() as u64);
            // The fold x = 24 (at u = 1/2) is where one subsegment ends and the next starts.
            let at_fold = subs
                .iter()
                .filter(|s| (s.b.uv[0].f64() - 0.5).abs() < 1e-6)
                .count();
            assert_eq!(at_fold, 1, "k {k}");
            let fold = subs
                .iter()
                .find(|s| (s.b.uv[0].f64() - 0.5).abs() < 1e-6)
                .unwrap();
            assert!((fold.b.x.f64() - 24.0).abs() < 1e-4, "{fold:?}");
            assert!(subs.iter().all(|s| s.a.x.min(s.b.x).f64() >= 24.0 - 1e-4));
            // Each side of the fold in the fewest equal steps within k: along the segment
            // x(t) = 64 t² + ..., the chord of a step dt errs by 64 dt²/4.
            let dt = (4.0 * k / 64.0f64).sqrt();
            let steps = |len: f64| (len / dt).ceil() as usize;
            assert_eq!(subs.len(), steps(0.5 / 0.8) + steps(0.3 / 0.8), "k {k}");
        }
        // A segment that starts or ends at the fold has none inside: one monotone piece.
        for (p0, p1) in [([0.5, 0.2], [0.9, 0.2]), ([0.1, 0.2], [0.5, 0.2])] {
            let (_, c) = check(&l, &segment(&l, p0, p1), 0.05);
            assert_eq!(c.folds, 0, "{p0:?}-{p1:?}");
        }
    }

    #[test]
    fn subsegmenter_splits_at_a_fold() {
        fold::<f32>();
        fold::<f64>();
    }

    #[test]
    fn subsegmenter_keeps_a_monotone_segment_whole_and_within_k() {
        let l = folding::<f64>();
        // u from 0.55 to 0.9: x increasing, no fold.
        let seg = segment(&l, [0.55, 0.1], [0.9, 0.1]);
        for k in [1.0, 0.1] {
            let (subs, c) = check(&l, &seg, k);
            assert_eq!(c.folds, 0);
            // The fewest equal steps with chord error within k: x'' = 2 a_t, error a_t dt²/4.
            let du: f64 = 0.35;
            let a_t = 100.0 * du * du;
            assert_eq!(
                subs.len() as f64,
                (1.0 / (4.0 * k / a_t).sqrt()).ceil(),
                "k {k}"
            );
        }
    }

    /// x's second derivative along a segment takes all three second-order terms of x(u, v)
    /// (u², v² and uv), each with its own sign: segments in both diagonal directions, where
    /// leaving out or flipping any of them misplaces x inside the segment.
    #[test]
    fn subsegmenter_takes_every_second_order_term_of_x() {
        // x = 30u² + 70v² - 90uv + 10u - 20v + 40: a saddle-free bowl tilted in (u, v).
        let l = screen_lembo::<f64>(quad(30.0, 70.0, -90.0, 10.0, -20.0, 40.0), y_plane());
        for (p0, p1) in [
            ([0.05, 0.05], [0.7, 0.25]),
            ([0.1, 0.8], [0.6, 0.05]),
            ([0.0, 0.0], [0.0, 0.9]),
        ] {
            for k in [0.5, 0.05] {
                let (subs, _) = check(&l, &segment(&l, p0, p1), k);
                assert!(subs.len() > 1, "{p0:?}-{p1:?} k {k}: x is not linear");
            }
        }
    }

    #[test]
    fn subsegmenter_linear_x_is_one_subsegment() {
        let l = screen_lembo::<f32>(x_linear(), y_plane());
        let seg = segment(&l, [0.0, 0.3], [0.6, 0.1]);
        let (subs, c) = check(&l, &seg, 0.5);
        assert_eq!((subs.len(), c.folds), (1, 0));
    }
}
