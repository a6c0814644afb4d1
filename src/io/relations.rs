//! Kümmerle et al. `.relations` files: one relation a line,
//! `t1 t2 x y z roll pitch yaw` (s, s, m, m, m, rad, rad, rad), meaning
//! δ = inv(X(t1)) ⊕ X(t2). Accepts `#` comment lines, runs of spaces, t1 > t2
//! and "-0.000000"; only planar relations (z = roll = pitch = 0).

use super::columns::{data_lines, fields, read_text};
use crate::error::InputError;
use crate::eval::Relation;
use crate::geom::pose;
use std::path::Path;

const KIND: &str = "relations";
/// Largest |z|, |roll|, |pitch| accepted as planar (m, rad).
const PLANAR_TOL: f64 = 1e-6;

/// Reads a relations file.
pub fn read_relations(path: &Path) -> Result<Vec<Relation>, InputError> {
    parse_relations(&read_text(path)?, &path.display().to_string())
}

/// Parses relations text; `file` names the source in errors. An error for a
/// malformed or non-finite line (named by number), a non-planar relation, or
/// no relation at all.
pub fn parse_relations(text: &str, file: &str) -> Result<Vec<Relation>, InputError> {
    let mut out = Vec::new();
    for (line_no, line) in data_lines(text) {
        let [t1, t2, x, y, z, roll, pitch, yaw] = fields::<8>(file, KIND, line_no, line)?;
        if z.abs() > PLANAR_TOL || roll.abs() > PLANAR_TOL || pitch.abs() > PLANAR_TOL {
            return Err(InputError::new(
                file,
                format!("non-planar relation (z {z}, roll {roll}, pitch {pitch}); only 2D relations are supported"),
            )
            .topic(KIND)
            .at(format!("line {line_no}")));
        }
        out.push(Relation {
            t1,
            t2,
            delta: pose(x, y, yaw),
        });
    }
    if out.is_empty() {
        return Err(InputError::new(file, "no relations in file").topic(KIND));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_benchmark_quirks() {
        let text = "# timestamp1 timestamp2 x y z roll pitch yaw\n\
            1134864645.90321 1134864646.32420 0.31293 0.02935 0.00000  0.00000 0.00000 0.24198\n\
            \n\
            5.0 4.0 -0.000000 1.5 0.000000 0.000000 -0.000000 -1.0\n";
        let r = parse_relations(text, "x.relations").unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].t1, 1134864645.90321);
        assert!((r[0].delta.rotation.angle() - 0.24198).abs() < 1e-12);
        assert!(r[1].t1 > r[1].t2);
        assert_eq!(r[1].delta.translation.y, 1.5);
    }

    #[test]
    fn bad_lines_are_named() {
        let e = parse_relations("1 2 0 0 0 0 0 0\n1 2 0 0 0 0 0\n", "f").unwrap_err();
        assert_eq!(e.position.as_deref(), Some("line 2"));
        let e = parse_relations("1 2 0 nan 0 0 0 0\n", "f").unwrap_err();
        assert!(e.to_string().contains("line 1") && e.to_string().contains("not finite"));
        let e = parse_relations("1 2 0 x 0 0 0 0\n", "f").unwrap_err();
        assert!(e.to_string().contains("column 4"));
        let e = parse_relations("1 2 0 0 0.5 0 0 0\n", "f").unwrap_err();
        assert!(e.to_string().contains("non-planar"));
        assert!(parse_relations("# only a header\n", "f").is_err());
    }
}
