//! The segmenter's tests: exact cases, the walk's error bound and its sampled properties.

use super::*;
use crate::raster::interval::{intervals, IntervalScratch};
use crate::raster::setup::tests::{
    quad, screen_lembo, x_linear, y_bowl, y_error, y_plane, y_saddle,
};
use crate::raster::DEFAULT_SEGMENT_CAP;
use crate::testkit::SplitMix64;

/// `miri` under Miri (which runs about a thousand times slower), else `native`.
const fn miri_or(miri: usize, native: usize) -> usize {
    if cfg!(miri) {
        miri
    } else {
        native
    }
}

/// Each interval of a scanline with its segments.
type Walks<R> = Vec<(Interval<R>, Vec<Segment<R>>)>;

/// The intervals of scanline `j` and the segments of each.
fn run<R: Real>(l: &ScreenLembo<R>, j: u32, k: f64) -> (Walks<R>, Counts) {
    let (mut ivs, mut counts) = (Vec::new(), Counts::default());
    intervals(
        l,
        j,
        R::of(k),
        &mut IntervalScratch::default(),
        &mut ivs,
        &mut counts,
    );
    let out = ivs
        .into_iter()
        .map(|iv| {
            let mut segs = Vec::new();
            segments(
                l,
                j,
                R::of(k),
                &iv,
                DEFAULT_SEGMENT_CAP,
                &mut segs,
                &mut counts,
            )
            .expect("under the cap");
            (iv, segs)
        })
        .collect::<Walks<R>>();
    let chords: usize = out.iter().map(|(_, s)| s.len()).sum();
    assert_eq!(counts.segments, chords as u64, "every chord counted once");
    (out, counts)
}

fn finite<R: Real>(p: &ConicPoint<R>) -> bool {
    p.uv[0].is_finite() && p.uv[1].is_finite() && p.x.is_finite()
}

fn closed_chain<R: Real>(tol: f64) {
    let l = screen_lembo::<R>(x_linear(), y_bowl());
    let (walks, _) = run(&l, 40, 0.1);
    let chain: Vec<Segment<R>> = walks.iter().flat_map(|(_, s)| s.iter().copied()).collect();
    assert!(chain.len() > 2, "{}", chain.len());
    for (n, s) in chain.iter().enumerate() {
        let next = &chain[(n + 1) % chain.len()];
        assert_eq!(s.p1.uv, next.p0.uv, "segment {n} does not meet the next");
        assert!(y_error(&l, 40, s.p0.uv) < tol, "{s:?}");
    }
    assert_eq!(chain.last().unwrap().p1.uv, chain[0].p0.uv);
}

/// On every interval of random lembos, in both datapaths and at three tolerances: the
/// walk gives the same segments and counts whether or not steps sure to pass the end are
/// skipped, and where a walk's first step is skipped, the step made there would indeed
/// have been refused. The skip must be taken on a good share of these lembos' intervals
/// (which are larger than a tessellated mesh's; 60 % of the bunny's are skipped), so
/// that the claim is tested.
fn skipped_steps_are_refused<R: Real>() {
    let mut rng = SplitMix64::new(0x9e37_79b9_7f4a_7c15);
    let (mut intervals_seen, mut skipped) = (0u64, 0u64);
    for n in 0..miri_or(4, 400) {
        let bend = [2.0, 10.0, 40.0, 200.0][n % 4];
        let Some(l) = crate::raster::setup::tests::random_lembo::<R>(&mut rng, bend) else {
            continue;
        };
        for k in [0.05, 0.5, 2.0] {
            let k = R::of(k);
            let reach = least_reach(&l, k);
            let mut scratch = IntervalScratch::default();
            for j in 0..crate::raster::setup::tests::SIDE {
                let (mut ivs, mut counts) = (Vec::new(), Counts::default());
                intervals(&l, j, k, &mut scratch, &mut ivs, &mut counts);
                for iv in ivs.iter().filter(|iv| !iv.straight) {
                    intervals_seen += 1;
                    let walked = |reach| {
                        let (mut out, mut counts) = (Vec::new(), Counts::default());
                        let cap = DEFAULT_SEGMENT_CAP;
                        walk(&l, j, k, iv, cap, reach, &mut out, &mut counts)
                            .expect("under the cap");
                        (out, counts)
                    };
                    assert_eq!(walked(None), walked(reach), "lembo {n}, scanline {j}");
                    let yj = R::of(j as f64 + 0.5);
                    let p = iv.start.uv;
                    let y0 = l.y.eval(p[0], p[1]) - yj;
                    let key = dot(iv.tau, p);
                    let Some(r) = reach else { continue };
                    if !passes_end(r, k, y0, p, iv.tau, key, iv.end_key) {
                        continue;
                    }
                    skipped += 1;
                    // The walk's first step, with the walk's constants.
                    let (h, h_scale, eps) = step_constants(&l);
                    let (gu, gv) = l.y.grad(p[0], p[1]);
                    let g = [gu, gv];
                    let sigma = walk_sign(h, g);
                    if let Some(q) = step(h, h_scale, eps, sigma, k, y0, p, g, norm(g)) {
                        let qk = dot(iv.tau, q);
                        assert!(
                            qk >= iv.end_key || qk <= key,
                            "lembo {n}, scanline {j}: a skipped step ends inside the \
                             interval ({key:?} < {qk:?} < {:?})",
                            iv.end_key
                        );
                    }
                }
            }
        }
    }
    // Measured: 17 664 of 88 122 (20.0 %) in both datapaths; a bound made weaker than
    // it is would skip fewer. (Not a share of Miri's four lembos.)
    assert!(
        cfg!(miri) || skipped * 100 >= intervals_seen * 19,
        "{skipped} of {intervals_seen} first steps skipped"
    );
}

