//! Tests of a pass variant that needs adapter features: where the test GPU has them the
//! test checks what the pass drew; where it has not (lavapipe lacks several), compiling
//! the variant must be the typed error that names what is missing.

use meshlight_graph::{GraphError, Result};

/// What lavapipe (Mesa 22.3) offers through wgpu 30 of what the passes use: the features
/// headless tests plan for when they stand for CI's adapter.
pub fn lavapipe() -> wgpu::Features {
    wgpu::Features::SHADER_INT64
        | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX
        | wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS
        | wgpu::Features::SUBGROUP
        | wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::INDIRECT_FIRST_INSTANCE
        | wgpu::Features::MULTI_DRAW_INDIRECT_COUNT
}

/// What an NVIDIA H200 (Vulkan) adds that changes implementation choices: 64-bit texture
/// atomics and mesh shaders.
pub fn h200() -> wgpu::Features {
    lavapipe()
        | wgpu::Features::TEXTURE_INT64_ATOMIC
        | wgpu::Features::TEXTURE_ATOMIC
        | wgpu::Features::EXPERIMENTAL_MESH_SHADER
}

/// `result` of compiling and running a pass that needs `features`: its value where the
/// test GPU has them. Where it has not, asserts that `result` is the
/// [`GraphError::MissingFeature`] of the pass named `pass`, naming the feature `named`,
/// logs that the GPU has no `what`, and returns `None`: the test ends there.
pub fn where_supported<T>(
    result: Result<T>,
    features: wgpu::Features,
    pass: &str,
    named: &str,
    what: &str,
) -> Option<T> {
    if crate::gpu().adapter.features().contains(features) {
        return Some(result.unwrap_or_else(|e| panic!("{e}")));
    }
    match result {
        Err(GraphError::MissingFeature {
            pass: refused,
            features,
            ..
        }) => {
            assert_eq!(refused, pass);
            assert!(features.contains(named), "{features}");
            eprintln!("no {what} here: the typed error, as expected");
        }
        other => panic!("expected the missing-feature error, got {:?}", other.err()),
    }
    None
}
