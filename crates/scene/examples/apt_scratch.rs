//! scratch
use envfield_scene::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let half = if args[1] == "eval" {
        Half::Evaluation
    } else {
        Half::Training
    };
    let seed: u64 = args[2].parse().unwrap();
    let c = Catalogue::read("data/sweethome3d-contrib")
        .unwrap()
        .only(half);
    let t = std::time::Instant::now();
    let a = apartment(&c, &ApartmentConfig::default(), seed).unwrap();
    println!(
        "built in {:.2}s size {:?} rooms {:?}",
        t.elapsed().as_secs_f32(),
        a.home.size,
        a.rooms.iter().map(|r| r.kind).collect::<Vec<_>>()
    );
    println!(
        "doors {:?}",
        a.doors
            .iter()
            .map(|d| (d.center, d.width, d.rooms))
            .collect::<Vec<_>>()
    );
    for (f, i) in a.home.furniture.iter().zip(&a.items) {
        println!(
            "  {:?} {} at {:?} yaw {:.2} seat {:?}",
            c.items[*i].role, c.items[*i].name, f.center, f.yaw, f.seat_height
        );
    }
    let m = a.home.scene.to_mesh();
    println!("triangles {}", m.triangles.len());
    m.write(format!("/tmp/apt_{}_{seed}.obj", args[1])).unwrap();
}
