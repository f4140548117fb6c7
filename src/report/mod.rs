//! The run report (DESIGN.md §7): `report.json` for tools (this module's types, serialised
//! as they are), `report.txt` and the command's summary lines for people ([`text`], the one
//! place a report is put into words). The files are written by [`crate::output`].

use crate::camera::Winding;
use crate::config::ArchConfig;
use crate::cost::model::CostReport;
use crate::discoid::report::BlendReport;
use crate::pipeline::discoid::PassCycles;
use crate::pipeline::rop_memory::MemoryReport;
use crate::pipeline::{Cycle, CycleReport, FetchReport, UnitInstance};
use crate::raster::Counts;
use crate::reference::metrics::Accuracy;
use serde::Serialize;

pub mod html;
pub mod text;

/// Version of the `report.json` layout; bumped when a field changes meaning or moves.
pub const SCHEMA_VERSION: u32 = 9;

/// Everything a run reports.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// What was drawn.
    pub scene: SceneInfo,
    /// How it was drawn.
    pub settings: Settings,
    /// What the path drew with, and how much primitive data that is.
    pub primitives: Primitives,
    /// Every effective architecture parameter, defaults included; null in functional mode.
    pub arch: Option<ArchConfig>,
    /// The unit instances this scene required; empty in functional mode.
    pub units: Vec<UnitInstance>,
    /// The functional model's counts of the path that ran (intervals, segments, fragments, ...).
    pub counts: Counts,
    /// Cycle accounting of the timed pipeline; null in functional mode.
    pub cycles: Option<CycleReport>,
    /// What the geometry fetch read through the memory port: the source, primitives,
    /// bytes and, for a mesh in memory, the vertex caches' hits and misses; null in
    /// functional mode.
    pub fetch: Option<FetchReport>,
    /// Area and energy of the instantiated units for this frame (DESIGN.md §12), a discoid
    /// scene's blend units and accumulation target included; null in functional mode.
    pub cost: Option<CostReport>,
    /// Accuracy against the exact reference; null without `--reference`.
    pub accuracy: Option<Accuracy>,
    /// The discoid blend units' counters and error; null for scenes without discoids.
    pub blend: Option<BlendSection>,
    /// With the DRAM memory model (`memory.model = "dram"`): the caches' hit rates, the
    /// tile tables' compression and fast-cleared tiles, DRAM atoms, activations, row hits
    /// and energy; left out with the port model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub memory_system: Option<MemoryReport>,
    /// The storage the simulated unit instantiates for this run.
    pub memory: Memory,
    /// What the simulation cost the host (not deterministic).
    pub host: Host,
}

/// `blend` in report.json: the blend units' counters and error, then the timed passes'
/// cycles.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlendSection {
    /// The counters and error, from the functional passes.
    #[serde(flatten)]
    pub blend: BlendReport,
    /// Timed runs: the cycles of each pass (depth, accumulation, resolve); null in
    /// functional mode.
    pub cycles_depth_pass: Option<Cycle>,
    /// The accumulation pass's frame cycles; null in functional mode.
    pub cycles_accumulation_pass: Option<Cycle>,
    /// The resolve pass's cycles; null in functional mode.
    pub cycles_resolve_pass: Option<Cycle>,
}

impl BlendSection {
    /// `blend` with the timed passes' cycles, when the passes were timed.
    pub fn new(blend: BlendReport, passes: Option<PassCycles>) -> Self {
        BlendSection {
            blend,
            cycles_depth_pass: passes.map(|p| p.depth),
            cycles_accumulation_pass: passes.map(|p| p.accumulation),
            cycles_resolve_pass: passes.map(|p| p.resolve),
        }
    }
}

/// The scene a report is about.
#[derive(Clone, Debug, Serialize)]
pub struct SceneInfo {
    /// The scene's name (its file's stem, or `default`).
    pub name: String,
    /// The scene file, or "(embedded default)".
    pub source: String,
    /// Viewport width \[pixels\].
    pub width: u32,
    /// Viewport height \[pixels\].
    pub height: u32,
    /// Lembos in the scene (curved discoids included) \[primitives\].
    pub lembos: u64,
    /// Each object's label with what it holds (`bunny (3674 lembos)`).
    pub objects: Vec<String>,
}

