//! Cause: a triangle with corners near 1e200 has a NaN area (the cross product overflows),
//! so the total area was NaN, `area * density > cap` was false, and a 1 km triangle beside
//! it was sampled at 5e9 points. Triangles of non-finite area are now left out of the
//! sampling, so the cap holds.

use afford::cloud::mesh::{expected_samples, sample_mesh, MAX_SAMPLES};
use afford::mesh::{Mesh, Part};
use nalgebra::Point3;

#[test]
fn a_nan_area_triangle_does_not_lift_the_sample_cap() {
    let mesh = Mesh {
        vertices: vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1000.0, 0.0, 0.0),
            Point3::new(0.0, 1000.0, 0.0),
            Point3::new(1e200, 0.0, 0.0),
            Point3::new(0.0, 1e200, 0.0),
            Point3::new(-1e200, -1e200, 1e200),
        ],
        triangles: vec![[0, 1, 2], [3, 4, 5]],
        parts: vec![Part::Other, Part::Other],
    };
    assert!(!mesh.area().is_finite());
    // 5e5 m^2 at 1 point per m^2 is under the cap: sampled as asked.
    let few = sample_mesh(&mesh, 1.0, 0);
    assert!((few.len() as f64 - 5e5).abs() < 5e3, "{}", few.len());
    assert!(few.points.iter().all(|p| p.x.abs() <= 1000.0));
    // 1e4 per m^2 would be 5e9: capped.
    let capped = expected_samples(&mesh, 1e4);
    assert!(capped <= MAX_SAMPLES * (1.0 + 1e-9), "{capped}");
}
