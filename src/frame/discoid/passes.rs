//! The three passes of the atlas of discoids (Piranda et al. 2006 section 3, DESIGN.md §4) in the
//! functional model.
//!
//! 1. **Depth**: every discoid fragment with beta > 0 that faces the eye writes the nearest
//!    depth (visibility splatting); no colour.
//! 2. **Accumulation**: fragments that face away from the eye are culled, fragments with
//!    beta = 0 discarded, and fragments farther than the threshold t behind the depth pass's
//!    surface (`linear_depth(z) > linear_depth(depth) + t`, t in world units along the view
//!    direction) discarded; the rest are blended by the ROP blend unit of the chosen
//!    [`BlendMode`] in equation (5)'s incremental form, with the interest values
//!    cos(alpha) and cos^N(gamma) of equation (6). Beside it, an f64 accumulation of the
//!    same fragments (`ExactAccum`) is the error reference. Rounded blending depends on
//!    order, so each pixel blends its fragments in primitive order (then by texture
//!    coordinates, for a folded lembo's two fragments), as GPU ROPs blend in API order:
//!    the pass collects the fragments it keeps and [`DiscoidTarget::blend_in_order`] blends
//!    them, so any unit order (functional or timed) gives the same bits.
//! 3. **Resolve**: per pixel, equation (6) from the averaged interest values, in the colour
//!    of the discoid that won the depth pass.
//!
//! Planar discoids are squares (two triangles) through the triangle path, their texture
//! coordinates from the world position in their tangent frame; curved discoids are lembos
//! through the lembo path, their texture coordinates from quadratics through the six
//! reference points' coordinates. Both use the datapath of the run.
//!
//! Deviations from the paper: the depth pass also culls back faces and discards beta = 0
//! (a square's corners outside the disk must not hide what is behind them), and the
//! threshold is in world units rather than depth-buffer units, so that it means the same
//! at every distance. The counters of fragments culled and discarded are those of the
//! accumulation pass.
//!
//! This file drives the passes over a scene (the lembo path's and the triangle path's
//! functional drivers into a sink that hands each fragment to the ROP's work,
//! [`super::target::process`]); what the blend units know of the discoids is
//! [`super::table`].

use super::table::DiscoidFragment;
use super::table::DiscoidTable;
use super::target::{process, resolve, DiscoidTarget, Pass};
use crate::camera::View;
use crate::datapath::{Datapath, Real};
use crate::discoid::blend::BlendMode;
use crate::discoid::report::BlendReport;
use crate::error::{Error, Result};
use crate::graph::UnitKind;
use crate::raster::fragment::FragmentSink;
use crate::raster::setup::ScreenLembo;
use crate::raster::subsegmenter::Subsegment;
use crate::raster::triangle::{render_triangles, ScreenTriangle, TriangleFragment, TriangleSink};
use crate::raster::{render_lembos, Counts, DEFAULT_SEGMENT_CAP};
use crate::rop::fragment_shader::FragmentShader;
use crate::rop::shade::to_u8;
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use crate::tolerance::Tolerance;

/// A fragment sink for both paths that feeds [`process`] in the functional model.
struct Sink<'a, R> {
    pass: Pass,
    target: &'a mut DiscoidTarget,
    table: &'a DiscoidTable<R>,
    shader: &'a FragmentShader<R>,
    view: &'a View,
}

impl<R: Real> Sink<'_, R> {
    /// Fragment `f` at pixel (i, j) through this pass.
    #[inline]
    fn put(&mut self, i: u32, j: u32, f: &DiscoidFragment<R>) {
        let idx = (j * self.target.width + i) as usize;
        process(
            self.pass,
            self.target,
            self.table,
            self.shader,
            self.view,
            idx,
            f,
        );
    }
}

impl<R: Real> FragmentSink<R> for Sink<'_, R> {
    fn fragment(
        &mut self,
        l: &ScreenLembo<R>,
        _sub: &Subsegment<R>,
        i: u32,
        j: u32,
        u: R,
        v: R,
        z: R,
    ) {
        // The ROP's work, as the timed ROP does it (a counting datapath charges it there);
        // then the charge goes back to the rasterizer that called.
        R::charge(UnitKind::Rop);
        if let Some(f) = self.table.lembo_fragment(l, u, v, z) {
            self.put(i, j, &f);
        }
        R::charge(UnitKind::FragmentRasterizer);
    }
}

