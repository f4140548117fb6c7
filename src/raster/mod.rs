//! The functional extreme method (Martinelli 2006 section 5): what is drawn, with no notion of
//! time. One file per stage of Figure 5, in dataflow order:
//!
//! ```text
//! setup ─► minmax ─► interval ─► segmenter ─► subsegmenter ─► fragment ─► FragmentSink (ROP)
//! ```
//!
//! Every stage is generic over the datapath [`Real`] (`f32` or `f64`) and works on one item
//! at a time into reused buffers, so the timed pipeline can call the same functions per
//! message. [`render_lembos`] runs the stages in order for a whole scene.

pub mod counts;
pub mod fragment;
pub mod interval;
pub mod minmax;
pub mod parallel;
pub mod probe;
pub mod refine;
pub mod screen;
pub mod segmenter;
pub mod setup;
pub mod subsegmenter;
pub mod triangle;
pub mod v2;

use crate::camera::View;
use crate::datapath::{Datapath, Real};
use crate::error::{Error, Result};
use crate::graph::UnitKind;
use crate::lembo::Lembo;
use crate::rop::{FrameBuffer, Rop};
use crate::scene::Scene;
pub use counts::Counts;
use fragment::FragmentSink;
use triangle::TriangleSource;

/// Default cap on segments per interval (DESIGN.md §8): far above what a visible patch needs
/// at k >= 1e-4 px on a 16384-pixel viewport, low enough to refuse runaway walks quickly.
pub const DEFAULT_SEGMENT_CAP: usize = 1 << 16;

/// What Setup's perspective tolerance is by default, as a fraction of k: with the walk's
/// error at most k and Setup's at most k/2, k bounds the end-to-end error of a fragment's
/// position to within 1.5 k.
pub const DEFAULT_PERSPECTIVE_FRACTION: f64 = 0.5;

/// The lembo path's tolerances \[pixels\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// k: the midpoint error of every segment of the walk (Martinelli 2006, section 5).
    pub k: f64,
    /// How far Setup's rebuilt screen quadratics may be from the true perspective projection
    /// before it splits a lembo ([`refine`], `--perspective-tol`); `None` is the paper's
    /// Setup, which projects six points and neither splits for perspective nor clips.
    pub perspective: Option<f64>,
}

impl Tolerance {
    /// k with the default perspective tolerance, k · [`DEFAULT_PERSPECTIVE_FRACTION`].
    pub fn new(k: f64) -> Self {
        Tolerance {
            k,
            perspective: Some(k * DEFAULT_PERSPECTIVE_FRACTION),
        }
    }

    /// k with Setup as the paper has it (`--perspective-tol off`).
    pub fn paper(k: f64) -> Self {
        Tolerance {
            k,
            perspective: None,
        }
    }
}

/// Setup's perspective tolerance as a user sets it (`--perspective-tol PX|off`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum PerspectiveTol {
    /// k · [`DEFAULT_PERSPECTIVE_FRACTION`].
    #[default]
    FollowK,
    /// A fixed tolerance \[pixels\], finite and > 0.
    Px(f64),
    /// The paper's Setup: no perspective split, no near-plane handling.
    Off,
}

impl PerspectiveTol {
    /// The tolerances for k \[pixels\].
    pub fn with_k(self, k: f64) -> Tolerance {
        match self {
            PerspectiveTol::FollowK => Tolerance::new(k),
            PerspectiveTol::Px(px) => Tolerance {
                k,
                perspective: Some(px),
            },
            PerspectiveTol::Off => Tolerance::paper(k),
        }
    }

    /// Parses `off` or a number of pixels; the error says what is accepted.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        if text.trim() == "off" {
            return Ok(PerspectiveTol::Off);
        }
        match text.trim().parse::<f64>() {
            Ok(px) => PerspectiveTol::px(px),
            Err(_) => Err(format!(
                "must be `off` or a tolerance in pixels, a finite number > 0 (got `{text}`)"
            )),
        }
    }

    /// A fixed tolerance, refused unless finite and > 0.
    pub fn px(px: f64) -> std::result::Result<Self, String> {
        if px.is_finite() && px > 0.0 {
            Ok(PerspectiveTol::Px(px))
        } else {
            Err(format!(
                "must be `off` or a tolerance in pixels, a finite number > 0 (got {px})"
            ))
        }
    }
}

impl From<f64> for Tolerance {
    /// k with the default perspective tolerance ([`Tolerance::new`]).
    fn from(k: f64) -> Self {
        Tolerance::new(k)
    }
}

