//! Scene files: what a `rodloop` run models.
//!
//! The crate is this one file: reading a scene (the TOML keys, their validation and the error
//! type) is one job, and the format described here is its reference.
//!
//! A scene is a small TOML file naming the sphere, the confinement, the bending-stiffness
//! profile and the accuracy. Every key is optional except where noted; unknown keys are an
//! error, reported with the line and column, so that a misspelt key never silently falls back
//! to a default. `data/scenes/` holds the paper's scenes.
//!
//! ```toml
//! # Homogeneous loops on the sphere (paper Secs. 3.1 and 4).
//! name = "homogeneous-surface"
//! radius = 1.0                  # sphere radius R
//! confinement = "surface"       # |r| = R ("enclosed": |r| <= R, solve and compare only)
//! lbar_min = 1.0                # range of L/(2 pi R) for diagrams
//! lbar_max = 5.0
//! accuracy = "default"          # fast | default | high
//!
//! [stiffness]
//! kind = "uniform"              # uniform | tanh | table
//! d = 1.0
//! ```
//!
//! An enclosed scene may name its wall in a `[wall]` table: `shape = "sphere"` (the default,
//! the sphere of `radius`) is the one shape. The wall's shape is the scene's
//! [`WallSpec`]; the binary maps it to the solver's wall in one place.
//!
//! The two-segment profile of Eq. (51) is `kind = "tanh"` with `d0, d1, s0, s1, gamma`
//! (`s0`, `s1` as fractions of L); a table is `kind = "table"` with arrays `s` (fractions of
//! L in `[0, 1)`, increasing) and `d`.

use std::path::Path;

use serde::Deserialize;

/// Errors reading or validating a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// TOML syntax error, unknown key or wrong type (the message names the line and key).
    #[error("scene file {path}: {message}")]
    Parse {
        /// The path (or `<string>`).
        path: String,
        /// The parser's message, with line and column.
        message: String,
    },
    /// A required key is absent.
    #[error("scene file {path}: missing key {key}: {reason}")]
    Missing {
        /// The path (or `<string>`).
        path: String,
        /// The missing key.
        key: String,
        /// Why it is needed.
        reason: String,
    },
    /// A value outside its domain (or a key the stiffness kind does not use, with an empty
    /// `value`).
    #[error("scene file {path}: {key}{}: {reason}", if value.is_empty() { String::new() } else { format!(" = {value}") })]
    Invalid {
        /// The path (or `<string>`).
        path: String,
        /// The offending key.
        key: String,
        /// Its value.
        value: String,
        /// What is wrong.
        reason: String,
    },
}

/// How the loop is confined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Confinement {
    /// On the sphere, `|r| = R`.
    #[default]
    Surface,
    /// Inside the sphere, `|r| ≤ R` (`solve`, `diagram`, `report` and `compare --scene enclosed`).
    Enclosed,
}

/// The wall of an enclosed scene (the `[wall]` table), in the scene's length units.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum WallSpec {
    /// The sphere of radius `radius` about the origin (paper Sec. 3.2).
    #[default]
    Sphere,
}

/// The `[wall]` table as written (flat, so that an unknown key keeps its line).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWall {
    shape: Option<String>,
}

impl RawWall {
    fn resolve(self, origin: &str) -> Result<WallSpec, SceneError> {
        match self.shape.as_deref().unwrap_or("sphere") {
            "sphere" => Ok(WallSpec::Sphere),
            other => Err(SceneError::Invalid {
                path: origin.to_string(),
                key: "wall.shape".into(),
                value: format!("{:?}", truncate(other, 80)),
                reason: "must be \"sphere\"".into(),
            }),
        }
    }
}

/// Accuracy level: a speed-for-accuracy dial.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Accuracy {
    /// Coarse resolution for quick looks.
    Fast,
    /// The default resolution.
    #[default]
    Default,
    /// Fine resolution with extrapolation.
    High,
}

impl std::str::FromStr for Accuracy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "fast" => Ok(Accuracy::Fast),
            "default" => Ok(Accuracy::Default),
            "high" => Ok(Accuracy::High),
            other => Err(format!("unknown accuracy {other:?} (fast, default, high)")),
        }
    }
}

/// The `[stiffness]` table as written: a flat struct, so that the TOML parser can point at the
/// line of an unknown key (an internally tagged enum would lose that position).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStiffness {
    kind: Option<String>,
    d: Option<NumberOrArray>,
    d0: Option<f64>,
    d1: Option<f64>,
    s0: Option<f64>,
    s1: Option<f64>,
    gamma: Option<f64>,
    s: Option<Vec<f64>>,
}

