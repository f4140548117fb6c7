//! Criterion benchmarks: the functional model on whole scenes by viewport size, the
//! per-scanline stages on their own, and the timed pipeline against the functional model
//! on the same frame (the issue 3 figure: timed wall / functional wall), and the triangle
//! path, functional and timed, a functional frame on several host threads, the discoid
//! passes, and what off-screen primitives and a
//! lembo far larger than the view cost. Setup (scene loading, projection) stays outside the timed
//! closures.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use lembo_sim::camera::View;
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::Datapath;
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::discoid::blend::{Accum, BlendInput};
use lembo_sim::frame::{self, discoid::render_discoids_functional};
use lembo_sim::job::render_reference;
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::pipeline::discoid::run_discoid_timed;
use lembo_sim::pipeline::{run_timed, SimOptions, Source};
use lembo_sim::raster::{
    fragment, interval, minmax, segmenter, setup, subsegmenter, triangle, Counts,
};
use lembo_sim::tolerance::PerspectiveTol;

#[path = "../tests/integration/support/scenes.rs"]
mod scenes;

fn scenes(c: &mut Criterion) {
    let mut g = c.benchmark_group("functional_render");
    g.sample_size(10);
    for name in ["sphere24.json", "bunny.json"] {
        for side in [512u32, 1024] {
            let s = scenes::trace(name, Some(side));
            let view = View::new(&s.camera, s.viewport);
            let frags = frame::render_functional(&s, &view, 0.5, Datapath::F32, false)
                .unwrap()
                .counts
                .fragments;
            g.throughput(Throughput::Elements(frags));
            g.bench_with_input(
                BenchmarkId::new(name.trim_end_matches(".json"), side),
                &side,
                |b, _| {
                    b.iter(|| {
                        frame::render_functional(&s, &view, 0.5, Datapath::F32, false).unwrap()
                    })
                },
            );
        }
    }
    g.finish();
}

fn stages(c: &mut Criterion) {
    let s = scenes::trace("sphere24.json", None);
    let view = View::new(&s.camera, s.viewport);
    let lembos: Vec<_> = s
        .lembos()
        .enumerate()
        .filter_map(|(i, (l, col))| setup::setup::<f32>(i as u32, &l, col, &view).ok())
        .collect();
    let work: Vec<(usize, u32)> = lembos
        .iter()
        .enumerate()
        .flat_map(|(i, l)| {
            let (j0, j1) = minmax::scanlines(l, view.viewport.height).unwrap();
            (j0..=j1).map(move |j| (i, j))
        })
        .collect();
    let mut g = c.benchmark_group("stages_sphere24_512");
    g.throughput(Throughput::Elements(work.len() as u64));
    g.bench_function("interval_manager_per_scanline", |b| {
        let mut scratch = interval::IntervalScratch::default();
        let mut out = Vec::new();
        let mut counts = Counts::default();
        b.iter(|| {
            for &(i, j) in &work {
                out.clear();
                interval::intervals(&lembos[i], j, 0.5, &mut scratch, &mut out, &mut counts);
            }
        })
    });
    let mut ivs = Vec::new();
    let mut counts = Counts::default();
    let mut scratch = interval::IntervalScratch::default();
    let mut items = Vec::new();
    for &(i, j) in &work {
        ivs.clear();
        interval::intervals(&lembos[i], j, 0.5, &mut scratch, &mut ivs, &mut counts);
        items.extend(ivs.iter().map(|iv| (i, j, *iv)));
    }
    g.bench_function("segmenter_per_scanline", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            for (i, j, iv) in &items {
                out.clear();
                segmenter::segments(&lembos[*i], *j, 0.5, iv, 1 << 16, &mut out, &mut counts)
                    .unwrap();
            }
        })
    });
    let mut segs = Vec::new();
    for (i, j, iv) in &items {
        let mut out = Vec::new();
        segmenter::segments(&lembos[*i], *j, 0.5, iv, 1 << 16, &mut out, &mut counts).unwrap();
        segs.extend(out.into_iter().map(|s| (*i, *j, s)));
    }
    g.bench_function("subsegmenter_per_scanline", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            for (i, _, s) in &segs {
                out.clear();
                subsegmenter::subsegments(&lembos[*i], s, 0.5, &mut out, &mut counts);
            }
        })
    });
    let mut subs = Vec::new();
    for (i, j, s) in &segs {
        let mut out = Vec::new();
        subsegmenter::subsegments(&lembos[*i], s, 0.5, &mut out, &mut counts);
        subs.extend(out.into_iter().map(|sub| (*i, *j, sub)));
    }
    g.bench_function("fragment_rasterizer_per_scanline", |b| {
        let mut sink = CountSink(0);
        b.iter(|| {
            for (i, j, sub) in &subs {
                fragment::rasterize(
                    &lembos[*i],
                    *j,
                    sub,
                    fragment::Columns::of(&view),
                    &mut sink,
                    &mut counts,
                );
            }
            sink.0
        })
    });
    g.bench_function("setup_and_minmax_per_scanline", |b| {
        b.iter(|| {
            let mut rows = 0u64;
            for (i, (l, col)) in s.lembos().enumerate() {
                if let Ok(sl) = setup::setup::<f32>(i as u32, &l, col, &view) {
                    if let Some((j0, j1)) = minmax::scanlines(&sl, view.viewport.height) {
                        rows += (j1 - j0 + 1) as u64;
                    }
                }
            }
            rows
        })
    });
    g.finish();
}

