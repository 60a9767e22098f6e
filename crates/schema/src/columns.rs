//! The dictionary of the columns of `branches.csv`, `critical.csv` and
//! `special_points.csv`.

/// What a column of `branches.csv` holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    /// [`Point::branch`](crate::Point::branch).
    Branch,
    /// [`Point::eta`](crate::Point::eta).
    Eta,
    /// [`Point::family`](crate::Point::family).
    Family,
    /// [`Point::sheet`](crate::Point::sheet).
    Sheet,
    /// The coordinate of the axis of the same name ([`Point::coords`](crate::Point::coords)).
    Coord,
    /// [`Point::energy`](crate::Point::energy).
    Energy,
    /// [`Point::energy_error`](crate::Point::energy_error).
    EnergyError,
    /// [`Point::index`](crate::Point::index).
    Index,
    /// [`Point::label`](crate::Point::label).
    Label,
    /// [`Point::state_file`](crate::Point::state_file).
    StateFile,
    /// A number in [`Point::extra`](crate::Point::extra).
    Number,
    /// An integer in [`Point::extra`](crate::Point::extra).
    Integer,
    /// Text in [`Point::extra`](crate::Point::extra).
    Text,
}

/// One entry of the column dictionary.
#[derive(Clone, Copy, Debug)]
pub struct ColumnSpec {
    /// Column name in `branches.csv`.
    pub name: &'static str,
    /// What it holds.
    pub field: Field,
    /// Meaning and units.
    pub meaning: &'static str,
}

const fn col(name: &'static str, field: Field, meaning: &'static str) -> ColumnSpec {
    ColumnSpec {
        name,
        field,
        meaning,
    }
}

/// Every column a `branches.csv` of rodloop may hold. Energies are `E R/(π D0)`, forces
/// `λ R³/D0`, lengths `L̄ = L/(2πR)`.
pub const COLUMNS: &[ColumnSpec] = &[
    col(
        "branch",
        Field::Branch,
        "paper branch number (0: the free circle)",
    ),
    col("eta", Field::Eta, "periods of the geodesic curvature"),
    col(
        "family",
        Field::Family,
        "family within the branch (0: a uniform rod's one family)",
    ),
    col(
        "sheet",
        Field::Sheet,
        "sheet of the family (monotone in lbar)",
    ),
    col("lbar", Field::Coord, "normalised length L/(2 pi R)"),
    col(
        "param",
        Field::Text,
        "name of the continued parameter (diagrams against a parameter)",
    ),
    col(
        "value",
        Field::Coord,
        "value of the continued parameter (diagrams against a parameter)",
    ),
    col("energy", Field::Energy, "energy E R/(pi D0)"),
    col(
        "energy_error",
        Field::EnergyError,
        "estimated error of energy (empty: none)",
    ),
    col(
        "index",
        Field::Index,
        "stability index (negative eigenvalues of the constrained Hessian)",
    ),
    col(
        "stability",
        Field::Label,
        "stable, metastable or unstable (surface diagrams)",
    ),
    col(
        "label",
        Field::Label,
        "stable, metastable or unstable (enclosed diagrams)",
    ),
    col(
        "state_file",
        Field::StateFile,
        "the state's loop table, relative to the diagram directory",
    ),
    col("energy_g", Field::Number, "geodesic part E_g R/(pi D0)"),
    col(
        "lambda_min",
        Field::Number,
        "smallest contact force lambda R^3/D0",
    ),
    col(
        "lambda_max",
        Field::Number,
        "largest contact force lambda R^3/D0",
    ),
    col(
        "arc",
        Field::Integer,
        "position along the family: sheet * 10^6 + rank in arclength",
    ),
    col(
        "multiplicity",
        Field::Integer,
        "distinct loops the state stands for (2: a mirror pair)",
    ),
    col("point_group", Field::Text, "point group of the loop"),
    col(
        "self_intersections",
        Field::Text,
        "self-intersections of the loop",
    ),
    col("p", Field::Integer, "paper winding number p, Eq. (50)"),
    col("k", Field::Number, "elliptic modulus k"),
    col("c", Field::Number, "c R"),
    col(
        "closure_residual",
        Field::Number,
        "closure residual in radians",
    ),
    col(
        "lowest",
        Field::Integer,
        "1 where the state is the lowest at its length",
    ),
    col(
        "attached",
        Field::Integer,
        "1 where the loop lies on the wall everywhere",
    ),
    col(
        "contact_fraction",
        Field::Number,
        "length fraction touching the wall",
    ),
    col(
        "contact_intervals",
        Field::Integer,
        "number of contact intervals",
    ),
    col("max_gap", Field::Number, "largest gap (R - |r|)/R"),
    col("gap_min", Field::Number, "smallest gap /R"),
    col("complementarity", Field::Number, "largest |lambda gap|"),
    col(
        "stationarity",
        Field::Number,
        "stationarity residual of the 3-D model",
    ),
    col(
        "cells",
        Field::Integer,
        "cells of the reported state (0: exact)",
    ),
    col("source", Field::Text, "where the state comes from"),
    col(
        "surface_energy",
        Field::Number,
        "energy of the branch's surface loop at this length",
    ),
    col(
        "branch_from",
        Field::Text,
        "how the branch is known: exact, periods (of the state's own moment) or continuation (the family's, where the moment has no periods)",
    ),
];

/// The dictionary entry of column `name`.
pub fn column(name: &str) -> Option<&'static ColumnSpec> {
    COLUMNS.iter().find(|c| c.name == name)
}

/// Columns of `critical.csv`.
pub const CRITICAL_COLUMNS: &[&str] = &[
    "index",
    "lbar_cr",
    "kind",
    "from_branch",
    "to_branch",
    "energy",
    "error_estimate",
];

/// Columns of `special_points.csv`.
pub const SPECIAL_COLUMNS: &[&str] = &[
    "kind",
    "lbar",
    "energy",
    "branch",
    "family",
    "index_before",
    "index_after",
    "error_estimate",
];
