//! The two languages, at the bottom of the house (it uses no other module): the language
//! choice ([`Lang`]), a typed table of the window's shared words in English and Simplified
//! Chinese ([`Key`]), words made in both ([`Text`]: a profile's names, an operation's progress),
//! and the bundled CJK font that lets egui draw the Chinese.
//!
//! What the layers above say in Chinese is said by the window (`ui::zh`: errors, link states,
//! the Tuya handshake's results): the window is the only reader of Chinese.
//!
//! Strings are looked up by [`Key`], an enum, so a misspelt key fails to compile:
//!
//! ```
//! use botbench::i18n::{tr, Key, Lang};
//! assert_eq!(tr(Lang::En, Key::Connect), "Connect");
//! assert_eq!(tr(Lang::Zh, Key::Connect), "连接");
//! assert_eq!(Key::Connect.get(Lang::Zh), "连接");
//! ```
//!
//! Profile names (`name: (en: "...", zh: "...")` in `assets/profiles/*.ron`) carry their own two
//! languages; [`Text::get`] picks one.
//!
//! Every Chinese character in `src/` and `assets/profiles/` must have a glyph in the bundled font
//! (`assets/fonts/`); `tests/i18n.rs` checks it, and `assets/fonts/make-subset.sh` regenerates
//! the font when it fails.

pub mod glyphs;
pub mod phrases;

use eframe::egui;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The UI language.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum Lang {
    /// English.
    #[default]
    En,
    /// Simplified Chinese.
    Zh,
}

impl Lang {
    /// One of two texts by language: for words said once, inline where they are used. Words
    /// shared across panels are [`Key`]s.
    pub fn tr<'a>(self, en: &'a str, zh: &'a str) -> &'a str {
        match self {
            Lang::En => en,
            Lang::Zh => zh,
        }
    }

    /// Both languages, in the order the switch shows them.
    pub const ALL: [Lang; 2] = [Lang::En, Lang::Zh];

    /// The language's name in itself, for the switch: "English", "中文".
    pub fn native_name(self) -> &'static str {
        match self {
            Lang::En => "English",
            Lang::Zh => "中文",
        }
    }

    /// The other language.
    pub fn toggled(self) -> Lang {
        match self {
            Lang::En => Lang::Zh,
            Lang::Zh => Lang::En,
        }
    }
}

