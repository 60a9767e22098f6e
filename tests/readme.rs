//! The README and the user guide (`docs/src/*.md`) cannot drift from the program:
//!
//! - every command of their ```sh blocks runs as written (with `--out` added so that nothing is
//!   written into the source tree) and completes its output directory;
//! - every table of critical lengths in a ```text block is what the command of the nearest
//!   ```sh block above it prints, line for line;
//! - every scene of their ```toml blocks loads, and the scene-key table names every key;
//! - the command reference has a row for every subcommand of `rodloop --help` naming every
//!   option of that subcommand's `--help`, and no option it lacks;
//! - the library example shown in the guide is, character for character, the example that
//!   CI builds, and it runs (its own assertions compare it with the exact loop);
//! - every relative link and picture points to a file of the repository, and the book's
//!   table of contents (`docs/src/SUMMARY.md`) lists exactly the guide's pages.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "../crates/solver/examples/library.rs"]
mod library_example;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The guide's pages (`docs/src/*.md`, SUMMARY.md included), sorted by name.
fn guide_pages() -> Vec<String> {
    let mut pages: Vec<String> = std::fs::read_dir(root().join("docs/src"))
        .expect("docs/src")
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".md"))
        .map(|n| format!("docs/src/{n}"))
        .collect();
    pages.sort();
    pages
}

/// README.md and every guide page, as (path, text).
fn documents() -> Vec<(String, String)> {
    let mut out = vec![("README.md".to_string(), read("README.md"))];
    for p in guide_pages() {
        let text = read(&p);
        out.push((p, text));
    }
    out
}

/// The fenced blocks of a text in document order: (language, lines).
fn fenced(text: &str) -> Vec<(String, Vec<String>)> {
    let mut out = Vec::new();
    let mut current: Option<(String, Vec<String>)> = None;
    for line in text.lines() {
        let t = line.trim_end();
        match &mut current {
            None => {
                if let Some(lang) = t.strip_prefix("```") {
                    current = Some((lang.to_string(), Vec::new()));
                }
            }
            Some((_, v)) if t == "```" => {
                let lines = std::mem::take(v);
                let (lang, _) = current.take().unwrap();
                out.push((lang, lines));
            }
            Some((_, v)) => v.push(t.to_string()),
        }
    }
    assert!(current.is_none(), "an unclosed ``` block");
    out
}

/// The blocks of one language, in document order.
fn blocks(text: &str, lang: &str) -> Vec<Vec<String>> {
    fenced(text)
        .into_iter()
        .filter(|(l, _)| l == lang)
        .map(|(_, b)| b)
        .collect()
}

/// Cargo lines of the sh blocks that are not `rodloop` runs: the test command (the one
/// running this test), and the install and build commands (what the test binary is).
const NOT_RUN_HERE: [&str; 3] = [
    "cargo test --release --workspace",
    "cargo install --path .",
    "cargo build --release",
];

fn run(args: &[&str], out: &Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_rodloop"))
        .current_dir(root())
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "documented command `rodloop {}` failed: {}",
        args.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).to_string()
}

#[test]
fn every_documented_command_runs_and_prints_its_tables() {
    let docs = documents();
    // Each distinct command runs once; its stdout is kept for the tables below it.
    let mut printed: BTreeMap<String, String> = BTreeMap::new();
    let mut tables = 0;
    for (path, text) in &docs {
        let mut last: Option<String> = None;
        for (lang, block) in fenced(text) {
            if lang == "sh" {
                for line in &block {
                    if line.is_empty() || line.starts_with('#') {
                        continue;
                    }
                    if NOT_RUN_HERE.contains(&line.as_str()) {
                        last = None;
                        continue;
                    }
                    let Some(rest) = line.strip_prefix("cargo run --release -- ") else {
                        panic!("{path}: sh line not covered by this test: {line}");
                    };
                    assert!(
                        !rest.contains(['"', '\'', '|', '>', '$', ';', '&']),
                        "{path}: shell syntax in a documented command: {line}"
                    );
                    if !printed.contains_key(rest) {
                        let args: Vec<&str> = rest.split_whitespace().collect();
                        let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
                            .join(format!("docs-{}", printed.len()));
                        let _ = std::fs::remove_dir_all(&out);
                        let stdout = run(&args, &out);
                        assert!(out.join("summary.json").exists(), "{path}: {line}");
                        printed.insert(rest.to_string(), stdout);
                    }
                    last = Some(rest.to_string());
                }
            } else if lang == "text" {
                let Some(head) = block.first() else { continue };
                if !head.starts_with("Critical lengths") {
                    continue;
                }
                let command = last.as_ref().unwrap_or_else(|| {
                    panic!("{path}: a table of critical lengths with no command above it")
                });
                let stdout = &printed[command];
                for line in &block {
                    if line.trim() == "…" {
                        continue;
                    }
                    assert!(
                        stdout.lines().any(|l| l.trim_end() == line),
                        "{path}: line not printed by `rodloop {command}`:\n{line}\n--- printed:\n{stdout}"
                    );
                }
                tables += 1;
            }
        }
    }
    // The README's main job and the exact diagram are among the commands, and their tables
    // are checked.
    for c in ["diagram", "diagram --model exact"] {
        assert!(printed.contains_key(c), "{:?}", printed.keys());
    }
    assert!(
        tables >= 3,
        "only {tables} tables of critical lengths were checked"
    );
    let readme = read("README.md");
    for line in [
        "cargo run --release -- diagram",
        "cargo test --release --workspace",
    ] {
        assert!(
            blocks(&readme, "sh").iter().flatten().any(|l| l == line),
            "the README lacks `{line}`"
        );
    }
    // CI runs exactly the README's test command.
    assert!(read(".ci/run")
        .lines()
        .any(|l| l.trim() == "cargo test --release --workspace"));
}

