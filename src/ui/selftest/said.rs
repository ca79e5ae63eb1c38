//! A self-test's texts as the window says them. The operation ([`crate::ops::selftest`])
//! writes them in English for the records, the logs and the command line: each step's detail
//! (what it measured against its limits), why a run ended early, the safe state, the device's
//! identity. In 中文 their fixed phrases ([`PHRASES`]) are said in Chinese and the names of the
//! wire they hold (a field's ident, a named value's, a bit's) by the profile's Chinese names;
//! numbers, units and command names stay as they are. A phrase the operation adds without a
//! translation here stays English (the window's 中文 test, `window_chinese`, finds it).

use crate::i18n::Lang;
use crate::profile::Command;
use std::collections::HashMap;

/// The English phrases of the self-test's texts and their Chinese, applied in this order (a
/// longer phrase before one it holds). A phrase that starts or ends with a letter matches only
/// at a word's edge there.
const PHRASES: &[(&str, &str)] = &[
    (" TOO NOISY", " 波动过大"),
    (" NO RISE", " 未上升"),
    (") WRONG", ")不符"),
    (" missing from the answer", " 应答中缺失"),
    (" samples outside", " 个样本超出范围"),
    (" (allowed ", "(允许 "),
    (" (expected ", "(应为 "),
    (" (rise ", "(上升 "),
    (", min ", ",下限 "),
    ("; max ", ";上限 "),
    (" spread ", " 波动 "),
    (" toggled: ", " 均已切换:"),
    ("toggled ", "已切换 "),
    ("never set: ", "从未置位:"),
    ("never clear: ", "从未清零:"),
    (" FAILED: ", " 失败:"),
    (": sent", ":已发送"),
    (": acknowledged", ":已确认"),
    ("then ", "随后 "),
    (" ms: ", " ms 内:"),
    (" within ", " "),
    (" to ", " 至 "),
    (" of ", "/"),
    ("link lost: ", "连接丢失:"),
    ("the operator aborted", "操作员中止"),
    ("cancelled before it started", "开始前已取消"),
    ("cancelled while setting the safe state", "设置安全状态时已取消"),
    ("safe state not reached: ", "未能进入安全状态:"),
    ("; no step run", ";未运行任何步骤"),
    (" step(s) not run", " 个步骤未运行"),
    ("step 'Device identity'", "步骤 '设备识别'"),
    ("step '", "步骤 '"),
    ("could not stop", "无法停止"),
    ("cancelled", "已取消"),
    ("none", "无"),
    ("bit ", "位 "),
];

/// The words of the device's identity line (`hw 0x03 fw 1.4.2 api 2.4 build 7 (...)`).
const DEVICE: &[(&str, &str)] = &[
    ("hw ", "硬件 "),
    ("fw ", "固件 "),
    ("api ", "API "),
    ("build ", "构建 "),
];

/// The name of the step that identifies the device (it is shown only when it failed).
pub const IDENTITY_STEP: (&str, &str) = ("Device identity", "设备识别");

/// A step's detail, a reason a run ended early or a safe-state line, in `lang`: in 中文 with
/// the names of `cmd`'s fields, named values and bits in Chinese and [`PHRASES`] said.
pub fn detail(text: &str, cmd: Option<&Command>, lang: Lang) -> String {
    match lang {
        Lang::En => text.to_string(),
        // A lost port's reason first: its phrases hold words of the table's (" to ").
        Lang::Zh => phrases(&crate::ui::zh::lost_port(&names(text, cmd)), PHRASES),
    }
}

/// The device's identity line in `lang`.
pub fn device(text: &str, lang: Lang) -> String {
    match lang {
        Lang::En => text.to_string(),
        Lang::Zh => phrases(text, DEVICE),
    }
}

/// `text` with each identifier (a run of letters, digits and `_`) that names a field of
/// `cmd`'s reply, one of its named values or one of its bits replaced by its Chinese name.
fn names(text: &str, cmd: Option<&Command>) -> String {
    let Some(cmd) = cmd else {
        return text.to_string();
    };
    let mut zh: HashMap<&str, &str> = HashMap::new();
    for f in &cmd.reply {
        zh.insert(&f.ident, &f.name.zh);
        for l in &f.labels {
            zh.insert(&l.ident, &l.name.zh);
        }
        for b in &f.bits {
            zh.insert(&b.ident, &b.name.zh);
        }
    }
    let mut out = String::with_capacity(text.len());
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        out.push_str(zh.get(word.as_str()).copied().unwrap_or(word));
        word.clear();
    };
    for c in text.chars() {
        if c.is_ascii_alphanumeric() || c == '_' {
            word.push(c);
        } else {
            flush(&mut word, &mut out);
            out.push(c);
        }
    }
    flush(&mut word, &mut out);
    out
}

/// `text` with each phrase of `table` replaced ([`crate::i18n::phrases::replace`]).
fn phrases(text: &str, table: &[(&str, &str)]) -> String {
    crate::i18n::phrases::replace(text, table)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn profile() -> std::sync::Arc<crate::profile::Profile> {
        crate::sim::msp_device::builtin_profile("window-cleaner").unwrap()
    }

    #[test]
    fn each_kind_of_step_detail_is_said_in_chinese_with_the_profiles_names() {
        let p = profile();
        let cases = [
            (
                "MSP_ADAPTER",
                "batteryVoltage 12.6 V to 12.7 V (allowed 11.5 V to 16.8 V), 2 of 5 samples outside",
            ),
            (
                "MSP_RAW_IMU",
                "gyroX spread 3 °/s (0 °/s to 3 °/s; max 30 °/s) TOO NOISY",
            ),
            (
                "MSP_ANALOG",
                "adcFan 35 → 36 (rise 1, min 500) NO RISE; then MSP_SET_FAN pwm=0: sent",
            ),
            (
                "MSP_FOURCORNER",
                "corners within 20000 ms: toggled none; never set: bit 0, bit 1",
            ),
            ("MSP_WATER_BOX", "status 0 (expected 1) WRONG, adc 12"),
        ];
        for (command, en) in cases {
            let zh = detail(en, p.command(command), Lang::Zh);
            let english: Vec<&str> = zh
                .split(|c: char| !c.is_ascii_alphabetic())
                .filter(|w| w.len() >= 3 && w.chars().skip(1).all(|c| c.is_ascii_lowercase()))
                // A value written to the wire (`pwm=0`) is its name.
                .filter(|w| *w != "pwm")
                .collect();
            assert!(english.is_empty(), "{en:?} → {zh:?}: {english:?}");
            assert_eq!(detail(en, p.command(command), Lang::En), en);
        }
        assert_eq!(
            detail("batteryVoltage 12.6 V (allowed 11.5 V to 16.8 V)", p.command("MSP_ADAPTER"), Lang::Zh),
            "电池电压 12.6 V(允许 11.5 V 至 16.8 V)"
        );
    }

    #[test]
    fn a_phrase_inside_a_word_is_left_alone() {
        assert_eq!(phrases("nonexistent none", PHRASES), "nonexistent 无");
        assert_eq!(
            device("hw 0x03 fw 1.4.2 api 2.4 build 7", Lang::Zh),
            "硬件 0x03 固件 1.4.2 API 2.4 构建 7"
        );
    }
}
