//! `envfield.rooms`' native half: a scene, its accessible region, and walks and sit-downs
//! planned in it by the planners of `room_nav`, with every pose and its checks.

use envfield::affordance::{
    check_pose, walk, AffordanceConfig, PoseSequence, WalkConfig, JOINT_COUNT,
};
use envfield::grid::Point3m;
use envfield::rooms::harness::{
    run_pair, FloorPlanner, Pair, RoomContext, RoomPlanner, RunSettings,
};
use envfield::rooms::{sample_region, AccessibleRegion, SceneTables};
use envfield::scene::{generate_room, read_scene, ImportConfig, RoomConfig, Scene};
use envfield::vae::Cvae;
use envfield_examples::Navmesh;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A scene: triangles in metres, z up, its floor at z = 0.
#[pyclass(module = "envfield._envfield", name = "Scene", frozen)]
pub struct PyScene {
    scene: Arc<Scene>,
    /// What reading it reported (its parts, the frame it was moved into), one line each.
    report: Vec<String>,
}

#[pymethods]
impl PyScene {
    /// Reads an OBJ, PLY, glTF or GLB file. `up` ("z" or "y") and `units` ("m",
    /// "cm", "mm" or metres per unit) override what the format fixes (glTF: y up, metres) or
    /// what is guessed.
    #[staticmethod]
    #[pyo3(signature = (path, up=None, units=None))]
    fn read(
        py: Python<'_>,
        path: PathBuf,
        up: Option<&str>,
        units: Option<&str>,
    ) -> PyResult<Self> {
        let up = up.map(str::parse).transpose().map_err(value_error)?;
        let units = units.map(str::parse).transpose().map_err(value_error)?;
        let config = ImportConfig::for_file(&path, up, units);
        let (scene, report) = py
            .detach(|| read_scene(&path, &config))
            .map_err(|e| PyOSError::new_err(format!("{}: {e}", path.display())))?;
        let report = report.warnings.iter().map(|w| w.to_string()).collect();
        Ok(Self {
            scene: Arc::new(scene),
            report,
        })
    }

    /// A room the generator furnishes from its own seed (walls, a door, beds, chairs, tables).
    #[staticmethod]
    #[pyo3(signature = (seed=0))]
    fn generated(seed: u64) -> PyResult<Self> {
        let room = generate_room(&RoomConfig::default(), seed).map_err(value_error)?;
        Ok(Self {
            scene: Arc::new(room.scene),
            report: Vec::new(),
        })
    }

    /// The warnings reading the file gave (empty when it read cleanly).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.report.clone()
    }

    /// The scene's box: `((xmin, ymin, zmin), (xmax, ymax, zmax))`, metres.
    #[getter]
    fn bounds(&self) -> PyResult<([f32; 3], [f32; 3])> {
        let b = self
            .scene
            .aabb()
            .ok_or_else(|| PyValueError::new_err("the scene is empty"))?;
        Ok((
            [b.mins.x, b.mins.y, b.mins.z],
            [b.maxs.x, b.maxs.y, b.maxs.z],
        ))
    }

    /// Where people can be in the scene: torsos drawn by the VAE in `vae_path` (`samples` of
    /// them; by default 240 per square metre of the scene's box), kept where some pose is
    /// supported, collision-free and plausible, as voxels joined to every seat by a sit-down.
    #[pyo3(signature = (vae_path, samples=None, seed=0))]
    fn region(
        &self,
        py: Python<'_>,
        vae_path: PathBuf,
        samples: Option<usize>,
        seed: u64,
    ) -> PyResult<PyRegion> {
        let vae = Cvae::load(&vae_path)
            .map_err(|e| PyOSError::new_err(format!("{}: {e}", vae_path.display())))?;
        let scene = Arc::clone(&self.scene);
        py.detach(move || -> PyResult<PyRegion> {
            let samples = match samples {
                Some(n) => n,
                None => envfield::rooms::sampling::samples_for(&scene).map_err(value_error)?,
            };
            envfield::rooms::sampling::check_sample_density(&scene, samples)
                .map_err(value_error)?;
            let region = sample_region(&vae, &scene, samples, seed).map_err(value_error)?;
            let tables = SceneTables::of(&scene).map_err(value_error)?;
            Ok(PyRegion {
                scene,
                region,
                tables,
                navmesh: None,
            })
        })
    }
}

