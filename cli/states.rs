//! Every traced state of a numeric diagram as a loop table, `OUT/states/*.csv`, in the
//! columns of `solve`'s `config.csv`: any point of a diagram can be re-solved
//! (`solve --from OUT/states/FILE`) or drawn (`draw OUT/states/FILE`). The row of
//! `branches.csv` names its file in the column `state_file`.

use anyhow::Result;
use rodloop_diagram::{DiagramOptions, NumericDiagram, TracedBranch};

use crate::output::OutputRun;

/// Points per state file (uniform in arclength); more when the tracing resolution has more
/// cells, and doubled until the file holds the state ([`uniform_profile_holding`]).
pub const STATE_POINTS: usize = 128;

/// Most points per state file: a state whose energy the file does not reproduce at this
/// many uniform samples is written with a warning.
pub const MAX_STATE_POINTS: usize = 16_384;

/// Relative agreement of the energy recomputed from a state file with the state's own
/// energy, at least: the file holds the trigonometric interpolant of the state's mesh
/// values, whose energy differs from the discrete one by the discretisation error (up to
/// 4e-6 relative on the paper's `D1/D0 = 0.5` diagram, `rodloop diagram --scene
/// data/scenes/inhomogeneous-d1-0.5.toml`); the tolerance is [`ESTIMATES`] times the row's
/// error estimate where that is larger.
pub const FILE_ENERGY_TOLERANCE: f64 = 1e-5;

/// [`FILE_ENERGY_TOLERANCE`] for a row without an error estimate (its half-resolution
/// partner failed): the discretisation error is not known there, and reaches 3e-5 relative
/// on random two-segment scenes (`cargo test --release --test random_scenes`).
pub const NO_ESTIMATE_TOLERANCE: f64 = 1e-4;

/// Multiple of a row's error estimate within which its file's energy must lie.
pub const ESTIMATES: f64 = 5.0;

/// `E R/(π D0)` recomputed from samples uniform in arclength over the whole loop (what a
/// state file holds): `½ Σ D κ² h` with `h = L/m`, the trapezoidal rule of Eq. (2) for a
/// periodic integrand (spectrally accurate once the samples resolve the loop).
pub fn energy_of_samples(
    profile: &[rodloop_solver::ProfilePoint],
    length: f64,
    r: f64,
    d0: f64,
) -> f64 {
    let h = length / profile.len().max(1) as f64;
    let e: f64 = profile
        .iter()
        .map(|p| 0.5 * p.d * p.kappa * p.kappa * h)
        .sum();
    e * r / (std::f64::consts::PI * d0)
}

/// The profile of `eq` at `m ≥ min_points` points uniform in arclength, `m` doubled (up to
/// [`MAX_STATE_POINTS`]) until the energy recomputed from the samples
/// ([`energy_of_samples`]) agrees with the state's own within `tol` (relative, at least
/// [`FILE_ENERGY_TOLERANCE`]): uniform samples of a graded mesh miss narrow features (a
/// very soft segment bent sharply near `L̄ = 1`, a steep stiffness step). Returns the
/// profile, the recomputed and the state's energy.
pub fn uniform_profile_holding(
    eq: &rodloop_solver::Equilibrium,
    min_points: usize,
    tol: f64,
    r: f64,
    d0: f64,
) -> Result<(Vec<rodloop_solver::ProfilePoint>, f64, f64)> {
    let own = eq.energy().total;
    let tol = tol.max(FILE_ENERGY_TOLERANCE) * own.abs().max(1.0);
    let model = eq.model();
    let length = model.length();
    // The points are chosen on `κ_g` alone (one interpolant, as `profile_uniform` builds it
    // for each of its columns), then the whole profile is sampled once and checked.
    let kg = rodloop_solver::periodic::TrigInterpolant::new(
        &eq.profile().iter().map(|p| p.kappa_g).collect::<Vec<_>>(),
    )?;
    let map = model.mesh();
    let energy_at = |m: usize| -> f64 {
        let h = length / m as f64;
        let e: f64 = (0..m)
            .map(|j| {
                let sigma = j as f64 / m as f64;
                let k = kg.eval(map.u_of_sigma(sigma));
                let d = model.stiffness().eval(sigma).per_arclength(length).0;
                0.5 * d * (k * k + 1.0 / (r * r)) * h
            })
            .sum();
        e * r / (std::f64::consts::PI * d0)
    };
    // Doubled until the samples give the state's energy, or give the same energy at twice
    // as many points (the file then holds the loop; what is left is the state's own
    // discretisation error, which the caller compares with its estimate).
    let mut m = min_points.max(8);
    let mut e_m = energy_at(m);
    while m < MAX_STATE_POINTS && (e_m - own).abs() > tol {
        let e_2m = energy_at(2 * m);
        m *= 2;
        let settled = (e_2m - e_m).abs() <= 1e-3 * tol;
        e_m = e_2m;
        if settled {
            break;
        }
    }
    let profile = eq.profile_uniform(m)?;
    let e = energy_of_samples(&profile, length, r, d0);
    Ok((profile, e, own))
}

