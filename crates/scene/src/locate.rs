//! Finding a key path in the scene text, so that errors found after parsing (a missing
//! material, a bad value) still name a line and column. TOML is re-read into toml's
//! spanned tree; JSON (already known to be valid) is scanned. A scene given as data has
//! no text: its errors carry the key path alone.

use crate::error::{line_column, path_string, SceneError, Seg};
use crate::load::SceneFormat;
use std::ops::Range;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// Where a key path lies in the text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Located {
    /// The span of the last key (None for an array element or the root).
    pub key: Option<Range<usize>>,
    /// The span (or start) of the value.
    pub value: Range<usize>,
    /// How many steps of the path were found.
    pub found: usize,
}

/// A scene file's text, its format and its name for messages.
pub struct Source<'a> {
    /// The text.
    pub text: &'a str,
    /// TOML or JSON.
    pub format: SceneFormat,
    /// The file name for messages.
    pub file: String,
    /// Whether there is text to point into (false for a scene given as data).
    pub has_text: bool,
    toml: Option<Spanned<DeValue<'a>>>,
}

impl<'a> Source<'a> {
    /// A source; `text` should already be known to parse.
    pub fn new(text: &'a str, format: SceneFormat, file: String) -> Self {
        let toml = match format {
            SceneFormat::Toml => DeTable::parse(text)
                .ok()
                .map(|t| Spanned::new(t.span(), DeValue::Table(t.into_inner()))),
            SceneFormat::Json => None,
        };
        Self {
            text,
            format,
            file,
            has_text: true,
            toml,
        }
    }

    /// A scene with no text (given as data): errors name the key path only.
    pub fn without_text(file: String) -> Self {
        Self {
            text: "",
            format: SceneFormat::Json,
            file,
            has_text: false,
            toml: None,
        }
    }

    /// The deepest part of `path` found in the text (the root when nothing is).
    pub fn locate(&self, path: &[Seg]) -> Located {
        match (&self.toml, self.format) {
            (Some(root), _) => locate_toml(root, path),
            (None, SceneFormat::Json) => locate_json(self.text, path),
            (None, SceneFormat::Toml) => Located {
                key: None,
                value: 0..0,
                found: 0,
            },
        }
    }

    /// An error at byte `offset` of the text.
    pub fn error_at(&self, offset: usize, path: &[Seg], message: impl Into<String>) -> SceneError {
        if !self.has_text {
            return SceneError::at_key(&self.file, path, message);
        }
        let (line, column) = line_column(self.text, offset);
        SceneError {
            file: self.file.clone(),
            line,
            column,
            key: path_string(path),
            message: message.into(),
        }
    }

    /// An error at the value of `path`.
    pub fn at_value(&self, path: &[Seg], message: impl Into<String>) -> SceneError {
        self.error_at(self.locate(path).value.start, path, message)
    }

    /// An error at the key of `path` (its value when it has no key).
    pub fn at_key(&self, path: &[Seg], message: impl Into<String>) -> SceneError {
        let l = self.locate(path);
        self.error_at(l.key.unwrap_or(l.value).start, path, message)
    }
}

fn locate_toml(root: &Spanned<DeValue>, path: &[Seg]) -> Located {
    let mut cur = root;
    let mut loc = Located {
        key: None,
        value: root.span(),
        found: 0,
    };
    for seg in path {
        let next = match (seg, cur.get_ref()) {
            (Seg::Key(k), DeValue::Table(t)) => t
                .iter()
                .find(|(name, _)| name.get_ref().as_ref() == k.as_str())
                .map(|(name, v)| (Some(name.span()), v)),
            (Seg::Index(i), DeValue::Array(a)) => a.get(*i).map(|v| (None, v)),
            _ => None,
        };
        let Some((key, v)) = next else { break };
        loc = Located {
            key,
            value: v.span(),
            found: loc.found + 1,
        };
        cur = v;
    }
    loc
}

fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// The end of the JSON string starting at `i` (a quote).
fn skip_string(b: &[u8], mut i: usize) -> usize {
    i += 1;
    while i < b.len() && b[i] != b'"' {
        i += if b[i] == b'\\' { 2 } else { 1 };
    }
    (i + 1).min(b.len())
}

/// The end of the JSON value starting at `i`.
fn skip_value(b: &[u8], mut i: usize) -> usize {
    match b.get(i) {
        Some(b'"') => skip_string(b, i),
        Some(b'{' | b'[') => {
            let mut depth = 0usize;
            while i < b.len() {
                match b[i] {
                    b'"' => {
                        i = skip_string(b, i);
                        continue;
                    }
                    b'{' | b'[' => depth += 1,
                    b'}' | b']' => {
                        depth -= 1;
                        if depth == 0 {
                            return i + 1;
                        }
                    }
                    _ => {}
                }
                i += 1;
            }
            i
        }
        _ => {
            while i < b.len() && !matches!(b[i], b',' | b'}' | b']') && !b[i].is_ascii_whitespace()
            {
                i += 1;
            }
            i
        }
    }
}

