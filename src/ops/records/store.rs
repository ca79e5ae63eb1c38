//! Where records are kept: [`Location`] (a SQLite file or a `postgres://` URL), the [`Store`]
//! trait, and its two kinds: [`SqliteStore`] (one file per PC, WAL, one transaction per record)
//! and [`LineStore`] (a line-wide PostgreSQL server, every record first kept in a local SQLite
//! spool and forwarded in order, exactly once).

use super::record::Record;
use super::schema::{self, SCHEMA_VERSION, SchemaError};
use super::sql::{Db, DbError, Lite};
use super::write;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Where records go: `--records FILE|postgres://...`, `BOTBENCH_RECORDS`, the window's setting.
#[derive(Debug, Clone, PartialEq)]
pub enum Location {
    /// A SQLite database file.
    Sqlite(PathBuf),
    /// A PostgreSQL server: the URL as given, and the same with its password hidden.
    Postgres {
        /// The URL as given (`postgres://user:secret@host:5432/line`).
        url: String,
        /// The URL as shown and logged (`postgres://user:***@host:5432/line`).
        shown: String,
    },
}

impl Location {
    /// Reads `--records`: a `postgres://` or `postgresql://` URL (checked whole: a malformed
    /// one is refused here, naming what is wrong), or else a file path (`sqlite:` before it is
    /// allowed). An empty value is refused.
    pub fn parse(given: &str) -> Result<Location, RecordsError> {
        let given = given.trim();
        if given.is_empty() {
            return Err(RecordsError::BadLocation {
                given: given.into(),
                why: "it is empty: give a file or a postgres:// URL".into(),
            });
        }
        let lower = given.to_ascii_lowercase();
        if lower.starts_with("postgres://") || lower.starts_with("postgresql://") {
            let shown = hide_password(given);
            let config: postgres::Config =
                given
                    .parse()
                    .map_err(|e: postgres::Error| RecordsError::BadLocation {
                        given: shown.clone(),
                        why: format!("not a PostgreSQL URL: {e}"),
                    })?;
            if config.get_hosts().is_empty() {
                return Err(RecordsError::BadLocation {
                    given: shown,
                    why: "it names no host (postgres://USER@HOST/DATABASE)".into(),
                });
            }
            return Ok(Location::Postgres {
                url: given.to_string(),
                shown,
            });
        }
        if lower.contains("://") {
            return Err(RecordsError::BadLocation {
                given: hide_password(given),
                why: "records go to a file or a postgres:// URL; this is neither".into(),
            });
        }
        let path = given.strip_prefix("sqlite:").unwrap_or(given);
        Ok(Location::Sqlite(PathBuf::from(path)))
    }

    /// The default: `BOTBENCH_RECORDS` when set, else `records.sqlite` in the user's data
    /// folder (`~/.local/share/botbench/` on Linux, `%APPDATA%\botbench\` on Windows).
    pub fn default_location() -> Result<Location, RecordsError> {
        if let Ok(v) = std::env::var("BOTBENCH_RECORDS")
            && !v.trim().is_empty()
        {
            return Location::parse(&v);
        }
        Ok(Location::Sqlite(data_folder()?.join("records.sqlite")))
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Sqlite(p) => write!(f, "{}", p.display()),
            Location::Postgres { shown, .. } => f.write_str(shown),
        }
    }
}

/// botbench's folder in the user's data folder (created when missing).
fn data_folder() -> Result<PathBuf, RecordsError> {
    let base = dirs::data_dir().ok_or_else(|| RecordsError::BadLocation {
        given: "the default records file".into(),
        why: "this system names no data folder for the user: give --records FILE".into(),
    })?;
    Ok(base.join("botbench"))
}

/// `postgres://user:secret@host/db` as `postgres://user:***@host/db`.
fn hide_password(url: &str) -> String {
    let Some(scheme_end) = url.find("://") else {
        return url.to_string();
    };
    let rest = &url[scheme_end + 3..];
    let auth_end = rest.find(['/', '?']).unwrap_or(rest.len());
    let Some(at) = rest[..auth_end].rfind('@') else {
        return url.to_string();
    };
    match rest[..at].find(':') {
        Some(colon) => format!(
            "{}{}:***{}",
            &url[..scheme_end + 3],
            &rest[..colon],
            &rest[at..]
        ),
        None => url.to_string(),
    }
}