#[test]
fn a_step_sure_to_pass_the_end_is_one_the_walk_refuses() {
    skipped_steps_are_refused::<f32>();
    skipped_steps_are_refused::<f64>();
}

#[test]
fn segmenter_closed_loop_forms_a_closed_chain() {
    closed_chain::<f32>(1e-3);
    closed_chain::<f64>(1e-9);
}

/// y = 10 + 80u² + 60v: parabolic level curves from edge to edge.
fn y_parabolic() -> crate::lembo::Quadratic<f64> {
    quad(80.0, 0.0, 0.0, 0.0, 60.0, 10.0)
}

#[test]
fn segmenter_midpoint_error_is_exactly_k() {
    for (y, j) in [(y_parabolic(), 40), (y_parabolic(), 25), (y_bowl(), 45)] {
        for k in [0.05, 0.1, 0.5] {
            let l = screen_lembo::<f64>(x_linear(), y);
            let (walks, c) = run(&l, j, k);
            let mut walked = 0;
            for (iv, segs) in &walks {
                // Every segment but the last (clamped to the interval end) is a full step.
                for s in &segs[..segs.len() - 1] {
                    let mid = [
                        0.5 * (s.p0.uv[0] + s.p1.uv[0]),
                        0.5 * (s.p0.uv[1] + s.p1.uv[1]),
                    ];
                    let err = y_error(&l, j, mid);
                    assert!((err - k).abs() <= 1e-9 * k, "k {k}: midpoint error {err}");
                    assert!(y_error(&l, j, s.p1.uv) < 1e-9);
                    walked += 1;
                }
                let last = segs.last().unwrap();
                assert_eq!(last.p1, iv.end);
                let mid = [
                    0.5 * (last.p0.uv[0] + last.p1.uv[0]),
                    0.5 * (last.p0.uv[1] + last.p1.uv[1]),
                ];
                assert!(y_error(&l, j, mid) <= k * (1.0 + 1e-9));
            }
            assert!(
                walked > 0 && c.segments_clamped == walks.len() as u64,
                "{c:?}"
            );
        }
    }
}

fn closing_chord_is_split_until_within_k<R: Real>(tol: f64) {
    // As if the walk found no step at an interval's start: the one chord to its end is
    // far off the curve (half a bowl's level curve), so it is split in walk key until
    // every chord is within k, in walk order, from the start to the end.
    let l = screen_lembo::<R>(x_linear(), y_bowl());
    let (walks, _) = run(&l, 45, 0.1);
    assert!(!walks.is_empty(), "scanline 45 crosses the bowl");
    for (iv, walked) in &walks {
        let (mut out, mut c) = (Vec::new(), Counts::default());
        let yj = R::of(45.5);
        last_chords(
            &l,
            yj,
            R::of(0.1),
            iv,
            iv.start,
            0,
            1 << 16,
            &mut out,
            &mut c,
        )
        .expect("under the cap");
        assert!(c.segments_refined > 2 && out.len() > 2, "{c:?}");
        // Split only where too far: each split adds one chord, and halving in key needs
        // no more than twice the chords of the walk at exactly k (16 against 12 here).
        assert_eq!(c.segments_refined + 1, out.len() as u64);
        assert_eq!(c.segments, out.len() as u64);
        assert!(
            out.len() <= 2 * walked.len(),
            "{} chords against {} walked",
            out.len(),
            walked.len()
        );
        assert_eq!((out[0].p0, out.last().unwrap().p1), (iv.start, iv.end));
        for (n, s) in out.iter().enumerate() {
            let mid = [
                (s.p0.uv[0] + s.p1.uv[0]) * R::of(0.5),
                (s.p0.uv[1] + s.p1.uv[1]) * R::of(0.5),
            ];
            assert!(y_error(&l, 45, mid) <= 0.1 + tol, "chord {n}: {s:?}");
            assert!(
                y_error(&l, 45, s.p1.uv) < tol,
                "chord {n} ends off the curve"
            );
            assert!(dot(iv.tau, s.p1.uv) > dot(iv.tau, s.p0.uv), "walk order");
            if n + 1 < out.len() {
                assert_eq!(s.p1, out[n + 1].p0);
            }
        }
    }
}

#[test]
fn segmenter_closing_chord_is_split_until_within_k() {
    closing_chord_is_split_until_within_k::<f32>(1e-3);
    closing_chord_is_split_until_within_k::<f64>(1e-9);
}

/// The walk never leaves the lembo's domain, even where the interval's end key lies
/// beyond the domain's edge (as rounding of an end key could put it): the step that
/// would leave the closed triangle is refused and the walk closes at the interval's end.
/// Every scanline of a parabolic and a bowl-shaped lembo, whose curves leave the domain
/// through each of its three edges.
#[test]
fn the_walk_stays_in_the_domain_past_a_wrong_end_key() {
    let mut exits = [0; 3];
    for y in [y_parabolic(), y_bowl()] {
        let l = screen_lembo::<f64>(x_linear(), y);
        for j in 0..crate::raster::setup::tests::SIDE {
            let (walks, _) = run(&l, j, 0.05);
            for (iv, _) in walks.iter().filter(|(iv, _)| !iv.straight) {
                let e = iv.end.uv;
                let near = 1e-9;
                exits[0] += (e[0] < near) as u32;
                exits[1] += (e[1] < near) as u32;
                exits[2] += (e[0] + e[1] > 1.0 - near) as u32;
                let wrong = Interval {
                    end_key: iv.end_key + 10.0,
                    ..*iv
                };
                let (mut out, mut c) = (Vec::new(), Counts::default());
                segments(&l, j, 0.05, &wrong, 1 << 16, &mut out, &mut c).expect("under the cap");
                assert_eq!(out.last().unwrap().p1, iv.end, "scanline {j}");
                for s in &out {
                    let q = s.p1.uv;
                    let eps = 1e-12;
                    assert!(
                        q[0] >= -eps && q[1] >= -eps && q[0] + q[1] <= 1.0 + eps,
                        "scanline {j}: the walk left the domain at {q:?}"
                    );
                }
            }
        }
    }
    assert!(
        exits.iter().all(|&n| n > 0),
        "exits through u = 0, v = 0, u + v = 1: {exits:?}"
    );
}

