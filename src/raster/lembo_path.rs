//! The lembo path in the driver's terms ([`super::driver`]): Setup (whole, or in pieces for
//! the guard band and the perspective tolerance), minmax's scanlines, and per scanline the
//! interval manager, segmenter, subsegmenter and fragment rasterizer into a
//! [`FragmentSink`], with a piece's scanlines compiled for AVX2 where the CPU has it.

use super::counts::Counts;
use super::driver::{Draw, Stages};
use super::fragment::{self, Columns, FragmentSink};
use super::screen::ScreenLembo;
use super::{facing, interval, minmax, segmenter, setup, subsegmenter};
use crate::camera::View;
use crate::datapath::Real;
use crate::error::{Error, Result};
use crate::graph::UnitKind;
use crate::lembo::set::LastParent;
use crate::scene::{LemboIndex, Scene};

/// The lembo path over a scene's lembos: what Setup and the walk are given.
pub struct LemboPath<'a, R> {
    /// The scene whose lembos, in scene order (a lembo's id is its place), are drawn, each
    /// made as Setup takes it.
    scene: &'a Scene,
    /// Where its objects' lembos start.
    starts: LemboIndex,
    /// How many lembos it has.
    count: usize,
    view: &'a View,
    /// k, the walk's midpoint error \[pixels\].
    k: R,
    /// Setup's perspective tolerance \[pixels\]; `None` is the paper's Setup.
    perspective: Option<f64>,
    /// At most this many segments per interval.
    segment_cap: usize,
}

impl<'a, R: Real> LemboPath<'a, R> {
    /// The lembos of `scene` seen through `view`, walked to midpoint error `k` \[pixels\]
    /// with at most `segment_cap` segments an interval, set up with the `perspective`
    /// tolerance \[pixels\] (`None`: the paper's Setup).
    pub fn new(
        scene: &'a Scene,
        view: &'a View,
        k: f64,
        perspective: Option<f64>,
        segment_cap: usize,
    ) -> Self {
        LemboPath {
            scene,
            starts: scene.lembo_index(),
            count: scene.lembo_count(),
            view,
            k: R::of(k),
            perspective,
            segment_cap,
        }
    }
}

impl<R: Real> Stages<R> for LemboPath<'_, R> {
    type Piece = ScreenLembo<R>;
    /// A subdivided lembo's parent, made once for its children.
    type SetupScratch = LastParent;
    type Buffers = Buffers<R>;

    fn primitives(&self) -> usize {
        self.count
    }

    /// Setup of lembo `n` into its pieces (none when it is culled).
    fn set_up(
        &self,
        n: usize,
        last: &mut LastParent,
        pieces: &mut Vec<ScreenLembo<R>>,
        counts: &mut Counts,
    ) {
        let (lembo, color) = self.scene.lembo_near(&self.starts, n, last);
        let first = pieces.len();
        counts.lembos += 1;
        R::charge(UnitKind::Setup);
        match setup::setup_pieces::<R>(n as u32, &lembo, color, self.view, self.perspective, pieces)
        {
            Ok(split) => counts.add_split(split, pieces.len() - first),
            Err(cull) => counts.add_cull(cull),
        }
    }

    /// Minmax: the back-face cull when the view culls, then the scanlines the piece
    /// crosses.
    fn rows(&self, l: &ScreenLembo<R>, counts: &mut Counts) -> Option<(u32, u32)> {
        R::charge(UnitKind::MinMax);
        if facing::faces_away(l, self.view) {
            counts.lembos_culled_backface += 1;
            return None;
        }
        let range = minmax::scanlines(l, self.view.viewport.height);
        if range.is_none() {
            counts.lembos_culled_outside += 1;
        }
        range.map(|(j0, j1)| (j0, j1 + 1))
    }
}

impl<R: Real, S: FragmentSink<R>> Draw<R, S> for LemboPath<'_, R> {
    #[inline]
    fn draw(
        &self,
        l: &ScreenLembo<R>,
        lo: u32,
        hi: u32,
        sink: &mut S,
        counts: &mut Counts,
        buffers: &mut Buffers<R>,
    ) -> std::result::Result<(), (u32, Error)> {
        let cols = Columns::of(self.view);
        let (k, cap) = (self.k, self.segment_cap);
        scanlines(l, lo, hi - 1, cols, k, cap, sink, counts, buffers)
    }
}

