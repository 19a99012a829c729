//! A page to watch people move: one self-contained HTML file holding a GLB (the scene, the
//! region as points, every person animated) and a small viewer on three.js (MIT; fetched by
//! `scripts/fetch_threejs.sh` into `data/three/` and embedded, so the page opens offline):
//! orbit camera, play and pause, a time slider, the region shown or hidden, the walls cut.
//! `#t=SECONDS` in the address opens it paused at that time; `#t=2&region=0&cut=0` without
//! the region, the walls whole.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// The three.js files a page embeds.
pub struct ThreeJs {
    dir: PathBuf,
}

/// Where `scripts/fetch_threejs.sh` puts three.js, under the workspace.
const THREE_DIR: &str = "data/three";

impl ThreeJs {
    /// three.js in `$ENVFIELD_THREE_DIR`, or the workspace's `data/three/`.
    ///
    /// # Errors
    /// Neither holds it: the message names the script that fetches it.
    pub fn find() -> Result<Self> {
        let dir = std::env::var_os("ENVFIELD_THREE_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| {
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("../..")
                    .join(THREE_DIR)
            });
        if !dir.join("three.module.min.js").is_file() {
            bail!(
                "three.js is not at {} (an --html page embeds it): run scripts/fetch_threejs.sh",
                dir.display()
            );
        }
        Ok(Self { dir })
    }

    fn read(&self, name: &str) -> Result<String> {
        let p = self.dir.join(name);
        std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))
    }

    /// The import map: each module as a data URL, their relative imports turned to the
    /// map's names (a data URL has no folder to resolve them in).
    fn import_map(&self) -> Result<String> {
        let module = |text: String| {
            format!(
                "data:text/javascript;base64,{}",
                base64::encode(text.as_bytes())
            )
        };
        let three = self
            .read("three.module.min.js")?
            .replace("\"./three.core.min.js\"", "\"three/core\"");
        let loader = self.read("GLTFLoader.js")?.replace(
            "'../utils/BufferGeometryUtils.js'",
            "'three/addons/utils/BufferGeometryUtils.js'",
        );
        let map = serde_json::json!({"imports": {
            "three": module(three),
            "three/core": module(self.read("three.core.min.js")?),
            "three/addons/loaders/GLTFLoader.js": module(loader),
            "three/addons/utils/BufferGeometryUtils.js": module(self.read("BufferGeometryUtils.js")?),
            "three/addons/controls/OrbitControls.js": module(self.read("OrbitControls.js")?),
        }});
        Ok(map.to_string())
    }
}

/// The page of `glb`, titled `title`; with `cut_walls` the scene is shown cut 1.3 m above its
/// lowest floor (a room's walls hide no one; a level of several floors wants it off), a box
/// on the page turns it on and off.
///
/// # Errors
/// three.js cannot be read.
pub fn viewer_page(glb: &[u8], title: &str, three: &ThreeJs, cut_walls: bool) -> Result<String> {
    let escaped: String = title
        .chars()
        .map(|c| match c {
            '<' => "&lt;".to_string(),
            '>' => "&gt;".to_string(),
            '&' => "&amp;".to_string(),
            '"' => "&quot;".to_string(),
            c => c.to_string(),
        })
        .collect();
    Ok(include_str!("viewer.html")
        .replace("__IMPORTMAP__", &three.import_map()?)
        .replace("__TITLE__", &escaped)
        .replace("__CUT__", if cut_walls { "true" } else { "false" })
        .replace("__GLB__", &base64::encode(glb)))
}
