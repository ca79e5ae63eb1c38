//! The command line's numbers, each read with its range: the ranges here are the ones `--help`
//! states (a test reads every numeric option's help and tries its bounds), and a value outside
//! is refused by the parser, before any file or port is opened.

use crate::document::number_within as within;
use std::ops::RangeInclusive;

/// Baud rates a serial port is opened at (`--baud`): what USB adapters and UARTs offer.
pub(crate) const BAUD: RangeInclusive<u32> = 300..=4_000_000;
/// How long a device may take to answer beyond the wire time (`--margin-ms`), ms: the link's
/// range, which the window and a station take too.
pub(crate) const MARGIN_MS: RangeInclusive<u64> = crate::link::MARGIN_MS;
/// How long to send nothing after the port opens (`--boot-wait-ms`), ms: the link's range.
pub(crate) const BOOT_WAIT_MS: RangeInclusive<u64> = crate::link::BOOT_WAIT_MS;
/// How long a simulator boots after each open (`sim --boot-ms`), ms.
pub(crate) const BOOT_MS: RangeInclusive<u64> = 0..=60_000;
/// Polls per second of `msp watch --rate`.
pub(crate) const RATE: RangeInclusive<f64> = 0.1..=1_000.0;
/// Answers `msp watch --count` waits for.
pub(crate) const COUNT: RangeInclusive<u64> = 1..=1_000_000_000;
/// Seconds `tuya --wait` gives the start-up handshake.
pub(crate) const HANDSHAKE_S: RangeInclusive<u64> = 1..=600;
/// Servos `servo provision --count` provisions in one run.
pub(crate) const PROVISION_COUNT: RangeInclusive<u32> = 1..=10_000;
/// Ms between looks for a new servo (`servo provision --wait-ms`).
pub(crate) const WAIT_MS: RangeInclusive<u64> = 1..=600_000;
/// A simulator's extra reply delay (`sim --latency-ms`).
pub(crate) const LATENCY_MS: RangeInclusive<u64> = 0..=10_000;

/// `--baud`: a rate within [`BAUD`].
pub(crate) fn baud(text: &str) -> Result<u32, String> {
    within(text, &BAUD, "a baud rate")
}

/// `--margin-ms`: within [`MARGIN_MS`].
pub(crate) fn margin_ms(text: &str) -> Result<u64, String> {
    within(text, &MARGIN_MS, "milliseconds")
}

/// `--boot-wait-ms`: within [`BOOT_WAIT_MS`].
pub(crate) fn boot_wait_ms(text: &str) -> Result<u64, String> {
    within(text, &BOOT_WAIT_MS, "milliseconds")
}

/// `sim --boot-ms`: within [`BOOT_MS`].
pub(crate) fn boot_ms(text: &str) -> Result<u64, String> {
    within(text, &BOOT_MS, "milliseconds")
}

/// `--dtr`, `--rts`: on, off or keep.
pub(crate) fn line_level(text: &str) -> Result<crate::link::LineLevel, String> {
    text.parse()
}

/// `msp watch --count`: within [`COUNT`].
pub(crate) fn count(text: &str) -> Result<u64, String> {
    within(text, &COUNT, "a count")
}

/// `tuya --wait`: within [`HANDSHAKE_S`].
pub(crate) fn handshake_s(text: &str) -> Result<u64, String> {
    within(text, &HANDSHAKE_S, "seconds")
}

/// `servo provision --count`: within [`PROVISION_COUNT`].
pub(crate) fn provision_count(text: &str) -> Result<u32, String> {
    within(text, &PROVISION_COUNT, "a count")
}

/// `servo provision --wait-ms`: within [`WAIT_MS`].
pub(crate) fn wait_ms(text: &str) -> Result<u64, String> {
    within(text, &WAIT_MS, "milliseconds")
}

/// `sim --latency-ms`: within [`LATENCY_MS`].
pub(crate) fn latency_ms(text: &str) -> Result<u64, String> {
    within(text, &LATENCY_MS, "milliseconds")
}

