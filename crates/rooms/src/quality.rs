//! How good a region is: the share of samples that afford a pose, floor and seat coverage,
//! and, on rooms whose furniture is known, what stands where nobody stands
//! ([`implausible`]). The `accessible` example's held-out protocol reports these.

use crate::torsos::seat_torsos;
use crate::{AccessibleRegion, Field3Report, RegionConfig, Result, RoomsError};
use envfield_affordance::{afford_all, Afford};
use envfield_grid::Point3m;
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::{Apartment, ObjectKind, Room, Scene};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The share (percent) of `targets` within `radius` of some point of `samples`; 100 for no
/// targets.
pub fn covered_pct(targets: &[Point3m], samples: &[Point3m], radius: f32) -> f64 {
    if targets.is_empty() {
        return 100.0;
    }
    let r2 = radius * radius;
    let hit = targets
        .par_iter()
        .filter(|t| {
            samples.iter().any(|s| {
                let d = [s[0] - t[0], s[1] - t[1], s[2] - t[2]];
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= r2
            })
        })
        .count();
    100.0 * hit as f64 / targets.len() as f64
}

/// How well a set of torso samples serves a generated room.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionQuality {
    /// Samples drawn.
    pub drawn: usize,
    /// Samples kept by the filter, percent of those drawn.
    pub kept_pct: f64,
    /// Kept samples where some pose is supported and collision-free, percent of those kept.
    pub affordable_pct: f64,
    /// Standing-affordable floor points (10 cm grid) within 0.2 m of a kept sample, percent.
    pub floor_coverage_pct: f64,
    /// Seats whose sitting torso location lies within [`SEAT_NEAR`] of a kept sample,
    /// percent.
    pub seat_coverage_pct: f64,
    /// Seats in the room.
    pub seats: usize,
    /// Seats whose sitting torso location lies within [`SEAT_NEAR`] of an accessible region voxel's
    /// centre, percent: the region keeps only its largest connected set of voxels, so a seat
    /// the samples cover may still be left out of it, and out of every planner's reach.
    #[serde(default)]
    pub region_seat_coverage_pct: f64,
    /// Beds whose lying torso location (the last frame of [`sit_on`](envfield_affordance::sit_on)
    /// on a bed) lies within [`SEAT_NEAR`] of an accessible region voxel's centre, percent
    /// (100 for a room without beds).
    #[serde(default)]
    pub region_bed_coverage_pct: f64,
    /// Beds in the room.
    #[serde(default)]
    pub beds: usize,
    /// Seats (chairs, sofas, beds) with a place where the filter seats or lays a body
    /// ([`seat_places`](crate::torsos::seat_places), 0.1 m apart over the seat's footprint)
    /// within [`SEAT_NEAR`] of an accessible region voxel's centre, percent (100 for none): a
    /// seat judged by its whole surface, not by the one point
    /// [`region_seat_coverage_pct`](Self::region_seat_coverage_pct) judges, which a model's
    /// scanned seat can put off the seat.
    #[serde(default)]
    pub region_seat_places_pct: f64,
    /// The same for beds alone.
    #[serde(default)]
    pub region_bed_places_pct: f64,
    /// Kept samples that [`implausible`] finds on or inside furniture people do not use that
    /// way, percent of those kept.
    pub implausible_pct: f64,
    /// The accessible region's voxels whose centre [`implausible`] finds so, percent.
    pub region_implausible_pct: f64,
    /// The accessible region's voxels.
    pub region_voxels: usize,
}

impl RegionQuality {
    /// The mean of each percentage over `qualities` as JSON (`kept_pct`, `affordable_pct`,
    /// `floor_coverage_pct`, `seat_coverage_pct`), 0 for none.
    pub fn mean_json(qualities: &[RegionQuality]) -> serde_json::Value {
        let n = qualities.len().max(1) as f64;
        let m = |f: fn(&RegionQuality) -> f64| qualities.iter().map(f).sum::<f64>() / n;
        serde_json::json!({
            "kept_pct": m(|x| x.kept_pct),
            "affordable_pct": m(|x| x.affordable_pct),
            "floor_coverage_pct": m(|x| x.floor_coverage_pct),
            "seat_coverage_pct": m(|x| x.seat_coverage_pct),
            "region_seat_coverage_pct": m(|x| x.region_seat_coverage_pct),
            "region_bed_coverage_pct": m(|x| x.region_bed_coverage_pct),
            "region_seat_places_pct": m(|x| x.region_seat_places_pct),
            "region_bed_places_pct": m(|x| x.region_bed_places_pct),
            "implausible_pct": m(|x| x.implausible_pct),
            "region_implausible_pct": m(|x| x.region_implausible_pct),
        })
    }
}

