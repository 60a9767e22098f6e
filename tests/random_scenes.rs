//! Two-segment scenes a user might write, through the binary: randomly generated profiles
//! (own generator, fixed seed) and the profile `d1 = 0.3, s0 = 0.2, s1 = 0.4, gamma = 100`.
//! For each diagram: every state file closes, lies on the sphere, has the branch of its row
//! (dominant harmonic of its moment `D κ_g`, or a family with states of that harmonic) and the energy of
//! its row; the completeness certificate leaves nothing unexplained; labels agree with the traced
//! energies (the lowest index-0 state is "stable", other index-0 states "metastable",
//! index > 0 "unstable", energies within their error estimates tied; one state listed twice
//! carries one label; every length has a stable state or a warning that says why not:
//! [`label_failures`]); and `rodloop solve --branch B` finds no state below the diagram's
//! lowest local minimum at sample lengths beyond three times both error estimates (a `solve`
//! result whose loop does not close is no equilibrium and is not compared; it is printed).
//!
//! `RODLOOP_RANDOM_SCENES=N` checks `N` scenes (default 3) on `RODLOOP_RANDOM_SPAN` of `L̄`
//! (default 0.3); `scripts/random_scenes.sh` runs more on longer ranges.

mod common;

use std::path::Path;

use common::{rodloop, rodloop_ok, tmp, Lcg};

/// A two-segment surface scene: `D1/D0` in 0.01–0.7 (log scale), the soft segment 0.1–0.9
/// of the loop at a random place, `γ` in 20–300, on `lo ≤ L̄ ≤ hi`.
struct Scene {
    d1: f64,
    s0: f64,
    s1: f64,
    gamma: f64,
    lo: f64,
    hi: f64,
}

impl Scene {
    /// Scene `k` of `n`: each of `D1/D0`, the soft segment's length and `γ` is drawn from
    /// its own `k`-th of `n` equal slices of its range (slices permuted differently for the
    /// three, a Latin hypercube), so that a few scenes span the ranges.
    fn random(g: &mut Lcg, span: f64, k: usize, n: usize) -> Self {
        let slice = |g: &mut Lcg, j: usize| (j as f64 + g.next()) / n as f64;
        let d1 = (0.01f64.ln() + slice(g, k) * (0.7f64.ln() - 0.01f64.ln())).exp();
        let len = 0.1 + 0.8 * slice(g, n - 1 - k);
        let s0 = g.range(0.0, 1.0 - len);
        let gamma = 20.0 + 280.0 * slice(g, (k + n / 2) % n);
        let lo = g.range(1.05, 2.9 - span);
        Self {
            d1,
            s0,
            s1: s0 + len,
            gamma,
            lo,
            hi: lo + span,
        }
    }

    fn toml(&self) -> String {
        format!(
            "name = \"random\"\nradius = 1.0\nconfinement = \"surface\"\nlbar_min = {}\n\
             lbar_max = {}\naccuracy = \"default\"\n\n[stiffness]\nkind = \"tanh\"\nd0 = 1.0\n\
             d1 = {}\ns0 = {}\ns1 = {}\ngamma = {}\n",
            self.lo, self.hi, self.d1, self.s0, self.s1, self.gamma
        )
    }
}

/// One row of `branches.csv`.
#[derive(Clone, Debug)]
struct Row {
    branch: u32,
    eta: u32,
    family: u32,
    arc: u64,
    lbar: f64,
    energy: f64,
    error: f64,
    stability: String,
    index: usize,
    file: String,
    /// The error estimate the label checks give the row: its own, or for a row without
    /// one the largest of its sheet (set by [`sheets`]).
    tie: f64,
    /// The indices `(below, above)` where the row is a located index change of its family
    /// (`index_changes` of the diagram's `branches/` files): the row's own index is one
    /// side's only.
    change: Option<(usize, usize)>,
    /// Whether the row is a fold or branch point of its family (an eigenvalue of the
    /// Hessian passes through zero there: its index is that of neither side).
    singular: bool,
    /// `dE/dL̄` of the traced state (its `branches/` file), where it is there.
    slope: Option<f64>,
}