/// `--port`: a path, not empty.
pub(crate) fn port_path(text: &str) -> Result<String, String> {
    if text.trim().is_empty() {
        return Err(
            "give the serial port's path, e.g. /dev/ttyUSB0 (`botbench ports` lists them)".into(),
        );
    }
    Ok(text.to_string())
}

/// `sim --drop`, `--corrupt`: a probability, 0 to 1.
pub(crate) fn probability(text: &str) -> Result<f64, String> {
    within(text, &(0.0..=1.0), "a probability")
}

/// A servo id that a command addresses and expects an answer from: 0 to 254 (255 is the
/// broadcast id, which every servo obeys and none answers).
pub(crate) fn servo_id(text: &str) -> Result<u8, String> {
    let broadcast = crate::protocol::servo::BROADCAST_ID;
    if text.trim() == broadcast.to_string() {
        return Err(format!(
            "{broadcast} is the broadcast id: every servo obeys it and none answers; give an id from 0 to {}",
            broadcast - 1
        ));
    }
    within(text, &(0..=broadcast - 1), "a servo id")
}

/// A servo id where the broadcast id may be given too (`servo write` and `servo angle` with
/// `--broadcast`): 0 to 255.
pub(crate) fn servo_id_or_broadcast(text: &str) -> Result<u8, String> {
    within(text, &(0..=255), "a servo id")
}

/// `msp watch --rate`: polls per second for each command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Rate {
    /// As fast as the wire allows.
    Max,
    /// This many polls per second, within [`RATE`].
    PerSecond(f64),
}

/// `msp watch --rate`: `max`, or polls per second within [`RATE`].
pub(crate) fn rate(text: &str) -> Result<Rate, String> {
    if text.trim().eq_ignore_ascii_case("max") {
        return Ok(Rate::Max);
    }
    within(text, &RATE, "polls per second")
        .map(Rate::PerSecond)
        .map_err(|e| format!("{e}, or max (as fast as the wire allows)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_read_within_their_range_and_errors_say_it() {
        assert_eq!(baud("115200"), Ok(115_200));
        let e = baud("0").unwrap_err();
        assert!(
            e.contains("0 is out of range; give a baud rate from 300 to 4000000"),
            "{e}"
        );
        assert!(baud("-1").unwrap_err().contains("not a number"));
        assert!(baud("").unwrap_err().contains("not a number"));
        assert!(baud(&"9".repeat(5000)).unwrap_err().len() < 200);
        assert_eq!(rate("max"), Ok(Rate::Max));
        assert_eq!(rate("MAX"), Ok(Rate::Max));
        assert_eq!(rate("20"), Ok(Rate::PerSecond(20.0)));
        for bad in ["0", "-1", "NaN", "inf", "1e9", "fast"] {
            let e = rate(bad).unwrap_err();
            assert!(e.contains("or max"), "{bad}: {e}");
        }
        assert!(probability("NaN").is_err());
        assert!(probability("1.5").is_err());
        assert_eq!(probability("0.25"), Ok(0.25));
        assert!(servo_id("255").unwrap_err().contains("broadcast"));
        assert_eq!(servo_id("254"), Ok(254));
        assert!(servo_id("256").is_err());
    }

    /// The window and a station read margins and boot waits with the link's ranges: each takes
    /// exactly what `--margin-ms` and `--boot-wait-ms` take.
    #[test]
    fn the_window_s_margin_and_boot_wait_accept_what_the_command_line_accepts() {
        use crate::link::ms_within;
        for ms in [
            0u64, 1, 2, 20, 300, 4_999, 5_000, 5_001, 29_999, 30_000, 30_001,
        ] {
            let t = ms.to_string();
            let (cli, window) = (margin_ms(&t), ms_within(&t, &crate::link::MARGIN_MS));
            assert_eq!(cli, window, "margin {ms}");
            let (cli, window) = (boot_wait_ms(&t), ms_within(&t, &crate::link::BOOT_WAIT_MS));
            assert_eq!(cli, window, "boot wait {ms}");
        }
        assert_eq!(MARGIN_MS, 1..=5_000);
        assert_eq!(BOOT_WAIT_MS, 0..=30_000);
    }
}
