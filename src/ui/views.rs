//! The window's views: each panel the connected device has, and each part of a panel that
//! shows one part at a time (the servo bench's and the Tuya console's tabs, the tuning table's
//! groups). The screenshot tour shoots every view, and the layout tests walk them.

use super::{App, PanelId};

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
        let station = self.station();
        self.panels()
            .into_iter()
            .flat_map(|panel| {
                let parts = station
                    .panels
                    .find(panel)
                    .map(|p| p.parts(station))
                    .unwrap_or_default();
                let whole = parts.is_empty();
                let named = parts.into_iter().enumerate().map(move |(part, name)| View {
                    panel,
                    part,
                    name: format!("{panel}-{name}"),
                });
                let single = whole.then(|| View {
                    panel,
                    part: 0,
                    name: panel.to_string(),
                });
                single.into_iter().chain(named).collect::<Vec<_>>()
            })
            .collect()
    }

    /// Shows `view`: its panel, with its tab chosen or its group brought to the top.
    pub fn show_view(&mut self, view: &View) {
        self.settings.panel = view.panel;
        self.station_mut()
            .with_panels(|panels, station| panels.show_part(view.panel, view.part, station));
    }
}
