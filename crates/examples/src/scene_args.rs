//! The scene flags every 3D example takes, and the scenes they name: a file of the user's, a
//! generated room, or a room furnished with Sweet Home 3D's models.

use anyhow::{Context, Result};
use envfield_rooms::sampling::check_sample_density;
use envfield_scene::{
    apartment, catalogue_room, generate_room, read_scene, ApartmentConfig, Catalogue, Half,
    ImportConfig, Room, RoomConfig, Scene, Units, UpAxis,
};
use std::path::PathBuf;

/// Where a 3D example's scene comes from (`#[command(flatten)]` it into an example's
/// arguments): `--scene FILE` with its `--up` axis and `--units`, or a generated room,
/// furnished from Sweet Home 3D's catalogue with `--catalogue`.
#[derive(Clone, Debug, clap::Args)]
pub struct SceneArgs {
    /// A scene to read instead of a generated room: OBJ or PLY (metres and z up unless
    /// --up and --units say otherwise), or glTF, `.gltf` or `.glb` (y up and metres, as its
    /// specification fixes them).
    #[arg(long, alias = "room")]
    pub scene: Option<PathBuf>,
    /// The scene file's up axis, z or y (game levels), overriding its format's: y for glTF,
    /// z for OBJ and PLY.
    #[arg(long)]
    pub up: Option<UpAxis>,
    /// The scene file's units: m (the default), cm, mm, or metres per unit.
    #[arg(long)]
    pub units: Option<Units>,
    /// Furnish the rooms with Sweet Home 3D's furniture models instead of the generator's
    /// boxes (scripts/fetch_sweethome3d.sh fetches them).
    #[arg(long)]
    pub catalogue: bool,
    /// Apartments of 2-4 rooms furnished with the evaluation half of the contributed models
    /// (models by other modellers than the default catalogue's, never trained or tuned on;
    /// scripts/fetch_sweethome3d_contrib.sh fetches them) instead of single rooms.
    #[arg(long, conflicts_with_all = ["catalogue", "scene"])]
    pub apartment: bool,
}

impl SceneArgs {
    /// Protects the scene file (`--scene`) from every write of this run
    /// ([`envfield_grid::protect_input`]): call it before checking the outputs, so that an
    /// output naming the scene, or an `--out` folder holding it under a name the example
    /// writes, is refused before any work. [`SceneArgs::read`] does it too.
    pub fn protect(&self) {
        if let Some(file) = &self.scene {
            envfield_grid::protect_input(file);
        }
    }

    /// The scene file, read and turned to metres and z up, with what the import did printed
    /// to stderr, and protected from every write of this run
    /// ([`envfield_grid::protect_input`]); `None` without `--scene`. With `samples`, a warning when that many torso
    /// samples are too few for the scene's floor.
    ///
    /// # Errors
    /// The file's import errors, naming it.
    pub fn read(&self, samples: Option<usize>) -> Result<Option<Scene>> {
        let Some(file) = &self.scene else {
            return Ok(None);
        };
        self.protect();
        let (scene, report) = read_scene(file, &ImportConfig::for_file(file, self.up, self.units))
            .with_context(|| format!("reading the scene {}", file.display()))?;
        eprintln!("{}: {report}", file.display());
        if let Some(n) = samples {
            if let Some(w) = check_sample_density(&scene, n)? {
                eprintln!("warning: {w}");
            }
        }
        Ok(Some(scene))
    }

    /// The maker of generated rooms of `config` (with `--catalogue`, furnished from the
    /// catalogue with [`RoomConfig::catalogue`]'s layout instead).
    ///
    /// # Errors
    /// No catalogue found with `--catalogue` (scripts/fetch_sweethome3d.sh fetches it), or
    /// one that cannot be read.
    pub fn rooms(&self, config: RoomConfig) -> Result<RoomMaker> {
        let apartments = if self.apartment {
            let dir = Catalogue::find_contrib()
                .context("no contributed furniture: run scripts/fetch_sweethome3d_contrib.sh")?;
            let read = Catalogue::read(&dir)
                .with_context(|| format!("reading the furniture at {}", dir.display()))?;
            Some(read.only(Half::Evaluation))
        } else {
            None
        };
        let catalogue = if self.catalogue {
            let dir = Catalogue::find()
                .context("no Sweet Home 3D catalogue: run scripts/fetch_sweethome3d.sh")?;
            let read = Catalogue::read(&dir)
                .with_context(|| format!("reading the catalogue at {}", dir.display()))?;
            Some(read)
        } else {
            None
        };
        Ok(RoomMaker {
            catalogue,
            apartments,
            config,
        })
    }

    /// The scene of room `seed`: the file's when `--scene` names one (the same for every
    /// seed), the generated or furnished room's otherwise, with the room itself (its known
    /// furniture) in that case.
    ///
    /// # Errors
    /// As [`SceneArgs::read`] and [`RoomMaker::room`].
    pub fn scene(
        &self,
        rooms: &RoomMaker,
        seed: u64,
        samples: Option<usize>,
    ) -> Result<(Scene, Option<Room>)> {
        let (scene, room, _) = self.scene_in_rooms(rooms, seed, samples)?;
        Ok((scene, room))
    }

    /// [`SceneArgs::scene`] with an apartment's rooms' interiors (empty for a file or a
    /// single room).
    ///
    /// # Errors
    /// As [`SceneArgs::scene`].
    pub fn scene_in_rooms(
        &self,
        rooms: &RoomMaker,
        seed: u64,
        samples: Option<usize>,
    ) -> Result<(Scene, Option<Room>, Vec<[f32; 4]>)> {
        match self.read(samples)? {
            Some(scene) => Ok((scene, None, Vec::new())),
            None => {
                let (room, zones) = rooms.room_and_rooms(seed)?;
                if let Some(n) = samples {
                    if let Some(w) = check_sample_density(&room.scene, n)? {
                        eprintln!("warning: {w}");
                    }
                }
                Ok((room.scene.clone(), Some(room), zones))
            }
        }
    }
}

/// Generated rooms: the generator's boxes, Sweet Home 3D's models, or apartments furnished
/// with the evaluation half of the contributed models.
pub struct RoomMaker {
    catalogue: Option<Catalogue>,
    apartments: Option<Catalogue>,
    config: RoomConfig,
}

impl RoomMaker {
    /// Room `seed`.
    ///
    /// # Errors
    /// Errors of the generator (a config it cannot lay out).
    pub fn room(&self, seed: u64) -> Result<Room> {
        Ok(self.room_and_rooms(seed)?.0)
    }

    /// Room `seed` and, for an apartment, its rooms' interiors (`[x_min, y_min, x_max,
    /// y_max]`; empty for a single room).
    ///
    /// # Errors
    /// As [`RoomMaker::room`].
    pub fn room_and_rooms(&self, seed: u64) -> Result<(Room, Vec<[f32; 4]>)> {
        if let Some(models) = &self.apartments {
            let apt = apartment(models, &ApartmentConfig::default(), seed)?;
            let rooms = apt.rooms.iter().map(|r| r.bounds).collect();
            return Ok((apt.home, rooms));
        }
        Ok(match &self.catalogue {
            Some(c) => (
                catalogue_room(c, &RoomConfig::catalogue(), seed)?,
                Vec::new(),
            ),
            None => (generate_room(&self.config, seed)?, Vec::new()),
        })
    }

    /// Whether the rooms are furnished from the catalogue.
    pub fn furnished(&self) -> bool {
        self.catalogue.is_some() || self.apartments.is_some()
    }
}
