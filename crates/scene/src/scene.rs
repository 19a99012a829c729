//! The signed-distance scene: objects made of parts (primitives or triangle meshes) at poses.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::query::{PointQuery, Ray, RayCast};
use parry3d::shape::{Ball, Capsule, Cuboid, Cylinder, SharedShape, TriMesh, TriMeshFlags};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{check_point, Result, SceneError};
use crate::mesh::TriangleMesh;
use crate::solid::Occupancy;

/// A solid primitive in its local frame: centred at the origin, axis along local z (z up).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Primitive {
    /// A box with these half extents along x, y, z.
    Cuboid {
        /// Half extents in metres.
        half_extents: [f32; 3],
    },
    /// A sphere.
    Ball {
        /// Radius in metres.
        radius: f32,
    },
    /// A capsule: the segment from `-half_height` to `+half_height` on z, inflated by `radius`.
    Capsule {
        /// Half the length of the inner segment.
        half_height: f32,
        /// Radius.
        radius: f32,
    },
    /// A cylinder along z from `-half_height` to `+half_height`.
    Cylinder {
        /// Half its height.
        half_height: f32,
        /// Radius.
        radius: f32,
    },
}

impl Primitive {
    /// A box from its full size `[x, y, z]` in metres.
    pub fn cuboid(size: [f32; 3]) -> Self {
        Primitive::Cuboid {
            half_extents: [size[0] / 2.0, size[1] / 2.0, size[2] / 2.0],
        }
    }

    fn check(&self) -> Result<()> {
        let (what, values): (&str, Vec<f32>) = match *self {
            Primitive::Cuboid { half_extents } => ("cuboid half extents", half_extents.to_vec()),
            Primitive::Ball { radius } => ("ball radius", vec![radius]),
            Primitive::Capsule {
                half_height,
                radius,
            } => ("capsule half height and radius", vec![half_height, radius]),
            Primitive::Cylinder {
                half_height,
                radius,
            } => ("cylinder half height and radius", vec![half_height, radius]),
        };
        let ok = match self {
            // A capsule's segment may have zero length (a ball).
            Primitive::Capsule {
                half_height,
                radius,
            } => {
                half_height.is_finite()
                    && *half_height >= 0.0
                    && radius.is_finite()
                    && *radius > 0.0
            }
            _ => values.iter().all(|v| v.is_finite() && *v > 0.0),
        };
        if ok {
            Ok(())
        } else {
            Err(SceneError::InvalidGeometry(format!(
                "{what} must be finite and positive, got {values:?}"
            )))
        }
    }

    /// The parry3d shape and the rotation that takes parry's y-axis shapes to our z axis.
    fn to_parry(self) -> (SharedShape, Option<UnitQuaternion<f32>>) {
        // parry's cylinders are along y; a quarter turn about x maps local y to z.
        let y_to_z =
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f32::consts::FRAC_PI_2);
        match self {
            Primitive::Cuboid { half_extents } => (
                SharedShape::new(Cuboid::new(Vector3::from(half_extents))),
                None,
            ),
            Primitive::Ball { radius } => (SharedShape::new(Ball::new(radius)), None),
            Primitive::Capsule {
                half_height,
                radius,
            } => (SharedShape::new(Capsule::new_z(half_height, radius)), None),
            Primitive::Cylinder {
                half_height,
                radius,
            } => (
                SharedShape::new(Cylinder::new(half_height, radius)),
                Some(y_to_z),
            ),
        }
    }
}

/// What an object is; furniture kinds tell planners what a person can do there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectKind {
    /// The walkable floor.
    Floor,
    /// A wall.
    Wall,
    /// A bed (lie on it, sit on its edge).
    Bed,
    /// A sofa (sit or lie).
    Sofa,
    /// A chair (sit).
    Chair,
    /// A table (walk around).
    Table,
    /// A desk (walk around).
    Desk,
    /// A cabinet, chest, dresser, kitchen unit or TV unit (walk around).
    Cabinet,
    /// A bookcase or wardrobe: tall, often hollow (walk around).
    Shelf,
    /// A piano (walk around, sit on its stool).
    Piano,
    /// A loaded triangle mesh (for example a scanned room).
    Mesh,
    /// Anything else.
    Other,
}

