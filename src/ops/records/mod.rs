//! Production records: one record per unit run, the same for every device kind and plan
//! ([`Record`]: the run, the unit, each step with its measurements and parameter writes), kept
//! in a [`Store`] (a SQLite file per PC by default, or a line-wide PostgreSQL server behind a
//! local spool), and read back as a unit's history, lists, exports and the yield [`report`].
//!
//! - [`record`]: the schema as Rust types; [`schema`]: the tables and their migrations.
//! - [`store`]: [`Location`] (`--records FILE|postgres://...`), the [`Store`] trait,
//!   [`SqliteStore`], the errors; [`line`]: [`LineStore`], PostgreSQL behind its spool.
//! - [`recorder`]: [`Recorder::save`], the one way a run's record is kept (with its fallback).
//! - [`query`]: filters, a unit's history, the list, the exports; [`report`]: yield, Pareto,
//!   histograms with Cpk, drift, and the HTML page.
//! - [`sql`]: one way to run SQL on both databases; [`write`]: a record into the tables and back.
//!
//! The run-then-record operations that use it are with the operations themselves:
//! `ops::selftest::run_recorded`, `ops::servo::provision::provision_recorded`,
//! `ops::preset::apply_recorded`.

pub mod demo;
pub mod line;
pub mod query;
pub mod record;
pub mod recorder;
pub mod report;
pub mod runs;
pub mod schema;
pub mod sql;
pub mod store;
pub mod write;

pub use line::LineStore;
pub use query::{Filter, History};
pub use record::{
    Measurement, ParamWrite, Record, RunContext, RunKind, SerialSource, StepClock, StepRecord,
    Unit, Verdict,
};
pub use recorder::{Keeper, Kept, Recorder};
pub use store::{Location, RecordsError, Saved, SqliteStore, Store};
