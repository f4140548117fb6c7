//! Segmenter: walks the curve Y(u, v) = y_j over one interval in chords whose midpoint error
//! is exactly k (Martinelli 2006 section 5, "The segmentation problem").
//!
//! Input: a [`ScreenLembo`], the scanline and an [`Interval`]. Output: [`Segment`]s from the
//! interval's start to its end.
//!
//! From a point P on the curve the step s = (du, dv) solves the paper's second-degree system
//! `∇Y·s = ±4k`, `sᵀHs = ∓8k` (Y on the chord is a parabola, so its extreme error is at the
//! midpoint). We write s = α τ + β g in the unit walk direction τ = rot_cw(∇Y)/|∇Y| and the
//! unit gradient g: the first equation fixes β, the second is a quadratic in α solved with
//! the stable formula, taking the forward (positive) root; the other root is the step back.
//! The sign of k is chosen once per interval from the curvature τᵀHτ, which keeps its sign
//! along a level curve of a quadratic. One deviation from the paper, documented in
//! DESIGN.md §13: the residual Y(P) of the previous step's rounding is folded into the
//! system (`∇Y·s = ±4k - 3Y(P)`, `sᵀHs = ∓8k + 4Y(P)`), which makes Y(P + s) = 0 and the
//! midpoint error exactly ±k from the true curve, so rounding does not accumulate along the
//! walk; with Y(P) = 0 it is the paper's system.
//!
//! The walk ends when a step would pass the interval end (measured by the interval's walk
//! key) or leave the domain: the last segment is clamped to the end. A flat curve (τᵀHτ
//! about 0, no finite step), a vanishing gradient or a system without a forward root also
//! clamp to the end. More than `cap` segments in one interval is refused.

use super::counts::Counts;
use super::interval::{ConicPoint, Interval, INTERIOR};
use super::screen::ScreenLembo;
use super::v2::{dot, norm, rot_cw, V2};
use crate::datapath::Real;

/// One chord of the curve, from `p0` to `p1` in walking order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment<R> {
    /// The chord's start.
    pub p0: ConicPoint<R>,
    /// Its end.
    pub p1: ConicPoint<R>,
}

/// The walk of one interval ran past the segment cap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CapExceeded;

#[inline(always)]
fn quad_form<R: Real>(h: (R, R, R), s: V2<R>, t: V2<R>) -> R {
    h.0 * s[0] * t[0] + h.1 * (s[0] * t[1] + s[1] * t[0]) + h.2 * s[1] * t[1]
}

/// Appends the segments of `iv` to `out`, making every step.
pub fn segments<R: Real>(
    l: &ScreenLembo<R>,
    j: u32,
    k: R,
    iv: &Interval<R>,
    cap: usize,
    out: &mut Vec<Segment<R>>,
    counts: &mut Counts,
) -> Result<(), CapExceeded> {
    walk(l, j, k, iv, cap, None, out, counts)
}

/// [`walk`] compiled for AVX2 where the CPU has it (`isa::kernels`): the same IEEE
/// operations in the same order, so the same segments (the timed segmenters call it; the
/// functional model inlines [`walk`] into its own AVX2 scan-line stages).
#[allow(clippy::too_many_arguments)]
pub fn walk_dispatched<R: Real>(
    l: &ScreenLembo<R>,
    j: u32,
    k: R,
    iv: &Interval<R>,
    cap: usize,
    reach: Option<f64>,
    out: &mut Vec<Segment<R>>,
    counts: &mut Counts,
) -> Result<(), CapExceeded> {
    #[cfg(target_arch = "x86_64")]
    if crate::isa::kernels() == crate::isa::Isa::Avx2 {
        // SAFETY: `kernels` says AVX2 only where the CPU has it.
        return unsafe { walk_avx2(l, j, k, iv, cap, reach, out, counts) };
    }
    walk(l, j, k, iv, cap, reach, out, counts)
}

