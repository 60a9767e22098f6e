//! An equilibrium's profile at points uniform in arclength, whatever its mesh: what a saved
//! configuration holds (a `config.csv` start is read as samples uniform in `s`, see
//! [`crate::StartShape::from_kappa_g_samples`]), and what a picture wants (more points than a
//! coarse tracing resolution has).

use crate::periodic::TrigColumns;
use crate::solve::{Equilibrium, ProfilePoint};
use crate::SolverError;

impl Equilibrium {
    /// The profile of [`Equilibrium::profile`] at the `m` arclengths `s_j = jL/m`,
    /// `j = 0..m`.
    ///
    /// Every quantity of the profile is a smooth periodic function of the mesh coordinate `u`
    /// (see [`crate::mesh`]); each is interpolated trigonometrically in `u` from its values at
    /// the `N` cell boundaries and evaluated at `u(s_j/L)`. So for a uniform mesh and
    /// `m = N` the samples are the profile's own (up to the dropped Nyquist mode of an even
    /// `N`). The exact relations are restored after interpolation: the point is put back on
    /// the sphere (`|r| = R`), `κ = sqrt(κ_g² + 1/R²)`, and `D` is the stiffness profile at
    /// `s_j` (not interpolated).
    ///
    /// Errors: [`SolverError::InvalidInput`] for `m < 8`.
    pub fn profile_uniform(&self, m: usize) -> Result<Vec<ProfilePoint>, SolverError> {
        if m < 8 {
            return Err(SolverError::InvalidInput(format!(
                "a uniform profile needs at least 8 points (got {m})"
            )));
        }
        let native = self.profile();
        let model = self.model();
        let (r, len) = (model.radius(), model.length());
        let map = model.mesh();
        let fields: [fn(&ProfilePoint) -> f64; 11] = [
            |p| p.x,
            |p| p.y,
            |p| p.z,
            |p| p.tau,
            |p| p.kappa_g,
            |p| p.kappa_g_prime,
            |p| p.lambda,
            |p| p.f_t,
            |p| p.f_n,
            |p| p.f_b,
            |p| p.f_g,
        ];
        // Every column interpolates the same native points: built and evaluated together.
        let interp = TrigColumns::new(
            &fields
                .iter()
                .map(|f| native.iter().map(f).collect())
                .collect::<Vec<Vec<f64>>>(),
        )?;
        let us = map.u_of_sigmas((0..m).map(|j| j as f64 / m as f64));
        let mut v = [0.0; 11];
        Ok((0..m)
            .map(|j| {
                let sigma = j as f64 / m as f64;
                let u = us[j];
                interp.eval(u, &mut v);
                let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                let back = if norm > 0.0 { r / norm } else { 1.0 };
                let kg = v[4];
                ProfilePoint {
                    s: sigma * len,
                    x: v[0] * back,
                    y: v[1] * back,
                    z: v[2] * back,
                    kappa: (kg * kg + 1.0 / (r * r)).sqrt(),
                    tau: v[3],
                    kappa_g: kg,
                    kappa_g_prime: v[5],
                    lambda: v[6],
                    f_t: v[7],
                    f_n: v[8],
                    f_b: v[9],
                    f_g: v[10],
                    d: model.stiffness().eval(sigma).per_arclength(len).0,
                }
            })
            .collect())
    }
}
