//! The architecture configuration's tests: the shipped files, parse and range errors
//! naming their fields, the graph's instances.

use super::*;
use crate::graph::{LinkConfig, TessSource, BOUNDARIES, KINDS, LINK_KEYS};
use std::path::PathBuf;

fn arch_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("sim/arch")
}

fn load(name: &str) -> ArchConfig {
    ArchConfig::load(&arch_dir().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Asserts a parse error naming `field` and returns its message.
fn assert_parse_err(text: &str, expected_field: &str) -> String {
    match ArchConfig::from_json(text, "t.json") {
        Err(Error::Parse {
            file,
            field,
            message,
        }) => {
            assert_eq!(file, "t.json");
            assert_eq!(field, expected_field, "{message}");
            message
        }
        other => panic!("{text}: expected a parse error, got {other:?}"),
    }
}

/// Asserts an invalid-value error naming `field` with `value`.
fn assert_invalid(text: &str, expected_field: &str, expected_value: &str) {
    match ArchConfig::from_json(text, "t.json") {
        Err(Error::Invalid {
            file, field, value, ..
        }) => {
            assert_eq!(file, "t.json");
            assert_eq!(field, expected_field);
            assert_eq!(value, expected_value);
        }
        other => panic!("{text}: expected an invalid-value error, got {other:?}"),
    }
}

/// Every file of `sim/arch/`, by name.
fn shipped_files() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(arch_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json"))
        .collect();
    names.sort();
    assert!(names.len() >= 4, "{names:?}");
    names
}

#[test]
fn config_files_load_and_validate() {
    for name in shipped_files() {
        let config = load(&name);
        config.validate(&name).unwrap();
        assert_eq!(format!("{}.json", config.name), name);
    }
}

/// The dotted paths of every value in a JSON object (`setup.count`, `links.x.fifo_depth`).
fn leaf_paths(v: &serde_json::Value, prefix: &str, out: &mut Vec<String>) {
    match v.as_object() {
        Some(map) => {
            for (k, v) in map {
                leaf_paths(v, &format!("{prefix}{k}."), out);
            }
        }
        None => out.push(prefix.trim_end_matches('.').to_string()),
    }
}

/// sim/arch/README.md says the shipped files list every field, so that they can be compared
/// line by line: each has exactly the fields `ArchConfig` serialises, no more, no fewer.
#[test]
fn config_shipped_files_list_every_field() {
    let mut every = Vec::new();
    leaf_paths(
        &serde_json::to_value(ArchConfig::default()).unwrap(),
        "",
        &mut every,
    );
    every.sort();
    for name in shipped_files() {
        let text = std::fs::read_to_string(arch_dir().join(&name)).unwrap();
        let mut listed = Vec::new();
        leaf_paths(&serde_json::from_str(&text).unwrap(), "", &mut listed);
        listed.sort();
        assert_eq!(listed, every, "{name}");
    }
}

/// The lembo path's unit instances on `config`, counted from the graph's kinds and the
/// file's count fields ([`ArchConfig::count_field`]) rather than from [`ArchConfig::unit`]:
/// a kind without a count field has one instance, a kind inside another none of its own.
fn lembo_units(config: &ArchConfig) -> u32 {
    let value = serde_json::to_value(config).unwrap();
    PrimitivePath::Lembo
        .kinds(config.tessellation.source)
        .iter()
        .filter(|k| k.inside().is_none())
        .map(|&k| match ArchConfig::count_field(k) {
            Some(field) => value
                .pointer(&format!("/{}", field.replace('.', "/")))
                .unwrap()
                .as_u64()
                .unwrap() as u32,
            None => 1,
        })
        .sum()
}

/// The baseline named `name` with each count field of the graph's kinds set to `count`
/// when `count` is Some, then the fields `sets` (dotted path, value), and the links `links`.
fn baseline_with(
    name: &str,
    count: Option<u32>,
    sets: &[(&str, u32)],
    links: LinksConfig,
) -> ArchConfig {
    let mut fields: Vec<(String, serde_json::Value)> = Vec::new();
    if let Some(count) = count {
        fields.extend(
            KINDS
                .iter()
                .filter_map(|&k| ArchConfig::count_field(k))
                .map(|f| (f.to_string(), count.into())),
        );
    }
    fields.extend(sets.iter().map(|(f, v)| (f.to_string(), (*v).into())));
    let mut c = ArchConfig::default().with_fields(&fields, "test").unwrap();
    c.name = name.to_string();
    c.links = links;
    c
}

#[test]
fn config_baseline_file_equals_defaults() {
    assert_eq!(load("baseline.json"), ArchConfig::default());
    assert_eq!(ArchConfig::baseline(), ArchConfig::default());
    ArchConfig::default().validate("default").unwrap();
    let d = ArchConfig::default();
    assert_eq!(d.units(), lembo_units(&d));
}

#[test]
fn config_minimal_has_one_of_each_unit_and_depth_one_fifos() {
    let config = load("minimal.json");
    let defaults = ArchConfig::default();
    let lembo_kinds = PrimitivePath::Lembo.kinds(TessSource::Memory);
    let own = lembo_kinds.iter().filter(|k| k.inside().is_none()).count();
    assert_eq!(config.units() as usize, own);
    for kind in KINDS {
        assert_eq!(config.unit(kind).0, 1, "{kind:?}");
    }
    for ((name, link), (_, default)) in config.links.all().into_iter().zip(defaults.links.all()) {
        assert_eq!(link.fifo_depth, 1, "{name}");
        assert_eq!(link.latency_cycles, default.latency_cycles, "{name}");
    }
    // Everything else is the baseline.
    let expected = baseline_with("minimal", Some(1), &[], config.links.clone());
    assert_eq!(config, expected);
}

#[test]
fn config_wide_has_its_counts_and_depths() {
    let config = load("wide.json");
    let defaults = ArchConfig::default();
    let counts = [
        ("segmenter.count", 4),
        ("subsegmenter.count", 4),
        ("rasterizer.count", 8),
        ("triangle_rasterizer.count", 2),
    ];
    assert_eq!(config.units(), lembo_units(&config));
    assert!(config.units() > defaults.units());
    for ((name, link), (_, default)) in config.links.all().into_iter().zip(defaults.links.all()) {
        let depth = match name {
            "rop_to_framebuffer" => 32,
            _ => 64,
        };
        assert_eq!(link.fifo_depth, depth, "{name}");
        assert_eq!(link.latency_cycles, default.latency_cycles, "{name}");
    }
    let expected = baseline_with("wide", None, &counts, config.links.clone());
    assert_eq!(config, expected);
}

#[test]
fn config_partial_file_keeps_defaults() {
    let config = ArchConfig::from_json(r#"{"segmenter": {"count": 3}}"#, "t.json").unwrap();
    let defaults = ArchConfig::default();
    assert_eq!(
        config,
        ArchConfig {
            segmenter: SegmenterConfig {
                count: 3,
                ..defaults.segmenter.clone()
            },
            ..defaults
        }
    );
    assert_eq!(
        ArchConfig::from_json("{}", "t.json").unwrap(),
        ArchConfig::default()
    );
}

#[test]
fn config_partial_link_keeps_its_boundary_defaults() {
    let text = r#"{"links": {"rasterizer_to_rop": {"fifo_depth": 32},
                             "rop_to_framebuffer": {"latency_cycles": 9}}}"#;
    let config = ArchConfig::from_json(text, "t.json").unwrap();
    assert_eq!(config.links, {
        let mut links = LinksConfig::default();
        *links.get_mut(UnitKind::FragmentRasterizer, UnitKind::Rop) = LinkConfig::new(32, 2);
        *links.get_mut(UnitKind::Rop, UnitKind::FrameBuffer) = LinkConfig::new(32, 9);
        links
    });
    let first = LINK_KEYS[0];
    for depth in ["null", "-1"] {
        assert_parse_err(
            &format!(r#"{{"links": {{"{first}": {{"fifo_depth": {depth}}}}}}}"#),
            &format!("links.{first}.fifo_depth"),
        );
    }
}

/// `links` is keyed by the graph's boundary names: an unknown or repeated name is
/// refused with its path, and what is written reads back the same, in the graph's order.
#[test]
fn config_links_follow_the_unit_graph() {
    let message = assert_parse_err(r#"{"links": {"setup_to_rop": {}}}"#, "links.setup_to_rop");
    assert!(
        message.contains(&format!(
            "unknown field `setup_to_rop`, expected one of `{}`",
            LINK_KEYS[0]
        )),
        "{message}"
    );
    let message = assert_parse_err(
        r#"{"links": {"rop_to_framebuffer": {}, "rop_to_framebuffer": {}}}"#,
        "links",
    );
    assert!(
        message.contains("duplicate field `rop_to_framebuffer`"),
        "{message}"
    );
    let mut links = LinksConfig::default();
    for (i, link) in links.all_mut().into_iter().enumerate() {
        *link = LinkConfig::new(i as u32 + 1, 2 * i as u64 + 1);
    }
    let json = serde_json::to_string(&links).unwrap();
    let at: Vec<usize> = LINK_KEYS
        .iter()
        .map(|k| json.find(&format!("\"{k}\":")).expect(k))
        .collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "{json}");
    let back: LinksConfig = serde_json::from_str(&json).unwrap();
    assert_eq!(back, links);
    for b in BOUNDARIES {
        assert_eq!(
            *LinksConfig::default().get(b.from, b.to),
            b.default,
            "{}",
            b.key
        );
    }
}

#[test]
fn config_unknown_field_names_its_path() {
    let message = assert_parse_err(r#"{"segmenter": {"cnt": 3}}"#, "segmenter.cnt");
    assert!(message.contains("unknown field `cnt`"), "{message}");
    assert_parse_err(
        r#"{"links": {"rasterizer_to_rop": {"depth": 3}}}"#,
        "links.rasterizer_to_rop.depth",
    );
    assert_parse_err(r#"{"clock": 400}"#, "clock");
}

#[test]
fn config_wrong_type_and_malformed_json_are_parse_errors() {
    assert_parse_err(r#"{"segmenter": {"count": -1}}"#, "segmenter.count");
    assert_parse_err(r#"{"rop": {"tile_px": 8.5}}"#, "rop.tile_px");
    assert_parse_err(r#"{"clock_mhz": "fast"}"#, "clock_mhz");
    let message = assert_parse_err("{} {}", "");
    assert!(message.contains("trailing characters"), "{message}");
    let message = assert_parse_err("not json", "");
    assert!(message.contains("line 1 column"), "{message}");
}

#[test]
fn config_zero_fifo_depth_is_refused_naming_the_link() {
    for (name, _) in ArchConfig::default().links.all() {
        let text = format!(r#"{{"links": {{"{name}": {{"fifo_depth": 0}}}}}}"#);
        assert_invalid(&text, &format!("links.{name}.fifo_depth"), "0");
    }
    assert_invalid(
        r#"{"links": {"rop_to_framebuffer": {"fifo_depth": 4097}}}"#,
        "links.rop_to_framebuffer.fifo_depth",
        "4097",
    );
    let first = LINK_KEYS[0];
    assert_invalid(
        &format!(r#"{{"links": {{"{first}": {{"latency_cycles": 0}}}}}}"#),
        &format!("links.{first}.latency_cycles"),
        "0",
    );
}

#[test]
fn config_zero_unit_count_is_refused_naming_the_unit() {
    assert_invalid(r#"{"segmenter": {"count": 0}}"#, "segmenter.count", "0");
    assert_invalid(
        r#"{"subsegmenter": {"count": 0}}"#,
        "subsegmenter.count",
        "0",
    );
    assert_invalid(r#"{"rasterizer": {"count": 65}}"#, "rasterizer.count", "65");
    assert_invalid(r#"{"rop": {"count": 0}}"#, "rop.count", "0");
    assert_invalid(r#"{"setup": {"count": 0}}"#, "setup.count", "0");
    assert_invalid(
        r#"{"triangle_setup": {"count": 65}}"#,
        "triangle_setup.count",
        "65",
    );
}

#[test]
fn config_front_end_batch_out_of_range_is_refused_naming_it() {
    assert_invalid(r#"{"setup": {"batch": 0}}"#, "setup.batch", "0");
    assert_invalid(
        r#"{"triangle_setup": {"batch": 65537}}"#,
        "triangle_setup.batch",
        "65537",
    );
    let ok = ArchConfig::from_json(
        r#"{"setup": {"count": 64, "batch": 1}, "triangle_setup": {"count": 4, "batch": 65536}}"#,
        "test",
    )
    .unwrap();
    assert_eq!(ok.unit(UnitKind::Setup).0, 64);
    assert_eq!(ok.unit(UnitKind::TriangleSetup).0, 4);
}

/// The triangle source and its units: an unknown source is a parse error naming the
/// field (with the sources it accepts), a zero vertex cache or count is refused.
#[test]
fn config_tessellation_fields_are_checked_naming_them() {
    let message = assert_parse_err(
        r#"{"tessellation": {"source": "disk"}}"#,
        "tessellation.source",
    );
    assert!(
        message.contains("`memory`") && message.contains("`onchip`"),
        "{message}"
    );
    assert_invalid(
        r#"{"tessellation": {"vertex_cache_entries": 0}}"#,
        "tessellation.vertex_cache_entries",
        "0",
    );
    assert_invalid(
        r#"{"tessellation": {"vertex_cache_entries": 4097}}"#,
        "tessellation.vertex_cache_entries",
        "4097",
    );
    assert_invalid(r#"{"tessellator": {"count": 0}}"#, "tessellator.count", "0");
    assert_invalid(r#"{"tessellator": {"batch": 0}}"#, "tessellator.batch", "0");
    assert_invalid(
        r#"{"domain_eval": {"cycles_per_vertex": 0}}"#,
        "domain_eval.cycles_per_vertex",
        "0",
    );
    let ok = ArchConfig::from_json(
        r#"{"tessellation": {"source": "onchip"}, "tessellator": {"count": 3}}"#,
        "test",
    )
    .unwrap();
    assert_eq!(ok.tessellation.source, TessSource::OnChip);
    assert_eq!(ok.unit(UnitKind::Tessellator).0, 3);
    let kinds: Vec<_> = ok
        .instances(PrimitivePath::Triangle)
        .into_iter()
        .map(|(u, _)| u.kind)
        .collect();
    assert!(kinds.contains(&UnitKind::DomainEval) && !kinds.contains(&UnitKind::Setup));
}

#[test]
fn config_out_of_range_costs_are_refused() {
    assert_invalid(
        r#"{"setup": {"latency_cycles": 0}}"#,
        "setup.latency_cycles",
        "0",
    );
    assert_invalid(
        r#"{"interval_manager": {"cycles_per_interval": 1000001}}"#,
        "interval_manager.cycles_per_interval",
        "1000001",
    );
    assert_invalid(
        r#"{"rasterizer": {"fragments_per_cycle": 65}}"#,
        "rasterizer.fragments_per_cycle",
        "65",
    );
    assert_invalid(
        r#"{"triangle_setup": {"cycles_per_clipped_piece": 0}}"#,
        "triangle_setup.cycles_per_clipped_piece",
        "0",
    );
    assert_invalid(r#"{"rop": {"tile_px": 0}}"#, "rop.tile_px", "0");
    assert_invalid(r#"{"rop": {"tile_px": 257}}"#, "rop.tile_px", "257");
    assert_invalid(
        r#"{"framebuffer": {"bytes_per_cycle": 0}}"#,
        "framebuffer.bytes_per_cycle",
        "0",
    );
    assert_invalid(
        r#"{"framebuffer": {"bytes_per_fragment_written": 4097}}"#,
        "framebuffer.bytes_per_fragment_written",
        "4097",
    );
}

#[test]
fn config_clock_must_be_positive_and_finite() {
    assert_invalid(r#"{"clock_mhz": 0}"#, "clock_mhz", "0");
    assert_invalid(r#"{"clock_mhz": -500}"#, "clock_mhz", "-500");
    assert_invalid(r#"{"clock_mhz": 100001}"#, "clock_mhz", "100001");
    // JSON has no NaN or infinity; too large a literal is a parse error, and a value
    // built in code is refused by validate.
    assert_parse_err(r#"{"clock_mhz": 1e400}"#, "clock_mhz");
    for clock_mhz in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let config = ArchConfig {
            clock_mhz,
            ..ArchConfig::default()
        };
        assert!(matches!(
            config.validate("code"),
            Err(Error::Invalid { field, .. }) if field == "clock_mhz"
        ));
    }
    let config = ArchConfig::from_json(r#"{"clock_mhz": 100000}"#, "t.json").unwrap();
    assert_eq!(config.clock_mhz, 100_000.0);
}

#[test]
fn config_name_must_be_short_and_non_empty() {
    assert_invalid(r#"{"name": ""}"#, "name", r#""""#);
    let long = "x".repeat(MAX_NAME_CHARS + 1);
    assert_invalid(
        &format!(r#"{{"name": "{long}"}}"#),
        "name",
        &format!("{long:?}"),
    );
    let longest = "é".repeat(MAX_NAME_CHARS);
    let text = format!(r#"{{"name": "{longest}"}}"#);
    assert_eq!(
        ArchConfig::from_json(&text, "t.json").unwrap().name,
        longest
    );
}

#[test]
fn config_missing_file_is_a_read_error() {
    let path = arch_dir().join("no_such_arch.json");
    assert!(matches!(ArchConfig::load(&path), Err(Error::Read { path: p, .. }) if p == path));
}

#[test]
fn config_serializes_back_to_itself() {
    let config = load("wide.json");
    let text = serde_json::to_string_pretty(&config).unwrap();
    assert_eq!(ArchConfig::from_json(&text, "round trip").unwrap(), config);
}

/// The sensitivity study's knobs (issue 48): their defaults are today's constants, halved
/// and doubled values are accepted, and out-of-range or non-1/64 values are refused naming
/// the field.
#[test]
fn config_sensitivity_knobs_default_halve_double_and_refuse() {
    // That the fetch's defaults are the formats' sizes is the lembo module's test
    // (`lembo::tessellate::tests`): the configuration sits below it.
    let d = ArchConfig::default();
    assert_eq!(d.framebuffer.access_cycles, Ratio::whole(1));
    assert_eq!(d.rop.fragments_per_cycle, Ratio::whole(1));
    assert_eq!(d.tessellator.cycles_per_triangle, Ratio::whole(1));
    assert_eq!(d.domain_eval.cycles_per_vertex, Ratio::whole(1));
    for scale in ["0.5", "2"] {
        let text = format!(
            r#"{{"framebuffer": {{"access_cycles": {scale}}}, "rop": {{"fragments_per_cycle": {scale}}},
                "tessellator": {{"cycles_per_triangle": {scale}}},
                "domain_eval": {{"cycles_per_vertex": {scale}}},
                "tessellation": {{"vertex_cache_entries": {}}},
                "fetch": {{"bytes_per_lembo": {}, "bytes_per_vertex": {},
                           "index_bytes_per_triangle": {}}}}}"#,
            if scale == "2" { 64 } else { 16 },
            if scale == "2" { 288 } else { 72 },
            if scale == "2" { 48 } else { 12 },
            if scale == "2" { 24 } else { 6 },
        );
        let a = ArchConfig::from_json(&text, "t.json").unwrap();
        assert_eq!(a.rop.fragments_per_cycle.get().to_string(), scale);
        // Whole values read back as the integers they were before they could be fractions.
        let back = serde_json::to_value(&a).unwrap();
        assert_eq!(back["framebuffer"]["access_cycles"].to_string(), scale);
    }
    for (text, field, value) in [
        (
            r#"{"framebuffer": {"access_cycles": 0}}"#,
            "framebuffer.access_cycles",
            "0",
        ),
        (
            r#"{"framebuffer": {"access_cycles": 0.3}}"#,
            "framebuffer.access_cycles",
            "0.3",
        ),
        (
            r#"{"framebuffer": {"access_cycles": 65}}"#,
            "framebuffer.access_cycles",
            "65",
        ),
        (
            r#"{"rop": {"fragments_per_cycle": 0}}"#,
            "rop.fragments_per_cycle",
            "0",
        ),
        (
            r#"{"rop": {"fragments_per_cycle": 65}}"#,
            "rop.fragments_per_cycle",
            "65",
        ),
        (
            r#"{"rop": {"fragments_per_cycle": -0.5}}"#,
            "rop.fragments_per_cycle",
            "-0.5",
        ),
        (
            r#"{"tessellator": {"cycles_per_triangle": 0.001}}"#,
            "tessellator.cycles_per_triangle",
            "0.001",
        ),
        (
            r#"{"domain_eval": {"cycles_per_vertex": 1000001}}"#,
            "domain_eval.cycles_per_vertex",
            "1000001",
        ),
        (
            r#"{"fetch": {"bytes_per_lembo": 0}}"#,
            "fetch.bytes_per_lembo",
            "0",
        ),
        (
            r#"{"fetch": {"bytes_per_vertex": 4097}}"#,
            "fetch.bytes_per_vertex",
            "4097",
        ),
        (
            r#"{"fetch": {"index_bytes_per_triangle": 0}}"#,
            "fetch.index_bytes_per_triangle",
            "0",
        ),
    ] {
        assert_invalid(text, field, value);
    }
    assert_parse_err(r#"{"fetch": {"bytes": 4}}"#, "fetch.bytes");
    assert_parse_err(
        r#"{"rop": {"fragments_per_cycle": "1"}}"#,
        "rop.fragments_per_cycle",
    );
}

/// Every kind of the unit graph has exactly one section declaring it (a kind inside another
/// has its host's): `unit` finds its count and latency, and `count_field` names a field
/// that sets the count, or none for a kind of one instance.
#[test]
fn config_every_kind_of_the_graph_has_one_section() {
    let declared = ArchConfig::declared_units();
    let mut wide = load("wide.json");
    for (i, link) in wide.links.all_mut().into_iter().enumerate() {
        link.latency_cycles = i as u64 + 1;
    }
    for kind in KINDS {
        let host = kind.inside().unwrap_or(kind);
        let sections: Vec<_> = declared.iter().filter(|(_, k)| *k == host).collect();
        assert_eq!(sections.len(), 1, "{kind:?}: {sections:?}");
        let (count, latency) = wide.unit(kind);
        match ArchConfig::count_field(kind) {
            Some(field) => {
                assert_eq!(field, format!("{}.count", sections[0].0));
                let set = [(field.to_string(), serde_json::json!(count + 1))];
                assert_eq!(
                    wide.with_fields(&set, "test").unwrap().unit(kind).0,
                    count + 1
                );
                let latency_field = field.replace(".count", ".latency_cycles");
                let set = [(latency_field, serde_json::json!(latency + 1))];
                assert_eq!(
                    wide.with_fields(&set, "test").unwrap().unit(kind).1,
                    latency + 1
                );
            }
            None => assert_eq!((count, latency), (1, 1), "{kind:?}"),
        }
    }
}

/// The names each enum field's rule lists (the README's table shows them) are exactly the
/// names serde reads and writes: each reads back as itself, and an unknown name is refused
/// with a message that lists them all.
#[test]
fn config_enum_rules_list_the_names_serde_accepts() {
    fn names_of<T: serde::de::DeserializeOwned + serde::Serialize>(rule: &rules::OneOf) {
        for name in rule.0 {
            let value: T = serde_json::from_value(serde_json::json!(name)).unwrap();
            assert_eq!(
                serde_json::to_value(&value).unwrap(),
                serde_json::json!(name)
            );
        }
        let message = serde_json::from_str::<T>("\"no_such_name\"")
            .err()
            .unwrap()
            .to_string();
        let listed: Vec<String> = message
            .split('`')
            .skip(3)
            .step_by(2)
            .map(str::to_string)
            .collect();
        assert_eq!(listed, rule.0, "{message}");
    }
    names_of::<CullBackfaces>(&sections::CULL_BACKFACES);
    names_of::<Reciprocal>(&sections::RECIPROCALS);
    names_of::<TessSource>(&sections::TESS_SOURCES);
}

/// A section's checks follow its declaration: for every field with a lower bound above 0,
/// the value 0 is refused naming the field's path; every default is accepted.
#[test]
fn config_every_declared_bound_is_checked() {
    ArchConfig::default().validate("default").unwrap();
    let mut refused = 0;
    for row in ArchConfig::rows() {
        let zero_refused = row.accepted.starts_with("1 ") || row.accepted.starts_with("1/");
        if !zero_refused || row.field == "name" {
            continue;
        }
        let set = [(row.field.clone(), serde_json::json!(0))];
        match ArchConfig::default().with_fields(&set, "--set") {
            Err(Error::Invalid { field, value, .. }) => {
                assert_eq!((field.as_str(), value.as_str()), (row.field.as_str(), "0"));
                refused += 1;
            }
            other => panic!("{}: {other:?}", row.field),
        }
    }
    assert!(refused > 50, "{refused}");
}

/// `sim/arch/README.md` holds the field table as the declarations generate it.
#[test]
fn config_readme_field_table_is_generated() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim/arch/README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let fresh = table::with_table(&readme, &fields_table()).unwrap_or_else(|| {
        panic!(
            "sim/arch/README.md has no generated field table: add the lines\n{}\n{}",
            table::BEGIN,
            table::END
        )
    });
    if fresh == readme {
        return;
    }
    if std::env::var_os(REFRESH).is_some_and(|v| v == "1") {
        std::fs::write(&path, &fresh).unwrap();
        return;
    }
    panic!(
        "sim/arch/README.md's field table differs from the declarations in src/config; \
         refresh it with\n  {REFRESH}=1 cargo test --lib config::tests::config_readme_field_table_is_generated"
    );
}

/// The variable that makes [`config_readme_field_table_is_generated`] rewrite the README.
const REFRESH: &str = "LEMBO_REFRESH_DOCS";

/// The table's generation: one row per field of a file, and the README's copy replaced
/// between its markers only.
#[test]
fn config_field_table_lists_every_field() {
    let mut every = Vec::new();
    leaf_paths(
        &serde_json::to_value(ArchConfig::default()).unwrap(),
        "",
        &mut every,
    );
    every.sort();
    let mut rows: Vec<String> = ArchConfig::rows().into_iter().map(|r| r.field).collect();
    rows.sort();
    assert_eq!(rows, every);
    let readme = format!("intro\n{}\nold\n{}\ncost model\n", table::BEGIN, table::END);
    let fresh = table::with_table(&readme, "| new |\n").unwrap();
    assert_eq!(
        fresh,
        format!(
            "intro\n{}\n\n| new |\n\n{}\ncost model\n",
            table::BEGIN,
            table::END
        )
    );
    assert_eq!(table::with_table("no markers", "x"), None);
    let row = ArchConfig::rows()
        .into_iter()
        .find(|r| r.field == "rop.tile_px")
        .unwrap();
    assert_eq!(
        (row.default.as_str(), row.accepted.as_str()),
        ("8", "1 to 256")
    );
}

/// The memory fields refuse what the caches and the DRAM cannot be, naming the field, before
/// any work: a cache smaller than a line, no ways, a line not a whole number of sectors, a
/// line that is not one tile, no channels or a count the mapping cannot split, an unknown
/// DRAM kind, and a ROP tile that splits a memory tile under the DRAM model.
#[test]
fn memory_fields_refuse_what_no_cache_or_dram_can_be() {
    let m = |fields: &str| format!(r#"{{"memory": {{{fields}}}}}"#);
    assert_invalid(
        &m(r#""colour_cache_bytes": 128"#),
        "memory.colour_cache_bytes",
        "128",
    );
    assert_invalid(
        &m(r#""depth_cache_bytes": 12288"#),
        "memory.depth_cache_bytes",
        "12288",
    );
    assert_invalid(&m(r#""cache_ways": 0"#), "memory.cache_ways", "0");
    assert_invalid(&m(r#""sector_bytes": 48"#), "memory.sector_bytes", "48");
    assert_invalid(
        &m(r#""sector_bytes": 512"#),
        "memory.cache_line_bytes",
        "256",
    );
    assert_invalid(
        &m(r#""cache_line_bytes": 512, "colour_cache_bytes": 32768, "depth_cache_bytes": 32768"#),
        "memory.cache_line_bytes",
        "512",
    );
    assert_invalid(&m(r#""channels": 0"#), "memory.channels", "0");
    assert_invalid(&m(r#""channels": 3"#), "memory.channels", "3");
    let message = assert_parse_err(&m(r#""dram": "hbm9""#), "memory.dram");
    assert!(message.contains("gddr6"), "{message}");
    // The port model leaves the ROP tile free; the DRAM model needs whole memory tiles.
    let tile = r#"{"rop": {"tile_px": 4}, "memory": {"model": "dram"}}"#;
    assert_invalid(tile, "rop.tile_px", "4");
    assert!(ArchConfig::from_json(r#"{"rop": {"tile_px": 4}}"#, "t.json").is_ok());
    assert!(ArchConfig::from_json(
        r#"{"rop": {"tile_px": 16}, "memory": {"model": "dram"}}"#,
        "t.json"
    )
    .is_ok());
    // Through --set, as from a file.
    let set = [("memory.channels".to_string(), serde_json::json!(0))];
    let e = ArchConfig::default()
        .with_fields(&set, "--set")
        .unwrap_err();
    assert!(
        matches!(&e, Error::Invalid { field, .. } if field == "memory.channels"),
        "{e}"
    );
}
