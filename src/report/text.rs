//! A report in words: `report.txt` ([`Report::to_text`]) and the lines a command prints
//! when it ends ([`Report::summary`]). Both read only the [`Report`], so what a person reads
//! is what `report.json` says; each section of `report.txt` has its own writer below.

use super::Report;
use crate::cost::model::{BlendCost, CostReport, OpCounts};
use crate::datapath::OPS;
use crate::pipeline::rop_memory::MemoryReport;
use crate::pipeline::{Cycle, FetchReport};
use std::fmt::Write as _;

/// Bytes in a mebibyte, for report.txt.
const MIB: f64 = (1u64 << 20) as f64;

/// A unit's functional units as words ("2 add, 1 mul"), or "-" for none.
pub(crate) fn functional_units(counts: &OpCounts) -> String {
    let fus: Vec<String> = OPS
        .iter()
        .zip(counts.to_array())
        .filter(|(_, n)| *n > 0)
        .map(|(op, n)| format!("{n} {}", op.name()))
        .collect();
    if fus.is_empty() {
        "-".to_string()
    } else {
        fus.join(", ")
    }
}

impl Report {
    /// The human-readable `report.txt`.
    pub fn to_text(&self) -> String {
        let mut t = String::new();
        self.write_scene(&mut t);
        self.write_counts(&mut t);
        self.write_cycles(&mut t);
        self.write_cost(&mut t);
        self.write_blend(&mut t);
        self.write_memory(&mut t);
        self.write_accuracy(&mut t);
        self.write_host(&mut t);
        t
    }

    /// The summary `render` prints: what was drawn, its cost on the model that ran, and
    /// its accuracy when measured; one line each, without the final newline's file list.
    pub fn summary(&self) -> String {
        let mut t = String::new();
        self.summarise_drawing(&mut t);
        self.summarise_timing(&mut t);
        self.summarise_cost(&mut t);
        self.summarise_accuracy(&mut t);
        t
    }

    /// Title, scene, settings and primitives.
    fn write_scene(&self, t: &mut String) {
        let s = &self.scene;
        let _ = writeln!(t, "lembo-sim report (schema {})", self.schema_version);
        let _ = writeln!(
            t,
            "scene     {} ({}), {}x{} px, {} lembos",
            s.name, s.source, s.width, s.height, s.lembos
        );
        for o in &s.objects {
            let _ = writeln!(t, "          - {o}");
        }
        let st = &self.settings;
        let _ = writeln!(
            t,
            "settings  mode {}, path {}, {}{}, datapath {}, reference {}{}",
            st.mode,
            st.path,
            match (st.k_px, st.tess) {
                (Some(k), _) => format!("k = {k} px"),
                (None, Some(n)) => format!("tessellation {n} ({} triangles per lembo)", n * n),
                (None, None) => String::new(),
            },
            match st.samples {
                1 => String::new(),
                n => format!(", {n} samples a pixel (multisampled, resolved)"),
            },
            st.datapath,
            if st.reference { "yes" } else { "no" },
            if st.reference && st.supersample > 1 {
                format!(" ({0}x{0} samples)", st.supersample)
            } else {
                String::new()
            }
        );
        let p = &self.primitives;
        let _ = writeln!(
            t,
            "primitives {} {}s, {} vertices, {} bytes{}",
            p.count,
            p.kind,
            p.vertices,
            p.bytes,
            p.quad_efficiency
                .map(|q| format!(", quad efficiency {:.1} %", 100.0 * q))
                .unwrap_or_default()
        );
    }

    /// The counters of the path that ran.
    fn write_counts(&self, t: &mut String) {
        let heading = if self.cycles.is_some() {
            "counts (timed pipeline, summed over its units: the same as the functional model's except fragments_passed_depth, the depth tests passed in the order the ROPs met the fragments)"
        } else {
            "counts (functional model)"
        };
        let _ = writeln!(t, "\n{heading}");
        if let Ok(serde_json::Value::Object(map)) = serde_json::to_value(self.counts) {
            let triangle = self.settings.path == "triangle";
            for (k, v) in map {
                let of_triangles = k.starts_with("triangles") || k == "quads";
                let of_lembos = !of_triangles
                    && !matches!(
                        k.as_str(),
                        "fragments" | "fragments_passed_depth" | "pixels_covered"
                    );
                if (triangle && of_lembos) || (!triangle && of_triangles) {
                    continue;
                }
                let _ = writeln!(t, "  {k:<28} {v}");
            }
        }
    }

