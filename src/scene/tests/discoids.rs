//! Tests of discoid objects: inline discoids, discoids from a mesh, surfel point clouds,
//! the blending threshold, the curved discoids of `sphere20`, and every refusal by field.

use super::*;

/// The sphere scene with its object replaced by `object` (JSON).
fn with_object(object: &str) -> Result<Scene> {
    sphere_with(r#"{"builtin": "sphere24"}"#, object)
}

fn discoid_set(scene: &Scene, i: usize) -> &DiscoidSet {
    scene.objects[i].discoids.as_ref().unwrap()
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
