//! The exact reference a run is measured against (for a discoid scene, the surface its
//! discoids stand for) and a frame's accuracy against it.

use super::validate::{PrimitivePath, RenderJob, TraceSettings};
use crate::camera::{Samples, View};
use crate::error::{Error, Result, COMMAND_LINE};
use crate::frame;
use crate::lembo::tessellate::Tessellation;
use crate::reference::flip::{flip_frame, FlipMap, PixelsPerDegree};
use crate::reference::leak::{self, Approximation};
use crate::reference::metrics::Visibility;
use crate::reference::oracle::{ReferenceImage, SceneLembos};
use crate::reference::{heatmap, metrics, oracle, see_through, Accuracy, Drawn};
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use std::time::Instant;

/// The scene whose lembos the exact reference of `scene` renders: the scene itself, or for
/// a discoid scene the surface its discoids stand for (`scene::surface`); a discoid
/// scene that does not say what surface that is has `--reference` refused naming why.
pub fn reference_scene(scene: &Scene) -> Result<std::borrow::Cow<'_, Scene>> {
    if scene.discoid_count() == 0 {
        return Ok(std::borrow::Cow::Borrowed(scene));
    }
    crate::scene::surface::surface_scene(scene)
        .map(std::borrow::Cow::Owned)
        .map_err(no_surface)
}

/// Refuses, before any work, `--reference` on a discoid scene that does not say what
/// surface it stands for ([`reference_scene`] without building the surface).
pub fn check_reference_scene(scene: &Scene) -> Result<()> {
    crate::scene::surface::check_surfaces(scene).map_err(no_surface)
}

/// The `--reference` error of a discoid scene without a surface.
fn no_surface(why: String) -> Error {
    Error::invalid(
        COMMAND_LINE,
        "--reference",
        "given",
        format!("the reference of a discoid scene is the surface its discoids stand for: {why}"),
    )
}

/// The exact reference of `scene`'s lembo surfaces for a render of `samples` per pixel,
/// with the wall time it took; for a discoid scene, pass its [`reference_scene`]. With one
/// sample, the pixel centres traced (and `supersample`² sub-samples a pixel when above 1);
/// with more, the area-averaged colours of `supersample`² sub-samples a pixel and the hits
/// at the pixels' first sample rows' samples ([`ReferenceImage::for_samples`]).
pub fn render_reference(
    scene: &Scene,
    view: &View,
    supersample: u32,
    samples: Samples,
) -> (ReferenceImage, f64) {
    crate::progress::stage("exact reference");
    let t = Instant::now();
    let reference = trace(scene, view, supersample, samples, oracle::DEFAULT_TILE);
    (reference, t.elapsed().as_secs_f64())
}

/// [`render_reference`] traced as `settings` say (tile side, threads): the same image.
pub fn render_reference_with(
    scene: &Scene,
    view: &View,
    supersample: u32,
    samples: Samples,
    settings: TraceSettings,
) -> Result<(ReferenceImage, f64)> {
    crate::progress::stage("exact reference");
    let t = Instant::now();
    let reference = settings.install(|| trace(scene, view, supersample, samples, settings.tile))?;
    Ok((reference, t.elapsed().as_secs_f64()))
}

/// The reference [`render_reference`] describes, binned in tiles of `tile` pixels.
fn trace(
    scene: &Scene,
    view: &View,
    supersample: u32,
    samples: Samples,
    tile: u32,
) -> ReferenceImage {
    // The lembos are made by id as the tiles ask for them: nothing holds them all
    // (DESIGN.md §3, "Streamed primitives").
    let lembos = SceneLembos::new(scene);
    let input = oracle::ReferenceInput {
        lembos: &lembos,
        view,
        light: &scene.light,
        background: scene.background,
        supersample,
        tile,
    };
    let reference = oracle::render_reference(&input);
    if samples == Samples::ONE {
        return reference;
    }
    let offset = samples.first_row_offset();
    let at_sample = oracle::render_reference(&oracle::ReferenceInput {
        view: &view.translated(offset),
        supersample: 1,
        ..input
    });
    reference.for_samples(at_sample, offset)
}

