//! Rooms furnished with real furniture models: Sweet Home 3D's default catalogue.
//!
//! `scripts/fetch_sweethome3d.sh` fetches the Debian package `sweethome3d` and unpacks its
//! catalogue (`DefaultFurnitureCatalog.properties`, which gives each model's size in
//! centimetres, and the OBJ models) into `data/sweethome3d/`. The models are GPL: they are
//! fetched, never committed, and neither are rooms made from them.
//!
//! [`Catalogue::read`] reads it, keeping the pieces people live among (beds, sofas, chairs,
//! armchairs, stools, tables, desks, cabinets, bookcases, wardrobes, a piano) with their
//! [`ObjectKind`]. [`Catalogue::model`] turns a model into the library's frame (z up, front
//! towards +y, its footprint centred on the origin, standing on z = 0) at its catalogue size,
//! as Sweet Home 3D scales it. [`catalogue_room`] furnishes a room as [`generate_room`] does,
//! with these models in place of boxes, each one [`Part::mesh`] whose inside comes from its
//! shape, not its normals.
//!
//! [`generate_room`]: crate::generate_room

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use envfield_grid::SplitMix64;
use nalgebra::{Point3, Vector3};

use crate::error::{Result, SceneError};
use crate::object::{ObjectKind, Part, SceneObject};
use crate::room::{at, furnish, kind_at, kind_order, Piece, Pieces, Room, RoomConfig};
use crate::TriangleMesh;

/// Where [`Catalogue::find`] looks when `ENVFIELD_SWEETHOME3D` is not set, relative to the
/// workspace root.
pub const CATALOGUE_DIR: &str = "data/sweethome3d";

/// One piece of the catalogue.
#[derive(Clone, Debug, PartialEq)]
pub struct CatalogueItem {
    /// The catalogue's id (`eTeks#chair`).
    pub id: String,
    /// Its English name (`Chair`).
    pub name: String,
    /// What it is.
    pub kind: ObjectKind,
    /// The OBJ model.
    pub model: PathBuf,
    /// Width (x), depth (y) and height, metres.
    pub size: [f32; 3],
    /// Where a person sits or lies (Sweet Home 3D's "drop on top" height) for seats, metres.
    pub seat_height: Option<f32>,
}

/// The furniture of a Sweet Home 3D catalogue that people live among.
#[derive(Debug)]
pub struct Catalogue {
    /// The pieces kept, in the catalogue's order.
    pub items: Vec<CatalogueItem>,
    models: Mutex<HashMap<usize, Arc<TriangleMesh>>>,
}

/// The kind of a catalogue piece by its English name; `None` for what rooms here leave out
/// (doors, windows, lights, bathroom and kitchen appliances, bunk and loft beds, corner sofas).
fn kind_of(name: &str) -> Option<ObjectKind> {
    Some(match name {
        "Bed 140x190" | "Bed 90x190" | "Bed" => ObjectKind::Bed,
        "Sofa" => ObjectKind::Sofa,
        "Chair" | "Armchair" | "Stool" => ObjectKind::Chair,
        "Round table" | "Square table" | "Table" | "Coffee table" => ObjectKind::Table,
        "Desk" => ObjectKind::Desk,
        "Chest" | "Bedside table" | "Kitchen cabinet" | "TV unit" | "Dresser"
        | "Glass door cabinet" => ObjectKind::Cabinet,
        "Bookcase" | "Filled bookcase" | "Wardrobe" => ObjectKind::Shelf,
        "Piano" => ObjectKind::Piano,
        _ => return None,
    })
}

impl Catalogue {
    /// The catalogue at `$ENVFIELD_SWEETHOME3D`, or at [`CATALOGUE_DIR`] under the first of
    /// the current folder and its parents that holds one; `None` when there is none (run
    /// `scripts/fetch_sweethome3d.sh`).
    pub fn find() -> Option<PathBuf> {
        if let Some(dir) = std::env::var_os("ENVFIELD_SWEETHOME3D") {
            return Some(PathBuf::from(dir));
        }
        let here = std::env::current_dir().ok()?;
        here.ancestors()
            .map(|d| d.join(CATALOGUE_DIR))
            .find(|d| d.join("DefaultFurnitureCatalog.properties").is_file())
    }

