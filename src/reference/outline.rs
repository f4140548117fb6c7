//! The sub-pixel silhouette error: for a pixel whose centre the render and the reference
//! cover differently, the distance from its centre to the reference's true outline (the
//! boundary of the set of screen positions whose reference ray hits a surface), found by
//! asking the reference about points between pixel centres.
//!
//! For a misplaced pixel centre `c`, with `D` the distance to the nearest pixel centre the
//! reference covers differently from `c` (the outline lies within `D` of `c`):
//! 1. **Contour.** Every cell of four neighbouring pixel centres within `D` of `c` whose
//!    corners disagree holds part of the outline. Each cell edge between centres that
//!    disagree is bisected with the reference: its *crossing* is a point of the outline.
//!    Inside the cell the outline is taken as the segment between its edges' crossings
//!    (marching squares; in a cell whose diagonal corners agree, the reference at the
//!    cell's centre decides which corners the two segments cut off). The nearest point of
//!    these segments to `c` is the *foot*.
//! 2. **Rays.** The ray from `c` through the foot, continued half a pixel beyond it (and
//!    clipped to the viewport), is bisected with the reference; so are the rays turned by
//!    ±`ANGLE_STEP` and, when the three distances make a parabola open upwards, the ray
//!    at its vertex (a segment's normal is the outline's at the segment's middle, not at
//!    the foot). Each ray whose end lies on the other side gives a crossing.
//!
//! The distance is the smallest over these crossings (rays, and the crossings on the cells'
//! edges), capped at `D`. Every crossing is a point of the true outline located to within
//! half of [`SILHOUETTE_RESOLUTION_PX`] along its segment, so the distance is never shorter
//! than the exact one by more than that; it equals the exact one to that resolution where
//! the outline is smooth at the scale of a pixel (tested on discs). Where two outlines meet
//! in a corner it can come out longer (by 0.1 px near a concave corner in the tests), and
//! outline features narrower than a pixel that no centre sees (a sliver of coverage
//! between centres) are found only if a ray meets them.
//!
//! Pixels farther than [`RAY_BOUND_PX`] from every centre of the other state (gross
//! errors: a coarse tessellation's chords, 24 px deep on sphere24) cast no rays: their
//! distance is the contour's (step 1), off by the chords' sagitta, under 1/(4R) px for an
//! outline of curvature radius R px (and short by up to half a cell's diagonal where a
//! chord cuts a corner). With no centre of the other state in the image at all, the caller
//! takes the image diagonal; in an image one pixel wide or high (no cells) the distance is
//! `D`. Pixels farther than [`CONTOUR_BOUND_PX`] from every centre of the other state take
//! `D` itself (within 0.71 px of the outline's distance).

use glam::DVec2;
use rayon::prelude::*;
use std::cell::RefCell;

use super::oracle::{TraceScratch, Tracer};

/// How finely outline points are located \[pixels\]: bisection stops when the interval
/// holding the crossing is this short, and the crossing is taken at its middle.
pub const SILHOUETTE_RESOLUTION_PX: f64 = 1.0 / 256.0;

/// The turn of the two rays beside the one through the contour's foot [radians].
const ANGLE_STEP: f64 = 0.1;

/// Rays are cast only from misplaced pixels whose bound `D` is at most this \[pixels\];
/// farther ones take the distance to the contour, so that the work grows with the
/// outline's length, not with the area of a gross error.
pub const RAY_BOUND_PX: f64 = 3.0;

/// Misplaced pixels farther than this \[pixels\] from every centre of the other state take
/// that distance `D` itself, within half a cell's diagonal (0.71 px) of the outline's: a
/// contour search over a disc of radius `D` per pixel would make a gross error's metric
/// cost grow as its area times `D²` (25 s for a floor of 78 767 missed pixels).
pub const CONTOUR_BOUND_PX: f64 = 16.0;

