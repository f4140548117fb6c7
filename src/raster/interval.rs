//! IntervalManager: the pieces of the curve Y(u, v) = y_j inside the domain, per scanline
//! (Martinelli 2006 section 5, "Managing Intervals").
//!
//! Input: a [`ScreenLembo`] and a scanline j (sample line y_j = j + 0.5). Output: the
//! [`Interval`]s of that scanline: each a start and an end point on the curve, in walking
//! order, that the segmenter connects.
//!
//! Roots on the three domain edges come from the numerically stable quadratic formula,
//! computed on each edge's own three points in a canonical order (`setup.rs`), so a lembo
//! and its neighbour find bit-identical roots, x values and decisions on a shared edge. The
//! number of roots on an edge is decided from the signs at its ends (a vertex exactly on the
//! scanline counts as above it) and of the edge's extremum, never from a rounded root, so a
//! crossing belongs to exactly one edge and is never doubled at a vertex.
//!
//! Pairing roots into intervals, which the paper leaves open, uses the walk partition of
//! `setup.rs`: within a part where `a·∇Y > 0` the curve is a graph over `rot_cw(a)`, so its
//! points in walking order are sorted by `rot_cw(a)·p`; along the walk (direction
//! `rot_cw(∇Y)`) an edge root where Y decreases counter-clockwise is an entry, the others
//! exits, and each entry pairs with the next root. Where the curve crosses the partition
//! line (the tips of an ellipse around an interior extremum) a virtual root ends one interval
//! and starts the next, which also turns a closed loop that touches no edge into two
//! intervals. At a saddle (the scanline within k/2 of the critical value) the curve is
//! taken as its two crossing lines: each interval is split at the crossing point into two
//! straight intervals, whose chords deviate from y_j by at most |y_j - y_saddle| <= k/2.
//!
//! Cost model hook: one interval per message; the timed pipeline charges per root pair.

use super::counts::Counts;
use super::screen::{edge_uv, Partition, ScreenLembo};
use super::v2::{dot, rot_cw, V2};
use crate::datapath::Real;

/// A point of the curve with its screen x \[pixels\] (from the edge curve on domain edges,
/// so shared edges agree bit for bit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConicPoint<R> {
    /// The point in the lembo's domain.
    pub uv: V2<R>,
    /// Its screen x \[pixels\].
    pub x: R,
    /// The domain edge (0: AB, 1: BC, 2: CA) the point was found on, or [`INTERIOR`].
    pub edge: u8,
}

/// [`ConicPoint::edge`] of a point not found on a domain edge.
pub const INTERIOR: u8 = 3;

/// One piece of the curve Y = y_j inside the domain, from `start` to `end` in walking order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval<R> {
    /// Where the walk starts.
    pub start: ConicPoint<R>,
    /// Where it ends.
    pub end: ConicPoint<R>,
    /// Walk key direction: `tau · p` increases strictly along the curve from start to end.
    pub tau: V2<R>,
    /// `tau · end`.
    pub end_key: R,
    /// The piece is a straight line (saddle case): one segment, no walk.
    pub straight: bool,
}

/// A root of the curve on the domain boundary (or a virtual one on the partition line).
#[derive(Clone, Copy, Debug)]
pub struct Crossing<R> {
    /// Where the curve crosses.
    pub p: ConicPoint<R>,
    /// Whether the walk enters the domain (or its part) here, rather than leaves.
    pub entry: bool,
    /// Part of the domain (+1 or -1) the crossing belongs to.
    pub part: i8,
    /// On the partition line rather than a domain edge.
    pub is_virtual: bool,
    key: R,
}

/// Reusable buffers of the interval manager (no allocation per scanline).
#[derive(Default)]
pub struct IntervalScratch<R> {
    crossings: Vec<Crossing<R>>,
}

/// Appends the intervals of scanline `j` to `out`.
pub fn intervals<R: Real>(
    l: &ScreenLembo<R>,
    j: u32,
    k: R,
    scratch: &mut IntervalScratch<R>,
    out: &mut Vec<Interval<R>>,
    counts: &mut Counts,
) {
    let xs = &mut scratch.crossings;
    let (a, saddle) = sorted_crossings(l, j, k, xs, counts);
    // One entry, then one exit: their interval, as `pair_crossings` would pair them, without
    // its loop.
    if let Some((p, q)) = entry_then_exit(xs, saddle) {
        out.push(Interval {
            start: p.p,
            end: q.p,
            tau: part_tau(a, p.part),
            end_key: q.key,
            straight: false,
        });
        counts.intervals += 1;
        return;
    }
    pair_crossings(l, a, saddle, xs, out, counts);
}

/// The crossings of scanline `j` in `xs` (cleared first), edge roots and any virtual ones,
/// sorted along the walk; the scanline's walk axis and saddle point, if any.
#[inline]
fn sorted_crossings<R: Real>(
    l: &ScreenLembo<R>,
    j: u32,
    k: R,
    xs: &mut Vec<Crossing<R>>,
    counts: &mut Counts,
) -> ([R; 2], Option<[R; 2]>) {
    let yj = R::of(j as f64 + 0.5);
    // The roots on the three domain edges, in edge order.
    xs.clear();
    for e in 0..3 {
        edge_crossings(l, e, yj, |p, entry| {
            xs.push(Crossing {
                p,
                entry,
                part: 1,
                is_virtual: false,
                key: R::zero(),
            })
        });
    }
    counts.edge_roots += xs.len() as u64;
    // The partition for this scanline: axis `a`, whether the domain is split, the saddle.
    let (a, split, saddle) = scanline_partition(l, yj, k, xs, counts);
    sort_crossings(l, a, split, xs);
    (a, saddle)
}

/// The entry and the exit, when the sorted crossings `xs` are one entry followed by one
/// exit of the same part and there is no saddle: most scanlines of a small lembo.
#[inline]
fn entry_then_exit<R: Real>(
    xs: &[Crossing<R>],
    saddle: Option<[R; 2]>,
) -> Option<(&Crossing<R>, &Crossing<R>)> {
    match (xs, saddle) {
        ([p, q], None) if p.entry && !q.entry && p.part == q.part => Some((p, q)),
        _ => None,
    }
}

