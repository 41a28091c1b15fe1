//! Scene-file errors: where (file, line, column, key path) and what.

/// One step of a key path: a table key or an array index.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Seg {
    /// A key of a table (object).
    Key(String),
    /// An index into an array.
    Index(usize),
}

impl From<&str> for Seg {
    fn from(s: &str) -> Self {
        Seg::Key(s.to_string())
    }
}

impl From<&String> for Seg {
    fn from(s: &String) -> Self {
        Seg::Key(s.clone())
    }
}

impl From<usize> for Seg {
    fn from(i: usize) -> Self {
        Seg::Index(i)
    }
}

/// A key path such as `objects[2].material`.
pub type KeyPath = Vec<Seg>;

/// Builds a [`KeyPath`] from keys (`&str`, `&String`) and indices (`usize`).
macro_rules! kp {
    ($($s:expr),* $(,)?) => {
        Vec::<$crate::error::Seg>::from([$($crate::error::Seg::from($s)),*])
    };
}
pub(crate) use kp;

/// Writes a key path as `objects[2].material`; keys that are not bare words are quoted.
pub fn path_string(path: &[Seg]) -> String {
    let mut s = String::new();
    for seg in path {
        match seg {
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
            Seg::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                let bare = !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                if bare {
                    s.push_str(k);
                } else {
                    s.push_str(&format!("{k:?}"));
                }
            }
        }
    }
    s
}

/// A malformed or inconsistent scene: the file, the 1-based line and column (in
/// characters; 0 when there is no text to point into: an unreadable file, or a scene
/// given as data), the key path of the offending entry (empty for syntax errors) and
/// what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.located())]
pub struct SceneError {
    /// The file the position refers to (a model file for errors inside a model); empty
    /// for a scene given as data.
    pub file: String,
    /// 1-based line; 0 when there is no position.
    pub line: usize,
    /// 1-based column in characters; 0 when there is no position.
    pub column: usize,
    /// Key path in the scene file, e.g. `objects[2].material` (may be empty).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl SceneError {
    /// An error with no position: a scene given as data, or no text to point into.
    pub fn at_key(file: &str, key: &[Seg], message: impl Into<String>) -> Self {
        SceneError {
            file: file.to_string(),
            line: 0,
            column: 0,
            key: path_string(key),
            message: message.into(),
        }
    }

    /// `file:line:column: key: message` (parts without a value are left out).
    fn located(&self) -> String {
        let mut s = self.file.clone();
        if self.line > 0 {
            s.push_str(&format!(":{}:{}", self.line, self.column));
        }
        for part in [&self.key, &self.message] {
            if !part.is_empty() {
                if !s.is_empty() {
                    s.push_str(": ");
                }
                s.push_str(part);
            }
        }
        s
    }
}

/// The 1-based line and column (in characters) of byte `offset` of `text`.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// The byte offset of 1-based `line` and byte `column` (as serde_json reports them).
pub fn offset_of(text: &str, line: usize, byte_column: usize) -> usize {
    let start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    (start + byte_column.saturating_sub(1)).min(text.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_and_positions() {
        let p: KeyPath = kp!["objects", 2usize, "material"];
        assert_eq!(path_string(&p), "objects[2].material");
        assert_eq!(
            path_string(&kp!["materials", "my gold", "eta"]),
            "materials.\"my gold\".eta"
        );
        let text = "ab\nçd\ne";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 3), (2, 1));
        // 'd' is byte 5 (ç takes two bytes) but column 2.
        assert_eq!(line_column(text, 5), (2, 2));
        assert_eq!(line_column(text, 99), (3, 2));
        assert_eq!(offset_of(text, 2, 3), 5);
        let e = SceneError {
            file: "s.toml".into(),
            line: 3,
            column: 7,
            key: "camera.fov".into(),
            message: "bad".into(),
        };
        assert_eq!(e.to_string(), "s.toml:3:7: camera.fov: bad");
        let v = SceneError::at_key("", &kp!["objects", 1usize, "solid"], "bad");
        assert_eq!(v.to_string(), "objects[1].solid: bad");
    }
}
