//! Implementation choice: a pass instance may hold several implementations of its stage,
//! best first, and compile keeps the one the adapter runs.
//!
//! The strongest reason to swap an implementation is the adapter: 64-bit texture atomics
//! or mesh shaders where it has them, the portable buffer and indirect-draw paths where
//! it has not. With [`Selection::Auto`] compile picks the first candidate whose setup
//! asks for nothing the adapter lacks; with [`Selection::Named`] the pipeline named one,
//! and the others only let a missing feature's error say which implementation would run.
//! The needs come from each candidate's own `setup`, so they cannot drift from what the
//! pass really requires. The plan keeps a [`ChoicePlan`] so dumps show what was chosen
//! and why.

use crate::adapter::AdapterClass;
use crate::error::{GraphError, Result};
use crate::names::feature_names;
use crate::pass::{Pass, SetupContext};
use crate::plan::{CandidatePlan, ChoicePlan, Selection};

/// The implementation name that lets compile pick by the adapter's features.
pub const AUTO: &str = "auto";

/// Several implementations of one stage for one pass instance, in preference order.
pub struct Choice {
    pub(crate) selection: Selection,
    pub(crate) candidates: Vec<Box<dyn Pass>>,
    /// Orders `auto` follows instead on some adapter classes.
    pub(crate) class_orders: Vec<ClassOrder>,
}

/// The order `auto` tries a stage's implementations in on one adapter class, and what
/// measurement says so.
#[derive(Clone, Debug)]
pub struct ClassOrder {
    /// The class the order is for.
    pub class: AdapterClass,
    /// Implementation names, best first; those left out follow in the stage's own order.
    pub best_first: Vec<&'static str>,
    /// Why, for the plan and its dumps.
    pub why: &'static str,
}

impl Choice {
    /// `auto`: compile keeps the first of `candidates` (best first) the adapter runs.
    pub fn auto(candidates: Vec<Box<dyn Pass>>) -> Self {
        Self {
            selection: Selection::Auto,
            candidates,
            class_orders: Vec::new(),
        }
    }
    /// `named` runs; `alternatives` (the stage's other implementations, best first) are
    /// only named in the error when the adapter cannot run `named`.
    pub fn named(named: Box<dyn Pass>, alternatives: Vec<Box<dyn Pass>>) -> Self {
        let mut candidates = vec![named];
        candidates.extend(alternatives);
        Self {
            selection: Selection::Named,
            candidates,
            class_orders: Vec::new(),
        }
    }
    /// `auto` follows `orders` on the classes they name (see [`ClassOrder`]).
    pub fn with_class_orders(mut self, orders: Vec<ClassOrder>) -> Self {
        self.class_orders = orders;
        self
    }
    /// `auto` over `candidates` (best first) when `wanted` is `auto`, else the candidate
    /// named `wanted` with the others as alternatives; an unknown name is an error
    /// listing the known ones.
    pub fn select(wanted: &str, mut candidates: Vec<Box<dyn Pass>>) -> Result<Self> {
        if wanted == AUTO {
            return Ok(Self::auto(candidates));
        }
        match candidates
            .iter()
            .position(|c| c.implementation().name == wanted)
        {
            Some(i) => {
                let named = candidates.remove(i);
                Ok(Self::named(named, candidates))
            }
            None => Err(GraphError::UnknownImplementation {
                stage: candidates
                    .first()
                    .map(|c| c.implementation().contract.stage.to_string())
                    .unwrap_or_default(),
                implementation: wanted.to_string(),
                known: candidates
                    .iter()
                    .map(|c| c.implementation().name)
                    .chain([AUTO])
                    .collect::<Vec<_>>()
                    .join(", "),
            }),
        }
    }
    /// How compile is to pick among the candidates.
    pub fn selection(&self) -> Selection {
        self.selection
    }
    /// The candidates' implementation names, in order.
    pub fn implementations(&self) -> Vec<&'static str> {
        self.candidates
            .iter()
            .map(|c| c.implementation().name)
            .collect()
    }
}

/// The features `pass` asks for in setup that `adapter` lacks. Setup runs as it will for
/// real (same adapter features, limits, parameters and bound slots), so a pass that
/// picks a variant by feature reports the variant it would pick.
pub(crate) fn missing_features(
    pass: &dyn Pass,
    adapter: wgpu::Features,
    limits: &wgpu::Limits,
    class: AdapterClass,
    params: &[(String, u64)],
    bound: Vec<&'static str>,
) -> Result<wgpu::Features> {
    let mut ctx = SetupContext::new(adapter, limits, class, params, bound);
    pass.setup(&mut ctx)?;
    Ok(ctx.required - adapter)
}

