use crate::{Cell2, Cell3, Grid2, Grid3};
use serde::{Deserialize, Serialize};
use std::f32::consts::SQRT_2;
use std::fmt;
use std::str::FromStr;

/// How an agent may step diagonally (`docs/move-rules.md` in the repository).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MoveRule {
    /// A diagonal step needs every orthogonal neighbour it passes free (no corner cutting). It
    /// matches what fast marching's stencil can see. The default.
    #[default]
    Strict,
    /// Only the destination must be free (corner cutting allowed), as in the VIN gridworlds.
    Vin,
}

impl fmt::Display for MoveRule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            MoveRule::Strict => "strict",
            MoveRule::Vin => "vin",
        })
    }
}

impl FromStr for MoveRule {
    type Err = crate::GridError;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "strict" => Ok(MoveRule::Strict),
            "vin" => Ok(MoveRule::Vin),
            _ => Err(crate::GridError::Invalid(format!(
                "unknown move rule {s:?} (expected strict or vin)"
            ))),
        }
    }
}

/// The neighbours a cell of a 2D grid is joined to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Neighbourhood2 {
    /// The 4 orthogonal neighbours.
    Four,
    /// All 8 neighbours, diagonals filtered by the move rule.
    Eight(MoveRule),
}

/// The neighbours a cell of a 3D grid is joined to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Neighbourhood3 {
    /// The 6 face neighbours.
    Six,
    /// All 26 neighbours; under [`MoveRule::Strict`] a move needs every cell of the 2x2(x2)
    /// block it crosses free.
    TwentySix(MoveRule),
}

/// The 8 step directions `(d_row, d_col)`: the 4 orthogonal ones first, then the diagonals.
pub const DIRECTIONS_8: [(isize, isize); 8] = [
    (-1, 0),
    (1, 0),
    (0, -1),
    (0, 1),
    (-1, -1),
    (-1, 1),
    (1, -1),
    (1, 1),
];

impl MoveRule {
    /// Whether a step from the free cell `from` by `(dr, dc)` (each in -1..=1, not both 0) is
    /// allowed on `grid`.
    pub fn allows(self, grid: &Grid2, from: Cell2, dr: isize, dc: isize) -> bool {
        let Some(to) = from.offset(dr, dc) else {
            return false;
        };
        if !grid.is_free(to) {
            return false;
        }
        if dr == 0 || dc == 0 || self == MoveRule::Vin {
            return true;
        }
        // Both orthogonal cells the diagonal passes must be free.
        from.offset(dr, 0).is_some_and(|c| grid.is_free(c))
            && from.offset(0, dc).is_some_and(|c| grid.is_free(c))
    }

    /// Whether a step from `from` to the neighbouring cell `to` (one of the 26 around it) is
    /// allowed on the 3D `grid`.
    pub fn allows3(self, grid: &Grid3, from: Cell3, to: Cell3) -> bool {
        if !grid.is_free(to) {
            return false;
        }
        if self == MoveRule::Vin {
            return true;
        }
        // Every cell of the block between `from` and `to` must be free.
        for x in from.x.min(to.x)..=from.x.max(to.x) {
            for y in from.y.min(to.y)..=from.y.max(to.y) {
                for z in from.z.min(to.z)..=from.z.max(to.z) {
                    if !grid.is_free(Cell3::new(x, y, z)) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

impl Grid2 {
    /// The cells an agent on `cell` can step to under `nb`, each with the step's length
    /// (1 or sqrt 2). Empty when `cell` is an obstacle or outside.
    pub fn neighbours(
        &self,
        cell: Cell2,
        nb: Neighbourhood2,
    ) -> impl Iterator<Item = (Cell2, f32)> + '_ {
        let (dirs, rule): (&[(isize, isize)], MoveRule) = match nb {
            Neighbourhood2::Four => (&DIRECTIONS_8[..4], MoveRule::Strict),
            Neighbourhood2::Eight(rule) => (&DIRECTIONS_8[..], rule),
        };
        let free = self.is_free(cell);
        dirs.iter().filter_map(move |&(dr, dc)| {
            if !free || !rule.allows(self, cell, dr, dc) {
                return None;
            }
            let to = cell.offset(dr, dc)?;
            Some((to, if dr != 0 && dc != 0 { SQRT_2 } else { 1.0 }))
        })
    }
}

impl Grid3 {
    /// The cells reachable in one step from `cell` under `nb`, each with the step's length
    /// (1, sqrt 2 or sqrt 3). Empty when `cell` is an obstacle or outside.
    pub fn neighbours(&self, cell: Cell3, nb: Neighbourhood3) -> Vec<(Cell3, f32)> {
        let mut out = Vec::with_capacity(26);
        if !self.is_free(cell) {
            return out;
        }
        for dx in -1isize..=1 {
            for dy in -1isize..=1 {
                for dz in -1isize..=1 {
                    let k = dx.abs() + dy.abs() + dz.abs();
                    if k == 0 || (k > 1 && nb == Neighbourhood3::Six) {
                        continue;
                    }
                    let (Some(x), Some(y), Some(z)) = (
                        cell.x.checked_add_signed(dx),
                        cell.y.checked_add_signed(dy),
                        cell.z.checked_add_signed(dz),
                    ) else {
                        continue;
                    };
                    let to = Cell3::new(x, y, z);
                    let rule = match nb {
                        Neighbourhood3::Six => MoveRule::Vin,
                        Neighbourhood3::TwentySix(rule) => rule,
                    };
                    if rule.allows3(self, cell, to) {
                        out.push((to, (k as f32).sqrt()));
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_cutting_depends_on_the_rule() {
        // .#
        // #.
        let g = Grid2::from_obstacles(2, 2, vec![false, true, true, false]).unwrap();
        let a = Cell2::new(0, 0);
        assert!(!MoveRule::Strict.allows(&g, a, 1, 1));
        assert!(MoveRule::Vin.allows(&g, a, 1, 1));
        assert_eq!(
            g.neighbours(a, Neighbourhood2::Eight(MoveRule::Strict))
                .count(),
            0
        );
        let v: Vec<_> = g
            .neighbours(a, Neighbourhood2::Eight(MoveRule::Vin))
            .collect();
        assert_eq!(v, vec![(Cell2::new(1, 1), SQRT_2)]);
    }

    #[test]
    fn neighbour_counts_in_open_3d() {
        let g = Grid3::new(3, 3, 3).unwrap();
        let c = Cell3::new(1, 1, 1);
        assert_eq!(g.neighbours(c, Neighbourhood3::Six).len(), 6);
        assert_eq!(
            g.neighbours(c, Neighbourhood3::TwentySix(MoveRule::Strict))
                .len(),
            26
        );
        let mut g = g;
        g.set_obstacle(Cell3::new(1, 1, 2), true).unwrap();
        // Blocking the cell above removes it and the 8 strict moves that cross it (4 edge + 4 corner).
        assert_eq!(
            g.neighbours(c, Neighbourhood3::TwentySix(MoveRule::Strict))
                .len(),
            17
        );
        assert_eq!(
            g.neighbours(c, Neighbourhood3::TwentySix(MoveRule::Vin))
                .len(),
            25
        );
    }
}