/// [`walk`] compiled for AVX2.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn walk_avx2<R: Real>(
    l: &ScreenLembo<R>,
    j: u32,
    k: R,
    iv: &Interval<R>,
    cap: usize,
    reach: Option<f64>,
    out: &mut Vec<Segment<R>>,
    counts: &mut Counts,
) -> Result<(), CapExceeded> {
    walk(l, j, k, iv, cap, reach, out, counts)
}

/// [`segments`], given the lembo's [`least_reach`] for k (worked out once for all its
/// intervals): a step sure to reach past the interval end is not made, which changes no
/// segment (`None`: every step is made).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn walk<R: Real>(
    l: &ScreenLembo<R>,
    j: u32,
    k: R,
    iv: &Interval<R>,
    cap: usize,
    reach: Option<f64>,
    out: &mut Vec<Segment<R>>,
    counts: &mut Counts,
) -> Result<(), CapExceeded> {
    let first = out.len();
    if iv.straight {
        out.push(Segment {
            p0: iv.start,
            p1: iv.end,
        });
        counts.segments += 1;
        return Ok(());
    }
    let yj = R::of(j as f64 + 0.5);
    let (h, h_scale, eps) = step_constants(l);
    let one = R::one();

    let grad = |p: V2<R>| {
        let (gu, gv) = l.y.grad(p[0], p[1]);
        [gu, gv]
    };
    let sigma = walk_sign(h, grad(iv.start.uv));

    let mut p = iv.start;
    let mut key = dot(iv.tau, p.uv);
    loop {
        if out.len() - first >= cap {
            return Err(CapExceeded);
        }
        let y0 = l.y.eval(p.uv[0], p.uv[1]) - yj;
        // Most walks of a small lembo end at the first step, past the interval end: that
        // step is not made where it is sure to get there.
        let next = match reach {
            Some(r) if passes_end(r, k, y0, p.uv, iv.tau, key, iv.end_key) => None,
            _ => {
                let g = grad(p.uv);
                step(h, h_scale, eps, sigma, k, y0, p.uv, g, norm(g))
            }
        };
        let stop = match next {
            Some(q) => {
                let qk = dot(iv.tau, q);
                let inside = q[0] >= -eps && q[1] >= -eps && q[0] + q[1] <= one + eps;
                if qk >= iv.end_key || qk <= key || !inside {
                    None
                } else {
                    key = qk;
                    Some(q)
                }
            }
            None => None,
        };
        match stop {
            Some(q) => {
                let p1 = ConicPoint {
                    uv: q,
                    x: l.x.eval(q[0], q[1]),
                    edge: INTERIOR,
                };
                out.push(Segment { p0: p, p1 });
                counts.segments += 1;
                p = p1;
            }
            None => {
                counts.segments_clamped += 1;
                return last_chords(l, yj, k, iv, p, first, cap, out, counts);
            }
        }
    }
}

