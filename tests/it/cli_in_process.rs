//! The command line run in this process, handed its port opener the way the binary hands it the
//! system's serial ports (`botbench::cli::main(PortOpener::system())`): a test's simulator is
//! reached through the opener it is given, served in lockstep, so nothing here depends on how
//! fast another process is scheduled.

use crate::support::served_window_cleaner;
use botbench::link::PortOpener;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

#[test]
fn the_command_line_opens_its_port_with_the_opener_it_is_handed() {
    let b = served_window_cleaner();
    let opened = Arc::new(AtomicUsize::new(0));
    let ports = {
        let (opened, served, path) = (opened.clone(), b.ports(), b.path().to_string());
        PortOpener::system().with_port(b.path(), move |baud| {
            opened.fetch_add(1, Ordering::SeqCst);
            served.open(&path, baud)
        })
    };
    let code = botbench::cli::run_args(["botbench", "msp", "--port", b.path(), "version"], &ports);
    assert_eq!(code, 0, "msp version against the served window cleaner");
    assert_eq!(
        opened.load(Ordering::SeqCst),
        1,
        "opened once, through the opener handed in"
    );

    // A port the opener does not serve is the system's: this one does not exist.
    let code = botbench::cli::run_args(
        [
            "botbench",
            "msp",
            "--port",
            "/nonexistent/botbench-tty",
            "version",
        ],
        &ports,
    );
    assert_eq!(code, 2, "a port that cannot be opened is bad input");
    assert_eq!(opened.load(Ordering::SeqCst), 1);
}
