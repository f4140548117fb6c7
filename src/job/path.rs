//! One lembo or triangle route drawn on one model into a [`PathRun`]: the image, measured
//! against the reference when there is one, and its report; a timed frame is priced
//! (DESIGN.md §12) by a counting run whose image must equal it.

use super::culling;
use super::discoids::run_discoids;
use super::reference::{measure, Measured};
use super::route::{sim_options, Model, PathRun, Route};
use super::sections::{host, scene_info, settings};
use super::validate::{PrimitivePath, RenderJob};
use crate::camera::View;
use crate::config::{ArchConfig, FetchConfig, MemoryModel};
use crate::cost::memory_kind::DramEnergySplit;
use crate::cost::memory_kind::MemoryKind;
use crate::cost::model::MemoryWork;
use crate::cost::{self, model::CostReport};
use crate::error::{Error, Result};
use crate::frame;
use crate::graph::TessSource;
use crate::pipeline::rop_memory::MemoryReport;
use crate::pipeline::{self, CycleReport, FetchReport, Source};
use crate::raster;
use crate::raster::triangle::TriangleSource;
use crate::reference::oracle::ReferenceImage;
use crate::report::{Host, Memory, Primitives, Report, SCHEMA_VERSION};
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use std::time::Instant;

/// Runs `job`'s path on `scene` on `model`, and with a `reference` (and the wall time it
/// took) the accuracy metrics, from the functional model's fragment probe; the timed image
/// must equal the functional one bit for bit, and this is checked on every such run.
pub fn run_path(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    model: Model,
    reference: Option<(&ReferenceImage, f64)>,
) -> Result<PathRun> {
    let route = Route::new(job, scene)?;
    if let Model::Timed(arch) = model {
        memory_kind_of(job, arch)?;
    }
    if let Route::Discoids = route {
        culling::check_discoids(job, scene, model)?;
        return run_discoids(job, scene, view, model, reference);
    }
    // Every model of the run (functional, timed, counting) draws through this view, so
    // they cull the same primitives.
    let (cull, culling) = culling::resolve(scene, view, model, &route);
    let view = &view.with_culling(cull);
    let (drawn, wall) = draw(job, scene, view, model, &route, reference.is_some())?;
    let measured = measure_drawn(job, scene, view, &route, &drawn, reference)?;
    let counts = drawn.counts();
    // The primitives' sizes: the architecture's, or its defaults for a functional frame.
    let sizes = model.arch().map(|a| a.fetch.clone()).unwrap_or_default();
    let primitives = primitives(scene, &route, &counts, &sizes);
    let (framebuffer, units, cycles, trace, fetch, memory_system) = match drawn {
        Drawn::Functional(f) => (f.framebuffer, Vec::new(), None, None, None, None),
        Drawn::Timed { timed, .. } => (
            timed.framebuffer,
            timed.units,
            Some(timed.cycles),
            timed.trace,
            timed.fetch,
            timed.memory,
        ),
    };
    let cost = match (model, &cycles) {
        (Model::Timed(arch), Some(cycles)) => Some(cost_of(
            job,
            scene,
            view,
            &route,
            arch,
            cycles,
            &counts,
            &framebuffer,
            fetch,
            memory_system.as_ref(),
        )?),
        _ => None,
    };
    let memory = Memory::new(
        FrameBuffer::stored_bytes_sampled(scene.viewport.width, scene.viewport.height, job.samples),
        0,
        primitives.bytes,
        model.arch().map(|a| a.fifo_entries(&units)),
    );
    let tess = match &route {
        Route::Triangles(t) => Some(t.level()),
        _ => None,
    };
    let report = Report {
        schema_version: SCHEMA_VERSION,
        scene: scene_info(scene),
        settings: settings(
            job,
            model,
            job.path.name(),
            (job.path == PrimitivePath::Lembo).then_some(job.k),
            tess,
            reference.is_some(),
            Some(culling),
        ),
        primitives,
        units,
        counts,
        host: route_host(job, wall, &counts, cycles.as_ref(), measured.as_ref()),
        cycles,
        fetch,
        cost,
        arch: model.arch().cloned(),
        accuracy: measured.as_ref().map(|m| m.accuracy.clone()),
        blend: None,
        memory_system,
        memory,
    };
    Ok(PathRun {
        report,
        framebuffer,
        error_maps: measured.map(|m| m.maps),
        trace,
    })
}

/// The drawn frame measured against `reference` (with the wall time it took), when the run
/// is measured and has a probed functional frame; a triangle's ids count per lembo.
fn measure_drawn(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    route: &Route,
    drawn: &Drawn,
    reference: Option<(&ReferenceImage, f64)>,
) -> Result<Option<Measured>> {
    Ok(match (reference, drawn.probed()) {
        (Some(reference), Some(frame)) => {
            let ids_per_lembo = match route {
                Route::Triangles(t) => t.triangles_per_lembo(),
                _ => 1,
            };
            Some(measure(job, scene, view, ids_per_lembo, frame, reference)?)
        }
        _ => None,
    })
}