/// Closes the walk from `p` to the interval end. The clamped chord's midpoint error is not
/// k by construction (the step that would have reached the end did not exist, passed it, or
/// left the domain): where it exceeds k, the chord is split at the curve point halfway in
/// walk key, recursively, so every chord of the walk stays within k of the scanline. The
/// curve is a graph over the walk direction inside the interval's part, so the point with a
/// given key is unique: the root of Y = y_j on the line `tau·p = key` where Y increases
/// across the curve (towards `rot_ccw(tau)`).
#[allow(clippy::too_many_arguments)]
fn last_chords<R: Real>(
    l: &ScreenLembo<R>,
    yj: R,
    k: R,
    iv: &Interval<R>,
    p: ConicPoint<R>,
    first: usize,
    cap: usize,
    out: &mut Vec<Segment<R>>,
    counts: &mut Counts,
) -> Result<(), CapExceeded> {
    // Rounding of Y in the datapath, so f32 does not split chords that are exactly k.
    let slack = k * R::of(1e-3) + R::epsilon() * R::of(64.0) * (yj.abs() + R::one());
    let too_far = |a: &ConicPoint<R>, b: &ConicPoint<R>| {
        let m = [
            (a.uv[0] + b.uv[0]) * R::of(0.5),
            (a.uv[1] + b.uv[1]) * R::of(0.5),
        ];
        (l.y.eval(m[0], m[1]) - yj).abs() > k + slack
    };
    // Nearly always the clamped chord is within k: it is the walk's last segment, and the
    // stack below (a kilobyte to set up) is not needed.
    // A chord of the walk, unless the interval has had `cap` already.
    let chord = |out: &mut Vec<Segment<R>>, counts: &mut Counts, p0, p1| {
        if out.len() - first >= cap {
            return Err(CapExceeded);
        }
        out.push(Segment { p0, p1 });
        counts.segments += 1;
        Ok(())
    };
    let far = too_far(&p, &iv.end);
    if !far {
        return chord(out, counts, p, iv.end);
    }
    // Depth-first, in walk order: (chord end, depth) still to close from `p`. The first
    // chord's test is the one just made.
    let mut known_far = Some(far);
    let mut todo = [(iv.end, 0u32); 48];
    let mut n = 1;
    let mut p = p;
    while n > 0 {
        let (e, depth) = todo[n - 1];
        let split = if depth + 1 < todo.len() as u32
            && known_far.take().unwrap_or_else(|| too_far(&p, &e))
        {
            let key = (dot(iv.tau, p.uv) + dot(iv.tau, e.uv)) * R::of(0.5);
            curve_at_key(l, yj, iv.tau, key).filter(|q| {
                let qk = dot(iv.tau, *q);
                let eps = R::epsilon() * R::of(64.0);
                qk > dot(iv.tau, p.uv)
                    && qk < dot(iv.tau, e.uv)
                    && q[0] >= -eps
                    && q[1] >= -eps
                    && q[0] + q[1] <= R::one() + eps
            })
        } else {
            None
        };
        match split {
            Some(q) => {
                let mid = ConicPoint {
                    uv: q,
                    x: l.x.eval(q[0], q[1]),
                    edge: INTERIOR,
                };
                todo[n - 1] = (e, depth + 1);
                todo[n] = (mid, depth + 1);
                n += 1;
                counts.segments_refined += 1;
            }
            None => {
                chord(out, counts, p, e)?;
                p = e;
                n -= 1;
            }
        }
    }
    Ok(())
}

/// The point of the curve Y = y_j on the line `tau·p = key` where Y increases towards
/// `rot_ccw(tau)`, or `None` when the line misses the curve.
// `!(x > 0)` is deliberate: it also rejects NaN.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn curve_at_key<R: Real>(l: &ScreenLembo<R>, yj: R, tau: V2<R>, key: R) -> Option<V2<R>> {
    let t2 = dot(tau, tau);
    if !(t2 > R::zero()) {
        return None;
    }
    // p(s) = o + s n, with o on the line and n = rot_ccw(tau) across it.
    let o = [tau[0] * key / t2, tau[1] * key / t2];
    let n = [-tau[1], tau[0]];
    let h = l.hessian;
    // Y(p(s)) - y_j = a s² + b s + c.
    let a = R::of(0.5) * quad_form(h, n, n);
    let (gu, gv) = l.y.grad(o[0], o[1]);
    let b = gu * n[0] + gv * n[1];
    let c = l.y.eval(o[0], o[1]) - yj;
    let disc = b * b - R::of(4.0) * a * c;
    if !(disc >= R::zero()) {
        return None;
    }
    let sq = disc.sqrt();
    // The root where dY/ds = 2 a s + b = +sqrt(disc), in the stable form.
    let s = if b < R::zero() {
        (sq - b) / (R::of(2.0) * a)
    } else {
        let d = b + sq;
        if d == R::zero() {
            return None;
        }
        -R::of(2.0) * c / d
    };
    let q = [o[0] + s * n[0], o[1] + s * n[1]];
    (q[0].is_finite() && q[1].is_finite()).then_some(q)
}

/// What every [`step`] of a walk on `l` takes from the lembo: y's Hessian, the scale its
/// forms are judged by and the relative tolerance they are judged with.
#[inline]
fn step_constants<R: Real>(l: &ScreenLembo<R>) -> ((R, R, R), R, R) {
    let h = l.hessian;
    let h_scale = h.0.abs().max(h.1.abs()).max(h.2.abs());
    (h, h_scale, R::epsilon() * R::of(64.0))
}

