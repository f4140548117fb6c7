//! Tests of the sweep plots: what each plot draws, and what it leaves out.

use super::chart::*;
use super::error::Labels;
use super::point::*;
use super::*;
use serde_json::json;

#[test]
fn pareto_front_of_nothing_is_empty() {
    assert!(pareto_front(&[]).is_empty());
}

#[test]
fn pareto_front_of_one_point_is_that_point() {
    assert_eq!(pareto_front(&[(3.0, 4.0)]), vec![0]);
}

#[test]
fn pareto_front_keeps_the_trade_off_in_ascending_x() {
    let points = [(5.0, 1.0), (1.0, 5.0), (3.0, 3.0), (4.0, 4.0), (6.0, 2.0)];
    assert_eq!(pareto_front(&points), vec![1, 2, 0]);
}

#[test]
fn pareto_front_ties_in_one_coordinate_are_dominated() {
    // (1, 2) beats (1, 3) on y and (2, 2) on x.
    let points = [(1.0, 3.0), (1.0, 2.0), (2.0, 2.0), (3.0, 1.0)];
    assert_eq!(pareto_front(&points), vec![1, 3]);
}

#[test]
fn pareto_front_keeps_every_duplicate_of_a_front_point() {
    let points = [(2.0, 2.0), (1.0, 3.0), (2.0, 2.0), (3.0, 3.0), (3.0, 3.0)];
    assert_eq!(pareto_front(&points), vec![1, 0, 2]);
}

#[test]
fn pareto_front_ignores_nan() {
    let points = [(f64::NAN, 0.0), (1.0, 1.0), (0.5, f64::NAN)];
    assert_eq!(pareto_front(&points), vec![1]);
}

#[test]
fn numbers_are_printed_with_three_significant_digits() {
    assert_eq!(fmt_num(52505.0), "52.5k");
    assert_eq!(fmt_num(2000.0), "2000");
    assert_eq!(fmt_num(0.00255), "0.00255");
    assert_eq!(fmt_num(0.5), "0.5");
    assert_eq!(fmt_num(1.0), "1");
    assert_eq!(fmt_num(1.5e6), "1.5M");
    assert_eq!(fmt_int(103_273), "103 273");
    assert_eq!(fmt_int(999), "999");
    assert_eq!(fmt_int(1_000_000), "1 000 000");
}

fn units(cycles: u64, busy: &[u64]) -> Value {
    let units: Vec<Value> = busy
        .iter()
        .enumerate()
        .map(|(i, &b)| {
            json!({"name": format!("Unit[{i}]"), "kind": "Unit", "busy": b,
                   "starved": (cycles - b) / 2, "blocked": cycles - b - (cycles - b) / 2})
        })
        .collect();
    json!({"total": cycles, "clock_mhz": 500.0, "units": units})
}

/// A sweep record as the sweep writes it, with only the fields the plots read and a few
/// they do not.
fn record(index: u64, params: Value, cycles: Option<u64>, psnr_db: Option<f64>) -> Value {
    let path = params["path"].as_str().unwrap().to_string();
    let k = params.get("k").cloned().unwrap_or(Value::Null);
    let tess = params.get("tess").cloned().unwrap_or(Value::Null);
    json!({
        "index": index,
        "key": format!("point-{index}"),
        "scene": "sphere24",
        "params": params,
        "report": {
            "schema_version": 3,
            "scene": {"name": "sphere24"},
            "settings": {"mode": if cycles.is_some() { "timed" } else { "functional" },
                         "path": path, "k_px": k, "tess": tess, "datapath": "f32"},
            "primitives": {"count": 24},
            "cycles": cycles.map(|c| units(c, &[c / 2, c / 4, c])),
            "accuracy": psnr_db.map(|p| json!({"psnr_db": p, "silhouette_mean_px": 1.0})),
        }
    })
}

