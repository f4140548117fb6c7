//! Tests of scene loading: the format and its defaults, cameras, meshes (OBJ, welding,
//! creases), inline lembos, transforms, discoids and surfels, and every refusal by field.

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

// ---- Discoids ------------------------------------------------------------------------

/// The sphere scene with its object replaced by `object` (JSON).
fn with_object(object: &str) -> Result<Scene> {
    sphere_with(r#"{"builtin": "sphere24"}"#, object)
}

fn discoid_set(scene: &Scene, i: usize) -> &DiscoidSet {
    scene.objects[i].discoids.as_ref().unwrap()
}

fn bunny_mesh() -> TriangleMesh {
    load_obj("test", "mesh", &traces().join("meshes/bunny.obj")).unwrap()
}

/// A binary little-endian surfel PLY file: one row x y z nx ny nz radius per vertex.
fn surfel_ply(rows: &[[f32; 7]], comment: &str) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\ncomment {comment}\nelement vertex {}\n",
        rows.len()
    )
    .into_bytes();
    for p in SURFEL_PROPERTIES {
        out.extend(format!("property float {p}\n").bytes());
    }
    out.extend(b"end_header\n");
    for x in rows.iter().flatten() {
        out.extend(x.to_le_bytes());
    }
    out
}

/// The content of `traces/pointclouds/bunny_surfels.ply`: the bunny mesh's vertices with
/// their unit normals and radius = the mean length of their edges, as f32.
fn bunny_surfels_ply() -> Vec<u8> {
    let rows: Vec<[f32; 7]> = discoids_from_mesh(&bunny_mesh(), false, 1.0)
        .unwrap()
        .iter()
        .map(|d| {
            let (c, n) = (d.center, d.normal);
            [c.x, c.y, c.z, n.x, n.y, n.z, d.radius].map(|x| x as f32)
        })
        .collect();
    surfel_ply(
        &rows,
        "lembo-sim surfels of traces/meshes/bunny.obj: its vertices, unit normals and \
         radius = mean length of the vertex's edges",
    )
}

/// A scene whose only object reads `ply` (bytes) as surfels.
fn scene_with_ply(ply: &[u8]) -> Result<Scene> {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.ply"), ply).unwrap();
    let text = SPHERE.replacen(
        r#""builtin": "sphere24""#,
        r#""discoids": {"surfels": "s.ply"}"#,
        1,
    );
    Scene::from_json(&text, "test.json", dir.path())
}

#[test]
fn committed_discoid_traces_load_with_their_counts() {
    // (file, discoids, lembos, threshold or None for the default)
    for (file, discoids, lembos, threshold) in [
        ("discoid_sphere20", 1280, 1280, Some(0.25 * 0.65)),
        ("discoid_threshold", 17 * 17 + 25 * 25, 0, Some(0.025)),
        ("bunny_discoids", 1839 + 5511, 0, None),
        ("surfels_bunny", 1839, 0, None),
    ] {
        let path = traces().join(format!("{file}.json"));
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.name, file);
        assert_eq!(scene.viewport, DEFAULT_VIEWPORT);
        assert_eq!(scene.discoid_count(), discoids, "{file}");
        assert_eq!(scene.lembo_count(), lembos, "{file}");
        assert!(scene.objects.iter().all(|o| o.mesh().is_none()));
        for o in &scene.objects {
            let set = o.discoids.as_ref().unwrap();
            assert_eq!(set.beta, BetaShape::Disk);
            assert_eq!(set.lembo_texcoords.len(), o.lembos.len());
            assert_eq!(set.surfels, file == "surfels_bunny");
        }
        let mut radii: Vec<f64> = scene
            .objects
            .iter()
            .flat_map(|o| &o.discoids.as_ref().unwrap().planar)
            .map(|d| d.radius)
            .collect();
        let want = threshold.unwrap_or_else(|| 0.25 * median(&mut radii));
        assert_eq!(scene.discoid_threshold, want, "{file}");
    }
}

