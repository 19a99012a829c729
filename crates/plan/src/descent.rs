use crate::planner::check_query;
use crate::{PlanOutcome, Planner, Result};
use envfield_grid::{descent_move, Cell2, Field2, FieldModel, Grid2, MoveRule};

/// Field descent: predict the whole field once, then step to the neighbour (under the move
/// rule) with the smallest value. Works on any [`FieldModel`], exact or learned.
///
/// The walk stops on the goal (success), after `max_steps` moves, or when stuck: every
/// neighbour is infinite, or the best one was visited already (a loop). Ties go to the first
/// direction in [`envfield_grid::DIRECTIONS_8`] order. It never enters an obstacle, and under
/// [`MoveRule::Strict`] never cuts a corner, whatever the field says.
pub struct FieldDescent<M> {
    /// The field model.
    pub model: M,
    /// The move rule the agent walks under.
    pub rule: MoveRule,
    name: String,
}

impl<M: FieldModel> FieldDescent<M> {
    /// Descent on `model` under `rule`; the planner takes the model's name.
    pub fn new(model: M, rule: MoveRule) -> Self {
        let name = model.name().to_string();
        Self { model, rule, name }
    }
}

/// `model`'s field towards `goal` on `grid`, checked to have the grid's shape.
pub(crate) fn predict_checked(
    model: &impl FieldModel,
    grid: &Grid2,
    goal: Cell2,
) -> Result<Field2> {
    let field = model.predict(grid, goal)?;
    if (field.rows(), field.cols()) != (grid.rows(), grid.cols()) {
        return Err(crate::PlanError::Invalid(format!(
            "model {} returned a {}x{} field for a {}x{} grid",
            model.name(),
            field.rows(),
            field.cols(),
            grid.rows(),
            grid.cols()
        )));
    }
    Ok(field)
}

/// Walks down `field` from `start` (see [`FieldDescent`]).
pub fn descend(
    grid: &Grid2,
    field: &Field2,
    rule: MoveRule,
    start: Cell2,
    goal: Cell2,
    max_steps: usize,
) -> PlanOutcome {
    let mut path = vec![start];
    let mut visited = std::collections::HashSet::new();
    visited.insert(start);
    let mut here = start;
    while here != goal && path.len() <= max_steps {
        match descent_move(grid, field, rule, here) {
            Some(next) if visited.insert(next) => {
                path.push(next);
                here = next;
            }
            _ => break,
        }
    }
    PlanOutcome {
        success: here == goal,
        path,
    }
}

impl<M: FieldModel> Planner for FieldDescent<M> {
    fn name(&self) -> &str {
        &self.name
    }

    fn plan(
        &self,
        grid: &Grid2,
        start: Cell2,
        goal: Cell2,
        max_steps: usize,
    ) -> Result<PlanOutcome> {
        check_query(grid, start, goal)?;
        let field = predict_checked(&self.model, grid, goal)?;
        Ok(descend(grid, &field, self.rule, start, goal, max_steps))
    }
}
