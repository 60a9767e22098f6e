//! Fuzz-style property test of the command-line layer: argument vectors mutated
//! from cheap valid commands (values replaced by extremes and junk, flags dropped, duplicated
//! or added) never panic or abort; each run ends in bounded time with exit 0 and a complete
//! output set, or exit 1 (2 for clap's usage errors) with a short message and nothing
//! half-written.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use proptest::prelude::*;

/// Cheap valid commands (each runs in well under a second).
const BASES: &[&[&str]] = &[
    &["analytic", "--lbar", "1.2", "--eta", "2", "--points", "16"],
    &[
        "analytic", "--lbar", "2.5", "--branch", "3", "--points", "16",
    ],
    &["euler", "--l", "2", "--lbar", "1.2", "--points", "16"],
    &["euler", "--branch", "2", "--lbar", "0.7", "--points", "16"],
    &[
        "solve",
        "--lbar",
        "1.2",
        "--branch",
        "1",
        "--accuracy",
        "fast",
    ],
    &["solve", "--lbar", "1.7", "--eta", "1", "--accuracy", "fast"],
    &[
        "diagram",
        "--model",
        "exact",
        "--lbar-min",
        "1",
        "--lbar-max",
        "2",
    ],
    &[
        "diagram", "--model", "exact", "--branch", "1,2", "--step", "0.05",
    ],
];

/// Replacement values: extremes, junk, and small valid numbers.
const VALUES: &[&str] = &[
    "-1",
    "0",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "1e-308",
    "18446744073709551615",
    "4294967296",
    "-0",
    "",
    "abc",
    "1,2",
    "2",
    "1.5",
    "0.5",
    "3",
    "fast",
    "high",
    "exact",
    "numeric",
    "--",
    "-",
    "1e400",
    "0x10",
    "1.2.3",
    "é",
];

/// Flags that may be added (never --out, which the harness sets, and never a switch to the
/// numeric diagram model, whose cost is the solver's to bound).
const FLAGS: &[&str] = &[
    "--lbar",
    "--eta",
    "--branch",
    "--l",
    "--points",
    "--accuracy",
    "--from",
    "--scene",
    "--step",
    "--lbar-min",
    "--lbar-max",
    "--resume",
    "--quiet",
    "--bogus",
    "-x",
    "--help",
];

#[derive(Clone, Debug)]
enum Mutation {
    ReplaceValue(usize, usize),
    Drop(usize),
    Duplicate(usize),
    AddFlag(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), 0..VALUES.len()).prop_map(|(i, v)| Mutation::ReplaceValue(i, v)),
        1 => any::<usize>().prop_map(Mutation::Drop),
        1 => any::<usize>().prop_map(Mutation::Duplicate),
        1 => (0..FLAGS.len(), 0..VALUES.len()).prop_map(|(f, v)| Mutation::AddFlag(f, v)),
    ]
}

fn apply(base: &[&str], muts: &[Mutation]) -> Vec<String> {
    let mut args: Vec<String> = base.iter().map(|s| s.to_string()).collect();
    let is_diagram_exact = base[0] == "diagram";
    for m in muts {
        // Positions 1.. (the subcommand stays).
        let n = args.len() - 1;
        if n == 0 {
            break;
        }
        match *m {
            Mutation::ReplaceValue(i, v) => {
                let i = 1 + i % n;
                // Keep the exact model of the diagram bases (see FLAGS).
                if !(is_diagram_exact && (args[i] == "exact" || args[i] == "--model")) {
                    args[i] = VALUES[v].to_string();
                }
            }
            Mutation::Drop(i) => {
                let i = 1 + i % n;
                if !(is_diagram_exact && (args[i] == "exact" || args[i] == "--model")) {
                    args.remove(i);
                }
            }
            Mutation::Duplicate(i) => {
                let i = 1 + i % n;
                let a = args[i].clone();
                args.insert(i, a);
            }
            Mutation::AddFlag(f, v) => {
                args.push(FLAGS[f].to_string());
                args.push(VALUES[v].to_string());
            }
        }
    }
    if is_diagram_exact && !args.iter().any(|a| a == "exact") {
        args.extend(["--model".into(), "exact".into()]);
    }
    args
}

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|e| {
            e.flatten()
                .map(|e| e.file_name().to_string_lossy().to_string())
                .filter(|n| n.starts_with('.'))
                .collect()
        })
        .unwrap_or_default()
}

fn out_dir() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-fuzz")
}

fn run_case(args: &[String]) -> Result<(), TestCaseError> {
    let out = out_dir();
    let _ = std::fs::remove_dir_all(&out);
    let mut child = Command::new(env!("CARGO_BIN_EXE_rodloop"))
        .args(args)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn rodloop");
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if t0.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            return Err(TestCaseError::fail(format!("{args:?} ran over 60 s")));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    prop_assert!(!err.contains("panicked"), "{:?}: {}", args, err);
    let code = status.code();
    prop_assert!(
        matches!(code, Some(0) | Some(1) | Some(2)),
        "{:?}: exit {:?} (abort or signal): {}",
        args,
        code,
        err
    );
    if code == Some(0) {
        // --help prints usage and writes nothing.
        if !args.iter().any(|a| a == "--help") {
            prop_assert!(out.join("summary.json").exists(), "{:?}: no summary", args);
            let s = std::fs::read_to_string(out.join("summary.json")).unwrap();
            prop_assert!(!s.contains("NaN") && !s.contains("null"), "{:?}", args);
        }
    } else {
        prop_assert!(err.starts_with("error"), "{:?}: {}", args, err);
        prop_assert!(err.len() < 4000, "{:?}: {} bytes", args, err.len());
        prop_assert!(
            !out.join("summary.json").exists(),
            "{:?}: summary after error",
            args
        );
    }
    prop_assert!(
        leftovers(&out).is_empty(),
        "{:?}: {:?}",
        args,
        leftovers(&out)
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 120, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_command_lines_end_cleanly(
        base in 0..BASES.len(),
        muts in prop::collection::vec(mutation(), 1..4),
    ) {
        run_case(&apply(BASES[base], &muts))?;
    }
}
