//! The DRAM memory model (`memory.model = "dram"`, DESIGN.md §3, "The memory system"):
//! ROP caches over tile tables, their traffic through a DRAM controller. Timing never
//! changes pixels; results do not depend on the host schedule; the report says where the
//! bytes went; the depth cache absorbs repeated tests.

use lembo_sim::camera::{Samples, View};
use lembo_sim::config::{ArchConfig, MemoryModel};
use lembo_sim::datapath::Datapath;
use lembo_sim::job::{run_path, Mode, Model, PathRun, PrimitivePath, RenderJob};
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::pipeline::rop_memory::MemoryReport;
use lembo_sim::pipeline::{run_timed, SimOptions, Source, TimedFrame};
use lembo_sim::scene::Scene;

use crate::support::{arch, render_job, scenes};

/// `a` with the DRAM memory model.
fn dram(mut a: ArchConfig) -> ArchConfig {
    a.memory.model = MemoryModel::Dram;
    a
}

/// A timed render of `scene` on `path` (the triangle path at n = 4) with `samples` a pixel.
fn render(scene: &Scene, path: PrimitivePath, samples: u32, a: &ArchConfig) -> PathRun {
    let job = RenderJob {
        trace: Default::default(),
        path,
        tess: (path == PrimitivePath::Triangle).then_some(4),
        samples: Samples::new(samples).unwrap(),
        mode: Mode::Timed,
        ..render_job(0.5, Datapath::F32)
    };
    let view = View::new(&scene.camera, scene.viewport);
    run_path(&job, scene, &view, Model::new(Some(a)), None).expect("timed run")
}

fn memory(run: &PathRun) -> &MemoryReport {
    run.report
        .memory_system
        .as_ref()
        .expect("the DRAM model reports its memory system")
}

/// The caches hold tags only and the controller moves no pixel: every image, depth and
/// winner is the port model's, on both paths, with one sample and with four (whose resolve
/// goes through the caches' surfaces too), and with ROP tiles of 16 pixels, whose spans
/// cross two memory tiles.
#[test]
fn the_dram_model_draws_what_the_port_model_draws() {
    let mut wide_tiles = ArchConfig::default();
    wide_tiles.rop.tile_px = 16;
    let runs = [
        ("bunny.json", 256, 1, ArchConfig::default()),
        ("sphere24.json", 128, 4, ArchConfig::default()),
        ("bunny.json", 256, 1, wide_tiles),
    ];
    for (name, side, samples, a) in runs {
        let s = scenes::trace(name, Some(side));
        for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
            let port = render(&s, path, samples, &a);
            let with_dram = render(&s, path, samples, &dram(a.clone()));
            let what = format!("{name} {path:?} {samples} samples, tile {}", a.rop.tile_px);
            assert!(port.report.memory_system.is_none(), "{what}");
            assert!(
                with_dram.framebuffer.color == port.framebuffer.color,
                "{what}"
            );
            assert!(
                with_dram.framebuffer.depth == port.framebuffer.depth,
                "{what}"
            );
            assert!(
                with_dram.framebuffer.primitive == port.framebuffer.primitive,
                "{what}"
            );
            let m = memory(&with_dram);
            assert!(m.atoms_written > 0, "{what}: {m:?}");
            if samples > 1 {
                // The resolve writes every pixel's resolved colour: at least the frame's
                // pixels in atoms.
                let pixels = u64::from(side * side);
                assert!(
                    m.atoms_written * u64::from(m.atom_bytes) >= 4 * pixels,
                    "{what}"
                );
            }
        }
    }
}

fn timed(scene: &Scene, a: &ArchConfig, options: &SimOptions) -> TimedFrame {
    let view = View::new(&scene.camera, scene.viewport);
    run_timed(scene, &view, 0.5, Datapath::F32, a, Source::Lembos, options).expect("timed run")
}

/// The controller is one unit fed through the ROPs' merge: seeded random orders and 2 to
/// 4 host threads give the same cycles and the same memory report.
#[test]
fn the_dram_model_does_not_depend_on_the_host_schedule() {
    let s = scenes::trace("sphere24.json", Some(256));
    let a = dram(arch("wide.json"));
    let first = timed(&s, &a, &SimOptions::default());
    assert!(first.memory.is_some());
    let runs = (1..=3)
        .map(|seed| SimOptions {
            perturb: Some(seed),
            ..SimOptions::default()
        })
        .chain((2..=4).map(|threads| SimOptions {
            host_threads: threads,
            partition_seed: Some(threads as u64),
            ..SimOptions::default()
        }));
    for options in runs {
        let t = timed(&s, &a, &options);
        assert_eq!(t.cycles, first.cycles, "{options:?}");
        assert_eq!(t.memory, first.memory, "{options:?}");
        assert!(t.framebuffer.color == first.framebuffer.color);
        assert_eq!(t.recoveries.unproven, 0);
    }
}

