//! The one line shown while the window is on a built-in demo device (as it is at the first
//! launch): it is simulated, and how to pick a real port instead.

use super::station::{Station, Target};
use crate::i18n::Lang;
use eframe::egui;

/// The line, in `lang`.
pub fn text(lang: Lang) -> &'static str {
    lang.tr(
        "This is a simulated device. To use a robot: plug in its USB serial adapter, choose its \
         port under Port above (e.g. /dev/ttyUSB0), then Connect.",
        "这是模拟设备。连接真实机器人:插入 USB 串口适配器,在上方“端口”中选择它\
         (如 /dev/ttyUSB0),然后点击“连接”。",
    )
}

/// Draws the line when the link is on a demo device; nothing otherwise.
pub fn show(ui: &mut egui::Ui, lang: Lang, rt: &Station) {
    if matches!(rt.link.target(), Some(Target::Demo(_))) {
        ui.label(egui::RichText::new(text(lang)).weak());
    }
}
