//! The signed-distance scene: objects made of parts (primitives or triangle meshes) at poses.

use nalgebra::{Isometry3, Point3, Vector3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::query::{PointQuery, Ray, RayCast};
use rayon::prelude::*;

use crate::error::{check_point, Result, SceneError};
use crate::mesh::TriangleMesh;
use crate::object::{ObjectKind, Part, SceneObject};

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

    /// The same scene with object `index` moved rigidly by `by` (a chair pulled out from
    /// under a table), every other object as it was, in the same order.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for an index past the objects; as [`SceneObject::moved`].
    pub fn with_moved(&self, index: usize, by: &Isometry3<f32>) -> Result<Scene> {
        if index >= self.objects.len() {
            return Err(SceneError::InvalidInput(format!(
                "object {index} to move: the scene has {} objects",
                self.objects.len()
            )));
        }
        let mut out = Scene::new();
        for (i, object) in self.objects.iter().enumerate() {
            out.add(if i == index {
                object.moved(by)?
            } else {
                object.clone()
            })?;
        }
        Ok(out)
    }

    /// The same scene without object `index` (the others in order; indices past it shift
    /// down by one). `None` when nothing would be left or the index is past the objects.
    pub fn without(&self, index: usize) -> Option<Scene> {
        if index >= self.objects.len() || self.objects.len() == 1 {
            return None;
        }
        let mut out = Scene::new();
        for (i, object) in self.objects.iter().enumerate() {
            if i != index {
                out.add(object.clone()).ok()?;
            }
        }
        Some(out)
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