/// The sign of k in the steps of a walk, from the curvature `τᵀHτ` along the walk direction
/// `τ = rot_cw(g)` at its start (where ∇Y = `g`).
#[inline]
fn walk_sign<R: Real>(h: (R, R, R), g: V2<R>) -> R {
    let t = rot_cw(g);
    if quad_form(h, t, t) > R::zero() {
        -R::one()
    } else {
        R::one()
    }
}

/// The residual |Y(P) - y_j| up to which [`least_reach`] holds, as a fraction of k.
const RESIDUAL_FRACTION: f64 = 0.125;

/// How much looser than computed [`least_reach`] takes each of the Hessian's forms and the
/// gradient bounds, relative to their magnitudes: many times the datapath's rounding of
/// them.
const LOOSE: f64 = 1e-4;

/// How many times the distance to the interval end a step must be sure to reach before it is
/// not made ([`passes_end`]).
const REACH_MARGIN: f64 = 1.5;

/// A lower bound on how far in walk key any `step` of k from a point of the lembo's domain
/// reaches, where the residual there is at most `RESIDUAL_FRACTION` k; `None` for a
/// partition other than [`Partition::Monotone`](super::screen::Partition) or where the bound
/// is not positive. In `f64`, from per-lembo bounds: once per lembo ([`walk`]).
///
/// With a monotone partition, every gradient g of the domain has `a·g ≥ d > 0` and `|g| ≤ s`
/// (`grad_bounds`, taken 10⁻⁴ looser for the datapath's rounding of g). So the unit
/// gradient ĝ is within an angle θ of `a` with cos θ ≥ d / s, the unit tangent
/// τ̂ = rot_cw(ĝ) within θ of `t = rot_cw(a)` (the walk direction `tau` of the part), the key
/// advance per unit of α is `tau·τ̂ = a·ĝ ≥ d / s`, and β = lin / |g| ≤ (4k + 3|y0|) / d = βm.
/// Writing τ̂ and ĝ in the basis (t, a), the Hessian's forms are bounded by its forms on t
/// and a and sin θ: |τ̂ᵀHτ̂| ≤ At, |τ̂ᵀHĝ| ≤ Bt, |ĝᵀHĝ| ≤ Gt below. The step's α is a
/// positive root of A α² + B α + C = 0 with |A| ≤ At, |B| ≤ 2 βm Bt and
/// |C| ≥ 8k - 4|y0| - βm² Gt = Cm, and any positive root of such a quadratic is at least
/// |C| / (|B| + sqrt(|A C|)) (from 2|C| / (|B| ± B + sqrt(B² ∓ 4|A C|))), which falls as |A|
/// and |B| grow and rises with |C|. The key advances by α a·ĝ + β tau·ĝ ≥ α d / s - βm.
// `!(x > 0)` is deliberate: it also rejects NaN.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn least_reach<R: Real>(l: &ScreenLembo<R>, k: R) -> Option<f64> {
    let super::screen::Partition::Monotone { a, grad_bounds } = l.partition else {
        return None;
    };
    let grad_bounds = grad_bounds.map(R::f64);
    let (h0, h1, h2) = (l.hessian.0.f64(), l.hessian.1.f64(), l.hessian.2.f64());
    let m = h0.abs() + 2.0 * h1.abs() + h2.abs();
    let slack = LOOSE * (grad_bounds[1] + m);
    let (d, s) = (grad_bounds[0] - slack, grad_bounds[1] + slack);
    if !(d > 0.01 * s && m.is_finite()) {
        return None;
    }
    let a = [a[0].f64(), a[1].f64()];
    let t = [a[1], -a[0]];
    let form = |p: [f64; 2], q: [f64; 2]| quad_form((h0, h1, h2), p, q).abs() + LOOSE * m;
    let (htt, hta, haa) = (form(t, t), form(t, a), form(a, a));
    let sin = (1.0 - (d / s) * (d / s)).max(0.0).sqrt() * (1.0 + LOOSE);
    let at = htt + 2.0 * sin * hta + sin * sin * haa;
    let bt = hta * (1.0 + sin * sin) + sin * (htt + haa);
    let gt = haa + 2.0 * sin * hta + sin * sin * htt;
    let k = k.f64();
    let y0 = RESIDUAL_FRACTION * k;
    let beta = (4.0 * k + 3.0 * y0) / d;
    let c = 8.0 * k - 4.0 * y0 - beta * beta * gt;
    if !(c > 0.0) {
        return None;
    }
    let alpha = c / (2.0 * beta * bt + (at * c).sqrt());
    let reach = alpha * d / s - beta * (1.0 + LOOSE);
    (reach > 0.0).then_some(reach)
}

