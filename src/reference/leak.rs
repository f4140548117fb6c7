//! Leaks: pixels where the render shows less than the exact lembo surface does.
//!
//! Where [`super::see_through`] holds the render against the input mesh's flat triangles,
//! this holds it against the exact reference's own visibility, so it tells a renderer leak
//! from the curved surface's own departure from the flat mesh (which the reference shows
//! too). At a pixel where the reference's hit H faces the eye (its lembo's geometric
//! normal, on the side of its normal function, at the hit, against the ray), the render
//! is a *candidate* when it shows there:
//! - **the background**;
//! - **a back face** farther than H: its stored normal and its drawn surface both turned
//!   from the eye ([`Drawn`]);
//! - **a farther surface of another part**: a winner whose lembo is not H's and shares no
//!   corner with it, at a greater depth than H.
//!
//! A candidate *leaks* when the exact surface around it is unbroken: within a margin of
//! the pixel the reference shows no background, no back face, not the winner's lembo, and
//! no lembo that is not joined to H's through corner-sharing lembos seen there. It looks
//! at the pixel centres first, then on a grid of 1/8 px through the reference's [`Tracer`],
//! so a slit in the exact surface narrower than a pixel is seen. Anything of the kind
//! nearby means an outline (a silhouette, an occluding edge, a contour, two surfaces
//! crossing) that the render drew slightly displaced, not a gap. The margin is
//! [`OUTLINE_MARGIN_PX`] plus how far the render may stray from the exact surface: on the
//! lembo path twice the measured largest scanline deviation (the walk's y error, standing
//! for the subsegments' x error, both bounded by the same tolerance k), on the triangle
//! path the lembo's deviation from its flat triangle over n² (a quadratic's error from its
//! chords shrinks with the square of the level), of H's lembo and of a farther winner's.
//!
//! A leak is so a gap between primitives in an unbroken surface (a crack that shows the
//! background, the inside of the mesh, or a part behind it). Where lembos are smaller than
//! the margin, a lembo joining two seen ones can fall between the grid's points; the
//! surface then reads as broken and a gap there is not counted: the count errs towards 0,
//! never towards a false leak.

use super::oracle::{LemboSource, ReferenceHit, ReferenceImage, TraceScratch, Tracer};
use super::see_through::OUTLINE_MARGIN_PX;
use super::surface::{faces_at, screen_deviation, share_a_corner, Drawn, Made, Shown};
use crate::camera::View;
use crate::lembo::set::LastParent;
use crate::lembo::Lembo;
use crate::raster::probe::PairHasher;
use crate::rop::framebuffer::FrameBuffer;
use glam::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::BuildHasherDefault;

/// How far a render's outlines may stray from the exact surface's, beyond
/// [`OUTLINE_MARGIN_PX`] (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Approximation {
    /// The lembo path: the largest scanline deviation the renderer measured \[pixels\].
    Lembos {
        /// `ProbeReport::max_scanline_deviation_px`, in pixels.
        deviation_px: f64,
    },
    /// The triangle path at tessellation level n.
    Triangles {
        /// The level n.
        level: u32,
    },
}

/// Leaking pixels by what the render shows there (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Leaks {
    /// The background.
    pub background: u64,
    /// A back face.
    pub back_face: u64,
    /// A farther surface of another part of the scene.
    pub farther: u64,
}

impl Leaks {
    /// Leaking pixels in all.
    pub fn total(&self) -> u64 {
        self.background + self.back_face + self.farther
    }
}

/// What a leaking pixel shows.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Background,
    BackFace,
    Farther,
}

