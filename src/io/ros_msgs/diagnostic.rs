//! `diagnostic_msgs/DiagnosticArray`: what a node says of its health
//! (`odocal live` publishes one; read here to check it field by field).

use super::{Field, Header, RosMsg};
use crate::io::cdr::{CdrError, CdrReader, CdrWriter};

/// `diagnostic_msgs/msg/KeyValue`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeyValueMsg {
    /// The key.
    pub key: String,
    /// The value, as text.
    pub value: String,
}

/// `diagnostic_msgs/msg/DiagnosticStatus`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DiagnosticStatusMsg {
    /// OK 0, WARN 1, ERROR 2, STALE 3.
    pub level: u8,
    /// What is described (e.g. `odocal: calibration`).
    pub name: String,
    /// One line of state.
    pub message: String,
    /// The hardware, if any.
    pub hardware_id: String,
    /// Values.
    pub values: Vec<KeyValueMsg>,
}

/// `diagnostic_msgs/msg/DiagnosticArray`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DiagnosticArrayMsg {
    /// Stamp.
    pub header: Header,
    /// One status per thing described.
    pub status: Vec<DiagnosticStatusMsg>,
}

impl RosMsg for DiagnosticArrayMsg {
    const TYPE: &'static str = "diagnostic_msgs/msg/DiagnosticArray";

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        let header = Header::read(r)?;
        // Each status is at least a level and four lengths.
        let n = r.seq_len(17)?;
        let mut status = Vec::with_capacity(n);
        for _ in 0..n {
            let level = r.u8()?;
            let name = r.string()?.to_string();
            let message = r.string()?.to_string();
            let hardware_id = r.string()?.to_string();
            let k = r.seq_len(10)?;
            let mut values = Vec::with_capacity(k);
            for _ in 0..k {
                values.push(KeyValueMsg {
                    key: r.string()?.to_string(),
                    value: r.string()?.to_string(),
                });
            }
            status.push(DiagnosticStatusMsg {
                level,
                name,
                message,
                hardware_id,
                values,
            });
        }
        Ok(Self { header, status })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        w.seq_len(self.status.len());
        for s in &self.status {
            w.u8(s.level);
            w.string(&s.name);
            w.string(&s.message);
            w.string(&s.hardware_id);
            w.seq_len(s.values.len());
            for v in &s.values {
                w.string(&v.key);
                w.string(&v.value);
            }
        }
    }
}
