//! The benchmarks, in one binary: decoder throughput (`decoders`), the plot path (`series`) and
//! one UI frame with the memory of an hour of telemetry (`ui_frame`).
//!
//! Run all with `cargo bench`, one with `cargo bench -- decoders` (`series`, `ui_frame`);
//! criterion's options follow, e.g. `--warm-up-time 1 --measurement-time 3`. `cargo test
//! --all-targets` runs each once, quickly, without `--bench`.

// Tests and benchmarks stop at the first thing that is not as set up: a panic is their report.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod decoders;
mod series;
mod ui_frame;

use criterion::Criterion;

/// The benchmarks by name, as given on the command line.
const SECTIONS: [&str; 3] = ["decoders", "series", "ui_frame"];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let asked: Vec<&str> = SECTIONS
        .into_iter()
        .filter(|s| args.iter().any(|a| a == s))
        .collect();
    let runs = |section| asked.is_empty() || asked.contains(&section);
    if runs("decoders") || runs("series") {
        // Criterion reads the rest of the command line itself: a section's name is the filter
        // its group names start with.
        let mut c = Criterion::default().configure_from_args();
        if runs("decoders") {
            decoders::benches(&mut c);
        }
        if runs("series") {
            series::benches(&mut c);
        }
        c.final_summary();
    }
    if runs("ui_frame") {
        ui_frame::run(!args.iter().any(|a| a == "--bench"));
    }
}
