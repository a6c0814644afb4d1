//! The error every reader returns for input it cannot use: it names the file,
//! the topic or record kind, and the position, so a user can find the bad bytes.

use std::fmt;

/// Input that cannot be used (missing, truncated, corrupt, inconsistent).
/// The binary maps it to exit code 2.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct InputError {
    /// The file (or `<memory>`).
    pub file: String,
    /// Topic, record kind or section, when known.
    pub topic: Option<String>,
    /// Position: message index, line number, byte offset.
    pub position: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl InputError {
    /// An error about a whole file.
    pub fn new(file: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            topic: None,
            position: None,
            message: message.into(),
        }
    }

    /// Adds the topic or record kind.
    pub fn topic(mut self, topic: impl Into<String>) -> Self {
        self.topic = Some(topic.into());
        self
    }

    /// Adds the position (e.g. "message 12", "line 40").
    pub fn at(mut self, position: impl Into<String>) -> Self {
        self.position = Some(position.into());
        self
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(t) = &self.topic {
            write!(f, ", {t}")?;
        }
        if let Some(p) = &self.position {
            write!(f, ", {p}")?;
        }
        write!(f, ": {}", self.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn message_names_file_topic_and_position() {
        let e = InputError::new("a.mcap", "truncated CDR")
            .topic("/scan")
            .at("message 7");
        assert_eq!(e.to_string(), "a.mcap, /scan, message 7: truncated CDR");
    }
}