/// Defines [`Key`] with its English and Chinese texts in one table.
macro_rules! keys {
    ($( $(#[$doc:meta])* $key:ident => $en:literal, $zh:literal; )*) => {
        /// A UI string. Its texts: [`Key::en`], [`Key::zh`], [`Key::get`] or [`tr`].
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Key {
            $( $(#[$doc])* $key, )*
        }

        impl Key {
            /// Every key, in table order.
            pub const ALL: &'static [Key] = &[ $( Key::$key, )* ];

            /// The English text.
            pub fn en(self) -> &'static str {
                match self {
                    $( Key::$key => $en, )*
                }
            }

            /// The Simplified Chinese text.
            pub fn zh(self) -> &'static str {
                match self {
                    $( Key::$key => $zh, )*
                }
            }
        }
    };
}

keys! {
    // ---- The shell and the connection bar ----
    /// The window title.
    AppTitle => "botbench — robot bench", "botbench 机器人调试台";
    /// Opens the port.
    Connect => "Connect", "连接";
    /// Closes the port.
    Disconnect => "Disconnect", "断开";
    /// The serial port picker.
    Port => "Port", "串口";
    /// The baud-rate picker.
    Baud => "Baud", "波特率";
    /// The device-profile picker.
    Profile => "Profile", "设备配置";
    /// Re-lists ports, or re-reads values.
    Refresh => "Refresh", "刷新";
    /// The built-in simulated device.
    DemoDevice => "Demo device", "演示设备";
    /// The UI-language switch.
    Language => "Language", "语言";
    /// The connection bar's menu of port options (DTR, RTS, boot wait, margin).
    PortOptions => "Port options", "端口选项";
    /// What the port options are for.
    PortOptionsHint => "Kept for this profile; applied at the next Connect.", "按设备配置保存, 下次连接时生效。";
    /// The DTR line set after the port opens.
    Dtr => "DTR after open", "打开后 DTR";
    /// The RTS line set after the port opens.
    Rts => "RTS after open", "打开后 RTS";
    /// A modem line left as the adapter set it.
    LineKeep => "keep", "保持";
    /// A modem line asserted.
    LineOn => "on", "置位";
    /// A modem line cleared.
    LineOff => "off", "清零";
    /// How long nothing is sent after the port opens (a board that reboots on open).
    BootWait => "Boot wait", "开机等待";
    /// The answer margin typed in ms (empty: auto).
    MarginMs => "Margin (empty: auto)", "应答余量(空: 自动)";

    // ---- The status bar (LinkStats) ----
    /// Round trip of the last exchange.
    RoundTrip => "round trip", "往返时间";
    /// Frame errors.
    Errors => "errors", "错误";
    /// Frames sent.
    Sent => "sent", "已发送";
    /// Frames received.
    Received => "received", "已接收";
    /// Exchanges that timed out.
    Timeouts => "timeouts", "超时";
    /// Attempts beyond the first.
    Retries => "retries", "重试";

    // ---- Panels ----
    /// The window-cleaner tuning panel.
    Tuning => "Tuning", "参数调节";
    /// The telemetry plots.
    Telemetry => "Telemetry", "遥测";
    /// The presets panel.
    Presets => "Presets", "预设";
    /// The raw-frame monitor.
    PacketMonitor => "Packet monitor", "数据包监视";
    /// Action commands.
    Actions => "Actions", "操作";
    /// The bus-servo panel.
    ServoBench => "Servo bench", "舵机调试台";
    /// The Tuya MCU panel.
    TuyaConsole => "Tuya console", "涂鸦控制台";
    /// The solar cleanbot panel.
    SolarCleanbot => "Solar cleanbot", "光伏清洁机器人";
    /// A device self-test.
    SelfTest => "Self-test", "自检";

    // ---- Tuning: the parameter table ----
    /// Reads every parameter.
    ReadAll => "Read all", "全部读取";
    /// Writes the edited parameters.
    WriteChanges => "Write changes", "写入修改";
    /// Drops the edits.
    Revert => "Revert", "还原";
    /// Column: the value on the device.
    Device => "Device", "设备值";
    /// Column: the value as edited.
    Edited => "Edited", "修改值";
    /// Column: the unit.
    Unit => "Unit", "单位";
    /// Column: the allowed range.
    Range => "Range", "范围";
    /// Column: a parameter's name.
    Name => "Name", "名称";
    /// Column or field: a value.
    Value => "Value", "数值";
    /// Read-back matched what was written.
    Verified => "Verified", "已校验";
    /// Read-back differed from what was written.
    Mismatch => "Mismatch", "不一致";
    /// No value read from the device yet.
    NotReadYet => "Not read yet", "尚未读取";
    /// A value outside the field's range.
    OutOfRange => "Out of range", "超出范围";
    /// Reads one value.
    Read => "Read", "读取";
    /// Writes one value.
    Write => "Write", "写入";
    /// Sends a command.
    Send => "Send", "发送";

    // ---- Telemetry ----
    /// Stops the plots.
    Pause => "Pause", "暂停";
    /// Restarts the plots.
    Resume => "Resume", "继续";
    /// Keeps the newest samples in view.
    Follow => "Follow", "跟随";
    /// The time window shown.
    Window => "Window", "时间窗口";
    /// How often telemetry is polled.
    PollRate => "Poll rate", "轮询频率";
    /// Saves samples as CSV.
    ExportCsv => "Export CSV", "导出 CSV";

    // ---- Presets ----
    /// Saves the device's values as a preset.
    SavePreset => "Save preset", "保存预设";
    /// Opens a preset file.
    OpenPreset => "Open preset", "打开预设";
    /// Compares a preset with the device.
    CompareWithDevice => "Compare with device", "与设备对比";
    /// Applies (a preset, a change).
    Apply => "Apply", "应用";

    // ---- General ----
    /// Cancels a dialog.
    Cancel => "Cancel", "取消";
    /// Confirms a dialog.
    Confirm => "Confirm", "确认";
    /// A filter box.
    Filter => "Filter", "过滤";
    /// Copies to the clipboard.
    Copy => "Copy", "复制";
    /// Saves to a file.
    Save => "Save", "保存";
    /// Clears a list.
    Clear => "Clear", "清除";
    /// Starts a run.
    Start => "Start", "开始";
    /// A check passed.
    Pass => "Pass", "通过";
    /// A check failed.
    Fail => "Fail", "失败";

    // ---- Servo bench ----
    /// Scans the bus for servos.
    Scan => "Scan", "扫描";
    /// Stops every servo.
    StopAll => "Stop all", "全部停止";
    /// Provisions the next servo on the line.
    ProvisionNext => "Provision next", "配置下一个";
    /// The servo's id.
    ServoId => "Servo ID", "舵机 ID";
    /// A servo answered.
    Present => "Present", "在线";
    /// Nothing answered.
    Absent => "Absent", "无应答";
    /// Garbled answers: maybe two servos share an id.
    PossibleDuplicate => "Possible duplicate ID", "可能存在重复 ID";

    // ---- Tuya console ----
    /// The start-up handshake.
    Handshake => "Handshake", "握手";
    /// The MCU's data points.
    DataPoints => "Data points", "数据点";
    /// An OTA update.
    FirmwareUpdate => "Firmware update", "固件升级";
}

impl Key {
    /// The text in `lang`.
    pub fn get(self, lang: Lang) -> &'static str {
        match lang {
            Lang::En => self.en(),
            Lang::Zh => self.zh(),
        }
    }
}

impl From<Key> for Text {
    fn from(key: Key) -> Self {
        Text::new(key.en(), key.zh())
    }
}

/// A separator as Chinese writes it: `: ` becomes `:`, `; ` becomes `;`, `, ` becomes `,`.
fn zh_sep(sep: &str) -> &str {
    match sep {
        ": " => ":",
        "; " => ";",
        ", " => ",",
        other => other,
    }
}

/// The text of `key` in `lang`.
pub fn tr(lang: Lang, key: Key) -> &'static str {
    key.get(lang)
}

