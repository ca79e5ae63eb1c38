//! The command line run in this process, handed its port opener the way the binary hands it the
//! system's serial ports (`botbench::cli::main(PortOpener::system())`): a test's simulator is
//! reached through the opener it is given, served in lockstep, so nothing here depends on how
//! fast another process is scheduled.

use crate::support::cli::{run_in_process, run_in_process_into};
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
    let ran = run_in_process(&["msp", "--port", b.path(), "version"], &ports);
    assert_eq!(
        ran.code,
        0,
        "msp version against the served window cleaner: {}",
        ran.text()
    );
    assert_eq!(
        opened.load(Ordering::SeqCst),
        1,
        "opened once, through the opener handed in"
    );

    // A port the opener does not serve is the system's: this one does not exist.
    let ran = run_in_process(
        &["msp", "--port", "/nonexistent/botbench-tty", "version"],
        &ports,
    );
    assert_eq!(
        ran.code,
        2,
        "a port that cannot be opened is bad input: {}",
        ran.text()
    );
    assert_eq!(opened.load(Ordering::SeqCst), 1);
}

#[test]
fn a_run_in_this_process_reads_the_profiles_of_the_folder_it_is_given_never_the_users() {
    let b = served_window_cleaner();
    let dir = crate::support::temp_dir();
    let broken = dir.path().join("window-cleaner.ron");
    std::fs::write(&broken, "(id: \"window-cleaner\",").unwrap();
    // Given the folder: its malformed profile is an error naming the file.
    let given = botbench::cli::Captured::default().with_profiles(dir.path());
    let ran = run_in_process_into(&["profiles"], &b.ports(), given);
    assert_eq!(ran.code, 2, "{}", ran.text());
    assert!(ran.err.contains("window-cleaner.ron"), "{}", ran.text());
    // The tests' runs get an empty folder: the built-ins, whatever the user has.
    let ran = run_in_process(&["profiles"], &b.ports());
    assert_eq!(ran.code, 0, "{}", ran.text());
    assert!(ran.out.contains("window-cleaner"), "{}", ran.text());
}