/// The value at `path` in valid JSON text, or the deepest part of it found.
fn locate_json(text: &str, path: &[Seg]) -> Located {
    let b = text.as_bytes();
    let start = skip_ws(b, 0);
    let mut loc = Located {
        key: None,
        value: start..skip_value(b, start),
        found: 0,
    };
    'path: for seg in path {
        let mut i = loc.value.start;
        match (seg, b.get(i)) {
            (Seg::Key(k), Some(b'{')) => loop {
                i = skip_ws(b, i + 1);
                if b.get(i) != Some(&b'"') {
                    break 'path;
                }
                let key_end = skip_string(b, i);
                let name: Option<String> = serde_json::from_str(&text[i..key_end]).ok();
                let v = skip_ws(b, skip_ws(b, key_end) + 1);
                let v_end = skip_value(b, v);
                if name.as_deref() == Some(k.as_str()) {
                    loc = Located {
                        key: Some(i..key_end),
                        value: v..v_end,
                        found: loc.found + 1,
                    };
                    continue 'path;
                }
                i = skip_ws(b, v_end);
                if b.get(i) != Some(&b',') {
                    break 'path;
                }
            },
            (Seg::Index(n), Some(b'[')) => {
                for k in 0.. {
                    i = skip_ws(b, i + 1);
                    if matches!(b.get(i), None | Some(b']')) {
                        break 'path;
                    }
                    let end = skip_value(b, i);
                    if k == *n {
                        loc = Located {
                            key: None,
                            value: i..end,
                            found: loc.found + 1,
                        };
                        continue 'path;
                    }
                    i = skip_ws(b, end);
                    if b.get(i) != Some(&b',') {
                        break 'path;
                    }
                }
            }
            _ => break,
        }
    }
    loc
}

/// The byte offset, within the raw string literal `raw` (quotes included; TOML basic,
/// literal or multi-line, or JSON), of 1-based (line, column) of its decoded content.
pub fn position_in_literal(raw: &str, line: usize, column: usize) -> usize {
    let (open, close, escapes) = if raw.starts_with("\"\"\"") {
        (3, 3, true)
    } else if raw.starts_with("'''") {
        (3, 3, false)
    } else if raw.starts_with('"') {
        (1, 1, true)
    } else if raw.starts_with('\'') {
        (1, 1, false)
    } else {
        (0, 0, false)
    };
    let end = raw.len().saturating_sub(close).max(open);
    let mut i = open;
    // A newline right after a multi-line opening delimiter is not part of the string.
    if open == 3 {
        if raw[i..].starts_with("\r\n") {
            i += 2;
        } else if raw[i..].starts_with('\n') {
            i += 1;
        }
    }
    let (mut l, mut c) = (1, 1);
    while i < end {
        while !raw.is_char_boundary(i) {
            i += 1;
        }
        if (l, c) >= (line, column) {
            return i;
        }
        let ch = raw[i..].chars().next().unwrap_or(' ');
        let mut step = ch.len_utf8();
        let mut decoded = Some(ch);
        if escapes && ch == '\\' {
            let next = raw[i + 1..].chars().next().unwrap_or(' ');
            step = match next {
                'u' => 6,
                'U' => 10,
                '\n' | '\r' | ' ' | '\t' => {
                    // TOML line-ending backslash: swallows whitespace and newlines.
                    let rest = &raw[i + 1..end];
                    decoded = None;
                    1 + rest.len() - rest.trim_start().len()
                }
                _ => 1 + next.len_utf8(),
            };
            if next == 'n' {
                decoded = Some('\n');
            }
        }
        match decoded {
            Some('\n') => {
                l += 1;
                c = 1;
            }
            Some(_) => c += 1,
            None => {}
        }
        i = (i + step).min(end);
    }
    end
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::kp;

    #[test]
    fn json_paths_are_found() {
        let text = r#"{"a": {"b": [1, {"c": "x]}"}, [2, 3]], "d": 4}, "e": true}"#;
        let l = locate_json(text, &kp!["a", "b", 1usize, "c"]);
        assert_eq!(&text[l.value.clone()], r#""x]}""#);
        assert_eq!(&text[l.key.unwrap()], r#""c""#);
        let l = locate_json(text, &kp!["a", "d"]);
        assert_eq!(&text[l.value], "4");
        let l = locate_json(text, &kp!["e"]);
        assert_eq!(&text[l.value], "true");
        // A missing key stops at its deepest ancestor.
        let l = locate_json(text, &kp!["a", "b", 2usize, 1usize]);
        assert_eq!((&text[l.value], l.found), ("3", 4));
        let l = locate_json(text, &kp!["a", "b", 2usize, 5usize]);
        assert_eq!((&text[l.value], l.found), ("[2, 3]", 3));
        let l = locate_json(text, &kp!["a", "zz"]);
        assert!(text[l.value].starts_with(r#"{"b""#));
    }

    #[test]
    fn toml_paths_are_found() {
        let text = "[camera]\nfov = 40\n[[objects]]\nm = 'a'\n[[objects]]\nm = 'b'\n";
        let s = Source::new(text, SceneFormat::Toml, "t.toml".into());
        let l = s.locate(&kp!["objects", 1usize, "m"]);
        assert_eq!(&text[l.value], "'b'");
        assert_eq!(&text[l.key.unwrap()], "m");
        let e = s.at_value(&kp!["objects", 1usize, "m"], "no");
        assert_eq!((e.line, e.column), (6, 5));
        assert_eq!(e.key, "objects[1].m");
    }

    #[test]
    fn literal_positions_follow_escapes() {
        let raw = r#""ab\ncd""#;
        assert_eq!(position_in_literal(raw, 1, 2), 2);
        // Line 2 column 2 ('d') is after the two-byte escape.
        assert_eq!(&raw[position_in_literal(raw, 2, 2)..], "d\"");
        let raw = "\"\"\"\nxy\nzw\"\"\"";
        assert_eq!(&raw[position_in_literal(raw, 2, 2)..], "w\"\"\"");
        let raw = "'a\\b'";
        assert_eq!(&raw[position_in_literal(raw, 1, 3)..], "b'");
    }
}
