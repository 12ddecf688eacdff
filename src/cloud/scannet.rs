//! ScanNet scene meta files (`scene0000_00.txt`): the `axisAlignment = m00 m01 ... m33`
//! line holds the 4x4 row-major matrix that brings the scan's mesh and clouds into an
//! axis-aligned frame (z up, metres). `--transform` takes that line, or the whole file.

/// The matrix text of the `axisAlignment` line of `text`, if `text` has one (the line as
/// ScanNet writes it, or the whole meta file); `None` otherwise.
pub(crate) fn axis_alignment(text: &str) -> Option<&str> {
    text.lines().find_map(|line| {
        let (key, value) = line.split_once('=')?;
        (key.trim() == "axisAlignment").then_some(value)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::frame::parse_matrix;

    #[test]
    fn the_line_or_the_whole_meta_file_gives_the_matrix() {
        let line = "axisAlignment = 0.945519 0.325568 0 -5.38439 -0.325568 0.945519 0 \
                    -2.87178 0 0 1 -0.06435 0 0 0 1";
        let meta = format!(
            "colorHeight = 968\ncolorToDepthExtrinsics = 0.999973 0.006791 0.003067 \
             -0.037687 -0.006784 0.999976 -0.002406 -0.003139 -0.003084 0.002385 \
             0.999992 -0.021237 0 0 0 1\n{line}\nnumDepthFrames = 5578\n"
        );
        for text in [line.to_string(), meta] {
            let m = parse_matrix(&text).unwrap();
            assert_eq!(m[(0, 0)], 0.945519);
            assert_eq!(m[(0, 3)], -5.38439);
            assert_eq!(m[(1, 0)], -0.325568);
            assert_eq!(m[(2, 3)], -0.06435);
            assert_eq!(m[(3, 3)], 1.0);
        }
        // A meta file without the line is not a matrix.
        let e = parse_matrix("colorHeight = 968\nnumDepthFrames = 5578\n").unwrap_err();
        assert!(e.contains("not a number"), "{e}");
        assert_eq!(axis_alignment("1 0 0 0"), None);
    }
}
