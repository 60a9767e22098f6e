//! Error type of the elliptic-integral functions.

use thiserror::Error;

/// Error returned by the elliptic-integral functions of this crate.
///
/// The Jacobi elliptic functions ([`crate::jacobi`]) are total and never
/// return an error; the integrals reject arguments outside their real domain.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SpecialError {
    /// The modulus `k` is outside `[-1, 1]` (the integrals are only real
    /// there; only `k²` matters, so `k` and `-k` are equivalent).
    #[error("elliptic modulus k = {k} is outside [-1, 1]")]
    ModulusOutOfRange {
        /// The offending modulus.
        k: f64,
    },
    /// The parameter `m = k²` is greater than 1.
    #[error("elliptic parameter m = {m} is greater than 1")]
    ParameterOutOfRange {
        /// The offending parameter.
        m: f64,
    },
    /// The characteristic `n` of an integral of the third kind is not `< 1`
    /// (`n = 1` is a pole, `n > 1` would be a Cauchy principal value, which is
    /// not supported).
    #[error("characteristic n = {n} of the third-kind integral is not < 1")]
    CharacteristicOutOfRange {
        /// The offending characteristic.
        n: f64,
    },
    /// An argument is NaN or infinite.
    #[error("argument {name} = {value} is not finite")]
    NotFinite {
        /// Name of the argument (`"k"`, `"m"`, `"n"`, `"phi"`).
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// The underlying `ellip` crate reported an error (should not happen for
    /// arguments that passed the checks above).
    #[error("ellip: {0}")]
    Ellip(String),
}

/// Convert an `ellip` error string into a [`SpecialError`].
pub(crate) fn from_ellip(e: &'static str) -> SpecialError {
    SpecialError::Ellip(e.to_string())
}