/// The partition of scanline `yj` (DESIGN.md §2): the walk axis, whether the domain is
/// split in two parts, and the saddle point when the conic degenerates there; an interior
/// extremum's tips on the scanline are pushed to `xs` as virtual crossings.
#[inline]
fn scanline_partition<R: Real>(
    l: &ScreenLembo<R>,
    yj: R,
    k: R,
    xs: &mut Vec<Crossing<R>>,
    counts: &mut Counts,
) -> ([R; 2], bool, Option<[R; 2]>) {
    match l.partition {
        Partition::Monotone { a, .. } => (a, false, None),
        Partition::Valley { a } => (a, true, None),
        Partition::Central {
            centre,
            y_centre,
            det,
            eig,
        } => {
            let level = yj - y_centre;
            if det > R::zero() {
                // Interior extremum: split along the major axis; the curve crosses it at the
                // ellipse's tips p = centre ± s a⊥ with y_c + λ⊥ s²/2 = y_j.
                let (a, la) = eig[0];
                let (ap, lp) = eig[1];
                let s2 = R::of(2.0) * level / lp;
                if s2 > R::zero() {
                    let s = s2.sqrt();
                    for sign in [R::one(), -R::one()] {
                        let uv = [centre[0] + sign * s * ap[0], centre[1] + sign * s * ap[1]];
                        if in_domain(uv) {
                            let (gu, gv) = l.y.grad(uv[0], uv[1]);
                            // Walking from part -1 into part +1 when the walk climbs a·∇Y.
                            let up = dot(rot_cw([gu, gv]), [la * a[0], la * a[1]]) > R::zero();
                            let p = ConicPoint {
                                uv,
                                x: l.x.eval(uv[0], uv[1]),
                                edge: INTERIOR,
                            };
                            let (from, to) = if up { (-1, 1) } else { (1, -1) };
                            // A tip on a domain edge is also an edge root there. Merged with
                            // it: an exit from the domain ends the walk in `from` (no entry
                            // into `to`, which is outside); an entry starts it in `to`.
                            let merged = tip_on_edge(xs, uv);
                            if merged != Some(true) {
                                xs.push(Crossing {
                                    p,
                                    entry: false,
                                    part: from,
                                    is_virtual: true,
                                    key: R::zero(),
                                });
                            }
                            if merged != Some(false) {
                                xs.push(Crossing {
                                    p,
                                    entry: true,
                                    part: to,
                                    is_virtual: true,
                                    key: R::zero(),
                                });
                            }
                            counts.virtual_roots += 1;
                        }
                    }
                }
                (a, true, None)
            } else {
                // Saddle: the transverse axis is the eigenvector whose eigenvalue has the
                // sign of the level.
                let a = if (eig[0].1 >= R::zero()) == (level >= R::zero()) {
                    eig[0].0
                } else {
                    eig[1].0
                };
                let v_mode = level.abs() <= k * R::of(0.5) && in_domain(centre);
                (a, true, v_mode.then_some(centre))
            }
        }
    }
}

/// Assigns parts to edge roots, computes walk keys and sorts the crossings by part, then
/// key, exits first.
#[inline]
fn sort_crossings<R: Real>(l: &ScreenLembo<R>, a: [R; 2], split: bool, xs: &mut [Crossing<R>]) {
    // Assign parts to edge roots and compute walk keys. Ties put exits first: a curve that
    // touches an edge from inside leaves and re-enters there.
    for c in xs.iter_mut() {
        if split && !c.is_virtual {
            let (gu, gv) = l.y.grad(c.p.uv[0], c.p.uv[1]);
            c.part = if dot(a, [gu, gv]) >= R::zero() { 1 } else { -1 };
        }
        c.key = dot(part_tau(a, c.part), c.p.uv);
    }
    let order = |p: &Crossing<R>, q: &Crossing<R>| {
        p.part
            .cmp(&q.part)
            .then(
                p.key
                    .partial_cmp(&q.key)
                    .unwrap_or(std::cmp::Ordering::Equal),
            )
            .then(p.entry.cmp(&q.entry))
    };
    // Most scanlines of a small lembo cross two edges: the stable sort of two, inline.
    if let [p, q] = xs {
        if order(q, p).is_lt() {
            std::mem::swap(p, q);
        }
    } else {
        xs.sort_by(order);
    }
}

/// Pairs the sorted crossings into intervals (an entry with the next exit of its part),
/// splitting at the saddle when there is one; counts unpaired roots.
#[inline]
fn pair_crossings<R: Real>(
    l: &ScreenLembo<R>,
    a: [R; 2],
    saddle: Option<[R; 2]>,
    xs: &mut [Crossing<R>],
    out: &mut Vec<Interval<R>>,
    counts: &mut Counts,
) {
    // The open interval's part and the index of its entry in `xs`.
    let mut pending: Option<(i8, usize)> = None;
    for n in 0..xs.len() {
        // An exit and an entry at the same place: exit first when an interval is open (the
        // curve touches an edge from inside: it leaves and re-enters there), entry first
        // when none is (the curve touches the domain at one point, e.g. a top vertex on the
        // scanline: an empty interval). "The same place" is within rounding of the walk
        // key: on a sliver two roots far apart in (u, v) can be a few ulps apart in key,
        // in either order (found by the datapath study, `nearly_degenerate_160.json`). The
        // swap only ever turns an order that would leave a root unpaired into one that
        // pairs.
        if let [c, d, ..] = &xs[n..] {
            let tol = R::epsilon() * R::of(256.0) * (R::one() + c.key.abs().max(d.key.abs()));
            if c.entry == pending.is_some()
                && d.entry != c.entry
                && d.part == c.part
                && (d.key - c.key).abs() <= tol
            {
                xs.swap(n, n + 1);
            }
        }
        let c = &xs[n];
        if c.entry {
            if pending.is_some() {
                counts.unpaired_roots += 1;
            }
            pending = Some((c.part, n));
        } else {
            match pending.take() {
                Some((part, start)) if part == c.part => {
                    let start = xs[start].p;
                    let tau = part_tau(a, part);
                    match saddle {
                        Some(centre) => {
                            let mid = ConicPoint {
                                uv: centre,
                                x: l.x.eval(centre[0], centre[1]),
                                edge: INTERIOR,
                            };
                            for (s, e) in [(start, mid), (mid, c.p)] {
                                out.push(Interval {
                                    start: s,
                                    end: e,
                                    tau,
                                    end_key: dot(tau, e.uv),
                                    straight: true,
                                });
                            }
                            counts.saddle_splits += 1;
                        }
                        None => out.push(Interval {
                            start,
                            end: c.p,
                            tau,
                            end_key: c.key,
                            straight: false,
                        }),
                    }
                    counts.intervals += 1;
                }
                Some(_) => counts.unpaired_roots += 2,
                None => counts.unpaired_roots += 1,
            }
        }
    }
    if pending.is_some() {
        counts.unpaired_roots += 1;
    }
}
/// When exactly one edge root lies at the tip `uv` (within rounding: the ellipse's tip is on
/// a domain edge), removes it and returns whether it was an entry. Rounding would otherwise
/// put it on either side of the partition line, with a walk key one ulp from the tip's,
/// and leave roots unpaired.
fn tip_on_edge<R: Real>(xs: &mut Vec<Crossing<R>>, uv: V2<R>) -> Option<bool> {
    let tol = R::epsilon() * R::of(64.0);
    let near = |c: &Crossing<R>| {
        !c.is_virtual && (c.p.uv[0] - uv[0]).abs() <= tol && (c.p.uv[1] - uv[1]).abs() <= tol
    };
    let mut found = xs.iter().enumerate().filter(|(_, c)| near(c));
    match (found.next(), found.next()) {
        (Some((n, _)), None) => Some(xs.remove(n).entry),
        _ => None,
    }
}