fn sweep() -> Vec<Value> {
    let mut records = Vec::new();
    let mut i = 0;
    let mut push = |params: Value, cycles, psnr| {
        records.push(record(i, params, Some(cycles), Some(psnr)));
        i += 1;
    };
    for (k, cycles, psnr) in [
        (0.125, 70_000, 48.0),
        (0.5, 52_505, 42.6),
        (2.0, 45_000, 35.0),
    ] {
        for (datapath, extra) in [("f32", 0), ("f64", 1_000)] {
            push(
                json!({"path": "lembo", "k": k, "datapath": datapath,
                       "arch.segmenter.count": 2, "arch.rasterizer.count": 4}),
                cycles + extra,
                psnr,
            );
        }
    }
    for (n, cycles, psnr) in [(1, 39_819, 24.4), (4, 48_282, 38.3), (8, 60_000, 45.0)] {
        push(
            json!({"path": "triangle", "tess": n, "datapath": "f32",
                   "arch.segmenter.count": 2, "arch.rasterizer.count": 4}),
            cycles,
            psnr,
        );
    }
    for (segmenters, cycles) in [(1, 80_000), (4, 50_000)] {
        push(
            json!({"path": "lembo", "k": 0.5, "datapath": "f32",
                   "arch.segmenter.count": segmenters, "arch.rasterizer.count": 4}),
            cycles,
            42.6,
        );
    }
    for (rasterizers, cycles) in [(2, 90_000), (8, 40_000)] {
        push(
            json!({"path": "lembo", "k": 0.5, "datapath": "f32",
                   "arch.segmenter.count": 2, "arch.rasterizer.count": rasterizers}),
            cycles,
            42.6,
        );
    }
    records
}

/// Whether the SVG holds `text`, escaped as the SVG backend escapes it.
fn has(svg: &str, text: &str) -> bool {
    let escaped = text
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;");
    svg.contains(&escaped)
}

fn read_svg(dir: &Path, name: &str) -> String {
    let svg = std::fs::read_to_string(dir.join(name)).unwrap();
    assert!(svg.starts_with("<svg"), "{name}: {}", &svg[..40]);
    assert!(svg.trim_end().ends_with("</svg>"), "{name}");
    assert_eq!(
        svg.matches("<text").count(),
        svg.matches("</text>").count(),
        "{name}"
    );
    svg
}

#[test]
fn no_empty_plot_a_count_changed_only_with_another_gets_none() {
    // The default run, and one point changing two counts at once: neither count has a
    // second value where the other is held, so there is nothing to plot (the smoke
    // spec's case); defaults come from the reports' architecture echo.
    let arch = |seg: u64, rop: u64| json!({"segmenter": {"count": seg}, "rop": {"count": rop}});
    let mut a = record(0, json!({"path": "lembo", "k": 0.5}), Some(1000), None);
    a["report"]["arch"] = arch(2, 4);
    let mut b = record(
        1,
        json!({"path": "lembo", "k": 0.5, "arch.segmenter.count": 4, "arch.rop.count": 8}),
        Some(800),
        None,
    );
    b["report"]["arch"] = arch(4, 8);
    let names: Vec<String> = plot_files(&[a.clone(), b], None)
        .unwrap()
        .into_iter()
        .map(|(n, _)| n)
        .collect();
    assert!(
        !names.iter().any(|n| n.starts_with("cycles_vs_units")),
        "{names:?}"
    );
    // One count changed alone is drawn, its default read from the echo.
    let mut c = record(
        2,
        json!({"path": "lembo", "k": 0.5, "arch.rop.count": 8}),
        Some(900),
        None,
    );
    c["report"]["arch"] = arch(2, 8);
    let files = plot_files(&[a, c], None).unwrap();
    let (_, svg) = files
        .iter()
        .find(|(n, _)| n.starts_with("cycles_vs_units"))
        .expect("a plot of arch.rop.count");
    let svg = String::from_utf8(svg.clone()).unwrap();
    assert!(has(&svg, "arch.rop.count"));
}

#[test]
fn utilisation_captions_name_what_sets_a_point_apart_and_fit() {
    // A one-at-a-time sweep: the base, then one count changed per point.
    let arch = |seg: u64, rop: u64| json!({"segmenter": {"count": seg}, "rop": {"count": rop}});
    let mut base = record(0, json!({"path": "lembo", "k": 0.5}), Some(1000), None);
    base["report"]["arch"] = arch(2, 4);
    let mut slow = record(
        1,
        json!({"path": "lembo", "k": 0.5, "arch.segmenter.count": 1}),
        Some(3000),
        None,
    );
    slow["report"]["arch"] = arch(1, 4);
    let mut fast = record(
        2,
        json!({"path": "lembo", "k": 0.5, "arch.rop.count": 8}),
        Some(500),
        None,
    );
    fast["report"]["arch"] = arch(2, 8);
    let files = plot_files(&[base, slow, fast], None).unwrap();
    let svg = &files
        .iter()
        .find(|(n, _)| n.starts_with("utilisation"))
        .unwrap()
        .1;
    let svg = String::from_utf8(svg.clone()).unwrap();
    assert!(has(
        &svg,
        "most cycles: lembo path, k=0.5, arch.segmenter.count=1, point 1"
    ));
    assert!(has(
        &svg,
        "fewest cycles: lembo path, k=0.5, arch.rop.count=8, point 2"
    ));
    // Long captions are cut at a comma.
    let long = (0..40)
        .map(|i| format!("p{i}=1"))
        .collect::<Vec<_>>()
        .join(", ");
    let cut = fit(long, CAPTION_CHARS);
    assert!(
        cut.chars().count() <= CAPTION_CHARS && cut.ends_with(", …"),
        "{cut}"
    );
    assert_eq!(fit("short".into(), CAPTION_CHARS), "short");
}

