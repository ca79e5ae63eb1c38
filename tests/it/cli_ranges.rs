//! Every numeric option and argument of the command line states its range in `--help`, and the
//! parser holds to it: the bounds are taken, the values just past them refused. Read from the
//! parser itself, so that an option added without a range fails here.

use botbench::cli::Cli;
use clap::CommandFactory;
use std::any::TypeId;
use std::ffi::OsString;

/// The numeric types an option may parse to.
fn is_numeric(id: impl PartialEq<TypeId>) -> bool {
    [
        TypeId::of::<u8>(),
        TypeId::of::<u16>(),
        TypeId::of::<u32>(),
        TypeId::of::<u64>(),
        TypeId::of::<i64>(),
        TypeId::of::<f64>(),
    ]
    .iter()
    .any(|t| id == *t)
}

/// The first `A to B` of a help text, as the two numbers' text.
fn stated_range(help: &str) -> Option<(String, String)> {
    let words: Vec<&str> = help.split_whitespace().collect();
    words.windows(3).find_map(|w| {
        let num = |s: &str| {
            let s = s.trim_end_matches([',', '.', ')', ';']);
            s.parse::<f64>().ok().map(|_| s.to_string())
        };
        (w[1] == "to").then(|| Some((num(w[0])?, num(w[2])?)))?
    })
}

/// Every argument of every subcommand: (path, argument).
fn all_args(cmd: &clap::Command, path: &str, out: &mut Vec<(String, clap::Arg)>) {
    for a in cmd.get_arguments() {
        out.push((format!("{path} {}", a.get_id()), a.clone()));
    }
    for sub in cmd.get_subcommands() {
        all_args(sub, &format!("{path} {}", sub.get_name()), out);
    }
}

/// Whether `arg`'s own parser takes `value`: the argument alone in a command of its own, given
/// as `--long=VALUE` (an option) or after `--` (a positional).
fn parses(arg: &clap::Arg, value: &str) -> bool {
    let alone = clap::Command::new("t")
        .no_binary_name(true)
        .arg(arg.clone().required(false));
    let argv: Vec<OsString> = match arg.get_long() {
        Some(long) => vec![format!("--{long}={value}").into()],
        None => vec!["--".into(), value.into()],
    };
    alone.try_get_matches_from(argv).is_ok()
}

/// A value just past a bound: one more (or less), or a tenth for a bound with a fraction.
fn past(bound: &str, up: bool) -> String {
    let step = if bound.contains('.') { 0.1 } else { 1.0 };
    let v: f64 = bound.parse().unwrap();
    let next = if up { v + step } else { v - step };
    if bound.contains('.') {
        format!("{next:.1}")
    } else {
        format!("{next:.0}")
    }
}

#[test]
fn every_numeric_option_states_its_range_and_the_parser_holds_to_it() {
    let cli = Cli::command();
    let mut args = Vec::new();
    all_args(&cli, "botbench", &mut args);
    let mut checked = 0;
    for (path, arg) in &args {
        if !is_numeric(arg.get_value_parser().type_id()) {
            continue;
        }
        let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
        let Some((lo, hi)) = stated_range(&help) else {
            panic!("{path}: its help states no range (`A to B`): {help:?}");
        };
        assert!(parses(arg, &lo), "{path}: {lo} refused; help: {help}");
        assert!(parses(arg, &hi), "{path}: {hi} refused; help: {help}");
        // Past the bounds, unless the bound is the type's own (u64::MAX, 0 for unsigned).
        let max_of_type = ["255", "65535", "4294967295", "18446744073709551615"];
        if !max_of_type.contains(&hi.as_str()) {
            let over = past(&hi, true);
            assert!(!parses(arg, &over), "{path}: {over} taken; help: {help}");
        }
        if lo != "0" {
            let under = past(&lo, false);
            assert!(!parses(arg, &under), "{path}: {under} taken; help: {help}");
        }
        checked += 1;
    }
    // --baud (gui, sim, msp, servo, tuya, preset ×3), --margin-ms, --poll-pipeline, --count,
    // servo ids, --ms, --power, --wait, --wait-ms, --latency-ms, --drop, --corrupt, --seed...
    assert!(checked >= 40, "only {checked} numeric options found");
}

/// `msp watch --rate`, which the `--poll-pipeline` help tells to write as `max`, takes it.
#[test]
fn what_the_help_tells_to_write_is_taken() {
    let cli = Cli::command();
    let mut args = Vec::new();
    all_args(&cli, "botbench", &mut args);
    let (_, rate) = args
        .iter()
        .find(|(p, _)| p == "botbench msp watch rate")
        .expect("msp watch --rate");
    let help = rate.get_help().unwrap().to_string();
    assert!(help.contains("0.1 to 1000, or max"), "{help}");
    for ok in ["max", "MAX", "0.1", "1000", "20"] {
        assert!(parses(rate, ok), "--rate {ok} refused");
    }
    for bad in ["0", "0.05", "1000.1", "-1", "NaN", "inf", "fast", ""] {
        assert!(!parses(rate, bad), "--rate {bad} taken");
    }
    // Every help that names `--rate max` is about an option that exists.
    let pipeline = args
        .iter()
        .find(|(p, _)| p == "botbench msp poll_pipeline")
        .map(|(_, a)| a.get_help().unwrap().to_string())
        .unwrap();
    assert!(pipeline.contains("`watch --rate max`"), "{pipeline}");
}
