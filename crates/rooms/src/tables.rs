//! The room tables' summary: every planner's outcomes gathered over pairs, as Table 3 (per
//! planner over all pairs) and Table 4 (aligned poses per pair kind), in text and JSON.

use crate::harness::{Outcome, PairKind, PlannerKind, Run};
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

/// Every planner's outcomes, by pair kind.
#[derive(Clone, Debug, Default)]
pub struct Tally {
    /// Outcomes by the pair kind's name (so the tables list `sit` before `walk`).
    by_kind: BTreeMap<&'static str, Vec<(PlannerKind, Outcome)>>,
    pairs: usize,
}

impl Tally {
    /// Adds one pair's runs.
    pub fn add(&mut self, kind: PairKind, runs: &[Run]) {
        self.push(kind, runs.iter().map(|r| (r.planner, r.outcome.clone())));
    }

    fn push(&mut self, kind: PairKind, outcomes: impl IntoIterator<Item = (PlannerKind, Outcome)>) {
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
    /// As [`crate::implausible`].
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

    fn of(&self, planner: PlannerKind) -> Vec<&Outcome> {
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
    pub fn table3(&self, planners: &[PlannerKind], line: &mut Value) -> String {
        let mut text = String::new();
        let _ = writeln!(
            text,
            "{:<12} {:>9} {:>10} {:>11} {:>11} {:>11} {:>11}",
            "planner", "reach %", "dist (m)", "s/path", "s/goal", "s/room", "path ratio"
        );
        for &planner in planners {
            let name = planner.name();
            let os = self.of(planner);
            let n = os.len().max(1) as f64;
            let pct =
                |f: fn(&Outcome) -> bool| 100.0 * os.iter().filter(|o| f(o)).count() as f64 / n;
            let m =
                |f: fn(&Outcome) -> f64| finite_mean(&os.iter().map(|o| f(o)).collect::<Vec<_>>());
            let reach = pct(|o| o.reached);
            let (dist, secs, ratio) = (m(|o| o.dist_m), m(|o| o.seconds), m(|o| o.path_ratio));
            let (goal_s, room_s) = (m(|o| o.goal_seconds), m(|o| o.room_seconds));
            line[format!("{name}_reach_pct")] = reach.into();
            if planner.field().is_some() {
                line[format!("{name}_no_route_pct")] = pct(|o| o.no_route).into();
                line[format!("{name}_relaxed_pct")] = pct(|o| o.relaxed).into();
            }
            line[format!("{name}_dist_m")] = dist.into();
            line[format!("{name}_s")] = secs.into();
            let all: Vec<f64> = os.iter().map(|o| o.seconds).collect();
            line[format!("{name}_s_median")] = finite_median(&all).into();
            line[format!("{name}_goal_s")] = goal_s.into();
            line[format!("{name}_room_s")] = room_s.into();
            line[format!("{name}_path_ratio")] = ratio.into();
            line[format!("{name}_support_pct")] = m(|o| o.poses.support).into();
            line[format!("{name}_free_pct")] = m(|o| o.poses.free).into();
            line[format!("{name}_valid_pct")] = m(|o| o.poses.valid).into();
            line[format!("{name}_implausible_pct")] = m(|o| o.poses.implausible).into();
            let _ = writeln!(
                text,
                "{name:<12} {reach:>9.1} {:>10.3} {:>11.5} {:>11.5} {:>11.5} {:>11}",
                dist.unwrap_or(f64::NAN),
                secs.unwrap_or(f64::NAN),
                goal_s.unwrap_or(f64::NAN),
                room_s.unwrap_or(f64::NAN),
                ratio.map_or("-".into(), |r| format!("{r:.3}"))
            );
        }
        text
    }

    /// Table 4 as JSON (`table4_<kind>`: per planner its shares, reach and pair count, and its
    /// path ratio, implausible share and seconds per path (mean and median) and per goal on
    /// that kind of pair) into `line` and as text rows.
    pub fn table4(&self, planners: &[PlannerKind], line: &mut Value) -> String {
        let mut text = String::new();
        for (kind, results) in &self.by_kind {
            let mut per = Map::new();
            for &planner in planners {
                let os: Vec<&Outcome> = results
                    .iter()
                    .filter(|(p, _)| *p == planner)
                    .map(|(_, o)| o)
                    .collect();
                let m = |f: fn(&Outcome) -> f64| {
                    finite_mean(&os.iter().map(|o| f(o)).collect::<Vec<_>>())
                };
                let (s, f, v) = (
                    m(|o| o.poses.support),
                    m(|o| o.poses.free),
                    m(|o| o.poses.valid),
                );
                let reach = m(|o| if o.reached { 100.0 } else { 0.0 });
                let _ = writeln!(
                    text,
                    "{kind:<5} {:<12} {:>6.1} {:>6.1} {:>6.1}  ({} pairs, {:.0}% reached)",
                    planner.name(),
                    s.unwrap_or(f64::NAN),
                    f.unwrap_or(f64::NAN),
                    v.unwrap_or(f64::NAN),
                    os.len(),
                    reach.unwrap_or(f64::NAN)
                );
                let all: Vec<f64> = os.iter().map(|o| o.seconds).collect();
                per.insert(
                    planner.name().into(),
                    json!({
                        "support_pct": s,
                        "free_pct": f,
                        "valid_pct": v,
                        "reach_pct": reach,
                        "pairs": os.len(),
                        "path_ratio": m(|o| o.path_ratio),
                        "implausible_pct": m(|o| o.poses.implausible),
                        "s": m(|o| o.seconds),
                        "s_median": finite_median(&all),
                        "goal_s": m(|o| o.goal_seconds),
                    }),
                );
            }
            line[format!("table4_{kind}")] = per.into();
        }
        text
    }
}
