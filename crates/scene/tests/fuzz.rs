//! Fuzz-style property tests of the scene parser: random and mutated scene files
//! never panic; each gives either a scene that passes validation or a short error.

use proptest::prelude::*;
use rodloop_scene::{Scene, StiffnessSpec};

const SHIPPED: &[&str] = &[
    include_str!("../../../data/scenes/homogeneous-surface.toml"),
    include_str!("../../../data/scenes/homogeneous-enclosed.toml"),
    include_str!("../../../data/scenes/inhomogeneous-d1-0.5.toml"),
    "[stiffness]\nkind = \"table\"\ns = [0.0, 0.25, 0.5, 0.75]\nd = [1.0, 0.5, 0.01, 2.0]\n",
];

/// Pieces a mutation may insert: keys, values, TOML syntax, extreme numbers.
const PIECES: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1",
    "0",
    "1e-300",
    "[",
    "]",
    "=",
    "\"",
    "\n",
    "[stiffness]",
    "kind = \"table\"",
    "kind = \"tanh\"",
    "kind = \"uniform\"",
    "s = [0.0, 0.5, 0.2]",
    "d = [1, -1, 2]",
    "d = 2",
    "gamma = 1e9",
    "radius = 0",
    "lbar_max = 60",
    "name = \"nullable\"",
    "accuracy = \"high\"",
    "confinement = \"enclosed\"",
    "s0 = 0.9",
    "#",
    ",",
    "{",
    "}",
    "é",
];

#[derive(Clone, Debug)]
enum Mutation {
    Delete(usize, usize),
    Insert(usize, usize),
    Duplicate(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0usize..20).prop_map(|(a, n)| Mutation::Delete(a, n)),
        (any::<usize>(), 0..PIECES.len()).prop_map(|(a, p)| Mutation::Insert(a, p)),
        (any::<usize>(), 0usize..40).prop_map(|(a, n)| Mutation::Duplicate(a, n)),
    ]
}

fn apply(text: &str, muts: &[Mutation]) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for m in muts {
        let len = chars.len().max(1);
        match *m {
            Mutation::Delete(a, n) => {
                let a = a % len;
                let b = (a + n).min(chars.len());
                if a < b {
                    chars.drain(a..b);
                }
            }
            Mutation::Insert(a, p) => {
                let a = a % (chars.len() + 1);
                for (k, c) in PIECES[p].chars().enumerate() {
                    chars.insert(a + k, c);
                }
            }
            Mutation::Duplicate(a, n) => {
                let a = a % len;
                let b = (a + n).min(chars.len());
                let piece: Vec<char> = chars[a.min(b)..b].to_vec();
                let at = b.min(chars.len());
                for (k, c) in piece.into_iter().enumerate() {
                    chars.insert(at + k, c);
                }
            }
        }
    }
    chars.into_iter().collect()
}

fn check(text: &str) {
    match Scene::from_toml(text, "fuzz.toml") {
        Ok(scene) => {
            // A scene that loads is valid: every number in its domain.
            scene
                .validate("fuzz.toml")
                .expect("a loaded scene validates");
            assert!(scene.radius.is_finite() && scene.radius > 0.0);
            assert!(scene.lbar_min > 0.0 && scene.lbar_max > scene.lbar_min);
            if let StiffnessSpec::Table { s, d } = &scene.stiffness {
                assert!(s.iter().chain(d).all(|v| v.is_finite()));
                assert!(d.iter().all(|&v| v > 0.0));
                assert!(s.windows(2).all(|w| w[1] > w[0]));
            }
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.is_empty());
            assert!(msg.len() < 2000, "error of {} bytes: {msg}", msg.len());
            assert!(msg.starts_with("scene file fuzz.toml"), "{msg}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Mutated shipped scenes: a success that validates, or a short error naming the file.
    #[test]
    fn mutated_scenes_never_panic(base in 0..SHIPPED.len(), muts in prop::collection::vec(mutation(), 0..6)) {
        check(&apply(SHIPPED[base], &muts));
    }

    /// Scenes assembled from random keys and values of the right and the wrong types.
    #[test]
    fn random_scenes_never_panic(
        radius in prop_oneof![Just(f64::NAN), Just(f64::INFINITY), any::<f64>(), -2.0..5.0f64],
        kind in prop_oneof![Just("uniform"), Just("tanh"), Just("table"), Just("bogus")],
        xs in prop::collection::vec(prop_oneof![Just(f64::NAN), any::<f64>(), -0.5..1.5f64], 0..8),
        ds in prop::collection::vec(prop_oneof![Just(0.0), any::<f64>(), 0.0..3.0f64], 0..8),
        lmin in -1.0..60.0f64,
        lmax in -1.0..60.0f64,
    ) {
        let num = |v: f64| if v.is_nan() { "nan".to_string() } else if v.is_infinite() { if v > 0.0 { "inf".into() } else { "-inf".into() } } else { format!("{v:?}") };
        let arr = |v: &[f64]| format!("[{}]", v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", "));
        let body = match kind {
            "uniform" => format!("d = {}", num(*ds.first().unwrap_or(&1.0))),
            "tanh" => format!(
                "d0 = {}\nd1 = {}\ns0 = {}\ns1 = {}\ngamma = {}",
                num(*ds.first().unwrap_or(&1.0)), num(*ds.get(1).unwrap_or(&0.5)),
                num(*xs.first().unwrap_or(&0.3)), num(*xs.get(1).unwrap_or(&0.8)), num(*ds.get(2).unwrap_or(&200.0))
            ),
            _ => format!("s = {}\nd = {}", arr(&xs), arr(&ds)),
        };
        let text = format!(
            "radius = {}\nlbar_min = {}\nlbar_max = {}\n[stiffness]\nkind = \"{kind}\"\n{body}\n",
            num(radius), num(lmin), num(lmax)
        );
        check(&text);
    }
}