    /// The frame's cycles and each unit's busy, starved and blocked share.
    fn write_cycles(&self, t: &mut String) {
        let Some(c) = &self.cycles else {
            let _ = writeln!(t, "\ncycles    n/a (functional mode)");
            return;
        };
        let _ = writeln!(
            t,
            "\ncycles    {} total at {} MHz = {} ({})",
            c.total,
            c.clock_mhz,
            c.fps
                .map(|f| format!("{f:.1} frames/s"))
                .unwrap_or_else(|| "empty frame".into()),
            self.arch
                .as_ref()
                .map(|a| format!("architecture {}", a.name))
                .unwrap_or_default()
        );
        if let Some(b) = &c.bottleneck {
            let _ = writeln!(t, "bottleneck {b} (most busy cycles)");
        }
        if let Some(f) = &self.fetch {
            let _ = writeln!(t, "{}", fetch_line(f));
        }
        if let Some(m) = &self.memory_system {
            let _ = writeln!(t, "{}", memory_line(m));
        }
        let _ = writeln!(
            t,
            "  {:<22} {:>10} {:>6} {:>10} {:>6} {:>10} {:>6} {:>9} {:>9} {:>5}",
            "unit", "busy", "%", "starved", "%", "blocked", "%", "in", "out", "fifo"
        );
        let pct = |x: Cycle| c.percent(x);
        for u in &c.units {
            let _ = writeln!(
                t,
                "  {:<22} {:>10} {:>6.1} {:>10} {:>6.1} {:>10} {:>6.1} {:>9} {:>9} {:>5}",
                u.name,
                u.busy,
                pct(u.busy),
                u.starved,
                pct(u.starved),
                u.blocked,
                pct(u.blocked),
                u.items_in,
                u.items_out,
                u.max_fifo_occupancy
            );
        }
    }

    /// The unit's area and energy, instance by instance (DESIGN.md §12).
    fn write_cost(&self, t: &mut String) {
        let Some(c) = &self.cost else {
            let _ = writeln!(t, "\ncost      n/a (functional mode)");
            return;
        };
        let _ = writeln!(t, "\ncost      {}", cost_head(c, "mm2", "uJ", "as"));
        if let Some(b) = &c.blend {
            let _ = writeln!(t, "  {}", blend_cost(b));
        }
        let _ = writeln!(
            t,
            "  {:<22} {:>9} {:>9} {:>10} {:>9} {:>9}  functional units",
            "unit", "mm2", "fifo mm2", "uJ", "fifo uJ", "leak uJ"
        );
        for u in &c.units {
            let _ = writeln!(
                t,
                "  {:<22} {:>9.4} {:>9.4} {:>10.3} {:>9.3} {:>9.3}  {}",
                u.name,
                u.area_mm2,
                u.fifo_area_mm2,
                u.energy_pj * 1e-6,
                u.fifo_energy_pj * 1e-6,
                u.fifo_leakage_pj * 1e-6,
                functional_units(&u.functional_units)
            );
        }
    }

    /// The blend units' counters, for a discoid scene.
    fn write_blend(&self, t: &mut String) {
        let Some(section) = &self.blend else { return };
        let b = &section.blend;
        let _ = writeln!(
            t,
            "\nblend     {} ({} bytes per fragment), threshold {} world units",
            b.mode, b.bytes_per_fragment, b.threshold
        );
        if let Ok(serde_json::Value::Object(map)) = serde_json::to_value(section) {
            for (k, v) in map {
                if !matches!(k.as_str(), "mode" | "bytes_per_fragment" | "threshold") {
                    let _ = writeln!(t, "  {k:<28} {v}");
                }
            }
        }
    }