#[test]
fn series_differing_in_datapath_have_their_own_marker_and_labels_do_not_overlap() {
    let records: Vec<Value> = [("f32", 0.5), ("f64", 0.5), ("f32", 2.0), ("f64", 2.0)]
        .iter()
        .enumerate()
        .map(|(i, &(dp, k))| {
            let mut r = record(
                i as u64,
                json!({"path": "lembo", "k": k, "datapath": dp}),
                Some(1000),
                Some(40.0),
            );
            r["report"]["settings"]["datapath"] = json!(dp);
            r
        })
        .collect();
    let files = plot_files(&records, None).unwrap();
    let svg = String::from_utf8(files[0].1.clone()).unwrap();
    assert!(has(&svg, "lembo path, datapath=f32"), "f32 series");
    assert!(has(&svg, "lembo path, datapath=f64"), "f64 series");
    // Labels: nearby points take free corners; the same text on the same spot once.
    let mut labels = Labels::default();
    let a = labels.place("k=2", (100, 100)).unwrap();
    let b = labels.place("k=0.5", (102, 101)).unwrap();
    assert_ne!(a, b);
    assert!(labels.place("k=2", (101, 100)).is_none());
    let boxes: Vec<[i32; 4]> = labels.placed.iter().map(|(_, _, r)| *r).collect();
    let overlap =
        |r: [i32; 4], q: [i32; 4]| r[0] < q[2] && q[0] < r[2] && r[1] < q[3] && q[1] < r[3];
    assert!(!overlap(boxes[0], boxes[1]));
}

#[test]
fn fifo_depths_get_their_own_plot() {
    let key = "arch.links.rasterizer_to_rop.fifo_depth";
    let records: Vec<Value> = [1u64, 4, 16, 64]
        .iter()
        .enumerate()
        .map(|(i, &d)| {
            record(
                i as u64,
                json!({"path": "lembo", "k": 0.5, key: d}),
                Some(2000 - 10 * d),
                None,
            )
        })
        .collect();
    let files = plot_files(&records, None).unwrap();
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert!(
        names.contains(&"cycles_vs_fifo_depth_sphere24.svg"),
        "{names:?}"
    );
    assert!(
        !names.iter().any(|n| n.starts_with("cycles_vs_units")),
        "{names:?}"
    );
    let svg = &files
        .iter()
        .find(|(n, _)| n.starts_with("cycles_vs_fifo"))
        .unwrap()
        .1;
    let svg = String::from_utf8(svg.clone()).unwrap();
    for text in [
        "sphere24: cycles against FIFO depths",
        "FIFO depth [entries], log scale",
        key,
    ] {
        assert!(has(&svg, text), "lacks {text:?}");
    }
}