/// The view a reference's hits were traced in: `view`, or moved to where a multisampled
/// run's reference traced them ([`ReferenceImage::hits_offset_px`]).
fn hits_view(view: &View, reference: &ReferenceImage) -> View {
    match reference.hits_offset_px {
        [0.0, 0.0] => *view,
        offset => view.translated(offset),
    }
}

/// What a run's image looks like against the reference, for a person to read.
pub struct ErrorMaps {
    /// The colour difference and the coverage disagreements (`error.png`,
    /// [`heatmap::error_heatmap`]).
    pub colour: image::RgbImage,
    /// The FLIP map in the reference implementation's colours (`flip.png`).
    pub flip: image::RgbImage,
}

/// A measured run's accuracy, error maps and the wall time the measuring took.
pub(super) struct Measured {
    pub(super) accuracy: Accuracy,
    pub(super) maps: ErrorMaps,
    /// The reference's wall time plus the metrics' \[seconds\].
    pub(super) reference_wall: f64,
    /// The metrics' wall time \[seconds\].
    pub(super) metrics_wall: f64,
    /// The reference's tile side \[pixels\] and the threads its metrics ran on.
    pub(super) tile: u32,
    pub(super) threads: u32,
}

impl Measured {
    /// `host` with the tile side and threads of this measurement, if any.
    pub(super) fn echo(
        measured: Option<&Measured>,
        mut host: crate::report::Host,
    ) -> crate::report::Host {
        host.reference_tile_px = measured.map(|m| m.tile);
        host.reference_threads = measured.map(|m| m.threads);
        host
    }
}

/// Measures `frame` (probed) against `reference` (with the wall time it took);
/// `ids_per_lembo` as [`measure_frame`] takes it.
pub(super) fn measure(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    ids_per_lembo: u64,
    frame: &frame::Frame,
    (reference, wall): (&ReferenceImage, f64),
) -> Result<Measured> {
    crate::progress::stage("accuracy metrics");
    let t1 = Instant::now();
    super::memory::return_freed_memory();
    let (accuracy, flip, threads) = job.trace.install(|| {
        let (accuracy, flip) = measure_frame_and_flip(
            scene,
            view,
            frame,
            reference,
            job.path,
            ids_per_lembo,
            job.flip_ppd,
            job.samples,
        );
        (accuracy, flip, rayon::current_num_threads() as u32)
    })?;
    let metrics_wall = t1.elapsed().as_secs_f64();
    Ok(Measured {
        accuracy,
        maps: ErrorMaps {
            colour: heatmap::error_heatmap(&frame.framebuffer, reference),
            flip: flip.to_image(),
        },
        reference_wall: wall + t1.elapsed().as_secs_f64(),
        metrics_wall,
        tile: job.trace.tile,
        threads,
    })
}

/// The accuracy of `frame` (rendered with `analyse`, one sample a pixel) of `scene` against
/// its `reference`: the metrics, with the reference traced anew where the sub-pixel
/// silhouette asks, the fragment probe's counts and the visibility counts
/// ([`visibility`]). `ids_per_lembo` maps the frame's winner ids to lembo ids: 1 on the
/// lembo path, n² on the triangle path at level n; FLIP is computed for the observer
/// `ppd`.
pub fn measure_frame(
    scene: &Scene,
    view: &View,
    frame: &frame::Frame,
    reference: &ReferenceImage,
    path: PrimitivePath,
    ids_per_lembo: u64,
    ppd: PixelsPerDegree,
) -> Accuracy {
    measure_frame_and_flip(
        scene,
        view,
        frame,
        reference,
        path,
        ids_per_lembo,
        ppd,
        Samples::ONE,
    )
    .0
}