/// The host section of a lembo or triangle route's report: a functional frame also
/// names its threads (the triangle path's analysed frame is drawn on one).
fn route_host(
    job: &RenderJob,
    wall: f64,
    counts: &raster::Counts,
    cycles: Option<&CycleReport>,
    measured: Option<&Measured>,
) -> Host {
    let mut h = host(
        wall,
        counts.fragments,
        cycles.map(|c| (c.total, job.host_threads)),
        measured.map(|m| m.reference_wall),
        measured.map(|m| m.metrics_wall),
    );
    if cycles.is_none() {
        // The functional frame's threads: the triangle path's analysed frame is drawn on
        // one (`frame::render_functional_on`).
        let one = measured.is_some() && job.path == PrimitivePath::Triangle;
        h.host_threads = Some(if one { 1 } else { job.threads() });
    }
    Measured::echo(measured, h)
}

/// The primitives section of a lembo or triangle route's report, their bytes at `sizes`.
fn primitives(
    scene: &Scene,
    route: &Route,
    counts: &raster::Counts,
    sizes: &FetchConfig,
) -> Primitives {
    match route {
        Route::Triangles(t) => Primitives {
            kind: "triangle".into(),
            count: t.len(),
            vertices: t.vertex_count(),
            bytes: t.bytes(sizes),
            quad_efficiency: counts.quad_efficiency(),
        },
        _ => {
            let lembos = scene.lembo_count() as u64;
            Primitives {
                kind: "lembo".into(),
                count: lembos,
                vertices: 6 * lembos,
                bytes: sizes.bytes_per_lembo * lembos,
                quad_efficiency: None,
            }
        }
    }
}

/// The cost of a timed lembo or triangle frame (DESIGN.md §12): the functional model runs
/// again in a counting datapath for the operations of each kind (its image must equal the
/// timed one, so counting cannot have changed what was drawn), priced with the timed run's
/// busy cycles and items, the bytes through the frame-buffer port and the `geometry_bytes`
/// the geometry fetch read.
#[allow(clippy::too_many_arguments)]
fn cost_of(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    route: &Route,
    arch: &ArchConfig,
    cycles: &CycleReport,
    counts: &raster::Counts,
    timed: &FrameBuffer,
    fetch: Option<FetchReport>,
    memory: Option<&MemoryReport>,
) -> Result<CostReport> {
    crate::progress::stage("pricing (counting run)");
    let grid = view.grid(job.samples);
    let (frame, mut ops) = match route {
        Route::Triangles(t) => cost::triangle_ops(scene, &grid, t, job.datapath),
        _ => cost::lembo_ops(scene, &grid, job.grid_tolerance(), job.datapath)?,
    };
    let frame = frame.resolve(job.samples);
    // The triangle corners whose transformed vertex setup reused: the vertex caches' hits
    // for a mesh in memory; on chip, each patch's points are set up once.
    let mut vertices_reused = fetch.and_then(|f| f.vertex_cache).map_or(0, |v| v.hits);
    if let (Route::Triangles(t), TessSource::OnChip) = (route, arch.tessellation.source) {
        cost::onchip::tessellation_ops(t, &mut ops);
        vertices_reused =
            (3 * t.len()).saturating_sub(t.lembos() as u64 * TriangleSource::vertices_per_chunk(t));
    }
    if frame.framebuffer.color != timed.color {
        return Err(Error::Internal(
            "the counting run's image differs from the timed one".into(),
        ));
    }
    let fb = &arch.framebuffer;
    // Multisampled, a fragment is a sample, and the resolve reads them all once.
    let (w, h) = (scene.viewport.width, scene.viewport.height);
    let framebuffer_bytes = counts.fragments * fb.bytes_per_fragment_tested
        + counts.fragments_passed_depth * fb.bytes_per_fragment_written
        + FrameBuffer::resolve_bytes(w, h, job.samples);
    let work = cost::model::Work {
        ops: &ops,
        cycles,
        framebuffer_bytes,
        accumulation_bytes: 0,
        geometry_bytes: fetch.map_or(0, |f| f.bytes),
        vertices_reused,
        blend: None,
        memory: memory.map(|m| memory_work(job, arch, m)).transpose()?,
    };
    Ok(cost::model::cost(&job.tech()?, arch, job.datapath, &work))
}