/// `d` is a number for a uniform profile and an array for a table.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
enum NumberOrArray {
    Number(f64),
    Array(Vec<f64>),
}

/// The scene file as written, before the stiffness table is resolved.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    #[serde(default = "default_name")]
    name: String,
    #[serde(default = "one")]
    radius: f64,
    #[serde(default)]
    confinement: Confinement,
    #[serde(default = "one")]
    lbar_min: f64,
    #[serde(default = "five")]
    lbar_max: f64,
    #[serde(default)]
    accuracy: Accuracy,
    stiffness: Option<RawStiffness>,
    wall: Option<RawWall>,
}

impl RawStiffness {
    fn resolve(self, origin: &str) -> Result<StiffnessSpec, SceneError> {
        let kind = self.kind.clone().unwrap_or_else(|| "uniform".into());
        let bad = |key: &str, reason: String| SceneError::Invalid {
            path: origin.to_string(),
            key: format!("stiffness.{key}"),
            value: String::new(),
            reason,
        };
        let missing = |key: &str, reason: String| SceneError::Missing {
            path: origin.to_string(),
            key: format!("stiffness.{key}"),
            reason,
        };
        let need = |key: &str, v: Option<f64>| {
            v.ok_or_else(|| missing(key, format!("required for kind = \"{kind}\"")))
        };
        let allowed: &[&str] = match kind.as_str() {
            "uniform" => &["d"],
            "tanh" => &["d0", "d1", "s0", "s1", "gamma"],
            "table" => &["s", "d"],
            other => {
                return Err(SceneError::Invalid {
                    path: origin.to_string(),
                    key: "stiffness.kind".into(),
                    value: format!("{other:?}"),
                    reason: "must be \"uniform\", \"tanh\" or \"table\"".into(),
                })
            }
        };
        let present = [
            ("d", self.d.is_some()),
            ("d0", self.d0.is_some()),
            ("d1", self.d1.is_some()),
            ("s0", self.s0.is_some()),
            ("s1", self.s1.is_some()),
            ("gamma", self.gamma.is_some()),
            ("s", self.s.is_some()),
        ];
        for (key, is_set) in present {
            if is_set && !allowed.contains(&key) {
                return Err(bad(key, format!("is not used by kind = \"{kind}\"")));
            }
        }
        let d_number = |d: Option<NumberOrArray>| match d {
            None => Ok(1.0),
            Some(NumberOrArray::Number(x)) => Ok(x),
            Some(NumberOrArray::Array(_)) => {
                Err(bad("d", "must be a number for kind = \"uniform\"".into()))
            }
        };
        Ok(match kind.as_str() {
            "uniform" => StiffnessSpec::Uniform {
                d: d_number(self.d)?,
            },
            "tanh" => StiffnessSpec::Tanh {
                d0: need("d0", self.d0)?,
                d1: need("d1", self.d1)?,
                s0: need("s0", self.s0)?,
                s1: need("s1", self.s1)?,
                gamma: need("gamma", self.gamma)?,
            },
            _ => StiffnessSpec::Table {
                s: self.s.ok_or_else(|| {
                    missing(
                        "s",
                        "required for kind = \"table\" (an array of positions s/L)".into(),
                    )
                })?,
                d: match self.d {
                    Some(NumberOrArray::Array(v)) => v,
                    Some(NumberOrArray::Number(_)) => {
                        return Err(bad(
                            "d",
                            "must be an array of stiffness values for kind = \"table\"".into(),
                        ))
                    }
                    None => {
                        return Err(missing(
                            "d",
                            "required for kind = \"table\" (an array of stiffness values)".into(),
                        ))
                    }
                },
            },
        })
    }
}

/// A bending-stiffness profile `D(s)`.
#[derive(Clone, Debug, PartialEq)]
pub enum StiffnessSpec {
    /// Uniform stiffness `D`.
    Uniform {
        /// The stiffness.
        d: f64,
    },
    /// Two-segment profile of Eq. (51):
    /// `D(s) = D0 − (D0 − D1)/2 [tanh(γ(s − s0* L)/L) − tanh(γ(s − s1* L)/L)]`.
    Tanh {
        /// Stiffness of the stiff segment `D0`.
        d0: f64,
        /// Stiffness of the soft segment `D1`.
        d1: f64,
        /// Start of the soft segment as a fraction of L (`s0*/L`).
        s0: f64,
        /// End of the soft segment as a fraction of L (`s1*/L`).
        s1: f64,
        /// Sharpness `γ`.
        gamma: f64,
    },
    /// Tabulated `D` at fractions of L, interpolated periodically.
    Table {
        /// Positions as fractions of L, increasing, in `[0, 1)`.
        s: Vec<f64>,
        /// Stiffness values (positive).
        d: Vec<f64>,
    },
}

