//! The figures crate's error type.

/// Everything that can go wrong while reading data for a figure or rendering one.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A CSV file is malformed.
    #[error("{path}: malformed CSV: {message}")]
    Csv {
        /// The file.
        path: String,
        /// What the CSV reader said.
        message: String,
    },
    /// A required column is absent.
    #[error("{path}: no column `{column}` (found columns: {found})")]
    MissingColumn {
        /// The file.
        path: String,
        /// The column that is needed.
        column: String,
        /// The columns that are there.
        found: String,
    },
    /// A cell is not a finite number.
    #[error("{path}: row {row}: column `{column}` is not a finite number (`{value}`)")]
    NotFinite {
        /// The file.
        path: String,
        /// 1-based row number counting the header as row 1.
        row: usize,
        /// The column.
        column: String,
        /// The text of the cell.
        value: String,
    },
    /// Too few rows to draw anything.
    #[error("{path}: needs at least {needed} data rows, found {found}")]
    TooFewRows {
        /// The file.
        path: String,
        /// Rows needed.
        needed: usize,
        /// Rows found.
        found: usize,
    },
    /// A figure was asked for with an impossible size or setting.
    #[error("invalid figure setting: {0}")]
    Invalid(String),
    /// A diagram directory the diagram figures cannot draw (no `summary.json`, a diagram
    /// against a parameter, a model or label they do not know); the message names the file.
    #[error("{0}")]
    Diagram(String),
    /// A diagram directory could not be read through the result schema (the message names
    /// the file and, where it applies, the row and column).
    #[error(transparent)]
    Schema(#[from] rodloop_schema::SchemaError),
    /// The SVG could not be rasterised.
    #[error("cannot rasterise the SVG: {0}")]
    Raster(String),
}