/// The effective settings of the run, defaults included.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    /// `timed` (the Figure 5 pipeline) or `functional` (untimed).
    pub mode: String,
    /// The architecture file, `(embedded baseline)`, or null in functional mode.
    pub arch_file: Option<String>,
    /// `lembo` or `triangle`.
    pub path: String,
    /// Tolerance k of the extreme method \[pixels\]; null for the triangle path.
    pub k_px: Option<f64>,
    /// Setup's perspective tolerance \[pixels\] (`--perspective-tol`, default k/2), or `"off"`
    /// for the paper's Setup; null for the triangle path.
    pub perspective_tol: Option<PerspectiveSetting>,
    /// Tessellation level n (n² triangles per lembo); null for the lembo path.
    pub tess: Option<u32>,
    /// `f32` or `f64`.
    pub datapath: String,
    /// Whether the exact reference was rendered and compared.
    pub reference: bool,
    /// Reference sub-samples per pixel side (1 = pixel centres only).
    pub supersample: u32,
    /// Samples per pixel of the render (1: one at each pixel centre; 2, 4 or 8:
    /// multisampled at Direct3D's standard positions and resolved, DESIGN.md §2).
    pub samples: u32,
    /// Back-face culling as the run resolved it (DESIGN.md §5); null on a discoid scene,
    /// whose passes cull back-facing fragments themselves (§4).
    pub culling: Option<CullingSetting>,
}

/// Back-face culling as a run resolved it from the architecture's switch and the scene
/// (DESIGN.md §5, "Back-face culling").
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct CullingSetting {
    /// The switch of the path drawn (`minmax.cull_backfaces` or
    /// `triangle_setup.cull_backfaces`): `off`, `on` or `auto`; `off` in functional mode,
    /// which has no architecture.
    pub switch: String,
    /// Whether the run culled back faces.
    pub culled: bool,
    /// The winding of a front face when it culled (`ccw`, `cw`), else null.
    pub front: Option<Winding>,
    /// The winding facing out of every object when each is a closed, consistently
    /// oriented mesh; null for a scene that is not, and when the switch is `off` (not
    /// asked).
    pub closed_outward: Option<Winding>,
    /// Whether every lembo's control net lies beyond the near plane (`auto` asks it too);
    /// null when the scene is not closed (not asked).
    pub beyond_near_plane: Option<bool>,
}

/// Setup's perspective tolerance as a report echoes it: pixels, or the string `"off"`.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
#[serde(untagged)]
pub enum PerspectiveSetting {
    /// The tolerance \[pixels\].
    Px(f64),
    /// Always `"off"`: the paper's Setup.
    Off(&'static str),
}

/// The primitives a path draws and their size in memory.
#[derive(Clone, Debug, Serialize)]
pub struct Primitives {
    /// `lembo` or `triangle`.
    pub kind: String,
    /// Primitives in the scene \[primitives\].
    pub count: u64,
    /// Vertices the primitive data holds: six control points per lembo (each lembo is read
    /// whole); the distinct vertices of the tessellated mesh for triangles \[vertices\].
    pub vertices: u64,
    /// Bytes of the primitive data as stored in memory, at the architecture's sizes
    /// (`fetch.*`; their defaults in functional mode): `fetch.bytes_per_lembo` per lembo
    /// (144: six points and six normals in f32); for triangles the whole indexed mesh,
    /// `fetch.bytes_per_vertex` per distinct vertex (24: position and normal) and
    /// `fetch.index_bytes_per_triangle` per triangle (12: three 32-bit indices). What the
    /// geometry fetch reads is `fetch.bytes` (a mesh's vertices once per cache miss)
    /// \[bytes\].
    pub bytes: u64,
    /// Covered pixels over pixels of the quads shaded, fragments / (4 quads); null for
    /// lembos, which are not rasterized in quads.
    pub quad_efficiency: Option<f64>,
}

/// The storage the simulated unit instantiates for this run (issue 7): each path counts
/// only the buffers it uses, so a lembo-only scene has no accumulation buffer and no
/// triangle-path FIFOs. Deterministic; the simulator's own memory is `host.peak_rss_bytes`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Memory {
    /// The frame buffer as stored: RGB8 colour, f32 depth and u32 winner id per pixel,
    /// width × height × 11 (the normal buffer kept for the accuracy metrics is the
    /// simulator's, not the unit's) \[bytes\].
    pub framebuffer_bytes: u64,
    /// The discoid accumulation target, `blend.accumulation_buffer_bytes`: width × height ×
    /// half the mode's `bytes_per_fragment` (which counts a read and a write), so 4, 8 or 16
    /// per pixel for rgba8, f16, f32; 0 for scenes without discoids \[bytes\].
    pub accumulation_bytes: u64,
    /// Primitive (parameter) storage, `primitives.bytes` \[bytes\].
    pub primitive_bytes: u64,
    /// FIFO capacity of the instantiated links: over every link (one per producer and
    /// consumer pair at each boundary), its `fifo_depth`. Item sizes are not modelled, so
    /// this is entries, not bytes; null in functional mode \[entries\].
    pub fifo_entries: Option<u64>,
    /// framebuffer_bytes + accumulation_bytes + primitive_bytes (the FIFOs are in entries
    /// and not included) \[bytes\].
    pub total_bytes: u64,
}