    /// The memory the unit holds.
    fn write_memory(&self, t: &mut String) {
        let m = &self.memory;
        let _ = writeln!(
            t,
            "\nmemory    {} bytes: frame buffer {}, accumulation {}, primitives {}; FIFOs {}",
            m.total_bytes,
            m.framebuffer_bytes,
            m.accumulation_bytes,
            m.primitive_bytes,
            m.fifo_entries
                .map(|e| format!("{e} entries"))
                .unwrap_or_else(|| "n/a (functional mode)".into())
        );
    }

    /// The accuracy against the exact reference, when measured.
    fn write_accuracy(&self, t: &mut String) {
        match &self.accuracy {
            Some(a) => {
                let _ = writeln!(t, "\naccuracy against the exact reference");
                for (k, v) in a.lines() {
                    let _ = writeln!(t, "  {k:<26} {v}");
                }
            }
            None => {
                let _ = writeln!(t, "\naccuracy  n/a (run with --reference)");
            }
        }
    }

    /// What the simulation cost the host.
    fn write_host(&self, t: &mut String) {
        let h = &self.host;
        let _ = writeln!(
            t,
            "\nhost      render {:.3} s, {:.1} M fragments/s{}{}{}{}",
            h.wall_seconds,
            h.fragments_per_second / 1e6,
            h.simulated_cycles_per_second
                .map(|c| format!(
                    ", {:.1} M simulated cycles/s on {} host thread{}",
                    c / 1e6,
                    h.host_threads.unwrap_or(1),
                    if h.host_threads == Some(1) { "" } else { "s" }
                ))
                .unwrap_or_default(),
            h.reference_wall_seconds
                .map(|r| format!(", reference {r:.3} s"))
                .unwrap_or_default(),
            h.metrics_wall_seconds
                .map(|m| format!(" (metrics {m:.3} s)"))
                .unwrap_or_default(),
            match (h.reference_tile_px, h.reference_threads) {
                (Some(tile), Some(threads)) =>
                    format!(", {tile} px tiles, {threads} reference threads"),
                _ => String::new(),
            }
        );
        if let Some(rss) = h.peak_rss_bytes {
            let _ = writeln!(
                t,
                "          peak resident memory {:.1} MiB",
                rss as f64 / MIB
            );
        }
    }

    /// The summary's first line: what was drawn, by which path, and its counts.
    fn summarise_drawing(&self, t: &mut String) {
        let r = self;
        let c = &r.counts;
        if let Some(b) = r.blend.as_ref().map(|s| &s.blend) {
            let _ = writeln!(
                t,
                "{}: {} discoids, {}x{} px, blend {} ({} bytes/fragment), threshold {}: {} fragments accumulated, {} beyond the threshold, {} beta = 0, {} back-facing, {} saturations; error max {:.4}, mean {:.5}{}",
                r.scene.name,
                r.primitives.count,
                r.scene.width,
                r.scene.height,
                b.mode,
                b.bytes_per_fragment,
                b.threshold,
                b.fragments_accumulated,
                b.discarded_threshold,
                b.discarded_beta_zero,
                b.culled_backface,
                b.saturations,
                b.error_max,
                b.error_mean,
                b.holes.map(|h| format!(", {h} holes")).unwrap_or_default()
            );
            return;
        }
        // Multisampled, the viewport is followed by its samples and the counts are the
        // sample grid's (a fragment is a sample).
        let px = match r.settings.samples {
            1 => "px".to_string(),
            n => format!("px x {n} samples"),
        };
        let _ = match r.settings.k_px {
            Some(k) => writeln!(
                t,
                "{}: {} lembos, {}x{} {px}, k = {} px, {}: {} scanlines, {} intervals, {} segments, {} subsegments, {} fragments ({} passed depth)",
                r.scene.name,
                r.scene.lembos,
                r.scene.width,
                r.scene.height,
                k,
                r.settings.datapath,
                c.scanlines,
                c.intervals,
                c.segments,
                c.subsegments,
                c.fragments,
                c.fragments_passed_depth
            ),
            None => writeln!(
                t,
                "{}: {} lembos as {} triangles (tessellation {}), {}x{} {px}, {}: {} culled, {} quads ({:.1} % efficiency), {} fragments ({} passed depth)",
                r.scene.name,
                r.scene.lembos,
                c.triangles,
                r.settings.tess.unwrap_or(1),
                r.scene.width,
                r.scene.height,
                r.settings.datapath,
                c.triangles_culled_behind_eye + c.triangles_culled_outside + c.triangles_degenerate,
                c.quads,
                100.0 * r.primitives.quad_efficiency.unwrap_or(0.0),
                c.fragments,
                c.fragments_passed_depth
            ),
        };
        if let Some(cull) = &r.settings.culling {
            let closed = match cull.closed_outward {
                Some(w) => format!("; scene closed, out {}", winding(w)),
                // `off` does not ask whether the scene is closed.
                None if cull.switch == "off" => String::new(),
                None => "; scene not closed".into(),
            };
            let _ = match cull.front {
                Some(front) => writeln!(
                    t,
                    "back-face culling ({}{closed}): front {}, {} lembos and {} triangles culled back-facing",
                    cull.switch,
                    winding(front),
                    c.lembos_culled_backface,
                    c.triangles_culled_backface
                ),
                None => writeln!(
                    t,
                    "back-face culling ({}{closed}): none culled back-facing",
                    cull.switch
                ),
            };
        }
    }

