//! A line-wide PostgreSQL server behind a local spool: every record is first committed to a
//! SQLite spool on this PC (so it survives the server, the network and this process), then
//! forwarded to the server oldest first, one transaction each, and removed from the spool only
//! after the server committed it. The server keys records by UUID (`ON CONFLICT DO NOTHING`),
//! so a crash between the server's commit and the spool's removal never stores one twice.

use super::record::Record;
use super::schema;
use super::sql::{Db, DbError, Pg};
use super::store::{RecordsError, Saved, SqliteStore, Store};
use super::write;
use std::path::PathBuf;
use std::time::Duration;

/// How long a connection to the server may take before records wait in the spool.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(3);
/// After the server failed, saves do not try it again for this long (a line never waits on an
/// unreachable server at every unit); [`Store::forward`] tries at once.
pub const RETRY_AFTER: Duration = Duration::from_secs(10);

/// The records of a line: a PostgreSQL server, and this PC's spool for it.
pub struct LineStore {
    url: String,
    shown: String,
    client: Option<postgres::Client>,
    spool: SqliteStore,
    /// Why the server was last not written to.
    last_error: Option<RecordsError>,
    /// Saves leave the server alone until then, after it failed.
    retry_at: Option<std::time::Instant>,
}

/// The spool file for the server at `shown` (password hidden): `BOTBENCH_SPOOL` when set,
/// else `spool-<12 hex digits of the URL's SHA-256>.sqlite` in botbench's data folder, one per
/// server so that records never go to another server than the one they were meant for.
pub fn spool_path(shown: &str) -> Result<PathBuf, RecordsError> {
    if let Ok(p) = std::env::var("BOTBENCH_SPOOL")
        && !p.trim().is_empty()
    {
        return Ok(PathBuf::from(p));
    }
    let base = dirs::data_dir().ok_or_else(|| RecordsError::BadLocation {
        given: shown.into(),
        why: "this system names no data folder for the spool: set BOTBENCH_SPOOL".into(),
    })?;
    let key = super::record::sha256_hex(shown.as_bytes());
    Ok(base
        .join("botbench")
        .join(format!("spool-{}.sqlite", &key[..12])))
}

impl LineStore {
    /// The server at `url` (shown as `shown`) with its spool at [`spool_path`]. Connects at
    /// once when it can; a server that cannot be reached or refuses is remembered, not an
    /// error: records wait in the spool. Errors: the spool cannot be opened.
    pub fn open(url: &str, shown: &str) -> Result<LineStore, RecordsError> {
        Self::with_spool(url, shown, &spool_path(shown)?)
    }

    /// [`LineStore::open`] with the spool at `spool`.
    pub fn with_spool(
        url: &str,
        shown: &str,
        spool: &std::path::Path,
    ) -> Result<LineStore, RecordsError> {
        let mut store = LineStore {
            url: url.to_string(),
            shown: shown.to_string(),
            client: None,
            spool: SqliteStore::open(spool)?,
            last_error: None,
            retry_at: None,
        };
        if let Err(e) = store.connect() {
            store.failed(e);
        }
        Ok(store)
    }

    /// The spool's file.
    pub fn spool_file(&self) -> &std::path::Path {
        self.spool.path()
    }

    /// Why the server was last not written to, if it was not.
    pub fn last_error(&self) -> Option<&RecordsError> {
        self.last_error.as_ref()
    }

    /// A connection to the server with its schema at this botbench's version (created or
    /// migrated under an advisory lock, so that two stations starting together migrate once).
    fn connect(&mut self) -> Result<&mut postgres::Client, RecordsError> {
        if self.client.as_ref().is_some_and(|c| c.is_closed()) {
            self.client = None;
        }
        if self.client.is_none() {
            let place = self.shown.clone();
            let err = |e: postgres::Error| RecordsError::from_db(&place, DbError::Postgres(e));
            let mut config: postgres::Config = self.url.parse().map_err(err)?;
            config.connect_timeout(CONNECT_TIMEOUT);
            config.application_name("botbench");
            let mut client = config.connect(postgres::NoTls).map_err(err)?;
            // A record leaves the spool once its commit returns: that commit must be on the
            // server's disk, whatever the server's own default (a server with asynchronous
            // commit loses its last commits in a crash; found with the tests' throw-away
            // cluster, stopped in immediate mode).
            client
                .batch_execute("SET synchronous_commit TO on")
                .map_err(err)?;
            let mut tx = client.transaction().map_err(err)?;
            // 0x626f7462656e6368 is "botbench": one lock for every botbench migrating.
            tx.execute("SELECT pg_advisory_xact_lock(7093006206163431016)", &[])
                .map_err(err)?;
            schema::migrate(&mut Pg(&mut tx)).map_err(|e| RecordsError::from_schema(&place, e))?;
            tx.commit().map_err(err)?;
            self.client = Some(client);
        }
        match self.client.as_mut() {
            Some(c) => Ok(c),
            None => Err(RecordsError::Unreachable {
                place: self.shown.clone(),
                why: "not connected".into(),
            }),
        }
    }