/// Keeps the candidate `choice` selects on this adapter; returns it and the plan of the
/// choice. An `auto` with no runnable candidate, or a named one the adapter cannot run,
/// is [`GraphError::MissingFeature`] naming what is missing and what would run.
pub(crate) fn resolve(
    pass_name: &str,
    choice: Choice,
    class: AdapterClass,
    mut missing: impl FnMut(&dyn Pass) -> Result<wgpu::Features>,
) -> Result<(Box<dyn Pass>, ChoicePlan)> {
    let Choice {
        selection,
        mut candidates,
        class_orders,
    } = choice;
    // On a class with an order of its own, `auto` tries that order first.
    let class_order = class_orders
        .into_iter()
        .find(|o| o.class == class && selection == Selection::Auto);
    if let Some(o) = &class_order {
        let rank = |c: &dyn Pass| {
            let name = c.implementation().name;
            o.best_first
                .iter()
                .position(|n| *n == name)
                .unwrap_or(o.best_first.len())
        };
        candidates.sort_by_key(|c| rank(c.as_ref()));
    }
    // A candidate whose setup refuses the parameters does not run; `auto` passes over it
    // (a parameter one implementation does not support yet), a named one reports it.
    let mut judged = Vec::with_capacity(candidates.len());
    let mut refusals = Vec::with_capacity(candidates.len());
    for (k, c) in candidates.iter().enumerate() {
        match missing(c.as_ref()) {
            Ok(m) => {
                judged.push(m);
                refusals.push(None);
            }
            Err(e) if k == 0 && selection != Selection::Auto => return Err(e),
            Err(e) => {
                judged.push(wgpu::Features::empty());
                refusals.push(Some(e.to_string()));
            }
        }
    }
    let plans: Vec<CandidatePlan> = candidates
        .iter()
        .zip(judged.iter().zip(&refusals))
        .map(|(c, (m, refused))| CandidatePlan {
            implementation: c.implementation().name,
            missing: m.iter_names().map(|(n, _)| n.to_string()).collect(),
            refused: refused.clone(),
        })
        .collect();
    let runnable = (0..judged.len()).position(|k| judged[k].is_empty() && refusals[k].is_none());
    let stage = candidates[0].implementation().contract.stage.to_string();
    let order = plans
        .iter()
        .map(|p| format!("`{}`", p.implementation))
        .collect::<Vec<_>>()
        .join(", ");
    let chosen = match (selection, runnable) {
        (Selection::Named, _) if !judged[0].is_empty() => {
            return Err(GraphError::MissingFeature {
                pass: pass_name.to_string(),
                stage: stage.clone(),
                features: feature_names(judged[0]),
                instead: match runnable {
                    Some(i) => format!(
                        "implementation `{}` of stage `{stage}` runs on it: name it, or `auto`, in the pipeline",
                        plans[i].implementation
                    ),
                    None => format!(
                        "no implementation of stage `{stage}` runs on it ({order}); use another adapter (MESHLIGHT_ADAPTER)"
                    ),
                },
            });
        }
        (Selection::Auto, None) if judged.iter().all(|m| m.is_empty()) => {
            // Every candidate refused the parameters: the first one's reason.
            return Err(GraphError::parameter(format!(
                "pass `{pass_name}`: no implementation of stage `{stage}` accepts its parameters: {}",
                plans
                    .iter()
                    .filter_map(|p| p.refused.as_deref())
                    .collect::<Vec<_>>()
                    .join("; ")
            )));
        }
        (Selection::Auto, None) => {
            return Err(GraphError::MissingFeature {
                pass: pass_name.to_string(),
                stage: stage.clone(),
                features: feature_names(judged.iter().fold(wgpu::Features::empty(), |a, m| a | *m)),
                instead: format!(
                    "`auto` found no implementation of stage `{stage}` this adapter runs ({order}); use another adapter (MESHLIGHT_ADAPTER)"
                ),
            });
        }
        (Selection::Auto, Some(i)) => i,
        _ => 0,
    };
    let name = plans[chosen].implementation;
    let on_class = class_order
        .as_ref()
        .map(|o| format!("on a {} `auto` tries {order} ({}); ", class.name(), o.why))
        .unwrap_or_default();
    let reason = match selection {
        Selection::Auto => {
            let skipped: Vec<String> = plans[..chosen]
                .iter()
                .map(|p| match &p.refused {
                    Some(why) => format!("`{}` refuses its parameters ({why})", p.implementation),
                    None => format!(
                        "`{}` needs {}, which the adapter lacks",
                        p.implementation,
                        p.missing.join(", ")
                    ),
                })
                .collect();
            if skipped.is_empty() {
                format!(
                    "{on_class}`{name}` is the first of {order} and the adapter has all it needs"
                )
            } else {
                format!(
                    "{on_class}{}; `{name}` is the next of {order}",
                    skipped.join("; ")
                )
            }
        }
        Selection::Named | Selection::Fixed => format!("`{name}` is named in the pipeline"),
    };
    let mut candidates = candidates;
    let pass = candidates.swap_remove(chosen);
    Ok((
        pass,
        ChoicePlan {
            selection,
            chosen: name,
            reason,
            candidates: plans,
        },
    ))
}
