//! The room tables' summary: every planner's outcomes gathered over pairs, as Table 3 (per
//! planner over all pairs) and Table 4 (aligned poses per pair kind), in text and JSON.

use crate::harness::{Outcome, PairKind, RoomPlanner, Run};
use envfield_scene::Room;
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;
use std::fmt::Write;

/// The mean of the finite values, `None` for none.
pub fn finite_mean(v: &[f64]) -> Option<f64> {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    (!f.is_empty()).then(|| f.iter().sum::<f64>() / f.len() as f64)
}

/// The median of the finite values, `None` for none.
pub fn finite_median(v: &[f64]) -> Option<f64> {
    let mut f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    f.sort_by(f64::total_cmp);
    let n = f.len();
    (n > 0).then(|| (f[(n - 1) / 2] + f[n / 2]) / 2.0)
}

/// One planner's outcomes on a set of pairs, summed up: what Table 3 gives over all pairs and
/// Table 4 per kind of pair.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlannerSummary {
    /// Pairs.
    pub pairs: usize,
    /// Percent of the pairs reached (`None` for no pair).
    pub reach_pct: Option<f64>,
    /// Percent whose strict search opened every allowed point.
    pub no_route_pct: Option<f64>,
    /// Percent that took the fallback.
    pub relaxed_pct: Option<f64>,
    /// Mean distance from the path's end to the goal, metres.
    pub dist_m: Option<f64>,
    /// Mean seconds per path.
    pub s: Option<f64>,
    /// Median seconds per path.
    pub s_median: Option<f64>,
    /// Mean seconds of per-goal work.
    pub goal_s: Option<f64>,
    /// Mean seconds of per-room work.
    pub room_s: Option<f64>,
    /// Mean path ratio of the pairs reached.
    pub path_ratio: Option<f64>,
    /// Mean shares of the poses supported, collision-free, valid and implausible, percent.
    pub support_pct: Option<f64>,
    /// See [`PlannerSummary::support_pct`].
    pub free_pct: Option<f64>,
    /// See [`PlannerSummary::support_pct`].
    pub valid_pct: Option<f64>,
    /// See [`PlannerSummary::support_pct`] (`None` where the furniture is unknown).
    pub implausible_pct: Option<f64>,
}

impl PlannerSummary {
    /// The summary of `outcomes`.
    pub fn of(outcomes: &[&Outcome]) -> Self {
        let m = |f: &dyn Fn(&Outcome) -> f64| {
            finite_mean(&outcomes.iter().map(|o| f(o)).collect::<Vec<_>>())
        };
        let pct = |f: &dyn Fn(&Outcome) -> bool| m(&|o| if f(o) { 100.0 } else { 0.0 });
        let seconds: Vec<f64> = outcomes.iter().map(|o| o.seconds).collect();
        Self {
            pairs: outcomes.len(),
            reach_pct: pct(&|o| o.reached),
            no_route_pct: pct(&|o| o.no_route),
            relaxed_pct: pct(&|o| o.relaxed),
            dist_m: m(&|o| o.dist_m),
            s: m(&|o| o.seconds),
            s_median: finite_median(&seconds),
            goal_s: m(&|o| o.goal_seconds),
            room_s: m(&|o| o.room_seconds),
            path_ratio: m(&|o| o.path_ratio),
            support_pct: m(&|o| o.poses.support),
            free_pct: m(&|o| o.poses.free),
            valid_pct: m(&|o| o.poses.valid),
            implausible_pct: m(&|o| o.poses.implausible),
        }
    }
}

/// Every planner's outcomes, by pair kind.
#[derive(Clone, Debug, Default)]
pub struct Tally {
    /// Outcomes by the pair kind's name (so the tables list `sit` before `walk`).
    by_kind: BTreeMap<&'static str, Vec<(RoomPlanner, Outcome)>>,
    pairs: usize,
}

impl Tally {
    /// Adds one pair's runs.
    pub fn add(&mut self, kind: PairKind, runs: &[Run]) {
        self.push(kind, runs.iter().map(|r| (r.planner, r.outcome.clone())));
    }

    fn push(&mut self, kind: PairKind, outcomes: impl IntoIterator<Item = (RoomPlanner, Outcome)>) {
        self.by_kind
            .entry(kind.name())
            .or_default()
            .extend(outcomes);
        self.pairs += 1;
    }

    /// Adds one pair's runs in a room whose furniture is known, each path's poses judged for
    /// plausibility ([`PoseShares::judge`](crate::harness::PoseShares::judge)).
    ///
    /// # Errors
    /// As [`crate::quality::implausible`].
    pub fn add_in(&mut self, kind: PairKind, runs: &[Run], room: &Room) -> crate::Result<()> {
        let mut judged = Vec::with_capacity(runs.len());
        for r in runs {
            let mut outcome = r.outcome.clone();
            outcome.poses.judge(&r.poses, room)?;
            judged.push((r.planner, outcome));
        }
        self.push(kind, judged);
        Ok(())
    }

    /// Pairs added.
    pub fn pairs(&self) -> usize {
        self.pairs
    }

    fn of(&self, planner: RoomPlanner) -> Vec<&Outcome> {
        self.by_kind
            .values()
            .flatten()
            .filter(|(p, _)| *p == planner)
            .map(|(_, o)| o)
            .collect()
    }

