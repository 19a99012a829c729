//! The maze text format (`docs/maze-format.md` in the repository).

use crate::io::write_atomic;
use crate::{Cell2, Grid2, GridError, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A maze: an occupancy grid with an optional start `S` and goal `G`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Maze {
    /// The occupancy grid.
    pub grid: Grid2,
    /// The start cell, when the maze marks one.
    pub start: Option<Cell2>,
    /// The goal cell, when the maze marks one.
    pub goal: Option<Cell2>,
}

impl Maze {
    /// A maze with no start or goal.
    pub fn new(grid: Grid2) -> Self {
        Self {
            grid,
            start: None,
            goal: None,
        }
    }

    /// The `rows x cols` window of the maze whose top-left cell is `(row, col)`; its start and
    /// goal are kept when both lie inside the window (moved into its frame), dropped together
    /// otherwise.
    ///
    /// # Errors
    /// [`GridError::Invalid`](crate::GridError) for an empty window or one that does not fit
    /// in the maze.
    pub fn window(&self, row: usize, col: usize, rows: usize, cols: usize) -> Result<Self> {
        let g = &self.grid;
        if rows == 0 || cols == 0 || row + rows > g.rows() || col + cols > g.cols() {
            return Err(crate::GridError::Invalid(format!(
                "a {rows}x{cols} window at ({row}, {col}) does not fit in a {}x{} maze",
                g.rows(),
                g.cols()
            )));
        }
        let obstacles = (0..rows)
            .flat_map(|r| (0..cols).map(move |c| (r, c)))
            .map(|(r, c)| g.obstacles()[(r + row) * g.cols() + c + col])
            .collect();
        let inside = |p: Option<Cell2>| {
            p.filter(|p| (row..row + rows).contains(&p.row) && (col..col + cols).contains(&p.col))
                .map(|p| Cell2::new(p.row - row, p.col - col))
        };
        let (start, goal) = (inside(self.start), inside(self.goal));
        let both = start.is_some() && goal.is_some();
        Ok(Self {
            grid: Grid2::from_obstacles(rows, cols, obstacles)?,
            start: start.filter(|_| both),
            goal: goal.filter(|_| both),
        })
    }

    /// The maze without its outermost rows and columns ([`Maze::window`] one cell in).
    ///
    /// # Errors
    /// As [`Maze::window`], for a maze under 3 cells a side.
    pub fn without_border(&self) -> Result<Self> {
        let (rows, cols) = (self.grid.rows(), self.grid.cols());
        self.window(1, 1, rows.saturating_sub(2), cols.saturating_sub(2))
    }

    /// Parses exactly one maze.
    ///
    /// # Errors
    /// [`GridError::MazeSyntax`] for malformed text, or when the text holds more than one maze.
    pub fn parse(text: &str) -> Result<Maze> {
        let mut mazes = parse_mazes(text)?;
        if mazes.len() != 1 {
            return Err(GridError::MazeSyntax {
                line: 1,
                column: 1,
                message: format!("expected one maze, found {}", mazes.len()),
            });
        }
        Ok(mazes.remove(0))
    }

    /// The maze in the text format, one line a row, each ending with a newline.
    ///
    /// # Errors
    /// [`GridError::Invalid`] when the start or goal lies on an obstacle or outside the grid.
    pub fn to_text(&self) -> Result<String> {
        let g = &self.grid;
        let mut chars: Vec<u8> = g
            .obstacles()
            .iter()
            .map(|&o| if o { b'#' } else { b'.' })
            .collect();
        for (cell, mark, what) in [(self.start, b'S', "start"), (self.goal, b'G', "goal")] {
            if let Some(cell) = cell {
                chars[g.check_free(cell, what)?] = mark;
            }
        }
        let mut out = String::with_capacity(g.len() + g.rows());
        for row in chars.chunks(g.cols()) {
            out.push_str(std::str::from_utf8(row).expect("ascii"));
            out.push('\n');
        }
        Ok(out)
    }
}

/// Parses one or more mazes separated by blank lines; lines starting with `;` are comments.
///
/// # Errors
/// [`GridError::MazeSyntax`] naming the line and column of the first problem: an unknown
/// character, rows of different lengths, a second `S` or `G`, or no maze at all.
pub fn parse_mazes(text: &str) -> Result<Vec<Maze>> {
    let mut mazes = Vec::new();
    let mut current: Option<Builder> = None;
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        if line.starts_with(';') {
            continue;
        }
        if line.trim().is_empty() {
            if let Some(b) = current.take() {
                mazes.push(b.finish()?);
            }
            continue;
        }
        current
            .get_or_insert_with(|| Builder::new(line_no))
            .push_row(line, line_no)?;
    }
    if let Some(b) = current.take() {
        mazes.push(b.finish()?);
    }
    if mazes.is_empty() {
        return Err(GridError::MazeSyntax {
            line: 1,
            column: 1,
            message: "no maze found (empty input or only comments)".into(),
        });
    }
    Ok(mazes)
}