/// Towards an end off the curve (as a bad end point would be), halving never brings the
/// last chord within k: the split stops (at the depth bound, 48 levels, or where f64's
/// walk keys can no longer be halved, a few levels further: 52 chords here), the walk
/// still closes at the end, and every chord before the last is within k.
#[test]
fn closing_chords_towards_an_end_off_the_curve_stop_at_the_depth_bound() {
    let l = screen_lembo::<f64>(x_linear(), y_parabolic());
    let (walks, _) = run(&l, 40, 0.05);
    let (iv, segs) = &walks[0];
    // A point halfway along the walk, moved across the curve 5 scanlines off it.
    let on = segs[segs.len() / 2].p1;
    let g = l.y.grad(on.uv[0], on.uv[1]);
    let gg = g.0 * g.0 + g.1 * g.1;
    let uv = [on.uv[0] + 5.0 * g.0 / gg, on.uv[1] + 5.0 * g.1 / gg];
    let end = ConicPoint { uv, ..on };
    let off = Interval {
        end,
        end_key: dot(iv.tau, uv),
        ..*iv
    };
    assert!(y_error(&l, 40, uv) > 4.0);
    let (mut out, mut c) = (Vec::new(), Counts::default());
    last_chords(&l, 40.5, 0.05, &off, iv.start, 0, 1 << 16, &mut out, &mut c)
        .expect("under the cap");
    assert_eq!(out.last().unwrap().p1, end);
    // Deterministic: the depth bound's 48 levels and the last halvings f64's keys allow.
    assert_eq!(out.len(), 52, "{} chords", out.len());
    for s in &out[..out.len() - 1] {
        let mid = [
            0.5 * (s.p0.uv[0] + s.p1.uv[0]),
            0.5 * (s.p0.uv[1] + s.p1.uv[1]),
        ];
        assert!(y_error(&l, 40, mid) <= 0.05 * (1.0 + 1e-6), "{s:?}");
    }
}

/// A closing chord is split only at points of the domain: where an interval's end lies
/// outside the closed triangle (as a wrong end would), the chords towards it are split
/// while their split points are inside, and the rest is left as one chord to the end.
#[test]
fn closing_chords_split_only_inside_the_domain() {
    let l = screen_lembo::<f64>(x_linear(), y_parabolic());
    let inside = |q: [f64; 2]| {
        let eps = 1e-12;
        q[0] >= -eps && q[1] >= -eps && q[0] + q[1] <= 1.0 + eps
    };
    let mut tested = 0;
    for j in 0..crate::raster::setup::tests::SIDE {
        let (walks, _) = run(&l, j, 0.05);
        let yj = j as f64 + 0.5;
        for (iv, _) in walks.iter().filter(|(iv, _)| !iv.straight) {
            for beyond in [0.05, 0.2, 0.5] {
                let key = iv.end_key + beyond * dot(iv.tau, iv.tau);
                let Some(q) = curve_at_key(&l, yj, iv.tau, key) else {
                    continue;
                };
                if inside(q) {
                    continue;
                }
                let end = ConicPoint {
                    uv: q,
                    x: l.x.eval(q[0], q[1]),
                    edge: INTERIOR,
                };
                let wrong = Interval {
                    end,
                    end_key: dot(iv.tau, q),
                    ..*iv
                };
                let (mut out, mut c) = (Vec::new(), Counts::default());
                last_chords(&l, yj, 0.05, &wrong, iv.start, 0, 1 << 16, &mut out, &mut c)
                    .expect("under the cap");
                assert_eq!(out.last().unwrap().p1, end);
                for s in &out[..out.len() - 1] {
                    assert!(inside(s.p1.uv), "scanline {j}: split at {:?}", s.p1.uv);
                }
                tested += 1;
            }
        }
    }
    assert!(tested > 20, "{tested} ends outside the domain");
}

