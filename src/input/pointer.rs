//! RFC 6901 JSON pointers (`/channels/0/tau`) and setting a value through one, for sweep
//! axes and `--set` ([`crate::scenario::overrides`]).
//!
//! The parent is resolved by `serde_json` ([`Value::pointer_mut`]); what is added here is
//! the check of a pointer's syntax (serde_json takes a bad escape such as `~2` as text),
//! setting a key that may be new, and, when the parent is missing, a message that names
//! the first missing step. Setting needs the parent to exist. On an object the last key may be new (the
//! scenario's validation then rejects a key it does not know, with its own message);
//! on an array the last token must index an existing element (no appending).

use serde_json::Value;

/// A parsed JSON pointer that addresses something below the document root.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pointer {
    /// As written.
    text: String,
    /// Unescaped reference tokens, at least one.
    tokens: Vec<String>,
}

impl std::fmt::Display for Pointer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

/// JSON type name of `v`, for messages.
fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// The array index a token names: decimal digits without a leading zero.
fn index(token: &str) -> Option<usize> {
    let digits = !token.is_empty() && token.bytes().all(|b| b.is_ascii_digit());
    if !digits || (token.len() > 1 && token.starts_with('0')) {
        return None;
    }
    token.parse().ok()
}

impl Pointer {
    /// Parses `text`; the message of an error says what is wrong with it.
    pub fn parse(text: &str) -> Result<Pointer, String> {
        if text.is_empty() {
            return Err("the empty pointer is the whole scenario; name a field such as /dt".into());
        }
        let Some(rest) = text.strip_prefix('/') else {
            return Err(format!("{text}: must start with `/` (e.g. /{text})"));
        };
        let mut tokens = Vec::new();
        for raw in rest.split('/') {
            let mut token = String::with_capacity(raw.len());
            let mut chars = raw.chars();
            while let Some(c) = chars.next() {
                if c != '~' {
                    token.push(c);
                    continue;
                }
                match chars.next() {
                    Some('0') => token.push('~'),
                    Some('1') => token.push('/'),
                    other => {
                        let got: String = other.map(String::from).unwrap_or_default();
                        return Err(format!(
                            "{text}: bad escape `~{got}` (only ~0 for `~` and ~1 for `/`)"
                        ));
                    }
                }
            }
            tokens.push(token);
        }
        Ok(Pointer {
            text: text.to_string(),
            tokens,
        })
    }

    /// The pointer as written.
    pub fn as_str(&self) -> &str {
        &self.text
    }

    /// The unescaped tokens, root first.
    pub fn tokens(&self) -> &[String] {
        &self.tokens
    }

    /// The pointer to the first `n` tokens, as text (`""` for the root).
    fn prefix(&self, n: usize) -> String {
        self.text
            .split('/')
            .take(n + 1)
            .collect::<Vec<_>>()
            .join("/")
    }

    /// Sets the addressed value to `value`. Returns whether the last key was created
    /// (absent from its object before). The error message starts with the pointer.
    pub fn set(&self, doc: &mut Value, value: Value) -> Result<bool, String> {
        let (last, parents) = self
            .tokens
            .split_last()
            .ok_or_else(|| format!("{}: addresses the whole scenario", self.text))?;
        let parent_text = self.prefix(parents.len());
        let parent = if parent_text.is_empty() {
            "the top level"
        } else {
            &parent_text
        };
        let Some(cur) = doc.pointer_mut(&parent_text) else {
            return Err(self.missing_parent(doc, parents.len()));
        };
        match cur {
            Value::Object(map) => Ok(map.insert(last.clone(), value).is_none()),
            Value::Array(items) => {
                let len = items.len();
                match index(last) {
                    Some(i) if i < len => {
                        items[i] = value;
                        Ok(false)
                    }
                    _ => Err(format!(
                        "{}: no element `{last}` in {parent} (an array of {len}; a pointer \
                         replaces elements, it does not append)",
                        self.text
                    )),
                }
            }
            other => Err(format!(
                "{}: {parent} is {}, not an object or array",
                self.text,
                kind(other)
            )),
        }
    }

