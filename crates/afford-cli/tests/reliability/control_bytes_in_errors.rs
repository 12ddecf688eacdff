//! Cause: error lines echoed bytes of the file and its name raw, so a NUL or an ANSI
//! escape reached the terminal and a newline in a file name split the one-line error in
//! two. Lines printed by `detect` now escape control characters (`afford_cli::batch::printable`).

use crate::common::*;

#[test]
fn control_bytes_and_newlines_are_escaped_in_the_one_line_error() {
    let d = tempfile::tempdir().unwrap();
    let bad = d.path().join("two\nlines.xyz");
    std::fs::write(&bad, b"0 0 \x1b[31mred\x00\n").unwrap();
    let o = afford(&["detect", &s(&bad)]);
    assert_eq!(o.status.code(), Some(2));
    let err = text(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err:?}");
    assert!(!err.contains('\u{1b}') && !err.contains('\0'), "{err:?}");
    assert!(err.contains("two\\nlines.xyz"), "{err:?}");
    assert_eq!(
        afford_cli::batch::printable("a\u{1b}[31m\n"),
        "a\\u{1b}[31m\\n"
    );
}
