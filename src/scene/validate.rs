//! Validation of a parsed scene file into a [`Scene`]: `Check` names the file in every
//! error; this file holds the scene-wide checks (viewport, name, camera, projection, light,
//! transforms, inline lembos) and `SceneSpec::validate`, which walks the objects.

use super::Light;
use super::{
    format::{
        CameraSpec, LemboSpec, LightSpec, ProjectionKind, ProjectionSpec, SceneSpec, TransformSpec,
    },
    mesh::Transform,
    Scene, DEFAULT_BACKGROUND, DEFAULT_THRESHOLD_PER_RADIUS, DEFAULT_VIEWPORT,
    MAX_WORLD_COORDINATE,
};
use crate::camera::{Camera, Projection, Viewport, MAX_VIEWPORT_SIDE};
use crate::discoid::Discoid;
use crate::error::{Error, Result};
use crate::lembo::shapes::{builtin_lembo_count, MAX_BUILTIN_LEMBOS, MAX_TERRAIN_CELLS};
use crate::lembo::Lembo;
use glam::{DMat3, DVec3};
use std::fmt;
use std::path::Path;

/// Builds errors that name the file being validated.
pub(super) struct Check<'a> {
    pub(super) file: &'a str,
}

/// Formats a vector as the file spells it, e.g. `[0, 1, 0.5]`.
pub(super) struct Vec3Value(pub(super) [f64; 3]);

/// The names of the alternatives present, joined with "and", or "none": the value an
/// "exactly one of" error reports.
pub(super) fn given(options: &[(&str, bool)]) -> String {
    let present: Vec<&str> = options
        .iter()
        .filter_map(|&(name, present)| present.then_some(name))
        .collect();
    if present.is_empty() {
        "none".to_string()
    } else {
        present.join(" and ")
    }
}

impl fmt::Display for Vec3Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [x, y, z] = self.0;
        write!(f, "[{x}, {y}, {z}]")
    }
}

