//! The lembos prepared for ray queries at any screen position ([`Tracer`]), in bounded
//! memory: each lembo's screen footprint (its projected Bézier net's box, or everywhere
//! when part of the net is at or behind the eye) binned per square screen tile, and the
//! lembos of a few consecutive tiles of one row (a [`Span`], whose lembos made are a
//! [`Band`]) made, prepared and sorted nearest first only while those tiles are traced.
//!
//! Binning makes every lembo once and keeps only its id in each tile its footprint meets
//! (4 bytes a tile) and, while binning, its tile range; a band makes again the lembos its
//! tiles list. A sample sees the lembos of its tile whose footprint holds it, nearest first
//! by the footprint's nearest depth and then by id: the same lembos in the same order
//! whatever the tile size, so every result is the same bit for bit at any tile size, span
//! or thread count.

use super::roots::{Patch, Root, Scratch};
use super::source::LemboSource;
use crate::camera::View;
use crate::lembo::set::LastParent;
use crate::lembo::{bezier_controls, Lembo};
use glam::DVec3;
use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::{Arc, Mutex};

/// Side of the square screen tiles that lembos are binned into by default \[pixels\].
pub const DEFAULT_TILE: u32 = 16;

/// The tile sides a tracer takes \[pixels\] (`--reference-tile`).
pub const TILE_RANGE: std::ops::RangeInclusive<u32> = 4..=1024;

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
        self.holds_x(x) && self.holds_y(y)
    }

    /// Whether its columns hold x.
    #[inline]
    fn holds_x(&self, x: f64) -> bool {
        match *self {
            Footprint::Everywhere => true,
            Footprint::Box { x0, x1, .. } => x >= x0 && x <= x1,
        }
    }

    /// Whether its rows hold y.
    #[inline]
    fn holds_y(&self, y: f64) -> bool {
        match *self {
            Footprint::Everywhere => true,
            Footprint::Box { y0, y1, .. } => y >= y0 && y <= y1,
        }
    }
}

/// Slack on screen boxes \[pixels\]: the hit of a sample on the box's edge projects to it
/// only up to rounding.
const SCREEN_SLACK: f64 = 1e-6;

/// The footprint of a lembo, or `None` when it cannot be visible (outside the viewport or
/// the depth range).
fn footprint(patch: &Patch, view: &View) -> Option<Footprint> {
    footprint_of(&patch.controls, view)
}

/// The footprint of the lembo whose Bézier control net is `controls` ([`footprint`]).
fn footprint_of(controls: &[DVec3; 6], view: &View) -> Option<Footprint> {
    let projected = controls.map(|c| view.project(c));
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

/// Where a lembo's footprint reaches, in tiles, as binning records it.
#[derive(Clone, Copy, Debug)]
enum Reach {
    /// Not visible: binned nowhere.
    Nowhere,
    /// Every tile.
    Everywhere,
    /// The tiles (tx0, ty0) to (tx1, ty1), inclusive.
    Tiles([u32; 4]),
}

/// Lembos made, per binning task, before the next task's.
const BINNING_CHUNK: usize = 1 << 14;

/// The lembos prepared for ray queries at any screen position, made a span of tiles at a
/// time (the module documentation). The reference image traces each span once
/// (`Tracer::band`); the accuracy metrics ask about any point ([`Tracer::covers`]), the
/// spans they reach kept in a small cache, most recently used last.
pub struct Tracer<'a> {
    view: &'a View,
    lembos: Lembos<'a>,
    bins: Arc<Bins>,
    /// Bands made for queries at any position, most recently used last.
    cache: Mutex<Vec<Arc<Band<'static>>>>,
}

/// Which lembos each screen tile of a view meets, and the spans they are made in: what
/// binning a source's lembos in a view finds (a lembo id for each tile it meets), kept by the reference
/// image traced with it ([`super::ReferenceImage::bins`]) so that its accuracy metrics ask
/// their queries of the same tiles without binning again ([`Tracer::with_bins`]).
#[derive(Debug)]
pub struct Bins {
    /// The view binned in, and the count of the lembos binned: what the bins are of.
    view: View,
    lembo_count: usize,
    tile: u32,
    tiles_x: u32,
    tiles_y: u32,
    /// The lembos whose net reaches at or behind the eye, ascending: in every tile.
    everywhere: Vec<u32>,
    /// Where each tile's lembos start in `entries`, and past the last tile, its end.
    starts: Vec<usize>,
    /// Per tile, ascending, the other lembos whose footprint box meets it.
    entries: Vec<u32>,
    /// The spans, row after row, each row's left to right.
    spans: Vec<Span>,
    /// Where each row's spans start in `spans`, and past the last row, their end.
    row_spans: Vec<usize>,
}