    /// The summary's timing line: cycles on the architecture, or the functional model's
    /// host speed.
    fn summarise_timing(&self, t: &mut String) {
        let r = self;
        let _ = match &r.cycles {
            Some(cy) => writeln!(
                t,
                "timed ({}): {} cycles = {} at {} MHz, bottleneck {}; host {:.3} s, {:.1} M simulated cycles/s",
                r.arch.as_ref().map(|a| a.name.as_str()).unwrap_or("?"),
                cy.total,
                cy.fps
                    .map(|f| format!("{f:.1} frames/s"))
                    .unwrap_or_else(|| "empty frame".into()),
                cy.clock_mhz,
                cy.bottleneck.as_deref().unwrap_or("none"),
                r.host.wall_seconds,
                r.host.simulated_cycles_per_second.unwrap_or(0.0) / 1e6
            ),
            None => writeln!(
                t,
                "render {:.3} s ({:.1} M fragments/s, functional model, {})",
                r.host.wall_seconds,
                r.host.fragments_per_second / 1e6,
                match r.host.host_threads {
                    Some(1) | None => "1 host thread".to_string(),
                    Some(n) => format!("{n} host threads"),
                }
            ),
        };
    }

    /// The summary's cost line, for a timed run.
    fn summarise_cost(&self, t: &mut String) {
        if let Some(c) = &self.cost {
            let _ = writeln!(
                t,
                "cost ({}, {} DRAM): {:.3} mm2, {:.1} uJ a frame{}",
                c.tech.name,
                c.framebuffer_dram
                    .map_or(c.tech.dram_kind.name(), |d| d.kind),
                c.area_mm2,
                c.energy_pj * 1e-6,
                c.power_mw
                    .map(|p| format!(", {p:.0} mW"))
                    .unwrap_or_default()
            );
            if let Some(b) = &c.blend {
                let _ = writeln!(t, "{}", blend_cost(b));
            }
        }
    }

    /// The summary's accuracy line, when the run was measured.
    fn summarise_accuracy(&self, t: &mut String) {
        let Some(a) = &self.accuracy else { return };
        let _ = writeln!(
            t,
            "accuracy: PSNR {:.2} dB, FLIP {:.4}, coverage +{} / -{} px, silhouette max {:.3} px, cracks {}, double hits {}{}{}",
            a.psnr_db,
            a.flip_mean,
            a.coverage_false_positive,
            a.coverage_false_negative,
            a.silhouette_max_px,
            a.crack_pixels,
            a.double_hit_pixels,
            a.see_through_px
                .map(|n| format!(", see-through {n} px"))
                .unwrap_or_default(),
            a.max_scanline_deviation_px
                .map(|d| format!(", max |y - y_j| {d:.4} px"))
                .unwrap_or_default()
        );
    }
}