/// Words in English and in Chinese: a profile's names (`name: (en: "...", zh: "...")` in
/// `assets/profiles/*.ron`), a progress message of an operation, a status line. [`Text::get`]
/// picks one.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Text {
    /// English.
    pub en: String,
    /// Simplified Chinese.
    pub zh: String,
}

impl Text {
    /// A message in both languages.
    pub fn new(en: impl Into<String>, zh: impl Into<String>) -> Self {
        Self {
            en: en.into(),
            zh: zh.into(),
        }
    }

    /// Words that read the same in both languages: a path, a number, a name a device gave.
    pub fn same(text: impl Into<String>) -> Self {
        let text = text.into();
        Self {
            zh: text.clone(),
            en: text,
        }
    }

    /// `self`, then `sep` and `then` (each language its own).
    pub fn then(&self, sep: &str, then: &Text) -> Text {
        Text::new(
            format!("{}{sep}{}", self.en, then.en),
            format!("{}{}{}", self.zh, zh_sep(sep), then.zh),
        )
    }

    /// The name in `lang`; falls back to the other language when this one is empty.
    pub fn get(&self, lang: Lang) -> &str {
        let (first, second) = match lang {
            Lang::En => (&self.en, &self.zh),
            Lang::Zh => (&self.zh, &self.en),
        };
        if first.is_empty() { second } else { first }
    }
}

/// The bundled subset of Noto Sans CJK SC (OpenType/CFF). Licence: SIL OFL 1.1, see
/// `assets/fonts/LICENSE-OFL.txt`; how it was made: `assets/fonts/README.md`.
pub const CJK_FONT: &[u8] = include_bytes!("../../assets/fonts/NotoSansCJKsc-Regular-subset.otf");

/// The name the bundled font goes by in egui's font definitions.
pub const CJK_FONT_NAME: &str = "noto-sans-cjk-sc-subset";

/// egui's default fonts with the bundled CJK font appended as the last fallback of the
/// proportional and monospace families (so Latin text keeps egui's own fonts).
pub fn cjk_font_definitions() -> egui::FontDefinitions {
    let mut fonts = egui::FontDefinitions::default();
    append_fallback(
        &mut fonts,
        CJK_FONT_NAME,
        egui::FontData::from_static(CJK_FONT),
    );
    fonts
}

/// Adds `data` as `name` and appends it as the last fallback of the proportional and
/// monospace families.
fn append_fallback(fonts: &mut egui::FontDefinitions, name: &str, data: egui::FontData) {
    fonts.font_data.insert(name.to_owned(), Arc::new(data));
    for family in [egui::FontFamily::Proportional, egui::FontFamily::Monospace] {
        fonts
            .families
            .entry(family)
            .or_default()
            .push(name.to_owned());
    }
}

/// The name a system CJK font goes by in egui's font definitions.
pub const SYSTEM_CJK_FONT_NAME: &str = "system-cjk";

