//! One flag vocabulary across every stage, read from the built binaries' own `--help` (every
//! stage of [`STAGES`] and every subcommand it lists): every command that writes has `--out`
//! and no positional output; a long flag has one value name (and arity) and one short letter
//! wherever it appears; a short letter means one long flag; no command offers two names of
//! one concept ([`SYNONYMS`]: at most one of each group is in use, across all stages); and a
//! choice is a clap value enum (its values listed by clap), never a hand-written `a|b` value.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use surfcap::stages::STAGES;

/// Commands that write no file of their own (a check, a listing, a runner of other commands).
const WRITES_NOTHING: &[&str] = &["check-set", "inspect", "plan run-task", "plan step"];

/// Names of one concept; the stages may use at most one name of each group. No synonyms are
/// allowed: a rename removes the old name everywhere.
const SYNONYMS: &[&[&str]] = &[
    &["--out", "--output", "--output-dir", "--out-dir", "--dest"],
    &["--segmentation", "--parts", "--seg", "--part-file"],
    &["--subject", "--subject-json"],
    &["--group", "--group-file"],
    &["--model", "--model-file"],
    &["--frame-count", "--n-frames", "--length", "--num-frames"],
    &["--pattern", "--frame-pattern", "--frame-names"],
    &["--correspondences", "--training-label", "--corr-kind"],
    &["--strict-parts", "--fallback-whole-body"],
    &["--threads", "--jobs", "-j"],
];

/// Flags that take a number or a keyword (not a closed choice), so their value names may show `|`.
const NUMBER_OR_KEYWORD: &[&str] = &["--sparse", "--orientation-weight"];

fn bin_dir() -> PathBuf {
    Path::new(env!("CARGO_BIN_EXE_surfcap")).parent().unwrap().to_path_buf()
}

/// One option line of a `--help`: long name, short letter, value names as printed.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Opt {
    long: String,
    short: Option<char>,
    values: String,
    help: String,
}

/// One command's help: its options, its positional arguments (name, description), its subcommands.
#[derive(Debug, Default)]
struct Help {
    usage: String,
    options: Vec<Opt>,
    positionals: Vec<(String, String)>,
    subcommands: Vec<String>,
}

/// Parses clap's help layout (short form, `  -o, --out <OUT>  text`, or long form, the text on
/// the following lines indented deeper).
fn parse_help(text: &str) -> Help {
    let mut h = Help::default();
    let mut section = "";
    let lines: Vec<&str> = text.lines().collect();
    for (i, line) in lines.iter().enumerate() {
        if let Some(u) = line.strip_prefix("Usage: ") {
            h.usage = u.to_string();
            continue;
        }
        if !line.starts_with(' ') && line.ends_with(':') {
            section = line;
            continue;
        }
        let body = line.trim_start();
        let indent = line.len() - body.len();
        if body.is_empty() || indent > 6 {
            continue;
        }
        // The description: after two spaces on the line, else the next deeper-indented lines.
        let (head, desc) = match body.find("  ") {
            Some(k) => (&body[..k], body[k..].trim().to_string()),
            None => {
                let mut d = String::new();
                for l in &lines[i + 1..] {
                    let t = l.trim_start();
                    if t.is_empty() {
                        continue;
                    }
                    if l.len() - t.len() <= 6 {
                        break;
                    }
                    d.push_str(t);
                    d.push(' ');
                }
                (body, d.trim().to_string())
            }
        };
        match section {
            "Options:" => {
                let (short, rest) = match head.strip_prefix('-') {
                    Some(r) if !r.starts_with('-') => {
                        let c = r.chars().next().unwrap();
                        (Some(c), r[1..].trim_start_matches(',').trim_start())
                    }
                    _ => (None, head),
                };
                let (long, values) = match rest.find(' ') {
                    Some(k) => (&rest[..k], rest[k + 1..].trim()),
                    None => (rest, ""),
                };
                if long.starts_with("--") {
                    h.options.push(Opt { long: long.into(), short, values: values.into(), help: desc });
                }
            }
            "Arguments:" => h.positionals.push((head.trim().to_string(), desc)),
            "Commands:" => {
                if head != "help" {
                    h.subcommands.push(head.to_string());
                }
            }
            _ => {}
        }
    }
    h
}

