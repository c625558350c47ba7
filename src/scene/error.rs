//! The error type of scene loading: every message names the key or index
//! that is wrong and the reason.

use std::fmt;

/// Why a scene could not be loaded. The [`fmt::Display`] text is the
/// message a user sees (CLI, FMI logger).
#[derive(Clone, Debug, PartialEq)]
pub enum SceneError {
    /// The file could not be read.
    Io {
        /// The path as given.
        path: String,
        /// The operating system's reason.
        message: String,
    },
    /// The text is not valid JSON.
    Json {
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// What the JSON parser expected.
        message: String,
    },
    /// A key, an entry of an array, or a generator parameter is wrong.
    Invalid {
        /// The key with its index path, e.g. `edges_vertices[3]` or
        /// `ancf:material.thickness`.
        key: String,
        /// The reason.
        message: String,
    },
    /// A physical value is outside its limits ([`super::limits`]).
    Limit {
        /// The key with its index path, e.g. `ancf:material.thickness`.
        key: String,
        /// Why the value was refused.
        source: super::limits::LimitError,
    },
}

impl SceneError {
    /// An [`SceneError::Invalid`] for `key`.
    pub fn invalid(key: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            key: key.into(),
            message: message.into(),
        }
    }

    /// The key an [`SceneError::Invalid`] or [`SceneError::Limit`] names
    /// (`None` for I/O and JSON syntax errors).
    pub fn key(&self) -> Option<&str> {
        match self {
            SceneError::Invalid { key, .. } | SceneError::Limit { key, .. } => Some(key),
            _ => None,
        }
    }

    /// From a `serde_json` syntax error, keeping its line and column.
    pub(crate) fn from_json(e: &serde_json::Error) -> SceneError {
        let full = e.to_string();
        // serde_json appends " at line L column C"; keep the message only.
        let message = match full.rfind(" at line ") {
            Some(i) => full[..i].to_string(),
            None => full,
        };
        SceneError::Json {
            line: e.line(),
            column: e.column(),
            message,
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneError::Io { path, message } => write!(f, "cannot read {path}: {message}"),
            SceneError::Json {
                line,
                column,
                message,
            } => write!(
                f,
                "malformed JSON at line {line}, column {column}: {message}"
            ),
            SceneError::Invalid { key, message } => write!(f, "{key}: {message}"),
            SceneError::Limit { key, source } => write!(f, "{key}: {source}"),
        }
    }
}

impl std::error::Error for SceneError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            SceneError::Limit { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Levenshtein distance between two short strings (for "did you mean").
pub(crate) fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for i in 1..=a.len() {
        cur[0] = i;
        for j in 1..=b.len() {
            let sub = prev[j - 1] + usize::from(a[i - 1] != b[j - 1]);
            cur[j] = sub.min(prev[j] + 1).min(cur[j - 1] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// The candidate closest to `word`, if it is close enough to be a likely
/// misspelling (case-insensitive edit distance at most a third of the
/// length, and at least 2 allowed).
pub(crate) fn closest<'a>(word: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let w = word.to_lowercase();
    candidates
        .iter()
        .map(|c| (edit_distance(&w, &c.to_lowercase()), *c))
        .filter(|&(d, c)| d <= (c.chars().count() / 3).max(2))
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// `"; did you mean 'x'?"` or an empty string.
pub(crate) fn suggestion(word: &str, candidates: &[&str]) -> String {
    match closest(word, candidates) {
        Some(c) => format!("; did you mean '{c}'?"),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_and_suggestions() {
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(
            closest("ancf:materail", &["ancf:material", "ancf:crease"]),
            Some("ancf:material")
        );
        assert_eq!(closest("zzzzzz", &["thickness", "density"]), None);
        assert!(suggestion("thicknes", &["thickness"]).contains("'thickness'"));
    }

    #[test]
    fn json_errors_keep_position() {
        let e = serde_json::from_str::<serde_json::Value>("{\n  \"a\": [1, 2,\n}").unwrap_err();
        let s = SceneError::from_json(&e);
        match &s {
            SceneError::Json { line, column, .. } => {
                assert_eq!(*line, 3);
                assert!(*column >= 1);
            }
            other => panic!("{other:?}"),
        }
        assert!(s.to_string().contains("line 3"), "{s}");
        assert!(!s.to_string().contains(" at line 3 column"), "{s}");
    }
}