fn one() -> f64 {
    1.0
}

/// At most `max` characters of `text`, with an ellipsis and the full length when cut (so that
/// an error never echoes a long array whole).
fn truncate(text: &str, max: usize) -> String {
    let count = text.chars().count();
    if count <= max {
        text.to_string()
    } else {
        let head: String = text.chars().take(max).collect();
        format!("{head}… ({count} characters)")
    }
}

impl Default for StiffnessSpec {
    fn default() -> Self {
        StiffnessSpec::Uniform { d: 1.0 }
    }
}

impl StiffnessSpec {
    /// Whether `D` is the same everywhere (then the arclength shift is a symmetry).
    pub fn is_uniform(&self) -> bool {
        matches!(self, StiffnessSpec::Uniform { .. })
    }

    /// Reference stiffness used to normalise energies and forces (`D` or `D0`; for a table the
    /// largest value).
    pub fn reference(&self) -> f64 {
        match self {
            StiffnessSpec::Uniform { d } => *d,
            StiffnessSpec::Tanh { d0, .. } => *d0,
            StiffnessSpec::Table { d, .. } => d.iter().cloned().fold(f64::NAN, f64::max),
        }
    }
}

/// Largest factor by which the sphere radius `R` and the product `R·D_ref` (`D_ref` the
/// reference stiffness: `d`, `d0`, or the table's largest value) may differ from 1, in the
/// scene's units (the other stiffness values are bounded relative to `D_ref` by
/// [`MIN_CONTRAST`] and [`MAX_CONTRAST`]).
///
/// The solver works in the scene's dimensional units. One pivot block of its KKT
/// factorisation (`rodloop_solver::kkt`) holds numbers of size 1 (frame recursions), `R`
/// (closure derivatives, `∝ h`) and `R·D` (bending, `∝ h D`), and a block whose pivot ratio
/// falls below `1e-13` counts as singular; the stability analysis searches its shifts on
/// an absolute scale. Measured with `rodloop solve` (branches 1 and 2 of a two-segment rod,
/// `D1/D0 = 0.5`, at `R·D0 = 1`): `R` from `1e-4` to `1e3` gives the same normalised energy
/// to 1e-10, `R = 3e3` fails in the stability analysis; `R·D0` from `1e-4` to `1e4` at
/// `R = 1` gives the same energies. `[1e-3, 1e3]` for both keeps one order of margin. A
/// scene in other units can be rescaled (only `L̄`, `D/D0` and `E R/D0` matter).
pub const MAX_SCALE: f64 = 1e3;

/// Smallest ratio `D/D_ref` of a stiffness value to the reference stiffness (`d0`, or the
/// table's largest value).
///
/// Newton stops at a KKT residual of `1e-10` in units of `D_ref/R`. On a segment of
/// stiffness `D` the stationarity residual changes by `D δκ_g`, so that tolerance fixes the
/// segment's curvature only to `δκ_g R ≲ 1e-10 D_ref/D`; `D/D_ref ≥ 1e-6` keeps that below
/// `1e-4`, the accuracy at which the contact force is reported.
pub const MIN_CONTRAST: f64 = 1e-6;

/// Largest ratio `D/D_ref` (a segment stiffer than the reference `d0`).
///
/// The KKT residual is measured in units of `D_ref/R`; its round-off floor grows like
/// `ε D/D_ref` times the curvature (`ε ≈ 2.2e-16`) summed over the cells, so above `1e4`
/// the floor (`≳ 1e-11` for the hundreds of cells of a solve) meets the tolerance `1e-10`
/// and Newton cannot certify convergence.
pub const MAX_CONTRAST: f64 = 1e4;

/// The error for a value outside its domain (the value cut to 80 characters).
fn invalid(origin: &str, key: &str, value: String, reason: &str) -> SceneError {
    SceneError::Invalid {
        path: origin.to_string(),
        key: key.to_string(),
        value: truncate(&value, 80),
        reason: reason.to_string(),
    }
}

