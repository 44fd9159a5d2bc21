//! The JUnit XML verdict of a batch check (`dsmcosim check … --junit FILE`), for CI
//! test-report viewers.
//!
//! One `<testsuite name="dsmcosim.check">` inside `<testsuites>`, one `<testcase>` per
//! scenario in argument order: `classname="dsmcosim.check"`, `name` the scenario name,
//! `file` the scenario file, `time` the wall seconds of its rerun and comparison. The
//! suite's `time` (and `testsuites`') is the wall time of the whole check, start to
//! end: scenarios rerun in parallel, so it is less than the testcases' times added up
//! (at least the longest of them), as a CI job's clock sees it. A
//! mismatch has a `<failure type="mismatch">` whose `message` is the first differing
//! record (file, time, column, stored and new values) and whose text is the full
//! explanation; a missing stored run or another error has an `<error type="missing">`
//! or `<error type="error">`. Times are the only wall-clock values; nothing here
//! reaches a digest.

use std::fmt::Write as _;

use super::batch::{Batch, Status};
use crate::trace::compare::Tolerance;

/// The JUnit XML text of `batch`.
pub fn render(batch: &Batch) -> String {
    let t = batch.totals();
    let time = format!("{:.3}", batch.wall_seconds());
    let counts = format!(
        "tests=\"{}\" failures=\"{}\" errors=\"{}\"",
        t.scenarios,
        t.mismatched,
        t.missing + t.errors
    );
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        x,
        "<testsuites name=\"dsmcosim check\" {counts} time=\"{time}\">"
    );
    let _ = writeln!(
        x,
        "  <testsuite name=\"dsmcosim.check\" {counts} skipped=\"0\" time=\"{time}\">"
    );
    let tolerance = match batch.tolerance {
        Tolerance::Exact => "exact".to_string(),
        Tolerance::Relative(r) => format!("{r:e}"),
    };
    let _ = writeln!(x, "    <properties>");
    for (name, value) in [
        ("against", batch.against.display().to_string()),
        ("tolerance", tolerance),
        ("layout", batch.layout.name().to_string()),
    ] {
        let _ = writeln!(
            x,
            "      <property name=\"{}\" value=\"{}\"/>",
            escape(name),
            escape(&value)
        );
    }
    let _ = writeln!(x, "    </properties>");
    for o in &batch.outcomes {
        let head = format!(
            "    <testcase classname=\"dsmcosim.check\" name=\"{}\" file=\"{}\" time=\"{:.3}\"",
            escape(&o.name),
            escape(&o.scenario.display().to_string()),
            o.wall_seconds
        );
        let element = match o.status() {
            Status::Match => None,
            Status::Mismatch => Some(("failure", "mismatch")),
            Status::Missing => Some(("error", "missing")),
            Status::Error => Some(("error", "error")),
        };
        match element {
            None => {
                let _ = writeln!(x, "{head}/>");
            }
            Some((tag, kind)) => {
                let message = o.headline().unwrap_or_default();
                let _ = writeln!(x, "{head}>");
                let _ = writeln!(
                    x,
                    "      <{tag} type=\"{kind}\" message=\"{}\">{}</{tag}>",
                    escape(&message),
                    escape(&o.text())
                );
                let _ = writeln!(x, "    </testcase>");
            }
        }
    }
    x.push_str("  </testsuite>\n</testsuites>\n");
    x
}

/// Escapes `text` for XML 1.0 character data and attribute values alike: `& < > " '`
/// as entities, tab, newline and carriage return as character references (so they
/// survive in attributes), and every character XML 1.0 cannot hold (other control
/// characters, U+FFFE, U+FFFF) as U+FFFD.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::batch::{Layout, Outcome};

    #[test]
    fn the_suite_time_is_the_checks_wall_time_not_the_sum() {
        // Two scenarios that ran side by side for 3 s and 2 s in a check of 3.25 s.
        let case = |name: &str, t: f64| Outcome {
            name: name.into(),
            scenario: format!("{name}.json").into(),
            stored: format!("r/{name}").into(),
            new: None,
            wall_seconds: t,
            result: Err(crate::Error::invalid("name", "x")),
            stored_failed: false,
        };
        let batch = Batch {
            layout: Layout::ByName,
            against: "r".into(),
            tolerance: Tolerance::Exact,
            outcomes: vec![case("a", 3.0), case("b", 2.0)],
            elapsed_seconds: 3.25,
        };
        let x = render(&batch);
        assert!(x.contains("<testsuites name=\"dsmcosim check\" tests=\"2\" failures=\"0\" errors=\"2\" time=\"3.250\">"), "{x}");
        assert!(x.contains("skipped=\"0\" time=\"3.250\">"), "{x}");
        assert!(
            x.contains("name=\"a\" file=\"a.json\" time=\"3.000\""),
            "{x}"
        );
        assert!(
            x.contains("name=\"b\" file=\"b.json\" time=\"2.000\""),
            "{x}"
        );
        assert!(!x.contains("5.000"), "{x}");
    }

    #[test]
    fn escapes_markup_whitespace_and_forbidden_characters() {
        assert_eq!(escape("plain"), "plain");
        assert_eq!(
            escape("a<b>&\"c\" 'd'"),
            "a&lt;b&gt;&amp;&quot;c&quot; &apos;d&apos;"
        );
        assert_eq!(escape("]]>"), "]]&gt;");
        assert_eq!(escape("l1\nl2\tx\r"), "l1&#10;l2&#9;x&#13;");
        assert_eq!(escape("\u{0}\u{1b}\u{FFFE}é"), "\u{FFFD}\u{FFFD}\u{FFFD}é");
        assert_eq!(escape("&amp;"), "&amp;amp;");
    }
}
