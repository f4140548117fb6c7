//! The lembos prepared for ray queries at any screen position ([`Tracer`]): each lembo's
//! screen footprint (its projected Bézier net's box, or everywhere when part of the net is
//! at or behind the eye) and the lembos binned per screen tile, nearest first.

use super::roots::{Patch, Root, Scratch};
use crate::camera::View;
use crate::lembo::Lembo;
use glam::DVec3;

/// Side of the square screen tiles that lembos are binned into \[pixels\].
pub(super) const TILE: u32 = 16;

/// The winning surface at a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceHit {
    /// Depth in [0, 1] of the hit point, as [`View::depth_of`] gives it.
    pub depth: f64,
    /// Unit normal of the normal function at (u, v), as shaded before the two-sided flip
    /// (zero where the normal function vanishes).
    pub normal: DVec3,
    /// Index of the lembo in [`super::ReferenceInput::lembos`].
    pub lembo: u32,
    /// Domain coordinates of the hit.
    pub u: f64,
    /// Domain v of the hit.
    pub v: f64,
}

/// Where a lembo can appear on screen.
#[derive(Clone, Copy, Debug)]
enum Footprint {
    /// Part of the control net is at or behind the eye: test every sample.
    Everywhere,
    /// The screen box of the projected control net \[pixels\] and its nearest depth.
    Box {
        x0: f64,
        y0: f64,
        x1: f64,
        y1: f64,
        z0: f64,
    },
}

impl Footprint {
    #[inline]
    fn contains(&self, x: f64, y: f64) -> bool {
        match *self {
            Footprint::Everywhere => true,
            Footprint::Box { x0, y0, x1, y1, .. } => x >= x0 && x <= x1 && y >= y0 && y <= y1,
        }
    }
}

/// Slack on screen boxes \[pixels\]: the hit of a sample on the box's edge projects to it
/// only up to rounding.
const SCREEN_SLACK: f64 = 1e-6;

/// The footprint of a lembo, or `None` when it cannot be visible (outside the viewport or
/// the depth range).
fn footprint(patch: &Patch, view: &View) -> Option<Footprint> {
    let projected = patch.controls.map(|c| view.project(c));
    if projected.iter().any(|p| p.w <= 0.0 || p.w.is_nan()) {
        return Some(Footprint::Everywhere);
    }
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    let (mut z0, mut z1) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &projected {
        (x0, x1, y0, y1) = (x0.min(p.x), x1.max(p.x), y0.min(p.y), y1.max(p.y));
        (z0, z1) = (z0.min(p.depth), z1.max(p.depth));
    }
    let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
    let s = SCREEN_SLACK;
    let (x0, y0, x1, y1) = (x0 - s, y0 - s, x1 + s, y1 + s);
    let outside = x1 < 0.0 || y1 < 0.0 || x0 > w || y0 > h || z1 < -s || z0 > 1.0 + s;
    (!outside).then_some(Footprint::Box { x0, y0, x1, y1, z0 })
}

/// The lembos prepared for ray queries at any screen position: patches, footprints and the
/// lembos binned per tile. The reference image samples it at fixed positions; the accuracy
/// metrics ask it about any point (the sub-pixel silhouette, `metrics.rs`).
pub struct Tracer<'a> {
    view: &'a View,
    pub(super) patches: Vec<Patch<'a>>,
    footprints: Vec<Option<Footprint>>,
    pub(super) tiles_x: u32,
    tiles_y: u32,
    /// Per tile, the lembos whose footprint meets it, nearest first.
    pub(super) bins: Vec<Vec<u32>>,
}

/// Buffers a [`Tracer`] reuses from query to query (one per thread).
#[derive(Default)]
pub struct TraceScratch {
    scratch: Scratch,
    roots: Vec<Root>,
}

