//! Growing a list to what a frame asked for. A list's length is a size parameter of the
//! compiled graph; when a frame's counters ask for more than it holds, the parameter is
//! raised to the next power of two, up to what the device binds. The clustering and the
//! virtual-geometry frame grow their lists this way.

use meshlight::graph::{CompiledGraph, Result};

/// One grow of a list, for logs and tests.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Growth {
    /// The frame that asked for more.
    pub frame: u64,
    /// The list's size parameter.
    pub param: &'static str,
    /// Its size before, in entries.
    pub from: u64,
    /// Its size after.
    pub to: u64,
}

/// What a frame asked of a list, and what to tell the user when it cannot have it.
pub struct Want {
    /// The frame that asked.
    pub frame: u64,
    /// The list's size parameter.
    pub param: &'static str,
    /// Entries the frame asked for.
    pub wanted: u64,
    /// The most entries this device binds.
    pub limit: u64,
    /// What is lost while the list is at `limit`, and what the user can do instead.
    pub when_full: &'static str,
    /// Where else than the pipeline's `[params]` the size can be set from the start.
    pub also_set_by: &'static str,
}

/// Raises the list of `want` to the next power of two at or above what the frame asked
/// for, logged as a warning. `None` when the list already holds that much, or when it is
/// at the device's limit (logged as an error: the frame lost entries).
pub fn grow(compiled: &mut CompiledGraph, want: Want) -> Result<Option<Growth>> {
    let Want {
        frame,
        param,
        wanted,
        limit,
        when_full,
        also_set_by,
    } = want;
    let now = param_value(compiled, param);
    if wanted <= now {
        return Ok(None);
    }
    let to = wanted.next_power_of_two().min(limit);
    if to <= now {
        log::error!(
            "frame {frame}: {wanted} `{param}` wanted, but {now} is the most this device binds; {when_full}"
        );
        return Ok(None);
    }
    log::warn!(
        "frame {frame}: {wanted} `{param}` wanted but the list holds {now}; raised `{param}` to {to} (start there with `{param} = {to}` in the pipeline's [params] or {also_set_by})"
    );
    compiled.set_param(param, to)?;
    Ok(Some(Growth {
        frame,
        param,
        from: now,
        to,
    }))
}

/// The current value of a size parameter of a compiled graph.
pub fn param_value(compiled: &CompiledGraph, name: &str) -> u64 {
    compiled
        .plan
        .params
        .iter()
        .find(|(n, _)| n == name)
        .map_or(0, |(_, v)| *v)
}
