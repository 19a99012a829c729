//! An apartment's region and its rooms: a door narrower than a body leaves the rooms behind
//! it out of the region, and `rooms_reached` says which. Needs Sweet Home 3D's default
//! catalogue (`scripts/fetch_sweethome3d.sh`); without it the test says it did not run, and
//! under CI (`CI=true`) it fails.

use envfield_affordance::{afford, standing_pose, FilterConfig};
use envfield_rooms::quality::rooms_reached;
use envfield_rooms::{AccessibleRegion, RegionConfig};
use envfield_scene::{apartment, Apartment, ApartmentConfig, Catalogue};
use std::path::Path;

fn catalogue(test: &str) -> Option<Catalogue> {
    let dir = Catalogue::find().or_else(|| {
        let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/sweethome3d");
        d.is_dir().then_some(d)
    });
    match dir {
        Some(d) => Some(Catalogue::read(d).expect("the catalogue reads")),
        None => {
            let reason =
                "the Sweet Home 3D catalogue is not fetched (scripts/fetch_sweethome3d.sh)";
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "CI=true: {reason}"
            );
            eprintln!("{test} did not run: {reason}");
            None
        }
    }
}

/// The region of standing torsos on a 0.2 m grid over the apartment's floor, as the filter
/// keeps them.
fn standing_region(apt: &Apartment) -> AccessibleRegion {
    let z = standing_pose().torso().z;
    let config = RegionConfig::default();
    let [w, d] = apt.home.size;
    let mut kept = Vec::new();
    for i in 0..(w / 0.2) as usize {
        for j in 0..(d / 0.2) as usize {
            let p = [0.1 + 0.2 * i as f32, 0.1 + 0.2 * j as f32, z];
            if afford(&apt.home.scene, p, &FilterConfig::default())
                .unwrap()
                .kept()
            {
                kept.push(p);
            }
        }
    }
    AccessibleRegion::from_kept(&apt.home.scene, kept, &config).unwrap()
}

#[test]
fn a_door_narrower_than_a_body_leaves_the_rooms_behind_it_unreached() {
    let Some(cat) = catalogue("a_door_narrower_than_a_body_leaves_the_rooms_behind_it_unreached")
    else {
        return;
    };
    let wide = ApartmentConfig {
        rooms: [2, 2],
        ..ApartmentConfig::default()
    };
    let apt = apartment(&cat, &wide, 7).unwrap();
    let region = standing_region(&apt);
    assert_eq!(rooms_reached(&apt, &region), vec![true, true]);
    // The same plan with a 0.3 m door: one room only, and the figure says which.
    let narrow = ApartmentConfig {
        door_width: [0.3, 0.3],
        ..wide
    };
    let apt = apartment(&cat, &narrow, 7).unwrap();
    let region = standing_region(&apt);
    let reached = rooms_reached(&apt, &region);
    assert_eq!(reached.iter().filter(|r| **r).count(), 1, "{reached:?}");
}