/// The buffers the scan-line stages reuse from one scanline to the next.
pub struct Buffers<R> {
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

/// The scan-line stages after minmax for scanlines `j0..=j1` of one set-up lembo or piece;
/// an error comes with the scanline it was met on. On an x86-64 CPU with AVX2 the stages the
/// compiler inlines here (the segmenter's walk, the subsegmenter, the fragment rasterizer's
/// spans) are compiled for it (three-operand instructions, rounding inline): the same IEEE
/// operations in the same order, so the same bits. What stays a call runs as compiled for
/// the baseline: the interval manager (inlined here it ran slower), the segmenter's step
/// and closing chords, and the sink's span where it is not inlined.
#[allow(clippy::too_many_arguments)]
fn scanlines<R: Real, S: FragmentSink<R>>(
    l: &ScreenLembo<R>,
    j0: u32,
    j1: u32,
    cols: Columns,
    k: R,
    segment_cap: usize,
    sink: &mut S,
    counts: &mut Counts,
    b: &mut Buffers<R>,
) -> std::result::Result<(), (u32, Error)> {
    #[cfg(target_arch = "x86_64")]
    if crate::isa::kernels() == crate::isa::Isa::Avx2 {
        // SAFETY: `kernels` says AVX2 only where the CPU has it.
        return unsafe { scanlines_avx2(l, j0, j1, cols, k, segment_cap, sink, counts, b) };
    }
    scanlines_as_compiled(l, j0, j1, cols, k, segment_cap, sink, counts, b)
}

/// [`scanlines`] compiled for AVX2.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn scanlines_avx2<R: Real, S: FragmentSink<R>>(
    l: &ScreenLembo<R>,
    j0: u32,
    j1: u32,
    cols: Columns,
    k: R,
    segment_cap: usize,
    sink: &mut S,
    counts: &mut Counts,
    b: &mut Buffers<R>,
) -> std::result::Result<(), (u32, Error)> {
    scanlines_as_compiled(l, j0, j1, cols, k, segment_cap, sink, counts, b)
}

/// [`scanlines`] for the instruction set its caller is compiled for.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn scanlines_as_compiled<R: Real, S: FragmentSink<R>>(
    l: &ScreenLembo<R>,
    j0: u32,
    j1: u32,
    cols: Columns,
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
        scanline(l, j, cols, k, segment_cap, reach, sink, counts, b).map_err(|e| (j, e))?;
    }
    Ok(())
}

/// The scan-line stages after minmax (interval manager to fragment) for scanline `j` of one
/// set-up lembo or piece, whose steps reach at least `reach` ([`segmenter::walk`]).
/// Scanline j's fragments are all in row j.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn scanline<R: Real, S: FragmentSink<R>>(
    l: &ScreenLembo<R>,
    j: u32,
    cols: Columns,
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
                fragment::rasterize(l, j, sub, cols, sink, counts);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::driver;
    use crate::raster::subsegmenter::Subsegment;
    use crate::raster::tests::shipped_at;
    use crate::raster::{Tolerance, DEFAULT_SEGMENT_CAP};

    /// Every fragment as the bits of (i, j, u, v, z).
    #[derive(Default, PartialEq, Debug)]
    struct Bits(Vec<[u64; 5]>);

    impl<R: Real> FragmentSink<R> for Bits {
        fn fragment(
            &mut self,
            _: &ScreenLembo<R>,
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
        if !crate::isa::avx2_comparable("the AVX2 scan-line stages") {
            return;
        }
        // Under Miri, which checks the AVX2 call's unsafe block, a small viewport suffices.
        let size = if cfg!(miri) { 48 } else { 384 };
        let (scene, view) = shipped_at(scene, size, size);
        let tol = Tolerance::new(0.5);
        let path = LemboPath::<R>::new(&scene, &view, tol.k, tol.perspective, DEFAULT_SEGMENT_CAP);
        let (mut pieces, mut rows) = (Vec::new(), Vec::new());
        let all = 0..path.primitives();
        let keep = |_: &ScreenLembo<R>, r| rows.push(r);
        driver::set_up(
            &path,
            all,
            &mut Default::default(),
            &mut pieces,
            keep,
            &mut Counts::default(),
        );
        let (mut dispatched, mut compiled) = (Bits::default(), Bits::default());
        let (mut c1, mut c2) = (Counts::default(), Counts::default());
        let (mut b1, mut b2) = (Buffers::default(), Buffers::default());
        let (k, cap) = (path.k, path.segment_cap);
        for (l, &(j0, end)) in pieces.iter().zip(&rows) {
            let j1 = end - 1;
            scanlines(
                l,
                j0,
                j1,
                Columns::plain(size),
                k,
                cap,
                &mut dispatched,
                &mut c1,
                &mut b1,
            )
            .unwrap();
            scanlines_as_compiled(
                l,
                j0,
                j1,
                Columns::plain(size),
                k,
                cap,
                &mut compiled,
                &mut c2,
                &mut b2,
            )
            .unwrap();
        }
        let least = if cfg!(miri) { 100 } else { 10_000 };
        assert!(dispatched.0.len() > least, "{}", dispatched.0.len());
        assert_eq!(c1, c2);
        assert!(dispatched == compiled, "the fragments differ");
    }

    #[test]
    fn scanlines_compiled_for_avx2_give_the_same_bits() {
        // Under Miri the default scene (24 lembos) alone.
        let scenes: &[&str] = match cfg!(miri) {
            true => &["traces/default.json"],
            false => &["traces/bunny.json", "traces/default.json"],
        };
        for &scene in scenes {
            dispatched_as_compiled::<f32>(scene);
            dispatched_as_compiled::<f64>(scene);
        }
    }
}
