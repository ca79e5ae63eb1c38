//! One way to run SQL on SQLite (rusqlite) and PostgreSQL (the `postgres` crate), so that the
//! records' writes, reads and report queries are written once: statements use `?1`, `?2` and
//! are given to PostgreSQL as `$1`, `$2`; values are [`Val`]s; every integer column is 64-bit
//! and every real one double precision in both.

use std::fmt;

/// A value bound to, or read from, a statement. Nulls carry their type (PostgreSQL types
/// parameters by the statement, and a null must still be of the column's type).
#[derive(Debug, Clone, PartialEq)]
pub enum Val {
    /// A 64-bit integer, or a null integer.
    Int(Option<i64>),
    /// A double, or a null double.
    Real(Option<f64>),
    /// Text, or a null text.
    Text(Option<String>),
}

impl Val {
    /// The value as an integer (a real truncated); `None` for null or text.
    pub fn int(&self) -> Option<i64> {
        match self {
            Val::Int(v) => *v,
            Val::Real(v) => v.map(|x| x as i64),
            Val::Text(_) => None,
        }
    }

    /// The value as a double; `None` for null or text.
    pub fn real(&self) -> Option<f64> {
        match self {
            Val::Int(v) => v.map(|x| x as f64),
            Val::Real(v) => *v,
            Val::Text(_) => None,
        }
    }

    /// The value as text (numbers printed); `None` for null.
    pub fn text(&self) -> Option<String> {
        match self {
            Val::Int(v) => v.map(|x| x.to_string()),
            Val::Real(v) => v.map(|x| x.to_string()),
            Val::Text(v) => v.clone(),
        }
    }

    /// Text, null when `None`.
    pub fn opt_text(v: &Option<String>) -> Val {
        Val::Text(v.clone())
    }

    /// Text, never null.
    pub fn text_of(v: &str) -> Val {
        Val::Text(Some(v.to_string()))
    }
}

/// Which SQL the database speaks, where the two differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dialect {
    /// SQLite 3.4x (bundled with rusqlite).
    Sqlite,
    /// PostgreSQL 12 or newer.
    Postgres,
}

impl Dialect {
    /// `floor(expr)` as a 64-bit integer, for `expr >= 0` (SQLite's CAST truncates, which is
    /// the floor there; PostgreSQL's rounds).
    pub fn floor(self, expr: &str) -> String {
        match self {
            Dialect::Sqlite => format!("CAST({expr} AS INTEGER)"),
            Dialect::Postgres => format!("CAST(FLOOR({expr}) AS BIGINT)"),
        }
    }

    /// The statement with `?N` placeholders as this database wants them.
    pub fn placeholders(self, sql: &str) -> String {
        match self {
            Dialect::Sqlite => sql.to_string(),
            Dialect::Postgres => {
                let mut out = String::with_capacity(sql.len());
                let mut chars = sql.chars().peekable();
                while let Some(c) = chars.next() {
                    if c == '?' && chars.peek().is_some_and(|n| n.is_ascii_digit()) {
                        out.push('$');
                    } else {
                        out.push(c);
                    }
                }
                out
            }
        }
    }
}

/// An error of the database itself (the records' errors say what it means for a record).
#[derive(Debug)]
pub enum DbError {
    /// From SQLite.
    Sqlite(rusqlite::Error),
    /// From PostgreSQL or the connection to it.
    Postgres(postgres::Error),
    /// A column of a type the records never use.
    Shape(String),
}

