//! Plain-text point lists (`.xyz`, `.txt`, `.csv`): one point per line, `x y z` first.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use nalgebra::Point3;

use super::ply::{body_err, io_err, read_line_capped, shorten, Line};
use super::CloudError;

/// Longest line accepted, in bytes.
const MAX_LINE: usize = 1 << 20;

/// Reads a text point list: per line, the first three numbers are x, y, z in metres; further
/// values (colour, intensity, ...) are ignored.
///
/// Values are separated by whitespace and/or commas. Blank lines and lines starting with `#`
/// or `//` are skipped, and so is one leading header line that does not start with three
/// numbers (e.g. `x,y,z`). A file without any point is an error. NaN values are kept.
pub fn read_xyz(path: &Path) -> Result<Vec<Point3<f64>>, CloudError> {
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    let mut r = BufReader::with_capacity(1 << 16, file);
    let mut out = Vec::new();
    let mut lineno = 0usize;
    let mut header_seen = false;
    loop {
        lineno += 1;
        let at = format!("line {lineno}");
        let bytes = match read_line_capped(&mut r, MAX_LINE).map_err(|e| io_err(path, e))? {
            Line::Eof => break,
            Line::TooLong => return Err(body_err(path, at, "line too long")),
            Line::Text(b, _) => b,
        };
        let Ok(text) = std::str::from_utf8(&bytes) else {
            return Err(body_err(path, at, "line is not text"));
        };
        let text = text.trim_start_matches('\u{feff}').trim();
        if text.is_empty() || text.starts_with('#') || text.starts_with("//") {
            continue;
        }
        let mut toks = text
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty());
        let mut xyz = [0f64; 3];
        let mut bad = None;
        for (k, v) in xyz.iter_mut().enumerate() {
            match toks.next() {
                None => {
                    bad = Some(format!("expected 3 numbers x y z, found {k}"));
                    break;
                }
                Some(t) => match t.parse::<f64>() {
                    Ok(x) => *v = x,
                    Err(_) => {
                        bad = Some(format!("'{}' is not a number", shorten(t)));
                        break;
                    }
                },
            }
        }
        match bad {
            None => out.push(Point3::from(xyz)),
            Some(_) if out.is_empty() && !header_seen => header_seen = true,
            Some(what) => return Err(body_err(path, at, what)),
        }
    }
    if out.is_empty() {
        return Err(body_err(
            path,
            format!("line {}", lineno.saturating_sub(1).max(1)),
            "no points in file",
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn file(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let p = dir.path().join(name);
        std::fs::File::create(&p).unwrap().write_all(bytes).unwrap();
        p
    }

    #[test]
    fn csv_with_header_comments_and_extra_columns() {
        let dir = tempfile::tempdir().unwrap();
        let p = file(
            &dir,
            "a.csv",
            b"x,y,z,intensity\r\n# comment\n\n1.5,-2,3e-1,7\n// c++ comment\n  4 , 5,6\n",
        );
        let pts = read_xyz(&p).unwrap();
        assert_eq!(
            pts,
            vec![Point3::new(1.5, -2.0, 0.3), Point3::new(4.0, 5.0, 6.0)]
        );
    }

    #[test]
    fn whitespace_separated_keeps_nan() {
        let dir = tempfile::tempdir().unwrap();
        let p = file(&dir, "a.xyz", b"0 0 0\n1\t2  3 255 0 0\nnan 1 2\n");
        let pts = read_xyz(&p).unwrap();
        assert_eq!(pts.len(), 3);
        assert_eq!(pts[1], Point3::new(1.0, 2.0, 3.0));
        assert!(pts[2].x.is_nan() && pts[2].z == 2.0);
    }

    #[test]
    fn point_count_first_line_is_skipped_as_header() {
        let dir = tempfile::tempdir().unwrap();
        let p = file(&dir, "a.txt", b"2\n1 2 3\n4 5 6\n");
        assert_eq!(read_xyz(&p).unwrap().len(), 2);
    }

    #[test]
    fn bad_line_after_data_is_an_error_naming_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = file(&dir, "a.xyz", b"x y z\n1 2 3\n4 five 6\n");
        let e = read_xyz(&p).unwrap_err();
        assert!(
            matches!(e, CloudError::Body { ref at, .. } if at == "line 3"),
            "{e}"
        );
        assert!(e.to_string().contains("'five' is not a number"), "{e}");
        let p = file(&dir, "b.xyz", b"1 2 3\n4 5\n");
        let e = read_xyz(&p).unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
    }

    #[test]
    fn second_header_line_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = file(&dir, "a.xyz", b"x y z\nunits m m m\n1 2 3\n");
        let e = read_xyz(&p).unwrap_err();
        assert!(
            matches!(e, CloudError::Body { ref at, .. } if at == "line 2"),
            "{e}"
        );
    }

    #[test]
    fn empty_garbage_and_missing_files_fail_cleanly() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_xyz(&file(&dir, "e.xyz", b"")).unwrap_err();
        assert!(matches!(e, CloudError::Body { .. }), "{e}");
        let e = read_xyz(&file(&dir, "h.xyz", b"x,y,z\n")).unwrap_err();
        assert!(matches!(e, CloudError::Body { .. }), "{e}");
        let e = read_xyz(&file(&dir, "g.xyz", &[0xff, 0xfe, 0x00, 0x81, b'\n', 1, 2])).unwrap_err();
        assert!(
            matches!(e, CloudError::Body { ref at, .. } if at == "line 1"),
            "{e}"
        );
        let e = read_xyz(&dir.path().join("missing.xyz")).unwrap_err();
        assert!(matches!(e, CloudError::Io { .. }), "{e}");
        assert!(!e.to_string().contains('\n'));
    }
}