/// The leaking pixels of `render` against `reference`, both of the tracer's view (see the
/// module documentation); `tracer` answers the reference between pixel centres, `lembos` are the
/// scene's lembos by id, `drawn` names the render's winners, `approximation` says how far
/// its outlines may stray.
///
/// # Panics
/// If the render kept no normal buffer, or it or the reference differs in size from the
/// viewport: bugs of the caller.
pub fn leaks(
    lembos: &dyn LemboSource,
    tracer: &Tracer,
    render: &FrameBuffer,
    reference: &ReferenceImage,
    drawn: Drawn,
    approximation: Approximation,
) -> Leaks {
    let view = tracer.view();
    let (w, h) = (view.viewport.width, view.viewport.height);
    assert_eq!(
        (render.width, render.height),
        (w, h),
        "render and view differ in size"
    );
    assert_eq!(
        (reference.width, reference.height),
        (w, h),
        "reference and view differ in size"
    );
    let normals = render
        .normal
        .as_ref()
        .expect("leaks need the render's normal buffer (keep_normals)");
    let check = Check {
        lembos,
        view,
        tracer,
        reference,
        approximation,
    };
    let w = w as usize;
    // Each task keeps the sub-pixel grid points it traced for the rows it takes next.
    let rows: Vec<Leaks> = (0..h as usize)
        .into_par_iter()
        .map_init(GridCache::default, |grid, j| {
            let mut made = [Made::new(lembos), Made::new(lembos), Made::new(lembos)];
            let mut scratch = TraceScratch::default();
            let mut out = Leaks::default();
            for k in j * w..(j + 1) * w {
                let shown = Shown::of_render(render, normals, k);
                let mut search = Search {
                    made: &mut made,
                    scratch: &mut scratch,
                    grid,
                };
                match check.leak(k, &shown, drawn, &mut search) {
                    Some(Kind::Background) => out.background += 1,
                    Some(Kind::BackFace) => out.back_face += 1,
                    Some(Kind::Farther) => out.farther += 1,
                    None => {}
                }
            }
            out
        })
        .collect();
    rows.into_iter().fold(Leaks::default(), |a, b| Leaks {
        background: a.background + b.background,
        back_face: a.back_face + b.back_face,
        farther: a.farther + b.farther,
    })
}

/// Points a pixel side of the grid the reference is searched on between pixel centres.
const SUBPIXEL_STEPS: u32 = 8;

/// What the reference shows at a point of the sub-pixel grid, as the search around a pixel
/// asks it: the lembo hit and whether its surface faces the point's ray; None where no
/// lembo is hit.
type GridSample = Option<(u32, bool)>;

/// Grid points [`SUBPIXEL_STEPS`] a pixel side a task has traced, by their grid
/// coordinates (`SUBPIXEL_STEPS` times a pixel's column and row, plus the step): the
/// searches around neighbouring pixels meet the same points, at the same screen positions
/// bit for bit, so each is traced once while it is kept. At most [`GRID_CACHE_POINTS`]
/// points in each of two generations, the older dropped when the newer fills.
#[derive(Default)]
struct GridCache {
    new: GridMap,
    old: GridMap,
}

/// Grid points' samples by grid coordinates, hashed by a multiply and a rotate a word.
type GridMap = HashMap<(i64, i64), GridSample, BuildHasherDefault<PairHasher>>;

/// Grid points a [`GridCache`] generation holds (24 bytes each, key and sample, plus the
/// table's own).
const GRID_CACHE_POINTS: usize = 1 << 17;

impl GridCache {
    /// The sample at grid point `key`, traced by `trace` unless kept.
    fn get(&mut self, key: (i64, i64), trace: impl FnOnce() -> GridSample) -> GridSample {
        if let Some(&sample) = self.new.get(&key).or_else(|| self.old.get(&key)) {
            return sample;
        }
        let sample = trace();
        if self.new.len() >= GRID_CACHE_POINTS {
            self.old = std::mem::take(&mut self.new);
        }
        self.new.insert(key, sample);
        sample
    }
}

/// What the search around a pixel works with: the lembos made (the reference's at the
/// pixel, the render's, and those the search meets), the tracer's buffers and the grid
/// points traced.
struct Search<'s, 'l> {
    made: &'s mut [Made<'l>; 3],
    scratch: &'s mut TraceScratch,
    grid: &'s mut GridCache,
}

/// The reference and what it takes to judge a pixel against it.
struct Check<'a> {
    lembos: &'a dyn LemboSource,
    view: &'a View,
    tracer: &'a Tracer<'a>,
    reference: &'a ReferenceImage,
    approximation: Approximation,
}