/// [`measure_frame`] of a frame drawn with `samples` per pixel and resolved (against the
/// reference [`render_reference`] made for them), with the FLIP map its `flip_mean` is the
/// mean of.
#[allow(clippy::too_many_arguments)]
pub fn measure_frame_and_flip(
    scene: &Scene,
    view: &View,
    frame: &frame::Frame,
    reference: &ReferenceImage,
    path: PrimitivePath,
    ids_per_lembo: u64,
    ppd: PixelsPerDegree,
    samples: Samples,
) -> (Accuracy, FlipMap) {
    let probe = frame.probe.unwrap_or_default();
    // Multisampled, the frame keeps each pixel's first sample row's geometry, and the
    // reference's hits are traced there: so are the outline and the see-through rays.
    let view = &hits_view(view, reference);
    let lembos = SceneLembos::new(scene);
    // Measured in sample rows, 1/samples of a pixel apart.
    let deviation_px = probe.max_scanline_deviation_px / samples.get() as f64;
    let level = match path {
        PrimitivePath::Lembo => None,
        PrimitivePath::Triangle => Some(ids_per_lembo.isqrt() as u32),
    };
    // FLIP runs beside the rest, in bands of rows on the same threads (`flip::flip`).
    let (flip, (tracer, visibility)) = rayon::join(
        || flip_frame(&frame.framebuffer, reference, ppd),
        || {
            // The reference's own tiles, when it says what they are: no second binning.
            let tracer = match &reference.bins {
                Some(bins) => oracle::Tracer::with_bins(&lembos, view, bins.clone()),
                None => oracle::Tracer::new(&lembos, view, oracle::DEFAULT_TILE),
            };
            let visibility = visibility(
                scene,
                &tracer,
                &frame.framebuffer,
                reference,
                level,
                deviation_px,
            );
            (tracer, visibility)
        },
    );
    let accuracy = metrics::measure(
        &frame.framebuffer,
        reference,
        &tracer,
        probe.double_hit_pixels,
        match path {
            PrimitivePath::Lembo => Some(deviation_px),
            PrimitivePath::Triangle => None,
        },
        visibility,
        &flip,
    );
    (accuracy, flip)
}

/// The see-through pixels of a render of `scene` (`reference::see_through`): the lembos
/// of objects built from a triangle mesh (`mesh` and `builtin` objects) are checked against
/// their triangles; None when the scene has no such object. `level` is the tessellation
/// level of a render of the triangle path (its winners' ids are `lembo * n² + k`), None
/// for the lembo path.
pub fn see_through_px(
    scene: &Scene,
    view: &View,
    render: &FrameBuffer,
    level: Option<u32>,
) -> Option<u64> {
    let lembos = SceneLembos::new(scene);
    let triangles = level.map(|n| Tessellation::new(scene.lembo_sets(), n));
    see_through_of(scene, &lembos, view, render, drawn(&triangles))
}

/// The visibility counts of a render of `scene` against its exact `reference`, which
/// `tracer` answers between pixel centres (both of the render's view): see-through
/// (None without a mesh, [`see_through_px`]) and the leaks (`reference::leak`). `level` as
/// [`see_through_px`] takes it; on the lembo path, `deviation_px` is the largest scanline
/// deviation the renderer measured \[pixels\] (how far its outlines may stray).
pub fn visibility(
    scene: &Scene,
    tracer: &oracle::Tracer,
    render: &FrameBuffer,
    reference: &ReferenceImage,
    level: Option<u32>,
    deviation_px: f64,
) -> Visibility {
    let lembos = SceneLembos::new(scene);
    let triangles = level.map(|n| Tessellation::new(scene.lembo_sets(), n));
    let drawn = drawn(&triangles);
    let see_through = see_through_of(scene, &lembos, tracer.view(), render, drawn);
    let approximation = match level {
        None => Approximation::Lembos { deviation_px },
        Some(level) => Approximation::Triangles { level },
    };
    let leaks = leak::leaks(&lembos, tracer, render, reference, drawn, approximation);
    Visibility {
        see_through_px: see_through,
        leak_px: Some(leaks.total()),
    }
}

/// The see-through pixels of a render of `scene` whose winners `drawn` names; None when no
/// object of the scene is built from a triangle mesh.
fn see_through_of(
    scene: &Scene,
    lembos: &SceneLembos,
    view: &View,
    render: &FrameBuffer,
    drawn: Drawn,
) -> Option<u64> {
    let meshed = scene.objects.iter().any(|o| o.from_mesh);
    meshed.then(|| see_through::see_through(lembos, view, render, drawn).total())
}

/// How a render's winners name surfaces: lembos, or the `triangles` of a tessellation.
fn drawn<'a>(triangles: &'a Option<Tessellation<'a>>) -> Drawn<'a> {
    Drawn {
        ids_per_lembo: triangles.as_ref().map_or(1, |t| t.triangles_per_lembo()),
        triangles: triangles.as_ref(),
    }
}
