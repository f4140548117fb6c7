//! The exact reference renderer (DESIGN.md §6): per sample, the ray against the true
//! world-space lembo, in `f64`, with no projection approximation.
//!
//! A ray is the intersection of two planes through it, with unit normals `n1` and `n2`
//! perpendicular to its direction `d` and to each other. On a lembo `b(u, v)` the planes
//! give two conics in the domain,
//!
//! ```text
//!   Q1(u, v) = n1 · (b(u, v) - O) = 0        Q2(u, v) = n2 · (b(u, v) - O) = 0
//! ```
//!
//! whose common roots in `u >= 0, v >= 0, u + v <= 1` are the hits, at ray parameter
//! `t = d · (b(u, v) - O)`. The roots are isolated by recursive subdivision of the domain
//! triangle: the map `(u, v) -> (Q1, Q2, t)` restricted to a sub-triangle is again a
//! quadratic triangle, whose Bézier control net (from its values at the corners and edge
//! midpoints) bounds it. A sub-triangle whose net's box excludes the origin of the (Q1, Q2)
//! plane, or lies outside the wanted range of `t`, holds no root. Otherwise 2D Newton runs
//! from the sub-triangle's centroid. When it converges to a root `r` (inside the
//! sub-triangle or not), the sub-triangle holds no other root if the Jacobian J of
//! (Q1, Q2) is regular on the triangle halfway between it and `r`, because for a quadratic
//! map `F(x) - F(r) = J((x + r) / 2) (x - r)` exactly; the determinant is a quadratic whose
//! Bernstein coefficients show a strict sign. Elsewhere (near the silhouette, where the ray
//! grazes the surface and two roots merge) subdivision continues down to a uv size of
//! 2^-20, where Newton runs from the centroid of every surviving sub-triangle.
//!
//! Roots within [`DOMAIN_TOLERANCE`] of the domain are kept and clamped onto it, so a ray
//! through a shared edge hits both neighbours; roots closer than [`SAME_ROOT_UV`] in uv
//! are one root.
//!
//! The image: per lembo, the Bézier control net is projected; a lembo whose net has a
//! point at or behind the eye (`w <= 0`) is tested at every sample, otherwise only at the
//! samples inside the net's screen box, found through square screen tiles (16 x 16 pixels
//! by default) whose lists are sorted nearest first, so that an early hit bounds the range
//! of `t` searched in the rest. The nearest hit with `t > 0` and depth in [0, 1] wins, ties
//! going to the smaller lembo index as in the rasterizer's depth test, and is shaded with
//! the exact unit normal of the normal function.
//!
//! Nothing holds every lembo (`tracer.rs`): binning keeps only ids, and each row of tiles
//! makes its own lembos again while it is traced. Rows of tiles and their pixel rows are
//! rendered in parallel; every sample is computed by the same sequential code over the
//! same lembos in the same order, so the image does not depend on the thread count or the
//! tile size.
//!
//! The same machinery answers at any screen position ([`Tracer`]), which the accuracy
//! metrics use between pixel centres. [`Tracer::covers`] asks only whether a ray hits: it
//! stops at the first root Newton finds inside a sub-triangle (no uniqueness proof), and
//! also prunes sub-triangles whose Bézier net's convex hull in the (Q1, Q2) plane excludes
//! the origin, which the box test cannot do for rays grazing the surface until the
//! sub-triangles are tiny. The image keeps the box test alone.

use crate::camera::View;
use crate::lembo::Lembo;
use crate::rop::shade::{to_u8, Shader};
use crate::scene::Light;
use glam::DVec3;
use rayon::prelude::*;
use roots::{Patch, Scratch};

mod roots;
mod source;
mod tracer;

pub use roots::{DOMAIN_TOLERANCE, SAME_ROOT_UV};
pub use source::{LemboSource, SceneLembos};
use tracer::Band;
pub use tracer::{Bins, ReferenceHit, TraceScratch, Tracer, DEFAULT_TILE, TILE_RANGE};

