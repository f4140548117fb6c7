//! `report.html`: one page a person opens in a browser for each render, compare and sweep
//! (OUTPUTS.md). A page is self-contained: its style is inline, it runs no script and
//! fetches nothing; the images it shows are the run's own files beside it, named by
//! relative links, so the folder can be moved or copied as a whole. What it says is read
//! from the same reports `report.json`, `compare.json` and `results.csv` hold.
//!
//! Builders here put reports into HTML; [`escape`] is applied to every piece of text that
//! comes from a report or a file name.

use super::{Host, Memory, Report};
use crate::cost::model::CostReport;
use crate::memory::cache::CacheStats;
use crate::memory::tiles::TableStats;
use crate::pipeline::rop_memory::MemoryReport;
use crate::pipeline::{Cycle, CycleReport};
use crate::reference::metrics::Accuracy;
use std::fmt::Write as _;
use std::path::Path;

/// The file name every page is written under.
pub const REPORT_HTML: &str = "report.html";

/// The page's style: plain, readable, printable; bars are coloured blocks.
const STYLE: &str = "
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:1.5em auto;max-width:1200px;padding:0 1em;color:#1b1b1b;background:#fff}
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ddd}
.sub{color:#555;margin-top:0}
table{border-collapse:collapse;margin:.5em 0;font-size:.9em}
th,td{padding:.2em .6em;border-bottom:1px solid #eee;text-align:right;white-space:nowrap}
th:first-child,td:first-child{text-align:left}th{background:#f4f4f4}
.scroll{overflow-x:auto;max-width:100%}
figure{display:inline-block;margin:.4em .8em .4em 0;vertical-align:top}
figure img{max-width:360px;height:auto;border:1px solid #ccc;image-rendering:pixelated}
figure.plot img{max-width:560px;image-rendering:auto}
figcaption{font-size:.85em;color:#444;max-width:360px}
.bar{display:flex;width:260px;height:12px;background:#e8e8e8;border:1px solid #ccc}
.bar span{display:block;height:100%}
.busy{background:#2b8a3e}.starved{background:#f0a202}.blocked{background:#c92a2a}
.key span{display:inline-block;width:.9em;height:.9em;margin:0 .3em 0 1em;vertical-align:middle}
pre{background:#f7f7f7;border:1px solid #e4e4e4;padding:.6em;font-size:.85em;overflow-x:auto}
";

/// Text made safe to put between tags or in an attribute.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A relative link's target, percent-encoded where a URL needs it (spaces, `#`, `?`, `%`
/// and anything outside ASCII), `/`-separated.
pub fn href(path: &str) -> String {
    let mut out = String::new();
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || b"/-_.~".contains(&b) {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

/// The link from a page in folder `dir` to the file `target`: relative when both resolve
/// under one root (always, on Unix), so that moving the two together keeps it working.
pub fn link_from(dir: &Path, target: &Path) -> String {
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (dir, target) = (absolute(dir), absolute(target));
    let (from, to): (Vec<_>, Vec<_>) = (dir.components().collect(), target.components().collect());
    let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = vec!["..".to_string(); from.len() - common];
    parts.extend(
        to[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    href(&parts.join("/"))
}

/// A whole page: `title`, a subtitle line and the body's sections.
pub fn page(title: &str, subtitle: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>{t}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{t}</h1>\n\
         <p class=\"sub\">{s}</p>\n{body}</body>\n</html>\n",
        t = escape(title),
        s = escape(subtitle),
    )
}

/// A section: a heading and its content (already HTML).
pub fn section(heading: &str, content: &str) -> String {
    section_at(2, heading, content)
}

/// A section under a heading of `level` (2 for `<h2>`).
pub fn section_at(level: u8, heading: &str, content: &str) -> String {
    format!("<h{level}>{}</h{level}>\n{content}\n", escape(heading))
}

/// A table of text cells; the first column is a row label, the rest are right-aligned.
pub fn table<S: AsRef<str>>(head: &[&str], rows: &[Vec<S>]) -> String {
    let mut t = String::from("<div class=\"scroll\"><table>\n<tr>");
    for h in head {
        let _ = write!(t, "<th>{}</th>", escape(h));
    }
    t.push_str("</tr>\n");
    for row in rows {
        t.push_str("<tr>");
        for cell in row {
            let _ = write!(t, "<td>{}</td>", escape(cell.as_ref()));
        }
        t.push_str("</tr>\n");
    }
    t.push_str("</table></div>\n");
    t
}

/// An image beside the page, with its caption; `plot` for a chart (smoothly scaled).
pub fn figure(file: &str, caption: &str, plot: bool) -> String {
    format!(
        "<figure{}><a href=\"{src}\"><img src=\"{src}\" alt=\"{alt}\"></a><figcaption>{cap}</figcaption></figure>\n",
        if plot { " class=\"plot\"" } else { "" },
        src = href(file),
        alt = escape(file),
        cap = escape(caption),
    )
}

/// A line of links to `files` beside the page that it does not show as images (the
/// reports and tables), so that every file of the run is one click from its page.
pub fn file_links(files: &[&str]) -> String {
    let links: Vec<String> = files
        .iter()
        .map(|f| format!("<a href=\"{}\">{}</a>", href(f), escape(f)))
        .collect();
    format!("<p>Files: {}</p>\n", links.join(", "))
}

/// A paragraph of text.
pub fn para(text: &str) -> String {
    format!("<p>{}</p>\n", escape(text))
}

/// JSON shown as it is in the report.
fn pre_json(value: &impl serde::Serialize) -> String {
    let text = serde_json::to_string_pretty(value).expect("a report part serialises");
    format!("<pre>{}</pre>\n", escape(&text))
}

/// Each unit's busy, starved and blocked cycles as a stacked bar over the frame's cycles,
/// with the numbers beside it (DESIGN.md §2 defines the three).
pub fn unit_bars(c: &CycleReport) -> String {
    let pct = |x: Cycle| c.percent(x);
    let mut t = String::from(
        "<p class=\"key\">of the frame's cycles:<span class=\"busy\"></span>busy\
         <span class=\"starved\"></span>starved (waiting for input)\
         <span class=\"blocked\"></span>blocked (output full); grey: finished or idle</p>\n\
         <div class=\"scroll\"><table>\n<tr><th>unit</th><th>busy / starved / blocked</th>\
         <th>busy</th><th>%</th><th>starved</th><th>%</th><th>blocked</th><th>%</th>\
         <th>items in</th><th>items out</th><th>max FIFO</th></tr>\n",
    );
    for u in &c.units {
        let _ = writeln!(
            t,
            "<tr><td>{}</td><td><div class=\"bar\" title=\"busy {:.1} %, starved {:.1} %, blocked {:.1} %\">\
             <span class=\"busy\" style=\"width:{:.2}%\"></span>\
             <span class=\"starved\" style=\"width:{:.2}%\"></span>\
             <span class=\"blocked\" style=\"width:{:.2}%\"></span></div></td>\
             <td>{}</td><td>{:.1}</td><td>{}</td><td>{:.1}</td><td>{}</td><td>{:.1}</td>\
             <td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&u.name),
            pct(u.busy),
            pct(u.starved),
            pct(u.blocked),
            pct(u.busy).min(100.0),
            pct(u.starved).min(100.0),
            pct(u.blocked).min(100.0),
            u.busy,
            pct(u.busy),
            u.starved,
            pct(u.starved),
            u.blocked,
            pct(u.blocked),
            u.items_in,
            u.items_out,
            u.max_fifo_occupancy,
        );
    }
    t.push_str("</table></div>\n");
    t
}

/// The page's sections on one run, from its report: accuracy, cycles with the unit bars,
/// cost, blend, counts, memory, the trace link, the settings and architecture echo, and
/// the host; headings at `level`.
pub fn report_sections(r: &Report, trace: Option<&str>, level: u8) -> String {
    [
        r.accuracy.as_ref().map(accuracy_section),
        Some(cycles_section(r)),
        r.cost.as_ref().map(cost_section),
        r.blend.as_ref().map(|b| ("Blend units", pre_json(b))),
        Some(counts_section(r)),
        Some(memory_section(&r.memory)),
        trace.map(timeline_section),
        Some(settings_section(r)),
        r.arch.as_ref().map(|a| ("Architecture", pre_json(a))),
        Some(host_section(&r.host)),
    ]
    .into_iter()
    .flatten()
    .map(|(heading, content)| section_at(level, heading, &content))
    .collect()
}

/// The accuracy metrics against the exact reference: heading and content.
fn accuracy_section(a: &Accuracy) -> (&'static str, String) {
    let rows: Vec<Vec<String>> = a.lines().into_iter().map(|(k, v)| vec![k, v]).collect();
    (
        "Accuracy against the exact reference",
        table(&["metric", "value"], &rows),
    )
}

/// The frame's cycles, clock, frame rate and bottleneck with the unit bars, or why there
/// are none: heading and content.
fn cycles_section(r: &Report) -> (&'static str, String) {
    let content = match &r.cycles {
        Some(c) => {
            let head = format!(
                "{} cycles at {} MHz: {}; bottleneck {} (most busy cycles){}",
                c.total,
                c.clock_mhz,
                c.fps
                    .map(|f| format!("{f:.1} frames/s"))
                    .unwrap_or_else(|| "empty frame".into()),
                c.bottleneck.as_deref().unwrap_or("none"),
                r.arch
                    .as_ref()
                    .map(|a| format!(", architecture {}", a.name))
                    .unwrap_or_default()
            );
            let fetch = r
                .fetch
                .as_ref()
                .map(|f| para(&super::text::fetch_line(f)))
                .unwrap_or_default();
            let memory = r
                .memory_system
                .as_ref()
                .map(memory_table)
                .unwrap_or_default();
            para(&head) + &fetch + &memory + &unit_bars(c)
        }
        None => para("n/a: functional mode (no timing model ran)"),
    };
    ("Cycles", content)
}

/// Where the DRAM model's bytes went: each surface's sectors through the ROP caches, and
/// the DRAM's atoms.
fn memory_table(m: &MemoryReport) -> String {
    let r = &m.rops;
    let row = |name: &str, c: &CacheStats, t: &TableStats, ratio: f64| {
        vec![
            name.to_string(),
            (c.hits + c.misses).to_string(),
            format!("{:.1} %", 100.0 * c.hit_rate()),
            t.sectors_read.to_string(),
            t.sectors_cleared_not_read.to_string(),
            t.sectors_written.to_string(),
            format!("{ratio:.2}:1"),
        ]
    };
    para(&super::text::memory_line(m))
        + &table(
            &[
                "surface",
                "sectors touched",
                "cache hits",
                "sectors read (fills)",
                "fills found cleared",
                "sectors written back",
                "compression",
            ],
            &[
                row(
                    "colour",
                    &r.colour_cache,
                    &r.colour,
                    m.colour_compression_ratio,
                ),
                row("depth", &r.depth_cache, &r.depth, m.depth_compression_ratio),
            ],
        )
}

/// The unit's area and the frame's energy, unit by unit: heading and content.
fn cost_section(c: &CostReport) -> (&'static str, String) {
    let rows: Vec<Vec<String>> = c
        .units
        .iter()
        .map(|u| {
            vec![
                u.name.clone(),
                format!("{:.4}", u.area_mm2),
                format!("{:.4}", u.fifo_area_mm2),
                format!("{:.3}", u.energy_pj * 1e-6),
                format!("{:.3}", u.fifo_energy_pj * 1e-6),
                format!("{:.3}", u.fifo_leakage_pj * 1e-6),
                super::text::functional_units(&u.functional_units),
            ]
        })
        .collect();
    let head = super::text::cost_head(c, "mm²", "µJ", "charged as");
    let blend = c
        .blend
        .as_ref()
        .map(|b| para(&super::text::blend_cost(b)))
        .unwrap_or_default();
    let split = table(
        &["energy", "µJ", "of what"],
        &[
            vec![
                "on chip".to_string(),
                format!("{:.3}", c.on_chip_energy_pj() * 1e-6),
                "operations, FIFO accesses, SRAM and logic leakage".to_string(),
            ],
            vec![
                "DRAM".to_string(),
                format!("{:.3}", c.dram_energy_pj() * 1e-6),
                match &c.framebuffer_dram {
                    Some(d) => format!(
                        "frame buffer by atoms and activations ({:.3} µJ read, {:.3} written, {:.3} activations), geometry fetched {} bytes at {} pJ/B",
                        d.read_pj * 1e-6,
                        d.write_pj * 1e-6,
                        d.activation_pj * 1e-6,
                        c.geometry_bytes,
                        c.tech.dram_pj_per_byte
                    ),
                    None => format!(
                    "{} bytes through the memory port (frame buffer {}, accumulation {}, geometry fetched {}) at {} pJ/B",
                    c.framebuffer_bytes + c.accumulation_bytes + c.geometry_bytes,
                    c.framebuffer_bytes,
                    c.accumulation_bytes,
                    c.geometry_bytes,
                    c.tech.dram_pj_per_byte
                ),
                },
            ],
            vec![
                "total".to_string(),
                format!("{:.3}", c.energy_pj * 1e-6),
                String::new(),
            ],
        ],
    );
    (
        "Cost: area and energy (DESIGN.md §12)",
        para(&head)
            + &blend
            + &split
            + &table(
                &[
                    "unit",
                    "area mm²",
                    "of it FIFO mm²",
                    "energy µJ",
                    "of it FIFO µJ",
                    "of it FIFO leakage µJ",
                    "functional units",
                ],
                &rows,
            ),
    )
}

/// The counters, of the timed pipeline or of the functional model: heading and content.
fn counts_section(r: &Report) -> (&'static str, String) {
    let counts = serde_json::to_value(r.counts).expect("counts serialise");
    let rows: Vec<Vec<String>> = counts
        .as_object()
        .into_iter()
        .flatten()
        .map(|(k, v)| vec![k.clone(), v.to_string()])
        .collect();
    let heading = if r.cycles.is_some() {
        "Counts (timed pipeline, summed over its units)"
    } else {
        "Counts (functional model)"
    };
    (heading, table(&["counter", "value"], &rows))
}

/// The bytes the unit holds, part by part: heading and content.
fn memory_section(m: &Memory) -> (&'static str, String) {
    (
        "Memory the unit holds",
        table(
            &["part", "bytes"],
            &[
                vec!["frame buffer".to_string(), m.framebuffer_bytes.to_string()],
                vec!["accumulation".to_string(), m.accumulation_bytes.to_string()],
                vec!["primitives".to_string(), m.primitive_bytes.to_string()],
                vec!["total".to_string(), m.total_bytes.to_string()],
                vec![
                    "FIFO entries".to_string(),
                    m.fifo_entries
                        .map_or_else(|| "n/a".into(), |e| e.to_string()),
                ],
            ],
        ),
    )
}

/// The link to the run's trace and how to open it: heading and content.
fn timeline_section(trace: &str) -> (&'static str, String) {
    (
        "Timeline",
        format!(
            "<p><a href=\"{trace}\">The trace of this run</a> is Chrome trace-event JSON: \
             open <a href=\"https://ui.perfetto.dev\">ui.perfetto.dev</a>, choose \
             \u{201c}Open trace file\u{201d} and pick it (it stays on your machine); \
             <code>chrome://tracing</code> reads it too.</p>\n"
        ),
    )
}

/// The settings echoed, with the scene and its primitives: heading and content.
fn settings_section(r: &Report) -> (&'static str, String) {
    (
        "Settings",
        pre_json(&r.settings)
            + &para(&format!(
                "scene {} ({}), {}x{} px, {} lembos; {} {}s, {} vertices, {} bytes",
                r.scene.name,
                r.scene.source,
                r.scene.width,
                r.scene.height,
                r.scene.lembos,
                r.primitives.count,
                r.primitives.kind,
                r.primitives.vertices,
                r.primitives.bytes
            )),
    )
}

/// The host's wall time, rates and peak memory: heading and content.
fn host_section(h: &Host) -> (&'static str, String) {
    (
        "Host",
        para(&format!(
            "render {:.3} s, {:.1} M fragments/s{}{}",
            h.wall_seconds,
            h.fragments_per_second / 1e6,
            h.simulated_cycles_per_second
                .map(|c| format!(", {:.1} M simulated cycles/s", c / 1e6))
                .unwrap_or_default(),
            h.peak_rss_bytes
                .map(|b| format!(
                    ", peak resident memory {:.1} MiB",
                    b as f64 / (1u64 << 20) as f64
                ))
                .unwrap_or_default()
        )),
    )
}

/// The page of one render: its images, links to its other files, then [`report_sections`].
/// `images` are the files beside the page with their captions, `others` the rest of its
/// files (report.json, report.txt); `trace` the link to the timeline, if written.
pub fn render_page(
    r: &Report,
    images: &[(&str, String)],
    others: &[&str],
    trace: Option<&str>,
) -> String {
    let figures: String = images
        .iter()
        .map(|(file, caption)| figure(file, caption, false))
        .collect::<String>()
        + &file_links(others);
    let subtitle = format!(
        "render: {} path, {} mode, {}x{} px{}{}",
        r.settings.path,
        r.settings.mode,
        r.scene.width,
        r.scene.height,
        r.settings
            .k_px
            .map(|k| format!(", k = {k} px"))
            .or(r.settings.tess.map(|n| format!(", tessellation {n}")))
            .unwrap_or_default(),
        match r.settings.samples {
            1 => String::new(),
            n => format!(", {n} samples a pixel (multisampled, resolved)"),
        }
    );
    page(
        &format!("lembo-sim: {}", r.scene.name),
        &subtitle,
        &(section("Images", &figures) + &report_sections(r, trace, 2)),
    )
}

/// The caption of an error map: what its colours mean (the legend under it repeats it).
pub const ERROR_MAP_CAPTION: &str = "error map: black where the render equals the reference; \
     a logarithmic ramp from purple (1 level) to pale yellow (255 levels) for the largest \
     channel difference; cyan for pixels only the render covers, green for pixels only the \
     reference covers. The scale is under the image.";

/// The caption of a FLIP map (`flip.png`): what its colours mean, its mean and the observer.
pub fn flip_map_caption(r: &Report) -> String {
    let of = r
        .accuracy
        .as_ref()
        .map(|a| {
            format!(
                ": mean {:.4}, for an observer at {:.2} pixels per degree",
                a.flip_mean, a.flip_pixels_per_degree
            )
        })
        .unwrap_or_default();
    format!(
        "FLIP map (Andersson et al. 2020, the reference implementation), the perceived \
         difference from the reference per pixel in the reference's magma ramp: black for \
         none, through purple and orange to pale yellow for 1{of}."
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_links_are_encoded() {
        assert_eq!(
            escape("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
        assert_eq!(href("my plots/a#1.svg"), "my%20plots/a%231.svg");
        assert_eq!(href("é"), "%C3%A9");
    }

    #[test]
    fn a_link_to_a_file_elsewhere_climbs_out_of_the_page_folder() {
        assert_eq!(
            link_from(Path::new("/x/out/bunny"), Path::new("/x/out/bunny/t.json")),
            "t.json"
        );
        assert_eq!(
            link_from(Path::new("/x/out/bunny"), Path::new("/x/traces/t.json")),
            "../../traces/t.json"
        );
        assert_eq!(
            link_from(Path::new("out/a"), Path::new("out/b c.json")),
            "../b%20c.json"
        );
    }

    #[test]
    fn a_table_escapes_its_cells() {
        let t = table(&["a"], &[vec!["<b>"]]);
        assert!(t.contains("<td>&lt;b&gt;</td>"), "{t}");
    }
}
