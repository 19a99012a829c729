//! What a scene is made of: objects of a kind ([`ObjectKind`]), each of parts (primitives or
//! triangle meshes) at poses.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::shape::{Ball, Capsule, Cuboid, Cylinder, SharedShape, TriMesh, TriMeshFlags};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SceneError};
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
    /// A floor-standing plant (walk around).
    Plant,
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
    pub(crate) shape: SharedShape,
    pub(crate) pose: Isometry3<f32>,
    pub(crate) aabb: Aabb,
    /// The primitive it was made from (`None` for a mesh).
    pub primitive: Option<Primitive>,
    /// A mesh's inside, from its shape rather than its normals (see [`Part::mesh`]).
    /// Made on the first query: reading a large scene costs nothing until it is asked.
    pub(crate) occupancy: Option<std::sync::Arc<std::sync::OnceLock<Occupancy>>>,
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
        mesh.check_extent("mesh")?;
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

    /// The same part moved rigidly by `by` (in the world frame): a chair pulled out, a door
    /// swung. A mesh keeps its inside (its occupancy moves with it).
    ///
    /// # Errors
    /// [`SceneError::InvalidGeometry`] for a motion that is not finite.
    pub fn moved(&self, by: &Isometry3<f32>) -> Result<Self> {
        check_pose(by)?;
        let pose = by * self.pose;
        Ok(Self {
            shape: self.shape.clone(),
            pose,
            aabb: self.shape.compute_aabb(&pose),
            primitive: self.primitive,
            occupancy: self.occupancy.clone(),
        })
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
    pub(crate) fn signed_distance(&self, p: &Point3<f32>) -> (f32, Point3<f32>) {
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
    pub(crate) parts: Vec<Part>,
    pub(crate) aabb: Option<Aabb>,
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

    /// The same object, every part moved rigidly by `by` (see [`Part::moved`]).
    ///
    /// # Errors
    /// As [`Part::moved`].
    pub fn moved(&self, by: &Isometry3<f32>) -> Result<Self> {
        let mut out = SceneObject::new(self.name.clone(), self.kind);
        for part in &self.parts {
            out.push(part.moved(by)?);
        }
        Ok(out)
    }
}
