//! The viewer page in a real browser: headless Chromium opens a page of a room with two
//! people, paused at a time, and its screenshot must show both (pixels of each one's colour),
//! not a blank or black canvas. Needs `chromium` (Debian's package; `.ci/run` installs it)
//! and three.js (`scripts/fetch_threejs.sh`); without them the test says by name that it did
//! not run, and under CI (`CI=true`) it fails.

use envfield_affordance::{sit_down, walk, Actor, SitConfig, WalkConfig};
use envfield_examples::{viewer_page, ThreeJs};
use envfield_scene::nalgebra::{Point3, Vector3};
use envfield_scene::TriangleMesh;
use std::path::Path;
use std::process::Command;

fn skip(test: &str, reason: &str) {
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "CI=true: {reason}"
    );
    eprintln!("{test} did not run: {reason}");
}

/// A 5 x 4 m floor and a 0.45 m bench, z up.
fn room() -> TriangleMesh {
    let mut m = TriangleMesh::default();
    let mut block = |lo: [f32; 3], hi: [f32; 3]| {
        let mut c = TriangleMesh::cube(1.0);
        for v in &mut c.vertices {
            for k in 0..3 {
                v[k] = lo[k] + (v[k] + 0.5) * (hi[k] - lo[k]);
            }
        }
        m.append(&c);
    };
    block([0.0, 0.0, -0.1], [5.0, 4.0, 0.0]);
    block([3.0, 2.0, 0.0], [3.6, 2.5, 0.45]);
    m
}

/// The share of pixels near `rgb` (each channel within 60).
fn share_near(img: &image::RgbaImage, rgb: [u8; 3]) -> f64 {
    let n = img
        .pixels()
        .filter(|p| (0..3).all(|k| (i32::from(p[k]) - i32::from(rgb[k])).abs() < 60))
        .count();
    n as f64 / (img.width() * img.height()) as f64
}

#[test]
fn the_page_shows_its_people_in_headless_chromium() {
    let test = "the_page_shows_its_people_in_headless_chromium";
    let Ok(three) = ThreeJs::find() else {
        return skip(test, "three.js is not fetched (scripts/fetch_threejs.sh)");
    };
    let browser = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| {
            Command::new(b)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        });
    let Some(browser) = browser else {
        return skip(test, "no chromium to run (apt-get install chromium)");
    };
    let mut walking = walk(
        &WalkConfig {
            cycles: 2,
            ..WalkConfig::default()
        },
        1,
    )
    .unwrap();
    for f in &mut walking.frames {
        *f = f.translated(&Vector3::new(1.0, 1.2, 0.0));
    }
    let mut seated = sit_down(&SitConfig::default()).unwrap();
    for f in &mut seated.frames {
        *f = f
            .rotated_about_z(std::f32::consts::PI, &Point3::origin())
            .translated(&Vector3::new(3.3, 2.25, 0.0));
    }
    let actors = [
        Actor {
            name: "walking",
            poses: &walking,
        },
        Actor {
            name: "sitting",
            poses: &seated,
        },
    ];
    let glb = envfield_affordance::glb_bytes(Some(&room()), &[], &actors).unwrap();
    let page = viewer_page(&glb, "two people", &three, true).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let html = dir.path().join("page.html");
    std::fs::write(&html, page).unwrap();
    let shot = dir.path().join("shot.png");
    let out = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--hide-scrollbars",
            "--window-size=900,650",
            "--virtual-time-budget=20000",
        ])
        .arg(format!(
            "--user-data-dir={}",
            dir.path().join("profile").display()
        ))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}#t=1.0", html.display()))
        .output()
        .expect("chromium runs");
    assert!(
        shot.is_file(),
        "no screenshot: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&shot).unwrap().to_rgba8();
    keep_for_readme(&shot);
    // The people's colours (COLOURS[0], [1] of the GLB, lit): red and blue.
    let red = share_near(&img, [217, 90, 60]).max(share_near(&img, [190, 70, 45]));
    let blue = share_near(&img, [50, 110, 217]).max(share_near(&img, [40, 90, 190]));
    let black = share_near(&img, [0, 0, 0]);
    let floor = share_near(&img, [240, 238, 234]);
    eprintln!("red {red:.4}, blue {blue:.4}, black {black:.3}, background and floor {floor:.3}");
    assert!(black < 0.5, "a black canvas: {black:.3}");
    assert!(
        red > 0.001 && blue > 0.001,
        "the people do not show: red {red:.4}, blue {blue:.4}"
    );
}

