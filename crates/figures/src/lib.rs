//! Figures for rodloop: pictures of loops on the sphere (four views, depth shading, colour
//! by any column, self-contacts), line plots of forces and shapes along a loop, and the
//! branch diagram with its critical points (the paper's Figs. 2, 3, 5, 6, 7).
//!
//! Everything is drawn as SVG by this crate (a few primitives suffice, and text stays text,
//! with Unicode symbols such as L̄, λ, η). PNGs are drawn with tiny-skia straight from the
//! document's drawing operations (`paint`; text shaped by rustybuzz), or rasterised from
//! the SVG text by `resvg` when a document holds raw markup; both use the DejaVu Sans font
//! bundled in `fonts/`, so no system font is ever needed.

mod error;

pub mod atlas;
pub mod color;
pub mod convergence;
pub mod data;
pub mod diagram;
mod diagram_data;
pub mod geometry;
pub mod k2;
pub mod loops;
pub mod overlay;
pub mod paint;
pub mod plot;
pub mod profiles;
pub mod raster;
pub mod svg;
pub mod view;
pub mod vtk;

pub use error::FigureError;