/// The reference's coverage at any screen position.
pub trait ReferenceCoverage: Sync {
    /// Whether the reference's ray through screen position (x, y) [pixels; pixel (i, j)'s
    /// centre is (i + 0.5, j + 0.5)] hits a surface. At a pixel centre it must agree with
    /// the reference image's sample there.
    fn covered(&self, x: f64, y: f64) -> bool;
}

impl ReferenceCoverage for Tracer<'_> {
    fn covered(&self, x: f64, y: f64) -> bool {
        thread_local! {
            static SCRATCH: RefCell<TraceScratch> = RefCell::new(TraceScratch::default());
        }
        SCRATCH.with(|s| self.covers(x, y, &mut s.borrow_mut()))
    }
}

/// A misplaced pixel: its index and the distance `D` to the nearest pixel centre of the
/// other reference state \[pixels\].
#[derive(Clone, Copy, Debug)]
pub struct Misplaced {
    /// The pixel's index, row-major.
    pub index: usize,
    /// The distance `D` \[pixels\].
    pub bound: f64,
}

/// The reference's centre samples, as the outline search reads them.
struct Grid<'a> {
    covered: &'a [bool],
    w: usize,
    h: usize,
}

/// Edge key: `2 * index + 0` for the edge from pixel `index` to its right neighbour,
/// `2 * index + 1` to the one below.
type EdgeKey = u64;

/// The four edges of the cell whose top-left centre is pixel (a, b), in the order top,
/// right, bottom, left, each as (key, start pixel, end pixel).
fn cell_edges(a: usize, b: usize, w: usize) -> [(EdgeKey, usize, usize); 4] {
    let k = b * w + a;
    let (right, below, diagonal) = (k + 1, k + w, k + w + 1);
    [
        (2 * k as u64, k, right),
        (2 * right as u64 + 1, right, diagonal),
        (2 * below as u64, below, diagonal),
        (2 * k as u64 + 1, k, below),
    ]
}

impl Grid<'_> {
    /// Screen position of pixel `k`'s centre.
    fn centre(&self, k: usize) -> DVec2 {
        DVec2::new((k % self.w) as f64 + 0.5, (k / self.w) as f64 + 0.5)
    }

    /// Calls `f(a, b)` for every cell (top-left centre (a, b)) within `bound` of pixel `k`'s
    /// centre that may hold a centre of the other state than `k`'s: cells all of whose
    /// corners are nearer than `bound` are skipped, since every centre nearer than the bound
    /// has `k`'s state.
    fn candidate_cells(&self, k: usize, bound: f64, mut f: impl FnMut(usize, usize)) {
        let (w, h) = (self.w as i64, self.h as i64);
        if w < 2 || h < 2 {
            return;
        }
        let (ci, cj) = ((k % self.w) as i64, (k / self.w) as i64);
        let d2 = bound * bound;
        let r = bound.ceil() as i64 + 1;
        for b in (cj - r).max(0)..=(cj + r).min(h - 2) {
            // Rows of the cell box [b, b + 1] against cj, in index units.
            let near_dy = (b - cj).max(cj - b - 1).max(0) as f64;
            let room = d2 - near_dy * near_dy;
            if room < 0.0 {
                continue;
            }
            let reach = room.sqrt() + 0.5 + 1e-9;
            let centre = ci as f64 - 0.5;
            let lo = ((centre - reach).ceil() as i64).max(0);
            let hi = ((centre + reach).floor() as i64).min(w - 2);
            // |a - ci + 0.5| below `inner`: every corner nearer than the bound.
            let far_dy = (b - cj).abs().max((b + 1 - cj).abs()) as f64;
            let inner_room = d2 - far_dy * far_dy;
            let inner = if inner_room > 0.0 {
                inner_room.sqrt() - 0.5 - 1e-9
            } else {
                0.0
            };
            let (skip_lo, skip_hi) = if inner > 0.0 {
                (
                    (centre - inner).floor() as i64 + 1,
                    (centre + inner).ceil() as i64 - 1,
                )
            } else {
                (i64::MAX, i64::MIN)
            };
            for a in lo..=hi {
                if a >= skip_lo && a <= skip_hi {
                    continue;
                }
                f(a as usize, b as usize);
            }
        }
    }

    /// Whether the corners of cell (a, b) disagree, and whether they form a saddle
    /// (diagonal corners agree, neighbours disagree).
    fn cell_kind(&self, a: usize, b: usize) -> (bool, bool) {
        let k = b * self.w + a;
        let c = self.covered;
        let (tl, tr, bl, br) = (c[k], c[k + 1], c[k + self.w], c[k + self.w + 1]);
        let mixed = !(tl == tr && tr == bl && bl == br);
        (mixed, mixed && tl == br && tr == bl && tl != tr)
    }
}

