//! The one way a run's record is kept: [`Recorder::save`] after every run (the command line's
//! and the window's alike), before the verdict is shown. It fills in where and by whom the run
//! was made, writes the record to its store, and when that fails keeps it in a fallback spool
//! (and, should that fail too, in memory and as JSON in the message), never dropping it.

use super::record::{Record, RunContext};
use super::store::{self, Location, RecordsError, Saved, SqliteStore, Store};
use std::path::{Path, PathBuf};

/// Where a record ended up.
#[derive(Debug, Clone, PartialEq)]
pub enum Kept {
    /// Committed to the store named.
    Stored {
        /// The file or server.
        place: String,
    },
    /// Committed to a spool on this PC, waiting to be forwarded.
    Spooled {
        /// The spool file.
        spool: String,
        /// Records waiting, this one included.
        waiting: u64,
        /// Why it waits.
        why: RecordsError,
    },
    /// Kept only in this process's memory (retried at the next save): every file failed.
    InMemory {
        /// Why.
        why: RecordsError,
        /// The record as JSON, for the log or the operator to keep.
        json: String,
    },
}

impl Kept {
    /// One line for the operator: `record saved to FILE`, `record kept in the spool FILE (3
    /// waiting): WHY`, or the error with the record's JSON.
    pub fn line(&self) -> String {
        match self {
            Kept::Stored { place } => format!("record saved to {place}"),
            Kept::Spooled {
                spool,
                waiting,
                why,
            } => format!(
                "record kept in the spool {spool} ({waiting} waiting to be forwarded): {why}"
            ),
            Kept::InMemory { why, json } => format!(
                "RECORD NOT WRITTEN to any file: {why}; it is kept until the next save, here it is: {json}"
            ),
        }
    }

    /// Whether the record reached its store.
    pub fn stored(&self) -> bool {
        matches!(self, Kept::Stored { .. })
    }
}

/// What keeps a run's record: the command line's [`Recorder`], the window's shared handle to
/// one. [`super::runs`] saves every record through it, before the verdict is shown.
pub trait Keeper {
    /// Keeps `record` (filling in the station's context), never dropping it: see [`Kept`].
    fn keep(&mut self, record: &mut Record) -> Kept;
}

impl Keeper for Recorder {
    fn keep(&mut self, record: &mut Record) -> Kept {
        self.save(record)
    }
}

/// Keeps every run's record: its store, where and by whom runs are made, and a fallback.
pub struct Recorder {
    store: Box<dyn Store>,
    /// Station, slot, fixture, operator, bundle hash: put into every record saved.
    pub context: RunContext,
    fallback_path: Option<PathBuf>,
    fallback: Option<SqliteStore>,
    in_memory: Vec<Record>,
}

impl Recorder {
    /// A recorder writing to `location` (see [`store::open`]); the fallback spool is
    /// `BOTBENCH_SPOOL` or `unsaved.sqlite` in botbench's data folder, opened only when needed.
    pub fn open(location: &Location, context: RunContext) -> Result<Recorder, RecordsError> {
        Recorder::open_spooled(location, context, None)
    }

    /// [`Recorder::open`] with the spool at `spool` when given (`--spool FILE`): a line
    /// server's records wait there, and records no store took go to its `.unsaved` sibling;
    /// else as `BOTBENCH_SPOOL` or the data folder say. Errors: as [`Recorder::open`].
    pub fn open_spooled(
        location: &Location,
        context: RunContext,
        spool: Option<&Path>,
    ) -> Result<Recorder, RecordsError> {
        let fallback = match spool {
            Some(p) => Some(unsaved_beside(p)),
            None => fallback_path(),
        };
        Ok(Recorder::with_store(
            store::open_spooled(location, spool)?,
            context,
            fallback,
        ))
    }

    /// A recorder writing to `store`, falling back to the SQLite file `fallback`.
    pub fn with_store(
        store: Box<dyn Store>,
        context: RunContext,
        fallback: Option<PathBuf>,
    ) -> Recorder {
        Recorder {
            store,
            context,
            fallback_path: fallback,
            fallback: None,
            in_memory: Vec::new(),
        }
    }

    /// The store's file or server.
    pub fn place(&self) -> String {
        self.store.place()
    }

    /// The store, for reading back.
    pub fn store(&mut self) -> &mut dyn Store {
        self.store.as_mut()
    }

    /// Records not yet in the store: in its spool, in the fallback, in memory.
    pub fn waiting(&mut self) -> u64 {
        let fallback = self
            .fallback
            .as_mut()
            .and_then(|f| f.count().ok())
            .unwrap_or(0);
        self.store.waiting() + fallback + self.in_memory.len() as u64
    }