impl ObjectKind {
    /// Whether people sit or lie on it (beds, sofas, chairs): standing on it, or sitting or
    /// lying on any other furniture, is implausible.
    pub fn is_seat(self) -> bool {
        matches!(self, Self::Bed | Self::Sofa | Self::Chair)
    }

    /// Whether it is furniture (not the floor, a wall, a whole mesh or unknown).
    pub fn is_furniture(self) -> bool {
        !matches!(self, Self::Floor | Self::Wall | Self::Mesh | Self::Other)
    }
}

/// One solid piece of an object, placed in the world.
#[derive(Clone)]
pub struct Part {
    shape: SharedShape,
    pose: Isometry3<f32>,
    aabb: Aabb,
    /// The primitive it was made from (`None` for a mesh).
    pub primitive: Option<Primitive>,
    /// A mesh's inside, from its shape rather than its normals (see [`Part::mesh`]).
    /// Made on the first query: reading a large scene costs nothing until it is asked.
    occupancy: Option<std::sync::Arc<std::sync::OnceLock<Occupancy>>>,
}

impl std::fmt::Debug for Part {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Part")
            .field("primitive", &self.primitive)
            .field("pose", &self.pose)
            .field("aabb", &self.aabb)
            .finish()
    }
}

impl Part {
    /// A primitive at `pose` (the pose of its local frame in the world).
    ///
    /// # Errors
    /// [`SceneError::InvalidGeometry`] for non-finite or non-positive sizes or a non-finite pose.
    pub fn primitive(primitive: Primitive, pose: Isometry3<f32>) -> Result<Self> {
        primitive.check()?;
        check_pose(&pose)?;
        let (shape, fix) = primitive.to_parry();
        let pose = match fix {
            Some(rot) => pose * Isometry3::from_parts(Translation3::identity(), rot),
            None => pose,
        };
        Ok(Self::from_shape(shape, pose, Some(primitive)))
    }

    /// A triangle mesh (already in world coordinates) as it comes: closed or open, in one
    /// piece or many, wound either way. The distance is to the nearest triangle; its sign
    /// ignores the normals. A point is inside when air cannot reach it from outside the mesh's
    /// box without crossing the surface (a lattice of cells of 1 cm or more; the crate's
    /// `solid` module): the solid of a closed carcass or of overlapping boxes, a closed
    /// cabinet's hollow. Open shells (a table top modelled as one sheet, a scan) enclose
    /// nothing and stay thin obstacles. An enclosed cavity that spans the mesh like a room (a
    /// room read with its ceiling) is air. Within a cell of the surface the distance is
    /// unsigned.
    ///
    /// # Errors
    /// [`SceneError::EmptyMesh`] / [`SceneError::InvalidGeometry`] from [`TriangleMesh::validate`].
    pub fn mesh(mesh: &TriangleMesh) -> Result<Self> {
        mesh.validate("mesh")?;
        let trimesh = TriMesh::with_flags(
            mesh.vertices.clone(),
            mesh.triangles.clone(),
            TriMeshFlags::MERGE_DUPLICATE_VERTICES,
        )
        .map_err(|e| SceneError::InvalidGeometry(format!("mesh: {e}")))?;
        let mut part = Self::from_shape(SharedShape::new(trimesh), Isometry3::identity(), None);
        part.occupancy = Some(std::sync::Arc::new(std::sync::OnceLock::new()));
        Ok(part)
    }

    fn from_shape(shape: SharedShape, pose: Isometry3<f32>, primitive: Option<Primitive>) -> Self {
        let aabb = shape.compute_aabb(&pose);
        Self {
            shape,
            pose,
            aabb,
            primitive,
            occupancy: None,
        }
    }

    /// For a mesh: the share of its box's cells that are inside, the cell side, and how many
    /// enclosed cavities were taken as rooms (see [`Part::mesh`]). `None` for a primitive.
    pub fn mesh_solidity(&self) -> Option<(f32, f32, usize)> {
        let o = self.occupancy()?;
        Some((o.inside_share(), o.cell(), o.rooms))
    }

