//! Surfels from a PLY point cloud (position, normal, radius per vertex), bounded and
//! checked vertex by vertex.

use super::{validate::unit, MAX_DISCOIDS};
use crate::discoid::Discoid;
use crate::error::{read_input, Error, Result, MAX_DATA_INPUT_BYTES};
use glam::DVec3;
use ply_rs_bw as ply;
use ply_rs_bw::ply::{PropertyAccess, PropertyAccessResult, PropertyType, ScalarType};
use std::path::Path;

/// The vertex properties a surfel point cloud must have, each a `float` or a `double`.
pub(super) const SURFEL_PROPERTIES: [&str; 7] = ["x", "y", "z", "nx", "ny", "nz", "radius"];

/// One vertex of a surfel PLY file as it is read (other properties are ignored).
#[derive(Default)]
pub(super) struct SurfelRecord {
    /// x, y, z, nx, ny, nz, radius, in [`SURFEL_PROPERTIES`] order.
    values: [f64; 7],
}

impl SurfelRecord {
    fn set(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        match SURFEL_PROPERTIES.iter().position(|&p| p == name) {
            Some(k) => {
                self.values[k] = value;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }
}

impl PropertyAccess for SurfelRecord {
    fn new() -> Self {
        SurfelRecord::default()
    }

    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set(name, f64::from(value))
    }

    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        self.set(name, value)
    }
}

/// Loads a surfel point cloud from a PLY file (ascii, binary_little_endian or
/// binary_big_endian): one planar discoid per vertex, from the `vertex` element (which must
/// come first) and its properties x y z nx ny nz radius. `field` names the scene field that
/// gave the path; `before` is how many discoids the scene already holds ([`MAX_DISCOIDS`] is
/// checked against the header's count before the payload is read).
pub(super) fn load_surfels(
    file: &str,
    field: &str,
    path: &Path,
    before: usize,
) -> Result<Vec<Discoid>> {
    let cloud_err = |message: String| Error::Mesh {
        file: file.to_string(),
        field: field.to_string(),
        path: path.to_path_buf(),
        message,
    };
    let bytes = read_input(path, MAX_DATA_INPUT_BYTES).map_err(|e| cloud_err(e.to_string()))?;
    let mut reader = ply::parser::Reader::new(std::io::Cursor::new(bytes));
    let parser = ply::parser::Parser::<SurfelRecord>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| cloud_err(format!("not a valid PLY file: {e}")))?;
    let vertex = match header.elements.first() {
        Some((name, element)) if name == "vertex" => element,
        Some((name, _)) => {
            return Err(cloud_err(format!(
                "the first element is `{name}`; a surfel file's first element must be `vertex`"
            )))
        }
        None => return Err(cloud_err("declares no elements".into())),
    };
    for name in SURFEL_PROPERTIES {
        match vertex.properties.get(name).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(ScalarType::Float | ScalarType::Double)) => {}
            Some(other) => {
                return Err(cloud_err(format!(
                    "vertex property `{name}` is {other:?}; it must be a float or a double"
                )))
            }
            None => {
                return Err(cloud_err(format!(
                    "the `vertex` element has no property `{name}` (a surfel needs {})",
                    SURFEL_PROPERTIES.join(" ")
                )))
            }
        }
    }
    if vertex.count == 0 {
        return Err(cloud_err("holds no vertices".into()));
    }
    let total = before.saturating_add(vertex.count);
    if total > MAX_DISCOIDS {
        return Err(Error::invalid(
            file,
            field,
            format!("{} surfels", vertex.count),
            format!("the scene would hold {total} discoids; at most {MAX_DISCOIDS} are accepted"),
        ));
    }
    let records = parser
        .read_payload_for_element(&mut reader, vertex, &header)
        .map_err(|e| cloud_err(format!("not a valid PLY file: {e}")))?;
    records
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let [x, y, z, nx, ny, nz, radius] = r.values;
            let center = DVec3::new(x, y, z);
            let normal = DVec3::new(nx, ny, nz);
            if !center.is_finite() || !normal.is_finite() || !radius.is_finite() {
                return Err(cloud_err(format!(
                    "vertex {i} has a non-finite value in {:?}",
                    r.values
                )));
            }
            let Some(normal) = unit(normal) else {
                return Err(cloud_err(format!("vertex {i} has a zero normal")));
            };
            if radius <= 0.0 {
                return Err(cloud_err(format!(
                    "vertex {i} has radius {radius}; it must be > 0"
                )));
            }
            Ok(Discoid {
                center,
                normal,
                radius,
            })
        })
        .collect()
}
