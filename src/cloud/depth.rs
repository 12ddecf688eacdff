//! Depth images: a 16-bit greyscale PNG (Kinect, RealSense, ScanNet, TUM and SUN RGB-D
//! style) and pinhole intrinsics give a cloud in the camera's optical frame (x right,
//! y down, z forward, metres). A depth of 0 means "no measurement" and gives no point.

use std::path::Path;

use nalgebra::Point3;

use super::source::Intrinsics;
use super::CloudError;

/// Largest decoded image accepted, bytes: a 16-bit image of 8192 x 8192 pixels, far above
/// any depth camera, so that a forged header cannot ask for gigabytes.
const MAX_IMAGE_BYTES: usize = 8192 * 8192 * 2;

/// Back-projects pixel (`u`, `v`) at depth `z` (metres) through `k`: the point in the
/// camera's optical frame.
pub fn back_project(k: &Intrinsics, u: f64, v: f64, z: f64) -> Point3<f64> {
    Point3::new((u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z)
}

/// Reads a 16-bit greyscale depth PNG: every pixel with a non-zero value `d` gives the
/// point at depth `d * scale` metres on its ray ([`back_project`]), row after row.
pub fn read_depth_png(
    path: &Path,
    k: &Intrinsics,
    scale: f64,
) -> Result<Vec<Point3<f64>>, CloudError> {
    let bad = |what: String| CloudError::Header {
        path: path.to_path_buf(),
        at: "PNG header".into(),
        what,
    };
    if !(scale.is_finite() && scale > 0.0) {
        return Err(super::source::select_error(
            path,
            format!("--depth-scale {scale}: must be a positive number of metres per unit"),
        ));
    }
    let file = std::fs::File::open(path).map_err(|source| CloudError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut dec = png::Decoder::new_with_limits(
        std::io::BufReader::new(file),
        png::Limits {
            bytes: MAX_IMAGE_BYTES,
        },
    );
    dec.set_transformations(png::Transformations::IDENTITY);
    let mut reader = dec.read_info().map_err(|e| bad(e.to_string()))?;
    let (colour, depth) = reader.output_color_type();
    if colour != png::ColorType::Grayscale || depth != png::BitDepth::Sixteen {
        return Err(bad(format!(
            "a depth image is 16-bit greyscale, this one is {depth:?}-bit {colour:?}"
        )));
    }
    let size = reader
        .output_buffer_size()
        .filter(|&n| n <= MAX_IMAGE_BYTES)
        .ok_or_else(|| bad("the image is larger than 8192 x 8192 pixels".into()))?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(|e| CloudError::Body {
        path: path.to_path_buf(),
        at: "image data".into(),
        what: e.to_string(),
    })?;
    let (w, h, stride) = (info.width as usize, info.height as usize, info.line_size);
    let mut points = Vec::new();
    for v in 0..h {
        let row = buf.get(v * stride..v * stride + 2 * w).unwrap_or(&[]);
        for (u, px) in row.chunks_exact(2).enumerate() {
            let d = u16::from_be_bytes([px[0], px[1]]);
            if d > 0 {
                points.push(back_project(k, u as f64, v as f64, d as f64 * scale));
            }
        }
    }
    Ok(points)
}

/// Writes `depth` (row-major, `width` pixels a row, raw 16-bit units) as a 16-bit
/// greyscale PNG: the inverse of [`read_depth_png`], for tests and examples.
pub fn write_depth_png(path: &Path, width: u32, depth: &[u16]) -> std::io::Result<()> {
    let height = u32::try_from(depth.len() / width.max(1) as usize).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "a depth image of more than 4294967295 rows",
        )
    })?;
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, height);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let mut w = enc.write_header().map_err(std::io::Error::other)?;
        let data: Vec<u8> = depth.iter().flat_map(|d| d.to_be_bytes()).collect();
        w.write_image_data(&data).map_err(std::io::Error::other)?;
    }
    crate::report::atomic::write_bytes(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixels_back_project_on_their_rays_and_zero_is_no_point() {
        let k = Intrinsics {
            fx: 100.0,
            fy: 50.0,
            cx: 1.0,
            cy: 0.5,
        };
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("d.png");
        // 3 x 2: row 0 = 1000, 0, 2000; row 1 = 500, 500, 0 (millimetres).
        write_depth_png(&p, 3, &[1000, 0, 2000, 500, 500, 0]).unwrap();
        let pts = read_depth_png(&p, &k, 0.001).unwrap();
        let want = [
            Point3::new(-0.01, -0.01, 1.0),
            Point3::new(0.02, -0.02, 2.0),
            Point3::new(-0.005, 0.005, 0.5),
            Point3::new(0.0, 0.005, 0.5),
        ];
        assert_eq!(pts.len(), want.len());
        for (a, b) in pts.iter().zip(&want) {
            assert!((a - b).norm() < 1e-12, "{a} vs {b}");
        }
    }

    #[test]
    fn colour_and_eight_bit_images_are_refused_with_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("rgb.png");
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, 2, 1);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().unwrap();
            w.write_image_data(&[0; 6]).unwrap();
        }
        std::fs::write(&p, &bytes).unwrap();
        let k = Intrinsics {
            fx: 1.0,
            fy: 1.0,
            cx: 0.0,
            cy: 0.0,
        };
        let e = read_depth_png(&p, &k, 0.001).unwrap_err().to_string();
        assert!(
            e.contains("rgb.png") && e.contains("16-bit greyscale"),
            "{e}"
        );
        let e = read_depth_png(&p, &k, 0.0).unwrap_err().to_string();
        assert!(e.contains("--depth-scale"), "{e}");
    }
}
