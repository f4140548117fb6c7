//! The side-by-side table of a compare, once for `compare.txt` and `report.html`: its
//! title, rows and notes ([`rows`]), the printed text ([`table`]) and the page.

use super::matching::{Level, MatchReport};
use super::report::CompareReport;
use crate::report::{html, Report};
use std::fmt::Write as _;

/// The side-by-side comparison, once, for compare.txt and report.html: a title, rows of
/// (name, lembo, triangle) and notes below.
pub struct Table {
    /// What was compared, on which architecture, at which k and tessellation.
    pub title: String,
    /// One row per quantity: its name, the lembo path's value and the triangle path's.
    pub rows: Vec<[String; 3]>,
    /// Lines under the rows: the ratios and, for a search, the levels tried and how close
    /// the chosen one came.
    pub notes: Vec<String>,
}

/// The side-by-side table: primitives, vertices, bytes, cycles, fragments, then every
/// accuracy metric, per path.
pub fn rows(r: &CompareReport) -> Table {
    let (l, tr) = (&r.lembo, &r.triangle);
    let title = title(r);
    let mut rows: Vec<[String; 3]> = Vec::new();
    // A row with one value per report.
    let mut both = |name: &str, value: &dyn Fn(&Report) -> String| {
        rows.push([name.to_string(), value(l), value(tr)])
    };
    both("primitives", &|r| r.primitives.count.to_string());
    both("vertices", &|r| r.primitives.vertices.to_string());
    // What the geometry fetch read through the memory port (a mesh's vertices once per
    // vertex-cache miss), and the primitive data as it lies in memory.
    both("primitive bytes fetched", &|r| {
        r.fetch
            .as_ref()
            .map_or_else(|| "-".into(), |f| f.bytes.to_string())
    });
    both("primitive bytes stored", &|r| {
        r.primitives.bytes.to_string()
    });
    both("cycles per frame", &|r| {
        r.cycles
            .as_ref()
            .map_or_else(|| "-".into(), |c| c.total.to_string())
    });
    both("bottleneck", &|r| {
        r.cycles
            .as_ref()
            .and_then(|c| c.bottleneck.clone())
            .unwrap_or_else(|| "-".into())
    });
    both("area mm2", &|r| {
        r.cost
            .as_ref()
            .map_or_else(|| "-".into(), |c| format!("{:.3}", c.area_mm2))
    });
    both("energy uJ/frame", &|r| {
        r.cost
            .as_ref()
            .map_or_else(|| "-".into(), |c| format!("{:.1}", c.energy_pj * 1e-6))
    });
    both("  of it on chip uJ", &|r| {
        r.cost.as_ref().map_or_else(
            || "-".into(),
            |c| format!("{:.1}", c.on_chip_energy_pj() * 1e-6),
        )
    });
    both("  of it DRAM uJ", &|r| {
        r.cost.as_ref().map_or_else(
            || "-".into(),
            |c| format!("{:.1}", c.dram_energy_pj() * 1e-6),
        )
    });
    both("fragments", &|r| r.counts.fragments.to_string());
    rows.push([
        "quad efficiency".to_string(),
        "-".into(),
        tr.primitives
            .quad_efficiency
            .map(|q| format!("{:.1} %", 100.0 * q))
            .unwrap_or_else(|| "-".into()),
    ]);
    if let (Some(a), Some(b)) = (&l.accuracy, &tr.accuracy) {
        for ((name, va), (_, vb)) in a.lines().into_iter().zip(b.lines()) {
            rows.push([name, va, vb]);
        }
    }
    let mut notes = Vec::new();
    if let Some(x) = &r.ratios {
        let pixel = |c: Option<f64>| c.map_or_else(|| "-".into(), |c| format!("{c:.3}"));
        rows.push([
            "cycles per primitive".to_string(),
            format!("{:.1}", x.cycles_per_lembo),
            format!("{:.2}", x.cycles_per_triangle),
        ]);
        rows.push([
            "cycles per covered pixel".to_string(),
            pixel(x.lembo_cycles_per_covered_pixel),
            pixel(x.triangle_cycles_per_covered_pixel),
        ]);
        notes.push(format!(
            "triangle/lembo: cycles per frame {:.2}, primitive bytes fetched {:.2} (stored {:.2}); lembo/triangle cycles per primitive {:.2} ({})",
            x.triangle_over_lembo_cycles,
            x.triangle_over_lembo_bytes_fetched,
            x.triangle_over_lembo_bytes,
            x.lembo_over_triangle_cycles_per_primitive,
            if r.tess.level == 1 {
                "at n = 1 a triangle spans its lembo's corners: the paper's \"a lembo costs 2-3 triangles\" compares this".to_string()
            } else {
                format!("per primitive, not per surface: at n = {} a lembo's surface is {} triangles", r.tess.level, r.tess.level * r.tess.level)
            }
        ));
    }
    if let Some(m) = &r.matched {
        notes.extend(match_notes(m));
    }
    Table { title, rows, notes }
}

