//! Tests of scene loading: the format and its defaults, cameras, meshes (OBJ, welding,
//! creases, truncated files), inline lembos, transforms, subdivision, and every refusal by
//! field; discoid objects in [`discoids`].

use super::mesh::load_obj;
use super::pointcloud::SURFEL_PROPERTIES;
use super::validate::median;
use super::*;
use crate::camera::Projection;
use crate::discoid::shapes::discoids_from_mesh;
use crate::discoid::{BetaShape, Discoid};
use crate::error::{Error, Result};
use crate::lembo::shapes::BUILTIN_NAMES;
use glam::DVec3;
use std::io::Write;
use std::path::{Path, PathBuf};

fn traces() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("traces")
}

const SPHERE: &str = r#"{
    "name": "t",
    "camera": {"eye": [0, 0, 4], "target": [0, 0, 0],
               "projection": {"kind": "perspective", "fovy_deg": 40, "near": 0.1, "far": 100}},
    "objects": [{"builtin": "sphere24"}]
}"#;

fn parse(text: &str) -> Result<Scene> {
    Scene::from_json(text, "test.json", &traces())
}

/// The sphere scene with one substring replaced; panics if it is absent.
fn sphere_with(from: &str, to: &str) -> Result<Scene> {
    assert!(SPHERE.contains(from), "{from}");
    parse(&SPHERE.replacen(from, to, 1))
}

/// The error, or the scene's name (a scene's Debug output is pages of numbers).
fn summary(r: &Result<Scene>) -> String {
    match r {
        Ok(scene) => format!("Ok(scene {:?})", scene.name),
        Err(e) => format!("{e:?}"),
    }
}

fn assert_parse_err(r: Result<Scene>, want_field: &str) -> String {
    match r {
        Err(Error::Parse {
            file,
            field,
            message,
        }) => {
            assert_eq!(file, "test.json");
            assert!(
                field.contains(want_field),
                "field {field:?} lacks {want_field:?}: {message}"
            );
            message
        }
        other => panic!(
            "expected a parse error at {want_field}, got {}",
            summary(&other)
        ),
    }
}

fn assert_invalid(r: Result<Scene>, want_field: &str) -> String {
    match r {
        Err(Error::Invalid {
            file,
            field,
            reason,
            ..
        }) => {
            assert_eq!(file, "test.json");
            assert_eq!(field, want_field, "{reason}");
            reason
        }
        other => panic!(
            "expected an invalid-value error at {want_field}, got {}",
            summary(&other)
        ),
    }
}

fn assert_mesh_err(r: Result<Scene>, want_field: &str) -> String {
    match r {
        Err(Error::Mesh { field, message, .. }) => {
            assert_eq!(field, want_field, "{message}");
            message
        }
        other => panic!(
            "expected a mesh error at {want_field}, got {}",
            summary(&other)
        ),
    }
}

#[test]
fn committed_traces_load_with_their_lembo_counts() {
    for (file, lembos) in [
        ("sphere24", 24),
        ("cylinder24", 24),
        ("surface96", 96),
        ("bunny", 3674),
        ("default", 24),
        ("capped_cylinder", 48),
        ("bevel_cube", 44),
        ("bunny_creased", 3674),
    ] {
        let path = traces().join(format!("{file}.json"));
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.name, file);
        assert_eq!(scene.lembo_count(), lembos, "{file}");
        assert_eq!(scene.lembos().count(), lembos, "{file}");
        assert_eq!(scene.source.as_deref(), Some(path.as_path()));
        assert_eq!(scene.viewport, DEFAULT_VIEWPORT);
        assert!(scene.objects.iter().all(|o| o.mesh().is_some()));
        assert!(scene.objects.iter().all(|o| o.discoids.is_none()));
        assert_eq!(scene.discoid_count(), 0);
        assert_eq!(scene.discoid_threshold, 0.0);
    }
}

#[test]
fn default_scene_is_the_sphere() {
    let scene = Scene::default_scene();
    assert_eq!(scene.name, "default");
    assert!(scene.source.is_none());
    assert_eq!(scene.lembo_count(), 24);
    let sphere = Scene::load(&traces().join("sphere24.json")).unwrap();
    assert_eq!(scene.camera, sphere.camera);
    assert_eq!(scene.light, sphere.light);
    assert_eq!(scene.objects[0].lembos, sphere.objects[0].lembos);
}

