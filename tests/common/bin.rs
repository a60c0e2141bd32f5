//! Running the `flexiso` binary the way a user does, and what it printed.

use std::io::Write;
use std::process::{Command, Stdio};

/// What one run of the binary did.
#[derive(Debug)]
pub struct Run {
    /// The exit code (-1 when killed by a signal).
    pub code: i32,
    /// Standard output, as text (lossy).
    pub stdout: String,
    /// Standard output, as bytes (for data written to `-`).
    pub stdout_bytes: Vec<u8>,
    /// Standard error, as text (lossy).
    pub stderr: String,
}

impl Run {
    /// True when the exit code is 0.
    pub fn success(&self) -> bool {
        self.code == 0
    }
}

/// Runs `flexiso ARGS` with nothing on standard input.
pub fn flexiso(args: &[&str]) -> Run {
    flexiso_with_stdin(args, &[])
}

/// Runs `flexiso ARGS` with no display named in its environment (no
/// `DISPLAY`, no `WAYLAND_DISPLAY`).
pub fn flexiso_without_display(args: &[&str]) -> Run {
    let mut c = Command::new(env!("CARGO_BIN_EXE_flexiso"));
    c.args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY");
    finish(c, &[])
}

/// Runs `flexiso ARGS` with `stdin` piped to its standard input.
pub fn flexiso_with_stdin(args: &[&str], stdin: &[u8]) -> Run {
    let mut c = Command::new(env!("CARGO_BIN_EXE_flexiso"));
    c.args(args);
    finish(c, stdin)
}

fn finish(mut c: Command, stdin: &[u8]) -> Run {
    let mut child = c
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run flexiso");
    let mut input = child.stdin.take().expect("piped stdin");
    // The binary may exit without reading: a broken pipe is its answer.
    let _ = input.write_all(stdin);
    drop(input);
    let out = child.wait_with_output().expect("wait for flexiso");
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stdout_bytes: out.stdout,
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}