/// Reads every maze of a text file.
///
/// # Errors
/// [`GridError::Io`] when the file cannot be read, [`GridError::MazeSyntax`] when it is
/// malformed (the message names the file, line and column).
pub fn read_mazes(path: impl AsRef<Path>) -> Result<Vec<Maze>> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| GridError::io(path, e))?;
    parse_mazes(&text).map_err(|e| match e {
        GridError::MazeSyntax {
            line,
            column,
            message,
        } => GridError::MazeSyntax {
            line,
            column,
            message: format!("{message} (in {})", path.display()),
        },
        other => other,
    })
}

/// The mazes in the text format, separated by blank lines.
///
/// # Errors
/// As [`Maze::to_text`].
pub fn format_mazes(mazes: &[Maze]) -> Result<String> {
    let parts: Result<Vec<String>> = mazes.iter().map(Maze::to_text).collect();
    Ok(parts?.join("\n"))
}

/// Writes mazes to a text file atomically (a temporary file, then a rename).
///
/// # Errors
/// As [`format_mazes`], or [`GridError::Io`].
pub fn write_mazes(path: impl AsRef<Path>, mazes: &[Maze]) -> Result<()> {
    write_atomic(path, format_mazes(mazes)?.as_bytes())
}

struct Builder {
    first_line: usize,
    cols: usize,
    cells: Vec<bool>,
    start: Option<Cell2>,
    goal: Option<Cell2>,
}

impl Builder {
    fn new(first_line: usize) -> Self {
        Self {
            first_line,
            cols: 0,
            cells: Vec::new(),
            start: None,
            goal: None,
        }
    }

    fn rows(&self) -> usize {
        self.cells.len().checked_div(self.cols).unwrap_or(0)
    }

    fn push_row(&mut self, line: &str, line_no: usize) -> Result<()> {
        let err = |column: usize, message: String| GridError::MazeSyntax {
            line: line_no,
            column,
            message,
        };
        let row = self.rows();
        let mut count = 0;
        for (j, ch) in line.chars().enumerate() {
            let cell = Cell2::new(row, j);
            let obstacle = match ch {
                '#' => true,
                '.' => false,
                'S' | 'G' => {
                    let slot = if ch == 'S' {
                        &mut self.start
                    } else {
                        &mut self.goal
                    };
                    if let Some(prev) = slot {
                        return Err(err(
                            j + 1,
                            format!(
                                "a second '{ch}' (the maze starting at line {} already has one at row {}, column {})",
                                self.first_line, prev.row, prev.col
                            ),
                        ));
                    }
                    *slot = Some(cell);
                    false
                }
                other => {
                    return Err(err(
                        j + 1,
                        format!("unknown character {other:?} (expected '#', '.', 'S' or 'G')"),
                    ))
                }
            };
            self.cells.push(obstacle);
            count += 1;
        }
        if self.cols == 0 {
            self.cols = count;
        } else if count != self.cols {
            return Err(err(
                count.min(self.cols) + 1,
                format!(
                    "row has {count} cells but the maze starting at line {} has {} per row",
                    self.first_line, self.cols
                ),
            ));
        }
        Ok(())
    }

    fn finish(self) -> Result<Maze> {
        let rows = self.rows();
        let grid = Grid2::from_obstacles(rows, self.cols, self.cells)?;
        Ok(Maze {
            grid,
            start: self.start,
            goal: self.goal,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn syntax(text: &str) -> (usize, usize, String) {
        match parse_mazes(text) {
            Err(GridError::MazeSyntax {
                line,
                column,
                message,
            }) => (line, column, message),
            other => panic!("expected a syntax error, got {other:?}"),
        }
    }

    #[test]
    fn parses_several_mazes_with_comments() {
        let text = "; two mazes\n###\n#S#\n#G#\n\n\n; second\n....\n.#..\n";
        let m = parse_mazes(text).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!((m[0].grid.rows(), m[0].grid.cols()), (3, 3));
        assert_eq!(m[0].start, Some(Cell2::new(1, 1)));
        assert_eq!(m[0].goal, Some(Cell2::new(2, 1)));
        assert!(m[1].start.is_none() && m[1].goal.is_none());
        assert!(m[1].grid.is_obstacle(Cell2::new(1, 1)));
        let again = parse_mazes(&format_mazes(&m).unwrap()).unwrap();
        assert_eq!(again, m);
    }

    #[test]
    fn malformed_text_names_line_and_column() {
        assert_eq!(syntax("##\n#x\n").0, 2);
        assert_eq!(syntax("##\n#x\n").1, 2);
        let (l, c, msg) = syntax("###\n##\n");
        assert_eq!((l, c), (2, 3));
        assert!(msg.contains("2 cells"), "{msg}");
        let (l, c, _) = syntax("G.\n.G\n");
        assert_eq!((l, c), (2, 2));
        assert_eq!(syntax("").0, 1);
        assert_eq!(syntax("; only a comment\n\n").0, 1);
        assert_eq!(syntax("S.S\n").1, 3);
    }

    #[test]
    fn crlf_line_endings_are_accepted() {
        let m = Maze::parse("#.\r\n.G\r\n").unwrap();
        assert_eq!(m.goal, Some(Cell2::new(1, 1)));
    }
}