#[test]
fn sphere20_scene_threshold_exceeds_the_overlap_gap() {
    // The lembos of overlapping discoids lie within twice SPHERE20_MAX_SAG of each
    // other (discoid::shapes): the default threshold, a quarter of the discoids'
    // radius, blends them and stays far below the sphere's diameter.
    use crate::discoid::shapes::{SPHERE20_LEVELS, SPHERE20_MAX_SAG, SPHERE20_RADIUS};
    let scene = Scene::load(&traces().join("discoid_sphere20.json")).unwrap();
    assert_eq!(scene.discoid_threshold, 0.25 * SPHERE20_RADIUS);
    assert!(scene.discoid_threshold > 100.0 * SPHERE20_MAX_SAG);
    assert_eq!(
        discoid_set(&scene, 0).lembo_texcoords.len(),
        20 * 4usize.pow(SPHERE20_LEVELS)
    );
}

#[test]
fn threshold_scene_is_two_sheets_a_radius_apart_with_a_much_smaller_threshold() {
    let scene = Scene::load(&traces().join("discoid_threshold.json")).unwrap();
    let (front, back) = (
        &discoid_set(&scene, 0).planar,
        &discoid_set(&scene, 1).planar,
    );
    let radius = 0.125;
    assert!(front.iter().chain(back).all(|d| d.radius == radius));
    assert!(front
        .iter()
        .all(|d| d.center.z == 0.0 && d.normal == DVec3::Z));
    // The back sheet: z = -radius + 0.03 sin(2 pi x), normals of that surface (the file
    // holds 6 decimals).
    for d in back {
        let x = d.center.x;
        let z = -radius + 0.03 * (std::f64::consts::TAU * x).sin();
        let slope = 0.03 * std::f64::consts::TAU * (std::f64::consts::TAU * x).cos();
        assert!((d.center.z - z).abs() < 1e-6, "{d:?}");
        assert!((d.normal - DVec3::new(-slope, 0.0, 1.0).normalize()).length() < 1e-5);
    }
    let gap = back
        .iter()
        .map(|d| -d.center.z)
        .fold(f64::INFINITY, f64::min);
    assert!(gap > 0.09, "{gap}");
    assert!(scene.discoid_threshold <= gap / 3.0);
    // Overlap: neighbours on the 0.125 grid are one radius apart.
    assert!((front[1].center - front[0].center).length() <= radius);
}

#[test]
fn bunny_from_mesh_subdivide_1_gives_v_plus_e_discoids() {
    let scene = Scene::load(&traces().join("bunny_discoids.json")).unwrap();
    let set = discoid_set(&scene, 0);
    assert_eq!(set.planar.len(), 1839 + 5511);
    assert!(!set.surfels);
    let mesh = bunny_mesh();
    for (d, p) in set.planar.iter().zip(&mesh.positions) {
        assert_eq!(d.center, *p);
    }
    // The first midpoint is that of the first triangle's first edge.
    let [a, b, _] = mesh.triangles[0].map(|i| mesh.positions[i as usize]);
    assert_eq!(set.planar[1839].center, 0.5 * (a + b));
    assert!(set
        .planar
        .iter()
        .all(|d| (d.normal.length() - 1.0).abs() < 1e-12));
}

#[test]
fn bunny_discoids_overlap_their_neighbours() {
    // radius_scale 0.85: every point of every subdivided triangle is inside the disk
    // (in the disk's plane) of one of its corners, and most inside two.
    let scene = Scene::load(&traces().join("bunny_discoids.json")).unwrap();
    let discoids = &discoid_set(&scene, 0).planar;
    let mesh = crate::discoid::shapes::subdivide_mesh(&bunny_mesh()).unwrap();
    let inside = |d: &Discoid, p: DVec3| {
        let q = p - d.center;
        (q - q.dot(d.normal) * d.normal).length() < d.radius
    };
    let (mut samples, mut twice) = (0, 0);
    let n = 8;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        for i in 0..=n {
            for j in 0..=(n - i) {
                let p = a + (i as f64 / n as f64) * (b - a) + (j as f64 / n as f64) * (c - a);
                let k = t
                    .iter()
                    .filter(|&&v| inside(&discoids[v as usize], p))
                    .count();
                assert!(k >= 1, "{p} is in none of its corners' disks");
                samples += 1;
                twice += usize::from(k >= 2);
            }
        }
    }
    assert!(twice as f64 / samples as f64 > 0.9);
}

