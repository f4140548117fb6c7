//! The architecture file's `links`: one [`LinkConfig`] per boundary of the unit graph,
//! read, written and defaulted from [`BOUNDARIES`] (a link given in part keeps its own
//! boundary's defaults for the rest).

use super::declare::{Row, Section};
use super::rules::{Check, Describe, Whole, CYCLES, MAX_FIFO_DEPTH};
use crate::error::Result;
use crate::graph::{self, LinkConfig, UnitKind, BOUNDARIES, LINK_KEYS};
use serde::{Deserialize, Serialize};

/// What a link's `fifo_depth` accepts.
const FIFO_DEPTH: Whole = Whole {
    min: 1,
    max: MAX_FIFO_DEPTH as u64,
    unit: "items (a FIFO must hold at least one item)",
};

/// The file's shape of one [`LinkConfig`]: a field left out keeps its boundary's default;
/// `null` is refused like any other value of the wrong type.
#[derive(Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
struct LinkSpec {
    #[serde(deserialize_with = "present")]
    fifo_depth: Option<u32>,
    #[serde(deserialize_with = "present")]
    latency_cycles: Option<u64>,
}

/// Deserializes a field that is present in the file (an absent one is `None` through
/// `#[serde(default)]`) without accepting `null` for it.
fn present<'de, D, T>(deserializer: D) -> std::result::Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    T::deserialize(deserializer).map(Some)
}

impl LinkSpec {
    /// This link with the fields the file left out taken from `default`.
    fn over(self, default: LinkConfig) -> LinkConfig {
        LinkConfig {
            fifo_depth: self.fifo_depth.unwrap_or(default.fifo_depth),
            latency_cycles: self.latency_cycles.unwrap_or(default.latency_cycles),
        }
    }
}

/// One [`LinkConfig`] per boundary of the unit graph, in the order of
/// [`graph::BOUNDARIES`], which names each and gives its default; every link of the
/// crossbar at that boundary shares it.
///
/// In a file, `links` is an object keyed by the boundaries' names; a link given in part
/// keeps its own boundary's defaults for the rest (`{"rasterizer_to_rop": {"fifo_depth":
/// 32}}` keeps latency 2), not the generic [`LinkConfig::default`].
#[derive(Clone, Debug, PartialEq)]
pub struct LinksConfig([LinkConfig; BOUNDARIES.len()]);

impl LinksConfig {
    /// The link of the boundary from `from` to `to`.
    ///
    /// # Panics
    /// When the graph has no such boundary.
    pub fn get(&self, from: UnitKind, to: UnitKind) -> &LinkConfig {
        &self.0[graph::boundary(from, to).expect("a boundary of the unit graph")]
    }

    /// The link of the boundary named `key`, if the graph has one.
    pub fn by_key(&self, key: &str) -> Option<&LinkConfig> {
        LINK_KEYS.iter().position(|k| *k == key).map(|i| &self.0[i])
    }

    /// The link of the boundary from `from` to `to`, mutable.
    ///
    /// # Panics
    /// When the graph has no such boundary.
    pub fn get_mut(&mut self, from: UnitKind, to: UnitKind) -> &mut LinkConfig {
        &mut self.0[graph::boundary(from, to).expect("a boundary of the unit graph")]
    }

    /// Every boundary of both paths with its link, in dataflow order.
    pub fn boundaries(&self) -> impl Iterator<Item = (&'static graph::Boundary, &LinkConfig)> {
        BOUNDARIES.iter().zip(&self.0)
    }

    /// Every link, mutable, in dataflow order (for tools and tests that set them all).
    pub fn all_mut(&mut self) -> [&mut LinkConfig; BOUNDARIES.len()] {
        self.0.each_mut()
    }