/// Every command (stage, or `stage subcommand`) with its parsed help.
fn all_commands() -> Vec<(String, Help)> {
    let dir = bin_dir();
    let mut out = Vec::new();
    for s in STAGES {
        let help = |args: &[&str]| {
            let o = Command::new(dir.join(s.bin)).args(args).arg("--help").output().unwrap();
            assert_eq!(o.status.code(), Some(0), "{} {args:?} --help", s.bin);
            parse_help(&String::from_utf8(o.stdout).unwrap())
        };
        let top = help(&[]);
        let mut queue: Vec<(Vec<String>, Help)> = vec![(Vec::new(), top)];
        while let Some((path, h)) = queue.pop() {
            if h.subcommands.is_empty() {
                let name = std::iter::once(s.name.to_string()).chain(path.iter().cloned()).collect::<Vec<_>>().join(" ");
                out.push((name, h));
                continue;
            }
            for sub in &h.subcommands {
                let mut p = path.clone();
                p.push(sub.clone());
                let args: Vec<&str> = p.iter().map(String::as_str).collect();
                queue.push((p.clone(), help(&args)));
            }
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

#[test]
fn the_help_parser_reads_both_layouts() {
    let text = "Does things\n\nUsage: x [OPTIONS] --out <OUT> <IN>\n\nArguments:\n  <IN>\n          Input folder\n\n\
                Options:\n  -o, --out <OUT>\n          Output artifact\n\n      --pair <A> <B> <C>\n          Three files\n\n\
                \x20 -h, --help\n          Print help\n";
    let h = parse_help(text);
    assert_eq!(h.usage, "x [OPTIONS] --out <OUT> <IN>");
    assert_eq!(h.positionals, vec![("<IN>".to_string(), "Input folder".to_string())]);
    assert_eq!(h.options[0], Opt { long: "--out".into(), short: Some('o'), values: "<OUT>".into(), help: "Output artifact".into() });
    assert_eq!(h.options[1].values, "<A> <B> <C>");
    let short = parse_help("Options:\n      --fit <FIT>  How [default: strided] [possible values: strided, exact]\n  -n <N>  Count\n");
    assert_eq!(short.options.len(), 1, "a short-only flag is not a long flag: {short:?}");
    assert!(short.options[0].help.contains("possible values"));
    let cmds = parse_help("Usage: p <COMMAND>\n\nCommands:\n  make  Write it\n  help  Print this\n");
    assert_eq!(cmds.subcommands, vec!["make".to_string()]);
}

#[test]
fn every_command_that_writes_has_out_and_no_positional_output() {
    let cmds = all_commands();
    assert!(cmds.len() >= STAGES.len() + 5, "stages and subcommands found: {}", cmds.len());
    let names: BTreeSet<&str> = cmds.iter().map(|(n, _)| n.as_str()).collect();
    for w in WRITES_NOTHING {
        assert!(names.contains(w), "{w} is not a command any more: update WRITES_NOTHING");
    }
    for (name, h) in &cmds {
        let has_out = h.options.iter().any(|o| o.long == "--out");
        if WRITES_NOTHING.contains(&name.as_str()) {
            assert!(!has_out, "{name} has --out: remove it from WRITES_NOTHING");
        } else {
            assert!(has_out, "{name} writes but has no --out: {}", h.usage);
            let out = h.options.iter().find(|o| o.long == "--out").unwrap();
            assert_eq!(out.short, Some('o'), "{name}: --out has -o everywhere");
        }
        for (arg, desc) in &h.positionals {
            let upper = arg.to_ascii_uppercase();
            assert!(
                !upper.contains("OUT") && !desc.to_ascii_lowercase().starts_with("output"),
                "{name}: positional output {arg} ({desc}); outputs are --out"
            );
        }
    }
}

#[test]
fn a_flag_has_one_value_name_and_one_short_letter_across_stages() {
    let mut values: BTreeMap<String, BTreeMap<String, Vec<String>>> = BTreeMap::new();
    let mut shorts: BTreeMap<String, BTreeSet<Option<char>>> = BTreeMap::new();
    let mut letters: BTreeMap<char, BTreeSet<String>> = BTreeMap::new();
    for (name, h) in all_commands() {
        for o in &h.options {
            values.entry(o.long.clone()).or_default().entry(o.values.clone()).or_default().push(name.clone());
            shorts.entry(o.long.clone()).or_default().insert(o.short);
            if let Some(c) = o.short {
                letters.entry(c).or_default().insert(o.long.clone());
            }
        }
    }
    let mut problems = Vec::new();
    for (flag, by_value) in &values {
        if by_value.len() > 1 {
            problems.push(format!("{flag} takes different values: {by_value:?}"));
        }
    }
    for (flag, s) in &shorts {
        if s.len() > 1 {
            problems.push(format!("{flag} has different short letters: {s:?}"));
        }
    }
    for (c, longs) in &letters {
        if longs.len() > 1 {
            problems.push(format!("-{c} means different flags: {longs:?}"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The vocabulary the pipelines rely on is there, under these value names.
    let one = |f: &str| values.get(f).map(|v| v.keys().next().unwrap().clone());
    assert_eq!(one("--out").as_deref(), Some("<OUT>"));
    assert_eq!(one("--segmentation").as_deref(), Some("<SEGMENTATION>"));
    assert_eq!(one("--subject").as_deref(), Some("<SUBJECT_JSON>"));
    assert_eq!(one("--frames").as_deref(), Some("<A:B>"));
    assert_eq!(one("--set").as_deref(), Some("<SET>"));
}

#[test]
fn no_two_names_for_one_concept() {
    let used: BTreeSet<String> = all_commands()
        .iter()
        .flat_map(|(_, h)| h.options.iter().map(|o| o.long.clone()).collect::<Vec<_>>())
        .collect();
    for group in SYNONYMS {
        let present: Vec<&&str> = group.iter().filter(|n| used.contains(**n)).collect();
        assert!(present.len() <= 1, "synonyms in use: {present:?}");
    }
}

#[test]
fn choices_are_value_enums() {
    let mut enums = 0;
    for (name, h) in all_commands() {
        for o in &h.options {
            if o.values.contains('|') && !NUMBER_OR_KEYWORD.contains(&o.long.as_str()) {
                panic!("{name} {}: a hand-written choice {}; make it a clap ValueEnum", o.long, o.values);
            }
            enums += o.help.to_ascii_lowercase().contains("possible values") as usize;
        }
    }
    // The enums of the stages the issue lists (method, placement, preset, sampler, formats, ...).
    assert!(enums >= 15, "value enums found: {enums}");
    for (cmd, flag) in [
        ("gpr-train", "--method"),
        ("transfer-eval", "--placement"),
        ("transfer-eval", "--correspondences"),
        ("synth", "--preset"),
        ("hmc-sample", "--sampler"),
        ("mesh-export", "--frame-format"),
        ("align", "--frame"),
        ("gpdm-train", "--fit"),
    ] {
        let cmds = all_commands();
        let h = &cmds.iter().find(|(n, _)| n == cmd).unwrap().1;
        let o = h.options.iter().find(|o| o.long == flag).unwrap_or_else(|| panic!("{cmd} {flag}"));
        assert!(o.help.to_ascii_lowercase().contains("possible values"), "{cmd} {flag}: {}", o.help);
    }
}