/// `curve_at_key` against a brute-force search on random lembos, random lines (walk
/// directions of any length) and scanlines: along the line, Y - y_j is a quadratic in the
/// distance across it, so it goes up through zero at most once; the search brackets that
/// crossing by sampling and bisects it. Where the search finds it, `curve_at_key` finds
/// the same point (on the curve, on the line); where it finds none, neither does
/// `curve_at_key` (up to a crossing beyond the sampled stretch). Nearly flat lembos (Y
/// almost linear along the line) need the stable form of the root on both signs of its
/// linear term: the textbook form loses the root to cancellation there.
///
/// Both outcomes must be met often enough to be tested. Across the line, at distance d
/// from the drawn point, Y - y_j = A d² + B d + C, and the line misses the curve exactly
/// where B² < 4 A C: where the curvature across the line (A, up to 2 `bend`) beats its
/// slope (B, mostly the linear part of up to 90 pixels) against the offset C (up to 10
/// pixels). So the nearly flat class never misses, and the others rarely: drawn from
/// this distribution (4·10⁵ draws per class) the miss rates are 2.3 % (bend 2), 9.7 %
/// (40), 8.9 % (200) and 0 (10⁻⁹), and a crossing within the sampled stretch is found
/// at 50, 72, 85 and 49 %. Of 400 lembos only 20.9 miss on average (sd 4.4), so a
/// floor of 20 held for half of all seeds; of 2 000, 104 miss (sd 9.8) and 1 280 are
/// found (sd 20), and the floors below sit 5 sd under those means.
#[test]
fn the_curve_point_at_a_key_is_the_upward_crossing_of_the_line() {
    let mut line_rng = SplitMix64::new(0x2545_f491_4f6c_dd1d);
    let mut next = move || line_rng.unit();
    let mut lembo_rng = SplitMix64::new(0x1234_5678_9abc_def1);
    let (mut found, mut none) = (0, 0);
    for n in 0..miri_or(8, 2000) {
        let bend = [2.0, 40.0, 200.0, 1e-9][n % 4];
        let Some(l) = crate::raster::setup::tests::random_lembo::<f64>(&mut lembo_rng, bend) else {
            continue;
        };
        let angle = next() * std::f64::consts::TAU;
        let length = 0.25 + 4.0 * next();
        let tau = [length * angle.cos(), length * angle.sin()];
        let (u, v) = (next(), next());
        let key = dot(tau, [u, v]);
        let yj = l.y.eval(u, v) + (next() - 0.5) * 20.0;
        // Y along the line, at signed distance d across it (towards rot_ccw(tau)).
        let t2 = dot(tau, tau);
        let (o, nu) = (
            [tau[0] * key / t2, tau[1] * key / t2],
            [-tau[1] / t2.sqrt(), tau[0] / t2.sqrt()],
        );
        let at = |d: f64| [o[0] + d * nu[0], o[1] + d * nu[1]];
        let f = |d: f64| {
            let p = at(d);
            l.y.eval(p[0], p[1]) - yj
        };
        let samples: Vec<f64> = (0..=4000).map(|i| -4.0 + 8.0 * i as f64 / 4000.0).collect();
        let up = samples
            .windows(2)
            .find(|w| f(w[0]) < 0.0 && f(w[1]) >= 0.0)
            .map(|w| {
                let (mut lo, mut hi) = (w[0], w[1]);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if f(mid) < 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                at(0.5 * (lo + hi))
            });
        let got = curve_at_key(&l, yj, tau, key);
        match (up, got) {
            (Some(p), Some(q)) => {
                found += 1;
                let err = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                assert!(err < 1e-7, "lembo {n}: {q:?} against {p:?}");
                assert!(
                    (dot(tau, q) - key).abs() < 1e-9 * length,
                    "lembo {n}: off the line"
                );
            }
            (None, None) => none += 1,
            (None, Some(q)) => {
                // Only a crossing beyond the sampled stretch.
                let d = dot([q[0] - o[0], q[1] - o[1]], nu);
                assert!(
                    d.abs() > 4.0,
                    "lembo {n}: {q:?} at {d} is no upward crossing"
                );
            }
            (Some(p), None) => panic!("lembo {n}: missed the crossing at {p:?}"),
        }
    }
    // (Not shares of Miri's eight lembos.)
    assert!(
        cfg!(miri) || found > 1170 && none > 55,
        "{found} found, {none} without a crossing"
    );
}

/// A closing chord whose midpoint error is k up to the datapath's rounding (each chord of
/// a walk, whose error is exactly k by construction) is not split.
/// At k = 0.001 the datapath's rounding of Y (in f32 about 10⁻⁵ at y = 45) is far more
/// than the part of the slack that scales with k.
fn chords_at_exactly_k_are_not_split<R: Real>(k: f64) {
    let mut chords = 0;
    for (y, j) in [(y_parabolic(), 40), (y_bowl(), 45)] {
        let l = screen_lembo::<R>(x_linear(), y);
        let (walks, _) = run(&l, j, k);
        for (iv, segs) in &walks {
            for s in &segs[..segs.len() - 1] {
                let piece = Interval {
                    start: s.p0,
                    end: s.p1,
                    end_key: dot(iv.tau, s.p1.uv),
                    ..*iv
                };
                let (mut out, mut c) = (Vec::new(), Counts::default());
                let yj = R::of(j as f64 + 0.5);
                last_chords(&l, yj, R::of(k), &piece, s.p0, 0, 64, &mut out, &mut c)
                    .expect("under the cap");
                assert_eq!(out.len(), 1, "scanline {j}, k {k}: {s:?}");
                chords += 1;
            }
        }
    }
    assert!(chords > 10, "{chords}");
}

#[test]
fn segmenter_chords_at_exactly_k_are_not_split() {
    for k in [0.1, 0.001] {
        chords_at_exactly_k_are_not_split::<f32>(k);
        chords_at_exactly_k_are_not_split::<f64>(k);
    }
}

/// The closing chords' split threshold is k plus the slack 10⁻³ k + 64 ε (|y_j| + 1), to
/// within 16 ε: a chord whose midpoint error is 16 ε under it is kept, one 16 ε over it is
/// split. At y_j = 0.5 the rounding of the error here is under ε / 2, while the slack's
/// rounding term is 96 ε.
#[test]
fn closing_chords_split_past_k_and_the_slack() {
    let (k, yj) = (2f64.powi(-10), 0.5);
    let slack = k * 1e-3 + f64::EPSILON * 64.0 * (yj + 1.0);
    let mut l = screen_lembo::<f64>(x_linear(), y_parabolic());
    l.hessian = (0.0, 0.0, 0.0);
    let point = |u: f64, v: f64| ConicPoint {
        uv: [u, v],
        x: l.x.eval(u, v),
        edge: INTERIOR,
    };
    let (p, end) = (point(0.2, 0.3), point(0.6, 0.3));
    let iv = along([1.0, 0.0], p, end);
    for (off, chords) in [(-16.0, 1), (16.0, 2)] {
        let error = k + slack + off * f64::EPSILON;
        // Y = y_j + error + (v - 0.3): the chord's midpoint (0.4, 0.3) is `error` off the
        // scanline, and the curve point halfway in key is (0.4, 0.3 - error).
        l.y = quad(0.0, 0.0, 0.0, 0.0, 1.0, yj + error - 0.3);
        let (mut out, mut c) = (Vec::new(), Counts::default());
        last_chords(&l, yj, k, &iv, p, 0, 64, &mut out, &mut c).expect("under the cap");
        assert_eq!(out.len(), chords, "midpoint error k + slack {off:+} ε");
        assert_eq!(c.segments_refined, chords as u64 - 1);
    }
}

