//! Tests of a pass variant that needs adapter features: where the test GPU has them the
//! test checks what the pass drew; where it has not (lavapipe lacks several), compiling
//! the variant must be the typed error that names what is missing.

use meshlight_graph::{GraphError, Result};

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
