//! The registry: (stage, implementation) → a factory building the pass from parameters.

use crate::adapter::AdapterClass;
use crate::choice::{AUTO, Choice, ClassOrder};
use crate::error::{GraphError, Result};
use crate::file::Params;
use crate::pass::Pass;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Builds a pass from its `params` table (stored boxed, so the registry holds every
/// implementation of every stage alike).
type Factory = Arc<dyn Fn(&Params) -> Result<Box<dyn Pass>> + Send + Sync>;

/// What a registered builder returns: a pass, or one already boxed.
pub trait IntoPass {
    /// The pass, boxed as the graph holds it.
    fn into_pass(self) -> Box<dyn Pass>;
}

impl<P: Pass + 'static> IntoPass for P {
    fn into_pass(self) -> Box<dyn Pass> {
        Box::new(self)
    }
}

impl IntoPass for Box<dyn Pass> {
    fn into_pass(self) -> Box<dyn Pass> {
        self
    }
}

/// The stages and implementations pipeline files can name, each with its factory, and per
/// stage the order `auto` tries them in.
#[derive(Default, Clone)]
pub struct Registry {
    factories: BTreeMap<(String, String), Factory>,
    /// Per stage, its implementations best first, for `auto`.
    preferences: BTreeMap<String, Vec<String>>,
    /// Per stage, orders that replace `preferences` on one adapter class, and why.
    class_preferences: BTreeMap<String, Vec<ClassOrder>>,
}

impl Registry {
    /// An empty registry.
    pub fn new() -> Self {
        Self::default()
    }
    /// Adds what builds `implementation` of `stage` from a pipeline entry's params: a
    /// pass's own `from_params`, or a closure naming the variant, e.g.
    /// `|p| SwRaster::from_params(p, Visibility64::Buffer)`. A second registration of the
    /// same pair replaces the first.
    pub fn register<P, F>(&mut self, stage: &'static str, implementation: &'static str, build: F)
    where
        P: IntoPass,
        F: Fn(&Params) -> Result<P> + Send + Sync + 'static,
    {
        let factory: Factory = Arc::new(move |params| Ok(build(params)?.into_pass()));
        self.factories
            .insert((stage.to_string(), implementation.to_string()), factory);
    }
    /// Registers the implementations of a stage that one type builds, each from its own
    /// variant (`build(params, variant)`), and makes `auto` try them in the order given.
    pub fn register_best_first<V, P, F>(
        &mut self,
        stage: &'static str,
        best_first: &[(&'static str, V)],
        build: F,
    ) where
        V: Copy + Send + Sync + 'static,
        P: IntoPass,
        F: Fn(&Params, V) -> Result<P> + Clone + Send + Sync + 'static,
    {
        for &(implementation, variant) in best_first {
            let build = build.clone();
            self.register(stage, implementation, move |params| build(params, variant));
        }
        let names: Vec<&'static str> = best_first.iter().map(|(name, _)| *name).collect();
        self.prefer(stage, &names);
    }
    /// Makes `auto` available for `stage`: compile keeps the first of `best_first` the
    /// adapter runs. Every name must be registered (checked when a file uses it).
    pub fn prefer(&mut self, stage: &'static str, best_first: &[&'static str]) {
        self.preferences.insert(
            stage.to_string(),
            best_first.iter().map(|s| s.to_string()).collect(),
        );
    }

    /// Makes `auto` try `stage`'s implementations in the order `best_first` on adapters
    /// of `class` (those it leaves out after, in the stage's own order): the same
    /// features can want another implementation where the hardware differs. `why`
    /// says what was measured, and the plan's choice names it.
    pub fn prefer_on(
        &mut self,
        stage: &'static str,
        class: AdapterClass,
        best_first: &[&'static str],
        why: &'static str,
    ) {
        let orders = self.class_preferences.entry(stage.to_string()).or_default();
        orders.retain(|o| o.class != class);
        orders.push(ClassOrder {
            class,
            best_first: best_first.to_vec(),
            why,
        });
    }

    /// The stage's implementations best first on adapters of `class`, when it has an
    /// `auto`.
    pub fn preference(&self, stage: &str, class: AdapterClass) -> Option<Vec<String>> {
        let order = self.preferences.get(stage)?;
        let first: &[&str] = self
            .class_preferences
            .get(stage)
            .and_then(|orders| orders.iter().find(|o| o.class == class))
            .map_or(&[], |o| o.best_first.as_slice());
        let mut names: Vec<String> = first.iter().map(|s| s.to_string()).collect();
        names.extend(
            order
                .iter()
                .filter(|n| !first.contains(&n.as_str()))
                .cloned(),
        );
        Some(names)
    }

    /// The pass for a pipeline entry as a [`Choice`]: for `auto`, every preferred
    /// implementation built from the same parameters; for a named implementation of a
    /// stage with an `auto`, the named one plus the others (built where the parameters
    /// suit them), so a missing feature's error names what would run instead.
    pub fn build_choice(
        &self,
        stage: &str,
        implementation: &str,
        params: &Params,
    ) -> Result<Option<Choice>> {
        let Some(order) = self.preferences.get(stage) else {
            if implementation == AUTO {
                return Err(GraphError::UnknownImplementation {
                    stage: stage.to_string(),
                    implementation: AUTO.to_string(),
                    known: format!(
                        "{} (stage `{stage}` has no `auto`: name one)",
                        self.implementations(stage).join(", ")
                    ),
                });
            }
            return Ok(None);
        };
        // The named one must build (its errors are the user's); the others are built
        // where the parameters suit them, only to be named as what would run.
        let named = (implementation != AUTO)
            .then(|| self.build(stage, implementation, params))
            .transpose()?;
        let mut candidates = Vec::with_capacity(order.len() + 1);
        for i in order {
            match self.build(stage, i, params) {
                Ok(pass) => candidates.push(pass),
                Err(e) if named.is_none() => return Err(e),
                Err(_) => {}
            }
        }
        if let Some(named) = named {
            candidates.retain(|c| c.implementation().name != implementation);
            candidates.insert(0, named);
        }
        let orders = self
            .class_preferences
            .get(stage)
            .cloned()
            .unwrap_or_default();
        Choice::select(implementation, candidates).map(|c| Some(c.with_class_orders(orders)))
    }

    /// Builds `implementation` of `stage` from `params`; an unknown pair is an error listing
    /// the stage's implementations.
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
    /// The stage's implementation names, `auto` last when the stage has one.
    pub fn implementations(&self, stage: &str) -> Vec<String> {
        let mut names: Vec<String> = self
            .factories
            .keys()
            .filter(|(s, _)| s == stage)
            .map(|(_, i)| i.clone())
            .collect();
        if self.preferences.contains_key(stage) {
            names.push(AUTO.to_string());
        }
        names
    }
    /// The registered stage names, each once, sorted.
    pub fn stage_names(&self) -> Vec<String> {
        let mut v: Vec<String> = self.factories.keys().map(|(s, _)| s.clone()).collect();
        v.dedup();
        v
    }
    /// Every registered (stage, implementation) pair, sorted.
    pub fn stages(&self) -> Vec<(String, String)> {
        self.factories.keys().cloned().collect()
    }
}
