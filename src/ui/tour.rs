//! The screenshot tour (`botbench gui --screenshots DIR`, used by `.ci/screenshot.sh`): one
//! launch of the window connects to each built-in demo device in turn, waits until it has come
//! up (see [`settled`]: answering, identified or shaken hands with, every plot holding
//! [`PLOTTED_SECS`] of samples), prepares what a technician would have on screen (the
//! servo bus scanned and a servo's parameters read, the Tuya MCU's own requests, the self-test
//! plan and the factory preset opened), then shows every view the device has ([`App::views`]:
//! each panel, each tab, each tuning group) at each size in [`SIZES`] and in each language,
//! and saves each as `DIR/<device>-<view>-<w>x<h>-<lang>.png`; then it closes the window.
//!
//! The shot is the window's own framebuffer (egui's viewport screenshot). Shots go size by
//! size and language by language, so that the window is resized twice a device, and each PNG
//! is written on a thread of its own while the next view is drawn. Each shot's frame is also
//! checked: a label it parts over two lines ([`super::layout::split_words`]) or a text drawn
//! over another ([`super::layout::overlapping_texts`]) is a failure.

use super::PanelId;
use super::presets::PresetsPanel;
use super::selftest::SelfTestPanel;
use super::servo_bench::ServoBenchPanel;
use super::station::Station;
use super::{App, View};
use crate::i18n::Lang;
use crate::profile::Protocol;
use crate::series::SeriesSet;
use crate::sim::SimKind;
use crate::sim::tuya_mcu::McuRequest;
use eframe::egui;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The window sizes shot, logical points: the line PCs' usual screen and a small one.
pub const SIZES: [[f32; 2]; 2] = [[1280.0, 800.0], [1024.0, 600.0]];
/// Seconds of samples each plot of a device holds before its first shot.
pub const PLOTTED_SECS: f64 = 1.5;
/// A device that has not come up (or a preparation not done) after this long is shot as it is
/// (and reported).
const PATIENCE: Duration = Duration::from_secs(30);
/// Frames drawn for a view before it is shot (egui lays a new view out over two passes).
const FRAMES_BEFORE_SHOT: u32 = 3;

/// One view to shoot.
#[derive(Debug, Clone)]
struct Shot {
    view: View,
    size: [f32; 2],
    lang: Lang,
}

/// Something done before the shots, and when it is done.
struct Prep {
    what: &'static str,
    start: fn(&mut App),
    done: fn(&App) -> bool,
}

/// Where the tour is.
enum Phase {
    /// Connect to the next device.
    Connect,
    /// Connected at this instant; waiting until it has come up ([`settled`]).
    Settle(Instant),
    /// The preparation step at this index, started at this instant.
    Prepare(usize, Instant),
    /// Arrange the next shot.
    Next,
    /// The shot is arranged; frames drawn at its size so far.
    Arrange(Shot, u32),
    /// The screenshot is asked for: the frame drawn now is checked, and the shot is waited for.
    Saving(String),
    /// All shot: the files are being written, then the window closes.
    Done,
}

/// PNG files being written: (file, its writer).
type Writers = Arc<Mutex<Vec<(PathBuf, JoinHandle<Result<(), String>>)>>>;

/// The tour's state. Messages (a file saved, a device that did not answer, a file that could not
/// be written, a split word) go to stderr, and the failures are counted in [`Tour::failures`].
pub struct Tour {
    dir: PathBuf,
    devices: Vec<SimKind>,
    device: usize,
    shots: Vec<Shot>,
    phase: Phase,
    /// The screenshots taken (the callback counts them).
    taken: Arc<Mutex<u64>>,
    /// The shots asked for.
    asked: u64,
    /// The frame of the shot asked for has been checked.
    checked: bool,
    writers: Writers,
    started: Instant,
    /// What went wrong so far.
    pub failures: Vec<String>,
    /// The generated records the Yield view shows (never the user's), while the tour runs.
    records: Option<Option<tempfile::TempDir>>,
}