/// The table's title: the scene, its size, the architecture, k and n, and how the searched
/// knob was chosen beside it.
fn title(r: &CompareReport) -> String {
    let l = &r.lembo;
    // How the searched knob was chosen, said beside it.
    let how = |path: &str| {
        r.matched
            .as_ref()
            .filter(|m| m.searched_path == path)
            .map(|m| {
                let target = format!(
                    "{} {} {}, the {} run's",
                    m.field,
                    m.relation,
                    m.metric.value(m.target),
                    m.target_path
                );
                match m.start {
                    Level::Tess(_) => format!(" (auto: smallest n with {target})"),
                    Level::K(k) => format!(" (matched: largest k from {k} px with {target})"),
                }
            })
            .unwrap_or_default()
    };
    format!(
        "compare {} ({}x{} px), architecture {}, k = {} px{}, tessellation {}{}",
        l.scene.name,
        l.scene.width,
        l.scene.height,
        l.arch.as_ref().map(|a| a.name.as_str()).unwrap_or("-"),
        l.settings.k_px.unwrap_or_default(),
        how("lembo"),
        r.tess.level,
        how("triangle"),
    )
}

/// The notes of a match: what was searched for and the levels tried, and how close the
/// chosen level came.
fn match_notes(m: &MatchReport) -> [String; 2] {
    let tried: Vec<String> = m
        .tried
        .iter()
        .map(|s| format!("{} {}", s.level, m.metric.value(s.value)))
        .collect();
    let searched = format!(
            "match ({}): the {} path's {} searched for {} {} the {} run's {}; tried (functional model) {}",
            m.metric.name(),
            m.searched_path,
            match m.start {
                Level::Tess(_) => "n",
                Level::K(_) => "k",
            },
            m.field,
            m.relation,
            m.target_path,
            m.metric.value(m.target),
            tried.join(", ")
        );
    [searched, format!("matched: {}", m.summary)]
}

/// The table as compare.txt and the command print it.
pub fn table(r: &CompareReport) -> String {
    let Table { title, rows, notes } = rows(r);
    let mut t = String::new();
    let _ = writeln!(t, "{title}");
    let _ = writeln!(t, "{:<28} {:>18} {:>18}", "", "lembo", "triangle");
    for [name, a, b] in rows {
        let _ = writeln!(t, "{name:<28} {a:>18} {b:>18}");
    }
    for note in notes {
        let _ = writeln!(t, "{note}");
    }
    t
}

/// The compare's `report.html`: the seven images and the montage, links to compare.json and
/// compare.txt, the table, and each path's report.
pub(super) fn page(r: &CompareReport) -> String {
    let Table { title, rows, notes } = rows(r);
    let figures: String = [
        ("lembo.png", "lembo path".to_string()),
        (
            "triangle.png",
            format!("triangle path, tessellation {}", r.tess.level),
        ),
        ("reference.png", "exact reference".to_string()),
        (
            "lembo_error.png",
            format!("lembo {}", html::ERROR_MAP_CAPTION),
        ),
        (
            "triangle_error.png",
            format!("triangle {}", html::ERROR_MAP_CAPTION),
        ),
        (
            "lembo_flip.png",
            format!("lembo path's {}", html::flip_map_caption(&r.lembo)),
        ),
        (
            "triangle_flip.png",
            format!("triangle path's {}", html::flip_map_caption(&r.triangle)),
        ),
        (
            "montage.png",
            "montage: the two paths' images, the reference and the two error maps side by \
             side, labelled with cycles, PSNR, FLIP and the silhouette error"
                .to_string(),
        ),
    ]
    .iter()
    .map(|(file, caption)| html::figure(file, caption, false))
    .collect::<String>()
        + &html::file_links(&["compare.json", "compare.txt"]);
    let rows: Vec<Vec<String>> = rows.into_iter().map(Vec::from).collect();
    let notes: String = notes.iter().map(|n| html::para(n)).collect();
    let body = html::section("Images", &figures)
        + &html::section(
            "Side by side",
            &(html::table(&["", "lembo", "triangle"], &rows) + &notes),
        )
        + &html::section("Lembo path", &html::report_sections(&r.lembo, None, 3))
        + &html::section(
            "Triangle path",
            &html::report_sections(&r.triangle, None, 3),
        );
    html::page(
        &format!("lembo-sim compare: {}", r.lembo.scene.name),
        &title,
        &body,
    )
}