/// `v` is a positive finite number.
fn positive(origin: &str, key: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            origin,
            key,
            v.to_string(),
            "must be a positive finite number",
        ))
    }
}

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// A short name used in output summaries.
    pub name: String,
    /// Sphere radius `R`.
    pub radius: f64,
    /// Confinement.
    pub confinement: Confinement,
    /// Smallest `L̄` of a diagram.
    pub lbar_min: f64,
    /// Largest `L̄` of a diagram.
    pub lbar_max: f64,
    /// Accuracy level.
    pub accuracy: Accuracy,
    /// Stiffness profile.
    pub stiffness: StiffnessSpec,
    /// The wall of an enclosed scene (`[wall]`; the sphere of [`Scene::radius`] by default).
    pub wall: WallSpec,
}

fn default_name() -> String {
    "scene".into()
}

fn five() -> f64 {
    5.0
}

impl Default for Scene {
    /// The built-in default scene: homogeneous loops on the unit sphere, `1 ≤ L̄ ≤ 5`.
    fn default() -> Self {
        Scene {
            name: "homogeneous-surface".into(),
            radius: 1.0,
            confinement: Confinement::Surface,
            lbar_min: 1.0,
            lbar_max: 5.0,
            accuracy: Accuracy::Default,
            stiffness: StiffnessSpec::Uniform { d: 1.0 },
            wall: WallSpec::Sphere,
        }
    }
}

/// A TOML error on one line: ``line L, column C (`source line`): message`` (the parser's own
/// rendering spans several lines, with the source line and a caret under it).
fn one_line_toml_error(text: &str, e: &toml::de::Error) -> String {
    let message = truncate(e.message().trim().replace('\n', " ").as_str(), 300);
    match e.span() {
        Some(span) => {
            let before = text.get(..span.start).unwrap_or(text);
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            let source = text.lines().nth(line - 1).unwrap_or("").trim();
            format!(
                "line {line}, column {column} (`{}`): {message}",
                truncate(source, 80)
            )
        }
        None => message,
    }
}

