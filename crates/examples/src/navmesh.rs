//! The navigation-mesh baseline of the room tables: Recast's pipeline in Rust (`rerecast`) builds
//! a navigation mesh of the scene's floor for a body of the gait's radius and height, and
//! Polyanya (`polyanya`, any-angle shortest paths on a navigation mesh) answers each path. The
//! crates are the example's and the bench's, not the library's: the library sees a
//! [`FloorPlanner`].
//!
//! Recast is y up; the scene is z up. A point `(x, y, z)` of the scene is `(x, z, -y)` in
//! Recast's frame (a rotation, so triangles keep their winding) and `(x, -y)` on Polyanya's
//! plane. Recast makes every flat top a body fits on walkable (a bed, a table); the pairs walk
//! on the floor, so only the floor's triangles are walkable here and the rest are obstacles.

use envfield_affordance::PoseSequence;
use envfield_grid::Point3m;
use envfield_rooms::harness::FloorPlanner;
use envfield_rooms::{Result as RoomsResult, RoomsError};
use envfield_scene::Scene;
use glam::{UVec3, Vec2, Vec3, Vec3A};
use rerecast::{AreaType, BuildContoursFlags, DetailNavmesh, HeightfieldBuilder, TriMesh};
use std::time::Instant;

/// The body and the build's settings, in metres.
#[derive(Clone, Copy, Debug)]
pub struct NavmeshConfig {
    /// The body's radius: how far the navigation mesh keeps from obstacles.
    pub radius: f32,
    /// The body's height: the headroom a walkable place needs.
    pub height: f32,
    /// The step a body climbs.
    pub climb: f32,
    /// Recast's cell on the floor plane.
    pub cell: f32,
}

impl NavmeshConfig {
    /// A walking body: its half-width (the largest sideways reach of any joint from the torso,
    /// across the direction it faces, over the gait's frames; a gap that wide lets it through,
    /// as the region's own joint checks do), and its tallest frame; climb 0.1 m; cells a third
    /// of the radius.
    pub fn for_gait(gait: &PoseSequence) -> Self {
        let (mut radius, mut height) = (0f32, 0f32);
        for frame in &gait.frames {
            let torso = frame.torso();
            let f = frame.facing();
            let norm = f.x.hypot(f.y).max(1e-6);
            let lowest = frame
                .joints
                .iter()
                .map(|j| j.z)
                .fold(f32::INFINITY, f32::min);
            for j in &frame.joints {
                let (dx, dy) = (j.x - torso.x, j.y - torso.y);
                radius = radius.max((f.x * dy - f.y * dx).abs() / norm);
                height = height.max(j.z - lowest);
            }
        }
        Self {
            radius,
            height,
            climb: 0.1,
            cell: radius / 3.0,
        }
    }
}

/// A navigation mesh of a scene's floor, ready for path queries.
pub struct Navmesh {
    mesh: polyanya::Mesh,
    /// Polygons and vertices of the Polyanya mesh (its size).
    pub polygons: usize,
    /// Vertices of the Polyanya mesh.
    pub vertices: usize,
    /// Seconds the build took, Recast's pipeline and Polyanya's import together.
    pub build_s: f64,
}

fn failed(stage: &str, e: impl std::fmt::Debug) -> RoomsError {
    RoomsError::InvalidInput(format!("navigation mesh: {stage} failed: {e:?}"))
}