impl Bins {
    /// The tile side \[pixels\].
    pub fn tile(&self) -> u32 {
        self.tile
    }
}

/// Consecutive tiles of one row whose lembos are made, and traced, together.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Span {
    /// The row of tiles.
    pub(super) row: u32,
    /// The tiles' columns.
    pub(super) tiles: std::ops::Range<u32>,
}

/// The most lembos a span's tiles list together (counted once a tile), unless one tile
/// alone lists more: what bounds the lembos a band holds made (about 800 bytes each).
const SPAN_LEMBOS: usize = 4096;

/// Where a tracer's lembos come from.
enum Lembos<'a> {
    /// Made by id.
    Source(&'a dyn LemboSource),
    /// Held (tests and small scenes).
    Held(Vec<(&'a Lembo, [f64; 3])>),
}

impl Lembos<'_> {
    fn source(&self) -> &dyn LemboSource {
        match self {
            Lembos::Source(s) => *s,
            Lembos::Held(h) => h,
        }
    }
}

/// One span's lembos, made and prepared: what tracing its tiles needs.
pub(super) struct Band<'a> {
    /// The lembos' ids, ascending.
    ids: Vec<u32>,
    /// The lembos, by position in `ids`, in chunks of [`BAND_CHUNK`] (made in parallel).
    lembos: Vec<Vec<Prepared<'a>>>,
    /// Per tile of the span, its lembos nearest first, each with its footprint inline (a
    /// sample's scan over its tile reads only this list, in order, until a box holds it).
    bins: Vec<Vec<BinEntry>>,
    /// The span's index in [`Tracer::spans`].
    span: usize,
    /// Its first tile's column.
    first_tile: u32,
}

/// A lembo of a band's tile: its position in the band's `ids` and its footprint.
#[derive(Clone, Copy)]
pub(super) struct BinEntry {
    footprint: Footprint,
    k: u32,
}

/// A lembo of a band, ready to trace.
struct Prepared<'a> {
    patch: Patch<'a>,
    colour: [f64; 3],
    footprint: Footprint,
}

/// Lembos a band makes in one parallel task.
const BAND_CHUNK: usize = 1024;

/// Buffers a [`Tracer`] reuses from query to query (one per thread).
#[derive(Default)]
pub struct TraceScratch {
    scratch: Scratch,
    roots: Vec<Root>,
}

impl<'a> Tracer<'a> {
    /// The held lembos (index = lembo id) seen by `view`, binned in tiles of
    /// [`DEFAULT_TILE`] pixels.
    pub fn of(lembos: impl IntoIterator<Item = &'a Lembo>, view: &'a View) -> Self {
        let held = lembos.into_iter().map(|l| (l, [0.0; 3])).collect();
        Self::build(Lembos::Held(held), view, DEFAULT_TILE)
    }

    /// The lembos of `source` seen by `view`, binned in tiles of `tile` pixels (in
    /// [`TILE_RANGE`]: checked by the caller, clamped here).
    pub fn new(source: &'a dyn LemboSource, view: &'a View, tile: u32) -> Self {
        Self::build(Lembos::Source(source), view, tile)
    }

    /// The lembos of `source` seen by `view`, in the tiles of `bins` when they are that
    /// source's in that view (binned by a tracer of the same source and view: the same
    /// tracer, whatever the tile side), else binned anew in tiles of `bins`' side.
    pub fn with_bins(source: &'a dyn LemboSource, view: &'a View, bins: Arc<Bins>) -> Self {
        if bins.view == *view && bins.lembo_count == source.len() {
            return Tracer {
                view,
                lembos: Lembos::Source(source),
                bins,
                cache: Mutex::new(Vec::new()),
            };
        }
        Self::new(source, view, bins.tile)
    }

    /// The tiles this tracer's lembos are binned in.
    pub fn bins(&self) -> Arc<Bins> {
        self.bins.clone()
    }

