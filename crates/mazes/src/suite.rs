//! The maze suite's sets: every layout family at every size, mazes without a border and
//! non-square windows, VIN's test sets and Minigrid's layouts when their folders are given.

use crate::{GeneratorKind, MazeGenerator, Result};
use envfield_grid::{read_mazes, GridError, Maze, MoveRule};
use std::path::{Path, PathBuf};

/// One row of the suite: a set of mazes and the rule they are walked by.
#[derive(Clone, Debug)]
pub struct MazeSet {
    /// The row's label, such as `rooms 16x16` or `VIN test 28x28`.
    pub label: String,
    /// The move rule the set is walked by.
    pub rule: MoveRule,
    /// The mazes.
    pub mazes: Vec<Maze>,
}

impl MazeSet {
    /// The mazes of a maze file, labelled by the file's name.
    ///
    /// # Errors
    /// Errors of reading and parsing the file.
    pub fn read(file: &Path, rule: MoveRule) -> Result<Self> {
        Ok(Self {
            label: file
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default(),
            rule,
            mazes: read_mazes(file)?,
        })
    }

    /// `count` generated mazes of `kind`, `size` cells a side, from `seed`, labelled
    /// `"{kind} {size}x{size}"`.
    ///
    /// # Errors
    /// Errors of the generator (a size it cannot make).
    pub fn generated(
        kind: GeneratorKind,
        size: usize,
        count: usize,
        seed: u64,
        rule: MoveRule,
    ) -> Result<Self> {
        Ok(Self {
            label: format!("{kind} {size}x{size}"),
            rule,
            mazes: MazeGenerator::new(kind, size)?.generate_many(count, seed)?,
        })
    }
}

/// The suite's sets: gridworlds (the `vin` rule) at 8 to 64 cells a side, crossings and rooms
/// at 8 to 64 and perfect mazes at 21 to 63 (the `strict` rule), `count` mazes each from
/// `seed`; a perfect maze without its border, two 16x40 windows; VIN's test sets from
/// `vin_dir` (`vin_test_{8,16,28}.txt`, the 16 also without its border) and every `.txt` of
/// `minigrid_dir`, when given.
///
/// # Errors
/// Errors of the generators and of reading the files.
pub fn suite_sets(
    count: usize,
    seed: u64,
    vin_dir: Option<&Path>,
    minigrid_dir: Option<&Path>,
) -> Result<Vec<MazeSet>> {
    let generated = |kind: GeneratorKind, size: usize| -> Result<Vec<Maze>> {
        MazeGenerator::new(kind, size)?.generate_many(count, seed)
    };
    let mut out = Vec::new();
    for (kind, rule, sizes) in [
        (
            GeneratorKind::Gridworld,
            MoveRule::Vin,
            &[8, 16, 28, 48, 64][..],
        ),
        (
            GeneratorKind::Crossings,
            MoveRule::Strict,
            &[8, 16, 28, 48, 64],
        ),
        (GeneratorKind::Rooms, MoveRule::Strict, &[8, 16, 28, 48, 64]),
        (GeneratorKind::Perfect, MoveRule::Strict, &[21, 41, 63]),
    ] {
        for &size in sizes {
            out.push(MazeSet {
                label: format!("{kind} {size}x{size}"),
                rule,
                mazes: generated(kind, size)?,
            });
        }
    }
    // Any frame: open edges and non-square mazes.
    let no_border = |kind, size| -> Result<Vec<Maze>> {
        Ok(generated(kind, size)?
            .iter()
            .map(Maze::without_border)
            .collect::<std::result::Result<_, _>>()?)
    };
    let window = |kind, size, rows, cols| -> Result<Vec<Maze>> {
        generated(kind, size)?
            .iter()
            .map(|m| {
                let mut w = m.window(0, 0, rows, cols)?;
                (w.start, w.goal) = (None, None);
                Ok(w)
            })
            .collect()
    };
    out.push(MazeSet {
        label: "perfect 41x41, border removed (39x39)".into(),
        rule: MoveRule::Strict,
        mazes: no_border(GeneratorKind::Perfect, 41)?,
    });
    out.push(MazeSet {
        label: "rooms 16x40 (window of 40x40)".into(),
        rule: MoveRule::Strict,
        mazes: window(GeneratorKind::Rooms, 40, 16, 40)?,
    });
    out.push(MazeSet {
        label: "gridworld 16x40 (window of 40x40)".into(),
        rule: MoveRule::Vin,
        mazes: window(GeneratorKind::Gridworld, 40, 16, 40)?,
    });
    for size in [8, 16, 28] {
        let Some(file) = vin_dir.map(|d| d.join(format!("vin_test_{size}.txt"))) else {
            break;
        };
        if file.is_file() {
            let mazes = read_mazes(&file)?;
            if size == 16 {
                out.push(MazeSet {
                    label: "VIN test 16, border removed (14x14)".into(),
                    rule: MoveRule::Vin,
                    mazes: mazes
                        .iter()
                        .map(Maze::without_border)
                        .collect::<std::result::Result<_, _>>()?,
                });
            }
            out.push(MazeSet {
                label: format!("VIN test {size}x{size}"),
                rule: MoveRule::Vin,
                mazes,
            });
        }
    }
    let mut minigrid: Vec<PathBuf> = match minigrid_dir {
        Some(dir) => std::fs::read_dir(dir)
            .map_err(|source| GridError::Io {
                path: dir.to_path_buf(),
                source,
            })?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "txt"))
            .collect(),
        None => Vec::new(),
    };
    minigrid.sort();
    for file in minigrid {
        let name = file.file_stem().unwrap_or_default().to_string_lossy();
        let mazes = read_mazes(&file)?;
        let Some(first) = mazes.first() else { continue };
        let (r, c) = (first.grid.rows(), first.grid.cols());
        out.push(MazeSet {
            label: format!("Minigrid {name} {r}x{c}"),
            rule: MoveRule::Strict,
            mazes,
        });
    }
    Ok(out)
}
