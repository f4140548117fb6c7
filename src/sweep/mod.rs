//! `lembo-sim sweep` and `sweep-merge` (DESIGN.md §7, issue 6): many runs of one spec file,
//! each a point of a parameter space on a scene, into one table.
//!
//! ```text
//!  spec.json ─► Spec::parse (shape, parameter values, grid expansion, keys)
//!            ─► Plan::load  (scenes, architectures, every run's RenderJob validated)
//!            ─► references (one per scene, shared) ─► runs on a rayon pool of --jobs threads
//!            ─► results.jsonl (one line per finished run, appended and flushed at once)
//!            ─► when all are done: results.jsonl sorted, results.csv, spec.json, plots
//! ```
//!
//! A spec (`sim/sweeps/README.md` documents the format) names scenes and a list of
//! *points*: a grid block is the cartesian product of its parameters' value lists (the first
//! parameter varies slowest), an explicit point gives one value per parameter, and the
//! points are the union of the blocks and then the explicit points, in that order (a point
//! met again adds its scenes to the first one's). Parameters are the render settings
//! (`path`, `k`, `tess`, `datapath`, `blend`, `threshold`) and any architecture field as
//! `arch.<dotted path>`; a block or point may restrict itself to some of the spec's scenes
//! with `scenes`. Every (point, scene) pair is a *run*; runs are numbered point-major in
//! that order, and each has a *key*: the scene as the spec writes it and the point's
//! parameters, sorted, in canonical form (`../../traces/sphere24.json|k=0.5|path="lembo"`).
//!
//! Everything is validated before the first run starts: the spec's shape, every value,
//! every combination, every scene and every point's architecture; a refused value names
//! the spec file, its field path (`grid[1].arch.rop.count[0]`) and the value.
//!
//! Resumption: a run's record is appended to `results.jsonl` as soon as it finishes, and a
//! sweep started again on the same directory skips the runs whose key is already there (a
//! truncated last line, from a kill mid-write, is dropped). `spec.json` in the directory
//! must then hold the same spec, and every record must belong to this spec and shard.
//! Sharding (`--shard I/N`) keeps the runs whose index is I modulo N; `sweep-merge` unions
//! the shards' records and writes what an unsharded run writes.
//!
//! Paths inside records (`report.scene.source`, `report.settings.arch_file`) are the
//! spec's own strings, so records do not depend on the directory a sweep ran from.
//!
//! One writer per folder: a sweep (and a merge, into its `--out`) holds a [`FolderLock`]
//! while it writes; see [`lock`].
//!
//! Layout, from the bottom up: [`spec`] (names and bounds, the file's shape, the expanded
//! spec, shards), `grid` (expanding blocks and points), `parse` (`Spec::parse`), [`plan`]
//! (`Plan::load`: everything validated before a run), the answer's files (`bracket`,
//! `curves`, `sensitivity`, `flips`, `reproduce`, `answer`, and `by`, the answer by value),
//! [`results`] (the folder's files:
//! reading `results.jsonl` back, `results.csv`, the final set), [`run`] (the request, the
//! pool, appends, resumption), [`merge`] (`sweep-merge`), [`lock`]. Each imports only files
//! before it (and `lock`); this file only declares them and re-exports their public items.

mod answer;
pub mod bracket;
mod by;
pub mod curves;
mod flips;
mod grid;
pub mod lock;
pub mod merge;
mod names;
mod parse;
pub mod plan;
mod reproduce;
pub mod results;
pub mod run;
pub mod sensitivity;
pub mod spec;

pub use lock::{FolderLock, LOCK_FILE};
pub use merge::{run_merge, MergeJob, MergeOutput};
pub use plan::Plan;
pub use results::{csv_bytes, RESULTS_CSV, RESULTS_JSONL, SPEC_JSON};
pub use run::{run_sweep, SweepError, SweepJob, SweepOutcome, SweepOutput, MAX_JOBS};
pub use spec::{Point, Run, Shard, Spec, MAX_RUNS};

#[cfg(test)]
mod tests {
    use super::results::unit_order;
    use super::*;
    use crate::error::{Error, Result};

    const BASE: &str = r#""name": "t", "scenes": ["a.json", "b.json"]"#;

    fn spec(rest: &str) -> Result<Spec> {
        Spec::parse(&format!("{{{BASE}, {rest}}}"), "s.json")
    }

    fn field_of(e: Error) -> String {
        match e {
            Error::Invalid { field, .. } | Error::Parse { field, .. } => field,
            other => panic!("unexpected error {other}"),
        }
    }

