//! Reader for the small CSV tables transcribed from the implemented papers
//! (`seed-tables/*.csv`): `#` comment lines, one header line, comma-separated
//! cells; an empty cell means "not reported". Every problem is an
//! [`InputError`] naming the file and line. The experiments turn the rows
//! into their own types.

use crate::error::InputError;
use std::path::Path;

/// A parsed table: header names and rows of raw cells with their line numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct SeedTable {
    /// The file name, for messages.
    pub file: String,
    /// Column names from the header line.
    pub columns: Vec<String>,
    /// Rows of trimmed cells, each with its 1-based line number.
    pub rows: Vec<(usize, Vec<String>)>,
}

/// Parses table text; `file` names it in errors.
pub fn parse_seed_table(file: &str, text: &str) -> Result<SeedTable, InputError> {
    let mut columns: Option<Vec<String>> = None;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<String> = line.split(',').map(|c| c.trim().to_string()).collect();
        match &columns {
            None => {
                if cells.iter().any(|c| c.is_empty()) {
                    return Err(InputError::new(file, "empty column name in header")
                        .at(format!("line {ln}")));
                }
                columns = Some(cells);
            }
            Some(h) if cells.len() != h.len() => {
                return Err(InputError::new(
                    file,
                    format!("{} cells, header has {}", cells.len(), h.len()),
                )
                .at(format!("line {ln}")));
            }
            Some(_) => rows.push((ln, cells)),
        }
    }
    let columns = columns.ok_or_else(|| InputError::new(file, "no header line"))?;
    Ok(SeedTable {
        file: file.to_string(),
        columns,
        rows,
    })
}

/// Reads and parses a table file.
pub fn read_seed_table(path: &Path) -> Result<SeedTable, InputError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| InputError::new(&name, e.to_string()))?;
    parse_seed_table(&name, &text)
}

impl SeedTable {
    fn index(&self, name: &str) -> Result<usize, InputError> {
        self.columns.iter().position(|c| c == name).ok_or_else(|| {
            InputError::new(&self.file, format!("missing column `{name}`")).at("header")
        })
    }

    /// A numeric column where empty cells are `None`; other text is an error.
    pub fn optional_numbers(&self, name: &str) -> Result<Vec<Option<f64>>, InputError> {
        let k = self.index(name)?;
        self.rows
            .iter()
            .map(|(ln, cells)| {
                let c = &cells[k];
                if c.is_empty() {
                    return Ok(None);
                }
                // [Paryanto] prints decimal commas; the transcriptions use points.
                match c.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(Some(v)),
                    _ => Err(InputError::new(
                        &self.file,
                        format!("column `{name}`: `{c}` is not a finite number"),
                    )
                    .at(format!("line {ln}"))),
                }
            })
            .collect()
    }

    /// A numeric column with every cell present.
    pub fn numbers(&self, name: &str) -> Result<Vec<f64>, InputError> {
        let v = self.optional_numbers(name)?;
        v.iter()
            .zip(&self.rows)
            .map(|(x, (ln, _))| {
                x.ok_or_else(|| {
                    InputError::new(&self.file, format!("column `{name}`: empty cell"))
                        .at(format!("line {ln}"))
                })
            })
            .collect()
    }

    /// A text column.
    pub fn text(&self, name: &str) -> Result<Vec<String>, InputError> {
        let k = self.index(name)?;
        Ok(self.rows.iter().map(|(_, c)| c[k].clone()).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_header_and_bad_cells_are_located() {
        let t = parse_seed_table("t.csv", "# c\n\na,b\n1,2\n# mid\n3,\n").unwrap();
        assert_eq!(t.columns, ["a", "b"]);
        assert_eq!(t.numbers("a").unwrap(), [1.0, 3.0]);
        assert_eq!(t.optional_numbers("b").unwrap(), [Some(2.0), None]);
        let e = t.numbers("b").unwrap_err();
        assert_eq!(e.position.as_deref(), Some("line 6"));
        assert!(t.numbers("c").is_err());
        let e = parse_seed_table("t.csv", "a,b\n1,2,3\n").unwrap_err();
        assert_eq!(e.position.as_deref(), Some("line 2"));
        let e = parse_seed_table("t.csv", "a,b\n1,x\n")
            .unwrap()
            .numbers("b")
            .unwrap_err();
        assert!(e.to_string().contains("line 2") && e.to_string().contains("`x`"));
        assert!(parse_seed_table("t.csv", "a,b\n1,nan\n")
            .unwrap()
            .numbers("b")
            .is_err());
        assert!(parse_seed_table("t.csv", "# only\n").is_err());
    }
}
