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
    let page = viewer_page(&glb, "two people", &three).unwrap();
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
