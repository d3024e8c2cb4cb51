//! GPU timings as a Chrome trace (the Trace Event Format's JSON object), which Perfetto
//! (ui.perfetto.dev) and `chrome://tracing` open: one complete event per timed unit
//! (a batch in `frame` timing, a pass in `passes` timing) at the time its timestamps
//! were written, with the passes a batch ran as its arguments.

use crate::exec::GpuTimings;
use crate::plan::Plan;
use serde::Serialize;
use std::collections::BTreeMap;

#[derive(Serialize)]
struct Trace {
    #[serde(rename = "traceEvents")]
    trace_events: Vec<Event>,
    #[serde(rename = "displayTimeUnit")]
    display_time_unit: &'static str,
}

#[derive(Serialize)]
struct Event {
    name: String,
    cat: &'static str,
    ph: &'static str,
    /// Microseconds.
    ts: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    dur: Option<f64>,
    pid: u32,
    tid: u32,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    args: BTreeMap<&'static str, String>,
}

/// The GPU timings of `frames` as a Chrome trace: each frame's units on one track, the
/// frames laid end to end in order (the time between frames is not measured, so each
/// starts where the one before ended). With the `plan` the frames ran, a batch's event
/// names its passes and a pass's its stage and implementation.
pub fn to_chrome_trace(frames: &[GpuTimings], plan: Option<&Plan>) -> String {
    let mut events = vec![Event {
        name: "thread_name".into(),
        cat: "__metadata",
        ph: "M",
        ts: 0.0,
        dur: None,
        pid: 1,
        tid: 1,
        args: BTreeMap::from([("name", "GPU".to_string())]),
    }];
    let mut origin = 0.0;
    for timings in frames {
        for ((name, _), [start, end]) in timings.passes.iter().zip(&timings.intervals) {
            let mut args = BTreeMap::from([
                ("frame", timings.frame.to_string()),
                ("timing", timings.mode.name().to_string()),
            ]);
            if let Some(plan) = plan {
                describe(plan, timings, name, &mut args);
            }
            events.push(Event {
                name: name.clone(),
                cat: "gpu",
                ph: "X",
                ts: origin + start,
                dur: Some(end - start),
                pid: 1,
                tid: 1,
                args,
            });
        }
        origin += timings.frame_us;
    }
    serde_json::to_string_pretty(&Trace {
        trace_events: events,
        display_time_unit: "ms",
    })
    .expect("a trace serialises: string keys only")
}

/// The passes of a batch, or the stage and implementation of a pass, as event arguments.
fn describe(
    plan: &Plan,
    timings: &GpuTimings,
    unit: &str,
    args: &mut BTreeMap<&'static str, String>,
) {
    match timings.mode {
        crate::exec::TimingMode::Passes => {
            if let Some(p) = plan.pass_index(unit).map(|i| &plan.passes[i]) {
                args.insert("stage", p.stage.to_string());
                args.insert("implementation", p.implementation_label());
            }
        }
        _ => {
            let batch = plan
                .batches
                .iter()
                .enumerate()
                .find(|(b, batch)| batch.label(*b) == unit);
            if let Some((_, batch)) = batch {
                let names: Vec<&str> = batch
                    .passes
                    .iter()
                    .map(|&p| plan.passes[p].name.as_str())
                    .collect();
                args.insert("passes", names.join(", "));
            }
        }
    }
}