#[test]
fn bunny_surfels_ply_is_generated_from_the_bunny_mesh() {
    // LEMBO_BLESS=1 (exactly: any other value blesses nothing) rewrites the committed file.
    let path = traces().join("pointclouds/bunny_surfels.ply");
    let want = bunny_surfels_ply();
    assert!(want.len() > 10_000, "{} bytes generated", want.len());
    if std::env::var_os("LEMBO_BLESS").is_some_and(|v| v == "1") {
        std::fs::write(&path, &want).unwrap();
    }
    let got = std::fs::read(&path).unwrap();
    assert!(got == want, "{} differs from its generator", path.display());
}

#[test]
fn surfels_round_trip_the_mesh_vertices_within_f32_rounding() {
    let scene = Scene::load(&traces().join("surfels_bunny.json")).unwrap();
    let set = discoid_set(&scene, 0);
    assert!(set.surfels);
    let mesh = bunny_mesh();
    let exact = discoids_from_mesh(&mesh, false, 1.0).unwrap();
    assert_eq!(set.planar.len(), mesh.positions.len());
    // Rounding to f32 moves x by at most |x| 2^-24.
    let f32_close = |a: f64, b: f64| (a - b).abs() <= b.abs() * 2f64.powi(-24) * 1.0001;
    for ((got, want), p) in set.planar.iter().zip(&exact).zip(&mesh.positions) {
        for k in 0..3 {
            assert!(f32_close(got.center[k], p[k]), "{got:?} {p}");
        }
        assert!(f32_close(got.radius, want.radius), "{got:?} {want:?}");
        assert!((got.normal - want.normal).length() < 1e-6);
    }
}

#[test]
fn surfel_ply_ascii_double_and_extra_properties_load() {
    let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n\
               property double z\nproperty uchar red\nproperty float nx\nproperty float ny\n\
               property float nz\nproperty double radius\nelement face 1\n\
               property list uchar int vertex_indices\nend_header\n\
               1 2 3 255 0 0 2 0.5\n-1 0 0.25 7 0 1 0 0.125\n3 0 1 1\n";
    let scene = scene_with_ply(ply.as_bytes()).unwrap();
    let set = discoid_set(&scene, 0);
    assert_eq!(
        set.planar,
        vec![
            Discoid {
                center: DVec3::new(1.0, 2.0, 3.0),
                normal: DVec3::Z,
                radius: 0.5
            },
            Discoid {
                center: DVec3::new(-1.0, 0.0, 0.25),
                normal: DVec3::Y,
                radius: 0.125
            }
        ]
    );
    assert!(set.surfels);
    assert_eq!(scene.objects[0].label, "surfels s.ply");
    // The same surfels in binary.
    let binary = surfel_ply(
        &[
            [1.0, 2.0, 3.0, 0.0, 0.0, 2.0, 0.5],
            [-1.0, 0.0, 0.25, 0.0, 1.0, 0.0, 0.125],
        ],
        "test",
    );
    assert_eq!(discoid_set(&scene_with_ply(&binary).unwrap(), 0), set);
}