/// Whether the stretch of a sheet between consecutive rows `p` and `q` (`p.lbar < q.lbar`)
/// has index 0: both rows' indices, where a located index change on either end takes its
/// index on the stretch's side, and a fold or branch point (an eigenvalue passes through
/// zero there) leaves the stretch the other row's index.
fn stretch_index0(p: &Row, q: &Row) -> bool {
    let after_p = p.change.map(|c| c.1).or((!p.singular).then_some(p.index));
    let before_q = q.change.map(|c| c.0).or((!q.singular).then_some(q.index));
    match (after_p, before_q) {
        (Some(a), Some(b)) => a == 0 && b == 0,
        (Some(a), None) => a == 0,
        (None, Some(b)) => b == 0,
        (None, None) => p.index == 0 && q.index == 0,
    }
}

/// The folds and branch points among the traced `sheets` ([`branch_files`]),
/// `(branch, family, L̄)`, from the sources of their states.
fn singular_points(sheets: &[serde_json::Value]) -> Vec<(u32, u32, f64)> {
    let mut out = Vec::new();
    for v in sheets {
        let (Some(b), Some(f)) = (v["branch"].as_u64(), v["family"].as_u64()) else {
            continue;
        };
        for p in v["points"].as_array().into_iter().flatten() {
            let singular = matches!(p["source"].as_str(), Some("fold" | "branch_point"));
            if let (true, Some(l)) = (singular, p["lbar"].as_f64()) {
                out.push((b as u32, f as u32, l));
            }
        }
    }
    out
}

/// The slopes `dE/dL̄` of the states of the traced `sheets` ([`branch_files`]),
/// `(branch, family, L̄, slope)`.
fn slopes(sheets: &[serde_json::Value]) -> Vec<(u32, u32, f64, f64)> {
    let mut out = Vec::new();
    for v in sheets {
        let (Some(b), Some(f)) = (v["branch"].as_u64(), v["family"].as_u64()) else {
            continue;
        };
        for p in v["points"].as_array().into_iter().flatten() {
            if let (Some(l), Some(d)) = (p["lbar"].as_f64(), p["slope"].as_f64()) {
                out.push((b as u32, f as u32, l, d));
            }
        }
    }
    out
}

/// Every traced sheet in the diagram's `branches/` files (one sheet per file, or the
/// `sheets` of a family's file).
fn branch_files(dir: &Path) -> Vec<serde_json::Value> {
    fn walk(v: serde_json::Value, out: &mut Vec<serde_json::Value>) {
        match v {
            serde_json::Value::Object(ref m) if m.contains_key("points") => out.push(v),
            serde_json::Value::Object(m) => m.into_iter().for_each(|(_, x)| walk(x, out)),
            serde_json::Value::Array(a) => a.into_iter().for_each(|x| walk(x, out)),
            _ => {}
        }
    }
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir.join("branches")) else {
        return out;
    };
    for e in entries.flatten() {
        let text = std::fs::read_to_string(e.path()).unwrap();
        walk(serde_json::from_str(&text).unwrap(), &mut out);
    }
    out
}

/// The located index changes of the traced `sheets` ([`branch_files`]),
/// `(branch, family, L̄, below, above)`.
fn index_changes(sheets: &[serde_json::Value]) -> Vec<(u32, u32, f64, usize, usize)> {
    let mut out = Vec::new();
    for v in sheets {
        let (Some(b), Some(f)) = (v["branch"].as_u64(), v["family"].as_u64()) else {
            continue;
        };
        for c in v["index_changes"].as_array().into_iter().flatten() {
            if let (Some(l), Some(lo), Some(hi)) =
                (c["lbar"].as_f64(), c["below"].as_u64(), c["above"].as_u64())
            {
                out.push((b as u32, f as u32, l, lo as usize, hi as usize));
            }
        }
    }
    out.sort_by(|x, y| x.partial_cmp(y).unwrap());
    out.dedup();
    out
}

