//! IntervalManager: the pieces of the curve Y(u, v) = y_j inside the domain, per scanline
//! (paper 001 section 5, "Managing Intervals").
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

use super::setup::{edge_uv, Partition, ScreenLembo};
use super::v2::{dot, rot_cw, V2};
use super::Counts;
use crate::datapath::Real;

/// A point of the curve with its screen x [pixels] (from the edge curve on domain edges,
/// so shared edges agree bit for bit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvePoint<R> {
    pub uv: V2<R>,
    pub x: R,
    /// The domain edge (0: AB, 1: BC, 2: CA) the point was found on, or [`INTERIOR`].
    pub edge: u8,
}

/// [`CurvePoint::edge`] of a point not found on a domain edge.
pub const INTERIOR: u8 = 3;

/// One piece of the curve Y = y_j inside the domain, from `start` to `end` in walking order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval<R> {
    pub start: CurvePoint<R>,
    pub end: CurvePoint<R>,
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
    pub p: CurvePoint<R>,
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
    let yj = R::of(j as f64 + 0.5);
    let xs = &mut scratch.crossings;
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
    let (a, split, saddle) = match l.partition {
        Partition::Monotone { a } => (a, false, None),
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
                            let p = CurvePoint {
                                uv,
                                x: l.x.eval(uv[0], uv[1]),
                                edge: INTERIOR,
                            };
                            let (from, to) = if up { (-1, 1) } else { (1, -1) };
                            xs.push(Crossing {
                                p,
                                entry: false,
                                part: from,
                                is_virtual: true,
                                key: R::zero(),
                            });
                            xs.push(Crossing {
                                p,
                                entry: true,
                                part: to,
                                is_virtual: true,
                                key: R::zero(),
                            });
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
    };

    // Assign parts to edge roots and compute walk keys. Ties put exits first: a curve that
    // touches an edge from inside leaves and re-enters there.
    for c in xs.iter_mut() {
        if split && !c.is_virtual {
            let (gu, gv) = l.y.grad(c.p.uv[0], c.p.uv[1]);
            c.part = if dot(a, [gu, gv]) >= R::zero() { 1 } else { -1 };
        }
        c.key = dot(part_tau(a, c.part), c.p.uv);
    }
    xs.sort_by(|p, q| {
        p.part
            .cmp(&q.part)
            .then(
                p.key
                    .partial_cmp(&q.key)
                    .unwrap_or(std::cmp::Ordering::Equal),
            )
            .then(p.entry.cmp(&q.entry))
    });

    let mut pending: Option<(i8, CurvePoint<R>)> = None;
    for c in xs.iter() {
        if c.entry {
            if pending.is_some() {
                counts.unpaired_roots += 1;
            }
            pending = Some((c.part, c.p));
        } else {
            match pending.take() {
                Some((part, start)) if part == c.part => {
                    let tau = part_tau(a, part);
                    match saddle {
                        Some(centre) => {
                            let mid = CurvePoint {
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
    mut push: impl FnMut(CurvePoint<R>, bool),
) {
    let c = &l.edges[e];
    let (two, three, four) = (R::of(2.0), R::of(3.0), R::of(4.0));
    let f0 = c.y[0] - yj;
    let f1 = c.y[2] - yj;
    let (s0, s1) = (f0 >= R::zero(), f1 >= R::zero());
    // y(t) - y_j = A t² + B t + C through the canonical start, middle and end.
    let cc = f0;
    let b = four * c.y[1] - three * c.y[0] - c.y[2];
    let a = two * c.y[0] + two * c.y[2] - four * c.y[1];
    let mut roots = [R::zero(); 2];
    let n = if s0 != s1 {
        roots[0] = one_root_in_unit(a, b, cc);
        1
    } else {
        if a == R::zero() {
            return;
        }
        let tm = -b / (two * a);
        if !(tm > R::zero() && tm < R::one()) {
            return;
        }
        let fm = cc - b * b / (four * a);
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
    let bx = four * c.x[1] - three * c.x[0] - c.x[2];
    let ax = two * c.x[0] + two * c.x[2] - four * c.x[1];
    // Lembo-order sign at the edge start decides the type of the first crossing.
    let start_above = if c.reversed { s1 } else { s0 };
    let mut pts = [(
        R::zero(),
        CurvePoint {
            uv: [R::zero(); 2],
            x: R::zero(),
            edge: e as u8,
        },
    ); 2];
    for (i, &t) in roots[..n].iter().enumerate() {
        let tl = if c.reversed { R::one() - t } else { t };
        pts[i] = (
            tl,
            CurvePoint {
                uv: edge_uv(e, tl),
                x: c.x[0] + t * (bx + t * ax),
                edge: e as u8,
            },
        );
    }
    if n == 2 && pts[1].0 < pts[0].0 {
        pts.swap(0, 1);
    }
    for (i, (_, p)) in pts[..n].iter().enumerate() {
        // Crossings alternate: the first leaves the start's side.
        let entry = start_above == (i % 2 == 0);
        push(*p, entry);
    }
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
