//! The line station's window (`botbench station BUNDLE`): one tile per slot with its fixture,
//! port, unit, step, progress and a PASS/FAIL banner readable from two metres; Start, STOP per
//! slot and STOP ALL always on screen; the operator's answers by buttons or by keys (Y/N for the
//! oldest question). The slots run on their own threads ([`crate::ops::station::runner`]); the
//! window only shows their events and sends their commands.
//!
//! The operator view holds only the scan and answer fields, Start, STOP, the banners and each
//! slot's history; nothing of ports, plans or settings can be changed from it. Unlocked, the
//! engineer sees each slot's configuration and may open an idle slot in today's window
//! ([`lent`]: the slot lends its port); each unlock, refused password, lock and lent slot is
//! recorded ([`crate::ops::station::access`]).

mod engineer;
pub mod lent;
mod open;
mod reason;
pub mod shots;
pub mod sound;
mod tile;

pub use engineer::Engineer;
pub use open::open;

use crate::i18n::{Lang, Text};
use crate::ops::station::{Answer, Command, Event, SlotHandle, What};
use crossbeam_channel::Receiver;
use eframe::egui;
use std::collections::VecDeque;

/// Verdicts kept per slot for its history.
const HISTORY: usize = 8;

/// What the window knows of one slot, from its events.
#[derive(Debug, Clone, Default)]
pub struct TileState {
    /// The slot's name.
    pub slot: String,
    /// The fixture's name.
    pub fixture: String,
    /// The fixture's name in 中文 (the English one when the bundle gives none).
    pub fixture_zh: String,
    /// Whether its port is there, and the path or why not.
    pub port: Option<(bool, String)>,
    /// How it waits for a unit (`button`, `scan`, `auto`), while idle.
    pub waiting: Option<&'static str>,
    /// The unit's serial, when known.
    pub serial: Option<String>,
    /// The step running: index (1-based), of, name in both languages.
    pub step: Option<(usize, usize, Text)>,
    /// The question waiting: kind and text in both languages.
    pub asking: Option<(&'static str, String, String)>,
    /// The last verdict: pass, failed step (both languages), why (typed: said in either).
    pub verdict: Option<(bool, Option<Text>, Option<crate::ops::station::Reason>)>,
    /// Recent verdicts, newest first: (pass, the serial, or the verdict's local time
    /// `HH:MM:SS` for a unit without one).
    pub history: VecDeque<(bool, String)>,
    /// What the operator types into the answer field.
    pub typed: String,
    /// Whether the slot has stopped.
    pub stopped: Option<String>,
    /// How many runs the records held of this unit before its last run.
    pub earlier_runs: Option<i64>,
    /// Where the last record went when it did not reach its store (spool or memory, and
    /// why); `None` when it was stored.
    pub kept_elsewhere: Option<String>,
    /// The slot's configuration, shown in the engineer view: port, profile, plan and steps.
    pub details: String,
    /// The slot's device profile's id (the engineer view speaks to the device with it).
    pub profile: String,
}

/// The station window's state.
pub struct LineStation {
    /// The station's id.
    pub id: String,
    /// The bundle's hash (shown short in the title bar).
    pub bundle_sha256: String,
    /// The language shown.
    pub lang: Lang,
    /// One tile per slot, in the bundle's order.
    pub tiles: Vec<TileState>,
    /// The engineer's unlock.
    pub engineer: Engineer,
    /// The records waiting in a spool: how many, the store, why (from [`What::Records`]).
    pub records: Option<RecordsWaiting>,
    /// A slot's number typed, waiting for its Y or N.
    pub slot_typed: Option<String>,
    /// The screenshot tour, when asked for (`--screenshots DIR`).
    pub shots: Option<shots::StationShots>,
    /// The slot open in the engineer view, if any.
    pub lent: Option<lent::Lent>,
    /// Where the engineer's unlocks, refused passwords and locks are recorded (the station's
    /// records); `None`: only logged.
    pub access: Option<crate::ops::station::StationContext>,
    /// Whether each verdict is sounded (the bundle's `sound`, else the operator's choice).
    pub sound: bool,
    /// The operator's choice of sound, once made on the bar: kept with the window's settings.
    pub sound_chosen: Option<bool>,
    /// What plays the verdict's sound ([`sound::SystemPlayer`]; a counter in tests).
    pub sounder: Box<dyn sound::VerdictSound>,
    /// The ordinary window's saved settings ([`crate::ui::Settings::saved_by_window`], or the
    /// window's own under File > Open station): the engineer view starts from them.
    pub window_settings: crate::ui::Settings,
    slots: Vec<SlotHandle>,
    events: Receiver<Event>,
    forwarder: Option<crate::ops::station::Forwarder>,
}

/// The station's records not yet in their store.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordsWaiting {
    /// How many wait (0: none).
    pub waiting: u64,
    /// The store (file or server).
    pub store: String,
    /// Why they wait.
    pub why: Option<String>,
}