    /// A mesh's occupancy, made on first use from the mesh parry3d holds.
    fn occupancy(&self) -> Option<&Occupancy> {
        let lock = self.occupancy.as_ref()?;
        let mesh = self.shape.as_trimesh()?;
        Some(lock.get_or_init(|| {
            Occupancy::of(&TriangleMesh {
                vertices: mesh.vertices().to_vec(),
                triangles: mesh.indices().to_vec(),
            })
        }))
    }

    /// Its world-space bounding box.
    pub fn aabb(&self) -> &Aabb {
        &self.aabb
    }

    /// The pose of the parry3d shape (for cylinders this includes the y-to-z quarter turn).
    pub fn pose(&self) -> &Isometry3<f32> {
        &self.pose
    }

    /// The parry3d shape, for queries this crate does not wrap.
    pub fn shape(&self) -> &SharedShape {
        &self.shape
    }

    /// Signed distance from `p` to this part (negative inside), and the projection.
    #[inline]
    fn signed_distance(&self, p: &Point3<f32>) -> (f32, Point3<f32>) {
        if let Some(occupancy) = self.occupancy() {
            let proj = self.shape.project_point(&self.pose, p, false);
            let d = nalgebra::distance(p, &proj.point);
            let local = self.pose.inverse_transform_point(p);
            return (if occupancy.inside(&local) { -d } else { d }, proj.point);
        }
        let proj = self.shape.project_point(&self.pose, p, false);
        let d = nalgebra::distance(p, &proj.point);
        (if proj.is_inside { -d } else { d }, proj.point)
    }

    /// Its surface as triangles in world coordinates.
    pub fn to_mesh(&self) -> TriangleMesh {
        let (vertices, triangles) = if let Some(c) = self.shape.as_cuboid() {
            c.to_trimesh()
        } else if let Some(b) = self.shape.as_ball() {
            b.to_trimesh(16, 8)
        } else if let Some(c) = self.shape.as_capsule() {
            c.to_trimesh(16, 8)
        } else if let Some(c) = self.shape.as_cylinder() {
            c.to_trimesh(24)
        } else if let Some(m) = self.shape.as_trimesh() {
            (m.vertices().to_vec(), m.indices().to_vec())
        } else {
            (Vec::new(), Vec::new())
        };
        TriangleMesh {
            vertices: vertices.iter().map(|v| self.pose * v).collect(),
            triangles,
        }
    }
}

fn check_pose(pose: &Isometry3<f32>) -> Result<()> {
    let t = pose.translation.vector;
    let q = pose.rotation.coords;
    if t.iter().chain(q.iter()).all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::InvalidGeometry(format!(
            "pose is not finite: {pose:?}"
        )))
    }
}

/// A named object: one or more parts (a table is a top and four legs).
#[derive(Clone, Debug)]
pub struct SceneObject {
    /// A name for reports and exports.
    pub name: String,
    /// What it is.
    pub kind: ObjectKind,
    parts: Vec<Part>,
    aabb: Option<Aabb>,
}

impl SceneObject {
    /// An object with no parts yet.
    pub fn new(name: impl Into<String>, kind: ObjectKind) -> Self {
        Self {
            name: name.into(),
            kind,
            parts: Vec::new(),
            aabb: None,
        }
    }

    /// Adds a part.
    pub fn push(&mut self, part: Part) {
        self.aabb = Some(match self.aabb {
            Some(a) => a.merged(&part.aabb),
            None => part.aabb,
        });
        self.parts.push(part);
    }

    /// Adds a primitive at `pose` and returns `self` (builder style).
    ///
    /// # Errors
    /// As [`Part::primitive`].
    pub fn with(mut self, primitive: Primitive, pose: Isometry3<f32>) -> Result<Self> {
        self.push(Part::primitive(primitive, pose)?);
        Ok(self)
    }

    /// Its parts.
    pub fn parts(&self) -> &[Part] {
        &self.parts
    }

    /// Its bounding box (`None` without parts).
    pub fn aabb(&self) -> Option<&Aabb> {
        self.aabb.as_ref()
    }
}

/// The nearest surface point to a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The point on the surface.
    pub point: Point3<f32>,
    /// The outward unit normal there.
    pub normal: Vector3<f32>,
    /// Signed distance of the query (negative inside).
    pub signed_distance: f32,
    /// Index of the object it belongs to.
    pub object: usize,
}