    /// Every boundary's link with its name, in dataflow order (the lembo path's, then
    /// the triangle path's).
    pub fn all(&self) -> [(&'static str, &LinkConfig); BOUNDARIES.len()] {
        let links = self.0.each_ref();
        std::array::from_fn(|i| (LINK_KEYS[i], links[i]))
    }
}

impl Section for LinksConfig {
    fn validate(&self, check: &Check) -> Result<()> {
        for (name, link) in self.all() {
            let check = check.at(name);
            check.field("fifo_depth", &link.fifo_depth, &FIFO_DEPTH)?;
            check.field("latency_cycles", &link.latency_cycles, &CYCLES)?;
        }
        Ok(())
    }

    /// Two rows a boundary, its defaults from [`BOUNDARIES`].
    fn rows(key: &str) -> Vec<Row> {
        let row = |b: &graph::Boundary, field: &str, default: String, rule: &dyn Describe| Row {
            field: format!("{key}.{}.{field}", b.key),
            default,
            accepted: rule.accepted(),
            what: match field {
                "fifo_depth" => format!(
                    "Capacity of each link from {} to {} [items].",
                    b.from.name(),
                    b.to.name()
                ),
                _ => format!(
                    "Transit time of each link from {} to {} [cycles].",
                    b.from.name(),
                    b.to.name()
                ),
            },
        };
        BOUNDARIES
            .iter()
            .flat_map(|b| {
                [
                    row(
                        b,
                        "fifo_depth",
                        b.default.fifo_depth.to_string(),
                        &FIFO_DEPTH,
                    ),
                    row(
                        b,
                        "latency_cycles",
                        b.default.latency_cycles.to_string(),
                        &CYCLES,
                    ),
                ]
            })
            .collect()
    }
}

impl Default for LinksConfig {
    fn default() -> LinksConfig {
        LinksConfig(BOUNDARIES.map(|b| b.default))
    }
}

impl Serialize for LinksConfig {
    fn serialize<S: serde::Serializer>(
        &self,
        serializer: S,
    ) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (key, link) in self.all() {
            map.serialize_entry(key, link)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for LinksConfig {
    fn deserialize<D: serde::Deserializer<'de>>(
        deserializer: D,
    ) -> std::result::Result<Self, D::Error> {
        deserializer.deserialize_map(LinksVisitor)
    }
}

/// Reads `links` as the derived form of a struct with one optional [`LinkSpec`] field per
/// boundary would, with the same messages for an unknown or repeated name.
struct LinksVisitor;

/// A name in `links`, as its index in [`graph::BOUNDARIES`]; an unknown name is refused
/// while the key is read, so that the error's path ends with it.
struct LinkKey(usize);

impl<'de> Deserialize<'de> for LinkKey {
    fn deserialize<D: serde::Deserializer<'de>>(
        deserializer: D,
    ) -> std::result::Result<Self, D::Error> {
        struct KeyVisitor;
        impl serde::de::Visitor<'_> for KeyVisitor {
            type Value = LinkKey;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("field identifier")
            }
            fn visit_str<E: serde::de::Error>(self, key: &str) -> std::result::Result<LinkKey, E> {
                LINK_KEYS
                    .iter()
                    .position(|k| *k == key)
                    .map(LinkKey)
                    .ok_or_else(|| E::unknown_field(key, &LINK_KEYS))
            }
        }
        deserializer.deserialize_identifier(KeyVisitor)
    }
}

impl<'de> serde::de::Visitor<'de> for LinksVisitor {
    type Value = LinksConfig;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("struct LinksSpec")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(
        self,
        mut map: A,
    ) -> std::result::Result<LinksConfig, A::Error> {
        let mut given: [Option<LinkSpec>; BOUNDARIES.len()] = Default::default();
        while let Some(LinkKey(i)) = map.next_key()? {
            if given[i].is_some() {
                return Err(serde::de::Error::duplicate_field(LINK_KEYS[i]));
            }
            given[i] = Some(map.next_value()?);
        }
        let mut links = LinksConfig::default();
        for (link, spec) in links.0.iter_mut().zip(given) {
            *link = spec.unwrap_or_default().over(*link);
        }
        Ok(links)
    }
}
