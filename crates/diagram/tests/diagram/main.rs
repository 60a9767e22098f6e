//! Integration tests of the numeric branch diagram (one test binary made of modules; the
//! diagrams of the default scene are computed once and shared).

mod certificate;
mod common;
mod default_scene;
mod extremes;
mod families;
mod great_circles;
mod inhomogeneous;
mod resolution;
mod resume;
mod shapes;
mod stepping;
