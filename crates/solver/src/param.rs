//! Scene parameters that continuation can move, chosen by name.

use rodloop_continuation::axis::Axis;

use crate::SolverError;

/// A continuation parameter (in the spirit of BifurcationKit's lenses): `lbar` =
/// `L̄ = L/(2πR)`; for the two-segment profile of Eq. (51), `d1` = `D1/D0`, `gamma` = `γ`,
/// `s0` = `s0*/L`, `s1` = `s1*/L`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Param {
    /// Normalised length.
    Lbar,
    /// Stiffness ratio `D1/D0`.
    D1,
    /// Sharpness of the stiffness transitions.
    Gamma,
    /// Start of the soft segment (fraction of the length).
    S0,
    /// End of the soft segment (fraction of the length).
    S1,
}

impl Param {
    /// The name used on the command line and in output files.
    pub fn name(self) -> &'static str {
        match self {
            Param::Lbar => "lbar",
            Param::D1 => "d1",
            Param::Gamma => "gamma",
            Param::S0 => "s0",
            Param::S1 => "s1",
        }
    }

    /// The axis the parameter is continued on: `d1` and `gamma` are positive scale
    /// parameters spanning decades and are continued in their logarithm (equal steps are
    /// equal factors); the others on a linear axis.
    pub fn axis(self) -> Axis {
        match self {
            Param::D1 | Param::Gamma => Axis::Log,
            Param::Lbar | Param::S0 | Param::S1 => Axis::Linear,
        }
    }

    /// Every parameter.
    pub const ALL: [Param; 5] = [Param::Lbar, Param::D1, Param::Gamma, Param::S0, Param::S1];
}

impl std::fmt::Display for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Param {
    type Err = SolverError;
    fn from_str(s: &str) -> Result<Self, SolverError> {
        Param::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| {
                SolverError::InvalidInput(format!(
                    "unknown parameter '{s}' (expected one of lbar, d1, gamma, s0, s1)"
                ))
            })
    }
}