impl Check<'_> {
    /// Whether pixel `k`, showing `shown`, leaks, and how.
    fn leak(&self, k: usize, shown: &Shown, drawn: Drawn, search: &mut Search) -> Option<Kind> {
        let [at, winners, around] = &mut *search.made;
        let hit = self.reference.hits[k].as_ref()?;
        // Cheap tests first, before the pixel's ray: most pixels show H's own lembo, or
        // something in front of H.
        if !shown.is_background() && shown.depth <= hit.depth {
            return None;
        }
        let (origin, dir) = self.ray_at(self.centre(k));
        let candidate = shown.is_background()
            || shown.normal.dot(-dir) < 0.0
            || drawn.lembo_of(shown.winner) != u64::from(hit.lembo);
        if !candidate {
            return None;
        }
        let h = at.get(u64::from(hit.lembo))?;
        if !faces_at(h, hit.u, hit.v, dir) {
            return None;
        }
        let mut margin = OUTLINE_MARGIN_PX + self.strays(h);
        let kind = if shown.is_background() {
            Kind::Background
        } else if drawn.back_face(shown, origin, dir, winners) {
            Kind::BackFace
        } else {
            let lembo = drawn.lembo_of(shown.winner);
            if lembo == u64::from(hit.lembo) {
                return None;
            }
            let shown_lembo = winners.get(lembo)?;
            if share_a_corner(shown_lembo, h) {
                return None;
            }
            margin = margin.max(OUTLINE_MARGIN_PX + self.strays(shown_lembo));
            Kind::Farther
        };
        // A farther surface the reference itself shows nearby is one whose crossing with
        // H's the render drew slightly displaced, not one seen through a gap.
        let shown_lembo = (kind == Kind::Farther).then(|| drawn.lembo_of(shown.winner));
        let (i, j) = (k % self.width(), k / self.width());
        let (scratch, grid) = (&mut *search.scratch, &mut *search.grid);
        let unbroken =
            |steps: u32, scratch: &mut TraceScratch, around: &mut Made, grid: &mut GridCache| {
                let mut seen = vec![hit.lembo];
                for (p, key) in self.disc(i, j, margin, steps) {
                    let mut sample = |hit: Option<ReferenceHit>| {
                        hit.map(|hit| {
                            let faces = around
                                .get(u64::from(hit.lembo))
                                .is_some_and(|l| faces_at(l, hit.u, hit.v, self.ray_at(p).1));
                            (hit.lembo, faces)
                        })
                    };
                    let at_p = if steps == 1 {
                        let q = p[1] as usize * self.width() + p[0] as usize;
                        sample(self.reference.hits[q])
                    } else {
                        grid.get(key, || sample(self.tracer.hit(p[0], p[1], scratch)))
                    };
                    let Some((lembo, faces)) = at_p else {
                        return false;
                    };
                    if shown_lembo == Some(u64::from(lembo)) || !faces {
                        return false;
                    }
                    if !seen.contains(&lembo) {
                        seen.push(lembo);
                    }
                }
                self.connected(&seen)
            };
        let leaks =
            unbroken(1, scratch, around, grid) && unbroken(SUBPIXEL_STEPS, scratch, around, grid);
        leaks.then_some(kind)
    }

    /// Whether every lembo of `ids` is joined to the first through lembos of `ids` that
    /// share a corner (bit for bit).
    fn connected(&self, ids: &[u32]) -> bool {
        let mut last = LastParent::default();
        let corners: Vec<_> = ids
            .iter()
            .map(|&id| self.lembos.lembo(id as usize, &mut last).0)
            .collect();
        let mut joined = vec![false; ids.len()];
        let mut stack = vec![0];
        joined[0] = true;
        while let Some(a) = stack.pop() {
            for b in 0..ids.len() {
                if !joined[b] && share_a_corner(&corners[a], &corners[b]) {
                    joined[b] = true;
                    stack.push(b);
                }
            }
        }
        joined.into_iter().all(|j| j)
    }

    fn width(&self) -> usize {
        self.view.viewport.width as usize
    }

    /// Pixel `k`'s centre \[pixels\].
    fn centre(&self, k: usize) -> [f64; 2] {
        let w = self.width();
        [(k % w) as f64 + 0.5, (k / w) as f64 + 0.5]
    }

    /// The ray through screen position `at` \[pixels\].
    fn ray_at(&self, at: [f64; 2]) -> (DVec3, DVec3) {
        self.view.ray(at[0], at[1])
    }

    /// The points of a grid of `steps` a pixel side, through the pixel centres, within
    /// `margin` of pixel (i, j)'s centre and on the viewport \[pixels\], each with its grid
    /// coordinates (`steps` times the pixel's column and row, plus the step).
    fn disc(
        &self,
        i: usize,
        j: usize,
        margin: f64,
        steps: u32,
    ) -> impl Iterator<Item = ([f64; 2], (i64, i64))> {
        let s = f64::from(steps);
        let r = (margin * s).floor() as i64;
        let (w, h) = (
            f64::from(self.view.viewport.width),
            f64::from(self.view.viewport.height),
        );
        let (cx, cy) = (i as f64 + 0.5, j as f64 + 0.5);
        (-r..=r)
            .flat_map(move |y| (-r..=r).map(move |x| (x, y)))
            .filter(move |&(x, y)| ((x * x + y * y) as f64) <= (margin * s).powi(2))
            .map(move |(x, y)| {
                let key = (
                    i as i64 * i64::from(steps) + x,
                    j as i64 * i64::from(steps) + y,
                );
                ([cx + x as f64 / s, cy + y as f64 / s], key)
            })
            .filter(move |(p, _)| p[0] > 0.0 && p[1] > 0.0 && p[0] < w && p[1] < h)
    }

    /// How far the render may stray from `lembo`'s exact outline \[pixels\].
    fn strays(&self, lembo: &Lembo) -> f64 {
        match self.approximation {
            Approximation::Lembos { deviation_px } => 2.0 * deviation_px,
            Approximation::Triangles { level } => {
                screen_deviation(lembo, self.view) / f64::from(level.max(1)).powi(2)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::surface::fixtures::{flat, square, view};
    use super::*;
    use crate::rop::framebuffer::NO_PRIMITIVE;

    /// The reference of `lembos` at the pixel centres, as `render_reference` traces it.
    fn reference(tracer: &Tracer) -> ReferenceImage {
        let mut scratch = TraceScratch::default();
        let hits = (0..128 * 128)
            .map(|k| tracer.hit((k % 128) as f64 + 0.5, (k / 128) as f64 + 0.5, &mut scratch))
            .collect();
        ReferenceImage {
            width: 128,
            height: 128,
            supersample: 1,
            hits,
            hits_offset_px: [0.0; 2],
            bins: None,
            color: vec![[0; 3]; 128 * 128],
            color_supersampled: None,
            coverage: None,
        }
    }

    /// A render that shows what `reference` shows, its normals facing the eye.
    fn render_of(reference: &ReferenceImage) -> FrameBuffer {
        let mut fb = FrameBuffer::new(128, 128, [0; 3], true);
        for (k, hit) in reference.hits.iter().enumerate() {
            if let Some(h) = hit {
                fb.write(k, h.depth as f32, h.lembo, [200; 3]);
                fb.normal.as_mut().unwrap()[k] = [0.0, 0.0, 1.0];
            }
        }
        fb
    }

    #[test]
    fn leaks_are_gaps_in_an_unbroken_surface_not_displaced_outlines() {
        let view = view();
        // A square of two triangles (ids 0 and 1) on screen [24, 104]² facing the eye, a
        // surface of another part behind it (2), and the inside of a surface behind it (3:
        // normals turned from the eye).
        let [a, b] = square();
        let lembos = [
            a,
            b,
            flat([[-30.0, 0.0], [-10.0, 0.0], [-30.0, 20.0]], -5.0, DVec3::Z),
            flat([[10.0, 0.0], [30.0, 0.0], [10.0, 20.0]], -5.0, -DVec3::Z),
        ];
        let source: Vec<(&Lembo, bool)> = lembos.iter().map(|l| (l, true)).collect();
        let tracer = Tracer::new(&source, &view, 16);
        let reference = reference(&tracer);
        let depth = view.depth_of(DVec3::ZERO) as f32;
        let behind = view.depth_of(DVec3::new(0.0, 0.0, -5.0)) as f32;
        // The render: the square, as the reference shows it.
        let mut fb = FrameBuffer::new(128, 128, [0; 3], true);
        for j in 24..104 {
            for i in 24..104 {
                let k = fb.index(i, j);
                fb.write(k, depth, u32::from(i + j < 128), [200; 3]);
                fb.normal.as_mut().unwrap()[k] = [0.0, 0.0, 1.0];
            }
        }
        let leaks_of = |fb: &FrameBuffer, drawn: Drawn| {
            leaks(
                &source,
                &tracer,
                fb,
                &reference,
                drawn,
                Approximation::Lembos { deviation_px: 0.1 },
            )
        };
        assert_eq!(leaks_of(&fb, Drawn::EXACT), Leaks::default());
        let mut set = |i: u32, j: u32, id: u32, z: f32, n: [f32; 3]| {
            let k = fb.index(i, j);
            fb.depth[k] = z;
            fb.primitive[k] = id;
            fb.normal.as_mut().unwrap()[k] = n;
        };
        let (up, down) = ([0.0, 0.0, 1.0], [0.0, 0.0, -1.0]);
        // Leaks: a crack, the inside of 3, part 2 seen through the square.
        set(60, 60, NO_PRIMITIVE, 1.0, up);
        set(84, 60, 3, behind, down);
        set(44, 60, 2, behind, up);
        // Not leaks: a shading normal turned away on the square itself; the neighbour
        // triangle a little behind (a patch's sag); 2 in front of the square (it hides);
        // the background within 2 px of the square's outline.
        set(70, 80, 0, depth, down);
        set(80, 70, 1, depth + 0.01, up);
        set(40, 40, 2, depth - 0.01, up);
        set(25, 60, NO_PRIMITIVE, 1.0, up);
        let found = leaks_of(&fb, Drawn::EXACT);
        assert_eq!(
            found,
            Leaks {
                background: 1,
                back_face: 1,
                farther: 1,
            }
        );
        assert_eq!(found.total(), 3);
        // The same ids on the triangle path at n = 2 (four triangles a lembo).
        for id in fb.primitive.iter_mut().filter(|p| **p != NO_PRIMITIVE) {
            *id = *id * 4 + 1;
        }
        let two = Drawn {
            ids_per_lembo: 4,
            triangles: None,
        };
        let triangles = leaks(
            &source,
            &tracer,
            &fb,
            &reference,
            two,
            Approximation::Triangles { level: 2 },
        );
        assert_eq!(triangles, found);
    }

    /// A hole many pixels wide in the render is a leak at each of its pixels: the searches
    /// around neighbouring pixels share their grid points (traced once a task), and a grid
    /// point is at the same screen position, bit for bit, whichever pixel's search meets it.
    #[test]
    fn every_pixel_of_a_wide_hole_leaks_and_neighbours_meet_the_same_grid_points() {
        let view = view();
        let lembos = square();
        let source: Vec<(&Lembo, bool)> = lembos.iter().map(|l| (l, true)).collect();
        let tracer = Tracer::new(&source, &view, 16);
        let reference = reference(&tracer);
        let mut fb = render_of(&reference);
        for j in 50..62 {
            for i in 58..70 {
                let k = fb.index(i, j);
                fb.primitive[k] = NO_PRIMITIVE;
                fb.depth[k] = 1.0;
            }
        }
        let approximation = Approximation::Lembos { deviation_px: 0.5 };
        let found = leaks(
            &source,
            &tracer,
            &fb,
            &reference,
            Drawn::EXACT,
            approximation,
        );
        assert_eq!(found.background, 144, "{found:?}");
        assert_eq!(found.total(), 144);
        let check = Check {
            lembos: &source,
            view: &view,
            tracer: &tracer,
            reference: &reference,
            approximation,
        };
        let (mut at, mut met) = (HashMap::new(), 0);
        for (i, j) in [(60, 55), (61, 55), (60, 56), (67, 59)] {
            for (p, key) in check.disc(i, j, 3.0, SUBPIXEL_STEPS) {
                let bits = p.map(f64::to_bits);
                assert_eq!(*at.entry(key).or_insert(bits), bits, "{key:?}");
                met += 1;
            }
        }
        let positions: std::collections::HashSet<_> = at.values().collect();
        assert_eq!(positions.len(), at.len(), "one grid point, one position");
        // The four discs (about 1 800 points each, three of them neighbours) share most of
        // their points.
        assert!(
            met > 4 * 1700 && at.len() < met * 2 / 3,
            "{} of {met}",
            at.len()
        );
    }

    /// Where the reference shows another part within the margin, the render's outline may
    /// be displaced onto it: not a leak; beyond the margin it is one.
    #[test]
    fn the_margin_grows_with_how_far_the_render_strays() {
        let view = view();
        // Two squares side by side, apart (no shared corner), the right one behind.
        let lembos = [
            flat([[-40.0, -40.0], [0.0, -40.0], [0.0, 0.0]], 0.0, DVec3::Z),
            flat([[0.5, -40.0], [40.0, -40.0], [0.5, 0.0]], -5.0, DVec3::Z),
        ];
        let source: Vec<(&Lembo, bool)> = lembos.iter().map(|l| (l, true)).collect();
        let tracer = Tracer::new(&source, &view, 16);
        let reference = reference(&tracer);
        let mut fb = render_of(&reference);
        // The left triangle's right edge, x = 64 on screen, drawn 3 px to the left: the
        // right triangle shows at x = 61.5, 62.5, 63.5 on row 100.
        let behind = view.depth_of(DVec3::new(0.0, 0.0, -5.0)) as f32;
        for i in 61..64 {
            let k = fb.index(i, 100);
            fb.depth[k] = behind;
            fb.primitive[k] = 1;
        }
        let at = |deviation_px: f64| {
            leaks(
                &source,
                &tracer,
                &fb,
                &reference,
                Drawn::EXACT,
                Approximation::Lembos { deviation_px },
            )
            .farther
        };
        // 2 px: the pixel 2.5 px from the edge leaks; 2 + 2 x 0.5 px: none does.
        assert_eq!(at(0.0), 1);
        assert_eq!(at(0.5), 0);
    }
}