impl Check<'_> {
    pub(super) fn invalid(
        &self,
        field: impl Into<String>,
        value: impl fmt::Display,
        reason: impl Into<String>,
    ) -> Error {
        Error::invalid(self.file, field, value, reason)
    }

    fn parse(&self, field: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Parse {
            file: self.file.to_string(),
            field: field.into(),
            message: message.into(),
        }
    }

    pub(super) fn finite(&self, field: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(field, x, "must be a finite number"))
        }
    }

    pub(super) fn vec3(&self, field: &str, v: [f64; 3]) -> Result<DVec3> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(DVec3::from_array(v))
        } else {
            Err(self.invalid(
                field,
                Vec3Value(v),
                "every component must be a finite number",
            ))
        }
    }

    pub(super) fn color(&self, field: &str, c: [f64; 3]) -> Result<[f64; 3]> {
        if c.iter().all(|x| (0.0..=1.0).contains(x)) {
            Ok(c)
        } else {
            Err(self.invalid(
                field,
                Vec3Value(c),
                "every channel must be in [0, 1] (linear RGB)",
            ))
        }
    }

    pub(super) fn viewport(&self, v: &Viewport) -> Result<()> {
        for (field, side) in [("viewport.width", v.width), ("viewport.height", v.height)] {
            if !(1..=MAX_VIEWPORT_SIDE).contains(&side) {
                return Err(self.invalid(
                    field,
                    side,
                    format!("must be in 1..={MAX_VIEWPORT_SIDE} pixels"),
                ));
            }
        }
        Ok(())
    }

    fn name(&self, name: &str) -> Result<()> {
        let ok = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if ok {
            Ok(())
        } else {
            Err(self.invalid(
                "name",
                format!("{name:?}"),
                "must be non-empty and made only of A-Z, a-z, 0-9, `_` and `-`: it names the output directory out/<name>/",
            ))
        }
    }

    fn camera(&self, c: &CameraSpec) -> Result<Camera> {
        let eye = self.vec3("camera.eye", c.eye)?;
        let target = self.vec3("camera.target", c.target)?;
        let up = self.vec3("camera.up", c.up)?;
        if eye == target {
            return Err(self.invalid(
                "camera.target",
                Vec3Value(c.target),
                "must differ from camera.eye",
            ));
        }
        let dir = target - eye;
        // Parallel (or zero) up leaves the camera's roll undefined.
        if up.cross(dir).length() <= 1e-9 * up.length() * dir.length() {
            return Err(self.invalid(
                "camera.up",
                Vec3Value(c.up),
                "must be non-zero and not parallel to the view direction (target - eye)",
            ));
        }
        let projection = self.projection(&c.projection)?;
        Ok(Camera {
            eye: c.eye,
            target: c.target,
            up: c.up,
            projection,
        })
    }

    fn projection(&self, p: &ProjectionSpec) -> Result<Projection> {
        let near = self.finite("camera.projection.near", p.near)?;
        let far = self.finite("camera.projection.far", p.far)?;
        if near <= 0.0 {
            return Err(self.invalid("camera.projection.near", near, "must be > 0"));
        }
        if far <= near {
            return Err(self.invalid(
                "camera.projection.far",
                far,
                format!("must be > near ({near})"),
            ));
        }
        match p.kind {
            ProjectionKind::Perspective => {
                if p.height.is_some() {
                    return Err(self.parse(
                        "camera.projection.height",
                        "a perspective projection takes `fovy_deg`, not `height` (which is for orthographic)",
                    ));
                }
                let Some(fovy_deg) = p.fovy_deg else {
                    return Err(self.parse(
                        "camera.projection",
                        "missing field `fovy_deg` (a perspective projection needs it)",
                    ));
                };
                let fovy_deg = self.finite("camera.projection.fovy_deg", fovy_deg)?;
                if !(fovy_deg > 0.0 && fovy_deg < 180.0) {
                    return Err(self.invalid(
                        "camera.projection.fovy_deg",
                        fovy_deg,
                        "must be in (0, 180) degrees",
                    ));
                }
                Ok(Projection::Perspective {
                    fovy_deg,
                    near,
                    far,
                })
            }
            ProjectionKind::Orthographic => {
                if p.fovy_deg.is_some() {
                    return Err(self.parse(
                        "camera.projection.fovy_deg",
                        "an orthographic projection takes `height`, not `fovy_deg` (which is for perspective)",
                    ));
                }
                let Some(height) = p.height else {
                    return Err(self.parse(
                        "camera.projection",
                        "missing field `height` (an orthographic projection needs it)",
                    ));
                };
                let height = self.finite("camera.projection.height", height)?;
                if height <= 0.0 {
                    return Err(self.invalid(
                        "camera.projection.height",
                        height,
                        "must be > 0 world units",
                    ));
                }
                Ok(Projection::Orthographic { height, near, far })
            }
        }
    }

    fn light(&self, l: &LightSpec) -> Result<Light> {
        let dir = self.vec3("light.direction_to_light", l.direction_to_light)?;
        if dir == DVec3::ZERO {
            return Err(self.invalid(
                "light.direction_to_light",
                Vec3Value(l.direction_to_light),
                "must be non-zero",
            ));
        }
        for (field, x) in [
            ("light.ka", l.ka),
            ("light.kd", l.kd),
            ("light.ks", l.ks),
            ("light.shininess", l.shininess),
        ] {
            self.finite(field, x)?;
            if x < 0.0 {
                return Err(self.invalid(field, x, "must be >= 0"));
            }
        }
        Ok(Light {
            direction_to_light: l.direction_to_light,
            ka: l.ka,
            kd: l.kd,
            ks: l.ks,
            shininess: l.shininess,
        })
    }

    pub(super) fn transform(&self, field: &str, t: &TransformSpec) -> Result<Transform> {
        let scale = self.finite(&format!("{field}.scale"), t.scale)?;
        if scale <= 0.0 {
            return Err(self.invalid(
                format!("{field}.scale"),
                scale,
                "must be > 0 (uniform scale)",
            ));
        }
        let r = self.vec3(&format!("{field}.rotate_deg"), t.rotate_deg)?;
        let translate = self.vec3(&format!("{field}.translate"), t.translate)?;
        // X first, then Y, then Z: the rightmost factor applies first.
        let rotate = DMat3::from_rotation_z(r.z.to_radians())
            * DMat3::from_rotation_y(r.y.to_radians())
            * DMat3::from_rotation_x(r.x.to_radians());
        Ok(Transform {
            scale,
            rotate,
            translate,
        })
    }
}

