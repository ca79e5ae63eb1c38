//! Where one run of the command line writes and reads, and what it keeps until it ends (the
//! warnings its JSON document carries, the capture files it finishes).
//!
//! The binary's run is the process's: stdout, stderr, stdin and Ctrl-C. A run in another
//! program's process ([`super::run_args_captured`]: a test that serves its simulator in lockstep
//! with the link, so that no verdict depends on how fast another process is scheduled) writes to
//! buffers it gets back, reads an empty stdin and leaves Ctrl-C to its host; several such runs
//! at once in one process never mix. A run's console belongs to the thread that runs it, for
//! as long as it runs: the command line writes only from that thread (its operations report
//! progress on the caller's thread; the link's workers never print).

use crate::capture::Capture;
use std::cell::RefCell;
use std::io::{BufRead, Write};

/// One run's console (see the module's documentation).
pub(crate) struct Console {
    /// Where stdout and stderr go: the process's, or two buffers.
    sink: Sink,
    /// Warnings said in this run (also on stderr), for the JSON document a command prints.
    pub(crate) warnings: Vec<String>,
    /// The captures this run records, finished when it ends.
    pub(crate) captures: Vec<Capture>,
    /// The boot wait this run opened its port with, ms (`None`: no port opened yet): the
    /// checklist of a device that never answers names the boot wait when it was 0.
    pub(crate) boot_wait_ms: Option<u64>,
}

#[derive(Clone)]
enum Sink {
    /// The process's stdout, stderr and stdin.
    Process,
    /// Buffers, and an empty stdin.
    Buffers(Captured),
}

/// Where a captured run writes ([`super::run_args_captured`]): its stdout and stderr, each
/// read as the run goes (another thread may watch for a prompt) or once it has ended; and what
/// its operator types (nothing, unless given: stdin is then closed).
#[derive(Debug, Clone, Default)]
pub struct Captured {
    out: std::sync::Arc<std::sync::Mutex<Vec<u8>>>,
    err: std::sync::Arc<std::sync::Mutex<Vec<u8>>>,
    input: std::sync::Arc<std::sync::Mutex<std::io::Cursor<Vec<u8>>>>,
    /// The run's Ctrl-C: raised by [`Captured::interrupt`].
    ctrl_c: crate::ops::Cancel,
    /// The folder of the user's profiles for this run ([`Captured::with_profiles`]); `None`:
    /// the process's ([`crate::profile::registry::user_dir`]).
    profiles: Option<std::path::PathBuf>,
}

impl Captured {
    /// A run whose operator types `input` (lines, each ended by `\n`), then closes stdin.
    pub fn typing(input: &str) -> Self {
        let c = Self::default();
        *c.input.lock().unwrap_or_else(|e| e.into_inner()) =
            std::io::Cursor::new(input.as_bytes().to_vec());
        c
    }

    /// The same run, whose user profiles (built-ins overridden, `profile import`'s default
    /// folder) are read from `dir` instead of the process's folder: a test's run never reads
    /// the profiles of whoever runs the tests. A missing folder is an empty one.
    pub fn with_profiles(mut self, dir: impl Into<std::path::PathBuf>) -> Self {
        self.profiles = Some(dir.into());
        self
    }

    /// The folder given by [`Self::with_profiles`], if any.
    pub fn profiles(&self) -> Option<&std::path::Path> {
        self.profiles.as_deref()
    }

    /// The operator presses Ctrl-C: the run's long operation stops safely, as the process's
    /// first Ctrl-C makes it ([`super::port::cancel_on_ctrl_c`]).
    pub fn interrupt(&self) {
        self.ctrl_c.cancel();
    }

    /// What the run has written to stdout so far.
    pub fn out(&self) -> String {
        Self::text(&self.out)
    }

    /// What the run has written to stderr so far.
    pub fn err(&self) -> String {
        Self::text(&self.err)
    }

    fn text(buffer: &std::sync::Mutex<Vec<u8>>) -> String {
        String::from_utf8_lossy(&buffer.lock().unwrap_or_else(|e| e.into_inner())).into_owned()
    }

    fn write(buffer: &std::sync::Mutex<Vec<u8>>, bytes: &[u8]) -> usize {
        buffer
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend_from_slice(bytes);
        bytes.len()
    }

    fn write_fmt_to(buffer: &std::sync::Mutex<Vec<u8>>, text: std::fmt::Arguments<'_>) {
        let _ = buffer
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .write_fmt(text);
    }
}

thread_local! {
    /// The console of the run on this thread, while it runs.
    static CONSOLE: RefCell<Option<Console>> = const { RefCell::new(None) };
}

impl Console {
    /// The process's stdout, stderr, stdin and Ctrl-C.
    pub(crate) fn process() -> Self {
        Self {
            sink: Sink::Process,
            warnings: Vec::new(),
            captures: Vec::new(),
            boot_wait_ms: None,
        }
    }

    /// The buffers of `into`, an empty stdin, and no Ctrl-C.
    pub(crate) fn buffers(into: &Captured) -> Self {
        Self {
            sink: Sink::Buffers(into.clone()),
            ..Self::process()
        }
    }
}

/// Runs `f` with `console` as this thread's run console; returns `f`'s result and the console
/// (its buffers, captures and warnings), as it was when `f` ended.
pub(crate) fn scoped<R>(console: Console, f: impl FnOnce() -> R) -> (R, Console) {
    let before = CONSOLE.with(|c| c.replace(Some(console)));
    let r = f();
    let after = CONSOLE.with(|c| c.replace(before));
    (r, after.unwrap_or_else(Console::process))
}

