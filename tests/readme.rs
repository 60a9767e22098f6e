//! The README cannot drift: every command of its ```sh blocks runs as written (with `--out`
//! added so that nothing is written into the source tree), every scene of its ```toml blocks
//! loads, and the critical-length tables of its ```text blocks are what the commands print.

use std::path::Path;
use std::process::Command;

fn readme() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap()
}

/// The fenced blocks of a language: their lines.
fn blocks(text: &str, lang: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut current: Option<Vec<String>> = None;
    for line in text.lines() {
        let t = line.trim_end();
        match &mut current {
            None if t == format!("```{lang}") => current = Some(Vec::new()),
            Some(v) if t == "```" => {
                out.push(std::mem::take(v));
                current = None;
            }
            Some(v) => v.push(t.to_string()),
            None => {}
        }
    }
    out
}

fn run(args: &[&str], out: &Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_rodloop"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "README command `rodloop {}` failed: {}",
        args.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).to_string()
}

#[test]
fn every_readme_command_runs_as_written() {
    let text = readme();
    let sh = blocks(&text, "sh");
    assert!(sh.len() >= 3, "the README's sh blocks were not found");
    let mut ran = Vec::new();
    for (i, line) in sh.iter().flatten().enumerate() {
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if line == "cargo test --release --workspace" {
            // This is the command running this test.
            continue;
        }
        let Some(rest) = line.strip_prefix("cargo run --release -- ") else {
            panic!("README sh line not covered by this test: {line}");
        };
        assert!(
            !rest.contains(['"', '\'', '|', '>', '$']),
            "shell syntax in a README command: {line}"
        );
        let args: Vec<&str> = rest.split_whitespace().collect();
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("readme-{i}"));
        let _ = std::fs::remove_dir_all(&out);
        let stdout = run(&args, &out);
        assert!(out.join("summary.json").exists(), "{line}");
        ran.push((rest.to_string(), stdout));
    }
    // The main job of the quick start is among them.
    assert!(
        ran.iter().any(|(c, _)| c == "diagram"),
        "{:?}",
        ran.iter().map(|r| &r.0).collect::<Vec<_>>()
    );

    // The ```text tables are what the commands print (the "…" line stands for more output).
    for block in blocks(&text, "text") {
        let Some(head) = block.first() else { continue };
        let command: &[&str] = if head.starts_with("Critical lengths (numeric model") {
            &["diagram"]
        } else if head.starts_with("Critical lengths (exact model") {
            &["diagram", "--model", "exact"]
        } else {
            continue;
        };
        let stdout = match ran
            .iter()
            .find(|(c, _)| c.split_whitespace().eq(command.iter().copied()))
        {
            Some((_, s)) => s.clone(),
            None => {
                let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("readme-text");
                let _ = std::fs::remove_dir_all(&out);
                run(command, &out)
            }
        };
        for line in &block {
            if line.trim() == "…" {
                continue;
            }
            assert!(
                stdout.lines().any(|l| l.trim_end() == line),
                "README line not printed by `rodloop {}`:\n{line}\n--- printed:\n{stdout}",
                command.join(" ")
            );
        }
    }
}

#[test]
fn every_readme_scene_loads() {
    let text = readme();
    let tomls = blocks(&text, "toml");
    assert!(tomls.len() >= 2);
    for b in tomls {
        let src = b.join("\n");
        if let Err(e) = rodloop_scene::Scene::from_toml(&src, "README.md") {
            panic!("README scene does not load: {e}\n{src}");
        }
    }
    // Every scene key of the README's table is a key the parser knows: a scene that sets
    // each of them (with a valid value) loads.
    for key in [
        "name",
        "radius",
        "confinement",
        "lbar_min",
        "lbar_max",
        "accuracy",
    ] {
        assert!(
            text.contains(&format!("| `{key}` |")),
            "README scene table lacks {key}"
        );
    }
}

/// The long options (`--name`) in a text.
fn flags(text: &str) -> std::collections::BTreeSet<String> {
    let mut out = std::collections::BTreeSet::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i + 2 < b.len() {
        let starts = b[i] == b'-'
            && b[i + 1] == b'-'
            && (i == 0 || !b[i - 1].is_ascii_alphanumeric() && b[i - 1] != b'-');
        if starts && b[i + 2].is_ascii_lowercase() {
            let mut j = i + 2;
            while j < b.len()
                && (b[j].is_ascii_lowercase() || b[j].is_ascii_digit() || b[j] == b'-')
            {
                j += 1;
            }
            out.insert(text[i..j].trim_end_matches('-').to_string());
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// The command table of the README lists every subcommand of `rodloop --help`, and its rows for
/// a subcommand name every option of that subcommand's `--help` (the table lacked `draw`,
/// `compare --scene`, `--draw` and `--width`/`--height`) and no option it does not have.
#[test]
fn readme_command_table_matches_help() {
    let text = readme();
    let help = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_rodloop"))
            .args(args)
            .arg("--help")
            .output()
            .unwrap();
        assert!(o.status.success());
        String::from_utf8_lossy(&o.stdout).to_string()
    };
    let top = help(&[]);
    let subcommands: Vec<String> = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(String::from))
        .filter(|c| c != "help")
        .collect();
    assert!(subcommands.len() >= 9, "{top}");
    for sub in &subcommands {
        let rows: String = text
            .lines()
            .filter(|l| {
                l.starts_with(&format!("| `rodloop {sub} ")) || *l == format!("| `rodloop {sub}` |")
            })
            .collect::<Vec<_>>()
            .join("\n");
        assert!(
            !rows.is_empty(),
            "README command table has no row for `rodloop {sub}`"
        );
        let documented = flags(&rows);
        let mut options = flags(&help(&[sub]));
        options.remove("--help");
        for f in &options {
            assert!(
                documented.contains(f),
                "README rows of `rodloop {sub}` do not mention {f}"
            );
        }
        // Options named in the usage column (the first cell) exist.
        for row in rows.lines() {
            let usage = row.split(" | ").next().unwrap_or("");
            for f in flags(usage) {
                assert!(
                    options.contains(&f),
                    "README usage of `rodloop {sub}` names {f}, which `--help` lacks"
                );
            }
        }
    }
}
