//! Typed access to a pass's `params` table in a pipeline file.

use crate::error::{GraphError, Result};

/// A pass's parameters. Getters take a default so every parameter is optional in files;
/// a value of the wrong type is an error naming the key and the type wanted.
#[derive(Clone, Debug, Default)]
pub struct Params {
    table: toml::Table,
}

impl Params {
    pub fn new(table: toml::Table) -> Self {
        Self { table }
    }

    fn err(key: &str, wanted: &str, got: &toml::Value) -> GraphError {
        GraphError::Parameter {
            pass: String::new(),
            message: format!("`{key}` must be {wanted}, not `{got}`"),
        }
    }

    pub fn u64(&self, key: &str, default: u64) -> Result<u64> {
        match self.table.get(key) {
            None => Ok(default),
            Some(toml::Value::Integer(i)) if *i >= 0 => Ok(*i as u64),
            Some(v) => Err(Self::err(key, "a non-negative integer", v)),
        }
    }
    pub fn u32(&self, key: &str, default: u32) -> Result<u32> {
        let v = self.u64(key, default as u64)?;
        u32::try_from(v).map_err(|_| GraphError::Parameter {
            pass: String::new(),
            message: format!("`{key}` = {v} does not fit in 32 bits"),
        })
    }
    pub fn bool(&self, key: &str, default: bool) -> Result<bool> {
        match self.table.get(key) {
            None => Ok(default),
            Some(toml::Value::Boolean(b)) => Ok(*b),
            Some(v) => Err(Self::err(key, "true or false", v)),
        }
    }
    pub fn string(&self, key: &str, default: &str) -> Result<String> {
        match self.table.get(key) {
            None => Ok(default.to_string()),
            Some(toml::Value::String(s)) => Ok(s.clone()),
            Some(v) => Err(Self::err(key, "a string", v)),
        }
    }
    /// Keys present, to let factories reject unknown parameters.
    pub fn keys(&self) -> impl Iterator<Item = &str> {
        self.table.keys().map(String::as_str)
    }
    /// Fails if any key is not in `known`: a misspelt parameter should not be ignored.
    pub fn only(&self, known: &[&str]) -> Result<()> {
        match self.keys().find(|k| !known.contains(k)) {
            Some(k) => Err(GraphError::Parameter {
                pass: String::new(),
                message: format!("unknown parameter `{k}`; known: {}", known.join(", ")),
            }),
            None => Ok(()),
        }
    }
}