/// Whether the step from `p` (residual `y0`, walk key `key`) is sure to reach at least
/// [`REACH_MARGIN`] times as far as the interval end `end_key` when every step of the lembo
/// reaches `reach` ([`least_reach`]), so that the walk would refuse it. The margin and 64
/// units in the last place of the keys cover the datapath's rounding of the step: at most
/// about sqrt(ε) relative, where its quadratic has a double root, and far less elsewhere.
/// `tests::a_step_sure_to_pass_the_end_is_one_the_walk_refuses` checks on random lembos that
/// every walk is the same with and without the skip, and that each skipped first step would
/// have been refused.
#[inline]
fn passes_end<R: Real>(reach: f64, k: R, y0: R, p: V2<R>, tau: V2<R>, key: R, end_key: R) -> bool {
    let rounding = 64.0
        * R::epsilon().f64()
        * (tau[0].f64().abs() + tau[1].f64().abs())
        * (1.0 + p[0].f64().abs() + p[1].f64().abs());
    y0.f64().abs() <= RESIDUAL_FRACTION * k.f64()
        && REACH_MARGIN * (end_key.f64() - key.f64()) + rounding <= reach
}

/// One step of the extreme method from `p`, or `None` when it has no finite forward solution.
// `!(gn > 0)` is deliberate: it also rejects NaN.
#[allow(clippy::too_many_arguments, clippy::neg_cmp_op_on_partial_ord)]
#[inline]
fn step<R: Real>(
    h: (R, R, R),
    h_scale: R,
    eps: R,
    sigma: R,
    k: R,
    y0: R,
    p: V2<R>,
    g: V2<R>,
    gn: R,
) -> Option<V2<R>> {
    let zero = R::zero();
    if !(gn > zero) {
        return None;
    }
    let gh = [g[0] / gn, g[1] / gn];
    let th = rot_cw(gh);
    let htt = quad_form(h, th, th);
    if htt.abs() <= eps * h_scale || h_scale == zero {
        return None;
    }
    let htg = quad_form(h, th, gh);
    let hgg = quad_form(h, gh, gh);
    let four = R::of(4.0);
    let lin = four * sigma * k - R::of(3.0) * y0; // ∇Y·s
    let quad = -R::of(8.0) * sigma * k + four * y0; // sᵀHs
    let beta = lin / gn;
    // htt α² + 2 β htg α + (β² hgg - quad) = 0
    let bq = R::of(2.0) * beta * htg;
    let cq = beta * beta * hgg - quad;
    let disc = bq * bq - four * htt * cq;
    if disc < zero {
        return None;
    }
    let q = -R::of(0.5) * (bq + bq.signum() * disc.sqrt());
    if q == zero {
        return None;
    }
    let (r1, r2) = (q / htt, cq / q);
    let alpha = match (r1 > zero, r2 > zero) {
        (true, true) => r1.min(r2),
        (true, false) => r1,
        (false, true) => r2,
        (false, false) => return None,
    };
    let s = [alpha * th[0] + beta * gh[0], alpha * th[1] + beta * gh[1]];
    let q = [p[0] + s[0], p[1] + s[1]];
    (q[0].is_finite() && q[1].is_finite()).then_some(q)
}

#[cfg(test)]
mod tests;