    /// Saves `record` with this recorder's context filled in where the record has none: to the
    /// store, else the fallback spool, else memory. What waited before is sent first, in order.
    pub fn save(&mut self, record: &mut Record) -> Kept {
        fill(&mut record.context, &self.context);
        // What waits here first, in order (the store's own spool it forwards itself).
        let _ = self.forward_kept();
        match self.store.save(record) {
            Ok(Saved::Stored) => Kept::Stored {
                place: self.store.place(),
            },
            Ok(Saved::Spooled { waiting, why }) => Kept::Spooled {
                spool: self.spool_name(),
                waiting,
                why,
            },
            Err(why) => self.keep_elsewhere(record, why),
        }
    }

    /// Sends what waits (fallback, memory, the store's spool) to the store now; the number
    /// still waiting.
    pub fn forward_waiting(&mut self) -> Result<u64, RecordsError> {
        self.forward_kept()?;
        self.store.forward()
    }

    /// Why the line server was last not written to, if the store has one and it was not.
    pub fn last_error(&self) -> Option<RecordsError> {
        self.store.last_error()
    }

    /// Sends what waits in the fallback spool and in memory to the store.
    fn forward_kept(&mut self) -> Result<(), RecordsError> {
        if self.fallback.is_none()
            && let Some(p) = self.fallback_path.as_ref().filter(|p| p.exists())
        {
            self.fallback = SqliteStore::open(p).ok();
        }
        if let Some(fallback) = self.fallback.as_mut() {
            while let Some(r) = fallback.oldest()? {
                self.store.save(&r)?;
                fallback.remove(&r.uuid)?;
            }
        }
        while let Some(r) = self.in_memory.first() {
            self.store.save(r)?;
            self.in_memory.remove(0);
        }
        Ok(())
    }

    fn spool_name(&self) -> String {
        self.store
            .spool_place()
            .unwrap_or_else(|| self.store.place())
    }

    fn keep_elsewhere(&mut self, record: &Record, why: RecordsError) -> Kept {
        if self.fallback.is_none()
            && let Some(p) = &self.fallback_path
        {
            match SqliteStore::open(p) {
                Ok(f) => self.fallback = Some(f),
                Err(e) => return self.keep_in_memory(record, why, Some(e)),
            }
        }
        let Some(fallback) = self.fallback.as_mut() else {
            return self.keep_in_memory(record, why, None);
        };
        match fallback.insert(record) {
            Ok(_) => Kept::Spooled {
                spool: fallback.path().display().to_string(),
                waiting: fallback.count().unwrap_or(1),
                why,
            },
            Err(e) => self.keep_in_memory(record, why, Some(e)),
        }
    }

    fn keep_in_memory(
        &mut self,
        record: &Record,
        why: RecordsError,
        also: Option<RecordsError>,
    ) -> Kept {
        self.in_memory.push(record.clone());
        let why = match also {
            Some(e) => RecordsError::Database {
                place: self.store.place(),
                why: format!("{why}; and the fallback spool: {e}"),
            },
            None => why,
        };
        Kept::InMemory {
            why,
            json: serde_json::to_string(record).unwrap_or_default(),
        }
    }
}

/// Fills what `record` leaves empty from `from`.
fn fill(record: &mut RunContext, from: &RunContext) {
    let take = |mine: &mut Option<String>, theirs: &Option<String>| {
        if mine.is_none() {
            mine.clone_from(theirs);
        }
    };
    take(&mut record.station, &from.station);
    take(&mut record.slot, &from.slot);
    take(&mut record.fixture, &from.fixture);
    take(&mut record.operator, &from.operator);
    take(&mut record.bundle_sha256, &from.bundle_sha256);
}

/// The file beside the spool `spool` that records no store took go to: `spool` with
/// `.unsaved` added.
fn unsaved_beside(spool: &Path) -> PathBuf {
    let mut name = spool.as_os_str().to_os_string();
    name.push(".unsaved");
    PathBuf::from(name)
}

/// The fallback spool: `BOTBENCH_SPOOL` (its `.unsaved` sibling) or `unsaved.sqlite` in
/// botbench's data folder.
fn fallback_path() -> Option<PathBuf> {
    if let Ok(p) = std::env::var("BOTBENCH_SPOOL")
        && !p.trim().is_empty()
    {
        return Some(unsaved_beside(Path::new(&p)));
    }
    dirs::data_dir().map(|d| d.join("botbench").join("unsaved.sqlite"))
}