/// On the bunny at 512x512, report.json says where the bytes went on both paths: cache
/// hit rates, compression ratios, fast-cleared tiles, DRAM atoms, activations and row hits.
#[test]
fn the_bunny_reports_its_memory_system_on_both_paths() {
    let s = scenes::trace("bunny.json", None);
    assert_eq!((s.viewport.width, s.viewport.height), (512, 512));
    for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
        let run = render(&s, path, 1, &dram(ArchConfig::default()));
        let m = memory(&run);
        for rate in [
            m.colour_cache_hit_rate,
            m.depth_cache_hit_rate,
            m.row_hit_rate,
        ] {
            assert!(rate > 0.0 && rate < 1.0, "{path:?}: {m:?}");
        }
        assert!(m.depth_compression_ratio > 1.0, "{path:?}: {m:?}");
        assert!(m.colour_compression_ratio >= 1.0, "{path:?}: {m:?}");
        assert!(m.atoms_read > 0 && m.atoms_written > 0 && m.activations > 0);
        // The bunny covers a fraction of the screen: the rest stays cleared.
        assert!(
            m.rops.cleared_tiles > 0 && m.rops.cleared_tiles < 4096,
            "{m:?}"
        );
        let json = serde_json::to_value(&run.report).unwrap();
        for key in [
            "atoms_read",
            "activations",
            "row_hit_rate",
            "depth_cache_hit_rate",
        ] {
            assert!(json["memory_system"][key].is_number(), "{path:?}: {key}");
        }
        assert!(json["memory_system"]["depth_compression_ratio"].is_number());
    }
}

/// traces/overdraw8.json: eight full-screen layers drawn cell by cell, so every pixel is
/// tested eight times in a row. The depth cache takes nearly every test: the depth surface's
/// DRAM traffic is a small fraction of what the port model moves for the tests.
#[test]
fn the_depth_cache_absorbs_an_overdraw_scenes_repeated_tests() {
    let s = scenes::trace("overdraw8.json", None);
    for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
        let run = render(&s, path, 1, &dram(ArchConfig::default()));
        let m = memory(&run);
        let tests = run.report.counts.fragments;
        let pixels = u64::from(s.viewport.width * s.viewport.height);
        assert_eq!(tests, 8 * pixels, "{path:?}: eight layers over every pixel");
        let d = &m.rops.depth_cache;
        assert!(d.hits + d.misses > 0);
        assert!(m.depth_cache_hit_rate > 0.9, "{path:?}: {m:?}");
        // A sector holds 8 pixels: without a cache every test would read one.
        let port_sectors = tests / 8;
        let depth_sectors = m.rops.depth.sectors_read + m.rops.depth.sectors_written;
        assert!(
            depth_sectors * 20 < port_sectors,
            "{path:?}: {depth_sectors} of {port_sectors}"
        );
    }
}

/// The DRAM model prices the frame buffer per atom and activation by the technology file's
/// memory kind, and each ROP's caches as SRAM; the port model keeps its bytes at the DRAM's
/// figure and no cache.
#[test]
fn the_dram_model_prices_atoms_activations_and_the_rop_caches() {
    let s = scenes::trace("sphere24.json", Some(128));
    let port = render(&s, PrimitivePath::Lembo, 1, &ArchConfig::default());
    let run = render(&s, PrimitivePath::Lembo, 1, &dram(ArchConfig::default()));
    let (pc, dc) = (port.report.cost.unwrap(), run.report.cost.unwrap());
    assert!(pc.framebuffer_dram.is_none());
    let m = run.report.memory_system.as_ref().unwrap();
    let d = dc.framebuffer_dram.expect("priced by atoms");
    // gddr6 in the embedded technology file: 7.5 pJ a bit read or written.
    let bits = 8.0 * f64::from(m.atom_bytes);
    assert!((d.read_pj - m.atoms_read as f64 * bits * 7.5).abs() < 1e-6 * d.read_pj.max(1.0));
    assert!((d.write_pj - m.atoms_written as f64 * bits * 7.5).abs() < 1e-6 * d.write_pj);
    assert!(d.activation_pj > 0.0);
    // The geometry fetch's reads are among the controller's atoms, not priced again by
    // the byte.
    assert!(m.geometry_atoms_read > 0);
    assert!((dc.dram_energy_pj() - d.total_pj).abs() < 1e-6 * d.total_pj);
    for u in &dc.units {
        let rop = u.name.starts_with("Rop");
        assert_eq!(u.cache_area_mm2 > 0.0, rop, "{}", u.name);
    }
    assert!(pc.units.iter().all(|u| u.cache_area_mm2 == 0.0));
    // Two 16 KB arrays a ROP at 0.69 µm² a bit, the embedded file's.
    let rop = dc.units.iter().find(|u| u.name == "Rop[0]").unwrap();
    let want = 2.0 * 16384.0 * 8.0 * 0.69e-6;
    assert!(
        (rop.cache_area_mm2 - want).abs() < 1e-9,
        "{}",
        rop.cache_area_mm2
    );
}