    #[test]
    fn grid_is_a_product_with_the_first_parameter_slowest_then_points() {
        let s = spec(
            r#""grid": [{"tess": [1, 2], "path": ["triangle"]}, {"k": [2, 1]}],
               "points": [{"k": 1}, {"k": 0.25, "scenes": ["b.json"]}]"#,
        )
        .unwrap();
        let keys: Vec<&str> = s.runs.iter().map(|r| r.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                r#"a.json|path="triangle"|tess=1"#,
                r#"b.json|path="triangle"|tess=1"#,
                r#"a.json|path="triangle"|tess=2"#,
                r#"b.json|path="triangle"|tess=2"#,
                "a.json|k=2.0",
                "b.json|k=2.0",
                // points[0] equals grid[1]'s second point: the union keeps it once.
                "a.json|k=1.0",
                "b.json|k=1.0",
                "b.json|k=0.25",
            ]
        );
        assert!(s.runs.iter().enumerate().all(|(i, r)| r.index == i));
    }

    #[test]
    fn an_area_budget_is_a_positive_area_of_a_timed_sweep() {
        let s = spec(r#""area_budget_mm2": 6.5, "points": [{}]"#).unwrap();
        assert_eq!(s.area_budget_mm2, Some(6.5));
        for bad in ["0", "-1", "1e999"] {
            let e = spec(&format!(r#""area_budget_mm2": {bad}, "points": [{{}}]"#)).unwrap_err();
            assert_eq!(field_of(e), "area_budget_mm2", "{bad}");
        }
        let e = spec(r#""mode": "functional", "area_budget_mm2": 6, "points": [{}]"#).unwrap_err();
        assert!(e.to_string().contains("mode timed"), "{e}");
        assert_eq!(field_of(e), "area_budget_mm2");
        // The interval managers and MinMax units are architecture counts like any other.
        let s = spec(r#""grid": [{"arch.interval_manager.count": [1, 2, 4]}]"#).unwrap();
        assert_eq!(s.points.len(), 3);
    }

    /// Back-face culling is an architecture field like any other: a point sets it on
    /// either path, and a value that is not off, on or auto is refused naming the point's
    /// field.
    #[test]
    fn culling_is_an_arch_field_of_a_sweep() {
        let s = spec(
            r#""grid": [{"arch.minmax.cull_backfaces": ["off", "on", "auto"],
                         "arch.triangle_setup.cull_backfaces": ["off"]}]"#,
        )
        .unwrap();
        assert_eq!(s.points.len(), 3);
        let base = crate::config::ArchConfig::default();
        let got: Vec<_> = s
            .points
            .iter()
            .map(|p| {
                let a = plan::point_arch("s.json", &base, p).unwrap();
                (a.minmax.cull_backfaces, a.triangle_setup.cull_backfaces)
            })
            .collect();
        use crate::config::CullBackfaces::{Auto, Off, On};
        assert_eq!(got, [(Off, Off), (On, Off), (Auto, Off)]);
        let e = spec(r#""points": [{"arch.minmax.cull_backfaces": "sometimes"}]"#).unwrap_err();
        assert_eq!(field_of(e), "points[0].arch.minmax.cull_backfaces");
    }

    #[test]
    fn arch_values_are_canonical_and_unknown_fields_named() {
        let s = spec(r#""points": [{"arch.clock_mhz": 400, "arch.segmenter.count": 4}]"#).unwrap();
        assert_eq!(
            s.points[0].params["arch.clock_mhz"],
            serde_json::json!(400.0)
        );
        let e = spec(r#""points": [{"arch.segmenter.cnt": 4}]"#).unwrap_err();
        assert!(e.to_string().contains("cycles_per_segment"), "{e}");
        assert_eq!(field_of(e), "points[0].arch.segmenter.cnt");
        let e = spec(r#""points": [{"arch.links": 4}]"#).unwrap_err();
        assert!(e.to_string().contains("group of fields"), "{e}");
        let e = spec(r#""grid": [{"arch.rop.count": [2, 1.5]}]"#).unwrap_err();
        assert_eq!(field_of(e), "grid[0].arch.rop.count[1]");
    }

    /// The sensitivity study's knobs: fractional architecture figures read back as given
    /// (whole ones as integers), technology figures as the technology file writes them,
    /// and an unknown technology field or a wrong type named.
    #[test]
    fn fractional_arch_and_tech_values_are_canonical() {
        let s = spec(
            r#""grid": [{"arch.rop.fragments_per_cycle": [0.5, 2],
                         "arch.framebuffer.access_cycles": [0.5, 1],
                         "tech.dram.pj_per_byte": [81.25, 325]}]"#,
        )
        .unwrap();
        assert_eq!(s.points.len(), 8);
        let p = &s.points[0].params;
        assert_eq!(p["arch.rop.fragments_per_cycle"], serde_json::json!(0.5));
        assert_eq!(p["tech.dram.pj_per_byte"], serde_json::json!(81.25));
        let p = &s.points[7].params;
        assert_eq!(p["arch.framebuffer.access_cycles"], serde_json::json!(1));
        assert_eq!(p["tech.dram.pj_per_byte"], serde_json::json!(325.0));
        let e = spec(r#""points": [{"tech.dram.pj": 1}]"#).unwrap_err();
        assert!(e.to_string().contains("unknown technology field"), "{e}");
        assert!(e.to_string().contains("pj_per_byte"), "{e}");
        assert_eq!(field_of(e), "points[0].tech.dram.pj");
        let e = spec(r#""grid": [{"tech.dram.pj_per_byte": [1, "x"]}]"#).unwrap_err();
        assert_eq!(field_of(e), "grid[0].tech.dram.pj_per_byte[1]");
        let e =
            spec(r#""mode": "functional", "points": [{"tech.dram.pj_per_byte": 1}]"#).unwrap_err();
        assert!(e.to_string().contains("mode timed"), "{e}");
        assert_eq!(field_of(e), "points[0].tech.dram.pj_per_byte");
    }

    #[test]
    fn bad_values_and_combinations_name_their_field() {
        for (rest, field) in [
            (r#""grid": [{"k": []}]"#, "grid[0].k"),
            (r#""grid": [{"k": [1, 100]}]"#, "grid[0].k[1]"),
            (r#""grid": [{"k": 1}]"#, "grid[0].k"),
            (r#""grid": [{}]"#, "grid[0]"),
            (r#""grid": []"#, "grid"),
            (
                r#""points": [{"tess": 0, "path": "triangle"}]"#,
                "points[0].tess",
            ),
            (r#""points": [{"tess": 2}]"#, "points[0].tess"),
            (r#""points": [{"k": 1, "path": "triangle"}]"#, "points[0].k"),
            (r#""points": [{"datapath": "f16"}]"#, "points[0].datapath"),
            (r#""points": [{"threshold": -1}]"#, "points[0].threshold"),
            (r#""points": [{"colour": 1}]"#, "points[0].colour"),
            (
                r#""points": [{"scenes": ["c.json"]}]"#,
                "points[0].scenes[0]",
            ),
            (r#""points": [{}], "viewport": [0, 4]"#, "viewport[0]"),
            (r#""points": [{}], "extra": 1"#, "extra"),
        ] {
            let e = spec(rest)
                .err()
                .unwrap_or_else(|| panic!("{rest} accepted"));
            assert_eq!(field_of(e), field, "{rest}");
        }
        let e = Spec::parse(r#"{"name": "t", "scenes": [], "points": [{}]}"#, "s").unwrap_err();
        assert_eq!(field_of(e), "scenes");
    }

    /// The viewport is an axis like the samples: a grid block's list, a point's value, or
    /// the spec's list that every point runs at; `[w, h]` and `"WxH"` alike, canonical as
    /// `"WxH"`; an empty list, a zero side or a viewport given twice refused naming it.
    #[test]
    fn viewports_are_an_axis() {
        let s = spec(r#""grid": [{"viewport": ["64x48", [32, 32]], "k": [1]}]"#).unwrap();
        let keys: Vec<&str> = s.runs.iter().map(|r| r.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                r#"a.json|k=1.0|viewport="64x48""#,
                r#"b.json|k=1.0|viewport="64x48""#,
                r#"a.json|k=1.0|viewport="32x32""#,
                r#"b.json|k=1.0|viewport="32x32""#,
            ]
        );
        assert_eq!(s.viewport, None);
        let s = spec(r#""viewport": [[64, 48], "32x32"], "points": [{"k": 1}, {"k": 2}]"#).unwrap();
        assert_eq!(s.points.len(), 4);
        assert_eq!(s.points[1].params["viewport"], "32x32");
        assert_eq!(s.points[1].field("viewport"), "viewport[1]");
        // One viewport, in either form, is every scene's, as before: no parameter.
        for one in ["[64, 48]", "[[64, 48]]", r#""64x48""#] {
            let s = spec(&format!(r#""viewport": {one}, "points": [{{}}]"#)).unwrap();
            assert_eq!(s.viewport, Some((64, 48)), "{one}");
            assert!(s.points[0].params.is_empty());
        }
        for (rest, field) in [
            (r#""viewport": [], "points": [{}]"#, "viewport"),
            (
                r#""viewport": [[64, 48], [0, 4]], "points": [{}]"#,
                "viewport[1]",
            ),
            (
                r#""viewport": [[64, 48], "64x48"], "points": [{}]"#,
                "viewport[1]",
            ),
            (r#""viewport": ["4x4", "8"], "points": [{}]"#, "viewport[1]"),
            (r#""grid": [{"viewport": []}]"#, "grid[0].viewport"),
            (r#""grid": [{"viewport": ["0x4"]}]"#, "grid[0].viewport[0]"),
            (
                r#""grid": [{"viewport": [[4, 20000]]}]"#,
                "grid[0].viewport[0]",
            ),
            (
                r#""viewport": ["4x4", "8x8"], "points": [{"viewport": "2x2"}]"#,
                "points[0].viewport",
            ),
        ] {
            let e = spec(rest)
                .err()
                .unwrap_or_else(|| panic!("{rest} accepted"));
            assert_eq!(field_of(e), field, "{rest}");
        }
    }

    /// `by` names a field the spec sweeps (two values or more), not a knob, in a spec
    /// with an area budget; each refusal names the field and says why.
    #[test]
    fn by_names_a_swept_field() {
        let grid = r#""grid": [{"arch.framebuffer.bytes_per_cycle": [32, 64], "k": [1, 2]}]"#;
        let s = spec(&format!(
            r#""area_budget_mm2": 50, "by": "arch.framebuffer.bytes_per_cycle", {grid}"#
        ))
        .unwrap();
        assert_eq!(s.by.as_deref(), Some("arch.framebuffer.bytes_per_cycle"));
        for (by, budget, why) in [
            ("k", true, "knobs"),
            ("arch.rop.count", true, "does not sweep it"),
            ("arch.framebuffer.bytes_per_cycle", false, "area_budget_mm2"),
        ] {
            let budget = if budget {
                r#""area_budget_mm2": 50,"#
            } else {
                ""
            };
            let e = spec(&format!(r#"{budget} "by": "{by}", {grid}"#)).unwrap_err();
            assert!(e.to_string().contains(why), "{by}: {e}");
            assert_eq!(field_of(e), "by");
        }
        let e = spec(&format!(
            r#""area_budget_mm2": 50, "by": "arch.rop.count", {grid}"#
        ))
        .unwrap_err();
        assert!(
            e.to_string().contains("arch.framebuffer.bytes_per_cycle"),
            "{e}"
        );
    }

    #[test]
    fn huge_grids_are_refused_before_expansion() {
        let list: Vec<String> = (1..=400).map(|i| i.to_string()).collect();
        let l = list.join(", ");
        let e = spec(&format!(
            r#""grid": [{{"arch.clock_mhz": [{l}], "arch.setup.latency_cycles": [{l}]}}]"#
        ))
        .unwrap_err();
        assert_eq!(field_of(e), "grid[0]");
    }

    #[test]
    fn shards_partition_the_indices() {
        assert!(Shard::new(2, 2).is_err());
        assert!(Shard::new(0, 0).is_err());
        let shards: Vec<Shard> = (0..3).map(|i| Shard::new(i, 3).unwrap()).collect();
        for index in 0..20 {
            assert_eq!(shards.iter().filter(|s| s.keeps(index)).count(), 1);
        }
    }

    #[test]
    fn units_sort_in_dataflow_order_and_by_instance() {
        let mut names = [
            "Rop[1]",
            "Segmenter[10]",
            "Setup",
            "Segmenter[9]",
            "FrameBuffer",
        ]
        .map(unit_order);
        names.sort();
        let names: Vec<&str> = names.iter().map(|(_, _, n)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "Setup",
                "Segmenter[9]",
                "Segmenter[10]",
                "Rop[1]",
                "FrameBuffer"
            ]
        );
    }

    #[test]
    fn csv_writes_the_value_a_run_used_where_its_point_left_the_default() {
        let records = vec![
            serde_json::json!({"index": 0, "scene": "s", "params": {"path": "lembo", "k": 1.0},
                "report": {"settings": {"path": "lembo", "k_px": 1.0, "tess": null,
                    "datapath": "f32"}, "arch": {"rop": {"count": 4}}, "blend": null}}),
            serde_json::json!({"index": 1, "scene": "s",
                "params": {"path": "triangle", "arch.rop.count": 2},
                "report": {"settings": {"path": "triangle", "k_px": null, "tess": 1,
                    "datapath": "f32"}, "arch": {"rop": {"count": 2}}, "blend": null}}),
        ];
        let text = String::from_utf8(csv_bytes(&records).unwrap()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(
            lines[0].starts_with("index,scene,arch.rop.count,k,path,"),
            "{}",
            lines[0]
        );
        // The lembo run used 4 ROPs by default; the triangle run has no k to report.
        assert!(lines[1].starts_with("0,s,4,1.0,lembo,"), "{}", lines[1]);
        assert!(lines[2].starts_with("1,s,2,,triangle,"), "{}", lines[2]);
    }

    #[test]
    fn csv_leaves_absent_values_empty() {
        let records = vec![
            serde_json::json!({"index": 0, "scene": "s", "params": {"k": 1.0},
                "report": {"cycles": {"total": 10, "fps": 5.0, "bottleneck": "Rop",
                    "units": [{"name": "Rop", "busy": 5}]},
                    "cost": {"area_mm2": 1.5, "energy_pj": 20.0},
                    "accuracy": null, "primitives": {"count": 2, "bytes": 8},
                    "counts": {"fragments": 3, "lembo_pieces": 4}, "blend": null,
                    "host": {"wall_seconds": 0.5}}}),
            serde_json::json!({"index": 1, "scene": "s, \"quoted\"", "params": {"tess": 2},
                "report": {"cycles": null, "accuracy": {"psnr_db": 40.0},
                    "primitives": {"count": 2, "bytes": 8}, "counts": {"fragments": 3},
                    "blend": null, "host": {"wall_seconds": 0.25}}}),
        ];
        let text = String::from_utf8(csv_bytes(&records).unwrap()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "index,scene,k,tess,cycles_total,fps,bottleneck,area_mm2,energy_pj,util.Rop,acc.psnr_db,primitives,primitive_bytes,geometry_bytes,fragments,lembo_pieces,blend.error_mean,blend.error_max,wall_seconds");
        assert_eq!(lines[1], "0,s,1.0,,10,5.0,Rop,1.5,20.0,0.5,,2,8,,3,4,,,0.5");
        assert_eq!(
            lines[2],
            "1,\"s, \"\"quoted\"\"\",,2,,,,,,,40.0,2,8,,3,,,,0.25"
        );
    }

    /// The DRAM model's columns appear when a run used it, empty for the port's runs.
    #[test]
    fn csv_gives_the_memory_columns_when_a_run_used_the_dram_model() {
        let run = |i: u32, memory: serde_json::Value| {
            serde_json::json!({"index": i, "scene": "s", "params": {},
                "report": {"cycles": null, "primitives": {"count": 1, "bytes": 1},
                    "counts": {"fragments": 1}, "host": {"wall_seconds": 0.1},
                    "memory_system": memory}})
        };
        let port = vec![run(0, serde_json::Value::Null)];
        let text = String::from_utf8(csv_bytes(&port).unwrap()).unwrap();
        assert!(!text.contains("mem."), "{text}");
        let dram = serde_json::json!({"atoms_read": 7, "geometry_atoms_read": 2,
            "atoms_written": 9, "activations": 3, "row_hit_rate": 0.5,
            "rop_read_latency_mean": 40.5, "colour_cache_hit_rate": 0.25, "depth_cache_hit_rate": 0.75,
            "colour_compression_ratio": 2.0, "depth_compression_ratio": 4.0,
            "rops": {"cleared_tiles": 11}});
        let both = vec![run(0, serde_json::Value::Null), run(1, dram)];
        let text = String::from_utf8(csv_bytes(&both).unwrap()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].ends_with(",wall_seconds,mem.atoms_read,mem.geometry_atoms_read,mem.atoms_written,mem.activations,mem.row_hit_rate,mem.rop_read_latency_mean,mem.colour_cache_hit_rate,mem.depth_cache_hit_rate,mem.colour_compression_ratio,mem.depth_compression_ratio,mem.cleared_tiles"), "{}", lines[0]);
        assert!(lines[1].ends_with(",0.1,,,,,,,,,,,"), "{}", lines[1]);
        assert!(
            lines[2].ends_with(",0.1,7,2,9,3,0.5,40.5,0.25,0.75,2.0,4.0,11"),
            "{}",
            lines[2]
        );
    }
}