impl Navmesh {
    /// Builds the navigation mesh of `scene` (floor at z = 0) for the body of `config`.
    ///
    /// # Errors
    /// [`RoomsError::InvalidInput`] naming the stage of Recast's pipeline that failed (a
    /// scene with no triangles, a floor too small for the body).
    pub fn build(scene: &Scene, config: &NavmeshConfig) -> RoomsResult<Self> {
        let t = Instant::now();
        let source = scene.to_mesh();
        // Walkable: flat within 45 degrees and lying on the floor, whichever way it is wound
        // (some exporters wind every face the other way; a floor slab's underside merges into
        // the span of its top, and a piece of furniture's into its own top, never walkable).
        let area_types = source
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| source.vertices[i as usize]);
                let n = (b - a).cross(&(c - a));
                let up = n.z.abs() >= n.norm() * std::f32::consts::FRAC_1_SQRT_2;
                let low = a.z.max(b.z).max(c.z) <= config.climb;
                if up && low {
                    AreaType::DEFAULT_WALKABLE
                } else {
                    AreaType::NOT_WALKABLE
                }
            })
            .collect();
        let trimesh = TriMesh {
            vertices: source
                .vertices
                .iter()
                .map(|p| Vec3A::new(p.x, p.z, -p.y))
                .collect(),
            indices: source
                .triangles
                .iter()
                .map(|t| UVec3::new(t[0], t[1], t[2]))
                .collect(),
            area_types,
        };
        let aabb = trimesh
            .compute_aabb()
            .ok_or_else(|| failed("reading the scene", "no triangles"))?;
        let (cs, ch) = (config.cell, config.cell / 2.0);
        let walkable_height = (config.height / ch).ceil() as u16;
        let walkable_climb = (config.climb / ch).floor() as u16;
        let walkable_radius = (config.radius / cs).ceil() as u16;
        let mut heightfield = HeightfieldBuilder {
            aabb,
            cell_size: cs,
            cell_height: ch,
        }
        .build()
        .map_err(|e| failed("the heightfield", e))?;
        heightfield
            .populate_from_trimesh(trimesh, walkable_height, walkable_climb)
            .map_err(|e| failed("rasterising", e))?;
        let mut compact = heightfield
            .into_compact(walkable_height, walkable_climb)
            .map_err(|e| failed("compacting", e))?;
        compact.erode_walkable_area(walkable_radius);
        compact.build_distance_field();
        // Recast's defaults: regions of at least 8 x 8 cells, merged below 20 x 20.
        compact
            .build_regions(0, 64, 400)
            .map_err(|e| failed("the regions", e))?;
        let contours = compact.build_contours(1.3, 12, BuildContoursFlags::default());
        let polygons = contours
            .into_polygon_mesh(6)
            .map_err(|e| failed("the polygons", e))?;
        let detail = DetailNavmesh::new(&polygons, &compact, 6.0 * cs, ch)
            .map_err(|e| failed("the detail mesh", e))?;
        let mut mesh: polyanya::Mesh = detail.try_into().map_err(|e| failed("Polyanya", e))?;
        // A start within 0.3 m of the mesh is moved onto it.
        mesh.search_delta = 0.05;
        mesh.search_steps = 6;
        let (polygons, vertices) = mesh.layers.iter().fold((0, 0), |(p, v), l| {
            (p + l.polygons.len(), v + l.vertices.len())
        });
        Ok(Self {
            mesh,
            polygons,
            vertices,
            build_s: t.elapsed().as_secs_f64(),
        })
    }
}

impl Navmesh {
    /// The room's navigation mesh for the walking body of `gait`, its size and build time
    /// printed, or `None` (said, with the reason) where Recast builds none.
    pub fn for_room(scene: &Scene, gait: &PoseSequence, seed: u64) -> Option<Self> {
        match Self::build(scene, &NavmeshConfig::for_gait(gait)) {
            Ok(m) => {
                eprintln!(
                    "room {seed}: navigation mesh of {} polygons, {} vertices, {:.1} ms",
                    m.polygons,
                    m.vertices,
                    1e3 * m.build_s
                );
                Some(m)
            }
            Err(e) => {
                eprintln!("room {seed}: no navigation mesh, its row is left out: {e}");
                None
            }
        }
    }
}

impl FloorPlanner for Navmesh {
    /// Polyanya's shortest path on the floor plane, its corners lifted to the torso's height
    /// (from the start's to the goal's along the path), the start and goal at its ends.
    fn floor_path(&self, start: Point3m, goal: Point3m) -> RoomsResult<Option<Vec<Point3m>>> {
        let plane = |p: Point3m| Vec2::new(p[0], -p[1]);
        let Some(path) = self.mesh.path(plane(start), plane(goal)) else {
            return Ok(None);
        };
        let mut corners = vec![Vec3::new(start[0], start[1], 0.0)];
        corners.extend(path.path.iter().map(|c| Vec3::new(c.x, -c.y, 0.0)));
        let total: f32 = corners.windows(2).map(|w| w[0].distance(w[1])).sum();
        let mut along = 0.0;
        let mut out = vec![start];
        for w in corners.windows(2) {
            along += w[0].distance(w[1]);
            let t = if total > 0.0 { along / total } else { 1.0 };
            out.push([w[1].x, w[1].y, start[2] + t * (goal[2] - start[2])]);
        }
        // Polyanya ends on the goal's projection (or the nearest point of the mesh to it).
        if let Some(last) = out.last_mut() {
            if (last[0] - goal[0]).hypot(last[1] - goal[1]) < 1e-3 {
                *last = goal;
            }
        }
        Ok(Some(out))
    }

    /// Vertices (2D position, height, neighbour list) and polygons (vertex and neighbour
    /// lists) of the Polyanya mesh, counted at their in-memory sizes; Polyanya's baked lookup
    /// structures are left out, so this is a lower bound.
    fn bytes(&self) -> usize {
        let v = self.mesh.layers.iter().map(|l| {
            l.vertices
                .iter()
                .map(|x| 12 + 4 * x.polygons.len())
                .sum::<usize>()
                + l.polygons
                    .iter()
                    .map(|p| 8 + 4 * p.vertices.len())
                    .sum::<usize>()
        });
        v.sum()
    }
}