/// The cost section's first sentence: area, energy, power, the energy on chip and in DRAM,
/// the technology and the DRAM bytes it priced; `mm2`, `uj` and `charged` spelled for the
/// page (text or HTML).
pub fn cost_head(c: &CostReport, mm2: &str, uj: &str, charged: &str) -> String {
    format!(
        "{:.3} {mm2}, {:.1} {uj} this frame{}: {:.1} {uj} on chip, {:.1} {uj} DRAM (technology {}; {} frame-buffer bytes{}, {} geometry bytes fetched, {charged} {} DRAM at {} pJ/B; SRAM leakage {:.3} {uj}, logic leakage {:.3} {uj})",
        c.area_mm2,
        c.energy_pj * 1e-6,
        c.power_mw
            .map(|p| format!(" = {p:.0} mW at the clock"))
            .unwrap_or_default(),
        c.on_chip_energy_pj() * 1e-6,
        c.dram_energy_pj() * 1e-6,
        c.tech.name,
        c.framebuffer_bytes,
        if c.blend.is_some() {
            format!(" and {} accumulation bytes", c.accumulation_bytes)
        } else {
            String::new()
        },
        c.geometry_bytes,
        c.tech.dram_kind.name(),
        c.tech.dram_pj_per_byte,
        c.sram_leakage_pj * 1e-6,
        c.logic_leakage_pj * 1e-6
    )
}

/// What the geometry fetch read, in a sentence: the source, primitives and bytes, and a
/// mesh's vertex caches.
pub fn fetch_line(f: &FetchReport) -> String {
    let cache = f
        .vertex_cache
        .map(|v| {
            let refs = (v.hits + v.misses).max(1);
            format!(
                "; vertex caches of {} entries: {} hits, {} misses ({:.1} % hit, {:.2} vertices read a triangle)",
                v.entries,
                v.hits,
                v.misses,
                100.0 * v.hits as f64 / refs as f64,
                v.misses as f64 / f.primitives.max(1) as f64
            )
        })
        .unwrap_or_default();
    format!(
        "geometry fetch ({}): {} primitives, {} bytes read through the memory port{cache}",
        f.source, f.primitives, f.bytes
    )
}

/// The DRAM memory model's frame in two sentences: where the bytes went.
pub fn memory_line(m: &MemoryReport) -> String {
    let r = &m.rops;
    format!(
        "memory system ({}, {} channel{}): ROP caches hit {:.1} % (colour) and {:.1} % (depth); \
         write-backs compressed {:.2}:1 (colour) and {:.2}:1 (depth); {} tiles still cleared; \
         hierarchical Z rejected {} of {} spans or pieces\n\
         DRAM: {} atoms of {} bytes read ({} by the geometry fetch), {} written, {} row \
         activations, {:.1} % row hits, mean read latency {:.0} DRAM cycles ({:.0} for the \
         ROPs' reads)",
        m.dram,
        m.channels,
        if m.channels == 1 { "" } else { "s" },
        100.0 * m.colour_cache_hit_rate,
        100.0 * m.depth_cache_hit_rate,
        m.colour_compression_ratio,
        m.depth_compression_ratio,
        r.cleared_tiles,
        r.depth.hz_rejects,
        r.depth.hz_tests,
        m.atoms_read,
        m.atom_bytes,
        m.geometry_atoms_read,
        m.atoms_written,
        m.activations,
        100.0 * m.row_hit_rate,
        m.read_latency_mean,
        m.rop_read_latency_mean,
    )
}

/// The blend units' cost in a sentence: what the precision modes trade (DESIGN.md §12).
pub fn blend_cost(b: &BlendCost) -> String {
    format!(
        "blend units {} (priced as {}): {:.4} mm2, {} per fragment blended; accumulation {} bytes a pixel, {:.1} uJ as DRAM",
        b.mode,
        b.priced_as,
        b.area_mm2,
        b.energy_pj_per_fragment
            .map(|e| format!("{e:.2} pJ"))
            .unwrap_or_else(|| "n/a".into()),
        b.accumulation_bytes_per_pixel,
        b.accumulation_energy_pj * 1e-6
    )
}

/// A winding as architecture files and reports spell it.
fn winding(w: crate::camera::Winding) -> &'static str {
    match w {
        crate::camera::Winding::Ccw => "ccw",
        crate::camera::Winding::Cw => "cw",
    }
}
