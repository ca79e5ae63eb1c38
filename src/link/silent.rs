//! What a technician checks when the device behind an open port never answers: power, wiring,
//! baud rate, profile, and (when the port was opened with no boot wait) a board that reboots
//! when the port opens. The checks are typed items, said in both languages; the settings they
//! name (the baud rate, the profile, the boot wait, the lines) are named by whoever shows them
//! ([`SettingNames`]): the command line by its options, the window by its fields. When the
//! computer itself was held up past the answer's deadline (a loaded computer), that is said
//! first, and the wiring only if the device still does not answer with the computer idle.

use crate::i18n::Text;
use std::time::Duration;

/// One thing to check when nothing answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SilentCheck {
    /// The device is powered.
    Power,
    /// TX to RX, RX to TX, GND to GND.
    Wiring,
    /// The port is at the device's baud rate.
    Baud,
    /// The profile is the device's.
    Profile,
    /// A board that reboots when the port opens (its USB adapter toggles DTR/RTS) needs a boot
    /// wait, or the lines set right after the open.
    Reboots,
    /// This computer ran this long behind the answer's deadline (a loaded computer): the answer
    /// may have come with nobody there to read it in time. Said first, as its own sentence.
    HostLate(Duration),
}

/// How the settings a check points to are named where the checklist is shown: `--baud` on the
/// command line, the Baud field in the window.
#[derive(Debug, Clone, PartialEq)]
pub struct SettingNames {
    /// The baud rate setting.
    pub baud: Text,
    /// The profile setting.
    pub profile: Text,
    /// The boot wait, with a value to try (2 s).
    pub boot_wait: Text,
    /// DTR and RTS set right after the open (off, or on).
    pub lines: Text,
}

impl SilentCheck {
    /// The checks, in the order they are said; [`SilentCheck::Reboots`] only when the port was
    /// opened with no boot wait (`boot_wait_given` false).
    pub fn list(boot_wait_given: bool) -> Vec<SilentCheck> {
        let mut checks = vec![
            SilentCheck::Power,
            SilentCheck::Wiring,
            SilentCheck::Baud,
            SilentCheck::Profile,
        ];
        if !boot_wait_given {
            checks.push(SilentCheck::Reboots);
        }
        checks
    }

    /// The checks of [`SilentCheck::list`], led by [`SilentCheck::HostLate`] when the timeout
    /// says this computer was held up `host_late` past the answer's deadline.
    pub fn list_after(boot_wait_given: bool, host_late: Option<Duration>) -> Vec<SilentCheck> {
        let mut checks: Vec<SilentCheck> =
            host_late.map(SilentCheck::HostLate).into_iter().collect();
        checks.extend(Self::list(boot_wait_given));
        checks
    }

    /// The check as a clause of the checklist's question (`is the device …`), naming its
    /// setting as `names` does; [`SilentCheck::Reboots`] is a question of its own.
    pub fn said(self, names: &SettingNames) -> Text {
        match self {
            SilentCheck::Power => Text::new("powered", "设备是否通电"),
            SilentCheck::Wiring => Text::new(
                "its TX wired to the adapter's RX (and RX to TX, GND to GND)",
                "其 TX 是否接到适配器的 RX(RX 接 TX,GND 接 GND)",
            ),
            SilentCheck::Baud => Text::new(
                format!("at this baud rate ({})", names.baud.en),
                format!("波特率是否相符({})", names.baud.zh),
            ),
            SilentCheck::Profile => Text::new(
                format!("with this profile ({})", names.profile.en),
                format!("设备配置是否相符({})", names.profile.zh),
            ),
            SilentCheck::Reboots => Text::new(
                format!(
                    "Or is it a board that reboots when the port opens (its USB adapter toggles \
                     DTR/RTS)? Give it time with {}, or set the lines right after the open: {}.",
                    names.boot_wait.en, names.lines.en
                ),
                format!(
                    "或者这是一块端口打开时会重启的板子(其 USB 适配器会翻转 DTR/RTS)?\
                     请用{}给它启动时间,或在打开后立即设置线路:{}。",
                    names.boot_wait.zh, names.lines.zh
                ),
            ),
            SilentCheck::HostLate(late) => crate::link::request::held_up_said(late),
        }
    }
}