/// Runs the extreme method over every lembo of `scene`, in scene order, into `sink`.
pub fn render_lembos<R: Real, S: FragmentSink<R>>(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    segment_cap: usize,
    sink: &mut S,
    counts: &mut Counts,
) -> Result<()> {
    let tol = tol.into();
    let k = R::of(tol.k);
    let mut buffers = Buffers::default();
    let mut pieces = Vec::new();
    for (id, (lembo, color)) in scene.lembos().enumerate() {
        set_up(id as u32, lembo, color, view, tol, &mut pieces, counts);
        for l in &pieces {
            render_lembo(l, view, k, segment_cap, sink, counts, &mut buffers)?;
        }
    }
    Ok(())
}

/// Setup of lembo `id` into `pieces` (cleared first; none when it is culled), counted.
fn set_up<R: Real>(
    id: u32,
    lembo: &Lembo,
    color: [f64; 3],
    view: &View,
    tol: Tolerance,
    pieces: &mut Vec<setup::ScreenLembo<R>>,
    counts: &mut Counts,
) {
    counts.lembos += 1;
    pieces.clear();
    R::charge(UnitKind::Setup);
    match setup::setup_pieces::<R>(id, lembo, color, view, tol.perspective, pieces) {
        Ok(split) => counts.add_split(split, pieces.len()),
        Err(cull) => counts.add_cull(cull),
    }
}

/// Minmax of a set-up piece: its first and last scanline, or None (counted) when it
/// crosses none of the viewport's.
fn scanline_range<R: Real>(
    l: &setup::ScreenLembo<R>,
    height: u32,
    counts: &mut Counts,
) -> Option<(u32, u32)> {
    R::charge(UnitKind::MinMax);
    let range = minmax::scanlines(l, height);
    if range.is_none() {
        counts.lembos_culled_outside += 1;
    }
    range
}

/// The reused buffers of the scan-line stages.
struct Buffers<R> {
    scratch: interval::IntervalScratch<R>,
    intervals: Vec<interval::Interval<R>>,
    segments: Vec<segmenter::Segment<R>>,
    subsegments: Vec<subsegmenter::Subsegment<R>>,
}

impl<R: Real> Default for Buffers<R> {
    fn default() -> Self {
        Buffers {
            scratch: Default::default(),
            intervals: Vec::new(),
            segments: Vec::new(),
            subsegments: Vec::new(),
        }
    }
}

/// The scan-line stages (minmax to fragment) for one set-up lembo or piece.
fn render_lembo<R: Real, S: FragmentSink<R>>(
    l: &setup::ScreenLembo<R>,
    view: &View,
    k: R,
    segment_cap: usize,
    sink: &mut S,
    counts: &mut Counts,
    b: &mut Buffers<R>,
) -> Result<()> {
    let (width, height) = (view.viewport.width, view.viewport.height);
    let Some((j0, j1)) = scanline_range(l, height, counts) else {
        return Ok(());
    };
    scanlines(l, j0, j1, width, k, segment_cap, sink, counts, b).map_err(|(_, e)| e)
}

/// The scan-line stages after minmax for scanlines `j0..=j1` of one set-up lembo or piece;
/// an error comes with the scanline it was met on. On an x86-64 CPU with AVX2 the stages the
/// compiler inlines here (the segmenter's walk, the subsegmenter, the fragment rasterizer's
/// spans) are compiled for it (three-operand instructions, rounding inline): the same IEEE
/// operations in the same order, so the same bits. What stays a call runs as compiled for
/// the baseline: the interval manager (inlined here it ran slower), the segmenter's step
/// and closing chords, and the sink's span where it is not inlined.
#[allow(clippy::too_many_arguments)]
fn scanlines<R: Real, S: FragmentSink<R>>(
    l: &setup::ScreenLembo<R>,
    j0: u32,
    j1: u32,
    width: u32,
    k: R,
    segment_cap: usize,
    sink: &mut S,
    counts: &mut Counts,
    b: &mut Buffers<R>,
) -> std::result::Result<(), (u32, Error)> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        return unsafe { scanlines_avx2(l, j0, j1, width, k, segment_cap, sink, counts, b) };
    }
    scanlines_as_compiled(l, j0, j1, width, k, segment_cap, sink, counts, b)
}