#[test]
fn segmenter_midpoint_error_stays_within_k_in_f32() {
    for (y, j) in [(y_parabolic(), 40), (y_bowl(), 45)] {
        let l = screen_lembo::<f32>(x_linear(), y);
        let (walks, _) = run(&l, j, 0.1);
        let mut checked = 0;
        for s in walks.iter().flat_map(|(_, s)| s) {
            let mid = [
                0.5 * (s.p0.uv[0] + s.p1.uv[0]),
                0.5 * (s.p0.uv[1] + s.p1.uv[1]),
            ];
            assert!(y_error(&l, j, mid) <= 0.1 + 1e-3);
            checked += 1;
        }
        assert!(checked > 5, "scanline {j}: {checked} segments");
    }
}

fn flat<R: Real>() {
    // A plane, and a curve so slightly bent that the step has no useful solution.
    for y in [y_plane(), quad(1e-9, 0.0, 0.0, 60.0, 30.0, 10.0)] {
        let l = screen_lembo::<R>(x_linear(), y);
        for j in [10, 25, 40, 69] {
            let (walks, c) = run(&l, j, 0.5);
            assert_eq!(walks.len(), 1);
            for (iv, segs) in &walks {
                assert_eq!(segs.len(), 1, "scanline {j}");
                assert_eq!((segs[0].p0, segs[0].p1), (iv.start, iv.end));
                assert!(finite(&segs[0].p0) && finite(&segs[0].p1));
            }
            assert_eq!((c.segments, c.segments_clamped), (1, 1));
        }
    }
}

#[test]
fn segmenter_flat_curve_emits_one_clamped_segment_per_interval() {
    flat::<f32>();
    flat::<f64>();
}

#[test]
fn segmenter_saddle_intervals_are_single_straight_segments() {
    let l = screen_lembo::<f32>(x_linear(), y_saddle());
    let (walks, c) = run(&l, 50, 0.5);
    assert!(c.saddle_splits > 0);
    for (iv, segs) in &walks {
        assert_eq!(segs.len(), 1);
        assert_eq!((segs[0].p0, segs[0].p1), (iv.start, iv.end));
    }
}

/// The chords closing a walk count towards the interval's cap, and only the interval's
/// own chords do (not those already in the output).
#[test]
fn closing_chords_count_towards_the_cap() {
    let l = screen_lembo::<f64>(x_linear(), y_bowl());
    let (walks, _) = run(&l, 45, 0.1);
    let iv = &walks[0].0;
    let close = |earlier: usize, cap: usize| {
        let (mut out, mut c) = (
            vec![
                Segment {
                    p0: iv.start,
                    p1: iv.start
                };
                earlier
            ],
            Counts::default(),
        );
        let r = last_chords(&l, 45.5, 0.1, iv, iv.start, earlier, cap, &mut out, &mut c);
        (r, out.len() - earlier)
    };
    let (r, chords) = close(0, 1 << 16);
    assert!(r.is_ok() && chords > 4, "{chords} closing chords");
    for earlier in [0, 5] {
        assert_eq!(
            close(earlier, chords),
            (Ok(()), chords),
            "{earlier} earlier"
        );
        assert_eq!(close(earlier, chords - 1), (Err(CapExceeded), chords - 1));
    }
}

#[test]
fn segmenter_cap_is_an_error() {
    let l = screen_lembo::<f64>(x_linear(), y_bowl());
    let (mut ivs, mut counts) = (Vec::new(), Counts::default());
    intervals(
        &l,
        45,
        0.01,
        &mut IntervalScratch::default(),
        &mut ivs,
        &mut counts,
    );
    // The cap counts this interval's chords, not those already in `out`.
    let earlier = Segment {
        p0: ivs[0].start,
        p1: ivs[0].start,
    };
    let mut segs = vec![earlier; 5];
    assert_eq!(
        segments(&l, 45, 0.01, &ivs[0], 3, &mut segs, &mut counts),
        Err(CapExceeded)
    );
    assert_eq!(segs.len(), 5 + 3);
    segs.clear();
    assert_eq!(
        segments(&l, 45, 0.01, &ivs[0], 3, &mut segs, &mut counts),
        Err(CapExceeded)
    );
    assert_eq!(segs.len(), 3);
    segs.clear();
    assert_eq!(
        segments(
            &l,
            45,
            0.01,
            &ivs[0],
            DEFAULT_SEGMENT_CAP,
            &mut segs,
            &mut counts
        ),
        Ok(())
    );
    assert!(segs.len() > 3);
}