#[test]
fn every_documented_scene_loads() {
    let mut tomls = 0;
    for (path, text) in documents() {
        for b in blocks(&text, "toml") {
            // A Cargo manifest excerpt (the library page) is not a scene.
            if b.first().map(String::as_str) == Some("[dependencies]") {
                continue;
            }
            let src = b.join("\n");
            if let Err(e) = rodloop_scene::Scene::from_toml(&src, &path) {
                panic!("{path}: scene does not load: {e}\n{src}");
            }
            tomls += 1;
        }
    }
    assert!(tomls >= 2, "only {tomls} scenes found");
    // Every scene key is in the scene table of the guide.
    let scenes = read("docs/src/scenes.md");
    let table: String = scenes
        .lines()
        .filter(|l| l.starts_with('|'))
        .collect::<Vec<_>>()
        .join("\n");
    for key in [
        "name",
        "radius",
        "confinement",
        "lbar_min",
        "lbar_max",
        "accuracy",
        "[stiffness]",
        "stiffness.kind",
        "stiffness.d0",
        "stiffness.d1",
        "stiffness.s0",
        "stiffness.s1",
        "stiffness.gamma",
        "stiffness.s",
        "[wall]",
        "wall.shape",
    ] {
        assert!(
            table.contains(&format!("`{key}`")),
            "docs/src/scenes.md scene table lacks {key}"
        );
    }
}

/// The long options (`--name`) in a text.
fn flags(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
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

/// The command table of the guide lists every subcommand of `rodloop --help`, and its rows for
/// a subcommand name every option of that subcommand's `--help` and no option it does not
/// have.
#[test]
fn command_reference_matches_help() {
    let text = read("docs/src/commands.md");
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
            "the command table has no row for `rodloop {sub}`"
        );
        let documented = flags(&rows);
        let mut options = flags(&help(&[sub]));
        options.remove("--help");
        for f in &options {
            assert!(
                documented.contains(f),
                "the command table's rows of `rodloop {sub}` do not mention {f}"
            );
        }
        // Options named in the usage column (the first cell) exist.
        for row in rows.lines() {
            let usage = row.split(" | ").next().unwrap_or("");
            for f in flags(usage) {
                assert!(
                    options.contains(&f),
                    "the usage of `rodloop {sub}` names {f}, which `--help` lacks"
                );
            }
        }
    }
}

/// The guide's library page shows the example file as it is, and the example runs: it
/// solves the saddle loop numerically and asserts that it matches the exact loop within the
/// error estimate, and that the two-segment rod's energy lies between the uniform rods'.
#[test]
fn library_example_is_shown_as_it_is_and_runs() {
    let page = read("docs/src/library.md");
    let example = read("crates/solver/examples/library.rs");
    let shown: Vec<Vec<String>> = blocks(&page, "rust,ignore");
    assert!(
        shown.iter().any(|b| b.join("\n")
            == example
                .trim_end()
                .lines()
                .map(str::trim_end)
                .collect::<Vec<_>>()
                .join("\n")),
        "docs/src/library.md does not show crates/solver/examples/library.rs as it is"
    );
    library_example::main().expect("the library example runs");
}

/// Relative links and pictures of the README and the guide point to files that exist; the
/// table of contents lists exactly the guide's pages.
#[test]
fn links_point_to_files_and_the_contents_list_every_page() {
    for (path, text) in documents() {
        let dir = Path::new(&path).parent().unwrap().to_path_buf();
        let mut rest = text.as_str();
        while let Some(i) = rest.find("](") {
            rest = &rest[i + 2..];
            let Some(end) = rest.find(')') else { break };
            let target = &rest[..end];
            rest = &rest[end..];
            if target.contains("://") || target.starts_with('#') || target.contains(' ') {
                continue;
            }
            let file = target.split('#').next().unwrap();
            assert!(
                root().join(&dir).join(file).exists(),
                "{path}: link to a missing file: {target}"
            );
        }
    }
    let summary = read("docs/src/SUMMARY.md");
    let listed: BTreeSet<String> = summary
        .lines()
        .filter_map(|l| l.split("](").nth(1))
        .filter_map(|t| t.split(')').next())
        .map(|t| format!("docs/src/{t}"))
        .collect();
    let pages: BTreeSet<String> = guide_pages()
        .into_iter()
        .filter(|p| p != "docs/src/SUMMARY.md")
        .collect();
    assert_eq!(listed, pages, "SUMMARY.md and the pages of docs/src differ");
    assert!(pages.len() >= 10, "{pages:?}");
}