/// The reference image, row 0 at the top. Two are equal when their pixels are (the tiles
/// their hits were traced in are how they were made, not what they are).
#[derive(Clone, Debug)]
pub struct ReferenceImage {
    /// Width \[pixels\].
    pub width: u32,
    /// Height \[pixels\].
    pub height: u32,
    /// Sub-samples per pixel side `s` (1 = the pixel centre only).
    pub supersample: u32,
    /// The hit at each pixel's point (i + 0.5, j + 0.5) + [`Self::hits_offset_px`].
    pub hits: Vec<Option<ReferenceHit>>,
    /// Where `hits` were traced from the pixel centres \[pixels\]: (0, 0), or for a
    /// multisampled run's reference ([`Self::for_samples`]) the offset of the sample a
    /// resolved frame keeps its depth, winner and normal from.
    pub hits_offset_px: [f64; 2],
    /// The tiles `hits` were traced in (None for an image made otherwise, as in tests): the
    /// accuracy metrics' queries between pixel centres use them ([`Tracer::with_bins`]).
    pub bins: Option<std::sync::Arc<Bins>>,
    /// The colour a render is compared with: the pixel centre shaded (the background where
    /// nothing is hit), or for a multisampled run's reference the area-averaged colour.
    pub color: Vec<[u8; 3]>,
    /// The mean of the s x s sub-samples' linear colours (a box filter), when s > 1.
    pub color_supersampled: Option<Vec<[u8; 3]>>,
    /// The fraction of the s x s sub-samples that hit a surface, when s > 1.
    pub coverage: Option<Vec<f32>>,
}

impl PartialEq for ReferenceImage {
    fn eq(&self, other: &Self) -> bool {
        (self.width, self.height, self.supersample)
            == (other.width, other.height, other.supersample)
            && self.hits == other.hits
            && self.hits_offset_px == other.hits_offset_px
            && self.color == other.color
            && self.color_supersampled == other.color_supersampled
            && self.coverage == other.coverage
    }
}

impl ReferenceImage {
    /// The centre-sample colour buffer as an `image` RGB8 image.
    pub fn to_image(&self) -> image::RgbImage {
        rgb_image(self.width, self.height, &self.color)
    }

    /// This supersampled reference made the reference of a multisampled render: its hits
    /// those of `at_sample`, the same scene traced from the pixel centres moved by `offset`
    /// \[pixels\] (where the resolved frame keeps its depth, winner and normal), and its
    /// colours the area-averaged ones, which a resolve approximates (DESIGN.md §6).
    ///
    /// # Panics
    /// If this reference is not supersampled, or the two differ in size: bugs of the caller.
    pub fn for_samples(mut self, at_sample: ReferenceImage, offset: [f64; 2]) -> ReferenceImage {
        assert_eq!(
            (self.width, self.height),
            (at_sample.width, at_sample.height)
        );
        self.color = self
            .color_supersampled
            .clone()
            .expect("a multisampled run's reference is supersampled");
        self.hits = at_sample.hits;
        self.hits_offset_px = offset;
        self.bins = at_sample.bins;
        self
    }

    /// This supersampled reference with the area-averaged colours as the colours a render is
    /// compared with, its hits staying at the pixel centres: the target of a one-sample
    /// render measured beside multisampled ones (a sweep with `samples` on an axis).
    ///
    /// # Panics
    /// If this reference is not supersampled: a bug of the caller.
    pub fn with_area_colours(mut self) -> ReferenceImage {
        self.color = self
            .color_supersampled
            .clone()
            .expect("an area-averaged target is supersampled");
        self
    }

    /// The box-filtered colour buffer, when supersampled.
    pub fn to_image_supersampled(&self) -> Option<image::RgbImage> {
        self.color_supersampled
            .as_ref()
            .map(|c| rgb_image(self.width, self.height, c))
    }
}

fn rgb_image(width: u32, height: u32, color: &[[u8; 3]]) -> image::RgbImage {
    let raw: Vec<u8> = color.iter().flatten().copied().collect();
    image::RgbImage::from_raw(width, height, raw).expect("buffer matches its size")
}

/// What the reference renders.
#[derive(Clone, Copy)]
pub struct ReferenceInput<'a> {
    /// The lembos, made by id (the id is the lembo's), with their linear RGB colours in
    /// [0, 1].
    pub lembos: &'a dyn LemboSource,
    /// The camera and viewport.
    pub view: &'a View,
    /// The light and material terms.
    pub light: &'a Light,
    /// Linear RGB in [0, 1] where nothing is hit.
    pub background: [f64; 3],
    /// Sub-samples per pixel side (1 = the pixel centre only; 0 is taken as 1).
    pub supersample: u32,
    /// Side of the square screen tiles the lembos are binned into \[pixels\], in
    /// [`TILE_RANGE`] ([`DEFAULT_TILE`]): memory and time, never the image.
    pub tile: u32,
}