impl<R: Real> TriangleSink<R> for Sink<'_, R> {
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, tf: &TriangleFragment<R>) {
        R::charge(UnitKind::Rop);
        let f = self.table.planar_fragment(t, tf);
        self.put(i, j, &f);
        R::charge(UnitKind::TriangleRasterizer);
    }
}

/// A discoid frame: the image, the counts of the paths that drew it, and the blend report.
pub struct DiscoidFrame {
    /// The resolved image.
    pub framebuffer: FrameBuffer,
    /// The counts of the path that drew the discoids (the accumulation pass's).
    pub counts: Counts,
    /// The passes' counters and the blend error.
    pub blend: BlendReport,
}

/// Refuses scenes that mix discoid objects with ordinary ones (not modelled).
pub fn check_scene(scene: &Scene) -> Result<()> {
    let has = scene.objects.iter().any(|o| o.discoids.is_some());
    if let Some((k, o)) = scene
        .objects
        .iter()
        .enumerate()
        .find(|(_, o)| has && o.discoids.is_none())
    {
        return Err(Error::invalid(
            scene.source_name(),
            format!("objects[{k}]"),
            &o.label,
            "a scene with discoids may hold only discoid objects (mixing opaque surfaces with the blend passes is not modelled)",
        ));
    }
    Ok(())
}

/// Renders a discoid scene's three passes with the functional model.
pub fn render_discoids_functional(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
    mode: BlendMode,
    threshold: f64,
) -> Result<DiscoidFrame> {
    render_discoids(scene, view, tol.into(), datapath, (mode, threshold), false)
}

/// [`render_discoids_functional`], keeping in the frame buffer the depth pass winner's
/// normal at each pixel when `keep_normals` (for the accuracy metrics); the same image.
pub fn render_discoids(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    datapath: Datapath,
    (mode, threshold): (BlendMode, f64),
    keep_normals: bool,
) -> Result<DiscoidFrame> {
    let settings = (mode, threshold);
    match datapath {
        Datapath::F32 => render_discoids_in::<f32, f32>(scene, view, tol, settings, keep_normals),
        Datapath::F64 => render_discoids_in::<f64, f32>(scene, view, tol, settings, keep_normals),
    }
}

/// [`render_discoids`] in the datapath word `R` with the blend ALU's word `B` (`f32` for
/// an image; the cost model's counting run gives counting words, which draw the same
/// bits).
pub fn render_discoids_in<R: Real, B: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    (mode, threshold): (BlendMode, f64),
    keep_normals: bool,
) -> Result<DiscoidFrame> {
    check_scene(scene)?;
    let vp = view.viewport;
    let table = DiscoidTable::<R>::new(scene, view);
    let shader = FragmentShader::<R>::new(&scene.light, view);
    let mut target = DiscoidTarget::new(vp.width, vp.height, mode, threshold);
    if keep_normals {
        target.normal = Some(vec![[0.0; 3]; vp.width as usize * vp.height as usize]);
    }
    let mut counts = Counts::default();
    for pass in [Pass::Depth, Pass::Accumulate] {
        let mut sink = Sink {
            pass,
            target: &mut target,
            table: &table,
            shader: &shader,
            view,
        };
        // Each pass draws every discoid; the counts are those of one pass.
        let mut c = Counts::default();
        render_lembos::<R, _>(scene, view, tol, DEFAULT_SEGMENT_CAP, &mut sink, &mut c)?;
        render_triangles::<R, _>(&table.planar, view, &mut sink, &mut c);
        counts = c;
    }
    target.blend_in_order::<B>();
    let background = scene.background.map(to_u8::<f64>);
    let framebuffer = resolve::<R, B>(&mut target, &table, &shader, background, vp.height);
    counts.fragments_passed_depth = target.report.fragments_accumulated;
    counts.pixels_covered = framebuffer.covered() as u64;
    Ok(DiscoidFrame {
        framebuffer,
        counts,
        blend: target.report,
    })
}
