//! A discoid scene's render (DESIGN.md §4): the three passes, timed or functional, their
//! report, a timed frame's cost (DESIGN.md §12) from a counting run whose image must equal
//! it, and with `--reference` the blended image measured against the surface the discoids
//! stand for.

use super::reference::reference_scene;
use super::reference::{ErrorMaps, Measured};
use super::route::{sim_options, Model, PathRun};
use super::sections::{host, scene_info, settings};
use super::validate::{PrimitivePath, RenderJob};
use crate::camera::View;
use crate::config::ArchConfig;
use crate::cost::{self, model::CostReport};
use crate::error::{Error, Result};
use crate::frame;
use crate::pipeline::{self, CycleReport, UnitInstance};
use crate::raster::Counts;
use crate::reference::flip::flip_frame;
use crate::reference::oracle::ReferenceImage;
use crate::reference::{heatmap, metrics, oracle};
use crate::report::{BlendSection, Memory, Primitives, Report, SCHEMA_VERSION};
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use std::time::Instant;

pub use crate::discoid::{CURVED_DISCOID_BYTES, PLANAR_DISCOID_BYTES};

/// A discoid scene's three passes (Piranda et al. 2006): timed on `arch`, or functional. With both,
/// the timed image is checked against the functional one.
pub(super) fn run_discoids(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    model: Model,
    reference: Option<(&ReferenceImage, f64)>,
) -> Result<PathRun> {
    let threshold = job.threshold.unwrap_or(scene.discoid_threshold);
    crate::progress::stage("discoid passes");
    let t0 = Instant::now();
    let passes = run_passes(job, scene, view, model, threshold)?;
    let wall = t0.elapsed().as_secs_f64();
    let measured = match reference {
        Some(reference) => Some(measure_discoids(
            job,
            scene,
            view,
            threshold,
            &passes.framebuffer,
            reference,
        )?),
        None => None,
    };
    let Passes {
        framebuffer,
        counts,
        blend,
        units,
        cycles,
        cost,
    } = passes;
    let (planar, curved) = discoid_counts(scene);
    let primitive_bytes = PLANAR_DISCOID_BYTES * planar + CURVED_DISCOID_BYTES * curved;
    let memory = Memory::new(
        FrameBuffer::stored_bytes(scene.viewport.width, scene.viewport.height),
        blend.blend.accumulation_buffer_bytes,
        primitive_bytes,
        model.arch().map(|a| a.fifo_entries(&units)),
    );
    let report = Report {
        schema_version: SCHEMA_VERSION,
        scene: scene_info(scene),
        settings: settings(
            job,
            model,
            "discoid",
            (curved > 0).then_some(job.k),
            None,
            false,
            None,
        ),
        primitives: Primitives {
            kind: "discoid".into(),
            count: planar + curved,
            vertices: 4 * planar + 6 * curved,
            bytes: primitive_bytes,
            quad_efficiency: counts.quad_efficiency(),
        },
        units,
        counts,
        cycles: cycles.clone(),
        fetch: cost.as_ref().map(|c| pipeline::FetchReport {
            source: "discoids",
            primitives: planar + curved,
            bytes: c.geometry_bytes,
            vertex_cache: None,
        }),
        cost,
        arch: model.arch().cloned(),
        accuracy: measured.as_ref().map(|m| m.accuracy.clone()),
        blend: Some(blend),
        memory_system: None,
        memory,
        host: Measured::echo(
            measured.as_ref(),
            host(
                wall,
                counts.fragments,
                cycles.map(|c| (c.total, job.host_threads)),
                measured.as_ref().map(|m| m.reference_wall),
                measured.as_ref().map(|m| m.metrics_wall),
            ),
        ),
    };
    Ok(PathRun {
        report,
        framebuffer,
        error_maps: measured.map(|m| m.maps),
        trace: None,
    })
}

/// What a discoid scene's passes yield, timed or functional: the blended image, its
/// counts and blend section, and when timed the units, cycles and cost.
struct Passes {
    framebuffer: FrameBuffer,
    counts: Counts,
    blend: BlendSection,
    units: Vec<UnitInstance>,
    cycles: Option<CycleReport>,
    cost: Option<CostReport>,
}