impl<'a> Tracer<'a> {
    /// The lembos (index = lembo id) seen by `view`.
    pub fn new(lembos: impl IntoIterator<Item = &'a Lembo>, view: &'a View) -> Self {
        let patches: Vec<Patch> = lembos.into_iter().map(Patch::new).collect();
        let footprints: Vec<Option<Footprint>> =
            patches.iter().map(|p| footprint(p, view)).collect();
        let tiles_x = view.viewport.width.div_ceil(TILE);
        let tiles_y = view.viewport.height.div_ceil(TILE);
        let mut bins = vec![Vec::new(); (tiles_x * tiles_y) as usize];
        for (id, f) in footprints.iter().enumerate() {
            let Some(f) = f else { continue };
            let (tx0, ty0, tx1, ty1) = match *f {
                Footprint::Everywhere => (0, 0, tiles_x - 1, tiles_y - 1),
                Footprint::Box { x0, y0, x1, y1, .. } => {
                    let tile =
                        |x: f64, n: u32| ((x / TILE as f64).floor().max(0.0) as u32).min(n - 1);
                    (
                        tile(x0, tiles_x),
                        tile(y0, tiles_y),
                        tile(x1, tiles_x),
                        tile(y1, tiles_y),
                    )
                }
            };
            for ty in ty0..=ty1 {
                for tx in tx0..=tx1 {
                    bins[(ty * tiles_x + tx) as usize].push(id as u32);
                }
            }
        }
        // Nearest first, so that the hits found early bound the search of the rest.
        let near = |id: &u32| match footprints[*id as usize] {
            Some(Footprint::Box { z0, .. }) => z0,
            _ => f64::NEG_INFINITY,
        };
        for bin in &mut bins {
            bin.sort_by(|a, b| near(a).total_cmp(&near(b)).then(a.cmp(b)));
        }
        Tracer {
            view,
            patches,
            footprints,
            tiles_x,
            tiles_y,
            bins,
        }
    }

    /// The lembos of the tile holding screen position (x, y), clamped into the viewport.
    fn bin_at(&self, x: f64, y: f64) -> &[u32] {
        let tile = |x: f64, n: u32| ((x / TILE as f64).floor().max(0.0) as u32).min(n - 1);
        let (tx, ty) = (tile(x, self.tiles_x), tile(y, self.tiles_y));
        &self.bins[(ty * self.tiles_x + tx) as usize]
    }

    /// The nearest hit at screen position (x, y) [pixels; pixel (i, j)'s centre is
    /// (i + 0.5, j + 0.5)], as the reference image's samples are computed: at a pixel centre
    /// it is that pixel's `hits` entry. Positions outside the viewport see only the lembos
    /// whose footprint meets the viewport.
    pub fn hit(&self, x: f64, y: f64, scratch: &mut TraceScratch) -> Option<ReferenceHit> {
        let bin = self.bin_at(x, y);
        self.trace(x, y, bin, &mut scratch.scratch, &mut scratch.roots)
    }

    /// Whether the ray through screen position (x, y) \[pixels\] hits a surface: the same
    /// condition as [`Tracer::hit`] being `Some` (a root with t > 0 and depth in [0, 1]),
    /// decided at the first such root found, which makes rays grazing an outline far
    /// cheaper to answer.
    pub fn covers(&self, x: f64, y: f64, scratch: &mut TraceScratch) -> bool {
        let view = self.view;
        let (origin, dir) = view.ray(x, y);
        for &id in self.bin_at(x, y) {
            let footprint = self.footprints[id as usize].expect("binned lembos have a footprint");
            if !footprint.contains(x, y) {
                continue;
            }
            let patch = &self.patches[id as usize];
            let mut accept = |r: &Root| {
                r.t > 0.0 && (0.0..=1.0).contains(&view.depth_of(patch.lembo.position_at(r.u, r.v)))
            };
            if patch.any_root(
                origin,
                dir,
                0.0,
                f64::INFINITY,
                &mut scratch.scratch,
                &mut accept,
            ) {
                return true;
            }
        }
        false
    }

    /// The nearest hit at screen position (x, y) \[pixels\] among the lembos of `bin`.
    pub(super) fn trace(
        &self,
        x: f64,
        y: f64,
        bin: &[u32],
        scratch: &mut Scratch,
        roots: &mut Vec<Root>,
    ) -> Option<ReferenceHit> {
        let view = self.view;
        let (origin, dir) = view.ray(x, y);
        let mut best: Option<ReferenceHit> = None;
        let mut best_t = f64::INFINITY;
        for &id in bin {
            let footprint = self.footprints[id as usize].expect("binned lembos have a footprint");
            if !footprint.contains(x, y) {
                continue;
            }
            let patch = &self.patches[id as usize];
            roots.clear();
            patch.roots(origin, dir, 0.0, best_t, scratch, roots);
            for r in roots.iter() {
                if r.t <= 0.0 || r.t.is_nan() {
                    continue;
                }
                let depth = view.depth_of(patch.lembo.position_at(r.u, r.v));
                let nearer =
                    best.is_none_or(|b| depth < b.depth || (depth == b.depth && id < b.lembo));
                if (0.0..=1.0).contains(&depth) && nearer {
                    best_t = r.t;
                    best = Some(ReferenceHit {
                        depth,
                        normal: patch.lembo.unit_normal_at(r.u, r.v),
                        lembo: id,
                        u: r.u,
                        v: r.v,
                    });
                }
            }
        }
        best
    }
}
