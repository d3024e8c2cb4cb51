//! What a host's profiler and a trace viewer see of a frame: the CPU scopes (compile,
//! prepare, each pass's record, submit) reach whatever backend the `profiling` crate is
//! built with (here its `tracing` backend, caught by a subscriber of the test's own),
//! and a frame's GPU timings export as a Chrome trace with one event per batch
//! (lavapipe in CI).

mod support;

use meshlight_graph::*;
use std::sync::{Arc, Mutex};
use support::*;

const N: u32 = 256;

/// Held by each test of this file: `tracing` caches per call site whether anyone listens,
/// and a scope first reached by the other test's thread while no subscriber of this
/// test's existed could be cached as unheard.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// fill → (readback: an encoder batch) → add: three batches.
fn graph() -> GraphBuilder {
    let mut g = GraphBuilder::new();
    let a = g.create_buffer("a", BufferDesc::array(Element::U32, N as u64));
    let b = g.create_buffer("b", BufferDesc::array(Element::U32, N as u64));
    let a1 = add_writer(
        &mut g,
        "fill",
        Arith::fill(N, 3),
        Bindings::new().bind("output", a),
        "output",
    );
    g.readback("a", a1, Some(0..16), 1).unwrap();
    let b1 = add_writer(
        &mut g,
        "add",
        Arith::add(N, 1),
        Bindings::new().bind("input", a1).bind("output", b),
        "output",
    );
    g.export(b1);
    g
}

/// Spans as the `tracing` backend of `profiling` opens them: name, and the `tag` a scope
/// with data carries.
#[derive(Default, Clone)]
struct Spans(Arc<Mutex<Vec<Span>>>);

/// A span's name and tag.
type Span = (String, Option<String>);

struct Tag(Option<String>);

impl tracing::field::Visit for Tag {
    fn record_str(&mut self, field: &tracing::field::Field, value: &str) {
        if field.name() == "tag" {
            self.0 = Some(value.to_string());
        }
    }
    fn record_debug(&mut self, field: &tracing::field::Field, value: &dyn std::fmt::Debug) {
        if field.name() == "tag" {
            self.0 = Some(format!("{value:?}").trim_matches('"').to_string());
        }
    }
}

impl tracing::Subscriber for Spans {
    fn enabled(&self, _: &tracing::Metadata<'_>) -> bool {
        true
    }
    fn new_span(&self, span: &tracing::span::Attributes<'_>) -> tracing::span::Id {
        let mut tag = Tag(None);
        span.record(&mut tag);
        let mut spans = self.0.lock().unwrap();
        spans.push((span.metadata().name().to_string(), tag.0));
        tracing::span::Id::from_u64(spans.len() as u64)
    }
    fn record(&self, _: &tracing::span::Id, _: &tracing::span::Record<'_>) {}
    fn record_follows_from(&self, _: &tracing::span::Id, _: &tracing::span::Id) {}
    fn event(&self, _: &tracing::Event<'_>) {}
    fn enter(&self, _: &tracing::span::Id) {}
    fn exit(&self, _: &tracing::span::Id) {}
}

#[test]
fn compile_prepare_record_and_submit_are_scopes_a_profiler_sees() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spans = Spans::default();
    tracing::subscriber::with_default(spans.clone(), || {
        // Call sites met before this subscriber existed are asked again.
        tracing::callsite::rebuild_interest_cache();
        let gpu = gpu();
        let compiled = graph().compile(&CompileOptions::for_gpu(&gpu)).unwrap();
        let mut exec = Executor::new(gpu);
        exec.execute(&compiled, &Imports::new()).unwrap();
    });
    let seen = spans.0.lock().unwrap().clone();
    let named = |name: &str| seen.iter().filter(|(n, _)| n == name).count();
    for scope in [
        "meshlight::compile",
        "meshlight::prepare",
        "meshlight::execute_frame",
        "meshlight::submit",
    ] {
        assert_eq!(named(scope), 1, "{scope}: {seen:?}");
    }
    // Every pass's record, tagged with its name; the programs of the two kernels built
    // for their passes.
    let records: Vec<&str> = seen
        .iter()
        .filter(|(n, _)| n == "meshlight::record")
        .filter_map(|(_, tag)| tag.as_deref())
        .collect();
    // The readback sunk past `add`, which does not write what it copies.
    assert_eq!(records, ["fill", "add", "readback:a"], "{seen:?}");
    assert!(
        seen.iter()
            .any(|(n, t)| n == "meshlight::prepare pass" && t.as_deref() == Some("fill")),
        "{seen:?}"
    );
}

#[test]
fn a_frames_timings_are_a_chrome_trace_with_an_event_per_batch() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let gpu = gpu();
    assert!(
        gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY),
        "this test needs an adapter with timestamps (lavapipe has them)"
    );
    let compiled = graph().compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let plan = &compiled.plan;
    // The two kernels in one compute pass, then the readback's copy.
    assert_eq!(plan.batches.len(), 2, "{:?}", plan.batches);
    let mut exec = Executor::new(gpu);
    exec.timing = TimingMode::Frame;
    exec.execute(&compiled, &Imports::new()).unwrap();
    exec.finish().unwrap();
    let timings = exec.take_gpu_timings().unwrap();
    assert_eq!(timings.len(), 1);
    let text = dump::to_chrome_trace(&timings, Some(plan));
    let trace: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let events = trace["traceEvents"]
        .as_array()
        .expect("a traceEvents array");
    let complete: Vec<&serde_json::Value> = events.iter().filter(|e| e["ph"] == "X").collect();
    assert_eq!(complete.len(), plan.batches.len(), "{text}");
    let mut last_end = 0.0;
    for (b, e) in complete.iter().enumerate() {
        assert_eq!(e["name"], plan.batches[b].label(b));
        let (ts, dur) = (e["ts"].as_f64().unwrap(), e["dur"].as_f64().unwrap());
        assert!(ts >= last_end - 1e-6 && dur >= 0.0, "{e}");
        last_end = ts + dur;
        assert!(e["pid"].is_number() && e["tid"].is_number(), "{e}");
    }
    assert_eq!(complete[0]["args"]["passes"], "fill, add");
    assert_eq!(complete[1]["args"]["passes"], "readback:a");
    assert_eq!(trace["displayTimeUnit"], "ms");
}
