//! What envfield's examples and benches share, so that each example stays arguments, calls
//! and printing: the scene flags (`--scene --up --units --catalogue`) as one clap group with
//! its loader ([`SceneArgs`]), and the navigation-mesh baseline of the room tables
//! ([`Navmesh`]: Recast's pipeline in Rust and Polyanya's any-angle search, crates the
//! library must not depend on). Not published.

mod motion_out;
mod navmesh;
mod scene_args;
mod viewer;

pub use motion_out::MotionArgs;
pub use navmesh::{Navmesh, NavmeshConfig};
pub use scene_args::{RoomMaker, SceneArgs};
pub use viewer::{viewer_page, ThreeJs};
