//! The screenshot tour (`botbench gui --screenshots DIR`, used by `.ci/screenshot.sh`): one
//! launch of the window connects to each built-in demo device in turn, waits until it has come
//! up (see [`settled`]: answering, identified or shaken hands with, every plot holding
//! [`PLOTTED_SECS`] of samples), then shows every panel the device has at each size in
//! [`SIZES`] and in each language, and saves each view as
//! `DIR/<device>-<panel>-<w>x<h>-<lang>.png`; then it closes the window. The shot is the
//! window's own framebuffer (egui's viewport screenshot).

use super::state::Target;
use super::{Action, AppState, PanelId};
use crate::i18n::Lang;
use crate::profile::Protocol;
use crate::series::SeriesSet;
use crate::sim::SimKind;
use eframe::egui;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The window sizes shot, logical points: the line PCs' usual screen and a small one.
pub const SIZES: [[f32; 2]; 2] = [[1280.0, 800.0], [1024.0, 600.0]];
/// Seconds of samples each plot of a device holds before its first shot.
pub const PLOTTED_SECS: f64 = 1.5;
/// A device that has not come up after this long is shot as it is (and reported).
const CONNECT_PATIENCE: Duration = Duration::from_secs(30);
/// Frames drawn at a shot's size before it is taken (egui lays out a new size over two passes).
const FRAMES_BEFORE_SHOT: u32 = 3;

/// One view to shoot.
#[derive(Debug, Clone, Copy)]
struct Shot {
    panel: PanelId,
    size: [f32; 2],
    lang: Lang,
}

/// Where the tour is.
enum Phase {
    /// Connect to the next device.
    Connect,
    /// Connected at this instant; waiting until it has come up ([`settled`]).
    Settle(Instant),
    /// Arrange the next shot.
    Next,
    /// The shot's size is asked for; frames drawn at it so far.
    Arrange(Shot, u32),
    /// The screenshot is asked for; its saving reports into the slot.
    Saving,
    /// All shot: the window is closing.
    Done,
}

/// The tour's state. Messages (a file saved, a device that did not answer, a file that could not
/// be written) go to stderr, and the failures are counted in [`Tour::failures`].
pub struct Tour {
    dir: PathBuf,
    devices: Vec<SimKind>,
    device: usize,
    shots: Vec<Shot>,
    phase: Phase,
    saved: Arc<Mutex<Option<Result<PathBuf, String>>>>,
    /// What went wrong so far.
    pub failures: Vec<String>,
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
            saved: Arc::new(Mutex::new(None)),
            failures: Vec::new(),
        }
    }

    /// One frame of the tour: what to apply this frame. `panels` are the panels the connected
    /// device has.
    pub fn step(&mut self, ctx: &egui::Context, rt: &AppState, panels: &[PanelId]) -> Vec<Action> {
        let mut actions = Vec::new();
        ctx.request_repaint();
        match self.phase {
            Phase::Connect => match self.devices.get(self.device) {
                Some(kind) => {
                    actions.push(Action::Connect {
                        target: Target::Demo(kind.name().to_string()),
                        baud: 115_200,
                        profile: kind.profile_id().to_string(),
                        margin_ms: None,
                    });
                    self.phase = Phase::Settle(Instant::now());
                }
                None => {
                    eprintln!("tour: done, {} failure(s)", self.failures.len());
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                    self.phase = Phase::Done;
                }
            },
            Phase::Settle(since) => {
                let up = settled(rt);
                if up || since.elapsed() >= CONNECT_PATIENCE {
                    if !up {
                        self.fail(format!(
                            "{} did not come up within {} s",
                            self.device_name(),
                            CONNECT_PATIENCE.as_secs()
                        ));
                    }
                    self.shots = panels
                        .iter()
                        .flat_map(|&panel| {
                            SIZES.into_iter().flat_map(move |size| {
                                [Lang::En, Lang::Zh].map(|lang| Shot { panel, size, lang })
                            })
                        })
                        .rev()
                        .collect();
                    self.phase = Phase::Next;
                }
            }
            Phase::Next => match self.shots.pop() {
                Some(shot) => {
                    actions.push(Action::ShowPanel(shot.panel));
                    actions.push(Action::SetLanguage(shot.lang));
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
                    self.phase = Phase::Arrange(shot, frames);
                } else {
                    let path = self.dir.join(self.file_name(&shot));
                    let slot = self.saved.clone();
                    ctx.request_screenshot(move |image| {
                        let result = save_png(&image, &path).map(|()| path);
                        if let Ok(mut s) = slot.lock() {
                            *s = Some(result);
                        }
                    });
                    self.phase = Phase::Saving;
                }
            }
            Phase::Saving => {
                let result = self.saved.lock().ok().and_then(|mut s| s.take());
                match result {
                    Some(Ok(path)) => {
                        eprintln!("tour: {}", path.display());
                        self.phase = Phase::Next;
                    }
                    Some(Err(e)) => {
                        self.fail(e);
                        self.phase = Phase::Next;
                    }
                    None => {}
                }
            }
            Phase::Done => {}
        }
        actions
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
            "{}-{:?}-{}x{}-{lang}.png",
            self.device_name(),
            shot.panel,
            shot.size[0],
            shot.size[1]
        )
    }

    fn fail(&mut self, what: String) {
        eprintln!("tour: {what}");
        self.failures.push(what);
    }
}

/// Whether the connected device has come up far enough to be shown: answering with no job
/// running, and by protocol: MSP identified (CMD_VERSION answered) and each plot of its profile
/// holding [`PLOTTED_SECS`] of samples (they are polled from the connection on:
/// [`crate::ops::telemetry::polls`]); Tuya shaken hands with; a servo bus at once (nothing is
/// polled until the servo bench asks).
fn settled(rt: &AppState) -> bool {
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
fn save_png(image: &egui::ColorImage, path: &std::path::Path) -> Result<(), String> {
    let [w, h] = image.size;
    let (w, h) = (
        u32::try_from(w).map_err(|e| e.to_string())?,
        u32::try_from(h).map_err(|e| e.to_string())?,
    );
    let bytes: Vec<u8> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
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
