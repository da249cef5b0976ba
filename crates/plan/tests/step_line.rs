//! `plan step`, as the pipelines' recipes run it: one line per step on a pipe, a spinner on a
//! terminal (a real pty, through util-linux `script`), nothing with `-q`, the command's failure
//! passed on, the command echoed with `-v` (`make V=1`).
use std::process::{Command, Output};

const PLAN: &str = env!("CARGO_BIN_EXE_plan");

fn step(extra: &[&str], command: &[&str]) -> Output {
    Command::new(PLAN)
        .arg("step")
        .args(extra)
        .args(["--label", "align A/walk", "--of", "3/12", "--"])
        .args(command)
        .env_remove("MAKEFLAGS")
        .output()
        .unwrap()
}

/// Runs `shell_command` on a pseudo-terminal and returns everything written to it.
fn in_pty(shell_command: &str, env: &[(&str, &str)]) -> String {
    let out = Command::new("script")
        .args(["-q", "-e", "-c", shell_command, "/dev/null"])
        .env_remove("MAKEFLAGS")
        .envs(env.iter().copied())
        .output()
        .expect("util-linux `script` runs commands on a pty (apt-get install util-linux)");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Whether `text` holds the spinner's line: the label and place followed by the elapsed time.
fn has_spinner(text: &str) -> bool {
    text.match_indices("align A/walk (3/12) ").any(|(i, m)| {
        let rest = &text[i + m.len()..];
        let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
        digits > 0 && rest[digits..].starts_with('s')
    })
}

#[test]
fn one_line_per_step_on_a_pipe() {
    let out = step(&[], &["sleep", "0.3"]);
    assert!(out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err:?}");
    let secs: f64 = err
        .strip_prefix("align A/walk (3/12), ")
        .and_then(|r| r.strip_suffix(" s\n"))
        .unwrap_or_else(|| panic!("{err:?}"))
        .parse()
        .unwrap();
    assert!((0.3..5.0).contains(&secs), "{err:?}");
    assert!(!has_spinner(&err));
}

#[test]
fn quiet_prints_nothing_and_verbose_echoes_the_command() {
    let out = step(&["-q"], &["true"]);
    assert!(out.status.success());
    assert!(out.stderr.is_empty(), "{:?}", String::from_utf8_lossy(&out.stderr));
    let out = step(&["-v"], &["echo", "two words"]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().next(), Some("echo 'two words'"), "{err:?}");
    assert_eq!(String::from_utf8(out.stdout).unwrap(), "two words\n", "the command's stdout passes through");
}

#[test]
fn a_failing_command_fails_the_step_and_says_which() {
    let out = step(&["-q"], &["sh", "-c", "echo 'align: x.ply: broken' >&2; exit 3"]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines[0], "align: x.ply: broken", "the stage's own error line first");
    assert!(lines[1].starts_with("align A/walk (3/12): failed after "), "{err:?}");
    let out = step(&[], &["/nonexistent/stage"]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.starts_with("plan: /nonexistent/stage: cannot start"), "{err:?}");
}

#[test]
fn a_spinner_on_a_terminal_only() {
    let cmd = format!("{PLAN} step --label 'align A/walk' --of 3/12 -- sleep 1");
    let tty = in_pty(&cmd, &[]);
    assert!(has_spinner(&tty), "no spinner on the pty: {tty:?}");
    assert!(tty.contains("align A/walk (3/12), "), "the done line: {tty:?}");
    let quiet = in_pty(&format!("{PLAN} step -q --label 'align A/walk' --of 3/12 -- sleep 1"), &[]);
    assert!(quiet.trim().is_empty(), "-q on a pty: {quiet:?}");
    // Under make -j the spinners of parallel jobs would overwrite each other: lines only.
    let parallel = in_pty(&cmd, &[("MAKEFLAGS", " -j2 --jobserver-auth=fifo:/tmp/x")]);
    assert!(!has_spinner(&parallel), "{parallel:?}");
    assert!(parallel.contains("align A/walk (3/12), "), "{parallel:?}");
}