/// The file of traced state `k` of `b`, relative to the diagram directory:
/// `states/branch-B-KKK.csv`, or `states/branch-B-family-F-sheet-S-KKK.csv` for a family of
/// a non-uniform rod (`k` counts the sheet's states in increasing `L̄`).
pub fn file_name(b: &TracedBranch, k: usize) -> String {
    if b.family == 0 {
        format!("states/branch-{}-{k:03}.csv", b.branch)
    } else {
        format!(
            "states/branch-{}-family-{}-sheet-{}-{k:03}.csv",
            b.branch, b.family, b.sheet
        )
    }
}

/// Write the state files into the run's `states/` directory (the traced states in parallel).
/// Returns the file of every row of [`NumericDiagram::rows`], in that order (empty where a
/// state could not be re-evaluated), and the warnings for those.
pub fn write_states(
    d: &NumericDiagram,
    opts: &DiagramOptions,
    run: &OutputRun,
) -> Result<(Vec<String>, Vec<String>)> {
    let dir = run.subdir("states")?;
    let jobs: Vec<(&TracedBranch, usize)> = d
        .branches
        .iter()
        .flat_map(|b| (0..b.points.len()).map(move |k| (b, k)))
        .collect();
    let (r, d0) = (opts.radius, opts.stiffness.reference());
    // Each file is checked: the energy recomputed from its samples must be the state's own
    // (within [`ESTIMATES`] times the row's error estimate, or [`FILE_ENERGY_TOLERANCE`]), and the state's own the row's.
    let one = |b: &TracedBranch, k: usize| -> Result<(String, Option<String>)> {
        let eq = b.equilibrium_of(opts, k)?;
        let p = &b.points[k];
        let est = ESTIMATES * p.energy_error.unwrap_or(0.0) / p.energy.abs().max(1.0);
        let m = STATE_POINTS.max(eq.model().cells());
        let want = if p.energy_error.is_some() {
            est
        } else {
            NO_ESTIMATE_TOLERANCE
        };
        let (profile, e_file, e_own) = uniform_profile_holding(&eq, m, want, r, d0)?;
        let table = crate::solve::config_table_in(&profile, r, d0)?;
        let name = file_name(b, k);
        let file = name.trim_start_matches("states/");
        crate::output::write_atomic(&dir, file, &table.to_bytes()?)?;
        let scale = p.energy.abs().max(1.0);
        let file_tol = if p.energy_error.is_some() {
            est.max(FILE_ENERGY_TOLERANCE)
        } else {
            NO_ESTIMATE_TOLERANCE
        } * scale;
        let row_tol = (p.energy - p.energy_trace).abs() + 1e-9 * scale;
        let problem = if (e_file - e_own).abs() > file_tol {
            Some(format!(
                "its file ({} points) gives E R/(π D0) = {e_file:.10} against the state's \
                 {e_own:.10}",
                profile.len()
            ))
        } else if (e_own - p.energy_trace).abs() > row_tol {
            Some(format!(
                "its re-solved state has E R/(π D0) = {e_own:.10} against {:.10} in its row",
                p.energy_trace
            ))
        } else {
            None
        };
        Ok((name, problem))
    };
    let results = parallel_map(&jobs, |&(b, k)| one(b, k).map_err(|e| format!("{e:#}")));
    let mut names = Vec::with_capacity(jobs.len());
    let mut warnings = Vec::new();
    for ((b, k), res) in jobs.iter().zip(results) {
        match res {
            Ok((n, problem)) => {
                if let Some(why) = problem {
                    warnings.push(format!(
                        "STATE FILE DOES NOT HOLD ITS ROW: {n} (branch {}, family {}, L̄ = {}): {why}",
                        b.branch, b.family, b.points[*k].value
                    ));
                }
                names.push(n);
            }
            Err(e) => {
                names.push(String::new());
                warnings.push(format!(
                    "state {k} of branch {} (L̄ = {}) has no state file: {e}",
                    b.branch, b.points[*k].value
                ));
            }
        }
    }
    Ok((names, warnings))
}