    /// Why the parent (the first `depth` tokens) is not in `doc`: the first step that
    /// is missing, as `<pointer>: no key `foo` in /network, so the parent /network/foo
    /// does not exist`.
    fn missing_parent(&self, doc: &Value, depth: usize) -> String {
        let parent = self.prefix(depth);
        for (k, token) in self.tokens[..depth].iter().enumerate() {
            let here_text = self.prefix(k);
            let Some(here_value) = doc.pointer(&here_text) else {
                break;
            };
            if doc.pointer(&self.prefix(k + 1)).is_some() {
                continue;
            }
            let here = if here_text.is_empty() {
                "the top level"
            } else {
                &here_text
            };
            let what = match here_value {
                Value::Object(map) => {
                    // The nearest key there, when one is close (the rule of the
                    // scenario's unknown fields: at most a third of its letters differ).
                    let near = map
                        .keys()
                        .map(|k| (strsim::damerau_levenshtein(token, k), k))
                        .min()
                        .filter(|(d, k)| *d <= (k.chars().count() / 3).max(1))
                        .map_or(String::new(), |(_, k)| format!(" (did you mean `{k}`?)"));
                    format!("no key `{token}` in {here}{near}")
                }
                Value::Array(items) => format!(
                    "no element `{token}` in {here} (an array of {})",
                    items.len()
                ),
                other => format!("{here} is {}, not an object or array", kind(other)),
            };
            return format!(
                "{}: {what}, so the parent {parent} does not exist",
                self.text
            );
        }
        format!("{}: the parent {parent} does not exist", self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn escapes_unescape() {
        let p = Pointer::parse("/a~1b/c~0d/0").unwrap();
        assert_eq!(p.tokens(), ["a/b", "c~d", "0"]);
        assert!(Pointer::parse("/a~2").unwrap_err().contains("~2"));
        assert!(Pointer::parse("dt")
            .unwrap_err()
            .contains("must start with `/`"));
        assert!(Pointer::parse("").is_err());
    }

    #[test]
    fn sets_existing_and_new_keys_and_elements() {
        let mut doc = json!({"channels": [{"tau": 1}, {"tau": 2}], "network": {}});
        assert!(!Pointer::parse("/channels/1/tau")
            .unwrap()
            .set(&mut doc, json!(5))
            .unwrap());
        assert!(Pointer::parse("/network/foo")
            .unwrap()
            .set(&mut doc, json!("x"))
            .unwrap());
        Pointer::parse("/channels/0")
            .unwrap()
            .set(&mut doc, json!({"tau": 9}))
            .unwrap();
        assert_eq!(
            doc,
            json!({"channels": [{"tau": 9}, {"tau": 5}], "network": {"foo": "x"}})
        );
    }

    #[test]
    fn missing_parents_are_named() {
        let mut doc = json!({"network": {"kind": "ideal"}, "channels": [], "dt": 1});
        let e = Pointer::parse("/network/foo/bar")
            .unwrap()
            .set(&mut doc, json!(1))
            .unwrap_err();
        assert_eq!(
            e,
            "/network/foo/bar: no key `foo` in /network, so the parent /network/foo does not exist"
        );
        let e = Pointer::parse("/nosuch/x")
            .unwrap()
            .set(&mut doc, json!(1))
            .unwrap_err();
        assert!(e.contains("no key `nosuch` in the top level,"), "{e}");
        // A mistyped key gets the nearest one.
        let e = Pointer::parse("/chanels/0/tau")
            .unwrap()
            .set(&mut doc, json!(1))
            .unwrap_err();
        assert!(
            e.contains("no key `chanels` in the top level (did you mean `channels`?), so"),
            "{e}"
        );
        let e = Pointer::parse("/channels/0")
            .unwrap()
            .set(&mut doc, json!(1))
            .unwrap_err();
        assert!(e.contains("does not append"), "{e}");
        let e = Pointer::parse("/dt/x")
            .unwrap()
            .set(&mut doc, json!(1))
            .unwrap_err();
        assert!(e.contains("/dt is a number"), "{e}");
        let e = Pointer::parse("/channels/01/tau")
            .unwrap()
            .set(&mut doc, json!(1))
            .unwrap_err();
        assert!(e.contains("no element `01`"), "{e}");
    }
}