impl RegionQuality {
    /// [`RegionQuality::mean_json`] with the least floor and seat coverage of any room
    /// (`min_floor_coverage_pct`, `min_seat_coverage_pct`).
    pub fn summary_json(qualities: &[RegionQuality]) -> serde_json::Value {
        let least =
            |f: fn(&RegionQuality) -> f64| qualities.iter().map(f).fold(f64::INFINITY, f64::min);
        let mut out = Self::mean_json(qualities);
        out["min_floor_coverage_pct"] = least(|q| q.floor_coverage_pct).into();
        out["min_seat_coverage_pct"] = least(|q| q.seat_coverage_pct).into();
        out["min_region_seat_coverage_pct"] = least(|q| q.region_seat_coverage_pct).into();
        out["min_region_bed_coverage_pct"] = least(|q| q.region_bed_coverage_pct).into();
        out["min_region_seat_places_pct"] = least(|q| q.region_seat_places_pct).into();
        let most = |f: fn(&RegionQuality) -> f64| qualities.iter().map(f).fold(0.0f64, f64::max);
        out["max_implausible_pct"] = most(|q| q.implausible_pct).into();
        out["max_region_implausible_pct"] = most(|q| q.region_implausible_pct).into();
        out
    }
}

/// What drawn torso samples are, before the filter: how many lie in each 0.1 m band of height
/// (keyed by the band's floor, `"0.9"`), and how many fall in each class of what they afford
/// (`"clear:first supported/first valid"`, such as `"true:Some(Standing)/None"`).
///
/// # Errors
/// As [`afford_all`].
pub fn drawn_summary(
    scene: &Scene,
    samples: &[Point3m],
    config: &RegionConfig,
) -> Result<serde_json::Value> {
    Ok(summarise_drawn(
        samples,
        &afford_all(scene, samples, &config.filter)?,
    ))
}

/// [`drawn_summary`] of `samples` whose filter answers (as [`afford_all`] gives them, in
/// order) are `affords`.
pub fn summarise_drawn(samples: &[Point3m], affords: &[Afford]) -> serde_json::Value {
    let mut heights = std::collections::BTreeMap::<i32, usize>::new();
    for s in samples {
        *heights.entry((s[2] * 10.0).floor() as i32).or_default() += 1;
    }
    let heights: serde_json::Map<String, serde_json::Value> = heights
        .into_iter()
        .map(|(k, v)| (format!("{:.1}", k as f32 / 10.0), v.into()))
        .collect();
    let mut kinds = std::collections::BTreeMap::<String, usize>::new();
    for a in affords {
        *kinds
            .entry(format!("{}:{:?}/{:?}", a.clear, a.supported, a.valid))
            .or_default() += 1;
    }
    serde_json::json!({"drawn_by_height_m": heights, "affords_clear_supported_valid": kinds})
}

/// Judges `samples` drawn for `room`: the filter's figures, floor coverage and seat coverage.
///
/// # Errors
/// As [`afford_all`]; [`RoomsError::InvalidInput`] for a room with no standing-affordable floor.
pub fn region_quality(
    room: &Room,
    samples: &[Point3m],
    config: &RegionConfig,
) -> Result<RegionQuality> {
    Ok(judged(room, samples, config)?.0)
}

/// [`region_quality`] with the region it judged (`None` when no sample is kept): the filter
/// asked once, its answers read by both.
fn judged(
    room: &Room,
    samples: &[Point3m],
    config: &RegionConfig,
) -> Result<(RegionQuality, Option<AccessibleRegion>)> {
    let start = std::time::Instant::now();
    let affords = afford_all(&room.scene, samples, &config.filter)?;
    let filter_ms = start.elapsed().as_secs_f64() * 1e3;
    let kept: Vec<Point3m> = affords.iter().filter(|a| a.kept()).map(|a| a.at).collect();
    let mut region = (!kept.is_empty())
        .then(|| AccessibleRegion::from_kept(&room.scene, kept, config))
        .transpose()?;
    if let Some(r) = region.as_mut() {
        r.times.filter_ms = filter_ms;
    }
    Ok((judge_region(room, &affords, region.as_ref())?, region))
}

