//! Planners by name: the names the examples and benchmarks take on their command lines.

use crate::{AStar, FieldDescent, Octile, PlanError, Planner, PolicyWalk, RelayDescent, Result};
use envfield_eikonal::{FastMarching, GraphDistance};
use envfield_grid::{FieldModel, MoveRule, Neighbourhood2, Policy};
use std::fmt;
use std::str::FromStr;

/// A field model that can be shared across threads, as planners hold them.
pub type BoxedField = Box<dyn FieldModel + Send + Sync>;

/// A policy that can be shared across threads.
pub type BoxedPolicy = Box<dyn Policy + Send + Sync>;

/// A planner by name. The learned ones (`field`, `relay`, `hyper`, `vin`) need a model from
/// the caller (see [`PlannerKind::build`]); the others are built here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PlannerKind {
    /// `field`: descent on the learned context-aligned field.
    Field,
    /// `relay`: the same field; a descent that fails is planned again through relay cells.
    Relay,
    /// `octile`: descent on the octile distance, blind to walls (the control).
    Octile,
    /// `octile-relay`: the control with relays.
    OctileRelay,
    /// `hyper`: descent on the hypernetwork's field.
    Hyper,
    /// `vin`: the VIN baseline, one network pass per step.
    Vin,
    /// `fmm`: descent on the fast-marching field.
    Fmm,
    /// `graph`: descent on the exact graph distance.
    Graph,
    /// `astar`: A* with the octile heuristic.
    AStar,
}

impl PlannerKind {
    /// Every planner, in the order of their names in [`PlannerKind::NAMES`].
    pub const ALL: [Self; 9] = [
        Self::Field,
        Self::Relay,
        Self::Octile,
        Self::OctileRelay,
        Self::Hyper,
        Self::Vin,
        Self::Fmm,
        Self::Graph,
        Self::AStar,
    ];

    /// The names, in the order of [`PlannerKind::ALL`].
    pub const NAMES: [&'static str; 9] = [
        "field",
        "relay",
        "octile",
        "octile-relay",
        "hyper",
        "vin",
        "fmm",
        "graph",
        "astar",
    ];

    /// The name the planner is parsed from.
    pub fn name(self) -> &'static str {
        Self::NAMES[Self::ALL.iter().position(|&k| k == self).unwrap_or(0)]
    }

    /// The family of weight files the planner needs (`context`, `hyper` or `vin`), if it
    /// learns.
    pub fn model_family(self) -> Option<&'static str> {
        match self {
            Self::Field | Self::Relay => Some("context"),
            Self::Hyper => Some("hyper"),
            Self::Vin => Some("vin"),
            _ => None,
        }
    }

    /// Builds the planner under `options`. `learned` is called with
    /// [`PlannerKind::model_family`] for the planners that need a model, and must give a
    /// field model for `context` and `hyper` and a policy for `vin`.
    ///
    /// # Errors
    /// The errors of `learned`; [`PlanError::Invalid`] when it gives the wrong kind of model.
    pub fn build<E: From<PlanError>>(
        self,
        options: &PlannerOptions,
        learned: impl FnOnce(&str) -> std::result::Result<Learned, E>,
    ) -> std::result::Result<NamedPlanner, E> {
        let rule = options.rule;
        let field: BoxedField = match self {
            Self::AStar => return Ok(NamedPlanner::AStar(AStar { rule })),
            Self::Fmm => Box::new(FastMarching::default()),
            Self::Graph => Box::new(GraphDistance::new(Neighbourhood2::Eight(rule))),
            Self::Octile | Self::OctileRelay => Box::new(Octile),
            Self::Field | Self::Relay | Self::Hyper | Self::Vin => {
                let family = self.model_family().unwrap_or_default();
                match (self, learned(family)?) {
                    (Self::Vin, Learned::Policy(p)) => {
                        return Ok(NamedPlanner::Policy(PolicyWalk(p)))
                    }
                    (Self::Field | Self::Relay | Self::Hyper, Learned::Field(f)) => f,
                    _ => {
                        return Err(PlanError::Invalid(format!(
                            "planner {self} needs a {}, and was given the other kind of model",
                            if self == Self::Vin {
                                "policy"
                            } else {
                                "field model"
                            }
                        ))
                        .into())
                    }
                }
            }
        };
        Ok(match self {
            Self::Relay | Self::OctileRelay => {
                let mut relay = RelayDescent::new(field, rule, options.relays);
                relay.candidates = options.candidates;
                NamedPlanner::Relay(relay)
            }
            _ => NamedPlanner::Field(FieldDescent::new(field, rule)),
        })
    }
}