impl fmt::Display for DbError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DbError::Sqlite(e) => write!(f, "{e}"),
            DbError::Postgres(e) => match e.as_db_error() {
                Some(db) => write!(f, "{} ({})", db.message(), db.code().code()),
                None => write!(f, "{e}"),
            },
            DbError::Shape(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for DbError {}

impl From<rusqlite::Error> for DbError {
    fn from(e: rusqlite::Error) -> Self {
        DbError::Sqlite(e)
    }
}

impl From<postgres::Error> for DbError {
    fn from(e: postgres::Error) -> Self {
        DbError::Postgres(e)
    }
}

/// A database connection or transaction that runs statements.
pub trait Db {
    /// Which SQL it speaks.
    fn dialect(&self) -> Dialect;
    /// Runs a statement; the number of rows it changed.
    fn exec(&mut self, sql: &str, params: &[Val]) -> Result<u64, DbError>;
    /// Runs a query; its rows, each a value per column.
    fn rows(&mut self, sql: &str, params: &[Val]) -> Result<Vec<Vec<Val>>, DbError>;
    /// Runs a query, handing each row to `each` as it comes (an export of many records).
    fn each_row(
        &mut self,
        sql: &str,
        params: &[Val],
        each: &mut dyn FnMut(Vec<Val>) -> Result<(), DbError>,
    ) -> Result<(), DbError>;
}

fn sqlite_params(params: &[Val]) -> Vec<&dyn rusqlite::ToSql> {
    params
        .iter()
        .map(|p| -> &dyn rusqlite::ToSql {
            match p {
                Val::Int(v) => v,
                Val::Real(v) => v,
                Val::Text(v) => v,
            }
        })
        .collect()
}

fn sqlite_row(row: &rusqlite::Row<'_>, n: usize) -> Result<Vec<Val>, rusqlite::Error> {
    use rusqlite::types::ValueRef;
    (0..n)
        .map(|i| {
            Ok(match row.get_ref(i)? {
                ValueRef::Null => Val::Int(None),
                ValueRef::Integer(v) => Val::Int(Some(v)),
                ValueRef::Real(v) => Val::Real(Some(v)),
                ValueRef::Text(t) => Val::Text(Some(String::from_utf8_lossy(t).into_owned())),
                ValueRef::Blob(b) => Val::Text(Some(String::from_utf8_lossy(b).into_owned())),
            })
        })
        .collect()
}

/// A SQLite connection (or a transaction, through its `Deref`) as a [`Db`].
pub struct Lite<'a>(pub &'a rusqlite::Connection);

impl Db for Lite<'_> {
    fn dialect(&self) -> Dialect {
        Dialect::Sqlite
    }

    fn exec(&mut self, sql: &str, params: &[Val]) -> Result<u64, DbError> {
        let mut stmt = self.0.prepare_cached(sql)?;
        Ok(stmt.execute(sqlite_params(params).as_slice())? as u64)
    }

    fn rows(&mut self, sql: &str, params: &[Val]) -> Result<Vec<Vec<Val>>, DbError> {
        let mut out = Vec::new();
        self.each_row(sql, params, &mut |r| {
            out.push(r);
            Ok(())
        })?;
        Ok(out)
    }

    fn each_row(
        &mut self,
        sql: &str,
        params: &[Val],
        each: &mut dyn FnMut(Vec<Val>) -> Result<(), DbError>,
    ) -> Result<(), DbError> {
        let mut stmt = self.0.prepare_cached(sql)?;
        let n = stmt.column_count();
        let mut rows = stmt.query(sqlite_params(params).as_slice())?;
        while let Some(row) = rows.next()? {
            each(sqlite_row(row, n)?)?;
        }
        Ok(())
    }
}

/// A PostgreSQL client or transaction as a [`Db`].
pub struct Pg<'a, C: postgres::GenericClient>(pub &'a mut C);

fn pg_params(params: &[Val]) -> Vec<&(dyn postgres::types::ToSql + Sync)> {
    params
        .iter()
        .map(|p| -> &(dyn postgres::types::ToSql + Sync) {
            match p {
                Val::Int(v) => v,
                Val::Real(v) => v,
                Val::Text(v) => v,
            }
        })
        .collect()
}

fn pg_row(row: &postgres::Row) -> Result<Vec<Val>, DbError> {
    use postgres::types::Type;
    let mut out = Vec::with_capacity(row.len());
    for (i, col) in row.columns().iter().enumerate() {
        let t = col.type_();
        let v = if *t == Type::INT8 {
            Val::Int(row.try_get::<_, Option<i64>>(i)?)
        } else if *t == Type::INT4 {
            Val::Int(row.try_get::<_, Option<i32>>(i)?.map(i64::from))
        } else if *t == Type::INT2 {
            Val::Int(row.try_get::<_, Option<i16>>(i)?.map(i64::from))
        } else if *t == Type::FLOAT8 {
            Val::Real(row.try_get::<_, Option<f64>>(i)?)
        } else if *t == Type::FLOAT4 {
            Val::Real(row.try_get::<_, Option<f32>>(i)?.map(f64::from))
        } else if *t == Type::BOOL {
            Val::Int(row.try_get::<_, Option<bool>>(i)?.map(i64::from))
        } else if [Type::TEXT, Type::VARCHAR, Type::BPCHAR, Type::NAME].contains(t) {
            Val::Text(row.try_get::<_, Option<String>>(i)?)
        } else {
            return Err(DbError::Shape(format!(
                "column {} is of type {t}, which the records do not use",
                col.name()
            )));
        };
        out.push(v);
    }
    Ok(out)
}

