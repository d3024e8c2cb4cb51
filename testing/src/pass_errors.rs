//! The errors a graph gives for one of its passes, as tests of refused passes read them.

use meshlight_graph::{GraphError, Result};

/// The message of a [`GraphError::Parameter`] that names the pass `pass`: what a test of
/// a graph holding a badly configured pass reads, to check that the error points at that
/// pass and says what to change. Any other outcome fails the test.
pub fn pass_parameter_message<T>(result: Result<T>, pass: &str) -> String {
    match result {
        Err(GraphError::Parameter {
            pass: named,
            message,
        }) => {
            assert_eq!(named, pass);
            message
        }
        other => panic!("{:?}", other.err()),
    }
}