/// The warnings a run's `summary.json` lists (none when it has no `warnings`).
fn warnings(summary: &serde_json::Value) -> Vec<String> {
    summary["warnings"]
        .as_array()
        .map(|w| {
            w.iter()
                .filter_map(|x| x.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

fn rows(dir: &Path) -> Vec<Row> {
    let mut r = csv::Reader::from_path(dir.join("branches.csv")).expect("branches.csv");
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (b, e, f, a, l, en, er, st, ix, sf) = (
        col("branch"),
        col("eta"),
        col("family"),
        col("arc"),
        col("lbar"),
        col("energy"),
        col("energy_error"),
        col("stability"),
        col("index"),
        col("state_file"),
    );
    let sheets = branch_files(dir);
    let changes = index_changes(&sheets);
    let singular = singular_points(&sheets);
    let slopes = slopes(&sheets);
    r.records()
        .map(|x| {
            let x = x.unwrap();
            Row {
                branch: x[b].parse().unwrap(),
                eta: x[e].parse().unwrap(),
                family: x[f].parse().unwrap(),
                arc: x[a].parse().unwrap(),
                lbar: x[l].parse().unwrap(),
                energy: x[en].parse().unwrap(),
                error: x[er].parse().unwrap_or(0.0),
                stability: x[st].to_string(),
                index: x[ix].parse().unwrap(),
                file: x[sf].to_string(),
                tie: 0.0,
                change: None,
                singular: false,
                slope: None,
            }
        })
        .map(|mut row: Row| {
            row.change = changes
                .iter()
                .find(|c| (c.0, c.1) == (row.branch, row.family) && (c.2 - row.lbar).abs() < 1e-12)
                .map(|c| (c.3, c.4));
            row.slope = slopes
                .iter()
                .find(|c| (c.0, c.1) == (row.branch, row.family) && (c.2 - row.lbar).abs() < 1e-12)
                .map(|c| c.3);
            row.singular = singular
                .iter()
                .any(|c| (c.0, c.1) == (row.branch, row.family) && (c.2 - row.lbar).abs() < 1e-12);
            row
        })
        .collect()
}

/// The sheets of the diagram: rows of one family and sheet (`arc / 10⁶`), by `L̄`; a row
/// without an error estimate takes the largest of its sheet as its `tie`.
fn sheets(rows: &[Row]) -> Vec<Vec<Row>> {
    let mut keys: Vec<(u32, u32, u64)> = rows
        .iter()
        .map(|r| (r.branch, r.family, r.arc / 1_000_000))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.iter()
        .map(|k| {
            let mut s: Vec<Row> = rows
                .iter()
                .filter(|r| (r.branch, r.family, r.arc / 1_000_000) == *k)
                .cloned()
                .collect();
            s.sort_by(|a, b| a.lbar.total_cmp(&b.lbar));
            let worst = s.iter().map(|r| r.error).fold(0.0, f64::max);
            for r in &mut s {
                r.tie = if r.error > 0.0 { r.error } else { worst };
            }
            s
        })
        .collect()
}

/// A sheet at `l` as the label checks see it: its energy ([`sheet_at`]), the uncertainty of
/// that energy (the larger `tie` of the rows around `l`, plus the distance of the quadratic
/// interpolation from the linear one), whether it has index 0 there, and whether a row
/// labelled "stable" lies on either side (at a row's own `L̄`: the row or a neighbour on
/// its sheet). `None` outside the sheet.
struct SheetAt {
    energy: f64,
    uncertainty: f64,
    index0: bool,
    stable_side: bool,
}

fn sheet_state(s: &[Row], l: f64) -> Option<SheetAt> {
    let (a, b) = (s.first()?.lbar, s.last()?.lbar);
    if l < a || l > b {
        return None;
    }
    if let Some(i) = s
        .iter()
        .enumerate()
        .filter(|(_, r)| r.lbar == l)
        .min_by(|x, y| x.1.energy.total_cmp(&y.1.energy))
        .map(|(i, _)| i)
    {
        let near = &s[i.saturating_sub(1)..(i + 2).min(s.len())];
        return Some(SheetAt {
            energy: s[i].energy,
            uncertainty: s[i].tie,
            index0: s[i].index == 0,
            stable_side: near.iter().any(|r| r.stability == "stable"),
        });
    }
    let k = s.partition_point(|r| r.lbar < l);
    let (p, q) = (&s[k - 1], &s[k]);
    let t = (l - p.lbar) / (q.lbar - p.lbar);
    let linear = p.energy + t * (q.energy - p.energy);
    let (quadratic, _) = sheet_at(s, l)?;
    // With both rows' slopes `dE/dL̄` (the `branches/` files), the cubic Hermite
    // interpolant, uncertain by its distance from the quadratic; else the quadratic,
    // uncertain by its distance from the linear one.
    let (energy, spread) = match (p.slope, q.slope) {
        (Some(dp), Some(dq)) => {
            let h = q.lbar - p.lbar;
            let hermite = (1.0 + 2.0 * t) * (1.0 - t) * (1.0 - t) * p.energy
                + t * (1.0 - t) * (1.0 - t) * h * dp
                + t * t * (3.0 - 2.0 * t) * q.energy
                + t * t * (t - 1.0) * h * dq;
            (hermite, (hermite - quadratic).abs())
        }
        _ => (quadratic, (quadratic - linear).abs()),
    };
    Some(SheetAt {
        energy,
        uncertainty: p.tie.max(q.tie) + spread,
        index0: stretch_index0(p, q),
        stable_side: p.stability == "stable" || q.stability == "stable",
    })
}

/// The stretches `a ≤ L̄ ≤ b` that the diagram's warnings name.
fn warned_stretches(warnings: &[String]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for w in warnings {
        let mut rest = w.as_str();
        while let Some(k) = rest.find(" ≤ L̄ ≤ ") {
            let before = &rest[..k];
            let start = before
                .rfind(|c: char| !(c.is_ascii_digit() || c == '.'))
                .map_or(0, |i| i + 1);
            let after = &rest[k + " ≤ L̄ ≤ ".len()..];
            let end = after
                .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                .unwrap_or(after.len());
            if let (Ok(a), Ok(b)) = (before[start..].parse(), after[..end].parse()) {
                out.push((a, b));
            }
            rest = &after[end..];
        }
    }
    out
}

/// The label checks on the rows of a diagram (from its files alone): each label agrees
/// with the index ("unstable" exactly when the index is > 0); a "stable" row has no local
/// minimum of another sheet below it by more than the error estimates (the sum of both
/// rows' and the interpolation's); a "metastable" row has one below it or tied with it
/// (except within `2·10⁻³` of an integer `L̄`, where the untraced great circle is lowest);
/// rows that are the same state (same branch, `L̄` and index, energies within their
/// estimates) carry one label; and every length of `lo ≤ L̄ ≤ hi` (a grid of step 0.005
/// and every row's `L̄`) has a state labelled "stable", unless a warning names a stretch
/// around it or it is a great-circle length.
fn label_failures(rows: &[Row], warnings: &[String], lo: f64, hi: f64, what: &str) -> Vec<String> {
    let mut bad = Vec::new();
    let sh = sheets(rows);
    for (i, s) in sh.iter().enumerate() {
        for r in s {
            let label_ok = match r.stability.as_str() {
                "unstable" => r.index > 0,
                "stable" | "metastable" => r.index == 0,
                _ => false,
            };
            if !label_ok {
                bad.push(format!(
                    "{what}: row at {} index {} labelled {}",
                    r.lbar, r.index, r.stability
                ));
                continue;
            }
            if r.index > 0 {
                continue;
            }
            let (mut lower, mut tied) = (None::<(f64, u32, u32)>, false);
            for (j, o) in sh.iter().enumerate() {
                let Some(x) = sheet_state(o, r.lbar).filter(|x| x.index0 && j != i) else {
                    continue;
                };
                let tol = r.tie + x.uncertainty + 1e-12 * r.energy.abs().max(1.0);
                if x.energy < r.energy - tol {
                    if lower.is_none_or(|(e, _, _)| x.energy < e) {
                        lower = Some((x.energy, o[0].branch, o[0].family));
                    }
                } else if x.energy <= r.energy + tol {
                    tied = true;
                }
            }
            let at_great_circle = (r.lbar - r.lbar.round()).abs() < 2e-3;
            if let (Some((e, b, f)), "stable") = (lower, r.stability.as_str()) {
                bad.push(format!(
                    "{what}: row of branch {} family {} at {:.6} (E {:.10}) is stable; branch {b} \
                     family {f} has index 0 at {e:.10}",
                    r.branch, r.family, r.lbar, r.energy
                ));
            }
            if r.stability == "metastable" && lower.is_none() && !tied && !at_great_circle {
                bad.push(format!(
                    "{what}: row of branch {} family {} at {:.6} (E {:.10}) is metastable but \
                     the lowest local minimum",
                    r.branch, r.family, r.lbar, r.energy
                ));
            }
        }
    }
    // One state, one label.
    let all: Vec<&Row> = sh.iter().flatten().collect();
    for (k, a) in all.iter().enumerate() {
        for b in &all[k + 1..] {
            let tied =
                (a.energy - b.energy).abs() <= a.tie + b.tie + 1e-12 * a.energy.abs().max(1.0);
            if (a.branch, a.index) == (b.branch, b.index)
                && a.lbar == b.lbar
                && tied
                && a.stability != b.stability
            {
                bad.push(format!(
                    "{what}: branch {} at {:.6} is listed as E {:.10} ({}, family {}) and \
                     {:.10} ({}, family {}): one state, two labels",
                    a.branch,
                    a.lbar,
                    a.energy,
                    a.stability,
                    a.family,
                    b.energy,
                    b.stability,
                    b.family
                ));
            }
        }
    }
    // A stable state at every length, or a warning.
    let warned = warned_stretches(warnings);
    let n = ((hi - lo) / 0.005).ceil().max(1.0) as usize;
    let mut grid: Vec<f64> = (0..=n)
        .map(|k| lo + (hi - lo) * k as f64 / n as f64)
        .chain(rows.iter().map(|r| r.lbar))
        .collect();
    grid.sort_by(f64::total_cmp);
    let mut missing: Vec<(f64, f64)> = Vec::new();
    for l in grid {
        if (l - l.round()).abs() < 2e-3
            || warned
                .iter()
                .any(|&(a, b)| l >= a - 0.005 && l <= b + 0.005)
        {
            continue;
        }
        if sh
            .iter()
            .any(|s| sheet_state(s, l).is_some_and(|x| x.stable_side))
        {
            continue;
        }
        match missing.last_mut() {
            Some((_, b)) if l - *b <= 0.0051 => *b = l,
            _ => missing.push((l, l)),
        }
    }
    for (a, b) in missing {
        bad.push(format!(
            "{what}: no state labelled stable on {a:.4} ≤ L̄ ≤ {b:.4} and no warning says why"
        ));
    }
    bad
}

/// Energy of a sheet at `l` (quadratic through the three nearest rows) and whether the
/// rows around `l` have index 0; `None` outside the sheet.
fn sheet_at(s: &[Row], l: f64) -> Option<(f64, bool)> {
    let (a, b) = (s.first()?.lbar, s.last()?.lbar);
    if s.len() < 2 || l < a || l > b {
        return None;
    }
    let k = s.partition_point(|r| r.lbar < l).clamp(1, s.len() - 1);
    let min0 = stretch_index0(&s[k - 1], &s[k]);
    if s.len() == 2 {
        let t = (l - s[0].lbar) / (s[1].lbar - s[0].lbar).max(1e-300);
        return Some((s[0].energy + t * (s[1].energy - s[0].energy), min0));
    }
    let j = if k + 1 < s.len() { k - 1 } else { k - 2 };
    let (p, q, r) = (&s[j], &s[j + 1], &s[j + 2]);
    if q.lbar - p.lbar < 1e-12 || r.lbar - q.lbar < 1e-12 {
        let t = (l - s[k - 1].lbar) / (s[k].lbar - s[k - 1].lbar).max(1e-300);
        return Some((s[k - 1].energy + t * (s[k].energy - s[k - 1].energy), min0));
    }
    let lag = |x: f64, y: f64, z: f64| (l - y) * (l - z) / ((x - y) * (x - z));
    let e = p.energy * lag(p.lbar, q.lbar, r.lbar)
        + q.energy * lag(q.lbar, p.lbar, r.lbar)
        + r.energy * lag(r.lbar, p.lbar, q.lbar);
    Some((e, min0))
}

/// A state file's `(s, x, y, z, κ² D, D κ_g)`: arclength, position, bending energy density
/// and the bending moment about the surface normal.
fn state(path: &Path) -> Vec<[f64; 6]> {
    let mut r = csv::Reader::from_path(path).expect("state file");
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let c = ["s", "x", "y", "z", "kappa", "D"].map(col);
    let kg = col("kappa_g");
    r.records()
        .map(|x| {
            let x = x.unwrap();
            let v = |i: usize| x[i].parse::<f64>().unwrap();
            // s, x, y, z, κ² D, D κ_g
            [
                v(c[0]),
                v(c[1]),
                v(c[2]),
                v(c[3]),
                v(c[4]) * v(c[4]) * v(c[5]),
                v(c[5]) * v(kg),
            ]
        })
        .collect()
}

/// The dominant harmonic of a signal over the loop (uniform samples) about its mean.
///
/// The branch count `η` is a count of the bending moment `D κ_g` (see the README), not of
/// `κ_g`: on a soft segment `κ_g = M/D` carries the profile's own shape, and on
/// `D1/D0 ≈ 0.04–0.09` near the 2-fold great circle the dominant harmonic of `κ_g` of a
/// branch-3 loop is 4 where that of its moment is 3.
fn dominant_harmonic(signal: &[f64]) -> u32 {
    let n = signal.len();
    let mean = signal.iter().sum::<f64>() / n as f64;
    let dev: Vec<f64> = signal.iter().map(|v| v - mean).collect();
    (1..=12u32)
        .map(|k| {
            let (mut c, mut s) = (0.0, 0.0);
            for (j, v) in dev.iter().enumerate() {
                let t = 2.0 * std::f64::consts::PI * f64::from(k) * j as f64 / n as f64;
                c += v * t.cos();
                s += v * t.sin();
            }
            (k, c * c + s * s)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap()
        .0
}

/// How far the energy recomputed from a state file may lie from its row: five error
/// estimates, at least `10⁻⁵` relative (`10⁻⁴` for a row without an estimate: the file holds
/// the interpolated loop, whose energy differs from the discrete one by the discretisation
/// error); what `rodloop diagram` checks before it writes.
fn file_tolerance(r: &Row) -> f64 {
    let scale = r.energy.abs().max(1.0);
    if r.error > 0.0 {
        (5.0 * r.error).max(1e-5 * scale)
    } else {
        1e-4 * scale
    }
}

/// The checks of the module docs on the diagram in `dir` of the scene `scene_file`; returns
/// the failures.
fn check_diagram(dir: &Path, scene_file: &Path, lo: f64, hi: f64, what: &str) -> Vec<String> {
    let mut bad = Vec::new();
    let rows = rows(dir);
    assert!(!rows.is_empty(), "{what}: no rows");
    // The completeness certificate: nothing found below the traced states is left
    // unexplained.
    let summary = common::summary(dir);
    let unexplained = summary["certificate"]["unexplained"]
        .as_array()
        .map_or(0, Vec::len);
    if summary["certificate"].is_null() || unexplained > 0 {
        bad.push(format!(
            "{what}: the certificate leaves {unexplained} state(s) unexplained: {}",
            summary["certificate"]["unexplained"]
        ));
    }
    // State files: closed, on the sphere, the row's energy; their dominant harmonics.
    let mut harmonics = Vec::with_capacity(rows.len());
    for r in &rows {
        let st = state(&dir.join(&r.file));
        let m = st.len();
        let h = st[1][0] - st[0][0];
        let gap = ((st[m - 1][1] - st[0][1]).powi(2)
            + (st[m - 1][2] - st[0][2]).powi(2)
            + (st[m - 1][3] - st[0][3]).powi(2))
        .sqrt();
        if gap > 1.5 * h {
            bad.push(format!(
                "{what}: {} is open (gap {gap:.3e}, spacing {h:.3e})",
                r.file
            ));
        }
        if st
            .iter()
            .any(|p| ((p[1] * p[1] + p[2] * p[2] + p[3] * p[3]).sqrt() - 1.0).abs() > 1e-9)
        {
            bad.push(format!("{what}: {} leaves the sphere", r.file));
        }
        let e = 0.5 * st.iter().map(|p| p[4]).sum::<f64>() * h / std::f64::consts::PI;
        if (e - r.energy).abs() > file_tolerance(r) {
            bad.push(format!(
                "{what}: {} holds E = {e:.8}, its row {:.8} ± {:.1e}",
                r.file, r.energy, r.error
            ));
        }
        let moment: Vec<f64> = st.iter().map(|p| p[5]).collect();
        harmonics.push(dominant_harmonic(&moment));
    }
    // Branch identity: a state's dominant harmonic of its moment `D κ_g` is its row's `η`, or, where a
    // soft segment bends the loop so that another harmonic dominates, the state lies on a
    // family (one curve followed by continuation from its seed) that has states of `η`
    // periods: its branch is the seed's, by continuation.
    for (r, &h) in rows.iter().zip(&harmonics) {
        let family_has_eta = rows
            .iter()
            .zip(&harmonics)
            .any(|(o, &ho)| (o.branch, o.family) == (r.branch, r.family) && ho == r.eta);
        if h != r.eta && !family_has_eta {
            bad.push(format!(
                "{what}: {} (row of branch {}, η = {}) has {h} periods of D κ_g, and no state of \
                 its family has {}",
                r.file, r.branch, r.eta, r.eta
            ));
        }
    }
    // Labels against the traced energies.
    let warnings = warnings(&summary);
    bad.extend(label_failures(&rows, &warnings, lo, hi, what));
    let sh = sheets(&rows);
    // `solve --branch B` at two sample lengths finds nothing below the stable state.
    for l in [lo + 0.3 * (hi - lo), lo + 0.8 * (hi - lo)] {
        // The lowest local minimum traced there, and the uncertainty of its energy.
        let stable: Option<(f64, f64)> = sh
            .iter()
            .filter_map(|s| sheet_state(s, l).filter(|x| x.index0))
            .map(|x| (x.energy, x.uncertainty))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        for eta in 1..=4u32 {
            let e = f64::from(eta);
            if !(l > (e - 1.0).max(0.0) + 0.02 && l < e + 1.0 - 0.02) {
                continue;
            }
            let branch = [2, 1, 3, 4][eta as usize - 1];
            let out = tmp(&format!("{what}-solve-{branch}-{l:.3}"));
            let o = rodloop(&[
                "solve",
                "--scene",
                scene_file.to_str().unwrap(),
                "--lbar",
                &format!("{l}"),
                "--branch",
                &branch.to_string(),
                "--out",
                out.to_str().unwrap(),
            ]);
            if !o.status.success() {
                continue;
            }
            // A state whose loop does not close (a KKT point with a half-turn holonomy, which
            // `solve` can return: its defect, checked by its own tests) is no equilibrium.
            let st = state(&out.join("config.csv"));
            let m = st.len();
            let gap = ((st[m - 1][1] - st[0][1]).powi(2)
                + (st[m - 1][2] - st[0][2]).powi(2)
                + (st[m - 1][3] - st[0][3]).powi(2))
            .sqrt();
            if gap > 1.5 * (st[1][0] - st[0][0]) {
                eprintln!(
                    "{what}: solve --branch {branch} at L̄ = {l:.4} returned an open loop (gap \
                     {gap:.3} R): not compared"
                );
                continue;
            }
            let s = common::summary(&out);
            let (es, err) = (
                s["energy"].as_f64().unwrap(),
                s["error_estimate"].as_f64().unwrap_or(0.0),
            );
            // Within three times both error estimates (the solve's and the traced state's,
            // with the interpolation's uncertainty).
            match stable {
                Some((st, unc)) if es < st - 3.0 * (err + unc) - 1e-9 * es.abs().max(1.0) => bad.push(format!(
                    "{what}: solve --branch {branch} at L̄ = {l:.4} finds E = {es:.8} below the diagram's stable {st:.8}"
                )),
                None => bad.push(format!(
                    "{what}: solve --branch {branch} at L̄ = {l:.4} finds E = {es:.8}; the diagram has no stable state there"
                )),
                _ => {}
            }
        }
    }
    bad
}

fn run_diagram(scene: &Path, out: &Path, extra: &[&str]) {
    let mut args = vec![
        "diagram",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    rodloop_ok(&args);
}

#[test]
fn random_two_segment_scenes() {
    let n: usize = std::env::var("RODLOOP_RANDOM_SCENES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let span: f64 = std::env::var("RODLOOP_RANDOM_SPAN")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.3);
    let mut g = Lcg(20_241_117);
    let mut bad = Vec::new();
    for k in 0..n {
        let sc = Scene::random(&mut g, span, k, n);
        let dir = tmp(&format!("random-scene-{k}"));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("scene.toml");
        std::fs::write(&file, sc.toml()).unwrap();
        let out = dir.join("diagram");
        run_diagram(&file, &out, &[]);
        let what = format!(
            "scene {k} (d1 = {:.4}, s0 = {:.3}, s1 = {:.3}, gamma = {:.1}, {:.3} ≤ L̄ ≤ {:.3})",
            sc.d1, sc.s0, sc.s1, sc.gamma, sc.lo, sc.hi
        );
        eprintln!("{what}");
        bad.extend(check_diagram(&out, &file, sc.lo, sc.hi, &what));
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// Scene 0 of `scripts/random_scenes.sh 6 0.6` (`d1 = 0.0187`, the soft segment 0.15–0.95
/// of the loop, `γ = 205`, `1.94 ≤ L̄ ≤ 2.54`): branch 3 has two families that are one state
/// near `L̄ = 2.23` and two sheets of one family that meet near `L̄ = 2.26`, their energies
/// equal within the estimates; each such pair carries one label, and the labels agree with
/// the traced energies everywhere.
#[test]
fn copies_of_one_state_share_their_label() {
    let mut g = Lcg(20_241_117);
    let sc = Scene::random(&mut g, 0.6, 0, 6);
    let dir = tmp("copies-one-label");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scene.toml");
    std::fs::write(&file, sc.toml()).unwrap();
    let out = dir.join("diagram");
    run_diagram(&file, &out, &[]);
    let summary = common::summary(&out);
    let warnings = warnings(&summary);
    let bad = label_failures(&rows(&out), &warnings, sc.lo, sc.hi, "random scene 0 of 6");
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The user's profile: branch 1 has index-0 states on 1 < L̄ < 1.19 that `solve` finds
/// (1.0980125 at 1.05, 1.3009405 at 1.1, 1.4749460 at 1.15); the diagram's stable state must
/// not lie above them.
#[test]
fn user_profile_stable_states_near_one() {
    let dir = tmp("user-profile");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scene.toml");
    let sc = Scene {
        d1: 0.3,
        s0: 0.2,
        s1: 0.4,
        gamma: 100.0,
        lo: 1.0,
        hi: 1.2,
    };
    std::fs::write(&file, sc.toml()).unwrap();
    let out = dir.join("diagram");
    run_diagram(&file, &out, &[]);
    let bad = check_diagram(&out, &file, 1.0, 1.2, "user profile");
    assert!(bad.is_empty(), "{}", bad.join("\n"));
    let sh = sheets(&rows(&out));
    for (l, solved) in [(1.05, 1.0980125), (1.1, 1.3009405), (1.15, 1.4749460)] {
        let stable = sh
            .iter()
            .filter_map(|s| sheet_at(s, l).filter(|x| x.1).map(|x| x.0))
            .min_by(f64::total_cmp)
            .expect("a stable state");
        assert!(
            stable <= solved + 1e-4,
            "at {l}: stable {stable} above solve's {solved}"
        );
    }
}

/// The paper's `D1/D0 = 0.001` scene near `L̄ = 1`: branch 2 family 1 bends its very soft
/// segment into a kink of `κ_g ≈ 10³/R` between the samples of a 128-point file (its energy
/// 20 % off); every state file must give the energy of its row.
#[test]
fn state_files_hold_their_rows_at_strong_contrast() {
    let out = tmp("d1-0.001-near-one");
    run_diagram(
        Path::new("data/scenes/inhomogeneous-d1-0.001.toml"),
        &out,
        &["--lbar-min", "1.0", "--lbar-max", "1.03", "--branch", "2"],
    );
    let mut bad = Vec::new();
    for r in rows(&out) {
        let st = state(&out.join(&r.file));
        let h = st[1][0] - st[0][0];
        let e = 0.5 * st.iter().map(|p| p[4]).sum::<f64>() * h / std::f64::consts::PI;
        // Within 0.2 %: these states bend the soft segment sharper than the tracing mesh
        // resolves well (their files and rows differ by up to 1e-3 relative, beyond the
        // rows' Richardson estimates, which the diagram warns about).
        if (e - r.energy).abs() > 2e-3 * r.energy.abs() {
            bad.push(format!(
                "{} at {}: file {e}, row {}",
                r.file, r.lbar, r.energy
            ));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// A profile drawn at random (`d1 = 0.054, s0 = 0.001, s1 = 0.502, gamma = 297`) on the
/// default range `1 ≤ L̄ ≤ 3`: a contrast close to the strong one with a sharp transition
/// at the loop's origin.
#[test]
fn random_profile_sharp_transition_at_the_origin() {
    let dir = tmp("sharp-origin");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scene.toml");
    let sc = Scene {
        d1: 0.054,
        s0: 0.001,
        s1: 0.502,
        gamma: 297.0,
        lo: 1.0,
        hi: 3.0,
    };
    std::fs::write(&file, sc.toml()).unwrap();
    let out = dir.join("diagram");
    run_diagram(&file, &out, &[]);
    let bad = check_diagram(&out, &file, 1.0, 3.0, "sharp transition at the origin");
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// A nearly uniform rod (`D1/D0 = 0.95`): the placement of the soft segment is nearly
/// neutral, and the families are those that leave the uniform circle at the critical
/// placements.
#[test]
fn nearly_uniform_profile() {
    let dir = tmp("nearly-uniform");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scene.toml");
    let sc = Scene {
        d1: 0.95,
        s0: 0.15,
        s1: 0.52,
        gamma: 80.0,
        lo: 1.4,
        hi: 1.7,
    };
    std::fs::write(&file, sc.toml()).unwrap();
    let out = dir.join("diagram");
    run_diagram(&file, &out, &[]);
    let bad = check_diagram(&out, &file, sc.lo, sc.hi, "nearly uniform");
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}
