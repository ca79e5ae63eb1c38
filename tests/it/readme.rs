//! The README runs as written (issue 29): every command of its `sh` blocks is run, in order, in
//! one bash session, as a new user would paste them, against the simulators the blocks
//! themselves start, and must end with exit 0 unless its comment says otherwise
//! (`# exit 1: ...`). A README change that breaks an example fails here.
//!
//! The blocks hold no placeholders (`...`, `<PORT>`): templates are `text` blocks or prose.
//! The simulators run as `botbench sim` processes, as the README starts them, under real-time
//! scheduling where this process may (as the rest of the suite runs a simulated device: a
//! device has a processor of its own, and a loaded host must not make it answer late).

use crate::support::cli::watched;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One command of a `sh` block.
#[derive(Debug, PartialEq)]
struct ShCommand {
    /// The README's line where it starts (1-based).
    line: usize,
    /// Its text, continuation lines joined with their backslash-newlines.
    text: String,
    /// The exit code its comment names (`# exit N: ...`), else 0.
    expected: i32,
    /// It ends with `&`: started in the background, its exit code not checked.
    background: bool,
}

/// The commands of every fenced block tagged `sh` in `markdown`, in order; an error names the
/// line of a placeholder or an unterminated block.
fn sh_commands(markdown: &str) -> Result<Vec<ShCommand>, String> {
    let mut commands = Vec::new();
    let mut in_sh = false;
    let mut pending: Option<ShCommand> = None;
    for (i, raw) in markdown.lines().enumerate() {
        let line = i + 1;
        if raw.starts_with("```") {
            in_sh = !in_sh && raw.trim_end() == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        if raw.contains("...") || raw.contains("<PORT>") {
            return Err(format!(
                "README.md:{line}: a placeholder in an sh block: {raw}"
            ));
        }
        let mut command = pending.take().unwrap_or(ShCommand {
            line,
            text: String::new(),
            expected: 0,
            background: false,
        });
        if !command.text.is_empty() {
            command.text.push('\n');
        }
        command.text.push_str(raw);
        if raw.trim_end().ends_with('\\') {
            pending = Some(command);
            continue;
        }
        let code = code_part(raw).trim_end();
        if code.trim().is_empty() {
            continue;
        }
        command.background = code.ends_with('&') && !code.ends_with("&&");
        command.expected = expected_exit(raw);
        commands.push(command);
    }
    if in_sh || pending.is_some() {
        return Err("README.md: an sh block or a command does not end".into());
    }
    Ok(commands)
}

/// `line` without its comment (a `#` at the start or after a blank; none of the README's
/// commands quotes a `#`).
fn code_part(line: &str) -> &str {
    if line.trim_start().starts_with('#') {
        return "";
    }
    match line.find(" #") {
        Some(at) => &line[..at],
        None => line,
    }
}

/// The exit code a command's comment names: `# exit N` at the comment's start, else 0.
fn expected_exit(line: &str) -> i32 {
    let Some(at) = line.find(" # ") else { return 0 };
    let comment = line[at + 3..].trim_start();
    comment
        .strip_prefix("exit ")
        .and_then(|rest| {
            let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
            digits.parse().ok()
        })
        .unwrap_or(0)
}

/// The bash script that runs `commands` and writes a line to `failures` for each command whose
/// exit code is not the one expected; background jobs are killed at its end.
fn script(commands: &[ShCommand], failures: &Path) -> String {
    let mut s = String::from(
        "set -u\n\
         __check() { if [ \"$1\" != \"$2\" ]; then\n\
             echo \"README.md:$3: exit $1, expected $2\" | tee -a \"$FAILURES\" >&2; fi; }\n\
         trap 'kill $(jobs -p) 2>/dev/null; wait' EXIT\n",
    );
    s = s.replace("$FAILURES", &failures.display().to_string());
    for c in commands {
        s.push_str(&format!("echo '== README.md:{}' >&2\n", c.line));
        s.push_str(&c.text);
        s.push('\n');
        if !c.background {
            s.push_str(&format!("__check $? {} {}\n", c.expected, c.line));
        }
    }
    s
}

/// A folder holding `botbench`: a script that runs the binary under test, `botbench sim` under
/// `chrt --fifo 10` where this process may use real-time scheduling.
fn bin_dir(tmp: &Path) -> PathBuf {
    let dir = tmp.join("bin");
    std::fs::create_dir_all(&dir).unwrap();
    let bin = env!("CARGO_BIN_EXE_botbench");
    let wrapper = format!(
        "#!/bin/sh\n\
         if [ \"${{1:-}}\" = sim ] && chrt --fifo 10 true 2>/dev/null; then\n\
         \x20   exec chrt --fifo 10 '{bin}' \"$@\"\n\
         fi\n\
         exec '{bin}' \"$@\"\n"
    );
    let path = dir.join("botbench");
    std::fs::write(&path, wrapper).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    dir
}

/// Ignored in the suite's run: it runs a user's processes (simulators and commands in processes
/// of their own, with the README's default margins), which the suite's eight test threads on two
/// cores would starve as no user's machine is. `.ci/run` runs it alone, right after the suite
/// (`cargo test --test it -- --ignored --exact readme::every_command_of_the_readmes_sh_blocks_runs_as_written`).
#[test]
#[ignore = "runs the README's commands as processes: run alone, as .ci/run does"]
fn every_command_of_the_readmes_sh_blocks_runs_as_written() {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("reads README.md");
    let commands = sh_commands(&readme).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        commands.iter().filter(|c| !c.background).count() >= 20,
        "the README's sh blocks hold the first tasks of every device: {commands:#?}"
    );
    let tmp = tempfile::tempdir().unwrap();
    let failures = tmp.path().join("failures");
    let path = format!(
        "{}:{}",
        bin_dir(tmp.path()).display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut bash = Command::new("bash");
    bash.arg("-c")
        .arg(script(&commands, &failures))
        .current_dir(tmp.path())
        // A new user's HOME: records go to its data folder, no user profiles.
        .env("HOME", tmp.path())
        .env("PATH", path)
        .env_remove("XDG_DATA_HOME")
        .env_remove("XDG_CONFIG_HOME")
        .env_remove("BOTBENCH_RECORDS")
        .env_remove("BOTBENCH_SPOOL")
        .env_remove("BOTBENCH_PROFILE_DIR")
        .stdin(std::process::Stdio::null());
    let ran = watched(&mut bash, "the README's sh blocks");
    let failed = std::fs::read_to_string(&failures).unwrap_or_default();
    assert!(
        failed.is_empty() && ran.code == 0,
        "README commands that did not end as written:\n{failed}\n(exit {})\nstdout:\n{}\nstderr:\n{}",
        ran.code,
        ran.out,
        ran.err
    );
}

#[test]
fn the_readme_test_reads_commands_continuations_exit_codes_and_refuses_placeholders() {
    let md = "text\n```sh\nbotbench sim servo-bus > s.txt &   # a simulator\n\
              # a comment line\n\
              botbench a \\\n    b   # exit 1: differs\n\
              botbench c          # read back; exit 1 on a mismatch\n```\n\
              ```text\nbotbench msp --port PORT ...\n```\n";
    let commands = sh_commands(md).unwrap();
    assert_eq!(commands.len(), 3, "{commands:#?}");
    assert!(commands[0].background);
    assert_eq!(
        (commands[1].line, commands[1].expected),
        (5, 1),
        "{commands:#?}"
    );
    assert_eq!(commands[1].text, "botbench a \\\n    b   # exit 1: differs");
    assert_eq!(
        commands[2].expected, 0,
        "exit named later in a comment is prose"
    );
    let planted = "```sh\nbotbench msp --port $p set ...\n```\n";
    assert!(sh_commands(planted).unwrap_err().contains("README.md:2"));
    assert!(sh_commands("```sh\nbotbench a\n").is_err());
}
