//! Names the build: `BOTBENCH_COMMIT` is the git commit botbench was built from (short hash),
//! else the `BOTBENCH_COMMIT` given in the environment (a source archive, a distribution's
//! build), else `unknown`. `botbench --version` and the window's title show it.

use std::path::PathBuf;
use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

fn main() {
    println!("cargo:rerun-if-env-changed=BOTBENCH_COMMIT");
    let commit = git(&["rev-parse", "--short=9", "HEAD"]);
    if commit.is_some() {
        // A new commit or a checkout moves HEAD or the branch it names (in a worktree, .git is a
        // file: ask git where they are). Packed refs change on `git gc`.
        let mut watch = vec!["HEAD".to_string(), "packed-refs".to_string()];
        if let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) {
            watch.push(branch);
        }
        for name in watch {
            if let Some(p) = git(&["rev-parse", "--git-path", &name]) {
                let p = PathBuf::from(p);
                if p.exists() {
                    println!("cargo:rerun-if-changed={}", p.display());
                }
            }
        }
    }
    let commit = commit
        .or_else(|| {
            std::env::var("BOTBENCH_COMMIT")
                .ok()
                .filter(|s| !s.is_empty())
        })
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=BOTBENCH_COMMIT={commit}");
}
