//! The flags that write people's motion for the tools people watch it in (`#[command(flatten)]`
//! them into an example's arguments): `--gltf OUT.glb` (three.js, Bevy, Blender), `--bvh DIR`
//! (one BVH file per person, for motion-capture tools), `--html OUT.html` (a page that plays
//! it in a browser, [`crate::viewer_page`]).

use crate::viewer::{viewer_page, ThreeJs};
use anyhow::{anyhow, bail, Context, Result};
use envfield_affordance::{glb_bytes, write_bvh, Actor};
use envfield_grid::{check_writable, protect_input, write_atomic};
use envfield_scene::nalgebra::Point3;
use envfield_scene::TriangleMesh;
use std::path::{Path, PathBuf};

/// Where the planned people's motion goes.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct MotionArgs {
    /// Write the scene and every planned person, animated, as one glTF binary file (.glb):
    /// it plays in three.js and Bevy and imports into Blender.
    #[arg(long, value_name = "OUT.glb")]
    pub gltf: Option<PathBuf>,
    /// Write each planned person's poses as a BVH file into this folder (person_0.bvh, ...).
    #[arg(long, value_name = "DIR")]
    pub bvh: Option<PathBuf>,
    /// Write a page that plays the scene and its people in a browser, self-contained
    /// (scripts/fetch_threejs.sh fetches the three.js it embeds).
    #[arg(long, value_name = "OUT.html")]
    pub html: Option<PathBuf>,
}

impl MotionArgs {
    /// Whether any of the outputs was asked for.
    pub fn any(&self) -> bool {
        self.gltf.is_some() || self.bvh.is_some() || self.html.is_some()
    }

    /// Protects `inputs` (the user's scene, say) from every write of the run
    /// ([`protect_input`]), then refuses, before any work, outputs that cannot be written or
    /// that name one of them: nothing a user saved is overwritten. An `--html`
    /// page needs three.js, looked for now.
    ///
    /// # Errors
    /// The flag and the path that cannot be written, or that is an input.
    pub fn check(&self, inputs: &[&Path]) -> Result<()> {
        // Every write of the run refuses an input from here on (by file identity).
        for input in inputs {
            protect_input(input);
        }
        for (flag, path, ext) in [
            ("--gltf", &self.gltf, "glb"),
            ("--html", &self.html, "html"),
        ] {
            let Some(path) = path else { continue };
            if path.extension().and_then(|e| e.to_str()) != Some(ext) {
                bail!("{flag} {}: the file must end in .{ext}", path.display());
            }
            check_writable(path).map_err(|e| anyhow!("{flag} {}: {e}", path.display()))?;
        }
        if let Some(dir) = &self.bvh {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("--bvh: creating {}", dir.display()))?;
            check_writable(dir.join("person_0.bvh"))
                .with_context(|| format!("--bvh {}", dir.display()))?;
        }
        if self.html.is_some() {
            ThreeJs::find().context("--html")?;
        }
        Ok(())
    }

    /// Writes what was asked for: the scene `mesh`, the `region` points (drawn on the page,
    /// hidden at will) and the `actors`, titled `title` on the page, its walls cut with
    /// `cut_walls` ([`viewer_page`]). Returns the files written.
    ///
    /// # Errors
    /// Writing fails, or an actor's poses are not finite.
    pub fn write(
        &self,
        mesh: &TriangleMesh,
        region: &[Point3<f32>],
        actors: &[Actor],
        title: &str,
        cut_walls: bool,
    ) -> Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        if self.gltf.is_some() || self.html.is_some() {
            if let Some(path) = &self.gltf {
                let glb = glb_bytes(Some(mesh), &[], actors)?;
                write_atomic(path, &glb).with_context(|| format!("--gltf {}", path.display()))?;
                written.push(path.clone());
            }
            if let Some(path) = &self.html {
                let glb = glb_bytes(Some(mesh), region, actors)?;
                let page = viewer_page(&glb, title, &ThreeJs::find()?, cut_walls)?;
                write_atomic(path, page.as_bytes())
                    .with_context(|| format!("--html {}", path.display()))?;
                written.push(path.clone());
            }
        }
        if let Some(dir) = &self.bvh {
            for (i, actor) in actors.iter().enumerate() {
                let path = dir.join(format!("person_{i}.bvh"));
                write_bvh(&path, actor.poses)
                    .with_context(|| format!("--bvh {}", path.display()))?;
                written.push(path);
            }
        }
        Ok(written)
    }
}
