//! Compile time of random graphs of 10, 100 and 1000 passes (target: 1000 passes < 2 ms).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use meshlight_graph::CompileOptions;
use meshlight_graph::synthetic::random_graph;

fn compile(c: &mut Criterion) {
    let mut group = c.benchmark_group("compile");
    for n in [10usize, 100, 1000] {
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, &n| {
            b.iter_batched(
                || random_graph(n, 0x5eed),
                |g| {
                    g.compile(&CompileOptions::new(wgpu::Features::empty()))
                        .expect("compiles")
                },
                criterion::BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, compile);
criterion_main!(benches);
