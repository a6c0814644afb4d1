//! A small markdown builder for a run's `report.md`: headings, paragraphs,
//! settings lists, tables and images, written atomically.

use super::VizError;
use std::fmt::Write as _;
use std::path::Path;

/// A markdown document under construction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    text: String,
}

/// Escapes the characters that would break a table cell or inline text.
fn cell(s: &str) -> String {
    s.replace('\\', "\\\\")
        .replace('|', "\\|")
        .replace(['\n', '\r'], " ")
}

impl Report {
    /// An empty report.
    pub fn new() -> Self {
        Self::default()
    }

    fn block(&mut self) {
        if !self.text.is_empty() && !self.text.ends_with("\n\n") {
            self.text.push('\n');
        }
    }

    /// A heading of `level` 1–6 (clamped).
    pub fn heading(&mut self, level: usize, title: &str) -> &mut Self {
        self.block();
        let hashes = "#".repeat(level.clamp(1, 6));
        let _ = writeln!(self.text, "{hashes} {}", cell(title));
        self
    }

    /// A paragraph of free text (markdown allowed).
    pub fn paragraph(&mut self, text: &str) -> &mut Self {
        self.block();
        let _ = writeln!(self.text, "{}", text.trim_end());
        self
    }

    /// A settings list: `- **key**: value` per pair.
    pub fn kv<K: AsRef<str>, V: AsRef<str>>(&mut self, pairs: &[(K, V)]) -> &mut Self {
        self.block();
        for (k, v) in pairs {
            let _ = writeln!(
                self.text,
                "- **{}**: {}",
                cell(k.as_ref()),
                cell(v.as_ref())
            );
        }
        self
    }

    /// A table. Rows shorter than the header are padded with empty cells;
    /// longer rows are an error (a silently cut column would mislead).
    pub fn table<S: AsRef<str>>(
        &mut self,
        headers: &[&str],
        rows: &[Vec<S>],
    ) -> Result<&mut Self, VizError> {
        if headers.is_empty() {
            return Err(VizError::Input("table without columns".into()));
        }
        if let Some(r) = rows.iter().find(|r| r.len() > headers.len()) {
            return Err(VizError::Input(format!(
                "table row has {} cells for {} columns",
                r.len(),
                headers.len()
            )));
        }
        self.block();
        let line = |cells: Vec<String>| format!("| {} |\n", cells.join(" | "));
        self.text
            .push_str(&line(headers.iter().map(|h| cell(h)).collect()));
        self.text
            .push_str(&line(headers.iter().map(|_| "---".to_string()).collect()));
        for r in rows {
            let mut cells: Vec<String> = r.iter().map(|c| cell(c.as_ref())).collect();
            cells.resize(headers.len(), String::new());
            self.text.push_str(&line(cells));
        }
        Ok(self)
    }

    /// An image (path relative to the report) with its caption below.
    pub fn image(&mut self, path: &str, caption: &str) -> &mut Self {
        self.block();
        let _ = writeln!(
            self.text,
            "![{}]({})\n\n*{}*",
            cell(caption),
            path.replace(' ', "%20"),
            cell(caption)
        );
        self
    }

    /// The markdown so far.
    pub fn as_str(&self) -> &str {
        &self.text
    }

    /// Writes the markdown to `path` atomically.
    pub fn write(&self, path: &Path) -> Result<(), VizError> {
        crate::io::atomic::write_bytes_atomic(path, self.text.as_bytes())
            .map_err(|e| VizError::io(path, e))
    }
}

/// Formats a number with `decimals` places, or `—` when it is not finite
/// (so a table never shows `NaN`).
pub fn num(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        "—".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_escapes_pipes_and_pads_short_rows() {
        let mut r = Report::new();
        r.table(&["a", "b"], &[vec!["x|y"], vec!["1", "2"]])
            .unwrap();
        assert_eq!(
            r.as_str(),
            "| a | b |\n| --- | --- |\n| x\\|y |  |\n| 1 | 2 |\n"
        );
    }

    #[test]
    fn too_long_row_is_an_error() {
        let mut r = Report::new();
        assert!(r.table(&["a"], &[vec!["1", "2"]]).is_err());
    }

    #[test]
    fn blocks_are_separated_by_blank_lines() {
        let mut r = Report::new();
        r.heading(1, "Run").paragraph("text").kv(&[("seed", "7")]);
        assert_eq!(r.as_str(), "# Run\n\ntext\n\n- **seed**: 7\n");
        assert_eq!(num(f64::NAN, 2), "—");
        assert_eq!(num(0.31999, 3), "0.320");
    }
}
