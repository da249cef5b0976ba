//! The text formats the plan must reproduce exactly: Python's `json.dumps(indent=1)` (the
//! merged tables have always been written by it) and printf's `%g` (frame rates on the
//! stages' command lines).

use plan::json_text::{dumps_indent1, parse, python_float};
use plan::transfer::fmt_g;

/// Known answer from CPython 3.11: `json.dumps(json.loads(INPUT), indent=1)`.
#[test]
fn json_matches_python_dumps_indent1() {
    let input = r#"{"b": 1e-05, "a": [1.5e+16, 0.0001, 123456789012345680000.0, -0.0, 2.5, 1e16, 7], "s": "\u00e9\u2192\ud83d\ude00 \\ \" \n \u007f", "e": [], "o": {}, "n": null, "t": true}"#;
    let want = "{\n \"b\": 1e-05,\n \"a\": [\n  1.5e+16,\n  0.0001,\n  1.2345678901234568e+20,\n  -0.0,\n  2.5,\n  1e+16,\n  7\n ],\n \"s\": \"\\u00e9\\u2192\\ud83d\\ude00 \\\\ \\\" \\n \\u007f\",\n \"e\": [],\n \"o\": {},\n \"n\": null,\n \"t\": true\n}";
    assert_eq!(dumps_indent1(&parse(input).unwrap()), want);
}

/// Python's own output parses back to the same text (a fixed point), and serde_json's float
/// text (what the stages write) reads back to the same number.
#[test]
fn json_round_trip() {
    for x in [0.1, 1.0 / 3.0, 6.02214076e23, 5e-324, 1e-7, 123.456, 1e21, -2.5e-5] {
        let py = python_float(x);
        assert_eq!(py.parse::<f64>().unwrap(), x, "{py}");
        let v = parse(&serde_json::to_string(&x).unwrap()).unwrap();
        assert_eq!(dumps_indent1(&v), py);
    }
    let text = "{\n \"z\": [\n  1,\n  {\n   \"y\": \"\\u00e9\"\n  }\n ],\n \"a\": 0.5\n}";
    assert_eq!(dumps_indent1(&parse(text).unwrap()), text, "key order and layout kept");
}

#[test]
fn json_errors_are_reported_not_panics() {
    for bad in ["", "{", "[1,", "{\"a\" 1}", "\"abc", "[1 2]", "nul", "{\"a\":1}x", &"[".repeat(10_000)] {
        assert!(parse(bad).is_err(), "{bad:.20} parsed");
    }
}

/// Reference: the shell's printf (C's `%g`).
#[test]
fn fmt_g_matches_printf() {
    let values = [25.0, 50.0, 29.97, 23.976, 0.5, 120.0, 1e-5, 1234567.0, 100000.0, 59.94005994, 999999.5, 0.0001, 0.00009999999];
    for x in values {
        let out = std::process::Command::new("printf").arg("%g").arg(x.to_string()).output().unwrap();
        assert_eq!(fmt_g(x), String::from_utf8(out.stdout).unwrap(), "{x}");
    }
}

/// `scripts/slurm-measure`'s table into Slurm requests: ×1.5 rounded up to 50 MB, CPUs the
/// ceiling of the share; a task running two stages asks for the larger of each.
#[test]
fn resources_from_measured_peaks() {
    use plan::resources::{Resources, Table};
    let t = Table::parse("stage            tasks  peak_MB  cpu_%    max_s\nalign 14 15 80 0.09\nrender 23 47 153 0.75\nhmc-sample 2 301 48 6.96\n").unwrap();
    assert_eq!(t.for_bins(&["align"]), Resources { cpus: 1, mem_mb: 50 });
    assert_eq!(t.for_bins(&["render"]), Resources { cpus: 2, mem_mb: 100 });
    assert_eq!(t.for_bins(&["hmc-sample", "render"]), Resources { cpus: 2, mem_mb: 500 });
    assert!(Table::parse("align 14 x 80 0.1\n").is_err());
    assert!(Table::parse("align 14 1e300 80 0.1\n").is_err());
}
