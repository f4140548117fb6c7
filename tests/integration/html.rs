//! report.html in a real browser: headless Chromium (from the distribution's packages;
//! `.ci/run` installs it) opens the page of a render, a compare and a sweep. Each page
//! loads without a console message (the pages run no script, so any message is an error),
//! every file it links to exists beside it, and its screenshot is not blank.

use crate::support::binary::{files_in, run};
use std::path::{Path, PathBuf};
use std::process::Command;

fn manifest() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The browser, or None (after checking this is not CI, where it must be present).
fn chromium() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| Command::new(b).arg("--version").output().is_ok());
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "Chromium is missing; .ci/run installs it (apt-get install chromium)"
        );
        eprintln!("skipped: Chromium is not installed (apt-get install chromium)");
    }
    found
}

/// What the browser made of a page: its console lines and its screenshot.
struct Visit {
    console: Vec<String>,
    screenshot: image::RgbaImage,
}

/// Opens `page` in headless Chromium, with a fresh profile and no network, and takes a
/// screenshot of its first `height` pixels.
fn visit(browser: &str, page: &Path, height: u32) -> Visit {
    let tmp = tempfile::tempdir().unwrap();
    let shot = tmp.path().join("shot.png");
    let page = std::path::absolute(page).unwrap();
    let out = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--v=0",
            "--hide-scrollbars",
        ])
        .arg(format!(
            "--user-data-dir={}",
            tmp.path().join("profile").display()
        ))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("--window-size=1280,{height}"))
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("the browser runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        shot.exists(),
        "no screenshot of {}: {stderr}",
        page.display()
    );
    Visit {
        console: stderr
            .lines()
            .filter(|l| l.contains(":CONSOLE"))
            .map(str::to_string)
            .collect(),
        screenshot: image::open(&shot).unwrap().to_rgba8(),
    }
}

/// The local files a page links to or shows (`src` and `href` that are not web addresses
/// or fragments), percent-decoded, relative to its folder.
fn linked_files(html: &str) -> Vec<String> {
    let mut found = Vec::new();
    for attr in ["src=\"", "href=\""] {
        for piece in html.split(attr).skip(1) {
            let target = &piece[..piece.find('"').unwrap()];
            if target.starts_with("http") || target.starts_with('#') {
                continue;
            }
            found.push(decode(target));
        }
    }
    found.sort();
    found.dedup();
    found
}

fn decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            out.push(u8::from_str_radix(&s[i + 1..i + 3], 16).unwrap());
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).unwrap()
}

/// Whether a screenshot shows something: not one flat colour, and more than a page of
/// white with a heading (at least 2 % of its pixels far from white, 64 colours or more).
fn not_blank(img: &image::RgbaImage) -> Result<(), String> {
    let mut colours = std::collections::HashSet::new();
    let mut inked = 0usize;
    for p in img.pixels() {
        colours.insert(p.0);
        if p.0[..3].iter().map(|&c| 255 - c as u32).sum::<u32>() > 96 {
            inked += 1;
        }
    }
    let share = inked as f64 / (img.width() * img.height()) as f64;
    if colours.len() < 64 || share < 0.02 {
        return Err(format!(
            "{} colours, {:.1} % of pixels inked",
            colours.len(),
            100.0 * share
        ));
    }
    Ok(())
}

/// The checks on one page, with the files it must show.
fn check_page(browser: &str, dir: &Path, must_show: &[&str]) {
    let page = dir.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    let linked = linked_files(&html);
    for name in must_show {
        assert!(
            linked.iter().any(|l| l == name),
            "{} does not show {name}: {linked:?}",
            page.display()
        );
    }
    for name in &linked {
        assert!(
            dir.join(name).is_file(),
            "{} names {name}, which is not there",
            page.display()
        );
    }
    assert!(!html.contains("<script"), "the pages run no script");
    let v = visit(browser, &page, 1800);
    assert!(
        v.console.is_empty(),
        "{}: console: {:?}",
        page.display(),
        v.console
    );
    not_blank(&v.screenshot).unwrap_or_else(|e| panic!("{} looks blank: {e}", page.display()));
}

#[test]
fn the_checks_see_a_console_error_a_missing_file_and_a_blank_page() {
    let Some(browser) = chromium() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let page = tmp.path().join("p.html");
    std::fs::write(
        &page,
        "<!DOCTYPE html><html><body><img src=\"gone%20away.png\">\
         <script>console.error('boom')</script></body></html>",
    )
    .unwrap();
    let v = visit(browser, &page, 400);
    assert!(
        v.console.iter().any(|l| l.contains("boom")),
        "{:?}",
        v.console
    );
    assert!(not_blank(&v.screenshot).is_err(), "a white page is blank");
    let html = std::fs::read_to_string(&page).unwrap();
    assert_eq!(linked_files(&html), ["gone away.png"]);
}

