//! The window's production records: where they go (the Yield view's setting, saved as
//! `FileKind::Records`), the one [`Recorder`] every job saves its run through (the self-test,
//! provisioning, preset apply), and the Yield view's report, computed on a thread of its own
//! (`yield-report`) with its own connection so that the window never waits on the database.

use crate::i18n::Text;
use crate::ops::records::report::{self, Query, Report};
use crate::ops::records::{self as records, Kept, Location, Recorder, RunContext};
use std::sync::{Arc, Mutex, MutexGuard};

/// Where the window's records go and the last report of them; shared with jobs and the report
/// thread. Cloning shares it. The window only takes the quick lock (what it shows); a job
/// saving a record holds the recorder's lock, which may wait on a database.
#[derive(Clone, Default)]
pub struct RecordsHandle {
    shared: Arc<Mutex<Shared>>,
    /// The recorder, opened at the first save, and the setting it was opened for.
    recorder: Arc<Mutex<Opened>>,
}

/// The recorder, with the setting it was opened for; `None` before the first save.
type Opened = Option<(Option<String>, Recorder)>;

#[derive(Default)]
struct Shared {
    /// Where records go; `None` for the default (see [`Location::default_location`]).
    setting: Option<String>,
    /// Why the records could not be opened, as said last.
    error: Option<String>,
    /// Records saved by this window (each save counts): the Yield view refreshes on a change.
    saved: u64,
    /// Records waiting in the spool, as of the last save.
    waiting: u64,
    /// The last report: the `saved` count it was computed at, and the report or why not.
    report: Option<(u64, Result<Report, Text>)>,
    /// A report is being computed.
    computing: bool,
}

impl RecordsHandle {
    fn lock(&self) -> MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Sets where records go (`None` or empty: the default); the recorder opens anew.
    pub fn configure(&self, setting: Option<String>) {
        let mut s = self.lock();
        s.setting = setting.filter(|t| !t.trim().is_empty());
        s.error = None;
        s.report = None;
        s.saved += 1;
    }

    /// The setting as typed (empty for the default).
    pub fn setting(&self) -> String {
        self.lock().setting.clone().unwrap_or_default()
    }

    /// Where records go, as shown (password hidden), or why the setting is not valid.
    pub fn location(&self) -> Result<Location, String> {
        let setting = self.lock().setting.clone();
        location_of(setting.as_deref())
    }

    /// Saves `record` (on the job thread, before the verdict is shown): to the store, else the
    /// spool or memory (see [`Recorder::save`]). The context is this PC's station and operator
    /// from `BOTBENCH_STATION` / `BOTBENCH_OPERATOR`.
    pub fn save(&self, record: &mut records::Record) -> Kept {
        let setting = self.lock().setting.clone();
        let mut held = self.recorder.lock().unwrap_or_else(|e| e.into_inner());
        if held
            .as_ref()
            .is_none_or(|(for_setting, _)| *for_setting != setting)
        {
            *held = None;
            let opened = location_of(setting.as_deref())
                .and_then(|l| Recorder::open(&l, context()).map_err(|e| e.to_string()));
            match opened {
                Ok(r) => {
                    *held = Some((setting.clone(), r));
                    self.lock().error = None;
                }
                Err(e) => self.lock().error = Some(e),
            }
        }
        let kept = match held.as_mut() {
            Some((_, r)) => r.save(record),
            // The setting cannot be opened: the default file keeps the record meanwhile.
            None => {
                let why = self.lock().error.clone().unwrap_or_default();
                match Location::default_location().and_then(|l| Recorder::open(&l, context())) {
                    Ok(mut r) => match r.save(record) {
                        Kept::Stored { place } => Kept::Spooled {
                            spool: place,
                            waiting: 1,
                            why: records::RecordsError::BadLocation {
                                given: setting.clone().unwrap_or_default(),
                                why,
                            },
                        },
                        other => other,
                    },
                    Err(e) => Kept::InMemory {
                        why: e,
                        json: serde_json::to_string(record).unwrap_or_default(),
                    },
                }
            }
        };
        let waiting = held.as_mut().map_or(0, |(_, r)| r.waiting());
        drop(held);
        let mut s = self.lock();
        s.waiting = waiting;
        s.saved += 1;
        kept
    }

