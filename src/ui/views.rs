//! The window's views: each panel the connected device has, and each part of a panel that
//! shows one part at a time (the servo bench's and the Tuya console's tabs, the tuning table's
//! groups). The screenshot tour shoots every view, and the layout tests walk them.

use super::{App, PanelId, servo_bench, tuning, tuya_console};

/// One view: a panel, and which of its parts (0 for a panel shown whole).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct View {
    /// The panel.
    pub panel: PanelId,
    /// Its part: a tab's or a group's index, 0 for a panel shown whole.
    pub part: usize,
    /// The view's name, for a file: `ServoBench-Params`, `Tuning-fan`, `Device`.
    pub name: String,
}

impl App {
    /// Every view the connected device has, in the navigation's order.
    pub fn views(&self) -> Vec<View> {
        self.panels()
            .into_iter()
            .flat_map(|panel| {
                let parts = self.parts(panel);
                let whole = parts.is_empty();
                let named = parts.into_iter().enumerate().map(move |(part, name)| View {
                    panel,
                    part,
                    name: format!("{panel:?}-{name}"),
                });
                let single = whole.then(|| View {
                    panel,
                    part: 0,
                    name: format!("{panel:?}"),
                });
                single.into_iter().chain(named).collect::<Vec<_>>()
            })
            .collect()
    }

    /// The parts of `panel` that it shows one at a time, by name (none: it is shown whole).
    fn parts(&self, panel: PanelId) -> Vec<String> {
        match panel {
            PanelId::ServoBench => servo_bench::Tab::ALL
                .iter()
                .map(|t| format!("{t:?}"))
                .collect(),
            PanelId::TuyaConsole => tuya_console::Tab::ALL
                .iter()
                .map(|t| format!("{t:?}"))
                .collect(),
            PanelId::Tuning => tuning::group_ids(self.station())
                .into_iter()
                .map(|id| if id.is_empty() { "other".into() } else { id })
                .collect(),
            _ => Vec::new(),
        }
    }

    /// Shows `view`: its panel, with its tab chosen or its group brought to the top.
    pub fn show_view(&mut self, view: &View) {
        self.settings.panel = view.panel;
        match view.panel {
            PanelId::ServoBench => {
                if let Some(&tab) = servo_bench::Tab::ALL.get(view.part) {
                    self.servo.tab = tab;
                }
            }
            PanelId::TuyaConsole => {
                if let Some(&tab) = tuya_console::Tab::ALL.get(view.part) {
                    self.tuya.tab = tab;
                }
            }
            PanelId::Tuning => {
                self.tuning.scroll_to =
                    tuning::group_ids(self.station()).into_iter().nth(view.part);
            }
            _ => {}
        }
    }
}