#[test]
fn render_compare_and_sweep_pages_load_whole_in_a_browser() {
    let Some(browser) = chromium() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let scene = |name: &str| manifest().join("traces").join(name);
    let ok = |args: &[&str]| {
        let out = run(args, tmp.path());
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };

    // A timed render with its reference, error map and a trace in another folder.
    let bunny = scene("bunny.json");
    ok(&[
        "render",
        bunny.to_str().unwrap(),
        "--reference",
        "--viewport",
        "256x256",
        "--trace-out",
        "traces out/bunny trace.json",
        "--out",
        "r",
    ]);
    check_page(
        browser,
        &tmp.path().join("r"),
        &[
            "image.png",
            "reference.png",
            "error.png",
            "flip.png",
            "report.json",
            "report.txt",
            "../traces out/bunny trace.json",
        ],
    );
    let html = std::fs::read_to_string(tmp.path().join("r/report.html")).unwrap();
    for part in [
        "busy / starved / blocked",
        "Cost: area and energy",
        "ui.perfetto.dev",
        "k_px",
    ] {
        assert!(html.contains(part), "the render page has no {part}");
    }

    // A discoid scene: no reference, no cycles table in functional mode.
    ok(&[
        "render",
        scene("bunny_discoids.json").to_str().unwrap(),
        "--mode",
        "functional",
        "--viewport",
        "256x256",
        "--out",
        "d",
    ]);
    check_page(
        browser,
        &tmp.path().join("d"),
        &["image.png", "report.json", "report.txt"],
    );

    // A compare: both paths, the reference, both error maps, the montage and the data.
    ok(&[
        "compare",
        scene("sphere24.json").to_str().unwrap(),
        "--tess",
        "2",
        "--viewport",
        "256x256",
        "--out",
        "c",
    ]);
    check_page(
        browser,
        &tmp.path().join("c"),
        &[
            "lembo.png",
            "triangle.png",
            "reference.png",
            "lembo_error.png",
            "triangle_error.png",
            "lembo_flip.png",
            "triangle_flip.png",
            "montage.png",
            "compare.json",
            "compare.txt",
        ],
    );

    // A sweep: every plot it wrote, and its results as a table.
    let spec = manifest().join("sim/sweeps/smoke.json");
    ok(&["sweep", spec.to_str().unwrap(), "--out", "s"]);
    let dir = tmp.path().join("s");
    let plots: Vec<String> = files_in(&dir)
        .into_iter()
        .filter(|f| f.ends_with(".svg"))
        .collect();
    assert!(!plots.is_empty());
    let plots: Vec<&str> = plots.iter().map(String::as_str).collect();
    check_page(browser, &dir, &plots);
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let rows = html.matches("<tr>").count();
    assert_eq!(rows, 19 + 1, "smoke.json's 19 runs and a header");

    // A sweep with an area budget, answered by value: it ends with a summary on stdout,
    // and its page shows the answer and the table by value, linked.
    let spec = tmp.path().join("answer.json");
    std::fs::write(
        &spec,
        format!(
            r#"{{"name": "answer", "scenes": [{:?}], "viewport": [48, 48],
                "area_budget_mm2": 100, "by": "arch.framebuffer.bytes_per_cycle",
                "grid": [{{"path": ["lembo"], "k": [2, 1]}}, {{"path": ["triangle"], "tess": [1, 2]}}],
                "points": [{{"path": "lembo", "k": 1, "arch.framebuffer.bytes_per_cycle": 16}},
                           {{"path": "triangle", "tess": 2, "arch.framebuffer.bytes_per_cycle": 16}}]}}"#,
            scene("sphere24.json")
        ),
    )
    .unwrap();
    let out = run(&["sweep", "answer.json", "--out", "a"], tmp.path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "runs",
        "failed",
        "time",
        "answer (answer.md):",
        "sphere24: at equal area",
    ] {
        assert!(
            stdout.contains(needle),
            "the summary lacks `{needle}`:\n{stdout}"
        );
    }
    let dir = tmp.path().join("a");
    let table = "answer_by_arch_framebuffer_bytes_per_cycle.md";
    check_page(
        browser,
        &dir,
        &["answer.md", table, "speedup_psnr_db_sphere24.svg"],
    );
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    for part in [
        "The answer: lembos against triangles",
        "How the answer moves with",
    ] {
        assert!(html.contains(part), "the sweep page has no {part}");
    }
}
