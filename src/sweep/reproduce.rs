//! The `lembo-sim render` command that reproduces one run of a sweep, for the runs
//! `answer.md` names (DESIGN.md §7): the scene and architecture files as the spec names
//! them (so relative to the spec's folder), the spec's viewport, the point's parameters as
//! flags, each `arch.` field as `--set`.

use serde_json::Value;

/// The command for the run of `record` (a line of `results.jsonl`), to run from the spec's
/// folder; None for a record without a scene source. A `tech.` parameter has no flag: it
/// is said after the command, to be written into a `--tech` file.
pub(super) fn render_command(record: &Value) -> Option<String> {
    let report = &record["report"];
    let scene = &report["scene"];
    let mut words: Vec<String> = vec![
        "lembo-sim render".into(),
        quote(scene["source"].as_str()?),
        format!(
            "--viewport {}x{}",
            scene["width"].as_u64()?,
            scene["height"].as_u64()?
        ),
    ];
    let settings = &report["settings"];
    if let Some(arch) = settings["arch_file"]
        .as_str()
        .filter(|a| !a.starts_with('('))
    {
        words.push(format!("--arch {}", quote(arch)));
    }
    let mut tech: Vec<String> = Vec::new();
    let params = record["params"].as_object()?;
    for (name, value) in params {
        let shown = match value {
            Value::String(s) => s.clone(),
            v => v.to_string(),
        };
        if let Some(field) = name.strip_prefix(super::names::ARCH) {
            words.push(format!("--set {}", quote(&format!("{field}={shown}"))));
        } else if name.starts_with(super::names::TECH) {
            tech.push(format!("{name} = {shown}"));
        } else if let Some(flag) = flag(name) {
            words.push(format!("{flag} {}", quote(&shown)));
        }
    }
    if settings["supersample"].as_u64().is_some_and(|s| s > 1) {
        words.push(format!("--supersample {}", settings["supersample"]));
    }
    if settings["reference"].as_bool() == Some(true) {
        words.push("--reference".into());
    }
    words.push(format!(
        "--out out/run{}",
        record["index"].as_u64().unwrap_or_default()
    ));
    let mut command = words.join(" ");
    if !tech.is_empty() {
        command = format!("{command} (with {} in a --tech file)", tech.join(", "));
    }
    Some(command)
}

/// The render flag of a point's parameter; None for one that has none (the sensitivity
/// marker).
fn flag(param: &str) -> Option<&'static str> {
    Some(match param {
        "path" => "--path",
        "k" => "--k",
        "tess" => "--tess",
        "samples" => "--samples",
        "datapath" => "--datapath",
        "perspective_tol" => "--perspective-tol",
        "blend" => "--blend",
        "threshold" => "--threshold",
        _ => return None,
    })
}

/// A word as a POSIX shell reads it back: bare when it holds only safe characters, else in
/// single quotes.
fn quote(word: &str) -> String {
    let safe = |c: char| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c);
    if !word.is_empty() && word.chars().all(safe) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_record_gives_the_render_command_of_its_point() {
        let record = json!({
            "index": 7,
            "params": {
                "path": "triangle", "tess": 16,
                "arch.rop.count": 8, "arch.tessellation.source": "onchip",
                "tech.dram.pj_per_byte": 20.0
            },
            "report": {
                "scene": {"source": "../../traces/my bunny.json", "width": 512, "height": 256},
                "settings": {"arch_file": "../arch/gpu.json", "reference": true, "supersample": 1}
            }
        });
        assert_eq!(
            render_command(&record).unwrap(),
            "lembo-sim render '../../traces/my bunny.json' --viewport 512x256 \
             --arch ../arch/gpu.json --set rop.count=8 --set tessellation.source=onchip \
             --path triangle --tess 16 --reference --out out/run7 \
             (with tech.dram.pj_per_byte = 20.0 in a --tech file)"
        );
        // The embedded baseline has no file to name.
        let record = json!({
            "index": 0, "params": {"k": 0.25},
            "report": {
                "scene": {"source": "s.json", "width": 8, "height": 8},
                "settings": {"arch_file": "(embedded baseline)", "reference": false, "supersample": 4}
            }
        });
        assert_eq!(
            render_command(&record).unwrap(),
            "lembo-sim render s.json --viewport 8x8 --k 0.25 --supersample 4 --out out/run0"
        );
    }

    #[test]
    fn quoting_survives_the_shell() {
        assert_eq!(quote("a'b c"), r"'a'\''b c'");
        assert_eq!(quote(""), "''");
        assert_eq!(quote("x=1.5"), "x=1.5");
    }
}