/// [`scanlines`] compiled for AVX2.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn scanlines_avx2<R: Real, S: FragmentSink<R>>(
    l: &setup::ScreenLembo<R>,
    j0: u32,
    j1: u32,
    width: u32,
    k: R,
    segment_cap: usize,
    sink: &mut S,
    counts: &mut Counts,
    b: &mut Buffers<R>,
) -> std::result::Result<(), (u32, Error)> {
    scanlines_as_compiled(l, j0, j1, width, k, segment_cap, sink, counts, b)
}

/// [`scanlines`] for the instruction set its caller is compiled for.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn scanlines_as_compiled<R: Real, S: FragmentSink<R>>(
    l: &setup::ScreenLembo<R>,
    j0: u32,
    j1: u32,
    width: u32,
    k: R,
    segment_cap: usize,
    sink: &mut S,
    counts: &mut Counts,
    b: &mut Buffers<R>,
) -> std::result::Result<(), (u32, Error)> {
    // The piece's bound on a step's reach, for all its intervals (a counting datapath makes
    // every step, for its counts).
    let reach = if R::COUNTS_OPERATIONS {
        None
    } else {
        segmenter::least_reach(l, k)
    };
    for j in j0..=j1 {
        scanline(l, j, width, k, segment_cap, reach, sink, counts, b).map_err(|e| (j, e))?;
    }
    Ok(())
}

/// The scan-line stages after minmax (interval manager to fragment) for scanline `j` of one
/// set-up lembo or piece, whose steps reach at least `reach` ([`segmenter::walk`]).
/// Scanline j's fragments are all in row j.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn scanline<R: Real, S: FragmentSink<R>>(
    l: &setup::ScreenLembo<R>,
    j: u32,
    width: u32,
    k: R,
    segment_cap: usize,
    reach: Option<f64>,
    sink: &mut S,
    counts: &mut Counts,
    b: &mut Buffers<R>,
) -> Result<()> {
    counts.scanlines += 1;
    b.intervals.clear();
    R::charge(UnitKind::IntervalManager);
    interval::intervals(l, j, k, &mut b.scratch, &mut b.intervals, counts);
    for iv in &b.intervals {
        b.segments.clear();
        R::charge(UnitKind::Segmenter);
        segmenter::walk(l, j, k, iv, segment_cap, reach, &mut b.segments, counts).map_err(
            |_| Error::SegmentCap {
                lembo: l.id as usize,
                scanline: j,
                cap: segment_cap,
            },
        )?;
        for seg in &b.segments {
            b.subsegments.clear();
            R::charge(UnitKind::Subsegmenter);
            subsegmenter::subsegments(l, seg, k, &mut b.subsegments, counts);
            for sub in &b.subsegments {
                R::charge(UnitKind::FragmentRasterizer);
                fragment::rasterize(l, j, sub, width, sink, counts);
            }
        }
    }
    Ok(())
}

/// A rendered frame and what it took.
pub struct Frame {
    /// The image, depth and winners.
    pub framebuffer: FrameBuffer,
    /// What the stages produced.
    pub counts: Counts,
    /// Fragment-level measurements, when requested.
    pub probe: Option<probe::ProbeReport>,
}

/// Renders `scene` with the functional model in the given datapath. With `analyse`, the
/// frame buffer keeps normals and every fragment is measured by a [`probe::Probe`] (slower).
///
/// `tol` is k \[pixels\] (with the default perspective tolerance) or a [`Tolerance`].
pub fn render_functional(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
    analyse: bool,
) -> Result<Frame> {
    let tol = tol.into();
    match datapath {
        Datapath::F32 => render_in::<f32>(scene, view, tol, analyse),
        Datapath::F64 => render_in::<f64>(scene, view, tol, analyse),
    }
}

/// [`render_functional`] or [`render_functional_triangles`] (with `triangles`) on `threads`
/// host threads: the same frame, bit for bit, for every count ([`parallel`]). The analysed
/// frame is drawn on one thread whatever `threads` says.
pub fn render_functional_on(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    triangles: Option<&dyn TriangleSource>,
    datapath: Datapath,
    analyse: bool,
    threads: u32,
) -> Result<Frame> {
    if analyse || threads <= 1 {
        return match triangles {
            Some(t) => Ok(render_functional_triangles(
                scene, view, t, datapath, analyse,
            )),
            None => render_functional(scene, view, tol, datapath, analyse),
        };
    }
    match (triangles, datapath) {
        (Some(t), Datapath::F32) => {
            parallel::render_triangles_in_bands::<f32>(scene, view, t, threads)
        }
        (Some(t), Datapath::F64) => {
            parallel::render_triangles_in_bands::<f64>(scene, view, t, threads)
        }
        (None, Datapath::F32) => parallel::render_lembos_in_bands::<f32>(scene, view, tol, threads),
        (None, Datapath::F64) => parallel::render_lembos_in_bands::<f64>(scene, view, tol, threads),
    }
}