/// [`least_reach`] against the steps it bounds, on random lembos with a monotone
/// partition, in both datapaths and at three tolerances: from every point of a grid over
/// the domain (its corners and edges included, where the gradient bounds are reached),
/// with residuals across ±`RESIDUAL_FRACTION` k and k of either sign, each step's advance
/// in walk key is at least the bound (up to 4 sqrt(ε) relative, the step's own rounding
/// where its quadratic has a double root); the bound does not change where the steps do
/// not (Y scaled along with k, Y mirrored across u = v). And it is not needlessly small: it
/// exists on most pairs, and is a fair share of the least advance found, most so where
/// the gradient turns little over the domain (d / s near 1), as the derivation's losses
/// (the forms bounded through sin θ, the root bound, βm taken whole off the advance)
/// shrink with θ; the floors are measured, with margin.
fn reach_bounds_every_step<R: Real>() {
    let mut rng = SplitMix64::new(0x2545_f491_4f6c_dd1d);
    // Per (lembo, k) with a bound: d / s and the bound over the least advance found.
    let mut ratios = Vec::new();
    let mut monotone = 0;
    for n in 0..miri_or(4, 400) {
        let bend = [2.0, 10.0, 40.0, 200.0][n % 4];
        let Some(l) = crate::raster::setup::tests::random_lembo::<R>(&mut rng, bend) else {
            continue;
        };
        let super::super::screen::Partition::Monotone { a, grad_bounds } = l.partition else {
            assert_eq!(least_reach(&l, R::of(0.5)), None, "lembo {n}");
            continue;
        };
        // The walk direction of the lembo's one part.
        let tau = rot_cw(a);
        let (h, h_scale, eps) = step_constants(&l);
        for k in [0.05, 0.5, 2.0] {
            monotone += 1;
            let reach = least_reach(&l, R::of(k));
            // The bound is the steps' bound: it cannot change where they do not. Y scaled
            // by λ and walked at λ k makes the same steps (the step's system is linear in
            // Y and k); Y mirrored across u = v (on the same domain) makes their mirror
            // images, whose key advances along the mirrored `a` are the same.
            let (hs, [gmin, gmax]) = (l.hessian, grad_bounds);
            for (lambda, mirror) in [(1.0 / 64.0, false), (256.0, false), (1.0, true)] {
                let times = |x: R| x * R::of(lambda);
                let mut other = l.clone();
                other.hessian = if mirror {
                    (hs.2, hs.1, hs.0)
                } else {
                    (times(hs.0), times(hs.1), times(hs.2))
                };
                other.partition = super::super::screen::Partition::Monotone {
                    a: if mirror { [a[1], a[0]] } else { a },
                    grad_bounds: [times(gmin), times(gmax)],
                };
                let there = least_reach(&other, R::of(lambda * k));
                let (r0, r1) = (reach.unwrap_or(0.0), there.unwrap_or(0.0));
                assert!(
                    (r1 - r0).abs() <= 1e-9 * r0.max(r1) + 1e-12,
                    "lembo {n}, k {k}, λ {lambda}, mirrored {mirror}: {there:?} against \
                     {reach:?}"
                );
            }
            let Some(reach) = reach else {
                continue;
            };
            let tol = 4.0 * R::epsilon().f64().sqrt() * reach;
            let mut least = f64::INFINITY;
            let m = 12;
            for i in 0..=m {
                for j in 0..=m - i {
                    let p = [R::of(i as f64 / m as f64), R::of(j as f64 / m as f64)];
                    let (gu, gv) = l.y.grad(p[0], p[1]);
                    let g = [gu, gv];
                    for f in [-1.0, -0.5, 0.0, 0.5, 1.0] {
                        let y0 = R::of(f * RESIDUAL_FRACTION * k);
                        for sigma in [R::one(), -R::one()] {
                            let k = R::of(k);
                            let Some(q) = step(h, h_scale, eps, sigma, k, y0, p, g, norm(g)) else {
                                continue;
                            };
                            let advance = dot(tau, q).f64() - dot(tau, p).f64();
                            assert!(
                                advance >= reach - tol,
                                "lembo {n}, k {k:?}, from {p:?} (residual {y0:?}, sign \
                                 {sigma:?}): advance {advance} < least reach {reach}"
                            );
                            least = least.min(advance);
                        }
                    }
                }
            }
            assert!(least.is_finite(), "lembo {n}, k {k}: no step made");
            let ds = grad_bounds[0].f64() / grad_bounds[1].f64();
            ratios.push((ds, reach / least));
        }
    }
    // Measured (both datapaths alike, to 1e-5): a bound on 802 of the 1 134 monotone
    // (lembo, k) pairs; the ratio's median 0.454, its largest 0.986; with d / s ≥ 0.9
    // (θ ≤ 26°) its least 0.174 over 336 pairs. The floors leave about 10 % of margin.
    // (Not shares of Miri's four lembos.)
    if cfg!(miri) {
        return;
    }
    assert!(
        ratios.len() * 100 >= monotone * 65,
        "{} of {monotone}",
        ratios.len()
    );
    let mut all: Vec<f64> = ratios.iter().map(|r| r.1).collect();
    all.sort_by(f64::total_cmp);
    let median = all[all.len() / 2];
    assert!(median >= 0.4, "median ratio {median}");
    for (ds, ratio) in ratios.iter().filter(|r| r.0 >= 0.9) {
        assert!(*ratio >= 0.15, "d / s {ds}: ratio {ratio}");
    }
}

#[test]
fn least_reach_bounds_every_step_and_not_by_much() {
    reach_bounds_every_step::<f64>();
    reach_bounds_every_step::<f32>();
}

/// The step at its exact ties. h = (3, -1, 1), σ = -1, k = 1/4, y0 = 0, g = (1, 0): the
/// quadratic in α is α² - 2α + 1, whose discriminant is exactly 0, so the step takes the
/// double root α = 1 (a discriminant of 0 is a step, not a miss). With h = (2, -1, 1) it
/// is α² - 2α, with roots 2 and 0: α = 0 is no step at all but the other branch of the
/// curve, so the step takes α = 2.
#[test]
fn the_step_takes_a_double_root_and_refuses_a_zero_root() {
    let eps = f64::EPSILON * 64.0;
    let step_with = |h: (f64, f64, f64)| {
        let h_scale = h.0.abs().max(h.1.abs()).max(h.2.abs());
        step::<f64>(
            h,
            h_scale,
            eps,
            -1.0,
            0.25,
            0.0,
            [0.5, 0.5],
            [1.0, 0.0],
            1.0,
        )
    };
    assert_eq!(step_with((3.0, -1.0, 1.0)), Some([-0.5, -0.5]));
    assert_eq!(step_with((2.0, -1.0, 1.0)), Some([-0.5, -1.5]));
}

