//! Scene parsing: the shipped scenes load, bad files are rejected with the key and line.

use rodloop_scene::{Accuracy, Confinement, Scene, SceneError, StiffnessSpec, WallSpec};

#[test]
fn shipped_scenes_parse() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            Scene::from_file(&path).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(
        n >= 4,
        "expected the paper's scenes in data/scenes, found {n}"
    );
}

#[test]
fn defaults_are_the_homogeneous_surface_scene() {
    let s = Scene::from_toml("", "<empty>").unwrap();
    assert_eq!(s.confinement, Confinement::Surface);
    assert_eq!(s.accuracy, Accuracy::Default);
    assert_eq!(s.stiffness, StiffnessSpec::Uniform { d: 1.0 });
    assert_eq!((s.lbar_min, s.lbar_max, s.radius), (1.0, 5.0, 1.0));
}

#[test]
fn unknown_key_is_an_error_naming_key_and_line() {
    let text = "radius = 1.0\nradus = 2.0\n";
    let err = Scene::from_toml(text, "x.toml").unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, SceneError::Parse { .. }));
    assert!(msg.contains("radus") && msg.contains("line 2"), "{msg}");
    let text = "[stiffness]\nkind = \"tanh\"\nd0 = 1\nd1 = 0.5\ns0 = 0.3\ns1 = 0.8\ngama = 200\n";
    let msg = Scene::from_toml(text, "x.toml").unwrap_err().to_string();
    assert!(msg.contains("gama") && msg.contains("line 7"), "{msg}");
}

#[test]
fn invalid_values_name_the_key() {
    for (text, key) in [
        ("radius = -1\n", "radius"),
        ("lbar_min = 3\nlbar_max = 2\n", "lbar_max"),
        (
            "[stiffness]\nkind = \"tanh\"\nd0 = 1\nd1 = 0\ns0 = 0.3\ns1 = 0.8\ngamma = 200\n",
            "stiffness.d1",
        ),
        (
            "[stiffness]\nkind = \"tanh\"\nd0 = 1\nd1 = 0.5\ns0 = 0.8\ns1 = 0.3\ngamma = 200\n",
            "stiffness.s1",
        ),
        (
            "[stiffness]\nkind = \"table\"\ns = [0.0, 0.5, 0.4]\nd = [1, 2, 3]\n",
            "stiffness.s",
        ),
        ("accuracy = \"extreme\"\n", "accuracy"),
        ("confinement = \"outside\"\n", "confinement"),
        ("[stiffness]\nkind = \"uniform\"\nd0 = 2\n", "stiffness.d0"),
        ("[stiffness]\nkind = \"tanh\"\nd0 = 1\n", "stiffness.d1"),
        ("[stiffness]\nkind = \"spline\"\n", "stiffness.kind"),
    ] {
        let msg = Scene::from_toml(text, "x.toml").unwrap_err().to_string();
        assert!(msg.contains(key), "{text:?}: {msg}");
    }
}

#[test]
fn table_profile_parses() {
    let text = "[stiffness]\nkind = \"table\"\ns = [0.0, 0.5, 0.7]\nd = [1, 0.5, 2]\n";
    let s = Scene::from_toml(text, "t.toml").unwrap();
    assert_eq!(
        s.stiffness,
        StiffnessSpec::Table {
            s: vec![0.0, 0.5, 0.7],
            d: vec![1.0, 0.5, 2.0]
        }
    );
    let two = "[stiffness]\nkind = \"table\"\ns = [0.0, 0.5]\nd = [1, 0.5]\n";
    assert!(Scene::from_toml(two, "t.toml")
        .unwrap_err()
        .to_string()
        .contains("stiffness.s"));
}

/// Table entries are checked at load time and the message names the entry.
#[test]
fn table_entries_are_validated_by_name() {
    for (s, d, want) in [
        (
            "[0.0, nan, 0.5]",
            "[1, 1, 1]",
            "stiffness.s[1] = NaN: must be a finite number",
        ),
        (
            "[0.0, 0.5, 0.4]",
            "[1, 1, 1]",
            "stiffness.s[2] = 0.4: must exceed stiffness.s[1] = 0.5",
        ),
        (
            "[0.0, 0.5, 1.0]",
            "[1, 1, 1]",
            "stiffness.s[2] = 1: must lie in [0, 1)",
        ),
        (
            "[0.0, 0.3, 0.6]",
            "[1, -0.5, 1]",
            "stiffness.d[1] = -0.5: must be a positive",
        ),
        (
            "[0.0, 0.3, 0.6]",
            "[1, 1, 0]",
            "stiffness.d[2] = 0: must be a positive",
        ),
        (
            "[0.0, 0.3, 0.6]",
            "[1, 1, inf]",
            "stiffness.d[2] = inf: must be a positive",
        ),
    ] {
        let text = format!("[stiffness]\nkind = \"table\"\ns = {s}\nd = {d}\n");
        let msg = Scene::from_toml(&text, "t.toml").unwrap_err().to_string();
        assert!(msg.contains(want), "{text:?}: {msg}");
    }
}