/// Renders the triangle path (the scene's lembos tessellated) with the functional model in
/// the given datapath. With `analyse`, the frame buffer keeps normals and double hits on
/// shared edges are counted ([`triangle::TriangleProbe`]).
pub fn render_functional_triangles(
    scene: &Scene,
    view: &View,
    tessellation: &dyn TriangleSource,
    datapath: Datapath,
    analyse: bool,
) -> Frame {
    match datapath {
        Datapath::F32 => triangles_in::<f32>(scene, view, tessellation, analyse),
        Datapath::F64 => triangles_in::<f64>(scene, view, tessellation, analyse),
    }
}

/// A frame drawn by `draw` into a ROP over a fresh frame buffer (keeping normals when
/// analysing); `draw` returns the probe's report when it measured one.
pub(crate) fn frame_with<R: Real>(
    scene: &Scene,
    view: &View,
    analyse: bool,
    draw: impl FnOnce(&mut Rop<R>, &mut Counts) -> Result<Option<probe::ProbeReport>>,
) -> Result<Frame> {
    let vp = view.viewport;
    let bg = scene.background.map(crate::rop::shade::to_u8::<f64>);
    let mut fb = FrameBuffer::new(vp.width, vp.height, bg, analyse);
    let mut counts = Counts::default();
    let mut rop = Rop::<R>::new(&mut fb, &scene.light, view);
    let probe = draw(&mut rop, &mut counts)?;
    (counts.fragments_passed_depth, counts.pixels_covered) = rop.finish();
    Ok(Frame {
        framebuffer: fb,
        counts,
        probe,
    })
}

fn triangles_in<R: Real>(
    scene: &Scene,
    view: &View,
    tessellation: &dyn TriangleSource,
    analyse: bool,
) -> Frame {
    let drawn = frame_with::<R>(scene, view, analyse, |rop, counts| {
        Ok(if analyse {
            let mut p = triangle::TriangleProbe::new(view.viewport.width, rop);
            triangle::render_triangles::<R, _>(tessellation, view, &mut p, counts);
            Some(probe::ProbeReport {
                double_hit_pixels: p.double_hit_pixels(),
                fragments: counts.fragments,
                ..Default::default()
            })
        } else {
            triangle::render_triangles::<R, _>(tessellation, view, rop, counts);
            None
        })
    });
    drawn.expect("the triangle path records no error")
}

