//! The text of a JSON message that does not parse (MCAP JSON channels): the field path
//! of the value the parser stopped in, and a NaN or infinity named as such — JSON has no
//! numbers for them, though Python's `json.dumps` (its default `allow_nan=True`) and
//! other writers emit `NaN`, `Infinity`, `-Infinity`.

/// The field path (`a.b[2]`, empty at the top level) of the value a parse error `e` of
/// `data` stopped in, and the error's text.
pub fn describe(data: &[u8], e: &serde_json::Error) -> (String, String) {
    let at = offset(data, e.line(), e.column());
    let non_finite = [at.saturating_sub(1), at].into_iter().find_map(|i| {
        NON_FINITE
            .into_iter()
            .find(|t| data[i..].starts_with(t))
            .map(|t| (i, t))
    });
    let path = path_at(data, non_finite.map_or(at, |(i, _)| i));
    let text = match non_finite {
        Some((_, t)) => format!(
            "invalid JSON: {e}: {} is not a JSON number (JSON has no NaN or infinity; log \
             null for a missing value, which --drop-invalid drops)",
            String::from_utf8_lossy(t)
        ),
        None => format!("invalid JSON: {e}"),
    };
    (path, text)
}

/// The field path (`a.b[2]`) of the JSON value starting at byte `at` of `text`, from
/// the objects and arrays open before it; empty at the top level.
fn path_at(text: &[u8], at: usize) -> String {
    enum Open {
        Object(Option<String>),
        Array(usize),
    }
    let mut open: Vec<Open> = Vec::new();
    let (mut in_string, mut escaped) = (false, false);
    let (mut string, mut last_string) = (Vec::new(), None);
    for &b in &text[..at.min(text.len())] {
        if in_string {
            match b {
                _ if escaped => {
                    escaped = false;
                    string.push(b);
                }
                b'\\' => escaped = true,
                b'"' => {
                    in_string = false;
                    last_string = Some(String::from_utf8_lossy(&string).into_owned());
                }
                _ => string.push(b),
            }
            continue;
        }
        match b {
            b'"' => {
                in_string = true;
                string.clear();
            }
            b'{' => open.push(Open::Object(None)),
            b'[' => open.push(Open::Array(0)),
            b'}' | b']' => {
                open.pop();
            }
            b':' => {
                if let Some(Open::Object(key)) = open.last_mut() {
                    *key = last_string.take();
                }
            }
            b',' => match open.last_mut() {
                Some(Open::Array(i)) => *i += 1,
                Some(Open::Object(key)) => *key = None,
                None => {}
            },
            _ => {}
        }
    }
    let mut path = String::new();
    for o in &open {
        match o {
            Open::Object(Some(k)) if path.is_empty() => path.push_str(k),
            Open::Object(Some(k)) => path = format!("{path}.{k}"),
            Open::Object(None) => {}
            Open::Array(i) => path = format!("{path}[{i}]"),
        }
    }
    path
}

/// Tokens of non-finite numbers some JSON writers emit (Python's `json.dumps`, with its
/// default `allow_nan=True`, writes `NaN`, `Infinity`, `-Infinity`).
const NON_FINITE: [&[u8]; 6] = [b"NaN", b"Infinity", b"-Infinity", b"nan", b"inf", b"-inf"];

/// Byte offset in `text` of the 1-based `line` and `column` of a JSON error.
fn offset(text: &[u8], line: usize, column: usize) -> usize {
    let start = if line <= 1 {
        0
    } else {
        memchr::memchr_iter(b'\n', text)
            .nth(line - 2)
            .map_or(text.len(), |i| i + 1)
    };
    (start + column.saturating_sub(1)).min(text.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Paths through objects and arrays, strings holding brackets, commas and escaped
    /// quotes skipped; a NaN and an infinity named with their field.
    #[test]
    fn paths_and_non_finite_tokens() {
        let text = br#"{"a":{"b":[1,{"c":2}],"s":"x,[\"]"},"d":[0.1,NaN]}"#;
        let at = |token: &str| {
            let s = std::str::from_utf8(text).unwrap();
            s.find(token).unwrap()
        };
        assert_eq!(path_at(text, at("2}")), "a.b[1].c");
        assert_eq!(path_at(text, at("NaN")), "d[1]");
        assert_eq!(path_at(text, 0), "");
        let e = serde_json::from_slice::<serde_json::Value>(text).unwrap_err();
        let (path, message) = describe(text, &e);
        assert_eq!(path, "d[1]");
        assert!(message.contains("NaN is not a JSON number"), "{message}");
        let inf = b"{\"x\":\n  -Infinity}";
        let e = serde_json::from_slice::<serde_json::Value>(inf).unwrap_err();
        let (path, message) = describe(inf, &e);
        assert_eq!(path, "x");
        assert!(
            message.contains("-Infinity is not a JSON number"),
            "{message}"
        );
        let bad = br#"{"x":[1,2"#;
        let e = serde_json::from_slice::<serde_json::Value>(bad).unwrap_err();
        assert_eq!(describe(bad, &e).1, format!("invalid JSON: {e}"));
    }
}