#[test]
fn an_area_budget_greys_larger_units_and_draws_a_front_per_path() {
    // Error falls with k and n; area grows with the interval managers and rasterizers.
    let mut records = Vec::new();
    for (i, (path, level, area)) in [
        ("lembo", 1.0, 4.0),
        ("lembo", 0.5, 5.0),
        ("lembo", 0.25, 9.0),
        ("triangle", 4.0, 3.0),
        ("triangle", 8.0, 5.5),
        ("triangle", 16.0, 12.0),
    ]
    .into_iter()
    .enumerate()
    {
        let params = if path == "lembo" {
            json!({"path": path, "k": level})
        } else {
            json!({"path": path, "tess": level as u64})
        };
        let mut r = record(
            i as u64,
            params,
            Some(1000 + 100 * i as u64),
            Some(30.0 + 2.0 * i as f64),
        );
        r["report"]["cost"] = json!({"area_mm2": area, "energy_pj": 1e6 * (1.0 + i as f64)});
        records.push(r);
    }
    let files = plot_files(&records, Some(6.0)).unwrap();
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert!(names.contains(&"error_vs_energy_sphere24.svg"), "{names:?}");
    for (name, svg) in &files {
        if !(name.starts_with("tradeoff") || name.starts_with("error_vs_energy")) {
            continue;
        }
        let svg = String::from_utf8(svg.clone()).unwrap();
        assert!(has(&svg, "units within 6 mm²"), "{name}");
        assert!(has(&svg, "over the area budget of 6 mm²"), "{name}");
        assert!(
            has(&svg, "each path&apos;s Pareto front") || has(&svg, "each path's Pareto front"),
            "{name}"
        );
        // The two larger units are drawn grey.
        assert!(svg.matches("#BEBEBE").count() >= 2, "{name}");
    }
    // Without a budget no point is grey and the front spans both paths.
    let files = plot_files(&records, None).unwrap();
    let svg = String::from_utf8(files[0].1.clone()).unwrap();
    assert!(has(&svg, "Pareto front over both paths"));
    assert!(!svg.contains("#BEBEBE"));
}

/// Records that carry FLIP get the error plots again with FLIP on the y axis (a record
/// without it, the first here, is left out of those only).
#[test]
fn flip_gets_its_own_error_plots() {
    let mut records = sweep();
    for (i, r) in records.iter_mut().enumerate().skip(1) {
        let psnr = r["report"]["accuracy"]["psnr_db"].as_f64().unwrap();
        r["report"]["accuracy"]["flip_mean"] =
            json!(10f64.powf(-psnr / 20.0) * (1.0 + i as f64 / 100.0));
    }
    let files = plot_files(&records, None).unwrap();
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "tradeoff_sphere24.svg",
            "flip_tradeoff_sphere24.svg",
            "cycles_vs_k_sphere24.svg",
            "cycles_vs_units_sphere24.svg",
            "utilisation_sphere24.svg",
            "vs_rasterizer_count_sphere24.svg",
            "vs_segmenter_count_sphere24.svg"
        ]
    );
    let flip = String::from_utf8(files[1].1.clone()).unwrap();
    for text in [
        "sphere24: FLIP against cycles",
        "mean FLIP [0-1] (report.json accuracy.flip_mean), log scale",
        "lembo path",
        "triangle path",
    ] {
        assert!(has(&flip, text), "flip_tradeoff lacks {text:?}");
    }
    // (Records without FLIP at all give no FLIP plot: the next test.)
}

#[test]
fn write_plots_draws_every_plot_a_timed_sweep_with_reference_supports() {
    let dir = tempfile::tempdir().unwrap();
    let names = write_plots(dir.path(), &sweep(), None).unwrap();
    assert_eq!(
        names,
        [
            "tradeoff_sphere24.svg",
            "cycles_vs_k_sphere24.svg",
            "cycles_vs_units_sphere24.svg",
            "utilisation_sphere24.svg",
            "vs_rasterizer_count_sphere24.svg",
            "vs_segmenter_count_sphere24.svg"
        ]
    );
    // Any numeric field that varies gets cycles, energy and PSNR against it, each path
    // with what it held.
    let svg = read_svg(dir.path(), "vs_segmenter_count_sphere24.svg");
    for text in [
        "sphere24: cycles, energy and PSNR against arch.segmenter.count",
        "held: lembo: ",
        "simulated frame time [cycles]",
        "PSNR against the reference [dB]",
        "held at the most common value: ",
    ] {
        assert!(has(&svg, text), "vs_segmenter_count lacks {text:?}");
    }
    let svg = read_svg(dir.path(), "tradeoff_sphere24.svg");
    for text in [
        "sphere24: image error against cycles",
        "simulated frame time [cycles], log scale",
        "RMS colour error 255*10^(-PSNR/20) [0-255], log scale",
        "lembo path",
        "triangle path",
        "Pareto front over both paths (circled)",
        "k=0.125",
        "n=8",
    ] {
        assert!(has(&svg, text), "tradeoff lacks {text:?}");
    }
    let svg = read_svg(dir.path(), "cycles_vs_k_sphere24.svg");
    for text in [
        "sphere24: cycles against k (lembo path)",
        "k, chord error of the extreme method [px], log scale",
        "simulated frame time [cycles]",
        // The datapath tells the series apart; the points where a count varies are
        // at k = 0.5 only.
        "datapath=f64",
        "not drawn: 4 point(s) whose other parameters were run at a single k",
    ] {
        assert!(has(&svg, text), "cycles_vs_k lacks {text:?}");
    }
    let svg = read_svg(dir.path(), "cycles_vs_units_sphere24.svg");
    for text in [
        "sphere24: cycles against unit counts",
        "unit instances [count]",
        "arch.segmenter.count",
        "arch.rasterizer.count",
        "path=lembo, arch.rasterizer.count=4, datapath=f32, k=0.5",
    ] {
        assert!(has(&svg, text), "cycles_vs_units lacks {text:?}");
    }
    let svg = read_svg(dir.path(), "utilisation_sphere24.svg");
    for text in [
        "sphere24: unit utilisation at the most and fewest cycles",
        "share of the frame time [%]",
        "most cycles: lembo path, k=0.5",
        "fewest cycles: triangle path, n=1",
        "Unit[2]",
        "starved",
    ] {
        assert!(has(&svg, text), "utilisation lacks {text:?}");
    }
}