/// A console on this thread's run's stdout, stderr and stdin, for a thread the run starts
/// (the station's operator input).
pub(crate) fn handle() -> Console {
    with(|c| Console {
        sink: c.sink.clone(),
        warnings: Vec::new(),
        captures: Vec::new(),
        boot_wait_ms: None,
    })
}

/// Runs `f` on this thread's run console (the process's when no run is under way).
pub(crate) fn with<R>(f: impl FnOnce(&mut Console) -> R) -> R {
    CONSOLE.with(|c| {
        let mut c = c.borrow_mut();
        f(c.get_or_insert_with(Console::process))
    })
}

/// Writes `text` to the run's stdout. A stdout that is gone (a closed pipe: `| head -1`) loses
/// the rest of the output, not the run.
pub(crate) fn write_out(text: std::fmt::Arguments<'_>) {
    with(|c| match &mut c.sink {
        Sink::Process => {
            let _ = std::io::stdout().lock().write_fmt(text);
        }
        Sink::Buffers(c) => Captured::write_fmt_to(&c.out, text),
    });
}

/// Writes `text` to the run's stderr.
pub(crate) fn write_err(text: std::fmt::Arguments<'_>) {
    with(|c| match &mut c.sink {
        Sink::Process => {
            let _ = std::io::stderr().lock().write_fmt(text);
        }
        Sink::Buffers(c) => Captured::write_fmt_to(&c.err, text),
    });
}

/// The run's stdout as a writer (an export streamed as it is read); its errors are stdout's
/// (gone: a closed pipe).
pub(crate) struct Stdout;

impl Write for Stdout {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        with(|c| match &mut c.sink {
            Sink::Process => std::io::stdout().lock().write(bytes),
            Sink::Buffers(c) => Ok(Captured::write(&c.out, bytes)),
        })
    }

    fn flush(&mut self) -> std::io::Result<()> {
        flush()
    }
}

/// Flushes the run's stdout (a line a script reads before the run ends).
pub(crate) fn flush() -> std::io::Result<()> {
    with(|c| match &c.sink {
        Sink::Process => std::io::stdout().flush(),
        Sink::Buffers(_) => Ok(()),
    })
}

/// The folder of the run's user profiles: the one its [`Captured`] names, else the process's
/// ([`crate::profile::registry::user_dir`]; `None` without a home folder).
pub(crate) fn user_profiles() -> Option<std::path::PathBuf> {
    let given = with(|c| match &c.sink {
        Sink::Process => None,
        Sink::Buffers(b) => b.profiles.clone(),
    });
    given.or_else(crate::profile::registry::user_dir)
}

/// Reads a line the operator typed into `line`; `Ok(0)` when stdin is closed (for a captured
/// run, once what it was given is read: [`Captured::typing`]).
pub(crate) fn read_line(line: &mut String) -> std::io::Result<usize> {
    let input = with(|c| match &c.sink {
        Sink::Process => None,
        Sink::Buffers(b) => Some(b.input.clone()),
    });
    match input {
        None => std::io::stdin().lock().read_line(line),
        Some(i) => i.lock().unwrap_or_else(|e| e.into_inner()).read_line(line),
    }
}

/// Whether this run is the process's own (its Ctrl-C is this run's to catch).
pub(crate) fn is_process() -> bool {
    with(|c| matches!(c.sink, Sink::Process))
}

/// Whether this run's stdout is a terminal a person reads (never for a captured run, nor a
/// pipe or a file): hints and progress are for them, not for a script.
pub(crate) fn stdout_is_terminal() -> bool {
    use std::io::IsTerminal;
    is_process() && std::io::stdout().is_terminal()
}

/// Whether this run's stderr is a terminal a person reads (never for a captured run, nor a
/// pipe or a file): where progress lines go, for them and not for a log.
pub(crate) fn stderr_is_terminal() -> bool {
    use std::io::IsTerminal;
    is_process() && std::io::stderr().is_terminal()
}

/// The Ctrl-C of a run in another program's process ([`Captured::interrupt`]); `None` for the
/// process's own run.
pub(crate) fn captured_ctrl_c() -> Option<crate::ops::Cancel> {
    with(|c| match &c.sink {
        Sink::Process => None,
        Sink::Buffers(b) => Some(b.ctrl_c.clone()),
    })
}

/// `println!` for the run's stdout.
macro_rules! outln {
    () => {
        $crate::cli::console::write_out(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::cli::console::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` for the run's stdout.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cli::console::write_out(format_args!($($arg)*))
    };
}

/// `eprintln!` for the run's stderr.
macro_rules! errln {
    () => {
        $crate::cli::console::write_err(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::cli::console::write_err(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `eprint!` for the run's stderr.
macro_rules! err {
    ($($arg:tt)*) => {
        $crate::cli::console::write_err(format_args!($($arg)*))
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_captured_run_writes_to_its_own_buffers_and_reads_no_operator() {
        let captured = Captured::default();
        let ((), _) = scoped(Console::buffers(&captured), || {
            outln!("a {}", 1);
            out!("b");
            errln!("c");
            err!("d");
            let mut line = String::new();
            assert_eq!(read_line(&mut line).unwrap(), 0);
            assert!(!is_process());
        });
        assert_eq!(captured.out(), "a 1\nb");
        let typed = Captured::typing("q\n");
        let ((), _) = scoped(Console::buffers(&typed), || {
            let mut line = String::new();
            assert_eq!(read_line(&mut line).unwrap(), 2);
            assert_eq!(line, "q\n");
            assert_eq!(read_line(&mut line).unwrap(), 0, "then closed");
        });
        assert_eq!(captured.err(), "c\nd");
        assert!(is_process(), "the thread's console is the process's again");
    }
}