/// A memory-bound frame's cycles follow its bytes: the bunny with units at 4 GHz against
/// the DRAM (so the DRAM bounds the frame), with the DRAM's bytes per cycle halved twice
/// (4, 2, then 1 channel), takes at least 1.6x the cycles each time. No per-message floor
/// stands in the way: the items are the same at every width.
#[test]
fn a_memory_bound_frame_follows_the_drams_bytes_per_cycle() {
    let s = scenes::trace("bunny.json", None);
    let mut a = dram(ArchConfig::default());
    a.clock_mhz = 4000.0;
    let mut last: Option<u64> = None;
    for channels in [4, 2, 1] {
        a.memory.channels = channels;
        let run = render(&s, PrimitivePath::Lembo, 1, &a);
        let cycles = run.report.cycles.as_ref().unwrap();
        assert_eq!(
            cycles.bottleneck.as_deref(),
            Some("FrameBuffer"),
            "{channels} channels"
        );
        if let Some(before) = last {
            let ratio = cycles.total.0 as f64 / before as f64;
            assert!(
                ratio >= 1.6,
                "{channels} channels: {ratio:.2}x the cycles of twice the width"
            );
        }
        last = Some(cycles.total.0);
    }
}

/// The geometry fetch reads through the controller, its atoms queued among the ROPs'
/// fills and write-backs in time: with each primitive 8 times larger to read, the fetch's
/// atoms grow with its bytes, and the ROPs' reads wait longer for theirs (on both paths),
/// while every pixel stays the same.
#[test]
fn the_rops_reads_wait_longer_when_the_fetch_reads_more() {
    let s = scenes::trace("bunny.json", Some(256));
    for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
        let runs: Vec<PathRun> = [1, 8]
            .into_iter()
            .map(|scale| {
                let mut a = dram(ArchConfig::default());
                a.fetch.bytes_per_lembo *= scale;
                a.fetch.bytes_per_vertex *= scale;
                render(&s, path, 1, &a)
            })
            .collect();
        let [light, heavy] = [&runs[0], &runs[1]].map(memory);
        let atom = u64::from(light.atom_bytes);
        for (run, m) in runs.iter().zip([light, heavy]) {
            let bytes = run.report.fetch.as_ref().expect("a fetch report").bytes;
            // Every batch reads the atoms its bytes span: at least bytes / atom of them.
            assert!(
                m.geometry_atoms_read >= bytes / atom && m.geometry_atoms_read > 0,
                "{path:?}: {} atoms for {bytes} bytes",
                m.geometry_atoms_read
            );
        }
        assert!(heavy.geometry_atoms_read > 4 * light.geometry_atoms_read);
        assert!(
            heavy.rop_read_latency_mean > 1.2 * light.rop_read_latency_mean,
            "{path:?}: the ROPs' reads took {:.1} DRAM cycles beside the light fetch, {:.1} \
             beside the heavy one",
            light.rop_read_latency_mean,
            heavy.rop_read_latency_mean
        );
        assert!(runs[1].framebuffer.color == runs[0].framebuffer.color);
    }
}

/// The fetch's reads close a loop of credits (controller, ROP, ..., setup, fetch): with
/// every FIFO one entry deep, on both paths and both triangle sources, the run neither
/// stops nor falls back on an unproven order, and seeded random orders and three host
/// threads give the same cycles and memory report.
#[test]
fn the_fetch_through_the_controller_runs_on_one_entry_fifos() {
    let s = scenes::trace("sphere24.json", Some(128));
    for (path, onchip) in [
        (PrimitivePath::Lembo, false),
        (PrimitivePath::Triangle, false),
        (PrimitivePath::Triangle, true),
    ] {
        let mut a = dram(arch("minimal.json"));
        for link in a.links.all_mut() {
            link.fifo_depth = 1;
        }
        if onchip {
            a.tessellation.source = lembo_sim::graph::TessSource::OnChip;
        }
        let tess = (path == PrimitivePath::Triangle).then(|| Tessellation::new(s.lembo_sets(), 4));
        let source = tess
            .as_ref()
            .map_or(Source::Lembos, |t| Source::Triangles(t));
        let view = View::new(&s.camera, s.viewport);
        let run = |options: &SimOptions| {
            run_timed(&s, &view, 0.5, Datapath::F32, &a, source, options).expect("timed run")
        };
        let first = run(&SimOptions::default());
        let what = format!("{path:?}, on chip {onchip}");
        assert_eq!(first.recoveries.unproven, 0, "{what}");
        assert!(
            first.memory.as_ref().unwrap().geometry_atoms_read > 0,
            "{what}"
        );
        for options in [
            SimOptions {
                perturb: Some(7),
                ..SimOptions::default()
            },
            SimOptions {
                host_threads: 3,
                partition_seed: Some(3),
                ..SimOptions::default()
            },
        ] {
            let t = run(&options);
            assert_eq!(t.cycles, first.cycles, "{what}: {options:?}");
            assert_eq!(t.memory, first.memory, "{what}: {options:?}");
            assert_eq!(t.recoveries.unproven, 0, "{what}: {options:?}");
        }
    }
}