    /// Records waiting in the spool, as of the last save.
    pub fn waiting(&self) -> u64 {
        self.lock().waiting
    }

    /// Why the records could not be opened, if they could not.
    pub fn error(&self) -> Option<String> {
        self.lock().error.clone()
    }

    /// The last report (or why there is none, in both languages) and whether it is out of
    /// date (records saved since, or none yet).
    pub fn report(&self) -> (Option<Result<Report, Text>>, bool) {
        let s = self.lock();
        let stale = s.report.as_ref().is_none_or(|(at, _)| *at != s.saved);
        (s.report.as_ref().map(|(_, r)| r.clone()), stale)
    }

    /// Whether a report is being computed.
    pub fn computing(&self) -> bool {
        self.lock().computing
    }

    /// Computes the report of `query` on the `yield-report` thread (its own connection), then
    /// wakes the window through `ctx`. Does nothing while one is being computed.
    pub fn refresh(&self, query: Query, ctx: &eframe::egui::Context) {
        let (setting, saved) = {
            let mut s = self.lock();
            if s.computing {
                return;
            }
            s.computing = true;
            (s.setting.clone(), s.saved)
        };
        let handle = self.clone();
        let ctx = ctx.clone();
        let spawned = std::thread::Builder::new()
            .name("yield-report".into())
            .spawn(move || {
                let result = compute(setting.as_deref(), &query);
                let mut s = handle.lock();
                s.report = Some((saved, result));
                s.computing = false;
                drop(s);
                ctx.request_repaint();
            });
        if let Err(e) = spawned {
            let mut s = self.lock();
            s.computing = false;
            s.report = Some((
                saved,
                Err(Text::new(
                    format!("cannot start the report thread: {e}"),
                    format!("无法启动报表线程:{e}"),
                )),
            ));
        }
    }
}

impl records::Keeper for RecordsHandle {
    fn keep(&mut self, record: &mut records::Record) -> Kept {
        self.save(record)
    }
}

fn location_of(setting: Option<&str>) -> Result<Location, String> {
    match setting {
        Some(t) => Location::parse(t),
        None => Location::default_location(),
    }
    .map_err(|e| e.to_string())
}

fn context() -> RunContext {
    let env = |n: &str| std::env::var(n).ok().filter(|v| !v.trim().is_empty());
    RunContext {
        station: env("BOTBENCH_STATION"),
        operator: env("BOTBENCH_OPERATOR"),
        ..RunContext::default()
    }
}

/// The report over the records at `setting`, read with a connection of its own; why not, in
/// both languages (what the store said is quoted as it came).
fn compute(setting: Option<&str>, query: &Query) -> Result<Report, Text> {
    let location = location_of(setting).map_err(Text::same)?;
    if let Location::Sqlite(p) = &location
        && !p.exists()
    {
        return Err(Text::new(
            format!("no records yet in {}", p.display()),
            format!("{} 中尚无记录", p.display()),
        ));
    }
    let mut store = records::store::open(&location).map_err(|e| Text::same(e.to_string()))?;
    report::of_store(store.as_mut(), query).map_err(|e| Text::same(e.to_string()))
}

/// A job's summary with what became of its record: unchanged when it was stored, else with
/// `; record kept in the spool ...` in both languages.
pub fn with_note(summary: crate::i18n::Text, kept: &Kept) -> crate::i18n::Text {
    use crate::i18n::Text;
    let zh = match kept {
        Kept::Stored { .. } => return summary,
        Kept::Spooled { waiting, .. } => format!("记录已存入本机缓存({waiting} 条等待上传)"),
        Kept::InMemory { .. } => "记录未能写入任何文件".to_string(),
    };
    summary.then("; ", &Text::new(kept.line(), zh))
}

/// `; record kept in the spool ...` for a failure's text, or nothing when it was stored.
pub fn note_en(kept: &Kept) -> String {
    if kept.stored() {
        String::new()
    } else {
        format!("; {}", kept.line())
    }
}