#[test]
fn bad_surfel_files_are_refused_naming_the_field() {
    let field = "objects[0].discoids.surfels";
    let header = |props: &str, n: usize| {
        format!("ply\nformat ascii 1.0\nelement vertex {n}\n{props}end_header\n")
    };
    let all: String = SURFEL_PROPERTIES
        .iter()
        .map(|p| format!("property float {p}\n"))
        .collect();
    for (body, want) in [
        (header(&all.replace("property float radius\n", ""), 1), "radius"),
        (header(&all.replace("float radius", "int radius"), 1), "radius"),
        (format!("{}0 0 0 0 0 1 0\n", header(&all, 1)), "radius 0"),
        (format!("{}0 0 0 0 0 0 1\n", header(&all, 1)), "zero normal"),
        (format!("{}0 0 nan 0 0 1 1\n", header(&all, 1)), "PLY"),
        (format!("{}0 0 0 0 0 1 1\n", header(&all, 2)), "PLY"),
        (header(&all, 0), "no vertices"),
        ("{\"not\": \"ply\"}".to_string(), "PLY"),
        (
            "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
                .to_string(),
            "first element",
        ),
    ] {
        let message = assert_mesh_err(scene_with_ply(body.as_bytes()), field);
        assert!(message.contains(want), "{want:?} not in {message:?}");
    }
    // A NaN in a binary file.
    let nan = surfel_ply(&[[0.0, f32::NAN, 0.0, 0.0, 0.0, 1.0, 1.0]], "t");
    let message = assert_mesh_err(scene_with_ply(&nan), field);
    assert!(
        message.contains("vertex 0 has a non-finite value"),
        "{message}"
    );
    // A truncated binary file.
    let mut binary = surfel_ply(&[[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0]], "t");
    binary.truncate(binary.len() - 3);
    assert_mesh_err(scene_with_ply(&binary), field);
    // A missing file names the field and gives the OS reason.
    let message = assert_mesh_err(
        with_object(r#"{"discoids": {"surfels": "pointclouds/missing.ply"}}"#),
        field,
    );
    assert!(message.contains("No such file"), "{message}");
}

#[test]
fn more_than_a_million_discoids_are_refused_before_reading_them() {
    // The header alone is read: no payload follows.
    let ply = "ply\nformat binary_little_endian 1.0\nelement vertex 1000001\n\
               property float x\nproperty float y\nproperty float z\nproperty float nx\n\
               property float ny\nproperty float nz\nproperty float radius\nend_header\n";
    let reason = assert_invalid(
        scene_with_ply(ply.as_bytes()),
        "objects[0].discoids.surfels",
    );
    assert!(
        reason.contains("1000001") && reason.contains("1000000"),
        "{reason}"
    );
    // The limit is on the scene's total: two inline discoids and 999,999 surfels.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.ply"), ply.replace("1000001", "999999")).unwrap();
    let two = r#"{"discoids": {"items": [{"center": [0, 0, 0], "normal": [0, 0, 1], "radius": 1},
                                         {"center": [1, 0, 0], "normal": [0, 0, 1], "radius": 1}]}},
                 {"discoids": {"surfels": "s.ply"}}"#;
    let text = SPHERE.replacen(r#"{"builtin": "sphere24"}"#, two, 1);
    let reason = assert_invalid(
        Scene::from_json(&text, "test.json", dir.path()),
        "objects[1].discoids.surfels",
    );
    assert!(reason.contains("1000001"), "{reason}");
}

const ITEMS: &str = r#"{"discoids": {"items": [
    {"center": [0, 0, 0], "normal": [0, 0, 2], "radius": 0.1},
    {"center": [1, 0, 0], "normal": [0, 1, 0], "radius": 0.2},
    {"center": [0, 1, 0], "normal": [1, 0, 0], "radius": 0.4}]}}"#;

