//! Small HTML helpers: escaping, and JSON documents rendered as tables.

use serde_json::Value;

/// Escapes text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Escapes a relative path for use in `src`/`href` (each component
/// percent-encoded where needed, `/` kept).
pub fn url_path(rel: &str) -> String {
    let mut out = String::new();
    for b in rel.bytes() {
        if b.is_ascii_alphanumeric() || b"-_.~/".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

fn scalar(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => escape(s),
        Value::Number(n) => match n.as_f64() {
            Some(x) if n.is_f64() => format_number(x),
            _ => n.to_string(),
        },
        Value::Bool(b) => b.to_string(),
        _ => json_to_html(v),
    }
}

/// Four significant digits, scientific notation for very small or large values.
pub fn format_number(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        "0".to_string()
    } else if (1e-3..1e5).contains(&a) {
        let digits = if a >= 1.0 {
            4usize.saturating_sub(a.log10().floor() as usize + 1)
        } else {
            4 + (-a.log10()).floor() as usize
        };
        format!("{x:.digits$}")
    } else {
        format!("{x:.3e}")
    }
}

/// Renders a JSON value: an array of objects as one table (columns = the
/// union of keys, `direction`, `motion`, `method` first), an object as a two-column
/// key/value table, scalars as text; nested values recursively.
pub fn json_to_html(v: &Value) -> String {
    match v {
        Value::Array(items) if !items.is_empty() && items.iter().all(Value::is_object) => {
            // Identifying columns first, then the others in key order.
            let mut cols: Vec<&str> = ["direction", "motion", "method"]
                .into_iter()
                .filter(|c| items.iter().any(|it| it.get(*c).is_some()))
                .collect();
            for it in items {
                for k in it.as_object().expect("object").keys() {
                    if !cols.contains(&k.as_str()) {
                        cols.push(k);
                    }
                }
            }
            let mut s = String::from("<table><thead><tr>");
            for c in &cols {
                s += &format!("<th>{}</th>", escape(c));
            }
            s += "</tr></thead><tbody>";
            for it in items {
                s += "<tr>";
                for c in &cols {
                    let cell = it.get(*c).map(scalar).unwrap_or_default();
                    s += &format!("<td>{cell}</td>");
                }
                s += "</tr>";
            }
            s + "</tbody></table>"
        }
        Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(scalar).collect();
            parts.join(", ")
        }
        Value::Object(map) => {
            let mut s = String::from("<table class=\"kv\"><tbody>");
            for (k, v) in map {
                s += &format!("<tr><th>{}</th><td>{}</td></tr>", escape(k), scalar(v));
            }
            s + "</tbody></table>"
        }
        _ => scalar(v),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
        assert_eq!(url_path("a b/c#.png"), "a%20b/c%23.png");
    }

    #[test]
    fn records_become_one_table() {
        let v: Value = serde_json::from_str(
            r#"[{"direction":"A->B","rms_pose_m":0.0123456},{"direction":"B->A","frames":40}]"#,
        )
        .unwrap();
        let h = json_to_html(&v);
        assert_eq!(h.matches("<tr>").count(), 3, "{h}");
        for col in ["direction", "rms_pose_m", "frames"] {
            assert!(h.contains(&format!("<th>{col}</th>")), "{h}");
        }
        assert!(
            h.contains("A-&gt;B") && h.contains("0.01235") && h.contains("40"),
            "{h}"
        );
    }

    #[test]
    fn number_formatting() {
        assert_eq!(format_number(0.0123456), "0.01235");
        assert_eq!(format_number(123.456), "123.5");
        assert_eq!(format_number(1.5e-7), "1.500e-7");
    }
}