/// What went wrong with the records, each naming the file or server.
#[derive(Debug, Clone, PartialEq)]
pub enum RecordsError {
    /// `--records` is neither a file nor a well-formed `postgres://` URL.
    BadLocation {
        /// What was given (password hidden).
        given: String,
        /// What is wrong with it.
        why: String,
    },
    /// The file is not a SQLite database at all.
    NotDatabase {
        /// The file.
        place: String,
    },
    /// The database has tables of its own and no botbench schema.
    NotBotbench {
        /// The file or server.
        place: String,
        /// Some of its tables.
        tables: Vec<String>,
    },
    /// Written by a newer botbench.
    NewerSchema {
        /// The file or server.
        place: String,
        /// Its schema version.
        found: i64,
    },
    /// The server cannot be reached (refused, no route, timed out, went away).
    Unreachable {
        /// The server.
        place: String,
        /// What the connection said.
        why: String,
    },
    /// The server refused the login (wrong user or password, no access to the database).
    LoginRefused {
        /// The server.
        place: String,
        /// What it said.
        why: String,
    },
    /// The disk (or the server's) is full.
    DiskFull {
        /// The file or server.
        place: String,
    },
    /// Anything else the database said.
    Database {
        /// The file or server.
        place: String,
        /// What it said.
        why: String,
    },
}

impl fmt::Display for RecordsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RecordsError::BadLocation { given, why } => {
                write!(f, "records location '{given}': {why}")
            }
            RecordsError::NotDatabase { place } => write!(
                f,
                "{place} is not a SQLite database (not a botbench records file): name another file with --records"
            ),
            RecordsError::NotBotbench { place, tables } => write!(
                f,
                "{place} is not a botbench records database: it holds other tables ({}) and no botbench_schema; name another file or database with --records",
                tables.join(", ")
            ),
            RecordsError::NewerSchema { place, found } => write!(
                f,
                "{place} holds records of schema version {found}, written by a newer botbench; this one knows up to version {SCHEMA_VERSION}: update botbench on this PC"
            ),
            RecordsError::Unreachable { place, why } => {
                write!(f, "the records server {place} cannot be reached: {why}")
            }
            RecordsError::LoginRefused { place, why } => write!(
                f,
                "the records server {place} refused the login: {why} (check the user and password in the URL)"
            ),
            RecordsError::DiskFull { place } => {
                write!(
                    f,
                    "{place}: the disk is full; the record could not be written there"
                )
            }
            RecordsError::Database { place, why } => write!(f, "{place}: {why}"),
        }
    }
}

impl std::error::Error for RecordsError {}

impl RecordsError {
    /// The error for `e` at `place`, said for what it means to a record.
    pub fn from_db(place: &str, e: DbError) -> RecordsError {
        let place = place.to_string();
        match &e {
            DbError::Sqlite(rusqlite::Error::SqliteFailure(f, _)) => match f.code {
                rusqlite::ErrorCode::NotADatabase => RecordsError::NotDatabase { place },
                rusqlite::ErrorCode::DiskFull => RecordsError::DiskFull { place },
                _ => RecordsError::Database {
                    place,
                    why: e.to_string(),
                },
            },
            DbError::Postgres(pe) => {
                use postgres::error::SqlState;
                match pe.code() {
                    Some(c)
                        if *c == SqlState::INVALID_PASSWORD
                            || *c == SqlState::INVALID_AUTHORIZATION_SPECIFICATION
                            || *c == SqlState::INVALID_CATALOG_NAME =>
                    {
                        RecordsError::LoginRefused {
                            place,
                            why: e.to_string(),
                        }
                    }
                    Some(c) if *c == SqlState::DISK_FULL => RecordsError::DiskFull { place },
                    Some(c) if c.code().starts_with("08") || c.code().starts_with("57P") => {
                        RecordsError::Unreachable {
                            place,
                            why: e.to_string(),
                        }
                    }
                    Some(_) => RecordsError::Database {
                        place,
                        why: e.to_string(),
                    },
                    // No SQL state: the connection itself (refused, closed, timed out).
                    None => RecordsError::Unreachable {
                        place,
                        why: e.to_string(),
                    },
                }
            }
            _ => RecordsError::Database {
                place,
                why: e.to_string(),
            },
        }
    }

    pub(super) fn from_schema(place: &str, e: SchemaError) -> RecordsError {
        match e {
            SchemaError::NotBotbench { tables } => RecordsError::NotBotbench {
                place: place.into(),
                tables,
            },
            SchemaError::Newer { found } => RecordsError::NewerSchema {
                place: place.into(),
                found,
            },
            SchemaError::Db(e) => RecordsError::from_db(place, e),
        }
    }