/// [`region_quality`] of samples whose filter answers (as [`afford_all`] gives them) are
/// `affords` and whose region (made from the kept ones, `None` when none is kept) is
/// `region`: for a caller that has both already.
///
/// # Errors
/// As [`region_quality`].
pub fn judge_region(
    room: &Room,
    affords: &[Afford],
    region: Option<&AccessibleRegion>,
) -> Result<RegionQuality> {
    let kept: Vec<Point3m> = affords.iter().filter(|a| a.kept()).map(|a| a.at).collect();
    let affordable = affords
        .iter()
        .filter(|a| a.kept() && a.valid.is_some())
        .count();
    let floor =
        crate::torsos::standing_floor(&room.scene, [0.0, 0.0, room.size[0], room.size[1]], 0.1)?;
    if floor.is_empty() {
        return Err(RoomsError::InvalidInput(
            "the room has no floor a standing pose is supported on".into(),
        ));
    }
    let seats = seat_torsos(room)?;
    let beds = bed_torsos(room)?;
    let implausible_share = |points: &[Point3m]| -> Result<f64> {
        let bad = points
            .par_iter()
            .map(|&p| implausible(room, p).map(|k| k.is_some()))
            .collect::<Result<Vec<bool>>>()?;
        Ok(100.0 * bad.iter().filter(|&&b| b).count() as f64 / points.len().max(1) as f64)
    };
    let places = crate::torsos::seat_places(room, 0.1)?;
    // The share (percent) of the pieces of `places` (all, or beds) one of whose places lies
    // within SEAT_NEAR of a centre.
    let held = |centres: &[Point3m], beds_only: bool| -> f64 {
        let of: Vec<&Vec<Point3m>> = places
            .iter()
            .filter(|(k, _)| !beds_only || room.furniture[*k].kind == ObjectKind::Bed)
            .map(|(_, p)| p)
            .collect();
        if of.is_empty() {
            return 100.0;
        }
        let hit = of
            .iter()
            .filter(|ps| covered_pct(ps, centres, SEAT_NEAR) > 0.0 && !ps.is_empty())
            .count();
        100.0 * hit as f64 / of.len() as f64
    };
    let (region_seat_places_pct, region_bed_places_pct) = match region {
        None => (0.0, 0.0),
        Some(region) => {
            let centres = region.voxel_centres();
            (held(&centres, false), held(&centres, true))
        }
    };
    let (region_voxels, region_implausible_pct, region_seat_coverage_pct, region_bed_coverage_pct) =
        match region {
            None => (0, 0.0, 0.0, 0.0),
            Some(region) => {
                let centres = region.voxel_centres();
                (
                    centres.len(),
                    implausible_share(&centres)?,
                    covered_pct(&seats, &centres, SEAT_NEAR),
                    covered_pct(&beds, &centres, SEAT_NEAR),
                )
            }
        };
    Ok(RegionQuality {
        implausible_pct: implausible_share(&kept)?,
        region_implausible_pct,
        region_voxels,
        drawn: affords.len(),
        kept_pct: 100.0 * kept.len() as f64 / affords.len().max(1) as f64,
        affordable_pct: if kept.is_empty() {
            0.0
        } else {
            100.0 * affordable as f64 / kept.len() as f64
        },
        floor_coverage_pct: covered_pct(&floor, &kept, 0.2),
        seat_coverage_pct: covered_pct(&seats, &kept, SEAT_NEAR),
        seats: seats.len(),
        region_seat_coverage_pct,
        region_bed_coverage_pct,
        beds: beds.len(),
        region_seat_places_pct,
        region_bed_places_pct,
    })
}

/// The lying torso location of each bed of `room` ([`seat_torsos`] of its beds alone).
fn bed_torsos(room: &Room) -> Result<Vec<Point3m>> {
    let beds = Room {
        scene: Scene::new(),
        size: room.size,
        furniture: room
            .furniture
            .iter()
            .filter(|f| f.kind == ObjectKind::Bed)
            .cloned()
            .collect(),
    };
    seat_torsos(&beds)
}

/// Which rooms of `apartment` the region reaches: a room is reached when an accessible
/// voxel's centre lies over its interior.
pub fn rooms_reached(apartment: &Apartment, region: &AccessibleRegion) -> Vec<bool> {
    let mut reached = vec![false; apartment.rooms.len()];
    for c in region.voxel_centres() {
        if let Some(r) = apartment.room_at(c[0], c[1]) {
            reached[r] = true;
        }
    }
    reached
}

/// How near a seat's seated torso location a sample or region voxel covers it, metres.
pub const SEAT_NEAR: f32 = 0.15;

/// A torso this far above a seat's surface stands on it.
const STANDING_ABOVE: f32 = 0.6;