impl Scene {
    /// Parse and validate a scene from TOML text; `origin` names it in messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, SceneError> {
        let raw: RawScene = toml::from_str(text).map_err(|e| SceneError::Parse {
            path: origin.to_string(),
            message: one_line_toml_error(text, &e),
        })?;
        let stiffness = raw.stiffness.unwrap_or_default().resolve(origin)?;
        if raw.wall.is_some() && raw.confinement != Confinement::Enclosed {
            return Err(SceneError::Invalid {
                path: origin.to_string(),
                key: "wall".into(),
                value: String::new(),
                reason:
                    "names the wall of confinement = \"enclosed\"; this scene is on the surface"
                        .into(),
            });
        }
        let wall = raw.wall.unwrap_or_default().resolve(origin)?;
        let scene = Scene {
            name: raw.name,
            radius: raw.radius,
            confinement: raw.confinement,
            lbar_min: raw.lbar_min,
            lbar_max: raw.lbar_max,
            accuracy: raw.accuracy,
            stiffness,
            wall,
        };
        scene.validate(origin)?;
        Ok(scene)
    }

    /// Read, parse and validate a scene file.
    pub fn from_file(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Check every value's domain, including the magnitudes double precision can resolve
    /// ([`MAX_SCALE`], [`MIN_CONTRAST`], [`MAX_CONTRAST`]).
    pub fn validate(&self, origin: &str) -> Result<(), SceneError> {
        let bad = |key: &str, value: String, reason: &str| invalid(origin, key, value, reason);
        let positive = |key: &str, v: f64| positive(origin, key, v);
        positive("radius", self.radius)?;
        positive("lbar_min", self.lbar_min)?;
        positive("lbar_max", self.lbar_max)?;
        if self.lbar_max <= self.lbar_min {
            return Err(bad(
                "lbar_max",
                self.lbar_max.to_string(),
                &format!("must exceed lbar_min = {}", self.lbar_min),
            ));
        }
        if self.lbar_max > 50.0 {
            return Err(bad(
                "lbar_max",
                self.lbar_max.to_string(),
                "must be at most 50",
            ));
        }
        self.validate_domains(origin)?;
        self.validate_magnitudes(origin)
    }

    /// Magnitudes (see [`MAX_SCALE`], [`MIN_CONTRAST`], [`MAX_CONTRAST`]), once every value
    /// is known to be positive and finite.
    fn validate_magnitudes(&self, origin: &str) -> Result<(), SceneError> {
        let bad = |key: &str, value: f64, reason: String| SceneError::Invalid {
            path: origin.to_string(),
            key: key.to_string(),
            value: if (1e-3..1e6).contains(&value) {
                value.to_string()
            } else {
                format!("{value:e}")
            },
            reason,
        };
        let r = self.radius;
        if !(1.0 / MAX_SCALE..=MAX_SCALE).contains(&r) {
            return Err(bad(
                "radius",
                r,
                format!("must lie in [{:e}, {MAX_SCALE:e}] (the solver works in the scene's units; see rodloop_scene::MAX_SCALE)", 1.0 / MAX_SCALE),
            ));
        }
        let values: Vec<(String, f64)> = match &self.stiffness {
            StiffnessSpec::Uniform { d } => vec![("stiffness.d".into(), *d)],
            StiffnessSpec::Tanh { d0, d1, .. } => {
                vec![("stiffness.d0".into(), *d0), ("stiffness.d1".into(), *d1)]
            }
            StiffnessSpec::Table { d, .. } => d
                .iter()
                .enumerate()
                .map(|(i, v)| (format!("stiffness.d[{i}]"), *v))
                .collect(),
        };
        let reference = self.stiffness.reference();
        if let Some((key, d)) = values.iter().find(|(_, d)| *d == reference) {
            let rd = r * d;
            if !(1.0 / MAX_SCALE..=MAX_SCALE).contains(&rd) {
                return Err(bad(
                    key,
                    *d,
                    format!(
                        "times radius = {r} gives {rd:e}, which must lie in [{:e}, {MAX_SCALE:e}] (see rodloop_scene::MAX_SCALE)",
                        1.0 / MAX_SCALE
                    ),
                ));
            }
        }
        for (key, d) in values.iter().filter(|(_, d)| *d != reference) {
            let ratio = d / reference;
            if !(MIN_CONTRAST..=MAX_CONTRAST).contains(&ratio) {
                return Err(bad(
                    key,
                    *d,
                    format!(
                        "is {ratio:e} times the reference stiffness {reference}; the ratio must lie in [{MIN_CONTRAST:e}, {MAX_CONTRAST:e}] (see rodloop_scene::MIN_CONTRAST)"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Domains of the single values (positive, fractions, ordering).
    fn validate_domains(&self, origin: &str) -> Result<(), SceneError> {
        let bad = |key: &str, value: String, reason: &str| invalid(origin, key, value, reason);
        let positive = |key: &str, v: f64| positive(origin, key, v);
        match &self.stiffness {
            StiffnessSpec::Uniform { d } => positive("stiffness.d", *d)?,
            StiffnessSpec::Tanh {
                d0,
                d1,
                s0,
                s1,
                gamma,
            } => {
                positive("stiffness.d0", *d0)?;
                positive("stiffness.d1", *d1)?;
                positive("stiffness.gamma", *gamma)?;
                for (k, v) in [("stiffness.s0", *s0), ("stiffness.s1", *s1)] {
                    if !(0.0..=1.0).contains(&v) {
                        return Err(bad(k, v.to_string(), "must be a fraction of L in [0, 1]"));
                    }
                }
                if s1 <= s0 {
                    return Err(bad(
                        "stiffness.s1",
                        s1.to_string(),
                        &format!("must exceed stiffness.s0 = {s0}"),
                    ));
                }
            }
            StiffnessSpec::Table { s, d } => {
                if s.len() != d.len() || s.is_empty() || s.len() == 2 {
                    return Err(bad(
                        "stiffness.s",
                        format!("{} values", s.len()),
                        &format!(
                            "needs 1 value (constant) or at least 3 (periodic interpolant), as many as stiffness.d ({})",
                            d.len()
                        ),
                    ));
                }
                for (i, &x) in s.iter().enumerate() {
                    let key = format!("stiffness.s[{i}]");
                    if !x.is_finite() {
                        return Err(bad(&key, x.to_string(), "must be a finite number"));
                    }
                    if !(0.0..1.0).contains(&x) {
                        return Err(bad(
                            &key,
                            x.to_string(),
                            "must lie in [0, 1) (a fraction of L)",
                        ));
                    }
                    if i > 0 && x <= s[i - 1] {
                        return Err(bad(
                            &key,
                            x.to_string(),
                            &format!(
                                "must exceed stiffness.s[{}] = {} (s must increase strictly)",
                                i - 1,
                                s[i - 1]
                            ),
                        ));
                    }
                }
                for (i, &v) in d.iter().enumerate() {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(bad(
                            &format!("stiffness.d[{i}]"),
                            v.to_string(),
                            "must be a positive finite number",
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}