#[inline]
fn part_tau<R: Real>(a: V2<R>, part: i8) -> V2<R> {
    let s = if part >= 0 { R::one() } else { -R::one() };
    rot_cw([s * a[0], s * a[1]])
}

#[inline]
fn in_domain<R: Real>(p: V2<R>) -> bool {
    p[0] >= R::zero() && p[1] >= R::zero() && p[0] + p[1] <= R::one()
}

/// The roots of Y = y_j on domain edge `e`, in lembo order along the edge, with whether each
/// is an entry (Y decreasing along the counter-clockwise boundary).
pub fn edge_crossings<R: Real>(
    l: &ScreenLembo<R>,
    e: usize,
    yj: R,
    mut push: impl FnMut(ConicPoint<R>, bool),
) {
    let c = &l.edges[e];
    let f0 = c.y[0] - yj;
    let f1 = c.y[2] - yj;
    let (s0, s1) = (f0 >= R::zero(), f1 >= R::zero());
    // y(t) - y_j = A t² + B t + C through the canonical start, middle and end.
    let cc = f0;
    let (a, b) = c.y_power();
    let mut roots = [R::zero(); 2];
    let n = if s0 != s1 {
        roots[0] = one_root_in_unit(a, b, cc);
        1
    } else {
        if a == R::zero() {
            return;
        }
        let tm = c.y_vertex((a, b));
        if !(tm > R::zero() && tm < R::one()) {
            return;
        }
        let fm = cc - c.y_dip((a, b));
        if (fm >= R::zero()) == s0 {
            return;
        }
        let (r1, r2) = stable_roots(a, b, cc);
        roots = [
            r1.min(r2).max(R::zero()).min(R::one()),
            r1.max(r2).max(R::zero()).min(R::one()),
        ];
        2
    };
    let (ax, bx) = c.x_power();
    // Lembo-order sign at the edge start decides the type of the first crossing.
    let start_above = if c.reversed { s1 } else { s0 };
    // The crossing at edge parameter t (canonical order), with its parameter in lembo order.
    let point = |t: R| {
        let tl = if c.reversed { R::one() - t } else { t };
        let p = ConicPoint {
            uv: edge_uv(e, tl),
            x: c.x[0] + t * (bx + t * ax),
            edge: e as u8,
        };
        (tl, p)
    };
    // Crossings alternate: the first, in lembo order, leaves the start's side.
    let (t0, p0) = point(roots[0]);
    if n == 1 {
        push(p0, start_above);
        return;
    }
    let (t1, p1) = point(roots[1]);
    let (first, second) = if t1 < t0 { (p1, p0) } else { (p0, p1) };
    push(first, start_above);
    push(second, !start_above);
}

/// Both roots of A t² + B t + C by the numerically stable formula (no cancellation between
/// -B and the square root); a vanishing A leaves the linear root in both places.
pub fn stable_roots<R: Real>(a: R, b: R, c: R) -> (R, R) {
    let disc = (b * b - R::of(4.0) * a * c).max(R::zero());
    let q = -R::of(0.5) * (b + b.signum() * disc.sqrt());
    if a == R::zero() || q == R::zero() {
        // Linear (or both coefficients zero: no information; use t = 0).
        let t = if b != R::zero() { -c / b } else { R::zero() };
        return (t, t);
    }
    (q / a, c / q)
}