    /// Reads `dir/DefaultFurnitureCatalog.properties` and keeps the pieces whose model is in
    /// `dir/resources/`, whose size is positive, that stand on the floor, and that
    /// [`ObjectKind`] names.
    ///
    /// # Errors
    /// [`SceneError::Io`] without the properties file; [`SceneError::Parse`] for a size that
    /// is not a number; [`SceneError::InvalidInput`] when no piece is kept.
    pub fn read(dir: impl AsRef<Path>) -> Result<Self> {
        let dir = dir.as_ref();
        let path = dir.join("DefaultFurnitureCatalog.properties");
        // Java properties files are ISO 8859-1: each byte is one character.
        let text: String = std::fs::read(&path)
            .map_err(|source| SceneError::Io {
                path: path.clone(),
                source,
            })?
            .into_iter()
            .map(char::from)
            .collect();
        // key#N=value, with backslash-continued lines joined.
        let mut fields: HashMap<usize, HashMap<String, (usize, String)>> = HashMap::new();
        let mut lines = text.lines().enumerate();
        while let Some((n, line)) = lines.next() {
            let mut line = line.trim_start().to_string();
            while line.ends_with('\\') {
                line.pop();
                match lines.next() {
                    Some((_, more)) => line.push_str(more.trim_start()),
                    None => break,
                }
            }
            if line.starts_with('#') || line.starts_with('!') {
                continue;
            }
            let Some((key, value)) = line.split_once('=') else {
                continue;
            };
            let Some((name, index)) = key.trim().split_once('#') else {
                continue;
            };
            let Ok(index) = index.parse::<usize>() else {
                continue;
            };
            fields
                .entry(index)
                .or_default()
                .insert(name.to_string(), (n + 1, value.trim().to_string()));
        }
        let mut indices: Vec<usize> = fields.keys().copied().collect();
        indices.sort_unstable();
        let mut items = Vec::new();
        for index in indices {
            let f = &fields[&index];
            let get = |k: &str| f.get(k).map(|(_, v)| v.as_str());
            let Some(kind) = get("name").and_then(kind_of) else {
                continue;
            };
            let number = |k: &str| -> Result<Option<f32>> {
                match f.get(k) {
                    None => Ok(None),
                    Some((line, v)) => v.parse::<f32>().map(Some).map_err(|_| SceneError::Parse {
                        path: path.clone(),
                        line: *line,
                        reason: format!("`{k}#{index}` is not a number: `{v}`"),
                    }),
                }
            };
            let size = [number("width")?, number("depth")?, number("height")?];
            let [Some(w), Some(d), Some(h)] = size else {
                continue;
            };
            let elevation = number("elevation")?.unwrap_or(0.0);
            let Some(model) = get("model").and_then(|m| m.rsplit('/').next()) else {
                continue;
            };
            let model = dir.join("resources").join(model);
            let usable = [w, d, h].iter().all(|v| v.is_finite() && *v > 0.0)
                && elevation == 0.0
                && get("modelRotation").is_none()
                && model.is_file();
            if !usable {
                continue;
            }
            let seat_height = if kind.is_seat() {
                number("dropOnTopElevation")?
                    .map(|v| v / 100.0)
                    .or(Some(h / 100.0))
            } else {
                None
            };
            items.push(CatalogueItem {
                id: get("id").unwrap_or_default().to_string(),
                name: get("name").unwrap_or_default().to_string(),
                kind,
                model,
                size: [w / 100.0, d / 100.0, h / 100.0],
                seat_height,
            });
        }
        if items.is_empty() {
            return Err(SceneError::InvalidInput(format!(
                "{}: no furniture model found (run scripts/fetch_sweethome3d.sh)",
                dir.display()
            )));
        }
        Ok(Self {
            items,
            models: Mutex::new(HashMap::new()),
        })
    }

    /// The kinds it holds, each once.
    pub fn kinds(&self) -> Vec<ObjectKind> {
        let mut kinds: Vec<ObjectKind> = Vec::new();
        for item in &self.items {
            if !kinds.contains(&item.kind) {
                kinds.push(item.kind);
            }
        }
        kinds
    }

    /// Item `index`'s model in the library's frame, at its catalogue size: Sweet Home 3D's
    /// models are y up with their front towards +z; here z is up, the front faces +y, the
    /// footprint is centred on the origin and the model stands on z = 0. Read once, then
    /// kept.
    ///
    /// # Errors
    /// [`SceneError::InvalidInput`] for an index out of range; the errors of
    /// [`TriangleMesh::read_obj`]; [`SceneError::InvalidGeometry`] for a flat model.
    pub fn model(&self, index: usize) -> Result<Arc<TriangleMesh>> {
        let item = self.items.get(index).ok_or_else(|| {
            SceneError::InvalidInput(format!(
                "catalogue item {index}: there are {}",
                self.items.len()
            ))
        })?;
        if let Some(m) = self.models.lock().ok().and_then(|m| m.get(&index).cloned()) {
            return Ok(m);
        }
        let mut mesh = TriangleMesh::read_obj(&item.model)?;
        // (x, y, z) y-up, front +z  ->  (-x, z, y): z up, front +y, still right-handed.
        for v in &mut mesh.vertices {
            *v = Point3::new(-v.x, v.z, v.y);
        }
        let (lo, hi) = crate::mesh::bounds(&mesh.vertices);
        let extent = hi - lo;
        if extent.iter().any(|e| e.is_nan() || *e <= 0.0) {
            return Err(SceneError::InvalidGeometry(format!(
                "{}: the model is flat ({extent:?})",
                item.model.display()
            )));
        }
        let scale = Vector3::from(item.size).component_div(&extent);
        let centre = Vector3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, lo.z);
        for v in &mut mesh.vertices {
            *v = Point3::from((v.coords - centre).component_mul(&scale));
        }
        let mesh = Arc::new(mesh);
        if let Ok(mut models) = self.models.lock() {
            models.insert(index, mesh.clone());
        }
        Ok(mesh)
    }
}

