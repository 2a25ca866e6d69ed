//! A TOML syntax or type error of a scene file as one line: where it is (line, column) and
//! the key it is about, as the scene's other errors name keys (`end_effector.mass`,
//! `cables[2].pulley`, `damping.foo`), then the toml crate's own words. The toml crate's
//! report is four lines (position, the line, a caret, the message); the key is found from
//! the text: the table of the last `[table]` or `[[array]]` header above the error (an
//! array of tables numbered from 0), then the key written before the error on its line
//! (through inline tables: `pulley = { radius = "x" }` → `pulley.radius`), or the field a
//! `missing field` / `unknown field` message names.

/// Where a TOML error is and what it says.
#[derive(Debug, Clone, PartialEq)]
pub struct TomlErrorReport {
    /// Line, from 1 (0 when the error has no position).
    pub line: usize,
    /// Column in characters, from 1.
    pub column: usize,
    /// The dotted key the error is about (`None` at the top level when no key is known).
    pub key: Option<String>,
    /// The toml crate's message, on one line.
    pub message: String,
}

impl std::fmt::Display for TomlErrorReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(f, "line {}, column {}: ", self.line, self.column)?;
        }
        if let Some(k) = &self.key {
            write!(f, "key `{k}`: ")?;
        }
        f.write_str(&self.message)
    }
}

/// The report of `e`, raised while reading `text`.
pub fn report(text: &str, e: &toml::de::Error) -> TomlErrorReport {
    let message = e
        .message()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ");
    let Some(span) = e.span() else {
        return TomlErrorReport {
            line: 0,
            column: 0,
            key: None,
            message,
        };
    };
    let start = floor_char_boundary(text, span.start.min(text.len()));
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line = text[..start].matches('\n').count() + 1;
    let column = text[line_start..start].chars().count() + 1;
    let line_text = text[line_start..].lines().next().unwrap_or("");
    // Up to the end of the error's line: a header there is the table it is about.
    let table = table_above(text, line_start + line_text.len());
    let on_line = if is_header(line_text).is_some() {
        Vec::new()
    } else {
        key_before(&text[line_start..start])
    };
    let field = named_field(&message);
    let mut parts: Vec<String> = table.into_iter().collect();
    parts.extend(on_line.iter().cloned());
    // A missing or unknown field of the table or inline table the error is in.
    if let Some(f) = field {
        if on_line.last() != Some(&f) {
            parts.push(f);
        }
    }
    let key = (!parts.is_empty()).then(|| parts.join("."));
    TomlErrorReport {
        line,
        column,
        key,
        message,
    }
}

/// The largest char boundary at or below `i`.
fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// The table name of a header line (`[a.b]` → `a.b`, `[[cables]]` → `cables` and true for
/// an array of tables), `None` for any other line.
fn is_header(line: &str) -> Option<(String, bool)> {
    let t = line.split('#').next().unwrap_or("").trim();
    let (inner, array) = match t.strip_prefix("[[").and_then(|r| r.strip_suffix("]]")) {
        Some(r) => (r, true),
        None => (t.strip_prefix('[')?.strip_suffix(']')?, false),
    };
    let name: String = inner
        .split('.')
        .map(str::trim)
        .collect::<Vec<_>>()
        .join(".");
    let bare = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.';
    let first_ok = name.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_');
    (first_ok && name.chars().all(bare)).then_some((name, array))
}

/// The table above byte `pos`: the last header before it, an array of tables as `name[k]`
/// (`k` counting its headers from 0); `None` at the top level.
fn table_above(text: &str, pos: usize) -> Option<String> {
    let mut last: Option<String> = None;
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    for l in text[..pos].lines() {
        if let Some((name, array)) = is_header(l) {
            last = Some(if array {
                let k = counts.entry(name.clone()).or_insert(0);
                *k += 1;
                format!("{name}[{}]", *k - 1)
            } else {
                name
            });
        }
    }
    last
}

/// The keys written before the error on its line: the inline tables it is in, then the key
/// whose value it is (`pulley = { radius = ` → [`pulley`, `radius`]).
fn key_before(prefix: &str) -> Vec<String> {
    let mut open: Vec<String> = Vec::new();
    let mut pending: Option<String> = None;
    let mut word = String::new();
    let mut chars = prefix.chars().peekable();
    let mut after_eq = false;
    // Arrays open in the value: their commas do not end the key's value.
    let mut arrays = 0usize;
    while let Some(c) = chars.next() {
        match c {
            '"' | '\'' => {
                // A quoted key or a string value: skipped (a key's quotes dropped).
                let mut s = String::new();
                while let Some(d) = chars.next() {
                    if d == '\\' && c == '"' {
                        chars.next();
                        continue;
                    }
                    if d == c {
                        break;
                    }
                    s.push(d);
                }
                if !after_eq {
                    word = s;
                }
            }
            '=' => {
                pending = Some(std::mem::take(&mut word));
                after_eq = true;
            }
            '[' if after_eq => arrays += 1,
            ']' if arrays > 0 => arrays -= 1,
            '{' if arrays == 0 => {
                if let Some(k) = pending.take() {
                    open.push(k);
                }
                after_eq = false;
            }
            '}' if arrays == 0 => {
                open.pop();
                pending = None;
            }
            ',' if arrays == 0 => {
                pending = None;
                after_eq = false;
                word.clear();
            }
            c if !after_eq && (c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.') => {
                word.push(c);
            }
            _ => {}
        }
    }
    open.extend(pending);
    open
}