/// All intersections of the line `origin + t dir` with the lembo inside its domain, as
/// `(t, u, v)` sorted by `t`, including any behind the origin (`t < 0`); callers that want
/// a ray filter on `t`. `t` is in units of `dir`, so `origin + t dir` is the hit point
/// (up to the solver's tolerance) whatever the length of `dir`; a zero or non-finite `dir`
/// gives no hits.
pub fn intersect_ray(lembo: &Lembo, origin: DVec3, dir: DVec3) -> Vec<(f64, f64, f64)> {
    let len = dir.length();
    if !(len > 0.0 && len.is_finite()) {
        return Vec::new();
    }
    let patch = Patch::new(std::borrow::Cow::Borrowed(lembo));
    let mut scratch = Scratch::default();
    let mut roots = Vec::new();
    patch.roots(
        origin,
        dir / len,
        f64::NEG_INFINITY,
        f64::INFINITY,
        &mut scratch,
        &mut roots,
    );
    let mut hits: Vec<(f64, f64, f64)> = roots.iter().map(|r| (r.t / len, r.u, r.v)).collect();
    hits.sort_by(|a, b| {
        a.0.total_cmp(&b.0)
            .then(a.1.total_cmp(&b.1))
            .then(a.2.total_cmp(&b.2))
    });
    hits
}

/// Renders the reference image: the centre sample of every pixel and, when
/// `supersample > 1`, an s x s grid of sub-samples at ((a + 0.5) / s, (b + 0.5) / s) within
/// the pixel. The spans of tiles are traced in parallel, each with only its own lembos
/// made (`tracer.rs`), their pixel rows in parallel too.
pub fn render_reference(input: &ReferenceInput) -> ReferenceImage {
    let (width, height) = (input.view.viewport.width, input.view.viewport.height);
    let s = input.supersample.max(1);
    let scene = Scene::new(input);
    let tile = scene.tracer.tile();
    let spans = scene.tracer.spans();
    // Spans in parallel, each span's pixel rows too: a thread waiting for its rows takes
    // another span, so about two spans a thread are held made at once.
    let pieces: Vec<Vec<Row>> = (0..spans.len())
        .into_par_iter()
        .map(|k| {
            let band = scene.tracer.band(k);
            let span = &spans[k];
            let columns = span.tiles.start * tile..(span.tiles.end * tile).min(width);
            (span.row * tile..((span.row + 1) * tile).min(height))
                .into_par_iter()
                .map(|j| scene.render_row(&band, j, columns.clone(), s))
                .collect::<Vec<Row>>()
        })
        .collect();
    let n = width as usize * height as usize;
    let mut image = Row {
        hits: Vec::with_capacity(n),
        color: Vec::with_capacity(n),
        color_supersampled: (s > 1).then(|| Vec::with_capacity(n)),
        coverage: (s > 1).then(|| Vec::with_capacity(n)),
    };
    // Each pixel row from its spans' pieces, left to right, each piece freed once copied.
    let mut pieces = pieces.into_iter().map(Vec::into_iter).collect::<Vec<_>>();
    let mut row_spans = 0..0;
    for j in 0..height {
        if j % tile == 0 {
            let first = row_spans.end;
            let count = spans[first..]
                .iter()
                .take_while(|s| s.row == j / tile)
                .count();
            row_spans = first..first + count;
        }
        for k in row_spans.clone() {
            image.append(
                pieces[k]
                    .next()
                    .expect("a span traced each of its pixel rows"),
            );
        }
    }
    ReferenceImage {
        width,
        height,
        supersample: s,
        hits: image.hits,
        hits_offset_px: [0.0; 2],
        bins: Some(scene.tracer.bins()),
        color: image.color,
        color_supersampled: image.color_supersampled,
        coverage: image.coverage,
    }
}

/// The prepared scene: the tracer, the colours and the shader.
struct Scene<'a> {
    input: &'a ReferenceInput<'a>,
    tracer: Tracer<'a>,
    shader: Shader<f64>,
    background: [f64; 3],
}