/// `f` over `items` on the available cores, results in the order of `items`.
pub fn parallel_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(items.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<R>>> =
        items.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(item) = items.get(k) else {
                    break;
                };
                let r = f(item);
                if let Ok(mut slot) = slots[k].lock() {
                    *slot = Some(r);
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|m| {
            m.into_inner()
                .ok()
                .flatten()
                .expect("every item was mapped by a worker")
        })
        .collect()
}

/// Every file under `dir` (recursively), as sorted paths relative to it with `/` separators:
/// what a command wrote into its output directory, for its `summary.json`.
pub fn files_in(dir: &std::path::Path) -> Result<Vec<String>> {
    fn walk(base: &std::path::Path, d: &std::path::Path, out: &mut Vec<String>) -> Result<()> {
        for e in std::fs::read_dir(d)? {
            let p = e?.path();
            if p.is_dir() {
                walk(base, &p, out)?;
            } else if let Ok(rel) = p.strip_prefix(base) {
                let parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                out.push(parts.join("/"));
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out)?;
    out.sort();
    Ok(out)
}

/// The file of point `k` of an enclosed diagram (`k` counts the points of its branch, family
/// and sheet in increasing `L̄`): `states/enclosed-branch-B-KKK.csv`, or
/// `states/enclosed-branch-B-family-F-sheet-S-KKK.csv` for a family of a non-uniform rod.
pub fn enclosed_file_name(p: &rodloop_diagram::enclosed::EnclosedPoint, k: usize) -> String {
    if p.family == 0 {
        format!("states/enclosed-branch-{}-{k:03}.csv", p.branch)
    } else {
        format!(
            "states/enclosed-branch-{}-family-{}-sheet-{}-{k:03}.csv",
            p.branch, p.family, p.sheet
        )
    }
}

/// The enclosed `config.csv` table (columns of `solve` on an enclosed scene, units of `R`
/// and `D0`) of a loop on the sphere of radius `r` given as `(s, x, y, z, κ_g, λ, D)` rows
/// in the model's units: the surface loop is the enclosed state where it is attached, with
/// curvature vector `(κ1, κ2) = (κ_g, −1/R)` in the Darboux frame (rotation-minimising on
/// the sphere, as in the 3-D model's start from a surface loop).
fn sphere_table(rows: &[[f64; 7]], r: f64, d0: f64) -> Result<crate::output::Table> {
    use crate::output::{Cell, Table};
    let mut table = Table::new(
        "config.csv",
        &[
            "s", "x", "y", "z", "gap", "kappa", "kappa_1", "kappa_2", "lambda", "D",
        ],
    );
    for &[s, x, y, z, kg, lam, d] in rows {
        let rad = (x * x + y * y + z * z).sqrt();
        table.push(vec![
            Cell::F(s / r),
            Cell::F(x / r),
            Cell::F(y / r),
            Cell::F(z / r),
            Cell::F((r - rad) / r),
            Cell::F((kg * kg + 1.0 / (r * r)).sqrt() * r),
            Cell::F(kg * r),
            Cell::F(-1.0),
            Cell::F(lam * r * r * r / d0),
            Cell::F(d / d0),
        ])?;
    }
    Ok(table)
}

/// The table of one enclosed diagram point's loop (see [`sphere_table`] for attached ones).
fn enclosed_table(
    p: &rodloop_diagram::enclosed::EnclosedPoint,
    r: f64,
    d0: f64,
) -> Result<crate::output::Table> {
    use rodloop_diagram::enclosed::PointShape;
    use std::f64::consts::PI;
    match &p.shape {
        PointShape::Model(st) => crate::enclosed::config_table_in(st, r, d0),
        PointShape::Surface(eq) => {
            let m = STATE_POINTS.max(eq.model().cells());
            let rows: Vec<[f64; 7]> = eq
                .profile_uniform(m)?
                .iter()
                .map(|q| [q.s, q.x, q.y, q.z, q.kappa_g, q.lambda, q.d])
                .collect();
            sphere_table(&rows, r, d0)
        }
        PointShape::Exact(l) => {
            // The exact loop lives on the unit sphere, in units of `R` and `D`.
            let len = l.length();
            let rows = (0..STATE_POINTS)
                .map(|i| {
                    let q = l.point(len * i as f64 / STATE_POINTS as f64)?;
                    Ok([
                        q.s * r,
                        q.x * r,
                        q.y * r,
                        q.z * r,
                        q.kappa_g / r,
                        q.lambda * d0 / (r * r * r),
                        d0,
                    ])
                })
                .collect::<Result<Vec<_>>>()?;
            sphere_table(&rows, r, d0)
        }
        PointShape::Circle => {
            // Radius `ρ = R L̄` about the centre, in the plane y = 0; curvature vector
            // (0, −1/ρ) in the frame whose tangent starts along x (the model's start).
            use crate::output::{Cell, Table};
            let rho = p.lbar;
            let mut table = Table::new(
                "config.csv",
                &[
                    "s", "x", "y", "z", "gap", "kappa", "kappa_1", "kappa_2", "lambda", "D",
                ],
            );
            for i in 0..STATE_POINTS {
                let a = 2.0 * PI * i as f64 / STATE_POINTS as f64;
                table.push(vec![
                    Cell::F(rho * a),
                    Cell::F(rho * a.sin()),
                    Cell::F(0.0),
                    Cell::F(rho * a.cos()),
                    Cell::F(1.0 - rho),
                    Cell::F(1.0 / rho),
                    Cell::F(0.0),
                    Cell::F(-1.0 / rho),
                    Cell::F(0.0),
                    Cell::F(1.0),
                ])?;
            }
            Ok(table)
        }
        PointShape::Missing => anyhow::bail!("its surface state could not be re-evaluated"),
    }
}

/// Write every point of an enclosed diagram into the run's `states/` directory (in
/// parallel): the lifted-off 3-D states as they are, attached ones as their surface loop.
/// Returns the file of every point of `d.points`, in that order (empty where none was
/// written), and the warnings for those.
pub fn write_enclosed_states(
    d: &rodloop_diagram::enclosed::EnclosedDiagram,
    radius: f64,
    d0: f64,
    run: &OutputRun,
) -> Result<(Vec<String>, Vec<String>)> {
    let dir = run.subdir("states")?;
    // Number the points of each (branch, family, sheet) in increasing L̄.
    let mut order: Vec<usize> = (0..d.points.len()).collect();
    let key = |i: usize| {
        let p = &d.points[i];
        (p.branch, p.family, p.sheet)
    };
    order.sort_by(|&a, &b| {
        key(a)
            .cmp(&key(b))
            .then(d.points[a].lbar.total_cmp(&d.points[b].lbar))
    });
    let mut names = vec![String::new(); d.points.len()];
    let mut count = 0;
    for (pos, &i) in order.iter().enumerate() {
        if pos > 0 && key(order[pos - 1]) != key(i) {
            count = 0;
        }
        names[i] = enclosed_file_name(&d.points[i], count);
        count += 1;
    }
    let jobs: Vec<usize> = (0..d.points.len()).collect();
    let results = parallel_map(&jobs, |&i| {
        let table = enclosed_table(&d.points[i], radius, d0).map_err(|e| format!("{e:#}"))?;
        let bytes = table.to_bytes().map_err(|e| format!("{e:#}"))?;
        let file = names[i].trim_start_matches("states/");
        crate::output::write_atomic(&dir, file, &bytes).map_err(|e| format!("{e:#}"))?;
        Ok::<(), String>(())
    });
    let mut warnings = Vec::new();
    for (i, res) in results.into_iter().enumerate() {
        if let Err(e) = res {
            let p = &d.points[i];
            warnings.push(format!(
                "the state of branch {} family {} at L̄ = {} has no state file: {e}",
                p.branch, p.family, p.lbar
            ));
            names[i].clear();
        }
    }
    Ok((names, warnings))
}