impl Memory {
    /// The memory section from its parts; the total is derived.
    pub fn new(
        framebuffer_bytes: u64,
        accumulation_bytes: u64,
        primitive_bytes: u64,
        fifo_entries: Option<u64>,
    ) -> Memory {
        Memory {
            framebuffer_bytes,
            accumulation_bytes,
            primitive_bytes,
            fifo_entries,
            total_bytes: framebuffer_bytes + accumulation_bytes + primitive_bytes,
        }
    }
}

/// Measurements of the simulator itself on this host (not deterministic).
#[derive(Clone, Debug, Serialize)]
pub struct Host {
    /// Wall time of the render, without the reference \[s\].
    pub wall_seconds: f64,
    /// Fragments generated per wall second of the render.
    pub fragments_per_second: f64,
    /// Simulated cycles per wall second of the timed render; null in functional mode.
    pub simulated_cycles_per_second: Option<f64>,
    /// Host threads the run drew its frame on: the timed model's (`--host-threads`), or a
    /// functional surface frame's (`--threads`; 1 for the frame measured against the
    /// reference); null for discoid scenes in functional mode.
    pub host_threads: Option<u32>,
    /// Wall time of the reference and metrics \[s\]; null without `--reference`.
    pub reference_wall_seconds: Option<f64>,
    /// Of that, the accuracy metrics (the sub-pixel silhouette's reference queries and the
    /// see-through check included) \[s\]; null without `--reference`.
    pub metrics_wall_seconds: Option<f64>,
    /// Side of the screen tiles the reference binned its lembos into (`--reference-tile`)
    /// \[pixels\]; null without `--reference`.
    pub reference_tile_px: Option<u32>,
    /// Host threads the reference's metrics ran on (`--reference-threads`, else the
    /// machine's cores or a sweep's `--jobs`); null without `--reference`.
    pub reference_threads: Option<u32>,
    /// Peak resident set of the simulator process so far (Linux `VmHWM`; null elsewhere).
    /// For `render`, read after the images are encoded, just before the report is written;
    /// a sweep's runs share one process, so theirs is the process's peak \[bytes\].
    pub peak_rss_bytes: Option<u64>,
}

/// The peak resident set of this process (`VmHWM` of /proc/self/status) \[bytes\]; None
/// where there is no such file.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kib = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .strip_suffix("kB")?
        .trim()
        .parse::<u64>()
        .ok()?;
    Some(kib * 1024)
}

/// PNG bytes of an RGB image.
///
/// The encoder's default compression in `image` 0.25 is already its fast one (fdeflate,
/// adaptive filtering): asking for `CompressionType::Fast` gives the same bytes (checked
/// 2026-11-26 on the bunny at 1024x1024), so there is no faster setting to choose.
pub fn png_bytes(img: &image::RgbImage) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .expect("encoding a PNG into memory cannot fail");
    out.into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_rss_is_read_where_proc_exists() {
        let rss = peak_rss_bytes();
        if std::path::Path::new("/proc/self/status").exists() {
            // At least the test binary's own pages, and not absurdly many.
            let rss = rss.expect("VmHWM is in /proc/self/status");
            assert!((1 << 20..1 << 40).contains(&rss), "{rss}");
        } else {
            assert_eq!(rss, None);
        }
    }

    #[test]
    fn memory_total_is_the_byte_figures_without_the_fifo_entries() {
        let m = Memory::new(11, 4, 144, Some(1000));
        assert_eq!(m.total_bytes, 159);
    }
}
