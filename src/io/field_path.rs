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

/// Parses `path` into steps.
pub fn parse(path: &str, style: Style) -> Result<Vec<Step>, String> {
    let at = match style {
        Style::Json => "",
        Style::Ulog => "field path ",
    };
    let mut steps = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = part.split_once('[').unwrap_or((part, ""));
        if !name.is_empty() {
            steps.push(Step::Key(name.to_string()));
        } else if style == Style::Ulog {
            return Err(format!("empty name in field path {path:?}"));
        } else if steps.is_empty() && rest.is_empty() {
            return Err(format!("empty field path {path:?}"));
        }
        while !rest.is_empty() {
            let (idx, after) = rest
                .split_once(']')
                .ok_or_else(|| format!("unclosed '[' in {at}{path:?}"))?;
            let i = idx
                .parse()
                .map_err(|_| format!("bad index {idx:?} in {at}{path:?}"))?;
            steps.push(Step::Index(i));
            rest = match after.strip_prefix('[') {
                Some(r) => r,
                None if after.is_empty() => "",
                None => return Err(format!("unexpected {after:?} in {at}{path:?}")),
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
        let both = |p: &str| (parse(p, Style::Json), parse(p, Style::Ulog));
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