/// Counts fragments, for stage benchmarks without a ROP.
struct CountSink(u64);

impl<R: lembo_sim::datapath::Real> fragment::FragmentSink<R> for CountSink {
    fn fragment(
        &mut self,
        _: &setup::ScreenLembo<R>,
        _: &subsegmenter::Subsegment<R>,
        _: u32,
        _: u32,
        _: R,
        _: R,
        _: R,
    ) {
        self.0 += 1;
    }
}

impl<R: lembo_sim::datapath::Real> triangle::TriangleSink<R> for CountSink {
    fn fragment(
        &mut self,
        _: &triangle::ScreenTriangle<R>,
        _: u32,
        _: u32,
        _: &triangle::TriangleFragment<R>,
    ) {
        self.0 += 1;
    }
}

/// The triangle rasterizer alone (quads and fragments into a counting sink), the blend units
/// alone (one fragment per mode), and the exact reference of a whole frame.
fn more_stages(c: &mut Criterion) {
    let mut g = c.benchmark_group("stages_more");
    g.sample_size(10);
    let s = scenes::trace("sphere24.json", None);
    let view = View::new(&s.camera, s.viewport);
    let t = Tessellation::new(s.lembo_sets(), 4);
    let mut tris = Vec::new();
    let (mut buf, mut pieces) = (Vec::new(), Vec::new());
    for c in 0..triangle::TriangleSource::chunks(&t) {
        triangle::TriangleSource::chunk(&t, c, &mut buf);
        for (k, tr) in buf.iter().enumerate() {
            let id = triangle::TriangleSource::id(&t, c, k);
            triangle::setup::<f32>(id, &tr.positions, &tr.normals, tr.color, &view, &mut pieces);
            tris.append(&mut pieces);
        }
    }
    g.throughput(Throughput::Elements(tris.len() as u64));
    g.bench_function("triangle_rasterizer/sphere24_tess4_512", |b| {
        let mut sink = CountSink(0);
        let mut counts = Counts::default();
        b.iter(|| {
            for st in &tris {
                triangle::rasterize(st, &mut sink, &mut counts);
            }
            sink.0
        })
    });
    let inputs: Vec<BlendInput> = (0..4096)
        .map(|i| BlendInput {
            beta: ((i * 37) % 251) as f64 / 251.0,
            diffuse: ((i * 53) % 241) as f64 / 241.0,
            specular: ((i * 71) % 239) as f64 / 239.0,
        })
        .collect();
    g.throughput(Throughput::Elements(inputs.len() as u64));
    for mode in [BlendMode::Rgba8, BlendMode::F16, BlendMode::F32] {
        g.bench_function(format!("blend/{}", mode.name()), |b| {
            b.iter(|| {
                let mut px = [Accum::default(); 8];
                for (n, f) in inputs.iter().enumerate() {
                    mode.blend(&mut px[n % 8], *f);
                }
                px
            })
        });
    }
    g.throughput(Throughput::Elements(s.viewport.pixels() as u64));
    g.bench_function("reference/sphere24_512", |b| {
        b.iter(|| render_reference(&s, &view, 1, lembo_sim::camera::Samples::ONE))
    });
    g.finish();
}

/// Timed (baseline architecture, one host thread and two) and functional on the bunny and
/// sphere24 at 1024x1024, one group so criterion reports every median from one run
/// (issue 14's target: timed within 1.5x of functional).
fn timed_vs_functional(c: &mut Criterion) {
    let mut g = c.benchmark_group("timed_vs_functional");
    g.sample_size(10);
    let arch = ArchConfig::baseline();
    for name in ["bunny", "sphere24"] {
        let s = scenes::trace(&format!("{name}.json"), Some(1024));
        let view = View::new(&s.camera, s.viewport);
        g.bench_function(format!("functional/{name}/1024"), |b| {
            b.iter(|| frame::render_functional(&s, &view, 0.5, Datapath::F32, false).unwrap())
        });
        for threads in [1, 2] {
            let options = SimOptions {
                host_threads: threads,
                ..SimOptions::default()
            };
            g.bench_function(format!("timed_baseline_{threads}t/{name}/1024"), |b| {
                b.iter(|| {
                    run_timed(
                        &s,
                        &view,
                        0.5,
                        Datapath::F32,
                        &arch,
                        Source::Lembos,
                        &options,
                    )
                    .unwrap()
                })
            });
        }
    }
    g.finish();
}