    /// Remembers why the server failed; saves leave it alone for [`RETRY_AFTER`].
    fn failed(&mut self, e: RecordsError) {
        // A broken connection is opened anew next time.
        self.client = None;
        self.last_error = Some(e);
        self.retry_at = Some(std::time::Instant::now() + RETRY_AFTER);
    }

    /// Forwards the spool, oldest first; the number left. Stops at the first failure (the
    /// order is kept: nothing newer goes before an older record). Unless `now`, a server that
    /// failed less than [`RETRY_AFTER`] ago is not tried.
    fn drain(&mut self, now: bool) -> Result<u64, RecordsError> {
        if !now
            && self.retry_at.is_some_and(|t| std::time::Instant::now() < t)
            && let Some(e) = &self.last_error
        {
            return Err(e.clone());
        }
        loop {
            let Some(record) = self.spool.oldest()? else {
                self.last_error = None;
                self.retry_at = None;
                return Ok(0);
            };
            if let Err(e) = self.send(&record) {
                self.failed(e.clone());
                return Err(e);
            }
            self.spool.remove(&record.uuid)?;
        }
    }

    /// Stores `record` on the server in one transaction (nothing when its UUID is there).
    fn send(&mut self, record: &Record) -> Result<(), RecordsError> {
        let place = self.shown.clone();
        let err = |e: DbError| RecordsError::from_db(&place, e);
        let client = self.connect()?;
        let mut tx = client.transaction().map_err(|e| err(e.into()))?;
        // The commit must be on the server's disk before the spool lets the record go, even
        // where the server commits asynchronously by default.
        tx.batch_execute("SET LOCAL synchronous_commit TO on")
            .map_err(|e| err(e.into()))?;
        write::insert(&mut Pg(&mut tx), record).map_err(err)?;
        tx.commit().map_err(|e| err(e.into()))
    }
}

impl Store for LineStore {
    fn place(&self) -> String {
        self.shown.clone()
    }

    fn save(&mut self, record: &Record) -> Result<Saved, RecordsError> {
        self.spool.insert(record)?;
        match self.drain(false) {
            Ok(_) => Ok(Saved::Stored),
            Err(why) => Ok(Saved::Spooled {
                waiting: self.spool.count()?,
                why,
            }),
        }
    }

    fn waiting(&mut self) -> u64 {
        self.spool.count().unwrap_or(0)
    }

    fn spool_place(&self) -> Option<String> {
        Some(self.spool.path().display().to_string())
    }

    fn forward(&mut self) -> Result<u64, RecordsError> {
        self.drain(true)
    }

    fn last_error(&self) -> Option<RecordsError> {
        self.last_error.clone()
    }

    fn reader(&self) -> Option<super::sql::Opener> {
        let url = self.url.clone();
        Some(Box::new(move || {
            let mut config: postgres::Config = url.parse()?;
            config.connect_timeout(CONNECT_TIMEOUT);
            config.application_name("botbench report");
            let client = config.connect(postgres::NoTls)?;
            Ok(Box::new(super::sql::OwnedPg(client)) as Box<dyn Db + Send>)
        }))
    }

    fn read(
        &mut self,
        f: &mut dyn FnMut(&mut dyn Db) -> Result<(), DbError>,
    ) -> Result<(), RecordsError> {
        let place = self.shown.clone();
        let client = match self.connect() {
            Ok(c) => c,
            Err(e) => {
                self.failed(e.clone());
                return Err(e);
            }
        };
        let out = f(&mut Pg(client)).map_err(|e| RecordsError::from_db(&place, e));
        if out.is_err() && self.client.as_ref().is_some_and(|c| c.is_closed()) {
            self.client = None;
        }
        out
    }
}
