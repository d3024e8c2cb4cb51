//! Dump a graph shaped like one virtual-geometry frame in every format.
//!
//!     cargo run -p meshlight-bench --example dump_graph && dot -Tsvg out/frame.dot -o out/frame.svg

use meshlight::graph::{CompileOptions, dump};

fn main() -> std::io::Result<()> {
    let plan = meshlight_bench::sample_frame_graph(1920, 1080)
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .expect("the sample graph compiles")
        .plan;
    std::fs::create_dir_all("out")?;
    std::fs::write("out/frame.dot", dump::to_dot(&plan))?;
    std::fs::write("out/frame.json", dump::to_json(&plan, None))?;
    std::fs::write("out/frame.mmd", dump::to_mermaid(&plan))?;
    std::fs::write("out/frame.html", dump::to_html(&plan, "sample frame", None))?;
    println!(
        "{} passes, transient memory {:.1} MiB with slot reuse ({:.1} MiB without); wrote out/frame.{{dot,json,mmd,html}}",
        plan.order.len(),
        plan.bytes_with_reuse as f64 / 1048576.0,
        plan.bytes_without_reuse as f64 / 1048576.0
    );
    Ok(())
}