    /// Whether the error may pass by itself (a server away, a refused login put right, a full
    /// disk cleared): records wait in the spool for it.
    pub fn is_transient(&self) -> bool {
        !matches!(self, RecordsError::BadLocation { .. })
    }
}

/// How a record was saved.
#[derive(Debug, Clone, PartialEq)]
pub enum Saved {
    /// In its store, committed.
    Stored,
    /// Kept in the local spool, waiting for the server: `waiting` records wait in all, and why.
    Spooled {
        /// Records waiting, this one included.
        waiting: u64,
        /// Why they wait.
        why: RecordsError,
    },
}

/// A place that keeps records. One record is one transaction: stored whole or not at all.
pub trait Store: Send {
    /// The file or server, as said in messages.
    fn place(&self) -> String;
    /// Saves `record` (and first forwards what waits in the spool, in order; a server that
    /// failed lately is not tried again for a while, so that a line does not wait on it each
    /// unit). An `Err` means it is kept nowhere: the caller keeps it ([`super::Recorder`]
    /// falls back to a spool of its own).
    fn save(&mut self, record: &Record) -> Result<Saved, RecordsError>;
    /// Records waiting in the spool for the server (0 for a local file).
    fn waiting(&mut self) -> u64;
    /// The spool's file, for a store that has one.
    fn spool_place(&self) -> Option<String> {
        None
    }
    /// Why the server was last not written to (a store with a spool), if it was not.
    fn last_error(&self) -> Option<RecordsError> {
        None
    }
    /// A second connection for reading beside [`Store::read`] (the report's yields), if the
    /// store can open one.
    fn reader(&self) -> Option<super::sql::Opener> {
        None
    }
    /// Forwards what waits in the spool now (the server tried even if it failed lately); the
    /// number still waiting.
    fn forward(&mut self) -> Result<u64, RecordsError>;
    /// Runs `f` on the database the records are read from (the server, for a line store).
    fn read(
        &mut self,
        f: &mut dyn FnMut(&mut dyn Db) -> Result<(), DbError>,
    ) -> Result<(), RecordsError>;
}

/// Opens the store at `location`: a SQLite file (created, or migrated, on first use), or a
/// PostgreSQL server behind its spool. Errors: a SQLite file that is not botbench's, of a newer
/// schema, or cannot be created. A server that cannot be reached is not an error here: records
/// wait in the spool until it is back.
pub fn open(location: &Location) -> Result<Box<dyn Store>, RecordsError> {
    open_spooled(location, None)
}

/// [`open`], a line server's spool at `spool` when given (`--spool`), else where
/// [`super::line::spool_path`] says. A SQLite file has no spool: `spool` is not used.
pub fn open_spooled(
    location: &Location,
    spool: Option<&Path>,
) -> Result<Box<dyn Store>, RecordsError> {
    match (location, spool) {
        (Location::Sqlite(path), _) => Ok(Box::new(SqliteStore::open(path)?)),
        (Location::Postgres { url, shown }, Some(spool)) => {
            Ok(Box::new(super::LineStore::with_spool(url, shown, spool)?))
        }
        (Location::Postgres { url, shown }, None) => {
            Ok(Box::new(super::LineStore::open(url, shown)?))
        }
    }
}

/// The records in one SQLite file.
pub struct SqliteStore {
    path: PathBuf,
    conn: rusqlite::Connection,
}

