//! Typed access to a pass's `params` table in a pipeline file.

use crate::choice::AUTO;
use crate::error::{GraphError, Result};

/// A pass's parameters. Getters take a default so every parameter is optional in files;
/// a value of the wrong type is an error naming the key and the type wanted.
#[derive(Clone, Debug, Default)]
pub struct Params {
    table: toml::Table,
}

impl Params {
    /// A pass's `params` table from a pipeline file.
    pub fn new(table: toml::Table) -> Self {
        Self { table }
    }

    fn err(key: &str, wanted: &str, got: &toml::Value) -> GraphError {
        GraphError::parameter(format!("`{key}` must be {wanted}, not `{got}`"))
    }

    /// The integer at `key`, or `default` when the table lacks it; an error names the key and
    /// what it holds.
    pub fn u64(&self, key: &str, default: u64) -> Result<u64> {
        match self.table.get(key) {
            None => Ok(default),
            Some(toml::Value::Integer(i)) if *i >= 0 => Ok(*i as u64),
            Some(v) => Err(Self::err(key, "a non-negative integer", v)),
        }
    }
    /// [`Params::u64`] that must fit in 32 bits.
    pub fn u32(&self, key: &str, default: u32) -> Result<u32> {
        let v = self.u64(key, default as u64)?;
        u32::try_from(v)
            .map_err(|_| GraphError::parameter(format!("`{key}` = {v} does not fit in 32 bits")))
    }
    /// `width` and `height`, both required and above 0: the size of what the pass
    /// draws into, which `what` names in the error (e.g. "the visibility buffer").
    pub fn size(&self, what: &str) -> Result<[u32; 2]> {
        let width = self.u32("width", 0)?;
        let height = self.u32("height", 0)?;
        Self::positive_size(width, height, &format!("{what}'s size"))
    }
    /// `[width, height]` when both are > 0, else the parameter error a pass's `width` and
    /// `height` give, `size` saying what they measure; for passes built in code too.
    pub fn positive_size(width: u32, height: u32, size: &str) -> Result<[u32; 2]> {
        if width == 0 || height == 0 {
            return Err(GraphError::parameter(format!(
                "`width` and `height` ({size}) must both be > 0, got {width} × {height}"
            )));
        }
        Ok([width, height])
    }
    /// The boolean at `key`, or `default` when the table lacks it.
    pub fn bool(&self, key: &str, default: bool) -> Result<bool> {
        match self.table.get(key) {
            None => Ok(default),
            Some(toml::Value::Boolean(b)) => Ok(*b),
            Some(v) => Err(Self::err(key, "true or false", v)),
        }
    }
    /// A finite number, written as an integer or a float (`far = 500` and `= 500.0`).
    pub fn f32(&self, key: &str, default: f32) -> Result<f32> {
        match self.table.get(key) {
            None => Ok(default),
            Some(v) => Self::finite(v).ok_or_else(|| Self::err(key, "a finite number", v)),
        }
    }
    /// `N` finite numbers, written as a TOML array (`light_color = [1.0, 0.9, 0.8]`).
    pub fn f32_array<const N: usize>(&self, key: &str, default: [f32; N]) -> Result<[f32; N]> {
        let Some(v) = self.table.get(key) else {
            return Ok(default);
        };
        let count = match N {
            2 => "two".to_string(),
            3 => "three".to_string(),
            4 => "four".to_string(),
            n => n.to_string(),
        };
        let wanted = || Self::err(key, &format!("an array of {count} finite numbers"), v);
        let toml::Value::Array(items) = v else {
            return Err(wanted());
        };
        let numbers: Option<Vec<f32>> = items.iter().map(Self::finite).collect();
        numbers
            .and_then(|n| <[f32; N]>::try_from(n).ok())
            .ok_or_else(wanted)
    }
    fn finite(v: &toml::Value) -> Option<f32> {
        let x = match v {
            toml::Value::Integer(i) => *i as f32,
            toml::Value::Float(f) => *f as f32,
            _ => return None,
        };
        x.is_finite().then_some(x)
    }
    /// A finite number, or `"auto"` (`None`): a value the pass resolves itself, from the
    /// adapter's class. `default` when the table lacks the key.
    pub fn f32_or_auto(&self, key: &str, default: Option<f32>) -> Result<Option<f32>> {
        match self.table.get(key) {
            None => Ok(default),
            Some(toml::Value::String(s)) if s == AUTO => Ok(None),
            Some(v) => Self::finite(v)
                .map(Some)
                .ok_or_else(|| Self::err(key, "a finite number or \"auto\"", v)),
        }
    }
    /// `true`, `false` or `"auto"` (`None`), as [`Self::f32_or_auto`].
    pub fn bool_or_auto(&self, key: &str, default: Option<bool>) -> Result<Option<bool>> {
        match self.table.get(key) {
            None => Ok(default),
            Some(toml::Value::String(s)) if s == AUTO => Ok(None),
            Some(toml::Value::Boolean(b)) => Ok(Some(*b)),
            Some(v) => Err(Self::err(key, "true, false or \"auto\"", v)),
        }
    }
    /// The string at `key`, or `default` when the table lacks it.
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
            Some(k) => Err(GraphError::parameter(format!(
                "unknown parameter `{k}`; known: {}",
                known.join(", ")
            ))),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(text: &str) -> Params {
        Params::new(toml::from_str(text).unwrap())
    }