/// With ENVFIELD_KEEP_SHOT set, the screenshot is copied there.
fn keep_for_readme(shot: &Path) {
    if let Some(to) = std::env::var_os("ENVFIELD_KEEP_SHOT") {
        std::fs::copy(shot, to).unwrap();
    }
}

/// What the examples' `--gltf` and `--bvh` write (through the same [`MotionArgs::write`]) for a
/// generated room with its region and three people, walking, sitting down and lying down,
/// passes the Khronos glTF-Validator (npm `gltf-validator`, `scripts/validate_gltf.sh`) with
/// no error and no warning. Needs node and npm; without them the test says by name that it
/// did not run, and under CI (`CI=true`) it fails.
#[test]
fn what_the_examples_write_passes_the_khronos_validator() {
    use envfield_affordance::{lie_down, LieConfig};
    use envfield_examples::MotionArgs;
    use envfield_scene::{generate_room, RoomConfig};
    let test = "what_the_examples_write_passes_the_khronos_validator";
    if Command::new("npm").arg("--version").output().is_err() {
        return skip(test, "no npm to install gltf-validator with");
    }
    let room = generate_room(&RoomConfig::default(), 5).unwrap();
    let walking = walk(&WalkConfig::default(), 2).unwrap();
    let seated = sit_down(&SitConfig::default()).unwrap();
    let lying = lie_down(&LieConfig::default()).unwrap();
    let actors = [
        Actor {
            name: "walking",
            poses: &walking,
        },
        Actor {
            name: "sitting down",
            poses: &seated,
        },
        Actor {
            name: "lying down",
            poses: &lying,
        },
    ];
    let region: Vec<Point3<f32>> = (0..200)
        .map(|i| {
            Point3::new(
                0.5 + (i % 20) as f32 * 0.1,
                0.5 + (i / 20) as f32 * 0.1,
                0.9,
            )
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("people.glb");
    let motion = MotionArgs {
        gltf: Some(glb.clone()),
        bvh: Some(dir.path().join("bvh")),
        html: None,
    };
    motion.check(&[]).unwrap();
    let written = motion
        .write(&room.scene.to_mesh(), &region, &actors, "room 5", true)
        .unwrap();
    assert_eq!(written.len(), 4, "{written:?}");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/validate_gltf.sh");
    let out = Command::new("bash").arg(script).arg(&glb).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "the validator found errors: {text}");
    assert!(text.contains("0 errors, 0 warnings"), "{text}");
}

/// An output that names an input of the run (the user's scene) is refused before any work, and
/// the input is left as it was.
#[test]
fn an_output_naming_the_scene_is_refused() {
    use envfield_examples::MotionArgs;
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.glb");
    std::fs::write(&scene, b"the user's scene").unwrap();
    let motion = MotionArgs {
        gltf: Some(scene.clone()),
        ..MotionArgs::default()
    };
    let e = motion.check(&[scene.as_path()]).unwrap_err().to_string();
    assert!(e.contains("--gltf") && e.contains("input"), "{e}");
    assert_eq!(std::fs::read(&scene).unwrap(), b"the user's scene");
    let motion = MotionArgs {
        html: Some(dir.path().join("page.htm")),
        ..MotionArgs::default()
    };
    assert!(motion.check(&[]).unwrap_err().to_string().contains(".html"));
}