impl SqliteStore {
    /// Opens (creating it and its folder if missing) the SQLite records file at `path`, in WAL
    /// mode with full sync, and brings its schema to this botbench's version.
    pub fn open(path: &Path) -> Result<SqliteStore, RecordsError> {
        let place = path.display().to_string();
        if path.is_dir() {
            return Err(RecordsError::BadLocation {
                given: place,
                why: "it is a folder; name a file in it".into(),
            });
        }
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(|e| RecordsError::Database {
                place: place.clone(),
                why: format!("cannot create its folder: {e}"),
            })?;
        }
        let err = |e: rusqlite::Error| RecordsError::from_db(&place, DbError::Sqlite(e));
        let mut conn = rusqlite::Connection::open(path).map_err(err)?;
        conn.busy_timeout(Duration::from_secs(10)).map_err(err)?;
        // The first read of the file: a file that is not SQLite fails here.
        let mode: String = conn
            .query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0))
            .map_err(err)?;
        if !mode.eq_ignore_ascii_case("wal") {
            return Err(RecordsError::Database {
                place,
                why: format!("cannot switch it to WAL mode (it stays in {mode})"),
            });
        }
        conn.execute_batch(
            "PRAGMA synchronous = FULL; PRAGMA foreign_keys = ON; PRAGMA temp_store = MEMORY; \
             PRAGMA cache_size = -65536;",
        )
        .map_err(err)?;
        let tx = conn
            .transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)
            .map_err(err)?;
        schema::migrate(&mut Lite(&tx)).map_err(|e| RecordsError::from_schema(&place, e))?;
        tx.commit().map_err(err)?;
        Ok(SqliteStore {
            path: path.to_path_buf(),
            conn,
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Limits the file to `pages` pages (of 4 KiB): what a full disk does, for tests of it.
    pub fn limit_pages(&mut self, pages: u64) -> Result<(), RecordsError> {
        self.conn
            .query_row(&format!("PRAGMA max_page_count = {pages}"), [], |_| Ok(()))
            .map_err(|e| RecordsError::from_db(&self.place(), DbError::Sqlite(e)))
    }

    /// Saves `record` in one transaction; `false` when one with its UUID was already there.
    pub fn insert(&mut self, record: &Record) -> Result<bool, RecordsError> {
        let place = self.place();
        let err = |e: DbError| RecordsError::from_db(&place, e);
        let tx = self
            .conn
            .transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)
            .map_err(|e| err(e.into()))?;
        let new = write::insert(&mut Lite(&tx), record).map_err(err)?;
        tx.commit().map_err(|e| err(e.into()))?;
        Ok(new)
    }

    /// The number of records stored.
    pub fn count(&mut self) -> Result<u64, RecordsError> {
        self.conn
            .query_row("SELECT COUNT(*) FROM runs", [], |r| r.get::<_, i64>(0))
            .map(|n| n.max(0) as u64)
            .map_err(|e| RecordsError::from_db(&self.place(), DbError::Sqlite(e)))
    }

    /// The oldest record stored (the spool's next to forward).
    pub fn oldest(&mut self) -> Result<Option<Record>, RecordsError> {
        let mut found = None;
        let place = self.place();
        write::load_each(
            &mut Lite(&self.conn),
            "id = (SELECT MIN(id) FROM runs)",
            &[],
            None,
            &mut |r| {
                found = Some(r);
                Ok(())
            },
        )
        .map_err(|e| RecordsError::from_db(&place, e))?;
        Ok(found)
    }

    /// Removes the record `uuid` whole (its steps, measurements and writes with it).
    pub fn remove(&mut self, uuid: &str) -> Result<(), RecordsError> {
        self.conn
            .execute("DELETE FROM runs WHERE uuid = ?1", [uuid])
            .map(|_| ())
            .map_err(|e| RecordsError::from_db(&self.place(), DbError::Sqlite(e)))
    }

    /// The connection, for bulk work (the bench's generator).
    pub fn connection(&mut self) -> &mut rusqlite::Connection {
        &mut self.conn
    }
}

impl Store for SqliteStore {
    fn place(&self) -> String {
        self.path.display().to_string()
    }

    fn save(&mut self, record: &Record) -> Result<Saved, RecordsError> {
        self.insert(record)?;
        Ok(Saved::Stored)
    }

    fn waiting(&mut self) -> u64 {
        0
    }

    fn forward(&mut self) -> Result<u64, RecordsError> {
        Ok(0)
    }

    fn reader(&self) -> Option<super::sql::Opener> {
        let path = self.path.clone();
        Some(Box::new(move || {
            let conn = rusqlite::Connection::open_with_flags(
                &path,
                rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY,
            )?;
            conn.busy_timeout(Duration::from_secs(10))?;
            conn.execute_batch("PRAGMA temp_store = MEMORY; PRAGMA cache_size = -65536;")?;
            Ok(Box::new(super::sql::OwnedLite(conn)) as Box<dyn Db + Send>)
        }))
    }

    fn read(
        &mut self,
        f: &mut dyn FnMut(&mut dyn Db) -> Result<(), DbError>,
    ) -> Result<(), RecordsError> {
        let place = self.place();
        f(&mut Lite(&self.conn)).map_err(|e| RecordsError::from_db(&place, e))
    }
}