impl LineStation {
    /// The window over running `slots` (their events on `events`), with the fixtures' names.
    pub fn new(
        bundle: &crate::ops::station::Bundle,
        slots: Vec<SlotHandle>,
        events: Receiver<Event>,
    ) -> Self {
        let tiles = bundle
            .slots
            .iter()
            .map(|s| TileState {
                slot: s.name.clone(),
                fixture: s.fixture.clone(),
                fixture_zh: s.fixture_zh.clone(),
                details: format!(
                    "{} · {} · {}: {}",
                    s.port.said(),
                    s.profile.id,
                    s.plan_name,
                    s.plan.step_names()
                ),
                profile: s.profile.id.clone(),
                ..TileState::default()
            })
            .collect();
        Self {
            id: bundle.id.clone(),
            bundle_sha256: bundle.sha256.clone(),
            lang: bundle.language,
            tiles,
            engineer: Engineer {
                password_sha256: bundle.engineer_password_sha256.clone(),
                ..Engineer::default()
            },
            records: None,
            slot_typed: None,
            shots: None,
            lent: None,
            access: None,
            sound: bundle.sound,
            sound_chosen: None,
            sounder: Box::new(sound::SystemPlayer),
            window_settings: crate::ui::Settings::default(),
            slots,
            events,
            forwarder: None,
        }
    }

    /// The window over a started station (its slots, events and records forwarder).
    pub fn started(
        bundle: &crate::ops::station::Bundle,
        started: crate::sim::fixture::StartedStation,
    ) -> Self {
        let mut st = Self::new(bundle, started.slots, started.events);
        st.forwarder = Some(started.forwarder);
        st.access = Some(started.context);
        st
    }

    /// Takes every event waiting; asks for the next frame soon while slots run.
    pub fn logic(&mut self, ctx: &egui::Context) {
        while let Ok(ev) = self.events.try_recv() {
            self.on_event(ev);
        }
        if let Some(mut tour) = self.shots.take() {
            tour.step(ctx, self);
            self.shots = Some(tour);
        }
        if let Some(lent) = &mut self.lent {
            let opener = self.slots.iter().find(|s| s.name == lent.slot);
            let profile = self.tiles.iter().find(|t| t.slot == lent.slot);
            if let (Some(handle), Some(tile)) = (opener, profile) {
                lent.logic(
                    ctx,
                    &handle.opener,
                    &tile.profile,
                    self.lang,
                    &self.window_settings,
                );
            }
        }
        ctx.request_repaint_after(std::time::Duration::from_millis(100));
    }

    /// Records `access` in the station's records (and the log).
    fn record(&self, access: &crate::ops::station::Access) {
        match &self.access {
            Some(station) => crate::ops::station::access::keep(station, access),
            None => log::warn!("station {}: {} (no records store)", self.id, access.said()),
        }
    }

    /// Asks idle slot `slot` for the engineer view (only unlocked, one slot at a time).
    pub fn open_engineer_view(&mut self, slot: &str) {
        if self.engineer.unlocked() && self.lent.is_none() {
            self.send(slot, Command::Lend);
            self.lent = Some(lent::Lent::asked(slot));
        }
    }

    /// Closes the engineer view: its window (and link) first, then the slot is given back.
    pub fn close_engineer_view(&mut self) {
        let Some(lent) = self.lent.take() else {
            return;
        };
        let slot = lent.slot.clone();
        let given_up = lent.port.is_some();
        // The view's window and its link go first: the port is free when the slot reopens it.
        drop(lent);
        // A slot that has not given up its port yet gets it back when it does (`on_lent`).
        if given_up {
            self.send(&slot, Command::Return);
            self.record(&crate::ops::station::Access::SlotReturned { slot });
        }
    }