/// The first surface a ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the (normalised) ray.
    pub distance: f32,
    /// The hit point.
    pub point: Point3<f32>,
    /// The outward unit normal there.
    pub normal: Vector3<f32>,
    /// Index of the object hit.
    pub object: usize,
}

/// Static geometry with signed distances, nearest points, normals and ray casts.
///
/// The signed distance of the scene is the minimum over its parts: exact outside every part,
/// and inside overlapping parts never deeper than the true depth of the union. Queries skip
/// objects and parts whose bounding box is farther than the best distance found so far, so a
/// room of a few dozen primitives costs a handful of exact projections per query.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    objects: Vec<SceneObject>,
    aabb: Option<Aabb>,
}

impl Scene {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// A scene of one triangle mesh (a scanned room), see [`Part::mesh`] for the sign.
    ///
    /// # Errors
    /// As [`Part::mesh`].
    pub fn from_mesh(name: &str, mesh: &TriangleMesh) -> Result<Self> {
        let mut object = SceneObject::new(name, ObjectKind::Mesh);
        object.push(Part::mesh(mesh)?);
        let mut scene = Scene::new();
        scene.add(object)?;
        Ok(scene)
    }

    /// Adds an object and returns its index.
    ///
    /// # Errors
    /// [`SceneError::InvalidGeometry`] for an object without parts.
    pub fn add(&mut self, object: SceneObject) -> Result<usize> {
        let aabb = *object.aabb().ok_or_else(|| {
            SceneError::InvalidGeometry(format!("object `{}` has no parts", object.name))
        })?;
        self.aabb = Some(match self.aabb {
            Some(a) => a.merged(&aabb),
            None => aabb,
        });
        self.objects.push(object);
        Ok(self.objects.len() - 1)
    }

    /// Its objects, in the order they were added.
    pub fn objects(&self) -> &[SceneObject] {
        &self.objects
    }

    /// Its bounding box (`None` when empty).
    pub fn aabb(&self) -> Option<&Aabb> {
        self.aabb.as_ref()
    }

    /// The best (signed distance, object, projection) over all parts.
    #[inline]
    fn nearest(&self, p: &Point3<f32>) -> (f32, usize, Point3<f32>) {
        let mut best = f32::INFINITY;
        let mut best_object = usize::MAX;
        let mut best_point = *p;
        for (i, object) in self.objects.iter().enumerate() {
            // A part can only lower the minimum if its box is nearer than it (or, once the
            // point is inside something, if the point is inside its box).
            let Some(aabb) = object.aabb.as_ref() else {
                continue;
            };
            let bound = aabb.distance_to_local_point(p, true);
            if bound > 0.0 && bound >= best {
                continue;
            }
            for part in &object.parts {
                let bound = part.aabb.distance_to_local_point(p, true);
                if bound > 0.0 && bound >= best {
                    continue;
                }
                let (d, q) = part.signed_distance(p);
                if d < best {
                    best = d;
                    best_object = i;
                    best_point = q;
                }
            }
        }
        (best, best_object, best_point)
    }

    /// The signed distance at `p` in metres: negative inside solid geometry, `+inf` for an
    /// empty scene. Cost: the bounding-box tests of all objects plus the exact projections
    /// that survive them.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for a non-finite point.
    pub fn signed_distance(&self, p: &Point3<f32>) -> Result<f32> {
        check_point(p, "query point")?;
        Ok(self.nearest(p).0)
    }