/// Generated records of a plausible line (three days, 2,000 units) in a temporary file, which
/// the window's records then point to; `None` (and the view shows why) if it cannot be made.
fn demo_records(app: &mut App) -> Option<tempfile::TempDir> {
    let dir = tempfile::tempdir().ok()?;
    let path = dir.path().join("tour-records.sqlite");
    let mut store = crate::ops::records::SqliteStore::open(&path).ok()?;
    let tx = store.connection().transaction().ok()?;
    let end = crate::ops::records::record::now_ms();
    crate::ops::records::demo::generate(2000, end - 3 * 86_400_000, end, 28, &mut |r| {
        let _ = crate::ops::records::write::insert(&mut crate::ops::records::sql::Lite(&tx), &r);
    });
    tx.commit().ok()?;
    app.station()
        .records
        .configure(Some(path.display().to_string()));
    Some(dir)
}

impl Tour {
    /// A tour of every demo device, saving into `dir` (created if missing).
    pub fn new(dir: PathBuf) -> Self {
        Self {
            dir,
            devices: SimKind::ALL.to_vec(),
            device: 0,
            shots: Vec::new(),
            phase: Phase::Connect,
            taken: Arc::new(Mutex::new(0)),
            asked: 0,
            checked: false,
            writers: Arc::default(),
            started: Instant::now(),
            failures: Vec::new(),
            records: None,
        }
    }

    /// One frame of the tour, before the window is drawn.
    pub fn step(&mut self, ctx: &egui::Context, app: &mut App) {
        ctx.request_repaint();
        match &self.phase {
            Phase::Connect => match self.devices.get(self.device) {
                Some(&kind) => {
                    if self.records.is_none() {
                        self.records = Some(demo_records(app));
                    }
                    app.connect_demo(kind);
                    self.phase = Phase::Settle(Instant::now());
                }
                None => self.finish(ctx),
            },
            Phase::Settle(since) => {
                let up = settled(app.station());
                if up || since.elapsed() >= PATIENCE {
                    if !up {
                        self.fail(format!(
                            "{} did not come up within {} s",
                            self.device_name(),
                            PATIENCE.as_secs()
                        ));
                    }
                    self.phase = Phase::Prepare(0, Instant::now());
                    self.start_prep(app, 0);
                }
            }
            Phase::Prepare(i, since) => {
                let (i, since) = (*i, *since);
                let preps = preparation(self.kind());
                let done = preps.get(i).is_none_or(|p| (p.done)(app));
                if done || since.elapsed() >= PATIENCE {
                    if !done && let Some(p) = preps.get(i) {
                        self.fail(format!("{}: {} not done", self.device_name(), p.what));
                    }
                    if i + 1 < preps.len() {
                        self.phase = Phase::Prepare(i + 1, Instant::now());
                        self.start_prep(app, i + 1);
                    } else {
                        // The Yield view is the same on every device: shot once, on the first.
                        let first = self.device == 0;
                        self.shots = shots(
                            app.views()
                                .into_iter()
                                .filter(|v| first || v.panel != PanelId::YIELD)
                                .collect(),
                        );
                        self.phase = Phase::Next;
                    }
                }
            }
            Phase::Next => match self.shots.pop() {
                Some(shot) => {
                    app.show_view(&shot.view);
                    app.settings.lang = shot.lang;
                    ctx.send_viewport_cmd(egui::ViewportCommand::InnerSize(shot.size.into()));
                    self.phase = Phase::Arrange(shot, 0);
                }
                None => {
                    self.device += 1;
                    self.phase = Phase::Connect;
                }
            },
            Phase::Arrange(shot, frames) => {
                let size = ctx.content_rect().size();
                let at_size = (size - egui::Vec2::from(shot.size)).length() < 1.0;
                let frames = if at_size { frames + 1 } else { 0 };
                if frames < FRAMES_BEFORE_SHOT {
                    self.phase = Phase::Arrange(shot.clone(), frames);
                } else {
                    let name = self.file_name(shot);
                    self.shoot(ctx, &name);
                    self.phase = Phase::Saving(name);
                }
            }
            Phase::Saving(_) => {
                let taken = self.taken.lock().map_or(0, |t| *t);
                if taken >= self.asked {
                    self.phase = Phase::Next;
                }
            }
            Phase::Done => {}
        }
    }

