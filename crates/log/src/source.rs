//! Where a reading sits in its log file: a text line or a topic's message.

use std::fmt;
use std::path::Path;

/// The place of a reading in its log, for error messages and summaries.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Source {
    /// A line of a text log (1-based).
    Line(usize),
    /// A message of a topic in a recorded bag (0-based among the topic's messages).
    Message {
        /// The topic's name, e.g. `/scan`.
        topic: String,
        /// The message's index among the topic's messages.
        index: usize,
    },
}

impl fmt::Display for Source {
    /// "line 1234" or "topic /scan message 17".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Source::Line(line) => write!(f, "line {line}"),
            Source::Message { topic, index } => write!(f, "topic {topic} message {index}"),
        }
    }
}

impl Source {
    /// The place in `path`, as errors name it: "log.clf:1234" or "log.bag: topic /scan message 17".
    pub fn in_file(&self, path: &Path) -> String {
        match self {
            Source::Line(line) => format!("{}:{line}", path.display()),
            Source::Message { .. } => format!("{}: {self}", path.display()),
        }
    }
}

/// The readings from `first` to `last`: "lines 5..900", "topic /scan messages 3..80", or "{first} to {last}".
pub fn span(first: &Source, last: &Source) -> String {
    match (first, last) {
        (Source::Line(a), Source::Line(b)) => format!("lines {a}..{b}"),
        (Source::Message { topic, index: a }, Source::Message { topic: t, index: b }) if topic == t => {
            format!("topic {topic} messages {a}..{b}")
        }
        _ => format!("{first} to {last}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sources_read_as_errors_name_them() {
        let line = Source::Line(1234);
        let message = Source::Message { topic: "/scan".into(), index: 17 };
        assert_eq!(line.to_string(), "line 1234");
        assert_eq!(message.to_string(), "topic /scan message 17");
        assert_eq!(line.in_file(Path::new("a.clf")), "a.clf:1234");
        assert_eq!(message.in_file(Path::new("a.bag")), "a.bag: topic /scan message 17");
        assert_eq!(span(&Source::Line(5), &line), "lines 5..1234");
        assert_eq!(span(&Source::Message { topic: "/scan".into(), index: 3 }, &message), "topic /scan messages 3..17");
        assert_eq!(span(&line, &message), "line 1234 to topic /scan message 17");
    }
}