/// [`cjk_font_definitions`] with `system` appended after the bundled font: drawn only for the
/// characters the bundled font lacks ([`glyphs::bundled_lacks`]).
pub fn font_definitions_with(system: &glyphs::SystemFont) -> egui::FontDefinitions {
    let mut fonts = cjk_font_definitions();
    let mut data = egui::FontData::from_owned(system.bytes.clone());
    data.index = system.index;
    append_fallback(&mut fonts, SYSTEM_CJK_FONT_NAME, data);
    fonts
}

/// Installs [`cjk_font_definitions`] into `ctx`, replacing its fonts. Call it once at start-up
/// (eframe's creation context, or a test harness); it takes effect on the next pass, or at once
/// if nothing has been laid out yet.
pub fn install_cjk_font(ctx: &egui::Context) {
    ctx.set_fonts(cjk_font_definitions());
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    fn is_cjk(c: char) -> bool {
        matches!(c as u32, 0x3000..=0x9FFF | 0xFF00..=0xFFEF)
    }

    /// Keys whose Chinese text may equal the English one (acronyms, product names). None yet.
    const SAME_IN_BOTH: &[Key] = &[];

    #[test]
    fn every_key_has_both_texts() {
        for &key in Key::ALL {
            assert!(!key.en().trim().is_empty(), "{key:?} has no English");
            assert!(!key.zh().trim().is_empty(), "{key:?} has no Chinese");
            assert_eq!(key.en(), key.en().trim(), "{key:?}: stray spaces");
            assert_eq!(key.zh(), key.zh().trim(), "{key:?}: stray spaces");
        }
    }

    #[test]
    fn chinese_texts_are_translated() {
        for &key in Key::ALL {
            if SAME_IN_BOTH.contains(&key) {
                continue;
            }
            assert_ne!(key.en(), key.zh(), "{key:?} is not translated");
            assert!(
                key.zh().chars().any(is_cjk),
                "{key:?}: no Chinese in {:?}",
                key.zh()
            );
            assert!(
                !key.en().chars().any(is_cjk),
                "{key:?}: Chinese in the English text"
            );
        }
    }

    #[test]
    fn all_lists_every_key_once() {
        let set: HashSet<Key> = Key::ALL.iter().copied().collect();
        assert_eq!(set.len(), Key::ALL.len());
        // `Key::ALL` comes from the same table as the enum, so this also pins its size.
        assert!(Key::ALL.len() >= 60);
    }

    #[test]
    fn lookups_agree() {
        for &key in Key::ALL {
            assert_eq!(tr(Lang::En, key), key.en());
            assert_eq!(tr(Lang::Zh, key), key.zh());
            assert_eq!(key.get(Lang::Zh), key.zh());
        }
        assert_eq!(tr(Lang::default(), Key::Connect), "Connect");
        assert_eq!(tr(Lang::Zh, Key::Connect), "连接");
    }

    #[test]
    fn lang_basics() {
        assert_eq!(Lang::default(), Lang::En);
        assert_eq!(Lang::En.toggled(), Lang::Zh);
        assert_eq!(Lang::Zh.toggled(), Lang::En);
        assert_eq!(Lang::Zh.native_name(), "中文");
        let ron = ron::to_string(&Lang::Zh).expect("serialize");
        assert_eq!(ron::from_str::<Lang>(&ron).expect("deserialize"), Lang::Zh);
    }

    #[test]
    fn text_picks_the_language_and_falls_back() {
        let t = Text {
            en: "Servo ID".into(),
            zh: "舵机ID".into(),
        };
        assert_eq!(t.get(Lang::En), "Servo ID");
        assert_eq!(t.get(Lang::Zh), "舵机ID");
        let only_en = Text {
            en: "Ping".into(),
            zh: String::new(),
        };
        assert_eq!(only_en.get(Lang::Zh), "Ping");
    }

    #[test]
    fn font_definitions_append_the_cjk_fallback() {
        let fonts = cjk_font_definitions();
        assert!(fonts.font_data.contains_key(CJK_FONT_NAME));
        for family in [egui::FontFamily::Proportional, egui::FontFamily::Monospace] {
            let list = &fonts.families[&family];
            assert_eq!(list.last().map(String::as_str), Some(CJK_FONT_NAME));
            assert!(list.len() > 1, "egui's default fonts stay first");
        }
    }
}