    fn build(lembos: Lembos<'a>, view: &'a View, tile: u32) -> Self {
        let tile = tile.clamp(*TILE_RANGE.start(), *TILE_RANGE.end());
        let tiles_x = view.viewport.width.div_ceil(tile);
        let tiles_y = view.viewport.height.div_ceil(tile);
        let reach = reaches(lembos.source(), view, tile, (tiles_x, tiles_y));
        let tiles = (tiles_x * tiles_y) as usize;
        let mut starts = vec![0usize; tiles + 1];
        let mut everywhere = Vec::new();
        let each_tile = |[tx0, ty0, tx1, ty1]: [u32; 4], f: &mut dyn FnMut(usize)| {
            for ty in ty0..=ty1 {
                for tx in tx0..=tx1 {
                    f((ty * tiles_x + tx) as usize);
                }
            }
        };
        for (id, r) in reach.iter().flatten().enumerate() {
            match *r {
                Reach::Nowhere => {}
                Reach::Everywhere => everywhere.push(id as u32),
                Reach::Tiles(t) => each_tile(t, &mut |k| starts[k + 1] += 1),
            }
        }
        for k in 0..tiles {
            starts[k + 1] += starts[k];
        }
        let mut entries = vec![0u32; starts[tiles]];
        let mut next = starts.clone();
        for (id, r) in reach.iter().flatten().enumerate() {
            if let Reach::Tiles(t) = *r {
                each_tile(t, &mut |k| {
                    entries[next[k]] = id as u32;
                    next[k] += 1;
                });
            }
        }
        let (spans, row_spans) = split_rows(&starts, tiles_x, tiles_y);
        let lembo_count = lembos.source().len();
        Tracer {
            view,
            lembos,
            bins: Arc::new(Bins {
                view: *view,
                lembo_count,
                tile,
                tiles_x,
                tiles_y,
                everywhere,
                starts,
                entries,
                spans,
                row_spans,
            }),
            cache: Mutex::new(Vec::new()),
        }
    }