    /// A slot said it gave up its port: to the engineer view if it asked for it, else back.
    fn on_lent(&mut self, slot: String, port: String) {
        match &mut self.lent {
            Some(lent) if lent.slot == slot && lent.port.is_none() => {
                lent.port = Some(port);
                self.record(&crate::ops::station::Access::SlotOpened { slot });
            }
            // Asked for earlier and no longer wanted.
            _ => self.send(&slot, Command::Return),
        }
    }

    fn on_event(&mut self, ev: Event) {
        if let What::Records {
            waiting,
            store,
            why,
        } = ev.what
        {
            self.records = Some(RecordsWaiting {
                waiting,
                store,
                why,
            });
            return;
        }
        if let What::Lent { port } = ev.what {
            self.on_lent(ev.slot, port);
            return;
        }
        if matches!(ev.what, What::Unit { .. })
            && self
                .lent
                .as_ref()
                .is_some_and(|l| l.slot == ev.slot && l.port.is_none())
        {
            // The slot started a unit before it saw the ask: it is not lent.
            self.lent = None;
        }
        let Some(t) = self.tiles.iter_mut().find(|t| t.slot == ev.slot) else {
            return;
        };
        match ev.what {
            What::Port { present, detail } => t.port = Some((present, detail)),
            What::Waiting { how } => {
                t.waiting = Some(how);
                t.step = None;
            }
            What::Unit { serial } => {
                t.waiting = None;
                t.serial = serial;
                t.verdict = None;
                t.step = None;
            }
            What::Step {
                index,
                of,
                name,
                name_zh,
                ..
            } => t.step = Some((index, of, Text::new(name, name_zh))),
            What::Ask {
                kind,
                text,
                text_zh,
                why,
            } => {
                // A retry question says why the step failed in 中文 from its typed reason.
                let text_zh = match (why, &t.step) {
                    (Some(why), Some((_, _, step))) => {
                        use crate::ui::zh::Zh;
                        format!("{} 失败:{}。重试一次?", step.zh, why.zh())
                    }
                    _ => text_zh,
                };
                t.asking = Some((kind, text, text_zh));
            }
            What::StepDone { .. } => t.asking = None,
            What::Verdict {
                pass,
                serial,
                failed_step,
                failed_step_zh,
                reason,
                earlier_runs,
                kept,
                stored,
                ..
            } => {
                t.asking = None;
                t.kept_elsewhere = (!stored).then_some(kept);
                t.earlier_runs = earlier_runs;
                t.serial.clone_from(&serial);
                let failed_step = failed_step.map(|en| {
                    let zh = failed_step_zh.unwrap_or_else(|| en.clone());
                    Text::new(en, zh)
                });
                t.verdict = Some((pass, failed_step, reason));
                // A unit without a serial is told by the time of its verdict.
                let unit =
                    serial.unwrap_or_else(|| chrono::Local::now().format("%H:%M:%S").to_string());
                t.history.push_front((pass, unit));
                t.history.truncate(HISTORY);
                if self.sound {
                    self.sounder.play(sound::Tone::of(pass));
                }
            }
            What::Stopped { why } => {
                t.asking = None;
                t.stopped = Some(why);
            }
            What::Records { .. } | What::Lent { .. } => {}
        }
    }

    /// Sends `command` to slot `slot`.
    pub fn send(&self, slot: &str, command: Command) {
        if let Some(s) = self.slots.iter().find(|s| s.name == slot) {
            let _ = s.commands.try_send(command);
        }
    }

    /// STOP for slot `slot`.
    pub fn stop(&self, slot: &str) {
        if let Some(s) = self.slots.iter().find(|s| s.name == slot) {
            s.cancel.cancel();
        }
    }

    /// STOP ALL.
    pub fn stop_all(&self) {
        self.slots.iter().for_each(|s| s.cancel.cancel());
    }