impl fmt::Display for PlannerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for PlannerKind {
    type Err = PlanError;

    fn from_str(s: &str) -> Result<Self> {
        match Self::NAMES.iter().position(|&n| n == s) {
            Some(i) => Ok(Self::ALL[i]),
            None => Err(PlanError::Invalid(format!(
                "unknown planner {s:?} (expected {})",
                Self::NAMES.join(", ")
            ))),
        }
    }
}

/// A learned model for [`PlannerKind::build`].
pub enum Learned {
    /// A field model (`context`, `hyper`).
    Field(BoxedField),
    /// A policy (`vin`).
    Policy(BoxedPolicy),
}

/// The settings of the planners built by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlannerOptions {
    /// The move rule the agent walks under.
    pub rule: MoveRule,
    /// For relayed planners: how often a failing walk may be split ([`RelayDescent::new`]).
    pub relays: usize,
    /// For relayed planners: [`RelayDescent::candidates`].
    pub candidates: usize,
}

impl Default for PlannerOptions {
    fn default() -> Self {
        Self {
            rule: MoveRule::Strict,
            relays: 1,
            candidates: 1,
        }
    }
}

/// A planner built by name, with its field model within reach (for pictures and profiles).
pub enum NamedPlanner {
    /// Field descent.
    Field(FieldDescent<BoxedField>),
    /// Relay descent.
    Relay(RelayDescent<BoxedField>),
    /// A*.
    AStar(AStar),
    /// A policy walked step by step.
    Policy(PolicyWalk<BoxedPolicy>),
}

impl NamedPlanner {
    /// The planner.
    pub fn planner(&self) -> &dyn Planner {
        match self {
            Self::Field(p) => p,
            Self::Relay(p) => p,
            Self::AStar(p) => p,
            Self::Policy(p) => p,
        }
    }

    /// The field model descent walks on, for planners that have one.
    pub fn field_model(&self) -> Option<&dyn FieldModel> {
        match self {
            Self::Field(p) => Some(p.model.as_ref()),
            Self::Relay(p) => Some(p.model.as_ref()),
            Self::AStar(_) | Self::Policy(_) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_unknown_ones_are_refused() {
        for kind in PlannerKind::ALL {
            assert_eq!(kind.name().parse::<PlannerKind>().unwrap(), kind);
        }
        let err = "dijkstra".parse::<PlannerKind>().unwrap_err().to_string();
        assert!(
            err.contains("dijkstra") && err.contains("octile-relay"),
            "{err}"
        );
    }

    #[test]
    fn builds_the_exact_planners_and_asks_for_learned_ones() {
        let options = PlannerOptions::default();
        let none = |_: &str| -> Result<Learned> { unreachable!("needs no model") };
        let none = &none;
        let fmm = PlannerKind::Fmm.build(&options, none).unwrap();
        assert_eq!(fmm.planner().name(), "fmm");
        assert!(fmm.field_model().is_some());
        let relay = PlannerKind::OctileRelay.build(&options, none).unwrap();
        assert_eq!(relay.planner().name(), "octile+relay");
        let astar = PlannerKind::AStar.build(&options, none).unwrap();
        assert!(astar.field_model().is_none());
        let mut asked = None;
        let field = PlannerKind::Relay.build(&options, |family| -> Result<Learned> {
            asked = Some(family.to_string());
            Ok(Learned::Field(Box::new(Octile)))
        });
        assert_eq!(asked.as_deref(), Some("context"));
        assert!(matches!(field.unwrap(), NamedPlanner::Relay(_)));
        // A field model where a policy is needed is refused.
        let wrong = PlannerKind::Vin.build(&options, |_| -> Result<Learned> {
            Ok(Learned::Field(Box::new(Octile)))
        });
        assert!(wrong.is_err());
    }
}