/// Where people can be in a scene, and the planners that move them through it.
#[pyclass(module = "envfield._envfield", name = "Region")]
pub struct PyRegion {
    scene: Arc<Scene>,
    region: AccessibleRegion,
    tables: SceneTables,
    /// Built the first time the navigation-mesh planner is asked for.
    navmesh: Option<Option<Navmesh>>,
}

/// One planned motion: the path, the poses along it and what the checks found.
#[pyclass(module = "envfield._envfield", name = "Plan", get_all, frozen)]
pub struct PyPlan {
    /// The planner's name.
    planner: String,
    /// "walk" or "sit".
    kind: String,
    /// Whether the path ends within 0.02 m of the goal.
    reached: bool,
    /// Seconds the planner took for the path.
    seconds: f64,
    /// Path length over the shortest through the region (NaN where it did not reach).
    path_ratio: f64,
    /// Torso locations along the path, metres: shape (steps, 3).
    path: Py<PyArray2<f32>>,
    /// Every joint of every pose, SMPL's 22 joints in order, metres: shape (frames, 22, 3).
    poses: Py<PyArray3<f32>>,
    /// Frames per second of the poses.
    fps: f32,
    /// Each pose rests on what holds it (feet, or feet and pelvis seated): shape (frames,).
    supported: Py<PyArray1<bool>>,
    /// No joint but the supporting ones inside the scene: shape (frames,).
    collision_free: Py<PyArray1<bool>>,
}

#[pymethods]
impl PyRegion {
    /// The centres of the region's voxels, metres: shape (voxels, 3).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let pts = self.region.voxel_centres();
        let n = pts.len();
        let flat: Vec<f32> = pts.into_iter().flatten().collect();
        flat.into_pyarray(py).reshape([n, 3])
    }

    /// The voxel's side, metres.
    #[getter]
    fn voxel(&self) -> f32 {
        self.region.frame.voxel
    }

    /// The region's sit-downs, one per place a body sits (each seat's), as
    /// `(start, seated)` torso locations in metres.
    #[getter]
    fn sit_downs(&self) -> Vec<([f32; 3], [f32; 3])> {
        self.region
            .sit_downs
            .iter()
            .map(|s| (s.start, s.seated))
            .collect()
    }

    /// The region's lie-downs, each from a sit-down onto the edge of a bed or sofa to lying
    /// on it, as `(start, lying)` torso locations in metres.
    #[getter]
    fn lie_downs(&self) -> Vec<([f32; 3], [f32; 3])> {
        self.region
            .lie_downs
            .iter()
            .map(|l| (l.sit.start, l.lying))
            .collect()
    }

    /// A walk from `start` to `goal` (standing torso locations in the region, metres) by
    /// `planner` (`room_nav`'s names: "ours_exact", "rrt", "rrtstar", "prm", "line",
    /// "navmesh"; the learned-field planners need a trained field and are not offered here).
    #[pyo3(signature = (start, goal, planner="ours_exact", seed=0))]
    fn walk(
        &mut self,
        py: Python<'_>,
        start: Point3m,
        goal: Point3m,
        planner: &str,
        seed: u64,
    ) -> PyResult<PyPlan> {
        let gait = walk(&WalkConfig::default(), seed).map_err(value_error)?;
        self.plan(py, Pair::walking(start, goal, gait), planner, seed)
    }

    /// Sitting down at the region's sit-down number `index` (see `sit_downs`), from its
    /// standing start to seated.
    #[pyo3(signature = (index, planner="ours_exact", seed=0))]
    fn sit_down(
        &mut self,
        py: Python<'_>,
        index: usize,
        planner: &str,
        seed: u64,
    ) -> PyResult<PyPlan> {
        let n = self.region.sit_downs.len();
        let sit = self.region.sit_downs.get(index).ok_or_else(|| {
            PyValueError::new_err(format!(
                "sit-down {index} asked for; the region has {n} (numbered from 0)"
            ))
        })?;
        let pair = Pair::sitting_down(sit).map_err(value_error)?;
        self.plan(py, pair, planner, seed)
    }

    /// Lying down by the region's lie-down number `index` (see `lie_downs`): from standing
    /// beside the bed or sofa, sitting on its edge, to lying on it.
    #[pyo3(signature = (index, planner="ours_exact", seed=0))]
    fn lie_down(
        &mut self,
        py: Python<'_>,
        index: usize,
        planner: &str,
        seed: u64,
    ) -> PyResult<PyPlan> {
        let n = self.region.lie_downs.len();
        let lie = self.region.lie_downs.get(index).ok_or_else(|| {
            PyValueError::new_err(format!(
                "lie-down {index} asked for; the region has {n} (numbered from 0)"
            ))
        })?;
        let pair = Pair::lying_down(lie).map_err(value_error)?;
        self.plan(py, pair, planner, seed)
    }
}

