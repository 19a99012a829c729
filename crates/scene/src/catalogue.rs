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
use serde::{Deserialize, Serialize};

use crate::error::{Result, SceneError};
use crate::object::{ObjectKind, Part, SceneObject};
use crate::room::{at, furnish, kind_at, kind_order, Piece, Pieces, Room, RoomConfig};
use crate::TriangleMesh;

/// Where [`Catalogue::find`] looks when `ENVFIELD_SWEETHOME3D` is not set, relative to the
/// workspace root.
pub const CATALOGUE_DIR: &str = "data/sweethome3d";

/// Where [`Catalogue::find_contrib`] looks when `ENVFIELD_SWEETHOME3D_CONTRIB` is not set,
/// relative to the workspace root: the contributed libraries
/// (`scripts/fetch_sweethome3d_contrib.sh`).
pub const CONTRIB_DIR: &str = "data/sweethome3d-contrib";

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
    /// What it is for, finer than its kind: which rooms of an apartment it furnishes and how.
    pub role: Role,
    /// Who modelled it (the catalogue's `creator`; `eTeks` for the default catalogue).
    pub creator: String,
    /// The library it came from: `default`, or a contributed library's folder name.
    pub library: String,
    /// Sweet Home 3D's `modelRotation`: a 3x3 matrix, row by row, that turns the model's file
    /// into its upright, front-facing frame before it is sized.
    pub rotation: Option<[f32; 9]>,
}

/// What a catalogue piece is for: the furnishing rules of an apartment's rooms place each
/// role its own way (a bedside table beside a bed's head, chairs around a dining table).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Role {
    /// A bed.
    Bed,
    /// A sofa or couch.
    Sofa,
    /// An armchair or ottoman.
    Armchair,
    /// A chair, dining or office.
    Chair,
    /// A stool (seat below 0.6 m).
    Stool,
    /// A bench.
    Bench,
    /// A dining table (or any table at 0.6 m or higher).
    DiningTable,
    /// A coffee table (a table lower than 0.6 m).
    CoffeeTable,
    /// A desk.
    Desk,
    /// A bedside table.
    BedsideTable,
    /// A TV unit or stand.
    TvUnit,
    /// A cabinet, chest, dresser or kitchen unit.
    Cabinet,
    /// A wardrobe or cupboard.
    Wardrobe,
    /// A bookcase or shelves.
    Bookcase,
    /// A floor-standing plant.
    Plant,
    /// A piano.
    Piano,
}

impl Role {
    /// The kind of object a piece of this role is in a scene.
    pub fn kind(self) -> ObjectKind {
        match self {
            Role::Bed => ObjectKind::Bed,
            Role::Sofa => ObjectKind::Sofa,
            Role::Armchair | Role::Chair | Role::Stool | Role::Bench => ObjectKind::Chair,
            Role::DiningTable | Role::CoffeeTable => ObjectKind::Table,
            Role::Desk => ObjectKind::Desk,
            Role::BedsideTable | Role::TvUnit | Role::Cabinet => ObjectKind::Cabinet,
            Role::Wardrobe | Role::Bookcase => ObjectKind::Shelf,
            Role::Plant => ObjectKind::Plant,
            Role::Piano => ObjectKind::Piano,
        }
    }
}

/// The furniture of a Sweet Home 3D catalogue that people live among.
#[derive(Debug)]
pub struct Catalogue {
    /// The pieces kept, in the catalogue's order.
    pub items: Vec<CatalogueItem>,
    models: Mutex<HashMap<usize, Arc<TriangleMesh>>>,
}

