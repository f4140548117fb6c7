//! The field table of `sim/arch/README.md` as Markdown, from the rows the declarations
//! give (`ArchConfig::rows`); a unit test holds the README's copy equal to it.

use super::declare::Row;

/// The line before the generated table in the README.
#[cfg(test)]
pub const BEGIN: &str = "<!-- fields: generated from src/config by config::fields_table; \
                         do not edit by hand -->";
/// The line after it.
#[cfg(test)]
pub const END: &str = "<!-- end of fields -->";

/// `rows` as the Markdown table the README holds between its `BEGIN` and `END` lines.
pub fn markdown(rows: &[Row]) -> String {
    let mut out = String::from("| Field | Default | Accepted | What |\n|---|---|---|---|\n");
    for row in rows {
        out.push_str(&format!(
            "| `{}` | `{}` | {} | {} |\n",
            row.field, row.default, row.accepted, row.what
        ));
    }
    out
}

/// `readme` with the text between its `BEGIN` and `END` lines replaced by `table`; None
/// when it lacks them.
#[cfg(test)]
pub fn with_table(readme: &str, table: &str) -> Option<String> {
    let start = readme.find(BEGIN)? + BEGIN.len();
    let end = start + readme[start..].find(END)?;
    Some(format!(
        "{}\n\n{table}\n{}",
        &readme[..start],
        &readme[end..]
    ))
}