/// `curve_at_key`'s root where the slope across the line is exactly 0 (b = 0: the bowl is
/// symmetric about u = v, and so is the line's point o = (key/2, key/2) for τ = (1, 1)):
/// the code takes the stable form -2c / (b + √disc), bit for bit, not the textbook
/// (√disc - b) / 2a, which differs from it in the last bit on some of these keys. Where c
/// is 0 too (the scanline through o itself), the root would be 0 / 0: None.
#[test]
fn curve_at_key_takes_the_stable_root_at_zero_slope_and_none_at_zero_slope_and_value() {
    let l = screen_lembo::<f64>(x_linear(), y_bowl());
    let (tau, n) = ([1.0, 1.0], [-1.0, 1.0]);
    let a = 0.5 * quad_form(l.hessian, n, n);
    let mut differ = 0;
    for i in 0..64 {
        let key = 0.05 + 0.01 * i as f64;
        let o = [key / 2.0, key / 2.0];
        let (gu, gv) = l.y.grad(o[0], o[1]);
        assert_eq!(gu * n[0] + gv * n[1], 0.0, "b at key {key}");
        let yj = l.y.eval(o[0], o[1]) + 2.2;
        let c = l.y.eval(o[0], o[1]) - yj;
        let sq = (-4.0 * a * c).sqrt();
        let (stable, textbook) = (-2.0 * c / sq, sq / (2.0 * a));
        differ += usize::from(stable != textbook);
        let want = [o[0] + stable * n[0], o[1] + stable * n[1]];
        assert_eq!(curve_at_key(&l, yj, tau, key), Some(want), "key {key}");
        let through = l.y.eval(o[0], o[1]);
        assert_eq!(curve_at_key(&l, through, tau, key), None, "key {key}");
    }
    assert!(
        differ > 0,
        "the two forms agree on every key: the test tells nothing"
    );
}

/// `least_reach` pinned on two lembos worked by hand. y = 20u² + 30v + 10 has gradients
/// (0, 30), (40, 30) and (0, 30) at the corners: a = (0, 1), a·g >= 30, |g| <= 50, Hessian
/// (40, 0, 0). y = -15v² + 10uv + 40u + 12 has (40, 0), (40, 10) and (50, -30): a = (1, 0),
/// a·g >= 40, |g| <= √3400, Hessian (0, 10, -30). The expected reaches are the derivation
/// in `least_reach`'s documentation (its 10⁻⁴ allowances included) evaluated from those
/// figures in 50-digit decimal arithmetic, outside this code.
#[test]
fn least_reach_is_the_derivations_bound_on_two_lembos_worked_by_hand() {
    let cases = [
        (
            quad(20.0, 0.0, 0.0, 0.0, 30.0, 10.0),
            [0.0, 1.0],
            [30.0, 50.0],
            (40.0, 0.0, 0.0),
        ),
        (
            quad(0.0, -15.0, 10.0, 40.0, 0.0, 12.0),
            [1.0, 0.0],
            [40.0, 3400f64.sqrt()],
            (0.0, 10.0, -30.0),
        ),
    ];
    let want = [
        [
            (0.5, 0.056_851_577_270_920_79),
            (0.1, 0.055_260_399_622_636_7),
        ],
        [
            (0.5, 0.094_310_103_993_291_58),
            (0.1, 0.066_823_839_761_733_53),
        ],
    ];
    for ((y, a, bounds, hessian), want) in cases.into_iter().zip(want) {
        let l = screen_lembo::<f64>(x_linear(), y);
        let crate::raster::screen::Partition::Monotone {
            a: got_a,
            grad_bounds,
        } = l.partition
        else {
            panic!("{:?}", l.partition);
        };
        assert_eq!((got_a, grad_bounds, l.hessian), (a, bounds, hessian));
        for (k, reach) in want {
            let got = least_reach(&l, k).expect("a positive bound");
            assert!(
                (got - reach).abs() <= 1e-13 * reach,
                "k = {k}: {got} against {reach}"
            );
        }
    }
}

/// `least_reach` gives no bound where its derivation does not hold or is not worth it: where
/// the gradient bounds allow `a·g = 0` (the walk could turn across `a`, and β has no
/// bound) and where `a·g` may fall under 1 % of `|g|`. A nearly flat Hessian makes the
/// bound's formula positive for all three, so the guard alone decides (2 % gives one).
#[test]
fn least_reach_gives_no_bound_where_the_gradient_may_turn_across_the_walk() {
    let mut l = screen_lembo::<f64>(x_linear(), quad(20.0, 0.0, 0.0, 0.0, 30.0, 10.0));
    l.hessian = (2f64.powi(-30), 0.0, 0.0);
    let bound = |l: &mut ScreenLembo<f64>, least: f64| {
        l.partition = crate::raster::screen::Partition::Monotone {
            a: [0.0, 1.0],
            grad_bounds: [least, 50.0],
        };
        least_reach(l, 0.5)
    };
    assert_eq!(bound(&mut l, 0.0), None, "a·g may be 0");
    assert_eq!(bound(&mut l, 0.3), None, "a·g may be 0.6 % of |g|");
    let reach = bound(&mut l, 1.0).expect("a·g at least 2 % of |g|");
    assert!(reach > 1.0, "{reach}");
}