    /// After the window is drawn: the frame of a shot is checked for words split over two
    /// lines.
    pub fn after_ui(&mut self, ctx: &egui::Context) {
        let Phase::Saving(name) = &self.phase else {
            return;
        };
        if self.checked {
            return;
        }
        self.checked = true;
        // The panels draw on the background layer; windows and popups on layers of their own.
        let mut layers = vec![egui::LayerId::background()];
        for id in ctx.memory(|m| m.layer_ids().collect::<Vec<_>>()) {
            if !layers.contains(&id) {
                layers.push(id);
            }
        }
        let shapes: Vec<_> = ctx.graphics(|g| {
            layers
                .iter()
                .filter_map(|id| g.get(*id))
                .flat_map(|list| list.all_entries().cloned())
                .collect()
        });
        let split = super::layout::split_words(&shapes);
        let name = name.clone();
        if !split.is_empty() {
            self.fail(format!("{name}: words split over two lines: {split:?}"));
        }
        // Over each other on the panels' own layer (a popup is drawn over them on purpose).
        let panels = ctx.graphics(|g| {
            g.get(egui::LayerId::background())
                .map(|l| l.all_entries().cloned().collect::<Vec<_>>())
                .unwrap_or_default()
        });
        let over = super::layout::overlapping_texts(&panels);
        if !over.is_empty() {
            self.fail(format!("{name}: texts drawn over texts: {over:?}"));
        }
    }

    /// Asks for a screenshot of the frame drawn now, written to `name` on a thread of its own.
    fn shoot(&mut self, ctx: &egui::Context, name: &str) {
        let path = self.dir.join(name);
        let (taken, writers) = (self.taken.clone(), self.writers.clone());
        self.asked += 1;
        self.checked = false;
        ctx.request_screenshot(move |image| {
            let to = path.clone();
            let writer = std::thread::Builder::new()
                .name("botbench-tour-png".into())
                .spawn(move || save_png(&image, &to));
            if let Ok(mut w) = writers.lock() {
                match writer {
                    Ok(handle) => w.push((path, handle)),
                    Err(e) => {
                        let failed = std::thread::spawn(move || Err(e.to_string()));
                        w.push((path, failed));
                    }
                }
            }
            if let Ok(mut t) = taken.lock() {
                *t += 1;
            }
        });
    }

    /// Waits for every file to be written, says how it went, and closes the window.
    fn finish(&mut self, ctx: &egui::Context) {
        let writers = self
            .writers
            .lock()
            .map(|mut w| std::mem::take(&mut *w))
            .unwrap_or_default();
        let n = writers.len();
        for (path, writer) in writers {
            match writer.join() {
                Ok(Ok(())) => eprintln!("tour: {}", path.display()),
                Ok(Err(e)) => self.fail(e),
                Err(_) => self.fail(format!("{}: the writer panicked", path.display())),
            }
        }
        eprintln!(
            "tour: {n} shots in {:.0} s",
            self.started.elapsed().as_secs_f64()
        );
        eprintln!("tour: done, {} failure(s)", self.failures.len());
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        self.phase = Phase::Done;
    }

    fn start_prep(&mut self, app: &mut App, i: usize) {
        if let Some(p) = preparation(self.kind()).get(i) {
            (p.start)(app);
        }
    }

    fn kind(&self) -> SimKind {
        self.devices
            .get(self.device)
            .copied()
            .unwrap_or(SimKind::WindowCleaner)
    }

    fn device_name(&self) -> &'static str {
        self.devices.get(self.device).map_or("?", |k| k.name())
    }

    fn file_name(&self, shot: &Shot) -> String {
        let lang = match shot.lang {
            Lang::En => "en",
            Lang::Zh => "zh",
        };
        format!(
            "{}-{}-{}x{}-{lang}.png",
            self.device_name(),
            shot.view.name,
            shot.size[0],
            shot.size[1]
        )
    }

    fn fail(&mut self, what: String) {
        eprintln!("tour: {what}");
        self.failures.push(what);
    }
}

/// Every view at every size in each language, in the order shot (last first, for `pop`):
/// size by size, then language by language, so that the window is resized once a size.
fn shots(views: Vec<View>) -> Vec<Shot> {
    let mut all = Vec::new();
    for size in SIZES {
        for lang in Lang::ALL {
            for view in &views {
                all.push(Shot {
                    view: view.clone(),
                    size,
                    lang,
                });
            }
        }
    }
    all.reverse();
    all
}