/// A missing key is named as missing (not "stiffness.s0 = : is required").
#[test]
fn missing_keys_are_named() {
    let text = "[stiffness]\nkind = \"tanh\"\nd0 = 1\nd1 = 0.5\ns1 = 0.8\ngamma = 200\n";
    let msg = Scene::from_toml(text, "t.toml").unwrap_err().to_string();
    assert!(msg.contains("missing key stiffness.s0"), "{msg}");
    assert!(!msg.contains(" = :"), "{msg}");
    let text = "[stiffness]\nkind = \"table\"\ns = [0.0, 0.5, 0.7]\n";
    let msg = Scene::from_toml(text, "t.toml").unwrap_err().to_string();
    assert!(msg.contains("missing key stiffness.d"), "{msg}");
}

/// A key the stiffness kind does not use is named without an empty `= :` (it was
/// "stiffness.gamma = : is not used by kind = \"uniform\""); so is an array where a number
/// belongs.
#[test]
fn unused_and_mistyped_keys_have_no_empty_value() {
    for (text, want) in [
        (
            "[stiffness]\nkind = \"uniform\"\nd = 1\ngamma = 3\n",
            "stiffness.gamma: is not used by kind = \"uniform\"",
        ),
        (
            "[stiffness]\nkind = \"uniform\"\nd = [1, 2, 3]\n",
            "stiffness.d: must be a number",
        ),
    ] {
        let msg = Scene::from_toml(text, "t.toml").unwrap_err().to_string();
        assert!(msg.contains(want), "{text:?}: {msg}");
        assert!(!msg.contains(" = :"), "{msg}");
    }
}

/// TOML errors are one line that names the line, column and source text (the parser's own
/// message spans five lines with a caret drawing).
#[test]
fn toml_errors_are_one_line_with_the_source() {
    for (text, want) in [
        (
            "name = \"x\"\nconfinment = \"surface\"\n",
            "line 2, column 1 (`confinment = \"surface\"`): unknown field `confinment`",
        ),
        (
            "radius = \"one\"\n",
            "line 1, column 10 (`radius = \"one\"`): invalid type",
        ),
        ("name = \"x\n", "line 1, column"),
    ] {
        let msg = Scene::from_toml(text, "t.toml").unwrap_err().to_string();
        assert!(!msg.contains('\n'), "{text:?}: {msg}");
        assert!(msg.starts_with("scene file t.toml: "), "{msg}");
        assert!(msg.contains(want), "{text:?}: {msg}");
    }
}

/// Errors do not echo long arrays whole.
#[test]
fn long_arrays_are_not_echoed_whole() {
    let n = 3000;
    let s: Vec<String> = (0..n).map(|i| format!("{}", i as f64 / n as f64)).collect();
    let d: Vec<String> = (0..n - 1).map(|_| "1.0".to_string()).collect();
    let text = format!(
        "[stiffness]\nkind = \"table\"\ns = [{}]\nd = [{}]\n",
        s.join(", "),
        d.join(", ")
    );
    let msg = Scene::from_toml(&text, "t.toml").unwrap_err().to_string();
    assert!(msg.len() < 500, "{} bytes: {msg}", msg.len());
    // A syntax error on a long line is cut too.
    let text = format!(
        "[stiffness]\nkind = \"table\"\ns = [{}, oops]\n",
        s.join(", ")
    );
    let msg = Scene::from_toml(&text, "t.toml").unwrap_err().to_string();
    assert!(msg.len() < 1000, "{} bytes: {msg}", msg.len());
}

/// The `[wall]` table of an enclosed scene: the sphere by default and by name; another
/// shape, a key the table does not know, or a wall on a surface scene is an error naming it.
#[test]
fn wall_table_names_the_enclosed_wall() {
    let enclosed = "confinement = \"enclosed\"\n";
    let s = Scene::from_toml(enclosed, "e.toml").unwrap();
    assert_eq!(s.wall, WallSpec::Sphere);
    let s = Scene::from_toml(&format!("{enclosed}[wall]\nshape = \"sphere\"\n"), "e.toml").unwrap();
    assert_eq!(s.wall, WallSpec::Sphere);
    let msg = Scene::from_toml(&format!("{enclosed}[wall]\nshape = \"cube\"\n"), "e.toml")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("wall.shape") && msg.contains("cube"), "{msg}");
    let msg = Scene::from_toml(&format!("{enclosed}[wall]\nsemi_axis = 2\n"), "e.toml")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("semi_axis") && msg.contains("line 3"), "{msg}");
    let msg = Scene::from_toml("[wall]\nshape = \"sphere\"\n", "s.toml")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("wall") && msg.contains("enclosed"), "{msg}");
}
