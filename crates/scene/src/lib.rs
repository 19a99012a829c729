//! Signed-distance 3D scenes for environment fields in indoor scenes (paper section 4 and
//! appendix A.2-A.3), built on parry3d and nalgebra. Metres, z up.
//!
//! - [`Scene`]: objects ([`SceneObject`]) made of [`Part`]s, primitives ([`Primitive`]:
//!   boxes, balls, capsules, cylinders) or triangle meshes, with the signed distance at any
//!   point (negative inside), the nearest surface point and normal ([`Scene::closest`]), ray
//!   casts and batched queries in parallel ([`Scene::signed_distances`]). A
//!   [`DistanceGrid`] samples it once for fast approximate reads ([`SignedDistance`]), and
//!   [`SurfaceColumns`] the surfaces straight beneath every point ([`SurfacesBeneath`]).
//! - [`TriangleMesh`]: OBJ and PLY input and output (a scanned room is one mesh,
//!   [`Scene::from_mesh`]); point clouds and paths export with [`write_point_cloud`] and
//!   [`write_polyline_obj`].
//! - [`generate_room`]: seeded furnished rooms (beds, sofas, chairs, tables, desks, cabinets)
//!   whose free floor stays connected; [`catalogue_room`]: the same rooms furnished with real
//!   furniture models ([`Catalogue`], Sweet Home 3D's, fetched by a script).
//! - [`import_mesh`]: a mesh from elsewhere into metres, z up, floor at z = 0, with a report
//!   naming the flag to set when the file looks y-up or in centimetres. A mesh's inside comes
//!   from its shape, not its normals ([`Part::mesh`]): open shells, overlapping parts and
//!   inverted winding are read as they are meant.
//! - [`sample_surface`] (the point cloud a scene encoder reads), [`voxelize`] into a
//!   [`envfield_grid::Grid3`], and [`floor_map`]: the bird's-eye map of section 4.1, a top-down
//!   depth image whose deepest pixels (the floor) are free.
//!
//! ```
//! use envfield_scene::{floor_map, generate_room, FloorMapConfig, RoomConfig};
//! use nalgebra::Point3;
//!
//! let room = generate_room(&RoomConfig::default(), 7)?;
//! // One metre above the floor in the middle of the room is free space...
//! let above = Point3::new(room.size[0] / 2.0, room.size[1] / 2.0, 1.0);
//! assert!(room.scene.signed_distance(&above)? > 0.0);
//! // ...and just below the floor's top is inside the floor.
//! let below = Point3::new(room.size[0] / 2.0, room.size[1] / 2.0, -0.02);
//! assert!(room.scene.signed_distance(&below)? < 0.0);
//! let map = floor_map(&room.scene, &FloorMapConfig::default())?;
//! assert!(map.grid.free_count() > 0);
//! # Ok::<(), envfield_scene::SceneError>(())
//! ```

mod apartment;
mod catalogue;
mod columns;
mod error;
mod floor;
mod gltf_in;
mod grid;
mod import;
mod mesh;
mod object;
mod ply;
mod room;
mod sample;
mod scene;
mod solid;

pub use apartment::{apartment, Apartment, ApartmentConfig, ApartmentRoom, Door, RoomType};
pub use catalogue::{
    catalogue_room, Catalogue, CatalogueItem, Half, Role, CATALOGUE_DIR, CONTRIB_DIR,
};
pub use columns::{SurfaceColumns, SurfacesBeneath};
pub use error::{Result, SceneError};
pub use floor::{floor_map, FloorMap, FloorMapConfig, MapFrame};
pub use gltf_in::{parse_gltf, read_gltf};
pub use grid::{DistanceGrid, SignedDistance, MAX_DISTANCE_SAMPLES};
pub use import::{import_mesh, read_scene, ImportConfig, ImportReport, Units, UpAxis, AXIS_MARGIN};
pub use mesh::{write_point_cloud, write_polyline_obj, MeshPart, TriangleMesh, MAX_COORDINATE};
pub use object::{ObjectKind, Part, Primitive, SceneObject};
pub use room::{generate_room, Furniture, Room, RoomConfig};
pub use sample::{sample_surface, voxelize, VoxelFrame, MAX_SURFACE_POINTS};
pub use scene::{RayHit, Scene, SurfacePoint};

pub use nalgebra;
pub use parry3d;