    #[test]
    fn numbers_take_integers_and_floats_and_refuse_the_rest() {
        let p = params(
            "a = 2\nb = 1.5\nc = nan\nd = \"x\"\ne = [1, 2.5, 3]\nf = [1, 2]\ng = [1, true, 3]",
        );
        assert_eq!(p.f32("a", 0.0).unwrap(), 2.0);
        assert_eq!(p.f32("b", 0.0).unwrap(), 1.5);
        assert_eq!(p.f32("missing", 7.0).unwrap(), 7.0);
        assert_eq!(p.f32_array("e", [0.0; 3]).unwrap(), [1.0, 2.5, 3.0]);
        assert_eq!(p.f32_array("missing", [4.0; 3]).unwrap(), [4.0; 3]);
        for (key, bad) in [
            ("c", p.f32("c", 0.0).err()),
            ("d", p.f32("d", 0.0).err()),
            ("f", p.f32_array("f", [0.0; 3]).err()),
            ("g", p.f32_array("g", [0.0; 3]).err()),
            ("b", p.f32_array("b", [0.0; 3]).err()),
        ] {
            match bad {
                Some(GraphError::Parameter { message, .. }) => {
                    assert!(message.contains(&format!("`{key}`")), "{message}")
                }
                other => panic!("{key}: {other:?}"),
            }
        }
    }

    #[test]
    fn auto_stands_for_a_value_the_pass_resolves_and_other_words_are_refused() {
        let p = params("a = \"auto\"\nb = 3\nc = \"often\"\nd = true");
        assert_eq!(p.f32_or_auto("a", Some(1.0)).unwrap(), None);
        assert_eq!(p.f32_or_auto("b", None).unwrap(), Some(3.0));
        assert_eq!(p.f32_or_auto("missing", Some(2.0)).unwrap(), Some(2.0));
        assert_eq!(p.bool_or_auto("a", Some(true)).unwrap(), None);
        assert_eq!(p.bool_or_auto("d", None).unwrap(), Some(true));
        for err in [
            p.f32_or_auto("c", None).err(),
            p.bool_or_auto("c", None).err(),
            p.bool_or_auto("b", None).err(),
        ] {
            let message = err.expect("refused").to_string();
            assert!(message.contains("\"auto\""), "{message}");
        }
    }

    #[test]
    fn a_size_needs_both_sides_above_zero_and_names_what_it_sizes() {
        assert_eq!(
            params("width = 64\nheight = 32")
                .size("the target")
                .unwrap(),
            [64, 32]
        );
        for text in ["width = 64", "height = 32", "width = 0\nheight = 32", ""] {
            let err = params(text).size("the target").unwrap_err().to_string();
            assert!(
                err.contains("the target's size") && err.contains("> 0"),
                "{err}"
            );
        }
    }
}