/// The technology file's memory kind of the DRAM model's `memory.dram`; a kind the file
/// lacks is refused naming the field, before any work. None with the port model.
fn memory_kind_of(job: &RenderJob, arch: &ArchConfig) -> Result<Option<MemoryKind>> {
    if arch.memory.model != MemoryModel::Dram {
        return Ok(None);
    }
    let tech = job.tech()?;
    let kind = tech.memory_kind(arch.memory.dram.name(), "architecture", "memory.dram")?;
    Ok(Some(kind.clone()))
}

/// The DRAM memory model's frame buffer for its cost: `m`'s atoms and activations priced
/// by the memory kind, and the ROP caches' SRAM and sector traffic.
fn memory_work(job: &RenderJob, arch: &ArchConfig, m: &MemoryReport) -> Result<MemoryWork> {
    let kind = memory_kind_of(job, arch)?.ok_or_else(|| {
        Error::Internal("a memory report from a run without the DRAM model".into())
    })?;
    let sector_bits = 8.0 * f64::from(arch.memory.sector_bytes);
    let c = [&m.rops.colour_cache, &m.rops.depth_cache];
    let sectors: u64 = c
        .iter()
        .map(|c| c.hits + c.misses + c.fills + c.write_backs)
        .sum();
    let cache_bytes = arch.memory.colour_cache_bytes + arch.memory.depth_cache_bytes;
    Ok(MemoryWork {
        dram: DramEnergySplit {
            kind: arch.memory.dram.name(),
            ..kind.energy_pj(m.atoms_read, m.atoms_written, m.atom_bytes, m.activations)
        },
        cache_bits_per_rop: 8.0 * f64::from(cache_bytes),
        cache_bits_moved: sectors as f64 * sector_bits,
    })
}

/// A surface path's image with what each model contributed (one per run, so the variants'
/// sizes do not matter).
#[allow(clippy::large_enum_variant)]
enum Drawn {
    /// The functional model alone (with its probe when the run is measured).
    Functional(frame::Frame),
    /// The timed pipeline; for a measured run also the functional model's probed frame.
    Timed {
        timed: pipeline::TimedFrame,
        probed: Option<frame::Frame>,
    },
}

impl Drawn {
    /// The functional frame carrying the fragment probe, when the run is measured.
    fn probed(&self) -> Option<&frame::Frame> {
        match self {
            Drawn::Functional(f) => Some(f),
            Drawn::Timed { probed, .. } => probed.as_ref(),
        }
    }

    /// The counts of the model that made the image.
    fn counts(&self) -> raster::Counts {
        match self {
            Drawn::Functional(f) => f.counts,
            Drawn::Timed { timed, .. } => timed.counts,
        }
    }
}

/// Draws a lembo or triangle `route` on `model`, with the wall time of that render alone
/// \[seconds\]; with `analyse`, the functional model also runs with its probe (a timed run
/// checks its image against it), outside the time taken.
fn draw(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    model: Model,
    route: &Route,
    analyse: bool,
) -> Result<(Drawn, f64)> {
    // Multisampled, both models draw the sample grid and the frames are resolved at the end.
    let grid = view.grid(job.samples);
    let functional = |analyse: bool| -> Result<frame::Frame> {
        let triangles = match route {
            Route::Triangles(t) => Some(t as &dyn raster::triangle::TriangleSource),
            _ => None,
        };
        frame::render_functional_on(
            scene,
            &grid,
            job.grid_tolerance(),
            triangles,
            job.datapath,
            analyse,
            job.threads(),
        )
    };
    let arch = match model {
        Model::Functional => {
            crate::progress::stage("functional model");
            let t0 = Instant::now();
            let frame = functional(analyse)?.resolve(job.samples);
            return Ok((Drawn::Functional(frame), t0.elapsed().as_secs_f64()));
        }
        Model::Timed(arch) => arch,
    };
    let (path, source) = match route {
        Route::Triangles(t) => (PrimitivePath::Triangle, Source::Triangles(t)),
        _ => (PrimitivePath::Lembo, Source::Lembos),
    };
    let options = sim_options(job, arch, path)?;
    crate::progress::stage("timed pipeline");
    let t0 = Instant::now();
    let timed = pipeline::run_timed(
        scene,
        &grid,
        job.grid_tolerance(),
        job.datapath,
        arch,
        source,
        &options,
    )?;
    let wall = t0.elapsed().as_secs_f64();
    let probed = if analyse {
        crate::progress::stage("functional model, probed");
        let frame = functional(true)?;
        if timed.framebuffer.color != frame.framebuffer.color {
            return Err(Error::Internal(
                "the timed image differs from the functional one".into(),
            ));
        }
        Some(frame.resolve(job.samples))
    } else {
        None
    };
    let timed = pipeline::TimedFrame {
        framebuffer: timed.framebuffer.resolve(job.samples),
        ..timed
    };
    Ok((Drawn::Timed { timed, probed }, wall))
}
