//! How a configuration section is declared once: the [`section!`] macro writes a section's
//! struct (its serde shape and field docs), its `Default` and its checks from one list of
//! fields, each with its type, default, rule and doc; the README's field table is read from
//! the same list ([`Section::rows`]).
//!
//! A declarative macro rather than a trait with a hand-written table of descriptors: the
//! struct, its `Default` and the checks must all name every field, and only a macro can
//! write the struct from the list; a table beside a hand-written struct would be the
//! second writing this module exists to remove. A derive (a proc-macro crate) would read
//! the same list from attributes, at the cost of a crate and a build step for what
//! `macro_rules!` already does here.

use super::rules::{Check, Checked, Describe};
use crate::error::Result;
use crate::graph::UnitKind;
use serde::Serialize;

/// One field of a section as declared: its key in the file, its doc and its rule.
pub struct Field {
    /// The key in the file (`count`).
    pub key: &'static str,
    /// The doc comment, line by line as written.
    pub doc: &'static str,
    /// What the field accepts.
    pub rule: &'static dyn Describe,
}

/// One row of the README's field table.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The dotted path (`setup.count`).
    pub field: String,
    /// The default, as JSON.
    pub default: String,
    /// What is accepted, in words.
    pub accepted: String,
    /// The first sentence of the field's doc.
    pub what: String,
}

/// A section of the architecture file: its checks, its rows in the field table, and the
/// unit kind whose instance count and latency it holds, if any.
pub trait Section {
    /// The unit kind this section configures; None for a section of no unit of its own.
    const UNIT: Option<UnitKind> = None;
    /// Whether its `count` sets the number of instances (else the unit has one).
    const REPLICATED: bool = false;

    /// Instances of its unit and their latency \[cycles\]; one of latency 1 for a unit with
    /// one instance, whose time is its port's and links'.
    fn instances(&self) -> (u32, u64) {
        (1, 1)
    }

    /// Checks every field; the first refused one is an error naming `check`'s path to it.
    fn validate(&self, check: &Check) -> Result<()>;

    /// Its rows in the field table, each field's path under `key`.
    fn rows(key: &str) -> Vec<Row>;
}

/// The rows of a section declared with [`section!`], each field's path under `key` (the
/// top level when empty): each field's default is read from the section's `Default` as it
/// serialises, so the table shows what a file would hold.
pub fn rows_of<S: Default + Serialize>(key: &str, fields: &[Field]) -> Vec<Row> {
    let defaults = serde_json::to_value(S::default()).expect("a section serialises");
    fields
        .iter()
        .map(|f| Row {
            field: match key {
                "" => f.key.to_string(),
                _ => format!("{key}.{}", f.key),
            },
            default: defaults[f.key].to_string(),
            accepted: f.rule.accepted(),
            what: summary(f.doc),
        })
        .collect()
}

/// A doc comment's first sentence on one line, as plain Markdown: rustdoc's escaped
/// brackets and intra-doc links become plain text, and a `|` cannot end a table cell.
pub fn summary(doc: &str) -> String {
    let text = doc.lines().map(str::trim).collect::<Vec<_>>().join(" ");
    let end = text.find(". ").map_or(text.len(), |i| i + 1);
    text[..end]
        .replace("\\[", "[")
        .replace("\\]", "]")
        .replace("[`", "`")
        .replace("`]", "`")
        .replace('|', "\\|")
        .trim()
        .to_string()
}

/// Checks one field of a section with its rule.
pub fn check_field<T: Checked>(check: &Check, key: &str, value: &T, rule: &T::Rule) -> Result<()> {
    check.field(key, value, rule)
}