#[test]
fn functional_records_without_reference_give_no_plot_and_no_error() {
    let records: Vec<Value> = [0.25, 0.5, 1.0]
        .iter()
        .enumerate()
        .map(|(i, k)| record(i as u64, json!({"path": "lembo", "k": k}), None, None))
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plots");
    assert!(write_plots(&out, &records, None).unwrap().is_empty());
    assert!(!out.exists());
}

#[test]
fn records_without_accuracy_give_no_tradeoff_plot() {
    let records: Vec<Value> = [(0.25, 60_000), (0.5, 52_000), (1.0, 47_000)]
        .iter()
        .enumerate()
        .map(|(i, &(k, c))| record(i as u64, json!({"path": "lembo", "k": k}), Some(c), None))
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let names = write_plots(dir.path(), &records, None).unwrap();
    assert_eq!(
        names,
        ["cycles_vs_k_sphere24.svg", "utilisation_sphere24.svg"]
    );
    let svg = read_svg(dir.path(), "cycles_vs_k_sphere24.svg");
    assert!(has(&svg, "all points"));
}

#[test]
fn records_that_are_not_sweep_points_are_skipped() {
    let records = [
        json!({"index": 0}),
        json!("text"),
        json!({"report": {"settings": {}}}),
    ];
    let dir = tempfile::tempdir().unwrap();
    assert!(write_plots(dir.path(), &records, None).unwrap().is_empty());
}

#[test]
fn scenes_get_their_own_plots_with_safe_file_names() {
    let mut a = record(
        0,
        json!({"path": "lembo", "k": 0.5}),
        Some(50_000),
        Some(40.0),
    );
    a["scene"] = json!("my scene/1");
    let b = record(
        1,
        json!({"path": "lembo", "k": 0.5}),
        Some(50_000),
        Some(40.0),
    );
    let dir = tempfile::tempdir().unwrap();
    let names = write_plots(dir.path(), &[a, b], None).unwrap();
    assert_eq!(
        names,
        [
            "tradeoff_my_scene_1.svg",
            "utilisation_my_scene_1.svg",
            "tradeoff_sphere24.svg",
            "utilisation_sphere24.svg"
        ]
    );
    assert!(has(
        &read_svg(dir.path(), "tradeoff_my_scene_1.svg"),
        "my scene/1: image error"
    ));
}

/// The unit-count plot holds the other varying fields at their most common value; where
/// two values are equally common it says which it held and which tied with it, instead of
/// holding one silently (the bandwidth at 32 and 64 here).
#[test]
fn the_unit_count_plot_says_a_tied_held_value() {
    let records: Vec<Value> = [(2, 32, 900), (4, 32, 500), (2, 64, 800), (4, 64, 400)]
        .into_iter()
        .enumerate()
        .map(|(i, (rops, bw, cycles))| {
            record(
                i as u64,
                json!({"path": "lembo", "k": 0.5, "arch.rop.count": rops,
                       "arch.framebuffer.bytes_per_cycle": bw}),
                Some(cycles),
                Some(40.0),
            )
        })
        .collect();
    let points: Vec<Point> = records.iter().filter_map(Point::from_record).collect();
    let series = held_series(&points, ArchAxis::Counts);
    assert_eq!(series.len(), 1);
    let note = series[0].0.note.as_deref().unwrap();
    assert!(
        note.contains("arch.framebuffer.bytes_per_cycle=32 (tied with 64)"),
        "{note}"
    );
    assert_eq!(series[0].1, [(2.0, 900.0), (4.0, 500.0)]);
}