/// The triangle path on the bunny at 1024x1024: its own triangles (level 1) and level 4
/// (59k triangles), functional, and level 1 timed on the baseline.
fn triangle_path(c: &mut Criterion) {
    let mut g = c.benchmark_group("triangle_path");
    g.sample_size(10);
    let s = scenes::trace("bunny.json", Some(1024));
    let view = View::new(&s.camera, s.viewport);
    for n in [1u32, 4] {
        let t = Tessellation::new(s.lembo_sets(), n);
        g.throughput(Throughput::Elements(t.len()));
        g.bench_with_input(BenchmarkId::new("functional/bunny/1024", n), &n, |b, _| {
            b.iter(|| frame::render_functional_triangles(&s, &view, &t, Datapath::F32, false))
        });
    }
    let t = Tessellation::new(s.lembo_sets(), 1);
    let (arch, options) = (ArchConfig::baseline(), SimOptions::default());
    g.throughput(Throughput::Elements(t.len()));
    g.bench_function("timed_baseline/bunny/1024/1", |b| {
        b.iter(|| {
            run_timed(
                &s,
                &view,
                0.5,
                Datapath::F32,
                &arch,
                Source::Triangles(&t),
                &options,
            )
            .unwrap()
        })
    });
    g.finish();
}

/// The three discoid passes on the bunny's 7350 planar discoids at 512x512, functional in
/// each blend mode and timed (rgba8, baseline).
fn discoid_passes(c: &mut Criterion) {
    let mut g = c.benchmark_group("discoid_passes");
    g.sample_size(10);
    let s = scenes::trace("bunny_discoids.json", None);
    let view = View::new(&s.camera, s.viewport);
    let t = s.discoid_threshold;
    for mode in [BlendMode::Rgba8, BlendMode::F16, BlendMode::F32] {
        g.bench_function(format!("functional/bunny_discoids/{}", mode.name()), |b| {
            b.iter(|| render_discoids_functional(&s, &view, 0.5, Datapath::F32, mode, t).unwrap())
        });
    }
    let (arch, options) = (ArchConfig::baseline(), SimOptions::default());
    g.bench_function("timed_baseline/bunny_discoids/rgba8", |b| {
        b.iter(|| {
            run_discoid_timed(
                &s,
                &view,
                0.5,
                Datapath::F32,
                &arch,
                BlendMode::Rgba8,
                t,
                &options,
            )
            .unwrap()
        })
    });
    g.finish();
}

/// Model only what a scene requires (issue 7): sphere24 alone against the same with nine
/// off-screen copies (90 % of the lembos off screen), functional and timed; and a lembo 2e7
/// px across (`traces/extremes/huge_curved.json`, k = 1e-4), which Setup splits.
fn scope_and_extremes(c: &mut Criterion) {
    let mut g = c.benchmark_group("scope_and_extremes");
    g.sample_size(10);
    let (arch, options) = (ArchConfig::baseline(), SimOptions::default());
    for copies in [0usize, 9] {
        let s = scenes::with_offscreen_copies(copies, 512);
        let view = View::new(&s.camera, s.viewport);
        g.bench_function(format!("functional/sphere24+{copies}_offscreen/512"), |b| {
            b.iter(|| frame::render_functional(&s, &view, 0.5, Datapath::F32, false).unwrap())
        });
        g.bench_function(
            format!("timed_baseline/sphere24+{copies}_offscreen/512"),
            |b| {
                b.iter(|| {
                    run_timed(
                        &s,
                        &view,
                        0.5,
                        Datapath::F32,
                        &arch,
                        Source::Lembos,
                        &options,
                    )
                    .unwrap()
                })
            },
        );
    }
    let s = scenes::trace("extremes/huge_curved.json", None);
    let view = View::new(&s.camera, s.viewport);
    for dp in [Datapath::F32, Datapath::F64] {
        g.bench_function(format!("functional/huge_curved/k1e-4/{}", dp.name()), |b| {
            b.iter(|| frame::render_functional(&s, &view, 1e-4, dp, false).unwrap())
        });
    }
    g.finish();
}

/// One functional frame on 1, 2 and 4 host threads (`--threads`, `frame::bands`): the
/// bunny at 1024x1024 on both paths; the frames are identical.
fn frame_threads(c: &mut Criterion) {
    let mut g = c.benchmark_group("frame_threads");
    g.sample_size(10);
    let s = scenes::trace("bunny.json", Some(1024));
    let view = View::new(&s.camera, s.viewport);
    let tol = PerspectiveTol::FollowK.with_k(0.5);
    let t = Tessellation::new(s.lembo_sets(), 1);
    for threads in [1u32, 2, 4] {
        for (path, source) in [
            ("lembo", None),
            ("triangle", Some(&t as &dyn triangle::TriangleSource)),
        ] {
            g.bench_with_input(
                BenchmarkId::new(format!("{path}/bunny/1024"), threads),
                &threads,
                |b, &n| {
                    b.iter(|| {
                        frame::render_functional_on(&s, &view, tol, source, Datapath::F32, false, n)
                            .unwrap()
                    })
                },
            );
        }
    }
    g.finish();
}

criterion_group!(
    benches,
    frame_threads,
    scope_and_extremes,
    scenes,
    stages,
    timed_vs_functional,
    triangle_path,
    discoid_passes,
    more_stages
);
criterion_main!(benches);
