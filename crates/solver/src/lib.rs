//! rodloop-solver
