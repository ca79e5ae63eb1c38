//! What a slot tells whoever shows the station (the window, the headless JSON lines), and what
//! it is told: events out, commands in, over crossbeam channels.

use super::reason::Reason;
use serde::Serialize;

/// One thing that happened at a slot.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Event {
    /// The slot's name; empty for the station's own events ([`What::Records`] from the
    /// forwarder).
    pub slot: String,
    /// What happened.
    #[serde(flatten)]
    pub what: What,
}

/// What happened at a slot. As JSON: `{"slot":"1","event":"step","index":2,...}`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "kebab-case")]
pub enum What {
    /// The slot's port: found and opened (`present`), or missing and waited for.
    Port {
        /// Whether it is there.
        present: bool,
        /// The path opened, or why it is missing.
        detail: String,
    },
    /// Idle, waiting for a unit: `how` it starts (`button`, `scan`, `auto`).
    Waiting {
        /// `button`, `scan` or `auto`.
        how: &'static str,
    },
    /// A unit's run started.
    Unit {
        /// Its serial, when known already (scanned to start it).
        serial: Option<String>,
    },
    /// A step started.
    Step {
        /// 1-based.
        index: usize,
        /// How many steps.
        of: usize,
        /// Its name (`Self-test (window-cleaner-selftest)`), as the records keep it.
        name: String,
        /// Its name in 中文.
        name_zh: String,
        /// 1 the first try, 2 the retry.
        attempt: u8,
    },
    /// The operator is asked something: `kind` `confirm` (yes/no), `measure` (a value),
    /// `scan` (a code), `retry` (yes/no: retry the failed step), `prompt` (do what the text
    /// says; the step watches for it).
    Ask {
        /// `confirm`, `measure`, `scan`, `retry` or `prompt`.
        kind: &'static str,
        /// The question in English.
        text: String,
        /// The question in 中文.
        text_zh: String,
        /// A retry question's cause: why the step failed (typed: the window says it in 中文).
        /// Not in the JSON lines, whose `text` says it.
        #[serde(skip)]
        why: Option<Reason>,
    },
    /// A step ended.
    StepDone {
        /// Its name.
        name: String,
        /// Its name in 中文.
        name_zh: String,
        /// PASS or FAIL.
        pass: bool,
        /// What was seen.
        detail: String,
    },
    /// The unit's verdict, said once its record is kept.
    Verdict {
        /// PASS or FAIL.
        pass: bool,
        /// The unit's serial, when known.
        serial: Option<String>,
        /// The first failed step.
        failed_step: Option<String>,
        /// Its name in 中文.
        failed_step_zh: Option<String>,
        /// Why it failed (as JSON: its English, [`Reason`]'s `Display`).
        reason: Option<Reason>,
        /// How many earlier runs of this serial the records hold.
        earlier_runs: Option<i64>,
        /// The record's UUID.
        record: String,
        /// Where the record went (`record saved to ...`, or the spool or memory and why).
        kept: String,
        /// Whether the record reached its store (`false`: kept in a spool or in memory, as
        /// `kept` says; the verdict stands either way).
        stored: bool,
    },
    /// The station's records not yet in their store (a line server away, a full disk): how
    /// many wait, where, and why. Said by a slot after each record and by the station's
    /// forwarder (`slot` empty) when the count changes.
    Records {
        /// Records waiting to be forwarded (0: everything is in the store).
        waiting: u64,
        /// The store (file or server, password hidden).
        store: String,
        /// Why they wait: the store's last error.
        why: Option<String>,
    },
    /// The slot is lent to the engineer view ([`Command::Lend`]): its runner closed its port
    /// and waits for [`Command::Return`]; the engineer's window opens `port` itself.
    Lent {
        /// The port's path as the slot found it (a simulated slot's served name).
        port: String,
    },
    /// The slot stopped (STOP, STOP ALL, end of `--once`): the device left in its safe state.
    Stopped {
        /// Why.
        why: String,
    },
}

/// What a slot is told.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Command {
    /// Start the next unit (the Start button).
    Start,
    /// An answer: `yes`/`no` to a Confirm or a retry question, a value to a Measure, a code
    /// to a Scan (a code also starts a slot that starts by scan).
    Answer(Answer),
    /// Lend the slot to the engineer view: taken only while the slot is idle (waiting for a
    /// unit); its runner closes its port, says [`What::Lent`] and waits for [`Command::Return`].
    /// Ignored while a unit runs.
    Lend,
    /// The engineer view closed: the runner opens its port again and waits for the next unit.
    Return,
}

/// The operator's answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Answer {
    /// Y, a pedal, a scanned PASS code.
    Yes,
    /// N, a scanned FAIL code.
    No,
    /// A typed or scanned value.
    Text(String),
}

impl Answer {
    /// `y`/`yes`/`pass` → Yes, `n`/`no`/`fail` → No (any case), else the text.
    pub fn parse(text: &str) -> Answer {
        let t = text.trim();
        match t.to_ascii_lowercase().as_str() {
            "y" | "yes" | "pass" | "ok" => Answer::Yes,
            "n" | "no" | "fail" => Answer::No,
            _ => Answer::Text(t.to_string()),
        }
    }
}
