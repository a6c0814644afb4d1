//! Whitespace-separated numeric text files (TUM, KITTI, relations): split a
//! line into a fixed number of finite numbers, or say which line and column is bad.

use crate::error::InputError;
use std::path::Path;

/// Reads a whole text file, mapping I/O failures to an [`InputError`].
pub(crate) fn read_text(path: &Path) -> Result<String, InputError> {
    std::fs::read_to_string(path)
        .map_err(|e| InputError::new(path.display().to_string(), format!("cannot read: {e}")))
}

/// Parses exactly `N` finite numbers from `line` (1-based `line_no` for messages).
pub(crate) fn fields<const N: usize>(
    file: &str,
    kind: &str,
    line_no: usize,
    line: &str,
) -> Result<[f64; N], InputError> {
    let bad = |msg: String| {
        InputError::new(file, msg)
            .topic(kind)
            .at(format!("line {line_no}"))
    };
    let tokens: Vec<&str> = line.split_whitespace().collect();
    if tokens.len() != N {
        return Err(bad(format!(
            "expected {N} numbers, found {} fields",
            tokens.len()
        )));
    }
    let mut out = [0.0; N];
    for (i, tok) in tokens.iter().enumerate() {
        let v: f64 = tok
            .parse()
            .map_err(|_| bad(format!("column {}: '{tok}' is not a number", i + 1)))?;
        if !v.is_finite() {
            return Err(bad(format!("column {}: '{tok}' is not finite", i + 1)));
        }
        out[i] = v;
    }
    Ok(out)
}

/// Lines that carry data: 1-based line number and text, skipping blank lines
/// and `#` comments.
pub(crate) fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines().enumerate().filter_map(|(i, l)| {
        let t = l.trim();
        (!t.is_empty() && !t.starts_with('#')).then_some((i + 1, t))
    })
}