impl Catalogue {
    /// Where the middle of item `index`'s seat lies in front of its footprint's centre: along
    /// the model's middle line from back to front, the longest run of 1 cm steps whose top
    /// surface lies within 4 cm of `seat_height`; `None` when there is none.
    ///
    /// # Errors
    /// As [`Catalogue::model`].
    pub fn seat_forward(&self, index: usize, seat_height: f32) -> Result<Option<f32>> {
        let model = self.model(index)?;
        let depth = self.items[index].size[1];
        let steps = (depth / 0.01) as usize;
        let mut best: Option<(usize, usize)> = None;
        let mut run: Option<usize> = None;
        for k in 0..=steps {
            let y = -depth / 2.0 + k as f32 * 0.01;
            let on_seat = k < steps
                && top_at(&model, 0.0, y).is_some_and(|z| (z - seat_height).abs() <= 0.04);
            match (on_seat, run) {
                (true, None) => run = Some(k),
                (false, Some(start)) => {
                    if best.is_none_or(|(a, b)| k - start > b - a) {
                        best = Some((start, k));
                    }
                    run = None;
                }
                _ => {}
            }
        }
        Ok(best.map(|(a, b)| -depth / 2.0 + (a + b) as f32 * 0.005))
    }
}

/// The highest surface of `mesh` straight above `(x, y)`, if any.
fn top_at(mesh: &TriangleMesh, x: f32, y: f32) -> Option<f32> {
    let mut top: Option<f32> = None;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        // Barycentric coordinates of (x, y) in the triangle's projection.
        let det = (b.y - c.y) * (a.x - c.x) + (c.x - b.x) * (a.y - c.y);
        if det.abs() < 1e-12 {
            continue;
        }
        let l1 = ((b.y - c.y) * (x - c.x) + (c.x - b.x) * (y - c.y)) / det;
        let l2 = ((c.y - a.y) * (x - c.x) + (a.x - c.x) * (y - c.y)) / det;
        let l3 = 1.0 - l1 - l2;
        if l1 >= 0.0 && l2 >= 0.0 && l3 >= 0.0 {
            let z = l1 * a.z + l2 * b.z + l3 * c.z;
            top = Some(top.map_or(z, |t| t.max(z)));
        }
    }
    top
}

/// A room furnished from `catalogue`: walls, doors, sizes and placement as
/// [`generate_room`](crate::generate_room) makes them with `config` and `seed`, every piece a
/// catalogue model at its catalogue size. Each kind the catalogue holds is tried once before
/// any is tried twice; within a kind the model is drawn at random.
///
/// # Errors
/// As [`generate_room`](crate::generate_room) and [`Catalogue::model`].
pub fn catalogue_room(catalogue: &Catalogue, config: &RoomConfig, seed: u64) -> Result<Room> {
    furnish(
        config,
        seed,
        &mut Models {
            catalogue,
            kinds: Vec::new(),
        },
    )
}

struct Models<'a> {
    catalogue: &'a Catalogue,
    kinds: Vec<ObjectKind>,
}

impl Pieces for Models<'_> {
    fn count(&mut self, config: &RoomConfig, rng: &mut SplitMix64) -> usize {
        self.kinds = self.catalogue.kinds();
        kind_order(&mut self.kinds, config, rng)
    }

    fn pick(&mut self, n: usize, rng: &mut SplitMix64) -> Piece {
        let kind = kind_at(&self.kinds, n, rng);
        let of_kind: Vec<usize> = (0..self.catalogue.items.len())
            .filter(|&i| self.catalogue.items[i].kind == kind)
            .collect();
        let item = of_kind[rng.below(of_kind.len())];
        let it = &self.catalogue.items[item];
        Piece {
            kind,
            size: it.size,
            seat_height: it.seat_height,
            seat_forward: it
                .seat_height
                .and_then(|h| self.catalogue.seat_forward(item, h).ok().flatten()),
            item,
        }
    }

    fn build(&self, piece: &Piece, n: usize, center: [f32; 2], yaw: f32) -> Result<SceneObject> {
        let model = self.catalogue.model(piece.item)?;
        let place = at(center[0], center[1], 0.0, yaw);
        let placed = TriangleMesh {
            vertices: model.vertices.iter().map(|v| place * v).collect(),
            triangles: model.triangles.clone(),
        };
        let name = format!("{} {n}", self.catalogue.items[piece.item].name).to_lowercase();
        let mut object = SceneObject::new(name, piece.kind);
        object.push(Part::mesh(&placed)?);
        Ok(object)
    }
}
