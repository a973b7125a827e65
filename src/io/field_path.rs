//! Field paths into a message, `a.b[2].c`: the mapping names MCAP (JSON, CDR) and ULog
//! fields this way. A ULog path names a field at every step; a JSON path may also start
//! with an index (`[0].x`, a message that is an array) and skips empty names.

/// One step of a field path: a field name or an array index.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// A field.
    Key(String),
    /// An element, 0-based.
    Index(usize),
}

/// Whose paths: the grammar and the words of the errors differ slightly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// MCAP messages decoded to JSON.
    Json,
    /// ULog formats: every step names a field.
    Ulog,
}

impl Style {
    /// What an error calls the path: nothing (JSON) or `field path ` (ULog).
    fn label(self) -> &'static str {
        match self {
            Self::Json => "",
            Self::Ulog => "field path ",
        }
    }
}

/// Why a field path does not parse; the path is quoted as written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FieldPathError {
    /// A ULog path with an empty step name (`a..b`, `[0].x`, ``).
    #[error("empty name in field path {path:?}")]
    EmptyName {
        /// The path.
        path: String,
    },
    /// A JSON path with no step at all.
    #[error("empty field path {path:?}")]
    Empty {
        /// The path.
        path: String,
    },
    /// A `[` without its `]`.
    #[error("unclosed '[' in {}{path:?}", style.label())]
    Unclosed {
        /// The path.
        path: String,
        /// Whose path.
        style: Style,
    },
    /// An index that is not a whole number ≥ 0.
    #[error("bad index {index:?} in {}{path:?}", style.label())]
    BadIndex {
        /// The text between the brackets.
        index: String,
        /// The path.
        path: String,
        /// Whose path.
        style: Style,
    },
    /// Text after an index that neither starts another index nor a field.
    #[error("unexpected {text:?} in {}{path:?}", style.label())]
    Unexpected {
        /// The text after the `]`.
        text: String,
        /// The path.
        path: String,
        /// Whose path.
        style: Style,
    },
}

/// Parses `path` into steps.
pub fn parse(path: &str, style: Style) -> Result<Vec<Step>, FieldPathError> {
    let mut steps = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = part.split_once('[').unwrap_or((part, ""));
        if !name.is_empty() {
            steps.push(Step::Key(name.to_string()));
        } else if style == Style::Ulog {
            return Err(FieldPathError::EmptyName { path: path.into() });
        } else if steps.is_empty() && rest.is_empty() {
            return Err(FieldPathError::Empty { path: path.into() });
        }
        while !rest.is_empty() {
            let (idx, after) = rest
                .split_once(']')
                .ok_or_else(|| FieldPathError::Unclosed {
                    path: path.into(),
                    style,
                })?;
            let i = idx.parse().map_err(|_| FieldPathError::BadIndex {
                index: idx.to_string(),
                path: path.into(),
                style,
            })?;
            steps.push(Step::Index(i));
            rest = match after.strip_prefix('[') {
                Some(r) => r,
                None if after.is_empty() => "",
                None => {
                    return Err(FieldPathError::Unexpected {
                        text: after.to_string(),
                        path: path.into(),
                        style,
                    });
                }
            };
        }
    }
    Ok(steps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_and_ulog_paths() {
        use Step::{Index, Key};
        let words = |p: &str, style| parse(p, style).map_err(|e| e.to_string());
        let both = |p: &str| (words(p, Style::Json), words(p, Style::Ulog));
        let esc = vec![Key("esc".into()), Index(2), Key("rpm".into())];
        assert_eq!(both("esc[2].rpm"), (Ok(esc.clone()), Ok(esc)));
        let grid = vec![Key("m".into()), Index(1), Index(0)];
        assert_eq!(both("m[1][0]"), (Ok(grid.clone()), Ok(grid)));
        // JSON only: a leading index, an empty name skipped.
        assert_eq!(
            both("[0].x"),
            (
                Ok(vec![Index(0), Key("x".into())]),
                Err("empty name in field path \"[0].x\"".into())
            )
        );
        assert_eq!(
            parse("a..b", Style::Json),
            Ok(vec![Key("a".into()), Key("b".into())])
        );
        assert_eq!(
            both(""),
            (
                Err("empty field path \"\"".into()),
                Err("empty name in field path \"\"".into())
            )
        );
        assert_eq!(
            both("a[1]x"),
            (
                Err("unexpected \"x\" in \"a[1]x\"".into()),
                Err("unexpected \"x\" in field path \"a[1]x\"".into())
            )
        );
        assert_eq!(
            both("a[1").1,
            Err("unclosed '[' in field path \"a[1\"".into())
        );
        assert_eq!(both("a[-1]").0, Err("bad index \"-1\" in \"a[-1]\"".into()));
    }
}
