//! Seeded scenes at the sizes of issue 12 (speed), for benchmarks and timed runs:
//!
//! - `chair_view`: one depth-camera view (Kinect-like, 640 x 480) of an armchair on its
//!   floor (100k-300k points);
//! - `room_view`: one depth view (640 x 480, up to 6 m) of a furnished room corner
//!   (200k-300k points);
//! - `room_scan`: the same room sampled from all its surfaces (about 1M points);
//! - `big_floor`: one chair on a 200 m x 200 m floor sampled every metre (issue 15: a
//!   large connected scene whose bounding box is far larger than what a body reaches).
//!
//! World frame: metres, z up, floor at z = 0. Deterministic: same points on every call.

use nalgebra::Point3;

use super::camera::{render_view, Camera};
use crate::furniture::*;
use afford::cloud::PointCloud;
use afford::mesh::Mesh;

/// Points wanted in the complete room scan (issue 12: "a 1M-point room scan").
pub const ROOM_SCAN_POINTS: f64 = 1.0e6;
/// Edge of the big floor, metres (issue 15: "a 200 m x 200 m floor").
pub const BIG_FLOOR_EDGE: f64 = 200.0;

/// One chair in the middle of a [`BIG_FLOOR_EDGE`] square floor: the chair and a patch of
/// floor around it sampled as a depth camera at 1-2 m would (30,000 points per m^2, 5-6 mm
/// apart), the rest of the floor every metre (one connected region; the units check,
/// seeing points a metre apart, warns that it may be centimetres).
pub fn big_floor() -> PointCloud {
    let mid = BIG_FLOOR_EDGE / 2.0;
    let mut pts = scene_cloud(
        &[chair(&ChairParams::default()).placed(mid, mid, 0.0)],
        30_000.0,
        0.0,
        4,
        true,
    )
    .points;
    let n = crate::count(BIG_FLOOR_EDGE);
    for i in 0..=n {
        for j in 0..=n {
            pts.push(Point3::new(i as f64, j as f64, 0.0));
        }
    }
    PointCloud::new(pts)
}

/// The furniture of a room corner: an armchair, a chair at a table, a stool, a three-seat
/// sofa, a bed, and two walls meeting in a corner (the committed sample's layout, with a
/// bed).
pub fn room_meshes() -> Vec<Mesh> {
    vec![
        chair(&ChairParams::with_arms()).placed(0.0, 0.0, 0.0),
        table(&TableParams::default()).placed(2.2, 0.0, 0.0),
        chair(&ChairParams::default()).placed(1.35, 0.0, 0.0),
        stool(&StoolParams::default()).placed(0.0, 1.6, 0.0),
        sofa(&SofaParams {
            seats: 3,
            ..SofaParams::default()
        })
        .placed(2.6, 2.1, 180.0),
        bed(&BedParams::single()).placed(1.6, -2.2, 0.0),
        // Two walls meeting in the corner (-0.6, -3.0): along x = -0.6 and along y = -3.0.
        wall(-0.6, -3.0, 3.2, 2.4, 0.1),
        wall(3.0, -0.6, 4.0, 2.4, 0.1).placed(0.0, 0.0, -90.0),
    ]
}

/// One depth view of `meshes` (floor added) from `position` towards `target`, measured
/// up to `max_range` metres.
fn view(
    meshes: &[Mesh],
    position: Point3<f64>,
    target: Point3<f64>,
    max_range: f64,
    seed: u64,
) -> PointCloud {
    let mesh = scene_mesh(meshes, true);
    let camera = Camera {
        max_range,
        ..Camera::looking_at(position, target)
    };
    render_view(&mesh, &camera, seed).0
}

/// The four scenes, by name, in the order chair view, room view, room scan, big floor.
pub fn speed_scenes() -> Vec<(&'static str, PointCloud)> {
    // A Kinect v1 (0.5-4 m) 2 m in front of an armchair, a little above it.
    let chair_view = view(
        &[armchair(&SofaParams::default())],
        Point3::new(1.9, 0.3, 1.5),
        Point3::new(0.0, 0.0, 0.3),
        4.0,
        1,
    );
    let room = room_meshes();
    // A longer-range depth camera (stereo, usable to 6 m) in the open corner of the room,
    // looking at the walls' corner over the furniture.
    let room_view = view(
        &room,
        Point3::new(4.2, 2.8, 1.9),
        Point3::new(0.9, -0.6, 0.3),
        6.0,
        2,
    );
    let area = scene_mesh(&room, true).area();
    let room_scan = scene_cloud(&room, ROOM_SCAN_POINTS / area, 0.003, 3, true);
    vec![
        ("chair_view", chair_view),
        ("room_view", room_view),
        ("room_scan", room_scan),
        ("big_floor", big_floor()),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_have_the_sizes_they_claim() {
        let scenes = speed_scenes();
        let size = |name: &str| scenes.iter().find(|(n, _)| *n == name).unwrap().1.len();
        assert!(
            (100_000..=300_000).contains(&size("chair_view")),
            "{}",
            size("chair_view")
        );
        assert!(
            (200_000..=300_000).contains(&size("room_view")),
            "{}",
            size("room_view")
        );
        let floor = scenes.iter().find(|(n, _)| *n == "big_floor").unwrap();
        let (lo, hi) = floor.1.bounds().unwrap();
        assert_eq!((hi.x - lo.x, hi.y - lo.y), (BIG_FLOOR_EDGE, BIG_FLOOR_EDGE));
        assert!(size("big_floor") > 40_401, "{}", size("big_floor"));
        let scan = size("room_scan") as f64;
        assert!(
            (scan - ROOM_SCAN_POINTS).abs() < 0.02 * ROOM_SCAN_POINTS,
            "{scan}"
        );
    }
}