/// The role of a default-catalogue piece by its English name; `None` for what rooms here
/// leave out (doors, windows, lights, bathroom and kitchen appliances, bunk and loft beds,
/// corner sofas, plants).
fn default_role(name: &str) -> Option<Role> {
    Some(match name {
        "Bed 140x190" | "Bed 90x190" | "Bed" => Role::Bed,
        "Sofa" => Role::Sofa,
        "Armchair" => Role::Armchair,
        "Chair" => Role::Chair,
        "Stool" => Role::Stool,
        "Round table" | "Square table" | "Table" => Role::DiningTable,
        "Coffee table" => Role::CoffeeTable,
        "Desk" => Role::Desk,
        "Bedside table" => Role::BedsideTable,
        "TV unit" => Role::TvUnit,
        "Chest" | "Kitchen cabinet" | "Dresser" | "Glass door cabinet" => Role::Cabinet,
        "Wardrobe" => Role::Wardrobe,
        "Bookcase" | "Filled bookcase" => Role::Bookcase,
        "Piano" => Role::Piano,
        _ => return None,
    })
}

/// The role of a contributed piece from its English name, its category and its size
/// (metres): the first rule that matches, in the order written. `None` for what apartments
/// here leave out: children's, bunk, loft and mezzanine beds, corner sofas, dressing tables,
/// freezers, bar stools and bar tables (seats higher than a standing body sits), tabletop
/// plants, and anything outside the living room, kitchen, bedroom and office categories.
fn contrib_role(name: &str, category: &str, size: [f32; 3], seat: Option<f32>) -> Option<Role> {
    if !matches!(category, "Living room" | "Kitchen" | "Bedroom" | "Office") {
        return None;
    }
    let n = name.to_lowercase();
    let has = |words: &[&str]| words.iter().any(|w| n.contains(w));
    let height = size[2];
    let left_out = [
        "bunk",
        "loft",
        "mezzanine",
        "crib",
        "baby",
        "child",
        "corner",
        "bar ",
        "island",
        "hanging",
        "dressing",
        "freezer",
    ];
    if has(&left_out) {
        return None;
    }
    Some(if has(&["bedside"]) {
        Role::BedsideTable
    } else if has(&["bed"]) {
        Role::Bed
    } else if has(&["sofa", "couch", "futon"]) {
        Role::Sofa
    } else if has(&["armchair", "ottoman"]) {
        Role::Armchair
    } else if has(&["stool"]) {
        if seat.unwrap_or(height) > 0.6 {
            return None;
        }
        Role::Stool
    } else if has(&["bench"]) {
        Role::Bench
    } else if has(&["chair", "seat"]) {
        Role::Chair
    } else if has(&["coffee table"]) {
        Role::CoffeeTable
    } else if has(&["tv stand", "tv unit", "television cabinet"]) {
        Role::TvUnit
    } else if has(&["desk", "technical table"]) {
        Role::Desk
    } else if has(&["table"]) {
        if height < 0.6 {
            Role::CoffeeTable
        } else {
            Role::DiningTable
        }
    } else if has(&["wardrobe", "cupboard"]) {
        Role::Wardrobe
    } else if has(&["bookcase", "shelves", "shelf"]) {
        Role::Bookcase
    } else if has(&["cabinet", "dresser", "chest", "drawers"]) {
        Role::Cabinet
    } else if has(&["plant", "yucca", "spathiphyllum", "orchid", "bamboo"]) {
        if height < 0.5 {
            return None;
        }
        Role::Plant
    } else if has(&["piano"]) {
        Role::Piano
    } else {
        return None;
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

    /// The contributed libraries at `$ENVFIELD_SWEETHOME3D_CONTRIB`, or at [`CONTRIB_DIR`]
    /// under the first of the current folder and its parents that holds them; `None` when
    /// there are none (run `scripts/fetch_sweethome3d_contrib.sh`).
    pub fn find_contrib() -> Option<PathBuf> {
        if let Some(dir) = std::env::var_os("ENVFIELD_SWEETHOME3D_CONTRIB") {
            return Some(PathBuf::from(dir));
        }
        let here = std::env::current_dir().ok()?;
        here.ancestors()
            .map(|d| d.join(CONTRIB_DIR))
            .find(|d| d.join("PACKAGE").is_file())
    }

    /// Reads a catalogue folder: Sweet Home 3D's default catalogue
    /// (`dir/DefaultFurnitureCatalog.properties` with its models in `dir/resources/`, as
    /// `scripts/fetch_sweethome3d.sh` leaves it), or contributed libraries (each
    /// `dir/<library>/PluginFurnitureCatalog.properties` with its models under the paths it
    /// names, as `scripts/fetch_sweethome3d_contrib.sh` leaves them). It keeps the pieces whose
    /// model is there, whose size is positive, that stand on the floor and that [`Role`]
    /// names.
    ///
    /// # Errors
    /// [`SceneError::Io`] without a properties file; [`SceneError::Parse`] for a size or a
    /// rotation that is not a number; [`SceneError::InvalidInput`] when no piece is kept.
    pub fn read(dir: impl AsRef<Path>) -> Result<Self> {
        let dir = dir.as_ref();
        let default = dir.join("DefaultFurnitureCatalog.properties");
        let mut items = Vec::new();
        if default.is_file() {
            read_library(&default, &dir.join("resources"), "default", &mut items)?;
        } else {
            let mut libraries: Vec<PathBuf> = std::fs::read_dir(dir)
                .map_err(|source| SceneError::Io {
                    path: dir.to_path_buf(),
                    source,
                })?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.join("PluginFurnitureCatalog.properties").is_file())
                .collect();
            libraries.sort();
            if libraries.is_empty() {
                return Err(SceneError::Io {
                    path: default,
                    source: std::io::Error::new(
                        std::io::ErrorKind::NotFound,
                        "no DefaultFurnitureCatalog.properties, nor a library folder with a \
                         PluginFurnitureCatalog.properties",
                    ),
                });
            }
            for lib in libraries {
                let name = lib
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                read_library(
                    &lib.join("PluginFurnitureCatalog.properties"),
                    &lib,
                    &name,
                    &mut items,
                )?;
            }
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
        let turn = item.rotation.map(|m| nalgebra::Matrix3::from_row_slice(&m));
        // (x, y, z) y-up, front +z  ->  (-x, z, y): z up, front +y, still right-handed.
        for v in &mut mesh.vertices {
            let u = turn.map_or(*v, |m| Point3::from(m * v.coords));
            *v = Point3::new(-u.x, u.z, u.y);
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

/// The half of the held-out split a model belongs to (`model_split.tsv`, beside this file:
/// drawn once by its stated rule, fixed since).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Half {
    /// Models anything may be trained, tuned or thresholded on: the default catalogue's and
    /// the contributed models the split gives training.
    Training,
    /// Contributed models that only evaluation sees.
    Evaluation,
}

/// The written-down split of the contributed models: `id`, half, role, name, creator.
const MODEL_SPLIT: &str = include_str!("model_split.tsv");

impl Catalogue {
    /// Which half of the held-out split item `index` belongs to: [`Half::Training`] for the
    /// default catalogue, the written-down half for a contributed model, `None` for a model
    /// the split does not list (one a later package added) or an index out of range.
    pub fn half(&self, index: usize) -> Option<Half> {
        let item = self.items.get(index)?;
        if item.library == "default" {
            return Some(Half::Training);
        }
        MODEL_SPLIT
            .lines()
            .filter(|l| !l.starts_with('#'))
            .find_map(|l| {
                let mut cols = l.split('\t');
                (cols.next() == Some(item.id.as_str())).then(|| cols.next())?
            })
            .and_then(|h| match h {
                "training" => Some(Half::Training),
                "evaluation" => Some(Half::Evaluation),
                _ => None,
            })
    }

    /// The same catalogue with only the models of `half` (models are read again as needed).
    pub fn only(&self, half: Half) -> Self {
        Self {
            items: (0..self.items.len())
                .filter(|&i| self.half(i) == Some(half))
                .map(|i| self.items[i].clone())
                .collect(),
            models: Mutex::new(HashMap::new()),
        }
    }

    /// Every item of `role`, by index.
    pub fn of_role(&self, role: Role) -> Vec<usize> {
        (0..self.items.len())
            .filter(|&i| self.items[i].role == role)
            .collect()
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

/// One catalogue piece's fields: each key's line number and value.
type Fields = HashMap<String, (usize, String)>;

/// A properties file's `key#N=value` entries by N, each with its line: Java properties,
/// ISO 8859-1, backslash-continued lines joined.
fn properties(path: &Path) -> Result<Vec<(usize, Fields)>> {
    let text: String = std::fs::read(path)
        .map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?
        .into_iter()
        .map(char::from)
        .collect();
    let mut fields: HashMap<usize, Fields> = HashMap::new();
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
    let mut out: Vec<_> = fields.into_iter().collect();
    out.sort_unstable_by_key(|(i, _)| *i);
    Ok(out)
}

/// Reads one library's properties file at `path` into `items`: models under `models`, named
/// by their file name in the default catalogue and by their path in a contributed one.
fn read_library(
    path: &Path,
    models: &Path,
    library: &str,
    items: &mut Vec<CatalogueItem>,
) -> Result<()> {
    let default = library == "default";
    for (index, f) in properties(path)? {
        let get = |k: &str| f.get(k).map(|(_, v)| v.as_str());
        let number = |k: &str| -> Result<Option<f32>> {
            match f.get(k) {
                None => Ok(None),
                Some((line, v)) => v.parse::<f32>().map(Some).map_err(|_| SceneError::Parse {
                    path: path.to_path_buf(),
                    line: *line,
                    reason: format!("`{k}#{index}` is not a number: `{v}`"),
                }),
            }
        };
        let Some(name) = get("name") else {
            continue;
        };
        let [Some(w), Some(d), Some(h)] = [number("width")?, number("depth")?, number("height")?]
        else {
            continue;
        };
        let size = [w / 100.0, d / 100.0, h / 100.0];
        let drop_on_top = number("dropOnTopElevation")?
            .filter(|v| *v > 0.0)
            .map(|v| v / 100.0);
        let role = if default {
            default_role(name)
        } else {
            contrib_role(name, get("category").unwrap_or(""), size, drop_on_top)
        };
        let Some(role) = role else {
            continue;
        };
        let kind = role.kind();
        let elevation = number("elevation")?.unwrap_or(0.0);
        let Some(model) = get("model") else {
            continue;
        };
        let model = if default {
            models.join(model.rsplit('/').next().unwrap_or(model))
        } else {
            models.join(model.trim_start_matches('/'))
        };
        let rotation = match f.get("modelRotation") {
            None => None,
            Some((line, v)) => {
                let m: Vec<f32> = v
                    .split_whitespace()
                    .map(str::parse)
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| SceneError::Parse {
                        path: path.to_path_buf(),
                        line: *line,
                        reason: format!("`modelRotation#{index}` is not nine numbers: `{v}`"),
                    })?;
                let m: [f32; 9] = m.try_into().map_err(|_| SceneError::Parse {
                    path: path.to_path_buf(),
                    line: *line,
                    reason: format!("`modelRotation#{index}` is not nine numbers: `{v}`"),
                })?;
                Some(m)
            }
        };
        // The default catalogue keeps its models unturned (as the rooms here were made).
        let usable = size.iter().all(|v| v.is_finite() && *v > 0.0)
            && elevation == 0.0
            && !(default && rotation.is_some())
            && get("doorOrWindow") != Some("true")
            && model.is_file();
        if !usable {
            continue;
        }
        let seat_height = kind.is_seat().then(|| drop_on_top.unwrap_or(size[2]));
        items.push(CatalogueItem {
            id: get("id").unwrap_or_default().to_string(),
            name: name.to_string(),
            kind,
            model,
            size,
            seat_height,
            role,
            creator: get("creator").unwrap_or("eTeks").to_string(),
            library: library.to_string(),
            rotation,
        });
    }
    Ok(())
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