/// The three passes on `model`: timed on its architecture (then priced by
/// [`discoid_cost`]), or functional.
fn run_passes(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    model: Model,
    threshold: f64,
) -> Result<Passes> {
    Ok(match model {
        Model::Timed(arch) => {
            let t = pipeline::discoid::run_discoid_timed(
                scene,
                view,
                job.tolerance(),
                job.datapath,
                arch,
                job.blend,
                threshold,
                &sim_options(
                    job,
                    arch,
                    if scene.lembo_count() > 0 {
                        PrimitivePath::Lembo
                    } else {
                        PrimitivePath::Triangle
                    },
                )?,
            )?;
            let cost = discoid_cost(job, scene, view, arch, threshold, &t)?;
            let blend = BlendSection::new(t.blend, Some(t.passes));
            Passes {
                framebuffer: t.framebuffer,
                counts: t.counts,
                blend,
                units: t.units,
                cycles: Some(t.cycles),
                cost: Some(cost),
            }
        }
        Model::Functional => {
            let f = frame::discoid::render_discoids_functional(
                scene,
                view,
                job.tolerance(),
                job.datapath,
                job.blend,
                threshold,
            )?;
            Passes {
                framebuffer: f.framebuffer,
                counts: f.counts,
                blend: BlendSection::new(f.blend, None),
                units: Vec::new(),
                cycles: None,
                cost: None,
            }
        }
    })
}

/// How many planar and curved (lembo-textured) discoids the scene's objects hold.
fn discoid_counts(scene: &Scene) -> (u64, u64) {
    scene
        .objects
        .iter()
        .filter_map(|o| o.discoids.as_ref())
        .fold((0u64, 0u64), |(p, c), d| {
            (
                p + d.planar.len() as u64,
                c + d.lembo_texcoords.len() as u64,
            )
        })
}

/// The cost of a timed discoid frame (DESIGN.md §12): the functional passes again in
/// counting words for the operations of each kind (their image must equal the timed one),
/// priced with the timed passes' busy cycles and items, the blend units' share of their
/// ROPs', and the bytes through the frame-buffer port, the accumulation target's apart.
fn discoid_cost(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    arch: &ArchConfig,
    threshold: f64,
    timed: &pipeline::discoid::DiscoidTimed,
) -> Result<CostReport> {
    let (frame, ops) = cost::discoid_ops(
        scene,
        view,
        job.tolerance(),
        job.datapath,
        (job.blend, threshold),
    )?;
    if frame.framebuffer.color != timed.framebuffer.color {
        return Err(Error::Internal(
            "the counting run's discoid image differs from the timed one".into(),
        ));
    }
    let work = cost::model::Work {
        ops: &ops,
        cycles: &timed.cycles,
        framebuffer_bytes: timed.port_bytes.framebuffer,
        accumulation_bytes: timed.port_bytes.accumulation,
        geometry_bytes: timed.port_bytes.geometry,
        // Planar discoids are read whole, without a vertex cache.
        vertices_reused: 0,
        blend: Some(cost::model::BlendWork {
            mode: job.blend,
            units: &timed.blend_units,
        }),
        memory: None,
    };
    Ok(cost::model::cost(&job.tech()?, arch, job.datapath, &work))
}

/// A discoid image measured against the surface its discoids stand for: the functional
/// passes drawn again keeping the depth winners' normals (their image must be the one
/// measured, bit for bit), then the metrics against the reference of [`reference_scene`].
fn measure_discoids(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    threshold: f64,
    image: &FrameBuffer,
    (reference, wall): (&ReferenceImage, f64),
) -> Result<Measured> {
    let t1 = Instant::now();
    let with_normals = frame::discoid::render_discoids(
        scene,
        view,
        job.tolerance(),
        job.datapath,
        (job.blend, threshold),
        true,
    )?
    .framebuffer;
    if with_normals.color != image.color {
        return Err(Error::Internal(
            "the discoid image drawn again for the metrics differs from the one measured".into(),
        ));
    }
    let surface = reference_scene(scene)?;
    let (accuracy, flip, threads) = job.trace.install(|| {
        let lembos = oracle::SceneLembos::new(surface.as_ref());
        let tracer = oracle::Tracer::new(&lembos, view, job.trace.tile);
        let flip = flip_frame(&with_normals, reference, job.flip_ppd);
        let accuracy = metrics::measure(
            &with_normals,
            reference,
            &tracer,
            0,
            None,
            Default::default(),
            &flip,
        );
        (accuracy, flip, rayon::current_num_threads() as u32)
    })?;
    let metrics_wall = t1.elapsed().as_secs_f64();
    Ok(Measured {
        accuracy,
        maps: ErrorMaps {
            colour: heatmap::error_heatmap(image, reference),
            flip: flip.to_image(),
        },
        reference_wall: wall + metrics_wall,
        metrics_wall,
        tile: job.trace.tile,
        threads,
    })
}