    /// Table 3 as JSON keys into `line` (`<planner>_reach_pct`, `_dist_m`, `_s` (per path, and
    /// `_s_median`), `_goal_s` (per goal), `_room_s` (per room), `_path_ratio`, `_support_pct`,
    /// `_free_pct`, `_valid_pct`, `_implausible_pct` (null where the furniture is unknown), and
    /// for ours `_no_route_pct` and `_relaxed_pct`) and as
    /// text rows.
    pub fn table3(&self, planners: &[RoomPlanner], line: &mut Value) -> String {
        let mut text = String::new();
        let _ = writeln!(
            text,
            "{:<12} {:>9} {:>10} {:>11} {:>11} {:>11} {:>11}",
            "planner", "reach %", "dist (m)", "s/path", "s/goal", "s/room", "path ratio"
        );
        for &planner in planners {
            let name = planner.name();
            let sum = PlannerSummary::of(&self.of(planner));
            // A planner left out of every room (the navigation mesh of a scene Recast could
            // not build) ran no pair: no figure, rather than a 0% it never earned.
            let Some(reach) = sum.reach_pct else {
                line[format!("{name}_reach_pct")] = Value::Null;
                let _ = writeln!(text, "{name:<12} left out: it ran on no pair");
                continue;
            };
            line[format!("{name}_reach_pct")] = reach.into();
            if planner.field().is_some() {
                line[format!("{name}_no_route_pct")] = sum.no_route_pct.unwrap_or(0.0).into();
                line[format!("{name}_relaxed_pct")] = sum.relaxed_pct.unwrap_or(0.0).into();
            }
            line[format!("{name}_dist_m")] = sum.dist_m.into();
            line[format!("{name}_s")] = sum.s.into();
            line[format!("{name}_s_median")] = sum.s_median.into();
            line[format!("{name}_goal_s")] = sum.goal_s.into();
            line[format!("{name}_room_s")] = sum.room_s.into();
            line[format!("{name}_path_ratio")] = sum.path_ratio.into();
            line[format!("{name}_support_pct")] = sum.support_pct.into();
            line[format!("{name}_free_pct")] = sum.free_pct.into();
            line[format!("{name}_valid_pct")] = sum.valid_pct.into();
            line[format!("{name}_implausible_pct")] = sum.implausible_pct.into();
            let _ = writeln!(
                text,
                "{name:<12} {reach:>9.1} {:>10.3} {:>11.5} {:>11.5} {:>11.5} {:>11}",
                sum.dist_m.unwrap_or(f64::NAN),
                sum.s.unwrap_or(f64::NAN),
                sum.goal_s.unwrap_or(f64::NAN),
                sum.room_s.unwrap_or(f64::NAN),
                sum.path_ratio.map_or("-".into(), |r| format!("{r:.3}"))
            );
        }
        text
    }

    /// Table 4 as JSON (`table4_<kind>`: per planner its shares, reach and pair count, and its
    /// path ratio, implausible share and seconds per path (mean and median) and per goal on
    /// that kind of pair) into `line` and as text rows.
    pub fn table4(&self, planners: &[RoomPlanner], line: &mut Value) -> String {
        let mut text = String::new();
        for (kind, results) in &self.by_kind {
            let mut per = Map::new();
            for &planner in planners {
                let os: Vec<&Outcome> = results
                    .iter()
                    .filter(|(p, _)| *p == planner)
                    .map(|(_, o)| o)
                    .collect();
                let sum = PlannerSummary::of(&os);
                let _ = writeln!(
                    text,
                    "{kind:<5} {:<12} {:>6.1} {:>6.1} {:>6.1}  ({} pairs, {:.0}% reached)",
                    planner.name(),
                    sum.support_pct.unwrap_or(f64::NAN),
                    sum.free_pct.unwrap_or(f64::NAN),
                    sum.valid_pct.unwrap_or(f64::NAN),
                    sum.pairs,
                    sum.reach_pct.unwrap_or(f64::NAN)
                );
                per.insert(
                    planner.name().into(),
                    json!({
                        "support_pct": sum.support_pct,
                        "free_pct": sum.free_pct,
                        "valid_pct": sum.valid_pct,
                        "reach_pct": sum.reach_pct,
                        "pairs": sum.pairs,
                        "path_ratio": sum.path_ratio,
                        "implausible_pct": sum.implausible_pct,
                        "s": sum.s,
                        "s_median": sum.s_median,
                        "goal_s": sum.goal_s,
                    }),
                );
            }
            line[format!("table4_{kind}")] = per.into();
        }
        text
    }
}

/// Puts the mean over rooms of each of `per_room`'s byte counts ([`RoomContext::bytes`]
/// of each room) into `line` as `<name>_per_room`.
///
/// [`RoomContext::bytes`]: crate::harness::RoomContext::bytes
pub fn mean_bytes(per_room: &[[(&'static str, usize); 6]], line: &mut Value) {
    for (j, (name, _)) in per_room.first().into_iter().flatten().enumerate() {
        let v: Vec<f64> = per_room.iter().map(|m| m[j].1 as f64).collect();
        line[format!("{name}_per_room")] = finite_mean(&v).into();
    }
}