/// The field a `missing field `x`` or `unknown field `x`` message names.
fn named_field(message: &str) -> Option<String> {
    for lead in ["missing field `", "unknown field `"] {
        if let Some(rest) = message.split(lead).nth(1) {
            return rest.split('`').next().map(str::to_string);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key_of(prefix: &str) -> Vec<String> {
        key_before(prefix)
    }

    #[test]
    fn keys_before_an_error_on_its_line() {
        assert_eq!(key_of("mass = "), ["mass"]);
        assert_eq!(key_of("pulley = { radius = "), ["pulley", "radius"]);
        assert_eq!(
            key_of("pulley = { radius = 1, entry_direction = "),
            ["pulley", "entry_direction"]
        );
        assert_eq!(key_of("pulley = "), ["pulley"]);
        assert_eq!(key_of("gravity = [0, 0"), ["gravity"]);
        assert_eq!(key_of("a = [1, 2], b = "), ["b"]);
        assert_eq!(key_of("\"odd key\" = "), ["odd key"]);
        assert!(key_of("").is_empty());
    }

    #[test]
    fn headers_and_their_tables() {
        assert_eq!(is_header("[tension]"), Some(("tension".into(), false)));
        assert_eq!(
            is_header("[[cables]]  # one"),
            Some(("cables".into(), true))
        );
        assert_eq!(is_header("[1.0, 2.0],"), None);
        assert_eq!(is_header("  [0.1, 0, 0],"), None);
        let text = "a = 1\n[[cables]]\nx = 1\n[[cables]]\nx = 2\n";
        assert_eq!(table_above(text, text.len()), Some("cables[1]".into()));
        assert_eq!(table_above(text, 0), None);
    }

    /// Each TOML error of a scene file is one line: the line, the column, the key and the
    /// toml crate's words (four lines with a caret before).
    #[test]
    fn scene_errors_are_one_line_naming_the_line_and_the_key() {
        use crate::scene::{Scene, SceneError};
        let base = crate::scene::DEFAULT_SCENE_TOML;
        let pulleys = include_str!("../../scenes/spatial_paper_pulleys.toml");
        let line_of =
            |text: &str, needle: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
        let damped = format!("{base}\n[damping]\nloss_factor = 0.01\nfoo = 2\n");
        let no_radius = pulleys.replacen("pulley = { radius = 0.05, ", "pulley = { ", 1);
        let typed = base.replace("mass = 30.0", "mass = \"a\"");
        let syntax = base.replace("mass = 30.0", "mass = ");
        let no_t_min = base.replace("t_min = 60.0", "");
        let inline_type = pulleys.replacen("radius = 0.05", "radius = \"5 cm\"", 1);
        let cases: [(&str, usize, &str, &str); 6] = [
            (
                &damped,
                line_of(&damped, "foo = 2"),
                "damping.foo",
                "unknown field `foo`",
            ),
            (
                &no_radius,
                line_of(&no_radius, "pulley = { entry"),
                "cables[0].pulley.radius",
                "missing field `radius`",
            ),
            (
                &typed,
                line_of(&typed, "mass = \"a\""),
                "end_effector.mass",
                "invalid type",
            ),
            (
                &syntax,
                line_of(&syntax, "mass = "),
                "end_effector.mass",
                "string values must be quoted",
            ),
            (
                &no_t_min,
                line_of(&no_t_min, "[tension]"),
                "tension.t_min",
                "missing field `t_min`",
            ),
            (
                &inline_type,
                line_of(&inline_type, "radius = \"5 cm\""),
                "cables[0].pulley.radius",
                "invalid type",
            ),
        ];
        for (text, line, key, what) in cases {
            let e = Scene::from_toml_str(text, "t.toml").unwrap_err();
            let SceneError::Parse { report, .. } = &e else {
                panic!("{e}");
            };
            assert_eq!(report.line, line, "{e}");
            assert_eq!(report.key.as_deref(), Some(key), "{e}");
            let msg = e.to_string();
            assert!(
                msg.starts_with(&format!("t.toml: line {line}, column "))
                    && msg.contains(&format!("key `{key}`: "))
                    && msg.contains(what)
                    && !msg.contains('\n'),
                "{msg}"
            );
        }
    }
}