    /// Signed distances of many points, in parallel (rayon).
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] naming the first non-finite point.
    pub fn signed_distances(&self, points: &[Point3<f32>]) -> Result<Vec<f32>> {
        if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(SceneError::InvalidInput(format!(
                "query point {i} ({:?}) is not finite",
                points[i].coords.as_slice()
            )));
        }
        Ok(points
            .par_iter()
            .with_min_len(256)
            .map(|p| self.nearest(p).0)
            .collect())
    }

    /// The nearest surface point, its outward normal and the query's signed distance (`None`
    /// for an empty scene).
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for a non-finite point.
    pub fn closest(&self, p: &Point3<f32>) -> Result<Option<SurfacePoint>> {
        check_point(p, "query point")?;
        let (d, object, q) = self.nearest(p);
        if object == usize::MAX {
            return Ok(None);
        }
        let offset = p - q;
        let normal = if offset.norm() > 1e-5 {
            offset.normalize() * d.signum()
        } else {
            // On the surface: the normalised gradient of the distance (central differences).
            let h = 1e-3;
            let g = Vector3::from_fn(|axis, _| {
                let mut a = *p;
                let mut b = *p;
                a[axis] += h;
                b[axis] -= h;
                self.nearest(&a).0 - self.nearest(&b).0
            });
            g.try_normalize(1e-12).unwrap_or_else(Vector3::z)
        };
        Ok(Some(SurfacePoint {
            point: q,
            normal,
            signed_distance: d,
            object,
        }))
    }

    /// The first surface hit by the ray from `origin` along `direction` within `max_distance`.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for a non-finite origin, a zero or non-finite direction, or a
    /// negative or NaN `max_distance`.
    pub fn cast_ray(
        &self,
        origin: &Point3<f32>,
        direction: &Vector3<f32>,
        max_distance: f32,
    ) -> Result<Option<RayHit>> {
        check_point(origin, "ray origin")?;
        let dir = direction
            .try_normalize(1e-12)
            .filter(|d| d.iter().all(|v| v.is_finite()))
            .ok_or_else(|| {
                SceneError::InvalidInput(format!(
                    "ray direction {direction:?} is zero or not finite"
                ))
            })?;
        if max_distance.is_nan() || max_distance < 0.0 {
            return Err(SceneError::InvalidInput(format!(
                "ray max_distance must be >= 0, got {max_distance}"
            )));
        }
        Ok(self.cast_normalised(&Ray::new(*origin, dir), max_distance, true))
    }

    /// Every surface the ray from `origin` along `direction` meets within `max_distance`, in
    /// order, at most `limit` of them: a solid's far side too (a slab's top, then its
    /// underside, then the floor beneath). Surfaces closer than 1 mm to the one before count
    /// once.
    ///
    /// # Errors
    /// As [`Scene::cast_ray`].
    pub fn surfaces_along(
        &self,
        origin: &Point3<f32>,
        direction: &Vector3<f32>,
        max_distance: f32,
        limit: usize,
    ) -> Result<Vec<RayHit>> {
        // Validated as a single cast is.
        self.cast_ray(origin, direction, 0.0)?;
        let dir = direction.normalize();
        let mut out: Vec<RayHit> = Vec::new();
        let mut from = 0.0;
        while out.len() < limit && from <= max_distance {
            let ray = Ray::new(origin + dir * from, dir);
            let Some(mut hit) = self.cast_normalised(&ray, max_distance - from, false) else {
                break;
            };
            hit.distance += from;
            from = hit.distance + 1e-3;
            out.push(hit);
        }
        Ok(out)
    }

    fn cast_normalised(&self, ray: &Ray, max_distance: f32, solid: bool) -> Option<RayHit> {
        let mut best: Option<RayHit> = None;
        let mut limit = max_distance;
        for (i, object) in self.objects.iter().enumerate() {
            let Some(aabb) = object.aabb.as_ref() else {
                continue;
            };
            if aabb.cast_local_ray(ray, limit, true).is_none() {
                continue;
            }
            for part in &object.parts {
                if part.aabb.cast_local_ray(ray, limit, true).is_none() {
                    continue;
                }
                if let Some(hit) = part
                    .shape
                    .cast_ray_and_get_normal(&part.pose, ray, limit, solid)
                {
                    limit = hit.time_of_impact;
                    best = Some(RayHit {
                        distance: hit.time_of_impact,
                        point: ray.point_at(hit.time_of_impact),
                        normal: hit.normal.try_normalize(1e-12).unwrap_or(-ray.dir),
                        object: i,
                    });
                }
            }
        }
        best
    }

    /// All its surfaces as one triangle mesh in world coordinates (for OBJ/PLY export).
    pub fn to_mesh(&self) -> TriangleMesh {
        let mut mesh = TriangleMesh::default();
        for part in self.objects.iter().flat_map(|o| &o.parts) {
            mesh.append(&part.to_mesh());
        }
        mesh
    }
}