/// The root in [0, 1] of a quadratic whose values at 0 and 1 have opposite signs; rounding
/// may put the computed root just outside, so the nearest root is clamped into the interval.
fn one_root_in_unit<R: Real>(a: R, b: R, c: R) -> R {
    let (r1, r2) = stable_roots(a, b, c);
    let dist = |t: R| {
        if t.is_nan() {
            R::infinity()
        } else {
            (-t).max(t - R::one()).max(R::zero())
        }
    };
    let t = if dist(r1) <= dist(r2) { r1 } else { r2 };
    t.max(R::zero()).min(R::one())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lembo::Quadratic;
    use crate::raster::setup::tests::{
        quad, scanline_fragments, screen_lembo, x_linear, y_bowl, y_error, y_plane, y_saddle,
    };
    use crate::testkit::SplitMix64;

    /// The intervals of scanline `j` and the counts.
    fn run<R: Real>(l: &ScreenLembo<R>, j: u32, k: f64) -> (Vec<Interval<R>>, Counts) {
        let (mut out, mut counts) = (Vec::new(), Counts::default());
        intervals(
            l,
            j,
            R::of(k),
            &mut IntervalScratch::default(),
            &mut out,
            &mut counts,
        );
        (out, counts)
    }

    /// On every scanline of random lembos (from nearly flat to strongly bent), in both
    /// datapaths: `intervals`, which pairs an entry followed by an exit without the pairing
    /// loop, gives the intervals and counts that the loop gives; and both ways are taken
    /// often (the loop on scanlines with other crossings).
    fn shortcut_pairs_as_the_loop<R: Real>() {
        let mut rng = SplitMix64::new(0x2545_f491_4f6c_dd1d);
        let (mut shortcut, mut looped) = (0, 0);
        for n in 0..300 {
            let bend = [2.0, 10.0, 40.0, 200.0][n % 4];
            let Some(l) = crate::raster::setup::tests::random_lembo::<R>(&mut rng, bend) else {
                continue;
            };
            for k in [0.05, 2.0] {
                for j in 0..crate::raster::setup::tests::SIDE {
                    let (got, got_counts) = run(&l, j, k);
                    let (mut want, mut counts) = (Vec::new(), Counts::default());
                    let mut xs = Vec::new();
                    let (a, saddle) = sorted_crossings(&l, j, R::of(k), &mut xs, &mut counts);
                    match entry_then_exit(&xs, saddle) {
                        Some(_) => shortcut += 1,
                        None if !xs.is_empty() => looped += 1,
                        None => {}
                    }
                    pair_crossings(&l, a, saddle, &mut xs, &mut want, &mut counts);
                    assert_eq!((got, got_counts), (want, counts), "lembo {n}, scanline {j}");
                }
            }
        }
        assert!(shortcut > 1000 && looped > 1000, "{shortcut} {looped}");
    }

    /// The tips an interior extremum puts on a scanline lie on the curve Y = y_j, for a bowl
    /// whose axes are not the domain's (y = 40.3 + 100 ((u-.3)² + (v-.3)²) + 80 (u-.3)(v-.3):
    /// eigenvectors along the diagonals, so both components of each tip move).
    fn tips_on_the_curve<R: Real>() {
        let l = screen_lembo::<R>(x_linear(), quad(100.0, 100.0, 80.0, -84.0, -84.0, 65.5));
        for j in [41, 45, 50] {
            let (mut xs, mut counts) = (Vec::new(), Counts::default());
            sorted_crossings(&l, j, R::of(0.5), &mut xs, &mut counts);
            assert_eq!(counts.virtual_roots, 2, "scanline {j}");
            let tips: Vec<_> = xs.iter().filter(|c| c.is_virtual).collect();
            assert!(!tips.is_empty(), "scanline {j}");
            for c in tips {
                let [u, v] = c.p.uv;
                let y = l.y.eval(u, v).f64();
                assert!(
                    (y - (j as f64 + 0.5)).abs() < tol::<R>(),
                    "scanline {j}: {y} at {u:?}, {v:?}"
                );
            }
        }
    }

    #[test]
    fn an_extremum_puts_its_tips_on_the_scanline() {
        tips_on_the_curve::<f32>();
        tips_on_the_curve::<f64>();
    }

    /// `pair_crossings` on crossings of one part at walk keys `keys` (entry or exit): the
    /// intervals as (start key, end key), and the unpaired roots.
    fn paired<R: Real>(keys: &[(R, bool)]) -> (Vec<(f64, f64)>, u64) {
        let in_one_part: Vec<_> = keys.iter().map(|&(key, entry)| (key, entry, 1)).collect();
        paired_in_parts(&in_one_part)
    }

    /// [`paired`] on crossings (key, entry, part) of either part.
    fn paired_in_parts<R: Real>(keys: &[(R, bool, i8)]) -> (Vec<(f64, f64)>, u64) {
        let l = screen_lembo::<R>(x_linear(), y_plane());
        let mut xs: Vec<Crossing<R>> = keys
            .iter()
            .map(|&(key, entry, part)| Crossing {
                p: ConicPoint {
                    uv: [R::of(0.25), R::of(0.25)],
                    x: key,
                    edge: 0,
                },
                entry,
                part,
                is_virtual: false,
                key,
            })
            .collect();
        let (mut out, mut counts) = (Vec::new(), Counts::default());
        pair_crossings(
            &l,
            [R::one(), R::zero()],
            None,
            &mut xs,
            &mut out,
            &mut counts,
        );
        let ends = out
            .iter()
            .map(|i| (i.start.x.f64(), i.end_key.f64()))
            .collect();
        (ends, counts.unpaired_roots)
    }

    /// An exit then an entry within rounding of one key (a few ulps apart, at keys near 0
    /// and near 1000) are the curve touching the domain at one point: paired entry first.
    /// Apart, they are not paired; an entry while one is open leaves the first unpaired and
    /// pairs the second; an exit then an entry while one is open are the curve touching an
    /// edge from inside; an entry and an exit of different parts are both unpaired.
    fn pairs_within_rounding<R: Real>() {
        let ulps = |key: f64| R::of(key) + R::epsilon() * R::of(4.0 * (1.0 + key));
        for key in [0.0, 1000.0] {
            let (out, unpaired) = paired(&[(R::of(key), false), (ulps(key), true)]);
            assert_eq!((out.len(), unpaired), (1, 0), "at key {key}");
        }
        assert_eq!(
            paired(&[(R::of(0.0), false), (R::of(0.5), true)]),
            (vec![], 2)
        );
        let r = |x: f64| R::of(x).f64();
        assert_eq!(
            paired(&[(R::of(0.0), true), (R::of(0.2), true), (R::of(0.5), false)]),
            (vec![(r(0.2), r(0.5))], 1)
        );
        // The curve touching an edge from inside: with an interval open, an exit then an
        // entry within rounding stay in that order (it leaves and re-enters there).
        let touch = R::of(0.5);
        assert_eq!(
            paired(&[
                (R::of(0.0), true),
                (touch, false),
                (ulps(0.5), true),
                (R::of(1.0), false)
            ]),
            (vec![(r(0.0), touch.f64()), (ulps(0.5).f64(), r(1.0))], 0)
        );
        // An entry of one part and an exit of the other do not pair.
        for (entry_part, exit_part) in [(-1, 1), (1, -1)] {
            assert_eq!(
                paired_in_parts(&[
                    (R::of(0.0), true, entry_part),
                    (R::of(0.5), false, exit_part)
                ]),
                (vec![], 2)
            );
        }
    }

    #[test]
    fn roots_within_rounding_of_each_other_pair() {
        pairs_within_rounding::<f32>();
        pairs_within_rounding::<f64>();
    }

    /// The domain is the closed triangle u, v >= 0, u + v <= 1.
    #[test]
    fn the_domain_is_the_closed_triangle() {
        for p in [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.5], [0.2, 0.3]] {
            assert!(in_domain::<f64>(p), "{p:?}");
        }
        let e = 1e-9;
        for p in [
            [-e, 0.3],
            [0.3, -e],
            [0.5 + e, 0.5],
            [0.6, 0.6],
            [-0.5, -0.5],
            [2.0, -1.0],
        ] {
            assert!(!in_domain::<f64>(p), "{p:?}");
        }
    }

    /// Every edge root of random lembos (curved in x as in y) lies on its edge with the
    /// screen x of the lembo there and y on the scanline.
    fn roots_lie_where_they_say<R: Real>() {
        let mut rng = SplitMix64::new(0x9e37_79b9_7f4a_7c15);
        let mut roots = 0;
        for n in 0..60 {
            let Some(l) = crate::raster::setup::tests::random_lembo::<R>(&mut rng, 40.0) else {
                continue;
            };
            for j in (0..crate::raster::setup::tests::SIDE).step_by(3) {
                for (e, on_edge) in roots_per_edge(&l, j).iter().enumerate() {
                    for (p, _) in on_edge {
                        roots += 1;
                        let [u, v] = p.uv;
                        assert_eq!(p.edge as usize, e);
                        let x = l.x.eval(u, v).f64();
                        let y = l.y.eval(u, v).f64();
                        let scale = 1.0 + x.abs();
                        assert!(
                            (p.x.f64() - x).abs() < tol::<R>() * scale,
                            "lembo {n}, scanline {j}: x {:?} against {x}",
                            p.x
                        );
                        assert!(
                            (y - (j as f64 + 0.5)).abs() < tol::<R>() * 10.0,
                            "lembo {n}, scanline {j}: y {y}"
                        );
                    }
                }
            }
        }
        assert!(roots > 1000, "{roots}");
    }

    #[test]
    fn edge_roots_lie_on_the_curve_at_their_x() {
        roots_lie_where_they_say::<f32>();
        roots_lie_where_they_say::<f64>();
    }

    /// The shortcut takes exactly two crossings, an entry then an exit of one part, with no
    /// saddle; anything else (an exit first, two entries, two parts, a saddle, one or three
    /// crossings) goes to the pairing loop.
    #[test]
    fn only_an_entry_then_an_exit_of_one_part_takes_the_shortcut() {
        let c = |entry: bool, part: i8| Crossing {
            p: ConicPoint {
                uv: [0.25, 0.25],
                x: 3.0,
                edge: INTERIOR,
            },
            entry,
            part,
            is_virtual: false,
            key: 0.0f64,
        };
        let (entry, exit) = (c(true, 1), c(false, 1));
        assert!(entry_then_exit(&[entry, exit], None).is_some());
        assert!(entry_then_exit(&[c(true, -1), c(false, -1)], None).is_some());
        for xs in [
            vec![exit, entry],
            vec![entry, entry],
            vec![exit, exit],
            vec![entry, c(false, -1)],
            vec![entry],
            vec![entry, exit, exit],
            vec![],
        ] {
            assert!(entry_then_exit(&xs, None).is_none(), "{xs:?}");
        }
        assert!(entry_then_exit(&[entry, exit], Some([0.5, 0.5])).is_none());
    }

    /// Checks that `iv` is one piece of the curve Y = y_j in the domain, inside its part of
    /// the partition: the walk key does not decrease from start to end, and every key
    /// strictly between has a curve point in the domain on the part's side. Along the line
    /// of one key, p(w) = key·τ + w·n with n = rot_ccw(τ) (the part's axis, so the part is
    /// where n·∇Y >= 0), Y is a quadratic in w whose derivative is affine: Y increases on a
    /// half-line only, so the part holds at most one curve point per key, and an interval
    /// joining the ends of two different pieces leaves keys between them with none.
    fn assert_one_piece<R: Real>(l: &ScreenLembo<R>, j: u32, iv: &Interval<R>, what: &str) {
        let y = l.y.cast::<f64>();
        let g = |p: [f64; 2]| y.eval(p[0], p[1]) - (j as f64 + 0.5);
        let len = iv.tau[0].f64().hypot(iv.tau[1].f64());
        let tau = [iv.tau[0].f64() / len, iv.tau[1].f64() / len];
        let n = [-tau[1], tau[0]];
        let key = |p: V2<R>| tau[0] * p[0].f64() + tau[1] * p[1].f64();
        let (k0, k1) = (key(iv.start.uv), key(iv.end.uv));
        let slack = if R::epsilon().f64() > 1e-10 {
            1e-5
        } else {
            1e-12
        };
        assert!(
            k0 <= k1 + slack,
            "{what}: key falls from {k0} to {k1}: {iv:?}"
        );
        for f in [0.125, 0.5, 0.875] {
            let t = k0 + f * (k1 - k0);
            let p = |w: f64| [t * tau[0] + w * n[0], t * tau[1] + w * n[1]];
            // The line's w range inside the triangle: each of u >= 0, v >= 0, 1 - u - v >= 0
            // is c0 + c1 w >= -slack.
            let (mut lo, mut hi) = (-10.0f64, 10.0f64);
            let (p0, p1) = (p(0.0), p(1.0));
            for (c0, c1) in [
                (p0[0], p1[0] - p0[0]),
                (p0[1], p1[1] - p0[1]),
                (1.0 - p0[0] - p0[1], p0[0] + p0[1] - p1[0] - p1[1]),
            ] {
                if c1 > 0.0 {
                    lo = lo.max(-(c0 + slack) / c1);
                } else if c1 < 0.0 {
                    hi = hi.min(-(c0 + slack) / c1);
                } else {
                    assert!(c0 >= -slack, "{what}: key {t} misses the domain: {iv:?}");
                }
            }
            // Y along the line: g0 + β w + α w²; the part is where 2αw + β >= 0.
            let (g0, gp, gm) = (g(p(0.0)), g(p(1.0)), g(p(-1.0)));
            let (alpha, beta) = ((gp + gm) / 2.0 - g0, (gp - gm) / 2.0);
            if alpha > 0.0 {
                lo = lo.max(-beta / (2.0 * alpha));
            } else if alpha < 0.0 {
                hi = hi.min(-beta / (2.0 * alpha));
            }
            let tol = 1e3 * slack * (1.0 + g0.abs());
            assert!(
                lo <= hi + slack && g(p(lo)) <= tol && g(p(hi)) >= -tol,
                "{what}: no curve point at key {t} ({f} of the way), w in [{lo}, {hi}], \
                 g {} .. {}: {iv:?}",
                g(p(lo)),
                g(p(hi))
            );
        }
    }

    /// On every scanline of random lembos (flat to strongly bent: planes, valleys, interior
    /// extrema and saddles), in both datapaths and with a saddle tolerance that makes the
    /// hyperbola near a saddle walked or split: no root is left unpaired, every walked
    /// interval is one piece of the curve in its part, and a split one meets its twin at
    /// the saddle.
    fn intervals_are_pieces<R: Real>() {
        let mut rng = SplitMix64::new(0x6a09_e667_f3bc_c908);
        // Walked intervals on lembos with an interior extremum, a saddle, or neither.
        let mut walked = [0u32; 3];
        for n in 0..200 {
            let bend = [2.0, 10.0, 40.0, 200.0][n % 4];
            let Some(l) = crate::raster::setup::tests::random_lembo::<R>(&mut rng, bend) else {
                continue;
            };
            let kind = match l.partition {
                Partition::Central { det, .. } if det > R::zero() => 0,
                Partition::Central { .. } => 1,
                _ => 2,
            };
            for k in [0.05, 2.0] {
                for j in 0..crate::raster::setup::tests::SIDE {
                    let (ivs, c) = run(&l, j, k);
                    let what = format!("lembo {n}, k {k}, scanline {j}");
                    assert_eq!(c.unpaired_roots, 0, "{what}: {c:?}");
                    for iv in &ivs {
                        if !iv.straight {
                            assert_one_piece(&l, j, iv, &what);
                            walked[kind] += 1;
                        }
                    }
                }
            }
        }
        assert!(
            walked[0] > 100 && walked[1] > 100 && walked[2] > 1000,
            "{walked:?}"
        );
    }

    #[test]
    fn every_interval_is_one_piece_of_the_curve_in_its_part() {
        intervals_are_pieces::<f32>();
        intervals_are_pieces::<f64>();
    }

    #[test]
    fn an_entry_then_an_exit_is_paired_as_by_the_loop() {
        shortcut_pairs_as_the_loop::<f32>();
        shortcut_pairs_as_the_loop::<f64>();
    }

    /// The roots of scanline `j` on each domain edge.
    fn roots_per_edge<R: Real>(l: &ScreenLembo<R>, j: u32) -> [Vec<(ConicPoint<R>, bool)>; 3] {
        let yj = R::of(j as f64 + 0.5);
        [0, 1, 2].map(|e| {
            let mut v = Vec::new();
            edge_crossings(l, e, yj, |p, entry| v.push((p, entry)));
            v
        })
    }

    /// A tolerance on |y - y_j| for curve points computed in `R` \[pixels\].
    fn tol<R: Real>() -> f64 {
        if R::epsilon().f64() > 1e-10 {
            1e-3
        } else {
            1e-9
        }
    }

    fn closed_loop<R: Real>() {
        let l = screen_lembo::<R>(x_linear(), y_bowl());
        assert_closed_loop(&l);
        // Just below the minimum: nothing at all.
        let (ivs, c) = run(&l, 39, 0.5);
        assert!(
            ivs.is_empty() && c.edge_roots + c.virtual_roots + c.unpaired_roots == 0,
            "{c:?}"
        );
        // y = 41.5 - 64 (u - 1/4)² - 32 (v - 1/4)²: a dome, whose steeper axis (the split
        // axis, larger |λ|) is u, with a first component of -1 as eigen_sym orients it.
        let l = screen_lembo::<R>(x_linear(), quad(-64.0, -32.0, 0.0, 32.0, 16.0, 35.5));
        assert!(
            matches!(l.partition, Partition::Central { eig, .. } if eig[0].0[0] < R::of(-0.9)),
            "{:?}",
            l.partition
        );
        assert_closed_loop(&l);
        // y = 40.5 ± 64 ((u - 1/4)² + (v - 1/4)²): the minimum or maximum exactly on
        // scanline 40 (exact in both datapaths) is a single point: nothing to pair.
        for s in [1.0, -1.0] {
            let y = quad(
                64.0 * s,
                64.0 * s,
                0.0,
                -32.0 * s,
                -32.0 * s,
                40.5 + 8.0 * s,
            );
            let l = screen_lembo::<R>(x_linear(), y);
            let (ivs, c) = run(&l, 40, 0.5);
            assert!(
                ivs.is_empty() && c.edge_roots + c.virtual_roots + c.unpaired_roots == 0,
                "{c:?} {ivs:?}"
            );
        }
    }

    /// Scanline 40 of `l` (a level of a bowl or dome wholly inside the domain) is a closed
    /// loop, walked as two halves between its tips.
    fn assert_closed_loop<R: Real>(l: &ScreenLembo<R>) {
        let (ivs, c) = run(l, 40, 0.5);
        assert_eq!(
            (c.edge_roots, c.virtual_roots, c.intervals, c.unpaired_roots),
            (0, 2, 2, 0),
            "{c:?}"
        );
        assert_eq!(ivs.len(), 2);
        // The two halves meet at the virtual roots, so the loop closes.
        assert_eq!(ivs[0].end.uv, ivs[1].start.uv);
        assert_eq!(ivs[1].end.uv, ivs[0].start.uv);
        for iv in &ivs {
            assert!(!iv.straight);
            assert_ne!(iv.start.uv, iv.end.uv);
            for p in [iv.start, iv.end] {
                assert_eq!(p.edge, INTERIOR);
                assert!(y_error(l, 40, p.uv) < tol::<R>(), "{p:?}");
            }
            // The walk key increases from start to end.
            assert!(dot(iv.tau, iv.start.uv) < iv.end_key);
            assert_one_piece(l, 40, iv, "closed loop");
        }
    }

    #[test]
    fn interval_closed_loop_without_edge_roots() {
        closed_loop::<f32>();
        closed_loop::<f64>();
    }

    fn tip_on_an_edge<R: Real>() {
        // y = 63.5 + 144 ((u - 1/3)² + (v - 1/3)²): on scanline 79 (y = 79.5) the circle of
        // radius 1/3 around (1/3, 1/3) touches u = 0 and v = 0 and crosses u + v = 1 at
        // (1/3, 2/3), exactly the tip on the partition line u = 1/3, and at (2/3, 1/3).
        let y = quad(144.0, 144.0, 0.0, -96.0, -96.0, 95.5);
        let l = screen_lembo::<R>(x_linear(), y);
        let (ivs, c) = run(&l, 79, 0.5);
        assert_eq!((c.unpaired_roots, c.intervals), (0, 2), "{c:?} {ivs:?}");
        // The left half from the tip on v = 0 to the tip on the hypotenuse, the right one
        // from the hypotenuse's other root back to the tip on v = 0.
        let near = |p: V2<R>, q: [f64; 2]| {
            (p[0].f64() - q[0]).abs() < 1e-4 && (p[1].f64() - q[1]).abs() < 1e-4
        };
        assert!(near(ivs[0].start.uv, [1.0 / 3.0, 0.0]), "{ivs:?}");
        assert!(near(ivs[0].end.uv, [1.0 / 3.0, 2.0 / 3.0]), "{ivs:?}");
        assert!(near(ivs[1].start.uv, [2.0 / 3.0, 1.0 / 3.0]), "{ivs:?}");
        assert!(near(ivs[1].end.uv, [1.0 / 3.0, 0.0]), "{ivs:?}");
        let (_, c) = scanline_fragments(&l, 79, 0.5);
        assert!(c.fragments > 0 && c.unpaired_roots == 0, "{c:?}");

        // y = 36.5 + 64 (u - 1/2)² + 256 v²: on scanline 40 the ellipse's tips (1/4, 0) and
        // (3/4, 0) are both on v = 0 (at the same v), each also an edge root there. Each
        // merges with its own edge root only: the upper half is one interval, tip to tip.
        let l = screen_lembo::<R>(x_linear(), quad(64.0, 256.0, 0.0, -64.0, 0.0, 52.5));
        let (ivs, c) = run(&l, 40, 0.5);
        assert_eq!(
            (c.edge_roots, c.unpaired_roots, ivs.len()),
            (2, 0, 1),
            "{c:?} {ivs:?}"
        );
        assert!(near(ivs[0].start.uv, [0.25, 0.0]), "{ivs:?}");
        assert!(near(ivs[0].end.uv, [0.75, 0.0]), "{ivs:?}");
        assert_one_piece(&l, 40, &ivs[0], "tips on v = 0");
    }

    #[test]
    fn interval_tip_on_a_domain_edge_merges_with_the_edge_root() {
        tip_on_an_edge::<f32>();
        tip_on_an_edge::<f64>();
    }

    fn saddle<R: Real>() {
        let l = screen_lembo::<R>(x_linear(), y_saddle());
        // |y_j - y_saddle| = 0.2 <= k/2: the curve is taken as the two crossing lines.
        let (ivs, c) = run(&l, 50, 0.5);
        assert!(c.saddle_splits > 0 && c.unpaired_roots == 0, "{c:?}");
        assert_eq!(ivs.len() as u64, 2 * c.saddle_splits);
        for pair in ivs.chunks(2) {
            assert!(pair.iter().all(|iv| iv.straight));
            // Split at the centre: the first half ends there and the second starts there.
            assert_eq!(pair[0].end.uv, pair[1].start.uv);
            let centre = pair[0].end.uv;
            assert!((centre[0].f64() - 0.3).abs() < 1e-6 && (centre[1].f64() - 0.3).abs() < 1e-6);
            for p in [pair[0].start, pair[1].end] {
                assert_ne!(p.edge, INTERIOR);
                assert!(y_error(&l, 50, p.uv) < tol::<R>());
            }
        }
        // With k/2 = 0.15 < 0.2 the hyperbola is walked: no split, still fully paired.
        let (ivs, c) = run(&l, 50, 0.3);
        assert_eq!((c.saddle_splits, c.unpaired_roots), (0, 0), "{c:?}");
        assert!(!ivs.is_empty() && ivs.iter().all(|iv| !iv.straight));
    }

    #[test]
    fn interval_saddle_crossing_splits_at_the_centre() {
        saddle::<f32>();
        saddle::<f64>();
    }

    /// y = 40u² - 40u + 30v + f: on edge AB (v = 0) a parabola with its minimum f - 10 at
    /// u = 1/2; everything else is higher.
    fn y_edge_dip(f: f64) -> Quadratic<f64> {
        quad(40.0, 0.0, 0.0, -40.0, 30.0, f)
    }

    fn tangent<R: Real>() {
        // The edge minimum exactly on scanline 20 (y = 20.5): a touching point, no roots.
        let l = screen_lembo::<R>(x_linear(), y_edge_dip(30.5));
        assert!(roots_per_edge(&l, 20).iter().all(|r| r.is_empty()));
        let (ivs, c) = run(&l, 20, 0.5);
        assert!(ivs.is_empty() && c.edge_roots == 0 && c.unpaired_roots == 0);
        // Within a few ulps around it: 0 or 2 roots on the edge, never 1, always paired.
        for n in -40..=40 {
            let l = screen_lembo::<R>(x_linear(), y_edge_dip(30.5 + n as f64 * 1e-7));
            let roots = roots_per_edge(&l, 20);
            assert!(
                roots[0].is_empty() || roots[0].len() == 2,
                "offset {n}e-7: {:?}",
                roots[0]
            );
            assert!(roots[1].is_empty() && roots[2].is_empty());
            if let [(p, p_entry), (q, q_entry)] = roots[0][..] {
                assert!(p.uv[0] <= q.uv[0] && p_entry != q_entry);
            }
            let (ivs, c) = run(&l, 20, 0.5);
            assert_eq!((c.edge_roots, c.unpaired_roots), (roots[0].len() as u64, 0));
            assert_eq!(2 * ivs.len(), roots[0].len());
        }
        // 1e-6 px below: two roots close to u = 1/2 in f64 (f32 may round the dip away).
        let l = screen_lembo::<R>(x_linear(), y_edge_dip(30.5 - 1e-6));
        let roots = roots_per_edge(&l, 20);
        if R::epsilon().f64() < 1e-10 {
            assert_eq!(roots[0].len(), 2);
        }
        for (p, _) in &roots[0] {
            assert!((p.uv[0].f64() - 0.5).abs() < 1e-3 && y_error(&l, 20, p.uv) < tol::<R>());
        }
    }

    #[test]
    fn interval_tangent_scanline_at_an_edge_extremum_has_zero_or_two_roots() {
        tangent::<f32>();
        tangent::<f64>();
    }

    /// Edges whose y has its extremum at their end vertex, which lies within a few ulps of
    /// scanline 60 (y = 60.5): y = A (u - 1)² + 30v + 60.5 + d on AB, for random A and tiny
    /// d. Where the edge's computed vertex is exactly t = 1, its parabola is monotonic along it,
    /// so ends on one side mean no roots; and among them are edges whose computed extremum
    /// value `fm` rounds to the other side of the scanline than the ends (the edge crossings
    /// must not trust it there). Returns (edges with the vertex at t = 1, those rounding so).
    fn extremum_at_the_end<R: Real>(ulp: f64) -> (u32, u32) {
        let mut rng = SplitMix64::new(0x9e37_79b9_7f4a_7c15);
        let (mut at_end, mut rounded_across) = (0, 0);
        let yj = R::of(60.5);
        for _ in 0..100_000 {
            let a = rng.range(-50.0, 50.0);
            let d = rng.range_i64(-8, 8) as f64 * ulp;
            let l = screen_lembo::<R>(x_linear(), quad(a, 0.0, 0.0, -2.0 * a, 30.0, a + 60.5 + d));
            let roots = roots_per_edge(&l, 60);
            for (c, roots) in l.edges.iter().zip(&roots) {
                let (pa, pb) = c.y_power();
                let above = (c.y[0] >= yj, c.y[2] >= yj);
                if pa == R::zero() || c.y_vertex((pa, pb)) != R::one() || above.0 != above.1 {
                    continue;
                }
                at_end += 1;
                let fm = c.y[0] - yj - c.y_dip((pa, pb));
                rounded_across += u32::from((fm >= R::zero()) != above.0);
                assert!(roots.is_empty(), "A = {a}, d = {d}: {roots:?}");
            }
        }
        (at_end, rounded_across)
    }

    #[test]
    fn an_edge_with_its_extremum_at_its_end_vertex_has_no_roots_between_ends_on_one_side() {
        // Both datapaths reach the rounding case often enough to catch a branch that trusts
        // `fm` at t = 1 (measured with this seed: 121 of 4 878 edges in f32, 13 of 4 196 in
        // f64).
        for (at_end, rounded_across) in [
            extremum_at_the_end::<f32>(4e-6),
            extremum_at_the_end::<f64>(8e-15),
        ] {
            assert!(
                at_end >= 4000 && rounded_across >= 5,
                "{at_end} {rounded_across}"
            );
        }
    }

    fn through_vertex<R: Real>() {
        // y = 10 + 40u + 20.5v: A = 10, B = 50, C = 30.5 exactly on scanline 30.
        let l = screen_lembo::<R>(x_linear(), quad(0.0, 0.0, 0.0, 40.0, 20.5, 10.0));
        let roots = roots_per_edge(&l, 30);
        // The crossing at C belongs to exactly one of its two edges (BC, CA).
        assert_eq!(roots.each_ref().map(|r| r.len()), [1, 0, 1]);
        assert_eq!(roots[2][0].0.uv, [R::zero(), R::one()]);
        let (ivs, c) = run(&l, 30, 0.5);
        assert_eq!((ivs.len(), c.edge_roots, c.unpaired_roots), (1, 2, 0));

        // C = 30.5 is the top vertex (A = 10, B = 30): the scanline touches only C; both of
        // its edges cross there, which pairs into one empty interval.
        let l = screen_lembo::<R>(x_linear(), quad(0.0, 0.0, 0.0, 20.0, 20.5, 10.0));
        let roots = roots_per_edge(&l, 30);
        assert_eq!(roots.each_ref().map(|r| r.len()), [0, 1, 1]);
        let (ivs, c) = run(&l, 30, 0.5);
        assert_eq!((ivs.len(), c.unpaired_roots), (1, 0));
        assert_eq!(ivs[0].start.uv, ivs[0].end.uv);

        // A = 30.5 is the bottom vertex: a vertex on the scanline counts as above it, so
        // nothing crosses.
        let l = screen_lembo::<R>(x_linear(), quad(0.0, 0.0, 0.0, 20.0, 10.0, 30.5));
        let (ivs, c) = run(&l, 30, 0.5);
        assert!(ivs.is_empty() && c.edge_roots == 0 && c.unpaired_roots == 0);
    }

    #[test]
    fn interval_vertex_on_the_scanline_is_not_doubled() {
        through_vertex::<f32>();
        through_vertex::<f64>();
    }

    #[test]
    fn interval_stable_roots_keep_the_linear_root_when_the_leading_coefficient_vanishes() {
        let (r1, r2) = stable_roots::<f32>(1e-12, 3.0, -1.5);
        let small = if r1.abs() < r2.abs() { r1 } else { r2 };
        assert!((small - 0.5).abs() <= f32::EPSILON, "{r1} {r2}");
        let (r1, r2) = stable_roots::<f64>(1e-12, 3.0, -1.5);
        let small = if r1.abs() < r2.abs() { r1 } else { r2 };
        // The exact root is 0.5 - 0.25e-12 / 3 + O(1e-25).
        assert!(
            (small - (0.5 - 0.25e-12 / 3.0)).abs() <= f64::EPSILON,
            "{r1} {r2}"
        );
        // The textbook formula loses the root to cancellation (the reason for the stable one).
        let naive = (-3.0f32 + (9.0f32 - 4.0 * 1e-12 * -1.5).sqrt()) / (2.0 * 1e-12);
        assert!((naive - 0.5).abs() > 0.4, "{naive}");
        // A = 0 exactly: the linear root in both places; nothing at all: t = 0, no NaN.
        assert_eq!(stable_roots::<f32>(0.0, 3.0, -1.5), (0.5, 0.5));
        assert_eq!(stable_roots::<f64>(0.0, 0.0, 2.0), (0.0, 0.0));
    }

    fn almost_linear_edge<R: Real>(lead: f64) {
        // On AB: y = lead u² + 40u + 10, crossing scanline 25 (y = 25.5) near u = 0.3875.
        let l = screen_lembo::<R>(x_linear(), quad(lead, 0.0, 0.0, 40.0, 30.0, 10.0));
        let roots = roots_per_edge(&l, 25);
        assert_eq!(roots[0].len(), 1);
        let p = roots[0][0].0;
        // The stable form of the smaller root (the textbook one cancels here too).
        let exact = 2.0 * 15.5 / (40.0 + (1600.0f64 + 4.0 * lead * 15.5).sqrt());
        let scale = if R::epsilon().f64() > 1e-10 {
            1e-6
        } else {
            1e-13
        };
        assert!(
            (p.uv[0].f64() - exact).abs() < scale,
            "{} vs {exact}",
            p.uv[0].f64()
        );
        assert!(
            (p.x.f64() - x_linear().eval(exact, 0.0)).abs() < 1e3 * scale,
            "{p:?}"
        );
    }

    #[test]
    fn interval_almost_linear_edge_yields_the_right_crossing() {
        for lead in [0.0, 1e-12, 1e-9, 1e-5, -1e-5] {
            almost_linear_edge::<f32>(lead);
            almost_linear_edge::<f64>(lead);
        }
    }

    #[test]
    fn interval_plane_pairs_its_two_edge_roots() {
        let l = screen_lembo::<f32>(x_linear(), y_plane());
        for j in 10..70 {
            let (ivs, c) = run(&l, j, 0.5);
            assert_eq!(
                (ivs.len(), c.edge_roots, c.unpaired_roots),
                (1, 2, 0),
                "scanline {j}"
            );
            assert!(ivs[0].start.edge != INTERIOR && ivs[0].end.edge != INTERIOR);
        }
    }
}