/// One rendered row, or the part of it in a span's columns.
#[derive(Default)]
struct Row {
    hits: Vec<Option<ReferenceHit>>,
    color: Vec<[u8; 3]>,
    color_supersampled: Option<Vec<[u8; 3]>>,
    coverage: Option<Vec<f32>>,
}

impl Row {
    /// `part` added at the right.
    fn append(&mut self, part: Row) {
        self.hits.extend(part.hits);
        self.color.extend(part.color);
        if let Some(part) = part.color_supersampled {
            self.color_supersampled
                .get_or_insert_with(Vec::new)
                .extend(part);
        }
        if let Some(part) = part.coverage {
            self.coverage.get_or_insert_with(Vec::new).extend(part);
        }
    }
}

impl<'a> Scene<'a> {
    fn new(input: &'a ReferenceInput<'a>) -> Self {
        Scene {
            input,
            tracer: Tracer::new(input.lembos, input.view, input.tile),
            shader: Shader::new(input.light),
            background: input.background,
        }
    }

    /// Linear RGB of a sample, hit on a lembo of `band`.
    fn shade(&self, band: &Band, hit: &Option<ReferenceHit>) -> [f64; 3] {
        match hit {
            None => self.background,
            Some(h) => {
                let (lembo, color) = band.lembo(h.lembo).expect("a band's hits are its lembos'");
                let to_eye = self.input.view.to_eye(lembo.position_at(h.u, h.v));
                self.shader
                    .shade(h.normal.to_array(), to_eye.to_array(), color)
            }
        }
    }

    /// Pixel row `j` in `columns`, which lie in the span of `band`.
    fn render_row(&self, band: &Band, j: u32, columns: std::ops::Range<u32>, s: u32) -> Row {
        let width = columns.len() as u32;
        let view = self.input.view;
        let mut scratch = Scratch::default();
        let mut roots = Vec::new();
        let mut row = Row {
            hits: Vec::with_capacity(width as usize),
            color: Vec::with_capacity(width as usize),
            color_supersampled: (s > 1).then(|| Vec::with_capacity(width as usize)),
            coverage: (s > 1).then(|| Vec::with_capacity(width as usize)),
        };
        let quantise = |c: [f64; 3]| c.map(to_u8);
        let tile = self.tracer.tile();
        // The lembos of the current tile column whose footprint holds the centres' row.
        let (mut row_tx, mut row_bin) = (None, Vec::new());
        for i in columns {
            let tx = i / tile;
            let (x, y) = (i as f64, j as f64);
            // For odd s the middle sub-sample is the pixel centre, (k + 0.5) / (2k + 1) = 0.5
            // exactly, so it is traced once.
            let centre_in_grid = s > 1 && s % 2 == 1;
            let centre = if centre_in_grid {
                None
            } else {
                if row_tx != Some(tx) {
                    band.row_bin(tx, y + 0.5, &mut row_bin);
                    row_tx = Some(tx);
                }
                let at = (x + 0.5, y + 0.5);
                Some(band.trace_in_row(view, at, &row_bin, &mut scratch, &mut roots))
            };
            let mut centre_hit = centre.flatten();
            if s > 1 {
                let mut sum = [0.0; 3];
                let mut covered = 0u32;
                for b in 0..s {
                    for a in 0..s {
                        let sx = x + (a as f64 + 0.5) / s as f64;
                        let sy = y + (b as f64 + 0.5) / s as f64;
                        let hit = band.trace(view, sx, sy, tx, &mut scratch, &mut roots);
                        if centre_in_grid && a == s / 2 && b == s / 2 {
                            centre_hit = hit;
                        }
                        covered += hit.is_some() as u32;
                        let c = self.shade(band, &hit);
                        for k in 0..3 {
                            sum[k] += c[k];
                        }
                    }
                }
                let n = (s * s) as f64;
                row.color_supersampled
                    .as_mut()
                    .expect("s > 1")
                    .push(quantise(sum.map(|c| c / n)));
                row.coverage
                    .as_mut()
                    .expect("s > 1")
                    .push(covered as f32 / n as f32);
            }
            row.color.push(quantise(self.shade(band, &centre_hit)));
            row.hits.push(centre_hit);
        }
        row
    }
}

#[cfg(test)]
mod tests;