/// The self-test panel as a run whose port went in its first step leaves it (the NO VERDICT
/// banner, `link lost during <step>`): a report of the plan open, about the unit identified,
/// with nothing measured.
fn link_lost_selftest(app: &mut App) {
    let Some(plan) = app.panel::<SelfTestPanel>().plan.clone() else {
        return;
    };
    let Some(first) = plan.steps.first() else {
        return;
    };
    let info = app.station().device.info.clone().and_then(Result::ok);
    let step = crate::ops::selftest::StepResult {
        name: first.name.clone(),
        kind: first.kind.name().into(),
        pass: false,
        detail: format!("link lost: {LOST_PORT}"),
        measurements: Vec::new(),
        started_ms: crate::ops::records::record::now_ms(),
        duration_ms: 0,
        interrupted: Some(crate::ops::selftest::Interruption::LinkLost),
    };
    let report = crate::ops::selftest::Report {
        plan: plan.name.clone(),
        profile: app.station().device.profile.id.clone(),
        device: info.as_ref().map(crate::ops::device::description),
        device_info: info,
        started: chrono::Local::now().to_rfc3339_opts(chrono::SecondsFormat::Millis, false),
        duration_ms: 0,
        safe_state: Vec::new(),
        results: vec![step.clone()],
        aborted: Some(format!("step '{}': {}", step.name, step.detail)),
        pass: false,
    };
    app.with_panel(|p: &mut SelfTestPanel, _| p.show_finished(vec![step]));
    let verdict = super::station::Verdict::SelfTest(Box::new(report));
    app.station_mut().verdicts.take(verdict);
}

/// Why a port was lost, in the words the link uses for an adapter pulled out (a failed read,
/// then the system's likely cause, `crate::system::vanished`): what the NO VERDICT banners show.
const LOST_PORT: &str = "port lost: port disconnected: /dev/ttyUSB0: Input/output error (os \
     error 5) — /dev/ttyUSB0 is gone: unplugged (no USB serial port is listed now); plug it in \
     again";

/// The Production tab as a servo whose port went while its rate was set leaves it (the NO
/// VERDICT banner, `link lost during set baud`): the record of a fresh servo given id 1.
fn link_lost_provisioning(app: &mut App) {
    use crate::ops::servo::provision::{Outcome, Record, step};
    let record = Record {
        time: chrono::Local::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, false),
        serial: Some(1001),
        id: Some(1),
        baud: None,
        result: Outcome::LinkLost {
            step: step::SET_BAUD.into(),
            reason: LOST_PORT.into(),
        },
        mismatches: Vec::new(),
        recorded: Vec::new(),
        timeline: Vec::new(),
        writes: Vec::new(),
    };
    let shown = record.clone();
    app.with_panel(move |servo: &mut ServoBenchPanel, _| {
        let state = servo.production.state.clone();
        servo.production.on_record(shown, state, None);
    });
    let verdict = super::station::Verdict::Provisioned(Box::new(record));
    app.station_mut().verdicts.take(verdict);
}