#[test]
fn defaults_fill_optional_fields() {
    let scene = parse(SPHERE).unwrap();
    assert_eq!(scene.viewport, DEFAULT_VIEWPORT);
    assert_eq!(scene.light, Light::default());
    assert_eq!(scene.background, DEFAULT_BACKGROUND);
    assert_eq!(scene.camera.up, [0.0, 1.0, 0.0]);
    assert_eq!(scene.objects[0].color, DEFAULT_COLOR);
    assert_eq!(scene.objects[0].label, "builtin sphere24");
    // A partial light keeps the other terms' defaults.
    let scene = sphere_with(r#""objects""#, r#""light": {"ka": 0.5}, "objects""#).unwrap();
    assert_eq!(
        scene.light,
        Light {
            ka: 0.5,
            ..Light::default()
        }
    );
}

#[test]
fn missing_scene_file_is_a_read_error() {
    let path = traces().join("no_such_scene.json");
    assert!(matches!(Scene::load(&path), Err(Error::Read { path: p, .. }) if p == path));
}

#[test]
fn malformed_json_is_a_parse_error_with_line_and_column() {
    for text in ["not json", "{ \"name\": \"t\",, }", ""] {
        match parse(text) {
            Err(Error::Parse { field, message, .. }) => {
                assert_eq!(field, "", "{text}");
                assert!(message.contains("line 1 column"), "{message}");
            }
            other => panic!("{}", summary(&other)),
        }
    }
    match parse(&format!("{SPHERE} {{}}")) {
        Err(Error::Parse { field, message, .. }) => {
            assert_eq!(field, "");
            assert!(message.contains("trailing characters"), "{message}");
        }
        other => panic!("{}", summary(&other)),
    }
    // Inside a value the path names where the parser stopped.
    let r = sphere_with(r#""eye": [0, 0, 4]"#, r#""eye": [0, 0 4]"#);
    assert_parse_err(r, "camera.eye");
}

#[test]
fn unknown_field_names_its_parent() {
    let message = assert_parse_err(sphere_with(r#""eye""#, r#""eyes""#), "camera");
    assert!(message.contains("eyes"), "{message}");
    assert_parse_err(sphere_with(r#""builtin""#, r#""shape""#), "objects[0]");
}

#[test]
fn wrong_type_names_the_field() {
    assert_parse_err(
        sphere_with(r#""fovy_deg": 40"#, r#""fovy_deg": "wide""#),
        "camera.projection.fovy_deg",
    );
    let inline = r#"{"lembos": [{"points": [[0,0,0],[1,0,0],[0,1,0],[0.5,0,0],[0,0.5,0],[0.5,0.5,0]],
                                 "normals": [[0,0,1],[0,0,1],[0,0,1],[0,0,1],[0,0,1]]}]}"#;
    // Five normals where six are needed.
    assert_parse_err(
        sphere_with(r#"{"builtin": "sphere24"}"#, inline),
        "objects[0].lembos[0].normals",
    );
}

#[test]
fn perspective_and_orthographic_fields_are_not_mixed() {
    assert_parse_err(
        sphere_with(r#""fovy_deg": 40"#, r#""height": 3"#),
        "camera.projection",
    );
    let r = sphere_with(
        r#""kind": "perspective""#,
        r#""kind": "orthographic", "height": 3"#,
    );
    assert_parse_err(r, "camera.projection.fovy_deg");
    let scene = sphere_with(
        r#""kind": "perspective", "fovy_deg": 40"#,
        r#""kind": "orthographic", "height": 3"#,
    )
    .unwrap();
    assert_eq!(
        scene.camera.projection,
        Projection::Orthographic {
            height: 3.0,
            near: 0.1,
            far: 100.0
        }
    );
}

#[test]
fn infinite_number_names_the_field() {
    // serde_json refuses numbers beyond f64's range as it parses; the path is kept.
    let message = assert_parse_err(
        sphere_with(r#""far": 100"#, r#""far": 1e999"#),
        "camera.projection.far",
    );
    assert!(message.contains("out of range"), "{message}");
    assert_parse_err(
        sphere_with(r#""eye": [0, 0, 4]"#, r#""eye": [0, -1e400, 4]"#),
        "camera.eye[1]",
    );
}

#[test]
fn viewport_sides_outside_1_to_16384_are_refused() {
    let with = |w: u32, h: u32| {
        sphere_with(
            r#""objects""#,
            &format!(r#""viewport": {{"width": {w}, "height": {h}}}, "objects""#),
        )
    };
    assert_invalid(with(0, 512), "viewport.width");
    assert_invalid(with(512, 16385), "viewport.height");
    assert_eq!(
        with(16384, 1).unwrap().viewport,
        Viewport {
            width: 16384,
            height: 1
        }
    );
    // A negative side does not fit a u32: a parse error at the field.
    assert_parse_err(
        sphere_with(
            r#""objects""#,
            r#""viewport": {"width": -1, "height": 8}, "objects""#,
        ),
        "viewport.width",
    );
}

#[test]
fn set_viewport_is_validated_like_the_file() {
    let mut scene = parse(SPHERE).unwrap();
    scene.set_viewport(640, 480).unwrap();
    assert_eq!(
        scene.viewport,
        Viewport {
            width: 640,
            height: 480
        }
    );
    match scene.set_viewport(640, 16385) {
        Err(Error::Invalid { field, .. }) => assert_eq!(field, "viewport.height"),
        other => panic!("{other:?}"),
    }
    assert_eq!(
        scene.viewport,
        Viewport {
            width: 640,
            height: 480
        }
    );
}

#[test]
fn near_must_be_positive_and_far_beyond_it() {
    assert_invalid(
        sphere_with(r#""near": 0.1"#, r#""near": 0"#),
        "camera.projection.near",
    );
    assert_invalid(
        sphere_with(r#""near": 0.1"#, r#""near": -1"#),
        "camera.projection.near",
    );
    assert_invalid(
        sphere_with(r#""far": 100"#, r#""far": 0.1"#),
        "camera.projection.far",
    );
    assert_invalid(
        sphere_with(r#""fovy_deg": 40"#, r#""fovy_deg": 180"#),
        "camera.projection.fovy_deg",
    );
}

#[test]
fn degenerate_cameras_are_refused() {
    assert_invalid(
        sphere_with(r#""target": [0, 0, 0]"#, r#""target": [0, 0, 4]"#),
        "camera.target",
    );
    let r = sphere_with(
        r#""target": [0, 0, 0]"#,
        r#""target": [0, 0, 0], "up": [0, 0, -2]"#,
    );
    assert_invalid(r, "camera.up");
}

#[test]
fn out_of_range_colours_and_light_terms_are_refused() {
    assert_invalid(
        sphere_with(r#""objects""#, r#""background": [0, 0, 1.5], "objects""#),
        "background",
    );
    let r = sphere_with(
        r#"{"builtin": "sphere24"}"#,
        r#"{"builtin": "sphere24", "color": [0.5, -0.1, 0]}"#,
    );
    assert_invalid(r, "objects[0].color");
    assert_invalid(
        sphere_with(r#""objects""#, r#""light": {"kd": -0.5}, "objects""#),
        "light.kd",
    );
    let r = sphere_with(
        r#""objects""#,
        r#""light": {"direction_to_light": [0, 0, 0]}, "objects""#,
    );
    assert_invalid(r, "light.direction_to_light");
}

#[test]
fn scene_name_must_be_a_directory_name() {
    let reason = assert_invalid(sphere_with(r#""name": "t""#, r#""name": "../up""#), "name");
    assert!(reason.contains("out/<name>/"), "{reason}");
    assert_invalid(sphere_with(r#""name": "t""#, r#""name": """#), "name");
}

#[test]
fn object_with_two_kinds_or_none_is_refused() {
    let r = sphere_with(
        r#"{"builtin": "sphere24"}"#,
        r#"{"builtin": "sphere24", "mesh": "meshes/bunny.obj"}"#,
    );
    let _ = assert_invalid(r, "objects[0]");
    assert_invalid(
        sphere_with(r#"{"builtin": "sphere24"}"#, r#"{"color": [1, 1, 1]}"#),
        "objects[0]",
    );
}

#[test]
fn unknown_builtin_lists_the_known_names() {
    let reason = assert_invalid(sphere_with("sphere24", "teapot"), "objects[0].builtin");
    for name in BUILTIN_NAMES {
        assert!(reason.contains(name), "{reason}");
    }
    assert!(reason.contains("terrainN"), "{reason}");
}

/// Builtin terrains are bounded together, before any is made: a few bytes of scene cannot
/// ask for more lembos than one terrain2048's.
#[test]
fn builtin_terrains_beyond_the_cap_are_refused_before_they_are_made() {
    let objects = r#"{"builtin": "terrain2048"}, {"builtin": "terrain1"}"#;
    let reason = assert_invalid(
        sphere_with(r#"{"builtin": "sphere24"}"#, objects),
        "objects[1].builtin",
    );
    assert!(reason.contains("8388610 lembos"), "{reason}");
}

#[test]
fn bad_transform_is_refused() {
    let r = sphere_with(
        r#"{"builtin": "sphere24"}"#,
        r#"{"builtin": "sphere24", "transform": {"scale": 0}}"#,
    );
    assert_invalid(r, "objects[0].transform.scale");
    let r = sphere_with(
        r#"{"builtin": "sphere24"}"#,
        r#"{"builtin": "sphere24", "transform": {"scale": 1e300}}"#,
    );
    assert_invalid(r, "objects[0].transform");
}

#[test]
fn missing_obj_file_is_a_mesh_error_with_the_os_reason() {
    let message = assert_mesh_err(
        sphere_with(
            r#""builtin": "sphere24""#,
            r#""mesh": "meshes/missing.obj""#,
        ),
        "objects[0].mesh",
    );
    let os = std::fs::read("/nonexistent/lembo-sim")
        .unwrap_err()
        .to_string();
    assert_eq!(message, os);
}

fn scene_with_obj(obj: &str) -> Result<Scene> {
    let dir = tempfile::tempdir().unwrap();
    let mut f = std::fs::File::create(dir.path().join("m.obj")).unwrap();
    f.write_all(obj.as_bytes()).unwrap();
    let text = SPHERE.replacen(r#""builtin": "sphere24""#, r#""mesh": "m.obj""#, 1);
    Scene::from_json(&text, "test.json", dir.path())
}

#[test]
fn obj_with_nan_coordinate_is_a_mesh_error() {
    let message = assert_mesh_err(
        scene_with_obj("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n"),
        "objects[0].mesh",
    );
    assert!(message.contains("non-finite"), "{message}");
}

#[test]
fn obj_without_triangles_or_with_bad_indices_is_a_mesh_error() {
    assert_mesh_err(
        scene_with_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        "objects[0].mesh",
    );
    assert_mesh_err(
        scene_with_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"),
        "objects[0].mesh",
    );
}

/// A file cut short or broken by hand names the line where it went wrong: a vertex cut
/// mid-number, a face cut to two corners (which tobj alone would drop as a line), a corner
/// naming a vertex the file does not give, or one that is not a number.
#[test]
fn a_truncated_or_malformed_obj_names_the_line() {
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n";
    for (tail, line) in [
        ("v 1 1", 6),
        ("f 2 4", 6),
        ("f 2 4 3\nf 2 4 5\n", 7),
        ("f 2/1 4 3\n", 6),
        ("f 2 4 3x\n", 6),
        ("vn 0 0\n", 6),
    ] {
        let message = assert_mesh_err(scene_with_obj(&format!("{head}{tail}")), "objects[0].mesh");
        assert!(
            message.starts_with(&format!("line {line} (")),
            "{tail:?}: {message}"
        );
    }
    // Negative indices count back from the last vertex given.
    let scene = scene_with_obj(&format!("{head}f -3 -1 -2\n")).unwrap();
    assert_eq!(scene.lembo_count(), 2);
}

#[test]
fn obj_quads_are_triangulated_and_normals_computed() {
    let scene = scene_with_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
    let mesh = scene.objects[0].mesh().unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    assert!(mesh.normals.iter().all(|n| *n == DVec3::Z));
    assert_eq!(scene.lembo_count(), 2);
}

#[test]
fn obj_triangle_whose_corners_weld_is_a_mesh_error_naming_it() {
    // Triangle 1's corners 2 and 3 differ by far less than the weld tolerance.
    let message = assert_mesh_err(
        scene_with_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1e-12 0\nf 1 2 3\nf 2 4 3\n"),
        "objects[0].mesh",
    );
    assert!(
        message.starts_with("triangle 1 ") && message.contains("corners 0 and 1"),
        "{message}"
    );
}

#[test]
fn split_obj_vertices_are_welded_into_shared_edges() {
    // Two triangles on one edge, written with separate positions and normals: the edge's
    // midpoint is shared and each side keeps its normals.
    let scene = scene_with_obj(
        "v 0 0 0\nv 2 0 0\nv 1 1 0\nv 0 0 0\nv 2 0 0\nv 1 -1 1\n\
         vn 0 0 1\nvn 0 -0.7 0.7\n\
         f 1//1 2//1 3//1\nf 5//2 4//2 6//2\n",
    )
    .unwrap();
    let l = scene.objects[0].lembos.to_vec();
    assert_eq!(l[0].points[3], l[1].points[3]);
    assert_eq!(l[0].normals[0], DVec3::Z);
    assert_ne!(l[1].normals[0], DVec3::Z);
}

#[test]
fn crease_angle_recomputes_a_meshs_normals() {
    let with = |angle: &str| {
        let text = SPHERE.replacen(
            r#""builtin": "sphere24""#,
            &format!(r#""mesh": "meshes/bunny.obj", "crease_angle_deg": {angle}"#),
            1,
        );
        parse(&text)
    };
    let creased = with("40").unwrap();
    let mesh = creased.objects[0].mesh().unwrap();
    assert_eq!(mesh.triangles.len(), 3674);
    assert!(
        mesh.positions.len() > 1839,
        "split vertices: {}",
        mesh.positions.len()
    );
    // 180 degrees averages every face: the computed normals, one per vertex.
    let all = with("180").unwrap();
    let computed = bunny_mesh().with_computed_normals();
    let mesh = all.objects[0].mesh().unwrap();
    assert_eq!(mesh.positions.len(), 1839);
    for (t, u) in mesh.triangles.iter().zip(&computed.triangles) {
        for (&i, &j) in t.iter().zip(u) {
            assert_eq!(mesh.normals[i as usize], computed.normals[j as usize]);
        }
    }
    for bad in ["-1", "180.5", "1e300"] {
        let reason = assert_invalid(with(bad), "objects[0].crease_angle_deg");
        assert!(reason.contains("[0, 180]"), "{reason}");
    }
    assert_parse_err(with("\"40\""), "objects[0].crease_angle_deg");
    let reason = assert_invalid(
        sphere_with(
            r#""builtin": "sphere24""#,
            r#""builtin": "sphere24", "crease_angle_deg": 40"#,
        ),
        "objects[0].crease_angle_deg",
    );
    assert!(reason.contains("`mesh` objects only"), "{reason}");
}

const INLINE: &str = r#"{"lembos": [{"points": [[0,0,0],[1,0,0],[0,1,0],[0.5,0,0.25],[0,0.5,0.25],[0.5,0.5,0.125]],
                                     "normals": [[0,0,1],[0,0,2],[0,0,1],[0,0.1,1],[0.1,0,1],[0.1,0.1,1]]}],
                        "transform": {"scale": 1, "rotate_deg": [0, 0, 0], "translate": [0, 0, 0]}}"#;

#[test]
fn inline_lembo_round_trips_through_an_identity_transform() {
    let scene = sphere_with(r#"{"builtin": "sphere24"}"#, INLINE).unwrap();
    let o = &scene.objects[0];
    assert!(o.mesh().is_none());
    assert_eq!(o.label, "inline lembos");
    let l = &o.lembos.get(0);
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 0.0, 0.25],
        [0.0, 0.5, 0.25],
        [0.5, 0.5, 0.125],
    ];
    assert_eq!(l.points.map(|p| p.to_array()), points);
    // Inline normals keep their length.
    assert_eq!(l.normals[1], DVec3::new(0.0, 0.0, 2.0));
}

#[test]
fn inline_lembo_is_rotated_with_its_normals() {
    let text = INLINE.replace(r#""rotate_deg": [0, 0, 0]"#, r#""rotate_deg": [0, 0, 90]"#);
    let scene = sphere_with(r#"{"builtin": "sphere24"}"#, &text).unwrap();
    let l = &scene.objects[0].lembos.get(0);
    // 90 degrees about z takes x to y.
    assert!((l.points[1] - DVec3::Y).length() < 1e-15);
    assert!((l.normals[1] - DVec3::new(0.0, 0.0, 2.0)).length() < 1e-15);
}

#[test]
fn inline_lembos_must_not_be_empty() {
    assert_invalid(
        sphere_with(r#"{"builtin": "sphere24"}"#, r#"{"lembos": []}"#),
        "objects[0].lembos",
    );
}

#[test]
fn transform_scales_then_rotates_then_translates() {
    let plain = parse(SPHERE).unwrap();
    let moved = sphere_with(
        r#"{"builtin": "sphere24"}"#,
        r#"{"builtin": "sphere24", "transform": {"scale": 2, "translate": [1, -2, 3]}}"#,
    )
    .unwrap();
    let offset = DVec3::new(1.0, -2.0, 3.0);
    for (a, b) in plain.objects[0]
        .lembos
        .iter()
        .zip(moved.objects[0].lembos.iter())
    {
        for k in 0..6 {
            assert!((b.points[k] - (2.0 * a.points[k] + offset)).length() < 1e-12);
            assert!((b.normals[k] - a.normals[k]).length() < 1e-12);
        }
    }
    let mesh = moved.objects[0].mesh().unwrap();
    assert!((mesh.positions[0] - (2.0 * DVec3::Y + offset)).length() < 1e-12);
    // X first, then Y: a 90-degree turn about x takes +y to +z, then 90 about y takes
    // +z to +x.
    let turned = sphere_with(
        r#"{"builtin": "sphere24"}"#,
        r#"{"builtin": "sphere24", "transform": {"rotate_deg": [90, 90, 0]}}"#,
    )
    .unwrap();
    let north = turned.objects[0].mesh().unwrap().positions[0];
    assert!((north - DVec3::X).length() < 1e-12, "{north}");
}

/// `subdivide` splits each lembo into 4^s; out of range, on discoids or beyond the scene's
/// cap, it is refused naming the field, before the subdivision is made.
#[test]
fn subdivided_objects_have_four_to_the_s_lembos_each() {
    let scene = sphere_with(
        r#"{"builtin": "sphere24"}"#,
        r#"{"builtin": "sphere24", "subdivide": 2}"#,
    )
    .unwrap();
    assert_eq!(scene.lembo_count(), 24 * 16);
    let reason = assert_invalid(
        sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"builtin": "sphere24", "subdivide": 6}"#,
        ),
        "objects[0].subdivide",
    );
    assert!(reason.contains("0 to 5"), "{reason}");
    // terrain10 subdivided once is 800 lembos; terrain100 (20 000) subdivided five times
    // would add 20 480 000.
    let reason = assert_invalid(
        sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"builtin": "terrain10", "subdivide": 1}, {"builtin": "terrain100", "subdivide": 5}"#,
        ),
        "objects[1].subdivide",
    );
    assert!(reason.contains("20480800 lembos"), "{reason}");
    let reason = assert_invalid(
        sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"discoids": {"builtin": "sphere20"}, "subdivide": 1}"#,
        ),
        "objects[0].subdivide",
    );
    assert!(reason.contains("discoids"), "{reason}");
}

/// The bunny's mesh as its OBJ file gives it.
fn bunny_mesh() -> TriangleMesh {
    load_obj("test", "mesh", &traces().join("meshes/bunny.obj")).unwrap()
}

mod discoids;
mod tessellation;
