use envfield_grid::GridError;

/// Everything that can go wrong in `envfield-eikonal`.
#[derive(Debug, thiserror::Error)]
pub enum EikonalError {
    /// An error from the grid types (a cell outside the grid, a bad shape, ...).
    #[error(transparent)]
    Grid(#[from] GridError),
    /// No source cell was given.
    #[error("no source cell given")]
    NoSources,
    /// The grid has no free cell at all.
    #[error("the grid has no free cell")]
    NoFreeCell,
    /// A source lies on an obstacle (or on a cell of zero speed).
    #[error("source {cell} is on an obstacle")]
    SourceOnObstacle {
        /// The source, formatted.
        cell: String,
    },
    /// A source lies outside the grid.
    #[error("source {cell} is outside the {shape} grid")]
    SourceOutside {
        /// The source, formatted.
        cell: String,
        /// The grid's shape, formatted.
        shape: String,
    },
    /// A speed is NaN, infinite or negative.
    #[error("speed at cell {cell} is {value}; speeds must be finite and non-negative")]
    InvalidSpeed {
        /// The cell, formatted.
        cell: String,
        /// The offending value.
        value: f32,
    },
    /// The speed map's shape differs from the grid's.
    #[error("speed map is {speed} but the grid is {grid}")]
    SpeedShape {
        /// The speed map's shape, formatted.
        speed: String,
        /// The grid's shape, formatted.
        grid: String,
    },
    /// The grid has more cells than fast marching can index: cell numbers and heap positions
    /// are 32-bit (about 4.29 billion cells, counting a two-cell padding on every side).
    #[error(
        "the {shape} grid is too large for fast marching: with a two-cell padding on every \
         side it needs more than {limit} cells"
    )]
    GridTooLarge {
        /// The grid's shape, formatted.
        shape: String,
        /// The most padded cells a solve can index.
        limit: usize,
    },
    /// A level-set march's input is out of range (see [`crate::level_set`]); the text names
    /// what and where.
    #[error("{0}")]
    LevelSet(String),
    /// A level-set march that cannot go on (an extension velocity dividing by zero, no
    /// update reaching a cell, the queue's self-test failing); the text names where.
    #[error("{0}")]
    March(String),
    /// A level set without a zero contour: `phi` never changes sign and is nowhere 0 (outside
    /// the mask), so no front can start.
    #[error("the array phi contains no zero contour (no zero level set)")]
    NoZeroContour,
    /// A solver setting is out of range.
    #[error("invalid solver setting: {0}")]
    InvalidConfig(String),
}

/// `Result` with [`EikonalError`].
pub type Result<T, E = EikonalError> = std::result::Result<T, E>;

impl From<EikonalError> for GridError {
    fn from(e: EikonalError) -> Self {
        match e {
            EikonalError::Grid(g) => g,
            other => GridError::Invalid(other.to_string()),
        }
    }
}