impl Check<'_> {
    pub(super) fn inline_lembo(
        &self,
        field: &str,
        l: &LemboSpec,
        t: Option<&Transform>,
    ) -> Result<Lembo> {
        let mut points = [DVec3::ZERO; 6];
        let mut normals = [DVec3::ZERO; 6];
        for k in 0..6 {
            points[k] = self.vec3(&format!("{field}.points[{k}]"), l.points[k])?;
            normals[k] = self.vec3(&format!("{field}.normals[{k}]"), l.normals[k])?;
        }
        if let Some(t) = t {
            // Normals keep their length: the file's normal function is the modeller's.
            points = points.map(|p| t.point(p));
            normals = normals.map(|n| t.rotate * n);
        }
        Ok(Lembo::new(points, normals))
    }
}

impl SceneSpec {
    pub(super) fn validate(self, check: &Check, base_dir: &Path) -> Result<Scene> {
        check.name(&self.name)?;
        let viewport = self.viewport.unwrap_or(DEFAULT_VIEWPORT);
        check.viewport(&viewport)?;
        let camera = check.camera(&self.camera)?;
        let light = check.light(&self.light.unwrap_or_default())?;
        let background =
            check.color("background", self.background.unwrap_or(DEFAULT_BACKGROUND))?;
        // The builtin shapes' lembos, counted before any is made.
        let mut builtin = 0u64;
        for (i, o) in self.objects.iter().enumerate() {
            let count = o.builtin.as_deref().and_then(builtin_lembo_count);
            builtin += count.unwrap_or(0);
            if builtin > MAX_BUILTIN_LEMBOS {
                return Err(check.invalid(
                    format!("objects[{i}].builtin"),
                    format!("{:?}", o.builtin.as_deref().unwrap_or_default()),
                    format!(
                        "the scene's builtin shapes would make {builtin} lembos up to here, \
                         more than the {MAX_BUILTIN_LEMBOS} accepted (one terrain{MAX_TERRAIN_CELLS})"
                    ),
                ));
            }
        }
        let mut radii = Vec::new();
        let mut lembos = 0;
        let objects = self
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| check.object(i, o, base_dir, &mut radii, &mut lembos))
            .collect::<Result<Vec<_>>>()?;
        let discoid_threshold = match self.discoid_threshold {
            Some(t) => {
                let t = check.finite("discoid_threshold", t)?;
                if t <= 0.0 {
                    return Err(check.invalid("discoid_threshold", t, "must be > 0 world units"));
                }
                t
            }
            None => DEFAULT_THRESHOLD_PER_RADIUS * median(&mut radii),
        };
        Ok(Scene {
            name: self.name,
            source: None,
            viewport,
            camera,
            light,
            background,
            discoid_threshold,
            objects,
        })
    }
}

/// Whether every point and every position coefficient is finite and at most
/// [`MAX_WORLD_COORDINATE`] in magnitude, and every normal finite.
pub(super) fn lembo_in_range(l: &Lembo) -> bool {
    let small = |x: f64| x.abs() <= MAX_WORLD_COORDINATE;
    l.is_finite()
        && l.points.iter().all(|p| small(p.abs().max_element()))
        && l.position.iter().all(|q| small(q.magnitude()))
        && l.normal.iter().all(|q| q.magnitude().is_finite())
}

/// Whether a world-space planar discoid's centre is at most [`MAX_WORLD_COORDINATE`] in
/// magnitude, its normal finite and its radius in [`f64::MIN_POSITIVE`],
/// [`MAX_WORLD_COORDINATE`].
pub(super) fn discoid_in_range(d: &Discoid) -> bool {
    d.center.is_finite()
        && d.center.abs().max_element() <= MAX_WORLD_COORDINATE
        && d.normal.is_finite()
        && (f64::MIN_POSITIVE..=MAX_WORLD_COORDINATE).contains(&d.radius)
}

/// `v` at unit length, or None when it is zero; robust to very small and very large finite
/// components.
pub(super) fn unit(v: DVec3) -> Option<DVec3> {
    let m = v.abs().max_element();
    if m > 0.0 {
        (v / m).try_normalize()
    } else {
        None
    }
}

/// The median of `x` (the mean of the two middle values for an even count), 0 when empty.
pub(super) fn median(x: &mut [f64]) -> f64 {
    x.sort_unstable_by(f64::total_cmp);
    let n = x.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => x[n / 2],
        _ => 0.5 * (x[n / 2 - 1] + x[n / 2]),
    }
}