fn render_in<R: Real>(scene: &Scene, view: &View, tol: Tolerance, analyse: bool) -> Result<Frame> {
    frame_with::<R>(scene, view, analyse, |rop, counts| {
        let cap = DEFAULT_SEGMENT_CAP;
        Ok(if analyse {
            let mut p = probe::Probe::new(scene, view.viewport, rop);
            render_lembos::<R, _>(scene, view, tol, cap, &mut p, counts)?;
            Some(p.report())
        } else {
            render_lembos::<R, _>(scene, view, tol, cap, rop, counts)?;
            None
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::subsegmenter::Subsegment;

    /// The shipped scene at `path` (from the crate's root) on a 384x384 viewport, and its view.
    fn shipped(path: &str) -> (Scene, View) {
        shipped_at(path, 384, 384)
    }

    /// The shipped scene at `path` (from the crate's root) on a `width` x `height`
    /// viewport, and its view (the raster modules' tests).
    pub(super) fn shipped_at(path: &str, width: u32, height: u32) -> (Scene, View) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
        let mut scene = Scene::load(&path).expect("a shipped scene");
        scene.set_viewport(width, height).expect("a valid viewport");
        let view = View::new(&scene.camera, scene.viewport);
        (scene, view)
    }

    /// Every fragment as the bits of (i, j, u, v, z).
    #[derive(Default, PartialEq, Debug)]
    struct Bits(Vec<[u64; 5]>);

    impl<R: Real> FragmentSink<R> for Bits {
        fn fragment(
            &mut self,
            _: &setup::ScreenLembo<R>,
            _: &Subsegment<R>,
            i: u32,
            j: u32,
            u: R,
            v: R,
            z: R,
        ) {
            let bits = |x: R| x.f64().to_bits();
            self.0.push([i as u64, j as u64, bits(u), bits(v), bits(z)]);
        }
    }

    /// The scan-line stages as dispatched (compiled for AVX2 where the CPU has it) give the
    /// fragments and counts of the stages compiled for the baseline instruction set, bit for
    /// bit, on every lembo of the bunny and of the default scene, in both datapaths.
    fn dispatched_as_compiled<R: Real>(scene: &str) {
        let (scene, view) = shipped(scene);
        let tol = Tolerance::new(0.5);
        let k = R::of(tol.k);
        let (mut pieces, mut counts) = (Vec::new(), Counts::default());
        let (mut dispatched, mut compiled) = (Bits::default(), Bits::default());
        let (mut c1, mut c2) = (Counts::default(), Counts::default());
        let (mut b1, mut b2) = (Buffers::default(), Buffers::default());
        for (id, (lembo, color)) in scene.lembos().enumerate() {
            set_up::<R>(
                id as u32,
                lembo,
                color,
                &view,
                tol,
                &mut pieces,
                &mut counts,
            );
            for l in &pieces {
                let Some((j0, j1)) = scanline_range(l, 384, &mut counts) else {
                    continue;
                };
                let cap = DEFAULT_SEGMENT_CAP;
                scanlines(l, j0, j1, 384, k, cap, &mut dispatched, &mut c1, &mut b1).unwrap();
                scanlines_as_compiled(l, j0, j1, 384, k, cap, &mut compiled, &mut c2, &mut b2)
                    .unwrap();
            }
        }
        assert!(dispatched.0.len() > 10_000, "{}", dispatched.0.len());
        assert_eq!(c1, c2);
        assert!(dispatched == compiled, "the fragments differ");
    }

    /// The triangle path's rows as dispatched (compiled for AVX2 where the CPU has it) draw
    /// the frame and counts of the rows compiled for the baseline instruction set, bit for
    /// bit, through the functional ROP, for the bunny tessellated once and twice, in both
    /// datapaths.
    fn triangle_rows_as_compiled<R: Real>(level: u32) {
        let (scene, view) = shipped("traces/bunny.json");
        let tessellation = crate::lembo::tessellate::Tessellation::new(&scene, level);
        let source: &dyn TriangleSource = &tessellation;
        let [dispatched, compiled] = [true, false].map(|dispatched| {
            let mut fb = FrameBuffer::new(384, 384, [0; 3], false);
            let mut counts = Counts::default();
            let mut rop = Rop::<R>::new(&mut fb, &scene.light, &view);
            let (mut triangles, mut pieces) = (Vec::new(), Vec::new());
            for c in 0..source.chunks() {
                source.chunk(c, &mut triangles);
                for (k, t) in triangles.iter().enumerate() {
                    let id = source.id(c, k);
                    triangle::setup::setup::<R>(
                        id,
                        &t.positions,
                        &t.normals,
                        t.color,
                        &view,
                        &mut pieces,
                    )
                    .count(&mut counts);
                    for st in &pieces {
                        if dispatched {
                            triangle::rasterize::rasterize_rows(st, 0, 384, &mut rop, &mut counts);
                        } else {
                            triangle::rasterize::rasterize_rows_as_compiled(
                                st,
                                0,
                                384,
                                &mut rop,
                                &mut counts,
                            );
                        }
                    }
                }
            }
            (counts.fragments_passed_depth, counts.pixels_covered) = rop.finish();
            (fb, counts)
        });
        assert!(
            dispatched.1.fragments > 10_000,
            "{}",
            dispatched.1.fragments
        );
        assert_eq!(dispatched.1, compiled.1);
        let bits =
            |fb: &FrameBuffer| -> Vec<u32> { fb.depth.iter().map(|d| d.to_bits()).collect() };
        assert!(
            bits(&dispatched.0) == bits(&compiled.0),
            "the depths differ"
        );
        assert!(
            dispatched.0.primitive[..] == compiled.0.primitive[..],
            "the winners differ"
        );
        assert!(
            dispatched.0.color[..] == compiled.0.color[..],
            "the colours differ"
        );
    }

    #[test]
    fn triangle_rows_compiled_for_avx2_give_the_same_bits() {
        for level in [1, 2] {
            triangle_rows_as_compiled::<f32>(level);
            triangle_rows_as_compiled::<f64>(level);
        }
    }

    #[test]
    fn scanlines_compiled_for_avx2_give_the_same_bits() {
        for scene in ["traces/bunny.json", "traces/default.json"] {
            dispatched_as_compiled::<f32>(scene);
            dispatched_as_compiled::<f64>(scene);
        }
    }
}