/// A lembo whose curve for scanline 40 (y = 40.5) is the parabola n = 1.5 t² - 2⁻⁴⁹ in
/// coordinates (n, t) of the domain: n the distance coordinate of domain edge `edge` (u,
/// v, then 1 - u - v), t = the walk coordinate - ½. The curve runs along the edge and
/// dips 2⁻⁴⁹ (1.8·10⁻¹⁵) outside it at t = 0, as rounding of a curve touching the edge
/// would: within the 64-ulp tolerance (1.4·10⁻¹⁴) of the walk's and the split's domain
/// guards. With y = ±24 (n - 1.5 t² + 2⁻⁴⁹) + 40.5, a chord of the curve across Δt has
/// midpoint error 9 Δt² pixels, exactly k = 0.25 at Δt = ⅙: a walk from t = -½ steps
/// onto t = 0. Returns the lembo (y and its Hessian set exactly: every coefficient has
/// few binary digits), the walk key direction and the point of the curve at `t`.
fn along_edge(edge: usize) -> (ScreenLembo<f64>, V2<f64>, impl Fn(f64) -> ConicPoint<f64>) {
    let dip = 2f64.powi(-49);
    // n = nu u + nv v + n0 and t = tu u + tv v + t0.
    let ((nu, nv, n0), (tu, tv, t0)) = match edge {
        0 => ((1.0, 0.0, 0.0), (0.0, 1.0, -0.5)),
        1 => ((0.0, 1.0, 0.0), (1.0, 0.0, -0.5)),
        _ => ((-1.0, -1.0, 1.0), (1.0, 0.0, -0.5)),
    };
    // y increases across the curve towards rot_ccw(tau), as the walk and the split expect.
    let s = 24.0 * (nv * tu - nu * tv);
    let y = quad(
        -1.5 * s * tu * tu,
        -1.5 * s * tv * tv,
        -3.0 * s * tu * tv,
        s * nu - 3.0 * s * tu * t0,
        s * nv - 3.0 * s * tv * t0,
        s * n0 - 1.5 * s * t0 * t0 + s * dip + 40.5,
    );
    let mut l = screen_lembo::<f64>(x_linear(), y);
    l.y = y;
    l.hessian = (2.0 * y.a, y.c, 2.0 * y.b);
    let tau = [tu, tv];
    let x = l.x;
    let at = move |t: f64| {
        let n = 1.5 * t * t - dip;
        // Solve n = nu u + nv v + n0, t + ½ = tu u + tv v for (u, v).
        let w = t - t0;
        let uv = match edge {
            0 => [n, w],
            1 => [w, n],
            _ => [w, 1.0 - w - n],
        };
        ConicPoint {
            uv,
            x: x.eval(uv[0], uv[1]),
            edge: INTERIOR,
        }
    };
    (l, tau, at)
}

/// The interval of `along_edge`'s curve from `start` to `end`, walked along `tau`.
fn along(tau: V2<f64>, start: ConicPoint<f64>, end: ConicPoint<f64>) -> Interval<f64> {
    Interval {
        start,
        end,
        tau,
        end_key: dot(tau, end.uv),
        straight: false,
    }
}

/// Asserts that `q` lies outside domain edge `edge` of `along_edge`, within the 64-ulp
/// tolerance.
fn assert_just_outside(q: V2<f64>, edge: usize) {
    let n = [q[0], q[1], 1.0 - q[0] - q[1]][edge];
    assert!(
        n < 0.0 && n > -64.0 * f64::EPSILON,
        "edge {edge}: n = {n:e}"
    );
}

/// The walk's domain guard takes a step that lands within its 64-ulp tolerance outside an
/// edge (here 2⁻⁴⁹ outside, at t = 0 of `along_edge`), for each edge: the walk from t = -½
/// to an end at t = 0.3 is four steps of exactly k (onto t = -⅓, -⅙, 0, ⅙) and the
/// closing chord. A guard without the tolerance refuses the step onto t = 0 and closes the
/// walk there with split chords, as does one whose tolerance is 64 times too small.
#[test]
fn the_walk_takes_a_step_within_rounding_outside_an_edge() {
    for edge in 0..3 {
        let (l, tau, at) = along_edge(edge);
        let end = at(0.3);
        let iv = along(tau, at(-0.5), end);
        let (mut out, mut c) = (Vec::new(), Counts::default());
        segments(&l, 40, 0.25, &iv, DEFAULT_SEGMENT_CAP, &mut out, &mut c).expect("under the cap");
        assert_eq!(out.len(), 5, "edge {edge}: {out:?}");
        assert_eq!(
            (c.segments_clamped, c.segments_refined),
            (1, 0),
            "edge {edge}"
        );
        for (i, s) in out[..4].iter().enumerate() {
            let want = at(i as f64 / 6.0 - 1.0 / 3.0).uv;
            let off = (s.p1.uv[0] - want[0])
                .abs()
                .max((s.p1.uv[1] - want[1]).abs());
            assert!(
                off < 1e-15,
                "edge {edge}, step {i}: {:?} for {want:?}",
                s.p1.uv
            );
        }
        // The third step's end lies outside the edge, within the tolerance.
        assert_just_outside(out[2].p1.uv, edge);
        assert_eq!(out[4].p1, end);
    }
}

/// The closing chords' split takes a split point within the 64-ulp tolerance outside an
/// edge: the chord of `along_edge` from t = -⅓ to ⅓ (midpoint error 4k) splits at the key
/// halfway, t = 0, 2⁻⁴⁹ outside the edge, and each half once more (at t = ∓⅙, where the
/// quarters are exactly k): four chords. Refusing the point at t = 0 keeps the chord
/// whole.
#[test]
fn closing_chords_split_at_a_point_within_rounding_outside_an_edge() {
    for edge in 0..3 {
        let (l, tau, at) = along_edge(edge);
        let start = at(-1.0 / 3.0);
        let iv = along(tau, start, at(1.0 / 3.0));
        let (mut out, mut c) = (Vec::new(), Counts::default());
        last_chords(&l, 40.5, 0.25, &iv, start, 0, 1 << 16, &mut out, &mut c)
            .expect("under the cap");
        assert_eq!(out.len(), 4, "edge {edge}: {out:?}");
        assert_eq!(c.segments_refined, 3, "edge {edge}");
        assert_just_outside(out[1].p1.uv, edge);
    }
}
