//! The registry: (stage, implementation) → a factory building the pass from parameters.

use crate::error::{GraphError, Result};
use crate::file::Params;
use crate::pass::Pass;
use std::collections::BTreeMap;

pub type Factory = fn(&Params) -> Result<Box<dyn Pass>>;

#[derive(Default, Clone)]
pub struct Registry {
    factories: BTreeMap<(String, String), Factory>,
}

impl Registry {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn register(
        &mut self,
        stage: &'static str,
        implementation: &'static str,
        factory: Factory,
    ) {
        self.factories
            .insert((stage.to_string(), implementation.to_string()), factory);
    }
    pub fn build(
        &self,
        stage: &str,
        implementation: &str,
        params: &Params,
    ) -> Result<Box<dyn Pass>> {
        let factory = self
            .factories
            .get(&(stage.to_string(), implementation.to_string()))
            .ok_or_else(|| GraphError::UnknownImplementation {
                stage: stage.to_string(),
                implementation: implementation.to_string(),
                known: self.implementations(stage).join(", "),
            })?;
        factory(params)
    }
    pub fn implementations(&self, stage: &str) -> Vec<String> {
        self.factories
            .keys()
            .filter(|(s, _)| s == stage)
            .map(|(_, i)| i.clone())
            .collect()
    }
    /// The registered stage names, each once, sorted.
    pub fn stage_names(&self) -> Vec<String> {
        let mut v: Vec<String> = self.factories.keys().map(|(s, _)| s.clone()).collect();
        v.dedup();
        v
    }
    pub fn stages(&self) -> Vec<(String, String)> {
        self.factories.keys().cloned().collect()
    }
}