    /// The spans, row after row, each row's left to right.
    /// The view the lembos are traced in.
    pub fn view(&self) -> &'a View {
        self.view
    }

    pub(super) fn spans(&self) -> &[Span] {
        &self.bins.spans
    }

    /// The tile side \[pixels\].
    pub(super) fn tile(&self) -> u32 {
        self.bins.tile
    }

    /// The lembos of span `span`, made and prepared.
    pub(super) fn band(&self, span: usize) -> Band<'static> {
        let Span { row, tiles } = &self.bins.spans[span];
        let first = (row * self.bins.tiles_x + tiles.start) as usize;
        let last = (row * self.bins.tiles_x + tiles.end) as usize;
        let of_tile = |t: usize| &self.bins.entries[self.bins.starts[t]..self.bins.starts[t + 1]];
        let mut ids: Vec<u32> = self.bins.entries[self.bins.starts[first]..self.bins.starts[last]]
            .iter()
            .chain(&self.bins.everywhere)
            .copied()
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let source = self.lembos.source();
        // Made in parallel chunks, each in id order (a subdivided lembo's parent once).
        let lembos: Vec<Vec<Prepared>> = ids
            .par_chunks(BAND_CHUNK)
            .map(|chunk| {
                let mut last = LastParent::default();
                chunk
                    .iter()
                    .map(|&id| {
                        let (lembo, colour) = source.lembo(id as usize, &mut last);
                        let patch = Patch::new(Cow::Owned(lembo));
                        let footprint =
                            footprint(&patch, self.view).expect("binned lembos have a footprint");
                        Prepared {
                            patch,
                            colour,
                            footprint,
                        }
                    })
                    .collect()
            })
            .collect();
        let local = |id: &u32| {
            ids.binary_search(id)
                .expect("a tile's lembos are the band's") as u32
        };
        // Nearest first, so that the hits found early bound the search of the rest; ties by
        // id.
        let at = |k: u32| &lembos[k as usize / BAND_CHUNK][k as usize % BAND_CHUNK];
        let near = |k: &u32| match at(*k).footprint {
            Footprint::Box { z0, .. } => z0,
            Footprint::Everywhere => f64::NEG_INFINITY,
        };
        let bins = (first..last)
            .map(|t| {
                let mut bin: Vec<u32> = of_tile(t)
                    .iter()
                    .chain(&self.bins.everywhere)
                    .map(local)
                    .collect();
                bin.sort_by(|a, b| near(a).total_cmp(&near(b)).then(a.cmp(b)));
                bin.into_iter()
                    .map(|k| BinEntry {
                        footprint: at(k).footprint,
                        k,
                    })
                    .collect()
            })
            .collect();
        Band {
            ids,
            lembos,
            bins,
            span,
            first_tile: tiles.start,
        }
    }

    /// The band of span `span`, from the cache or made and kept there (the least recently
    /// used one dropped beyond two a thread).
    fn cached_band(&self, span: usize) -> Arc<Band<'static>> {
        let capacity = 2 * rayon::current_num_threads() + 2;
        {
            let mut cache = self
                .cache
                .lock()
                .expect("no query panics holding the cache");
            if let Some(k) = cache.iter().position(|b| b.span == span) {
                let band = cache.remove(k);
                cache.push(band.clone());
                return band;
            }
        }
        let band = Arc::new(self.band(span));
        let mut cache = self
            .cache
            .lock()
            .expect("no query panics holding the cache");
        if let Some(made) = cache.iter().find(|b| b.span == span) {
            return made.clone();
        }
        if cache.len() >= capacity {
            cache.remove(0);
        }
        cache.push(band.clone());
        band
    }

    /// The span holding tile (`tx`, `ty`).
    fn span_at(&self, tx: u32, ty: u32) -> usize {
        let row = &self.bins.spans
            [self.bins.row_spans[ty as usize]..self.bins.row_spans[ty as usize + 1]];
        self.bins.row_spans[ty as usize] + row.partition_point(|s| s.tiles.end <= tx)
    }

    /// The tile (column, row) holding screen position (x, y), clamped into the viewport.
    fn tile_at(&self, x: f64, y: f64) -> (u32, u32) {
        let tile =
            |x: f64, n: u32| ((x / self.bins.tile as f64).floor().max(0.0) as u32).min(n - 1);
        (tile(x, self.bins.tiles_x), tile(y, self.bins.tiles_y))
    }

    /// The nearest hit at screen position (x, y) [pixels; pixel (i, j)'s centre is
    /// (i + 0.5, j + 0.5)], as the reference image's samples are computed: at a pixel centre
    /// it is that pixel's `hits` entry. Positions outside the viewport see only the lembos
    /// whose footprint meets the viewport.
    pub fn hit(&self, x: f64, y: f64, scratch: &mut TraceScratch) -> Option<ReferenceHit> {
        let (tx, ty) = self.tile_at(x, y);
        let band = self.cached_band(self.span_at(tx, ty));
        band.trace(
            self.view,
            x,
            y,
            tx,
            &mut scratch.scratch,
            &mut scratch.roots,
        )
    }

    /// Whether the ray through screen position (x, y) \[pixels\] hits a surface: the same
    /// condition as [`Tracer::hit`] being `Some` (a root with t > 0 and depth in [0, 1]),
    /// decided at the first such root found, which makes rays grazing an outline far
    /// cheaper to answer.
    pub fn covers(&self, x: f64, y: f64, scratch: &mut TraceScratch) -> bool {
        let view = self.view;
        let (origin, dir) = view.ray(x, y);
        let (tx, ty) = self.tile_at(x, y);
        let band = self.cached_band(self.span_at(tx, ty));
        for entry in band.bin(tx) {
            if !entry.footprint.contains(x, y) {
                continue;
            }
            let patch = &band.at(entry.k).patch;
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
}

/// Every lembo's reach in tiles of `tile` pixels, `tiles` = (columns, rows), in id order
/// chunk after chunk: the lembos made in parallel chunks, each chunk in order.
fn reaches(
    source: &dyn LemboSource,
    view: &View,
    tile: u32,
    (tiles_x, tiles_y): (u32, u32),
) -> Vec<Vec<Reach>> {
    let n = source.len();
    (0..n.div_ceil(BINNING_CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut last = LastParent::default();
            (c * BINNING_CHUNK..((c + 1) * BINNING_CHUNK).min(n))
                .map(|id| {
                    let controls = bezier_controls(&source.points(id, &mut last));
                    match footprint_of(&controls, view) {
                        None => Reach::Nowhere,
                        Some(Footprint::Everywhere) => Reach::Everywhere,
                        Some(Footprint::Box { x0, y0, x1, y1, .. }) => {
                            let at = |x: f64, n: u32| {
                                ((x / tile as f64).floor().max(0.0) as u32).min(n - 1)
                            };
                            Reach::Tiles([
                                at(x0, tiles_x),
                                at(y0, tiles_y),
                                at(x1, tiles_x),
                                at(y1, tiles_y),
                            ])
                        }
                    }
                })
                .collect()
        })
        .collect()
}

/// Splits every row of tiles into spans of consecutive tiles listing at most
/// [`SPAN_LEMBOS`] lembos together (a tile listing more is a span alone); `starts` are the
/// tiles' offsets into the lists. Returns the spans and where each row's start.
fn split_rows(starts: &[usize], tiles_x: u32, tiles_y: u32) -> (Vec<Span>, Vec<usize>) {
    let mut spans = Vec::new();
    let mut row_spans = Vec::with_capacity(tiles_y as usize + 1);
    for row in 0..tiles_y {
        row_spans.push(spans.len());
        let listed = |tx: u32| {
            let t = (row * tiles_x + tx) as usize;
            starts[t + 1] - starts[t]
        };
        let mut first = 0;
        let mut held = 0;
        for tx in 0..tiles_x {
            if tx > first && held + listed(tx) > SPAN_LEMBOS {
                spans.push(Span {
                    row,
                    tiles: first..tx,
                });
                (first, held) = (tx, 0);
            }
            held += listed(tx);
        }
        spans.push(Span {
            row,
            tiles: first..tiles_x,
        });
    }
    row_spans.push(spans.len());
    (spans, row_spans)
}

impl Band<'_> {
    /// The lembo at position `k` of the band.
    fn at(&self, k: u32) -> &Prepared<'_> {
        &self.lembos[k as usize / BAND_CHUNK][k as usize % BAND_CHUNK]
    }

    /// The positions of the lembos of the tile in column `tx` (one of the span's), nearest
    /// first.
    fn bin(&self, tx: u32) -> &[BinEntry] {
        &self.bins[(tx - self.first_tile) as usize]
    }

    /// The lembo of id `id`, with its colour; None when the band does not hold it.
    pub(super) fn lembo(&self, id: u32) -> Option<(&Lembo, [f64; 3])> {
        let k = self.ids.binary_search(&id).ok()?;
        let lembo = self.at(k as u32);
        Some((&lembo.patch.lembo, lembo.colour))
    }

    /// The nearest hit at screen position (x, y) \[pixels\] among the lembos of the band's
    /// tile column `tx`.
    pub(super) fn trace(
        &self,
        view: &View,
        x: f64,
        y: f64,
        tx: u32,
        scratch: &mut Scratch,
        roots: &mut Vec<Root>,
    ) -> Option<ReferenceHit> {
        let seen = self.bin(tx).iter().filter(|e| e.footprint.contains(x, y));
        self.nearest(view, (x, y), seen, scratch, roots)
    }

    /// The lembos of the band's tile column `tx` whose footprint holds the screen row y, in
    /// the tile's order, into `row` (what [`Band::trace_in_row`] scans for every sample of
    /// that row and column).
    pub(super) fn row_bin(&self, tx: u32, y: f64, row: &mut Vec<BinEntry>) {
        row.clear();
        row.extend(self.bin(tx).iter().filter(|e| e.footprint.holds_y(y)));
    }

    /// [`Band::trace`] at (x, y), `row` being [`Band::row_bin`] of its tile column at y:
    /// the same lembos in the same order, so the same hit, with the rows' test made once a
    /// row instead of once a sample.
    pub(super) fn trace_in_row(
        &self,
        view: &View,
        (x, y): (f64, f64),
        row: &[BinEntry],
        scratch: &mut Scratch,
        roots: &mut Vec<Root>,
    ) -> Option<ReferenceHit> {
        let seen = row.iter().filter(|e| e.footprint.holds_x(x));
        self.nearest(view, (x, y), seen, scratch, roots)
    }

    /// The nearest hit at (x, y) among the lembos `seen`, in their order.
    fn nearest<'e>(
        &self,
        view: &View,
        (x, y): (f64, f64),
        seen: impl Iterator<Item = &'e BinEntry>,
        scratch: &mut Scratch,
        roots: &mut Vec<Root>,
    ) -> Option<ReferenceHit> {
        let (origin, dir) = view.ray(x, y);
        let mut best: Option<ReferenceHit> = None;
        let mut best_t = f64::INFINITY;
        for entry in seen {
            let k = entry.k;
            let id = self.ids[k as usize];
            let patch = &self.at(k).patch;
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