impl PyRegion {
    fn plan(&mut self, py: Python<'_>, pair: Pair, planner: &str, seed: u64) -> PyResult<PyPlan> {
        let planner: RoomPlanner = planner.parse().map_err(value_error)?;
        if planner.learned() {
            return Err(PyValueError::new_err(format!(
                "planner {:?} descends a learned field, which envfield.rooms does not train; \
                 use \"ours_exact\" (ours on the exact field) or a baseline",
                planner.name()
            )));
        }
        if planner == RoomPlanner::Navmesh && self.navmesh.is_none() {
            let gait = walk(&WalkConfig::default(), seed).map_err(value_error)?;
            let scene = Arc::clone(&self.scene);
            self.navmesh = Some(py.detach(move || Navmesh::for_room(&scene, &gait, seed)));
        }
        let navmesh = match (&self.navmesh, planner) {
            (Some(Some(m)), _) => Some((m as &dyn FloorPlanner, m.build_s)),
            (Some(None), RoomPlanner::Navmesh) => {
                return Err(PyValueError::new_err(
                    "no navigation mesh could be built for this scene",
                ))
            }
            _ => None,
        };
        let room = RoomContext {
            scene: &self.scene,
            region: &self.region,
            net: None,
            tables: Some(&self.tables),
            tables_s: 0.0,
            navmesh,
        };
        let settings = RunSettings {
            seed,
            ..RunSettings::default()
        };
        let kind = pair.kind;
        let (run, checks) = py.detach(|| -> PyResult<_> {
            let runs = run_pair(&room, &pair, &[planner], &settings).map_err(value_error)?;
            let run = runs.into_iter().next().ok_or_else(|| {
                PyValueError::new_err(format!("planner {} gave no run", planner.name()))
            })?;
            let checks = checks(&self.scene, &run.poses)?;
            Ok((run, checks))
        })?;
        let steps = run.path.len();
        let path: Vec<f32> = run.path.iter().flatten().copied().collect();
        let frames = run.poses.frames.len();
        let joints: Vec<f32> = run
            .poses
            .frames
            .iter()
            .flat_map(|f| f.joints.iter().flat_map(|j| [j.x, j.y, j.z]))
            .collect();
        let (supported, collision_free): (Vec<bool>, Vec<bool>) = checks.into_iter().unzip();
        Ok(PyPlan {
            planner: planner.name().to_string(),
            kind: kind.name().to_string(),
            reached: run.outcome.reached,
            seconds: run.outcome.seconds,
            path_ratio: run.outcome.path_ratio,
            path: path.into_pyarray(py).reshape([steps, 3])?.unbind(),
            poses: joints
                .into_pyarray(py)
                .reshape([frames, JOINT_COUNT, 3])?
                .unbind(),
            fps: run.poses.fps,
            supported: supported.into_pyarray(py).unbind(),
            collision_free: collision_free.into_pyarray(py).unbind(),
        })
    }
}

/// Each frame's support and collision checks against the scene itself.
fn checks(scene: &Scene, poses: &PoseSequence) -> PyResult<Vec<(bool, bool)>> {
    let config = AffordanceConfig::default();
    poses
        .frames
        .iter()
        .zip(&poses.supports)
        .map(|(pose, &support)| {
            let r = check_pose(scene, pose, support, &config).map_err(value_error)?;
            Ok((r.supported, r.collision_free))
        })
        .collect()
}