/// Bisects the segment from `p0` (coverage `s0`) to `p1` (the other coverage) until the
/// interval holding a crossing is at most [`SILHOUETTE_RESOLUTION_PX`] long; the fraction of
/// the way to `p1` of its middle.
fn bisect(coverage: &dyn ReferenceCoverage, p0: DVec2, p1: DVec2, s0: bool) -> f64 {
    let len = (p1 - p0).length();
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while (hi - lo) * len > SILHOUETTE_RESOLUTION_PX {
        let mid = 0.5 * (lo + hi);
        let p = p0 + mid * (p1 - p0);
        if coverage.covered(p.x, p.y) == s0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The distance from point `p` to the segment `a`-`b`, and the nearest point.
fn to_segment(p: DVec2, a: DVec2, b: DVec2) -> (f64, DVec2) {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = a + t * ab;
    ((p - q).length(), q)
}

/// The distance \[pixels\] from each misplaced pixel's centre to the reference outline (see
/// the module documentation), in the order given. `covered` is the reference's centre
/// samples, row-major `w` x `h`.
pub fn outline_distances(
    covered: &[bool],
    w: usize,
    h: usize,
    pixels: &[Misplaced],
    coverage: &dyn ReferenceCoverage,
) -> Vec<f64> {
    let outline = Outline::new(Grid { covered, w, h }, pixels, coverage);
    pixels.par_iter().map(|m| outline.distance(m)).collect()
}

/// The outline crossings the searches read: every mixed cell edge near a misplaced pixel,
/// bisected once, and every saddle cell's centre sample.
struct Outline<'a> {
    grid: Grid<'a>,
    coverage: &'a dyn ReferenceCoverage,
    /// The edges crossed, sorted, and where along each the outline crosses (0 to 1).
    edges: Vec<EdgeKey>,
    crossings: Vec<f64>,
    /// The saddle cells (by top-left pixel), sorted, and whether each one's centre is
    /// covered.
    saddles: Vec<u64>,
    saddle_centres: Vec<bool>,
}

impl<'a> Outline<'a> {
    /// Collects and bisects the edges and saddles the pixels within
    /// [`CONTOUR_BOUND_PX`] read.
    fn new(grid: Grid<'a>, pixels: &[Misplaced], coverage: &'a dyn ReferenceCoverage) -> Self {
        let (covered, w) = (grid.covered, grid.w);
        let (mut edges, mut saddles) = (Vec::new(), Vec::new());
        for m in pixels.iter().filter(|m| m.bound <= CONTOUR_BOUND_PX) {
            grid.candidate_cells(m.index, m.bound, |a, b| {
                let (mixed, saddle) = grid.cell_kind(a, b);
                if !mixed {
                    return;
                }
                for (key, p, q) in cell_edges(a, b, w) {
                    if covered[p] != covered[q] {
                        edges.push(key);
                    }
                }
                if saddle {
                    saddles.push((b * w + a) as u64);
                }
            });
        }
        edges.sort_unstable();
        edges.dedup();
        saddles.sort_unstable();
        saddles.dedup();
        let crossings: Vec<f64> = edges
            .par_iter()
            .map(|&key| {
                let p = (key / 2) as usize;
                let q = if key.is_multiple_of(2) { p + 1 } else { p + w };
                bisect(coverage, grid.centre(p), grid.centre(q), covered[p])
            })
            .collect();
        let saddle_centres: Vec<bool> = saddles
            .par_iter()
            .map(|&k| {
                let c = grid.centre(k as usize) + DVec2::splat(0.5);
                coverage.covered(c.x, c.y)
            })
            .collect();
        Outline {
            grid,
            coverage,
            edges,
            crossings,
            saddles,
            saddle_centres,
        }
    }

    /// Where the outline crosses edge `key`.
    fn crossing(&self, key: EdgeKey) -> DVec2 {
        let t = self.crossings[self.edges.binary_search(&key).expect("edge collected")];
        let p = (key / 2) as usize;
        let step = if key.is_multiple_of(2) {
            DVec2::X
        } else {
            DVec2::Y
        };
        self.grid.centre(p) + t * step
    }

    /// The distance from misplaced pixel `m`'s centre to the outline.
    fn distance(&self, m: &Misplaced) -> f64 {
        if m.bound > CONTOUR_BOUND_PX {
            return m.bound;
        }
        let c = self.grid.centre(m.index);
        let (best, nearest_crossing) = self.nearest_segment(m, c);
        let Some((contour, foot)) = best else {
            return m.bound;
        };
        if m.bound > RAY_BOUND_PX {
            return contour.min(m.bound);
        }
        self.along_rays(c, self.grid.covered[m.index], foot, nearest_crossing)
            .min(m.bound)
    }

    /// The nearest point of the outline's segments (marching squares over the cells within
    /// `m`'s bound) with its distance from `c`, and the distance to the nearest crossing.
    fn nearest_segment(&self, m: &Misplaced, c: DVec2) -> (Option<(f64, DVec2)>, f64) {
        let (grid, covered) = (&self.grid, self.grid.covered);
        let mut best: Option<(f64, DVec2)> = None;
        // The nearest crossing: a point of the outline itself.
        let mut nearest_crossing = f64::INFINITY;
        let mut keep = |(d, q): (f64, DVec2), ends: [DVec2; 2]| {
            if best.is_none_or(|(b, _)| d < b) {
                best = Some((d, q));
            }
            for e in ends {
                nearest_crossing = nearest_crossing.min((e - c).length());
            }
        };
        grid.candidate_cells(m.index, m.bound, |a, b| {
            let (mixed, saddle) = grid.cell_kind(a, b);
            if !mixed {
                return;
            }
            let sides = cell_edges(a, b, grid.w);
            if saddle {
                let k = (b * grid.w + a) as u64;
                let centre = self.saddle_centres[self.saddles.binary_search(&k).expect("saddle")];
                let [top, right, bottom, left] = sides.map(|(key, _, _)| self.crossing(key));
                // The centre agrees with the top-left corner: the top-right and
                // bottom-left corners are cut off; otherwise the other two.
                let pairs = if centre == covered[sides[0].1] {
                    [(top, right), (bottom, left)]
                } else {
                    [(top, left), (bottom, right)]
                };
                for (p, q) in pairs {
                    keep(to_segment(c, p, q), [p, q]);
                }
            } else {
                let mut ends = sides
                    .iter()
                    .filter(|(_, p, q)| covered[*p] != covered[*q])
                    .map(|(key, _, _)| self.crossing(*key));
                if let (Some(p), Some(q)) = (ends.next(), ends.next()) {
                    keep(to_segment(c, p, q), [p, q]);
                }
            }
        });
        (best, nearest_crossing)
    }

    /// The distance from `c` (covered: `mine`) to the outline along the ray towards the
    /// segments' nearest point `foot` and rays turned about it, no farther than the
    /// nearest crossing.
    fn along_rays(&self, c: DVec2, mine: bool, foot: DVec2, nearest_crossing: f64) -> f64 {
        let (w, h, coverage) = (self.grid.w, self.grid.h, self.coverage);
        let along = foot - c;
        let len = along.length();
        if len == 0.0 {
            return nearest_crossing;
        }
        // A crossing of the outline along the ray from c in direction `dir`,
        // searched within `reach` (clipped to the viewport), if the ray's end there lies
        // on the other side.
        let crossing_along = |dir: DVec2, reach: f64| -> Option<f64> {
            let mut reach = reach;
            for (p, d, size) in [(c.x, dir.x, w as f64), (c.y, dir.y, h as f64)] {
                if d > 0.0 {
                    reach = reach.min((size - p) / d);
                } else if d < 0.0 {
                    reach = reach.min(-p / d);
                }
            }
            let end = c + reach * dir;
            (coverage.covered(end.x, end.y) != mine).then(|| reach * bisect(coverage, c, end, mine))
        };
        let dir = along / len;
        let Some(r0) = crossing_along(dir, len + 0.5) else {
            return nearest_crossing;
        };
        // The contour's normal is the outline's at the chord's middle, not at the foot:
        // the distance along rays turned by ±ANGLE_STEP, and at the vertex of the
        // parabola through the three, finds the nearest direction.
        let turned = |a: f64| DVec2::from_angle(a).rotate(dir);
        let mut best = r0.min(nearest_crossing);
        if let (Some(rm), Some(rp)) = (
            crossing_along(turned(-ANGLE_STEP), r0 + 0.5),
            crossing_along(turned(ANGLE_STEP), r0 + 0.5),
        ) {
            best = best.min(rm).min(rp);
            let curvature = rm - 2.0 * r0 + rp;
            if curvature > 0.0 {
                let vertex = (0.5 * (rm - rp) / curvature).clamp(-2.0, 2.0) * ANGLE_STEP;
                if let Some(r) = crossing_along(turned(vertex), r0 + 0.5) {
                    best = best.min(r);
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A disc of radius `r` about `centre`, covered where the distance is at most `r`.
    struct Disc {
        centre: DVec2,
        r: f64,
    }

    impl ReferenceCoverage for Disc {
        fn covered(&self, x: f64, y: f64) -> bool {
            (DVec2::new(x, y) - self.centre).length() <= self.r
        }
    }

    fn grid_of(c: &dyn ReferenceCoverage, w: usize, h: usize) -> Vec<bool> {
        (0..w * h)
            .map(|k| c.covered((k % w) as f64 + 0.5, (k / w) as f64 + 0.5))
            .collect()
    }

    /// The nearest centre of the other state, by brute force.
    fn bound(covered: &[bool], w: usize, k: usize) -> f64 {
        let (x, y) = ((k % w) as f64, (k / w) as f64);
        (0..covered.len())
            .filter(|&p| covered[p] != covered[k])
            .map(|p| ((x - (p % w) as f64).powi(2) + (y - (p / w) as f64).powi(2)).sqrt())
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn distances_to_a_disc_outline_are_exact_to_the_resolution() {
        let (w, h) = (40, 36);
        let disc = Disc {
            centre: DVec2::new(19.37, 17.81),
            r: 11.3,
        };
        let covered = grid_of(&disc, w, h);
        // Every pixel within 5 px of the outline, on both sides.
        let pixels: Vec<Misplaced> = (0..w * h)
            .filter(|&k| {
                let c = DVec2::new((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
                ((c - disc.centre).length() - disc.r).abs() < 5.0
            })
            .map(|k| Misplaced {
                index: k,
                bound: bound(&covered, w, k),
            })
            .collect();
        assert!(pixels.len() > 500);
        let d = outline_distances(&covered, w, h, &pixels, &disc);
        let (mut rays, mut contour) = (0, 0);
        for (m, d) in pixels.iter().zip(d) {
            let c = DVec2::new((m.index % w) as f64 + 0.5, (m.index / w) as f64 + 0.5);
            let exact = ((c - disc.centre).length() - disc.r).abs();
            // Beyond the ray bound, the contour's chords are off by their sagitta.
            let tolerance = if m.bound <= RAY_BOUND_PX {
                rays += 1;
                SILHOUETTE_RESOLUTION_PX
            } else {
                contour += 1;
                SILHOUETTE_RESOLUTION_PX + 1.0 / (4.0 * disc.r)
            };
            assert!(
                (d - exact).abs() <= tolerance,
                "pixel {}: {d} vs {exact}",
                m.index
            );
        }
        assert!(rays > 300 && contour > 100, "{rays} {contour}");
    }

    #[test]
    fn two_overlapping_discs_a_saddle_and_a_thin_image() {
        // Two overlapping discs: the outline is the union's, arcs of both circles.
        const DISCS: [(f64, f64, f64); 2] = [(4.0, 4.0, 2.9), (9.0, 9.0, 5.0)];
        struct Two;
        impl ReferenceCoverage for Two {
            fn covered(&self, x: f64, y: f64) -> bool {
                DISCS
                    .iter()
                    .any(|&(cx, cy, r)| (DVec2::new(x, y) - DVec2::new(cx, cy)).length() <= r)
            }
        }
        // The distance to the union's outline: to the points of each circle outside the
        // other disc, sampled every 1e-5 radians.
        let exact = |c: DVec2| {
            let mut best = f64::INFINITY;
            for (n, &(cx, cy, r)) in DISCS.iter().enumerate() {
                let (ox, oy, or) = DISCS[1 - n];
                for s in 0..628_319 {
                    let p = DVec2::new(cx, cy) + r * DVec2::from_angle(s as f64 * 1e-5);
                    if (p - DVec2::new(ox, oy)).length() >= or {
                        best = best.min((p - c).length());
                    }
                }
            }
            best
        };
        let (w, h) = (16, 16);
        let covered = grid_of(&Two, w, h);
        // By the arcs, and near where the circles meet, the outline's concave corners: the
        // contour's chords cut them, and the distance may come out a little long there,
        // never short.
        let res = SILHOUETTE_RESOLUTION_PX;
        for (k, slack) in [
            (5 * w + 3, res),
            (12 * w + 12, res),
            (2 * w + 6, res),
            (3 * w + 7, 0.01),
            (6 * w + 4, 0.1),
        ] {
            let pixels = [Misplaced {
                index: k,
                bound: bound(&covered, w, k),
            }];
            let d = outline_distances(&covered, w, h, &pixels, &Two)[0];
            let e = exact(DVec2::new((k % w) as f64 + 0.5, (k / w) as f64 + 0.5));
            assert!(d >= e - res && d <= e + slack, "pixel {k}: {d} vs {e}");
        }

        // Opposite quadrants covered: the cell about (8, 8) is a saddle, and the outline
        // has a corner there, which the contour cuts. From (7.5, 7.5) the ray towards the
        // cut crosses the outline only at the corner and beyond, so the nearest crossing on
        // the cell's edges, 0.5 along the axes, is the distance.
        struct Quadrants;
        impl ReferenceCoverage for Quadrants {
            fn covered(&self, x: f64, y: f64) -> bool {
                (x - 8.0) * (y - 8.0) > 0.0
            }
        }
        let covered = grid_of(&Quadrants, w, h);
        let pixels: Vec<Misplaced> = [7 * w + 7, 7 * w + 4, 3 * w + 8]
            .map(|k| Misplaced {
                index: k,
                bound: bound(&covered, w, k),
            })
            .to_vec();
        let d = outline_distances(&covered, w, h, &pixels, &Quadrants);
        assert!((d[0] - 0.5).abs() <= SILHOUETTE_RESOLUTION_PX, "{d:?}");
        assert!((d[1] - 0.5).abs() <= SILHOUETTE_RESOLUTION_PX, "{d:?}");
        assert!((d[2] - 0.5).abs() <= SILHOUETTE_RESOLUTION_PX, "{d:?}");

        // One row: no cells, the bound stands.
        let row = [false, false, true];
        let one = [Misplaced {
            index: 0,
            bound: 2.0,
        }];
        assert_eq!(outline_distances(&row, 3, 1, &one, &Two), vec![2.0]);
    }
}