/// Declares a section of the architecture file once: its doc, then each field's doc, name,
/// type, default (after `=`) and rule (after `=>`, a [`Checked::Rule`] of its type). It
/// writes the struct (`#[serde(default, deny_unknown_fields)]`, fields in declared order,
/// which is the order a file is echoed in), its `Default`, and its [`Section`] (the checks
/// in declared order, the table rows). After the name, `replicated(Kind)` says the section
/// holds `Kind`'s `count` and `latency_cycles`, `single(Kind)` that it configures a unit
/// with one instance.
macro_rules! section {
    (
        $(#[doc = $doc:literal])*
        pub struct $name:ident $(: $role:ident($kind:ident))? {
            $(
                $(#[doc = $fdoc:literal])*
                pub $field:ident: $ty:ty = $default:expr => $rule:expr,
            )*
        }
    ) => {
        $(#[doc = $doc])*
        #[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
        #[serde(default, deny_unknown_fields)]
        pub struct $name {
            $(
                $(#[doc = $fdoc])*
                pub $field: $ty,
            )*
        }

        impl Default for $name {
            fn default() -> $name {
                $name {
                    $($field: $default,)*
                }
            }
        }

        impl $name {
            /// Every field as declared, in order.
            pub const FIELDS: &'static [$crate::config::declare::Field] = &[
                $($crate::config::declare::Field {
                    key: stringify!($field),
                    doc: concat!($($fdoc, "\n",)*),
                    rule: &$rule,
                },)*
            ];
        }

        impl $crate::config::declare::Section for $name {
            $($crate::config::declare::section!(@role $role $kind);)?

            fn validate(&self, check: &$crate::config::rules::Check) -> $crate::error::Result<()> {
                $($crate::config::declare::check_field(
                    check,
                    stringify!($field),
                    &self.$field,
                    &$rule,
                )?;)*
                Ok(())
            }

            fn rows(key: &str) -> Vec<$crate::config::declare::Row> {
                $crate::config::declare::rows_of::<$name>(key, $name::FIELDS)
            }
        }
    };
    (@role replicated $kind:ident) => {
        const UNIT: Option<$crate::graph::UnitKind> = Some($crate::graph::UnitKind::$kind);
        const REPLICATED: bool = true;
        fn instances(&self) -> (u32, u64) {
            (self.count, self.latency_cycles)
        }
    };
    (@role single $kind:ident) => {
        const UNIT: Option<$crate::graph::UnitKind> = Some($crate::graph::UnitKind::$kind);
    };
}

/// Declares the whole architecture once: its own fields (as [`section!`]'s), then its
/// sections (doc, name, type), in the order a file is echoed in. It writes the struct, its
/// `Default`, `validate` (every field and section in declared order), the kind-to-section
/// lookups `unit` and `count_field` (from each section's [`Section::UNIT`]), and the field
/// table's rows.
macro_rules! architecture {
    (
        $(#[doc = $doc:literal])*
        pub struct $name:ident {
            $(
                $(#[doc = $fdoc:literal])*
                pub $field:ident: $ty:ty = $default:expr => $rule:expr,
            )*
            sections:
            $(
                $(#[doc = $sdoc:literal])*
                pub $section:ident: $sty:ty,
            )*
        }
    ) => {
        $(#[doc = $doc])*
        #[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
        #[serde(default, deny_unknown_fields)]
        pub struct $name {
            $(
                $(#[doc = $fdoc])*
                pub $field: $ty,
            )*
            $(
                $(#[doc = $sdoc])*
                pub $section: $sty,
            )*
        }

        impl Default for $name {
            fn default() -> $name {
                $name {
                    $($field: $default,)*
                    $($section: <$sty>::default(),)*
                }
            }
        }

        impl $name {
            /// The architecture's own fields as declared, in order.
            const FIELDS: &'static [$crate::config::declare::Field] = &[
                $($crate::config::declare::Field {
                    key: stringify!($field),
                    doc: concat!($($fdoc, "\n",)*),
                    rule: &$rule,
                },)*
            ];

            /// Checks every value against what the simulator accepts, fields then sections
            /// in the file's order; the first refused value is returned as
            /// [`Error::Invalid`](crate::error::Error::Invalid) naming `file` and its dotted
            /// field path.
            pub fn validate(&self, file: &str) -> $crate::error::Result<()> {
                let check = $crate::config::rules::Check::new(file);
                $($crate::config::declare::check_field(
                    &check,
                    stringify!($field),
                    &self.$field,
                    &$rule,
                )?;)*
                $($crate::config::declare::Section::validate(
                    &self.$section,
                    &check.at(stringify!($section)),
                )?;)*
                Ok(())
            }

            /// How many instances of `kind` this architecture has, and the latency of each
            /// \[cycles\], from the section that declares `kind` (a kind inside another, a
            /// blend unit in its ROP, has its host's).
            ///
            /// # Panics
            /// When no section declares the kind (a unit test holds every kind of the
            /// graph declared).
            pub fn unit(&self, kind: $crate::graph::UnitKind) -> (u32, u64) {
                let host = kind.inside().unwrap_or(kind);
                $(if <$sty as $crate::config::declare::Section>::UNIT == Some(host) {
                    return $crate::config::declare::Section::instances(&self.$section);
                })*
                panic!("no section of the architecture declares {kind:?}")
            }

            /// The architecture field that sets `kind`'s instance count (`"rasterizer.count"`);
            /// None for a kind that has one instance by construction (the geometry fetch and
            /// the frame-buffer port). A kind inside another has its host's.
            pub fn count_field(kind: $crate::graph::UnitKind) -> Option<&'static str> {
                use $crate::config::declare::Section;
                let host = kind.inside().unwrap_or(kind);
                $(if <$sty as Section>::REPLICATED && <$sty as Section>::UNIT == Some(host) {
                    return Some(concat!(stringify!($section), ".count"));
                })*
                None
            }

            /// The section declaring each kind, by the kinds' [`Section::UNIT`] (for the
            /// test that every kind of the graph has one).
            #[cfg(test)]
            pub(super) fn declared_units() -> Vec<(&'static str, $crate::graph::UnitKind)> {
                let mut out = Vec::new();
                $(if let Some(kind) = <$sty as $crate::config::declare::Section>::UNIT {
                    out.push((stringify!($section), kind));
                })*
                out
            }

            /// Every row of the field table: the architecture's own fields, then each
            /// section's, in the file's order.
            pub fn rows() -> Vec<$crate::config::declare::Row> {
                let mut rows = $crate::config::declare::rows_of::<$name>("", $name::FIELDS);
                $(rows.extend(<$sty as $crate::config::declare::Section>::rows(
                    stringify!($section),
                ));)*
                rows
            }
        }
    };
}

pub(crate) use {architecture, section};