/// What a technician would have on screen before the shots of a device of `kind`.
fn preparation(kind: SimKind) -> Vec<Prep> {
    match kind {
        SimKind::WindowCleaner => vec![
            Prep {
                what: "the self-test plan and the factory preset opened",
                start: |app| {
                    let dir = super::files::shipped_dir();
                    if let Ok(p) = super::files::shipped_in(&dir, "window-cleaner-factory.ron") {
                        app.with_panel(|presets: &mut PresetsPanel, st| {
                            presets.path = p.display().to_string();
                            presets.open(st);
                        });
                    }
                    app.with_panel(|selftest: &mut SelfTestPanel, st| selftest.open(st));
                },
                done: |app| {
                    app.panel::<SelfTestPanel>().plan.is_some()
                        && app.panel::<PresetsPanel>().loaded.is_some()
                },
            },
            Prep {
                what: "a self-test with no verdict: the link lost in its first step",
                start: link_lost_selftest,
                done: |app| app.station().verdicts.selftest.is_some(),
            },
            Prep {
                what: "the Yield view's report of the tour's generated records computed",
                start: |app| {
                    let query = crate::ops::records::report::Query {
                        filter: crate::ops::records::Filter {
                            since_ms: Some(crate::ops::records::record::now_ms() - 7 * 86_400_000),
                            ..Default::default()
                        },
                        ..Default::default()
                    };
                    let ctx = app.station().ctx.clone();
                    app.station().records.refresh(query, &ctx);
                },
                done: |app| {
                    !app.station().records.computing() && app.station().records.report().0.is_some()
                },
            },
        ],
        SimKind::ServoBus => vec![
            Prep {
                what: "the bus scanned, a servo selected and the provisioning plan open",
                start: |app| {
                    let dir = super::files::shipped_dir();
                    let scan = app.with_panel(|servo: &mut ServoBenchPanel, st| {
                        if let Ok(p) = super::files::shipped_in(&dir, "servo-provision-plan.ron") {
                            servo.production.plan_path = p.display().to_string();
                            servo.production.load(st);
                        }
                        servo.scan.start(st)
                    });
                    if let Some(scan) = scan {
                        app.apply_from(PanelId::SERVO_BENCH, scan);
                    }
                },
                done: |app| {
                    let servo = app.panel::<ServoBenchPanel>();
                    app.station().job_progress().is_none()
                        && servo.selected.is_some()
                        && servo.production.plan.is_some()
                },
            },
            Prep {
                what: "the servo's parameters read",
                start: |app| {
                    let params = app.views().into_iter().find(|v| v.name.ends_with("Params"));
                    if let Some(v) = params {
                        app.show_view(&v);
                    }
                },
                done: |app| {
                    app.station().job_progress().is_none()
                        && !app.panel::<ServoBenchPanel>().params.values.is_empty()
                },
            },
            Prep {
                what: "a provisioning with no verdict: the link lost while the rate was set",
                start: link_lost_provisioning,
                done: |app| !app.panel::<ServoBenchPanel>().production.history.is_empty(),
            },
        ],
        SimKind::TuyaVacuum => vec![Prep {
            what: "the MCU's own requests answered",
            start: |app| {
                for r in [
                    McuRequest::LocalTime,
                    McuRequest::WifiTest,
                    McuRequest::NetStatus,
                    McuRequest::Mac,
                ] {
                    app.apply(super::Action::DemoMcuRequest(r));
                }
            },
            done: |app| app.station().device.tuya.requests.len() >= 4,
        }],
        SimKind::SolarCleanbot => Vec::new(),
    }
}

/// Whether the connected device has come up far enough to be shown: answering with no job
/// running, and by protocol: MSP identified (CMD_VERSION answered) and each plot of its profile
/// holding [`PLOTTED_SECS`] of samples (they are polled from the connection on:
/// [`crate::ops::telemetry::polls`]); Tuya shaken hands with; a servo bus at once (nothing is
/// polled until the servo bench asks).
fn settled(rt: &Station) -> bool {
    let d = &rt.device;
    let plotted = || {
        d.profile.plots.iter().all(|p| {
            d.plots
                .get(&p.id)
                .and_then(SeriesSet::span)
                .is_some_and(|(first, last)| last - first >= PLOTTED_SECS)
        })
    };
    let up = match d.profile.protocol {
        Protocol::Msp => matches!(d.info, Some(Ok(_))) && plotted(),
        Protocol::Tuya => d.tuya.done_at.is_some(),
        Protocol::Servo => true,
    };
    rt.connected() && rt.job_progress().is_none() && up
}

/// Writes `image` to `path` as PNG (the folder is created if missing).
pub(crate) fn save_png(image: &egui::ColorImage, path: &std::path::Path) -> Result<(), String> {
    let [w, h] = image.size;
    let (w, h) = (
        u32::try_from(w).map_err(|e| e.to_string())?,
        u32::try_from(h).map_err(|e| e.to_string())?,
    );
    let bytes = image.as_raw().to_vec();
    let buffer = image::RgbaImage::from_raw(w, h, bytes)
        .ok_or_else(|| format!("a {w}×{h} screenshot has the wrong number of pixels"))?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    buffer
        .save(path)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}