/// What is implausible about a torso at `p` in `room`, judged by the room's known furniture
/// ([`Room::furniture`]): the kind of the piece it is inside (any furniture but a seat, whose
/// box holds the torso of whoever sits there), or of the first surface straight below it when
/// that is furniture people do not sit or lie on (a table, desk, cabinet, shelf or piano), or
/// a seat it stands on (more than 0.6 m above a surface of the seat at least half its seat
/// height up; over a chair's legs or base a body stands on the floor). `None` when it is
/// plausible: over the floor, or sitting or lying on a bed, sofa or chair.
///
/// The affordance figures cannot see this: a body lying on a table is supported and free of
/// collisions.
///
/// # Errors
/// [`RoomsError::InvalidInput`] for a point that is not finite.
pub fn implausible(room: &Room, p: Point3m) -> Result<Option<ObjectKind>> {
    if !p.iter().all(|v| v.is_finite()) {
        return Err(RoomsError::InvalidInput(format!(
            "torso location {p:?} is not finite"
        )));
    }
    for f in &room.furniture {
        if f.kind.is_seat() {
            continue;
        }
        if f.covers(p[0], p[1]) && p[2] >= 0.0 && p[2] < f.size[2] {
            return Ok(Some(f.kind));
        }
    }
    let below = room
        .scene
        .cast_ray(&Point3::from(p), &-Vector3::z(), p[2].max(0.0) + 1.0)?;
    Ok(below.and_then(|hit| {
        let kind = room.scene.objects()[hit.object].kind;
        // Standing on a seat: high above a surface of it that is at least half the seat's
        // height up (its seat, arms or back), not above its legs or base beside the feet.
        let seat_top = room
            .furniture
            .iter()
            .find(|f| f.object == hit.object)
            .map_or(0.0, |f| f.seat_height.unwrap_or(f.size[2]));
        let stands_on = hit.distance > STANDING_ABOVE && hit.point.z >= SEAT_PART_SHARE * seat_top;
        let wrong = kind.is_furniture() && (!kind.is_seat() || stands_on);
        wrong.then_some(kind)
    }))
}

/// A surface of a seat at least this share of its seat height up counts as one a body could
/// stand on; lower parts (legs, a base, a stretcher) stand on the floor between the feet.
const SEAT_PART_SHARE: f32 = 0.5;

/// Uniform samples in the room's box (interior, floor to wall top): the no-learning control.
pub fn uniform_in_room(room: &Room, height: f32, n: usize, seed: u64) -> Vec<Point3m> {
    let mut rng = envfield_grid::SplitMix64::new(seed ^ 0x0F1F);
    (0..n)
        .map(|_| {
            [
                rng.next_f32() * room.size[0],
                rng.next_f32() * room.size[1],
                rng.next_f32() * height,
            ]
        })
        .collect()
}

/// The held-out protocol of the region table (the `accessible` example's `--rooms`): each
/// room judged three ways on the same furniture, ours (the trained VAE's samples), its
/// untrained twin's samples and uniform samples in the room's box (the controls), with the
/// learned field's report on the first rooms. Rooms are added in order of seed.
#[derive(Clone, Debug, Default)]
pub struct HeldOut {
    /// Ours, a room each.
    pub ours: Vec<RegionQuality>,
    /// The untrained twin's samples.
    pub untrained: Vec<RegionQuality>,
    /// Uniform samples in the room's box.
    pub uniform: Vec<RegionQuality>,
    /// The learned field's reports ([`HeldOut::add_field`]).
    pub fields: Vec<Field3Report>,
}

impl HeldOut {
    /// Judges `room`: ours from `drawn` (filtered once; the region and its quality read the
    /// same answers), the controls from `twin` and `uniform` ([`uniform_in_room`]). Returns
    /// ours' region (`None` when no sample is kept), for a learned field to be trained on.
    ///
    /// # Errors
    /// As [`region_quality`].
    pub fn add(
        &mut self,
        room: &Room,
        drawn: &[Point3m],
        twin: &[Point3m],
        uniform: &[Point3m],
        config: &RegionConfig,
    ) -> Result<Option<AccessibleRegion>> {
        let (ours, region) = judged(room, drawn, config)?;
        self.ours.push(ours);
        self.untrained.push(region_quality(room, twin, config)?);
        self.uniform.push(region_quality(room, uniform, config)?);
        Ok(region)
    }

    /// Adds a room's learned-field report.
    pub fn add_field(&mut self, report: Field3Report) {
        self.fields.push(report);
    }

    /// The table's line: ours' means, least coverage and most implausibility
    /// ([`RegionQuality::summary_json`]), the controls' means (`untrained_vae`,
    /// `uniform_box`), ours per room (seeds from `first_seed`), and the learned fields'
    /// summary ([`Field3Report::summary_json`]).
    pub fn summary_json(&self, first_seed: u64) -> serde_json::Value {
        let per_room: Vec<_> = self
            .ours
            .iter()
            .zip(first_seed..)
            .map(|(q, seed)| serde_json::json!({"seed": seed, "quality": q}))
            .collect();
        let mut line = serde_json::json!({
            "untrained_vae": RegionQuality::mean_json(&self.untrained),
            "uniform_box": RegionQuality::mean_json(&self.uniform),
            "per_room": per_room,
        });
        let parts = [
            RegionQuality::summary_json(&self.ours),
            Field3Report::summary_json(&self.fields),
        ];
        for part in parts.iter().filter_map(|p| p.as_object()) {
            for (k, v) in part {
                line[k] = v.clone();
            }
        }
        line
    }
}