#[test]
fn inline_discoids_are_normalised_and_default_to_the_disk_beta() {
    let scene = with_object(ITEMS).unwrap();
    let o = &scene.objects[0];
    assert_eq!(o.label, "inline discoids");
    assert!(o.lembos.is_empty() && o.mesh().is_none());
    let set = discoid_set(&scene, 0);
    assert_eq!(set.beta, BetaShape::Disk);
    assert!(!set.surfels && set.lembo_texcoords.is_empty());
    assert_eq!(set.planar[0].normal, DVec3::Z);
    assert_eq!(set.planar[2].radius, 0.4);
    assert_eq!(scene.discoid_count(), 3);
    let star = with_object(&ITEMS.replace(r#""items""#, r#""beta": "star", "items""#)).unwrap();
    assert_eq!(discoid_set(&star, 0).beta, BetaShape::Star);
}

#[test]
fn discoid_transform_scales_radii_and_rotates_normals() {
    let moved = ITEMS.replacen(
        "]}}",
        r#"]}, "transform": {"scale": 2, "rotate_deg": [0, 0, 90], "translate": [0, 0, 1]}}"#,
        1,
    );
    let scene = with_object(&moved).unwrap();
    let d = discoid_set(&scene, 0).planar[1];
    // (1, 0, 0) scaled to (2, 0, 0), turned 90 degrees about z to (0, 2, 0), raised by 1.
    assert!((d.center - DVec3::new(0.0, 2.0, 1.0)).length() < 1e-15);
    assert!((d.normal - DVec3::new(-1.0, 0.0, 0.0)).length() < 1e-15);
    assert_eq!(d.radius, 0.4);
    // The default threshold follows the scale.
    assert!((scene.discoid_threshold - 0.25 * 0.4).abs() < 1e-15);
    let huge = ITEMS.replacen("]}}", r#"]}, "transform": {"scale": 1e13}}"#, 1);
    assert_invalid(with_object(&huge), "objects[0].transform");
}

#[test]
fn default_threshold_is_a_quarter_of_the_median_discoid_radius() {
    // Odd count: the middle radius.
    assert_eq!(with_object(ITEMS).unwrap().discoid_threshold, 0.25 * 0.2);
    // Even count, over two objects: the mean of the two middle radii.
    let four = format!(
        r#"{ITEMS}, {{"discoids": {{"items": [{{"center": [0, 0, 0], "normal": [0, 0, 1], "radius": 0.8}}]}}}}"#
    );
    let t = with_object(&four).unwrap().discoid_threshold;
    assert!((t - 0.25 * 0.3).abs() < 1e-15, "{t}");
    // Curved discoids count their disk radius, scaled.
    let sphere20 =
        with_object(r#"{"discoids": {"builtin": "sphere20"}, "transform": {"scale": 2}}"#).unwrap();
    let want = 0.25 * 2.0 * crate::discoid::shapes::SPHERE20_RADIUS;
    assert!((sphere20.discoid_threshold - want).abs() < 1e-15);
    // A given threshold wins; a scene without discoids has 0.
    let given = sphere_with(r#""objects""#, r#""discoid_threshold": 0.01, "objects""#);
    assert_eq!(given.unwrap().discoid_threshold, 0.01);
    assert_eq!(parse(SPHERE).unwrap().discoid_threshold, 0.0);
}

#[test]
fn bad_threshold_is_refused() {
    for bad in ["0", "-0.5"] {
        let r = sphere_with(
            r#""objects""#,
            &format!(r#""discoid_threshold": {bad}, "objects""#),
        );
        assert_invalid(r, "discoid_threshold");
    }
    let r = sphere_with(r#""objects""#, r#""discoid_threshold": 1e999, "objects""#);
    assert_parse_err(r, "discoid_threshold");
}

#[test]
fn bad_inline_discoids_name_the_field() {
    let zero_radius = ITEMS.replace(r#""radius": 0.2"#, r#""radius": 0"#);
    let reason = assert_invalid(
        with_object(&zero_radius),
        "objects[0].discoids.items[1].radius",
    );
    assert!(reason.contains("> 0"), "{reason}");
    let zero_normal = ITEMS.replace("[0, 0, 2]", "[0, 0, 0]");
    assert_invalid(
        with_object(&zero_normal),
        "objects[0].discoids.items[0].normal",
    );
    let huge = ITEMS.replace(r#""center": [0, 1, 0]"#, r#""center": [0, 1e999, 0]"#);
    assert_parse_err(with_object(&huge), "objects[0].discoids.items[2].center");
    assert_invalid(
        with_object(r#"{"discoids": {"items": []}}"#),
        "objects[0].discoids.items",
    );
}

#[test]
fn discoids_need_exactly_one_source() {
    let two = r#"{"discoids": {"builtin": "sphere20", "surfels": "x.ply"}}"#;
    match with_object(two) {
        Err(Error::Invalid { field, value, .. }) => {
            assert_eq!(field, "objects[0].discoids");
            assert_eq!(value, "builtin and surfels");
        }
        other => panic!("{}", summary(&other)),
    }
    assert_invalid(
        with_object(r#"{"discoids": {"beta": "disk"}}"#),
        "objects[0].discoids",
    );
    // Discoids are one object kind among the others.
    assert_invalid(
        with_object(r#"{"builtin": "sphere24", "discoids": {"builtin": "sphere20"}}"#),
        "objects[0]",
    );
}

#[test]
fn bad_discoid_options_name_the_field() {
    let message = assert_parse_err(
        with_object(r#"{"discoids": {"builtin": "sphere20", "beta": "square"}}"#),
        "objects[0].discoids.beta",
    );
    assert!(message.contains("gaussian"), "{message}");
    let reason = assert_invalid(
        with_object(r#"{"discoids": {"builtin": "sphere21"}}"#),
        "objects[0].discoids.builtin",
    );
    assert!(reason.contains("sphere20"), "{reason}");
    assert_invalid(
        with_object(r#"{"discoids": {"from_mesh": "meshes/bunny.obj", "subdivide": 2}}"#),
        "objects[0].discoids.subdivide",
    );
    assert_invalid(
        with_object(r#"{"discoids": {"builtin": "sphere20", "subdivide": 1}}"#),
        "objects[0].discoids.subdivide",
    );
    assert_invalid(
        with_object(r#"{"discoids": {"from_mesh": "meshes/bunny.obj", "radius_scale": 0}}"#),
        "objects[0].discoids.radius_scale",
    );
    assert_parse_err(
        with_object(r#"{"discoids": {"builtin": "sphere20", "radius": 1}}"#),
        "objects[0].discoids",
    );
}

#[test]
fn bad_discoid_meshes_name_the_field() {
    let message = assert_mesh_err(
        with_object(r#"{"discoids": {"from_mesh": "meshes/missing.obj"}}"#),
        "objects[0].discoids.from_mesh",
    );
    assert!(message.contains("No such file"), "{message}");
    // A zero normal in the file leaves its vertex's discoid without one.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("m.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 0\nf 1//1 2//1 3//2\n",
    )
    .unwrap();
    let text = SPHERE.replacen(
        r#""builtin": "sphere24""#,
        r#""discoids": {"from_mesh": "m.obj"}"#,
        1,
    );
    let r = Scene::from_json(&text, "test.json", dir.path());
    let message = assert_mesh_err(r, "objects[0].discoids.from_mesh");
    assert!(message.contains("vertex 2 has a zero normal"), "{message}");
}

#[test]
fn the_ewa_beta_is_refused_on_curved_discoids_and_a_surface_beside_its_own() {
    let e = with_object(r#"{"discoids": {"builtin": "sphere20", "beta": "ewa"}}"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("objects[0].discoids.beta"), "{e}");
    let e = with_object(r#"{"discoids": {"builtin": "sphere20", "surface": "meshes/bunny.obj"}}"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("objects[0].discoids.surface"), "{e}");
    let ok = with_object(
        r#"{"discoids": {"items": [{"center": [0, 0, 0], "normal": [0, 0, 1], "radius": 0.5}],
            "beta": "ewa"}}"#,
    )
    .unwrap();
    assert_eq!(discoid_set(&ok, 0).beta, BetaShape::Ewa);
    assert_eq!(discoid_set(&ok, 0).surface, None);
}

#[test]
fn sphere20_object_puts_its_lembos_in_the_lembo_path() {
    let scene = with_object(
        r#"{"discoids": {"builtin": "sphere20", "beta": "gaussian"}, "color": [0.1, 0.2, 0.3],
            "transform": {"translate": [1, 0, 0]}}"#,
    )
    .unwrap();
    let o = &scene.objects[0];
    assert_eq!(o.label, "builtin discoids sphere20");
    assert_eq!(o.color, [0.1, 0.2, 0.3]);
    let set = discoid_set(&scene, 0);
    let n = 20 * 4usize.pow(crate::discoid::shapes::SPHERE20_LEVELS);
    assert_eq!((o.lembos.len(), set.lembo_texcoords.len()), (n, n));
    assert!(set.planar.is_empty() && set.beta == BetaShape::Gaussian);
    let plain = crate::discoid::shapes::sphere20();
    assert_eq!(set.lembo_texcoords, plain.texcoords);
    for (l, p) in o.lembos.iter().zip(&plain.lembos) {
        assert_eq!(l.points[0], p.points[0] + DVec3::X);
        assert_eq!(l.normals[0], p.normals[0]);
    }
    assert_eq!(scene.lembo_count(), n);
    assert_eq!(scene.discoid_count(), n);
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
