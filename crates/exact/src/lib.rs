//! rodloop-exact
pub mod euler;