/// The checklist as one paragraph: `nothing answered: is the device powered, …, and with this
/// profile (…)?`, then the reboot question when it is one of `checks`. With a
/// [`SilentCheck::HostLate`] among them, the loaded computer comes first and the rest only for a
/// device that still does not answer: `this computer was held up 12 ms past the answer's
/// deadline (…): close other programs and retry; if it still does not answer with the computer
/// idle: is the device powered, …?`.
pub fn checklist(checks: &[SilentCheck], names: &SettingNames) -> Text {
    let host_late = checks.iter().find_map(|c| match c {
        SilentCheck::HostLate(late) => Some(*late),
        _ => None,
    });
    let clauses: Vec<Text> = checks
        .iter()
        .filter(|c| !matches!(c, SilentCheck::Reboots | SilentCheck::HostLate(_)))
        .map(|c| c.said(names))
        .collect();
    let en: Vec<&str> = clauses.iter().map(|c| c.en.as_str()).collect();
    let zh: Vec<&str> = clauses.iter().map(|c| c.zh.as_str()).collect();
    let en = match en.split_last() {
        Some((last, [])) => (*last).to_string(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
        None => String::new(),
    };
    let mut said = match host_late {
        None => Text::new(
            format!("nothing answered: is the device {en}?"),
            format!("无应答:{}?", zh.join("、")),
        ),
        Some(late) => SilentCheck::HostLate(late).said(names).then(
            "; ",
            &Text::new(
                format!("if it still does not answer with the computer idle: is the device {en}?"),
                format!("若电脑空闲时仍无应答:{}?", zh.join("、")),
            ),
        ),
    };
    if checks.contains(&SilentCheck::Reboots) {
        said = said.then(" ", &SilentCheck::Reboots.said(names));
    }
    said
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> SettingNames {
        SettingNames {
            baud: Text::same("--baud"),
            profile: Text::same("--profile"),
            boot_wait: Text::same("--boot-wait-ms 2000"),
            lines: Text::same("--dtr off --rts off (or on)"),
        }
    }

    #[test]
    fn the_checklist_reads_as_one_question_in_each_language() {
        let said = checklist(&SilentCheck::list(true), &names());
        assert_eq!(
            said.en,
            "nothing answered: is the device powered, its TX wired to the adapter's RX (and RX \
             to TX, GND to GND), at this baud rate (--baud) and with this profile (--profile)?"
        );
        assert!(said.zh.starts_with("无应答:设备是否通电、"), "{}", said.zh);
        assert!(!said.zh.contains("Or is it"));
        let with_boot = checklist(&SilentCheck::list(false), &names());
        assert!(
            with_boot.en.ends_with("--dtr off --rts off (or on)."),
            "{}",
            with_boot.en
        );
        assert!(
            with_boot.zh.contains("--boot-wait-ms 2000"),
            "{}",
            with_boot.zh
        );
        for c in SilentCheck::list(false) {
            assert!(!c.said(&names()).zh.is_empty());
        }
    }

    /// After a timeout on a held-up computer the loaded computer leads, and the wiring follows
    /// only for a device that still does not answer (issue 25, item 4e).
    #[test]
    fn a_held_up_computer_leads_the_checklist() {
        let late = Some(Duration::from_millis(31));
        let checks = SilentCheck::list_after(true, late);
        assert_eq!(
            checks.first(),
            Some(&SilentCheck::HostLate(Duration::from_millis(31)))
        );
        let said = checklist(&checks, &names());
        assert_eq!(
            said.en,
            "this computer was held up 31 ms past the answer's deadline (a loaded computer: the \
             answer may have come while it was): close other programs and retry; if it still \
             does not answer with the computer idle: is the device powered, its TX wired to the adapter's RX (and RX to \
             TX, GND to GND), at this baud rate (--baud) and with this profile (--profile)?"
        );
        assert!(
            said.zh
                .starts_with("这台电脑在应答截止时间后被拖住了 31 ms"),
            "{}",
            said.zh
        );
        assert!(
            said.zh.contains("若电脑空闲时仍无应答:设备是否通电"),
            "{}",
            said.zh
        );
        assert_eq!(
            SilentCheck::list_after(false, None),
            SilentCheck::list(false)
        );
    }
}