impl<C: postgres::GenericClient> Db for Pg<'_, C> {
    fn dialect(&self) -> Dialect {
        Dialect::Postgres
    }

    fn exec(&mut self, sql: &str, params: &[Val]) -> Result<u64, DbError> {
        let sql = Dialect::Postgres.placeholders(sql);
        Ok(self.0.execute(sql.as_str(), &pg_params(params))?)
    }

    fn rows(&mut self, sql: &str, params: &[Val]) -> Result<Vec<Vec<Val>>, DbError> {
        let sql = Dialect::Postgres.placeholders(sql);
        self.0
            .query(sql.as_str(), &pg_params(params))?
            .iter()
            .map(pg_row)
            .collect()
    }

    fn each_row(
        &mut self,
        sql: &str,
        params: &[Val],
        each: &mut dyn FnMut(Vec<Val>) -> Result<(), DbError>,
    ) -> Result<(), DbError> {
        use postgres::fallible_iterator::FallibleIterator;
        let sql = Dialect::Postgres.placeholders(sql);
        let params = pg_params(params);
        let mut it = self.0.query_raw(
            sql.as_str(),
            params.iter().map(|p| *p as &dyn postgres::types::ToSql),
        )?;
        while let Some(row) = it.next()? {
            each(pg_row(&row)?)?;
        }
        Ok(())
    }
}

/// A SQLite connection of its own, as a [`Db`] another thread can take.
pub struct OwnedLite(pub rusqlite::Connection);

impl Db for OwnedLite {
    fn dialect(&self) -> Dialect {
        Dialect::Sqlite
    }
    fn exec(&mut self, sql: &str, params: &[Val]) -> Result<u64, DbError> {
        Lite(&self.0).exec(sql, params)
    }
    fn rows(&mut self, sql: &str, params: &[Val]) -> Result<Vec<Vec<Val>>, DbError> {
        Lite(&self.0).rows(sql, params)
    }
    fn each_row(
        &mut self,
        sql: &str,
        params: &[Val],
        each: &mut dyn FnMut(Vec<Val>) -> Result<(), DbError>,
    ) -> Result<(), DbError> {
        Lite(&self.0).each_row(sql, params, each)
    }
}

/// A PostgreSQL client of its own, as a [`Db`] another thread can take.
pub struct OwnedPg(pub postgres::Client);

impl Db for OwnedPg {
    fn dialect(&self) -> Dialect {
        Dialect::Postgres
    }
    fn exec(&mut self, sql: &str, params: &[Val]) -> Result<u64, DbError> {
        Pg(&mut self.0).exec(sql, params)
    }
    fn rows(&mut self, sql: &str, params: &[Val]) -> Result<Vec<Vec<Val>>, DbError> {
        Pg(&mut self.0).rows(sql, params)
    }
    fn each_row(
        &mut self,
        sql: &str,
        params: &[Val],
        each: &mut dyn FnMut(Vec<Val>) -> Result<(), DbError>,
    ) -> Result<(), DbError> {
        Pg(&mut self.0).each_row(sql, params, each)
    }
}

/// Opens a second connection to the same records, on the thread that uses it: the report
/// computes its yields there beside the rest.
pub type Opener = Box<dyn FnOnce() -> Result<Box<dyn Db + Send>, DbError> + Send>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_become_dollars_for_postgres_only() {
        let sql = "SELECT a FROM t WHERE b = ?1 AND c > ?12 AND d = '?'";
        assert_eq!(Dialect::Sqlite.placeholders(sql), sql);
        assert_eq!(
            Dialect::Postgres.placeholders(sql),
            "SELECT a FROM t WHERE b = $1 AND c > $12 AND d = '?'"
        );
    }
}
