//! The station window's screenshot tour (`botbench station BUNDLE --screenshots DIR`, used by
//! `.ci/screenshot.sh` with the demo bundle): once every slot is busy (a question waiting or a
//! verdict out), the window is shot at each size of [`crate::ui::tour::SIZES`] in English and
//! 中文 (`station-question-<w>x<h>-<lang>.png`); then the first yes/no question is answered no
//! (a FAIL banner with its failed step and reason, as an operator sees one) and every other
//! yes, and once every slot has its verdict, shot again (`station-verdicts-...`); then the
//! window closes.

use super::LineStation;
use crate::i18n::Lang;
use crate::ops::station::{Answer, Command};
use eframe::egui;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Frames drawn at a shot's size before it is taken.
const FRAMES_BEFORE_SHOT: u32 = 3;
/// A station not at the moment wanted by then is shot as it is (and said).
const PATIENCE: Duration = Duration::from_secs(90);

/// Where the station's tour is.
enum Phase {
    /// Waiting for the moment `what` (`question`, `verdicts`), since then.
    Wait(&'static str, Instant),
    /// Shots of `what` left, the one arranged and its frames.
    Arrange(&'static str, Vec<([f32; 2], Lang)>, u32),
    /// A shot asked for; the rest to take after it.
    Saving(&'static str, Vec<([f32; 2], Lang)>),
    /// All shot: the window closes.
    Done,
}

/// The tour's state.
pub struct StationShots {
    dir: PathBuf,
    phase: Phase,
    taken: Arc<Mutex<Vec<Result<PathBuf, String>>>>,
    asked: usize,
}

impl StationShots {
    /// A tour writing into `dir`.
    pub fn new(dir: PathBuf) -> Self {
        Self {
            dir,
            phase: Phase::Wait("question", Instant::now()),
            taken: Arc::default(),
            asked: 0,
        }
    }

    fn all() -> Vec<([f32; 2], Lang)> {
        let mut v = Vec::new();
        for size in crate::ui::tour::SIZES {
            for lang in [Lang::En, Lang::Zh] {
                v.push((size, lang));
            }
        }
        v.reverse();
        v
    }

    /// One step, before the station is drawn.
    pub fn step(&mut self, ctx: &egui::Context, st: &mut LineStation) {
        ctx.request_repaint_after(Duration::from_millis(50));
        let phase = std::mem::replace(&mut self.phase, Phase::Done);
        self.phase = match phase {
            Phase::Wait(what, since) => {
                // A question for the operator (Yes/No, a value, a code), not a prompt that the
                // simulated fixture acts out by itself.
                let question =
                    |t: &super::TileState| matches!(&t.asking, Some((k, _, _)) if *k != "prompt");
                let busy = |t: &super::TileState| question(t) || t.verdict.is_some();
                let ready = match what {
                    "question" => st.tiles.iter().all(busy) && st.tiles.iter().any(question),
                    _ => st.tiles.iter().all(|t| t.verdict.is_some()),
                };
                let late = since.elapsed() > PATIENCE;
                if late {
                    eprintln!("station tour: the {what} moment never came; shot as it is");
                }
                if ready || late {
                    Phase::Arrange(what, Self::all(), 0)
                } else {
                    Phase::Wait(what, since)
                }
            }
            Phase::Arrange(what, mut left, frames) => match left.last().copied() {
                Some((size, lang)) => {
                    st.lang = lang;
                    if frames == 0 {
                        ctx.send_viewport_cmd(egui::ViewportCommand::InnerSize(size.into()));
                    }
                    let at = (ctx.content_rect().size() - egui::Vec2::from(size)).length() < 1.0;
                    let frames = if at { frames + 1 } else { 1 };
                    if frames <= FRAMES_BEFORE_SHOT {
                        Phase::Arrange(what, left, frames)
                    } else {
                        left.pop();
                        let tag = if lang == Lang::Zh { "zh" } else { "en" };
                        let name = format!("station-{what}-{}x{}-{tag}.png", size[0], size[1]);
                        self.shoot(ctx, self.dir.join(name));
                        Phase::Saving(what, left)
                    }
                }
                None if what == "question" => {
                    let mut said_no = false;
                    for t in &st.tiles {
                        let yes_no = matches!(&t.asking, Some(("confirm", _, _)));
                        let answer = if yes_no && !said_no {
                            said_no = true;
                            Answer::No
                        } else {
                            Answer::Yes
                        };
                        if t.asking.is_some() {
                            st.send(&t.slot, Command::Answer(answer));
                        }
                    }
                    Phase::Wait("verdicts", Instant::now())
                }
                None => {
                    self.finish(ctx);
                    Phase::Done
                }
            },
            Phase::Saving(what, left) => {
                let taken = self.taken.lock().map_or(0, |t| t.len());
                if taken >= self.asked {
                    Phase::Arrange(what, left, 0)
                } else {
                    Phase::Saving(what, left)
                }
            }
            Phase::Done => Phase::Done,
        };
    }

    fn shoot(&mut self, ctx: &egui::Context, path: PathBuf) {
        self.asked += 1;
        let taken = self.taken.clone();
        ctx.request_screenshot(move |image| {
            let saved = crate::ui::tour::save_png(&image, &path).map(|()| path);
            if let Ok(mut t) = taken.lock() {
                t.push(saved);
            }
        });
    }

    /// Says what was written and closes the window.
    fn finish(&mut self, ctx: &egui::Context) {
        let taken = self.taken.lock().map(|t| t.clone()).unwrap_or_default();
        let mut failed = 0;
        for t in &taken {
            match t {
                Ok(p) => eprintln!("station tour: {}", p.display()),
                Err(e) => {
                    failed += 1;
                    eprintln!("station tour: FAILED {e}");
                }
            }
        }
        eprintln!(
            "station tour: done, {} shots, {failed} failures",
            taken.len()
        );
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }
}