    /// Y or N typed (a key, a pedal seen as a key): the answer to the oldest yes/no question
    /// waiting; a slot's number first (`2` then `Y`) answers that slot's question. A number
    /// not followed by Y or N is forgotten at the next other key.
    fn keys(&mut self, ctx: &egui::Context) {
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let pressed: Vec<egui::Key> = ctx.input(|i| {
            i.events
                .iter()
                .filter_map(|e| match e {
                    egui::Event::Key {
                        key, pressed: true, ..
                    } => Some(*key),
                    _ => None,
                })
                .collect()
        });
        for key in pressed {
            let answer = match key {
                egui::Key::Y => Answer::Yes,
                egui::Key::N => Answer::No,
                other => {
                    // A slot's number: its name, typed with the digit keys.
                    self.slot_typed = other
                        .name()
                        .parse::<u32>()
                        .ok()
                        .map(|n| n.to_string())
                        .filter(|n| self.tiles.iter().any(|t| &t.slot == n));
                    continue;
                }
            };
            let yes_no = |t: &&TileState| matches!(t.asking, Some(("confirm" | "retry", _, _)));
            let slot = match self.slot_typed.take() {
                Some(named) => self
                    .tiles
                    .iter()
                    .filter(yes_no)
                    .find(|t| t.slot == named)
                    .map(|t| t.slot.clone()),
                None => self.tiles.iter().find(yes_no).map(|t| t.slot.clone()),
            };
            if let Some(slot) = slot {
                self.send(&slot, Command::Answer(answer));
            }
        }
    }

    /// The header's records line, while any wait: how many, where to, and why, in red.
    fn records_line(&self, ui: &mut egui::Ui, zh: bool) {
        let Some(r) = self.records.as_ref().filter(|r| r.waiting > 0) else {
            return;
        };
        let why = r.why.as_deref().unwrap_or_default();
        let text = if zh {
            format!(
                "记录:{} 条在本机暂存,等待发送到 {}:{why}",
                r.waiting, r.store
            )
        } else {
            format!(
                "Records: {} waiting on this PC to be forwarded to {}: {why}",
                r.waiting, r.store
            )
        };
        ui.label(
            egui::RichText::new(text)
                .size(18.0)
                .strong()
                .color(egui::Color32::from_rgb(200, 30, 30)),
        );
    }

    /// The bar's sound box: operators may mute the verdict's sound (it changes nothing of a
    /// unit's test); the choice is kept with the window's settings.
    fn sound_box(&mut self, ui: &mut egui::Ui, zh: bool) {
        let label = if zh {
            "判定提示音"
        } else {
            "Sound on verdict"
        };
        if ui.checkbox(&mut self.sound, label).changed() {
            self.sound_chosen = Some(self.sound);
        }
    }

    /// Uses the operator's earlier choice of sound (`None`: the bundle's).
    pub fn with_sound_chosen(mut self, chosen: Option<bool>) -> Self {
        if let Some(on) = chosen {
            self.sound = on;
            self.sound_chosen = Some(on);
        }
        self
    }

    /// The bar's line while a slot is in the engineer view: which, and the way back.
    fn lent_line(&mut self, ui: &mut egui::Ui, zh: bool) {
        let Some(lent) = &self.lent else {
            return;
        };
        let fixture = self
            .tiles
            .iter()
            .find(|t| t.slot == lent.slot)
            .map(|t| if zh { &t.fixture_zh } else { &t.fixture }.clone())
            .unwrap_or_default();
        let mut back = false;
        ui.horizontal(|ui| {
            ui.label(
                egui::RichText::new(if zh {
                    format!("工程师视图:工位 {} {fixture}(该工位暂停)", lent.slot)
                } else {
                    format!(
                        "Engineer view: slot {} {fixture} (the slot waits)",
                        lent.slot
                    )
                })
                .size(18.0)
                .strong(),
            );
            back = ui
                .button(
                    egui::RichText::new(if zh {
                        "返回工位"
                    } else {
                        "Back to the station"
                    })
                    .size(18.0),
                )
                .clicked();
        });
        if back {
            self.close_engineer_view();
        }
    }

