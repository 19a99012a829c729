//! The room navigation harness (paper Tables 3 and 4): the planners by name
//! ([`RoomPlanner`]), the walking, sit-down and lie-down pairs ([`pairs()`]), one run of every planner on
//! a pair with its poses fitted and checked ([`run_pair`], [`fit`]). `room_nav`, `level` and the
//! `room_planning` bench all run it; [`crate::tables`] sums it up.
//!
//! Each planner's work is split as a navigation mesh splits it, and timed so: once per room
//! ([`RoomContext`]: the scene's distance grid ours' pose checks read, a navigation mesh's
//! build), once per goal (the exact field's fast marching, the learned field's one batched
//! pass over the region), and per path (the search, whose steps are lookups).

mod pairs;
mod planner;
mod run;
mod scoring;

pub use pairs::{pairs, standing_places, Pair, PairKind, PairOptions, LIE_APART, SEAT_APART};
pub use planner::{
    learned_table, FieldKind, FloorPlanner, PairSetup, RoomPlanner, EXACT_BAND, NEAR_STALL,
    PIN_RADIUS,
};
pub use run::{run_pair, RoomContext, RunSettings};
pub use scoring::{fit, Outcome, PoseShares, Run};
