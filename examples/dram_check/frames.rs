//! The DRAM check's frame traces: what the timed pipeline's DRAM controller receives on a
//! real frame (issue 51, item 5), so DRAMsim3 and the in-house controller can be compared
//! on the traffic the model produces, not only on generated patterns. Shared by the
//! example (`frames`, which writes them and runs DRAMsim3 on them) and the test that keeps
//! the recorded comparison current (`tests/integration/dram_check.rs`, which includes this
//! file).
//!
//! Each frame runs `run_timed` with the DRAM memory model on one channel at 2 000 MHz and
//! keeps the controller's requests in submission order (`SimOptions::dram_requests`), every
//! arrival set to 0: the trace is the frame's requests in the order the ROP caches and the
//! geometry fetch sent them, offered as fast as the memory takes them.

use lembo_sim::camera::View;
use lembo_sim::config::{ArchConfig, MemoryModel};
use lembo_sim::datapath::Datapath;
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::memory::trace::{self, Request};
use lembo_sim::pipeline::{run_timed, SimOptions, Source};
use lembo_sim::scene::Scene;
use std::path::Path;

/// The frames: the bunny at 512x512 on both paths (the triangle path at n = 4) with the
/// default memory system, and overdraw8 (eight full-screen layers, 256x256) on both paths
/// with fast clear and compression off, so every sector moves raw.
pub const FRAMES: [&str; 4] = [
    "bunny_lembo",
    "bunny_triangle",
    "overdraw8_raw_lembo",
    "overdraw8_raw_triangle",
];

/// The pipeline's lembo tolerance for every frame.
const TOLERANCE: f64 = 0.5;
/// The triangle path's tessellation level.
const TESSELLATION: u32 = 4;

/// The requests of frame `name` (one of [`FRAMES`]), every arrival 0.
pub fn frame(name: &str) -> Result<Vec<Request>, String> {
    let (file, raw) = match name {
        "bunny_lembo" | "bunny_triangle" => ("bunny.json", false),
        "overdraw8_raw_lembo" | "overdraw8_raw_triangle" => ("overdraw8.json", true),
        other => return Err(format!("no frame {other}")),
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("traces")
        .join(file);
    let scene = Scene::load(&path).map_err(|e| e.to_string())?;
    let mut arch = ArchConfig {
        clock_mhz: 2000.0,
        ..ArchConfig::default()
    };
    arch.memory.model = MemoryModel::Dram;
    arch.memory.channels = 1;
    if raw {
        arch.memory.fast_clear = false;
        arch.memory.depth_compression = false;
        arch.memory.colour_compression = false;
    }
    let options = SimOptions {
        dram_requests: true,
        ..SimOptions::default()
    };
    let view = View::new(&scene.camera, scene.viewport);
    let tess = name
        .ends_with("triangle")
        .then(|| Tessellation::new(scene.lembo_sets(), TESSELLATION));
    let source = match &tess {
        Some(t) => Source::Triangles(t),
        None => Source::Lembos,
    };
    let run = run_timed(
        &scene,
        &view,
        TOLERANCE,
        Datapath::F32,
        &arch,
        source,
        &options,
    )
    .map_err(|e| e.to_string())?;
    let requests = run.dram_requests.ok_or("the DRAM model kept no requests")?;
    Ok(requests
        .into_iter()
        .map(|r| Request { arrival: 0, ..r })
        .collect())
}

/// FNV-1a (64 bits) over the trace's text as `memory::trace::write` writes it: what the
/// record keeps to tell a stale trace.
pub fn checksum(requests: &[Request]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in trace::write(requests).bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}