    /// Draws the station: the title bar with STOP ALL, then the tiles.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        self.keys(ui.ctx());
        let zh = self.lang == Lang::Zh;
        egui::Panel::top("station-bar")
            .frame(crate::ui::backdrop::bar(ui.style()))
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    let stop_all = egui::Button::new(
                        egui::RichText::new(if zh { "全部停止" } else { "STOP ALL" })
                            .size(22.0)
                            .strong()
                            .color(egui::Color32::WHITE),
                    )
                    .fill(egui::Color32::from_rgb(200, 30, 30));
                    if ui.add(stop_all).clicked() {
                        self.stop_all();
                    }
                    ui.heading(format!(
                        "{} {}",
                        if zh { "工位" } else { "Station" },
                        self.id
                    ));
                    ui.label(format!(
                        "{} {}",
                        if zh { "配置包" } else { "bundle" },
                        &self.bundle_sha256[..12.min(self.bundle_sha256.len())]
                    ));
                    let lang = if zh { "English" } else { "中文" };
                    if ui.button(lang).clicked() {
                        self.lang = if zh { Lang::En } else { Lang::Zh };
                    }
                    self.sound_box(ui, zh);
                    if let Some(access) = self.engineer.show(ui, zh) {
                        self.record(&access);
                        if access == crate::ops::station::Access::Lock {
                            // Locked: back to the operator view; the slot resumes.
                            self.close_engineer_view();
                        }
                    }
                });
                self.records_line(ui, zh);
                self.lent_line(ui, zh);
            });
        if let Some(lent) = &mut self.lent {
            lent.ui(ui, zh);
            return;
        }
        egui::CentralPanel::default()
            .frame(crate::ui::backdrop::central(ui.style()))
            .show(ui, |ui| {
                let n = self.tiles.len().max(1);
                let columns = if ui.available_width() > 1100.0 {
                    n.min(3)
                } else {
                    n.min(2)
                };
                let mut actions = Vec::new();
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.columns(columns, |cols| {
                        for (i, t) in self.tiles.iter_mut().enumerate() {
                            let col = &mut cols[i % columns];
                            let engineer = self.engineer.unlocked();
                            actions.extend(tile::show(col, t, self.lang, engineer));
                        }
                    });
                });
                for (slot, action) in actions {
                    match action {
                        tile::Action::Stop => self.stop(&slot),
                        tile::Action::Send(c) => self.send(&slot, c),
                        tile::Action::Engineer => self.open_engineer_view(&slot),
                    }
                }
            });
    }
}

/// Opens the station window over a started station (with `screenshots`, its screenshot tour
/// into that folder); returns when it is closed (every slot is stopped then). Errors: the
/// window could not be opened.
pub fn run(
    bundle: &crate::ops::station::Bundle,
    started: crate::sim::fixture::StartedStation,
    screenshots: Option<std::path::PathBuf>,
) -> Result<(), String> {
    let mut station = LineStation::started(bundle, started);
    if screenshots.is_some() {
        // The tour's verdicts are not a line's: the box is shown as the bundle says, unheard.
        station.sounder = Box::new(sound::Silent);
    }
    station.shots = screenshots.map(shots::StationShots::new);
    // The engineer view is today's window with the settings it saved (a tour's are defaults).
    if station.shots.is_none() {
        station.window_settings = crate::ui::Settings::saved_by_window().unwrap_or_default();
    }
    // `BOTBENCH_WINDOW_SIZE=1024x600`: the window's size where no window manager maximises it
    // (the screenshots under Xvfb).
    let size = std::env::var("BOTBENCH_WINDOW_SIZE")
        .ok()
        .and_then(|s| {
            let (w, h) = s.split_once('x')?;
            Some([w.trim().parse::<f32>().ok()?, h.trim().parse::<f32>().ok()?])
        })
        .unwrap_or([1280.0, 800.0]);
    crate::system::heap::keep_freed_memory(crate::system::heap::WINDOW_KEPT_BYTES);
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size(size)
            .with_min_inner_size([800.0, 500.0])
            // A line PC shows the station and nothing else.
            .with_maximized(true)
            .with_title(format!("botbench station {}", bundle.id)),
        dithering: false,
        ..Default::default()
    };
    eframe::run_native(
        "botbench-station",
        options,
        Box::new(move |cc| {
            crate::i18n::install_cjk_font(&cc.egui_ctx);
            let saved: Option<Saved> = cc
                .storage
                .and_then(|s| eframe::get_value(s, eframe::APP_KEY));
            let station = station.with_sound_chosen(saved.and_then(|s| s.sound));
            Ok(Box::new(station))
        }),
    )
    .map_err(|e| e.to_string())
}

/// What the station window keeps between runs (eframe storage).
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(default)]
struct Saved {
    /// The operator's choice of the verdict's sound (`None`: the bundle's).
    sound: Option<bool>,
}

impl eframe::App for LineStation {
    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        crate::ui::backdrop::clear_color(visuals)
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        // A screenshot tour's choices are not the operator's.
        if self.shots.is_none() {
            let saved = Saved {
                sound: self.sound_chosen,
            };
            eframe::set_value(storage, eframe::APP_KEY, &saved);
        }
    }

    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        LineStation::logic(self, ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        LineStation::ui(self, ui);
    }
}

impl Drop for LineStation {
    /// The window closed: every slot stops (its device left in its safe state).
    fn drop(&mut self) {
        self.stop_all();
    }
}
