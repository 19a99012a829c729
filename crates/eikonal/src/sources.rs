use crate::{EikonalError, Result};

/// Checks every source (inside the grid, not an obstacle, not a zero-speed cell) and returns
/// `keep(source, index)` for each. Shared by fast marching and the graph solvers.
pub(crate) fn check_sources<C: Copy + std::fmt::Display, T>(
    sources: &[C],
    index: impl Fn(C) -> Option<usize>,
    blocked: impl Fn(usize) -> bool,
    speed: Option<&[f32]>,
    shape: &str,
    keep: impl Fn(C, usize) -> T,
) -> Result<Vec<T>> {
    if sources.is_empty() {
        return Err(EikonalError::NoSources);
    }
    sources
        .iter()
        .map(|&s| {
            let i = index(s).ok_or_else(|| EikonalError::SourceOutside {
                cell: s.to_string(),
                shape: shape.to_string(),
            })?;
            if blocked(i) || speed.is_some_and(|v| v[i] == 0.0) {
                return Err(EikonalError::SourceOnObstacle {
                    cell: s.to_string(),
                });
            }
            Ok(keep(s, i))
        })
        .collect()
}
