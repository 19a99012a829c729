//! The examples meet hostile input (the cases of `docs/hostile-input.md`): each must exit
//! with a clear error, never a panic, an abort or a hang, and must leave a user's file as it
//! was. The example binaries are the ones `cargo test` builds beside this test; where they
//! are missing (a run of this test alone) it skips with a message, except under CI.
//! `ENVFIELD_EXAMPLES_DIR` points it at other builds (the binaries from before the fixes fail
//! every test here).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The built example `name`, beside this test's binary (`target/<profile>/examples/`).
fn example(name: &str) -> Option<PathBuf> {
    let dir = match std::env::var_os("ENVFIELD_EXAMPLES_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => std::env::current_exe()
            .ok()?
            .parent()?
            .parent()?
            .join("examples"),
    };
    let path = dir.join(name);
    if path.is_file() {
        return Some(path);
    }
    let reason = format!("{} not built (run the whole `cargo test`)", path.display());
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "CI=true: {reason}"
    );
    eprintln!("skipping: {reason}");
    None
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("envfield-entry-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `args` and asserts a clean refusal: exit status 1 (anyhow's error), no panic (101) or
/// abort, and `expect` in the message.
fn refuses(out: Output, expect: &str) {
    refuses_with(out, 1, expect);
}

/// Runs `args` and asserts clap's refusal of a bad flag: exit status 2 and `expect` in the
/// message.
fn refuses_usage(out: Output, expect: &str) {
    refuses_with(out, 2, expect);
}

/// A refusal with exit status `code`, `expect` in the message and no panic.
fn refuses_with(out: Output, code: i32, expect: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(code),
        "not a clean error:\n{stderr}"
    );
    assert!(stderr.contains(expect), "expected `{expect}` in:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

fn run(bin: &Path, args: &[&str]) -> Output {
    Command::new(bin)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

#[test]
fn fmm_refuses_absurd_repeats_several_mazes_and_overflowing_spacings() {
    let Some(fmm) = example("fmm") else { return };
    let dir = scratch("fmm");
    let grid = write(&dir, "grid.txt", "#####\n#S..#\n#.#G#\n#####\n");
    let two = write(&dir, "two.txt", "S.G\n\n..G\nS..\n");
    refuses(
        run(&fmm, &[&grid, "--repeat", "18446744073709551615"]),
        "--repeat",
    );
    refuses(run(&fmm, &[&grid, "--repeat", "100000000000"]), "--repeat");
    refuses(run(&fmm, &[&two]), "holds 2 mazes");
    let out = dir.join("f.npy");
    refuses(
        run(
            &fmm,
            &[&grid, "--spacing", "1e38", "--out", &out.to_string_lossy()],
        ),
        "overflow",
    );
    assert!(!out.exists(), "no field written");
    let png = write(&dir, "bad.png", "not a png at all");
    refuses(run(&fmm, &[&png]), "bad.png");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn maze_nav_refuses_zero_and_absurd_counts_and_checks_outputs_first() {
    let Some(nav) = example("maze_nav") else {
        return;
    };
    let dir = scratch("nav");
    let astar = ["--size", "8", "--planner", "astar"];
    refuses(
        run(&nav, &[&astar[..], &["--count", "0"]].concat()),
        "at least 1",
    );
    refuses(
        run(&nav, &[&astar[..], &["--pairs", "100000000000"]].concat()),
        "more than",
    );
    refuses(
        run(&nav, &[&astar[..], &["--count", "100000000000"]].concat()),
        "more than",
    );
    let wall = write(&dir, "wall.txt", "#\n");
    refuses(
        run(&nav, &["--mazes", &wall, "--planner", "astar"]),
        "no (start, goal) pair",
    );
    refuses(
        run(
            &nav,
            &[&astar[..], &["--paths", "/nonexistent/p.json"]].concat(),
        ),
        "does not exist",
    );
    // A truncated VIN file is an error, not a silent fall back to the shipped VIN.
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let bytes = std::fs::read(models.join("vin_8.safetensors")).unwrap();
    let broken = dir.join("broken.safetensors");
    std::fs::write(&broken, &bytes[..bytes.len() / 2]).unwrap();
    let args = ["--size", "8", "--count", "2", "--planner", "vin", "--model"];
    refuses(
        run(&nav, &[&args[..], &[&*broken.to_string_lossy()]].concat()),
        "broken.safetensors",
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn training_refuses_no_data_and_no_steps_and_keeps_the_file() {
    let dir = scratch("train");
    let good = dir.join("good.safetensors");
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/vin_8.safetensors");
    std::fs::copy(&shipped, &good).unwrap();
    let out = good.to_string_lossy().into_owned();
    if let Some(train) = example("train_maze") {
        let base = ["--size", "8", "--out"];
        refuses(
            run(&train, &[&base[..], &[&out, "--mazes", "0"]].concat()),
            "at least 1",
        );
        refuses(
            run(&train, &[&base[..], &[&out, "--steps", "0"]].concat()),
            "trains nothing",
        );
        refuses(
            run(&train, &[&base[..], &[&out, "--stop-at", "0"]].concat()),
            "trains nothing",
        );
        let folder = format!("{}/", dir.display());
        refuses(
            run(&train, &[&base[..], &[&folder, "--mazes", "4"]].concat()),
            "folder",
        );
        let args = [&base[..], &[&out, "--mazes", "4", "--lr=-1"]].concat();
        refuses(run(&train, &args), "lr must be positive");
    }
    if let Some(vin) = example("train_vin") {
        for zero in ["--epochs", "--max-steps"] {
            let args = ["--size", "8", "--mazes", "4", zero, "0", "--out", &out];
            refuses(run(&vin, &args), "trains nothing");
        }
    }
    assert_eq!(
        std::fs::read(&good).unwrap(),
        std::fs::read(&shipped).unwrap()
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn room_refuses_absurd_point_counts_and_radii_quickly() {
    let Some(room) = example("room") else { return };
    let dir = scratch("room");
    let out = dir.to_string_lossy().into_owned();
    refuses(
        run(&room, &["--points", "18446744073709551615", "--out", &out]),
        "surface points",
    );
    let t = std::time::Instant::now();
    refuses(
        run(&room, &["--body-radius", "1e30", "--out", &out]),
        "body radius",
    );
    assert!(t.elapsed().as_secs() < 60, "{:?}", t.elapsed());
    let bad = write(&dir, "bad.obj", "v 1 2\n");
    refuses(run(&room, &["--scene", &bad, "--out", &out]), "line 1");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn birdseye_multi_refuses_impossible_crowds_and_bad_rooms() {
    let Some(bin) = example("birdseye_multi") else {
        return;
    };
    let dir = scratch("birdseye");
    let out = dir.to_string_lossy().into_owned();
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/models/birdseye.safetensors");
    let go = |extra: &[&str]| {
        let mut args = vec!["--model", model, "--out", &out];
        args.extend_from_slice(extra);
        run(&bin, &args)
    };
    refuses(go(&["--people", "0"]), "at least 1");
    // More people than the floor holds, even an absurd count: refused at once.
    let t = std::time::Instant::now();
    refuses(go(&["--people", "1000000000"]), "do not fit");
    assert!(t.elapsed().as_secs() < 30, "{:?}", t.elapsed());
    refuses(go(&["--people", "60"]), "people");
    refuses(go(&["--body-radius", "nan"]), "--body-radius");
    refuses(go(&["--body-radius", "100"]), "no free cell");
    refuses(go(&["--step-length", "0.01"]), "--step-length");
    refuses(go(&["--directions", "2"]), "directions");
    let empty = write(&dir, "empty.obj", "");
    refuses(go(&["--room", &empty]), "no triangles");
    refuses(go(&["--rooms", "0", "--json"]), "at least 1");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 53: a batch goes on past a room too small for its crowd, counting it apart; one room
/// read from a file reports every loop's figures; every run says why it ended.
#[test]
fn birdseye_multi_counts_small_rooms_apart_and_reports_each_loop() {
    let Some(bin) = example("birdseye_multi") else {
        return;
    };
    let dir = scratch("birdseye-batch");
    let out = dir.to_string_lossy().into_owned();
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/models/birdseye.safetensors");
    // Room 61 cannot hold 16 people with separate starts and goals; 62 can.
    let batch = run(
        &bin,
        &[
            "--model",
            model,
            "--out",
            &out,
            "--rooms",
            "2",
            "--people",
            "16",
            "--seed",
            "61",
            "--json",
            "--loops",
            "pibt_exact,grid_pibt",
        ],
    );
    assert!(
        batch.status.success(),
        "{}",
        String::from_utf8_lossy(&batch.stderr)
    );
    let text = String::from_utf8_lossy(&batch.stdout);
    let figures: serde_json::Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(figures["rooms_too_small"], serde_json::json!([61]));
    assert_eq!(figures["rooms_run"], 1);
    for key in [
        "pibt_exact_reach_pct",
        "grid_pibt_reach_pct",
        "pibt_exact_sum_of_costs_ratio",
    ] {
        assert!(figures.get(key).is_some(), "{key} missing: {figures}");
    }
    // Every room too small: refused, naming why.
    refuses(
        run(
            &bin,
            &[
                "--model", model, "--out", &out, "--rooms", "1", "--people", "16", "--seed", "61",
                "--json",
            ],
        ),
        "no room of the 1 held 16 people",
    );
    // One room read from a file: each loop's figures and ending.
    let obj = "v 0 0 0\nv 4 0 0\nv 4 3 0\nv 0 3 0\nf 1 2 3\nf 1 3 4\n";
    let scene = write(&dir, "floor.obj", obj);
    let one = run(
        &bin,
        &[
            "--model",
            model,
            "--out",
            &out,
            "--scene",
            &scene,
            "--people",
            "6",
            "--json",
            "--loops",
            "ours_exact,alg1_exact,orca",
        ],
    );
    assert!(
        one.status.success(),
        "{}",
        String::from_utf8_lossy(&one.stderr)
    );
    let text = String::from_utf8_lossy(&one.stdout);
    let figures: serde_json::Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    for name in ["ours_exact", "alg1_exact", "orca"] {
        for what in [
            "reach_pct",
            "person_collisions",
            "furniture_collisions",
            "ms_per_step",
        ] {
            let key = format!("{name}_{what}");
            assert!(figures.get(&key).is_some(), "{key} missing: {figures}");
        }
        let ending = &figures[format!("{name}_ending")];
        assert!(ending == "arrived" || ending == "step_budget", "{ending}");
    }
    assert_eq!(figures["ours_exact_person_collisions"], 0);
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 36, cases 1, 2, 13-16 and 18: the room and crowd trainers write no untrained weights
/// over a user's file, refuse counts that would abort or hang, and say when there is nothing
/// to resume.
#[test]
fn the_room_trainers_keep_the_file_and_refuse_absurd_counts() {
    let dir = scratch("room-train");
    let good = dir.join("good.safetensors");
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/vae.safetensors");
    std::fs::copy(&shipped, &good).unwrap();
    let out = good.to_string_lossy().into_owned();
    let huge = "18446744073709551615";
    if let Some(vae) = example("train_vae") {
        let go = |extra: &[&str]| {
            let mut args = vec!["--rooms", "1", "--out", &out];
            args.extend_from_slice(extra);
            run(&vae, &args)
        };
        refuses(go(&["--steps", "0"]), "trains nothing");
        let t = std::time::Instant::now();
        refuses(go(&["--scenes", huge]), "scenes_per_step");
        refuses(go(&["--torsos", huge]), "torsos");
        refuses(go(&["--scenes", "16", "--torsos", "10000000"]), "1,000,000");
        assert!(t.elapsed().as_secs() < 30, "{:?}", t.elapsed());
        let missing = dir.join("none.ckpt").to_string_lossy().into_owned();
        refuses(go(&["--resume", &missing]), "no checkpoint");
    }
    if let Some(birdseye) = example("train_birdseye") {
        let go = |extra: &[&str]| {
            let mut args = vec!["--out", &out];
            args.extend_from_slice(extra);
            run(&birdseye, &args)
        };
        let small = ["--rooms", "2", "--eval-rooms", "2"];
        refuses(
            go(&[&small[..], &["--steps", "0"]].concat()),
            "trains nothing",
        );
        let t = std::time::Instant::now();
        refuses(go(&["--rooms", "2", "--eval-rooms", "0"]), "--eval-rooms");
        let goals = ["--goals-per-room", huge];
        refuses(go(&[&small[..], &goals].concat()), "--goals-per-room");
        refuses(go(&["--rooms", huge]), "--rooms");
        let resume = ["--resume", "--steps", "10"];
        refuses(go(&[&small[..], &resume].concat()), "no checkpoint");
        assert!(t.elapsed().as_secs() < 30, "{:?}", t.elapsed());
    }
    assert_eq!(
        std::fs::read(&good).unwrap(),
        std::fs::read(&shipped).unwrap()
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 36, cases 9-11, 14 and 17: no pairs, an untrained field, a seed range that wraps,
/// an unknown planner, a per-walk log that cannot be written,
/// an absurd heading count and a room a hundred metres wide are refused, not run.
#[test]
fn room_nav_and_birdseye_refuse_empty_runs_wrapping_seeds_and_huge_rooms() {
    let dir = scratch("nav-crowd");
    let out = dir.to_string_lossy().into_owned();
    let huge = "18446744073709551615";
    if let Some(nav) = example("room_nav") {
        refuses(run(&nav, &["--pairs", "0", "--out", &out]), "--pairs");
        refuses(
            run(&nav, &["--field-steps", "0", "--out", &out]),
            "--field-steps",
        );
        refuses(
            run(&nav, &["--seed", huge, "--rooms", "2", "--out", &out]),
            "64 bits",
        );
        refuses_usage(
            run(&nav, &["--planners", "ours,astar", "--out", &out]),
            "unknown planner `astar`",
        );
        let nowhere = dir.join("no/such/folder/walks.jsonl");
        refuses(
            run(
                &nav,
                &["--walks-out", &nowhere.to_string_lossy(), "--out", &out],
            ),
            "--walks-out",
        );
        // Motion out: the wrong extension, and the scene itself as the output.
        let glb = dir.join("people.txt");
        refuses(
            run(&nav, &["--gltf", &glb.to_string_lossy(), "--out", &out]),
            "--gltf",
        );
        let mine = dir.join("mine.glb");
        std::fs::write(&mine, "the user's scene").unwrap();
        let mine_s = mine.to_string_lossy();
        refuses(
            run(
                &nav,
                &["--scene", &mine_s, "--gltf", &mine_s, "--out", &out],
            ),
            "is an input of this run",
        );
        assert_eq!(std::fs::read_to_string(&mine).unwrap(), "the user's scene");
    }
    if let Some(crowd) = example("birdseye_multi") {
        let model = concat!(env!("CARGO_MANIFEST_DIR"), "/models/birdseye.safetensors");
        let go = |extra: &[&str]| {
            let mut args = vec!["--model", model, "--out", &out];
            args.extend_from_slice(extra);
            run(&crowd, &args)
        };
        refuses(go(&["--seed", huge, "--rooms", "2", "--json"]), "64 bits");
        refuses(go(&["--directions", huge]), "--directions");
        // A 100 x 100 m floor with a box on it.
        let mut obj =
            String::from("v 0 0 0\nv 100 0 0\nv 100 100 0\nv 0 100 0\nf 1 2 3\nf 1 3 4\n");
        obj.push_str("v 50 50 0\nv 51 50 0\nv 51 51 1\nf 5 6 7\n");
        let big = write(&dir, "big.obj", &obj);
        let t = std::time::Instant::now();
        refuses(go(&["--room", &big]), "more than 256");
        assert!(t.elapsed().as_secs() < 30, "{:?}", t.elapsed());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 36, cases 3 and 8 (and the import of the real-scenes issue): a scene whose floor is
/// 1 m up and a kilometre from the origin, or written y-up, walks as the same scene at the
/// origin does once imported; read with the wrong up axis, it warns naming `--up y` (its
/// furniture stands on no floor that way).
#[test]
fn room_scenes_are_moved_onto_their_floor_and_turned_upright() {
    let Some(room) = example("room") else { return };
    let dir = scratch("import");
    // A 5 x 4 m floor, two walls 2.5 m high and three boxes standing on the floor (a table, a
    // bed, a cabinet: what stands on the floor tells up), as (x, y, z) corners of quads.
    let mut quads: Vec<[[f32; 3]; 4]> = vec![
        [[0., 0., 0.], [5., 0., 0.], [5., 4., 0.], [0., 4., 0.]],
        [[0., 4., 0.], [5., 4., 0.], [5., 4., 2.5], [0., 4., 2.5]],
        [[0., 0., 0.], [0., 4., 0.], [0., 4., 2.5], [0., 0., 2.5]],
    ];
    for ([x0, y0], [x1, y1], h) in [
        ([2., 1.], [3., 2.], 0.8),
        ([0.5, 2.5], [1.2, 3.5], 0.5),
        ([3.5, 0.2], [4.5, 0.9], 1.0),
    ] {
        quads.extend([
            [[x0, y0, h], [x1, y0, h], [x1, y1, h], [x0, y1, h]],
            [[x0, y0, 0.], [x1, y0, 0.], [x1, y0, h], [x0, y0, h]],
            [[x0, y1, 0.], [x1, y1, 0.], [x1, y1, h], [x0, y1, h]],
            [[x0, y0, 0.], [x0, y1, 0.], [x0, y1, h], [x0, y0, h]],
            [[x1, y0, 0.], [x1, y1, 0.], [x1, y1, h], [x1, y0, h]],
        ]);
    }
    let obj = |f: &dyn Fn([f32; 3]) -> [f32; 3]| {
        let mut text = String::new();
        for (k, q) in quads.iter().enumerate() {
            for v in q {
                let [x, y, z] = f(*v);
                text.push_str(&format!("v {x} {y} {z}\n"));
            }
            let b = 4 * k + 1;
            text.push_str(&format!(
                "f {} {} {}\nf {} {} {}\n",
                b,
                b + 1,
                b + 2,
                b,
                b + 2,
                b + 3
            ));
        }
        text
    };
    let origin = write(&dir, "origin.obj", &obj(&|v| v));
    let far = write(
        &dir,
        "far.obj",
        &obj(&|[x, y, z]| [x + 1000., y + 2000., z + 1.]),
    );
    let y_up = write(
        &dir,
        "y_up.obj",
        &obj(&|[x, y, z]| [x + 1000., z + 1., -y - 2000.]),
    );
    let out = dir.join("out").to_string_lossy().into_owned();
    let valid = |args: &[&str]| {
        let done = run(&room, &[args, &["--out", &out]].concat());
        let stdout = String::from_utf8_lossy(&done.stdout).into_owned();
        assert!(
            done.status.success(),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
        let line = stdout.lines().last().unwrap_or_default().to_string();
        let key = "\"valid_percent\":";
        let at = line.find(key).expect("valid_percent") + key.len();
        let value: String = line[at..]
            .chars()
            .take_while(|c| *c != ',' && *c != '}')
            .collect();
        (value, String::from_utf8_lossy(&done.stderr).into_owned())
    };
    let (at_origin, _) = valid(&["--scene", &origin]);
    let (moved, report) = valid(&["--scene", &far]);
    assert_eq!(moved, at_origin, "{report}");
    assert!(report.contains("floor found at z = 1.000"), "{report}");
    let (_, warned) = valid(&["--scene", &y_up]);
    assert!(warned.contains("--up y"), "{warned}");
    let (upright, report) = valid(&["--scene", &y_up, "--up", "y"]);
    assert_eq!(upright, at_origin);
    // Issue 56: read right, no warning at all; read right but 10 degrees off level, the tilt
    // is named (not the axis), and the floor that no body fits on is refused naming its
    // causes and --body-radius.
    assert!(!report.contains("warning"), "{report}");
    let (c, s) = (10f32.to_radians().cos(), 10f32.to_radians().sin());
    let tilted = write(
        &dir,
        "tilted.obj",
        &obj(&|[x, y, z]| [x, c * y - s * z, s * y + c * z]),
    );
    let done = run(&room, &["--scene", &tilted, "--out", &out]);
    let said = String::from_utf8_lossy(&done.stderr);
    assert!(
        said.contains("not level") && said.contains("10.0 degrees"),
        "{said}"
    );
    assert!(!said.contains("--up y"), "{said}");
    if !done.status.success() {
        assert!(said.contains("--body-radius"), "{said}");
    }
    // Case 7: the accessible region of the raised, far scene (refused as "no floor?" before).
    if let Some(accessible) = example("accessible") {
        let args = ["--scene", &far, "--no-field", "--json", "--samples", "2000"];
        let done = run(&accessible, &[&args[..], &["--out", &out]].concat());
        let stdout = String::from_utf8_lossy(&done.stdout);
        assert!(
            done.status.success(),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
        let key = "\"accessible_voxels\":";
        let at = stdout.find(key).expect("accessible_voxels") + key.len();
        let voxels: usize = stdout[at..]
            .chars()
            .take_while(|c| c.is_ascii_digit())
            .collect::<String>()
            .parse()
            .unwrap();
        assert!(voxels > 500, "{voxels} voxels:\n{stdout}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 36, cases 5 and 6: a region drawn from torso samples does not scale to a 100 x 100 m
/// floor (a game level's size), and says so at once instead of returning a few specks; a floor
/// the samples cover thinly gets a warning naming `--samples`.
#[test]
fn accessible_refuses_floors_too_large_and_warns_of_thin_samples() {
    let Some(accessible) = example("accessible") else {
        return;
    };
    let dir = scratch("density");
    let out = dir.join("out").to_string_lossy().into_owned();
    let floor = |side: f32| {
        format!(
            "v 0 0 0\nv {side} 0 0\nv {side} {side} 0\nv 0 {side} 0\nf 1 2 3\nf 1 3 4\n\
             v 1 1 0\nv 2 1 0\nv 2 2 0.8\nf 5 6 7\n"
        )
    };
    let big = write(&dir, "big.obj", &floor(100.0));
    let t = std::time::Instant::now();
    let args = ["--scene", &big, "--no-field", "--out", &out];
    refuses(run(&accessible, &args), "the `level` example");
    assert!(t.elapsed().as_secs() < 10, "{:?}", t.elapsed());
    let mid = write(&dir, "mid.obj", &floor(20.0));
    let done = run(
        &accessible,
        &[
            "--scene",
            &mid,
            "--no-field",
            "--samples",
            "500",
            "--json",
            "--out",
            &out,
        ],
    );
    let stderr = String::from_utf8_lossy(&done.stderr);
    assert!(stderr.contains("set --samples 96000"), "{stderr}");
    // Case 4: a 1 cm cube and nothing else. Feet touching its sides used to "stand" there;
    // a foot rests only on what lies beneath it, so nothing affords a pose, and it says so.
    let cube = write(
        &dir,
        "cube.obj",
        "v 0 0 0\nv 0.01 0 0\nv 0.01 0.01 0\nv 0 0.01 0\n\
         v 0 0 0.01\nv 0.01 0 0.01\nv 0.01 0.01 0.01\nv 0 0.01 0.01\n\
         f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n\
         f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n",
    );
    refuses(
        run(
            &accessible,
            &["--scene", &cube, "--no-field", "--out", &out],
        ),
        "no torso sample affords a pose",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 36, the cases not tried before: a field planted in `room_nav --fields` under the name
/// of another's is refused by its fingerprint; an output that is a link elsewhere is replaced,
/// its target kept; a read-only output folder gives an error naming the path (run as another
/// user where the test runs as root, since root writes anywhere).
#[test]
fn room_nav_refuses_planted_fields_and_keeps_what_links_point_at() {
    let Some(nav) = example("room_nav") else {
        return;
    };
    let dir = scratch("planted");
    let (out, fields) = (dir.join("out"), dir.join("fields"));
    std::fs::create_dir_all(&out).unwrap();
    let victim = write(&dir, "victim.txt", "keep");
    std::os::unix::fs::symlink(&victim, out.join("top.png")).unwrap();
    let (out_s, fields_s) = (out.to_string_lossy(), fields.to_string_lossy());
    let go = |steps: &str| {
        let args = [
            "--seed",
            "10001",
            "--pairs",
            "1",
            "--big-budget",
            "100",
            "--json",
        ];
        let more = [
            "--fields",
            &fields_s,
            "--field-steps",
            steps,
            "--out",
            &out_s,
        ];
        run(&nav, &[&args[..], &more].concat())
    };
    let done = go("2");
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    // Every planner's three costs (issue 34), the navigation mesh among them.
    let stdout = String::from_utf8_lossy(&done.stdout);
    let line: serde_json::Value =
        serde_json::from_str(stdout.lines().last().unwrap_or_default()).unwrap();
    for planner in ["ours", "ours_exact", "ours_raw", "prm", "navmesh"] {
        for cost in ["s", "goal_s", "room_s"] {
            let key = format!("{planner}_{cost}");
            assert!(
                line[&key].as_f64().is_some_and(|v| v >= 0.0),
                "{key}: {line}"
            );
        }
    }
    assert!(
        line["ours_goal_s"].as_f64() > Some(0.0) && line["navmesh_room_s"].as_f64() > Some(0.0)
    );
    assert!(line["distances_bytes_per_room"].as_f64() > Some(0.0));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep");
    assert!(!std::fs::symlink_metadata(out.join("top.png"))
        .unwrap()
        .is_symlink());
    // The 2-step field planted as the 3-step one of the same region.
    let kept = std::fs::read_dir(&fields)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let name = kept
        .to_string_lossy()
        .replace("_2.safetensors", "_3.safetensors");
    std::fs::copy(&kept, &name).unwrap();
    refuses(go("3"), "not a field of this region");
    // A read-only folder, as the nobody user.
    let locked = dir.join("locked");
    std::fs::create_dir_all(&locked).unwrap();
    std::fs::set_permissions(&locked, std::os::unix::fs::PermissionsExt::from_mode(0o555)).unwrap();
    let as_nobody = Command::new("setpriv")
        .args(["--reuid=65534", "--regid=65534", "--clear-groups", "--"])
        .arg(&nav)
        .args(["--out", &locked.join("out").to_string_lossy()])
        .env("RUST_BACKTRACE", "0")
        .output();
    // Without setpriv, or not as root, there is no other user to be: nothing to try.
    if let Ok(o) = as_nobody {
        if !String::from_utf8_lossy(&o.stderr).contains("setpriv:") {
            refuses(o, "locked/out");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn level_walks_up_a_ramp_and_refuses_a_level_of_one_floor() {
    let Some(level) = example("level") else {
        return;
    };
    let dir = scratch("level");
    let out = dir.join("out").to_string_lossy().into_owned();
    // A floor 9 x 3 m, a platform 1 m up over x in [5, 9] (its top and its front), and a ramp
    // from x = 2 up to the platform's edge: open sheets, as game levels often are.
    let two = write(
        &dir,
        "two.obj",
        "v 0 0 0\nv 9 0 0\nv 9 3 0\nv 0 3 0\nf 1 2 3\nf 1 3 4\n\
         v 5 0 1\nv 9 0 1\nv 9 3 1\nv 5 3 1\nf 5 6 7\nf 5 7 8\n\
         v 5 0 0\nv 5 3 0\nf 9 10 8\nf 9 8 5\n\
         v 2 0 0\nv 2 3 0\nf 11 5 8\nf 11 8 12\n",
    );
    let args = |scene: &str, rise: &str| {
        [
            "--scene",
            scene,
            "--up",
            "z",
            "--voxel",
            "0.1",
            "--pairs",
            "2",
            "--goals",
            "1",
            "--rise",
            rise,
            "--sampler-budget",
            "500",
            "--json",
            "--out",
            &out,
        ]
        .map(str::to_owned)
    };
    let done = Command::new(&level)
        .args(args(&two, "0.6"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&done.stdout);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    let summary: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();
    assert_eq!(summary["pairs"], 2, "{summary}");
    assert!(summary["rise_m_mean"].as_f64().unwrap() >= 0.6, "{summary}");
    assert_eq!(summary["ours_exact_reach_pct"], 100.0, "{summary}");
    // One floor: nothing to climb, said so.
    let flat = write(
        &dir,
        "flat.obj",
        "v 0 0 0\nv 6 0 0\nv 6 3 0\nv 0 3 0\nf 1 2 3\nf 1 3 4\n",
    );
    let a = args(&flat, "0.6");
    refuses(
        run(&level, &a.each_ref().map(String::as_str)),
        "its levels are not joined",
    );
    let a = args(&dir.join("missing.obj").to_string_lossy(), "0.6");
    refuses(
        run(&level, &a.each_ref().map(String::as_str)),
        "fetch_recast_levels.sh",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `apartments` refuses a count out of range, a furniture folder that holds none, and a VAE
/// file that is not one, naming what is wrong.
#[test]
fn apartments_refuses_bad_counts_folders_and_weights() {
    let Some(apts) = example("apartments") else {
        return;
    };
    let dir = scratch("apartments");
    refuses(run(&apts, &["--count", "0"]), "--count");
    refuses(run(&apts, &["--count", "1001"]), "--count");
    let empty = dir.to_string_lossy().into_owned();
    refuses(
        run(&apts, &["--furniture", &empty]),
        "reading the furniture",
    );
    let bad = write(&dir, "vae.safetensors", "not weights");
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sweethome3d-contrib");
    if models.is_dir() {
        refuses(
            run(
                &apts,
                &["--furniture", &models.to_string_lossy(), "--vae", &bad],
            ),
            "vae.safetensors",
        );
    }
    refuses_usage(run(&apts, &["--half", "both-and-more"]), "--half");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs a trainer that must succeed; the model it wrote to `out`.
fn trained(bin: &Path, args: &[&str], out: &str) -> Vec<u8> {
    let done = run(bin, args);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    std::fs::read(out).unwrap()
}

/// Issue 56, what a user saved is never lost: a resume that would train nothing refuses and
/// keeps the model (train_vin, train_maze); `--walks-out` is written only at the end and never
/// onto the scene; an `--out` folder holding the scene as `scene.obj` is refused before any
/// work (accessible, room_nav, level, room). And the panics and hangs of that sweep: a scene
/// reaching 1e20 m, an unbounded `--big-budget`, `--eval-mazes`, a level in centimetres.
#[test]
fn nothing_a_user_saved_is_lost_and_far_scenes_are_refused() {
    let dir = scratch("saved");
    let d = |name: &str| dir.join(name).to_string_lossy().into_owned();
    if let Some(vin) = example("train_vin") {
        let out = d("v.safetensors");
        let base = ["--size", "8", "--mazes", "8", "--eval-mazes", "4"];
        let before = trained(
            &vin,
            &[&base[..], &["--max-steps", "3", "--out", &out]].concat(),
            &out,
        );
        let ckpt = format!("{out}.ckpt");
        for steps in ["3", "2"] {
            let args = [
                &base[..],
                &["--resume", &ckpt, "--max-steps", steps, "--out", &out],
            ];
            refuses(run(&vin, &args.concat()), "trains nothing");
        }
        assert_eq!(std::fs::read(&out).unwrap(), before);
        refuses(
            run(
                &vin,
                &["--eval-mazes", "18446744073709551615", "--out", &out],
            ),
            "--eval-mazes",
        );
    }
    if let Some(train) = example("train_maze") {
        let out = d("m.safetensors");
        let base = ["--arch", "plain", "--size", "8"];
        let before = trained(
            &train,
            &[&base[..], &["--steps", "3", "--out", &out]].concat(),
            &out,
        );
        let ckpt = format!("{out}.ckpt");
        let args = [
            &base[..],
            &["--steps", "3", "--resume", &ckpt, "--out", &out],
        ];
        refuses(run(&train, &args.concat()), "trains nothing");
        // A checkpoint of another architecture than --arch (the data differ): refused, the
        // model kept (it trained the plain network on the context network's data).
        let other = [
            "--arch", "context", "--size", "8", "--steps", "9", "--resume", &ckpt, "--out", &out,
        ];
        refuses(run(&train, &other), "--arch plain");
        assert_eq!(std::fs::read(&out).unwrap(), before);
    }
    // A user's scene, named scene.obj, in the folder given as --out.
    let scene = dir.join("scene.obj");
    let text = "v 0 0 0\nv 4 0 0\nv 4 3 0\nv 0 3 0\nf 1 2 3\nf 1 3 4\n";
    std::fs::write(&scene, text).unwrap();
    let (scene_s, out_s) = (scene.to_string_lossy().into_owned(), d(""));
    for name in ["accessible", "room_nav", "room"] {
        if let Some(bin) = example(name) {
            refuses(run(&bin, &["--scene", &scene_s, "--out", &out_s]), "--out");
        }
    }
    if let Some(level) = example("level") {
        refuses(
            run(&level, &["--scene", &scene_s, "--up", "z", "--out", &out_s]),
            "--out",
        );
    }
    if let Some(nav) = example("room_nav") {
        // --walks-out onto the scene; and a run that fails keeps an old --walks-out file.
        let o = d("nav");
        refuses(
            run(
                &nav,
                &["--scene", &scene_s, "--walks-out", &scene_s, "--out", &o],
            ),
            "--walks-out",
        );
        let walks = dir.join("walks.jsonl");
        std::fs::write(&walks, "old records\n").unwrap();
        let missing = d("missing.obj");
        let args = [
            "--scene",
            &missing,
            "--walks-out",
            &walks.to_string_lossy(),
            "--out",
            &o,
        ];
        refuses(run(&nav, &args), "missing.obj");
        assert_eq!(std::fs::read_to_string(&walks).unwrap(), "old records\n");
        refuses(
            run(&nav, &["--big-budget", "1000000000", "--out", &o]),
            "--big-budget",
        );
    }
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), text);
    // Coordinates reaching 1e20 m: refused naming the vertex, never a panic in parry3d.
    let far = dir.join("far.obj");
    std::fs::write(&far, "v 0 0 0\nv 4e20 0 0\nv 4e20 3 0\nf 1 2 3\n").unwrap();
    if let Some(room) = example("room") {
        refuses(
            run(
                &room,
                &["--scene", &far.to_string_lossy(), "--out", &d("r")],
            ),
            "vertex 1",
        );
    }
    // A level 800 m wide (an apartment in centimetres, read as metres): refused at once,
    // naming --units, where it built millions of columns for minutes.
    let wide = dir.join("wide.obj");
    std::fs::write(
        &wide,
        "v 0 0 0\nv 800 0 0\nv 800 600 0\nv 0 600 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    if let Some(level) = example("level") {
        let t = std::time::Instant::now();
        refuses(
            run(
                &level,
                &[
                    "--scene",
                    &wide.to_string_lossy(),
                    "--up",
                    "z",
                    "--out",
                    &d("l"),
                ],
            ),
            "--units",
        );
        assert!(t.elapsed().as_secs() < 60);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 56, flags that would be ignored are refused: `accessible --scene S --rooms N` (it
/// evaluated generated rooms and never read S), `birdseye_multi --room S --rooms N` the same,
/// `accessible --field-steps 0` (figures of an untrained field), `room_nav --save-field` with
/// several rooms (it saved nothing).
#[test]
fn flags_that_would_be_ignored_are_refused() {
    let dir = scratch("ignored");
    let scene = dir.join("s.obj");
    std::fs::write(&scene, "v 0 0 0\nv 4 0 0\nv 4 3 0\nf 1 2 3\n").unwrap();
    let (s, out) = (
        scene.to_string_lossy().into_owned(),
        dir.join("o").to_string_lossy().into_owned(),
    );
    if let Some(acc) = example("accessible") {
        refuses(
            run(&acc, &["--scene", &s, "--rooms", "1", "--out", &out]),
            "--scene",
        );
        refuses(
            run(&acc, &["--field-steps", "0", "--out", &out]),
            "--field-steps",
        );
    }
    if let Some(crowd) = example("birdseye_multi") {
        refuses(
            run(&crowd, &["--room", &s, "--rooms", "2", "--out", &out]),
            "--rooms",
        );
    }
    if let Some(nav) = example("room_nav") {
        let field = dir.join("f.safetensors").to_string_lossy().into_owned();
        refuses(
            run(
                &nav,
                &["--save-field", &field, "--rooms", "2", "--out", &out],
            ),
            "--save-field",
        );
        // Where fields go is checked before the training, not after it.
        refuses(
            run(&nav, &["--fields", &s, "--pairs", "1", "--out", &out]),
            "is a file",
        );
        let missing = dir.join("no/such/f.safetensors");
        refuses(
            run(
                &nav,
                &["--save-field", &missing.to_string_lossy(), "--out", &out],
            ),
            "--save-field",
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 56: `room_nav --fields DIR` on a scene keeps the trained field and loads it on the
/// next run (it kept nothing: every run trained again).
#[test]
fn a_scenes_field_is_kept_and_found_again() {
    let (Some(acc), Some(nav)) = (example("accessible"), example("room_nav")) else {
        return;
    };
    let dir = scratch("scene_fields");
    let room = dir.join("room").to_string_lossy().into_owned();
    let made = run(&acc, &["--no-field", "--out", &room]);
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let scene = format!("{room}/scene.obj");
    let (fields, out) = (
        dir.join("fields").to_string_lossy().into_owned(),
        dir.join("out").to_string_lossy().into_owned(),
    );
    let go = || {
        let args = ["--scene", &scene, "--fields", &fields, "--field-steps", "2"];
        let more = [
            "--planners",
            "ours",
            "--pairs",
            "1",
            "--json",
            "--out",
            &out,
        ];
        run(&nav, &[&args[..], &more].concat())
    };
    let first = go();
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let kept = std::fs::read_dir(&fields).unwrap().count();
    assert_eq!(kept, 1, "one field kept for the scene");
    let second = go();
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(second.status.success(), "{err}");
    assert!(err.contains("field loaded from"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 53, the 3D party: in an apartment furnished with models never trained or tuned on,
/// four people walk in from other rooms and sit at its dining table, its chairs pulled out
/// first, while two others walk through; no two bodies overlap at any frame (bones as
/// capsules, every pair), every pose is checked against the scene. With the chairs left
/// tucked under the table (`--as-found`) nobody sits at it. Needs the contributed furniture (scripts/fetch_sweethome3d_contrib.sh).
#[test]
fn a_party_of_four_sits_down_with_no_body_overlapping() {
    let Some(party) = example("party") else {
        return;
    };
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sweethome3d-contrib");
    if !models.is_dir() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true: the contributed furniture is not fetched"
        );
        return;
    }
    let lines = |extra: &[&str]| {
        let mut args = vec![
            "--apartments",
            "1",
            "--seed",
            "31018",
            "--passers",
            "2",
            "--json",
        ];
        args.extend_from_slice(extra);
        let done = run(&party, &args);
        assert!(
            done.status.success(),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
        String::from_utf8_lossy(&done.stdout)
            .lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
            .collect::<Vec<_>>()
    };
    let laid = lines(&[]);
    let (one, summary) = (&laid[0], laid.last().unwrap());
    assert_eq!(one["at"], "table", "{one}");
    assert!(
        one["chairs_pulled_m"]
            .as_array()
            .unwrap()
            .iter()
            .all(|m| m.as_f64().unwrap() > 0.2),
        "{one}"
    );
    assert_eq!(summary["body_overlaps"], 0, "{summary}");
    assert!(summary["seated_pct"].as_f64().unwrap() >= 75.0, "{summary}");
    assert!(
        summary["passers_through"].as_u64().unwrap() >= 1,
        "{summary}"
    );
    assert!(summary["valid_pct"].as_f64().unwrap() >= 95.0, "{summary}");
    let found = lines(&["--as-found"]);
    assert_eq!(found[0]["at"], "room", "{}", found[0]);
    refuses(run(&party, &["--people", "9"]), "--people");
}
